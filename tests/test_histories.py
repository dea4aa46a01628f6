"""Load histories: segment kinds, chaining, evaluate, tables."""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from halfslip import HalfslipInputError, LoadHistory, Segment
from halfslip.histories import LOADS


def ramp(duration=1.0, steps=1, **to):
    return {"ramp": {"to": to, "duration": duration, "steps": steps}}


def test_ramp_is_a_straight_line_to_the_target():
    history = LoadHistory.from_segments([ramp(duration=2.0, steps=4, P=1.0e5, Q=2.0e4)])
    np.testing.assert_allclose(history.t, [0.0, 0.5, 1.0, 1.5, 2.0])
    np.testing.assert_allclose(history.P, [0.0, 2.5e4, 5.0e4, 7.5e4, 1.0e5])
    np.testing.assert_allclose(history.Q, [0.0, 5.0e3, 1.0e4, 1.5e4, 2.0e4])
    assert history.P[-1] == 1.0e5 and history.Q[-1] == 2.0e4  # the target exactly
    assert not history.M.any() and not history.sigma.any()
    assert history.n_steps == 4
    np.testing.assert_array_equal(history.step_times, history.t[1:])
    (segment,) = history.segments
    assert (segment.kind, segment.start, segment.stop, segment.steps) == ("ramp", 0, 4, 4)
    assert (segment.t_start, segment.t_stop) == (0.0, 2.0)


def test_ramp_defaults_to_one_step_and_unnamed_loads_hold():
    history = LoadHistory.from_segments(
        [ramp(P=1.0e5, M=3.0), {"ramp": {"to": {"Q": 1.0e4}, "duration": 1.0}}]
    )
    assert history.n_steps == 2
    np.testing.assert_array_equal(history.P, [0.0, 1.0e5, 1.0e5])
    np.testing.assert_array_equal(history.M, [0.0, 3.0, 3.0])
    np.testing.assert_array_equal(history.Q, [0.0, 0.0, 1.0e4])


def test_hold_keeps_every_load():
    history = LoadHistory.from_segments(
        [ramp(P=1.0e5, Q=1.0e4, M=2.0, sigma=1.0e7), {"hold": {"duration": 3.0, "steps": 3}}]
    )
    np.testing.assert_allclose(history.t, [0.0, 1.0, 2.0, 3.0, 4.0])
    for name, value in {"P": 1.0e5, "Q": 1.0e4, "M": 2.0, "sigma": 1.0e7}.items():
        np.testing.assert_array_equal(getattr(history, name)[1:], value)
    assert history.segments[1].kind == "hold"


def test_cycles_follow_the_harmonic_with_phase_and_mean():
    history = LoadHistory.from_segments(
        [
            ramp(P=1.0e5),
            {
                "cycles": {
                    "count": 3,
                    "period": 0.5,
                    "steps_per_cycle": 8,
                    "P": {"amplitude": 1.0e4},  # mean: the current 1e5
                    "Q": {"mean": 2.0e3, "amplitude": 3.0e4, "phase": 90.0},
                    "sigma": {"amplitude": 1.0e7, "phase": -30.0},
                }
            },
        ]
    )
    cycles = history.segments[1]
    assert (cycles.kind, cycles.count, cycles.period, cycles.steps_per_cycle) == ("cycles", 3, 0.5, 8)
    assert (cycles.start, cycles.stop, cycles.t_start) == (1, 25, 1.0)
    assert cycles.t_stop == pytest.approx(2.5)
    inside = slice(cycles.start + 1, cycles.stop + 1)
    tau = (history.t[inside] - 1.0) / 0.5
    np.testing.assert_allclose(history.P[inside], 1.0e5 + 1.0e4 * np.sin(2 * np.pi * tau), rtol=1e-12)
    np.testing.assert_allclose(history.Q[inside], 2.0e3 + 3.0e4 * np.cos(2 * np.pi * tau), rtol=1e-12, atol=1e-8)
    np.testing.assert_allclose(
        history.sigma[inside], 1.0e7 * np.sin(2 * np.pi * tau - math.pi / 6), rtol=1e-12, atol=1e-5
    )
    np.testing.assert_array_equal(history.M, 0.0)
    # every cycle is sampled at bit-identical values
    for name in LOADS:
        samples = getattr(history, name)[cycles.start + 1 : cycles.stop + 1].reshape(3, 8)
        assert (samples == samples[0]).all()
    # the harmonics are kept for a steady-state solver
    assert cycles.harmonics["Q"].mean == 2.0e3
    assert cycles.harmonics["Q"].amplitude == 3.0e4
    assert cycles.harmonics["Q"].phase == pytest.approx(math.pi / 2)
    assert cycles.harmonics["M"].amplitude == 0.0
    # Q starts at 2e3 + 3e4 on the harmonic and sigma at 1e7 sin(-30 deg), both
    # from 0 in the history: jumps, bridged by the first step
    jumps = history.jumps()
    assert [(jump.segment, jump.load, jump.before, jump.t) for jump in jumps] == [
        (1, "Q", 0.0, 1.0),
        (1, "sigma", 0.0, 1.0),
    ]
    assert [jump.after for jump in jumps] == pytest.approx([3.2e4, -5.0e6])


