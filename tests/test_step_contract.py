"""The step contract (solvers/base.py): every method is a TangentialSolver, every step says
whether it met its tolerance, and the result records it (issue 14, item 3)."""
from __future__ import annotations

import textwrap

import numpy as np
import pytest

import halfslip as hs
import halfslip.solvers.general as general_module
from halfslip.cli import summarize
from halfslip.geometry import Hertz, NormalProblem
from halfslip.solvers.base import TangentialSolver
from halfslip.solvers.exact import ExactMemory
from halfslip.solvers.general import CHECK_TOL, GeneralSolver
from halfslip.state import Loads

SCENE = textwrap.dedent("""
    name: contract
    material: {E: 200.0e9, nu: 0.3}
    friction: 0.6
    geometry: {kind: hertz, radius: 50.0e-3}
    loads:
      - ramp: {to: {P: 1.0e5}, duration: 1.0, steps: 4}
      - ramp: {to: {Q: 4.0e4, sigma: 2.0e7}, duration: 1.0, steps: 12}
    solver: {method: general, nodes: 64}
    output: {every: 100}
""")


def test_both_methods_keep_the_contract():
    assert issubclass(ExactMemory, TangentialSolver) and issubclass(GeneralSolver, TangentialSolver)
    assert GeneralSolver.cycle_tolerance is not None and TangentialSolver.cycle_tolerance is None


def test_converged_steps_are_recorded(tmp_path):
    scene = hs.parse_scene(SCENE)
    ds = hs.simulate(scene)
    assert ds.attrs["count_failed_steps"] == 0
    assert ds["converged"].dtype == np.int8 and np.all(ds["converged"].values == 1)
    assert np.all(ds["residual"].values <= 1.0)
    assert ds["converged"].attrs["units"] == "1" and ds["residual"].attrs["long_name"]


def test_a_failed_step_is_stored_counted_and_summarised(monkeypatch, tmp_path):
    """A step the solver could not solve to its tolerance is kept in the result whatever
    output.every says, counted, and named in the summary: it never looks like a right one.

    In the sixth step (the second with slip), every answer of the fine lattice's active set (the
    whole step and each sub-step it is retaken in) comes back with its equilibrium off by 7.5 times
    the check's tolerance (one stick cell's shear raised by 7.5 CHECK_TOL f P / h, far inside its
    Coulomb bound: 4e-5 of it). The step's own verification must see it and report converged=False
    with residual 7.5 (the worst of its sub-steps), and the simulator must record and count it.
    """
    original_step, original_solve = GeneralSolver.step, GeneralSolver._active_set
    seen = {"steps": 0, "perturbed": 0}

    def counting_step(self, *args):
        seen["steps"] += 1
        return original_step(self, *args)

    def perturbed_once(self, lat, n, r, qmax, total, status, *scales):
        q, delta, pattern, Tq, iterations, restarts, sizes = original_solve(self, lat, n, r, qmax, total, status,
                                                                            *scales)
        if lat.h == min(self._lattices):  # the fine lattice (the error estimate's shadow is twice as coarse)
            if seen["steps"] == 6:
                stick = np.flatnonzero(pattern == 0)
                cell = stick[np.argmax(qmax[stick] - np.abs(q[stick]))]  # the stick cell furthest from its bound
                q = q.copy()
                q[cell] += 7.5 * CHECK_TOL * float(np.sum(qmax))  # h sum qmax = f P
                seen["perturbed"] += 1
        return q, delta, pattern, Tq, iterations, restarts, sizes

    monkeypatch.setattr(GeneralSolver, "step", counting_step)
    monkeypatch.setattr(GeneralSolver, "_active_set", perturbed_once)
    scene = hs.parse_scene(SCENE)
    ds = hs.simulate(scene)
    assert seen["steps"] == 16 and seen["perturbed"] >= 1
    assert ds.attrs["count_failed_steps"] == 1
    bad = ds["converged"].values == 0
    assert bad.sum() == 1 and ds["residual"].values[bad][0] == pytest.approx(7.5, rel=1e-6)
    assert np.all(ds["residual"].values[~bad] <= 1.0)
    assert ds["t"].values[bad][0] == pytest.approx(1.0 + 2.0 / 12.0)  # the sixth step
    assert ds.sizes["t"] == 3  # the initial state, the failed step (off the every-100 grid), the last step
    text = "\n".join(summarize(ds, tmp_path / "x.h5"))
    assert "NOT CONVERGED: 1 of 16 steps" in text and "7.5 x tolerance" in text


