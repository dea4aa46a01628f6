"""The result carries its own structure (issue 15).

A scene built in Python and the same scene read from YAML give the same
result, the same analyses and the same figures; every stored time is the
time of a marched step, and skipped cycles are data whose final state and
energy are those of a run that marches every cycle.
"""
from __future__ import annotations

import dataclasses

import matplotlib
import numpy as np
import pytest
import xarray as xr

matplotlib.use("Agg")

import halfslip as hs  # noqa: E402
from halfslip import plot, post  # noqa: E402
from helpers import hertz_pad_segments, hertz_pad_text  # noqa: E402

# hertz_pad with a hold after the cycles (the march goes on after a skip) and a moderate resolution
EXTRA_HOLD = [{"hold": {"duration": 0.5, "steps": 5}}]
YAML = hertz_pad_text(count=8, steps=40) + "  - hold: {duration: 0.5, steps: 5}\noutput: {points: 41}\n"
NOT_THE_SAME = {"scene", "scene_sha256", "wall_time"}
"""What may differ between the two: the scene text (none for a Python scene), its hash, the run time."""


def python_scene(yaml_scene):
    """The same scene, built from Python objects (no text, no file)."""
    history = hs.LoadHistory.from_segments(hertz_pad_segments(count=8, steps=40) + EXTRA_HOLD)
    return hs.Scene(name=yaml_scene.name, material=yaml_scene.material, friction=yaml_scene.friction,
                    profile=yaml_scene.profile, history=history,
                    output=dataclasses.replace(yaml_scene.output))


@pytest.fixture(scope="module")
def pair():
    from_yaml = hs.parse_scene(YAML)
    from_python = python_scene(from_yaml)
    assert from_python.text is None
    return hs.simulate(from_yaml), hs.simulate(from_python)


def without_run_attrs(ds: xr.Dataset) -> xr.Dataset:
    out = ds.copy()
    out.attrs = {k: v for k, v in ds.attrs.items() if k not in NOT_THE_SAME}
    return out


def same(a, b) -> None:
    if isinstance(a, xr.Dataset):
        xr.testing.assert_identical(without_run_attrs(a), without_run_attrs(b))
    elif isinstance(a, xr.DataArray):
        xr.testing.assert_identical(a, b)
    else:
        np.testing.assert_array_equal(a, b)


def test_python_and_yaml_scenes_give_the_same_result(pair):
    from_yaml, from_python = pair
    assert int(from_yaml.attrs["skipped_cycles"]) > 0  # the pair exercises skipped cycles
    assert "permanent_stick_left" in from_python  # simulate found the cycles of the Python scene
    same(from_yaml, from_python)


ACCESSOR_CALLS = {
    "check": (),
    "cycles": (),
    "select_cycle": (),
    "slip_amplitude": (),
    "dissipation_per_cycle": (),
    "surface_stress": (),
    "ruiz": (),
    "hysteresis_loops": (),
    "permanent_stick": (),
    "loop_tangent_point": (),
    "stress_range": (),
    "kind": (),
}


def test_every_accessor_method_is_listed_here():
    public = {name for name in dir(post.HalfslipAccessor) if not name.startswith("_")}
    assert public == set(ACCESSOR_CALLS)


@pytest.mark.parametrize("method", sorted(ACCESSOR_CALLS))
def test_every_accessor_method_gives_the_same_numbers(pair, method):
    from_yaml, from_python = pair
    a = getattr(from_yaml.halfslip, method)(*ACCESSOR_CALLS[method])
    b = getattr(from_python.halfslip, method)(*ACCESSOR_CALLS[method])
    same(a, b)
    if method == "cycles":
        assert a.sizes["cycle"] >= 2 and int(a.repeats[-1]) > 1


def numbers(values) -> list:
    """Nested lists of floats with NaN as text, so that == compares them (NaN != NaN)."""
    return [repr(v) for v in np.asarray(values, float).ravel()] + [repr(np.shape(values))]


def figure_numbers(fig) -> list:
    """Everything a figure draws, as numbers and text: lines, patches, collections, texts, limits, ticks."""
    out = []
    for ax in fig.axes:
        out.append(("limits", ax.get_xlim(), ax.get_ylim()))
        out.append(("ticks", tuple(ax.get_xticks()), tuple(t.get_text() for t in ax.get_xticklabels())))
        for line in ax.get_lines():
            out.append(("line", numbers(line.get_xydata())))
        for patch in ax.patches:
            out.append(("patch", numbers(patch.get_path().vertices)))
        for collection in ax.collections:
            out.append(("collection", [numbers(p.vertices) for p in collection.get_paths()],
                        numbers(collection.get_offsets())))
        for image in ax.images:
            out.append(("image", numbers(image.get_array())))
        for text in ax.texts:
            out.append(("text", text.get_text(), tuple(text.get_position())))
        out.append(("title", ax.get_title(), ax.get_xlabel(), ax.get_ylabel()))
    return out