def test_cycles_about_the_current_value_start_without_a_jump():
    history = LoadHistory.from_segments(
        [ramp(P=1.0e5), {"cycles": {"count": 2, "period": 1.0, "Q": {"amplitude": 1.0e4}}}]
    )
    assert history.jumps() == ()
    assert history.segments[1].steps_per_cycle == 64
    assert history.n_steps == 1 + 128
    assert history.Q[-1] == 0.0 and history.P[-1] == 1.0e5


def test_inline_table_offsets_from_the_segment_start_and_absent_columns_hold():
    history = LoadHistory.from_segments(
        [
            ramp(duration=2.0, P=1.0e5, M=1.0),
            {"table": {"t": [0.5, 1.0, 3.0], "Q": [1.0e3, -2.0e3, 0.0], "P": [1.1e5, 1.2e5, 1.0e5]}},
        ]
    )
    np.testing.assert_array_equal(history.t, [0.0, 2.0, 2.5, 3.0, 5.0])
    np.testing.assert_array_equal(history.Q, [0.0, 0.0, 1.0e3, -2.0e3, 0.0])
    np.testing.assert_array_equal(history.P, [0.0, 1.0e5, 1.1e5, 1.2e5, 1.0e5])
    np.testing.assert_array_equal(history.M, [0.0, 1.0, 1.0, 1.0, 1.0])
    assert history.segments[1].kind == "table" and history.segments[1].source is None


def test_table_row_at_offset_zero_must_repeat_the_current_values():
    start = ramp(P=1.0e5)
    history = LoadHistory.from_segments([start, {"table": {"t": [0.0, 1.0], "P": [1.0e5, 5.0e4]}}])
    np.testing.assert_array_equal(history.t, [0.0, 1.0, 2.0])  # the repeated row is dropped
    with pytest.raises(HalfslipInputError) as error:
        LoadHistory.from_segments([start, {"table": {"t": [0.0, 1.0], "P": [9.0e4, 5.0e4]}}])
    assert error.value.field == "loads[1].table.P[0]"
    assert "must equal the current P" in error.value.message


