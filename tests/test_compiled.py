"""The compiled Hertz marcher against the Python reference path."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import halfslip as hs
from halfslip.geometry import Hertz, NormalProblem
from halfslip.solvers.exact import ExactMemory
from halfslip.state import Loads

pytest.importorskip("numba")

A = 4 * (1 - 0.3**2) / 200e9
F = 0.6
P0 = 1e5


def test_kernel_equals_python_step_by_step():
    """Random history with separation, gross sliding and every kind of step:
    the compiled march reproduces the Python path bit for bit (same operations)."""
    method = ExactMemory(NormalProblem(Hertz(0.05), A), F, 2 * P0)
    rng = np.random.default_rng(7)
    n = 3000
    P = np.abs(P0 * (1 + 0.5 * np.sin(np.arange(n) / 37) + 0.2 * rng.standard_normal(n)))
    P[100:110] = 0.0
    Q = 0.8 * F * P * np.sin(np.arange(n) / 13 + 0.3 * rng.standard_normal(n))
    Q[500] = 2 * F * P[500]
    state = method.initial_state()
    rows = []
    for i in range(n):
        state, report = method.step(state, float(i), Loads(P[i], Q[i], 0.0, 0.0))
        rows.append((report.regime, state.stick_right, state.contact_right, state.dissipation, state.shift))
    last, steps = method.march(method.initial_state(), np.arange(n, dtype=float), P, Q)
    rows = np.array(rows, float)
    np.testing.assert_array_equal(rows[:, 0], steps["regime"])
    for k, name in [(1, "stick_right"), (2, "contact_right"), (3, "dissipation"), (4, "shift")]:
        np.testing.assert_array_equal(rows[:, k], steps[name])
    assert last.memory.P == state.memory.P and last.memory.W == state.memory.W


def test_simulate_uses_the_kernel_for_extents_and_agrees_with_fields_run():
    scene = hs.load_scene(__import__("pathlib").Path(__file__).resolve().parents[1] / "examples" / "motor.yaml")
    extents = dataclasses.replace(scene, output=dataclasses.replace(scene.output, fields=()))
    a = hs.simulate(extents)
    b = hs.simulate(scene)  # fields stored: the Python step path
    for name in ("stick_left", "stick_right", "contact_right", "dissipation", "rigid_shift", "regime"):
        np.testing.assert_array_equal(a[name].values, b[name].values)
    for k in ("count_steps", "count_slip_solves", "count_stick_steps", "count_normal_solves", "skipped_cycles"):
        assert a.attrs[k] == b.attrs[k], k
