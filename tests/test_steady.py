"""Direct steady state against marching, and the cycle-skipping machinery."""
from __future__ import annotations

import dataclasses
import math
import textwrap

import numpy as np
import pytest

import halfslip as hs
from halfslip.steady import motor_stick_level

HERTZ_SCENE = """
name: steady-hertz
material: {{E: 200.0e9, nu: 0.3}}
friction: 0.6
geometry: {{kind: hertz, radius: 50.0e-3}}
loads:
  - ramp: {{to: {{P: {P0}, Q: {Q0}}}, duration: 1.0, steps: 10}}
  - cycles:
      count: {count}
      period: 1.0
      steps_per_cycle: {spc}
      P: {{amplitude: {Pa}, phase: 0.0}}
      Q: {{mean: {Qm}, amplitude: {Qa}, phase: {phase}}}
output: {{fields: [], every: 1}}
solver: {{skip_steady_cycles: false}}
"""


def marched_permanent_stick(ds, spc):
    last = ds.isel(t=slice(-spc, None))
    return float(last.stick_left.max()), float(last.stick_right.min())


def hertz_scene(P0=1e5, Qm=0.0, Pa=0.0, Qa=2e4, phase=0.0, count=20, spc=400):
    """Ramp to the loop's starting point, then harmonic P and Q about (P0, Qm)."""
    Q0 = Qm + Qa * math.sin(math.radians(phase))
    return hs.parse_scene(textwrap.dedent(HERTZ_SCENE.format(
        P0=P0, Q0=Q0, Qm=Qm, Pa=Pa, Qa=Qa, phase=phase, count=count, spc=spc)))


def test_hertz_ss2_closed_form_equals_marching():
    """(SS2) at constant P; the turning points are sampled exactly, so 1e-10."""
    scene = hertz_scene(Qa=2.5e4)
    steady = hs.steady_state(scene)
    assert steady.attrs["method"] == "SS2 closed form"
    A, R, f = scene.material.compliance, 50e-3, 0.6
    a2 = 2 * A * R * 1e5 / math.pi
    d = math.sqrt(a2 - A * R * 5e4 / (math.pi * f))
    assert float(steady.permanent_stick_right) == pytest.approx(d, rel=1e-12)
    ds = hs.simulate(scene)
    left, right = marched_permanent_stick(ds, 400)
    assert right == pytest.approx(d, rel=1e-10)
    assert left == pytest.approx(-d, rel=1e-10)


@pytest.mark.parametrize("Pa, Qa, phase, Qm", [(3e4, 3e4, 90.0, 0.0), (5e4, 2.5e4, 60.0, 1e4), (2e4, 3.5e4, 120.0, -5e3)])
def test_motor_point_T_equals_marching(Pa, Qa, phase, Qm):
    """a(P_T) against 20 marched cycles; the tangency falls between samples: O(dtheta^2)
    with 1000 steps per cycle ~ 4e-5 relative in P_T, 2e-5 in a; tolerance 1e-4."""
    scene = hertz_scene(Pa=Pa, Qa=Qa, phase=phase, Qm=Qm, spc=1000)
    steady = hs.steady_state(scene, per_cycle=False)
    assert steady.attrs["method"].startswith("Barber-Davies-Hills")
    ds = hs.simulate(scene)
    left, right = marched_permanent_stick(ds, 1000)
    assert right == pytest.approx(float(steady.permanent_stick_right), rel=1e-4)
    assert left == pytest.approx(float(steady.permanent_stick_left), rel=1e-4)


def test_motor_closed_form_P_T_against_dense_loop():
    h = {k: v for k, v in hertz_scene(Pa=3e4, Qa=3e4, phase=70.0, Qm=1e3).history.segments[1].harmonics.items()}
    th = np.linspace(0, 2 * np.pi, 1_000_001)
    P = h["P"].mean + h["P"].amplitude * np.sin(th + h["P"].phase)
    Q = h["Q"].mean + h["Q"].amplitude * np.sin(th + h["Q"].phase)
    dense = (np.min(Q + 0.6 * P) - np.max(Q - 0.6 * P)) / 1.2
    assert motor_stick_level(h, 0.6) == pytest.approx(dense, rel=1e-10)


def test_gross_sliding_is_said_plainly():
    scene = hertz_scene(Qa=7e4)
    steady = hs.steady_state(scene, per_cycle=False)
    assert int(steady.regime) == 3
    assert np.isnan(float(steady.permanent_stick_right))


