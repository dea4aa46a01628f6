"""NormalProblem.solve(P, M, near=...): the warm start of the general normal solver.

The warm start begins the Newton iteration at the first-order prediction
from a nearby solution and falls back to the cold start when it does not
converge. Its answer must be the cold answer to the solver's own tolerance:
each solve stops at a point where the scaled residuals are below
max(tol, rounding level), i.e. within |J^-1| max(tol, noise) of the root
in (x0, d) (J the scaled Jacobian there), so two solves of the same loads
may differ by twice that ("resolution" below). On the punch benchmark's
normal solves the warm and cold edges differ by at most 0.78 of one
resolution (1.3e-11 of the width, at loads 1e-5 of nominal where the
residual is at rounding level), the pressures by 6.4e-11 of the peak.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from halfslip import geometry, load_scene
from halfslip.geometry import Hertz, Material, NormalProblem, RoundedPunch, TabulatedProfile

A = Material(E=115e9, nu=0.3).compliance  # Ti-6Al-4V, the dovetail example
W, R = 2e-3, 10e-3  # flat half-width and corner radius [m]
P_NOMINAL = 2e5  # N/m
EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
PRESSURE_RTOL = 1e-9  # of the peak sampled pressure; measured 6.4e-11 on the benchmark's solves


def resolution(problem: NormalProblem, solution) -> float:
    """|dx0| + |dd| bounding how far an accepted solve may lie from the root (module docstring)."""
    equations = geometry._ContactEquations(
        problem._pieces, problem.compliance, solution.P, solution.M, solution.half_width
    )
    _, J, noise = equations(solution.center, solution.half_width)
    bound = np.abs(np.linalg.inv(J)) @ np.maximum(problem.tol, noise)
    return float(bound[0] + bound[1])


def loads_of_contact(problem: NormalProblem, left: float, right: float) -> tuple[float, float]:
    """(P, M) whose contact is [left, right]: N1 and N2 evaluated on that contact."""
    x0, d = 0.5 * (left + right), 0.5 * (right - left)
    moments = geometry._chebyshev_moments(problem._pieces, np.array([x0]), np.array([d]))
    _, I1, I2 = moments.slope[0]
    P = d * I1 / problem.compliance
    return P, d * d * I2 / (2.0 * problem.compliance) + P * x0


def assert_warm_is_cold(problem, warm, cold):
    assert not warm.separated and warm.P == cold.P and warm.M == cold.M
    allowed = 2.0 * resolution(problem, cold)
    assert abs(warm.left - cold.left) <= allowed, (warm.left - cold.left, allowed)
    assert abs(warm.right - cold.right) <= allowed, (warm.right - cold.right, allowed)
    x = cold.center + cold.half_width * np.array([-0.95, -0.7, -0.3, 0.0, 0.4, 0.8, 0.95])
    p_cold = cold.pressure(x)
    assert np.allclose(warm.pressure(x), p_cold, rtol=0, atol=PRESSURE_RTOL * np.max(p_cold))
    assert warm.rotation == pytest.approx(cold.rotation, rel=1e-9, abs=1e-12 * cold.half_width / R)


def nearby(rng, problem, P, M, spread=5e-3):
    """A solution at loads a few per mille from (P, M): P by up to ``spread``, M by ``spread`` (|M| + P d)."""
    d = problem.solve(P, M).half_width
    return problem.solve(P * (1 + rng.uniform(-spread, spread)), M + rng.uniform(-spread, spread) * (abs(M) + P * d))


def warm_iterations(problem, P, M, near):
    """The solution with ``near`` and whether the warm iteration gave it (no fallback)."""
    calls = []
    original = problem._solve_warm

    def spy(*args):
        calls.append(original(*args))
        return calls[-1]

    problem._solve_warm = spy
    try:
        solution = problem.solve(P, M, near=near)
    finally:
        del problem._solve_warm
    return solution, len(calls) == 1 and calls[0] is not None


# ---------------------------------------------------------------------------
# rounded punch with moments
# ---------------------------------------------------------------------------

PUNCH_CONTACTS = [
    # (left, right) / W: the contact the loads are built for
    (-1.3, 1.0001),  # right edge just past the end of the flat (a kink of h'')
    (-1.00002, 1.00001),  # both edges just past the flat ends, a small load with a small moment
    (-0.9, 1.5),  # large moment: the left part of the flat lifts off
    (-0.2, 1.8),  # most of the flat lifted off
    (-0.999, 1.2),  # lift-off just starting
    (-1.6, 1.4),  # both edges on the corners
]


@pytest.mark.parametrize("contact", PUNCH_CONTACTS)
def test_punch_warm_equals_cold_at_random_nearby_loads(contact):
    problem = NormalProblem(RoundedPunch(W, R), A)
    P, M = loads_of_contact(problem, contact[0] * W, contact[1] * W)
    cold = problem.solve(P, M)
    assert cold.left == pytest.approx(contact[0] * W, rel=1e-9)
    assert cold.right == pytest.approx(contact[1] * W, rel=1e-9)
    rng = np.random.default_rng(PUNCH_CONTACTS.index(contact))
    used_warm = 0
    for _ in range(8):
        near = nearby(rng, problem, P, M)
        warm, was_warm = warm_iterations(problem, P, M, near)
        used_warm += was_warm
        assert_warm_is_cold(problem, warm, cold)
    assert used_warm == 8  # nearby loads never need the fallback


def test_punch_random_loads_with_moments():
    """The benchmark's load range: P in [0.4, 1.6] P_n, M = m P W / 2 with |m| <= 1.25 (lift-off above ~1.05)."""
    problem = NormalProblem(RoundedPunch(W, R), A)
    rng = np.random.default_rng(7)
    for _ in range(30):
        P = P_NOMINAL * rng.uniform(0.4, 1.6)
        M = rng.uniform(-1.25, 1.25) * P * W / 2
        near = nearby(rng, problem, P, M)
        warm, was_warm = warm_iterations(problem, P, M, near)
        assert was_warm
        assert_warm_is_cold(problem, warm, problem.solve(P, M))


