"""Derived quantities of a run: cycles, slip amplitude, energy, surface stress.

Every function takes a result dataset of docs/interface.md (from
:func:`halfslip.simulate` or :func:`halfslip.io.read_result`) and returns
DataArrays or Datasets whose variables carry ``units`` and ``long_name``. The
same functions are reachable as an xarray accessor once ``halfslip`` is
imported::

    import halfslip as hs
    ds = hs.simulate(hs.load_scene("examples/hertz_pad.yaml"))
    ds.halfslip.slip_amplitude().max()       # peak slip amplitude of the last cycle [m]
    ds.halfslip.dissipation_per_cycle()      # J/m per cycle, and J/m^2 per point

Cycles
------
A cycle is a time window [t_start, t_stop]. By default the windows are the
periods of the history's ``cycles`` segments (read from the result's segment
table, :mod:`halfslip.cycles`; never from the scene text); a user-given ``period`` cuts the run instead into whole periods
counted back from its last stored step. Windows are mapped onto the stored
steps *by time*, so results stored every n-th step (``output.every``) work; a
window whose ends are not stored steps is taken between the nearest stored
steps and flagged ``aligned = 0``. Only windows that lie wholly inside the
stored time range are listed (an interrupted run loses its unfinished cycle).

Cycles skipped by the simulator (``solver.skip_steady_cycles``: once a cycle
repeats, the run goes on from the segment's end) are never stored steps and
are not listed; the last marched cycle stands for them (``repeats`` = 1 + the
number skipped). The segment table says what was skipped
(``segment_cycles_skipped``, ``segment_skip_t_start``,
``segment_skip_dissipation``); ``final_t`` and ``final_dissipation`` give the
run's last state.

Functions taking ``cycle`` accept an index into that list (negative from the
end, default -1: the last full cycle) or ``None`` for the whole run.

This module computes; :mod:`halfslip.plot` draws (it imports this module,
never the other way round). The helpers the figures need are public here:
:func:`friction`, :func:`timeline`, :func:`loop_integral`,
:func:`elastic_compliance`, :func:`result_kind`.
"""
from __future__ import annotations

import math
import warnings
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
import xarray as xr

from . import cycles as _cycles
from .errors import HalfslipInputError

__all__ = [
    "cauchy_matrix",
    "check_result",
    "cycles",
    "dissipation_per_cycle",
    "elastic_compliance",
    "friction",
    "hysteresis_loops",
    "loop_integral",
    "loop_tangent_point",
    "peak",
    "permanent_stick",
    "result_kind",
    "ruiz",
    "select_cycle",
    "slip_amplitude",
    "stress_range",
    "surface_stress",
    "timeline",
    "Timeline",
]

REQUIRED_VARIABLES = ("P", "Q", "M", "sigma", "contact_left", "contact_right", "stick_left", "stick_right", "regime")
"""Variables every halfslip result carries (besides the coordinate ``t``)."""



def _attrs(units: str, long_name: str, **extra) -> dict:
    return {"units": units, "long_name": long_name, **extra}


# ---------------------------------------------------------------------------
# checks


def check_result(ds: xr.Dataset, needs: Iterable[str] = (), what: str = "this") -> xr.Dataset:
    """Raise :class:`HalfslipInputError` unless `ds` is a halfslip result with `needs`.

    Parameters
    ----------
    ds : xarray.Dataset
        The candidate result.
    needs : iterable of str
        Per-point fields (``p``, ``q``, ``slip``) the caller needs.
    what : str
        Name of the caller's product, for the message.

    Returns
    -------
    xarray.Dataset
        `ds` itself.
    """
    if not isinstance(ds, xr.Dataset):
        raise HalfslipInputError(f"expected a halfslip result dataset, got {type(ds).__name__}")
    missing = [name for name in ("t", *REQUIRED_VARIABLES) if name not in ds.variables]
    if missing or "scene" not in ds.attrs:
        lacking = ", ".join(missing) if missing else "the 'scene' attribute"
        raise HalfslipInputError(f"not a halfslip result (it lacks {lacking})")
    absent = [name for name in needs if name not in ds.data_vars]
    if absent:
        raise HalfslipInputError(
            f"{what} needs the per-point field(s) {', '.join(absent)}, which this run did not store; "
            f"add them to output.fields of the scene and run it again"
        )
    if ds.sizes["t"] < 1:
        raise HalfslipInputError("the result holds no stored steps")
    return ds


def result_kind(ds: xr.Dataset) -> str | None:
    """What kind of halfslip file a dataset is, from its variables and attributes.

    Returns
    -------
    {'run', 'sweep', 'steady'} or None
        ``'run'``: a result of :func:`halfslip.simulate` / ``halfslip run``
        (passes :func:`check_result`); ``'sweep'``: a result of
        :func:`halfslip.sweep` (attribute ``sweep_hash`` and variable
        ``done``); ``'steady'``: a dataset of :func:`halfslip.steady_state` /
        ``halfslip steady -o`` (scalars ``permanent_stick_left``,
        ``permanent_stick_right``, ``regime`` and the attribute ``method``,
        no time axis); None for anything else.
    """
    if not isinstance(ds, xr.Dataset):
        return None
    if "sweep_hash" in ds.attrs and "done" in ds.variables:
        return "sweep"
    steady_names = ("permanent_stick_left", "permanent_stick_right", "regime")
    if (all(name in ds.data_vars for name in steady_names) and "t" not in ds.dims
            and all(ds[name].ndim == 0 for name in steady_names) and "method" in ds.attrs):
        return "steady"
    try:
        check_result(ds)
    except HalfslipInputError:
        return None
    return "run"


