"""The exact level-memory method against the closed forms of physics.md.

Tolerances: the method is exact for straight load steps, so stick edges and
q(x) are compared to the closed forms (J1, J2) at 1e-10 relative -- the only
errors are rounding in the level arithmetic and in a(P) (Newton to machine
precision for the punch). Looser tolerances are stated where a sampled
quantity (a minimum over discrete steps, a trapezoid integral) is compared.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from halfslip.solvers.exact import ExactMemory
from halfslip.state import Loads, Regime

import helpers
from helpers import A, F, P0, PROFILES



march = helpers.states  # the states of stepping through (P, Q) points


def make(kind, P_max=P0, stations=None):
    return helpers.make(kind, "exact", P_max=P_max, stations=stations)


def rel_err(a, b):
    return np.max(np.abs(np.asarray(a) - np.asarray(b))) / np.max(np.abs(b))


@pytest.mark.parametrize("kind", PROFILES)
@pytest.mark.parametrize("ratio", [0.05, 0.3, 0.7, 0.95])
def test_cattaneo_mindlin_jaeger_ciavarella(kind, ratio):
    """J1: b = a(P - Q/f), q = f [p(x, P) - p(x, P - Q/f)] after P then Q."""
    problem, method = make(kind)
    Q = ratio * F * P0
    state = march(method, [(P0, 0.0), (P0, Q)])[-1]
    b = problem.half_width(P0 - Q / F)
    assert state.stick_right == pytest.approx(b, rel=1e-10)
    assert state.stick_left == pytest.approx(-b, rel=1e-10)
    a = problem.half_width(P0)
    x = np.linspace(-a, a, 801)
    _, q = method.tractions(state.memory, x)
    q_closed = F * (problem.pressure(x, P0) - problem.pressure(x, P0 - Q / F))
    assert rel_err(q, q_closed) < 1e-10


@pytest.mark.parametrize("kind", PROFILES)
def test_mindlin_unloading_and_reloading(kind):
    """J2 on unloading from Q_max; on reloading to Q_max the J1 state returns."""
    problem, method = make(kind)
    Qmax = 0.6 * F * P0
    a = problem.half_width(P0)
    x = np.linspace(-a, a, 801)
    loaded = march(method, [(P0, 0.0), (P0, Qmax)])[-1]
    for Q in (0.4 * Qmax, 0.0, -0.5 * Qmax):
        state = march(method, [(P0, Q)], loaded)[-1]
        c = problem.half_width(P0 - (Qmax - Q) / (2 * F))
        assert state.stick_right == pytest.approx(c, rel=1e-10)
        _, q = method.tractions(state.memory, x)
        q_closed = (
            -F * problem.pressure(x, P0)
            + 2 * F * problem.pressure(x, P0 - (Qmax - Q) / (2 * F))
            - F * problem.pressure(x, P0 - Qmax / F)
        )
        assert rel_err(q, q_closed) < 1e-10
    # reloading back to Q_max restores the monotonic-loading traction (Masing)
    back = march(method, [(P0, -0.5 * Qmax), (P0, Qmax)], loaded)[-1]
    _, q_back = method.tractions(back.memory, x)
    _, q_loaded = method.tractions(loaded.memory, x)
    assert rel_err(q_back, q_loaded) < 1e-10


@pytest.mark.parametrize("kind", PROFILES)
@pytest.mark.parametrize("k_unload", [0.3, 0.45, 0.52, 0.7])
def test_receding_contact_after_proportional_loading(kind, k_unload):
    """J3: loaded in proportion to (P0, k f P0) (full stick, q = k f p), then unloaded along dQ = k' f dP:
    the levels above P_c are set to -+f, q = k f p(P) -+ (1 +- k) f [p(P) - p(P_c)] with P - P_c =
    abs(k' - k) (P0 - P) / (1 +- k) (backwards for k' > k), the stick zone that of P_c (to rounding)."""
    problem, method = make(kind)
    k = 0.5
    state = march(method, [(P, k * F * P) for P in np.linspace(0.05, 1.0, 20) * P0])[-1]
    back = k_unload > k
    for P in (0.95 * P0, 0.8 * P0, 0.6 * P0):
        state = march(method, [(P, k * F * P0 + k_unload * F * (P - P0))], state)[-1]
        Pc = helpers.j3_stick_load(P, k, k_unload)
        c = problem.half_width(Pc)
        assert state.stick_right == pytest.approx(c, rel=1e-10)
        assert state.stick_left == pytest.approx(-c, rel=1e-10)
        a = problem.half_width(P)
        x = np.linspace(-a, a, 801)
        _, q = method.tractions(state.memory, x)
        sign = -1.0 if back else 1.0
        q_closed = k * F * problem.pressure(x, P) + sign * (1 - sign * k) * F * (
            problem.pressure(x, P) - problem.pressure(x, Pc))
        assert rel_err(q, q_closed) < 1e-10


def motor_loop(P_mean, P_amp, Q_mean, Q_amp, phase_deg, n):
    theta = 2 * np.pi * np.arange(1, n + 1) / n
    P = P_mean + P_amp * np.sin(theta)
    Q = Q_mean + Q_amp * np.sin(theta + np.radians(phase_deg))
    return P, Q


def stick_level_T(P, Q):
    """P_T of the point T where lines of gradient +f and -f touch the loop."""
    theta = np.linspace(0, 2 * np.pi, 200001)
    return (np.min(Q(theta) + F * P(theta)) - np.max(Q(theta) - F * P(theta))) / (2 * F)


@pytest.mark.parametrize(
    "P_amp, Q_mean, Q_amp, phase",
    [
        (0.3 * P0, 0.0, 0.3 * P0, 90.0),
        (0.5 * P0, 0.1 * P0, 0.25 * P0, 90.0),
        (0.2 * P0, -0.05 * P0, 0.35 * P0, 45.0),
        (0.4 * P0, 0.0, 0.2 * P0, 150.0),
    ],
)
@pytest.mark.parametrize("kind", PROFILES)
def test_barber_davies_hills_permanent_stick_zone(kind, P_amp, Q_mean, Q_amp, phase):
    """After the first cycle the stick zone never shrinks below a(P_T) and reaches it.

    The minimum over the sampled steps of a cycle approaches a(P_T) to second order
    in the angular step (the tangency falls between samples): 4000 steps per cycle,
    dtheta^2 ~ 2.5e-6, tolerance 1e-5 relative.
    """
    problem, method = make(kind, P_max=P0 + P_amp)
    n = 4000
    P, Q = motor_loop(P0, P_amp, Q_mean, Q_amp, phase, n)
    ramp = [(P0 * k / 10, Q0 * k / 10) for k, Q0 in zip(range(1, 11), [Q[-1]] * 10)]
    state = march(method, ramp)[-1]
    cycles = []
    for _ in range(3):
        states = march(method, list(zip(P, Q)), state)
        cycles.append(np.array([s.stick_right for s in states]))
        state = states[-1]
    P_T = stick_level_T(
        lambda th: P0 + P_amp * np.sin(th), lambda th: Q_mean + Q_amp * np.sin(th + np.radians(phase))
    )
    assert 0 < P_T < np.min(P), "test loop must have a permanent stick zone inside the contact"
    expected = problem.half_width(P_T)
    for stick in cycles[1:]:
        assert np.nanmin(stick) == pytest.approx(expected, rel=1e-5)
        assert np.all(stick >= expected * (1 - 1e-12))


def test_barber_davies_hills_gross_sliding_every_cycle():
    """A loop crossing abs(Q) = f P slides grossly each cycle: nothing sticks permanently."""
    problem, method = make("hertz", P_max=1.6 * P0)
    P, Q = motor_loop(P0, 0.6 * P0, 0.0, 0.5 * P0, 90.0, 400)
    assert np.any(np.abs(Q) >= F * P)
    state = march(method, [(P0, 0.0)])[-1]
    for _ in range(3):
        states = march(method, list(zip(P, Q)), state)
        regimes = [s.memory.P[-1] for s in states]  # noqa: F841 - states exercised
        gross = [i for i, s in enumerate(states) if np.isnan(s.stick_right)]
        assert gross, "every cycle must pass through gross sliding"
        state = states[-1]
        # after gross sliding the memory was wiped: w = +-f on every level
        i = gross[-1]
        mem = states[i].memory
        assert np.allclose(np.abs(mem.slopes()), F, rtol=1e-12)


def test_full_stick_when_P_and_Q_rise_together():
    """physics.md trap 1: Q/P = 0.5 f raised from zero sticks fully, q = (Q/P) p."""
    for kind in PROFILES:
        problem, method = make(kind, stations=np.linspace(-3e-4, 3e-4, 61))
        path = [(P0 * k / 7, 0.5 * F * P0 * k / 7) for k in range(1, 8)]
        states = march(method, path)
        a = problem.half_width(P0)
        x = np.linspace(-a, a, 401)
        p, q = method.tractions(states[-1].memory, x)
        assert rel_err(q, 0.5 * F * p) < 1e-12
        assert states[-1].stick_right == pytest.approx(a, rel=1e-12)
        slip = method.slip(states[-1].memory)
        assert np.nanmax(np.abs(slip)) < 1e-12 * a


def _state_key(state):
    m = state.memory
    return np.concatenate([m.P, m.W, [state.dissipation, state.shift, state.stick_right]])


@pytest.mark.parametrize("kind", PROFILES)
def test_step_size_independence(kind):
    """Segment ends agree to 1e-12 whether a segment is sampled by 1 or 1000 steps."""
    corners = [(P0, 0.2 * F * P0), (1.2 * P0, -0.3 * F * P0), (0.6 * P0, 0.1 * F * P0),
               (0.9 * P0, 0.5 * F * P0), (0.3 * P0, -0.1 * F * P0), (1.1 * P0, 0.0)]
    _, method = make(kind, P_max=1.2 * P0)
    coarse = march(method, corners)
    fine_state = method.initial_state()
    start = (0.0, 0.0)
    for k, end in enumerate(corners):
        steps = [(start[0] + (end[0] - start[0]) * j / 1000, start[1] + (end[1] - start[1]) * j / 1000)
                 for j in range(1, 1001)]
        fine_state = march(method, steps, fine_state)[-1]
        a, b = _state_key(coarse[k]), _state_key(fine_state)
        assert a.shape == b.shape
        scale = np.maximum(np.abs(a), np.abs(a).max() * 1e-3)
        assert np.max(np.abs(a - b) / scale) < 1e-12, k
        start = end


def integrate_q(problem, method, mem):
    """int q dx by tanh-sinh quadrature on each annulus a_k < abs(x) < a_{k+1}.

    q has square-root ends and, on the punch at small levels, near-singular
    layers of width a(P) - w at the annulus ends; the doubly-exponential node
    clustering of tanh-sinh resolves both to ~1e-14 (1e-11 for levels below
    1e-3 P, where the layer is thinner than 1e-9 a).
    """
    kinks = [getattr(problem.profile, "flat_half_width", 0.0)]  # h'' jumps there: log terms in p
    a = np.unique(np.concatenate([[0.0], kinks, problem.half_width(np.asarray(mem.P))]))
    a = a[a <= a[-1]]
    u = np.arange(-4.0, 4.0 + 1e-12, 1.0 / 64)
    t = np.tanh(0.5 * np.pi * np.sinh(u))
    wts = 0.5 * np.pi * np.cosh(u) / np.cosh(0.5 * np.pi * np.sinh(u)) ** 2 / 64
    total = 0.0
    for lo, hi in zip(a[:-1], a[1:]):
        x = 0.5 * (lo + hi) + 0.5 * (hi - lo) * t
        _, q = method.tractions(mem, x)
        total += 2 * 0.5 * (hi - lo) * np.sum(q * wts)  # q is even in x
    return total


piecewise_paths = st.lists(
    st.tuples(st.floats(0.05, 1.0), st.floats(-1.0, 1.0)), min_size=2, max_size=12
)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(path=piecewise_paths, kind=st.sampled_from(sorted(PROFILES)))
def test_invariants_on_random_histories(path, kind):
    """Equilibrium, Coulomb, monotone dissipation, locked-in strain in stick."""
    problem, method = make(kind, P_max=P0)
    x = np.linspace(-1.0, 1.0, 201) * float(problem.half_width(P0))
    method = ExactMemory(problem, F, P0, stations=x)
    state = method.initial_state()
    for i, (p_frac, q_frac) in enumerate(path):
        P = p_frac * P0
        Q = q_frac * F * P * 0.999
        new, report = method.step(state, float(i + 1), Loads(P, Q, 0.0, 0.0))
        mem = new.memory
        assert mem.W[-1] == pytest.approx(Q, rel=1e-12, abs=1e-12 * F * P)
        assert integrate_q(problem, method, mem) == pytest.approx(Q, rel=1e-11, abs=1e-11 * F * P)
        p, q = method.tractions(mem, x)
        assert np.all(np.abs(q) <= F * p + 1e-12 * F * np.max(p))
        assert new.dissipation >= state.dissipation
        # stations stuck at the end of the step did not slip during it
        before, after = method.slip(state.memory), method.slip(mem)
        stuck = (np.abs(x) < 0.999 * new.stick_right) & np.isfinite(before)
        scale = A * F * P0  # natural slip scale (A/pi) f P up to O(1)
        assert np.all(np.abs(after[stuck] - before[stuck]) <= 1e-12 * scale)
        state = new


def test_separation_and_recontact():
    """P -> 0 loses the memory; re-contact starts afresh and sticks."""
    problem, method = make("hertz")
    states = march(method, [(P0, 0.3 * F * P0), (0.0, 0.0), (P0, 0.0)])
    assert states[1].memory.P == (0.0,)
    assert np.isnan(states[1].contact_right)
    _, q = method.tractions(states[2].memory, np.linspace(-1e-4, 1e-4, 11))
    assert np.all(q == 0.0)
    assert states[2].stick_right == pytest.approx(problem.half_width(P0), rel=1e-12)


def test_gross_sliding_reported_and_survived():
    problem, method = make("hertz")
    s0 = march(method, [(P0, 0.0)])[-1]
    s1, report = method.step(s0, 2.0, Loads(P0, 1.2 * F * P0, 0, 0))
    assert report.regime == Regime.GROSS_SLIDING
    assert "gross sliding" in report.message
    assert s1.memory.W[-1] == pytest.approx(F * P0)
    s2, report = method.step(s1, 3.0, Loads(P0, 0.5 * F * P0, 0, 0))
    assert report.regime == Regime.PARTIAL_SLIP
    assert s2.stick_right == pytest.approx(problem.half_width(P0 - 0.5 * F * P0 / (2 * F)), rel=1e-12)


def test_dissipation_equals_loop_work():
    """Over a closed constant-P cycle the elastic energy returns: D_cycle = closed integral Q d(shift).

    The loop integral is a trapezoid over 8000 samples of a smooth loop, error
    O(n^-2) ~ 1e-7 relative; tolerance 1e-6.
    """
    _, method = make("hertz")
    state = march(method, [(P0, 0.0), (P0, 0.4 * F * P0)])[-1]
    theta = np.linspace(0, 2 * np.pi, 8001)[1:]
    Q = 0.4 * F * P0 * np.cos(theta)
    states = march(method, [(P0, q) for q in Q], state)
    shift = np.array([state.shift] + [s.shift for s in states])
    Qs = np.concatenate([[0.4 * F * P0], Q])
    work = np.trapezoid(Qs, shift)
    D = states[-1].dissipation - state.dissipation
    assert D > 0
    assert work == pytest.approx(D, rel=1e-6)


def test_slip_against_log_kernel_integral_of_q():
    """Slip of Cattaneo loading equals S(x) - S(0), S = (A/pi) int q(xi) ln abs(x - xi) dxi.

    The relative displacement is integrated by adaptive quadrature of the
    reconstructed q against the log kernel (breakpoints at x and at the stick and
    contact edges), independently of the level formula. Observed agreement 1e-12
    relative to the peak slip at most stations and 3e-8 at x = 0.9 a, where quad
    falls short of its requested 1e-12 next to the sqrt edge of q; tolerance 1e-7.
    """
    from scipy.integrate import quad

    problem, _ = make("hertz")
    a = float(problem.half_width(P0))
    Q = 0.5 * F * P0
    b = float(problem.half_width(P0 - Q / F))
    x = np.array([0.3, 0.6, 0.8, 0.9, 0.97]) * a
    method = ExactMemory(problem, F, P0, stations=x)
    state = march(method, [(P0, 0.0), (P0, Q)])[-1]
    slip = method.slip(state.memory)

    def q_of(xi):
        return method.tractions(state.memory, np.array([xi]))[1][0]

    def S(xx):
        pts = sorted({-b, b, xx})
        val = quad(lambda xi: q_of(xi) * np.log(abs(xx - xi)), -a, a, points=pts, limit=500,
                   epsabs=0, epsrel=1e-12)[0]
        return A / math.pi * val

    independent = np.array([S(xx) for xx in x]) - S(0.0)
    assert np.max(np.abs(slip - independent)) < 1e-7 * np.max(np.abs(slip))
    assert np.all(slip[x > b] > 0)  # positive slip under rising Q
    assert np.all(np.abs(slip[x < b]) < 1e-12 * np.max(slip))  # the stick zone did not slip
