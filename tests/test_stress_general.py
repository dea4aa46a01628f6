"""Stress tests of the general solver: moments, bulk tension, scales, step sizes, limits, many cycles.

Fast variants run by default; long ones (marked slow) with ``pytest --runslow``.
Every step of every history goes through :func:`check_step`, which asserts the
invariants of physics.md: finite values, non-decreasing dissipation, Coulomb
(abs(q) <= f p), equilibrium of the output tractions (int p = P, int p x = M,
int q = Q, by quadrature of ``solver.tractions``), the stick zone inside the
contact, a bounded stuck solution on STICK steps (consistency residual) and a clean
report (no fallback message). Where the answer is known in
closed form (physics.md J1, J2, the moderate bulk-tension shift, SS2, the
Jaeger-Ciavarella construction generalised to a moment) it is asserted too.

Cases that expose a solver defect are kept, with the assertion that fails, and
skipped with the reason "BUG: ..." (nothing is marked xfail).

Quadrature. p and q vanish like square roots at the contact edges, q* like a
square root at the stick edges, q has logarithmic kinks at every knot of the
piecewise-linear stick data and square-root points at the singular material
points, and p has x ln x kinks at the ends of a punch flat. The contact is cut at
all of these, the panels next to each special point are graded geometrically
(ratio 4, down to 4^-19 of the width), and every panel is integrated by 12-point
Gauss-Legendre in theta after x = c + d sin(theta), which removes the square
roots at the panel ends (8 points leave 2e-10 next to the x ln x kinks of a punch).
Against 16-point rules with ratio-2 grading and against 50-digit integrals of the
closed-form pressure, this integrates p, p x and q to ~1e-11 (the tolerances below
are set from that).
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from halfslip.geometry import Hertz, NormalProblem, RoundedPunch
from halfslip.solvers import _general_points as points
from halfslip.solvers.general import COULOMB_TOL, SINGULAR_LEFT, GeneralSolver
from halfslip.state import GROSS_SLIDING_MESSAGE, Loads, Regime

import helpers
from helpers import A, F
P0 = 1.0e5
from helpers import R_CORNER, R_HERTZ, W_FLAT
EPS = float(np.finfo(float).eps)

# --- invariant tolerances -----------------------------------------------------
#: int p dx = P (relative). The normal problem stops at 1e-13 and is exact for these
#: profiles; the quadrature above is good to ~1e-11 (measured <= 5e-11 on these histories).
P_TOL = 1e-10
#: int p x dx = M, relative to P times the contact width (same sources as P_TOL).
M_TOL = 1e-10
#: int q dx = Q, relative to f P. The solver carries the force exactly (a fix-up force
#: absorbs the discretisation residual of equilibrium), and the output q is the exact
#: inversion of the same piecewise-linear data; the two agree to rounding in the sums
#: over clustered knots (measured <= 2e-9 f P on these histories), hence 1e-8.
Q_TOL = 1e-8
#: solver.shear_force (the force of the representation) = Q, relative to f P: the fix-up
#: force makes it exact up to rounding.
FORCE_TOL = 1e-10
#: Coulomb: the solver accepts a configuration whose excess abs(q) - f p is below
#: COULOMB_TOL (1e-3) of f max p; the same bound is asserted everywhere on the contact.

#: Consistency residual gamma_0 of a full-stick step (state.memory.residual, relative to f max p):
#: zero in exact arithmetic, a discretisation estimate otherwise (measured <= 6e-17 on every
#: STICK step here). A stuck solution accepted with a residual above the solver's own stick
#: acceptance (STICK_COULOMB_TOL = 1e-3) would not be bounded at the edges: its force would
#: sit in the fix-up term instead.
RESIDUAL_TOL = 1e-3

#: Edges, when compared with a closed form that is exact for the solver's data
#: (E piecewise linear: J1, J2 after gross sliding, the moderate tension shift, the
#: generalised Jaeger-Ciavarella): Newton stops at a scaled residual of 1e-12, which
#: places the edges to ~1e-12 of the width; 1e-9 of the width leaves rounding room.
EXACT_EDGE_TOL = 1e-9


# --- set-up -------------------------------------------------------------------
def hertz_problem(radius=R_HERTZ, compliance=A):
    return NormalProblem(Hertz(radius), compliance)


def punch_problem(w=W_FLAT, radius=R_CORNER, compliance=A):
    return NormalProblem(RoundedPunch(w, radius), compliance)


def make(kind, nodes=128):
    return helpers.make(kind, "general", nodes=nodes)


def breaks_of(problem):
    profile = problem.profile
    if isinstance(profile, RoundedPunch) and profile.flat_half_width > 0.0:
        return np.array([-profile.flat_half_width, profile.flat_half_width])
    return np.zeros(0)


# --- quadrature over the contact -------------------------------------------------
_THETA, _WEIGHT = np.polynomial.legendre.leggauss(12)
_THETA = 0.5 * math.pi * _THETA
_WEIGHT = 0.5 * math.pi * _WEIGHT
_GRADING = 0.25 ** np.arange(1, 20)


def contact_nodes(solver, memory):
    """Quadrature points x and weights over the contact (see the module docstring)."""
    normal, shear = memory.normal, memory.shear
    L, R = normal.left, normal.right
    W = R - L
    breaks = breaks_of(solver.problem)
    special = [L, R, *breaks, *memory.X[memory.kind >= SINGULAR_LEFT]]
    cuts = [np.array([L, R]), memory.X, breaks]
    if shear.radius > 0.0:
        special += [shear.stick_left, shear.stick_right]
        cuts.append(shear.center + shear.radius * np.asarray(shear.knots[0]))
    for s in special:
        cuts += [s - W * _GRADING, s + W * _GRADING]
    cuts = np.unique(np.clip(np.concatenate(cuts), L, R))
    lo, hi = cuts[:-1, None], cuts[1:, None]
    centre, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
    x = (centre + half * np.sin(_THETA)).ravel()
    w = (half * np.cos(_THETA) * _WEIGHT).ravel()
    return x, w


def normal_conditioning(problem, normal):
    """Relative rounding of int p = P caused by representing the edges as floats.

    For a punch under a tiny load the edge sits a distance e above the end of the
    flat, and P ~ e^(3/2): the float edge (relative precision eps) fixes P only to
    ~ (3/2) eps |edge| / e (measured 9e-9 against 50-digit integrals at P = 1e-7 N/m).
    """
    breaks = breaks_of(problem)
    if breaks.size == 0:
        return 0.0
    edges = np.array([normal.left, normal.right])
    gap = np.min(np.abs(edges[:, None] - breaks[None, :]))
    return 2.0 * EPS * float(np.max(np.abs(edges))) / max(gap, 1e-300)


ALLOWED_MESSAGES = ("", GROSS_SLIDING_MESSAGE)


def check_step(solver, prev, state, report, clean=True):
    """Assert the invariants of one step; return (x, w, p, q) on the contact (None if separated)."""
    mem = state.memory
    assert all(math.isfinite(v) for v in (state.t, *state.loads, state.shift, state.dissipation))
    assert state.dissipation >= prev.dissipation
    if clean:
        assert report.message in ALLOWED_MESSAGES or report.message.startswith("separated"), report.message
    P, Q, M = state.loads.P, state.loads.Q, state.loads.M
    if not P > 0.0:
        assert report.regime == Regime.SEPARATED
        assert mem.X.size == 0 and math.isnan(state.contact_left) and math.isnan(state.contact_right)
        return None
    normal = mem.normal
    assert (state.contact_left, state.contact_right) == (normal.left, normal.right)
    for arr in (mem.X, mem.E, mem.kappa, mem.G):
        assert np.all(np.isfinite(arr))
    assert mem.X[0] == normal.left and mem.X[-1] == normal.right
    carried = max(-F * P, min(F * P, Q))
    if report.regime == Regime.GROSS_SLIDING:
        assert abs(Q) >= F * P and math.isnan(state.stick_left) and math.isnan(state.stick_right)
    else:
        assert report.regime in (Regime.STICK, Regime.PARTIAL_SLIP)
        assert normal.left <= state.stick_left <= state.stick_right <= normal.right
    if report.regime == Regime.STICK:
        assert mem.residual <= RESIDUAL_TOL
    assert solver.shear_force(mem) == pytest.approx(carried, abs=FORCE_TOL * F * P)
    x, w = contact_nodes(solver, mem)
    p, q = solver.tractions(mem, x)
    assert np.all(np.isfinite(p)) and np.all(np.isfinite(q)) and np.all(p >= 0.0)
    W = normal.right - normal.left
    assert float(w @ p) == pytest.approx(P, rel=P_TOL + normal_conditioning(solver.problem, normal))
    assert float(w @ (p * x)) == pytest.approx(M, abs=(M_TOL + normal_conditioning(solver.problem, normal)) * P * W)
    assert float(w @ q) == pytest.approx(carried, abs=Q_TOL * F * P)
    excess = float(np.max(np.abs(q) - F * p)) / (F * float(np.max(p)))
    assert excess <= COULOMB_TOL, f"Coulomb excess {excess:.3g} of f max p"
    return x, w, p, q


def walk(solver, path, state=None, clean=True):
    """Step through ``path`` (tuples of up to four loads), checking every step; return [(state, report)]."""
    state = solver.initial_state() if state is None else state
    return helpers.march(solver, path, state, t0=state.t,
                         check=lambda prev, new, report: check_step(solver, prev, new, report, clean))


def strain_on(memory, x):
    """Locked-in strain E at x, interpolated as the solver does (square-root points included)."""
    Xa, (Ea,) = points.augment(memory.X, memory.kind, memory.spacing, [(memory.E, memory.kappa)])
    return np.interp(x, Xa, Ea)


def edge_error(state, left, right):
    """Largest distance of the stick edges from (left, right), in contact widths."""
    W = state.contact_right - state.contact_left
    return max(abs(state.stick_left - left), abs(state.stick_right - right)) / W


# =============================================================================
# 1. a moment that lifts part of the punch flat
# =============================================================================
def rotation_matched_load(problem, P_stick, rotation, scale):
    """(P', M') with P' = P_stick whose contact has the given rigid rotation."""
    def mismatch(M):
        return problem.solve(P_stick, M).rotation - rotation

    M = brentq(mismatch, -2.0 * scale, 2.0 * scale, xtol=1e-15 * scale, rtol=4 * EPS, maxiter=200)
    return problem.solve(P_stick, M)


