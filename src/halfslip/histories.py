"""Load histories: the trajectory of (P, Q, M, sigma) over time.

A history is a chain of segments, each starting where the previous one ended,
from the unloaded state at t = 0. It is sampled once, when built, into the
points the marching solvers step between: point 0 is the initial state
(t = 0, all loads 0) and step k goes in a straight line from point k - 1 to
point k. :meth:`LoadHistory.evaluate` returns the exact segment functions at
any time (linear for ramp, hold and tables, the harmonic for cycles).

Segment kinds (the ``loads`` list of a scene, see docs/interface.md):

``ramp: {to: {P, Q, M, sigma}, duration, steps=1}``
    Straight line from the current values to ``to``; unnamed loads hold.
``hold: {duration, steps=1}``
    All loads constant.
``cycles: {count, period, steps_per_cycle=64, P/Q/M/sigma: {mean, amplitude, phase}}``
    X(t) = mean + amplitude sin(2 pi (t - t0) / period + phase), phase in
    degrees; mean defaults to the current value, amplitude and phase to 0.
    Sampled at t0 + k period / steps_per_cycle, k = 1 .. count steps_per_cycle,
    so every cycle has bit-identical samples. Where the harmonic at t0 differs
    from the current value the first step bridges the jump with a straight
    line (:meth:`LoadHistory.jumps` lists them).
``table: {file: loads.csv}`` or ``table: {t: [...], P: [...], ...}``
    Columns t, P, Q, M, sigma; absent load columns hold. Times are offsets
    from the segment start and increase strictly. A first time > 0 is reached
    by a straight line from the current values; a first time == 0 is allowed
    only when its values equal the current ones (the row is then dropped).
"""
from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from . import limits
from .errors import (
    HalfslipInputError,
    check_count,
    check_list,
    check_mapping,
    check_number,
    check_string,
    excerpt,
    join,
    suggest,
)
from .io import PATH_CHARS, read_input_text
from .state import frozen

LOADS = ("P", "Q", "M", "sigma")
"""Names of the four loads, in the order used everywhere."""

SEGMENT_KINDS = ("ramp", "hold", "cycles", "table")
"""Segment kinds of a scene's ``loads`` list."""

DEFAULT_STEPS_PER_CYCLE = 64

_RELATIVE_TOLERANCE = 1e-9

MAX_STEPS = 20_000_000
"""Most sampled steps a history may have (five float arrays of this length: 0.8 GB)."""


@dataclass(frozen=True)
class Harmonic:
    """One load's harmonic in a ``cycles`` segment.

    X(tau) = mean + amplitude sin(2 pi tau + phase), tau = (t - t0) / period.

    Attributes
    ----------
    mean, amplitude : float
        In the load's SI unit.
    phase : float
        Phase angle in radians (the scene gives degrees).
    """

    mean: float
    amplitude: float
    phase: float

    def value(self, tau: ArrayLike) -> np.ndarray:
        """Return the load at cycle coordinate(s) `tau` = (t - t0) / period."""
        return self.mean + self.amplitude * np.sin(2.0 * np.pi * np.asarray(tau, dtype=float) + self.phase)


@dataclass(frozen=True)
class Segment:
    """One segment of a :class:`LoadHistory`, located in the sampled arrays.

    Attributes
    ----------
    kind : str
        ``'ramp'``, ``'hold'``, ``'cycles'``, ``'table'`` or ``'arrays'``
        (a history given as arrays).
    start, stop : int
        The segment covers sampled points ``start .. stop`` inclusive; point
        `start` is where it begins, i.e. where the previous segment ended.
    t_start, t_stop : float
        Times of points `start` and `stop` [s].
    period : float or None
        Cycle period [s] (cycles only).
    count : int or None
        Number of cycles (cycles only).
    steps_per_cycle : int or None
        Sampled steps per cycle (cycles only).
    harmonics : Mapping[str, Harmonic] or None
        For cycles, the harmonic of each of P, Q, M, sigma (loads not named
        in the scene have amplitude 0 about their current value).
    source : str or None
        The CSV file a table was read from.
    line : int or None
        Line of the segment in the scene file.
    """

    kind: str
    start: int
    stop: int
    t_start: float
    t_stop: float
    period: float | None = None
    count: int | None = None
    steps_per_cycle: int | None = None
    harmonics: Mapping[str, Harmonic] | None = None
    source: str | None = None
    line: int | None = None

    @property
    def steps(self) -> int:
        """Number of steps in the segment."""
        return self.stop - self.start