def friction(ds: xr.Dataset) -> float:
    """The Coulomb friction coefficient f of a run (attribute ``friction``)."""
    if "friction" not in ds.attrs:
        raise HalfslipInputError("the result lacks its 'friction' attribute")
    return float(ds.attrs["friction"])


# ---------------------------------------------------------------------------
# cycles


@dataclass(frozen=True)
class Timeline:
    """The stored times of a run and the cycles its segment table lists.

    Every stored time is the time of a marched step (halfslip 0.3), so
    ``t_eff`` is ``t``; it stays for code written against 0.2. ``repeats[i]``
    = k + 1 at the last marched step of a segment whose last k cycles were
    skipped as repeats of the cycle ending there, else 1.
    """

    t: np.ndarray
    t_eff: np.ndarray
    repeats: np.ndarray
    windows: list
    spacing: dict  # segment index -> regular gap between stored steps [s]


def timeline(ds: xr.Dataset, strict: bool = True) -> Timeline:
    """The stored times of a run with its cycles and skipped cycles (:class:`Timeline`).

    Read from the result's segment table (:mod:`halfslip.cycles`). Without
    `strict` a result without one gives the plain times (no cycles, no skips).
    """
    t = np.asarray(ds["t"].values, float)
    try:
        segments = _cycles.read_segments(ds)
    except HalfslipInputError:
        if strict:
            raise
        return Timeline(t, t, np.ones(t.size, np.int64), [], {})
    return Timeline(t, t, _cycles.repeats_at(t, segments), _cycles.scene_windows(segments),
                    _cycles.storage_spacing(ds, segments))


def cycles(ds: xr.Dataset, period: float | None = None, start: float | None = None) -> xr.Dataset:
    """The cycles of a run, located among its stored steps.

    Parameters
    ----------
    ds : xarray.Dataset
        A halfslip result.
    period : float, optional
        Cut the run into windows of this length [s] instead of using the
        scene's ``cycles`` segments.
    start : float, optional
        With `period`: time of the first window's start (default: whole
        periods counted back from the last stored step).

    Returns
    -------
    xarray.Dataset
        Dimension ``cycle`` (0, 1, ...; possibly of length 0), one entry per
        cycle whose steps are stored, with variables ``t_start``, ``t_stop``
        [s] (the window), ``i_start``, ``i_stop`` (indices of the stored steps
        bounding it, inclusive), ``segment`` (index of the scene segment, -1
        for a user period), ``aligned`` (1 when both ends are stored steps)
        and ``repeats`` (how many cycles of the scene the entry stands for:
        k + 1 for the last marched cycle of a segment whose last k cycles the
        simulator skipped as repeats of it, else 1).

    Notes
    -----
    A window counts as stored when the stored steps cover it without a gap
    longer than the segment's storage interval (``output.every`` steps, the
    attribute ``output_every``). Cycles skipped by ``solver.skip_steady_cycles``
    are not listed: the entry of the last marched cycle stands for them
    (``repeats``).
    """
    check_result(ds)
    rows = _cycles.stored_windows(ds, period, start)
    columns = list(zip(*rows)) if rows else [[]] * 7
    source = "scene cycles segments" if period is None else f"period {float(period):g} s"
    out = xr.Dataset(
        {
            "t_start": ("cycle", np.asarray(columns[0], float), _attrs("s", "start of the cycle")),
            "t_stop": ("cycle", np.asarray(columns[1], float), _attrs("s", "end of the cycle")),
            "i_start": ("cycle", np.asarray(columns[2], np.int64), _attrs("1", "index of the stored step starting the cycle")),
            "i_stop": ("cycle", np.asarray(columns[3], np.int64), _attrs("1", "index of the stored step ending the cycle")),
            "segment": ("cycle", np.asarray(columns[4], np.int64), _attrs("1", "scene load segment (-1: user period)")),
            "aligned": ("cycle", np.asarray(columns[5], np.int8), _attrs("1", "both ends of the cycle are stored steps")),
            "repeats": ("cycle", np.asarray(columns[6], np.int64), _attrs("1", "cycles of the scene this entry stands for")),
        },
        coords={"cycle": ("cycle", np.arange(len(rows)), _attrs("1", "cycle number"))},
        attrs={"source": source, "skipped_cycles": int(np.sum(timeline(ds, strict=False).repeats - 1))},
    )
    return out