def lift_and_shear(solver, problem):
    """P and M = 0.85 P w raised together, then Q to 0.2, 0.5, 0.8 f P (checked against the
    generalised Jaeger-Ciavarella construction), then Q reversed to -0.5 f P and back."""
    w = W_FLAT
    M1 = 0.85 * P0 * w
    state = walk(solver, [(P0 * k / 4, 0.0, M1 * k / 4) for k in range(1, 5)])[-1][0]
    lifted = problem.solve(P0, M1)
    assert (state.contact_left, state.contact_right) == (lifted.left, lifted.right)
    assert -0.8 * w < lifted.left < -0.7 * w and lifted.right > 1.6 * w  # flat partly lifted, corner loaded
    x = np.linspace(lifted.left, lifted.right, 1601)
    assert np.all(solver.tractions(state.memory, x)[1] == 0.0)  # no shear without Q and sigma
    for ratio in (0.2, 0.5, 0.8):
        Q = ratio * F * P0
        state, report = walk(solver, [(P0, Q, M1)], state)[-1]
        assert report.regime == Regime.PARTIAL_SLIP
        stick = rotation_matched_load(problem, P0 - Q / F, lifted.rotation, P0 * w)
        assert edge_error(state, stick.left, stick.right) < EXACT_EDGE_TOL
        p, q = solver.tractions(state.memory, x)
        assert np.max(np.abs(q - F * (p - stick.pressure(x)))) <= 1e-9 * F * p.max()
    return walk(solver, [(P0, -0.5 * F * P0, M1), (P0, 0.5 * F * P0, M1)], state)[-1][0]


def in_phase_about_lift(per_cycle, cycles, P_amplitude):
    """P, Q, M and sigma in phase about the lifted state; M/P = (0.85 +- 0.05) w."""
    path = []
    for k in range(1, cycles * per_cycle + 1):
        s = math.sin(2 * math.pi * k / per_cycle)
        P = P0 * (1 + P_amplitude * s)
        path.append((P, 0.4 * F * P0 * s, (0.85 + 0.05 * s) * P * W_FLAT, 2e7 * s))
    return path


@pytest.mark.parametrize("nodes,per_cycle", [(128, 8), pytest.param(512, 32, marks=pytest.mark.slow)])
def test_moment_lifts_flat_then_shear(nodes, per_cycle):
    """A moment M = 0.85 P w moves the punch contact onto its right corner and lifts the
    left part of the flat (contact [-0.73 w, 1.62 w]); then Q is applied.

    Contact edges equal NormalProblem.solve(P, M) exactly (same call). With E = 0 after
    P and M raised together (q = 0), a monotone Q on a fixed (P, M) gives the Jaeger-
    Ciavarella construction with the rigid rotation alpha held: q = f [p(x; P, M) -
    p(x; P', M')] with P' = P - Q/f and M' such that the (P', M') contact has the same
    rotation; the stick zone is that contact. E stays piecewise linear, so the solver is
    exact (edges 1e-9 of the width, measured 4e-14; q 1e-9 of f max p, measured 6e-13).
    Then two in-phase cycles of P (+-10%), Q, M and sigma about the lifted state: all
    invariants, including the moment equilibrium int p x = M, at every step, and the flat
    stays partly lifted.
    """
    problem, solver = make("punch", nodes)
    state = lift_and_shear(solver, problem)
    path = in_phase_about_lift(per_cycle, 2, 0.1)
    for (state, report), (P, _, M, _) in zip(walk(solver, path, state), path):
        normal = problem.solve(P, M)
        assert (state.contact_left, state.contact_right) == (normal.left, normal.right)
        assert state.contact_left > -W_FLAT
        assert report.regime == Regime.PARTIAL_SLIP