def test_a_march_takes_fewer_iterations_warm():
    """Steps of 3e-3 in P and M, each solve warm from the previous: at most 3 iterations, cold needs 5 or more."""
    problem = NormalProblem(RoundedPunch(W, R), A)
    P = P_NOMINAL * (1 + 0.3 * np.sin(np.linspace(0, 2, 60)))
    M = 0.4 * P * W * np.cos(np.linspace(0, 3, 60))
    previous, warm_total, cold_total = None, 0, 0
    for load, moment in zip(P, M):
        warm = problem.solve(load, moment, near=previous)
        cold = problem.solve(load, moment)
        assert_warm_is_cold(problem, warm, cold)
        if previous is not None:
            assert warm.iterations <= 3
            warm_total += warm.iterations
            cold_total += cold.iterations
        previous = warm
    assert warm_total <= 0.5 * cold_total, (warm_total, cold_total)


def test_edge_coefficients_match_the_pressure_at_the_edges():
    """k in p = sqrt(dist) (k + O(dist)): p / sqrt(dist) at dist = e and e / 4, extrapolated, to 1e-6.

    e = 1e-3 of the distance from the edge to the nearest kink of h'' (or of d),
    within which the O(dist) term is the leading correction.
    """
    problem = NormalProblem(RoundedPunch(W, R), A)
    for contact in PUNCH_CONTACTS + [(-1.5, 1.5)]:
        solution = problem.solve(*loads_of_contact(problem, contact[0] * W, contact[1] * W))
        k_left, k_right = solution._pressure.edge_coefficients()
        for k, edge, inwards in ((k_left, solution.left, 1.0), (k_right, solution.right, -1.0)):
            e = 1e-3 * min([solution.half_width] + [abs(edge - kink) for kink in (-W, W)])
            ratio = [float(solution.pressure(edge + inwards * h)) / math.sqrt(h) for h in (e, e / 4)]
            assert k == pytest.approx((4 * ratio[1] - ratio[0]) / 3, rel=1e-6), contact


def test_prediction_is_first_order():
    """The predicted start is O(dP^2) off the root: 10x smaller step, ~100x smaller error."""
    problem = NormalProblem(RoundedPunch(W, R), A)
    P, M = loads_of_contact(problem, -0.9 * W, 1.5 * W)
    near = problem.solve(P, M)
    errors = []
    for step in (1e-2, 1e-3):
        target = problem.solve(P * (1 + step), M * (1 - step))
        x0, d = geometry._warm_contact(near, target.P, target.M)
        errors.append(max(abs(x0 - target.center), abs(d - target.half_width)) / target.half_width)
    assert errors[1] < 0.03 * errors[0], errors


# ---------------------------------------------------------------------------
# fallback and errors
# ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    "near_loads, loads",
    [
        ((P_NOMINAL, 0.6 * P_NOMINAL * W), (1e-4 * P_NOMINAL, 0.5e-4 * P_NOMINAL * W)),
        ((100 * P_NOMINAL, 0.0), (1e-3 * P_NOMINAL, 0.5e-3 * P_NOMINAL * W)),
        ((P_NOMINAL, 0.62 * P_NOMINAL * W), (1e-5 * P_NOMINAL, 0.52e-5 * P_NOMINAL * W)),
    ],
)
def test_a_far_near_falls_back_to_the_cold_start(near_loads, loads):
    """The warm iteration fails from these: the answer is the cold one, bit for bit."""
    problem = NormalProblem(RoundedPunch(W, R), A)
    near = problem.solve(*near_loads)
    solution, was_warm = warm_iterations(problem, *loads, near)
    assert not was_warm
    cold = problem.solve(*loads)
    assert (solution.left, solution.right, solution.iterations, solution.residual) == (
        cold.left, cold.right, cold.iterations, cold.residual
    )