@pytest.mark.parametrize("kind", plot.KINDS)
def test_every_figure_kind_draws_the_same_numbers(pair, kind):
    from_yaml, from_python = pair
    a, b = plot.figure(from_yaml, kind), plot.figure(from_python, kind)
    try:
        drawn = figure_numbers(a)
        assert drawn == figure_numbers(b)
        assert any(item[0] == "line" and len(item[1]) > 1 for item in drawn)  # it drew something
    finally:
        import matplotlib.pyplot as plt

        plt.close(a)
        plt.close(b)


# ---------------------------------------------------------------------------
# the time axis


@pytest.fixture(scope="module")
def skipped_and_full():
    scene = hs.parse_scene(YAML)
    full_scene = dataclasses.replace(scene, solver=dataclasses.replace(scene.solver, skip_steady_cycles=False))
    return scene, hs.simulate(scene), hs.simulate(full_scene)


def test_every_stored_time_is_the_time_of_a_marched_step(skipped_and_full):
    scene, skipped, full = skipped_and_full
    h = scene.history
    step = skipped["step"].values
    assert np.all(np.diff(step) > 0)
    np.testing.assert_array_equal(skipped["t"].values, h.t[step])  # each stored t is its step's time
    cyc = int(np.flatnonzero(skipped.segment_kind.values == 2)[0])
    k = int(skipped.segment_cycles_skipped[cyc])
    t_from, t_to = float(skipped.segment_skip_t_start[cyc]), float(skipped.segment_t_stop[cyc])
    assert k > 0 and k == skipped.attrs["skipped_cycles"]
    # no stored step inside the skipped stretch; the skip starts at a stored (marched) step
    t = skipped["t"].values
    assert not np.any((t > t_from) & (t <= t_to))
    assert t_from in t
    # every stored step was marched: the fully marched run stored the same state at the same step
    rows = np.searchsorted(full["step"].values, step)
    np.testing.assert_array_equal(full["step"].values[rows], step)
    before = t <= t_from
    for name in ("P", "Q", "contact_left", "stick_left", "stick_right", "rigid_shift", "dissipation", "slip"):
        np.testing.assert_array_equal(skipped[name].values[before], full[name].values[rows][before], err_msg=name)
    # marched steps = all steps less the skipped cycles
    spc = int(skipped.segment_steps_per_cycle[cyc])
    assert skipped.attrs["count_steps"] == full.attrs["count_steps"] - k * spc


def test_skipped_cycles_are_data_and_the_final_state_is_exact(skipped_and_full):
    scene, skipped, full = skipped_and_full
    cyc = int(np.flatnonzero(skipped.segment_kind.values == 2)[0])
    k = int(skipped.segment_cycles_skipped[cyc])
    t_from = float(skipped.segment_skip_t_start[cyc])
    # the skipped energy is k times the last marched cycle's
    last = post.dissipation_per_cycle(skipped).dissipation.values[-1]
    assert float(skipped.segment_skip_dissipation[cyc]) == pytest.approx(k * last, rel=1e-12)
    assert float(skipped.dissipation.sel(t=t_from)) + float(skipped.segment_skip_dissipation[cyc]) == pytest.approx(
        float(full.dissipation.sel(t=float(skipped.segment_t_stop[cyc]))), rel=1e-12)
    # the final state: time and energy of the fully marched run's end, the same stick and contact
    assert float(skipped.final_t) == float(full.t[-1]) == float(full.final_t)
    assert float(skipped.final_dissipation) == pytest.approx(float(full.dissipation[-1]), rel=1e-12)
    assert float(full.final_dissipation) == float(full.dissipation[-1])
    for name in ("contact_left", "contact_right", "stick_left", "stick_right", "rigid_shift", "dissipation"):
        assert float(skipped[name][-1]) == pytest.approx(float(full[name][-1]), rel=1e-12, abs=1e-18), name
    # after the skip the march goes on (the hold) from the repeated state: the same stored steps as marching all
    tail = skipped["step"].values > int(skipped.segment_last_step[cyc])
    assert tail.sum() == 5
    # the analyses agree: last cycle's permanent stick zone and energy (the instants that set the zone's
    # ends at the same phase of their cycles, the skipped cycles apart)
    zone_skipped, zone_full = post.permanent_stick(skipped), post.permanent_stick(full)
    for name in ("left", "right", "half_width", "left_error", "right_error"):
        assert float(zone_skipped[name]) == pytest.approx(float(zone_full[name]), rel=1e-12), name
    period = float(skipped.segment_period[cyc])
    for name in ("t_left", "t_right"):
        assert float(zone_full[name]) - float(zone_skipped[name]) == pytest.approx(k * period, rel=1e-12), name
    assert last == pytest.approx(float(post.dissipation_per_cycle(full).dissipation[-1]), rel=1e-9)


