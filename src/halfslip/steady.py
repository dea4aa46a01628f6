"""The steady cycle of a periodic load segment, found directly (no marching).

Two exact constructions (physics.md, "Steady state under in-phase cyclic
loading" and "Varying P: ... Barber-Davies-Hills"):

* in phase -- the loads move to and fro along a straight segment between end
  points 1 and 2 in (P, Q, M, sigma): the permanent stick zone [-m, n] solves
  (SS1). Writing Delta q* = -2 f p~ turns (SS1) into the normal problem (N1) for
  the same profile with a *prescribed* rotation alpha~ = alpha0 + A Delta sigma/(8 f)
  and load P~ = P0 - Delta Q/(2 f); Hertz with M = 0 has the closed form (SS2).
* out of phase, M = sigma = 0, symmetric profile (the motor): lines of
  gradient +f and -f touching the loading loop meet at T,
  P_T = (min(Q + f P) - max(Q - f P)) / (2 f); the permanent stick zone is
  [-a(P_T), a(P_T)] (a(P_min) if T lies above the smallest load).

Whether the contact shakes down to full stick (the finite-range form of S1),
stays in partial slip or slides grossly is said in ``regime``.
"""
from __future__ import annotations

import cmath
import dataclasses
import math

import numpy as np
import xarray as xr
from scipy.optimize import brentq

from .errors import HalfslipInputError
from .geometry import Hertz, NormalProblem
from .state import Regime
from . import variables
from .variables import SUMMARY

LOADS = ("P", "Q", "M", "sigma")


def cyclic_segment(scene, index: int | None = None):
    """The ``cycles`` segment to analyse: ``index`` into the history, or the last one."""
    segments = scene.history.segments
    if index is not None:
        cyclic = [i for i, seg in enumerate(segments) if seg.kind == "cycles"]
        if isinstance(index, bool) or not isinstance(index, int) or not 0 <= index < len(segments):
            which = f"the cycles segments are {', '.join(map(str, cyclic))}" if cyclic else "it has no cycles segment"
            raise HalfslipInputError(f"the history has segments 0 .. {len(segments) - 1} and {which}; "
                                     f"got {str(index)[:40]}", field="--segment")
        seg = segments[index]
        if seg.kind != "cycles":
            raise HalfslipInputError(f"segment {index} is a {seg.kind}, not cycles", field=f"loads[{index}]")
        return index, seg
    for i in range(len(segments) - 1, -1, -1):
        if segments[i].kind == "cycles":
            return i, segments[i]
    raise HalfslipInputError("the load history has no cycles segment: there is no steady cycle to find", field="loads")


def in_phase_end_points(harmonics) -> tuple[dict, dict] | None:
    """End points of a straight-segment loop, or None when the loads are out of phase.

    Loads whose phases differ by 0 or 180 degrees move along a straight line.
    The end points are ordered so that Q rises from 1 to 2 (P rises when Q is
    constant).
    """
    moving = {k: h for k, h in harmonics.items() if h.amplitude != 0.0}
    if not moving:
        return None
    ref = next(iter(moving.values())).phase
    signs = {}
    for k, h in moving.items():
        d = math.remainder(h.phase - ref, math.pi)
        if abs(d) > 1e-9:
            return None
        signs[k] = 1.0 if abs(math.remainder(h.phase - ref, 2 * math.pi)) < 1e-9 else -1.0
    one = {k: h.mean - h.amplitude * signs.get(k, 0.0) for k, h in harmonics.items()}
    two = {k: h.mean + h.amplitude * signs.get(k, 0.0) for k, h in harmonics.items()}
    if (two["Q"] - one["Q"], two["P"] - one["P"]) < (0.0, 0.0):
        one, two = two, one
    return one, two


def motor_stick_level(harmonics, friction: float) -> float:
    """P_T of the point T for a harmonic P-Q loop (closed form).

    Q -/+ f P is harmonic; its extremes are mean -/+ f P_mean +/- the modulus of
    the complex amplitude Q_a e^{i phi_Q} -/+ f P_a e^{i phi_P}.
    """
    hp, hq = harmonics["P"], harmonics["Q"]
    zP = hp.amplitude * cmath.exp(1j * hp.phase)
    zQ = hq.amplitude * cmath.exp(1j * hq.phase)
    c_plus = hq.mean - friction * hp.mean + abs(zQ - friction * zP)  # max (Q - f P)
    c_minus = hq.mean + friction * hp.mean - abs(zQ + friction * zP)  # min (Q + f P)
    return (c_minus - c_plus) / (2.0 * friction)