def test_in_phase_P_and_Q_within_the_cone_shakes_down_to_full_stick():
    """In-phase P and Q with abs(dQ) < f dP pass the finite-range S1 test: full stick."""
    scene = hertz_scene(Pa=3e4, Qa=1e4, phase=0.0)
    steady = hs.steady_state(scene, per_cycle=False)
    assert int(steady.regime) == 1
    ds = hs.simulate(scene)
    regime = ds.regime.values[-400:]
    assert np.all(regime == 1)


def test_cycle_skipping_matches_full_marching():
    """Skipping the repeated cycles changes neither the final state nor the dissipation (1e-12)."""
    full_scene = hertz_scene(Pa=3e4, Qa=3e4, phase=90.0, count=30, spc=100)
    scene = dataclasses.replace(full_scene, solver=dataclasses.replace(full_scene.solver, skip_steady_cycles=True))
    skipped = hs.simulate(scene)
    full = hs.simulate(full_scene)
    assert full.attrs["skipped_cycles"] == 0
    assert skipped.attrs["skipped_cycles"] >= 25
    assert skipped.attrs["count_steps"] < full.attrs["count_steps"] / 5
    # the last stored step is the last marched one; the final state is that state (the cycle repeats)
    # at final_t, with final_dissipation
    assert float(skipped.final_t) == pytest.approx(float(full.t[-1]), rel=1e-12)
    for name in ("stick_left", "stick_right", "rigid_shift", "contact_right"):
        assert float(skipped[name][-1]) == pytest.approx(float(full[name][-1]), rel=1e-12)
    assert float(skipped.final_dissipation) == pytest.approx(float(full.dissipation[-1]), rel=1e-12)
    assert float(full.final_dissipation) == float(full.dissipation[-1])


def test_counters_constant_P_one_normal_solve_and_full_stick_no_slip_solve():
    t = np.linspace(0.0, 10.0, 201)
    P = np.full_like(t, 1e5)
    P[0] = 0.0
    Q = 0.3 * 0.6 * 1e5 * np.sin(t)
    Q[0] = 0.0
    base = hertz_scene()
    const_P = dataclasses.replace(base, history=hs.LoadHistory.from_arrays(t, P, Q))
    ds = hs.simulate(const_P)
    assert ds.attrs["count_normal_solves"] == 1
    # P and Q rising together inside the friction cone: full stick, never a slip solve
    ramp = dataclasses.replace(base, history=hs.LoadHistory.from_arrays(t, 1e5 * t, 0.3 * 0.6 * 1e5 * t))
    ds = hs.simulate(ramp)
    assert ds.attrs["count_slip_solves"] == 0
    assert np.all(ds.regime.values[1:] == 1)


PUNCH_SCENE = """
name: ss1-punch
material: {{E: 115.0e9, nu: 0.3}}
friction: 0.6
geometry: {{kind: rounded_punch, flat_half_width: 2.0e-3, radius: 10.0e-3}}
loads:
  - ramp: {{to: {{P: 2.0e5}}, duration: 1.0, steps: 10}}
  - cycles:
      count: {count}
      period: 1.0
      steps_per_cycle: 20
      P: {{amplitude: 2.0e4, phase: 0.0}}
      Q: {{amplitude: 6.0e4, phase: 0.0}}
      M: {{amplitude: 20.0, phase: 0.0}}
      sigma: {{amplitude: 1.0e7, phase: 0.0}}
solver: {{method: general, nodes: {nodes}, skip_steady_cycles: {skip}}}
output: {{fields: [], every: 1}}
"""


def punch_scene(count=20, skip=True, nodes=128):
    """Rounded punch, P, Q, M and sigma in phase, moderate tension: (SS1) applies."""
    return hs.parse_scene(PUNCH_SCENE.format(count=count, skip=str(skip).lower(), nodes=nodes))


