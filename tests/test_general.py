"""The general lattice solver against closed forms, the exact method, and its own invariants.

The solver (``halfslip.solvers.general``) carries a constant shear per cell of
width h = W / nodes and solves each step as a strictly convex problem, checked
to rounding (``StepReport.residual``). What remains is the error of the
lattice, and where a contact edge moves during a slipping step, of the step.
Every tolerance below comes from a measurement at two to six resolutions, with
the observed order and the measured value at the tested resolution in the
test's docstring, and a margin of 2-5x over the largest measured value.

Error measures used throughout (W: contact width):

- stick edges: distance to the closed form, / W. First order in h: about
  0.1-0.25 of a cell, the exact fraction depending on where the edge falls in
  its cell (so the error is not monotone from one resolution to the next).
- q, ``rms``: root mean square of q - q_closed over the contact (4001 points),
  / max abs(q_closed); first order in h.
- q, ``away``: largest abs(q - q_closed) more than 0.05 W from every stick edge
  (and old stick edge), / max abs(q_closed); first order in h. Within a cell of
  a stick edge q = (q_j / cap_j) p is off by O(1) of the local shear (the true
  ratio q / p varies like a square root there), so no pointwise bound is
  asserted next to the edges.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

import halfslip.solvers.general as general_module
from halfslip.geometry import NormalProblem
from halfslip.solvers.base import BACKWARD_SLIP, FORWARD_SLIP, OUT_OF_CONTACT, STICK
from halfslip.solvers.exact import ExactMemory
from halfslip.solvers.general import GeneralSolver
from halfslip.state import Loads, Regime

import helpers
from helpers import A, F, P0, PROFILES
from helpers import R_HERTZ as R

march = helpers.march


def make(kind, nodes=1024, **kw):
    return helpers.make(kind, "general", nodes=nodes, **kw)


def q_errors(q, q_closed, x, edges, width):
    """(rms, away) of the module notes; ``edges`` are the stick edges (and old stick edges) as abs(x)."""
    scale = float(np.max(np.abs(q_closed)))
    rms = float(np.sqrt(np.mean((q - q_closed) ** 2))) / scale
    away = np.ones(x.shape, bool)
    for e in edges:
        away &= np.abs(np.abs(x) - e) > 0.05 * width
    return rms, float(np.max(np.abs(q - q_closed)[away])) / scale


def j2_closed(problem, x, Q_max, Q):
    """(J2) after loading to Q_max at constant P0 and unloading to Q."""
    return (-F * problem.pressure(x, P0) + 2 * F * problem.pressure(x, P0 - (Q_max - Q) / (2 * F))
            - F * problem.pressure(x, P0 - Q_max / F))


# ---------------------------------------------------------------------------
# closed forms
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("kind", PROFILES)
@pytest.mark.parametrize("ratio", [0.05, 0.5, 0.95])
def test_cattaneo_mindlin_and_jaeger_ciavarella(kind, ratio):
    """J1 at 1024 nodes: b = a(P - Q/f) (Hertz: a sqrt(1 - Q/fP)), q = f [p(x, P) - p(x, P - Q/f)].

    Edges, first order (max over 17 ratios 0.1 .. 0.9: 1.8e-3 / 4.7e-4 /
    2.5e-4 / 1.3e-4 / 6.3e-5 of W at 128 .. 2048 nodes, Hertz; punch 6.2e-4
    / 3.1e-4 / 1.8e-4 / 8.2e-5 at 256 .. 2048): measured at most 1.1e-4 on
    these six cases and 1.8e-4 over the scan; tolerance 4e-4.
    q, first order (rms 2.0e-2 / 1.2e-2 / 6.9e-3 / 3.1e-3 at 256 .. 2048,
    punch, Q = 0.05 f P, the worst case): rms at most 6.9e-3 (tolerance
    1.5e-2), away at most 2.7e-3 (tolerance 6e-3).
    """
    problem, solver = make(kind)
    Q = ratio * F * P0
    state, report = march(solver, [(P0, 0.0), (P0, Q)])[-1]
    assert report.regime == Regime.PARTIAL_SLIP and report.slipped and report.converged
    a = float(problem.half_width(P0))
    b = float(problem.half_width(P0 - Q / F))
    W = 2 * a
    assert abs(state.stick_right - b) / W < 4e-4
    assert abs(state.stick_left + b) / W < 4e-4
    x = np.linspace(-a, a, 4001)
    _, q = solver.tractions(state.memory, x)
    q_closed = F * (problem.pressure(x, P0) - problem.pressure(x, P0 - Q / F))
    rms, away = q_errors(q, q_closed, x, [b], W)
    assert rms < 1.5e-2 and away < 6e-3, (rms, away)


@pytest.mark.parametrize("kind", PROFILES)
def test_mindlin_unloading(kind):
    """J2 at 1024 nodes after loading to Q_max = 0.6 f P: reversed slip zones reach
    c = a(P - (Q_max - Q)/(2f)), q of (J2).

    Edges, first order (at most 6.2e-4 / 2.4e-4 / 1.3e-4 / 8.9e-5 of W at
    256 / 512 / 1024 / 2048 nodes over both profiles and the three Q):
    measured at most 1.3e-4, tolerance 4e-4. q (edges: c and the old stick
    edge b, where the locked displacement has a square-root onset), first
    order: rms 1.9e-2 / 1.1e-2 / 6.6e-3 / 3.5e-3 (tolerance 1.5e-2), away
    1.7e-2 / 8.0e-3 / 3.9e-3 / 1.8e-3 (tolerance 1e-2), worst of both
    profiles and the three Q.
    """
    problem, solver = make(kind)
    Q_max = 0.6 * F * P0
    loaded = march(solver, [(P0, 0.0), (P0, Q_max)])[-1][0]
    a = float(problem.half_width(P0))
    W = 2 * a
    b = float(problem.half_width(P0 - Q_max / F))
    x = np.linspace(-a, a, 4001)
    for Q in (0.4 * Q_max, 0.0, -0.5 * Q_max):
        state, report = march(solver, [(P0, Q)], loaded)[-1]
        c = float(problem.half_width(P0 - (Q_max - Q) / (2 * F)))
        assert report.regime == Regime.PARTIAL_SLIP and report.converged
        assert abs(state.stick_right - c) / W < 4e-4
        assert abs(state.stick_left + c) / W < 4e-4
        _, q = solver.tractions(state.memory, x)
        rms, away = q_errors(q, j2_closed(problem, x, Q_max, Q), x, [c, b], W)
        assert rms < 1.5e-2 and away < 1e-2, (Q, rms, away)


@pytest.mark.parametrize("sigma_over_Q", [0.0, 500.0, 1000.0])
def test_bulk_tension_moderate(sigma_over_Q):
    """Q and sigma raised together at constant P on Hertz (1024 nodes): stick zone centred at
    e = -A R sigma/(4f) (Nowell-Hills), half-width a sqrt(1 - Q/(fP)).

    Edges over the ten steps, first order: at most 7.7e-4 / 4.3e-4 / 1.7e-4 /
    7.8e-5 of W at 256 / 512 / 1024 / 2048 nodes; tolerance 4e-4.
    """
    problem, solver = make("hertz")
    a = float(problem.half_width(P0))
    path = [(P0, 0.0)] + [(P0, 0.5 * F * P0 * k / 10, 0.0, sigma_over_Q * 0.5 * F * P0 * k / 10)
                          for k in range(1, 11)]
    for state, report in march(solver, path)[1:]:
        Q, sigma = state.loads.Q, state.loads.sigma
        e = -A * R * sigma / (4 * F)
        b = a * math.sqrt(1 - Q / (F * P0))
        assert report.regime == Regime.PARTIAL_SLIP and report.converged
        assert abs(state.stick_left - (e - b)) / (2 * a) < 4e-4
        assert abs(state.stick_right - (e + b)) / (2 * a) < 4e-4


def test_bulk_tension_reverses_slip():
    """A large sigma reverses the slip at the left end (1024 nodes): the cells there slip backward
    with q = -f p, those at the right end forward with q = +f p, one stick run between.

    Slip cells carry q = +- f cap_j, so q = +- f p to rounding (measured
    1.9e-16 of f max p; tolerance 1e-12); stick cells obey Coulomb to the
    active set's own threshold (FLIP_TOL = 1e-10 of f max p; tolerance 1e-9;
    the stick cells are at least 5.0e-2 f max p below it). The per-station ``state`` codes follow
    the cells.
    """
    problem, solver = make("hertz")
    a = float(problem.half_width(P0))
    path = [(P0, 0.0)] + [(P0, 0.3 * F * P0 * k / 10, 0.0, 1e9 * k / 10) for k in range(1, 11)]
    state, report = march(solver, path)[-1]
    assert report.regime == Regime.PARTIAL_SLIP and report.converged
    status = state.memory.status
    assert status[0] == -1 and status[-1] == 1 and solver.stick_intervals(state) == 1
    x = np.linspace(-a, a, 4001)[1:-1]
    p, q = solver.tractions(state.memory, x)
    codes = solver.station_states(state, x, q)
    back, forward, stick = codes == BACKWARD_SLIP, codes == FORWARD_SLIP, codes == STICK
    assert back.any() and forward.any() and stick.any() and np.all(back | forward | stick)
    assert x[back].max() < x[stick].min() and x[stick].max() < x[forward].min()  # backward | stick | forward
    assert x[back].max() < state.stick_left + state.memory.spacing
    assert x[forward].min() > state.stick_right - state.memory.spacing
    scale = F * p.max()
    assert np.max(np.abs(q[back] + F * p[back])) <= 1e-12 * scale
    assert np.max(np.abs(q[forward] - F * p[forward])) <= 1e-12 * scale
    assert np.all(np.abs(q[stick]) <= F * p[stick] + 1e-9 * scale)
    assert solver.shear_force(state.memory) == pytest.approx(state.loads.Q, rel=1e-12)


def test_steady_state_permanent_stick_zone():
    """In-phase cyclic Q and sigma at constant P on Hertz (512 nodes, 40 steps per cycle) settle on
    SS2: d^2 = a(P0)^2 - A R dQ/(pi f), e = -A R dsigma/(8 f), whatever the mean.

    At the trough the stick zone is the permanent one: edges within 6.25e-5
    of W at 512, 1024 and 2048 nodes (0.03-0.13 cells), 3.0e-5 at 4096;
    tolerance 2e-4. From trough to peak the shear changes by
    dq = 2 f p - (2f/(A R)) sqrt(d^2 - (x - e)^2) (SS1 solved for Hertz), first
    order: rms 4.5e-3 / 2.6e-3 / 1.3e-3 / 7.7e-4 / 4.3e-4 and away 8.0e-3 /
    4.0e-3 / 2.0e-3 / 9.9e-4 / 4.9e-4 at 256 .. 4096 nodes; tolerances at
    512: 6e-3 and 1e-2. At the peak the material between the permanent zone
    and the first loading's stick edge (c1^2 = a^2 - 2 A R Q1 / (pi f),
    e1 = -A R sigma1 / (4 f), Q1 and sigma1 the first peak's) carries its
    bound again without slipping, so the discrete problem barely fixes the
    edge: 0.39 / 0.73 / 1.04 / 0.58 / 1.04 cells off the permanent zone's at
    256 .. 4096 nodes, while at 8192 the whole band slips by 1e-11 m and the
    edge is 0.07 W off, at the first loading's; q, checked by dq, is well
    determined. Since 0.3.9 the step's estimate says so (_undecided_band:
    0.073 W at 512 nodes, one cell before): asserted, it reaches from the
    reported edges to the first loading's. The cycle repeats: states a cycle
    apart are the same to the solver's own tolerance (same_state; measured
    bit-identical).
    """
    problem, solver = make("hertz", 512)
    a = float(problem.half_width(P0))
    W = 2 * a
    Q_mean, dQ, s_mean, ds = 0.15 * F * P0, 0.7 * F * P0, 3e7, 1e8
    n = 40
    path = [(P0, 0.0)]
    for k in range(1, 3 * n + n // 4 + 1):
        ramp = min(1.0, k / 10)
        phase = math.sin(2 * math.pi * k / n)
        path.append((P0, Q_mean * ramp + 0.5 * dQ * phase, 0.0, s_mean * ramp + 0.5 * ds * phase))
    out = march(solver, path)
    assert all(report.converged for _, report in out)
    d = math.sqrt(a * a - A * R * dQ / (math.pi * F))
    e = -A * R * ds / (8 * F)
    Q1, s1 = Q_mean + 0.5 * dQ, s_mean + 0.5 * ds
    c1, e1 = math.sqrt(a * a - 2 * A * R * Q1 / (math.pi * F)), -A * R * s1 / (4 * F)
    x = np.linspace(-a, a, 4001)
    dq_closed = 2 * F * problem.pressure(x, P0) - (2 * F / (A * R)) * np.sqrt(np.clip(d * d - (x - e) ** 2, 0.0, None))
    for cycle in (1, 2):
        trough, _ = out[cycle * n + 3 * n // 4]
        peak, report = out[(cycle + 1) * n + n // 4]
        assert report.regime == Regime.PARTIAL_SLIP
        assert abs(trough.stick_left - (e - d)) / W < 2e-4
        assert abs(trough.stick_right - (e + d)) / W < 2e-4
        dq = solver.tractions(peak.memory, x)[1] - solver.tractions(trough.memory, x)[1]
        scale = np.max(np.abs(dq_closed))
        rms = np.sqrt(np.mean((dq - dq_closed) ** 2)) / scale
        away = (np.abs(x - (e - d)) > 0.05 * W) & (np.abs(x - (e + d)) > 0.05 * W)
        assert rms < 6e-3 and np.max(np.abs(dq - dq_closed)[away]) / scale < 1e-2
        reach = report.error_estimate * W
        assert reach >= max(abs(peak.stick_left - (e1 - c1)), abs(peak.stick_right - (e1 + c1)))
    assert solver.same_state(out[n + 3 * n // 4][0], out[2 * n + 3 * n // 4][0])
    assert solver.same_state(out[2 * n + n // 4][0], out[3 * n + n // 4][0])


# ---------------------------------------------------------------------------
# the first trap, and the exact method
# ---------------------------------------------------------------------------

#: rms error of q against (Q/P) p after proportional loading, by resolution (module notes): worst measured
#: over both profiles and 1 / 10 / 50 steps 2.3e-2 / 8.4e-3 / 3.2e-3 at 32 / 128 / 512 nodes (the punch in
#: 50 steps; 1.8e-3 at 1024: order 0.7-0.85), tolerances 2.5x.
PROPORTIONAL_RMS = {32: 6e-2, 128: 2e-2, 512: 8e-3}


@pytest.mark.parametrize("kind", PROFILES)
@pytest.mark.parametrize("nodes", [32, 128, 512])
@pytest.mark.parametrize("steps", [1, 10, 50])
def test_proportional_loading_sticks_fully(kind, nodes, steps):
    """physics.md, first trap: P and Q from zero with Q/P = 0.5 f stick fully, q = (Q/P) p.

    Arrivals lock the displacement of the stuck increments at the instant
    they arrive, so no cell slips in any step at any resolution (the shortcut
    of pinning arrivals to the previous step was 23% off with up to 86 nodes
    slipping), and q converges to (Q/P) p: rms error in PROPORTIONAL_RMS.
    """
    problem, solver = make(kind, nodes)
    path = [(P0 * k / steps, 0.5 * F * P0 * k / steps) for k in range(1, steps + 1)]
    out = march(solver, path)
    for state, report in out:
        assert report.regime == Regime.STICK and not report.slipped and report.converged
        assert not np.any(state.memory.status) and not np.any(state.memory.G)
    state = out[-1][0]
    a = state.contact_right
    x = np.linspace(-a, a, 4001)
    p, q = solver.tractions(state.memory, x)
    rms = np.sqrt(np.mean((q - 0.5 * F * p) ** 2)) / (0.5 * F * p.max())
    assert rms < PROPORTIONAL_RMS[nodes], rms


PROPORTIONAL_UNLOADING = (
    "open defect (issue 14): proportional unloading reports sub-cell slip zones at the receding edges: "
    "(S1) says a receding edge under a shear drive slips, and the edge material's traction ratio that "
    "would say it does not (J3: the zone is |k' - k| wide) is known to the lattice's error only")


@pytest.mark.parametrize("kind", PROFILES)
@pytest.mark.parametrize("nodes", [256, 1024])
def test_proportional_unloading_sticks(kind, nodes):
    """Loaded in proportion to (P0, 0.5 f P0) in 10 steps, then unloaded in proportion to half of it in
    10 more: the exact answer sticks throughout (J3 with k' = k: no slip zone), q = (Q/P) p. Asserted:
    no cell slips (nothing dissipated), q stays (Q/P) p (PROPORTIONAL_RMS, set for loading at 512 nodes),
    and every stick edge within its step's estimate of the contact edge.

    An open defect is kept as a recorded outcome, PROPORTIONAL_UNLOADING. About half of the unloading
    steps report PARTIAL_SLIP with a slip zone inside the end cell. Measured in 0.3.9 (edge to contact
    edge, in cells): Hertz 0.002 - 0.058 at 256 nodes and 0.003 - 0.019 at 1024; punch 0.001 - 0.074
    and 0.002 - 0.025. The estimate's half-cell floor for such zones (SUBCELL_PLACEMENT) covers them.
    Two things make them:
    * (S1) flags any receding edge with a shear drive, while the exact criterion there is the drive
      against the edge material's ratio, u - chi f v (zero here), and chi is known to the lattice's
      error only (1e-3 of it);
    * END_RULE_WITHIN puts 0.08 - 0.09 of a cell where the local form finds none (w_est = 0) with the
      contact edge at the end cell's centre (its constant term; J1 with a zone of 0.002 cells reads 0.09).
    Neither has a fix that holds up yet (docs/general_solver.md, limits: no measured chi uncertainty
    separates this from J3, and a refit through w_est = 0 doubles the rule's largest error elsewhere).
    """
    problem, solver = make(kind, nodes)
    k = 0.5
    path = [(P0 * j / 10, k * F * P0 * j / 10) for j in range(1, 11)]
    path += [(P0 * (1 - 0.05 * j), k * F * P0 * (1 - 0.05 * j)) for j in range(1, 11)]
    out = march(solver, path)
    partial = 0
    for state, report in out:
        assert report.converged and not report.slipped
        assert not np.any(state.memory.status) and state.dissipation == 0.0
        W = state.contact_right - state.contact_left
        off = max(state.stick_left - state.contact_left, state.contact_right - state.stick_right)
        assert off <= report.error_estimate * W, PROPORTIONAL_UNLOADING
        partial += report.regime == Regime.PARTIAL_SLIP
    assert partial <= 10  # only unloading steps (loading ones stick: test_proportional_loading_sticks_fully)
    state = out[-1][0]
    a = state.contact_right
    x = np.linspace(state.contact_left, a, 4001)
    p, q = solver.tractions(state.memory, x)
    rms = np.sqrt(np.mean((q - k * F * p) ** 2)) / (k * F * p.max())
    assert rms < PROPORTIONAL_RMS[512], rms


#: rms of q - closed form / max abs(q_closed) for P, Q, sigma from zero (below), measured (Hertz, Q/P = 0
#: and 0.3 f; 1 and 10 steps): 7.5e-3 / 1.9e-3 / 4.6e-4 at 128 / 512 / 2048 nodes in one step, 2.8e-3 /
#: 7.8e-4 / 1.6e-4 in ten: first order; tolerances 2x. Double counting the bulk strain on arrival (the
#: defect this guards) gave 11 slipping cells and q / (f p) = -0.5 at the right edge at 1024 nodes.
FORMATION_TENSION_RMS = {128: 1.5e-2, 512: 4e-3}


@pytest.mark.parametrize("nodes", [128, 512])
@pytest.mark.parametrize("steps", [1, 10])
@pytest.mark.parametrize("ratio", [0.0, 0.3])
def test_proportional_loading_with_tension_sticks_fully(nodes, steps, ratio):
    """P, Q = ratio f P and sigma from zero in proportion (Hertz): (S1) holds at both edges all along
    (|Q +- (pi/4) a sigma| <= (ratio + 0.4) f P), so the contact sticks fully and by (M1)

        q = (Q/P) p + int sigma' s / (4 sqrt(a(lam)^2 - s^2)) dlam = (Q/P) p + sigma x sqrt(a^2 - x^2) / (2 a^2)

    (a(lam) = a sqrt(lam)). Arrivals under tension lock A sigma / 4 where the contact
    forms plus the increments, which carry the rest of the bulk strain.
    """
    problem, solver = make("hertz", nodes)
    a = problem.half_width(P0)
    sigma = 0.4 * F * P0 * 4.0 / (math.pi * a)
    path = [(P0 * k / steps, ratio * F * P0 * k / steps, 0.0, sigma * k / steps) for k in range(1, steps + 1)]
    out = march(solver, path)
    for state, report in out:
        assert report.regime == Regime.STICK and not report.slipped and report.converged
    state = out[-1][0]
    x = np.linspace(-a, a, 4001)
    p, q = solver.tractions(state.memory, x)
    closed = ratio * F * p + sigma * x * np.sqrt(np.maximum(a * a - x * x, 0.0)) / (2.0 * a * a)
    rms = np.sqrt(np.mean((q - closed) ** 2)) / np.max(np.abs(closed))
    assert rms < FORMATION_TENSION_RMS[nodes], rms



#: The random Hertz history's first two steps (benchmarks/random_histories.py, seed 0: P, Q, M and sigma in
#: proportion from zero, Q = 0.54 f P, M = 1.3e-4 m P): every point sticks (the lattice and the IC baseline
#: alike); the contact forms in the first step and grows on both sides in the second while the moment moves it.
MOVING_GROWTH = [(14554.425309821816, 7869.492777251394, 1.8722875097725042, 5478192.98620122),
                 (29108.850619643632, 15738.985554502788, 3.7445750195450085, 10956385.97240244)]
MOVING_GROWTH_WIDTH = 6.045147908506354e-4
"""The history's reference width (its cells are this over ``nodes``)."""
#: max |q - exact| / max |exact| over the contact's inner 94 % after the forming step, measured 4.8e-4 / 1.4e-4
#: at 512 / 1024 nodes (about second order; q by GeneralSolver.tractions at 31 points): tolerance 2x.
FORMING_STUCK_TOL = {512: 1e-3, 1024: 3e-4}
#: The same after the second step, which starts in contact and grows while the moment moves it: measured 2.9e-4
#: / 1.5e-4 at 512 / 1024 nodes (7.2e-5 at 2048; at these 31 points: the cells straddling the first step's edges
#: converge as the square root of the cell, docs/general_solver.md "Edge paths") since 0.4.13, whose step paths
#: are the normal problem's to far below a cell (EdgePath._verify); 1.7e-3 / 1.5e-3 before (1.8e-3 at 2048 and 4096,
#: benchmarks/stuck_growth_exact.py: the single cubic's edges, 2.4e-4 of the width off mid-step, set the locks of
#: the material arriving in the step). Tolerance 2x.
GROWING_STUCK_TOL = {512: 6e-4, 1024: 3e-4}


@pytest.mark.parametrize("nodes", [512, 1024])
def test_a_contact_growing_under_a_moment_sticks_as_m1_says(nodes):
    """P, Q, M and sigma in proportion from zero (MOVING_GROWTH): both steps stick everywhere, and the shear
    is the exact fully stuck one (helpers.stuck_shear): after the forming step to FORMING_STUCK_TOL, after the
    second, whose contact starts in contact and grows on both sides while the moment moves it, to
    GROWING_STUCK_TOL (the arrivals' locks from an edge path accurate to far below a cell; docs/general_solver.md,
    "Edge paths"). The second step's path is a table (its single cubic is not within the allowance)."""
    problem, solver = make("hertz", nodes, width=MOVING_GROWTH_WIDTH)
    out = helpers.march(solver, MOVING_GROWTH)
    errors = []
    for k, (state, report) in enumerate(out, 1):
        assert report.regime == Regime.STICK and not report.slipped and report.converged
        W = state.contact_right - state.contact_left
        x = np.linspace(state.contact_left + 0.03 * W, state.contact_right - 0.03 * W, 31)
        exact = np.array([helpers.stuck_shear(problem, MOVING_GROWTH[:k], v) for v in x])
        _, q = solver.tractions(state.memory, x)
        errors.append(float(np.max(np.abs(q - exact)) / np.max(np.abs(exact))))
    assert errors[0] <= FORMING_STUCK_TOL[nodes], errors
    assert errors[1] <= GROWING_STUCK_TOL[nodes], errors
    second = [v for _, v, _ in solver._paths._items.values() if v is not None and v.loads1 == Loads(*MOVING_GROWTH[1])]
    assert second and all(p.kind == "table" for p in second)


def motor_path(spc=64, cycles=2, P1=3e4, Q1=3e4):
    path = [(P0 * k / 20, Q1 * k / 20) for k in range(1, 21)]
    for _ in range(cycles):
        for k in range(1, spc + 1):
            w = 2 * math.pi * k / spc
            path.append((P0 + P1 * math.sin(w), Q1 * math.cos(w)))
    return path


def test_agreement_with_exact_varying_P():
    """Motor loop (P = P0 + P1 sin wt, Q = Q1 sin(wt + 90 deg)) on Hertz at 512 nodes against the exact
    method: contact edges (1e-12), regimes, stick edges, q and the dissipation of the second cycle.

    Stick edges, first order (max 5.5e-4 / 3.1e-4 / 1.9e-4 / 1.3e-4 of W at
    256 .. 2048 nodes): tolerance 8e-4. q rms (of the exact q's max) 6.2e-3
    / 3.2e-3 / 3.1e-3 / 1.7e-3: tolerance 8e-3. Dissipation of the second
    cycle 0.42% low at 256 .. 1024 nodes alike (the time step's error, the
    lattice's is far below): tolerance 1.2%. Regimes agree on every other
    step at 256 .. 1024 nodes.
    Steps that run parallel to a slip line (abs(dQ/dP) within 1% of f) are
    compared by their dissipation only: there material locked at the slip
    limit makes the zone pattern ill-conditioned, and the general solver
    reports a few cells slipping where the exact method sticks, dissipating
    at most 1.2e-8 of a cycle's energy at 512 nodes (1.1e-5 at 256, 2.9e-9
    at 1024; tolerance 1e-6).
    """
    problem = NormalProblem(PROFILES["hertz"], A)
    general = GeneralSolver(problem, F, 512)
    exact = ExactMemory(problem, F, 1.3e5)
    path = motor_path()
    og, oe = march(general, path), march(exact, path)
    first = 20 + 64  # the second cycle starts after the ramp and one cycle
    cycle_g = og[-1][0].dissipation - og[first - 1][0].dissipation
    cycle_e = oe[-1][0].dissipation - oe[first - 1][0].dissipation
    assert cycle_g == pytest.approx(cycle_e, rel=1.2e-2)
    prev = (0.0, 0.0)
    for i, (P, Q) in enumerate(path):
        (sg, rg), (se, re) = og[i], oe[i]
        assert rg.converged, i
        a = se.contact_right
        W = se.contact_right - se.contact_left
        assert sg.contact_right == pytest.approx(a, rel=1e-12)
        parallel = abs(abs((Q - prev[1]) / (P - prev[0])) - F) < 0.01 * F
        prev = (P, Q)
        if parallel:
            if re.regime == Regime.STICK:
                assert sg.dissipation - og[i - 1][0].dissipation < 1e-6 * cycle_e, i
            continue
        assert rg.regime == re.regime, i
        assert abs(sg.stick_left - se.stick_left) / W < 8e-4, i
        assert abs(sg.stick_right - se.stick_right) / W < 8e-4, i
        x = np.linspace(-a, a, 401)
        qg, qe = general.tractions(sg.memory, x)[1], exact.tractions(se.memory, x)[1]
        assert np.sqrt(np.mean((qg - qe) ** 2)) < 8e-3 * np.max(np.abs(qe)), i


def cattaneo_cycles(nodes, stations=None):
    """Two Cattaneo-Mindlin cycles Q = 0.6 f P0 sin(2 pi k / 40) at constant P0 on Hertz: (general, exact) runs."""
    problem = NormalProblem(PROFILES["hertz"], A)
    general = GeneralSolver(problem, F, nodes, stations=stations)
    exact = ExactMemory(problem, F, P0, stations=stations)
    path = [(P0, 0.0)] + [(P0, 0.6 * F * P0 * math.sin(2 * math.pi * k / 40)) for k in range(1, 81)]
    return general, march(general, path), exact, march(exact, path)


def test_shift_slip_and_dissipation_against_exact():
    """Cattaneo-Mindlin cycles at constant P, 1024 nodes (datum l = profile length scale for both): the
    regimes, stick edges, rigid shift, slip of tracked stations and dissipation per cycle agree with the
    exact method.

    Measured at 256 / 512 / 1024 / 2048 nodes: shift 4.2e-6 / 8.2e-7 /
    2.6e-7 / 5.0e-8 of its range (order ~2; tolerance 1e-6); slip 9.0e-4 /
    5.0e-4 / 8.3e-5 / 1.4e-5 of the largest slip (tolerance 3e-4); energy
    per cycle 2.5e-4 / 6.6e-5 / 1.7e-5 / 3.6e-6 (order ~2; tolerance 5e-5);
    stick edges 1.7e-3 / 9.2e-4 / 4.4e-4 / 1.6e-4 of W (first order, worst
    right after a reversal where the new slip zones are a cell wide;
    tolerance 1e-3). Regimes agree except where the exact slip zones are
    narrower than a cell (the step after each peak: 9.2e-4 W, 0.95 of a
    cell at 1024 nodes), where the lattice may see full stick (it does at
    256 and 512 nodes, where that zone is 0.24 and 0.47 of a cell).
    """
    a = float(NormalProblem(PROFILES["hertz"], A).half_width(P0))
    W = 2 * a
    stations = np.linspace(-a, a, 41)[1:-1]
    general, og, exact, oe = cattaneo_cycles(1024, stations)
    for (sg, rg), (se, re) in zip(og, oe):
        assert rg.converged
        narrow = re.regime == Regime.PARTIAL_SLIP and se.contact_right - se.stick_right < W / 1024
        assert rg.regime == re.regime or (narrow and rg.regime == Regime.STICK)
        if re.regime == Regime.PARTIAL_SLIP:
            assert abs(sg.stick_left - se.stick_left) < 1e-3 * W and abs(sg.stick_right - se.stick_right) < 1e-3 * W
    shifts_g = np.array([s.shift for s, _ in og])
    shifts_e = np.array([s.shift for s, _ in oe])
    assert np.max(np.abs(shifts_g - shifts_e)) < 1e-6 * (shifts_e.max() - shifts_e.min())
    slips_g = np.array([general.slip(s.memory) for s, _ in og[1:]])
    slips_e = np.array([exact.slip(s.memory) for s, _ in oe[1:]])
    assert np.array_equal(np.isnan(slips_g), np.isnan(slips_e))
    assert np.nanmax(np.abs(slips_g - slips_e)) <= 3e-4 * np.nanmax(np.abs(slips_e))
    per_cycle_g = og[-1][0].dissipation - og[40][0].dissipation
    per_cycle_e = oe[-1][0].dissipation - oe[40][0].dissipation
    assert per_cycle_g == pytest.approx(per_cycle_e, rel=5e-5)


# ---------------------------------------------------------------------------
# moment
# ---------------------------------------------------------------------------


def test_moment_moves_the_contact_and_the_stick_zone():
    """Hertz with M (1024 nodes): P and M raised together (centre x0 = M/P) stick; then Q gives Cattaneo
    about x0; moving M at constant P and Q then moves the contact, the edge it moves towards advances
    stuck, the other recedes slipping, and the stick zone follows the contact.

    Cattaneo edges: 1.4e-4 / 6.5e-5 / 1.9e-5 / 1.2e-5 of W at 256 .. 2048
    nodes; tolerance 9e-5. The contact moves 3% of its width per step.
    Material arriving at the advancing edge sticks ((S1) holds there): by
    default the step is sub-stepped one cell of arrival at a time, and the
    stick zone reaches the advancing edge (no band of slip). Without those
    sub-steps (``arrivals=False``) the arrivals lock the displacement of the
    stuck increments of a fully stuck contact, missing the shear the
    receding slip zone sheds, and a band next to the advancing edge slips:
    first order in the (sub-)step, 0.051 / 0.082 / 0.095 / 0.090 of the edge
    travel per sub-step at 256 .. 2048 nodes (9.5e-4 W at 1024); tolerance
    0.2 of it.
    """
    for arrivals in (True, False):
        problem, solver = make("hertz", arrivals=arrivals)
        a = float(problem.half_width(P0))
        W = 2 * a
        x0 = 0.3 * a
        out = march(solver, [(P0 * k / 10, 0.0, x0 * P0 * k / 10) for k in range(1, 11)])
        assert all(report.regime == Regime.STICK for _, report in out)
        state, report = march(solver, [(P0, 0.5 * F * P0, x0 * P0)], out[-1][0])[-1]
        b = a * math.sqrt(0.5)
        assert abs(state.stick_left - (x0 - b)) / W < 9e-5 and abs(state.stick_right - (x0 + b)) / W < 9e-5
        centres = [0.5 * (state.stick_left + state.stick_right)]
        band = 0.0
        for k in range(1, 11):
            state, report = march(solver, [(P0, 0.5 * F * P0, (x0 - 0.06 * a * k) * P0)], state)[-1]
            assert report.regime == Regime.PARTIAL_SLIP and report.converged
            assert state.contact_left == pytest.approx(x0 - 0.06 * a * k - a, rel=1e-12)
            assert solver.stick_intervals(state) == 1
            assert state.memory.status[-1] == 1  # the receding edge slips
            assert state.contact_left <= state.stick_left < state.stick_right < state.contact_right
            band = max(band, (state.stick_left - state.contact_left) / W)
            centres.append(0.5 * (state.stick_left + state.stick_right))
        assert np.all(np.diff(centres) < 0.0)
        if arrivals:
            assert band == 0.0
        else:
            per_substep = 0.03 / math.ceil(0.03 / solver.travel)
            assert 0.0 < band < 0.2 * per_substep, band


# ---------------------------------------------------------------------------
# states and invariants
# ---------------------------------------------------------------------------


def test_gross_sliding_separation_and_recontact():
    """abs(Q) > f P slides (and says so), P <= 0 separates and forgets, contact re-forms stuck
    (256 nodes; the re-formed q = (Q/P) p: rms 2.8e-4 of its max, tolerance 1e-3 as for proportional
    loading, test_proportional_loading_sticks_fully)."""
    problem, solver = make("hertz", 256)
    out = march(solver, [(P0, 0.0), (P0, 0.5 * F * P0), (P0, 1.2 * F * P0), (P0, 0.3 * F * P0),
                         (0.0, 0.0), (-1.0, 0.0), (P0, 0.2 * F * P0)])
    regimes = [r.regime for _, r in out]
    assert regimes == [Regime.STICK, Regime.PARTIAL_SLIP, Regime.GROSS_SLIDING, Regime.PARTIAL_SLIP,
                       Regime.SEPARATED, Regime.SEPARATED, Regime.STICK]
    assert all(r.converged for _, r in out)
    assert "gross sliding" in out[2][1].message
    state = out[2][0]
    a = state.contact_right
    x = np.linspace(-a, a, 4001)
    p, q = solver.tractions(state.memory, x)
    assert np.max(np.abs(q - F * p)) <= 1e-12 * F * p.max()
    assert solver.shear_force(state.memory) == pytest.approx(F * P0, rel=1e-12)
    assert math.isnan(state.stick_left) and math.isnan(state.stick_right)
    separated = out[4][0]
    assert math.isnan(separated.contact_left) and separated.memory.q.size == 0 and separated.memory.normal is None
    assert solver.stick_intervals(separated) == 0
    assert np.all(solver.station_states(separated, x, np.zeros_like(x)) == OUT_OF_CONTACT)
    state, report = out[-1]
    assert not report.slipped and not np.any(state.memory.G)
    p, q = solver.tractions(state.memory, x)
    assert np.sqrt(np.mean((q - 0.2 * F * p) ** 2)) < 1e-3 * 0.2 * F * p.max()


def test_holds_and_normal_solves():
    """A step that changes neither P nor M solves no normal problem; a hold changes nothing and
    reports no error estimate (NaN)."""
    problem, solver = make("hertz", 256)
    (s1, r1), (s2, r2), (s3, r3) = march(solver, [(P0, 0.0), (P0, 0.2 * F * P0), (P0, 0.2 * F * P0)])
    assert r1.normal_solved and not r2.normal_solved and not r3.normal_solved
    assert solver.counters["normal_solves"] == 1
    assert r3.regime == Regime.STICK and not r3.slipped
    assert s3.memory is s2.memory and s3.dissipation == s2.dissipation
    assert math.isnan(r3.error_estimate)


def test_step_does_not_mutate_its_input():
    problem, solver = make("punch", 256)
    state = march(solver, [(P0, 0.1 * F * P0, 1e-5 * P0, 1e7)])[-1][0]
    fields = ("status", "q", "g", "G", "capacity")
    memories = (state.memory, state.memory.coarse)
    before = [{k: getattr(m, k).copy() for k in fields} for m in memories]
    scalars = (state.shift, state.dissipation, state.stick_left, state.memory.shift, state.memory.first)
    march(solver, [(0.9 * P0, 0.4 * F * P0, 0.0, -1e7), (1.1 * P0, -0.3 * F * P0)], state)
    assert (state.shift, state.dissipation, state.stick_left, state.memory.shift, state.memory.first) == scalars
    for mem, saved in zip(memories, before):
        for k, v in saved.items():
            arr = getattr(mem, k)
            assert np.array_equal(arr, v)
            assert not arr.flags.writeable
            with pytest.raises(ValueError):
                arr[...] = 0


loads_step = st.tuples(
    st.floats(0.3, 1.5),  # P / P0
    st.floats(-0.9, 0.9),  # Q / (f P)
    st.floats(-0.3, 0.3),  # M / (P a0)
    st.floats(-3e7, 3e7),  # sigma
)


@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(kind=st.sampled_from(sorted(PROFILES)), steps=st.lists(loads_step, min_size=3, max_size=8))
def test_invariants_on_random_histories(kind, steps):
    """Every step converges (residual <= 1) and reports a finite error estimate when it slipped;
    dissipation never decreases; no traction outside the contact; equilibrium of the carried force
    (h sum q_j: measured 4.4e-16 of f P over 844 random steps at 128 nodes; tolerance 1e-12) and of
    the output q (trapezoid on 20001 points across cell jumps and square-root edges: measured
    7.5e-5 of f P; tolerance 3e-4); Coulomb (q_j <= f cap_j up to FLIP_TOL = 1e-10 of f max p;
    measured excess 0, tolerance 1e-9); the stick intervals and the per-station codes agree with
    the cells (split stick zones: 45 of the 844 steps)."""
    problem, solver = make(kind, 128)
    a0 = float(problem.half_width(P0))
    path = [(P * P0, Qr * F * P * P0, Mr * P * P0 * a0, sigma) for P, Qr, Mr, sigma in steps]
    previous = 0.0
    for state, report in march(solver, path):
        assert report.converged and report.residual <= 1.0, report
        if report.slipped:
            assert math.isfinite(report.error_estimate) and report.error_estimate >= 0.0
        assert state.dissipation >= previous
        previous = state.dissipation
        if report.regime == Regime.SEPARATED:
            continue
        L, Rr = state.contact_left, state.contact_right
        x = np.linspace(L - 0.1 * (Rr - L), Rr + 0.1 * (Rr - L), 20001)
        p, q = solver.tractions(state.memory, x)
        outside = (x <= L) | (x >= Rr)
        assert np.all(p[outside] == 0.0) and np.all(q[outside] == 0.0)
        fP = F * state.loads.P
        assert abs(solver.shear_force(state.memory) - state.loads.Q) <= 1e-12 * fP
        integral = float(np.sum(0.5 * (q[1:] + q[:-1]) * np.diff(x)))
        assert abs(integral - state.loads.Q) <= 3e-4 * fP
        assert np.max(np.abs(q) - F * p) <= 1e-9 * F * p.max()
        status = state.memory.status
        runs = np.count_nonzero(np.diff(np.concatenate(([0], (status == 0).astype(np.int8), [0]))) == 1)
        assert solver.stick_intervals(state) == runs
        codes = solver.station_states(state, state.memory.x, solver.tractions(state.memory, state.memory.x)[1])
        expected = np.select([status == 0, status > 0, status < 0], [STICK, FORWARD_SLIP, BACKWARD_SLIP])
        inside = (state.memory.x >= L) & (state.memory.x <= Rr)
        assert np.array_equal(codes[inside], expected[inside])


@pytest.mark.parametrize("kind", PROFILES)
def test_convergence_under_refinement(kind):
    """At 64 / 256 / 1024 nodes: the J2 shear (unloading from 0.6 f P to 0) and the J1 stick edges
    (worst over Q = 0.1 .. 0.9 f P) converge at about first order.

    Observed order per doubling (two doublings per pair): J2 q rms 1.07 /
    0.73 (Hertz: 5.0e-2, 1.1e-2, 4.1e-3) and 0.98 / 0.69 (punch: 6.6e-2,
    1.7e-2, 6.6e-3); J1 edges 1.34 / 0.92 (Hertz: 3.0e-3, 4.6e-4, 1.3e-4 of
    W) and 1.88 / 0.90 (punch: 8.4e-3, 6.2e-4, 1.8e-4). Asserted: every order
    above 0.35 (half the smallest), the J2 rms at 1024 below 2e-2 and the J1
    edges at 1024 below half a cell (measured 0.13 and 0.18 of a cell).
    """
    problem = NormalProblem(PROFILES[kind], A)
    Q_max = 0.6 * F * P0
    a = float(problem.half_width(P0))
    W = 2 * a
    x = np.linspace(-a, a, 4001)
    q_closed = j2_closed(problem, x, Q_max, 0.0)
    rms, edges = [], []
    for nodes in (64, 256, 1024):
        solver = GeneralSolver(problem, F, nodes)
        out = march(solver, [(P0, 0.0), (P0, Q_max), (P0, 0.0)])
        rms.append(q_errors(solver.tractions(out[-1][0].memory, x)[1], q_closed, x, [], W)[0])
        worst = 0.0
        for ratio in np.linspace(0.1, 0.9, 9):
            state = march(solver, [(P0, ratio * F * P0)], out[0][0])[-1][0]
            b = float(problem.half_width(P0 - ratio * P0))
            worst = max(worst, abs(state.stick_left + b) / W, abs(state.stick_right - b) / W)
        edges.append(worst)
    for errors in (rms, edges):
        order = np.log2(np.array(errors[:-1]) / np.array(errors[1:])) / 2.0
        assert np.all(order > 0.35), (rms, edges, order)
    assert rms[-1] < 2e-2
    assert edges[-1] < 0.5 / 1024


def test_dissipation_per_cycle_converges():
    """The energy per Cattaneo-Mindlin cycle against the exact method converges at about second order:
    relative error 2.5e-4 at 256 nodes, 1.7e-5 at 1024 (order 1.9 per doubling); asserted: order above
    1 and the error at 1024 below 5e-5."""
    errors = []
    for nodes in (256, 1024):
        _, og, _, oe = cattaneo_cycles(nodes)
        per_cycle_g = og[-1][0].dissipation - og[40][0].dissipation
        per_cycle_e = oe[-1][0].dissipation - oe[40][0].dissipation
        errors.append(abs(per_cycle_g / per_cycle_e - 1.0))
    assert math.log2(errors[0] / errors[1]) / 2.0 > 1.0, errors
    assert errors[1] < 5e-5


# ---------------------------------------------------------------------------
# the new design: sub-steps, the error estimate, split stick zones, restarts
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("kind", PROFILES)
def test_substeps_cut_the_dissipation_error_of_a_growing_slipping_contact(kind):
    """P and Q raised together at dQ/dP = 1.2 f (slipping while the contact grows), then Q reversed
    while P keeps growing, in two straight steps (512 nodes), against the exact method.

    Without sub-steps (travel = stick_travel = 0, arrivals=False) the dissipation is 8.2%
    (Hertz) / 7.5% (punch) low; with sub-steps of the contact travel alone
    (stick_travel = 0) the error falls at about second order in the sub-step
    (Hertz: 2.05 / 0.71 / 0.22 / 0.052% for travel 0.08 / 0.04 / 0.02 /
    0.01; punch: 5.1 / 1.35 / 0.28% for 0.04 / 0.02 / 0.01; the same to 0.1%
    at 1024 nodes; arrivals=False isolates it), and with the defaults (also
    sub-steps of one cell of arrival while part of the contact slips) it is
    +0.006% / +0.13% (189 / 49 sub-steps over the three steps). Asserted:
    above 4% without, below 1% at the defaults, and travel 0.01 at least 6x
    better than 0.04 (measured 13.6x / 18.5x: order above 1.3).
    """
    problem = NormalProblem(PROFILES[kind], A)
    path = [(0.5 * P0, 0.0), (P0, 1.2 * F * 0.5 * P0), (1.5 * P0, -0.1 * F * P0)]
    reference = march(ExactMemory(problem, F, 2 * P0), path)[-1][0].dissipation
    errors = {}
    for travel, stick_travel in ((0.0, 0.0), (0.04, 0.0), (0.01, 0.0), (None, None)):
        solver = GeneralSolver(problem, F, 512, travel=travel, stick_travel=stick_travel, arrivals=travel is None)
        out = march(solver, path)
        assert all(report.converged for _, report in out)
        assert (solver.counters["substeps"] > 0) == (travel != 0.0)
        errors[travel] = out[-1][0].dissipation / reference - 1.0
    assert abs(errors[0.0]) > 4e-2, errors
    assert abs(errors[None]) < 1e-2, errors
    assert abs(errors[0.01]) < abs(errors[0.04]) / 6, errors


def test_error_estimate_on_every_slipping_step_bounds_the_edge_error():
    """The two-grid estimate (distance of the stick edges to a half-resolution shadow's, / W; the largest
    of a step's sub-steps; at least EDGE_PLACEMENT = 0.1 of a cell) is reported on every slipping step
    and bounds the actual edge error within a measured factor.

    J1 (Q = 0.25, 0.5, 0.75 f P) and J2 (unloading from 0.6 f P to 0.4, 0,
    -0.5 of it) on both profiles at 128 / 256 / 512 nodes (36 steps): actual
    / estimate is 0.35 in the median and at most 1.06 (punch, 256 nodes);
    asserted: at most 3 on every step, below 0.6 in the median. Over a
    denser scan (19 loads and 12 unloadings per resolution, 128 .. 1024
    nodes, 248 steps) at most 1.65. Without the floor (since 0.3.2 the edges
    are placed by the traction margin, 0.09 of a cell in the median) the
    lattices agreed by chance to 0.003 of a cell where the error was 0.1 (a
    ratio of 39; this test's punch at 128 nodes: 3.4). The memory keeps the
    last sub-step's estimate (at most the reported one). Without the shadow
    (estimate=False) the report carries NaN.
    """
    ratios = []
    for kind in PROFILES:
        for nodes in (128, 256, 512):
            problem, solver = make(kind, nodes)
            a = float(problem.half_width(P0))
            W = 2 * a
            base = march(solver, [(P0, 0.0)])[-1][0]
            cases = []
            for ratio in (0.25, 0.5, 0.75):
                state, report = march(solver, [(P0, ratio * F * P0)], base)[-1]
                cases.append((state, report, float(problem.half_width(P0 - ratio * P0))))
            Q_max = 0.6 * F * P0
            loaded = march(solver, [(P0, Q_max)], base)[-1][0]
            for fraction in (0.4, 0.0, -0.5):
                state, report = march(solver, [(P0, fraction * Q_max)], loaded)[-1]
                cases.append((state, report, float(problem.half_width(P0 - (1 - fraction) * Q_max / (2 * F)))))
            for state, report, b in cases:
                assert report.slipped and report.regime == Regime.PARTIAL_SLIP
                estimate = report.error_estimate
                assert math.isfinite(estimate) and estimate > 0.0 and state.memory.error <= estimate
                actual = max(abs(state.stick_left + b), abs(state.stick_right - b)) / W
                assert actual <= 3.0 * estimate, (kind, nodes, b, actual, estimate)
                ratios.append(actual / estimate)
    assert np.median(ratios) < 0.6, np.median(ratios)
    problem, solver = make("hertz", 256, estimate=False)
    _, report = march(solver, [(P0, 0.0), (P0, 0.5 * F * P0)])[-1]
    assert report.slipped and math.isnan(report.error_estimate)


@pytest.mark.parametrize("kind", PROFILES)
@pytest.mark.parametrize("nodes", [128, 1024])
def test_slip_zone_narrower_than_a_cell(kind, nodes):
    """J1 at Q = 0.001 .. 0.03 f P: slip zones of 0.1 to 1 cell at 128 nodes, 0.5 to 8 at 1024.

    Where the end cell sticks, (S1) says the edge slips and the slip zone is placed inside the end
    cell ((x - E) m^2 -> x - c, the local Cattaneo solution): the largest edge error is 0.18 /
    0.16 of a cell (Hertz, 128 / 1024 nodes), 0.06 / 0.18 (punch); with the end cell taken as the
    edge (until 0.3.1) 0.68 / 0.51 and 0.32 / 0.68. Tolerance 0.3 of a cell. A step whose cells all
    stick but whose edges slip by (S1) is a partial slip whose slip zones are within the end cells
    (no cell slipped: nothing dissipated), and its estimate is at least SUBCELL_PLACEMENT of a cell
    (a whole cell until 0.3.3); every step's estimate bounds its error within 1.5x.
    """
    problem, solver = make(kind, nodes)
    a = float(problem.half_width(P0))
    base = march(solver, [(P0, 0.0)])[-1][0]
    worst = 0.0
    for ratio in np.linspace(0.001, 0.03, 30):
        state, report = march(solver, [(P0, ratio * F * P0)], base)[-1]
        b = float(problem.half_width(P0 - ratio * P0))
        h = state.memory.spacing
        worst = max(worst, abs(state.stick_right - b) / h, abs(state.stick_left + b) / h)
        assert report.regime == Regime.PARTIAL_SLIP and report.converged
        assert -a < state.stick_left < state.stick_right < a
        if not report.slipped:
            assert np.all(state.memory.status == 0) and state.dissipation == base.dissipation
            assert report.error_estimate >= general_module.SUBCELL_PLACEMENT * h / (2 * a)
        # the estimate bounds the error: measured error / estimate <= 1.15 over Q = 0.001 .. 0.06 f P
        # at 128 .. 1024 nodes with a floor of 0.2 cell where the zone is within the end cell (0.5 since)
        error = max(abs(state.stick_right - b), abs(state.stick_left + b)) / (2 * a)
        assert error <= 1.5 * report.error_estimate, (ratio, error, report.error_estimate)
    assert worst < 0.3, worst


@pytest.mark.parametrize("kind", PROFILES)
@pytest.mark.parametrize("windows", [False, True])
def test_sub_cell_zones_at_receding_edges_against_exact(kind, windows):
    """J3 with P falling slowly: (P0, 0.3 f P0) reached proportionally in 10 steps, then P down to 0.99 P0
    in 20 steps along dQ/dP = 0.25 f and 0.35 f (both edges recede while slipping: zones of 3e-6 .. 2e-4
    of the width, inside the end cell), at 512 nodes, against the exact method. The outermost stick
    points of the zones narrower than 1.5 cells are within SUBCELL_PLACEMENT of the cell that placed them
    (the lattice's, or the window's fine cell where a window reported the edge): the floor of their
    estimate (0.3 since 0.4.9) is twice the largest error measured on the closed forms (0.068 of a cell
    on the lattice, 0.146 of a fine cell on the windows; here 0.036 / 0.054 on the lattice and 0.127 /
    0.071 on the windows, Hertz / punch,
    benchmarks/subcell_exact.py). Every step's estimate covers its error."""
    problem = NormalProblem(PROFILES[kind], A)
    exact = ExactMemory(problem, F, 1.3 * P0)
    general = GeneralSolver(problem, F, 512, edge_windows=windows)
    worst = 0.0
    for kp in (0.25, 0.35):
        path = [(P0 * j / 10, 0.3 * F * P0 * j / 10) for j in range(1, 11)]
        path += [(P0 * (1 - 0.01 * j / 20), 0.3 * F * P0 - kp * F * 0.01 * P0 * j / 20) for j in range(1, 21)]
        for (sg, rg), (se, _) in zip(march(general, path), march(exact, path)):
            assert rg.converged
            W = se.contact_right - se.contact_left
            errors = []
            for side, got, want, edge in ((-1, sg.stick_left, se.stick_left, se.contact_left),
                                          (1, sg.stick_right, se.stick_right, se.contact_right)):
                cell = next((w.spacing for w in sg.memory.windows if w.side == side and got != w.lattice_edge),
                            sg.memory.spacing)
                errors.append(abs(got - want))
                if abs(want - edge) < 1.5 * cell and abs(got - edge) < 1.5 * cell:
                    worst = max(worst, abs(got - want) / cell)
            assert max(errors) / W <= rg.error_estimate, (kp, max(errors) / W, rg.error_estimate)
    assert 0.0 < worst <= general_module.SUBCELL_PLACEMENT, worst


def test_an_end_cell_near_its_bound_places_its_zone_to_half_a_cell():
    """_run_edges on 16 unit cells (Hertz's contact only for its edges): a stick run from the end cell, whose
    contact edge (S1) says slips. The zone is put inside the end cell by the local form, to SUBCELL_PLACEMENT
    of a cell; with the end cell within END_RATIO_ERROR of its bound (q = 0.97 of it) it may as well slip,
    and the zone take the whole cell: half a cell."""
    problem = NormalProblem(helpers.PROFILES["hertz"], A)
    N = problem.solve(P0)
    n = 16
    x = N.left + np.arange(n) + 0.5
    qmax = np.ones(n)
    status = np.zeros(n, np.int8)
    q = np.full(n, 0.3)
    q[0] = 0.9
    drives = ((1.0, 0.0), (0.0, 0.0))
    left, _, placement = general_module._run_edges(x, q, qmax, status, N, 1.0, 0, n - 1, (True, False), drives, 0)
    assert N.left < left <= x[0] + general_module.EDGE_INSIDE
    assert placement == general_module.SUBCELL_PLACEMENT == 0.3
    q[0] = 1.0 - 0.6 * general_module.END_RATIO_ERROR
    placement = general_module._run_edges(x, q, qmax, status, N, 1.0, 0, n - 1, (True, False), drives, 0)[2]
    assert placement == 0.5


def test_slip_zone_of_about_a_cell():
    """A rounded punch under Q and sigma at 128 nodes: the slip zones grow from 0.1 to 1.2 cells, through
    the end cell. Where the end cell is the only slipping cell the edge is placed by the local
    Cattaneo form, as within the end cell (since 0.3.3). Against the same scene at 2048 nodes (its own
    estimate at most 0.02 of a 128-node cell): largest error 0.22 of a cell, 0.54 when the traction
    margin's square was extrapolated there (it stopped at the end cell's centre, 0.5 cell from the
    contact edge, where the zones were 0.7 - 1.0 cell). Tolerance 0.3 of a cell, as for the zones within
    the end cell; and every step's estimate bounds its error (measured: error / estimate <= 0.9).
    """
    import halfslip as hs

    reference = hs.simulate(hs.parse_scene(helpers.NARROW_SLIP_SCENE), nodes=2048)
    run = hs.simulate(hs.parse_scene(helpers.NARROW_SLIP_SCENE), nodes=128)
    ramp = run.step.values > 4
    W = (reference.contact_right - reference.contact_left).values[ramp]
    error = np.maximum(abs(run.stick_left - reference.stick_left),
                       abs(run.stick_right - reference.stick_right)).values[ramp] / W
    zones = (reference.contact_right - reference.stick_right).values[ramp] * 128 / W
    assert zones.min() < 0.5 and zones.max() > 1.0  # through the end cell
    assert np.all(run.regime.values[ramp] == 2)
    assert error.max() * 128 < 0.3, error * 128
    assert np.all(error <= run.error_estimate.values[ramp]), (error, run.error_estimate.values[ramp])


@pytest.mark.parametrize("kind", PROFILES)
def test_shear_error_estimate_bounds_the_shear_error(kind):
    """The two-grid estimate of the shear (int abs(q_fine - q_shadow) dx / f P, both as (q_j / cap_j) p)
    bounds int abs(q - q_J1) dx / f P on J1 (Q = 0.25, 0.5, 0.75 f P) at 128 / 256 / 512 nodes.

    Measured: error / estimate 0.34 .. 0.68 (0.51 in the median) on both profiles, the error
    2.7e-3 / 1.3e-3 / 6.8e-4 of f P (Hertz, Q = 0.25 f P): first order, as the estimate
    assumes. Asserted: the ratio at most 1 (the estimate bounds the error, margin 1.5x) and at
    least 0.2 (it is not idly pessimistic).
    """
    for nodes in (128, 256, 512):
        problem, solver = make(kind, nodes)
        base = march(solver, [(P0, 0.0)])[-1][0]
        for ratio in (0.25, 0.5, 0.75):
            state, report = march(solver, [(P0, ratio * F * P0)], base)[-1]
            x = np.linspace(state.contact_left, state.contact_right, 20001)
            q = solver.tractions(state.memory, x)[1]
            closed = F * (problem.pressure(x, P0) - problem.pressure(x, P0 - ratio * P0))
            error = np.trapezoid(np.abs(q - closed), x) / (F * P0)
            estimate = report.shear_error_estimate
            assert 0.2 * estimate <= error <= estimate, (nodes, ratio, error, estimate)


#: The load samples of benchmarks/random_histories.py random_history(0, "punch") up to its step 61.
SPLIT_HISTORY = helpers.DATA / "split_history.csv"
#: The IC reference at N = 8000 (benchmarks/reference/runs/punch_0_8000.npz) at step 61, relative to
#: the contact width from its left edge: outermost stick point, left and right end of the widest stick
#: interval (its own error 2e-5 .. 1e-4 of W from its N = 4000 run).
SPLIT_REFERENCE = (0.0098, 0.4991, 1.0)
#: Measured: 1.4e-3 / 8e-5 of W at 256 / 1024 nodes (a third of a cell, and a tenth); tolerances 2x a
#: cell of 256 and 1e-3.
SPLIT_TOL = {256: 2.0 / 256, 1024: 1e-3}


@pytest.mark.parametrize("nodes", [256, 1024])
def test_split_stick_zones_are_represented(nodes):
    """A random (P, Q, M, sigma) history on the rounded punch (Ti-6Al-4V, w = 2 mm, R = 10 mm, f = 0.6)
    whose step 61 has two stick intervals, [0.010, 0.285] and [0.499, 1] of the contact from its
    left edge, with slip between them and in a thin zone at the left edge (the IC reference agrees).

    Asserted: two stick intervals; the outermost stick point and the ends of the widest interval
    against the reference within SPLIT_TOL; every cell between the intervals slips; the
    per-station codes slip / stick / slip / stick across them. (The one-step case from zero that
    this test used before had an interior slip zone only because the formation step was not
    sub-stepped: the IC reference and four sub-steps stick fully there.)
    """
    from halfslip.geometry import RoundedPunch

    data = np.loadtxt(SPLIT_HISTORY, delimiter=",")
    problem = NormalProblem(RoundedPunch(flat_half_width=2e-3, radius=10e-3), 4 * (1 - 0.3**2) / 115e9)
    width = max(problem.solve(P, M).right - problem.solve(P, M).left for P, M in data[1:, [1, 3]])
    solver = GeneralSolver(problem, 0.6, nodes, width=width)
    state, report = march(solver, data[1:, 1:])[-1]
    assert report.converged and report.regime == Regime.PARTIAL_SLIP
    assert solver.stick_intervals(state) == 2
    (a, b), (c, d) = solver.stick_zones(state)
    L, W = state.contact_left, state.contact_right - state.contact_left
    found = np.array([a - L, c - L, d - L]) / W
    assert np.all(np.abs(found - SPLIT_REFERENCE) <= SPLIT_TOL[nodes]), found
    mem = state.memory
    between = (mem.x > b + mem.spacing) & (mem.x < c - mem.spacing)
    assert np.all(mem.status[between] != 0)
    stations = L + W * np.array([0.5 * (a - L) / W, 0.15, 0.39, 0.75])
    codes = solver.station_states(state, stations, solver.tractions(mem, stations)[1])
    assert codes[1] == STICK and codes[3] == STICK
    assert codes[0] in (FORWARD_SLIP, BACKWARD_SLIP) and codes[2] in (FORWARD_SLIP, BACKWARD_SLIP), codes


ISLAND_HISTORY = helpers.DATA / "island_history.csv"


def test_an_island_at_a_slipping_edge_is_in_the_estimate():
    """A random (P, Q, M, sigma) history on Hertz (benchmarks/random_histories.py, seed 1).

    Its 95th step shrinks the contact at both edges with a shear drive, so (S1) says both edges slip.
    Until 0.3.6 a 3-cell stick island stayed at the left contact edge at 1024 nodes, 0.2 of the width
    outside the next stick interval, which 2048 and 4096 nodes and the IC reference do not have: the
    end cells carried their shear over the whole cell, not like the pressure over their supports.
    Now 1024 nodes have no island there either (asserted: two stick intervals, the outermost stick
    point that of the inner one).

    The 89th step at 512 nodes has an island of 3.8 cells at the left contact edge (at 1024 and 2048
    nodes it is there too, 0.006 - 0.007 of the width wide: this one is real) 0.24 of the width outside
    the next stick interval. A lattice cannot tell such an island from one that is not, and the shadow
    lattice has it too: an island of at most UNCONFIRMED_ISLAND cells at an edge that (S1) says slips
    reaches the estimate to the next stick run (estimate 1.6e-3 against an error of 0.2 until 0.3.2):
    asserted, the estimate covers the island's distance to the interval within 10 %.
    """
    data = np.loadtxt(ISLAND_HISTORY, delimiter=",")
    problem = NormalProblem(PROFILES["hertz"], 1.82e-11)
    width = max(problem.solve(P, M).right - problem.solve(P, M).left for P, M in data[1:, [1, 3]] if P > 0)
    solver = GeneralSolver(problem, 0.6, 1024, width=width)
    state, report = march(solver, data[1:96, 1:])[-1]
    zones = solver.stick_zones(state)
    assert report.converged and len(zones) == 2
    assert zones[0][0] == state.stick_left and state.stick_left - state.contact_left > 0.15 * (
        state.contact_right - state.contact_left)
    solver = GeneralSolver(problem, 0.6, 512, width=width)
    state, report = march(solver, data[1:90, 1:])[-1]
    zones = solver.stick_zones(state)
    W = state.contact_right - state.contact_left
    assert report.converged and len(zones) == 2
    island, inner = zones[0], zones[1]
    assert island[0] == state.stick_left and abs(island[0] - state.contact_left) < state.memory.spacing
    assert island[1] - island[0] < general_module.UNCONFIRMED_ISLAND * state.memory.spacing
    assert report.error_estimate >= 0.9 * (inner[0] - island[0]) / W > 0.15


def test_undecided_band_counts_the_cells_at_their_bound_that_do_not_slip():
    """_undecided_band: at the edge beside the stuck cell ``end`` (``step`` the way out), the stuck cells
    at their bound (within qtol) inward and the slipping cells that do not slip (within stol) outward.
    Cells of unit capacity: 0..1 slip backwards by 1, 2 slips by 1e-12 (not slipping), 3..4 are stuck at
    -1 (at the bound), 5..12 stuck inside it, 13 stuck at the bound within qtol, 14..15 slip forwards by
    1."""
    n = 16
    qmax = np.ones(n)
    status = np.zeros(n, np.int8)
    status[:3], status[14:] = -1, 1
    q = np.full(n, 0.5)
    q[:5], q[13:] = -1.0, 1.0
    q[13] = 1.0 - 1e-12
    s = np.zeros(n)
    s[:2], s[2], s[14:] = -1.0, -1e-12, 1.0
    band = general_module._undecided_band
    assert band(q, qmax, s, status, 3, -1, 1e-10, 1e-10) == (2, 1)
    assert band(q, qmax, s, status, 3, -1, 1e-10, 1e-13) == (2, 0)  # cell 2 slips at this tolerance
    assert band(q, qmax, s, status, 13, 1, 1e-10, 1e-10) == (1, 0)
    q[13] = 1.0 - 1e-9  # inside its bound at qtol
    assert band(q, qmax, s, status, 13, 1, 1e-10, 1e-10) == (0, 0)
    q[3:5] = -0.9
    assert band(q, qmax, s, status, 3, -1, 1e-10, 1e-13) == (0, 0)


def test_undecided_reach_spans_the_patterns_either_way():
    """_undecided_reach on cells of width 1 (16 cells, unit capacity, Hertz's contact only for the
    contact edges, which no run here reaches): the stick cells 3..12, cells 0..2 and 13..15 slipping
    forwards by 1. With margins that grow inwards and no undecided cell, 0. With cells 3 and 4 at their
    bound, the edge the pattern with them slipping gives (from cell 5) is the reach, plus the
    EDGE_PLACEMENT floor. With a two-cell island 3..4 at its bound beside slipping cells 5..6 (no
    slip), the island slipping leaves the run 7..12: the reach goes to its edge. With every stick cell
    at its bound, the reach is their span."""
    problem = NormalProblem(helpers.PROFILES["hertz"], A)
    N = problem.solve(P0)
    n = 16
    x = np.arange(n) + 0.5
    qmax = np.ones(n)
    status = np.zeros(n, np.int8)
    status[:3] = status[13:] = 1
    q = np.ones(n)
    inner = np.abs(np.arange(n) - 7.5)
    q[3:13] = 1.0 - 0.2 * (5.0 - inner[3:13]) ** 0.5  # margins growing inwards like a square root
    s = np.zeros(n)
    s[:3] = s[13:] = 1.0
    reach = general_module._undecided_reach
    edges = general_module._run_edges(x, q, qmax, status, N, 1.0, 3, 12)[:2]
    args = (N, 1.0, 3, 12, (False, False), None)
    assert reach(x, q, qmax, s, status, *args, edges, 1e-10, 1e-10) == 0.0
    q[3:5] = 1.0
    edges = general_module._run_edges(x, q, qmax, status, N, 1.0, 3, 12)[:2]
    alt = status.copy()
    alt[3:5] = 1
    other = general_module._run_edges(x, q, qmax, alt, N, 1.0, 5, 12)[0]
    got = reach(x, q, qmax, s, status, *args, edges, 1e-10, 1e-10)
    assert got == pytest.approx(abs(other - edges[0]) + general_module.EDGE_PLACEMENT, rel=1e-12)
    assert 1.5 < got < 3.5
    status[5:7], q[5:7], s[5:7] = 1, 1.0, 0.0  # an island 3..4, then cells 5..6 at the bound, not slipping
    edges = general_module._run_edges(x, q, qmax, status, N, 1.0, 3, 12)[:2]
    got = reach(x, q, qmax, s, status, *args, edges, 1e-10, 1e-10)
    alt[5:7] = 1
    other = general_module._run_edges(x, q, qmax, alt, N, 1.0, 7, 12)[0]
    assert got == pytest.approx(abs(other - edges[0]) + general_module.EDGE_PLACEMENT, rel=1e-12)
    assert got > 3.5
    status[:] = 0
    status[:3] = status[13:] = 1
    q[3:13] = 1.0
    edges = general_module._run_edges(x, q, qmax, status, N, 1.0, 3, 12)[:2]
    assert reach(x, q, qmax, s, status, *args, edges, 1e-10, 1e-10) == 10.0


def test_an_undecided_band_at_the_dovetails_load_maximum_is_in_the_estimate(monkeypatch):
    """The dovetail example at 1000 nodes, the load maximum of its last marched cycle (t = 4.25 s,
    after 16 skipped cycles). There the three stuck cells next to the right stick edge carry their bound
    to 1e-10 of it and do not slip: the step is as much solved with them slipping (with zero slip), and
    that pattern puts the edge about three cells further in. Finer lattices do not decide it either: a
    16000-node run put the edge 12.4 um inside the 1000 - 8000-node ones (docs/user_guide.md), and at
    2000, 4000 and 8000 nodes the band is 6, 12 and 23 cells, about 12.5 um each time. Until 0.3.9 the
    estimate did not see it (5.6 um at 1000 nodes, 2.1 um at 2000); since, a band of undecided cells
    (_undecided_band) is in it. Asserted: the band is there (at least two cells, each within FLIP_TOL of
    its bound), the pattern with the band slipping passes the step's checks as well, and the estimate
    reaches the edge that pattern gives."""
    import dataclasses

    import halfslip as hs

    kept = {}
    step = GeneralSolver.step

    def record(self, state, t1, loads1):
        out = step(self, state, t1, loads1)
        if abs(t1 - 4.25) < 1e-9:
            kept["solver"], kept["out"] = self, out
        return out

    monkeypatch.setattr(GeneralSolver, "step", record)
    scene = hs.load_scene(helpers.EXAMPLES / "dovetail.yaml")
    hs.simulate(dataclasses.replace(scene, output=dataclasses.replace(scene.output, fields=())))
    solver, (state, report) = kept["solver"], kept["out"]
    mem = state.memory
    qmax = solver.f * mem.capacity
    stuck = np.flatnonzero(mem.status == 0)
    k = stuck[-1]
    assert mem.status[k + 1] == 1 and abs(mem.x[k] + 0.5 * mem.spacing - state.stick_right) < mem.spacing
    tight = general_module.FLIP_TOL * float(qmax.max())
    band = 0
    while mem.status[k - band] == 0 and mem.q[k - band] >= qmax[k - band] - tight:
        band += 1
    assert band >= 2
    # the band slipping forwards (its slip zero) is an answer of the step as well: Coulomb holds with
    # equality there, the slip direction (zero slip) holds, stick, equilibrium and the rest are the same cells
    other = mem.status.copy()
    other[k - band + 1:k + 1] = 1
    assert np.all(np.abs(mem.q) <= qmax + tight)
    edge = general_module._run_edges(mem.x, mem.q, qmax, other, mem.normal, mem.spacing, stuck[0], k - band)[1]
    W = state.contact_right - state.contact_left
    assert state.stick_right - edge > (band - 1) * mem.spacing
    assert report.error_estimate * W >= state.stick_right - edge


def test_projected_gradient_restart_finds_the_answer(monkeypatch):
    """With the active set cut to one iteration before each restart (MAX_ACTIVE_SET = 1), the
    projected-gradient restart still finds the unique answer: a J1 step (Hertz, 128 nodes, not
    sub-stepped) converges, its restarts are counted (measured 2: the fine lattice and the shadow),
    and the state equals the unrestricted one (the strictly convex problem has one solution: same
    pattern, q to 1e-9 of f max p, measured 0). About 2 s per restart (2000 gradient iterations)."""
    path = [(P0, 0.0), (P0, 0.5 * F * P0)]
    reference = march(make("hertz", 128, stick_travel=0.0)[1], path)[-1][0]
    monkeypatch.setattr(general_module, "MAX_ACTIVE_SET", 1)
    problem, solver = make("hertz", 128, stick_travel=0.0)
    out = march(solver, path)
    assert all(report.converged for _, report in out)
    assert solver.counters["restarts"] > 0
    state = out[-1][0]
    assert np.array_equal(state.memory.status, reference.memory.status)
    scale = F * float(reference.memory.capacity.max())
    assert np.max(np.abs(state.memory.q - reference.memory.q)) <= 1e-9 * scale


def test_an_edge_whose_margin_does_not_grow_is_put_between_the_cells():
    """_run_edges: a stick run's edge comes from the ratio rho of the traction margins f cap - abs(q) of its
    two outermost cells, through the lattice's response to a square-root edge (EDGE_RULE: u(rho) cells
    outward of the outermost stick cell's centre, since 0.3.7); where rho exceeds what a square-root margin
    gives on the lattice (EDGE_RULE_REACH: the margin does not grow inwards, as in a band of cells just under their bound
    before a load maximum) the edge is put midway between the stick and the slip cell's centres and
    reported as placed to half a cell (since 0.3.3; it went to the slip cell's centre, up to 0.84 of a cell
    from the converged edge on the dovetail at 1000 nodes, 0.47 since). Cells of width 1, the run 3..12 of
    16, cells 0..2 and 13..15 slipping forwards (q = cap), the inner cells 5..10 unloaded (margin 2)."""
    problem = NormalProblem(helpers.PROFILES["hertz"], A)
    N = problem.solve(P0)
    x = np.arange(16) + 0.5
    cap = np.full(16, 2.0)
    status = np.zeros(16, np.int8)
    status[:3] = status[13:] = 1
    q = cap.copy()
    q[5:11] = 0.0
    # margins 0.03 / 0.1 on the left (rho = 0.3, the edge 0.17 cells outside cell 3's centre), 0.6 / 1 on the
    # right (rho = 0.6, 0.63 cells outside cell 12's)
    for j, margin in ((3, 0.03), (4, 0.1), (12, 0.6), (11, 1.0)):
        q[j] = cap[j] - margin
    left, right, placement = general_module._run_edges(x, q, cap, status, N, 1.0, 3, 12)
    assert general_module._edge_rule(0.3) == pytest.approx(0.1692, abs=1e-4)
    assert general_module._edge_rule(0.6) == pytest.approx(0.6310, abs=1e-4)
    assert left == pytest.approx(x[3] - general_module._edge_rule(0.3), abs=1e-12)
    assert right == pytest.approx(x[12] + general_module._edge_rule(0.6), abs=1e-12)
    assert placement == 0.0  # the square-root law: the step's EDGE_PLACEMENT floor is enough
    # a cell about to slip (rho = 0): the edge lies inside it, 0.17 of a cell inward of its centre
    q[3] = cap[3]
    left, _, _ = general_module._run_edges(x, q, cap, status, N, 1.0, 3, 12)
    assert left == pytest.approx(x[3] + 0.174637, abs=1e-12)
    # rho = 0.75, beyond what J1 gives on Hertz but within what a square root gives on a few-cell slip zone
    # (EDGE_RULE_REACH): where the rule ends, 0.82 of a cell outward
    q[12] = cap[12] - 0.75
    _, right, placement = general_module._run_edges(x, q, cap, status, N, 1.0, 3, 12)
    assert right == pytest.approx(x[12] + general_module._edge_rule(general_module.EDGE_RULE_RHO), abs=1e-12)
    assert right == pytest.approx(x[12] + 0.8232, abs=1e-4) and placement == 0.0
    # a margin that falls again in the third cell in (0.05 in cell 5 against 0.1 in cell 4; since 0.3.8): the
    # rule still places the edge, but it read a square root that the next cell does not continue (a margin an
    # earlier slip left, as on the dovetail early in each loading half), so it is placed to half a cell only
    q[3], q[5] = cap[3] - 0.03, cap[5] - 0.05
    left, _, placement = general_module._run_edges(x, q, cap, status, N, 1.0, 3, 12)
    assert left == pytest.approx(x[3] - general_module._edge_rule(0.3), abs=1e-12) and placement == 0.5
    q[5] = 0.0
    # a flat margin on the right (the same in cells 11 and 12): bracketed, midway between 12 and 13, to half a cell
    q[11] = q[12] = cap[12] - 1e-3
    left, right, placement = general_module._run_edges(x, q, cap, status, N, 1.0, 3, 12)
    assert right == pytest.approx(x[12] + 0.5, abs=1e-12)
    assert placement == 0.5
    # each side's placement (since 0.4.6, for the windows' own estimate): the left edge is placed by the rule
    assert general_module._run_edges(x, q, cap, status, N, 1.0, 3, 12, side=0)[2] == 0.0
    assert general_module._run_edges(x, q, cap, status, N, 1.0, 3, 12, side=1)[2] == 0.5


#: How well EDGE_RULE places the stick edges of J1 and J2 away from the contact edges, in cells: measured
#: (benchmarks/calibrate_edge_rule.py) at most 0.004 (Hertz) and 0.024 (punch) at 256 nodes; the rule of
#: 0.3.3 - 0.3.6 (the margin's square extrapolated linearly) was 0.17 - 0.20 off. The punch's pressure
#: varies faster over a cell than Hertz's (the flat's ends), the next order of the local form.
EDGE_RULE_TOL = 0.03


@pytest.mark.parametrize("kind,unload,lo,hi", [
    ("hertz", None, 0.30, 0.36), ("punch", None, 0.50, 0.56), ("hertz", 0.8, 0.30, 0.36), ("punch", 0.8, 0.30, 0.36),
])
def test_stick_edges_within_their_cells_against_j1_and_j2(kind, unload, lo, hi):
    """J1 (from (P0, 0) to Q, Q/fP in [lo, hi]) or J2 (back from Q_max = unload f P0) at 256 nodes, the
    stick edge swept through several cells: its distance from the closed form is at most EDGE_RULE_TOL of
    a cell at every load (the lattice's own response to a square-root edge, EDGE_RULE)."""
    problem, solver = helpers.make(kind, "general", nodes=256, estimate=False)
    loaded = helpers.states(solver, [(P0, 0.0)] + ([] if unload is None else [(P0, unload * F * P0)]))[-1]
    worst = 0.0
    for r in np.linspace(lo, hi, 61):
        state, _ = solver.step(loaded, loaded.t + 1.0, Loads(P0, r * F * P0, 0.0, 0.0))
        c = float(problem.half_width(P0 - r * P0 if unload is None else P0 - (unload - r) * P0 / 2))
        assert state.memory.status[0] != 0 and state.memory.status[-1] != 0  # slip zones at both edges
        worst = max(worst, abs(state.stick_left + c), abs(state.stick_right - c))
    assert worst / state.memory.spacing <= EDGE_RULE_TOL


#: How well END_RULE_WITHIN / END_RULE_END place a slip zone of up to two cells at a contact edge, in cells:
#: measured (benchmarks/calibrate_edge_rule.py, J1 at 256 nodes, the edge at 21 places across a cell) at most
#: 0.085 within the end cell and 0.055 beyond it, on both profiles; the local Cattaneo form alone (0.3.3 -
#: 0.3.6) was up to 0.20 off.
END_RULE_TOL = 0.1


@pytest.mark.parametrize("kind", ["hertz", "punch"])
def test_slip_zones_at_the_contact_edge_against_j1(kind):
    """J1 with slip zones of 0 - 2.2 cells at the contact edges, the lattice shifted against the contact
    (its width set so that the contact edge falls at 6 places across its cells): every stick edge within
    END_RULE_TOL of a cell of the closed form, whether the end cell sticks (the slip zone within it, (S1)
    says the edge slips) or alone slips."""
    problem = NormalProblem(PROFILES[kind], A)
    a = float(problem.half_width(P0))
    worst = {0: 0.0, 1: 0.0}
    for shift in np.linspace(1.0, 1.0 + 4.0 / 256, 6):
        solver = GeneralSolver(problem, F, 256, width=2 * a * shift, estimate=False)
        loaded = helpers.states(solver, [(P0, 0.0)])[-1]
        h, E = loaded.memory.spacing, loaded.contact_right
        for w in np.linspace(0.01, 2.2, 23):
            c = E - w * h
            r = brentq(lambda r: float(problem.half_width(P0 * (1 - r))) - c, 1e-14, 0.5, xtol=1e-15)
            state, _ = solver.step(loaded, 2.0, Loads(P0, r * F * P0, 0.0, 0.0))
            status = state.memory.status
            branch = 0 if status[-1] == 0 else 1 if status[-2] == 0 else None
            if branch is not None:
                error = max(abs(state.stick_right - c), abs(state.stick_left + c)) / h
                worst[branch] = max(worst[branch], error)
    assert 0.0 < max(worst.values()) <= END_RULE_TOL, worst


#: Sub-cell slip zones at receding contact edges against J3, in cells: measured at 512 nodes at most 0.031
#: (punch) and 0.009 (Hertz) over slip zones of 0 - 1.5 cells; with the slip's sign taken from q at the end
#: cell (until 0.3.8) the punch's backward slip zones were put at the contact edge, 0.27 of a cell off.
J3_TOL = 0.06


@pytest.mark.parametrize("kind", ["hertz", "punch"])
@pytest.mark.parametrize("k_unload", [0.45, 0.51, 0.52])
def test_receding_edges_against_j3(kind, k_unload):
    """J3: loaded in proportion to (P0, k f P0) (full stick, q = k f p), then unloaded along dQ = k' f dP
    (the contact recedes; the edge material keeps q / (f p) = k, so the edges slip backwards for k' > k
    and forwards for k' < k): q = k f p(P) -+ (1 +- k) f [p(P) - p(P_c)], P - P_c = |k' - k| (P0 - P) /
    (1 +- k), the stick zone that of P_c (the levels of the exact method: the top ones set to -+f).
    From P0 to 0.6 P0 in 40 steps at 512 nodes the slip zones grow from 0 to 0.18 - 1.5 cells, inside the
    end cell or beyond it: every stick edge within J3_TOL of a cell of the closed form."""
    k = 0.5
    problem, solver = helpers.make(kind, "general", nodes=512, estimate=False)
    state = helpers.states(solver, [(P, k * F * P) for P in np.linspace(0.05, 1.0, 20) * P0])[-1]
    h = state.memory.spacing
    worst, slipped = 0.0, 0.0
    for P in np.linspace(1.0, 0.6, 41)[1:] * P0:
        state, _ = solver.step(state, state.t + 1.0, Loads(P, k * F * P0 + k_unload * F * (P - P0), 0.0, 0.0))
        c = float(problem.half_width(helpers.j3_stick_load(P, k, k_unload)))
        worst = max(worst, abs(state.stick_left + c) / h, abs(state.stick_right - c) / h)
        slipped = max(slipped, (state.contact_right - c) / h)
    assert slipped > 1.5 * J3_TOL  # an edge put at the contact edge would fail
    assert worst <= J3_TOL, worst


@pytest.mark.parametrize("kind", ["hertz", "punch"])
def test_reversed_slip_zones_inside_the_end_cell_against_j2(kind):
    """J2 just after the reversal from Q_max = 0.9 f P0 (dQ = 0.0005 .. 0.03 f P0 at 256 nodes): the reversed
    slip zones, c = a(P0 - dQ/(2f)), are 0.005 - 0.96 of a cell wide, most of them inside the end cell, and
    every stick edge is within J3_TOL of a cell of the closed form (measured 0.014 / 0.010 of a cell, Hertz
    / punch). Until 0.3.7 their margins were read against the bound of q's sign there, +f p, while they slip
    backwards: the edges stayed at the contact's, off by the zone's width (up to 0.26 / 0.32 of a cell)."""
    problem, solver = helpers.make(kind, "general", nodes=256, estimate=False)
    top = helpers.states(solver, [(P0, 0.0), (P0, 0.9 * F * P0)])[-1]
    h = top.memory.spacing
    worst, widest = 0.0, 0.0
    for dq in (0.0005, 0.001, 0.002, 0.004, 0.008, 0.016, 0.03):
        state, _ = solver.step(top, top.t + 1.0, Loads(P0, (0.9 - dq) * F * P0, 0.0, 0.0))
        c = float(problem.half_width(P0 - dq * P0 / 2))
        worst = max(worst, abs(state.stick_left + c) / h, abs(state.stick_right - c) / h)
        widest = max(widest, (state.contact_right - c) / h)
    assert widest > 1.5 * J3_TOL  # an edge left at the contact's would fail
    assert worst <= J3_TOL, worst


def test_bracketed_edges_on_the_dovetail():
    """The dovetail (2 cycles, no skipping) at 500 nodes against 4000 (its own error about 0.01 of a
    500-node cell): over the partially slipping steps after the ramp, the load maxima left out (there the
    edge lies in a band of cells within 1e-3 of their bound and moves by rounding: an 8000-node run put it
    13 um from the 4000- and 16000-node runs' edge), the stick edges are within half a cell. Measured:
    largest 0.39 of a cell, 95th percentile 0.30; 0.65 / 0.43 before 0.3.3 put edges whose margin does
    not grow inwards midway between the two cells."""
    import halfslip as hs

    text = helpers.example_text("dovetail", **{"count: 20": "count: 2", "fields: [p, q, slip]": "fields: []",
                                               "skip_steady_cycles: true": "skip_steady_cycles: false"})

    reference = hs.simulate(hs.parse_scene(text), nodes=4000)
    run = hs.simulate(hs.parse_scene(text), nodes=500)
    W = (reference.contact_right - reference.contact_left).values
    error = np.maximum(abs(run.stick_left - reference.stick_left),
                       abs(run.stick_right - reference.stick_right)).values / W * 500
    t = run.t.values
    steps = (reference.regime.values == 2) & (t > 1.0) & np.isfinite(error) & (np.abs((t - 0.25) % 1.0) > 1e-9)
    assert steps.sum() > 150
    assert error[steps].max() < 0.5, error[steps].max()


def _split_history():
    """The split-stick punch history (256 nodes) marched once: (solver, [(state, report)]), the reference
    width."""
    from halfslip.geometry import RoundedPunch

    data = np.loadtxt(SPLIT_HISTORY, delimiter=",")
    problem = NormalProblem(RoundedPunch(flat_half_width=2e-3, radius=10e-3), 4 * (1 - 0.3**2) / 115e9)
    width = max(problem.solve(P, M).right - problem.solve(P, M).left for P, M in data[1:, [1, 3]])
    solver = GeneralSolver(problem, 0.6, 256, width=width)
    return (solver, helpers.march(solver, data[1:, 1:])), width


def _split_history_with_and_without(monkeypatch, name, replacement):
    """:func:`_split_history` as it is and with general.<name> replaced by ``replacement``: ((solver,
    [(state, report)]) for each, the reference width)."""
    kept, width = _split_history()
    monkeypatch.setattr(general_module, name, replacement)
    return kept, _split_history()[0], width


def test_the_sub_steps_start_from_the_pattern_moving_to_the_end(monkeypatch):
    """A sub-step's active set starts from its start pattern moved part of the way to the whole step's
    end pattern (_toward). The problem of each sub-step is strictly convex, so the start changes only
    the iterations: on the split-stick punch history (256 nodes) every state is the same to 1e-12 of
    its scale with and without the hint (the final patterns agree, so the last solves are the same
    arithmetic), and the hint saves iterations (measured: 465 against 583 on it since 0.4.2, 736 against
    905 before; 15 / 25 % on the random histories, benchmarks/random_histories.py seed 0, Hertz / punch,
    1024 nodes)."""
    (hinted, with_hint), (plain, without), width = _split_history_with_and_without(
        monkeypatch, "_toward", lambda now, end, fraction: None)
    assert hinted.counters["substeps"] > 0
    assert hinted.counters["iterations"] < plain.counters["iterations"]
    for (a, _), (b, _) in zip(with_hint, without):
        ma, mb = a.memory, b.memory
        if ma.normal is None:
            assert mb.normal is None
            continue
        assert np.array_equal(ma.status, mb.status)
        scale = float(np.max(np.abs(mb.q))) or 1.0
        assert np.max(np.abs(ma.q - mb.q)) <= 1e-12 * scale
        assert a.stick_left == pytest.approx(b.stick_left, rel=0, abs=1e-12 * width)
        assert a.stick_right == pytest.approx(b.stick_right, rel=0, abs=1e-12 * width)


def test_the_fine_takes_start_from_the_shadows_whole_step_pattern(monkeypatch):
    """The shadow lattice takes each step whole first (GeneralSolver._rough): that take decides the
    sub-steps, is the shadow of a step of at most SHADOW_EVERY sub-steps, and the fine takes start from its
    pattern refined (_refined: fine cells 2c and 2c + 1 take coarse cell c's status), moved part of the way
    for a sub-step (_toward). Only the iterations change (each step is strictly convex): on the split-stick
    punch history (256 nodes) every state and estimate is the same to 1e-12 of its scale with and without
    the hint, and the hint saves iterations (measured: 465 against 636 on it; on the random histories at
    1024 nodes the whole-step trial on the shadow took the CPU time per step down 8-11 % with the states the
    same to the last bit)."""
    from types import SimpleNamespace

    coarse = SimpleNamespace(normal=object(), first=3, status=np.array([1, 0, 0, -1], np.int8))
    first, status = general_module._refined(coarse)
    assert first == 6 and status.tolist() == [1, 1, 0, 0, 0, 0, -1, -1]
    assert general_module._refined(SimpleNamespace(normal=None, first=0, status=np.zeros(0, np.int8))) is None

    (hinted, with_hint), (plain, without), width = _split_history_with_and_without(
        monkeypatch, "_refined", lambda memory: None)
    assert hinted.counters["substeps"] > 0
    assert hinted.counters["iterations"] < plain.counters["iterations"]
    for (a, ra), (b, rb) in zip(with_hint, without):
        for ma, mb in ((a.memory, b.memory), (a.memory.coarse, b.memory.coarse)):
            if ma is None or ma.normal is None:
                assert mb is None or mb.normal is None
                continue
            assert np.array_equal(ma.status, mb.status)
            scale = float(np.max(np.abs(mb.q))) or 1.0
            assert np.max(np.abs(ma.q - mb.q)) <= 1e-12 * scale
        assert a.stick_left == pytest.approx(b.stick_left, rel=0, abs=1e-12 * width)
        assert ra.error_estimate == pytest.approx(rb.error_estimate, rel=1e-9, abs=1e-12)


def test_the_shadow_takes_every_few_sub_steps_and_does_not_feed_the_fine_lattice(monkeypatch):
    """The shadow lattice takes a step of at most SHADOW_EVERY sub-steps once, whole (the take that decided
    them), and a longer one again on every SHADOW_EVERY-th sub-step and the last: on the split-stick punch
    history (256 nodes) the shadow's takes are counted against the sub-steps, and with SHADOW_EVERY = 1 (a
    take for every sub-step) and MAX_SUBSTEPS (one per step) the fine lattice's states are the same to the
    last bit, while the estimates change. (The fine lattice reads the shadow's pattern as a start, and its
    stick edges for the number of sub-steps; the shadow's own sub-steps change its state a little, which
    here changes no such decision.)"""
    counts = []  # per step: the shadow's takes, whether it moved in contact, its sub-steps
    take, step0 = GeneralSolver._take, GeneralSolver.step

    def counted(self, *args, shadow=False, **kwargs):
        counts[-1][0] += shadow
        return take(self, *args, shadow=shadow, **kwargs)

    def step(self, state, t1, loads1):
        substeps = self.counters["substeps"]
        counts.append([0, state.loads != loads1 and loads1.P > 0])
        out = step0(self, state, t1, loads1)
        counts[-1].append(self.counters["substeps"] - substeps)
        return out

    monkeypatch.setattr(GeneralSolver, "_take", counted)
    monkeypatch.setattr(GeneralSolver, "step", step)
    runs, longer = {}, {}
    default = general_module.SHADOW_EVERY
    for every in (default, 1, general_module.MAX_SUBSTEPS):
        monkeypatch.setattr(general_module, "SHADOW_EVERY", every)
        counts.clear()
        runs[every] = _split_history()[0][1]
        for shadows, moved, pieces in counts:
            expected = 0 if not moved else 1 if pieces <= every else 1 + sum(
                1 for k in range(1, pieces + 1) if k % every == 0 or k == pieces)
            assert shadows == expected
        longer[every] = sum(1 for _, _, pieces in counts if pieces > every)
    assert longer[default] > 0  # steps whose shadow took sub-steps
    base = runs[default]
    for every in (1, general_module.MAX_SUBSTEPS):
        differ = 0
        for (a, ra), (b, rb) in zip(base, runs[every]):
            if a.memory.normal is None:
                continue
            assert np.array_equal(a.memory.q, b.memory.q) and a.stick_left == b.stick_left
            assert a.dissipation == b.dissipation
            differ += ra.error_estimate != rb.error_estimate
        assert differ > 0


#: A receding contact under slip against the exact method, at 256 nodes and the default sub-steps:
#: the history's dissipation, relative. Measured -0.015 % (Hertz) and -0.04 % (punch); before 0.3.5, which
#: lost the dissipation of the cells that leave the contact while slipping, -0.56 % and -3.3 %.
RECEDING_DISSIPATION_TOL = 3e-3


@pytest.mark.parametrize("kind", ["hertz", "punch"])
def test_a_receding_contact_keeps_the_dissipation_of_the_cells_that_leave(kind):
    """Cattaneo slip at P0, then P falling to 0.6 P0 at constant Q (the slip zones grow while the edges
    recede: cells leave the contact slipping), reversal, reloading and a second recession with slip:
    the dissipation after every step against the exact method (RECEDING_DISSIPATION_TOL of the total).
    The cells that leave slip until the receding edge passes them (GeneralSolver._leaving); the end
    state does not hold them."""
    problem = NormalProblem(PROFILES[kind], A)
    path = [(P0, 0.0), (P0, 0.5 * F * P0), (0.6 * P0, 0.5 * F * P0), (0.6 * P0, -0.3 * F * P0),
            (P0, -0.3 * F * P0), (0.7 * P0, 0.4 * F * P0)]
    exact = march(ExactMemory(problem, F, P0), path)
    general = march(GeneralSolver(problem, F, 256), path)
    total = exact[-1][0].dissipation
    for (g, _), (e, _) in zip(general, exact):
        assert abs(g.dissipation - e.dissipation) <= RECEDING_DISSIPATION_TOL * total


#: The step above whose stick set only shrinks, split into 16 equal steps, against the exact method: its
#: dissipation, relative. Measured -0.034 % (Hertz) and -0.002 % (punch) at 256 nodes; 1, 2 and 4 steps
#: -11.8 / +2.5 / +0.76 % and -17.0 / +2.7 / +0.34 % (second order from 2 on): 6x the larger at 16.
SHRINKING_DISSIPATION_TOL = 2e-3
#: ... and with one step it is off by more than this (what the sub-steps are for there).
ONE_STEP_DISSIPATION_OFF = 5e-2


@pytest.mark.parametrize("kind", ["hertz", "punch"])
def test_a_step_whose_stick_set_only_shrinks_ends_in_the_same_state_however_split(kind):
    """The receding contact's last step above ((P0, -0.3 f P0) -> (0.7 P0, 0.4 f P0): Q reverses while P
    falls), split into 1, 2, 4 and 16 equal steps without the solver's own sub-steps. Every cell stuck at the
    end was stuck throughout, with its lock unchanged, and every slipping cell is at its bound, so the end
    state is the same however the step is split (q to rounding, the same stick edges): the premise, a stick
    set that only shrinks over the 16 steps, is asserted. Only the dissipation depends on the path: one
    step misses it by more than ONE_STEP_DISSIPATION_OFF, 16 meet SHRINKING_DISSIPATION_TOL. So the sub-steps
    the stick edges' travel asks for (GeneralSolver._pieces) are there for the dissipation here, not for
    the state (benchmarks/time_convergence.py: on the random histories the edges' error in time is several
    times below the lattice's own)."""
    problem = NormalProblem(PROFILES[kind], A)
    path = [(P0, 0.0), (P0, 0.5 * F * P0), (0.6 * P0, 0.5 * F * P0), (0.6 * P0, -0.3 * F * P0),
            (P0, -0.3 * F * P0)]
    last = np.array((0.7 * P0, 0.4 * F * P0))
    exact = march(ExactMemory(problem, F, P0), path + [tuple(last)])
    wanted = exact[-1][0].dissipation - exact[-2][0].dissipation
    solver = GeneralSolver(problem, F, 256, travel=0.0, stick_travel=0.0, arrivals=False)
    start = march(solver, path)[-1][0]
    ends = {}
    for pieces in (1, 2, 4, 16):
        lo = np.array(start.loads[:2])
        run = [s for s, _ in march(solver, [tuple(lo + (k / pieces) * (last - lo)) for k in range(1, pieces + 1)],
                                   start, t0=start.t)]
        ends[pieces] = run[-1]
        if pieces == 16:
            stuck = [{s.memory.first + i for i in np.flatnonzero(np.asarray(s.memory.status) == 0)}
                     for s in [start] + run]
            assert all(b <= a for a, b in zip(stuck, stuck[1:]))
    one = ends[1]
    W = one.contact_right - one.contact_left
    for pieces, end in ends.items():
        assert (end.memory.first, end.memory.q.size) == (one.memory.first, one.memory.q.size)
        assert np.max(np.abs(end.memory.q - one.memory.q)) <= 1e-12 * F * float(np.max(one.memory.capacity))
        assert abs(end.stick_left - one.stick_left) <= 1e-12 * W and abs(end.stick_right - one.stick_right) <= 1e-12 * W
    off = {pieces: abs(end.dissipation - start.dissipation - wanted) / wanted for pieces, end in ends.items()}
    assert off[1] > ONE_STEP_DISSIPATION_OFF
    assert off[16] <= SHRINKING_DISSIPATION_TOL


def periodic_run(nodes=128, cycles=3, per_cycle=24):
    """A rounded punch under P, Q, M and sigma cycling in phase (the dovetail's kind of history): every
    step's (stick edges, q, locked displacements less the shift, dissipation)."""
    problem, _ = helpers.make("punch", "general", nodes=nodes)
    a = float(problem.half_width(P0))
    phases = []
    for k in range(1, per_cycle + 1):
        s = math.sin(2 * math.pi * k / per_cycle)
        phases.append(Loads(P0 * (1 + 0.1 * s), F * P0 * (0.1 + 0.15 * s), 0.05 * a * P0 * s, 2e7 * s))
    # the contacts of the samples, solved once, as the simulator keeps them (simulator.contact_edges)
    normals = {(loads.P, loads.M): problem.solve(loads.P, loads.M) for loads in phases}
    problem, solver = helpers.make("punch", "general", nodes=nodes, normals=normals)
    state = helpers.states(solver, [(P0, 0.1 * F * P0)])[-1]
    out = []
    for c in range(cycles):
        for loads in phases:
            state, report = solver.step(state, state.t + 1.0, loads)
            mem = state.memory
            out.append((state.stick_left, state.stick_right, mem.q.copy(), mem.g - state.shift, state.dissipation,
                        report.error_estimate))
    return out, solver


def test_what_a_contact_keeps_across_cycles_changes_no_answer(monkeypatch):
    """The cell loads, end cells and their columns and edge paths kept per contact across a
    periodic history's cycles (since 0.3.8; the Woodbury columns until 0.4.0) are found again, not different: the same history with nothing
    kept beyond a take gives the same states to rounding (a column set solved beside other columns rounds
    differently: measured 0 here), and the kept run does find them (fewer end cells built)."""
    built = {"kept": 0, "not": 0}
    original = general_module._EndCell.__init__

    def counting(which):
        def init(self, *args, **kwargs):
            built[which] += 1
            original(self, *args, **kwargs)
        return init

    monkeypatch.setattr(general_module._EndCell, "__init__", counting("kept"))
    kept, _ = periodic_run()
    for name, value in (("END_CELLS_KEPT", 0), ("LOADS_KEPT", 0)):
        monkeypatch.setattr(general_module, name, value)
    monkeypatch.setattr(general_module._EndCell, "__init__", counting("not"))
    fresh, _ = periodic_run()
    assert built["kept"] < 0.5 * built["not"], built  # the later cycles find the first one's end cells
    for a, b in zip(kept, fresh):
        assert a[0] == pytest.approx(b[0], abs=1e-12 * abs(b[0])) and a[1] == pytest.approx(b[1], abs=1e-12 * abs(b[1]))
        assert np.max(np.abs(a[2] - b[2])) <= 1e-12 * F * np.max(np.abs(b[2]) + 1.0)
        assert np.max(np.abs(a[3] - b[3])) <= 1e-12 * np.max(np.abs(b[3]))
        assert a[4] == pytest.approx(b[4], rel=1e-12) and a[5] == pytest.approx(b[5], rel=1e-9, abs=1e-15)


def test_kept_store_keeps_its_budget_and_its_contact():
    """_Kept: what one contact stored is not found for another (the key holds id(normal), and the object is
    checked), and the oldest items go once the bytes exceed the budget."""
    first, second = object(), object()
    kept = general_module._Kept(100)
    kept.put("a", (first,), 1, 40)
    kept.put("b", (first,), 2, 40)
    assert kept.get("a", (first,)) == 1 and kept.get("a", (second,)) is None
    kept.put("c", (second,), 3, 40)  # 120 bytes: "a" goes
    assert kept.get("a", (first,)) is None and kept.get("b", (first,)) == 2 and kept.get("c", (second,)) == 3
    assert kept.size == 80


def test_the_arrivals_sizes_match_the_lattice_and_the_pattern_together(monkeypatch):
    """A Hertz contact that grows while part of it slips and the cells arriving at its edges stick (256 nodes,
    P 1e5 -> 1.3e5, Q -0.3 f P -> -0.12 f P, a moment and a compressive bulk tension): at every take whose active set fitted the arrivals' sizes (0.4.1: in its own iterations),
    the end state must satisfy what the sizes are defined by, checked here outside the compiled code:

    * the lattice's displacement ARRIVAL_MATCH cells beyond the growing edge changes over the step by
      size x the shape's change there (_displacement of the start and end shears, package datum), to 1e-9
      of the displacement a cell's bound shear makes (A f max p h: the solves are exact to rounding, 3e-14 of
      it seen; the equations' terms are up to 1e3 of it, and sizes 0.1 % off give 1.5e-3);
    * the arrived cells that stick are locked at g0 + size x shape (g0 the displacement at the start);
    * the step converged: its own check (Coulomb, slip direction, equilibrium) with those locks.
    """
    problem = NormalProblem(PROFILES["hertz"], A)
    solver = GeneralSolver(problem, F, 256)
    seen = []
    sizes_of = general_module.GeneralSolver._active_set
    take = general_module.GeneralSolver._take

    def active_set(self, *args):
        out = sizes_of(self, *args)
        if args[-1] is not None:  # the fit (_arrival_fit's, or _arrived's: the same numbers)
            seen.append({"fit": args[-1], "sizes": out[-1]})
        return out

    def taking(self, mem, h, loads0, loads1, N1, path, load, hint=None, shadow=False):
        count = len(seen)
        out = take(self, mem, h, loads0, loads1, N1, path, load, hint, shadow)
        if len(seen) > count:
            seen[-1].update(mem=mem, out=out, h=h, loads0=loads0, loads1=loads1, N1=N1)
        return out

    monkeypatch.setattr(general_module.GeneralSolver, "_active_set", active_set)
    monkeypatch.setattr(general_module.GeneralSolver, "_take", taking)
    state = solver.initial_state()
    state, report = solver.step(state, 1.0, Loads(1e5, -0.3 * F * 1e5, 0.0, 0.0))
    state, report = solver.step(state, 2.0, Loads(1.3e5, -0.12 * F * 1.3e5, 6.5, -27e6))
    assert report.converged and report.slipped
    fitted = [s for s in seen if s.get("sizes")]
    assert len(fitted) >= 3
    for s in fitted:
        side_of, now, phi, K, e, m1 = s["fit"]
        mem, out, h = s["mem"], s["out"], s["h"]
        end = out.memory
        x = end.x
        scale = A * F * float(end.capacity.max()) * h
        # the cells beyond the old contact's, and their displacement at the step's start
        cell = end.first + np.arange(x.size)
        arrived = (cell < mem.first) | (cell >= mem.first + mem.q.size)
        g0 = np.zeros(x.size)
        g0[arrived] = solver._displacement(mem.shift, mem.x, mem.q, mem.spacing, s["loads0"].sigma, x[arrived],
                                           mem.normal)
        for j, size in s["sizes"]:
            cells = np.flatnonzero(side_of == j)
            side = -1 if cells[0] < x.size // 2 else 1
            xe = np.array([x[0] - general_module.ARRIVAL_MATCH * h if side < 0
                           else x[-1] + general_module.ARRIVAL_MATCH * h])
            before = solver._displacement(mem.shift, mem.x, mem.q, mem.spacing, s["loads0"].sigma, xe, mem.normal)
            after = solver._displacement(end.shift, end.x, end.q, h, s["loads1"].sigma, xe, s["N1"])
            assert abs(after[0] - before[0] - size * m1[j]) <= 1e-9 * scale
            stuck = cells[end.status[cells] == 0]
            assert np.allclose(end.g[stuck], g0[stuck] + size * phi[j, stuck], rtol=0.0, atol=1e-9 * scale)
        assert out.residual <= 1.0


def _moment_scale(kind: str) -> float:
    """P0 times about a tenth of the contact's half-width at P0: the moments of the compiled-route tests'
    histories."""
    return P0 * (1e-4 if kind == "hertz" else 2e-4)


@pytest.mark.parametrize("kind", ["hertz", "punch"])
def test_the_compiled_arrivals_are_the_python_route(kind, monkeypatch):
    """A growing contact's arrivals and their fit in one compiled pass (GeneralSolver._arrived, since 0.4.4;
    every take on a hermite edge path) against the Python route it stands in for (_arrivals, then
    _arrival_fit): the same operations in the same order, so the same numbers to the last bit - the arrived
    cells' locks, their start displacements, the match points', and every array of the fit (at an r0 of the
    test's choosing) - at every take of a history whose contact grows and shrinks under P, Q, M and sigma
    while part of it slips (both lattices, sub-steps included)."""
    problem = NormalProblem(PROFILES[kind], A)
    solver = GeneralSolver(problem, F, 256)
    arrived = general_module.GeneralSolver._arrived
    compared = {"takes": 0, "fits": 0}

    def checked(self, mem, N1, path, x, known, h, first, lat, glock):
        before_glock = glock.copy()
        got = arrived(self, mem, N1, path, x, known, h, first, lat, glock)
        if got is None:
            return got
        g0, before, terms = got
        locks, g0_ref, before_ref = self._arrivals(mem, path.loads0, path.loads1, N1, path, x, known, h)
        before_glock[~known] = locks
        assert np.array_equal(glock, before_glock) and np.array_equal(g0, g0_ref) and before == before_ref
        r0 = 0.37 * float(np.max(np.abs(glock)))
        fit, fit_ref = terms(r0), self._arrival_fit(mem, lat, h, path.loads1, path, x, known, g0_ref, before_ref,
                                                    before_glock, r0)
        assert (fit is None) == (fit_ref is None)
        if fit is not None:
            assert all(np.array_equal(a, b) for a, b in zip(fit, fit_ref))
            compared["fits"] += 1
        compared["takes"] += 1
        return got

    monkeypatch.setattr(general_module.GeneralSolver, "_arrived", checked)
    scale = _moment_scale(kind)
    path = [(P0, 0.3 * F * P0), (1.5 * P0, -0.2 * F * P0, 0.4 * scale, -3e7), (2.2 * P0, 0.5 * F * P0, -0.6 * scale,
            4e7), (1.1 * P0, 0.1 * F * P0, 0.2 * scale, 0.0), (2.5 * P0, -0.6 * F * 2.5 * P0, 0.0, -2e7)]
    for state, report in march(solver, path):
        assert report.converged
    assert compared["takes"] >= 10 and compared["fits"] >= 3, compared


@pytest.mark.parametrize("kind", ["hertz", "punch"])
def test_the_compiled_leaving_cells_are_the_python_route(kind, monkeypatch):
    """The dissipation of the cells that leave the contact while slipping in one compiled pass
    (_leaving_terms, since 0.4.4) against the Python route it replaced (written out here: the slipping old
    cells outside the take, lam from the receding edges' travel, the end's displacement from
    _displacement's general path, the slip with the shear only), and against its own fallback for points
    inside an end cell's support (_displacement, then _leaving_slip): the same numbers to the last bit at
    every fine take of a history whose contact recedes under P, M and sigma while it slips."""
    problem = NormalProblem(PROFILES[kind], A)
    solver = GeneralSolver(problem, F, 256)
    leaving = general_module.GeneralSolver._leaving
    seen = []

    def checked(self, mem, N1, first, n, shift, x, q, h, sigma1, total):
        assert total == float(np.sum(q))
        got = leaving(self, mem, N1, first, n, shift, x, q, h, sigma1, total)
        cell = mem.first + np.arange(mem.q.size)
        out = ((cell < first) | (cell >= first + n)) & (mem.status != 0)
        if not np.any(out):
            assert got == 0.0
            return got
        xs, N0 = mem.x[out], mem.normal
        lam = np.where(xs < N0.center,
                       (xs - N0.left) / (N1.left - N0.left) if N1.left != N0.left else 1.0,
                       (xs - N0.right) / (N1.right - N0.right) if N1.right != N0.right else 1.0)
        lam = np.clip(lam, 0.0, 1.0)
        g1 = self._displacement(shift, x, q, h, sigma1, xs, N1)
        slip = lam * (g1 - mem.g[out])
        slip = np.where(mem.status[out] * slip > 0.0, slip, 0.0)
        terms = self.f * general_module.LEAVING_PRESSURE * mem.capacity[out] * np.abs(slip)
        assert got == float(np.sum(terms)) * mem.spacing
        fallback = general_module._leaving_slip(xs, np.flatnonzero(out), g1, mem.status, mem.g, mem.capacity,
                                                N0.left, N0.right, N0.center, N1.left, N1.right,
                                                self.f * general_module.LEAVING_PRESSURE)
        assert np.array_equal(fallback, terms)
        seen.append(got)
        return got

    monkeypatch.setattr(general_module.GeneralSolver, "_leaving", checked)
    scale = _moment_scale(kind)
    path = [(2.5 * P0, 0.5 * F * 2.5 * P0, 0.3 * scale, 2e7), (1.2 * P0, -0.6 * F * 1.2 * P0, -0.5 * scale, -3e7),
            (0.6 * P0, 0.5 * F * 0.6 * P0, 0.4 * scale, 1e7)]
    for state, report in march(solver, path):
        assert report.converged
    assert len(seen) >= 5 and sum(d > 0.0 for d in seen) >= 3, seen


def test_the_end_rules_polynomial_is_numpys_to_the_last_bit():
    """The end rules' two-variable polynomial in the compiled edge placement (_polyval2d, since 0.4.4) is
    numpy.polynomial.polynomial.polyval2d as it takes scalars - the same Horner steps - so the placements
    did not move: equal to the last bit at the rules' own coefficients over their range (w_est in 0 .. 2,
    u_e in -1 .. 1 cells) and beyond it, signs of zero included."""
    rng = np.random.default_rng(3)
    for rule in general_module._END_RULES.values():
        for w, u in [(0.0, 0.0), (-0.0, 0.5), (1.0, -0.0)] + list(zip(rng.uniform(-1, 3, 200), rng.uniform(-2, 2, 200))):
            got = general_module._polyval2d(float(w), float(u), rule)
            want = float(np.polynomial.polynomial.polyval2d(w, u, rule))
            assert got == want or (math.isnan(got) and math.isnan(want)), (w, u)


@pytest.mark.parametrize("kind", ["hertz", "punch"])
def test_the_compiled_shear_distance_is_the_numpy_route(kind, monkeypatch):
    """The two lattices' shear distance behind each step's shear error estimate, int abs(q_fine - q_shadow)
    dx with q = (q_j / cap_j) p in each cell, in one compiled pass (_shear_apart_kernel, since 0.4.4) against
    numpy's steps written out here (the ratios, the shadow's cell of each fine centre, the sum): the same
    number to the last bit at every step of a history that slips under P, Q, M and sigma."""
    problem = NormalProblem(PROFILES[kind], A)
    solver = GeneralSolver(problem, F, 256)
    apart = general_module._shear_apart
    seen = []

    def checked(fine, coarse):
        got = apart(fine, coarse)

        def ratio(m):
            return np.divide(m.q, m.capacity, out=np.zeros_like(m.q), where=m.capacity > 0.0)

        J = np.clip(np.floor(fine.x / coarse.spacing).astype(np.int64) - coarse.first, 0, coarse.q.size - 1)
        assert got == fine.spacing * float(np.sum(fine.capacity * np.abs(ratio(fine) - ratio(coarse)[J])))
        seen.append(got)
        return got

    monkeypatch.setattr(general_module, "_shear_apart", checked)
    scale = _moment_scale(kind)
    path = [(P0, 0.3 * F * P0), (1.5 * P0, -0.2 * F * P0, 0.4 * scale, -3e7), (0.8 * P0, 0.5 * F * 0.8 * P0,
            -0.6 * scale, 4e7), (1.2 * P0, -0.4 * F * 1.2 * P0, 0.2 * scale, 0.0)]
    for state, report in march(solver, path):
        assert report.converged
    assert len(seen) >= 4 and all(v > 0.0 for v in seen[1:]), seen


def test_the_compiled_start_pattern_is_the_python_route():
    """A sub-step's start pattern moved part of the way towards the whole step's (_toward, compiled since
    0.4.4) against the Python steps it replaced, written out here, on random patterns, overlaps and
    fractions, halves included (Python's round takes half to even, and so does the compiled np.rint)."""
    from types import SimpleNamespace

    def python_route(now, end, fraction):
        first, e = end
        lo, hi = max(now.first, first), min(now.first + now.q.size, first + e.size)
        if hi <= lo:
            return None
        s = e.copy()
        s[lo - first:hi - first] = now.status[lo - now.first:hi - now.first]
        for a, b in general_module._runs(s != e):
            count = int(round(fraction * (b - a)))
            if count == 0:
                continue
            if a > 0 and s[a - 1] == e[a]:
                s[a:a + count] = e[a:a + count]
            elif b < s.size and s[b] == e[b - 1]:
                s[b - count:b] = e[b - count:b]
        return first, s

    rng = np.random.default_rng(11)
    halves = 0
    for _ in range(2000):
        n, m = rng.integers(1, 40, 2)
        status = np.repeat(rng.integers(-1, 2, 6).astype(np.int8), rng.integers(0, 12, 6))[:n]
        e = np.repeat(rng.integers(-1, 2, 6).astype(np.int8), rng.integers(0, 12, 6))[:m]
        if status.size == 0 or e.size == 0:
            continue
        now = SimpleNamespace(normal=object(), first=int(rng.integers(-5, 5)), status=status, q=np.zeros(status.size))
        end = (int(rng.integers(-5, 5)), e)
        fraction = float(rng.choice([0.5, 0.25, 1.0 / 3.0, 1.0, rng.uniform()]))
        got, want = general_module._toward(now, end, fraction), python_route(now, end, fraction)
        assert (got is None) == (want is None)
        if got is not None:
            assert got[0] == want[0] and np.array_equal(got[1], want[1])
            halves += fraction == 0.5
    assert halves > 100


#: A sampled Hertz profile (TabulatedProfile's cubic spline reproduces it exactly) against the analytic one in
#: the general solver, along a path whose contact grows and shrinks while it slips (256 nodes): the tabulated
#: profile's steps take an edge path through normal solves, not its a(P) (0.4.5: that is a root-finding over the
#: profile's moments, 0.8 ms an arrival point; the tabulated example under the general solver took 5.2 s, then
#: 0.94 s), the analytic one's the exact a(P). Measured: stick edges 2.7e-10 of the width apart at most, contact
#: edges 3.9e-16, the dissipation 2.1e-9 (with the single hermite cubic for the path until 0.4.13: 2.2e-10 and
#: 1.2e-9; the paths' tables agree with the normal problem to 1e-12 of the edges' travel).
HERMITE_EDGE_TOL = 1e-8
HERMITE_DISSIPATION_TOL = 1e-8


def test_a_symmetric_tabulated_profile_takes_the_hermite_path():
    from halfslip.geometry import Hertz, TabulatedProfile
    from halfslip.solvers._general_path import EdgePath

    x = np.linspace(-3e-3, 3e-3, 241)
    tabulated = NormalProblem(TabulatedProfile(x, x**2 / (2 * R)), A)
    hertz = NormalProblem(Hertz(R), A)
    assert hertz.cheap_half_width and not tabulated.cheap_half_width
    loads0, loads1 = Loads(P0, 0.0, 0.0, 0.0), Loads(1.1 * P0, 0.0, 0.0, 0.0)
    kinds = [EdgePath(pr, pr.solve(P0), pr.solve(1.1 * P0), loads0, loads1).kind for pr in (hertz, tabulated)]
    assert kinds == ["symmetric", "table"]  # (the single cubic of a 10 % step is not within the allowance)
    assert EdgePath(tabulated, None, tabulated.solve(P0), Loads(0.0, 0.0, 0.0, 0.0), loads0).kind == "symmetric"
    path = ([(P0, 0.0)] + [(P0 * (1 + 0.5 * k / 20), 0.4 * F * P0 * k / 20, 0.0, 2e7 * k / 20) for k in range(1, 21)]
            + [(P0 * (1.5 - 0.4 * k / 20), 0.4 * F * P0 * (1 - 2 * k / 20), 0.0, 2e7 * (1 - k / 20))
               for k in range(1, 21)])
    runs = [helpers.march(GeneralSolver(pr, F, 256), path) for pr in (hertz, tabulated)]
    for (a, _), (b, _) in zip(*runs):
        W = a.contact_right - a.contact_left
        assert max(abs(a.stick_left - b.stick_left), abs(a.stick_right - b.stick_right)) <= HERMITE_EDGE_TOL * W
    a, b = runs[0][-1][0], runs[1][-1][0]
    assert b.dissipation == pytest.approx(a.dissipation, rel=HERMITE_DISSIPATION_TOL)
