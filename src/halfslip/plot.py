"""Pictures of halfslip files: runs, sweeps and steady states.

This module draws; :mod:`halfslip.post` computes (this module imports it,
never the other way round). Every drawing function takes a dataset, draws on
the Axes it is given (``ax=`` for one panel, ``axes=`` for several: a
sequence of Axes, or a Figure / SubFigure to lay the panels out in) or on a
new Agg figure, and returns the :class:`matplotlib.figure.Figure`. Nothing
touches pyplot, so no global figure state is created or leaked, and no
drawing function writes a file: :func:`plot_run` and :func:`write_figures`
do::

    import halfslip as hs
    from halfslip.plot import plot_run, loop
    ds = hs.simulate(hs.load_scene("examples/hertz_pad.yaml"))
    plot_run(ds, "figures/")          # figures/hertz-pad-trajectory.png, ...
    fig = loop(ds)                    # one figure, to show or save yourself

Kinds of a run and what they need:

``trajectory``  loads only: the path in the P-Q plane coloured by regime.
``map``         zone extents only: contact and stick zone against time.
``tractions``   fields p and q: q(x) and the Coulomb bounds +-f p(x).
``slip``        field slip (and q for the energy panel): slip amplitude and
                energy dissipated per cycle along x.
``loop``        loads and shift: the Q - delta hysteresis loop of every cycle
                with the elastic part C Q taken out of delta, and its area.
``stress``      fields p and q: surface direct stress sigma_xx(x, 0) at chosen
                instants and its envelope and range over the cycle.
``ruiz``        fields p, q and slip: the Ruiz parameters tau delta and
                sigma tau delta along x.
``loads``       loads only: P, Q, M and sigma against time.

Other files: :func:`sweep_map` (a sweep result), :func:`steady`
(a ``halfslip steady -o`` file); :func:`write_figures` picks by the file's
kind (:func:`halfslip.post.result_kind`).

Axes read in engineering units (um, mm, MPa, kN/m, ...) chosen by
:func:`unit_scale`, never with an offset or a "1e7" above the axis.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure, SubFigure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.ticker import MaxNLocator, ScalarFormatter

from . import cycles, post
from .errors import HalfslipInputError
from .si import unit_scale  # noqa: F401  (public here since 0.1: every figure's axes use it)

KINDS = ("trajectory", "map", "tractions", "slip", "loop", "stress", "ruiz", "loads")
"""Figure kinds of a run, in the order :func:`plot_run` writes them."""

NEEDS = {"trajectory": (), "map": (), "tractions": ("p", "q"), "slip": ("slip",), "loop": (),
         "stress": ("p", "q"), "ruiz": ("p", "q", "slip"), "loads": ()}
"""Per-point fields each kind needs."""

FILE_KINDS = {"sweep": "sweep", "steady": "steady"}
"""The one figure kind of each other file kind (:func:`halfslip.post.result_kind`)."""

REGIME_COLOURS = {0: "#b0b0b0", 1: "#1f77b4", 2: "#ff7f0e", 3: "#d62728"}
"""Colour of each regime: separated, stick, partial slip, gross sliding."""

REGIME_NAMES = {0: "separated", 1: "full stick", 2: "partial slip", 3: "gross sliding"}

STICK_COLOUR = "#9ecae1"
SLIP_COLOUR = "#fdae6b"
OUT_COLOUR = "#f0f0f0"
SLIP_LINE = "#d94801"
ENERGY_LINE = "#54278f"
SKIP_HATCH = {"facecolor": "white", "edgecolor": "0.5", "hatch": "///", "lw": 0.0}

DPI = 150
_LABEL_BOX = {"boxstyle": "round,pad=0.2", "facecolor": "white", "edgecolor": "none", "alpha": 0.85}
SIZE = (7.5, 5.0)  # inches: 1125 x 750 px at DPI


# ---------------------------------------------------------------------------
# helpers


def _plain(ax: Axes) -> None:
    """Tick labels without an offset or a power-of-ten multiplier (the unit label carries the scale)."""
    for axis in (ax.xaxis, ax.yaxis):
        if axis.get_scale() == "linear":
            formatter = ScalarFormatter(useOffset=False)
            formatter.set_scientific(False)
            axis.set_major_formatter(formatter)


def _figure(size=SIZE) -> Figure:
    fig = Figure(figsize=size, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _root(ax: Axes) -> Figure:
    return ax.get_figure(root=True)


def _panels(axes, rows: int, cols: int, size, **kwargs):
    """(root figure, 2-D array of Axes, container or None) for a drawing of rows x cols panels.

    `axes` is None (a new figure), a Figure / SubFigure (the panels are laid
    out in it), one Axes (only for one panel) or a sequence of rows * cols
    Axes. The container is the (sub)figure the drawing owns, where a
    suptitle and a figure legend go; None when the caller gave Axes.
    """
    count = rows * cols
    if axes is None:
        fig = _figure(size)
        grid = np.array(fig.subplots(rows, cols, squeeze=False, **kwargs), dtype=object)
        container = fig
    elif isinstance(axes, (Figure, SubFigure)):
        grid = np.array(axes.subplots(rows, cols, squeeze=False, **kwargs), dtype=object)
        container = axes
    else:
        flat = [axes] if isinstance(axes, Axes) else list(np.asarray(axes, dtype=object).ravel())
        if len(flat) != count or not all(isinstance(ax, Axes) for ax in flat):
            raise ValueError(f"this figure has {count} panel(s) ({rows} x {cols}); pass {count} Axes, "
                             "or a Figure / SubFigure to lay them out in")
        grid = np.array(flat, dtype=object).reshape(rows, cols)
        container = None
    for ax in grid.flat:
        _plain(ax)
    return _root(grid.flat[0]), grid, container


def _one_axes(ax, size=SIZE):
    """(root figure, Axes) for a one-panel drawing: `ax`, the first Axes of a (sub)figure, or a new figure."""
    fig, grid, _ = _panels(ax, 1, 1, size)
    return fig, grid[0, 0]


def _suptitle(container, grid, text: str, fontsize=10) -> None:
    if container is not None:
        container.suptitle(text, fontsize=fontsize)
    else:
        grid.flat[0].set_title(text, fontsize=fontsize)


def _title(ds: xr.Dataset, what: str) -> str:
    name = ds.attrs.get("scene_name") or "halfslip run"
    return f"{name}: {what}"


def _cycle_table(ds: xr.Dataset) -> xr.Dataset:
    try:
        return post.cycles(ds)
    except HalfslipInputError:  # no segment table (a file of halfslip 0.2 or older): treat as acyclic
        return _empty_cycles()


def _empty_cycles() -> xr.Dataset:
    return xr.Dataset({"t_start": ("cycle", np.zeros(0)), "t_stop": ("cycle", np.zeros(0))}, coords={"cycle": np.arange(0)})


def _nearest_steps(ds: xr.Dataset, times) -> list[int]:
    """Stored steps nearest to the given times; a time inside skipped cycles is the same phase of the
    last marched cycle, which they repeat (:meth:`halfslip.cycles.Segments.marched_time`)."""
    t = ds["t"].values
    end = max(float(t[-1]), float(ds["final_t"])) if "final_t" in ds else float(t[-1])
    segments = cycles.read_segments(ds) if cycles.has_segments(ds) else None
    indices = []
    for time in times:
        time = float(time)
        span = end - t[0]
        if not (t[0] - 1e-9 * span <= time <= end + 1e-9 * span):
            raise HalfslipInputError(f"time {time:g} s lies outside the run (t = {t[0]:g} .. {end:g} s)", field="--at")
        if segments is not None:
            time = segments.marched_time(time)
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


def _instant_label(ds: xr.Dataset, i: int, kP: float, uP: str) -> str:
    row = ds.isel(t=i)
    P_i, Q_i = float(row.P), float(row.Q)
    Q_i = 0.0 if abs(Q_i) <= 1e-9 * max(abs(P_i), 1.0) else Q_i  # rounding of sin(pi)
    return f"t = {float(row.t):.4g} s:  P = {P_i / kP:.4g}, Q = {Q_i / kP:.4g} {uP}"


def _instant_colours(n: int):
    import matplotlib

    cmap = matplotlib.colormaps["viridis"]
    return [cmap(k / max(n - 1, 1) * 0.9) for k in range(n)]


def _cycle_of(ds: xr.Dataset):
    """-1 (the last full cycle) for cyclic runs, None (the whole run) otherwise."""
    return -1 if _cycle_table(ds).sizes["cycle"] else None


def _stick_zone(ds: xr.Dataset, cycle):
    if cycle is None:
        return None
    zone = post.permanent_stick(ds, cycle)
    left, right = float(zone["left"]), float(zone["right"])
    return (left, right) if np.isfinite(left) else None


def _segments_by_regime(x: np.ndarray, y: np.ndarray, regime: np.ndarray):
    """Line segments (k-1 -> k) grouped by the regime of step k."""
    points = np.stack([x, y], axis=1)
    segments = np.stack([points[:-1], points[1:]], axis=1)
    return segments, regime[1:]


@dataclass(frozen=True)
class _TimeAxis:
    """Time as drawn: stretches of cycles the simulator skipped are compressed into thin bands.

    ``real`` and ``shown`` are matching knots of a piecewise-linear map;
    ``bands`` lists (shown start, shown stop, cycles skipped) of each skip.
    """

    real: np.ndarray
    shown: np.ndarray
    bands: tuple

    def __call__(self, t):
        return np.interp(np.asarray(t, float), self.real, self.shown)

    def pieces(self):
        """(real start, real stop) of the stretches outside the bands."""
        edges = [self.real[0]]
        for k in range(1, len(self.real) - 1, 2):
            edges += [self.real[k], self.real[k + 1]]
        edges.append(self.real[-1])
        return [(edges[k], edges[k + 1]) for k in range(0, len(edges), 2)]


BAND = 0.04
"""Width of a band of skipped cycles on a time axis, as a fraction of the time actually marched."""


def _time_axis(ds: xr.Dataset) -> _TimeAxis:
    """The drawn time axis: from the first stored step to the run's last state (``final_t``),
    each stretch of skipped cycles (the segment table) a thin band."""
    t = np.asarray(ds["t"].values, float)
    end = max(float(t[-1]), float(ds["final_t"])) if "final_t" in ds else float(t[-1])
    try:
        skips = cycles.read_segments(ds).skipped_stretches()
    except HalfslipInputError:
        skips = []
    marched = (end - t[0]) - sum(b - a for _k, a, b, _n in skips)
    width = BAND * marched if marched > 0 else 0.0
    real, shown, bands, offset = [t[0]], [t[0]], [], 0.0
    for _k, a, b, count in skips:
        w = min(b - a, width)
        real += [a, b]
        shown += [a - offset, a - offset + w]
        bands.append((a - offset, a - offset + w, count))
        offset += (b - a) - w
    real.append(end)
    shown.append(end - offset)
    return _TimeAxis(np.asarray(real, float), np.asarray(shown, float), tuple(bands))


def _draw_time_axis(ax: Axes, axis: _TimeAxis, label: bool = True, text: bool = True) -> None:
    """Limits, real-time ticks and the skip bands of a panel drawn against ``axis(t)``."""
    ax.set_xlim(axis.shown[0], axis.shown[-1])
    if axis.bands:
        total = axis.shown[-1] - axis.shown[0] or 1.0
        ticks, labels = [], []
        for r0, r1 in axis.pieces():
            share = (axis(r1) - axis(r0)) / total
            values = MaxNLocator(nbins=max(1, int(round(7 * share)))).tick_values(r0, r1)
            values = [v for v in values if r0 - 1e-9 * abs(r1 - r0 or 1) <= v <= r1 + 1e-9 * abs(r1 - r0 or 1)] or [r1]
            for v in values:
                ticks.append(float(axis(v)))
                labels.append(f"{v:.6g}")
        ax.set_xticks(ticks, labels)
        for d0, d1, count in axis.bands:
            ax.axvspan(d0, d1, zorder=3, **SKIP_HATCH)
            if text:
                ax.text(0.5 * (d0 + d1), 0.5, f"{count} cycles skipped", transform=ax.get_xaxis_transform(),
                        rotation=90, ha="center", va="center", fontsize=7, zorder=4, bbox=_LABEL_BOX)
    if label:
        ax.set_xlabel("time t [s]" + (" (hatched: skipped cycles, repeats of the steady cycle)" if axis.bands else ""))


# ---------------------------------------------------------------------------
# kinds of a run


def trajectory(ds: xr.Dataset, ax=None) -> Figure:
    """The loading path in the P-Q plane, coloured by regime, with the lines Q = +-f P.

    For cyclic runs with M = sigma = 0 the point T where lines of gradient +f
    and -f touch the last cycle's loop is marked (:func:`halfslip.post.loop_tangent_point`);
    the permanent stick zone is [-a(P_T), a(P_T)].

    Parameters
    ----------
    ds : xarray.Dataset
        A run.
    ax : matplotlib Axes, Figure or SubFigure, optional
        Where to draw (default: a new figure).

    Returns
    -------
    matplotlib.figure.Figure
    """
    post.check_result(ds)
    fig, ax = _one_axes(ax)
    f = post.friction(ds)
    P, Q, regime = ds["P"].values, ds["Q"].values, ds["regime"].values.astype(int)
    kP, uP = unit_scale(np.concatenate([P, Q]), "N/m")
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


def _draw_map(ax, ds: xr.Dataset, kx: float, time=None) -> None:
    t = ds["t"].values if time is None else time(ds["t"].values)
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


def _map_layout(ds: xr.Dataset):
    table = _cycle_table(ds)
    if not table.sizes["cycle"]:
        return table, None, None, 1
    k0 = max(0, table.sizes["cycle"] - 2)
    i0, i1 = int(table["i_start"][k0]), int(table["i_stop"][-1])
    window = ds.isel(t=slice(i0, i1 + 1))
    bands = _slip_bands(window)
    return table, window, bands, 3 if bands is not None else 2


def stick_slip_map(ds: xr.Dataset, axes=None) -> Figure:
    """Contact and stick-zone edges against time: the stick-slip map.

    Stick zone blue, slip zones orange, out of contact grey. Cycles the
    simulator skipped as repeats of the steady cycle are drawn as a thin
    hatched band on the time axis (the ticks keep the real times on both
    sides of it), so the marched part fills the panel. For cyclic runs a
    second panel zooms on the last two stored cycles and marks the permanent
    stick zone of the last cycle (dashed); when the slip zones there are thin
    (less than 4 % of the contact width, e.g. a wide flat punch) the zoom is
    split into one panel per contact edge, each scaled to its slip band.

    Parameters
    ----------
    ds : xarray.Dataset
        A run.
    axes : Figure, SubFigure or sequence of Axes, optional
        Where to draw: 1 panel for a run without cycles, 2 for a cyclic run,
        3 when its slip zones are thin (default: a new figure).

    Returns
    -------
    matplotlib.figure.Figure
    """
    post.check_result(ds)
    edges = np.concatenate([ds[k].values for k in ("contact_left", "contact_right")])
    kx, ux = unit_scale(edges, "m")
    lim = np.nanmax(np.abs(edges)) / kx if np.any(np.isfinite(edges)) else 1.0
    table, window, bands, panels = _map_layout(ds)
    cyclic = window is not None
    size = (SIZE[0], 6.2 if panels == 2 else 7.6) if cyclic else SIZE
    ratios = [1.0] + [0.8] * (panels - 1)
    fig, grid, container = _panels(axes, panels, 1, size, **({"height_ratios": ratios} if axes is None or
                                                              isinstance(axes, (Figure, SubFigure)) else {}))
    axes = list(grid[:, 0])
    time = _time_axis(ds)
    _draw_map(axes[0], ds, kx, time)
    axes[0].set_title(_title(ds, "stick-slip map"))
    axes[0].set_ylim(-1.1 * lim, 1.1 * lim)
    _draw_time_axis(axes[0], time, label=not cyclic)
    if cyclic:
        k0 = max(0, table.sizes["cycle"] - 2)
        t0, t1 = float(table["t_start"][k0]), float(table["t_stop"][-1])
        axes[0].axvspan(time(t0), time(t1), facecolor="none", edgecolor="k", lw=0.8, ls=":", zorder=5)
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
        axes[-1].set_xlabel("time t [s]")
    for ax in axes:
        ax.set_ylabel(f"x [{ux}]")
    handles = [Patch(color=STICK_COLOUR, label="stick"), Patch(color=SLIP_COLOUR, label="slip"),
               Patch(facecolor=OUT_COLOUR, edgecolor="0.6", label="out of contact")]
    if cyclic:
        handles.append(Line2D([], [], color="k", ls="--", label="permanent stick zone of the last cycle"))
    if time.bands:
        handles.append(Patch(label="cycles skipped (repeats)", **SKIP_HATCH))
    if container is not None:
        container.legend(handles=handles, loc="outside lower center", fontsize=8, ncols=len(handles), frameon=False)
    else:
        axes[-1].legend(handles=handles, loc="lower center", fontsize=7, ncols=3, framealpha=0.9)
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


def tractions(ds: xr.Dataset, at=None, ax=None) -> Figure:
    """Shear traction q(x) and the Coulomb bounds +-f p(x) at chosen instants.

    Parameters
    ----------
    ds : xarray.Dataset
        A result with the fields p and q.
    at : sequence of float, optional
        Times [s]; the nearest stored steps are drawn. Default: the start and
        the quarters of the last cycle (of the run, when it has no cycles).
    ax : matplotlib Axes, Figure or SubFigure, optional
        Where to draw (default: a new figure). The legend sits to the right
        of the axes.

    Returns
    -------
    matplotlib.figure.Figure
    """
    post.check_result(ds, NEEDS["tractions"], "the tractions figure")
    fig, ax = _one_axes(ax, (9.0, 4.6))
    f = post.friction(ds)
    steps = _default_instants(ds) if not at else _nearest_steps(ds, at)
    x = ds["x"].values
    kx, ux = unit_scale(x, "m")
    p, q = ds["p"].values[steps], ds["q"].values[steps]
    kq, uq = unit_scale(np.concatenate([f * p.ravel(), q.ravel()]), "Pa")
    kP, uP = unit_scale(np.concatenate([ds["P"].values, ds["Q"].values]), "N/m")
    for colour, i in zip(_instant_colours(len(steps)), steps):
        ax.plot(x / kx, ds["q"].values[i] / kq, color=colour, lw=1.8, label=_instant_label(ds, i, kP, uP))
        ax.plot(x / kx, f * ds["p"].values[i] / kq, color=colour, lw=0.9, ls="--")
        ax.plot(x / kx, -f * ds["p"].values[i] / kq, color=colour, lw=0.9, ls="--")
    ax.axhline(0.0, color="0.6", lw=0.6)
    ax.plot([], [], color="0.3", lw=1.8, label="shear traction q(x)")
    ax.plot([], [], color="0.3", lw=0.9, ls="--", label=f"±f p(x), f = {f:g}")
    ax.set_xlabel(f"x [{ux}]")
    ax.set_ylabel(f"traction [{uq}]")
    ax.set_xlim(x[0] / kx, x[-1] / kx)
    ax.set_title(_title(ds, "shear traction within the Coulomb bounds"))
    ax.legend(fontsize=7.5, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, framealpha=0.9)
    ax.grid(True, lw=0.3, alpha=0.5)
    top = float(np.nanmax(np.abs(np.concatenate([f * p.ravel(), q.ravel()])))) / kq
    ax.set_ylim(-1.1 * top, 1.1 * top)
    return fig


def _slip_zone_widths(window: xr.Dataset) -> tuple[float, float]:
    """Widest left and right slip zones [m] over the steps of `window` (0 where none)."""
    cl, cr = window["contact_left"].values, window["contact_right"].values
    sl, sr = window["stick_left"].values, window["stick_right"].values
    with np.errstate(invalid="ignore"):
        left = np.where(np.isfinite(sl), sl - cl, cr - cl)
        right = np.where(np.isfinite(sr), cr - sr, cr - cl)
    left, right = left[np.isfinite(left)], right[np.isfinite(right)]
    return (float(left.max()) if left.size else 0.0, float(right.max()) if right.size else 0.0)


RESOLVED_STATIONS = 8
"""Slip zones narrower than this many station spacings make the station integral of the energy unreliable."""


def slip(ds: xr.Dataset, axes=None) -> Figure:
    """Slip amplitude and frictional energy per cycle along x.

    For cyclic runs both refer to the last full cycle (the permanent stick
    zone is shaded); otherwise to the whole run. The energy panel needs q.
    When the slip zones are thin (less than 4 % of the contact width) the
    figure shows one column per contact edge, zoomed on its slip zone, with
    the stations marked.

    The energy panel compares the integral over the stations,
    int (loop integral q dg) dx (trapezoid over the ``output.points``
    stations), with the solver's dissipation (integrated on its own nodes).
    They differ for two reasons. (1) Station sampling: when a slip zone spans
    only a few stations the energy density, which rises from 0 at the stick
    edge to its peak inside the zone, is cut to a triangle or two (a zone
    narrower than the spacing is missed altogether). (2) The solver's own
    resolution: the general solver's dissipation is a few per cent low when
    its slip zones span fewer than 16 lattice spacings (the run's messages
    say so). On the dovetail (201 stations 21.7 um apart; slip zones 0.04 um
    and 37.6 um wide; 512 nodes) the station integral is 11.3 % below the
    solver's energy; with 1601 stations it is 4.7 % above it, which is (2):
    at 2048 nodes the solver's energy per cycle is 3.8 % higher than at 512,
    and 1601 stations then agree with it to 0.1 %.
    The figure states the difference and, when a slip zone spans fewer than
    :data:`RESOLVED_STATIONS` station spacings, reason (1) and its remedy
    (raise ``output.points``).

    Parameters
    ----------
    ds : xarray.Dataset
        A result with the field slip (and q for the energy panel).
    axes : Figure, SubFigure or sequence of Axes, optional
        Where to draw: rows (1, or 2 with q) x columns (1, or 2 for thin slip
        zones: one per contact edge) panels (default: a new figure).

    Returns
    -------
    matplotlib.figure.Figure
    """
    post.check_result(ds, NEEDS["slip"], "the slip figure")
    cycle = _cycle_of(ds)
    cyclic = cycle is not None
    amplitude = post.slip_amplitude(ds, cycle=cycle).values
    window = post.select_cycle(ds, cycle)
    x = ds["x"].values
    kx, ux = unit_scale(x, "m")
    kg, ug = unit_scale(amplitude, "m")
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
            density = post.loop_integral(q_all, g_all)
            density[np.all(~np.isfinite(g_all), axis=0) & np.any(q_all != 0, axis=0)] = np.nan
            total = float(ds["dissipation"][-1] - ds["dissipation"][0])
            label = "over the run"
    stick = _stick_zone(ds, cycle)
    columns = _edge_windows(window, stick, x)
    rows = 2 if has_q else 1
    fig, grid, container = _panels(axes, rows, len(columns), (SIZE[0], 6.2) if has_q else SIZE,
                                   **({"sharex": "col"} if axes is None or isinstance(axes, (Figure, SubFigure)) else {}))
    finite_amplitude = np.isfinite(amplitude)
    for col, (low, high) in enumerate(columns):
        ax = grid[0, col]
        marker = "o" if len(columns) > 1 else None
        ax.plot(x / kx, amplitude / kg, color=SLIP_LINE, lw=1.8, marker=marker, ms=3)
        # shade only under the stored points (where=): no shading past the last one
        ax.fill_between(x / kx, 0, np.where(finite_amplitude, amplitude, 0.0) / kg, where=finite_amplitude,
                        color=SLIP_LINE, alpha=0.15, lw=0)
        if has_q:
            ke, ue = unit_scale(density, "J/m^2")
            axe = grid[1, col]
            known = np.isfinite(density)
            axe.plot(x / kx, density / ke, color=ENERGY_LINE, lw=1.8, marker=marker, ms=3)
            axe.fill_between(x / kx, 0, np.where(known, density, 0.0) / ke, where=known,
                             color=ENERGY_LINE, alpha=0.15, lw=0)
        tops = [amplitude / kg] + ([density / ke] if has_q else [])
        for axis, values in zip(grid[:, col], tops):
            if stick is not None:
                axis.axvspan(stick[0] / kx, stick[1] / kx, color=STICK_COLOUR, alpha=0.5, lw=0)
            axis.grid(True, lw=0.3, alpha=0.5)
            peak = float(np.nanmax(values)) if np.any(np.isfinite(values)) else 0.0
            axis.set_ylim(0.0, 1.6 * peak if peak > 0 else 1.0)  # headroom for the notes
            axis.set_xlim((x[0] if low is None else low) / kx, (x[-1] if high is None else high) / kx)
        grid[-1, col].set_xlabel(f"x [{ux}]" + ("" if len(columns) == 1 else (" (left edge)" if col == 0 else " (right edge)")))
    grid[0, 0].set_ylabel(f"slip amplitude [{ug}]")
    # notes go into the column where the slip is (not into a panel where nothing slips)
    peak_col = 0
    if len(columns) > 1 and np.any(finite_amplitude):
        peak_col = 0 if x[int(np.nanargmax(amplitude))] < 0.5 * (x[0] + x[-1]) else 1
    where = (0.5, "center") if len(columns) == 1 else (0.05, "left")
    spacing = float(np.median(np.diff(x))) if x.size > 1 else float("nan")
    widths = _slip_zone_widths(window)
    narrow = [w for w in widths if 0 < w < RESOLVED_STATIONS * spacing]
    if has_q:
        grid[1, 0].set_ylabel(f"energy {label} [{ue}]")
        known = np.isfinite(density)  # bridge stations without a value
        integral = float(np.trapezoid(np.interp(x, x[known], density[known]), x)) if known.any() else float("nan")
        kE, uE = unit_scale([integral, total], "J/m")
        text = f"∫ (∮ q dg) dx over the stations:\n{integral / kE:.4g} {uE}; solver's energy {total / kE:.4g} {uE}"
        if total and np.isfinite(integral):
            gap = integral / total - 1.0
            text += f" ({gap:+.1%})"
            if abs(gap) > 0.02 and narrow:
                kw, uw = unit_scale([spacing, *widths], "m")
                text += (f"\nslip zones {widths[0] / kw:.3g} and {widths[1] / kw:.3g} {uw} wide,\n"
                         f"stations {spacing / kw:.3g} {uw} apart: too few for\nthe ∫; raise "
                         "output.points to resolve them")
        grid[1, peak_col].annotate(text, (where[0], 0.95), xycoords="axes fraction", fontsize=7.5,
                                   ha=where[1], va="top", bbox=_LABEL_BOX)
    warnings = []
    if "p" in ds.data_vars:  # stations in contact without a slip value show as gaps: say so
        lost = int(np.sum(np.any((window["p"].values > 0) & ~np.isfinite(window["slip"].values), axis=0)))
        if lost:
            warnings.append(f"{lost} station(s) in contact carry no slip value (NaN in the result): gaps")
    finite = np.nan_to_num(amplitude)
    slipping = int(np.sum(finite > 1e-3 * finite.max())) if finite.max() > 0 else 0
    if 0 < slipping < 12:
        warnings.append(f"only {slipping} stations slip: raise output.points for detail")
    top = 0.95
    if stick is not None:
        grid[0, peak_col].annotate("shaded: permanent stick zone", (where[0], top), xycoords="axes fraction",
                                   fontsize=8, ha=where[1], va="top", bbox=_LABEL_BOX)
        top = 0.83
    if warnings:
        grid[0, peak_col].annotate("\n".join(warnings), (where[0], top), xycoords="axes fraction", fontsize=8,
                                   ha=where[1], va="top", color="#a50f15", bbox=_LABEL_BOX)
    _suptitle(container, grid, _title(ds, "slip amplitude and energy dissipated") + f"\n{_cycle_label(ds, cycle)}")
    return fig


def _loop_data(ds: xr.Dataset):
    """(Q, shift_slip, compliance, labels, work, dissipation) for the loop figure; one row per loop."""
    table = _cycle_table(ds)
    if table.sizes["cycle"]:
        loops = post.hysteresis_loops(ds)
        energy = post.dissipation_per_cycle(ds)
        labels = [f"cycle {int(c)} (t = {float(a):g} .. {float(b):g} s)"
                  for c, a, b in zip(table["cycle"].values, table["t_start"].values, table["t_stop"].values)]
        return (loops["Q"].values, loops["shift_slip"].values, loops["compliance"].values, labels,
                loops["work"].values, energy["dissipation"].values)
    Q, shift = ds["Q"].values, ds["rigid_shift"].values
    C = post.elastic_compliance(Q, shift, ds["regime"].values)
    return Q[None], (shift - C * Q)[None], np.array([C]), ["whole run (no cycles)"], None, None


def loop(ds: xr.Dataset, ax=None) -> Figure:
    """The Q - delta hysteresis loop of every stored cycle, with the elastic part taken out.

    The rigid shift delta of a fretting contact is nearly proportional to Q
    (the raw loop is a thin lens around a straight line); the figure plots Q
    against delta - C Q, where C is the elastic (fully stuck) compliance
    fitted at the reversal points of Q (:func:`halfslip.post.elastic_compliance`),
    which opens the loop without changing its area (the loop integral of
    C Q dQ vanishes). The last cycle is drawn bold, earlier ones thin.

    The annotation gives the loop area, the loop integral of Q d(delta) of
    the last cycle (trapezoid over its stored steps), next to the solver's
    dissipation in that cycle: over a closed steady cycle the elastic energy
    returns to its start, so the two agree (to the trapezoid's O(1/n^2), n
    stored steps per cycle) when Q is the only load that works; when M or
    sigma vary they work too, and the area is the work of Q alone.

    Parameters
    ----------
    ds : xarray.Dataset
        A run (loads and ``rigid_shift``). Without cycles the whole run's path is drawn.
    ax : matplotlib Axes, Figure or SubFigure, optional
        Where to draw (default: a new figure).

    Returns
    -------
    matplotlib.figure.Figure
    """
    post.check_result(ds)
    if "rigid_shift" not in ds.data_vars:
        raise HalfslipInputError("the loop figure needs the variable rigid_shift, which this result lacks")
    fig, ax = _one_axes(ax, (9.0, 5.0))
    Q, slip_shift, compliance, labels, work, dissipation = _loop_data(ds)
    kQ, uQ = unit_scale(Q, "N/m")
    kd, ud = unit_scale(slip_shift - np.nanmean(slip_shift), "m")
    n = Q.shape[0]
    colours = _instant_colours(n)
    for k in range(n):
        last = k == n - 1
        ax.plot(slip_shift[k] / kd, Q[k] / kQ, color=colours[k] if not last else "k", lw=1.8 if last else 0.8,
                alpha=1.0 if last else 0.6, label=labels[k] if (last or n <= 6) else None, zorder=3 if last else 2)
    # direction of travel on the last loop
    x_last, y_last = slip_shift[-1][np.isfinite(slip_shift[-1])], Q[-1][np.isfinite(Q[-1])]
    if x_last.size > 4:
        m = x_last.size // 8
        ax.annotate("", (x_last[m + 1] / kd, y_last[m + 1] / kQ), (x_last[m] / kd, y_last[m] / kQ),
                    arrowprops={"arrowstyle": "-|>", "color": "k", "lw": 1.2}, zorder=4)
    C = float(compliance[-1])
    ax.set_xlabel(f"δ − C·Q: rigid shift less its elastic part [{ud}]")
    ax.set_ylabel(f"shear force Q [{uQ}]")
    ax.axhline(0.0, color="0.8", lw=0.6, zorder=0)
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.set_title(_title(ds, "Q–δ hysteresis loop, elastic part removed"))
    text = [f"C = {C:.4g} m per N/m\n(elastic, fitted at the reversals of Q)"]
    if work is not None and len(work):
        area, solver = float(work[-1]), float(dissipation[-1])
        ke, ue = unit_scale([area, solver], "J/m")
        text.append(f"loop area ∮ Q dδ of the last cycle:\n{area / ke:.4g} {ue} per cycle")
        if solver:
            text.append(f"solver's dissipation in it:\n{solver / ke:.4g} {ue} ({area / solver - 1:+.2%})")
        if np.any(np.ptp(post.select_cycle(ds)[["M", "sigma"]].to_array().values, axis=1) > 0):
            text.append("M and σ vary too: the area is\nthe work of Q alone")
    if str(ds.attrs.get("method", "")) == "general":
        text.append("steps of a few nm: the shift's\nresolution at solver.nodes")
    legend = ax.legend(fontsize=7.5, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0,
                       title="\n".join(text), title_fontsize=7.5, framealpha=0.9)
    legend._legend_box.align = "left"
    return fig


def stress(ds: xr.Dataset, at=None, axes=None) -> Figure:
    """Surface direct stress sigma_xx(x, 0) at chosen instants, and its envelope over the cycle.

    Top: sigma_xx(x, 0) of the substrate at the instants of the tractions
    figure (:func:`halfslip.post.surface_stress`; tension positive). Bottom:
    its maximum and minimum over the last cycle (over the run without cycles)
    shaded, and the range max - min, whose peak is marked (the stress range
    that drives fretting fatigue cracks at the trailing edge of the contact).
    The stress is that of the contact tractions: the substrate's own bulk
    stress sigma_B is not in a result (``sigma`` is the *difference* of the
    two bodies' bulk stresses) and is taken as 0 -- add it for an assessment.

    Parameters
    ----------
    ds : xarray.Dataset
        A result with the fields p and q.
    at : sequence of float, optional
        Times [s] of the top panel (default: as :func:`tractions`).
    axes : Figure, SubFigure or sequence of 2 Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    post.check_result(ds, NEEDS["stress"], "the stress figure")
    fig, grid, container = _panels(axes, 2, 1, (9.5, 6.6), **({"sharex": True} if axes is None or
                                                                     isinstance(axes, (Figure, SubFigure)) else {}))
    top, bottom = grid[0, 0], grid[1, 0]
    steps = _default_instants(ds) if not at else _nearest_steps(ds, at)
    cycle = _cycle_of(ds)
    snapshots = post.surface_stress(ds.isel(t=steps)).values
    envelope = post.stress_range(ds, cycle)
    x = ds["x"].values
    kx, ux = unit_scale(x, "m")
    ks, us = unit_scale(np.concatenate([snapshots.ravel(), envelope["max"].values, envelope["min"].values]), "Pa")
    kP, uP = unit_scale(np.concatenate([ds["P"].values, ds["Q"].values]), "N/m")
    for colour, i, row in zip(_instant_colours(len(steps)), steps, snapshots):
        top.plot(x / kx, row / ks, color=colour, lw=1.6, label=_instant_label(ds, i, kP, uP))
    top.legend(fontsize=7.5, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, framealpha=0.9)
    top.set_ylabel(f"σxx(x, 0) [{us}]")
    bottom.fill_between(x / kx, envelope["min"].values / ks, envelope["max"].values / ks, color="#c6dbef",
                        lw=0, label="between min and max over the cycle")
    bottom.plot(x / kx, envelope["max"].values / ks, color="#2171b5", lw=0.9)
    bottom.plot(x / kx, envelope["min"].values / ks, color="#2171b5", lw=0.9)
    bottom.plot(x / kx, envelope["range"].values / ks, color="#a50f15", lw=1.8, label="range: max − min")
    x_peak, peak = float(envelope["x_peak_range"]), float(envelope["peak_range"])
    bottom.plot(x_peak / kx, peak / ks, "v", color="#a50f15", ms=7)
    right_half = x_peak > 0.5 * (x[0] + x[-1])
    bottom.annotate(f"largest range {peak / ks:.4g} {us}\nat x = {x_peak / kx:.4g} {ux}", (x_peak / kx, peak / ks),
                    xytext=(-10 if right_half else 10, -4), textcoords="offset points", fontsize=8, va="top",
                    ha="right" if right_half else "left", bbox=_LABEL_BOX)
    bottom.legend(fontsize=7.5, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, framealpha=0.9)
    bottom.set_ylabel(f"σxx(x, 0) [{us}]")
    bottom.set_xlabel(f"x [{ux}]")
    stick = _stick_zone(ds, cycle)
    for ax in (top, bottom):
        ax.axhline(0.0, color="0.6", lw=0.6)
        ax.grid(True, lw=0.3, alpha=0.5)
        ax.set_xlim(x[0] / kx, x[-1] / kx)
        if stick is not None:
            ax.axvspan(stick[0] / kx, stick[1] / kx, color=STICK_COLOUR, alpha=0.35, lw=0)
    top.set_title("at the instants (tension positive; shaded: permanent stick zone)", fontsize=9)
    bottom.set_title(f"envelope over {_cycle_label(ds, cycle)}", fontsize=9)
    _suptitle(container, grid, _title(ds, "surface direct stress σxx(x, 0) in the substrate")
              + "\nfrom the contact tractions; the substrate's bulk stress σ_B is not included (σ_B = 0)")
    return fig


def ruiz(ds: xr.Dataset, axes=None) -> Figure:
    """The Ruiz fretting parameters along x over the last cycle (the run, without cycles).

    Top: the two-factor form tau delta = max over the cycle of abs(q) times
    the slip amplitude [J/m^2] (frictional work, where wear and crack
    initiation concentrate). Bottom: the three-factor form sigma tau delta =
    max over the cycle of [max(sigma_xx, 0) abs(q)] times the slip amplitude
    (Ruiz, Boddington and Chen 1984; the fretting fatigue damage parameter of
    Nowell and Hills), with sigma_xx the surface stress of the contact
    tractions (bulk stress sigma_B = 0) and only its tensile part: compression
    does not open a crack. Both from :func:`halfslip.post.ruiz`; peaks marked.

    Parameters
    ----------
    ds : xarray.Dataset
        A result with the fields p, q and slip.
    axes : Figure, SubFigure or sequence of 2 Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    post.check_result(ds, NEEDS["ruiz"], "the Ruiz figure")
    fig, grid, container = _panels(axes, 2, 1, (SIZE[0], 6.2), **({"sharex": True} if axes is None or
                                                                     isinstance(axes, (Figure, SubFigure)) else {}))
    cycle = _cycle_of(ds)
    values = post.ruiz(ds, cycle)
    x = ds["x"].values
    kx, ux = unit_scale(x, "m")
    two = values["shear_slip"].values
    three = values["ruiz"].values / 1e6  # MPa x J/m^2
    k2, u2 = unit_scale(two, "J/m^2")
    k3, u3 = unit_scale(three, "J/m^2")
    panels = ((grid[0, 0], two / k2, f"τ·δ [{u2}]", "two-factor: max|q| × slip amplitude", "#6a51a3", u2),
              (grid[1, 0], three / k3, f"σ·τ·δ [MPa·{u3}]", "three-factor: max(σxx⁺ |q|) × slip amplitude",
               "#a50f15", f"MPa·{u3}"))
    stick = _stick_zone(ds, cycle)
    for ax, y, ylabel, what, colour, unit in panels:
        ax.plot(x / kx, y, color=colour, lw=1.8, label=what)
        known = np.isfinite(y)
        ax.fill_between(x / kx, 0, np.where(known, y, 0.0), where=known, color=colour, alpha=0.15, lw=0)
        if np.any(y > 0):
            k = int(np.nanargmax(y))
            ax.plot(x[k] / kx, y[k], "v", color=colour, ms=7)
            ax.text(0.98, 0.95, f"peak (▼) {y[k]:.4g} {unit} at x = {x[k] / kx:.4g} {ux}", transform=ax.transAxes,
                    fontsize=8, ha="right", va="top", bbox=_LABEL_BOX)
            ax.set_ylim(0.0, 1.35 * float(np.nanmax(y)))
        else:
            ax.set_ylim(0.0, 1.0)
            ax.text(0.5, 0.5, "zero everywhere: no slip, or no tension where it slips", transform=ax.transAxes,
                    ha="center", va="center", fontsize=8)
        if stick is not None:
            ax.axvspan(stick[0] / kx, stick[1] / kx, color=STICK_COLOUR, alpha=0.35, lw=0)
        ax.set_ylabel(ylabel)
        ax.grid(True, lw=0.3, alpha=0.5)
        ax.set_xlim(x[0] / kx, x[-1] / kx)
        ax.legend(fontsize=7.5, loc="upper left", framealpha=0.9)
    grid[1, 0].set_xlabel(f"x [{ux}]")
    _suptitle(container, grid, _title(ds, "Ruiz fretting parameters") + f"\n{_cycle_label(ds, cycle)}"
              + "\nσxx from the contact tractions (bulk stress σ_B = 0); shaded: permanent stick zone")
    return fig


LOAD_UNITS = {"P": ("N/m", "normal load P"), "Q": ("N/m", "shear force Q"), "M": ("N", "moment M"),
              "sigma": ("Pa", "bulk tension σ")}


def loads(ds: xr.Dataset, axes=None) -> Figure:
    """The four loads P, Q, M and sigma against time, one panel each.

    Cycles the simulator skipped as repeats of the steady cycle are a thin
    hatched band on the time axis (the ticks keep the real times), as in the
    stick-slip map.

    Parameters
    ----------
    ds : xarray.Dataset
        A run.
    axes : Figure, SubFigure or sequence of 4 Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    post.check_result(ds)
    fig, grid, container = _panels(axes, 4, 1, (SIZE[0], 7.0), **({"sharex": True} if axes is None or
                                                                     isinstance(axes, (Figure, SubFigure)) else {}))
    time = _time_axis(ds)
    shown = time(ds["t"].values)
    kF, uF = unit_scale(np.concatenate([ds["P"].values, ds["Q"].values]), "N/m")
    for n, name in enumerate(("P", "Q", "M", "sigma")):
        ax = grid[n, 0]
        unit, long_name = LOAD_UNITS[name]
        values = ds[name].values
        k, u = (kF, uF) if unit == "N/m" else unit_scale(values, unit)
        ax.plot(shown, values / k, color="#08519c", lw=1.2)
        if np.ptp(values) == 0:
            ax.text(0.99, 0.9, "constant", transform=ax.transAxes, ha="right", va="top", fontsize=8, color="0.4")
        ax.set_ylabel(f"{long_name.split()[-1]} [{u}]")
        ax.set_title(long_name, fontsize=8, loc="left", pad=2)
        ax.grid(True, lw=0.3, alpha=0.5)
        _draw_time_axis(ax, time, label=n == 3, text=n == 0)
    _suptitle(container, grid, _title(ds, "loads against time"))
    return fig


def _cycle_label(ds: xr.Dataset, cycle) -> str:
    """The cycle a figure refers to, in words."""
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


# ---------------------------------------------------------------------------
# other halfslip files: sweeps and steady states


def _sweep_axis(ds: xr.Dataset, dim: str):
    """(values as drawn, label) of a sweep dimension, in engineering units."""
    values = ds[dim].values
    if not np.issubdtype(values.dtype, np.number):
        return np.arange(values.size), dim
    units = ds[dim].attrs.get("units")
    if units and units != "1":
        k, u = unit_scale(values, units)
        return values / k, f"{dim} [{u}]"
    return values, dim


def _sweep_panels(part: xr.Dataset):
    """[(title, DataArray in SI, unit)] of a sweep's summaries, and a note on a uniform regime."""
    ok = part["status"] == "ok"
    width = (part["permanent_stick_right"] - part["permanent_stick_left"]).fillna(0.0).where(ok)
    panels = [("permanent stick zone size", width, "m")]
    for name in ("dissipation_per_cycle", "peak_slip_amplitude"):
        values = part[name].where(ok)
        if bool(values.notnull().any()):
            panels.append((part[name].attrs.get("long_name", name), values, part[name].attrs.get("units", "1")))
    regime = part["regime"].where(ok & (part["regime"] >= 0))
    present = sorted({int(r) for r in regime.values.ravel() if np.isfinite(r)})
    note = ""
    if len(present) > 1:
        panels.append(("regime", regime, "regime"))
    elif present:
        note = f"regime: {REGIME_NAMES.get(present[0], present[0])} in every case"
    return panels, note


def sweep_map(ds: xr.Dataset, axes=None) -> Figure:
    """Pictures of a sweep result: maps over two varied fields, curves over one.

    Panels: size of the permanent stick zone (``permanent_stick_right -
    permanent_stick_left``; 0 where nothing sticks permanently), dissipation
    per cycle and peak slip amplitude (panels whose values are all NaN are
    left out), and the regime when it differs between cases (a regime shared
    by every case is said in the title instead). With two grid dimensions
    each panel is a map over them (first dimension on the y axis); with one,
    a curve; with more, the extra dimensions are held at their first value
    (named in the title); explicit cases are drawn against the case number.
    Failed and pending cases are blank. Axes and colour bars read in
    engineering units (kN/m, MPa, mm, ...).

    Parameters
    ----------
    ds : xarray.Dataset
        A result of :func:`halfslip.sweep` (or read back from its file).
    axes : Figure, SubFigure or sequence of Axes, optional
        Where to draw: one Axes per panel (rows of two).

    Returns
    -------
    matplotlib.figure.Figure
    """
    if post.result_kind(ds) != "sweep":
        raise ValueError("not a sweep result (no sweep_hash attribute or done variable)")
    dims = list(ds["done"].dims)
    held = {d: 0 for d in dims[2:]}
    part = ds.isel(held) if held else ds
    panels, note = _sweep_panels(part)
    cols = min(len(panels), 2)
    rows = math.ceil(len(panels) / cols)
    fig, grid, container = _panels(axes, rows, cols, (max(5.0 * cols, 7.0), 3.9 * rows + 0.6))  # an odd last Axes stays empty
    shown = dims[:2]
    for k, ax in enumerate(grid.flat):
        if k >= len(panels):
            ax.set_visible(False)
            continue
        label, values, unit = panels[k]
        if label == "regime":
            import matplotlib.colors as mcolors

            present = sorted({int(r) for r in values.values.ravel() if np.isfinite(r)})
            cmap = mcolors.ListedColormap([REGIME_COLOURS[r] for r in present])
            norm = mcolors.BoundaryNorm(np.arange(len(present) + 1) - 0.5, len(present))
            codes = values.copy(data=np.searchsorted(present, np.nan_to_num(values.values, nan=-1)).astype(float))
            codes = codes.where(values.notnull())
            title = "regime"
        else:
            kv, uv = unit_scale(values.values, unit)
            codes = values / kv
            title = f"{label} [{uv}]"
        if len(shown) == 2:
            ydim, xdim = shown
            x, xlabel = _sweep_axis(part, xdim)
            y, ylabel = _sweep_axis(part, ydim)
            z = codes.transpose(ydim, xdim).values.astype(float)
            if label == "regime":
                mesh = ax.pcolormesh(x, y, z, cmap=cmap, norm=norm, shading="nearest")
                bar = container.colorbar(mesh, ax=ax, ticks=range(len(present))) if container else \
                    _root(ax).colorbar(mesh, ax=ax, ticks=range(len(present)))
                bar.ax.set_yticklabels([REGIME_NAMES[r] for r in present])
            else:
                mesh = ax.pcolormesh(x, y, z, shading="nearest", cmap="viridis")
                bar = (container or _root(ax)).colorbar(mesh, ax=ax)
                bar.ax.yaxis.set_major_formatter(ScalarFormatter(useOffset=False))
                bar.set_label(title, fontsize=8)
            ax.set_xlabel(xlabel)
            ax.set_ylabel(ylabel)
        else:
            xdim = shown[0]
            x, xlabel = _sweep_axis(part, xdim)
            if label == "regime":
                ax.plot(x, values.values.astype(float), "o-", color="0.3", lw=0.8)
                ax.set_yticks(present, [REGIME_NAMES[r] for r in present])
            else:
                ax.plot(x, codes.values.astype(float), "o-", color="#08519c", lw=1.4, ms=4)
            ax.set_xlabel(xlabel)
            ax.grid(True, lw=0.3, alpha=0.5)
        ax.set_title(title, fontsize=9)
    import textwrap

    heading = textwrap.fill(str(ds.attrs.get("title", "halfslip sweep")), 40 * cols + 20)
    extras = []
    if held:
        extras.append(", ".join(f"{d} = {part[d].item()}" for d in held))
    if note:
        extras.append(note)
    if int(ds.attrs.get("count_failed", 0) or 0):
        extras.append(f"{int(ds.attrs['count_failed'])} failed case(s) blank")
    _suptitle(container, grid, heading + ("\n" + "; ".join(extras) if extras else ""))
    return fig


def steady(ds: xr.Dataset, ax=None) -> Figure:
    """The steady cycle of a ``halfslip steady -o`` file (:func:`halfslip.steady_state`).

    With the slip amplitude stored (``per_cycle``): the slip amplitude of the
    steady cycle along x with the permanent stick zone shaded; without it, the
    permanent stick zone as a bar along x. A box gives the regime, the
    construction (``method``), the permanent stick zone and, when stored,
    the dissipation per cycle and peak slip amplitude.

    Parameters
    ----------
    ds : xarray.Dataset
        A steady-state dataset.
    ax : matplotlib Axes, Figure or SubFigure, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    if post.result_kind(ds) != "steady":
        raise HalfslipInputError("not a steady-state result (it lacks permanent_stick_left/right, regime or method)")
    fig, ax = _one_axes(ax)
    left, right = float(ds["permanent_stick_left"]), float(ds["permanent_stick_right"])
    regime = int(ds["regime"])
    has_slip = "slip_amplitude" in ds.data_vars and "x" in ds.coords
    extent = [left, right] + (list(ds["x"].values[[0, -1]]) if has_slip else [])
    kx, ux = unit_scale(extent, "m")
    lines = [f"regime: {REGIME_NAMES.get(regime, regime)}", f"construction: {ds.attrs.get('method', '?')}"]
    if np.isfinite(left):
        lines.append(f"permanent stick zone [{left / kx:.4g}, {right / kx:.4g}] {ux}")
    else:
        lines.append("no permanent stick zone")
    if "dissipation_per_cycle" in ds.data_vars:
        ke, ue = unit_scale([float(ds["dissipation_per_cycle"])], "J/m")
        lines.append(f"dissipation per cycle {float(ds['dissipation_per_cycle']) / ke:.4g} {ue}")
    if has_slip:
        x = ds["x"].values
        amplitude = ds["slip_amplitude"].values
        kg, ug = unit_scale(amplitude, "m")
        known = np.isfinite(amplitude)
        ax.plot(x / kx, amplitude / kg, color=SLIP_LINE, lw=1.8, label="slip amplitude of the steady cycle")
        ax.fill_between(x / kx, 0, np.where(known, amplitude, 0.0) / kg, where=known, color=SLIP_LINE, alpha=0.15, lw=0)
        if "peak_slip_amplitude" in ds.data_vars:
            lines.append(f"peak slip amplitude {float(ds['peak_slip_amplitude']) / kg:.4g} {ug}")
        ax.set_ylabel(f"slip amplitude [{ug}]")
        ax.set_xlim(x[0] / kx, x[-1] / kx)
        peak = float(np.nanmax(amplitude)) / kg if known.any() else 0.0
        ax.set_ylim(0.0, 1.6 * peak if peak > 0 else 1.0)  # headroom for the boxes
    else:
        ax.set_yticks([])
        ax.set_ylim(0.0, 1.0)
        if np.isfinite(left):
            span = right - left
            ax.set_xlim((left - 0.25 * span) / kx, (right + 0.25 * span) / kx)
    if np.isfinite(left):
        ax.axvspan(left / kx, right / kx, color=STICK_COLOUR, alpha=0.6, lw=0, label="permanent stick zone")
    ax.set_xlabel(f"x [{ux}]")
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.text(0.02, 0.97, "\n".join(lines), transform=ax.transAxes, fontsize=8, va="top", ha="left", bbox=_LABEL_BOX)
    ax.legend(fontsize=8, loc="upper right", framealpha=0.9)
    ax.set_title(_title(ds, "steady cycle, found directly"), fontsize=10)
    return fig


DRAW = {"trajectory": trajectory, "map": stick_slip_map, "tractions": tractions, "slip": slip, "loop": loop,
        "stress": stress, "ruiz": ruiz, "loads": loads, "sweep": sweep_map, "steady": steady}
"""The function drawing each kind (run kinds, and the figure of sweep and steady files)."""


# ---------------------------------------------------------------------------
# files


def figure(ds: xr.Dataset, kind: str, at=None) -> Figure:
    """The figure of one `kind` of a run (see :data:`KINDS`), or ``sweep`` / ``steady`` for those files."""
    if kind not in DRAW:
        raise HalfslipInputError(f"unknown figure kind {kind!r}; expected one of {', '.join(KINDS)}", field="--kind")
    if kind in FILE_KINDS:
        return DRAW[kind](ds)
    post.check_result(ds, NEEDS[kind], f"the {kind} figure")
    if kind in ("tractions", "stress"):
        return DRAW[kind](ds, at=at)
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


def _stem(ds: xr.Dataset) -> str:
    source = ds.encoding.get("source")
    return Path(source).stem if source else str(ds.attrs.get("scene_name") or "halfslip")


def _write(ds: xr.Dataset, out, kinds, at) -> list[Path]:
    paths = output_paths(out, kinds, _stem(ds))
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
        Instants of the tractions and stress figures [s].

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
            if kind not in KINDS:
                raise HalfslipInputError(f"unknown figure kind {kind!r} for a run; expected one of {', '.join(KINDS)}",
                                         field="--kind")
            post.check_result(ds, NEEDS[kind], f"the {kind} figure")
    return _write(ds, out, kinds, at)


def write_figures(ds: xr.Dataset, out: str | os.PathLike, kinds=None, at=None) -> list[Path]:
    """Write the figures of any halfslip file and return their paths.

    The file's kind (:func:`halfslip.post.result_kind`) picks them: a run
    gets :func:`plot_run`; a sweep result its :func:`sweep_map` (kind
    ``sweep``); a steady-state file its :func:`steady` figure (kind
    ``steady``). `out` is a folder or a file name as for :func:`plot_run`.

    Raises
    ------
    HalfslipInputError
        For a dataset that is no halfslip file, or kinds that do not fit it.
    """
    kind = post.result_kind(ds)
    if kind == "run":
        return plot_run(ds, out, kinds=kinds, at=at)
    if kind is None:
        post.check_result(ds)  # raises, naming what the dataset lacks
    only = FILE_KINDS[kind]
    if kinds is not None and list(dict.fromkeys(kinds)) != [only]:
        other = ", ".join(k for k in kinds if k != only)
        raise HalfslipInputError(f"a {kind} file has the one figure kind {only!r}, not {other}", field="--kind")
    return _write(ds, out, [only], at)