def test_rounded_punch_with_moment_and_tension_ss1_equals_marching():
    """(SS1) with M and sigma against 20 marched cycles of the general solver.

    Tolerance 2e-4 of the contact width at 1024 nodes: the general solver places a
    stick edge to about 0.1 of a cell (sub-cell interpolation of the Coulomb
    margin). Measured (left, right) edge differences: 2.4e-3, 9.3e-4 at 128
    nodes; 1.4e-4, 9.3e-5 at 512; 3.1e-6, 8.9e-5 at 1024 (the same with 20, 80
    and 320 steps per cycle: in-phase loading, the state depends on the end
    points only); 1.3e-4, 5.6e-5 at 2048; 1.0e-4, 2.7e-5 at 4096 -- not
    monotone below 1e-4: the edge's position within its cell.
    """
    scene = punch_scene(nodes=1024)
    steady = hs.steady_state(scene, per_cycle=False)
    assert steady.attrs["method"] == "SS1"
    assert "not moderate" not in steady.attrs.get("note", "")
    ds = hs.simulate(scene)
    assert ds.attrs["skipped_cycles"] >= 12  # the cycle repeats to tolerance within a few cycles
    last = ds.isel(t=slice(-20, None))
    width = float(last.contact_right.min() - last.contact_left.max())
    left, right = marched_permanent_stick(ds, 20)
    assert abs(left - float(steady.permanent_stick_left)) < 2e-4 * width
    assert abs(right - float(steady.permanent_stick_right)) < 2e-4 * width
    # and the permanent stick zone is a real partial-slip answer, not the whole contact
    assert float(last.contact_right.min()) - right > 2e-3 * width


@pytest.mark.parametrize("windows", [False, True])
def test_general_solver_skips_steady_cycles_like_full_marching(windows):
    """Skipping by the general solver's same_state changes the results by less than its tolerance.

    The states one cycle apart agree to SAME_STATE_TOL (1e-8 of f max p in q and of
    A f max p W in the locked displacements, on the same cells): the active-set
    pattern repeats, so without the edge windows the skipped run's last stored cycle
    agrees with the fully marched one to rounding in the stick edges (asserted to
    1e-9 of the width) and in its dissipation per cycle (1e-9). With them (the
    default since 0.4.6) their shear is not compared (it creeps by about 4e-6 of f
    max p a cycle, docs/general_solver.md): the edges agree to the cycle tolerance,
    1e-3 of a cell (measured 7.3e-4 of a cell, 128 nodes, 7 of 10 cycles skipped),
    the dissipation to 1e-5 (measured 3.0e-6 per cycle, 2.3e-6 in total).
    """
    from halfslip import post

    def scene(skip):
        s = punch_scene(count=10, skip=skip)
        return dataclasses.replace(s, solver=dataclasses.replace(s.solver, edge_windows=windows))

    skipped = hs.simulate(scene(True))
    full = hs.simulate(scene(False))
    assert full.attrs["skipped_cycles"] == 0 and skipped.attrs["skipped_cycles"] >= 3
    assert skipped.attrs["count_steps"] < full.attrs["count_steps"]
    last = full.isel(t=slice(-20, None))
    width = float(last.contact_right.min() - last.contact_left.max())
    edges, energy = (1e-3 * width / 128, 1e-5) if windows else (1e-9 * width, 1e-9)
    for a, b in zip(marched_permanent_stick(skipped, 20), marched_permanent_stick(full, 20)):
        assert abs(a - b) < edges
    d_skip = post.dissipation_per_cycle(skipped).dissipation.values
    d_full = post.dissipation_per_cycle(full).dissipation.values
    assert d_skip[-1] == pytest.approx(d_full[-1], rel=energy)
    assert float(skipped.final_dissipation) == pytest.approx(float(full.dissipation[-1]), rel=energy)


def test_general_state_difference_tells_a_first_cycle_from_a_steady_one():
    """The first cycle changes the memory (difference >> 1); a state equals itself (0)."""
    from halfslip.solvers.general import GeneralSolver
    from halfslip.state import Loads

    scene = punch_scene(count=3, skip=False)
    h = scene.history
    solver = GeneralSolver(hs.NormalProblem(scene.profile, scene.material.compliance), scene.friction, 128)
    state = solver.initial_state()
    ends = {}
    for i in range(1, h.t.size):
        state, _ = solver.step(state, h.t[i], Loads(h.P[i], h.Q[i], h.M[i], h.sigma[i]))
        if (i - 10) % 20 == 0:
            ends[(i - 10) // 20] = state
    assert solver.state_difference(ends[0], ends[0]) == 0.0
    assert solver.state_difference(ends[0], ends[1]) > 10.0
    assert solver.same_state(ends[2], ends[3])