def contact_with_rotation(problem: NormalProblem, load: float, rotation: float):
    """Contact of ``problem``'s profile under load ``load`` with a prescribed rotation.

    Solves for the moment that produces ``rotation`` (N1-N2 with alpha given),
    by bracketing and Brent's method on NormalProblem.solve(load, M).rotation.
    Returns the NormalSolution.
    """
    if isinstance(problem.profile, Hertz):  # centred Hertz contact at x0 = -alpha R
        return problem.solve(load, -rotation * problem.profile.radius * load)

    def residual(M):
        return problem.solve(load, M).rotation - rotation

    sol0 = problem.solve(load, 0.0)
    scale = load * max(sol0.half_width, 1e-300) * 0.05
    r0 = residual(0.0)
    if r0 == 0.0:
        return sol0
    # the rotation falls as the moment grows: step the moment against the residual
    step = scale if r0 > 0 else -scale
    lo, hi = 0.0, step
    for _ in range(60):
        try:
            r_hi = residual(hi)
        except ValueError:
            break
        if np.sign(r_hi) != np.sign(r0):
            M = brentq(residual, min(lo, hi), max(lo, hi), xtol=1e-14 * scale, rtol=1e-14)
            return problem.solve(load, M)
        lo, hi = hi, hi * 1.6
    raise ValueError("no contact under this load carries the prescribed rotation (the stick zone would leave the profile)")


def steady_state(scene, segment: int | None = None, *, per_cycle: bool = True) -> xr.Dataset:
    """Permanent stick zone and steady-cycle quantities of a periodic segment.

    Parameters
    ----------
    scene : Scene
    segment : int, optional
        Index of the cycles segment (default: the last one).
    per_cycle : bool
        Also march two cycles to report the slip amplitude and the energy
        dissipated per cycle in the steady cycle.

    Returns
    -------
    xarray.Dataset
        Scalars ``permanent_stick_left``, ``permanent_stick_right`` [m] (NaN when
        nothing sticks permanently), ``regime`` (1 full stick after shakedown, 2
        partial slip, 3 gross sliding), and with ``per_cycle`` ``dissipation_per_cycle``
        [J/m] and ``peak_slip_amplitude`` [m]; attributes ``method`` and ``note``.
    """
    index, seg = cyclic_segment(scene, segment)
    h = seg.harmonics
    f = scene.friction
    problem = NormalProblem(scene.profile, scene.material.compliance)
    A = scene.material.compliance
    P = scene.history.P[seg.start + 1 : seg.stop + 1]
    Q = scene.history.Q[seg.start + 1 : seg.stop + 1]
    attrs = {"segment": index}
    with np.errstate(divide="ignore", invalid="ignore"):
        shear_ratio = float(np.max(np.where(P > 0, np.abs(Q) / (f * P), np.inf)))
    ends = in_phase_end_points(h)
    if shear_ratio >= 1.0:
        left = right = math.nan
        regime = Regime.GROSS_SLIDING
        method = "gross sliding check"
        note = f"max abs(Q)/(f P) = {shear_ratio:.4g} >= 1: the contact slides grossly every cycle"
    elif ends is not None:
        left, right, regime, method, note, extra = _in_phase(problem, A, f, *ends)
        attrs.update(extra)
    elif all(h[k].amplitude == 0.0 and h[k].mean == 0.0 for k in ("M", "sigma")) and scene.profile.symmetric:
        P_T = motor_stick_level(h, f)
        P_min = h["P"].mean - h["P"].amplitude
        attrs["P_T"] = P_T
        method = "Barber-Davies-Hills tangents (point T)"
        if P_T <= 0.0:
            left = right = math.nan
            regime = Regime.PARTIAL_SLIP
            note = "the tangents of gradient +-f meet at P_T <= 0: no point sticks permanently"
        else:
            b = float(problem.half_width(min(P_T, P_min)))
            left, right = -b, b
            regime = Regime.PARTIAL_SLIP
            note = f"permanent stick zone a(P_T), P_T = {P_T:.6g} N/m"
            if P_T >= P_min:
                note = "T lies above the smallest load: the whole contact at the smallest load sticks permanently"
    else:
        raise HalfslipInputError(
            "no direct steady state for loads out of phase with a moment or bulk tension; march the scene "
            "(halfslip run) and read the permanent stick zone from the last cycle",
            field=f"loads[{index}]",
        )
    note, _, warning = note.partition("; warning: ")  # a warning is its own attribute (stderr on the command line)
    if warning:
        attrs = {**attrs, "warning": warning}
    ds = xr.Dataset(
        {
            "permanent_stick_left": ((), left, variables.attrs("permanent_stick_left", SUMMARY)),
            "permanent_stick_right": ((), right, variables.attrs("permanent_stick_right", SUMMARY)),
            "regime": ((), np.int8(regime), variables.attrs("regime", SUMMARY, flag_values=Regime.flag_values(),
                                                  flag_meanings=Regime.flag_meanings())),
        },
        attrs={"halfslip_version": _version(), "method": method, "note": note, "scene_name": scene.name,
               "max_shear_ratio": shear_ratio, **attrs},
    )
    if per_cycle:
        ds = ds.merge(_per_cycle_quantities(scene, index, seg))
    return ds