def test_a_time_inside_skipped_cycles_picks_the_same_phase_of_the_last_marched_cycle(skipped_and_full):
    _scene, skipped, _full = skipped_and_full
    from halfslip.cycles import read_segments

    segments = read_segments(skipped)
    cyc = segments.cycles()[0]
    t_from, period = float(segments.skip_t_start[cyc]), float(segments.period[cyc])
    assert segments.marched_time(t_from + 2 * period + 0.25 * period) == pytest.approx(t_from - 0.75 * period)
    assert segments.marched_time(float(segments.t_stop[cyc])) == t_from
    assert segments.marched_time(0.5) == 0.5


def test_a_result_without_a_segment_table_is_refused_in_one_line(skipped_and_full):
    _scene, skipped, _full = skipped_and_full
    old = skipped.drop_vars([name for name in skipped.variables if name.startswith("segment_")])
    with pytest.raises(hs.HalfslipInputError, match="no segment table") as caught:
        post.cycles(old)
    assert "\n" not in str(caught.value)


@pytest.mark.parametrize("stop_after", [60, -2])  # before the skip (mid-cycles), after it (in the hold)
def test_an_interrupted_run_with_skipped_cycles_resumes_to_the_same_file(tmp_path, stop_after):
    """The skipper's state is part of the checkpointed run state: written, read back, continued."""
    from halfslip.io import read_checkpoint, read_result, write_run

    scene = hs.parse_scene(YAML)
    whole = hs.simulate(scene)
    if stop_after < 0:
        stop_after += int(whole.attrs["count_steps"])
        assert stop_after > int(whole.segment_last_step[1]) - int(whole.segment_cycles_skipped[1]) * 40
    polls = iter(range(10**9))
    path = tmp_path / "run.h5"

    class Writer:
        def due(self):
            return False

        def write(self, ds, checkpoint=None):
            write_run(ds, path, checkpoint)

    partial = hs.simulate(scene, writer=Writer(), stop_requested=lambda: next(polls) >= stop_after)
    assert partial.attrs["complete"] == 0
    resumed = hs.simulate(scene, resume=(read_result(path), read_checkpoint(path)))
    ignore = {"wall_time"}
    a, b = resumed.copy(), whole.copy()
    a.attrs = {k: v for k, v in a.attrs.items() if k not in ignore}
    b.attrs = {k: v for k, v in b.attrs.items() if k not in ignore}
    xr.testing.assert_identical(a, b)


def test_a_checkpoint_whose_skipper_state_does_not_fit_is_refused(tmp_path):
    from halfslip.io import read_checkpoint, read_result, write_run

    scene = hs.parse_scene(YAML)
    path = tmp_path / "run.h5"
    polls = iter(range(10**9))

    class Writer:
        def due(self):
            return False

        def write(self, ds, checkpoint=None):
            write_run(ds, path, checkpoint)

    hs.simulate(scene, writer=Writer(), stop_requested=lambda: next(polls) >= 100)
    ds, checkpoint = read_result(path), read_checkpoint(path)
    assert checkpoint["skipper"]["previous"]  # a cycle end was seen: there is a state to tamper with
    for tampered in ({**checkpoint["skipper"], "previous": {99: checkpoint["state"]}},
                     {**checkpoint["skipper"], "previous": {1: 1.5}},
                     {**checkpoint["skipper"], "skipped": [1, 2]}):
        with pytest.raises(hs.HalfslipInputError, match="checkpoint does not fit"):
            hs.simulate(scene, resume=(ds, {**checkpoint, "skipper": tampered}))
    assert hs.simulate(scene, resume=(ds, checkpoint)).attrs["complete"] == 1