@dataclass(frozen=True)
class Jump:
    """A load that jumps at the start of a cycles segment.

    The harmonic at the segment start differs from the value the previous
    segment ended with; the first step of the segment bridges the two with a
    straight line.
    """

    segment: int
    load: str
    t: float
    before: float
    after: float


class LoadHistory:
    """An immutable, sampled load history.

    Parameters
    ----------
    t : array_like, shape (n_steps + 1,)
        Strictly increasing sample times, ``t[0] == 0`` [s].
    loads : Mapping[str, array_like]
        Samples of P, Q, M, sigma, each shape (n_steps + 1,), 0 at point 0;
        absent loads are 0 throughout.
    segments : sequence of Segment
        Contiguous segments covering points 0 .. n_steps.

    Notes
    -----
    Build histories with :meth:`from_segments` or :meth:`from_arrays`; the
    constructor only checks consistency. All arrays are read-only.
    """

    __slots__ = ("_t", "_loads", "_segments", "_jumps")

    def __init__(self, t: ArrayLike, loads: Mapping[str, ArrayLike], segments: Sequence[Segment]) -> None:
        times = _frozen(t)
        if times.ndim != 1 or times.size < 2:
            raise ValueError("t must be 1-D with at least two points")
        if times[0] != 0.0 or not np.all(np.diff(times) > 0):
            raise ValueError("t must start at 0 and increase strictly")
        unknown = set(loads) - set(LOADS)
        if unknown:
            raise ValueError(f"unknown loads {sorted(unknown)}; expected {LOADS}")
        arrays = {}
        for name in LOADS:
            values = _frozen(loads[name]) if name in loads else _frozen(np.zeros_like(times))
            if values.shape != times.shape:
                raise ValueError(f"{name} has shape {values.shape}, t has {times.shape}")
            if values[0] != 0.0:
                raise ValueError(f"{name} must be 0 at t = 0 (the unloaded initial state)")
            arrays[name] = values
        segments = tuple(segments)
        ends = [0] + [segment.stop for segment in segments]
        if [segment.start for segment in segments] != ends[:-1] or ends[-1] != times.size - 1:
            raise ValueError("segments must be contiguous and cover every sampled point")
        self._t = times
        self._loads = arrays
        self._segments = segments
        self._jumps = _find_jumps(times, arrays, segments)

    # -- constructors -----------------------------------------------------

    @classmethod
    def from_segments(
        cls,
        segments: Sequence[Mapping[str, Any]],
        *,
        base_dir: str | os.PathLike | None = None,
        lines: Sequence[int | None] | None = None,
    ) -> LoadHistory:
        """Build a history from segment specifications.

        Parameters
        ----------
        segments : sequence of mapping
            The ``loads`` list of a scene: each item a one-key mapping such
            as ``{'ramp': {'to': {'P': 1e5}, 'duration': 1.0, 'steps': 20}}``
            (see the module docstring).
        base_dir : path, optional
            Directory that relative table files are resolved against
            (default: the working directory).
        lines : sequence of int or None, optional
            Scene line of each segment, kept in :attr:`Segment.line`.

        Raises
        ------
        HalfslipInputError
            With the field path (``loads[1].cycles.Q.amplitude``) of the bad
            value; for CSV content also the CSV file and its line.
        """
        specs = check_list(segments, "loads")
        if not specs:
            raise HalfslipInputError("needs at least one segment", field="loads")
        builder = _Builder()
        base = Path(base_dir) if base_dir is not None else Path.cwd()
        for index, spec in enumerate(specs):
            field = f"loads[{index}]"
            if not isinstance(spec, Mapping) or len(spec) != 1:
                kinds = ", ".join(SEGMENT_KINDS)
                if isinstance(spec, Mapping) and len(spec) > 1:
                    message = f"a segment has exactly one kind ({kinds}); got {', '.join(map(str, spec))}"
                else:
                    message = f"expected a mapping with one key, one of {kinds}"
                raise HalfslipInputError(message, field=field)
            ((kind, body),) = spec.items()
            if kind not in SEGMENT_KINDS:
                raise HalfslipInputError(
                    f"unknown segment kind {excerpt(kind)}{suggest(kind, SEGMENT_KINDS)}", field=join(field, str(kind))
                )
            line = lines[index] if lines is not None else None
            field = join(field, kind)
            if kind == "ramp":
                builder.ramp(body, field, line)
            elif kind == "hold":
                builder.hold(body, field, line)
            elif kind == "cycles":
                builder.cycles(body, field, line)
            else:
                builder.table(_table_from_spec(body, field, base), field, "table", line)
        return builder.build(cls)

    @classmethod
    def from_arrays(
        cls,
        t: ArrayLike,
        P: ArrayLike,
        Q: ArrayLike,
        M: ArrayLike | None = None,
        sigma: ArrayLike | None = None,
    ) -> LoadHistory:
        """Build a history from sampled arrays (a single segment of kind 'arrays').

        Parameters
        ----------
        t : array_like, shape (n,)
            Strictly increasing times, ``t[0] >= 0`` [s].
        P, Q : array_like, shape (n,)
            Normal and shear load [N/m].
        M, sigma : array_like, shape (n,), optional
            Moment [N] and bulk tension [Pa]; 0 when absent.

        Returns
        -------
        LoadHistory

        Raises
        ------
        HalfslipInputError
            For non-finite values, unequal lengths or times that do not
            increase; the field names the array and the row (``t[3]``).

        Notes
        -----
        The history always starts unloaded at t = 0. When ``t[0] > 0`` that
        state is prepended and the first step is a straight line from it;
        when ``t[0] == 0`` the loads given there must all be 0.
        """
        columns = {"t": t, "P": P, "Q": Q, "M": M, "sigma": sigma}
        table = _inline_table({name: values for name, values in columns.items() if values is not None}, "")
        builder = _Builder()
        builder.table(table, "", "arrays", None)
        return builder.build(cls)

    # -- the samples ------------------------------------------------------

    @property
    def t(self) -> np.ndarray:
        """Sample times, shape (n_steps + 1,) [s]."""
        return self._t

    @property
    def P(self) -> np.ndarray:
        """Normal load at the samples, shape (n_steps + 1,) [N/m]."""
        return self._loads["P"]

    @property
    def Q(self) -> np.ndarray:
        """Shear load at the samples, shape (n_steps + 1,) [N/m]."""
        return self._loads["Q"]

    @property
    def M(self) -> np.ndarray:
        """Moment at the samples, shape (n_steps + 1,) [N]."""
        return self._loads["M"]

    @property
    def sigma(self) -> np.ndarray:
        """Differential bulk tension at the samples, shape (n_steps + 1,) [Pa]."""
        return self._loads["sigma"]

    @property
    def segments(self) -> tuple[Segment, ...]:
        """The segments, in order."""
        return self._segments

    @property
    def n_steps(self) -> int:
        """Number of steps (samples less the initial point)."""
        return self._t.size - 1

    @property
    def step_times(self) -> np.ndarray:
        """End time of each step, ``t[1:]``, shape (n_steps,) [s]."""
        return self._t[1:]

    @property
    def duration(self) -> float:
        """Time of the last sample [s]."""
        return float(self._t[-1])

    def loads(self) -> dict[str, np.ndarray]:
        """Return the sampled loads as a dict ``{'P', 'Q', 'M', 'sigma'}``."""
        return dict(self._loads)

    # -- derived ----------------------------------------------------------

    def evaluate(self, t: ArrayLike) -> dict[str, np.ndarray]:
        """Return the loads at arbitrary times.

        Parameters
        ----------
        t : array_like
            Times in ``[0, duration]`` [s], any shape.

        Returns
        -------
        dict of str to ndarray
            ``{'P', 'Q', 'M', 'sigma'}``, each of the shape of `t`: linear
            between samples in ramp, hold and table segments, the harmonic in
            cycles segments (the bridging first step of a jump is linear).

        Raises
        ------
        ValueError
            If a time lies outside the history.
        """
        times = np.asarray(t, dtype=float)
        flat = np.atleast_1d(times).ravel()
        slack = 1e-12 * self.duration
        if np.any(~((flat >= -slack) & (flat <= self.duration + slack))):
            raise ValueError(f"times must lie in [0, {self.duration:g}] s")
        values = {name: np.interp(flat, self._t, samples) for name, samples in self._loads.items()}
        jumped = {(jump.segment, jump.load) for jump in self._jumps}
        for index, segment in enumerate(self._segments):
            if segment.kind != "cycles":
                continue
            for name, harmonic in segment.harmonics.items():
                begin = self._t[segment.start + 1] if (index, name) in jumped else segment.t_start
                inside = (flat > begin) & (flat <= segment.t_stop)
                values[name][inside] = harmonic.value((flat[inside] - segment.t_start) / segment.period)
        return {name: array.reshape(times.shape) for name, array in values.items()}

    def jumps(self) -> tuple[Jump, ...]:
        """Loads whose cycles harmonic starts away from the current value."""
        return self._jumps

    def ranges(self) -> dict[str, tuple[float, float]]:
        """Return ``{load: (min, max)}`` over the sampled points."""
        return {name: (float(values.min()), float(values.max())) for name, values in self._loads.items()}

    def max_shear_ratio(self, friction: float) -> float:
        """Largest ``|Q| / (f P)`` over the sampled points with P > 0.

        Parameters
        ----------
        friction : float
            Coulomb coefficient f >= 0.

        Returns
        -------
        float
            ``inf`` when |Q| > 0 at a point with P <= 0 (or with f = 0);
            values >= 1 mean gross sliding somewhere.
        """
        P, shear = self.P, np.abs(self.Q)
        if np.any((P <= 0) & (shear > 0)):
            return math.inf
        loaded = P > 0
        if not np.any(shear[loaded] > 0):
            return 0.0
        if friction == 0:
            return math.inf
        return float(np.max(shear[loaded] / (friction * P[loaded])))

    def __repr__(self) -> str:
        kinds = ", ".join(segment.kind for segment in self._segments)
        return f"LoadHistory(n_steps={self.n_steps}, duration={self.duration:g}, segments=[{kinds}])"