def _in_phase(problem, A, f, one, two):
    """Straight-segment loop between end points one -> two (Q rising)."""
    dQ = two["Q"] - one["Q"]
    dP = two["P"] - one["P"]
    dM = two["M"] - one["M"]
    dsig = two["sigma"] - one["sigma"]
    P0 = 0.5 * (one["P"] + two["P"])
    s1 = problem.solve(one["P"], one["M"])
    s2 = problem.solve(two["P"], two["M"])
    extra = {"end_points": str({"one": one, "two": two})}
    # finite-range S1 on the smaller contact: shakedown to full stick?
    small = s1 if s1.half_width <= s2.half_width else s2
    sign = 1.0 if small is s1 else -1.0  # orient so that the small contact is the start
    d, x0 = small.half_width, small.center
    dM0 = dM - x0 * dP
    stuck = all(
        abs(sign * (dQ - e * math.pi / 4 * d * dsig)) < f * sign * (dP - e * 2 * dM0 / d)
        for e in (1.0, -1.0)
    ) if dP != 0.0 else False
    if stuck:
        return small.left, small.right, Regime.STICK, "finite-range no-slip test (S1)", (
            "the load range passes the no-slip test at both edges: the contact shakes down to full stick"), extra
    load = P0 - dQ / (2 * f)
    if load <= 0.0:
        return math.nan, math.nan, Regime.PARTIAL_SLIP, "SS1", (
            "Delta Q >= 2 f P0: the slip zones meet, nothing sticks permanently"), extra
    alpha = 0.5 * (s1.rotation + s2.rotation) + A * dsig / (8 * f)
    sol = contact_with_rotation(problem, load, alpha)
    method = "SS2 closed form" if isinstance(problem.profile, Hertz) and dM == 0 and one["M"] == 0 else "SS1"
    note = (f"permanent stick zone from (SS1): load P0 - dQ/(2f) = {load:.6g} N/m, "
            f"rotation alpha0 + A dsigma/(8f) = {alpha:.6g}")
    if abs(math.pi / 4 * d * dsig) >= abs(dQ):
        note += f"; warning: {TENSION_WARNING}"
    left = max(sol.left, s1.left, s2.left)
    right = min(sol.right, s1.right, s2.right)
    return left, right, Regime.PARTIAL_SLIP, method, note, extra


def _per_cycle_quantities(scene, index, seg) -> xr.Dataset:
    """March the history up to two cycles of the segment; measure the second cycle.

    The short history keeps the segments before ``index`` and the first two
    cycles of the segment itself, so the run's segment table lists its cycles
    and :mod:`halfslip.post` measures the last one, as for any run.
    """
    from . import post
    from .histories import LoadHistory
    from .simulator import simulate

    count = min(2, int(seg.count))
    stop = seg.start + count * seg.steps_per_cycle
    h = scene.history
    sl = slice(0, stop + 1)
    cycles = dataclasses.replace(seg, stop=stop, t_stop=float(h.t[stop]), count=count)
    history = LoadHistory(h.t[sl], {name: values[sl] for name, values in h.loads().items()},
                          (*h.segments[:index], cycles))
    short = dataclasses.replace(
        scene, history=history, output=dataclasses.replace(scene.output, fields=("slip",), every=1),
        solver=dataclasses.replace(scene.solver, skip_steady_cycles=False),
    )
    ds = simulate(short)
    amplitude = post.slip_amplitude(ds)
    dissipated = float(post.dissipation_per_cycle(ds)["dissipation"][-1])
    return xr.Dataset(
        {
            "dissipation_per_cycle": ((), dissipated, variables.attrs("dissipation_per_cycle", SUMMARY)),
            "peak_slip_amplitude": ((), float(amplitude.max()), variables.attrs("peak_slip_amplitude", SUMMARY)),
            "slip_amplitude": (("x",), amplitude.values, variables.attrs("slip_amplitude", SUMMARY)),
        },
        coords={"x": ("x", ds.x.values, variables.attrs("x"))},
    )


TENSION_WARNING = "the tension range is not moderate (slip may reverse at one end) -- SS1 assumes it is"
"""The attribute ``warning`` of a steady state whose tension range SS1 does not cover."""


def _version() -> str:
    from ._version import __version__

    return __version__
