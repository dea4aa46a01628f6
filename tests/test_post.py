"""Derived quantities (halfslip.post) against closed forms, energy balance and the files.

Reference solutions used here (physics.md):

* Hertz: a^2 = 2 A R P / pi, p0 = a / (A R), p = p0 sqrt(1 - x^2/a^2).
* Cattaneo (monotonic Q from 0 at constant P): stick zone b = a sqrt(1 - Q/(fP)),
  q = (f p0 / a) [sqrt(a^2 - x^2) - sqrt(b^2 - x^2)] (second term inside b only).
* PV int_{-c}^{c} sqrt(c^2 - xi^2) / (x - xi) dxi = pi (x - sign(x) sqrt(x^2 - c^2) [abs(x) > c]).
* PV int_{-a}^{a} dxi / (pi sqrt(a^2 - xi^2) (x - xi)) = 0 inside, sign(x) / sqrt(x^2 - a^2) outside.
* Cyclic Q = +-Qa at constant P: permanent stick half-width c = a(P - Qa/f); the
  slip amplitude, from the level construction with w changing by 2f on the levels
  [P - Qa/f, P_x], is delta(x) = (f / 2R) [|x| sqrt(x^2 - c^2) - c^2 arccosh(|x|/c)].
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from scipy.integrate import quad

import halfslip as hs
from halfslip import post
from halfslip.errors import HalfslipInputError
from halfslip.io import read_result, write_result

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
HERTZ_PAD = (EXAMPLES / "hertz_pad.yaml").read_text()
from helpers import hertz_pad_text  # noqa: E402

# hertz_pad.yaml: steel, R = 50 mm, P = 1e5 N/m, Q = 1.8e4 sin(2 pi t), f = 0.6
F, R, P, QA = 0.6, 50.0e-3, 1.0e5, 1.8e4
A = 4 * (1 - 0.3**2) / 200.0e9
A_P = np.sqrt(2 * A * R * P / np.pi)  # contact half-width
P0 = A_P / (A * R)  # peak pressure


scene_text = hertz_pad_text


@pytest.fixture(scope="module")
def hertz_full():
    """hertz_pad with every cycle marched (no skipping)."""
    return hs.simulate(hs.parse_scene(scene_text(count=4, extra="solver: {skip_steady_cycles: false}\n")))


@pytest.fixture(scope="module")
def hertz_skipping():
    """hertz_pad as written: the simulator skips the steady cycles."""
    return hs.simulate(hs.parse_scene(HERTZ_PAD))


def synthetic(x, p, q, left, right, scene=HERTZ_PAD):
    """A one-step result dataset of the documented form carrying the given fields."""
    nt = 1
    zeros = np.zeros(nt)
    ds = xr.Dataset(
        {k: ("t", zeros.copy()) for k in ("P", "Q", "M", "sigma", "stick_left", "stick_right", "shift", "dissipation")},
        coords={"t": ("t", zeros.copy(), {"units": "s", "long_name": "time"}), "x": ("x", x, {"units": "m"})},
    )
    ds["contact_left"] = ("t", [left])
    ds["contact_right"] = ("t", [right])
    ds["regime"] = ("t", np.ones(nt, np.int8))
    ds["p"] = (("t", "x"), np.asarray(p, float)[None])
    ds["q"] = (("t", "x"), np.asarray(q, float)[None])
    ds.attrs.update(scene=scene, friction=F)
    return ds


# ---------------------------------------------------------------------------
# the Cauchy integral and the surface stress


def _pv_reference(nodes, q, x):
    """PV int q(xi)/(x - xi) of the piecewise-linear interpolant, by scipy quad (singularity subtracted)."""
    f = lambda s: np.interp(s, nodes, q, left=0.0, right=0.0)  # noqa: E731
    lo, hi = nodes[0], nodes[-1]
    if not lo < x < hi:
        return quad(lambda s: f(s) / (x - s), lo, hi, points=list(nodes[1:-1]), limit=500, epsabs=1e-13)[0]
    qx = f(x)
    regular = quad(lambda s: (f(s) - qx) / (x - s) if s != x else 0.0, lo, hi,
                   points=sorted(set(nodes[1:-1]) | {x}), limit=500, epsabs=1e-13)[0]
    return regular + qx * np.log((x - lo) / (hi - x))


def test_cauchy_matrix_matches_independent_quadrature():
    # Both sides integrate the same piecewise-linear q, one by exact element
    # logs, one by adaptive quadrature with the singularity subtracted: they
    # must agree to quadrature accuracy (1e-9 of the integral's scale),
    # at nodes (where the element logs cancel pairwise) and between them.
    rng = np.random.default_rng(7)
    nodes = np.sort(np.concatenate([[-1.0, 1.0], rng.uniform(-1, 1, 40)]))
    q = rng.normal(size=nodes.size)
    q[0] = q[-1] = 0.0
    x = np.concatenate([nodes[1:-1:5], [-0.3123, 0.5551, 0.9, -1.5, 2.0]])
    got = post.cauchy_matrix(nodes, x) @ q
    want = np.array([_pv_reference(nodes, q, xi) for xi in x])
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-9 * np.abs(want).max())


def _stuck_closed_form(x, Q, a):
    """sigma_xx of the Q part of a bonded contact: 0 inside, -(2Q/pi) sign(x)/sqrt(x^2 - a^2) outside."""
    X = np.abs(x)
    return np.where(X < a, 0.0, -(2 * Q / np.pi) * np.sign(x) / np.sqrt(np.maximum(x * x - a * a, 1e-300)))


def test_stuck_closed_form_itself_by_quadrature():
    # The closed form used below, checked by quadrature of the exact singular
    # traction: xi = a sin(theta) removes the edge singularity; inside the
    # contact the remaining Cauchy pole is handled by QAWC (weight='cauchy').
    Q, a = 3.0e4, A_P
    for x in (-2.1 * a, -1.3 * a, 1.05 * a, 1.7 * a):
        integral = quad(lambda th: Q / np.pi / (x - a * np.sin(th)), -np.pi / 2, np.pi / 2, epsabs=1e-12, limit=200)[0]
        assert -(2 / np.pi) * integral == pytest.approx(_stuck_closed_form(np.array([x]), Q, a)[0], rel=1e-9)
    for x in (-0.7 * a, 0.0, 0.25 * a, 0.9 * a):
        th0 = np.arcsin(x / a)

        def g(th, th0=th0):
            # 1/(x - a sin th) = g(th)/(th - th0): x - a sin th = -2a cos((th + th0)/2) sin((th - th0)/2),
            # written without cancellation; QAWC integrates g/(th - th0)
            return -1.0 / (a * np.cos(0.5 * (th + th0)) * np.sinc(0.5 * (th - th0) / np.pi))

        integral = quad(g, -np.pi / 2, np.pi / 2, weight="cauchy", wvar=th0, epsabs=1e-6, limit=200)[0]
        assert abs(integral * a) < 1e-9  # zero, against an integrand of size 1/a over a range pi


@pytest.mark.parametrize("n", [1600])
def test_surface_stress_of_fully_stuck_hertz_contact(n):
    # Bonded Hertz contact under Q: q = Q/(pi sqrt(a^2 - x^2)) plus the Hertz
    # pressure gives sigma_xx = -p inside and -(2Q/pi) sign(x)/sqrt(x^2 - a^2)
    # outside (tension behind the pad, x < -a). Sampled on stations, the
    # inverse-sqrt edge singularity is not resolved: the error is
    # O(sqrt(h/a)); measured 1.2 % (inside) and 1.5 % (outside) of 2Q/(pi a)
    # at h = a/400, so 2.5 % is the bound; and the order must be ~1/2.
    Q, a = 3.0e4, A_P

    def error(n):
        x = np.linspace(-2 * a, 2 * a, n)  # even n: no station exactly at +-a
        X = np.abs(x)
        p = np.where(X < a, P0 * np.sqrt(np.clip(1 - (x / a) ** 2, 0, None)), 0.0)
        q = np.where(X < a, Q / (np.pi * np.sqrt(np.clip(a * a - x * x, 1e-300, None))), 0.0)
        sigma = post.surface_stress(synthetic(x, p, q, -a, a), edge_nodes=False).values[0]
        exact = -p + _stuck_closed_form(x, Q, a)
        scale = 2 * Q / (np.pi * a)
        away = (X < 0.8 * a) | (X > 1.2 * a)
        assert np.all(sigma[x < -1.2 * a] > 0), "the surface behind the pad must be in tension"
        return np.max(np.abs(sigma - exact)[away]) / scale

    assert error(n) < 0.025
    order = np.log2(error(800) / error(3200)) / 2
    assert 0.4 < order < 0.65


@pytest.fixture(scope="module")
def cattaneo():
    """hertz_pad, one cycle, p and q on 401 stations: at t = 1.25 the Cattaneo state (Q = Qa from 0)."""
    ds = hs.simulate(hs.parse_scene(scene_text(count=1, extra="output: {fields: [p, q], points: 401}\n")))
    return ds.sel(t=[1.25])


def test_surface_stress_of_cattaneo_partial_slip(cattaneo):
    # sigma_xx = -p - (2 f p0/a) sign(x) [sqrt(x^2 - b^2)[|x|>b] - sqrt(x^2 - a^2)[|x|>a]].
    # Away from the edges +-a, +-b (more than 0.05 a) q is smooth: error O(h^2),
    # measured 4.5e-4 p0 at 401 stations -> bound 1e-3 p0. Next to them q and p
    # behave like square roots: O(h^(1/2)), measured 3.3e-2 p0 -> bound 5e-2 p0.
    assert float(cattaneo.Q[0]) == pytest.approx(QA)
    x = cattaneo.x.values
    X = np.abs(x)
    b = A_P * np.sqrt(1 - QA / (F * P))

    def root(c):
        return np.where(X > c, np.sqrt(np.maximum(x * x - c * c, 0.0)), 0.0)

    p = np.where(X < A_P, P0 * np.sqrt(np.clip(1 - (x / A_P) ** 2, 0, None)), 0.0)
    exact = -p - 2 * F * P0 / A_P * np.sign(x) * (root(b) - root(A_P))
    sigma = post.surface_stress(cattaneo).values[0]
    err = np.abs(sigma - exact) / P0
    away = (np.abs(X - A_P) > 0.05 * A_P) & (np.abs(X - b) > 0.05 * A_P)
    assert err[away].max() < 1e-3
    assert err.max() < 5e-2
    # the peak tension sits at the trailing edge, 2 f p0 sqrt(Q/(fP)) in the limit
    top = post.peak(post.surface_stress(cattaneo))
    assert float(top.x) == pytest.approx(-A_P, abs=2 * (x[1] - x[0]))
    assert float(top.value) == pytest.approx(2 * F * P0 * np.sqrt(QA / (F * P)), rel=0.1)
    assert top.value.attrs["units"] == "Pa"


def test_surface_stress_edge_nodes_help_at_the_edge(cattaneo):
    # Adding the contact edges as q = 0 nodes must not be worse anywhere by more than
    # rounding and must improve the station next to the trailing edge.
    x = cattaneo.x.values
    with_edges = post.surface_stress(cattaneo).values[0]
    without = post.surface_stress(cattaneo, edge_nodes=False).values[0]
    b = A_P * np.sqrt(1 - QA / (F * P))
    X = np.abs(x)
    p = np.where(X < A_P, P0 * np.sqrt(np.clip(1 - (x / A_P) ** 2, 0, None)), 0.0)
    root = lambda c: np.where(X > c, np.sqrt(np.maximum(x * x - c * c, 0.0)), 0.0)  # noqa: E731
    exact = -p - 2 * F * P0 / A_P * np.sign(x) * (root(b) - root(A_P))
    k = np.argmin(np.abs(x + A_P))  # the station nearest the trailing edge
    assert abs(with_edges[k] - exact[k]) < 0.7 * abs(without[k] - exact[k])


# ---------------------------------------------------------------------------
# energy


def test_dissipation_per_cycle_equals_loop_work(hertz_full):
    # Constant P, closed Q cycle: the energy dissipated equals the work of Q on
    # the rigid shift, loop integral Q d(shift) (the datum term in the shift is
    # proportional to Q and integrates to zero round a closed loop). The
    # dissipation is the solver's exact energy; the loop integral is a
    # trapezoid over 100 steps per cycle, error O(N^-2): measured 6.8e-4,
    # bound 2e-3.
    energy = post.dissipation_per_cycle(hertz_full)
    loops = post.hysteresis_loops(hertz_full)
    assert energy.sizes["cycle"] == 4 and loops.sizes["cycle"] == 4
    steady = float(energy.dissipation[-1])
    assert steady > 0
    assert float(loops.work[-1]) == pytest.approx(steady, rel=2e-3)
    assert float(loops.work[-1]) != pytest.approx(steady, rel=1e-5)  # it is a trapezoid, not a copy
    # every cycle after the first is the same (Cattaneo-Mindlin shakedown to a steady loop)
    np.testing.assert_allclose(energy.dissipation.values[1:], steady, rtol=1e-9)
    assert float(energy.dissipation[0]) < steady  # the first cycle starts from Q = 0
    assert energy.dissipation.attrs["units"] == "J/m"
    assert energy.dissipation_density.attrs["units"] == "J/m^2"


def test_loop_work_converges_at_second_order():
    # The trapezoid error of the loop integral must fall ~4x per doubling of
    # the steps per cycle (observed order > 1.8), which shows the 100-step
    # bound above is the quadrature and not a mismatch.
    errors = []
    for steps in (50, 100, 200):
        ds = hs.simulate(hs.parse_scene(scene_text(count=2, steps=steps, extra="output: {fields: []}\n")))
        steady = float(post.dissipation_per_cycle(ds).dissipation[-1])
        errors.append(abs(float(post.hysteresis_loops(ds).work[-1]) / steady - 1))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(orders > 1.8), (errors, orders)


def test_pointwise_dissipation_integrates_to_the_total(hertz_full):
    # int (loop q dg) dx over x must give the cycle's energy. Two trapezoids
    # (time, 100 steps; x, 201 stations across edges where the density has a
    # sqrt shape): measured 3.5e-3, bound 1e-2.
    energy = post.dissipation_per_cycle(hertz_full)
    density = energy.dissipation_density.isel(cycle=-1)
    values, x = density.values, hertz_full.x.values
    known = np.isfinite(values)  # NaN: stations out of contact
    assert np.all(known[np.abs(x) < 0.999 * float(hertz_full.contact_right.max())])
    assert np.all(values[known] >= -1e-12 * values[known].max())  # friction dissipates: q dg >= 0
    total = np.trapezoid(np.interp(x, x[known], values[known]), x)
    assert total == pytest.approx(float(energy.dissipation[-1]), rel=1e-2)


# ---------------------------------------------------------------------------
# slip amplitude


def _amplitude_closed_form(x):
    c = A_P * np.sqrt(1 - QA / (F * P))  # a(P - dQ/(2f)), dQ = 2 Qa
    X = np.abs(x)
    out = np.zeros_like(x)
    slip = (X > c) & (X < A_P)
    out[slip] = F / (2 * R) * (X[slip] * np.sqrt(X[slip] ** 2 - c**2) - c**2 * np.arccosh(X[slip] / c))
    return out, c


@pytest.mark.parametrize("which", ["hertz_full", "hertz_skipping"])
def test_slip_amplitude_hertz_pad(which, request):
    # Zero inside the permanent stick zone c = a(P - dQ/(2f)) and positive
    # outside; equal to the closed form delta(x). The exact method's slip is
    # exact to rounding (level integrals in closed form): bound 1e-6 of the peak.
    ds = request.getfixturevalue(which)
    amplitude = post.slip_amplitude(ds)
    assert amplitude.attrs["units"] == "m" and "long_name" in amplitude.attrs
    x = ds.x.values
    want, c = _amplitude_closed_form(x)
    in_contact = np.abs(x) < A_P
    got = amplitude.values
    finite = np.isfinite(got)
    assert np.all(finite[in_contact])
    peak = want.max()
    check = in_contact & finite
    np.testing.assert_allclose(got[check], want[check], rtol=0, atol=1e-6 * peak)
    inside = check & (np.abs(x) < c)
    outside = check & (np.abs(x) > c + (x[1] - x[0]))
    assert np.all(np.abs(got[inside]) <= 1e-12 * peak)
    assert np.all(got[outside] > 0)
    assert float(amplitude.max()) == pytest.approx(want[check].max(), rel=1e-6)
    zone = post.permanent_stick(ds)
    assert float(zone.half_width) == pytest.approx(c, rel=1e-12)
    assert np.isnan(got[~in_contact]).all()  # never in contact: no amplitude


def test_every_station_in_contact_has_a_slip_value(hertz_full):
    in_contact = hertz_full.p.values > 0
    assert np.all(np.isfinite(hertz_full.slip.values[in_contact]))


def test_slip_amplitude_general_solver_agrees_with_exact():
    # The discretised general solver on the same scene: its largest error in the
    # slip amplitude falls at first order or better in 1/nodes (measured 6.9, 3.3,
    # 1.5, 0.55, 0.08 % of the peak at 128 .. 2048 nodes): bound 2 % at 512
    # nodes and the error at least 1.7x smaller than at 256 (measured 2.25x).
    scene = hs.parse_scene(scene_text(count=2, extra="solver: {skip_steady_cycles: false}\n"))
    exact = post.slip_amplitude(hs.simulate(scene, method="exact")).values
    peak = np.nanmax(exact)
    errors = {}
    for nodes in (256, 512):
        general = hs.simulate(scene, method="general", nodes=nodes)
        got = post.slip_amplitude(general).values
        both = np.isfinite(got) & np.isfinite(exact)
        errors[nodes] = np.max(np.abs(got[both] - exact[both])) / peak
    assert errors[512] < 0.02
    assert errors[512] < 0.6 * errors[256]


# ---------------------------------------------------------------------------
# cycles


def test_cycles_of_a_skipping_run_stand_for_the_skipped_ones(hertz_full, hertz_skipping):
    table = post.cycles(hertz_skipping)
    skipped = int(hertz_skipping.attrs["skipped_cycles"])
    assert skipped > 0
    assert table.sizes["cycle"] + skipped == 20
    assert int(table.repeats[-1]) == skipped + 1 and np.all(table.repeats.values[:-1] == 1)
    assert np.all(table.aligned.values == 1)
    # the last stored cycle is the steady one: same energy and same loop as a run marching every cycle
    steady = float(post.dissipation_per_cycle(hertz_full).dissipation[-1])
    assert float(post.dissipation_per_cycle(hertz_skipping).dissipation[-1]) == pytest.approx(steady, rel=1e-9)
    # the energies of all 20 cycles add up to the run's total (its last state: final_dissipation)
    energy = post.dissipation_per_cycle(hertz_skipping)
    total = float((energy.dissipation * energy.repeats).sum())
    assert total == pytest.approx(float(hertz_skipping.final_dissipation - hertz_skipping.dissipation.sel(t=1.0)), rel=1e-12)
    window = post.select_cycle(hertz_skipping)
    assert float(window.t[-1]) == pytest.approx(float(table.t_stop[-1]))  # a marched time, not the segment end
    assert float(hertz_skipping.t[-1]) == float(table.t_stop[-1])  # no stored step stands for the skipped ones


def test_cycles_by_user_period_and_sparse_storage():
    # every = 3 does not divide 40 steps per cycle: cycle ends are not stored,
    # the nearest stored steps stand in (aligned = 0), and the energy per cycle is
    # still within the energy of one stored interval of the exact value.
    text = scene_text(count=4, steps=40, extra="solver: {skip_steady_cycles: false}\noutput: {fields: [], every: 3}\n")
    ds = hs.simulate(hs.parse_scene(text))
    table = post.cycles(ds)
    assert table.sizes["cycle"] == 4
    assert np.any(table.aligned.values == 0)
    dense = hs.simulate(hs.parse_scene(text.replace("every: 3", "every: 1")))
    steady = float(post.dissipation_per_cycle(dense).dissipation[-1])
    per_step = steady / 40 * 3
    assert abs(float(post.dissipation_per_cycle(ds).dissipation[-1]) - steady) < 2 * per_step
    by_period = post.cycles(dense, period=1.0)
    assert by_period.sizes["cycle"] == 5  # counted back from the end: the ramp [0, 1] is a window too
    assert int(by_period.segment[0]) == -1
    np.testing.assert_allclose(by_period.t_stop.values[1:], post.cycles(dense).t_stop.values)


def test_no_cycles_and_bad_requests():
    text = HERTZ_PAD.split("  - cycles:")[0] + "  - ramp: {to: {Q: 1.0e4}, duration: 1.0, steps: 10}\n"
    ds = hs.simulate(hs.parse_scene(text))
    assert post.cycles(ds).sizes["cycle"] == 0
    with pytest.raises(HalfslipInputError, match="no complete stored cycle"):
        post.slip_amplitude(ds)
    whole = post.slip_amplitude(ds, cycle=None)
    assert whole.attrs["cycle"] == "whole run"
    with pytest.raises(HalfslipInputError, match="does not exist"):
        post.slip_amplitude(ds, cycle=5, period=0.5)
    bare = ds.drop_vars(["slip"])
    with pytest.raises(HalfslipInputError, match="did not store") as caught:
        post.slip_amplitude(bare, cycle=None)
    assert "\n" not in str(caught.value)
    with pytest.raises(HalfslipInputError, match="not a halfslip result"):
        post.cycles(xr.Dataset({"a": ("t", [1.0])}))


def test_loop_tangent_point_and_permanent_stick_of_the_motor():
    # Motor: P = P0 + Pa sin, Q = Qa cos (Pa = Qa = 3e4, P0 = 1e5), a circle in the
    # P-Q plane. Lines of gradient +-f touch it at Q +- fP = +-sqrt(Qa^2 + f^2 Pa^2),
    # so P_T = P0 - sqrt(Qa^2 + f^2 Pa^2)/f, Q_T = 0. Sampling 128 points per cycle
    # misses the tangent point by at most R (1 - cos(pi/128)): 3e-4 relative,
    # bound 1e-3. The permanent stick zone of the marched run is a(P_T)
    # (Barber-Davies-Hills), to the same sampling bound.
    ds = hs.simulate(hs.load_scene(EXAMPLES / "motor.yaml"))
    P_T, Q_T = post.loop_tangent_point(ds)
    want = 1.0e5 - np.sqrt(3.0e4**2 + (F * 3.0e4) ** 2) / F
    assert P_T == pytest.approx(want, rel=1e-3)
    assert abs(Q_T) < 1e-3 * want
    zone = post.permanent_stick(ds)
    assert float(zone.half_width) == pytest.approx(A_P * np.sqrt(P_T / 1.0e5), rel=1e-3)
    assert float(zone.left) == pytest.approx(-float(zone.right))


def test_ruiz_is_product_and_peaks_in_the_slip_zone(hertz_full):
    ruiz = post.ruiz(hertz_full)
    amplitude = post.slip_amplitude(hertz_full)
    np.testing.assert_allclose(ruiz.ruiz.values, ruiz.stress_shear.values * np.nan_to_num(amplitude.values))
    c = float(post.permanent_stick(hertz_full).half_width)
    assert c < abs(float(ruiz.x_peak)) < A_P  # where slip and tension meet: the slip zones
    assert float(ruiz.peak) == pytest.approx(float(ruiz.ruiz.max()))
    # fully reversed shear: both edges see the same history, mirrored
    np.testing.assert_allclose(ruiz.ruiz.values, ruiz.ruiz.values[::-1], rtol=1e-6, atol=1e-9 * float(ruiz.peak))
    for name in ("ruiz", "stress_shear", "peak", "x_peak"):
        assert {"units", "long_name"} <= set(ruiz[name].attrs)


def test_accessor_matches_functions(hertz_full):
    ds = hertz_full
    xr.testing.assert_identical(ds.halfslip.slip_amplitude(), post.slip_amplitude(ds))
    xr.testing.assert_identical(ds.halfslip.dissipation_per_cycle(), post.dissipation_per_cycle(ds))
    xr.testing.assert_identical(ds.halfslip.surface_stress(), post.surface_stress(ds))
    xr.testing.assert_identical(ds.halfslip.ruiz(), post.ruiz(ds))
    xr.testing.assert_identical(ds.halfslip.hysteresis_loops(), post.hysteresis_loops(ds))
    xr.testing.assert_identical(ds.halfslip.cycles(), post.cycles(ds))
    loops = ds.halfslip.hysteresis_loops()
    assert loops.Q.dims == ("cycle", "step")
    assert loops["Q"].attrs["units"] == "N/m" and loops["shift"].attrs["units"] == "m"
    # a loop closes: the shift returns to its start at constant P in a steady cycle
    last = loops.isel(cycle=-1)
    shift = last["shift"].values
    assert shift[-1] == pytest.approx(shift[0], abs=1e-9 * np.abs(shift).max())


def test_stress_range_is_the_envelope_of_the_surface_stress_over_the_cycle(hertz_full):
    ds = hertz_full
    envelope = ds.halfslip.stress_range()
    stress = post.surface_stress(post.select_cycle(ds))
    np.testing.assert_array_equal(envelope["max"].values, stress.max("t").values)
    np.testing.assert_array_equal(envelope["range"].values, (stress.max("t") - stress.min("t")).values)
    assert float(envelope.peak_range) == pytest.approx(float(np.max(envelope["range"])))
    # the tension peak's range sits just outside the contact, at the trailing edges
    assert A_P * 0.9 < abs(float(envelope.x_peak_range)) < A_P * 1.1
    for name in envelope.data_vars:
        assert {"units", "long_name"} <= set(envelope[name].attrs)


def test_elastic_compliance_reads_the_stuck_slope():
    # a synthetic closed loop: elastic slope C plus Masing branches that leave each reversal flat,
    # rising: k (Q + Qa)^2 - 2 k Qa^2, falling: 2 k Qa^2 - k (Qa - Q)^2 (continuous at +-Qa);
    # width 4 k Qa^2 = 3 % of the elastic shift, as on hertz_pad
    C, Qa = 3.0e-11, 1.0e4
    k = 0.03 * C * Qa / (4 * Qa**2)
    theta = np.linspace(0.0, 2 * np.pi, 201)
    Q = Qa * np.sin(theta)
    rising = np.cos(theta) >= 0
    hysteresis = np.where(rising, k * (Q + Qa) ** 2 - 2 * k * Qa**2, 2 * k * Qa**2 - k * (Qa - Q) ** 2)
    shift = C * Q + hysteresis
    assert post.elastic_compliance(Q, shift) == pytest.approx(C, rel=2e-3)
    assert abs(np.polyfit(Q, shift, 1)[0] / C - 1) > 5e-3  # a straight fit through the loop would not do
    stuck = np.ones_like(Q, dtype=int)  # full stick throughout: the least-squares slope, exactly
    assert post.elastic_compliance(Q, C * Q + 1e-6, stuck) == pytest.approx(C, rel=1e-9)


def test_accessor_draws_nothing():
    # post computes, halfslip.plot draws: ds.halfslip.plot(...) is gone (README, migration notes)
    assert not hasattr(post.HalfslipAccessor, "plot")


# ---------------------------------------------------------------------------
# files


def test_round_trip_through_hdf5(tmp_path, hertz_skipping):
    import h5py

    path = write_result(hertz_skipping, tmp_path / "run.h5")
    with xr.open_dataset(path) as reopened:
        reopened = reopened.load()
    assert set(reopened.variables) == set(hertz_skipping.variables)
    for name, variable in hertz_skipping.variables.items():
        np.testing.assert_array_equal(reopened[name].values, variable.values, err_msg=name)
        assert reopened[name].attrs.get("units") == variable.attrs.get("units"), name
        assert reopened[name].attrs.get("long_name") == variable.attrs.get("long_name"), name
    for key, value in hertz_skipping.attrs.items():
        np.testing.assert_array_equal(reopened.attrs[key], value, err_msg=key)
    # the derived quantities of the reopened file are those of the run
    xr.testing.assert_identical(post.dissipation_per_cycle(reopened), post.dissipation_per_cycle(hertz_skipping))
    xr.testing.assert_identical(post.slip_amplitude(reopened), post.slip_amplitude(hertz_skipping))
    np.testing.assert_array_equal(read_result(path).slip.values, hertz_skipping.slip.values)
    with h5py.File(path, "r") as h5:
        np.testing.assert_array_equal(h5["Q"][()], hertz_skipping.Q.values)
        assert h5["slip"].shape == hertz_skipping.slip.shape
        assert h5["dissipation"].attrs["units"] in ("J/m", b"J/m")


@pytest.mark.slow
def test_dovetail_last_cycle_agrees_with_the_direct_steady_state():
    # The marched general solver (512 nodes over a 4.2 mm contact: spacing h = 8 um)
    # against (SS1) solved directly (halfslip.steady): the permanent stick edges
    # of the last cycle within 2 h and the energy per cycle within 10 %
    # (measured: 0.7 um and 0.01 %; the first two cycles differ by 12 um and
    # 1.7 %, so the last cycle is used; the margin is for a solver still being
    # written). The peak slip amplitude is not compared: 201 stations
    # undersample it (18 nm here, 47 nm with 1601 stations).
    scene = hs.load_scene(EXAMPLES / "dovetail.yaml")
    ds = hs.simulate(scene)
    steady = hs.steady_state(scene)
    h = float(ds.contact_right[-1] - ds.contact_left[-1]) / scene.solver.nodes
    zone = post.permanent_stick(ds)
    assert float(zone.left) == pytest.approx(float(steady.permanent_stick_left), abs=2 * h)
    assert float(zone.right) == pytest.approx(float(steady.permanent_stick_right), abs=2 * h)
    energy = float(post.dissipation_per_cycle(ds).dissipation[-1])
    assert energy == pytest.approx(float(steady.dissipation_per_cycle), rel=0.1)


def test_permanent_stick_says_which_instants_set_its_ends_and_their_estimates(tmp_path):
    """The ends of the permanent stick zone are stick edges of single instants: permanent_stick gives
    those instants (the largest stick_left, the smallest stick_right of the cycle) and the solver's edge
    error estimate there in metres (error_estimate x contact width), and the run summary says them for
    a general-method run (since 0.3.3; an 8000-node dovetail run put its right end 13 um off at a load
    maximum with an estimate of 13.5 um there, and the summary's line did not say so). The exact
    method's estimates are 0: nothing is added."""
    from halfslip.cli import summarize

    text = (Path(__file__).resolve().parent / "data" / "golden" / "general.yaml").read_text()
    ds = hs.simulate(hs.parse_scene(text))
    zone = post.permanent_stick(ds)
    window = post.select_cycle(ds)
    i, k = int(np.argmax(window.stick_left.values)), int(np.argmin(window.stick_right.values))
    assert float(zone.left) == float(window.stick_left[i]) and float(zone.right) == float(window.stick_right[k])
    assert float(zone.t_left) == float(window.t[i]) and float(zone.t_right) == float(window.t[k])
    for end, j in (("left_error", i), ("right_error", k)):
        width = float(window.contact_right[j] - window.contact_left[j])
        assert float(zone[end]) == pytest.approx(float(window.error_estimate[j]) * width, rel=1e-12)
        assert float(zone[end]) > 0.0
    line = next(line for line in summarize(ds, tmp_path / "x.h5") if "permanent stick zone" in line)
    assert f"ends set at t = {float(zone.t_left):g} / {float(zone.t_right):g} s, edge error estimates" in line
    exact = hs.simulate(hs.load_scene(EXAMPLES / "motor.yaml"))
    assert float(post.permanent_stick(exact).left_error) == 0.0
    line = next(line for line in summarize(exact, tmp_path / "x.h5") if "permanent stick zone" in line)
    assert "estimate" not in line