# -- building -------------------------------------------------------------


@dataclass(frozen=True)
class _Table:
    """Columns of a table segment and where each row came from.

    `file` and `row_lines` are set for CSV tables; inline rows are located by
    their index in the field path instead.
    """

    t: np.ndarray
    columns: Mapping[str, np.ndarray]
    file: str | None = None
    row_lines: Sequence[int] | None = None

    def error(self, message: str, field: str, column: str, row: int) -> HalfslipInputError:
        """Return an error located at `row` of `column`."""
        if self.file is None:
            return HalfslipInputError(message, field=f"{join(field, column)}[{row}]")
        return HalfslipInputError(message, file=self.file, line=self.row_lines[row], field=join(field, column))


class _Builder:
    """Accumulates sampled points and segments while a history is parsed."""

    def __init__(self) -> None:
        self.times: list[np.ndarray] = [np.zeros(1)]
        self.values: dict[str, list[np.ndarray]] = {name: [np.zeros(1)] for name in LOADS}
        self.current = dict.fromkeys(LOADS, 0.0)
        self.scale = dict.fromkeys(LOADS, 0.0)
        self.t_now = 0.0
        self.index = 0
        self.segments: list[Segment] = []

    def append(self, t: np.ndarray, values: Mapping[str, np.ndarray], field: str | None = None,
               **segment: Any) -> None:
        """Append sampled points (not including the current one) as one segment.

        Times that overflow or that rounding makes equal (a duration far below
        the current time's resolution) are refused, naming ``field``.
        """
        if not (np.all(np.isfinite(t)) and t[0] > self.t_now and np.all(np.diff(t) > 0)):
            raise HalfslipInputError(
                f"the segment's times, from t = {self.t_now:g} s, do not increase strictly in floating point "
                "(a duration or period too large, or too small for the current time)",
                field=field,
            )
        self.times.append(t)
        for name in LOADS:
            samples = np.broadcast_to(values.get(name, self.current[name]), t.shape).astype(float)
            self.values[name].append(samples)
            self.current[name] = float(samples[-1])
            self.scale[name] = max(self.scale[name], float(np.max(np.abs(samples))))
        self.segments.append(
            Segment(
                start=self.index,
                stop=self.index + t.size,
                t_start=self.t_now,
                t_stop=float(t[-1]),
                **segment,
            )
        )
        self.index += t.size
        self.t_now = float(t[-1])

    def reserve(self, steps: int, field: str) -> None:
        """Refuse a history longer than MAX_STEPS before allocating it."""
        if self.index + steps > MAX_STEPS:
            raise HalfslipInputError(
                f"the history would have {self.index + steps:,} steps; at most {MAX_STEPS:,} are supported "
                "(use fewer steps per segment, or rely on skip_steady_cycles with fewer cycles per segment)",
                field=field,
            )

    def ramp(self, body: Any, field: str, line: int | None) -> None:
        """Add a ramp segment from its spec."""
        check_mapping(body, field, ("to", "duration", "steps"), ("to", "duration"))
        targets = check_mapping(body["to"], join(field, "to"), LOADS)
        ends = {name: check_number(value, join(join(field, "to"), name)) for name, value in targets.items()}
        duration = check_number(body["duration"], join(field, "duration"), positive=True)
        steps = check_count(body.get("steps", 1), join(field, "steps"))
        self.reserve(steps, join(field, "steps"))
        fraction = np.arange(1, steps + 1) / steps
        values = {name: self.current[name] * (1.0 - fraction) + end * fraction for name, end in ends.items()}
        with np.errstate(over="ignore"):
            times = self.t_now + duration * fraction
        self.append(times, values, join(field, "duration"), kind="ramp", line=line)

    def hold(self, body: Any, field: str, line: int | None) -> None:
        """Add a hold segment from its spec."""
        check_mapping(body, field, ("duration", "steps"), ("duration",))
        duration = check_number(body["duration"], join(field, "duration"), positive=True)
        steps = check_count(body.get("steps", 1), join(field, "steps"))
        self.reserve(steps, join(field, "steps"))
        fraction = np.arange(1, steps + 1) / steps
        with np.errstate(over="ignore"):
            times = self.t_now + duration * fraction
        self.append(times, {}, join(field, "duration"), kind="hold", line=line)

    def cycles(self, body: Any, field: str, line: int | None) -> None:
        """Add a cycles segment from its spec."""
        check_mapping(body, field, ("count", "period", "steps_per_cycle", *LOADS), ("count", "period"))
        count = check_count(body["count"], join(field, "count"))
        period = check_number(body["period"], join(field, "period"), positive=True)
        per_cycle = check_count(body.get("steps_per_cycle", DEFAULT_STEPS_PER_CYCLE), join(field, "steps_per_cycle"))
        self.reserve(count * per_cycle, join(field, "count"))
        harmonics = {}
        for name in LOADS:
            load_field = join(field, name)
            spec = check_mapping(body.get(name, {}), load_field, ("mean", "amplitude", "phase"))
            harmonics[name] = Harmonic(
                mean=check_number(spec.get("mean", self.current[name]), join(load_field, "mean")),
                amplitude=check_number(spec.get("amplitude", 0.0), join(load_field, "amplitude")),
                phase=math.radians(check_number(spec.get("phase", 0.0), join(load_field, "phase"))),
            )
        k = np.arange(1, count * per_cycle + 1)
        tau = (k % per_cycle) / per_cycle  # bit-identical samples in every cycle
        values = {name: harmonic.value(tau) for name, harmonic in harmonics.items()}
        with np.errstate(over="ignore"):  # overflowing times are refused by append
            times = self.t_now + k * (period / per_cycle)
        self.append(
            times,
            values,
            join(field, "period"),
            kind="cycles",
            period=period,
            count=count,
            steps_per_cycle=per_cycle,
            harmonics=MappingProxyType(harmonics),
            line=line,
        )

    def table(self, table: _Table, field: str, kind: str, line: int | None) -> None:
        """Add a table (or arrays) segment: offsets from the current time."""
        t = table.t
        for row in range(1, t.size):
            if not t[row] > t[row - 1]:
                raise table.error(
                    f"times must increase strictly; {t[row]:g} follows {t[row - 1]:g}", field, "t", row
                )
        if t[0] < 0:
            raise table.error(f"times are offsets from the segment start and must be >= 0; got {t[0]:g}", field, "t", 0)
        rows = slice(None)
        if t[0] == 0:
            for name, values in table.columns.items():
                if not _close(values[0], self.current[name], self.scale[name]):
                    raise table.error(
                        f"at time offset 0 the value must equal the current {name} = {self.current[name]:g}, "
                        f"got {values[0]:g} (start the table at a time > 0 to ramp to it)",
                        field,
                        name,
                        0,
                    )
            if t.size == 1:
                raise table.error("needs a row after time offset 0", field, "t", 0)
            rows = slice(1, None)
        self.append(
            self.t_now + t[rows],
            {name: values[rows] for name, values in table.columns.items()},
            field,
            kind=kind,
            source=table.file,
            line=line,
        )

    def build(self, cls: type[LoadHistory]) -> LoadHistory:
        """Return the finished history."""
        loads = {name: np.concatenate(parts) for name, parts in self.values.items()}
        return cls(np.concatenate(self.times), loads, self.segments)