def _cycle_window(ds: xr.Dataset, cycle: int | None, period: float | None) -> tuple[int, int, str]:
    """Indices (inclusive) of the stored steps of `cycle`, and a label."""
    if cycle is None:
        return 0, ds.sizes["t"] - 1, "whole run"
    table = cycles(ds, period=period)
    n = table.sizes["cycle"]
    if n == 0:
        raise HalfslipInputError(
            "this run has no complete stored cycle; give period=... to cut it into cycles, "
            "or cycle=None for the whole run"
        )
    if not -n <= int(cycle) < n:
        raise HalfslipInputError(f"cycle {cycle} does not exist; the run has {n} complete stored cycles")
    row = table.isel(cycle=int(cycle))
    label = f"cycle {int(row.cycle)} (t = {float(row.t_start):g} .. {float(row.t_stop):g} s)"
    if int(row.repeats) > 1:
        label += f", steady: repeated {int(row.repeats) - 1} more times"
    return int(row.i_start), int(row.i_stop), label


def select_cycle(ds: xr.Dataset, cycle: int | None = -1, period: float | None = None) -> xr.Dataset:
    """The stored steps of one cycle (both ends included), as a dataset.

    Parameters
    ----------
    ds : xarray.Dataset
    cycle : int or None
        Index into :func:`cycles` (default -1: the last full cycle); None for
        the whole run.
    period : float, optional
        See :func:`cycles`.

    Returns
    -------
    xarray.Dataset
        The steps of the cycle. Attribute ``selection`` names the cycle.
    """
    check_result(ds)
    i0, i1, label = _cycle_window(ds, cycle, period)
    out = ds.isel(t=slice(i0, i1 + 1))
    out.attrs = {**ds.attrs, "selection": label}
    return out


# ---------------------------------------------------------------------------
# slip and energy


def slip_amplitude(ds: xr.Dataset, cycle: int | None = -1, period: float | None = None) -> xr.DataArray:
    """Slip amplitude of every point over one cycle: (max - min) / 2 of ``slip``.

    Only the instants a point is in contact count (``slip`` is NaN outside);
    a point never in contact during the cycle gets NaN. The peak is
    ``slip_amplitude(ds).max()``, its place :func:`peak`.

    Parameters
    ----------
    ds : xarray.Dataset
        A result with the ``slip`` field.
    cycle : int or None
        See :func:`select_cycle`.
    period : float, optional
        See :func:`cycles`.

    Returns
    -------
    xarray.DataArray, shape (nx,)
        ``slip_amplitude`` [m] along ``x``.
    """
    check_result(ds, ("slip",), "the slip amplitude")
    window = select_cycle(ds, cycle, period)
    slip = window["slip"].values
    with warnings.catch_warnings():  # all-NaN columns (never in contact) give NaN, quietly
        warnings.simplefilter("ignore", RuntimeWarning)
        amplitude = 0.5 * (np.nanmax(slip, axis=0) - np.nanmin(slip, axis=0))
    return xr.DataArray(
        amplitude,
        coords={"x": ds["x"]},
        dims="x",
        name="slip_amplitude",
        attrs=_attrs("m", "slip amplitude, (max - min)/2 over the cycle", cycle=window.attrs["selection"]),
    )