@pytest.mark.skip(reason=(
    "BUG (or the documented interior-slip limitation, met here in a smooth in-phase cycle): "
    "with P amplitude 20% (P = 0.8 P0, Q = -0.5 f P, M = 0.8 P w, sigma = -2e7 at the load "
    "minimum, phase 6/8) no slip configuration passes the checks: 'kept the closest (violation "
    "20 x tolerance)', Coulomb excess 2.0e-2 of f max p, the same at 128 and 512 nodes and with "
    "8, 16 or 32 steps/cycle (which then take 3, 16 and 32 s for two cycles)"))
@pytest.mark.parametrize("nodes", [128, 512])
def test_moment_lifted_flat_large_in_phase_cycle(nodes):
    """As above with P +-20%: every step clean, all invariants."""
    problem, solver = make("punch", nodes)
    state = lift_and_shear(solver, problem)
    walk(solver, in_phase_about_lift(8, 2, 0.2), state)


def test_moment_at_constant_load_without_shear():
    """Raising M at constant P with Q = sigma = 0 leaves q = 0: full stick, nothing to solve.

    (S1) fails at the receding edge, but the stuck solution is exact; before 1c1d1b7 the
    step tried every slip configuration, fell back to 'kept full stick' with a failure
    message and slipped=True, and was halved three times (16 normal solves, ~3 s).
    """
    problem, solver = make("punch", 64)
    state = walk(solver, [(P0, 0.0, 0.0)])[-1][0]
    before = dict(solver.counters)
    state, report = walk(solver, [(P0, 0.0, 0.85 * P0 * W_FLAT)], state, clean=False)[-1]
    x = np.linspace(state.contact_left, state.contact_right, 801)
    assert np.all(solver.tractions(state.memory, x)[1] == 0.0)
    assert report.regime == Regime.STICK
    assert report.message == "" and not report.slipped
    assert solver.counters["normal_solves"] - before["normal_solves"] <= 2


# =============================================================================
# 2. bulk tension: the moderate closed form, reversal, and sigma alone
# =============================================================================
def moderate_tension_valid(a, b, e):
    """The moderate solution q = f [p(x) - p*(x - e)] (p* of half-width b) is admissible:
    the stick zone lies in the contact and abs(q) <= f p on it (p*(x - e) <= 2 p(x))."""
    if abs(e) + b >= a:
        return False
    x = np.linspace(e - b, e + b, 20001)
    return bool(np.all(np.sqrt(np.maximum(b * b - (x - e) ** 2, 0.0)) <= 2.0 * np.sqrt(a * a - x * x)))


@pytest.mark.parametrize("nodes,steps,sigma_over_Q", [
    (128, 10, 2000.0), (128, 10, 4000.0), (128, 10, 6000.0),
    pytest.param(512, 40, 2000.0, marks=pytest.mark.slow),
    pytest.param(512, 40, 4000.0, marks=pytest.mark.slow),
    pytest.param(512, 40, 6000.0, marks=pytest.mark.slow),
])
def test_bulk_tension_moderate_closed_form(nodes, steps, sigma_over_Q):
    """Q and sigma raised together at constant P on Hertz (E = 0 at the start).

    physics.md (N1, T1): with q = f p(x) - f p*(x - e), p* the Hertz pressure of half-width
    b = a sqrt(1 - Q/(fP)), the Hilbert transform on the stick zone is f e/(A R), which
    cancels A sigma/4 for e = -A R sigma/(4 f). Asserted up to sigma/Q = 6000 (e = -0.28 a,
    stick zone reaching 0.99 a), at every step where it applies: admissible (checked) and
    no point of its stick zone slipped before (E = 0 there). At sigma/Q <= 4000 that is
    every step; at 6000 the first steps reverse slip at the left end. Exact for the solver
    (E piecewise linear): edges and q to 1e-9 (measured 7e-14)."""
    problem, solver = make("hertz", nodes)
    a = float(problem.half_width(P0))
    path = [(P0, 0.0)] + [(P0, 0.5 * F * P0 * k / steps, 0.0, sigma_over_Q * 0.5 * F * P0 * k / steps)
                          for k in range(1, steps + 1)]
    x = np.linspace(-a, a, 2001)
    never_slipped = [-a, a]  # points inside have stuck at every step so far: E = 0 there
    checked = 0
    for state, report in walk(solver, path)[1:]:
        Q, sigma = state.loads.Q, state.loads.sigma
        e = -A * R_HERTZ * sigma / (4 * F)
        b = a * math.sqrt(1 - Q / (F * P0))
        assert report.regime == Regime.PARTIAL_SLIP
        # the closed form needs E = 0 on its stick zone and to be admissible; at sigma/Q = 6000
        # the first steps are not (b ~ a: the shifted zone would leave the contact; the solver
        # reverses slip at the left end instead), and later ones only once the stick zone
        # has moved off the points that slipped then
        applies = moderate_tension_valid(a, b, e) and never_slipped[0] <= e - b and e + b <= never_slipped[1]
        never_slipped = [max(never_slipped[0], state.stick_left), min(never_slipped[1], state.stick_right)]
        if not applies:
            continue
        checked += 1
        assert edge_error(state, e - b, e + b) < EXACT_EDGE_TOL
        p, q = solver.tractions(state.memory, x)
        shifted = np.sqrt(np.maximum(b * b - (x - e) ** 2, 0.0)) / (A * R_HERTZ)
        assert np.max(np.abs(q - F * (p - shifted))) <= 1e-9 * F * p.max()
    assert checked >= (steps if sigma_over_Q < 5000 else 1)


@pytest.mark.parametrize("nodes", [128, pytest.param(512, marks=pytest.mark.slow)])
def test_bulk_tension_reverses_slip_at_one_end(nodes):
    """sigma = 2e4 Q (6e8 Pa at Q = 0.5 f P): the moderate solution is not admissible
    (stick zone would leave the contact), slip reverses at the left end: q = -f p there,
    +f p at the right end (by construction of the zones: 1e-12), opposite-sign zones at
    every step, and all invariants."""
    problem, solver = make("hertz", nodes)
    a = float(problem.half_width(P0))
    steps = 10
    path = [(P0, 0.0)] + [(P0, 0.5 * F * P0 * k / steps, 0.0, 2e4 * 0.5 * F * P0 * k / steps)
                          for k in range(1, steps + 1)]
    for state, report in walk(solver, path)[1:]:
        assert report.regime == Regime.PARTIAL_SLIP
        assert state.memory.shear.config.left == -1 and state.memory.shear.config.right == 1
        e = -A * R_HERTZ * state.loads.sigma / (4 * F)
        assert not moderate_tension_valid(a, a * math.sqrt(1 - state.loads.Q / (F * P0)), e)
        x = np.linspace(state.contact_left, state.contact_right, 4001)[1:-1]
        p, q = solver.tractions(state.memory, x)
        left, right = x < state.stick_left, x > state.stick_right
        assert left.any() and right.any()
        assert np.allclose(q[left], -F * p[left], rtol=1e-12, atol=1e-12 * F * p.max())
        assert np.allclose(q[right], F * p[right], rtol=1e-12, atol=1e-12 * F * p.max())


def tension_alone(u):
    return (P0, 0.0, 0.0, 1e8 * math.sin(2 * math.pi * u))


@pytest.mark.parametrize("nodes,cycles", [(64, 12), (128, 12), pytest.param(256, 30, marks=pytest.mark.slow),
                                          pytest.param(1024, 12, marks=pytest.mark.slow)])