def test_table_from_csv_round_trips(tmp_path):
    rng = np.random.default_rng(7)
    t = np.cumsum(rng.uniform(0.01, 0.1, 40))
    columns = {"t": t, "P": rng.uniform(5.0e4, 1.5e5, 40), "sigma": rng.normal(0.0, 1.0e7, 40)}
    lines = ["# written by the test", ",".join(columns)]
    lines += [",".join(repr(float(value)) for value in row) for row in zip(*columns.values())]
    (tmp_path / "loads.csv").write_text("\n".join(lines) + "\n")

    history = LoadHistory.from_segments(
        [ramp(P=1.0e5, Q=5.0e3), {"table": {"file": "loads.csv"}}], base_dir=tmp_path
    )
    table = history.segments[1]
    assert table.source == str(tmp_path / "loads.csv")
    assert (table.start, table.stop) == (1, 41)
    np.testing.assert_array_equal(history.t[2:], 1.0 + t)
    np.testing.assert_array_equal(history.P[2:], columns["P"])
    np.testing.assert_array_equal(history.sigma[2:], columns["sigma"])
    np.testing.assert_array_equal(history.Q[1:], 5.0e3)  # no Q column: Q holds


@pytest.mark.parametrize(
    ("text", "line", "field", "words"),
    [
        ("t,Q\n0.1,1\n0.2\n", 3, "loads[0].table", "row has 1 values"),
        ("t,Q\n0.1,1\n0.2,2 kN\n", 3, "loads[0].table.Q", "without a unit"),
        ("t,Q\n\n# note\n0.1,1\n0.2,nan\n", 5, "loads[0].table.Q", "finite"),
        ("t,Q\n0.2,1\n0.1,2\n", 3, "loads[0].table.t", "increase strictly"),
        ("t,Qx\n0.1,1\n", 1, "loads[0].table", "did you mean 'Q'"),
        ("P,Q\n1,1\n", 1, "loads[0].table", "no column 't'"),
        ("t,Q\n", 1, "loads[0].table", "no rows"),
        ("", 1, "loads[0].table", "empty table"),
        ("t,Q\n-0.1,1\n", 2, "loads[0].table.t", ">= 0"),
    ],
)
def test_csv_errors_name_the_file_line_and_column(tmp_path, text, line, field, words):
    (tmp_path / "bad.csv").write_text(text)
    with pytest.raises(HalfslipInputError) as error:
        LoadHistory.from_segments([{"table": {"file": "bad.csv"}}], base_dir=tmp_path)
    assert (error.value.file, error.value.line, error.value.field) == (str(tmp_path / "bad.csv"), line, field)
    assert words in error.value.message


def test_missing_csv_names_the_file_field(tmp_path):
    with pytest.raises(HalfslipInputError) as error:
        LoadHistory.from_segments([{"table": {"file": "nowhere.csv"}}], base_dir=tmp_path)
    assert error.value.field == "loads[0].table.file"
    assert "nowhere.csv" in error.value.message and error.value.line is None


def test_segments_chain_each_starting_where_the_last_ended():
    history = LoadHistory.from_segments(
        [
            ramp(duration=1.0, steps=5, P=1.0e5),
            {"hold": {"duration": 0.5, "steps": 2}},
            {"cycles": {"count": 2, "period": 1.0, "steps_per_cycle": 10, "Q": {"amplitude": 2.0e4}}},
            {"table": {"t": [0.5, 1.0], "Q": [1.0e4, 0.0]}},
            ramp(duration=1.0, steps=4, P=0.0),
        ]
    )
    segments = history.segments
    assert segments[0].start == 0 and segments[-1].stop == history.n_steps
    for before, after in zip(segments, segments[1:]):
        assert after.start == before.stop
        assert after.t_start == before.t_stop == history.t[before.stop]
    assert [segment.steps for segment in segments] == [5, 2, 20, 2, 4]
    assert np.all(np.diff(history.t) > 0)
    assert history.t[-1] == pytest.approx(1.0 + 0.5 + 2.0 + 1.0 + 1.0)
    assert history.P[-1] == 0.0