def loop_integral(y: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Trapezoid of y dx along axis 0: sum 0.5 (y_k + y_k+1) (x_k+1 - x_k); NaN increments count 0.

    Parameters
    ----------
    y, x : ndarray, shape (n, ...)
        Values along a path of n stored steps (e.g. q and slip, or Q and shift).

    Returns
    -------
    ndarray, shape (...)
        The line integral of y dx along the path (a loop integral when the
        path closes).
    """
    dx = np.diff(x, axis=0)
    ymid = 0.5 * (y[1:] + y[:-1])
    return np.nansum(np.where(np.isfinite(dx) & np.isfinite(ymid), ymid * dx, 0.0), axis=0)


def dissipation_per_cycle(ds: xr.Dataset, period: float | None = None) -> xr.Dataset:
    """Frictional energy dissipated in each cycle, in total and per point.

    Parameters
    ----------
    ds : xarray.Dataset
        A result; the per-point density needs the fields ``q`` and ``slip``.
    period : float, optional
        See :func:`cycles`.

    Returns
    -------
    xarray.Dataset
        ``dissipation`` (cycle) [J/m]: difference of the cumulative
        ``dissipation`` across the cycle (as exact as the solver's energy).
        ``dissipation_density`` (cycle, x) [J/m^2], when q and slip are
        stored: the loop integral of q dg, by the trapezoid rule over the
        stored steps (error O(1/n^2) for n stored steps per cycle; points
        entering contact contribute from their first stored instant; NaN for
        a loaded station whose slip is NaN throughout the cycle).
        ``t_start``, ``t_stop`` of each cycle.
    """
    check_result(ds, (), "the dissipation per cycle")
    if "dissipation" not in ds.data_vars:
        raise HalfslipInputError("not a halfslip result (it lacks dissipation)")
    table = cycles(ds, period=period)
    D = ds["dissipation"].values
    i0, i1 = table["i_start"].values, table["i_stop"].values
    # every stored step is a marched one: a cycle's energy is the difference across it, also for
    # the last marched cycle that k skipped ones repeat (their energy is segment_skip_dissipation)
    per_cycle = D[i1] - D[i0]
    out = xr.Dataset(
        {
            "dissipation": ("cycle", per_cycle, _attrs("J/m", "frictional energy dissipated in the cycle")),
            "t_start": table["t_start"],
            "t_stop": table["t_stop"],
            "repeats": table["repeats"],
        },
        coords={"cycle": table["cycle"]},
        attrs={"source": table.attrs["source"]},
    )
    if "q" in ds.data_vars and "slip" in ds.data_vars:
        q, g = ds["q"].values, ds["slip"].values
        density = np.array([loop_integral(q[a : b + 1], g[a : b + 1]) for a, b in zip(i0, i1)]).reshape(len(i0), ds.sizes["x"])
        for row, (a, b) in enumerate(zip(i0, i1)):  # loaded stations without any slip value: unknown, not zero
            unknown = np.all(~np.isfinite(g[a : b + 1]), axis=0) & np.any(q[a : b + 1] != 0, axis=0)
            density[row, unknown] = np.nan
        out["dissipation_density"] = xr.DataArray(
            density,
            coords={"cycle": table["cycle"], "x": ds["x"]},
            dims=("cycle", "x"),
            attrs=_attrs("J/m^2", "frictional energy dissipated in the cycle per unit area, loop integral of q dg"),
        )
    return out


def hysteresis_loops(ds: xr.Dataset, period: float | None = None) -> xr.Dataset:
    """The Q - shift loop of every cycle.

    Parameters
    ----------
    ds : xarray.Dataset
    period : float, optional
        See :func:`cycles`.

    Returns
    -------
    xarray.Dataset
        ``Q`` [N/m], ``shift`` [m], ``P`` [N/m] and ``t`` [s] over the
        dimensions (cycle, step); ``step`` counts the stored steps from the
        cycle's start (both ends included, so a loop closes). Cycles with
        fewer stored steps than the longest are padded with NaN.
        ``work`` (cycle) [J/m]: the loop integral of Q d(shift) (trapezoid),
        equal to the dissipation per cycle at constant P, M and sigma (energy
        balance over a closed cycle).
        ``compliance`` (cycle) [m/(N/m)]: the elastic (fully stuck) tangential
        compliance C fitted by :func:`elastic_compliance`, and
        ``shift_slip`` (cycle, step) [m] = shift - C Q: the shift with its
        elastic part removed, which opens the loop (the raw Q - shift loop is
        nearly a straight line). Its loop integral equals ``work``, since the
        loop integral of C Q dQ vanishes on a closed loop.

    Notes
    -----
    The rigid shift is defined up to a term proportional to Q (the datum of the
    logarithmic kernel, attribute ``shift_datum`` of the result), so compare
    loops only of the same run or at constant P, where the datum cancels in
    the loop's area.
    """
    check_result(ds)
    table = cycles(ds, period=period)
    i0, i1 = table["i_start"].values, table["i_stop"].values
    length = int(np.max(i1 - i0) + 1) if len(i0) else 0
    data = {}
    for name in ("Q", "shift", "P", "t"):
        values = ds[_variable(ds, name)].values
        block = np.full((len(i0), length), np.nan)
        for row, (a, b) in enumerate(zip(i0, i1)):
            block[row, : b - a + 1] = values[a : b + 1]
        data[name] = block
    loops = xr.Dataset(
        {name: (("cycle", "step"), block, dict(ds[_variable(ds, name)].attrs)) for name, block in data.items()},
        coords={"cycle": table["cycle"], "step": ("step", np.arange(length), _attrs("1", "stored step within the cycle"))},
        attrs={"source": table.attrs["source"], "shift_datum": ds.attrs.get("shift_datum", np.nan)},
    )
    work = np.array([loop_integral(data["Q"][k], data["shift"][k]) for k in range(len(i0))])
    loops["work"] = ("cycle", work, _attrs("J/m", "loop integral of Q d(shift) over the cycle"))
    regime = ds["regime"].values
    compliance = np.array([
        elastic_compliance(data["Q"][k, : b - a + 1], data["shift"][k, : b - a + 1], regime[a : b + 1])
        for k, (a, b) in enumerate(zip(i0, i1))
    ])
    loops["compliance"] = ("cycle", compliance, _attrs("m/(N/m)", "elastic (fully stuck) tangential compliance C"))
    loops["shift_slip"] = (("cycle", "step"), data["shift"] - compliance[:, None] * data["Q"],
                           _attrs("m", "shift less its elastic part C Q"))
    return loops


def _variable(ds: xr.Dataset, name: str) -> str:
    """The result variable holding `name`: ``shift`` is stored as ``rigid_shift`` since 0.2."""
    return "rigid_shift" if name == "shift" and "rigid_shift" in ds.variables else name


def elastic_compliance(Q: np.ndarray, shift: np.ndarray, regime: np.ndarray | None = None) -> float:
    """The elastic (fully stuck) tangential compliance d(shift)/dQ of a Q - shift loop.

    Fitted, in this order of preference, from

    1. the steps taken in full stick (``regime`` 1, where shift = C Q + const
       exactly): least-squares slope of their increments;
    2. the steps right after each reversal of Q (Mindlin: at a reversal the
       whole contact sticks and the slip zones grow again from the edges, so
       the loop leaves the reversal point with the elastic slope): least
       squares over the steps until Q has moved :data:`REVERSAL_REACH` of its
       range, the median over the reversals; a closed loop is followed round,
       so a reversal at its start counts;
    3. the least-squares slope of the whole loop (no reversal, no stick).

    Parameters
    ----------
    Q, shift : ndarray, shape (n,)
        Shear force [N/m] and rigid shift [m] at the stored steps of a cycle.
    regime : ndarray, shape (n,), optional
        Regime of each step (1 = full stick).

    Returns
    -------
    float
        C [m/(N/m)]; NaN with fewer than two steps in which Q changes.

    Notes
    -----
    With P varying in the cycle the shift also moves with P, and the slope
    read at the reversals includes that; the figure's axis label says what is
    plotted (shift - C Q), not that it is pure slip.
    """
    Q = np.asarray(Q, float)
    shift = np.asarray(shift, float)
    keep = np.isfinite(Q) & np.isfinite(shift)
    if regime is not None:
        regime = np.asarray(regime)[keep]
    Q, shift = Q[keep], shift[keep]
    if Q.size < 2:
        return float("nan")
    dQ, ds_ = np.diff(Q), np.diff(shift)
    scale = float(np.max(np.abs(Q))) or 1.0
    moving = np.abs(dQ) > 1e-9 * scale
    if regime is not None:
        stuck = moving & (regime[1:] == 1)
        if np.count_nonzero(stuck) >= 2:
            return float(np.sum(dQ[stuck] * ds_[stuck]) / np.sum(dQ[stuck] ** 2))
    if not np.any(moving):
        return float("nan")
    closed = abs(Q[-1] - Q[0]) <= 1e-6 * scale
    if closed:  # go round the loop twice so that a reversal at its start has steps after it
        Q, shift = np.concatenate([Q, Q[1:]]), np.concatenate([shift, shift[1:]])
    steps = np.flatnonzero(np.abs(np.diff(Q)) > 1e-9 * scale)
    signs = np.sign(np.diff(Q)[steps])
    starts = [int(steps[k]) for k in range(1, signs.size) if signs[k] != signs[k - 1]]
    if closed:
        starts = [k for k in starts if k < len(Q) // 2 + 1]
    reach = REVERSAL_REACH * float(np.ptp(Q))
    slopes = []
    for r in starts:  # least squares over the steps until Q has moved `reach` from the reversal
        end = r + 1
        while end + 1 < len(Q) and abs(Q[end] - Q[r]) < reach and np.sign(Q[end + 1] - Q[end]) == np.sign(Q[r + 1] - Q[r]):
            end += 1
        dq, dd = Q[r : end + 1] - Q[r], shift[r : end + 1] - shift[r]
        if np.sum(dq**2) > 0:
            slopes.append(float(np.sum(dq * dd) / np.sum(dq**2)))
    if slopes:
        return float(np.median(slopes))
    dQm, dsm = Q - Q.mean(), shift - shift.mean()
    return float(np.sum(dQm * dsm) / np.sum(dQm**2))


REVERSAL_REACH = 0.05
"""How far (fraction of the cycle's range of Q) past a reversal :func:`elastic_compliance` fits the elastic slope.

Far enough to average the shift's step-to-step scatter of the general
solver (about 1 % of a step's increment), near enough that the slip zones
regrowing from the edges add little: on hertz_pad the fitted C is 0.06 %
above the first step's slope (the loop's width is 3 % of the elastic shift).
"""


def permanent_stick(ds: xr.Dataset, cycle: int | None = -1, period: float | None = None) -> xr.Dataset:
    """The permanent stick zone of a cycle: the intersection of its stick zones.

    Each end is the stick edge of one instant of the cycle (for the left end
    the instant whose stick zone starts furthest right), usually a load
    extreme, where the edge can be ill-conditioned; ``t_left`` / ``t_right``
    say which instants, and ``left_error`` / ``right_error`` the stick-edge
    error estimate the solver reported there (``error_estimate`` times the
    contact width; 0 for the exact method, NaN for a result without the
    variable; since 0.3.3).

    Returns
    -------
    xarray.Dataset
        Scalars ``left``, ``right`` [m] (NaN when some instant of the cycle
        has no stick zone, or the intersection is empty), ``half_width``
        [m] = (right - left)/2, ``t_left``, ``t_right`` [s] and
        ``left_error``, ``right_error`` [m] (NaN with the ends).
    """
    check_result(ds)
    window = select_cycle(ds, cycle, period)
    sl, sr = window["stick_left"].values, window["stick_right"].values
    left, right = _cycles.stick_intersection(sl, sr)
    t_ends, errors = [math.nan, math.nan], [math.nan, math.nan]
    if math.isfinite(left):
        width = (window["contact_right"] - window["contact_left"]).values
        estimate = window["error_estimate"].values if "error_estimate" in window else np.full(sl.size, math.nan)
        for k, i in enumerate((int(np.argmax(sl)), int(np.argmin(sr)))):
            t_ends[k] = float(window["t"].values[i])
            errors[k] = float(estimate[i] * width[i])
    return xr.Dataset(
        {
            "left": ((), left, _attrs("m", "left edge of the permanent stick zone")),
            "right": ((), right, _attrs("m", "right edge of the permanent stick zone")),
            "half_width": ((), 0.5 * (right - left), _attrs("m", "half-width of the permanent stick zone")),
            "t_left": ((), t_ends[0], _attrs("s", "instant whose stick zone sets the left edge")),
            "t_right": ((), t_ends[1], _attrs("s", "instant whose stick zone sets the right edge")),
            "left_error": ((), errors[0], _attrs("m", "stick-edge error estimate at t_left")),
            "right_error": ((), errors[1], _attrs("m", "stick-edge error estimate at t_right")),
        },
        attrs={"cycle": window.attrs["selection"]},
    )


def loop_tangent_point(ds: xr.Dataset, cycle: int | None = -1, period: float | None = None) -> tuple[float, float]:
    """Point T where lines of gradient +f and -f touch the cycle's P-Q loop.

    P_T = (min(Q + fP) - max(Q - fP)) / (2 f), Q_T = (min(Q + fP) + max(Q - fP)) / 2
    over the stored steps of the cycle. For a symmetric profile with
    M = sigma = 0 under a steady cycle the permanent stick zone is
    [-a(P_T), a(P_T)] (Barber-Davies-Hills); P_T <= 0 means no point sticks
    throughout the cycle.

    Returns
    -------
    (P_T, Q_T) : tuple of float
        [N/m].
    """
    check_result(ds)
    f = friction(ds)
    window = select_cycle(ds, cycle, period)
    P, Q = window["P"].values, window["Q"].values
    upper = float(np.min(Q + f * P))
    lower = float(np.max(Q - f * P))
    return (upper - lower) / (2.0 * f), 0.5 * (upper + lower)


# ---------------------------------------------------------------------------
# surface stress


def cauchy_matrix(nodes: np.ndarray, x: np.ndarray | None = None) -> np.ndarray:
    """Matrix K with ``K @ q = PV int q(xi) / (x - xi) dxi`` for piecewise-linear q.

    q is linear between the `nodes` (sorted, distinct) and zero outside them;
    each element's integral is taken exactly:

        int_e (alpha + s xi) / (x - xi) dxi = q_e(x) ln|(x - x_j) / (x - x_j+1)| - s h,

    with q_e the element's linear function extended to x. At a node the
    logarithmic singularities of the two adjacent elements cancel (q is
    continuous), which the matrix realises by reading ln 0 as 0 in both. At
    the outermost nodes the integral is finite only if q vanishes there.

    Parameters
    ----------
    nodes : ndarray, shape (n,)
    x : ndarray, shape (m,), optional
        Evaluation points (default: the nodes).

    Returns
    -------
    ndarray, shape (m, n)
    """
    nodes = np.asarray(nodes, float)
    x = nodes if x is None else np.asarray(x, float)
    if nodes.ndim != 1 or nodes.size < 2 or not np.all(np.diff(nodes) > 0):
        raise ValueError("nodes must be 1-D, increasing, at least two")
    xl, xr_ = nodes[:-1], nodes[1:]
    h = xr_ - xl
    d_left = x[:, None] - xl[None, :]
    d_right = x[:, None] - xr_[None, :]
    with np.errstate(divide="ignore"):
        ln_left = np.where(d_left == 0.0, 0.0, np.log(np.abs(np.where(d_left == 0.0, 1.0, d_left))))
        ln_right = np.where(d_right == 0.0, 0.0, np.log(np.abs(np.where(d_right == 0.0, 1.0, d_right))))
    L = ln_left - ln_right
    # coefficient of q_j (left node) and q_j+1 (right node) of each element;
    # (x_j+1 - x) L is written so that the term with a vanishing factor drops exactly
    coef_left = (-d_right * ln_left + d_right * ln_right) / h + 1.0
    coef_right = (d_left * L) / h - 1.0
    K = np.zeros((x.size, nodes.size))
    K[:, :-1] += coef_left
    K[:, 1:] += coef_right
    return K


def surface_stress(ds: xr.Dataset, sigma_B: float | xr.DataArray = 0.0, edge_nodes: bool = True) -> xr.DataArray:
    """Direct stress sigma_xx(x, 0) at the surface of the substrate (physics.md).

        sigma_xx = -p(x) - (2/pi) PV int q(xi) / (x - xi) dxi + sigma_B

    The Cauchy integral is exact for q piecewise linear between the stored
    stations (:func:`cauchy_matrix`). The contact edges ``contact_left`` and
    ``contact_right`` of each instant are added as nodes where q = 0 (Coulomb,
    abs(q) <= f p, with p vanishing at the edge of an incomplete contact), so
    the element that straddles an edge does not smear the traction across it;
    this cuts the error next to the edges (where the tension peaks) several
    times. The stations cover the contact with a margin, so q vanishes at
    both ends. Positive is tension; q > 0 puts the surface behind the pad
    (x < left edge) in tension. The peak tension is
    ``surface_stress(ds).max()``, its place and time :func:`peak`.

    Parameters
    ----------
    ds : xarray.Dataset
        A result with the fields ``p`` and ``q``.
    sigma_B : float or DataArray over t, optional
        Bulk stress of the substrate parallel to the surface [Pa] (0 unless given).
    edge_nodes : bool
        Add the contact edges as nodes with q = 0 (default). Turn off for
        tractions that do not vanish at the edges (a bonded contact, where q
        is singular there; no result of halfslip is of this kind).

    Returns
    -------
    xarray.DataArray, shape (nt, nx)
        ``sigma_xx`` [Pa] at the stored stations.

    Notes
    -----
    Accuracy: where q is smooth the error is O(h^2) (h the station spacing);
    within a few stations of a contact or stick-zone edge, where q and p
    behave like square roots, it is O(h^(1/2)) locally. On the Cattaneo
    solution with 201 stations (hertz_pad) that is 2e-3 p0 away from the
    edges and 5 % of p0 at the station next to the stick-zone edge.
    """
    check_result(ds, ("p", "q"), "the surface stress")
    x = ds["x"].values
    q = ds["q"].values
    edges = np.stack([ds["contact_left"].values, ds["contact_right"].values], axis=1)
    if not edge_nodes:
        edges = np.full_like(edges, np.nan)
    integral = np.empty_like(q)
    matrices: dict = {}
    for i in range(q.shape[0]):
        extra = tuple(
            float(e) for e in edges[i]
            if np.isfinite(e) and x[0] < e < x[-1] and np.min(np.abs(x - e)) > 1e-9 * (x[-1] - x[0])
        )
        if extra not in matrices:
            nodes = np.concatenate([x, extra])
            order = np.argsort(nodes, kind="stable")
            matrices[extra] = (cauchy_matrix(nodes[order], x), order)
        K, order = matrices[extra]
        values = np.concatenate([q[i], np.zeros(len(extra))])[order]
        integral[i] = K @ values
    sigma = -ds["p"].values - (2.0 / np.pi) * integral
    out = xr.DataArray(
        sigma,
        coords={"t": ds["t"], "x": ds["x"]},
        dims=("t", "x"),
        name="sigma_xx",
        attrs=_attrs("Pa", "surface direct stress sigma_xx(x, 0) in the substrate"),
    )
    if isinstance(sigma_B, xr.DataArray) or sigma_B != 0.0:
        out = (out + sigma_B).assign_attrs(out.attrs).rename("sigma_xx")
    return out


def stress_range(ds: xr.Dataset, cycle: int | None = -1, period: float | None = None,
                 sigma_B: float | xr.DataArray = 0.0) -> xr.Dataset:
    """Envelope of the surface direct stress sigma_xx(x, 0) over one cycle.

    Parameters
    ----------
    ds : xarray.Dataset
        A result with the fields ``p`` and ``q``.
    cycle, period
        See :func:`select_cycle` (None: the whole run).
    sigma_B : float or DataArray over t
        Bulk stress of the substrate [Pa] (see :func:`surface_stress`).

    Returns
    -------
    xarray.Dataset
        ``max``, ``min`` and ``range`` = max - min (x) [Pa] over the stored
        steps of the cycle (only steps that are stored count: the envelope of
        a coarsely stored cycle is a lower bound), and scalars
        ``peak_range`` [Pa], ``x_peak_range`` [m].
    """
    check_result(ds, ("p", "q"), "the stress range")
    window = select_cycle(ds, cycle, period)
    stress = surface_stress(window, sigma_B)
    top, bottom = stress.max("t"), stress.min("t")
    spread = (top - bottom).values
    k = int(np.nanargmax(spread)) if np.any(np.isfinite(spread)) else 0
    return xr.Dataset(
        {
            "max": ("x", top.values, _attrs("Pa", "cycle maximum of sigma_xx(x, 0)")),
            "min": ("x", bottom.values, _attrs("Pa", "cycle minimum of sigma_xx(x, 0)")),
            "range": ("x", spread, _attrs("Pa", "range (max - min) of sigma_xx(x, 0) over the cycle")),
            "peak_range": ((), float(spread[k]), _attrs("Pa", "largest range of sigma_xx(x, 0)")),
            "x_peak_range": ((), float(ds["x"].values[k]), _attrs("m", "where the range of sigma_xx(x, 0) peaks")),
        },
        coords={"x": ds["x"]},
        attrs={"cycle": window.attrs["selection"]},
    )


def ruiz(ds: xr.Dataset, cycle: int | None = -1, period: float | None = None, sigma_B: float = 0.0) -> xr.Dataset:
    """Ruiz fretting-fatigue parameter along the surface over one cycle.

        ruiz(x) = max over the cycle of [max(sigma_xx, 0) |q|] * slip amplitude

    (the tensile part of the surface stress only: compression does not open a
    crack; Ruiz, Boddington and Chen 1984), the three-factor form sigma tau
    delta that Nowell and Hills call the fretting fatigue damage parameter.
    The two-factor form tau delta (the frictional work parameter, which
    correlates with where fretting cracks start and with wear) is returned as
    ``shear_slip``.

    Parameters
    ----------
    ds : xarray.Dataset
        A result with the fields ``p``, ``q`` and ``slip``.
    cycle, period
        See :func:`select_cycle`.
    sigma_B : float
        Bulk stress of the substrate [Pa].

    Returns
    -------
    xarray.Dataset
        ``ruiz`` (x) [Pa^2 m], ``stress_shear`` (x) [Pa^2] (the cycle maximum
        of max(sigma_xx, 0) |q|), ``slip_amplitude`` (x) [m], and scalars
        ``peak`` [Pa^2 m], ``x_peak`` [m] (NaN when the parameter is zero everywhere),
        ``shear_slip`` (x) [J/m^2 = Pa m]: the cycle maximum of abs(q) times
        the slip amplitude (two-factor form).
    """
    check_result(ds, ("p", "q", "slip"), "the Ruiz parameter")
    window = select_cycle(ds, cycle, period)
    stress = surface_stress(window, sigma_B).values
    product = np.maximum(stress, 0.0) * np.abs(window["q"].values)
    stress_shear = np.max(product, axis=0)
    amplitude = slip_amplitude(ds, cycle, period)
    value = stress_shear * np.nan_to_num(amplitude.values)
    if np.any(value > 0):
        k = int(np.argmax(value))
        top, where = float(value[k]), float(ds["x"].values[k])
    else:
        top, where = 0.0, float("nan")
    return xr.Dataset(
        {
            "ruiz": ("x", value, _attrs("Pa^2 m", "Ruiz parameter max(sigma_xx q) times slip amplitude")),
            "stress_shear": ("x", stress_shear, _attrs("Pa^2", "cycle maximum of max(sigma_xx, 0) |q|")),
            "slip_amplitude": amplitude,
            "peak": ((), top, _attrs("Pa^2 m", "peak of the Ruiz parameter")),
            "x_peak": ((), where, _attrs("m", "where the Ruiz parameter peaks")),
            "shear_slip": ("x", np.max(np.abs(window["q"].values), axis=0) * np.nan_to_num(amplitude.values),
                           _attrs("J/m^2", "two-factor Ruiz parameter: cycle maximum of abs(q) times slip amplitude")),
        },
        coords={"x": ds["x"]},
        attrs={"cycle": window.attrs["selection"]},
    )


def peak(da: xr.DataArray, kind: str = "max") -> xr.Dataset:
    """The extreme of a DataArray and where (and when) it occurs.

    Parameters
    ----------
    da : xarray.DataArray
    kind : {'max', 'min', 'abs'}

    Returns
    -------
    xarray.Dataset
        ``value`` with the units of `da`, and one scalar per dimension of `da`
        (e.g. ``x``, ``t``) giving the coordinate of the extreme.
    """
    values = da.values
    if kind not in ("max", "min", "abs"):
        raise ValueError("kind must be 'max', 'min' or 'abs'")
    if not np.any(np.isfinite(values)):
        raise HalfslipInputError(f"{da.name or 'the quantity'} has no finite value")
    score = {"max": values, "min": -values, "abs": np.abs(values)}[kind]
    flat = int(np.nanargmax(score))
    index = np.unravel_index(flat, values.shape)
    out = xr.Dataset({"value": ((), float(values[index]), dict(da.attrs))})
    for dim, i in zip(da.dims, index):
        if dim in da.coords:
            coord = da.coords[dim]
            out[dim] = ((), float(coord.values[i]), dict(coord.attrs))
    return out


# ---------------------------------------------------------------------------
# the accessor


@xr.register_dataset_accessor("halfslip")
class HalfslipAccessor:
    """``ds.halfslip.<name>(...)`` for every function of :mod:`halfslip.post`."""

    def __init__(self, ds: xr.Dataset):
        self._ds = ds

    def check(self, needs: Iterable[str] = ()) -> xr.Dataset:
        return check_result(self._ds, needs)

    def cycles(self, period: float | None = None, start: float | None = None) -> xr.Dataset:
        return cycles(self._ds, period, start)

    def select_cycle(self, cycle: int | None = -1, period: float | None = None) -> xr.Dataset:
        return select_cycle(self._ds, cycle, period)

    def slip_amplitude(self, cycle: int | None = -1, period: float | None = None) -> xr.DataArray:
        return slip_amplitude(self._ds, cycle, period)

    def dissipation_per_cycle(self, period: float | None = None) -> xr.Dataset:
        return dissipation_per_cycle(self._ds, period)

    def surface_stress(self, sigma_B: float = 0.0, edge_nodes: bool = True) -> xr.DataArray:
        return surface_stress(self._ds, sigma_B, edge_nodes)

    def ruiz(self, cycle: int | None = -1, period: float | None = None, sigma_B: float = 0.0) -> xr.Dataset:
        return ruiz(self._ds, cycle, period, sigma_B)

    def hysteresis_loops(self, period: float | None = None) -> xr.Dataset:
        return hysteresis_loops(self._ds, period)

    def permanent_stick(self, cycle: int | None = -1, period: float | None = None) -> xr.Dataset:
        return permanent_stick(self._ds, cycle, period)

    def loop_tangent_point(self, cycle: int | None = -1, period: float | None = None) -> tuple[float, float]:
        return loop_tangent_point(self._ds, cycle, period)

    def stress_range(self, cycle: int | None = -1, period: float | None = None, sigma_B: float = 0.0) -> xr.Dataset:
        return stress_range(self._ds, cycle, period, sigma_B)

    def kind(self) -> str | None:
        return result_kind(self._ds)
