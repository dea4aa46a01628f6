"""Scenes: the examples, defaults, relative paths, and checks in Python."""
from __future__ import annotations

import pickle
from pathlib import Path

import numpy as np
import pytest

import halfslip as hs
from halfslip import HalfslipInputError, OutputOptions, Scene, SolverOptions, load_scene, parse_scene

import helpers

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"

MINIMAL = helpers.MINIMAL_SCENE


def shear_ratio_everywhere(scene: Scene) -> float:
    """max |Q|/(fP) on a grid 20 times finer than the steps (the harmonics between samples too)."""
    history = scene.history
    t = np.linspace(0.0, history.duration, 20 * history.n_steps + 1)
    loads = history.evaluate(t)
    loaded = loads["P"] > 0
    assert np.all(loads["Q"][~loaded] == 0.0)
    return float(np.max(np.abs(loads["Q"][loaded]) / (scene.friction * loads["P"][loaded])))


@pytest.mark.parametrize("path", sorted(p for p in EXAMPLES.glob("*.yaml") if "sweep" not in p.name), ids=lambda path: path.name)
def test_examples_load_without_warnings(path):
    scene = load_scene(path)
    assert scene.path == path and scene.text == path.read_text()
    assert scene.warnings() == ()
    assert scene.history.max_shear_ratio(scene.friction) < 1.0
    assert shear_ratio_everywhere(scene) < 1.0


def test_examples_cover_the_documented_scenes():
    names = {path.name for path in EXAMPLES.glob("*.yaml")}
    assert {"hertz_pad.yaml", "motor.yaml", "dovetail.yaml", "tabulated.yaml"} <= names


def test_hertz_pad_cycles_shear_at_thirty_percent_of_the_sliding_limit():
    scene = load_scene(EXAMPLES / "hertz_pad.yaml")
    assert isinstance(scene.profile, hs.Hertz) and scene.profile.radius == 50e-3
    assert (scene.material.E, scene.material.nu, scene.friction) == (200e9, 0.3, 0.6)
    ramp, cycles = scene.history.segments
    assert scene.history.P[ramp.stop] == 1.0e5
    assert (cycles.count, cycles.steps_per_cycle) == (20, 100)
    assert cycles.harmonics["Q"].amplitude == pytest.approx(0.3 * 0.6 * 1.0e5)
    assert cycles.harmonics["P"].amplitude == 0.0


def test_motor_rotating_force_slips_without_sliding():
    scene = load_scene(EXAMPLES / "motor.yaml")
    cycles = scene.history.segments[-1]
    P, Q = cycles.harmonics["P"], cycles.harmonics["Q"]
    assert Q.phase - P.phase == pytest.approx(np.pi / 2)
    assert 0.5 < shear_ratio_everywhere(scene) < 1.0
    # the loop is steeper than the friction line somewhere: the edges slip
    inside = slice(cycles.start, cycles.stop + 1)
    slope = np.diff(scene.history.Q[inside]) / np.diff(scene.history.P[inside])
    assert np.max(np.abs(slope)) > scene.friction


def test_dovetail_cycles_all_four_loads_in_phase_about_the_mean():
    scene = load_scene(EXAMPLES / "dovetail.yaml")
    assert isinstance(scene.profile, hs.RoundedPunch)
    assert (scene.profile.flat_half_width, scene.profile.radius) == (2e-3, 10e-3)
    ramp, cycles = scene.history.segments
    means = {"P": 2.0e5, "Q": 2.0e4, "M": 5.0, "sigma": 2.0e7}
    amplitudes = {"P": 2.0e4, "Q": 3.0e4, "M": 5.0, "sigma": 2.0e7}
    for name, harmonic in cycles.harmonics.items():
        assert scene.history.loads()[name][ramp.stop] == means[name]
        assert (harmonic.mean, harmonic.amplitude, harmonic.phase) == (means[name], amplitudes[name], 0.0)
    assert (cycles.count, cycles.steps_per_cycle) == (20, 100)
    assert shear_ratio_everywhere(scene) == pytest.approx(5.0e4 / (0.6 * 2.2e5), rel=1e-6)


def test_tabulated_example_reads_the_profile_relative_to_the_scene(monkeypatch, tmp_path):
    monkeypatch.chdir(tmp_path)  # the profile is found relative to the scene, not the working directory
    scene = load_scene(EXAMPLES / "tabulated.yaml")
    assert isinstance(scene.profile, hs.TabulatedProfile) and scene.profile.symmetric
    assert [segment.kind for segment in scene.history.segments] == ["ramp", "table", "hold"]


def test_defaults_and_unquoted_exponents():
    scene = parse_scene(MINIMAL)
    assert scene.name == "scene" and scene.path is None and scene.text == MINIMAL
    assert scene.material == hs.Material(E=2.0e11, nu=0.3)  # "200e9" is a number, not text
    # nodes from the default tol 1e-4: ceil(0.1 / 1e-4) (halfslip.scene.NODES_PER_TOL)
    assert scene.solver == SolverOptions() == SolverOptions("auto", 1000, True) == SolverOptions(tol=1e-4)
    assert SolverOptions(tol=1e-3).nodes == 100 and SolverOptions(tol=1e-3, nodes=64).nodes == 64
    assert scene.output == OutputOptions() == OutputOptions(("p", "q", "slip"), 1, 201)
    assert [segment.line for segment in scene.history.segments] == [5]


