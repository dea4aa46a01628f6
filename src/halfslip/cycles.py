"""Cycles, counted once: the segment table of a result, skipped cycles, cycle windows.

A run knows the structure of its load history; it writes it into the result
as data (the ``segment`` dimension, :func:`segment_table`), and everything
that needs cycles afterwards -- :mod:`halfslip.post`, :mod:`halfslip.plot`,
:mod:`halfslip.sweep`, :mod:`halfslip.steady`, ``--resume`` -- reads it from
there (:func:`read_segments`), never from the scene text.

The cycle skipper (``solver.skip_steady_cycles``) lives here too:
:class:`CycleSkipper` holds what is fixed for a history (where cycles end,
the solver's tolerance); what changes while a run marches is a
:class:`SkipState`, immutable, replaced at every step and checkpointed with
the run's state (:meth:`SkipState.to_tree`).

When the rest of a segment is skipped, the result keeps the last marched
step at its own time, and the segment says what stands for the rest:
``segment_cycles_skipped`` cycles from ``segment_skip_t_start`` to the
segment's ``segment_t_stop``, adding ``segment_skip_dissipation`` [J/m].
The state at the segment's end *is* the state at ``segment_skip_t_start``
(the cycle repeats, and every cycle of a segment is sampled bit-identically),
with time and dissipation moved on; the run's last state is ``final_t`` and
``final_dissipation``.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Mapping

import numpy as np
import xarray as xr

from . import variables
from .errors import HalfslipInputError
from .histories import SEGMENT_KINDS as HISTORY_SEGMENT_KINDS
from .state import ContactState

__all__ = [
    "CycleSkipper",
    "SEGMENT_DIM",
    "SEGMENT_KINDS",
    "Segments",
    "Skip",
    "SkipState",
    "Window",
    "has_segments",
    "period_windows",
    "read_segments",
    "repeats_at",
    "scene_windows",
    "segment_table",
    "stick_intersection",
    "stored_windows",
    "window_regime",
]

TIME_TOLERANCE = 1e-9
"""Relative tolerance (of the cycle period) for matching window ends to stored times."""

SEGMENT_DIM = "segment"
"""Dimension of the segment table of a result."""

OLD_RESULT_MESSAGE = ("this result has no segment table (it was written by halfslip 0.2 or older); "
                      "run its scene again to analyse its cycles")


# ---------------------------------------------------------------------------
# the skipper


@dataclass(frozen=True)
class Skip:
    """What stands for the skipped rest of one segment.

    Attributes
    ----------
    count : int
        Cycles skipped.
    t_from : float
        Time the skipping starts: the end of the last marched cycle [s].
    dissipation : float
        Energy the skipped cycles dissipate, ``count`` times the last cycle's [J/m].
    """

    count: int
    t_from: float
    dissipation: float


@dataclass(frozen=True)
class SkipState:
    """What the cycle skipper has seen so far; immutable, part of a run's checkpointed state.

    Attributes
    ----------
    previous : dict
        Segment index -> the state at the last cycle end of that segment.
    traces : dict
        Segment index -> (stick edges of the last full cycle, shape (n, 2), or
        None; stick edges of the current cycle so far, a tuple of pairs). Only
        kept when the solver states a cycle tolerance.
    skipped : dict
        Segment index -> :class:`Skip`.
    """

    previous: Mapping = field(default_factory=dict)
    traces: Mapping = field(default_factory=dict)
    skipped: Mapping = field(default_factory=dict)

    @property
    def total(self) -> int:
        return sum(skip.count for skip in self.skipped.values())

    def to_tree(self) -> dict:
        """Pure data for the checkpoint (``io.encode_tree``)."""
        return {
            "previous": dict(self.previous),
            "skipped": {k: [s.count, float(s.t_from), float(s.dissipation)] for k, s in self.skipped.items()},
            "traces": {k: {"previous": prev, "current": np.asarray(cur, float).reshape(-1, 2)}
                       for k, (prev, cur) in self.traces.items()},
        }

    @classmethod
    def from_tree(cls, tree: Mapping) -> "SkipState":
        """Inverse of :meth:`to_tree` (a checkpoint read back)."""
        skipped = {}
        for k, v in tree["skipped"].items():
            count, t_from, dissipation = v
            skipped[int(k)] = Skip(int(count), float(t_from), float(dissipation))
        traces = {int(k): (v["previous"], tuple(tuple(float(e) for e in r) for r in np.asarray(v["current"], float)))
                  for k, v in tree.get("traces", {}).items()}
        return cls(dict(tree["previous"]), traces, skipped)


class CycleSkipper:
    """Stops marching a ``cycles`` segment once its cycle repeats.

    After each full cycle the state is compared (``solver.same_state``, to the
    solver's tolerance) with the state one cycle earlier. When they agree the
    remaining cycles are skipped: the run goes on from the segment's end with
    the repeated state, its dissipation grown by the remaining cycles times
    the dissipation of the last cycle -- exact, since every cycle from then
    on is the same. Every cycle of a segment is sampled bit-identically, so
    the state at the segment's end is the state at the end of any steady cycle.

    The skipper itself is fixed for a history; what it has seen is a
    :class:`SkipState` that :meth:`observe` and :meth:`check` return anew.
    """

    def __init__(self, history, solver):
        self.same = solver.same_state
        # a solver whose states agree only to a tolerance also asks that the cycle's stick
        # edges repeat, step by step, to ``cycle_tolerance(state)`` [m]: a difference that
        # the memory at the cycle's end hides (a slip zone that reached less far at a peak
        # in a narrow strip) shows there
        self.tolerance = solver.cycle_tolerance
        self.ends = {}  # step index of a cycle end -> (segment index, segment)
        self.segment_of = []  # (start, stop, segment index) of the cycles segments
        for k, seg in enumerate(history.segments):
            if seg.kind == "cycles" and seg.count and seg.count > 2:
                for j in range(1, seg.count):
                    self.ends[seg.start + j * seg.steps_per_cycle] = (k, seg)
                self.segment_of.append((seg.start, seg.stop, k))
        self._sorted_ends = np.array(sorted(self.ends), dtype=np.int64)
        self.t = history.t

    def observe(self, skip: SkipState, i: int, state: ContactState) -> SkipState:
        """Record the stick edges of step i (only when the solver states a cycle tolerance)."""
        if self.tolerance is None:
            return skip
        for start, stop, k in self.segment_of:
            if start < i <= stop:
                previous, current = skip.traces.get(k, (None, ()))
                traces = {**skip.traces, k: (previous, current + ((state.stick_left, state.stick_right),))}
                return dataclasses.replace(skip, traces=traces)
        return skip

    def next_end(self, i: int) -> int:
        """The first cycle end after step i (a large number when there is none)."""
        k = int(np.searchsorted(self._sorted_ends, i, side="right"))
        return int(self._sorted_ends[k]) if k < len(self._sorted_ends) else 1 << 62

    def check(self, skip: SkipState, i: int, state: ContactState):
        """``(skip state, jump)`` after step i; jump is None or (new index, new state) at the segment's end."""
        if i not in self.ends:
            return skip, None
        k, seg = self.ends[i]
        prev = skip.previous.get(k)
        repeats = True
        traces = skip.traces
        if self.tolerance is not None:
            last, current = traces.get(k, (None, ()))
            cur = np.asarray(current, dtype=float).reshape(-1, 2)
            traces = {**traces, k: (cur, ())}
            if last is None or last.shape != cur.shape:
                repeats = False
            else:
                both_nan = np.isnan(last) & np.isnan(cur)
                diff = np.where(both_nan, 0.0, np.abs(last - cur))
                repeats = bool(np.all(diff <= self.tolerance(state)))  # NaN against a number fails
        skip = dataclasses.replace(skip, previous={**skip.previous, k: state}, traces=traces)
        if prev is None or not repeats or not self.same(prev, state):
            return skip, None
        remaining = (seg.stop - i) // seg.steps_per_cycle
        added = remaining * (state.dissipation - prev.dissipation)
        skip = dataclasses.replace(skip, skipped={**skip.skipped, k: Skip(remaining, float(state.t), added)})
        new = dataclasses.replace(state, t=float(self.t[seg.stop]), dissipation=state.dissipation + added)
        return skip, (seg.stop, new)


# ---------------------------------------------------------------------------
# the segment table of a result


SEGMENT_KINDS = (*HISTORY_SEGMENT_KINDS, "arrays")
"""The codes of ``segment_kind`` (flag_values 0..4, flag_meanings in this order)."""

SEGMENT_VARIABLES = variables.SEGMENT
"""The variables over the ``segment`` dimension of a result: name -> (units, long_name)."""


def segment_table(history, skip: SkipState | None) -> dict:
    """The ``segment`` variables of a result, as ``{name: (dims, values, attrs)}``."""
    segments = history.segments
    skipped = {} if skip is None else skip.skipped
    none = Skip(0, float("nan"), 0.0)
    cyc = [s.kind == "cycles" for s in segments]
    values = {
        "segment_kind": np.array([SEGMENT_KINDS.index(s.kind) for s in segments], np.int8),
        "segment_first_step": np.array([s.start for s in segments], np.int64),
        "segment_last_step": np.array([s.stop for s in segments], np.int64),
        "segment_t_start": np.array([s.t_start for s in segments], float),
        "segment_t_stop": np.array([s.t_stop for s in segments], float),
        "segment_period": np.array([s.period if c else np.nan for s, c in zip(segments, cyc)], float),
        "segment_cycle_count": np.array([s.count if c else 0 for s, c in zip(segments, cyc)], np.int64),
        "segment_steps_per_cycle": np.array([s.steps_per_cycle if c else 0 for s, c in zip(segments, cyc)], np.int64),
        "segment_cycles_skipped": np.array([skipped.get(k, none).count for k in range(len(segments))], np.int64),
        "segment_skip_t_start": np.array([skipped.get(k, none).t_from for k in range(len(segments))], float),
        "segment_skip_dissipation": np.array([skipped.get(k, none).dissipation for k in range(len(segments))], float),
    }
    table = {name: (SEGMENT_DIM, array, variables.attrs(name)) for name, array in values.items()}
    table["segment_kind"][2].update(flag_values=np.arange(len(SEGMENT_KINDS), dtype=np.int8),
                                    flag_meanings=" ".join(SEGMENT_KINDS))
    return table


def describe_skips(skip: SkipState | None) -> str:
    """``'loads[1]: 18'``: the skipped cycles per segment, for people (attribute ``skipped_cycles_per_segment``)."""
    if skip is None:
        return ""
    return ", ".join(f"loads[{k}]: {s.count}" for k, s in sorted(skip.skipped.items()))


@dataclass(frozen=True)
class Segments:
    """The segment table of a result, read back (arrays over the segments)."""

    kind: np.ndarray
    first_step: np.ndarray
    last_step: np.ndarray
    t_start: np.ndarray
    t_stop: np.ndarray
    period: np.ndarray
    cycle_count: np.ndarray
    steps_per_cycle: np.ndarray
    cycles_skipped: np.ndarray
    skip_t_start: np.ndarray
    skip_dissipation: np.ndarray

    def __len__(self) -> int:
        return len(self.kind)

    def cycles(self) -> list[int]:
        """Indices of the ``cycles`` segments."""
        return [k for k in range(len(self)) if self.kind[k] == "cycles"]

    def skipped_stretches(self) -> list[tuple[int, float, float, int]]:
        """(segment, time the skip starts, segment end, cycles skipped) of every skip."""
        return [(k, float(self.skip_t_start[k]), float(self.t_stop[k]), int(self.cycles_skipped[k]))
                for k in range(len(self)) if self.cycles_skipped[k] > 0]


    def marched_time(self, t: float) -> float:
        """The marched time whose state stands for time t: inside a skipped stretch, the same phase of
        the last marched cycle (the skipped cycles repeat it); elsewhere t itself."""
        for k, t_from, t_to, _count in self.skipped_stretches():
            period = float(self.period[k])
            if t_from < t <= t_to + 1e-9 * period:
                phase = (t - t_from) % period
                if phase <= 1e-9 * period or period - phase <= 1e-9 * period:
                    return t_from  # a cycle end: the state that ends the last marched cycle
                return t_from - period + phase
        return t


def has_segments(ds: xr.Dataset) -> bool:
    return "segment_kind" in ds.variables


def read_segments(ds: xr.Dataset) -> Segments:
    """The segment table of a result (:class:`Segments`); a result without one is refused in one line."""
    if not has_segments(ds):
        raise HalfslipInputError(OLD_RESULT_MESSAGE)
    columns = {f.name: np.asarray(ds[f"segment_{f.name}"].values) for f in dataclasses.fields(Segments)}
    codes = columns["kind"].astype(np.int64)
    if np.any((codes < 0) | (codes >= len(SEGMENT_KINDS))):
        raise HalfslipInputError("the result's segment_kind holds an unknown code")
    columns["kind"] = np.array([SEGMENT_KINDS[c] for c in codes], dtype=object)
    return Segments(**columns)


# ---------------------------------------------------------------------------
# windows of full cycles


@dataclass(frozen=True)
class Window:
    """One cycle as a time window; ``repeats`` = 1 + the cycles skipped as repeats of it."""

    t_start: float
    t_stop: float
    segment: int
    repeats: int = 1


def scene_windows(segments: Segments) -> list[Window]:
    """Every marched cycle of the history's ``cycles`` segments, in order (skipped cycles left out)."""
    windows = []
    for k in segments.cycles():
        period = float(segments.period[k])
        marched = int(segments.cycle_count[k]) - int(segments.cycles_skipped[k])
        for c in range(marched):
            t0 = float(segments.t_start[k]) + c * period
            repeats = 1 + int(segments.cycles_skipped[k]) if c == marched - 1 else 1
            windows.append(Window(t0, t0 + period, k, repeats))
    return windows


def repeats_at(t: np.ndarray, segments: Segments) -> np.ndarray:
    """Per stored step: k + 1 at the last marched step of a segment whose last k cycles were skipped, else 1."""
    repeats = np.ones(t.size, np.int64)
    for k, t_from, _t_to, count in segments.skipped_stretches():
        at = np.flatnonzero(np.abs(t - t_from) <= TIME_TOLERANCE * float(segments.period[k]))
        if at.size:
            repeats[at[0]] = count + 1
    return repeats


def period_windows(t: np.ndarray, period: float, start: float | None) -> list[Window]:
    """Windows of a user-given `period` [s]: from `start`, or whole periods counted back from the last stored step."""
    if not np.isfinite(period) or period <= 0:
        raise HalfslipInputError(f"the period must be a positive number of seconds, got {period!r}")
    tol = TIME_TOLERANCE * period
    if start is None:  # whole periods counted back from the last stored step
        count = int(np.floor((t[-1] - t[0]) / period + TIME_TOLERANCE))
        first = t[-1] - count * period
    else:
        first = float(start)
        count = int(np.floor((t[-1] - first) / period + TIME_TOLERANCE))
    return [Window(first + k * period, first + (k + 1) * period, -1) for k in range(count) if first + k * period >= t[0] - tol]


def stored_windows(ds: xr.Dataset, period: float | None = None, start: float | None = None) -> list[tuple]:
    """The cycles whose steps are stored: rows (t_start, t_stop, i_start, i_stop, segment, aligned, repeats).

    Scene cycles (``period`` None) come from the segment table; a user
    ``period`` cuts the stored time range instead (:func:`period_windows`).
    Windows are mapped onto the stored steps by time; see
    :func:`halfslip.post.cycles` for the rules.
    """
    t = np.asarray(ds["t"].values, float)
    if period is None:
        segments = read_segments(ds)
        windows, spacing = scene_windows(segments), storage_spacing(ds, segments)
        repeats = None
    else:
        windows, spacing = period_windows(t, float(period), start), {}
        repeats = repeats_at(t, read_segments(ds)) if has_segments(ds) else np.ones(t.size, np.int64)
    rows = []
    for window in windows:
        length = window.t_stop - window.t_start
        tol = TIME_TOLERANCE * length
        if window.t_start < t[0] - tol or window.t_stop > t[-1] + tol:
            continue  # not (wholly) stored: unfinished or before the record
        i0 = int(np.argmin(np.abs(t - window.t_start)))
        i1 = int(np.argmin(np.abs(t - window.t_stop)))
        if i1 <= i0:
            continue
        # a scene cycle is stored when no gap exceeds its storage interval; a user window, when
        # no gap exceeds half the window (skipped cycles are never stored steps)
        gap_limit = (spacing.get(window.segment, 0.0) if period is None else 0.5 * length) * (1 + 1e-6) + tol
        inside = t[i0 : i1 + 1]
        ends = (abs(inside[0] - window.t_start), abs(inside[-1] - window.t_stop))
        if max(np.max(np.diff(inside)), 2 * max(ends)) > gap_limit:
            continue  # steps missing (not stored)
        aligned = max(ends) <= tol
        count = window.repeats if repeats is None else int(repeats[i1])
        rows.append((window.t_start, window.t_stop, i0, i1, window.segment, int(aligned), count))
    return rows


def storage_spacing(ds: xr.Dataset, segments: Segments) -> dict[int, float]:
    """Segment index -> the regular gap between stored steps of each cycles segment [s]."""
    every = int(ds.attrs.get("output_every", 1))
    return {k: every * float(segments.period[k]) / int(segments.steps_per_cycle[k]) for k in segments.cycles()}


# ---------------------------------------------------------------------------
# per-cycle quantities


def stick_intersection(stick_left: np.ndarray, stick_right: np.ndarray) -> tuple[float, float]:
    """The permanent stick zone of a window: the intersection of its stick zones.

    (NaN, NaN) when some instant has no stick zone or the intersection is empty.
    """
    stick_left, stick_right = np.asarray(stick_left, float), np.asarray(stick_right, float)
    if stick_left.size == 0 or not (np.all(np.isfinite(stick_left)) and np.all(np.isfinite(stick_right))):
        return float("nan"), float("nan")
    left, right = float(np.max(stick_left)), float(np.min(stick_right))
    if left > right:
        return float("nan"), float("nan")
    return left, right


def window_regime(regime: np.ndarray) -> int:
    """One regime for a window of steps (its first step is where it starts, so it does not count).

    Gross sliding if any step slides, full stick if every step sticks,
    separated if every step is out of contact, else partial slip.
    """
    regime = np.asarray(regime)
    steps = regime[1:] if regime.size > 1 else regime
    if np.any(steps == 3):
        return 3
    if np.all(steps == 1):
        return 1
    if np.all(steps == 0):
        return 0
    return 2