def _table_from_spec(body: Any, field: str, base: Path) -> _Table:
    """Read a table segment's spec: a CSV file or inline columns."""
    check_mapping(body, field, ("file", "t", *LOADS))
    if "file" in body:
        if len(body) > 1:
            extra = next(key for key in body if key != "file")
            raise HalfslipInputError(
                "give either a file or inline columns, not both", field=join(field, extra)
            )
        path = base / check_string(body["file"], join(field, "file"))
        columns, row_lines = read_csv_columns(path, ("t", *LOADS), ("t",), field)
        return _Table(t=columns.pop("t"), columns=columns, file=str(path), row_lines=row_lines)
    check_mapping(body, field, ("t", *LOADS), ("t",))
    return _inline_table(body, field)


def _inline_table(columns: Mapping[str, Any], field: str) -> _Table:
    """Check inline columns (lists or arrays) of equal length, ``t`` among them."""
    arrays = {name: check_column(values, join(field, name)) for name, values in columns.items()}
    times = arrays.pop("t")
    if times.size == 0:
        raise HalfslipInputError("needs at least one row", field=join(field, "t"))
    for name, values in arrays.items():
        if values.size != times.size:
            raise HalfslipInputError(f"has {values.size} values but t has {times.size}", field=join(field, name))
    return _Table(t=times, columns=arrays)