def test_evaluate_matches_the_samples_and_the_exact_segment_functions():
    history = LoadHistory.from_segments(
        [
            ramp(duration=1.0, steps=4, P=1.0e5, M=2.0),
            {
                "cycles": {
                    "count": 2,
                    "period": 1.0,
                    "steps_per_cycle": 16,
                    "Q": {"mean": 0.0, "amplitude": 2.0e4, "phase": 90.0},  # jumps from 0 to 2e4
                    "sigma": {"amplitude": 1.0e7},
                }
            },
            {"table": {"t": [1.0, 2.0], "P": [5.0e4, 8.0e4]}},
        ]
    )
    at_steps = history.evaluate(history.step_times)
    for name in LOADS:
        scale = np.max(np.abs(getattr(history, name))) + 1.0
        np.testing.assert_allclose(at_steps[name], getattr(history, name)[1:], rtol=0, atol=1e-12 * scale)
    # ramp and table: straight lines between samples
    assert history.evaluate(0.1)["P"] == pytest.approx(1.0e4)
    assert history.evaluate(3.5)["P"] == pytest.approx(0.5 * (1.0e5 + 5.0e4))
    assert history.evaluate(4.5)["P"] == pytest.approx(6.5e4)
    # cycles: the harmonic itself between the samples, not a chord
    t = np.array([1.3, 1.71, 2.9])
    values = history.evaluate(t)
    np.testing.assert_allclose(values["sigma"], 1.0e7 * np.sin(2 * np.pi * (t - 1.0)))
    np.testing.assert_allclose(values["Q"], 2.0e4 * np.cos(2 * np.pi * (t - 1.0)))
    # the jump of Q is bridged by a straight line over the first step
    first_step = 1.0 + 1.0 / 16
    assert history.evaluate(1.0 + 0.5 / 16)["Q"] == pytest.approx(0.5 * history.Q[history.segments[1].start + 1])
    assert history.evaluate(first_step)["Q"] == pytest.approx(2.0e4 * np.cos(2 * np.pi / 16))
    # shapes follow the input; times outside the history are refused
    assert history.evaluate(np.zeros((2, 3)))["P"].shape == (2, 3)
    with pytest.raises(ValueError):
        history.evaluate(history.duration + 1.0)


def test_from_arrays_prepends_the_unloaded_state():
    history = LoadHistory.from_arrays([0.5, 1.0, 2.0], [1.0e5, 1.2e5, 1.0e5], [0.0, 1.0e4, -1.0e4])
    np.testing.assert_array_equal(history.t, [0.0, 0.5, 1.0, 2.0])
    np.testing.assert_array_equal(history.P, [0.0, 1.0e5, 1.2e5, 1.0e5])
    np.testing.assert_array_equal(history.M, 0.0)
    assert [segment.kind for segment in history.segments] == ["arrays"]

    from_zero = LoadHistory.from_arrays([0.0, 1.0], [0.0, 1.0e5], [0.0, 0.0], M=[0.0, 1.0], sigma=[0.0, 2.0])
    np.testing.assert_array_equal(from_zero.t, [0.0, 1.0])
    np.testing.assert_array_equal(from_zero.sigma, [0.0, 2.0])


@pytest.mark.parametrize(
    ("arrays", "field"),
    [
        ({"t": [0.0, 1.0], "P": [1.0, 2.0], "Q": [0.0, 0.0]}, "P[0]"),  # t = 0 must be unloaded
        ({"t": [1.0, 1.0], "P": [1.0, 2.0], "Q": [0.0, 0.0]}, "t[1]"),
        ({"t": [1.0, 2.0], "P": [1.0], "Q": [0.0, 0.0]}, "P"),
        ({"t": [1.0, 2.0], "P": [1.0, np.inf], "Q": [0.0, 0.0]}, "P[1]"),
        ({"t": [], "P": [], "Q": []}, "t"),
    ],
)
def test_from_arrays_rejects_bad_arrays(arrays, field):
    with pytest.raises(HalfslipInputError) as error:
        LoadHistory.from_arrays(**arrays)
    assert error.value.field == field


