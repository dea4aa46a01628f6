"""Tests of halfslip.geometry: profiles and the normal problem (physics.md N1-N3).

Every tolerance states where it comes from. Numbers in SI: steel
(A = 1.8e-11 1/Pa), lengths of millimetres.
"""
from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import IntegrationWarning, quad

from halfslip.geometry import (
    Hertz,
    Material,
    NormalProblem,
    NormalSolution,
    RoundedPunch,
    TabulatedProfile,
)

A = Material(E=200e9, nu=0.3).compliance  # 1.82e-11 1/Pa
R = 10e-3  # corner / cylinder radius [m]
W = 2e-3  # flat half-width [m]
EPS = np.finfo(float).eps


# ---------------------------------------------------------------------------
# helpers
# ---------------------------------------------------------------------------


def hertz_half_width(P: float, radius: float = R) -> float:
    return math.sqrt(2.0 * A * radius * P / math.pi)


def punch_load(a: float, w: float = W, radius: float = R) -> float:
    """physics.md closed form, evaluated here independently of the module."""
    phi0 = math.asin(w / a)
    return a * a * (math.pi - 2.0 * phi0 - math.sin(2.0 * phi0)) / (2.0 * A * radius)


def equilibrium(solution: NormalSolution, kinks=(), samples=None) -> tuple[float, float]:
    """(int p dx, int p x dx) by quadrature of the pressure function alone.

    Both work in theta, x = x0 + d cos theta, which turns the sqrt of p at
    the edges into a smooth sin^2. Analytic profiles: scipy's adaptive QAGS
    split at the kinks of h'' (the corners, where p has an (x - w) ln|x - w|
    term), asking 1e-13. Tabulated profiles, whose pressure has a mild
    (x - xi)^2 ln|x - xi| term at every sample xi: 16-point Gauss-Legendre
    between consecutive samples, good to ~1e-14 (checked against QAGS with
    the samples as points).
    """
    left, right = solution.left, solution.right
    x0, d = solution.center, solution.half_width
    if samples is None:
        points = sorted(math.acos((k - x0) / d) for k in kinks if left < k < right)
        options = dict(points=points or None, limit=500, epsabs=0.0, epsrel=1e-13)

        def weighted(t: float, power: int) -> float:
            x = x0 + d * math.cos(t)
            return float(solution.pressure(x)) * x**power * d * math.sin(t)

        with warnings.catch_warnings():
            warnings.simplefilter("ignore", IntegrationWarning)  # roundoff warnings at the 1e-13 request
            load = quad(weighted, 0.0, math.pi, args=(0,), **options)[0]
            moment = quad(weighted, 0.0, math.pi, args=(1,), **options)[0]
        return load, moment
    breaks = np.unique(np.concatenate(([left, right], samples[(samples > left) & (samples < right)])))
    theta = np.arccos(np.clip((breaks - x0) / d, -1.0, 1.0))
    nodes, weights = np.polynomial.legendre.leggauss(16)
    half = 0.5 * (theta[:-1] - theta[1:])[:, None]
    t = 0.5 * (theta[:-1] + theta[1:])[:, None] + half * nodes
    x = x0 + d * np.cos(t)
    p = np.concatenate([solution.pressure(chunk) for chunk in np.array_split(x.ravel(), x.size // 4000 + 1)])
    f = p.reshape(x.shape) * d * np.sin(t) * half * weights
    return float(f.sum()), float((f * x).sum())


def assert_equilibrium(solution: NormalSolution, kinks=(), samples=None) -> None:
    """(N2) to 1e-10: the quadratures resolve ~1e-13, the solver stops at 1e-13."""
    load, moment = equilibrium(solution, kinks, samples)
    assert abs(load - solution.P) <= 1e-10 * solution.P
    assert abs(moment - solution.M) <= 1e-10 * (abs(solution.M) + solution.P * solution.half_width)


def punch_pressure_by_quadrature(x: float, a: float, w: float = W, radius: float = R) -> float:
    """The symmetric formula of physics.md, integrated numerically.

    With xi = a cos t, PV int h'(xi) / (sqrt(a^2 - xi^2) (xi - x)) dxi
    = PV int_0^pi h'(a cos t) / (a cos t - x) dt, and subtracting h'(x)
    (PV int_0^pi dt / (a cos t - x) = 0 for |x| < a) leaves a bounded
    integrand with kinks at the corners and at x, handled by quad's points.
    """

    def slope(xi: float) -> float:
        return math.copysign(max(abs(xi) - w, 0.0), xi) / radius

    def integrand(t: float) -> float:
        xi = a * math.cos(t)
        return 0.0 if xi == x else (slope(xi) - slope(x)) / (xi - x)

    points = sorted({math.acos(x / a), math.acos(w / a), math.acos(-w / a)} - {0.0, math.pi})
    value = quad(integrand, 0.0, math.pi, points=points, limit=400, epsabs=0.0, epsrel=1e-13)[0]
    return math.sqrt(a * a - x * x) / (math.pi * A) * value


# ---------------------------------------------------------------------------
# profiles
# ---------------------------------------------------------------------------


def test_profiles_gap_and_slope():
    x = np.linspace(-5e-3, 5e-3, 11)
    assert np.allclose(Hertz(R).gap(x), x**2 / (2 * R), rtol=1e-15, atol=0)
    assert np.allclose(Hertz(R).slope(x), x / R, rtol=1e-15, atol=0)
    punch = RoundedPunch(W, R)
    beyond = np.maximum(np.abs(x) - W, 0)
    assert np.allclose(punch.gap(x), beyond**2 / (2 * R), rtol=1e-15, atol=0)
    assert np.allclose(punch.slope(x), np.sign(x) * beyond / R, rtol=1e-15, atol=1e-300)
    assert punch.length_scale == W + R and Hertz(R).length_scale == R
    assert punch.gap(np.zeros((2, 3))).shape == (2, 3)


def test_tabulated_profile_subtracts_h0_and_detects_symmetry():
    x = np.linspace(-3e-3, 3e-3, 61)
    profile = TabulatedProfile(x, x**2 / (2 * R) + 1e-6)
    assert profile.symmetric
    assert profile.length_scale == pytest.approx(3e-3, rel=1e-15)
    # the not-a-knot spline reproduces cubics: h and h' exact to rounding
    probe = np.linspace(-2.9e-3, 2.9e-3, 37)
    assert np.allclose(profile.gap(probe), probe**2 / (2 * R), rtol=0, atol=1e-15)
    assert np.allclose(profile.slope(probe), probe / R, rtol=0, atol=1e-13)
    assert not TabulatedProfile(x, x**2 / (2 * R) + 1e-3 * x**3).symmetric
    assert not TabulatedProfile(x + 1e-5, x**2).symmetric  # span not mirrored
    with pytest.raises(ValueError):
        profile.x[0] = 0.0  # samples are read-only


@pytest.mark.parametrize(
    "make, name",
    [
        (lambda: Hertz(0.0), "radius"),
        (lambda: Hertz(-1.0), "radius"),
        (lambda: Hertz(math.inf), "radius"),
        (lambda: RoundedPunch(-1e-3, R), "flat_half_width"),
        (lambda: RoundedPunch(math.nan, R), "flat_half_width"),
        (lambda: RoundedPunch(W, 0.0), "radius"),
        (lambda: TabulatedProfile([-1, 0, 1], [1, 0, 1]), "4 samples"),
        (lambda: TabulatedProfile([-1, 0, 2, 1], [1, 0, 1, 1]), "increasing"),
        (lambda: TabulatedProfile([1, 2, 3, 4], [1, 0, 1, 2]), "bracket 0"),
        (lambda: TabulatedProfile([-1, 0, 1, 2], [1, 0, math.nan, 2]), "finite"),
        (lambda: TabulatedProfile([-1, 0, 1, 2], [1, 0, 1]), "equal length"),
        (lambda: NormalProblem(Hertz(R), 0.0), "compliance"),
        (lambda: NormalProblem(Hertz(R), A, tol=0.0), "tol"),
    ],
)
def test_invalid_inputs_raise_value_error(make, name):
    with pytest.raises(ValueError, match=name):
        make()


# ---------------------------------------------------------------------------
# Hertz
# ---------------------------------------------------------------------------


def test_hertz_closed_forms():
    """a^2 = 2ARP/pi, p = sqrt(a^2 - x^2)/(AR) to 1e-12: a few roundings apart."""
    problem = NormalProblem(Hertz(R), A)
    P = np.array([1e2, 1e4, 1e6])
    a = np.array([hertz_half_width(p) for p in P])
    assert np.allclose(problem.half_width(P), a, rtol=1e-12, atol=0)
    assert np.allclose(problem.load(a), P, rtol=1e-12, atol=0)
    x = np.linspace(-1.0, 1.0, 41)[:, None] * a  # (41, 3) against P (3,)
    expected = np.sqrt(np.maximum(a**2 - x**2, 0)) / (A * R)
    assert np.allclose(problem.pressure(x, P), expected, rtol=1e-12, atol=1e-12 * expected.max())
    for load, half_width in zip(P, a):
        solution = problem.solve(load)
        assert solution.center == 0.0 and not solution.separated
        assert solution.half_width == pytest.approx(half_width, rel=1e-12)
        inner = np.linspace(-0.999, 0.999, 101) * half_width  # off the edges, where p ~ sqrt
        exact = np.sqrt(half_width**2 - inner**2) / (A * R)
        assert np.allclose(solution.pressure(inner), exact, rtol=1e-12, atol=0)
        assert_equilibrium(solution)


def test_hertz_moment_shifts_the_hertzian_pressure():
    """With M the contact centre is x0 = M/P, the rotation -x0/R (N1: x/R + alpha = (x - x0)/R)."""
    problem = NormalProblem(Hertz(R), A)
    P, M = 1e5, 3e5 * 1e-4
    a = hertz_half_width(P)
    x0 = M / P
    for solution in (problem.solve(P, M), problem._solve_general(P, M)):
        # closed form: exact to rounding; general solver: to its 1e-13 tolerance
        assert solution.center == pytest.approx(x0, abs=1e-12 * a)
        assert solution.half_width == pytest.approx(a, rel=1e-12)
        assert solution.rotation == pytest.approx(-x0 / R, rel=1e-12)
        inner = x0 + np.linspace(-0.99, 0.99, 51) * a
        exact = np.sqrt(a**2 - (inner - x0) ** 2) / (A * R)
        assert np.allclose(solution.pressure(inner), exact, rtol=1e-10, atol=0)
        assert_equilibrium(solution)


def test_rotation_satisfies_n1():
    """(A/pi) PV int p / (x - xi) = h'(x) + alpha on the contact, for the punch under a moment.

    QAWC on the pressure (bounded, sqrt at the ends) reaches ~1e-9 of the
    slope scale; 1e-7 leaves room.
    """
    problem = NormalProblem(RoundedPunch(W, R), A)
    P = 1e6
    a = float(problem.half_width(P))
    solution = problem.solve(P, 0.4 * P * a)
    scale = solution.half_width / R
    for x in solution.left + np.array([0.1, 0.3, 0.5, 0.7, 0.9]) * (solution.right - solution.left):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", IntegrationWarning)
            pv = quad(solution.pressure, solution.left, solution.right, weight="cauchy", wvar=x, limit=400)[0]
        displacement_slope = -A / math.pi * pv
        expected = float(problem.profile.slope(x)) + solution.rotation
        assert displacement_slope == pytest.approx(expected, abs=1e-7 * scale)


# ---------------------------------------------------------------------------
# rounded punch, closed forms
# ---------------------------------------------------------------------------


def test_punch_half_width_inverts_the_load():
    """load(half_width(P)) == P from 1e-8 to 1e3 times P_ref = P(a = 2w).

    The tolerance is 1e-12 down to 1e-5 P_ref. Below, the map a -> P is too
    ill-conditioned for it: a is a double, so P(a) can only be as close as
    cond * eps, cond = a P'(a) / P ~ 3 / delta^2 as a -> w (delta = acos(w / a));
    there the bound is 4 cond eps (observed: 1.4e-11 near 2e-8 P_ref, where
    cond eps = 4e-11). The well-conditioned way round, half_width(load(a)) == a,
    holds to 1e-14.
    """
    problem = NormalProblem(RoundedPunch(W, R), A)
    P_ref = punch_load(2 * W)
    P = P_ref * np.logspace(-8, 3, 221)
    a = problem.half_width(P)
    assert np.all(a > W) and np.all(np.diff(a) > 0)
    delta = np.arccos(W / a)
    cond = a * (a * 2 * delta / (A * R)) / P  # P'(a) = a (pi - 2 phi0) / (A R)
    error = np.abs(problem.load(a) / P - 1)
    assert np.all(error[P >= 1e-5 * P_ref] <= 1e-12)
    assert np.all(error <= np.maximum(1e-12, 4 * cond * EPS))
    # independent closed form of physics.md, moderate loads (no cancellation in it)
    for load in P_ref * np.array([1e-2, 1.0, 1e2]):
        assert punch_load(float(problem.half_width(load))) == pytest.approx(load, rel=1e-12)
    sizes = W * (1 + np.logspace(-6, 3, 50))
    assert np.allclose(problem.half_width(problem.load(sizes)), sizes, rtol=1e-14, atol=0)


def test_punch_half_width_tends_to_the_flat():
    """a -> w as P -> 0+, with no NaN; a = 0 for P <= 0; shapes are kept."""
    problem = NormalProblem(RoundedPunch(W, R), A)
    tiny = np.array([1e-300, 1e-100, 1e-30, 1e-12, 1e-6])
    a = problem.half_width(tiny)
    assert np.all(np.isfinite(a)) and np.all(a >= W)
    assert a[0] == W and a[-1] - W < 1e-3 * W
    assert np.all(np.diff(a) >= 0)
    assert problem.half_width(0.0) == 0.0 and problem.half_width(-5.0) == 0.0
    assert problem.half_width(np.ones((2, 3))).shape == (2, 3)
    assert problem.load(0.5 * W) == 0.0 and problem.load(W) == 0.0
    p = problem.pressure(np.linspace(-W, W, 9), 1e-6)
    assert np.all(np.isfinite(p)) and np.all(p >= 0)


def test_punch_pressure_against_quadrature():
    """Closed-form p(x) (logarithms) vs the symmetric formula integrated by quad: 1e-9 of p(0).

    The quadrature resolves ~1e-13; the closed form loses eps / delta^2 by
    cancellation for light loads (delta^2 ~ 1e-2 at the lightest load here).
    """
    problem = NormalProblem(RoundedPunch(W, R), A)
    for P in punch_load(2 * W) * np.array([1e-4, 1e-2, 1.0, 30.0]):
        a = float(problem.half_width(P))
        scale = float(problem.pressure(0.0, P))
        xs = [0.0, 0.5 * W, 0.99 * W, W, 1.001 * W, 0.5 * (W + a), 0.999 * a, -0.7 * a, -W]
        for x in (x for x in xs if abs(x) < a):
            assert float(problem.pressure(x, P)) == pytest.approx(punch_pressure_by_quadrature(x, a), abs=1e-9 * scale)
        solution = problem.solve(P)
        grid = np.linspace(-a, a, 57)
        assert np.allclose(solution.pressure(grid), problem.pressure(grid, P), rtol=0, atol=1e-12 * scale)
        assert_equilibrium(solution, kinks=(-W, W))


def test_load_to_is_the_integral_of_the_pressure():
    """NormalSolution.load_to(x) = int p from the left edge to x (closed form) against scipy's QAGS
    on p split at the knots (asking 1e-13): 1e-12 of P, measured <= 6e-15 (Hertz, the punch with
    and without a moment, a tabulated profile with an x^3 kink whose slope jumps have the quadratic
    term that only tabulated profiles have). The second moment's sign flipped is off by 4e-3 P
    there. 0 left of the contact, P right of it; ``magnitude`` bounds the value."""
    xs = np.linspace(-3e-3, 3e-3, 41)
    tab = TabulatedProfile(x=xs, h=0.5 * xs**2 / 0.05 + 2e3 * np.abs(xs) ** 3)
    cases = [(Hertz(radius=R), 1e5, 0.0), (Hertz(radius=R), 1e5, 3.0), (RoundedPunch(W, R), 3e6, 0.0),
             (RoundedPunch(W, R), 3e6, 1e3), (tab, 1e5, 0.0), (tab, 1e5, 2.0)]
    for profile, P, M in cases:
        N = NormalProblem(profile, A).solve(P, M)
        knots = N._pressure.knots
        for x in np.linspace(N.left, N.right, 13)[1:-1]:
            inside = [k for k in knots if N.left < k < x]
            ref = quad(lambda u: float(N.pressure(u)), N.left, x, points=inside or None, limit=400,
                       epsabs=0.0, epsrel=1e-13)[0]
            value, size = N.load_to(x, magnitude=True)
            assert abs(float(value) - ref) <= 1e-12 * P, (profile, P, M, x)
            assert float(size) * (1.0 + 1e-14) >= abs(float(value))
        assert float(N.load_to(N.left - 1e-6)) == 0.0
        assert float(N.load_to(N.right + 1e-6)) == pytest.approx(P, rel=1e-13)
    assert np.shape(N.load_to(np.zeros((2, 3)))) == (2, 3)


def test_punch_pressure_broadcasts():
    problem = NormalProblem(RoundedPunch(W, R), A)
    P = punch_load(2 * W) * np.array([0.1, 1.0, 10.0])
    x = np.linspace(-6 * W, 6 * W, 25)[:, None]
    table = problem.pressure(x, P)
    assert table.shape == (25, 3)
    for j, load in enumerate(P):
        assert np.array_equal(table[:, j], problem.pressure(x[:, 0], load))
        assert np.all(table[np.abs(x[:, 0]) >= problem.half_width(load), j] == 0.0)


def test_load_increments_follow_n3():
    """dp/dP = 1 / (pi sqrt(d^2 - s^2)) and dp/dM = 2 s / (pi d^2 sqrt(d^2 - s^2)) (N3).

    Incomplete contact: the edges move, but p vanishes there, so the first
    order change is the rigid flat punch on the current contact. Central
    differences with steps 1e-4 of the load: truncation ~1e-8, solver noise
    ~1e-9 (tol 1e-13 over a 1e-4 step); tolerance 1e-6 of the derivative.
    """
    x = np.linspace(-9e-3, 9e-3, 3601)[::60]
    sampled = np.linspace(-6e-3, 6e-3, 481)
    profiles = (Hertz(R), RoundedPunch(W, R), TabulatedProfile(sampled, RoundedPunch(W, R).gap(sampled)))
    for profile in profiles:
        problem = NormalProblem(profile, A)
        P = punch_load(1.6 * W)
        a = float(problem.half_width(P))
        inner = x[np.abs(x) < 0.95 * a]
        step = 1e-4 * P
        dp_dP = (problem.pressure(inner, P + step) - problem.pressure(inner, P - step)) / (2 * step)
        flat = 1 / (math.pi * np.sqrt(a * a - inner**2))
        assert np.allclose(dp_dP, flat, rtol=1e-6, atol=0)
    problem = NormalProblem(RoundedPunch(W, R), A)
    P = punch_load(1.6 * W)
    M = 0.3 * P * 1.6 * W
    solution = problem.solve(P, M)
    d, x0 = solution.half_width, solution.center
    s = x[np.abs(x - x0) < 0.95 * d] - x0
    step = 1e-4 * P * d
    dp_dM = (problem.solve(P, M + step).pressure(x0 + s) - problem.solve(P, M - step).pressure(x0 + s)) / (2 * step)
    rigid = 2 * s / (math.pi * d * d * np.sqrt(d * d - s * s))
    assert np.allclose(dp_dM, rigid, rtol=0, atol=1e-6 * np.max(np.abs(rigid)))


# ---------------------------------------------------------------------------
# general solver
# ---------------------------------------------------------------------------


def test_general_solver_reproduces_the_punch_closed_form():
    """M = 0 through the general solver: edges to 1e-12 of a (the solver stops at 1e-13)."""
    problem = NormalProblem(RoundedPunch(W, R), A)
    for P in punch_load(2 * W) * np.array([1e-3, 1.0, 1e3]):
        closed, general = problem.solve(P), problem._solve_general(P, 0.0)
        a = closed.half_width
        assert general.left == pytest.approx(closed.left, abs=1e-12 * a)
        assert general.right == pytest.approx(closed.right, abs=1e-12 * a)
        assert general.rotation == pytest.approx(0.0, abs=1e-12 * a / R)
        assert_equilibrium(general, kinks=(-W, W))


def test_punch_under_a_large_moment_lifts_off_the_flat():
    """The contact shifts: the left edge moves onto the flat (part of it lifts off), p >= 0."""
    problem = NormalProblem(RoundedPunch(W, R), A)
    P = punch_load(1.5 * W)
    a = float(problem.half_width(P))
    previous = -a
    for ratio in (0.1, 0.3, 0.5, 0.8):
        solution = problem.solve(P, ratio * P * a)
        assert solution.left > previous and solution.right > a  # both edges move right
        previous = solution.left
        assert_equilibrium(solution, kinks=(-W, W))
        p = solution.pressure(np.linspace(solution.left, solution.right, 2001))
        assert np.all(p >= -1e-12 * p.max())
    assert -W < solution.left < W  # the left edge sits on the flat


def test_punch_moment_beyond_the_flat_is_hertz_on_the_corner():
    """When the whole contact is on the corner parabola it is Hertz about x = w: closed form to 1e-12."""
    problem = NormalProblem(RoundedPunch(W, R), A)
    P = 1e4
    a = hertz_half_width(P)
    x0 = W + 3 * a
    solution = problem.solve(P, P * x0)
    assert solution.center == pytest.approx(x0, rel=1e-12)
    assert solution.half_width == pytest.approx(a, rel=1e-12)
    assert solution.rotation == pytest.approx(-(x0 - W) / R, rel=1e-12)
    assert_equilibrium(solution)


def test_separated_for_non_positive_load():
    """P <= 0: separated, zero pressure, never an exception (any moment)."""
    for profile in (Hertz(R), RoundedPunch(W, R), TabulatedProfile(np.linspace(-1, 1, 9), np.linspace(-1, 1, 9) ** 2)):
        problem = NormalProblem(profile, A)
        for P, M in ((0.0, 0.0), (-1.0, 0.0), (-1.0, 5.0), (0.0, -3.0)):
            solution = problem.solve(P, M)
            assert solution.separated
            assert solution.left == solution.right == solution.center == solution.half_width == 0.0
            assert np.all(solution.pressure(np.linspace(-1, 1, 7)) == 0.0)
            assert solution.pressure(0.0) == 0.0
    with pytest.raises(ValueError, match="finite"):
        NormalProblem(Hertz(R), A).solve(math.nan)


def test_asymmetric_profile_has_no_symmetric_fast_path():
    x = np.linspace(-3e-3, 3e-3, 61)
    problem = NormalProblem(TabulatedProfile(x, x**2 / (2 * R) + x**3 / R**2), A)
    with pytest.raises(ValueError, match="symmetric"):
        problem.half_width(1e4)
    P = 1e5
    solution = problem.solve(P)
    assert solution.center != 0.0
    assert_equilibrium(solution, samples=x)
    solution = problem.solve(P, 0.2 * P * solution.half_width)
    assert_equilibrium(solution, samples=x)


def test_tabulated_load_too_large_raises():
    x = np.linspace(-1e-3, 1e-3, 41)
    problem = NormalProblem(TabulatedProfile(x, x**2 / (2 * R)), A)
    a_max = 1e-3
    P_max = math.pi * a_max**2 / (2 * A * R)
    assert problem.half_width(0.5 * P_max) == pytest.approx(hertz_half_width(0.5 * P_max), rel=1e-12)
    calls = (lambda: problem.half_width(2 * P_max), lambda: problem.solve(2 * P_max), lambda: problem.load(2 * a_max))
    for call in calls:
        with pytest.raises(ValueError, match="too large for the tabulated profile"):
            call()
    with pytest.raises(ValueError, match="too large for the tabulated profile"):
        problem.solve(0.1 * P_max, 0.1 * P_max * 0.95e-3)  # centroid near the end: contact would leave the span


# ---------------------------------------------------------------------------
# tabulated profiles: convergence with the sampling
# ---------------------------------------------------------------------------


def sampled_errors(profile, reference, P, M, span, counts):
    """Errors in the edges and pressure of the tabulated profile vs the reference solution."""
    exact = reference.solve(P, M)
    a = exact.half_width
    inner = exact.center + a * np.linspace(-0.999, 0.999, 801)
    p_exact = exact.pressure(inner)
    rows = []
    for n in counts:
        x = np.linspace(-span, span, n)
        solution = NormalProblem(TabulatedProfile(x, profile.gap(x)), A).solve(P, M)
        assert_equilibrium(solution, samples=x)
        edges = max(abs(solution.left - exact.left), abs(solution.right - exact.right)) / a
        rows.append((n, edges, np.max(np.abs(solution.pressure(inner) - p_exact)) / p_exact.max()))
    return np.array(rows)


def print_table(title, rows):
    with np.errstate(divide="ignore", invalid="ignore"):  # errors that are exactly 0
        orders = np.log2(rows[:-1, 1:] / rows[1:, 1:])
    print(f"\n{title}\n{'samples':>8} {'edge err':>10} {'order':>6} {'p err':>10} {'order':>6}")
    for i, (n, edge, pressure) in enumerate(rows):
        tail = f"{orders[i - 1, 0]:6.2f} {pressure:10.2e} {orders[i - 1, 1]:6.2f}" if i else f"{'':6} {pressure:10.2e}"
        print(f"{int(n):8d} {edge:10.2e} {tail}")
    return orders


def test_tabulated_hertz_is_exact():
    """The not-a-knot spline reproduces the parabola: edges and p to rounding at every sampling (1e-12)."""
    a = hertz_half_width(1e5)
    rows = sampled_errors(Hertz(R), NormalProblem(Hertz(R), A), 1e5, 0.0, 1.5 * a, [25, 49, 97, 193, 385])
    print_table("tabulated Hertz, M = 0", rows)
    assert np.all(rows[:, 1] < 1e-12) and np.all(rows[:, 2] < 1e-12)
    rows = sampled_errors(Hertz(R), NormalProblem(Hertz(R), A), 1e5, 0.3e5 * a, 2.5 * a, [41, 161])
    assert np.all(rows[:, 1] < 1e-12) and np.all(rows[:, 2] < 1e-11)


def test_tabulated_punch_converges():
    """Sampled rounded punch (samples on the corners, span +-2.5w) vs the closed form.

    The spline smooths the jump of h'' at the corners: the edges converge
    at order 4 (observed 4.0), the pressure at order 1 in the max norm
    (observed 0.92-1.07, the error sits at the corners). Bounds: 3.5 and 0.8.
    """
    P = punch_load(1.6 * W)
    counts = [10 * 2**k + 1 for k in range(3, 8)]  # 81 ... 1281, the corners on samples
    reference = NormalProblem(RoundedPunch(W, R), A)
    rows = sampled_errors(RoundedPunch(W, R), reference, P, 0.0, 2.5 * W, counts)
    orders = print_table("tabulated rounded punch, M = 0", rows)
    assert np.all(orders[:, 0] > 3.5) and np.all(orders[:, 1] > 0.8)
    a = float(reference.half_width(P))
    rows = sampled_errors(RoundedPunch(W, R), reference, P, 0.4 * P * a, 2.5 * W, counts)
    orders = print_table("tabulated rounded punch, M = 0.4 P a", rows)
    assert np.all(orders[-3:, 0] > 3.5) and np.all(orders[:, 1] > 0.8)


class Quartic:
    """h = x^4 / (4 L^3), which the spline does not reproduce. Closed form from the symmetric formula:
    P = 3 pi a^4 / (8 A L^3), p = sqrt(a^2 - x^2) (a^2 / 2 + x^2) / (A L^3)."""

    L = 5e-3

    def gap(self, x):
        return x**4 / (4 * self.L**3)

    def half_width(self, P):
        return (8 * A * self.L**3 * P / (3 * math.pi)) ** 0.25

    def pressure(self, x, a):
        return np.sqrt(np.maximum(a * a - x * x, 0)) * (a * a / 2 + x * x) / (A * self.L**3)


def test_tabulated_smooth_profile_converges():
    """Quartic gap, samples with the edges on samples (span +-1.5a, 12 2^k intervals).

    Spline error O(h^4) in h, O(h^3) in h': observed order 3.5 in the edges
    and 3.0 in p; bounds 3.2 and 2.8.
    """
    quartic = Quartic()
    P = 1e5
    a = quartic.half_width(P)
    inner = a * np.linspace(-0.999, 0.999, 801)
    p_exact = quartic.pressure(inner, a)
    rows = []
    for n in [12 * 2**k + 1 for k in range(2, 7)]:
        x = np.linspace(-1.5 * a, 1.5 * a, n)
        solution = NormalProblem(TabulatedProfile(x, quartic.gap(x)), A).solve(P)
        assert_equilibrium(solution, samples=x)
        pressure_error = np.max(np.abs(solution.pressure(inner) - p_exact)) / p_exact.max()
        rows.append((n, abs(solution.right - a) / a, pressure_error))
    orders = print_table("tabulated quartic, M = 0", np.array(rows))
    assert np.all(orders[:, 0] > 3.2) and np.all(orders[:, 1] > 2.8)


def test_default_accuracy_of_a_reasonably_sampled_profile():
    """401 samples over +-1.5a (corners anywhere): edges within 1e-6 of a (observed ~1e-8)."""
    P = punch_load(1.6 * W)
    reference = NormalProblem(RoundedPunch(W, R), A)
    a = float(reference.half_width(P))
    for M in (0.0, 0.3 * P * a):
        rows = sampled_errors(RoundedPunch(W, R), reference, P, M, 1.5 * a, [401])
        assert rows[0, 1] < 1e-6


# ---------------------------------------------------------------------------
# property: equilibrium and p >= 0 on the punch
# ---------------------------------------------------------------------------


@settings(max_examples=40, deadline=None)
@given(
    corner=st.floats(0.05, 20.0),  # R / w
    load=st.floats(-6.0, 3.0),  # log10(P / P_ref), P_ref = P(a = 2w)
    moment=st.floats(-3.0, 3.0),  # M / (P a(P)); any moment is admissible on the punch
)
def test_punch_equilibrium_and_positive_pressure(corner, load, moment):
    """(N2) to 1e-10 and p >= -1e-9 max p for random (P, M) on random punches.

    Loads below 1e-6 P_ref are left out: there the edges are so
    ill-conditioned (the loads ~ (a - w)^(3/2)) that the residual is
    rounding-limited above 1e-10.
    """
    radius = corner * W
    problem = NormalProblem(RoundedPunch(W, radius), A)
    P = punch_load(2 * W, radius=radius) * 10.0**load
    M = moment * P * float(problem.half_width(P))
    solution = problem.solve(P, M)
    assert_equilibrium(solution, kinks=(-W, W))
    p = solution.pressure(np.linspace(solution.left, solution.right, 1001))
    assert np.all(p >= -1e-9 * p.max())


def test_piece_cos_integrals_match_the_angles():
    """The compiled cos(m theta) integrals of the slope pieces (unit vectors of the pieces' mid and half
    angles raised to the m-th power) against the angles themselves (atan2, cos, sin), on random contacts
    over 200 pieces, thin pieces (1e-12 of the contact) and contacts so small that the half-angle legs
    underflow (the 1e-300 P contact a(0+) of the exact method asks for).

    Tolerance: 1e-14 absolute on integrals of size up to pi (the recurrences for m <= 5 add a few
    eps), and 1e-12 relative to the piece's own width for the thin pieces: both formulas are accurate
    relative to the width (the width is one atan2 of non-negative legs); a cancellation there would show
    as 1e-4 or worse.
    """
    from halfslip.geometry import _half_angle_legs, _piece_integrals, _SlopePieces

    def by_angles(pieces, center, half_width):
        x0, d = center[:, None], half_width[:, None]
        left, right = x0 - d, x0 + d
        first = np.searchsorted(pieces.breaks, left.min(), side="right")
        last = np.searchsorted(pieces.breaks, right.max(), side="left") + 1
        lower = np.minimum(np.maximum(pieces.lower[first:last], left), right)
        upper = np.minimum(np.maximum(pieces.upper[first:last], left), right)
        y_lo, x_lo = _half_angle_legs(lower, left, right)
        y_up, x_up = _half_angle_legs(upper, left, right)
        with np.errstate(divide="ignore", invalid="ignore"):
            cross = np.where(upper > lower, (right - left) * (upper - lower) / (y_lo * x_up + x_lo * y_up), 0.0)
        width = 2.0 * np.arctan2(cross, x_lo * x_up + y_lo * y_up)
        mid = np.arctan2(y_lo, x_lo) + np.arctan2(y_up, x_up)
        m = np.arange(1, 6)
        return np.concatenate((width[..., None], (2.0 / m) * np.cos(mid[..., None] * m)
                               * np.sin(0.5 * width[..., None] * m)), axis=-1)

    rng = np.random.default_rng(7)
    breaks = np.sort(rng.uniform(-1e-3, 1e-3, 200))
    breaks = np.sort(np.concatenate((breaks, breaks[50:60] + 1e-15)))  # thin pieces
    pieces = _SlopePieces(breaks, np.zeros(breaks.size + 1), rng.standard_normal((breaks.size + 1, 3)))
    center = rng.uniform(-2e-4, 2e-4, 300)
    half_width = rng.uniform(1e-6, 8e-4, 300)
    got = _piece_integrals(pieces, center, half_width).cos_integrals
    want = by_angles(pieces, center, half_width)
    assert np.max(np.abs(got - want)) <= 1e-14
    width = np.abs(want[..., :1])
    thin = (width > 0.0) & (width < 1e-6)
    assert np.any(thin)
    assert np.max((np.abs(got - want) / np.where(width > 0.0, width, 1.0))[thin[..., 0]]) <= 1e-12
    tiny = _piece_integrals(pieces, np.array([0.0]), np.array([1e-310])).cos_integrals
    assert np.all(np.isfinite(tiny))
    assert np.allclose(tiny, by_angles(pieces, np.array([0.0]), np.array([1e-310])), rtol=0.0, atol=1e-14)


@pytest.mark.parametrize("kind", ["hertz", "punch", "tabulated"])
def test_one_contacts_solution_in_one_compiled_call_is_the_batched_route(kind):
    """NormalProblem._solution takes a contact's rotation, pressure coefficients and inner knots from one
    compiled call (_geometry_kernels._contact_solution, since 0.4.3, the general solver asks at every
    sub-step) instead of _piece_integrals, _moments_from and _ContactPressure.from_integrals: the same
    operations, so the same numbers to the last bit (the sums over the pieces stay numpy's), on contacts
    anywhere across a Hertz pad, a rounded punch and a tabulated profile of 399 samples."""
    from halfslip import geometry as geo

    x = np.linspace(-5e-3, 5e-3, 399)
    profile = {"hertz": Hertz(R), "punch": RoundedPunch(W, R),
               "tabulated": TabulatedProfile(x, x**2 / (2 * R) + 1e-7 * np.sin(3e3 * x) ** 2)}[kind]
    problem = NormalProblem(profile, A)
    rng = np.random.default_rng(3)
    for _ in range(100):
        d = rng.uniform(1e-6, 2e-3)
        center = rng.uniform(-1e-3, 1e-3)
        got = problem._solution(1.0, 0.0, center, d)
        data = geo._piece_integrals(problem._pieces, np.array([center]), np.array([d]))
        rotation = -float(geo._moments_from(data, np.array([d])).slope[0, 0]) / math.pi
        pressure = geo._ContactPressure.from_integrals(problem._pieces, problem.compliance, center, d, data)
        assert got.rotation == rotation
        assert got._pressure.smooth == pressure.smooth
        assert np.array_equal(got._pressure.knots, pressure.knots)
        assert np.array_equal(got._pressure.jumps, pressure.jumps)