def check_column(values: Any, field: str) -> np.ndarray:
    """Check a column of numbers and return it as a float array.

    Parameters
    ----------
    values : list, tuple or ndarray
        The column.
    field : str
        Field path of the column; an entry's error names ``{field}[row]``.

    Returns
    -------
    ndarray, shape (len(values),)
    """
    if not isinstance(values, np.ndarray):
        values = check_list(values, field)
    return np.array([check_number(value, f"{field}[{row}]") for row, value in enumerate(values)], dtype=float)


def read_csv_columns(
    path: str | os.PathLike,
    allowed: Sequence[str],
    required: Sequence[str],
    field: str,
    what: str = "table",
    max_rows: int | None = None,
) -> tuple[dict[str, np.ndarray], list[int]]:
    """Read a comma-separated table with a header row of column names.

    Blank lines and lines starting with ``#`` are skipped.

    Parameters
    ----------
    path : path
        The CSV file.
    allowed, required : sequence of str
        Column names that may (must) appear in the header.
    field : str
        Field path of the table in the scene (e.g. ``loads[2].table``); the
        errors name ``{field}.file`` or ``{field}.{column}``.
    what : str
        What the table is ("table", "profile"), for messages.
    max_rows : int, optional
        Most lines the file may have besides the header (default
        :data:`halfslip.limits.MAX_TABLE_ROWS`); the file is read with
        :func:`halfslip.io.read_input_text` within
        :data:`halfslip.limits.MAX_TABLE_BYTES`.

    Returns
    -------
    columns : dict of str to ndarray
        One float array, shape (n_rows,), per column in the header.
    row_lines : list of int
        1-based line of each data row in the file.

    Raises
    ------
    HalfslipInputError
        An unreadable file names the field ``{field}.file`` (the caller adds
        where it was given); bad content names the CSV file and its line.
    """
    path = Path(path)
    file_field = join(field, "file")
    text = read_input_text(path, what, limits.MAX_TABLE_BYTES, field=file_field)
    max_rows = limits.MAX_TABLE_ROWS if max_rows is None else max_rows
    count = text.count("\n") + (not text.endswith("\n"))
    if count > max_rows + 1:  # counted before the text is split: a long file costs no memory
        raise HalfslipInputError(
            f"{what} file {excerpt(str(path), PATH_CHARS)} has {count:,} lines; at most {max_rows:,} rows "
            f"and a header are read (halfslip.limits, docs/interface.md \"Limits\")",
            field=file_field,
        )

    def bad(message: str, line: int, column: str | None = None) -> HalfslipInputError:
        return HalfslipInputError(message, file=str(path), line=line, field=join(field, column) if column else field)

    lines = [
        (number, line.strip())
        for number, line in enumerate(text.splitlines(), start=1)
        if line.strip() and not line.lstrip().startswith("#")
    ]
    if not lines:
        raise bad(f"empty table; expected a header row such as {','.join(allowed)}", 1)
    header_line, header = lines[0]
    names = [name.strip() for name in header.split(",")]
    for name in names:
        if name not in allowed:
            raise bad(
                f"unknown column {excerpt(name)} in the header{suggest(name, allowed)} (columns: {', '.join(allowed)})",
                header_line,
            )
        if names.count(name) > 1:
            raise bad(f"column {excerpt(name)} appears twice in the header", header_line)
    for name in required:
        if name not in names:
            raise bad(f"the header has no column {name!r}", header_line)
    if len(lines) == 1:
        raise bad("the table has a header but no rows", header_line)
    rows = []
    for number, line in lines[1:]:
        cells = [cell.strip() for cell in line.split(",")]
        if len(cells) != len(names):
            raise bad(f"row has {len(cells)} values, the header has {len(names)}", number)
        row = []
        for name, cell in zip(names, cells):
            try:
                row.append(check_number(_parse_cell(cell), ""))
            except HalfslipInputError as error:
                raise bad(error.message, number, name) from None
        rows.append(row)
    data = np.array(rows, dtype=float)
    return {name: data[:, index] for index, name in enumerate(names)}, [number for number, _ in lines[1:]]