@pytest.mark.parametrize(
    ("segments", "field"),
    [
        ([{"ramp": {"to": {"P": 1.0}}}], "loads[0].ramp.duration"),
        ([{"ramp": {"to": {"F": 1.0}, "duration": 1.0}}], "loads[0].ramp.to.F"),
        ([{"hold": {"duration": 0.0}}], "loads[0].hold.duration"),
        ([{"hold": {"duration": 1.0, "steps": 1.5}}], "loads[0].hold.steps"),
        ([{"cycles": {"count": 0, "period": 1.0}}], "loads[0].cycles.count"),
        ([{"cycles": {"count": 1, "period": 1.0, "steps_per_cycle": 0}}], "loads[0].cycles.steps_per_cycle"),
        ([{"cycles": {"count": 1, "period": float("nan")}}], "loads[0].cycles.period"),
        ([{"cycles": {"count": 1, "period": 1.0, "Q": {"phase": "90 deg"}}}], "loads[0].cycles.Q.phase"),
        ([{"table": {"t": [1.0], "Q": [1.0, 2.0]}}], "loads[0].table.Q"),
        ([{"table": {"file": "x.csv", "t": [1.0]}}], "loads[0].table.t"),
        ([{"hold": {"duration": 1.0}}, {"wait": {}}], "loads[1].wait"),
        ([], "loads"),
    ],
)
def test_bad_segments_name_the_field(segments, field):
    with pytest.raises(HalfslipInputError) as error:
        LoadHistory.from_segments(segments)
    assert error.value.field == field


def test_ranges_and_shear_ratio():
    history = LoadHistory.from_segments(
        [ramp(P=1.0e5, Q=3.0e4), {"cycles": {"count": 1, "period": 1.0, "Q": {"amplitude": 1.5e4}}}]
    )
    assert history.ranges()["Q"] == pytest.approx((0.0, 4.5e4))  # from the unloaded start
    assert history.max_shear_ratio(0.6) == pytest.approx(4.5e4 / 6.0e4)
    assert history.max_shear_ratio(0.0) == math.inf
    # shear without normal load can never be carried by friction
    unloaded = LoadHistory.from_segments([ramp(Q=1.0)])
    assert unloaded.max_shear_ratio(0.6) == math.inf
    assert LoadHistory.from_segments([ramp(P=1.0)]).max_shear_ratio(0.0) == 0.0


def test_history_is_immutable():
    history = LoadHistory.from_segments([ramp(steps=3, P=1.0)])
    for name in ("t", *LOADS):
        with pytest.raises(ValueError):
            getattr(history, name)[0] = 1.0
    with pytest.raises(AttributeError):
        history.segments[0].stop = 7  # type: ignore[misc]
    assert isinstance(history.segments[0], Segment)


loads_strategy = st.fixed_dictionaries(
    {}, optional={name: st.floats(-1.0e6, 1.0e6, allow_nan=False) for name in LOADS}
)
segment_strategy = st.one_of(
    st.builds(
        lambda to, duration, steps: {"ramp": {"to": to, "duration": duration, "steps": steps}},
        loads_strategy,
        st.floats(1e-3, 10.0),
        st.integers(1, 8),
    ),
    st.builds(
        lambda duration, steps: {"hold": {"duration": duration, "steps": steps}},
        st.floats(1e-3, 10.0),
        st.integers(1, 8),
    ),
)


@settings(max_examples=50, deadline=None)
@given(st.lists(segment_strategy, min_size=1, max_size=6))
def test_ramps_and_holds_chain_and_evaluate_consistently(segments):
    history = LoadHistory.from_segments(segments)
    assert history.n_steps == sum(next(iter(spec.values())).get("steps", 1) for spec in segments)
    expected = dict.fromkeys(LOADS, 0.0)
    for segment, spec in zip(history.segments, segments):
        expected.update(spec.get("ramp", {}).get("to", {}))
        for name in LOADS:
            assert getattr(history, name)[segment.stop] == expected[name]
    values = history.evaluate(history.t)
    for name in LOADS:
        np.testing.assert_allclose(values[name], getattr(history, name), rtol=1e-12, atol=1e-6)