def test_tension_alone_cycled_stick_zone_centred(nodes, cycles):
    """Constant P, Q = 0, sigma cycled (+-1e8 Pa) on Hertz: the problem is antisymmetric, so
    at every step the slip zones have opposite signs, the stick zone is centred and
    q(-x) = -q(x); and the cycle repeats.

    Tolerances: the lattice is symmetric about the contact centre; the stick zone may be
    off-centre only through the order in which the two edges' points are laid and merged,
    far below the edge accuracy (3e-4 of the width at 64 nodes): 1e-5 of the width
    (measured 2.2e-6 at 64, 1.5e-7 at 128). |q(x) + q(-x)| <= 2 max |q - q_exact|: the
    pointwise error of q next to the stick edges is 8.5e-3 (64) and 3.8e-3 (128) of f max p
    against 1024 nodes, so 1e-2 (measured 5.9e-3 and 4e-4). After the 10th cycle the state
    repeats (edges, E and q to 1e-4, as in the many-cycles tests below).
    """
    problem, solver = make("hertz", nodes)
    a = float(problem.half_width(P0))
    state = walk(solver, [(P0, 0.0)])[-1][0]
    kept = cycle(solver, state, tension_alone, 16, cycles, keep=range(cycles), full_check=(0, cycles - 1))
    x = np.linspace(-a, a, 801)
    for states in kept.values():
        for state in states:
            cfg = state.memory.shear.config
            assert cfg.left == -cfg.right != 0
            assert abs(state.stick_left + state.stick_right) / 2 <= 1e-5 * 2 * a
            p, q = solver.tractions(state.memory, x)
            assert np.max(np.abs(q + q[::-1])) <= 1e-2 * F * p.max()
    assert_same_cycle(solver, kept[9], kept[cycles - 1])


# =============================================================================
# 3. extreme loads and scales: dimensional analysis
# =============================================================================
# Scaling law of the formulation. Lengths x l, loads P, Q x s, M x s l, sigma x s / l and the
# compliance A x l / s leave (N1)-(N3), (T1) and (T2) invariant: p, q scale as s / l, the strain
# E is unchanged, slips as l, dissipation as s l. For Hertz the only length of the normal
# problem is a = sqrt(2 A R P / pi), so A can stay fixed: every (R, P) is similar, p0 = a/(A R),
# and the dissipation scales as A (f P)^2 (energy = load x slip, slip ~ A p0 a).
LENGTHS = [1e-6, 1.0, 1e3]  # Hertz radius R = 50 mm x this: 50 nm, 50 mm, 50 m
LOADS = [1e-6, 1e5, 1e9]  # P [N/m]


def hertz_exact_history(P, a):
    """P and M = 0.3 a P raised together, then Q and sigma together (dimensionless shift)."""
    x0 = 0.3 * a
    # (not P/4 .. P: a would double exactly, and W/h = 2 nodes, the lattice's refinement
    # threshold, would be met to rounding; which side it falls on changes the resolution)
    path = [(P * u, 0.0, x0 * P * u, 0.0) for u in (0.3, 0.55, 0.8, 1.0)]
    p0 = 2 * P / (math.pi * a)
    path += [(P, 0.5 * F * P * k / 4, x0 * P, 0.4 * F * p0 * k / 4) for k in range(1, 5)]
    return x0, path


@pytest.mark.parametrize("length", LENGTHS)
@pytest.mark.parametrize("load", LOADS + [pytest.param(v, marks=pytest.mark.slow) for v in (1e-3, 1.0, 1e3)])
def test_scaling_hertz_exact(length, load):
    """Hertz at R from 50 nm to 50 m and P from 1e-6 to 1e9 N/m: a = sqrt(2 A R P / pi)
    (1e-12), and the closed form of a Cattaneo shear with bulk tension about the contact
    centre x0 = M/P (stick zone x0 - A R sigma/(4f) +- a sqrt(1 - Q/fP)) holds to 1e-9 of
    the width at every step of every scale (E piecewise linear: exact; the solver's
    tolerances are all relative, so nothing may depend on the scale). q / p0 on x / a is
    the same at every scale to 1e-6 and the dissipation / (A (f P)^2) to 1e-7 (rounding; see
    test_scaling_general_history for these bounds; measured 1e-12 and 1e-10)."""
    R = R_HERTZ * length
    problem = hertz_problem(R)
    solver = GeneralSolver(problem, F, 128)
    a = float(problem.half_width(load))
    assert a == pytest.approx(math.sqrt(2 * A * R * load / math.pi), rel=1e-12)
    x0, path = hertz_exact_history(load, a)
    out = walk(solver, path)
    for state, _ in out[4:]:
        assert state.contact_left == pytest.approx(x0 - a, rel=1e-12, abs=1e-12 * a)
        e = x0 - A * R * state.loads.sigma / (4 * F)
        b = a * math.sqrt(1 - state.loads.Q / (F * load))
        assert edge_error(state, e - b, e + b) < EXACT_EDGE_TOL
    ref_problem = hertz_problem()
    ref = GeneralSolver(ref_problem, F, 128)
    a_ref = float(ref_problem.half_width(P0))
    ref_out = walk(ref, hertz_exact_history(P0, a_ref)[1])
    u = np.linspace(-0.7, 1.3, 401)[1:-1]  # inside: q ~ sqrt at the edges, which sit at -0.7 a to rounding
    q = solver.tractions(out[-1][0].memory, u * a)[1] / (load / a)
    q_ref = ref.tractions(ref_out[-1][0].memory, u * a_ref)[1] / (P0 / a_ref)
    assert np.max(np.abs(q - q_ref)) <= 1e-6 * np.max(np.abs(q_ref))
    for (s, _), (r, _) in zip(out[4:], ref_out[4:]):
        assert s.dissipation / (A * (F * load) ** 2) == pytest.approx(r.dissipation / (A * (F * P0) ** 2),
                                                                      rel=1e-7, abs=1e-15)


PUNCH_LENGTHS = [5e-6, 1.0, 5e3]  # flat half-width 0.2 mm x this: 1 nm .. 0.2 mm .. 1 m


@pytest.mark.parametrize("length", PUNCH_LENGTHS)
@pytest.mark.parametrize("load", [1e-6, 1e5, 1e9])
def test_scaling_punch_exact(length, load):
    """Rounded punch with w and R scaled by l (w from 1 nm to 1 m), P by s = P / 1e5 N/m,
    A by l / s (the similar geometry: a / w fixed). J1 at every step (b = a(P - Q/f), exact:
    1e-9 of the width), the contact a = l a_ref (1e-12), and q / (s/l) on x / l identical to
    the reference scale to 1e-6 of its maximum (rounding, as in test_scaling_general_history;
    measured 1e-12)."""
    s = load / P0
    problem = punch_problem(W_FLAT * length, R_CORNER * length, A * length / s)
    solver = GeneralSolver(problem, F, 128)
    path = [(load, 0.0)] + [(load, F * load * r) for r in (0.2, 0.5, 0.8)]
    out = walk(solver, path)
    ref_problem = punch_problem()
    assert float(problem.half_width(load)) == pytest.approx(length * float(ref_problem.half_width(P0)), rel=1e-12)
    for state, _ in out[1:]:
        b = float(problem.half_width(load - state.loads.Q / F))
        assert edge_error(state, -b, b) < EXACT_EDGE_TOL
    ref = GeneralSolver(ref_problem, F, 128)
    ref_out = walk(ref, [(P0, Q / s) for P, Q in path])
    u = np.linspace(-1.4, 1.4, 561) * W_FLAT
    q = solver.tractions(out[-1][0].memory, u * length)[1] * (length / s)
    q_ref = ref.tractions(ref_out[-1][0].memory, u)[1]
    assert np.max(np.abs(q - q_ref)) <= 1e-6 * np.max(np.abs(q_ref))