# -- helpers --------------------------------------------------------------


def _parse_cell(cell: str) -> float | str:
    """Return a CSV cell as a float, or the text itself when it is no number."""
    try:
        return float(cell)
    except ValueError:
        return cell


def _frozen(values: ArrayLike) -> np.ndarray:
    """Return a read-only float copy of `values`."""
    return frozen(np.array(values, dtype=float))


def _close(a: float, b: float, scale: float) -> bool:
    """Whether `a` and `b` agree to round-off relative to `scale`."""
    return abs(a - b) <= _RELATIVE_TOLERANCE * max(abs(a), abs(b), scale)


def _find_jumps(t: np.ndarray, loads: Mapping[str, np.ndarray], segments: Sequence[Segment]) -> tuple[Jump, ...]:
    """List the loads whose cycles harmonic starts away from the current value."""
    jumps = []
    for index, segment in enumerate(segments):
        if segment.kind != "cycles":
            continue
        for name, harmonic in segment.harmonics.items():
            before = float(loads[name][segment.start])
            after = float(harmonic.value(0.0))
            scale = max(abs(harmonic.mean) + abs(harmonic.amplitude), float(np.max(np.abs(loads[name]))))
            if not _close(before, after, scale):
                jumps.append(Jump(segment=index, load=name, t=float(t[segment.start]), before=before, after=after))
    return tuple(jumps)