def test_far_nears_give_the_cold_answer():
    """Any near, however far (warm iteration or fallback), gives the cold answer."""
    problem = NormalProblem(RoundedPunch(W, R), A)
    rng = np.random.default_rng(11)
    loads = [(P_NOMINAL * 10 ** rng.uniform(-5, 2), 0.0) for _ in range(12)]
    loads = [(P, rng.uniform(-1.2, 1.2) * P * W / 2) for P, _ in loads]
    solutions = [problem.solve(P, M) for P, M in loads]
    for (P, M), cold in zip(loads, solutions):
        for near in solutions[::3]:
            assert_warm_is_cold(problem, problem.solve(P, M, near=near), cold)


def test_separated_or_foreign_near():
    problem = NormalProblem(RoundedPunch(W, R), A)
    P, M = P_NOMINAL, 0.3 * P_NOMINAL * W
    cold = problem.solve(P, M)
    separated = problem.solve(0.0, 0.0)
    assert problem.solve(P, M, near=separated) == cold  # separated near: the cold start
    assert problem.solve(-1.0, M, near=cold).separated
    with pytest.raises(ValueError, match="near must be a NormalSolution or None, got tuple"):
        problem.solve(P, M, near=(cold.center, cold.half_width))


def test_span_error_unchanged_with_near():
    """A contact that would leave a tabulated span raises today's error with or without near."""
    x = np.linspace(-1e-3, 1e-3, 41)
    problem = NormalProblem(TabulatedProfile(x, x**2 / (2 * R)), A)
    P = 0.1 * math.pi * 1e-6 / (2 * A * R)  # a = 0.32 mm
    near = problem.solve(P, P * 0.66e-3)  # the right edge at 0.98 mm
    assert near.right < 1e-3
    with pytest.raises(ValueError) as cold_error:
        problem.solve(P, P * 0.7e-3)  # the contact would reach 1.02 mm
    with pytest.raises(ValueError) as warm_error:
        problem.solve(P, P * 0.7e-3, near=near)
    assert str(warm_error.value) == str(cold_error.value)
    assert "too large for the tabulated profile" in str(warm_error.value)


# ---------------------------------------------------------------------------
# tabulated profiles
# ---------------------------------------------------------------------------


def tabulated_cases():
    x = np.linspace(-3e-3, 3e-3, 61)
    asymmetric = TabulatedProfile(x, x**2 / (2 * R) + x**3 / R**2)
    sampled = np.linspace(-5e-3, 5e-3, 201)
    punch = TabulatedProfile(sampled, RoundedPunch(W, R).gap(sampled))  # symmetric: the general path for M != 0
    worn = load_scene(EXAMPLES / "tabulated.yaml")  # the example's worn pad: not convex (a wear scar)
    return [
        pytest.param(asymmetric, A, 1e5, (-0.5, 0.0, 0.5), id="asymmetric"),
        pytest.param(punch, A, P_NOMINAL, (-1.0, 0.3, 1.1), id="sampled-punch"),
        pytest.param(worn.profile, worn.material.compliance, 5e4, (-0.4, 0.1, 0.4), id="worn-pad"),
    ]


@pytest.mark.parametrize("profile, compliance, P, moments", tabulated_cases())
def test_tabulated_warm_equals_cold(profile, compliance, P, moments):
    assert isinstance(profile, TabulatedProfile)
    problem = NormalProblem(profile, compliance)
    d = problem.solve(P).half_width
    rng = np.random.default_rng(3)
    for m in moments:
        load = P * rng.uniform(0.8, 1.2)
        M = m * load * d
        cold = problem.solve(load, M)
        for _ in range(4):
            warm, was_warm = warm_iterations(problem, load, M, nearby(rng, problem, load, M))
            assert was_warm
            assert_warm_is_cold(problem, warm, cold)


# ---------------------------------------------------------------------------
# closed forms ignore near
# ---------------------------------------------------------------------------


def test_closed_forms_ignore_near():
    x = np.linspace(-3e-3, 3e-3, 61)
    cases = [
        (NormalProblem(Hertz(50e-3), A), 1e5, 2.0),  # Hertz: any M
        (NormalProblem(RoundedPunch(W, R), A), P_NOMINAL, 0.0),  # punch, M = 0
        (NormalProblem(RoundedPunch(0.0, R), A), P_NOMINAL, 5.0),  # punch without a flat: Hertz
        (NormalProblem(TabulatedProfile(x, x**2 / (2 * R)), A), 1e5, 0.0),  # symmetric table, M = 0
    ]
    for problem, P, M in cases:
        plain = problem.solve(P, M)
        near = problem.solve(1.003 * P, M + 1e-3 * P * plain.half_width)
        assert problem.solve(P, M, near=near) == plain
        assert plain.iterations == 0 and plain.residual == 0.0