def general_history(P, a, p_scale):
    """P, Q, M and sigma all varying, with slip reversals (dimensionless corners)."""
    corners = [(1.0, 0.0, 0.0, 0.0), (1.0, 0.5, 0.0, 0.0), (0.8, -0.2, 0.1, 0.05), (1.0, 0.3, -0.05, -0.05),
               (1.1, 0.6, 0.0, 0.02), (0.9, -0.4, 0.05, 0.0)]
    return [(P * c[0], F * P * c[0] * c[1], P * a * c[2], p_scale * c[3]) for c in corners]


def run_general_scaled(kind, length, load):
    """The general history at a scale; dimensionless edges, q and dissipation at every step."""
    if kind == "hertz":
        R = R_HERTZ * length
        problem = hertz_problem(R)
        a = float(problem.half_width(load))
        p_scale, x_scale, energy = a / (A * R), a, A * (F * load) ** 2
    else:
        s = load / P0
        problem = punch_problem(W_FLAT * length, R_CORNER * length, A * length / s)
        a = float(problem.half_width(load))
        p_scale, x_scale, energy = load / a, length, s * length
    solver = GeneralSolver(problem, F, 128)
    out = walk(solver, general_history(load, a, p_scale))
    u = np.linspace(-1.0, 1.0, 401) * a / x_scale
    return [((st.stick_left / a, st.stick_right / a),
             solver.tractions(st.memory, u * x_scale)[1] / p_scale,
             st.dissipation / energy) for st, _ in out]


def assert_same_dimensionless(results, reference, edge_tol, q_tol, energy_tol):
    for (edges, q, d), (edges_ref, q_ref, d_ref) in zip(results, reference):
        assert max(abs(edges[0] - edges_ref[0]), abs(edges[1] - edges_ref[1])) <= edge_tol
        assert np.max(np.abs(q - q_ref)) <= q_tol * F * np.max(np.abs(q_ref))
        assert d == pytest.approx(d_ref, rel=energy_tol, abs=1e-300)


SCALES = [(length, load) for length in (1e-6, 1e3) for load in (1e-6, 1e9)]


@pytest.mark.parametrize("kind", ["hertz", "punch"])
@pytest.mark.parametrize("length,load", SCALES)
def test_scaling_general_history(kind, length, load):
    """The general history (P, Q, M, sigma varying, two reversals) at extreme scales (lengths
    x 1e-6 and x 1e3, P = 1e-6 and 1e9 N/m) equals the reference scale in dimensionless form
    to rounding: every tolerance of the solver is relative, so only the rounding of the
    rescaled inputs differs. Stick edges / a to 1e-9 (measured 5e-13; a 1e-15 change of P
    at the reference scale moves them by 2e-13); q / p_scale to 1e-6 of its maximum: q* rises
    like sqrt(distance) from a stick edge, so an edge moved by 1e-13 of the width changes q at
    a grid point next to it by up to ~sqrt(1e-13) (measured 5e-9; 3.6e-8 for P x (1 + 1e-15));
    dissipation to 1e-7 (measured 1.2e-8)."""
    reference = run_general_scaled(kind, 1.0, P0)
    assert_same_dimensionless(run_general_scaled(kind, length, load), reference, 1e-9, 1e-6, 1e-7)


# =============================================================================
# 4. step sizes
# =============================================================================
SPLITS = {
    "one": [1.0],
    "many": list(np.arange(1, 21) / 20),
    "tiny_first": [1e-9, 1.0],
    "graded": [1e-9, 1e-6, 1e-3, 0.1, 1.0],
    "tiny_last": [1 - 1e-9, 1.0],
    "tiny_mid": [0.5, 0.5 + 1e-9, 1.0],
    "tiny_2e-9": [2e-9, 1.0],
}
def split_path(corners, fractions, start=(0.0, 0.0, 0.0, 0.0)):
    path = []
    for end in corners:
        path += [tuple(a + f * (b - a) for a, b in zip(start, end)) for f in fractions]
        start = end
    return path


TINY_ZONE = (
    "BUG: a slip zone narrower than 1e-9 of the width (CM step of 1e-9 of the ramp) is reported "
    "STICK and gets no singular point, but the contact-edge points keep the slipped strain; the "
    "next step interpolates it linearly over a whole lattice cell, so the stick edges of the "
    "next CM step are off by up to 2e-6 a at 128 nodes (1e-6 a at 512; Hertz Q = 7e-6 f P after "
    "7e-10 f P: a - b = 1.95e-6 a instead of 3.5e-9 a, a slip zone 560x too wide; punch: 1.1e-6 a)")


MIS_TRIM = (
    "BUG: a step that continues a slip by a tiny amount (here 1e-9 of the segment) is reported "
    "as STICK with stick edges = contact edges (Hertz: 0.226 of the width off b = a sqrt(0.3); "
    "punch: 0.071): GeneralSolver._slip_update counts as stuck every slip-zone point whose strain "
    "changes by less than TRIM_TOL = 1e-3 of max abs(E), a threshold that does not scale with "
    "the step, so the whole slip zone is 'trimmed' and the stick edge moves to the contact edge "
    "(q itself stays right). Measuring against the step's own change fixes this but broke the "
    "periodicity of the in-phase shear-and-tension and dovetail cycles below (4dc6199, reverted)")


def splits_param(name):
    if name == "graded":
        return pytest.param(name, marks=pytest.mark.skip(reason=TINY_ZONE))
    if name in ("tiny_last", "tiny_mid"):
        return pytest.param(name, marks=pytest.mark.skip(reason=MIS_TRIM))
    return name


@pytest.mark.parametrize("kind", ["hertz", "punch"])
@pytest.mark.parametrize("split", [splits_param(name) for name in SPLITS])
def test_step_splitting_from_rest(kind, split):
    """A Cattaneo-Mindlin ramp of Q at constant P, and a straight in-phase segment of P, Q, M
    and sigma from the loaded, unsheared state, each taken as one step or split (20 equal
    steps, a step of 1e-9 first or last or in the middle, a graded sequence 1e-9, 1e-6,
    1e-3, 0.1, 1): invariants at every step; the CM stick zone is J1, b = a(P - Q/f), at
    every step (exact: 1e-9 of the width); the segment ends where the single step does
    (E = 0 at its start and zones monotone along a straight line: 1e-9, measured 1e-13).
    Before 4dc6199 a tiny step continuing a slip (tiny_last, tiny_mid) was reported as STICK
    with the stick edges at the contact edges (0.23 of the width off for Hertz)."""
    problem, solver = make(kind, 128)
    a = float(problem.half_width(P0))
    fractions = SPLITS[split]
    loaded = walk(solver, [(P0, 0.0)])[-1][0]
    for state, _ in walk(solver, split_path([(P0, 0.7 * F * P0)], fractions, (P0, 0.0)), loaded):
        b = float(problem.half_width(P0 - state.loads.Q / F))
        assert edge_error(state, -b, b) < EXACT_EDGE_TOL
    end = (1.3 * P0, 0.6 * F * 1.3 * P0, 0.15 * a * P0, 3e7)
    single = walk(solver, [end], loaded)[-1][0]
    state = walk(solver, split_path([end], fractions, (P0, 0.0, 0.0, 0.0)), loaded)[-1][0]
    assert edge_error(state, single.stick_left, single.stick_right) < EXACT_EDGE_TOL