def test_options_and_name_are_read(tmp_path):
    text = MINIMAL + "name: pad\nsolver: {method: general, nodes: 64.0}\noutput: {fields: [], every: 5, points: 11}\n"
    path = tmp_path / "pad.yaml"
    path.write_text(text)
    scene = load_scene(path)
    assert scene.name == "pad"
    assert scene.solver == SolverOptions("general", 64, True)
    assert scene.output == OutputOptions((), 5, 11)
    assert load_scene(path).history.n_steps == 10


def test_name_defaults_to_the_file_stem(tmp_path):
    (tmp_path / "my_contact.yaml").write_text(MINIMAL)
    assert load_scene(tmp_path / "my_contact.yaml").name == "my_contact"


def test_table_files_are_relative_to_the_scene(tmp_path, monkeypatch):
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "loads.csv").write_text("t,Q\n1.0,1.0e4\n2.0,0.0\n")
    (tmp_path / "sub" / "scene.yaml").write_text(MINIMAL + "  - table: {file: loads.csv}\n")
    monkeypatch.chdir(tmp_path)
    scene = load_scene("sub/scene.yaml")
    assert scene.history.segments[1].source == str(Path("sub") / "loads.csv")
    np.testing.assert_array_equal(scene.history.Q[-2:], [1.0e4, 0.0])
    # parse_scene takes the base directory explicitly
    other = parse_scene(MINIMAL + "  - table: {file: loads.csv}\n", base_dir=tmp_path / "sub")
    np.testing.assert_array_equal(other.history.t, scene.history.t)


def test_inline_profile():
    x = np.linspace(-1e-3, 1e-3, 21)
    text = MINIMAL.replace(
        "geometry: {kind: hertz, radius: 50e-3}",
        f"geometry: {{kind: profile, x: {x.tolist()}, h: {(x**2 / 0.1).tolist()}}}",
    )
    profile = parse_scene(text).profile
    assert isinstance(profile, hs.TabulatedProfile)
    np.testing.assert_allclose(profile.gap(5e-4), 2.5e-6, rtol=1e-9)


def test_warnings_for_gross_sliding_and_jumps():
    text = MINIMAL + "  - cycles: {count: 1, period: 1, Q: {amplitude: 7e4, phase: 90}}\n"
    jump, sliding = parse_scene(text).warnings()
    assert jump.startswith("loads[1] (line 6): Q jumps from 0 to 70000")
    assert "|Q| > fP" in sliding and "gross sliding" in sliding


def test_errors_from_parse_scene_name_the_line_and_field():
    text = MINIMAL.replace("steps: 10", "steps: ten")
    with pytest.raises(HalfslipInputError) as error:
        parse_scene(text, path="inline.yaml")
    assert (error.value.file, error.value.line, error.value.field) == ("inline.yaml", 5, "loads[0].ramp.steps")
    assert str(error.value) == "inline.yaml:5: loads[0].ramp.steps: expected a number, got the string 'ten'"


@pytest.mark.parametrize(
    ("make", "field"),
    [
        (lambda: SolverOptions(method="fastest"), "solver.method"),
        (lambda: SolverOptions(nodes=7), "solver.nodes"),
        (lambda: SolverOptions(tol=0.5), "solver.tol"),
        (lambda: SolverOptions(tol=-1e-4), "solver.tol"),
        (lambda: SolverOptions(tol="fine"), "solver.tol"),
        (lambda: SolverOptions(skip_steady_cycles="yes"), "solver.skip_steady_cycles"),
        (lambda: OutputOptions(fields=("p", "sigma_xx")), "output.fields[1]"),
        (lambda: OutputOptions(fields="p"), "output.fields"),
        (lambda: OutputOptions(every=0), "output.every"),
        (lambda: OutputOptions(points=1), "output.points"),
    ],
)
def test_options_check_themselves(make, field):
    """Each option refuses a bad value with an error naming its field (solver.tol: a positive fraction
    of the contact width below 0.1)."""
    with pytest.raises(HalfslipInputError) as error:
        make()
    assert error.value.field == field


def test_scene_built_in_python_is_checked():
    history = hs.LoadHistory.from_arrays([1.0], [1.0e5], [0.0])
    scene = Scene("pad", hs.Material(2e11, 0.3), 0.5, hs.Hertz(0.05), history)
    assert scene.text is None and scene.solver == SolverOptions()
    with pytest.raises(HalfslipInputError, match="Poisson"):
        Scene("pad", hs.Material(2e11, -1.0), 0.5, hs.Hertz(0.05), history)
    with pytest.raises(HalfslipInputError) as error:
        Scene("pad", hs.Material(2e11, 0.3), -0.5, hs.Hertz(0.05), history)
    assert error.value.field == "friction"


@pytest.mark.parametrize(
    ("parts", "text"),
    [
        ({"file": "a.yaml", "line": 3, "field": "friction"}, "a.yaml:3: friction: bad"),
        ({"file": "a.yaml", "line": None, "field": None}, "a.yaml: bad"),
        ({"file": None, "line": None, "field": "friction"}, "friction: bad"),
        ({"file": None, "line": None, "field": None}, "bad"),
    ],
)
def test_error_text_leaves_out_unknown_parts(parts, text):
    error = HalfslipInputError("bad", **parts)
    assert str(error) == text
    assert isinstance(error, ValueError)
    assert str(pickle.loads(pickle.dumps(error))) == text  # survives a trip to a worker process


def test_public_names():
    for name in (
        "load_scene parse_scene Scene SolverOptions OutputOptions LoadHistory Segment Material Hertz "
        "RoundedPunch TabulatedProfile NormalProblem HalfslipInputError __version__"
    ).split():
        assert hasattr(hs, name), name
    assert isinstance(hs.__version__, str)
