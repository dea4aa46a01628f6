"""halfslip as its users meet it (issue 16): the Python API in a notebook, messages, CF, the command line."""
from __future__ import annotations

import dataclasses
import io
from pathlib import Path

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

import halfslip as hs
from halfslip.cli import main
from halfslip.io import read_result, write_result
from halfslip.progress import Progress

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
HERTZ = EXAMPLES / "hertz_pad.yaml"

GROSS = """\
name: gross
material: {E: 2.0e11, nu: 0.3}
friction: 0.5
geometry: {kind: hertz, radius: 0.05}
loads:
  - ramp: {to: {P: 1.0e5}, duration: 1.0, steps: 10}
  - cycles: {count: 4, period: 1.0, steps_per_cycle: 20, Q: {amplitude: 6.0e4}}
"""


def cli(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


# -- a notebook user -------------------------------------------------------------


def test_a_notebook_user_gets_progress_checked_constructors_and_a_short_repr(capsys):
    scene = hs.load_scene(HERTZ)
    text = repr(scene)
    assert "\n" not in text and len(text) < 200 and "loads:" not in text, text
    assert text.startswith("Scene('hertz-pad', E=200 GPa, nu=0.3, friction=0.6, hertz R=50 mm, ")
    assert text.endswith("2 segments, 2020 steps, t = 0 .. 21 s)")

    ds = hs.simulate(scene, progress=True)  # a TypeError before 0.2
    err = capsys.readouterr().err
    assert "hertz-pad" in err and "220/220" in err and "1,800 steps skipped as steady cycles" in err, err
    assert ds.attrs["complete"] == 1

    calls = []
    hs.simulate(scene, progress=lambda i, n: calls.append((i, n)))  # the callable of 0.1 still works
    assert calls[-1] == (2020, 2020) and all(n == 2020 for _, n in calls)

    bad = [
        (lambda: hs.Material(E=-1, nu=0.3), "material.E: must be > 0, got -1"),
        (lambda: hs.Material(E="200 GPa", nu=0.3), "material.E: '200 GPa' carries a unit"),
        (lambda: hs.Material(E=2e11, nu=0.5), "material.nu: Poisson's ratio must lie in (-1, 0.5)"),
        (lambda: hs.Material(E=2e11, nu=True), "material.nu: expected a number"),
        (lambda: hs.Hertz(radius=0.0), "geometry.radius: must be > 0"),
        (lambda: hs.RoundedPunch(flat_half_width=-1e-3, radius=0.01), "geometry.flat_half_width: must be >= 0"),
        (lambda: hs.SolverOptions(method="fast"), "solver.method"),
        (lambda: hs.OutputOptions(every=0), "output.every: must be an integer >= 1"),
        (lambda: dataclasses.replace(scene, friction="0.6"), "friction: expected a number"),
        (lambda: dataclasses.replace(scene, profile="hertz"), "geometry: expected a geometry profile"),
    ]
    for make, message in bad:
        with pytest.raises(hs.HalfslipInputError) as caught:
            make()
        assert str(caught.value).startswith(message), str(caught.value)
    # the same values in YAML give the same error
    with pytest.raises(hs.HalfslipInputError, match="material.E: must be > 0, got -1"):
        hs.parse_scene(GROSS.replace("E: 2.0e11", "E: -1"))


def test_the_progress_total_drops_by_the_skipped_cycles_and_does_not_jump():
    stream = io.StringIO()
    seen = []

    class Watch(Progress):
        def advance(self, done=1, skipped=0):
            super().advance(done, skipped)
            seen.append((self.bar.n, self.bar.total))

    hs.simulate(hs.load_scene(HERTZ), progress=Watch(file=stream))
    marched = [n for n, _ in seen]
    assert np.all(np.diff(marched) == 1)  # one step at a time, no jump to the end
    assert seen[0][1] == 2020 and seen[-1] == (220, 220)  # 18 cycles of 100 steps taken off the total


# -- messages as data ------------------------------------------------------------


def test_messages_are_stored_with_step_time_kind_and_value(tmp_path):
    for method in ("exact", "general"):
        scene = hs.parse_scene(GROSS)
        scene = dataclasses.replace(scene, solver=dataclasses.replace(scene.solver, nodes=64))
        ds = hs.simulate(scene, method=method)
        kinds = ds["message_kind"].values
        assert set(kinds) == {"gross_sliding"}, kinds
        assert ds["message_step"].dims == ("message",) and ds["message_step"].dtype == np.int64
        steps, t = ds["message_step"].values, ds["message_t"].values
        np.testing.assert_array_equal(t, scene.history.t[steps])
        Q, P = scene.history.Q[steps], scene.history.P[steps]
        np.testing.assert_allclose(ds["message_value"].values, np.abs(Q) / (0.5 * P), rtol=1e-12)
        assert (ds["message_value"].values > 1).all()
        assert int(ds["message_count"].values[0]) == len(steps)  # fewer than the cap: all kept
        assert ds["message_t"].attrs["units"] == "s"
    write_result(ds, tmp_path / "gross.h5")
    back = read_result(tmp_path / "gross.h5")
    assert list(back["message_kind"].values) == list(kinds)
    assert back.attrs["messages"] == "abs(Q) > f P: gross sliding, shear force carried limited to f P"


def test_the_message_log_keeps_the_first_and_the_worst_and_counts_all():
    from halfslip.messages import MAX_RECORDS_PER_KIND, MessageLog, classify

    log = MessageLog()
    for step in range(1000):
        log.add(step, 0.1 * step, "slip_solve_closest", 2.0 + (step == 700) * 50.0, "kept the closest")
    log.add(5, 0.5, "slip_zone_resolution", 6.0, "narrow")
    kept = [r for r in log.records if r[2] == "slip_solve_closest"]
    assert len(kept) == MAX_RECORDS_PER_KIND and kept[0][0] == 0
    assert max(kept, key=lambda r: r[3])[0] == 700 and log.counts["slip_solve_closest"] == 1000
    # a step taken in halves joins two messages with "; ": two records
    two = classify("separated (P <= 0): shear force Q = -300 N/m not carried; "
                   "slip solve: no slip-zone configuration met the Coulomb and slip-direction checks; "
                   "kept the closest (violation 20 x tolerance)")
    assert [(k, v) for k, v, _ in two] == [("separated_shear", 300.0), ("slip_solve_closest", 20.0)]


def test_the_run_summary_groups_messages_by_kind_with_first_and_worst_step(tmp_path):
    scene = tmp_path / "gross.yaml"
    scene.write_text(GROSS)
    result = cli("run", scene, "-o", tmp_path / "gross.h5")
    assert result.exit_code == 0, result.output
    notes = [line for line in result.stdout.splitlines() if "note:" in line]
    assert len(notes) == 1, result.stdout
    assert notes[0].startswith("  note: gross_sliding x ") and "first at step " in notes[0]
    assert "worst at step " in notes[0] and "abs(Q)/(f P) = 1.2)" in notes[0]
    assert len(notes[0]) < 250


def test_files_of_0_1_are_read_with_rigid_shift(tmp_path):
    ds = hs.simulate(hs.load_scene(HERTZ))
    assert "rigid_shift" in ds and "shift" not in ds.data_vars
    assert float(ds.rigid_shift.sel(t=1.25)) == float(ds["rigid_shift"].values[ds.t.values == 1.25][0])
    old = ds.rename_vars(rigid_shift="shift")
    write_result(old, tmp_path / "old.h5")
    back = read_result(tmp_path / "old.h5")
    assert "rigid_shift" in back.data_vars and "shift" not in back.data_vars
    np.testing.assert_array_equal(back["rigid_shift"].values, ds["rigid_shift"].values)
    assert hs.post.hysteresis_loops(back)["shift"].attrs["units"] == "m"


# -- CF ------------------------------------------------------------------------


def test_result_files_carry_the_cf_attributes(tmp_path):
    ds = hs.simulate(hs.load_scene(HERTZ))
    assert ds.attrs["Conventions"] == "CF-1.10"
    assert ds["t"].attrs["axis"] == "T" and ds["x"].attrs["axis"] == "X"
    write_result(ds, tmp_path / "run.h5")
    write_result(hs.steady_state(hs.load_scene(HERTZ)), tmp_path / "steady.h5")
    with h5py.File(tmp_path / "run.h5") as f:
        assert f.attrs["Conventions"] in ("CF-1.10", b"CF-1.10")
        for name, axis in (("t", "T"), ("x", "X")):
            assert f[name].attrs["axis"] in (axis, axis.encode())
            assert "_FillValue" not in f[name].attrs, name
        assert "_FillValue" in f["stick_left"].attrs  # data variables keep theirs (NaN: nothing sticks)
    with h5py.File(tmp_path / "steady.h5") as f:
        assert f.attrs["Conventions"] in ("CF-1.10", b"CF-1.10")


# -- the command line ----------------------------------------------------------


def test_quiet_silences_every_command_that_prints(tmp_path):
    out, steady = tmp_path / "run.h5", tmp_path / "steady.h5"
    runs = {
        "validate": ("validate", HERTZ),
        "run": ("run", HERTZ, "-o", out),
        "steady": ("steady", HERTZ, "-o", steady),
        "plot": ("plot", steady, "-o", tmp_path / "figures"),
    }
    for name, args in runs.items():
        loud = cli(*args)
        assert loud.exit_code == 0 and loud.stdout.strip(), (name, loud.output)
        quiet = cli(*args, "--quiet")
        assert quiet.exit_code == 0, (name, quiet.output)
        assert quiet.stdout == "" and quiet.stderr == "", (name, quiet.output)
    warned = tmp_path / "gross.yaml"
    warned.write_text(GROSS)
    quiet = cli("validate", warned, "--quiet")  # warnings still go to stderr
    assert quiet.stdout == "" and quiet.stderr.startswith("halfslip: warning: |Q| > fP")


def test_summaries_give_lengths_and_energies_with_si_prefixes(tmp_path):
    run = cli("run", HERTZ, "-o", tmp_path / "run.h5")
    assert "final contact [-240.7, 240.7] µm, stick zone [-221.9, 221.9] µm" in run.stdout
    assert "dissipation per cycle 222.2 µJ/m (last full cycle), first cycle 179.4 µJ/m" in run.stdout
    steady = cli("steady", HERTZ)
    assert "permanent stick zone   [-201.4, 201.4] µm" in steady.stdout
    assert "peak slip amplitude    40.56 nm" in steady.stdout
    assert "e-0" not in run.stdout + steady.stdout


def test_help_has_no_markup_and_file_arguments_complete_as_files():
    import click

    for command in main.commands.values():
        text = cli(*([command.name] if command.name != "main" else []), "--help").stdout
        assert "``" not in text, command.name
        files = [p for p in command.params if isinstance(p, click.Argument)]
        assert all(isinstance(p.type, click.Path) for p in files), command.name
    missing = cli("run", "nothere.yaml")
    assert missing.exit_code == 2 and missing.stderr == "halfslip: nothere.yaml: no such file\n"


def test_steady_warnings_go_to_stderr(tmp_path, monkeypatch):
    import xarray as xr

    from halfslip import cli as cli_module

    def fake(scene, segment=None):
        return xr.Dataset({"permanent_stick_left": -1e-4, "permanent_stick_right": 1e-4, "regime": np.int8(2)},
                          attrs={"method": "SS1", "note": "permanent stick zone from (SS1)",
                                 "warning": "the tension range is not moderate"})

    monkeypatch.setattr("halfslip.steady.steady_state", fake)
    result = cli("steady", HERTZ)
    assert result.exit_code == 0, result.output
    assert "warning" not in result.stdout
    assert result.stderr == "halfslip: warning: the tension range is not moderate\n"
    assert cli_module  # the command imports steady_state from halfslip.steady when it runs


def test_the_first_general_run_says_it_compiles(tmp_path, monkeypatch):
    """A general run whose compiled kernels are not in numba's cache yet (the first after installing: about
    20 s of compilation with no progress) says so on stderr, once, before marching; a cached one, an exact
    run or --quiet do not. What the note reads (numba's cache index) agrees with numba: after a general run
    in this process the active set is cached."""
    import halfslip.solvers._toeplitz as kernel

    scene = tmp_path / "general.yaml"
    scene.write_text(GROSS.replace("cycles: {count: 4", "cycles: {count: 1").replace(
        "loads:\n", "loads:\n  - ramp: {to: {P: 5.0e4, sigma: 1.0e7}, duration: 1.0, steps: 2}\n"))
    note = "halfslip: note: compiling the general solver's kernels"
    monkeypatch.setattr(kernel, "compiled_and_cached", lambda: False)
    first = cli("run", scene, "-o", tmp_path / "a.h5")
    assert first.exit_code == 0, first.output
    assert first.stderr.count(note) == 1 and first.stdout.strip()
    for args in (("run", scene, "-o", tmp_path / "b.h5", "--quiet"), ("run", HERTZ, "-o", tmp_path / "c.h5")):
        assert note not in cli(*args).stderr
    sweep = tmp_path / "sweep.yaml"  # a sweep's workers would compile at once: said before they start
    sweep.write_text(f"scene: {scene.name}\nvary:\n  friction: [0.5, 0.6]\n")
    swept = cli("sweep", sweep, "-o", tmp_path / "sweep.h5", "--workers", 1)
    assert swept.exit_code == 0 and swept.stderr.count(note) == 1, swept.output
    monkeypatch.undo()
    assert kernel.compiled_and_cached()
    assert note not in cli("run", scene, "-o", tmp_path / "d.h5").stderr