AFTER_SLIP_BUG = (
    "BUG: small steps after a Cattaneo slip (P0, Q = 0.7 f P0) towards (1.3 P0, 0.2 f P0, "
    "0.1 a P0, 2e7) mis-solve the growing contact (128 nodes; HEAD 80484a2). A first step of "
    "lam = 2e-9 of the segment: 'kept the closest (violation ... x tolerance)'; towards "
    "(1.3 P0, 0.2 f P0, 0, 0) the punch returns config (-1, 0) as STICK without any message, "
    "Coulomb excess 2.1 of f max p, int q - Q = -3.4e-5 f P, and Hertz (with the message) q up "
    "to 8.6 f p within 1e-6 a of the edges, the stick data jumping at the new edge. lam in "
    "[1e-8, 1e-4]: 'no slip-zone configuration converged; kept full stick'; the graded sequence "
    "1e-9, 1e-6, 1e-3, 0.1 then carries Coulomb excesses of 18-31 f max p to the end of the "
    "segment (lam = 1e-9 first is fine). Punch, 128 and 512 nodes, first step lam = 0.01: "
    "unreported Coulomb excess 1.3e-2 in the arrival strip at the stuck advancing right edge "
    "(x = 1.0003 a), 5.5e-3 at lam = 0.02; lam = 0.05 (20 equal steps): 'kept the closest "
    "(violation 8 x tolerance)'. 512 nodes, 100 equal steps: the unreported excess in that strip "
    "reaches 1.35e-2 (punch) and grows over steps 88-97 to 1.05e-3 (Hertz, x = 1.19-1.21 a)")


@pytest.mark.parametrize("kind,nodes,steps", [
    ("hertz", 128, 10),
    ("punch", 128, 10),
    pytest.param("punch", 128, 20, marks=pytest.mark.skip(reason=AFTER_SLIP_BUG)),
    pytest.param("hertz", 512, 100, marks=[pytest.mark.slow, pytest.mark.skip(reason=AFTER_SLIP_BUG)]),
    pytest.param("punch", 512, 100, marks=[pytest.mark.slow, pytest.mark.skip(reason=AFTER_SLIP_BUG)]),
])
def test_step_splitting_after_slip(kind, nodes, steps):
    """The in-phase segment taken after a Cattaneo slip, as one step and as `steps` equal
    steps: invariants at every step; the stick edges agree to 1e-4 of the width (the
    solver's discretisation tolerance: the step reverses slip at both ends, and the one-
    step arrival strains are first order in the step; measured <= 3e-5)."""
    problem, solver = make(kind, nodes)
    a = float(problem.half_width(P0))
    slipped = walk(solver, [(P0, 0.0), (P0, 0.7 * F * P0)])[-1][0]
    end = (1.3 * P0, 0.2 * F * P0, 0.1 * a * P0, 2e7)
    single = walk(solver, [end], slipped)[-1][0]
    fractions = list(np.arange(1, steps + 1) / steps)
    state = walk(solver, split_path([end], fractions, (P0, 0.7 * F * P0, 0.0, 0.0)), slipped)[-1][0]
    assert edge_error(state, single.stick_left, single.stick_right) < 1e-4


@pytest.mark.parametrize("kind", ["hertz", "punch"])
@pytest.mark.parametrize("split", [
    "tiny_first",
    pytest.param("tiny_2e-9", marks=pytest.mark.skip(reason=AFTER_SLIP_BUG)),
    pytest.param("graded", marks=pytest.mark.skip(reason=AFTER_SLIP_BUG)),
])
def test_tiny_steps_after_slip(kind, split):
    """As above with a first step of 1e-9 or 2e-9 of the segment (or the graded sequence 1e-9,
    1e-6, 1e-3, 0.1, 1): invariants at every step and the same end state as the single step
    (1e-4 of the width; measured 2e-7 after a first step of 1e-9)."""
    problem, solver = make(kind, 128)
    a = float(problem.half_width(P0))
    slipped = walk(solver, [(P0, 0.0), (P0, 0.7 * F * P0)])[-1][0]
    end = (1.3 * P0, 0.2 * F * P0, 0.1 * a * P0, 2e7)
    single = walk(solver, [end], slipped)[-1][0]
    state = walk(solver, split_path([end], SPLITS[split], (P0, 0.7 * F * P0, 0.0, 0.0)), slipped)[-1][0]
    assert edge_error(state, single.stick_left, single.stick_right) < 1e-4


# =============================================================================
# 5. stick zone shrinking to nothing, gross sliding, separation, tiny loads
# =============================================================================
def j1_edge_tol(problem, P_stick, W):
    """Tolerance on b = a(P - Q/f) near Q = f P: Newton stops at 1e-12 of f P in the force
    and the stick zone carries f (P - Q/f), so the edge is fixed only to
    ~1e-12 P da/dP (10x margin; Hertz: a/(2 P_stick), punch: (2/3)(a - w)/P_stick);
    1e-9 of the width otherwise."""
    dP = 1e-4 * P_stick
    slope = float(problem.half_width(P_stick + dP) - problem.half_width(P_stick - dP)) / (2 * dP)
    return EXACT_EDGE_TOL * W + 1e-11 * P0 * abs(slope)


@pytest.mark.parametrize("kind", ["hertz", "punch"])
def test_stick_zone_vanishes_gross_sliding_and_back(kind):
    """Q -> f P at constant P in steps down to 1 - Q/fP = 1e-5 (J1 at every step), then
    gross sliding (abs(Q) > f P: regime, message, q = f p, carried force f P), then back
    into partial slip: after gross sliding the state is that of Cattaneo at Q_max = +-f P,
    so unloading follows J2, c = a(P - (Q_max - Q)/(2f)), exactly (E piecewise linear)."""
    problem, solver = make(kind, 128)
    a = float(problem.half_width(P0))
    state = walk(solver, [(P0, 0.0)])[-1][0]
    for gap in np.logspace(-1, -5, 5):
        state, report = walk(solver, [(P0, (1 - gap) * F * P0)], state)[-1]
        b = float(problem.half_width(gap * P0))
        assert report.regime == Regime.PARTIAL_SLIP
        assert max(abs(state.stick_left + b), abs(state.stick_right - b)) <= j1_edge_tol(problem, gap * P0, 2 * a)
    for Q_max, Qs in ((F * P0, (0.5, -0.5)), (-F * P0, (0.3,))):
        state, report = walk(solver, [(P0, 1.5 * Q_max)], state)[-1]
        assert report.regime == Regime.GROSS_SLIDING and report.message == GROSS_SLIDING_MESSAGE
        x = np.linspace(-a, a, 801)
        p, q = solver.tractions(state.memory, x)
        assert np.allclose(q, math.copysign(F, Q_max) * p, rtol=1e-12, atol=0.0)
        for ratio in Qs:
            state, report = walk(solver, [(P0, ratio * F * P0)], state)[-1]
            c = float(problem.half_width(P0 - abs(Q_max - ratio * F * P0) / (2 * F)))
            assert report.regime == Regime.PARTIAL_SLIP
            assert edge_error(state, -c, c) < EXACT_EDGE_TOL


