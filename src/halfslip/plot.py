"""Pictures of a run: loading path, stick-slip map, tractions, slip and energy.

Each ``kind`` function takes a result dataset and returns a
:class:`matplotlib.figure.Figure` drawn on the Agg canvas; nothing touches
pyplot, so no global figure state is created or leaked (a figure is freed
when it is no longer referenced). :func:`plot_run` writes files::

    import halfslip as hs
    from halfslip.plot import plot_run
    ds = hs.simulate(hs.load_scene("examples/hertz_pad.yaml"))
    plot_run(ds, "figures/")          # figures/hertz-pad-trajectory.png, ...

Kinds and what they need:

``trajectory``  loads only: the path in the P-Q plane coloured by regime.
``map``         zone extents only: contact and stick zone against time.
``tractions``   fields p and q: q(x) and the Coulomb bounds +-f p(x).
``slip``        field slip (and q for the energy panel): slip amplitude and
                energy dissipated per cycle along x.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import xarray as xr
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from . import post
from .errors import HalfslipInputError

KINDS = ("trajectory", "map", "tractions", "slip")
"""Figure kinds, in the order :func:`plot_run` writes them."""

NEEDS = {"trajectory": (), "map": (), "tractions": ("p", "q"), "slip": ("slip",)}
"""Per-point fields each kind needs."""

REGIME_COLOURS = {0: "#b0b0b0", 1: "#1f77b4", 2: "#ff7f0e", 3: "#d62728"}
"""Colour of each regime: separated, stick, partial slip, gross sliding."""

REGIME_NAMES = {0: "separated", 1: "full stick", 2: "partial slip", 3: "gross sliding"}

STICK_COLOUR = "#9ecae1"
SLIP_COLOUR = "#fdae6b"
OUT_COLOUR = "#f0f0f0"

DPI = 150
_LABEL_BOX = {"boxstyle": "round,pad=0.2", "facecolor": "white", "edgecolor": "none", "alpha": 0.85}
SIZE = (7.5, 5.0)  # inches: 1125 x 750 px at DPI


# ---------------------------------------------------------------------------
# helpers


def _figure(size=SIZE) -> Figure:
    fig = Figure(figsize=size, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


_PREFIXES = ((1e9, "G"), (1e6, "M"), (1e3, "k"), (1.0, ""), (1e-3, "m"), (1e-6, "µ"), (1e-9, "n"), (1e-12, "p"))


def _scale(values, unit: str) -> tuple[float, str]:
    """Factor and unit label so that the largest magnitude reads 1 .. 1000 (SI prefixes)."""
    values = np.asarray(values, float)
    finite = np.abs(values[np.isfinite(values)])
    top = float(finite.max()) if finite.size else 0.0
    if top == 0.0:
        return 1.0, unit
    for factor, prefix in _PREFIXES:
        if top >= factor:
            break
    if unit.startswith("N/") or unit == "N":  # kN/m, not mN/m; forces read in N or kN
        factor, prefix = (1e3, "k") if top >= 1e3 else (1.0, "")
    if unit == "J/m^2" or unit == "J/m":
        return factor, f"{prefix}{unit.replace('^2', '²')}"
    return factor, f"{prefix}{unit}"


def _title(ds: xr.Dataset, what: str) -> str:
    name = ds.attrs.get("scene_name") or "halfslip run"
    return f"{name}: {what}"


def _cycle_table(ds: xr.Dataset) -> xr.Dataset:
    try:
        return post.cycles(ds)
    except HalfslipInputError:  # the stored scene cannot be read: treat as acyclic
        return _empty_cycles()


def _empty_cycles() -> xr.Dataset:
    return xr.Dataset({"t_start": ("cycle", np.zeros(0)), "t_stop": ("cycle", np.zeros(0))}, coords={"cycle": np.arange(0)})


def _nearest_steps(ds: xr.Dataset, times) -> list[int]:
    t = ds["t"].values
    indices = []
    for time in times:
        time = float(time)
        span = t[-1] - t[0]
        if not (t[0] - 1e-9 * span <= time <= t[-1] + 1e-9 * span):
            raise HalfslipInputError(f"time {time:g} s lies outside the run (t = {t[0]:g} .. {t[-1]:g} s)", field="--at")
        indices.append(int(np.argmin(np.abs(t - time))))
    return indices


def _default_instants(ds: xr.Dataset) -> list[int]:
    """Four instants: quarters of the last cycle, else quarters of the run."""
    table = _cycle_table(ds)
    t = ds["t"].values
    if table.sizes["cycle"]:
        t0, t1 = float(table["t_start"][-1]), float(table["t_stop"][-1])
        times = t0 + (t1 - t0) * np.array([0.0, 0.25, 0.5, 0.75])
    else:
        times = t[0] + (t[-1] - t[0]) * np.array([0.25, 0.5, 0.75, 1.0])
    return list(dict.fromkeys(_nearest_steps(ds, times)))


def _segments_by_regime(x: np.ndarray, y: np.ndarray, regime: np.ndarray):
    """Line segments (k-1 -> k) grouped by the regime of step k."""
    points = np.stack([x, y], axis=1)
    segments = np.stack([points[:-1], points[1:]], axis=1)
    return segments, regime[1:]


# ---------------------------------------------------------------------------
# kinds


def trajectory(ds: xr.Dataset) -> Figure:
    """The loading path in the P-Q plane, coloured by regime, with the lines Q = +-f P.

    For cyclic runs with M = sigma = 0 the point T where lines of gradient +f
    and -f touch the last cycle's loop is marked (:func:`halfslip.post.loop_tangent_point`);
    the permanent stick zone is [-a(P_T), a(P_T)].
    """
    post.check_result(ds)
    f = post._friction(ds)
    P, Q, regime = ds["P"].values, ds["Q"].values, ds["regime"].values.astype(int)
    kP, uP = _scale(np.concatenate([P, Q]), "N/m")
    fig = _figure()
    ax = fig.add_subplot()
    segments, seg_regime = _segments_by_regime(P / kP, Q / kP, regime)
    colours = [REGIME_COLOURS.get(int(r), "k") for r in seg_regime]
    ax.add_collection(LineCollection(segments, colors=colours, linewidths=1.6))
    ax.plot(P[-1] / kP, Q[-1] / kP, "o", ms=5, color="k", zorder=5)
    P_max = float(np.nanmax(P)) if P.size else 1.0
    P_line = np.array([0.0, 1.08 * max(P_max, 1e-30)])
    ax.plot(P_line / kP, f * P_line / kP, color="0.3", lw=1.0, ls="-")
    ax.plot(P_line / kP, -f * P_line / kP, color="0.3", lw=1.0, ls="-")
    ax.annotate(f"Q = +fP (f = {f:g})", (P_line[1] / kP, f * P_line[1] / kP), xytext=(-4, -4),
                textcoords="offset points", ha="right", va="top", fontsize=8, color="0.3", bbox=_LABEL_BOX)
    ax.annotate("Q = −fP", (P_line[1] / kP, -f * P_line[1] / kP), xytext=(-4, 4),
                textcoords="offset points", ha="right", va="bottom", fontsize=8, color="0.3", bbox=_LABEL_BOX)
    handles = [Line2D([], [], color=REGIME_COLOURS[r], lw=2, label=REGIME_NAMES[r]) for r in sorted(set(seg_regime.tolist()))]
    handles.append(Line2D([], [], marker="o", ls="", color="k", label="end of run"))
    table = _cycle_table(ds)
    no_moment = not np.any(ds["M"].values) and not np.any(ds["sigma"].values)
    if table.sizes["cycle"] and no_moment:
        P_T, Q_T = post.loop_tangent_point(ds)
        window = post.select_cycle(ds)
        reach = max(float(np.max(window["P"].values)) - P_T, 0.05 * P_max)
        dP = np.array([-0.15 * reach, 1.15 * reach])
        for sign in (1.0, -1.0):
            ax.plot((P_T + dP) / kP, (Q_T + sign * f * dP) / kP, color="k", lw=0.9, ls="--")
        if P_T > 0:
            ax.plot(P_T / kP, Q_T / kP, marker="D", ms=7, color="k", zorder=6)
            ax.annotate(
                f"T ({P_T / kP:.4g}, {Q_T / kP:.4g}) {uP}\npermanent stick zone ±a(P_T)",
                (P_T / kP, Q_T / kP), xytext=(0, -14), textcoords="offset points", fontsize=8, va="top", ha="center",
                bbox=_LABEL_BOX,
            )
            handles.append(Line2D([], [], marker="D", ls="--", color="k", label="T: lines of gradient ±f touch the last cycle"))
        else:
            handles.append(Line2D([], [], ls="--", color="k", label="lines of gradient ±f: no permanent stick (P_T ≤ 0)"))
    ax.set_xlim(0.0, P_line[1] / kP)
    Q_abs = float(np.nanmax(np.abs(Q))) if Q.size else 0.0
    Q_lim = 1.1 * max(f * P_line[1], Q_abs, 1e-30)  # the whole friction cone: how far from sliding
    ax.set_ylim(-Q_lim / kP, Q_lim / kP)
    ax.axhline(0.0, color="0.8", lw=0.6, zorder=0)
    ax.set_xlabel(f"normal load P [{uP}]")
    ax.set_ylabel(f"shear force Q [{uP}]")
    ax.set_title(_title(ds, "loading path, coloured by regime"))
    ax.legend(handles=handles, loc="upper left", fontsize=8, framealpha=0.9)
    ax.grid(True, lw=0.3, alpha=0.5)
    return fig


def _draw_map(ax, ds: xr.Dataset, kx: float) -> None:
    t = ds["t"].values
    cl, cr = ds["contact_left"].values / kx, ds["contact_right"].values / kx
    sl, sr = ds["stick_left"].values / kx, ds["stick_right"].values / kx
    contact = np.isfinite(cl) & np.isfinite(cr)
    stick = contact & np.isfinite(sl) & np.isfinite(sr)
    ax.set_facecolor(OUT_COLOUR)
    # the state stored at t_k holds over the step (t_k-1, t_k]: step="pre"
    ax.fill_between(t, np.where(contact, cl, 0), np.where(contact, cr, 0), where=contact, step="pre", color=SLIP_COLOUR, lw=0)
    ax.fill_between(t, np.where(stick, sl, 0), np.where(stick, sr, 0), where=stick, step="pre", color=STICK_COLOUR, lw=0)
    ax.step(t, cl, where="pre", color="k", lw=0.7)
    ax.step(t, cr, where="pre", color="k", lw=0.7)
    ax.step(t, sl, where="pre", color="#08519c", lw=0.5)
    ax.step(t, sr, where="pre", color="#08519c", lw=0.5)


THIN_SLIP = 0.04
"""Slip bands narrower than this fraction of the contact get a zoom on each edge in the map."""


def stick_slip_map(ds: xr.Dataset) -> Figure:
    """Contact and stick-zone edges against time: the stick-slip map.

    Stick zone blue, slip zones orange, out of contact grey. For cyclic runs a
    second panel zooms on the last two stored cycles and marks the permanent
    stick zone of the last cycle (dashed); when the slip zones there are thin
    (less than 4 % of the contact width, e.g. a wide flat punch) the zoom is
    split into one panel per contact edge, each scaled to its slip band.
    """
    post.check_result(ds)
    edges = np.concatenate([ds[k].values for k in ("contact_left", "contact_right")])
    kx, ux = _scale(edges, "m")
    lim = np.nanmax(np.abs(edges)) / kx if np.any(np.isfinite(edges)) else 1.0
    table = _cycle_table(ds)
    cyclic = table.sizes["cycle"] > 0
    line = post._timeline(ds, strict=False)
    bands = None
    if cyclic:
        k0 = max(0, table.sizes["cycle"] - 2)
        t0, t1 = float(table["t_start"][k0]), float(table["t_stop"][-1])
        i0, i1 = int(table["i_start"][k0]), int(table["i_stop"][-1])
        window = ds.isel(t=slice(i0, i1 + 1)).assign_coords(t=("t", line.t_eff[i0 : i1 + 1]))
        bands = _slip_bands(window)
    panels = 1 + (0 if not cyclic else 2 if bands is not None else 1)
    fig = _figure((SIZE[0], 6.2 if panels == 2 else 7.6) if cyclic else SIZE)
    axes = list(fig.subplots(panels, 1, height_ratios=[1.0] + [0.8] * (panels - 1))) if panels > 1 else [fig.add_subplot()]
    _draw_map(axes[0], ds, kx)
    axes[0].set_title(_title(ds, "stick-slip map"))
    axes[0].set_ylim(-1.1 * lim, 1.1 * lim)
    span = float(ds["t"][-1] - ds["t"][0]) or 1.0
    for i in np.flatnonzero(line.repeats > 1):  # cycles the simulator skipped as repeats
        axes[0].axvspan(line.t_eff[i], line.t[i], facecolor="white", edgecolor="0.5", hatch="///", lw=0.0, zorder=3)
        narrow = (line.t[i] - line.t_eff[i]) < 0.3 * span
        axes[0].text(0.5 * (line.t_eff[i] + line.t[i]), 0.0, f"{line.repeats[i] - 1} cycles skipped:\nrepeats of the steady cycle",
                     ha="center", va="center", fontsize=7 if narrow else 8, rotation=90 if narrow else 0,
                     zorder=4, bbox=_LABEL_BOX)
    if cyclic:
        axes[0].axvspan(t0, t1, facecolor="none", edgecolor="k", lw=0.8, ls=":", zorder=5)
        zone = post.permanent_stick(ds)
        left, right = float(zone["left"]), float(zone["right"])
        tl0 = float(table["t_start"][-1])
        more = int(table["repeats"][-1]) - 1
        title = (f"last {table.sizes['cycle'] - k0} stored cycle(s), t = {t0:g} .. {t1:g} s"
                 + (f" (the last repeats {more} more times)" if more else ""))
        zooms = axes[1:]
        limits = [(-1.1 * lim, 1.1 * lim)] if bands is None else [
            tuple(np.array(band) / kx) for band in (bands[1], bands[0])]  # right edge on top
        for n, (ax, (low, high)) in enumerate(zip(zooms, limits)):
            _draw_map(ax, window, kx)
            ax.set_xlim(t0, t1)
            ax.set_ylim(low, high)
            if np.isfinite(left):
                for edge in (left, right):
                    ax.hlines(edge / kx, tl0, t1, colors="k", linestyles="--", lw=1.0)
                label_at = right if bands is None or n == 0 else left
                ax.annotate(
                    f"permanent stick zone [{left / kx:.4g}, {right / kx:.4g}] {ux}",
                    (0.5 * (tl0 + t1), label_at / kx), xytext=(0, -4 if label_at == right else 4),
                    textcoords="offset points", fontsize=8, ha="center",
                    va="top" if label_at == right else "bottom", bbox=_LABEL_BOX,
                )
        if bands is None:
            zooms[0].set_title(title, fontsize=10)
        else:
            zooms[0].set_title(title + "\nslip zones are thin: zoom on the right edge (top) and the left edge (bottom)",
                               fontsize=9)
    for ax in axes:
        ax.set_ylabel(f"x [{ux}]")
    axes[-1].set_xlabel("time t [s]")
    axes[0].set_xlim(float(ds["t"][0]), float(ds["t"][-1]))
    fig.legend(
        handles=[Patch(color=STICK_COLOUR, label="stick"), Patch(color=SLIP_COLOUR, label="slip"),
                 Patch(facecolor=OUT_COLOUR, edgecolor="0.6", label="out of contact")]
        + ([Line2D([], [], color="k", ls="--", label="permanent stick zone of the last cycle")] if cyclic else []),
        loc="outside lower center", fontsize=8, ncols=4, frameon=False,
    )
    return fig


def _slip_bands(window: xr.Dataset):
    """((low, high) of the left slip band, (low, high) of the right one) with margins, or None if not thin."""
    cl, cr = window["contact_left"].values, window["contact_right"].values
    sl, sr = window["stick_left"].values, window["stick_right"].values
    if not (np.all(np.isfinite(cl)) and np.all(np.isfinite(cr)) and np.all(np.isfinite(sl)) and np.all(np.isfinite(sr))):
        return None
    width = float(np.max(cr) - np.min(cl))
    left = (float(np.min(cl)), float(np.max(np.maximum(sl, cl))))
    right = (float(np.min(np.minimum(sr, cr))), float(np.max(cr)))
    band = max(left[1] - left[0], right[1] - right[0])
    if width <= 0 or band >= THIN_SLIP * width:
        return None
    margin = max(0.3 * band, 0.002 * width)
    return (left[0] - margin, left[1] + margin), (right[0] - margin, right[1] + margin)


def tractions(ds: xr.Dataset, at=None) -> Figure:
    """Shear traction q(x) and the Coulomb bounds +-f p(x) at chosen instants.

    Parameters
    ----------
    ds : xarray.Dataset
        A result with the fields p and q.
    at : sequence of float, optional
        Times [s]; the nearest stored steps are drawn. Default: the start and
        the quarters of the last cycle (of the run, when it has no cycles).
    """
    post.check_result(ds, NEEDS["tractions"], "the tractions figure")
    f = post._friction(ds)
    steps = _default_instants(ds) if not at else _nearest_steps(ds, at)
    x = ds["x"].values
    kx, ux = _scale(x, "m")
    p, q = ds["p"].values[steps], ds["q"].values[steps]
    kq, uq = _scale(np.concatenate([f * p.ravel(), q.ravel()]), "Pa")
    fig = _figure()
    ax = fig.add_subplot()
    import matplotlib

    cmap = matplotlib.colormaps["viridis"]
    kP, uP = _scale(np.concatenate([ds["P"].values, ds["Q"].values]), "N/m")
    for n, i in enumerate(steps):
        colour = cmap(n / max(len(steps) - 1, 1) * 0.9)
        row = ds.isel(t=i)
        P_i, Q_i = float(row.P), float(row.Q)
        Q_i = 0.0 if abs(Q_i) <= 1e-9 * max(abs(P_i), 1.0) else Q_i  # rounding of sin(pi)
        label = f"t = {float(row.t):.4g} s:  P = {P_i / kP:.4g}, Q = {Q_i / kP:.4g} {uP}"
        ax.plot(x / kx, ds["q"].values[i] / kq, color=colour, lw=1.8, label=label)
        ax.plot(x / kx, f * ds["p"].values[i] / kq, color=colour, lw=0.9, ls="--")
        ax.plot(x / kx, -f * ds["p"].values[i] / kq, color=colour, lw=0.9, ls="--")
    ax.axhline(0.0, color="0.6", lw=0.6)
    ax.plot([], [], color="0.3", lw=1.8, label="shear traction q(x)")
    ax.plot([], [], color="0.3", lw=0.9, ls="--", label=f"±f p(x), f = {f:g}")
    ax.set_xlabel(f"x [{ux}]")
    ax.set_ylabel(f"traction [{uq}]")
    ax.set_xlim(x[0] / kx, x[-1] / kx)
    ax.set_title(_title(ds, "shear traction within the Coulomb bounds"))
    ax.legend(fontsize=7.5, loc="lower center", framealpha=0.9)
    ax.grid(True, lw=0.3, alpha=0.5)
    top = float(np.nanmax(np.abs(np.concatenate([f * p.ravel(), q.ravel()])))) / kq
    ax.set_ylim(-1.9 * top, 1.15 * top)  # room for the legend below the curves
    return fig


def slip(ds: xr.Dataset) -> Figure:
    """Slip amplitude and frictional energy per cycle along x.

    For cyclic runs both refer to the last full cycle (the permanent stick
    zone is shaded); otherwise to the whole run. The energy panel needs q.
    When the slip zones are thin (less than 4 % of the contact width) the
    figure shows one column per contact edge, zoomed on its slip zone, with
    the stations marked.
    """
    post.check_result(ds, NEEDS["slip"], "the slip figure")
    table = _cycle_table(ds)
    cyclic = table.sizes["cycle"] > 0
    cycle = -1 if cyclic else None
    amplitude = post.slip_amplitude(ds, cycle=cycle).values
    window = post.select_cycle(ds, cycle)
    x = ds["x"].values
    kx, ux = _scale(x, "m")
    kg, ug = _scale(amplitude, "m")
    has_q = "q" in ds.data_vars
    density = total = None
    if has_q:
        if cyclic:
            energy = post.dissipation_per_cycle(ds)
            density = energy["dissipation_density"].values[-1]
            total = float(energy["dissipation"][-1])
            label = "per cycle"
        else:
            q_all, g_all = ds["q"].values, ds["slip"].values
            density = post._loop_integral(q_all, g_all)
            density[np.all(~np.isfinite(g_all), axis=0) & np.any(q_all != 0, axis=0)] = np.nan
            total = float(ds["dissipation"][-1] - ds["dissipation"][0])
            label = "over the run"
    zone = post.permanent_stick(ds) if cyclic else None
    stick = (float(zone["left"]), float(zone["right"])) if zone is not None and np.isfinite(float(zone["left"])) else None
    columns = _edge_windows(window, stick, x)
    rows = 2 if has_q else 1
    fig = _figure((SIZE[0], 6.2) if has_q else SIZE)
    grid = np.atleast_2d(fig.subplots(rows, len(columns), sharex="col", squeeze=False))
    for col, (low, high) in enumerate(columns):
        ax = grid[0, col]
        marker = "o" if len(columns) > 1 else None
        ax.plot(x / kx, amplitude / kg, color="#d94801", lw=1.8, marker=marker, ms=3)
        ax.fill_between(x / kx, 0, np.nan_to_num(amplitude) / kg, color="#d94801", alpha=0.15, lw=0)
        if has_q:
            ke, ue = _scale(density, "J/m^2")
            axe = grid[1, col]
            axe.plot(x / kx, density / ke, color="#54278f", lw=1.8, marker=marker, ms=3)
            axe.fill_between(x / kx, 0, np.nan_to_num(density) / ke, where=np.isfinite(density),
                             color="#54278f", alpha=0.15, lw=0)
        for axis in grid[:, col]:
            if stick is not None:
                axis.axvspan(stick[0] / kx, stick[1] / kx, color=STICK_COLOUR, alpha=0.5, lw=0)
            axis.grid(True, lw=0.3, alpha=0.5)
            axis.set_ylim(bottom=0.0)
            axis.set_xlim((x[0] if low is None else low) / kx, (x[-1] if high is None else high) / kx)
        grid[-1, col].set_xlabel(f"x [{ux}]" + ("" if len(columns) == 1 else (" (left edge)" if col == 0 else " (right edge)")))
    grid[0, 0].set_ylabel(f"slip amplitude [{ug}]")
    if has_q:
        grid[1, 0].set_ylabel(f"energy {label} [{ue}]")
        known = np.isfinite(density)  # bridge stations without a value
        integral = float(np.trapezoid(np.interp(x, x[known], density[known]), x)) if known.any() else float("nan")
        grid[1, -1].annotate(
            f"∫ (∮ q dg) dx = {integral:.4g} J/m\nsolver's energy {total:.4g} J/m",
            (0.5 if len(columns) == 1 else 0.05, 0.92), xycoords="axes fraction", fontsize=8,
            ha="center" if len(columns) == 1 else "left", va="top", bbox=_LABEL_BOX,
        )
    warnings = []
    if "p" in ds.data_vars:  # stations in contact without a slip value show as gaps: say so
        lost = int(np.sum(np.any((window["p"].values > 0) & ~np.isfinite(window["slip"].values), axis=0)))
        if lost:
            warnings.append(f"{lost} station(s) in contact carry no slip value (NaN in the result): gaps")
    finite = np.nan_to_num(amplitude)
    slipping = int(np.sum(finite > 1e-3 * finite.max())) if finite.max() > 0 else 0
    if 0 < slipping < 12:
        warnings.append(f"only {slipping} stations slip: raise output.points for detail")
    where = (0.5, "center") if len(columns) == 1 else (0.05, "left")
    top = 0.92
    if stick is not None:
        grid[0, 0].annotate("shaded: permanent stick zone", (where[0], top), xycoords="axes fraction", fontsize=8,
                            ha=where[1], va="top", bbox=_LABEL_BOX)
        top = 0.80
    if warnings:
        grid[0, 0].annotate("\n".join(warnings), (where[0], top), xycoords="axes fraction", fontsize=8,
                            ha=where[1], va="top", color="#a50f15", bbox=_LABEL_BOX)
    fig.suptitle(_title(ds, "slip amplitude and energy dissipated") + f"\n{_cycle_label(ds, cycle)}", fontsize=10)
    return fig


def _cycle_label(ds: xr.Dataset, cycle) -> str:
    """The cycle a slip figure refers to, in words."""
    return post.select_cycle(ds, cycle).attrs["selection"]


def _edge_windows(window: xr.Dataset, stick, x: np.ndarray) -> list:
    """[(None, None)] (whole x range), or [(low, high) of the left edge, (low, high) of the right edge] for thin slip zones."""
    if stick is None:
        return [(None, None)]
    cl, cr = window["contact_left"].values, window["contact_right"].values
    if not (np.any(np.isfinite(cl)) and np.any(np.isfinite(cr))):
        return [(None, None)]
    left_out, right_out = float(np.nanmin(cl)), float(np.nanmax(cr))
    width = right_out - left_out
    band = max(stick[0] - left_out, right_out - stick[1])
    if width <= 0 or band >= THIN_SLIP * width:
        return [(None, None)]
    spacing = float(np.median(np.diff(x)))
    margin = max(0.5 * band, 4 * spacing)
    return [(left_out - margin, stick[0] + margin), (stick[1] - margin, right_out + margin)]


DRAW = {"trajectory": trajectory, "map": stick_slip_map, "tractions": tractions, "slip": slip}
"""The function drawing each kind."""


# ---------------------------------------------------------------------------
# files


def figure(ds: xr.Dataset, kind: str, at=None) -> Figure:
    """The figure of one `kind` (see :data:`KINDS`)."""
    if kind not in DRAW:
        raise HalfslipInputError(f"unknown figure kind {kind!r}; expected one of {', '.join(KINDS)}", field="--kind")
    post.check_result(ds, NEEDS[kind], f"the {kind} figure")
    if kind == "tractions":
        return tractions(ds, at=at)
    return DRAW[kind](ds)


def output_paths(out: str | os.PathLike, kinds, stem: str) -> list[Path]:
    """Where :func:`plot_run` writes each kind.

    A folder (existing, or a path without suffix) receives ``<stem>-<kind>.png``;
    a file name is used as it is for one kind and becomes
    ``<name>-<kind><suffix>`` beside it for several.
    """
    out = Path(out)
    if out.is_dir() or not out.suffix:
        return [out / f"{stem}-{kind}.png" for kind in kinds]
    if len(kinds) == 1:
        return [out]
    return [out.with_name(f"{out.stem}-{kind}{out.suffix}") for kind in kinds]


def plot_run(ds: xr.Dataset, out: str | os.PathLike, kinds=None, at=None) -> list[Path]:
    """Write figures of a run and return their paths.

    Parameters
    ----------
    ds : xarray.Dataset
        A halfslip result.
    out : path
        A folder (created if missing) or a file name (its suffix picks the
        format: .png, .pdf, .svg).
    kinds : sequence of str, optional
        Subset of :data:`KINDS`; default all that the stored fields allow.
        A kind asked for explicitly whose fields were not stored raises.
    at : sequence of float, optional
        Instants of the tractions figure [s].

    Returns
    -------
    list of pathlib.Path
    """
    post.check_result(ds)
    if kinds is None:
        kinds = [kind for kind in KINDS if all(name in ds.data_vars for name in NEEDS[kind])]
    else:
        kinds = list(dict.fromkeys(kinds))
        for kind in kinds:
            if kind not in DRAW:
                raise HalfslipInputError(f"unknown figure kind {kind!r}; expected one of {', '.join(KINDS)}", field="--kind")
            post.check_result(ds, NEEDS[kind], f"the {kind} figure")
    source = ds.encoding.get("source")
    stem = Path(source).stem if source else str(ds.attrs.get("scene_name") or "halfslip")
    paths = output_paths(out, kinds, stem)
    for path in paths:
        if not path.parent.exists():
            if path.parent == Path(out):
                path.parent.mkdir(parents=True)
            else:
                raise HalfslipInputError(f"folder {str(path.parent)!r} does not exist", field="-o")
    written = []
    for kind, path in zip(kinds, paths):
        fig = figure(ds, kind, at=at)
        fig.savefig(path, dpi=DPI)
        written.append(path)
    return written
