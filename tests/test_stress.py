"""Stress tests of the exact method: long runs, tiny steps, limits, scaling.

Fast variants run by default; long ones (marked slow) with ``pytest --runslow``.
Each case asserts the invariants (equilibrium W(P) = Q, Coulomb bound,
non-decreasing dissipation, finite values) and, where known, the answer.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from halfslip.geometry import Hertz, NormalProblem, RoundedPunch
from halfslip.solvers.exact import ExactMemory
from halfslip.state import Loads, Regime

A = 4 * (1 - 0.3**2) / 200e9
F = 0.6
P0 = 1.0e5


def check_invariants(method, prev, state, Q_applied):
    mem = state.memory
    P = mem.P[-1]
    assert all(math.isfinite(v) for v in (*mem.P, *mem.W, state.dissipation, state.shift))
    assert state.dissipation >= prev.dissipation
    # Coulomb on every level; a narrow piece's slope carries the rounding of W over its width
    widths = np.diff(mem.P)
    rounding = 64 * np.finfo(float).eps * (F * P + np.max(np.abs(mem.W))) / np.maximum(widths, 1e-300)
    assert np.all(np.abs(mem.slopes()) <= F + rounding)
    carried = max(-F * P, min(F * P, Q_applied))
    assert mem.W[-1] == pytest.approx(carried, rel=1e-12, abs=1e-12 * F * max(P, 1e-300))


def run_cycles(method, n_cycles, per_cycle=8, Qa=0.4 * F * P0):
    state = method.initial_state()
    state, _ = method.step(state, 1.0, Loads(P0, 0.0, 0, 0))
    snapshots = []
    theta = 2 * np.pi * np.arange(1, per_cycle + 1) / per_cycle
    Qs = (Qa * np.sin(theta)).tolist()
    for c in range(n_cycles):
        for k, Q in enumerate(Qs):
            state, _ = method.step(state, 1.0 + c + k / per_cycle, Loads(P0, Q, 0, 0))
        if c in (9, n_cycles - 1):
            snapshots.append(state)
    return snapshots


@pytest.mark.parametrize("n_cycles", [1000, pytest.param(100_000, marks=pytest.mark.slow)])
def test_no_drift_over_many_cycles(n_cycles):
    """The state after the last cycle equals the 10th cycle's to 1e-12."""
    method = ExactMemory(NormalProblem(Hertz(50e-3), A), F, P0)
    tenth, last = run_cycles(method, n_cycles)
    assert last.memory.P == pytest.approx(tenth.memory.P, rel=1e-12)
    assert np.allclose(last.memory.W, tenth.memory.W, rtol=0, atol=1e-12 * F * P0)
    assert last.shift == pytest.approx(tenth.shift, rel=1e-12)
    per_cycle = (last.dissipation - tenth.dissipation) / (n_cycles - 10)
    assert per_cycle > 0


@pytest.mark.parametrize("tiny", [1e-9, 1e-6, 1e-3])
def test_tiny_steps_change_nothing(tiny):
    """Splitting steps at a fraction `tiny` of their length gives the same states (1e-12)."""
    method = ExactMemory(NormalProblem(RoundedPunch(0.2e-3, 10e-3), A), F, 1.2 * P0)
    corners = [(P0, 0.3 * F * P0), (1.2 * P0, -0.4 * F * P0), (0.7 * P0, 0.2 * F * P0), (1.1 * P0, 0.5 * F * P0)]
    plain = method.initial_state()
    split = method.initial_state()
    start = (0.0, 0.0)
    for P1, Q1 in corners:
        plain, _ = method.step(plain, 1.0, Loads(P1, Q1, 0, 0))
        mid = (start[0] + tiny * (P1 - start[0]), start[1] + tiny * (Q1 - start[1]))
        prev = split
        split, _ = method.step(split, 1.0, Loads(*mid, 0, 0))
        check_invariants(method, prev, split, mid[1])
        prev = split
        split, _ = method.step(split, 1.0, Loads(P1, Q1, 0, 0))
        check_invariants(method, prev, split, Q1)
        assert np.allclose(split.memory.P, plain.memory.P, rtol=1e-12, atol=0)
        assert np.allclose(split.memory.W, plain.memory.W, rtol=0, atol=1e-12 * F * P0)
        assert split.dissipation == pytest.approx(plain.dissipation, rel=1e-10, abs=1e-15)
        start = (P1, Q1)