def test_an_active_set_that_cannot_converge_is_reported(monkeypatch, tmp_path):
    """The active set is cut to one iteration before each restart (MAX_ACTIVE_SET = 1) and the
    projected-gradient restart is disabled (it returns the all-stick pattern), so no step whose
    pattern must change can converge: those steps return their last iterate with converged=False
    and a residual above 1 (the all-stick iterate violates Coulomb), the message says why, and the
    simulator records and counts every one of them. (MAX_ACTIVE_SET = 1 alone is not enough: the
    restarts find the answer, test_general.test_projected_gradient_restart_finds_the_answer.)"""
    monkeypatch.setattr(general_module, "MAX_ACTIVE_SET", 1)
    monkeypatch.setattr(general_module, "_projected_gradient",
                        lambda lat, n, r, qmax, total, q0, iterations=0: np.zeros(n, np.int8))
    problem = NormalProblem(Hertz(radius=50e-3), 4 * (1 - 0.3**2) / 200e9)
    solver = GeneralSolver(problem, 0.6, 64)
    state = solver.initial_state()
    state, report = solver.step(state, 1.0, Loads(1e5, 0.0, 0.0, 0.0))
    assert report.converged and report.residual <= 1.0  # full stick: the first pattern is right
    state, report = solver.step(state, 2.0, Loads(1e5, 3e4, 0.0, 0.0))
    assert not report.converged and report.residual > 1.0
    assert "active set not converged" in report.message
    assert solver.counters["restarts"] > 0
    ds = hs.simulate(hs.parse_scene(SCENE))
    failed = int(ds.attrs["count_failed_steps"])
    bad = ds["converged"].values == 0
    assert failed >= 1 and bad.sum() == failed
    assert np.all(ds["residual"].values[bad] > 1.0)
    text = "\n".join(summarize(ds, tmp_path / "x.h5"))
    assert f"NOT CONVERGED: {failed} of 16 steps" in text


def test_station_states_follow_cattaneo_mindlin():
    """Hertz, constant P, Q raised to 0.6 fP then lowered to 0.2 fP (exact method): while Q rises the
    points with b < |x| < a slip forward (q = +f p), b/a = sqrt(1 - Q/(fP)) (J1); after the reversal
    the outer zones slip backward out to c = a(P - (Q_max - Q)/(2f)) (J2). Stations within two station
    spacings of an edge are not asserted (the edge falls between stations)."""
    scene = hs.parse_scene(textwrap.dedent("""
        name: cm
        material: {E: 200.0e9, nu: 0.3}
        friction: 0.5
        geometry: {kind: hertz, radius: 50.0e-3}
        loads:
          - ramp: {to: {P: 1.0e5}, duration: 1.0, steps: 2}
          - ramp: {to: {Q: 3.0e4}, duration: 1.0, steps: 10}
          - ramp: {to: {Q: 1.0e4}, duration: 1.0, steps: 10}
        output: {fields: [q], points: 401}
    """))
    ds = hs.simulate(scene)
    assert ds.attrs["method"] == "exact"
    x = ds.x.values
    h = 2 * (x[1] - x[0])
    a = float(ds.contact_right.isel(t=-1))
    states = ds["state"]
    assert states.dtype == np.int8 and "forward_slip" in states.attrs["flag_meanings"]
    loaded = ds.sel(t=2.0)
    b = a * np.sqrt(1 - 3.0e4 / (0.5 * 1.0e5))
    s = loaded["state"].values
    assert np.all(s[np.abs(x) > a + h] == 0)
    assert np.all(s[np.abs(x) < b - h] == 1)
    assert np.all(s[(np.abs(x) > b + h) & (np.abs(x) < a - h)] == 2)
    unloaded = ds.isel(t=-1)["state"].values
    c = a * np.sqrt(1 - (3.0e4 - 1.0e4) / (2 * 0.5 * 1.0e5))
    assert np.all(unloaded[(np.abs(x) > c + h) & (np.abs(x) < a - h)] == 3)
    assert np.all(unloaded[np.abs(x) < c - h] == 1)
    assert np.all(ds["stick_intervals"].values[1:] == 1) and ds["stick_intervals"].values[0] == 0


def test_station_states_show_opposite_slip_under_tension():
    """General solver, Hertz, constant P and a large bulk tension alone: the slip zones at the two
    edges slip in opposite directions (physics.md, slip of opposite sign at the two ends)."""
    scene = hs.parse_scene(textwrap.dedent("""
        name: tension
        material: {E: 200.0e9, nu: 0.3}
        friction: 0.6
        geometry: {kind: hertz, radius: 50.0e-3}
        loads:
          - ramp: {to: {P: 1.0e5}, duration: 1.0, steps: 2}
          - ramp: {to: {sigma: 1.0e8}, duration: 1.0, steps: 8}
        solver: {nodes: 64}
        output: {fields: [q], points: 201}
    """))
    ds = hs.simulate(scene)
    last = ds.isel(t=-1)
    s, x = last["state"].values, ds.x.values
    left = s[x < float(last.stick_left)]
    right = s[x > float(last.stick_right)]
    assert {2, 3} <= set(np.unique(left[left > 0])) | set(np.unique(right[right > 0]))
    assert set(np.unique(left[left > 0])) != set(np.unique(right[right > 0]))