SMALL_STICK_PUNCH = (
    "BUG: punch, Q = (1 - 1e-11) f P: the stick zone [-b, b] overhangs the flat by b - w = 6.6e-9 "
    "of the width and its edges come out 2.4e-8 of the width (4x the overhang) from J1, above "
    "the conditioning bound 4e-9 (the stick interval ends within 1e-8 of the width of the "
    "knots at +-w, the regime of the tiny-load punch bug below)")


@pytest.mark.parametrize("kind", [pytest.param("hertz", marks=pytest.mark.skip(reason=MIS_TRIM)),
                                  pytest.param("punch", marks=pytest.mark.skip(reason=SMALL_STICK_PUNCH))])
def test_stick_zone_vanishes_in_small_increments(kind):
    """Continuing the approach to Q = f P in decades (1 - Q/fP = 1e-6 .. 1e-11): J1 still holds
    (to the conditioning of the edge, j1_edge_tol). With the trim against max abs(E) these
    steps are reported as STICK with the stick zone = the contact (Hertz: 0.5 of the width off)."""
    problem, solver = make(kind, 128)
    a = float(problem.half_width(P0))
    state = walk(solver, [(P0, 0.0), (P0, (1 - 1e-5) * F * P0)])[-1][0]
    for gap in np.logspace(-6, -11, 6):
        state, report = walk(solver, [(P0, (1 - gap) * F * P0)], state)[-1]
        b = float(problem.half_width(gap * P0))
        assert report.regime == Regime.PARTIAL_SLIP
        assert max(abs(state.stick_left + b), abs(state.stick_right - b)) <= j1_edge_tol(problem, gap * P0, 2 * a)


SEPARATION_PATH = [(P0, 0.5 * F * P0), (1e-9 * P0, 0.0), (0.0, 0.0), (1e-12 * P0, 0.3 * F * 1e-12 * P0),
                   (P0, 0.3 * F * P0), (1e-6 * P0, -0.3 * F * P0), (P0, 0.0), (1e-6 * P0, 0.5 * F * 1e-6 * P0),
                   (1e-6 * P0, -0.5 * F * 1e-6 * P0), (P0, 0.1 * F * P0), (-1.0, 0.0), (2e-12 * P0, F * 1e-12 * P0)]
TINY_PUNCH = (
    "BUG: rounded punch under tiny P (contact overhangs the flat by e = a - w ~ 4e-9 w at "
    "P = 1e-7 N/m): loading P and Q = 0.3 f P together from separation (exact: q = 0.3 f p) "
    "gives q / (0.3 f p) = 0.63-0.72 in the interior and int q = 0.81 Q while the representation "
    "says Q (the exact inversion of the stick data loses accuracy when knots lie within ~1e-9 of "
    "the width from the ends; E itself is right to 2.5e-4); 1.7e-4 f P at P = 1e-5 N/m. "
    "Unloading (P0, 0.5 f P0) -> (1e-9 P0, 0) also fails: 'no slip-zone configuration converged; "
    "kept full stick', int q - Q = 7.8e-6 f P")


@pytest.mark.parametrize("kind", ["hertz", pytest.param("punch", marks=pytest.mark.skip(reason=TINY_PUNCH))])
def test_separation_recontact_and_tiny_loads(kind):
    """P down to 1e-9 P0, separation (P = 0 and P < 0: memory lost), re-contact at
    P = 1e-12 P0 with Q/P = 0.3 f, P tiny (1e-6 P0) under a shear history of +-0.3 f P0
    (gross sliding) and +-0.5 f P: regimes as expected and invariants at every step; on
    re-contact from separation with Q/P fixed the contact sticks fully, q = (Q/P) p
    (test_general: 5e-4 of max q at 32-512 nodes)."""
    problem, solver = make(kind, 128)
    out = walk(solver, SEPARATION_PATH)
    regimes = [r.regime for _, r in out]
    assert regimes[2] == regimes[10] == Regime.SEPARATED
    assert regimes[5] == Regime.GROSS_SLIDING
    for i in (3, 11):  # re-contact from separation, loads proportional
        state, report = out[i]
        assert report.regime == Regime.STICK and not report.slipped
        x = np.linspace(state.contact_left, state.contact_right, 1601)
        p, q = solver.tractions(state.memory, x)
        ratio = state.loads.Q / state.loads.P
        assert np.max(np.abs(q - ratio * p)) <= 5e-4 * ratio * p.max()


# =============================================================================
# 6. many cycles
# =============================================================================
def cycle(solver, state, loads_of, per_cycle, cycles, keep, full_check):
    """Run `cycles` cycles; return {cycle: [states]} for the cycles in `keep`.

    Every step gets the cheap invariants; steps of the cycles in `full_check` get all of them.
    """
    kept = {}
    for c in range(cycles):
        for k in range(1, per_cycle + 1):
            prev = state
            state, report = solver.step(state, 10.0 + c + k / per_cycle, Loads(*loads_of(k / per_cycle)))
            if c in full_check:
                check_step(solver, prev, state, report)
            else:
                assert state.dissipation >= prev.dissipation and math.isfinite(state.shift)
                assert report.message in ALLOWED_MESSAGES, report.message
                assert state.contact_left <= state.stick_left <= state.stick_right <= state.contact_right
                assert solver.shear_force(state.memory) == pytest.approx(state.loads.Q, abs=FORCE_TOL * F * P0)
            if c in keep:
                kept.setdefault(c, []).append(state)
    return kept


def assert_same_cycle(solver, tenth, last, edge_tol=1e-4, strain_tol=1e-4, q_tol=1e-4):
    """Stick edges (contact widths), E on a common grid (max abs(E)) and q (f max p) at every phase."""
    for s10, sN in zip(tenth, last):
        assert (sN.contact_left, sN.contact_right) == (s10.contact_left, s10.contact_right)
        assert edge_error(sN, s10.stick_left, s10.stick_right) <= edge_tol
        x = np.linspace(s10.contact_left, s10.contact_right, 2001)
        e10, eN = strain_on(s10.memory, x), strain_on(sN.memory, x)
        assert np.max(np.abs(eN - e10)) <= strain_tol * np.max(np.abs(e10))
        p, q10 = solver.tractions(s10.memory, x)
        assert np.max(np.abs(solver.tractions(sN.memory, x)[1] - q10)) <= q_tol * F * p.max()