def test_stick_zone_shrinks_to_nothing_then_gross_sliding_and_back():
    problem = NormalProblem(Hertz(50e-3), A)
    method = ExactMemory(problem, F, P0)
    state, _ = method.step(method.initial_state(), 1.0, Loads(P0, 0, 0, 0))
    a = float(problem.half_width(P0))
    ratios = 1 - np.logspace(-1, -12, 12)
    widths = []
    for r in ratios:
        prev = state
        state, report = method.step(state, 1.0, Loads(P0, r * F * P0, 0, 0))
        check_invariants(method, prev, state, r * F * P0)
        assert report.regime == Regime.PARTIAL_SLIP
        widths.append(state.stick_right)
        # P_Y = P - Q/f cancels: its relative rounding is ~eps P/P_Y, halved in b = a sqrt(P_Y/P)
        conditioning = 64 * np.finfo(float).eps / (1 - r)
        assert state.stick_right == pytest.approx(a * math.sqrt(1 - r), rel=max(1e-12, conditioning))
    assert np.all(np.diff(widths) < 0)
    prev = state
    state, report = method.step(state, 1.0, Loads(P0, 1.5 * F * P0, 0, 0))
    assert report.regime == Regime.GROSS_SLIDING and math.isnan(state.stick_right)
    check_invariants(method, prev, state, 1.5 * F * P0)
    prev = state
    state, report = method.step(state, 1.0, Loads(P0, 0.0, 0, 0))
    assert report.regime == Regime.PARTIAL_SLIP
    assert state.stick_right == pytest.approx(float(problem.half_width(P0 / 2)), rel=1e-12)  # reversal of Q = f P
    check_invariants(method, prev, state, 0.0)


def test_P_to_zero_recontact_and_tiny_P_under_large_Q_history():
    problem = NormalProblem(RoundedPunch(0.2e-3, 10e-3), A)
    method = ExactMemory(problem, F, P0)
    path = [(P0, 0.5 * F * P0), (1e-9 * P0, 0.0), (0.0, 0.0), (1e-12 * P0, 0.3 * F * 1e-12 * P0),
            (P0, 0.3 * F * P0), (1e-6 * P0, -0.3 * F * P0), (P0, 0.0)]
    state = method.initial_state()
    for P, Q in path:
        prev = state
        state, report = method.step(state, 1.0, Loads(P, Q, 0, 0))
        if P > 0:
            check_invariants(method, prev, state, Q)
        else:
            assert report.regime == Regime.SEPARATED and state.memory.P == (0.0,)


@pytest.mark.parametrize("load_scale", [1e-6, 1e-2, 1.0, 1e4, 1e9 / P0])
@pytest.mark.parametrize("length_scale", [1e-9, 1e-3, 1.0])
def test_dimensional_scaling(load_scale, length_scale):
    """Scaling loads by s and lengths by l: b/a, q/p0 and W/P are invariant; a scales with sqrt(s R)."""
    R = 50e-3 * length_scale
    problem = NormalProblem(Hertz(R), A)
    P = P0 * load_scale
    method = ExactMemory(problem, F, P)
    path = [(P, 0.0), (P, 0.5 * F * P), (0.8 * P, -0.2 * F * P), (1.0 * P, 0.3 * F * P)]
    state = method.initial_state()
    for Pk, Qk in path:
        state, _ = method.step(state, 1.0, Loads(Pk, Qk, 0, 0))
    a = float(problem.half_width(P))
    assert a == pytest.approx(math.sqrt(2 * A * R * P / math.pi), rel=1e-12)
    ratio = state.stick_right / a
    ref = ExactMemory(NormalProblem(Hertz(50e-3), A), F, P0)
    s = ref.initial_state()
    for Pk, Qk in path:
        s, _ = ref.step(s, 1.0, Loads(Pk / load_scale, Qk / load_scale, 0, 0))
    assert ratio == pytest.approx(s.stick_right / float(ref.problem.half_width(P0)), rel=1e-10)
    assert np.allclose(np.asarray(state.memory.W) / P, np.asarray(s.memory.W) / P0, rtol=0, atol=1e-12)
    # dissipation scales as f P * (A f P): energy ~ load x slip
    assert state.dissipation / (A * (F * P) ** 2) == pytest.approx(s.dissipation / (A * (F * P0) ** 2), rel=1e-8)