@pytest.mark.parametrize("cycles", [30, pytest.param(1000, marks=pytest.mark.slow)])
def test_many_cycles_hertz_shear(cycles):
    """Hertz, constant P, Q = 0.6 f P sin: after the 10th cycle the state repeats (stick
    edges 1e-4 of the width, E 1e-4 of max abs(E), q 1e-4 of f max p: the solver's
    tolerance; measured 1e-13 / 1e-10 / 1e-10), the dissipation per cycle is constant
    (1e-6: trapezoid of identical states), and at the load extremes the stick zone is the
    permanent one, a(P - dQ/(2f)) (J2; 2e-5 of the width at 128 nodes, as test_general)."""
    problem, solver = make("hertz", 128)
    a = float(problem.half_width(P0))
    per_cycle = 16
    state = walk(solver, [(P0, 0.0)])[-1][0]
    kept = cycle(solver, state, lambda u: (P0, 0.6 * F * P0 * math.sin(2 * math.pi * u), 0.0, 0.0),
                 per_cycle, cycles, keep=(8, 9, cycles - 2, cycles - 1), full_check=(0, 9, cycles - 1))
    assert_same_cycle(solver, kept[9], kept[cycles - 1])
    per_cycle_10 = kept[9][-1].dissipation - kept[8][-1].dissipation
    per_cycle_last = kept[cycles - 1][-1].dissipation - kept[cycles - 2][-1].dissipation
    assert per_cycle_10 > 0 and per_cycle_last == pytest.approx(per_cycle_10, rel=1e-6)
    c = a * math.sqrt(1 - 0.6)
    for k in (per_cycle // 4 - 1, 3 * per_cycle // 4 - 1):  # Q = +-Q_max
        assert edge_error(kept[cycles - 1][k], -c, c) < 2e-5


def shear_and_tension(u):
    s = math.sin(2 * math.pi * u)
    return (P0, 0.15 * F * P0 + 0.35 * F * P0 * s, 0.0, 3e7 + 5e7 * s)


@pytest.mark.parametrize("cycles", [12, pytest.param(1000, marks=pytest.mark.slow)])
def test_many_cycles_shear_and_tension(cycles):
    """Hertz, constant P, Q and sigma in phase (Q = 0.15 f P + 0.35 f P sin, sigma = 3e7 + 5e7
    sin): at the load extremes of every kept cycle from the second on, the stick zone is the
    permanent stick zone of SS2, half-width d^2 = a^2 - A R dQ/(pi f), centre
    e = -A R dsigma/(8 f) (2e-5 of the width; measured 4.7e-6 at 128 nodes); after the 10th
    cycle the state repeats (edges, E and q to 1e-4; measured 1e-13 / 1e-10 / 1e-10)."""
    problem, solver = make("hertz", 128)
    a = float(problem.half_width(P0))
    per_cycle = 16
    ramp = walk(solver, [(P0, 0.0)] + [(P0, 0.15 * F * P0 * k / 4, 0.0, 3e7 * k / 4) for k in range(1, 5)])
    kept = cycle(solver, ramp[-1][0], shear_and_tension, per_cycle, cycles, keep=(1, 2, 9, cycles - 1),
                 full_check=(1, cycles - 1))
    d = math.sqrt(a * a - A * R_HERTZ * 0.7 * F * P0 / (math.pi * F))
    e = -A * R_HERTZ * 1e8 / (8 * F)
    for states in kept.values():
        for k in (per_cycle // 4 - 1, 3 * per_cycle // 4 - 1):
            assert edge_error(states[k], e - d, e + d) < 2e-5
    assert_same_cycle(solver, kept[9], kept[cycles - 1])


def lifted_flat_cycle(u):
    s = math.sin(2 * math.pi * u)
    P = P0 * (1 + 0.1 * s)
    return (P, 0.4 * F * P0 * s, (0.85 + 0.05 * s) * P * W_FLAT, 2e7 * s)


LIFTED_FLAT_DRIFT = (
    "BUG: punch (w = 0.2 mm) with the flat partly lifted, P (+-10%), Q, M and sigma in phase "
    "(lifted_flat_cycle), 128 nodes, 16 steps/cycle: no periodic state in 30 cycles. Consecutive "
    "cycles differ by 2e-4..2e-3 of f max p in q and 3e-4..4e-3 of max abs(E), and in cycles 5, "
    "15, 22, 26 a stick edge jumps by 4e-2 of the width and back (HEAD 80484a2; on 9d17811 q "
    "jumped by 3.7e-2 of f max p in cycles 4, 14, 19, 29); at 256 nodes a step of cycle 1 fails "
    "('kept the closest (violation 1.7 x tolerance)')")


@pytest.mark.parametrize("history,nodes,per_cycle,cycles", [
    pytest.param("lifted_flat", 128, 16, 30, marks=pytest.mark.skip(reason=LIFTED_FLAT_DRIFT)),
    pytest.param("dovetail", 128, 16, 30, marks=pytest.mark.slow),
    pytest.param("dovetail", 256, 16, 200, marks=pytest.mark.slow),
])
def test_many_cycles_punch_moment_and_tension(history, nodes, per_cycle, cycles):
    """Rounded punch, P, Q, M and sigma in phase: about the partly lifted flat of test 1, and
    the dovetail of the benchmarks (w = 2 mm, R = 10 mm, Ti; 16 s for 30 cycles at 128 nodes,
    hence slow only; 200 cycles at 256 nodes keep the slow run near 10 minutes). After the
    10th cycle the state repeats: edges, E and q to 1e-4 (the solver's tolerance; the
    dovetail measured 1e-13 / 2e-9 / 4e-10 at 256 nodes)."""
    if history == "dovetail":
        from halfslip.geometry import Material

        problem = NormalProblem(RoundedPunch(2e-3, 10e-3), Material(115e9, 0.3).compliance)
        solver = GeneralSolver(problem, F, nodes)
        mean, amplitude = (2e5, 2e4, 5.0, 2e7), (2e4, 3e4, 5.0, 2e7)
        state = walk(solver, [tuple(m * k / 10 for m in mean) for k in range(1, 11)])[-1][0]

        def loads(u):
            s = math.sin(2 * math.pi * u)
            return tuple(m + am * s for m, am in zip(mean, amplitude))
    else:
        problem, solver = make("punch", nodes)
        state = lift_and_shear(solver, problem)
        loads = lifted_flat_cycle
    kept = cycle(solver, state, loads, per_cycle, cycles, keep=(9, cycles - 1), full_check=(9, cycles - 1))
    assert_same_cycle(solver, kept[9], kept[cycles - 1])


@pytest.mark.parametrize("nodes,per_cycle", [(64, 40), (128, 32), pytest.param(64, 32, marks=pytest.mark.slow),
                                              pytest.param(128, 40, marks=pytest.mark.slow)])
def test_coulomb_after_reversal_at_coarse_resolution(nodes, per_cycle):
    """Two Cattaneo-Mindlin cycles at coarse resolution: Coulomb within COULOMB_TOL at every step.

    The first step after the reversal at Q = -0.6 f P leaves material between the first
    stick edge (a square-root point of E at 0.632 a) and the new slip zones locked at the
    slip limit; the interpolation error next to that point must not push q beyond f p by
    more than the solver's own acceptance."""
    problem, solver = make("hertz", nodes)
    path = [(P0, 0.0)] + [(P0, 0.6 * F * P0 * math.sin(2 * math.pi * k / per_cycle))
                          for k in range(1, 2 * per_cycle + 1)]
    walk(solver, path)
