"""Batch parameter sweeps: one scene, many cases, one result dataset.

A sweep file (docs/interface.md, "Sweep file"; docs/sweeps.md) names a base
scene and the fields to change::

    scene: dovetail.yaml
    vary:                                       # a grid: the product of the lists
      loads[1].cycles.Q.amplitude: {linspace: [1.0e4, 6.0e4, 11]}
      loads[1].cycles.sigma.amplitude: [0.0, 1.0e7, 2.0e7, 4.0e7]
    # or instead of vary:  cases: [{friction: 0.5}, {friction: 0.7, geometry.radius: 0.02}]
    # optional:            set: {solver.nodes: 256}    (applied to every case)
    #                      per_cycle: false            (skip the per-cycle marching)

Each case is the base scene's parsed YAML data with the case's values put in
at their paths, dumped and read again with :func:`~halfslip.scene.parse_scene`,
so a case is validated exactly like a scene file. A case whose scene has a
cycles segment with a direct steady-state construction is solved with
:func:`~halfslip.steady.steady_state`; any other case is marched with
:func:`~halfslip.simulator.simulate` and summarised over its last cycle.

The result is one :class:`xarray.Dataset`: for a grid one dimension per varied
path (named by the path, the values as coordinate), for explicit cases a
``case`` dimension with each varied path as a coordinate on it. Its variables
are the per-case summaries (``SUMMARIES``) plus ``done``, a mask of the cases
that have run. While a sweep runs, the whole dataset is rewritten atomically
every few seconds, so an interrupted sweep rerun with the same output file
runs only the cases not yet done; ``sweep_hash`` in the attributes makes sure
it is the same sweep.

Cases run in-process (one worker), in local worker processes
(:class:`concurrent.futures.ProcessPoolExecutor`, the default) or on an
existing ``dask.distributed`` cluster (``scheduler=``). Every case is a
deterministic function of its scene, so all three give identical numbers.
"""
from __future__ import annotations

import contextlib
import copy
import dataclasses
import hashlib
import json
import math
import os
import re
import signal
import sys
import threading
import time
import uuid
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
import yaml

from .errors import (
    HalfslipInputError,
    check_bool,
    check_count,
    check_mapping,
    check_number,
    describe,
    EXCERPT_CHARS,
    excerpt,
    join,
)
from . import limits
from .io import PATH_CHARS, read_input_text
from .scene import _line_of, _read_yaml, parse_scene
from .state import Regime
from .variables import SUMMARY

__all__ = [
    "SUMMARIES",
    "Sweep",
    "is_sweep_result",
    "load_sweep",
    "parse_sweep",
    "plot_sweep",
    "sweep",
]

SUMMARIES: dict[str, tuple[str, str]] = {name: SUMMARY[name] for name in (
    "permanent_stick_left", "permanent_stick_right", "peak_slip_amplitude", "dissipation_per_cycle", "regime",
    "status", "run_time", "method", "done")}
"""Per-case variables of a sweep result: name -> (units, long_name)."""

REGIME_NO_RESULT = -1
"""``regime`` of a case that has not run or failed."""

_REGIME_FLAGS = np.concatenate([[REGIME_NO_RESULT], Regime.flag_values()]).astype(np.int8)
_REGIME_MEANINGS = "no_result " + Regime.flag_meanings()  # a run's names, and one for no result

NOT_RUN = "not run"
"""``status`` of a case that has not run yet."""

CHECKPOINT_SECONDS = 5.0
"""Default interval between rewrites of the output file while a sweep runs."""

_SWEEP_KEYS = ("scene", "vary", "cases", "set", "per_cycle")
_SPACINGS = ("linspace", "logspace")
_PATH = re.compile(r"[A-Za-z_][A-Za-z0-9_]*(\[\d+\])*(\.[A-Za-z_][A-Za-z0-9_]*(\[\d+\])*)*")
_TOKEN = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)|\[(\d+)\]")

try:  # the C dumper is several times faster; the text it writes is the same YAML
    _Dumper = yaml.CSafeDumper
except AttributeError:  # pragma: no cover - PyYAML built without libyaml
    _Dumper = yaml.SafeDumper


# -- the sweep file ----------------------------------------------------------


@dataclasses.dataclass(frozen=True, eq=False)
class Sweep:
    """A checked sweep: the base scene's data and the values of every case.

    Build it with :func:`load_sweep` or :func:`parse_sweep`; run it with
    :func:`sweep`.

    Attributes
    ----------
    kind : {'grid', 'cases'}
        A product of value lists (``vary``) or an explicit list (``cases``).
    paths : tuple of str
        The varied scene paths; for a grid, in the order of the dimensions.
    axes : tuple of tuple
        For a grid, the values of each path (plain YAML data); empty for cases.
    cases : tuple of dict
        For explicit cases, each case's mapping path -> value; empty for a grid.
    fixed : dict
        Path -> value applied to every case (``set``).
    per_cycle : bool
        Ask :func:`~halfslip.steady.steady_state` for the per-cycle
        quantities (dissipation, slip amplitude), which march two cycles.
    scene_path : pathlib.Path
        The base scene file.
    scene_text : str
        Its text.
    scene_data : Any
        Its parsed YAML data (not to be modified).
    file : pathlib.Path or None
        The sweep file (None for a sweep given as a mapping).
    text : str
        The sweep file's text (or a JSON rendering of the mapping).
    lines : dict
        Field path in the sweep file -> line, for error messages.
    """

    kind: str
    paths: tuple[str, ...]
    axes: tuple[tuple[Any, ...], ...]
    cases: tuple[dict[str, Any], ...]
    fixed: dict[str, Any]
    per_cycle: bool
    scene_path: Path
    scene_text: str
    scene_data: Any
    file: Path | None
    text: str
    lines: dict[str, int]

    @property
    def shape(self) -> tuple[int, ...]:
        """Shape of the result arrays: one axis per path (grid) or (n_cases,)."""
        if self.kind == "grid":
            return tuple(len(values) for values in self.axes)
        return (len(self.cases),)

    @property
    def dims(self) -> tuple[str, ...]:
        """Dimension names of the result arrays."""
        return self.paths if self.kind == "grid" else ("case",)

    @property
    def n_cases(self) -> int:
        """Number of cases."""
        return int(np.prod(self.shape, dtype=np.int64))

    def overrides(self, index: int) -> dict[str, Any]:
        """The values of case `index` (flat, C order for a grid): path -> value."""
        if self.kind == "grid":
            where = np.unravel_index(index, self.shape)
            return {path: values[i] for path, values, i in zip(self.paths, self.axes, where)}
        return dict(self.cases[index])

    @property
    def hash(self) -> str:
        """SHA-256 of what determines the results: scene text, cases, options.

        Comments and layout of the sweep file do not enter; a change of the
        base scene's text, a value, a path or an option does.
        """
        content = {
            "scene": self.scene_text,
            "kind": self.kind,
            "paths": list(self.paths),
            "axes": [list(values) for values in self.axes],
            "cases": [dict(case) for case in self.cases],
            "set": self.fixed,
            "per_cycle": self.per_cycle,
        }
        text = json.dumps(content, sort_keys=True, default=repr)
        return hashlib.sha256(text.encode("utf-8")).hexdigest()

    def case_scene_text(self, index: int) -> str:
        """The YAML text of case `index`'s scene."""
        data = copy.deepcopy(self.scene_data)
        for path, value in {**self.fixed, **self.overrides(index)}.items():
            _set_path(data, path, value)
        if isinstance(data, dict):
            data.setdefault("name", self.scene_path.stem)  # as load_scene would name it
        return yaml.dump(data, Dumper=_Dumper, sort_keys=False, width=1000)

    def case_scene(self, index: int):
        """The :class:`~halfslip.scene.Scene` of case `index`.

        Raises
        ------
        HalfslipInputError
            When the case's values do not make a valid scene; the error names
            the sweep file, the line of the offending value and its field.
        """
        overrides = self.overrides(index)
        try:
            text = self.case_scene_text(index)
            return parse_scene(text, base_dir=self.scene_path.parent)
        except _PathError as error:  # checked when the sweep was built; kept for safety
            raise self._case_error(index, overrides, HalfslipInputError(str(error), field=error.path)) from None
        except HalfslipInputError as error:
            raise self._case_error(index, overrides, error) from None

    # -- locating errors of one case in the sweep file

    def value_field(self, index: int, path: str) -> str:
        """Field path (in the sweep file) of the value that case `index` takes for `path`."""
        if path in self.fixed and path not in self.paths:
            return f"set.{path}"
        if self.kind == "cases":
            return f"cases[{index}].{path}"
        axis = self.paths.index(path)
        i = int(np.unravel_index(index, self.shape)[axis])
        item = f"vary.{path}[{i}]"
        return item if item in self.lines else f"vary.{path}"

    def line_of(self, field: str) -> int | None:
        """Line of a field of the sweep file (or of its nearest recorded ancestor)."""
        return _line_of(field, self.lines)

    def _case_error(self, index: int, overrides: Mapping[str, Any], error: HalfslipInputError) -> HalfslipInputError:
        """Relocate a scene error of case `index` to the sweep file."""
        file = str(self.file) if self.file is not None else None
        related = [path for path in {**self.fixed, **overrides} if _related(path, error.field)]
        if related:
            path = related[0]
            field = self.value_field(index, path)
            if error.field == path and error.file is None:
                message = error.message
            else:
                inner = HalfslipInputError(error.message, file=error.file, field=error.field)
                message = f"{inner}" if error.file is not None else f"in the scene, {inner}"
        else:
            field = f"cases[{index}]" if self.kind == "cases" else "vary"
            values = ", ".join(f"{path} = {_short(_text(value))}" for path, value in overrides.items())
            inner = HalfslipInputError(error.message, file=error.file, field=error.field)
            message = f"case {index} ({values}) makes the scene invalid: {inner}"
        return HalfslipInputError(message, file=file, line=self.line_of(field), field=field)


class _PathError(ValueError):
    """A path that cannot be followed in the scene data."""

    def __init__(self, message: str, path: str):
        super().__init__(message)
        self.path = path


def _related(path: str, field: str | None) -> bool:
    """True when scene field `field` is `path`, inside it, or contains it."""
    if not field:
        return False
    for outer, inner in ((path, field), (field, path)):
        if inner == outer or inner.startswith(outer + ".") or inner.startswith(outer + "["):
            return True
    return False


def _tokens(path: str) -> list[str | int]:
    """``'loads[1].cycles.Q'`` -> ``['loads', 1, 'cycles', 'Q']``."""
    return [key if key else int(index) for key, index in _TOKEN.findall(path)]


def _set_path(data: Any, path: str, value: Any) -> None:
    """Put `value` at `path` in the plain YAML data `data` (in place).

    Missing mapping keys on the way are created (the scene check rejects
    keys a scene does not know); list indices must exist.
    """
    tokens = _tokens(path)
    node = data
    walked = ""
    for position, token in enumerate(tokens):
        last = position == len(tokens) - 1
        if isinstance(token, int):
            if not isinstance(node, list):
                raise _PathError(f"{walked} is {describe(node)}, not a list: cannot take item [{token}]", path)
            if token >= len(node):
                raise _PathError(f"{walked} has {len(node)} items; there is no item [{token}]", path)
            if last:
                node[token] = copy.deepcopy(value)
            else:
                node = node[token]
            walked = f"{walked}[{token}]"
        else:
            if not isinstance(node, dict):
                what = walked or "the scene"
                raise _PathError(f"{what} is {describe(node)}, not a mapping: cannot take field {excerpt(token)}", path)
            if last:
                node[token] = copy.deepcopy(value)
            else:
                if token not in node or node[token] is None:
                    node[token] = {}
                node = node[token]
            walked = join(walked, token)


def _get_path(data: Any, path: str) -> tuple[bool, Any]:
    """(True, value) at `path` in `data`, or (False, None) when absent."""
    node = data
    for token in _tokens(path):
        if isinstance(token, int):
            if not isinstance(node, list) or token >= len(node):
                return False, None
        elif not isinstance(node, dict) or token not in node:
            return False, None
        node = node[token]
    return True, node


def _text(value: Any) -> str:
    """A value as compact YAML flow text (for coordinates and messages)."""
    if isinstance(value, str):
        return value
    if isinstance(value, float):
        return repr(value)
    return json.dumps(value, separators=(", ", ": "), default=repr)


def _short(text: str) -> str:
    """A value's text for a message: whole if short, else an :func:`~halfslip.errors.excerpt`."""
    return text if len(text) <= EXCERPT_CHARS else excerpt(text)


def load_sweep(path: str | os.PathLike) -> Sweep:
    """Read and check a sweep file.

    Parameters
    ----------
    path : path
        The sweep YAML file.

    Returns
    -------
    Sweep

    Raises
    ------
    HalfslipInputError
        For a missing or unreadable file and any bad content, with file, line
        and field.
    """
    path = Path(path)
    return parse_sweep(read_input_text(path, "sweep", limits.MAX_SCENE_BYTES), path=path)


def parse_sweep(
    text: str | Mapping[str, Any],
    path: str | os.PathLike | None = None,
    base_dir: str | os.PathLike | None = None,
) -> Sweep:
    """Build a :class:`Sweep` from YAML text (or from the equivalent mapping).

    Parameters
    ----------
    text : str or Mapping
        The sweep YAML, or its plain data (``{"scene": ..., "vary": {...}}``).
    path : path, optional
        Where the text came from; named in errors.
    base_dir : path, optional
        Directory the scene path is relative to (default: the directory of
        `path`, else the working directory).

    Returns
    -------
    Sweep

    Raises
    ------
    HalfslipInputError
        For bad content (with file, line and field), for a base scene that is
        missing or invalid (with the scene's own file and line), and for a
        varied path that is not a field of the scene.
    """
    path = Path(path) if path is not None else None
    file = str(path) if path is not None else None
    if base_dir is not None:
        base = Path(base_dir)
    else:
        base = path.parent if path is not None else Path.cwd()
    if isinstance(text, Mapping):
        data, lines = copy.deepcopy(dict(text)), {}
        text = json.dumps(data, default=repr)
    else:
        try:
            data, lines = _read_yaml(text)
        except HalfslipInputError as error:
            if "flow mapping" in error.message and "got '['" in error.message:
                error = HalfslipInputError(
                    f"{error.message}; inside {{...}} quote a path that has [i]: "
                    '{"loads[1].cycles.Q.amplitude": 2.0e4}', line=error.line)
            raise error.located(file, None) from None
    try:
        return _build_sweep(data, lines, base, text, path)
    except HalfslipInputError as error:
        if error.file is not None:  # an error of the base scene: keep its own location
            raise
        raise error.located(file, _line_of(error.field, lines)) from None


def _build_sweep(data: Any, lines: dict[str, int], base: Path, text: str, path: Path | None) -> Sweep:
    if data is None:
        raise HalfslipInputError("the sweep file is empty")
    check_mapping(data, "", _SWEEP_KEYS, ("scene",))
    if ("vary" in data) == ("cases" in data):
        if "vary" in data:
            raise HalfslipInputError("give either vary (a grid) or cases (a list), not both", field="cases")
        raise HalfslipInputError("missing: give vary (a grid of values) or cases (a list of cases)", field="vary")
    scene_name = data["scene"]
    if not isinstance(scene_name, str) or not scene_name:
        raise HalfslipInputError(f"expected the path of a scene file, got {describe(scene_name)}", field="scene")
    scene_path = base / scene_name
    if not scene_path.exists():
        raise HalfslipInputError(f"no such scene file {excerpt(str(scene_path), PATH_CHARS)}", field="scene")
    scene_text = read_input_text(scene_path, "scene", limits.MAX_SCENE_BYTES, field="scene")
    parse_scene(scene_text, path=scene_path)  # the base scene must be valid itself (its errors name it)
    scene_data, _ = _read_yaml(scene_text)

    per_cycle = check_bool(data.get("per_cycle", True), "per_cycle")
    fixed = {}
    if "set" in data:
        if not isinstance(data["set"], Mapping) or not data["set"]:
            raise HalfslipInputError(f"expected a mapping path -> value, got {describe(data['set'])}", field="set")
        fixed = {_check_path(key, f"set.{key}"): value for key, value in data["set"].items()}

    if "vary" in data:
        vary = data["vary"]
        if not isinstance(vary, Mapping) or not vary:
            raise HalfslipInputError(
                f"expected a mapping path -> values (a list, or {{linspace: [a, b, n]}}), got {describe(vary)}",
                field="vary",
            )
        paths, axes = [], []
        for key, spec in vary.items():
            field = f"vary.{key}"
            paths.append(_check_path(key, field))
            values = _values(spec, field)
            seen = set()
            for i, value in enumerate(values):
                number = isinstance(value, (int, float)) and not isinstance(value, bool)
                marker = float(value) if number else _text(value)
                if marker in seen:
                    raise HalfslipInputError(f"value {_short(_text(value))} is listed twice", field=f"{field}[{i}]")
                seen.add(marker)
            axes.append(tuple(values))
            cases = math.prod(len(values) for values in axes)  # exact integers: no overflow
            if cases > limits.MAX_SWEEP_CASES:
                raise _too_many_cases(cases, field)
        sweep = Sweep("grid", tuple(paths), tuple(axes), (), fixed, per_cycle, scene_path, scene_text,
                      scene_data, path, text, lines)
    else:
        cases = data["cases"]
        if not isinstance(cases, list) or not cases:
            raise HalfslipInputError(
                f"expected a list of mappings path -> value, got {describe(cases)}", field="cases"
            )
        if len(cases) > limits.MAX_SWEEP_CASES:
            raise _too_many_cases(len(cases), "cases")
        checked, paths = [], {}
        for index, case in enumerate(cases):
            field = f"cases[{index}]"
            if not isinstance(case, Mapping) or not case:
                raise HalfslipInputError(f"expected a mapping path -> value, got {describe(case)}", field=field)
            checked.append({_check_path(key, f"{field}.{key}"): value for key, value in case.items()})
            paths.update(dict.fromkeys(checked[-1]))
        sweep = Sweep("cases", tuple(paths), (), tuple(checked), fixed, per_cycle, scene_path, scene_text,
                      scene_data, path, text, lines)
    _check_overlaps(sweep)
    _check_paths_exist(sweep)
    return sweep


CASE_BYTES = 200
"""Memory of one case in a sweep result: about ten numbers and a status text."""


def _too_many_cases(count: int, field: str) -> HalfslipInputError:
    """The error of a sweep with more than MAX_SWEEP_CASES cases, with its memory estimate."""
    return HalfslipInputError(
        f"the sweep would have {count:,} cases (a result of about {count * CASE_BYTES / 1e9:.3g} GB, and a run "
        f"each); at most {limits.MAX_SWEEP_CASES:,} (halfslip.limits.MAX_SWEEP_CASES)",
        field=field,
    )


def _check_path(key: Any, field: str) -> str:
    if not isinstance(key, str) or not _PATH.fullmatch(key):
        raise HalfslipInputError(
            f"{excerpt(key)} is not a scene path; write fields joined by dots and list items in brackets, "
            "e.g. loads[1].cycles.Q.amplitude",
            field=field,
        )
    return key


def _values(spec: Any, field: str) -> list[Any]:
    """The list of values of one grid axis."""
    if isinstance(spec, list):
        if not spec:
            raise HalfslipInputError("the list of values is empty", field=field)
        return list(spec)
    if isinstance(spec, Mapping) and len(spec) == 1 and next(iter(spec)) in _SPACINGS:
        kind, args = next(iter(spec.items()))
        where = f"{field}.{kind}"
        if not isinstance(args, list) or len(args) != 3:
            got = f"{len(args)} values" if isinstance(args, list) else describe(args)
            raise HalfslipInputError(f"expected [start, stop, count], got {got}", field=where)
        start = check_number(args[0], f"{where}[0]")
        stop = check_number(args[1], f"{where}[1]")
        count = check_count(args[2], f"{where}[2]")
        if count > limits.MAX_SWEEP_CASES:  # before numpy allocates the values
            raise _too_many_cases(count, f"{where}[2]")
        if kind == "linspace":
            return [float(v) for v in np.linspace(start, stop, count)]
        if not (start > 0 and stop > 0):
            raise HalfslipInputError(
                f"logspace takes the end values themselves (like numpy.geomspace), both > 0; got {start:g} and "
                f"{stop:g} (for 10^-3 .. 10^0 write {{logspace: [1.0e-3, 1.0, 4]}})",
                field=where,
            )
        return [float(v) for v in np.geomspace(start, stop, count)]
    raise HalfslipInputError(
        f"expected a list of values, {{linspace: [start, stop, count]}} or {{logspace: [start, stop, count]}}, "
        f"got {describe(spec)}",
        field=field,
    )


def _check_overlaps(sweep: Sweep) -> None:
    every = list(sweep.paths) + [p for p in sweep.fixed if p not in sweep.paths]
    for i, one in enumerate(every):
        for other in every[i + 1:]:
            if _related(one, other):
                raise HalfslipInputError(
                    f"overlaps {excerpt(one)}: one path lies inside the other", field=_first_field(sweep, other)
                )
    for path in sweep.paths:
        if path in sweep.fixed:
            raise HalfslipInputError(f"{excerpt(path)} is both varied and set", field=f"set.{path}")


def _first_field(sweep: Sweep, path: str) -> str:
    """Sweep-file field where `path` first appears."""
    if sweep.kind == "grid" and path in sweep.paths:
        return f"vary.{path}"
    if sweep.kind == "cases":
        for index, case in enumerate(sweep.cases):
            if path in case:
                return f"cases[{index}].{path}"
    return f"set.{path}"


def _check_paths_exist(sweep: Sweep) -> None:
    """Reject paths the scene cannot have (unknown keys, missing list items).

    Each path is tried alone in the base scene with its first value: an
    "unknown key" error on (or above) the path, or a path that cannot be
    followed, is an error of the sweep file. Other errors (a bad value) are
    left to the cases, which record them in ``status``.
    """
    trials = dict(sweep.fixed)
    for path in sweep.paths:
        if sweep.kind == "grid":
            trials.setdefault(path, sweep.axes[sweep.paths.index(path)][0])
        else:
            trials.setdefault(path, next(case[path] for case in sweep.cases if path in case))
    name = sweep.scene_path.name
    for path, value in trials.items():
        data = copy.deepcopy(sweep.scene_data)
        field = _first_field(sweep, path)
        try:
            _set_path(data, path, value)
        except _PathError as error:
            raise HalfslipInputError(f"not a field of the scene {name}: {error}", field=field) from None
        present, _ = _get_path(sweep.scene_data, path)
        if present:
            continue
        try:
            parse_scene(yaml.dump(data, Dumper=_Dumper, sort_keys=False), base_dir=sweep.scene_path.parent)
        except HalfslipInputError as error:
            unknown = error.message.startswith("unknown key") or error.message.startswith("expected a mapping")
            if unknown and _related(path, error.field) and len(error.field or "") <= len(path):
                raise HalfslipInputError(f"not a field of the scene {name}: {error.message}", field=field) from None


# -- one case ------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class CaseResult:
    """What one case produced (returned by a worker to the driver)."""

    index: int
    summaries: dict[str, float]
    status: str
    method: str
    run_time: float
    full: xr.Dataset | None = None


_WORKER_SWEEP: Sweep | None = None


def _init_worker(spec: Sweep) -> None:
    """Initializer of a local worker process: keep the sweep, leave Ctrl-C to the driver."""
    global _WORKER_SWEEP
    _WORKER_SWEEP = spec
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _run_in_worker(index: int, keep_full: bool) -> CaseResult:
    assert _WORKER_SWEEP is not None
    return run_case(_WORKER_SWEEP, index, keep_full=keep_full)


class _CaseInterrupted(Exception):
    """A marching run inside a case was interrupted (its result is partial)."""


def run_case(spec: Sweep, index: int, *, keep_full: bool = False) -> CaseResult:
    """Build and solve case `index` of `spec`; never raises for a failing case.

    Parameters
    ----------
    spec : Sweep
    index : int
        Flat case index (C order over the grid).
    keep_full : bool
        Return the full dataset of the case (for ``cases_dir``).

    Returns
    -------
    CaseResult
        ``status`` is ``'ok'`` or the one-line error; summaries are NaN (and
        ``regime`` -1) for a failed case.

    Raises
    ------
    KeyboardInterrupt
        When interrupted, so that an interrupted case is never recorded.
    """
    started = time.perf_counter()
    method = ""
    try:
        scene = spec.case_scene(index)
        summaries, method, full = solve_case(scene, per_cycle=spec.per_cycle)
        status = "ok"
    except KeyboardInterrupt:
        raise
    except _CaseInterrupted:
        raise KeyboardInterrupt from None
    except Exception as error:  # a failing case is a result, not the end of the sweep
        summaries, full = _empty_summaries(), None
        status = _one_line(error)
    return CaseResult(index, summaries, status, method, time.perf_counter() - started, full if keep_full else None)


def _one_line(error: BaseException) -> str:
    text = str(error) if isinstance(error, HalfslipInputError) else f"{type(error).__name__}: {error}"
    return " ".join(text.split()) or type(error).__name__


def _empty_summaries() -> dict[str, float]:
    return {
        "permanent_stick_left": math.nan,
        "permanent_stick_right": math.nan,
        "peak_slip_amplitude": math.nan,
        "dissipation_per_cycle": math.nan,
        "regime": REGIME_NO_RESULT,
    }


def solve_case(scene, *, per_cycle: bool = True) -> tuple[dict[str, float], str, xr.Dataset]:
    """Summaries of one scene: directly when possible, else by marching.

    Returns
    -------
    summaries : dict
        ``permanent_stick_left``, ``permanent_stick_right``, ``peak_slip_amplitude``,
        ``dissipation_per_cycle``, ``regime``.
    method : str
        ``'steady: <construction>'`` or ``'march: <method>'``.
    full : xarray.Dataset
        The steady-state or the simulation dataset.
    """
    from .steady import steady_state

    if any(segment.kind == "cycles" for segment in scene.history.segments):
        try:
            ds = steady_state(scene, per_cycle=per_cycle)
        except HalfslipInputError:  # no direct construction for these loads: march
            pass
        else:
            summaries = _empty_summaries()
            for name in summaries:
                if name in ds:
                    summaries[name] = float(ds[name]) if name != "regime" else int(ds[name])
            return summaries, f"steady: {ds.attrs['method']}", ds
    return march_case(scene)


def march_case(scene) -> tuple[dict[str, float], str, xr.Dataset]:
    """March `scene` with :func:`~halfslip.simulator.simulate` and summarise its last cycle.

    The last cycle is the last fully stored cycle of the last ``cycles``
    segment (with ``skip_steady_cycles`` the last marched one, which the
    skipped ones repeat), found by :func:`halfslip.post.cycles` from the
    result's segment table. Every step is stored (``output.every = 1``) and
    ``slip`` is added to the stored fields. The permanent stick zone is the
    intersection of the stick zones of that cycle's steps
    (:func:`halfslip.post.permanent_stick`); the regime is gross sliding if
    any step slides, full stick if every step sticks, else partial slip
    (:func:`halfslip.cycles.window_regime`). Without a cycles segment the
    window is the last segment of the history and the per-cycle quantities
    are NaN.
    """
    from . import post
    from .cycles import read_segments, stick_intersection, window_regime
    from .simulator import simulate

    fields = tuple(dict.fromkeys((*scene.output.fields, "slip")))
    scene = dataclasses.replace(scene, output=dataclasses.replace(scene.output, fields=fields, every=1))
    ds = simulate(scene)
    if not ds.attrs.get("complete", 1):
        raise _CaseInterrupted
    segments = read_segments(ds)
    cyclic = segments.cycles()
    summaries = _empty_summaries()
    if cyclic:
        table = post.cycles(ds)
        table = table.isel(cycle=np.flatnonzero(table["segment"].values == cyclic[-1]))
        if not table.sizes["cycle"]:
            raise RuntimeError("the marched result holds no complete cycle of the last cycles segment")
        part = ds.isel(t=slice(int(table["i_start"][-1]), int(table["i_stop"][-1]) + 1))
        summaries["dissipation_per_cycle"] = float(part["dissipation"][-1] - part["dissipation"][0])
        summaries["peak_slip_amplitude"] = float(post.slip_amplitude(part, cycle=None).max())
    else:  # no cycles: the last segment of the history
        steps = ds["step"].values
        part = ds.isel(t=np.flatnonzero((steps >= segments.first_step[-1]) & (steps <= segments.last_step[-1])))
    left, right = stick_intersection(part["stick_left"].values, part["stick_right"].values)
    summaries["permanent_stick_left"], summaries["permanent_stick_right"] = left, right
    summaries["regime"] = window_regime(part["regime"].values)
    return summaries, f"march: {ds.attrs['method']}", ds


# -- the result dataset ------------------------------------------------------


class _Table:
    """Per-case arrays of a sweep, filled as results arrive."""

    def __init__(self, spec: Sweep):
        n = spec.n_cases
        self.spec = spec
        self.values = {name: np.full(n, math.nan) for name in
                       ("permanent_stick_left", "permanent_stick_right", "peak_slip_amplitude",
                        "dissipation_per_cycle", "run_time")}
        self.regime = np.full(n, REGIME_NO_RESULT, dtype=np.int8)
        self.status = np.full(n, NOT_RUN, dtype=object)
        self.method = np.full(n, "", dtype=object)
        self.done = np.zeros(n, dtype=bool)

    def record(self, result: CaseResult) -> None:
        i = result.index
        for name, value in result.summaries.items():
            if name == "regime":
                self.regime[i] = value
            else:
                self.values[name][i] = value
        self.values["run_time"][i] = result.run_time
        self.status[i] = result.status
        self.method[i] = result.method
        self.done[i] = True

    def restore(self, ds: xr.Dataset) -> None:
        """Take over the finished cases of an earlier, interrupted run of the same sweep."""
        done = ds["done"].values.reshape(-1).astype(bool)
        for name, array in self.values.items():
            array[done] = ds[name].values.reshape(-1)[done]
        self.regime[done] = ds["regime"].values.reshape(-1)[done]
        self.status[done] = ds["status"].values.reshape(-1)[done].astype(object)
        self.method[done] = ds["method"].values.reshape(-1)[done].astype(object)
        self.done |= done

    @property
    def failed(self) -> int:
        return int(np.sum(self.done & (self.status != "ok")))

    def dataset(self, attrs: Mapping[str, Any]) -> xr.Dataset:
        spec = self.spec
        shape, dims = spec.shape, spec.dims

        def var(name, array):
            units, long_name = SUMMARIES[name]
            return (dims, array.reshape(shape), {"units": units, "long_name": long_name})

        data = {name: var(name, array) for name, array in self.values.items()}
        data["regime"] = var("regime", self.regime)
        data["regime"][2].update(flag_values=_REGIME_FLAGS, flag_meanings=_REGIME_MEANINGS)
        data["status"] = var("status", self.status)
        data["method"] = var("method", self.method)
        data["done"] = var("done", self.done)
        order = ["permanent_stick_left", "permanent_stick_right", "peak_slip_amplitude", "dissipation_per_cycle",
                 "regime", "status", "run_time", "method", "done"]
        ds = xr.Dataset({name: data[name] for name in order}, coords=_coordinates(spec))
        ds.attrs.update(attrs)
        return ds


def _coordinates(spec: Sweep) -> dict[str, Any]:
    attrs = {"long_name": "varied scene field"}
    if spec.kind == "grid":
        return {
            path: (path, _coordinate_values(list(values)), {**attrs, "units": _units_of(path)})
            for path, values in zip(spec.paths, spec.axes)
        }
    coords: dict[str, Any] = {"case": ("case", np.arange(spec.n_cases), {"long_name": "case number", "units": "1"})}
    for path in spec.paths:
        present, base = _get_path(spec.scene_data, path)
        values = [case[path] if path in case else (base if present else None) for case in spec.cases]
        coords[path] = ("case", _coordinate_values(values), {**attrs, "units": _units_of(path)})
    return coords


def _coordinate_values(values: list[Any]) -> np.ndarray:
    """Numbers -> float64 (int64 for integers; NaN for absent); booleans -> bool; else text."""
    present = [v for v in values if v is not None]
    if present and all(isinstance(v, bool) for v in present) and len(present) == len(values):
        return np.array(values, dtype=bool)
    if present and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in present):
        if all(isinstance(v, int) for v in present) and len(present) == len(values):
            return np.array(values, dtype=np.int64)
        return np.array([math.nan if v is None else float(v) for v in values], dtype=float)
    return np.array(["" if v is None else _text(v) for v in values], dtype=object)


_UNIT_OF_FIELD = {
    "friction": "1", "E": "Pa", "nu": "1", "radius": "m", "flat_half_width": "m", "P": "N/m", "Q": "N/m",
    "M": "N", "sigma": "Pa", "duration": "s", "period": "s", "phase": "degree", "count": "1",
    "steps": "1", "steps_per_cycle": "1", "nodes": "1", "every": "1", "points": "1",
}
_LOAD_NAMES = ("P", "Q", "M", "sigma")


def _units_of(path: str) -> str:
    """Units of a scene field, from its path (docs/interface.md); '1' when unknown or dimensionless."""
    keys = [token for token in _tokens(path) if isinstance(token, str)]
    last = keys[-1]
    if last in ("amplitude", "mean") and len(keys) >= 2 and keys[-2] in _LOAD_NAMES:
        return _UNIT_OF_FIELD[keys[-2]]
    return _UNIT_OF_FIELD.get(last, "1")


def is_sweep_result(ds: xr.Dataset) -> bool:
    """True for a dataset written by :func:`sweep` (so ``halfslip plot`` can dispatch)."""
    return "sweep_hash" in ds.attrs and "done" in ds


# -- running -------------------------------------------------------------------


class _ProgressLine:
    """``cases 120/1000, 3 failed, 57.3 cases/s, 15 s left`` on a terminal (stderr)."""

    def __init__(self, enabled: bool, stream=None):
        self.stream = stream or sys.stderr
        self.enabled = enabled
        self.started = time.perf_counter()
        self.last = 0.0
        self.shown = False

    def __call__(self, done: int, failed: int, total: int, ran: int) -> None:
        if not self.enabled:
            return
        now = time.perf_counter()
        if now - self.last < 0.2 and done < total:
            return
        self.last = now
        elapsed = now - self.started
        rate = ran / elapsed if elapsed > 0 else 0.0
        left = (total - done) / rate if rate > 0 else math.nan
        self.stream.write(f"\r  cases {done}/{total}, {failed} failed, {rate:,.3g} cases/s, "
                          f"{_duration(left)} left ")
        self.stream.flush()
        self.shown = True

    def close(self) -> None:
        if self.shown:
            self.stream.write("\n")
            self.stream.flush()


def _duration(seconds: float) -> str:
    if not math.isfinite(seconds):
        return "? s"
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.1f} min"
    return f"{seconds / 3600:.1f} h"


def sweep(
    spec_or_path: Sweep | Mapping[str, Any] | str | os.PathLike,
    *,
    output: str | os.PathLike | None = None,
    workers: int | None = None,
    scheduler: Any = None,
    cases_dir: str | os.PathLike | None = None,
    progress: bool | Callable[[int, int, int], None] = True,
    checkpoint_seconds: float = CHECKPOINT_SECONDS,
) -> xr.Dataset:
    """Run every case of a sweep and return one dataset of per-case summaries.

    Parameters
    ----------
    spec_or_path : Sweep, mapping or path
        A sweep file, its plain data (scene path relative to the working
        directory) or a :class:`Sweep`.
    output : path, optional
        HDF5 file, rewritten atomically every `checkpoint_seconds` and at the
        end. If it already holds an unfinished run of the same sweep, only
        the cases not yet done run; a different sweep there is an error.
    workers : int, optional
        1 runs in this process; more run that many local worker processes
        (default: the number of cores). Ignored with `scheduler`.
    scheduler : str or distributed.Client, optional
        Address of a running ``dask.distributed`` scheduler (or a client
        connected to one); the cases run on its workers, which must be able
        to import the same halfslip and read files the scene names.
    cases_dir : path, optional
        Also write each case's full result (steady-state or simulation
        dataset) to ``case_<index>.h5`` in this folder.
    progress : bool or callable(done, failed, total)
        True shows a progress line on stderr when it is a terminal; a
        callable is called in this process after every finished case.
        Raising KeyboardInterrupt from it stops the sweep like Ctrl-C.
    checkpoint_seconds : float
        Interval between rewrites of `output`.

    Returns
    -------
    xarray.Dataset
        Summaries (``SUMMARIES``) over the sweep's dimensions, with attributes
        ``sweep_hash``, ``sweep`` (the sweep file), ``scene`` (the base scene),
        ``complete`` (0 when interrupted), ``count_cases``, ``count_done``,
        ``count_failed``, ``count_run`` (cases run by this call), ``wall_time``,
        ``backend``.

    Raises
    ------
    HalfslipInputError
        For a bad sweep file, a bad base scene, or an `output` holding a
        different sweep.
    """
    from ._version import __version__
    from .io import read_result, write_result

    if isinstance(spec_or_path, Sweep):
        spec = spec_or_path
    elif isinstance(spec_or_path, Mapping):
        spec = parse_sweep(spec_or_path)
    else:
        spec = load_sweep(spec_or_path)
    table = _Table(spec)
    out = Path(output) if output is not None else None
    if out is not None:
        if not out.parent.exists():
            raise HalfslipInputError(f"folder {str(out.parent)!r} does not exist", field="output")
        if out.exists():
            _restore(table, spec, out, read_result)
    cases = Path(cases_dir) if cases_dir is not None else None
    if cases is not None:
        cases.mkdir(parents=True, exist_ok=True)
    pending = [int(i) for i in np.flatnonzero(~table.done)]

    if scheduler is not None:
        backend = "dask"
    else:
        workers = int(workers) if workers is not None else (os.cpu_count() or 1)
        if workers < 1:
            raise HalfslipInputError(f"must be >= 1, got {workers}", field="workers")
        backend = "in-process" if min(workers, len(pending)) <= 1 else "processes"
    width = len(str(max(spec.n_cases - 1, 0)))
    show = _ProgressLine(progress is True and sys.stderr.isatty())
    callback = progress if callable(progress) else None
    attrs = {
        "title": f"halfslip sweep over {', '.join(spec.paths)}",
        "halfslip_version": __version__,
        "sweep_hash": spec.hash,
        "sweep_kind": spec.kind,
        "sweep_paths": json.dumps(list(spec.paths)),
        "sweep": spec.text,
        "sweep_file": str(spec.file) if spec.file is not None else "",
        "scene_file": str(spec.scene_path),
        "scene": spec.scene_text,
        "per_cycle": int(spec.per_cycle),
        "backend": backend,
    }
    state = {"ran": 0, "last_write": time.perf_counter(), "complete": 1}
    started = time.perf_counter()

    def finish_attrs() -> dict[str, Any]:
        done = int(table.done.sum())
        return {
            **attrs,
            "complete": int(state["complete"] and done == spec.n_cases),
            "count_cases": spec.n_cases,
            "count_done": done,
            "count_failed": table.failed,
            "count_run": state["ran"],
            "wall_time": time.perf_counter() - started,
        }

    def write(force: bool = False) -> None:
        now = time.perf_counter()
        if out is not None and (force or now - state["last_write"] >= checkpoint_seconds):
            with _signals_deferred():
                write_result(table.dataset(finish_attrs()), out)
            state["last_write"] = time.perf_counter()

    def on_result(result: CaseResult) -> None:
        if cases is not None and result.full is not None:  # first, so that a recorded case has its file
            full = result.full.assign_attrs(
                sweep_hash=spec.hash, sweep_case=result.index,
                sweep_overrides=json.dumps(spec.overrides(result.index), default=repr),
            )
            with _signals_deferred():
                write_result(full, cases / f"case_{result.index:0{width}d}.h5")
        table.record(result)
        state["ran"] += 1
        done = int(table.done.sum())
        show(done, table.failed, spec.n_cases, state["ran"])
        if callback is not None:
            callback(done, table.failed, spec.n_cases)
        write()

    keep_full = cases is not None
    try:
        if backend == "in-process":
            _run_here(spec, pending, keep_full, on_result)
        elif backend == "processes":
            _run_processes(spec, pending, keep_full, on_result, workers)
        else:
            _run_dask(spec, pending, keep_full, on_result, scheduler)
    except KeyboardInterrupt:  # like simulate: stop, keep what is done, say so in `complete`
        state["complete"] = 0
    except BaseException:
        show.close()
        with contextlib.suppress(Exception):  # keep the finished cases; never mask the error
            write(force=True)
        raise
    show.close()
    write(force=True)
    return table.dataset(finish_attrs())


def _restore(table: _Table, spec: Sweep, out: Path, read_result) -> None:
    try:
        previous = read_result(out)
    except Exception as error:
        raise HalfslipInputError(
            f"exists but is not a readable result file ({type(error).__name__}); choose another output",
            file=str(out), field="output",
        ) from None
    found = previous.attrs.get("sweep_hash")
    if found is None or "done" not in previous:
        raise HalfslipInputError(
            "exists and is not a sweep result; choose another output or remove the file",
            file=str(out), field="output",
        )
    if found != spec.hash:
        raise HalfslipInputError(
            f"holds a different sweep (sweep_hash {str(found)[:12]}..., this sweep {spec.hash[:12]}...): the "
            "scene, the values or the options differ; choose another output or remove the file to start over",
            file=str(out), field="output",
        )
    table.restore(previous)


@contextlib.contextmanager
def _signals_deferred():
    """Hold Ctrl-C and SIGTERM off while a file is written; raise KeyboardInterrupt after it.

    An interrupt inside h5netcdf/h5py would leave a half-closed file and a
    traceback on stderr; the write itself is atomic, so waiting for it is
    short and safe. Outside the main thread this does nothing.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught = []
    signals = [signal.SIGINT] + ([signal.SIGTERM] if hasattr(signal, "SIGTERM") else [])
    previous = {}
    for number in signals:
        previous[number] = signal.signal(number, lambda signum, frame: caught.append(signum))
    try:
        yield
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler if handler is not None else signal.SIG_DFL)
    if caught:
        raise KeyboardInterrupt


class _InterruptFlag:
    """While active (main thread only), note that Ctrl-C (or a SIGTERM mapped to it) came.

    Needed because :func:`~halfslip.simulator.simulate` swallows
    KeyboardInterrupt and returns a partial run: the flag tells the driver
    that the case that was running when the signal came is not to be
    recorded. Handlers set in Python (the default Ctrl-C handler, the CLI's
    SIGTERM handler) are wrapped and still run; others are left alone.
    """

    def __init__(self):
        self.raised = False
        self.previous = {}

    def __enter__(self):
        if threading.current_thread() is not threading.main_thread():
            return self
        for number in (signal.SIGINT, getattr(signal, "SIGTERM", None)):
            if number is None:
                continue
            handler = signal.getsignal(number)
            if callable(handler):
                def wrapped(signum, frame, handler=handler):
                    self.raised = True
                    handler(signum, frame)

                self.previous[number] = signal.signal(number, wrapped)
        return self

    def __exit__(self, *exc):
        for number, handler in self.previous.items():
            signal.signal(number, handler)
        return False


def _run_here(spec: Sweep, pending: list[int], keep_full: bool, on_result) -> None:
    with _InterruptFlag() as flag:
        for index in pending:
            result = run_case(spec, index, keep_full=keep_full)
            if flag.raised:
                raise KeyboardInterrupt
            on_result(result)


_PRELOAD = ["halfslip.sweep", "halfslip.steady", "halfslip.simulator", "halfslip.solvers", "dask.array"]
"""Modules the forkserver imports once for all workers (xarray imports dask.array on first use when
dask is installed; a module that fails to import is skipped)."""


def _process_context():
    """forkserver where there is one (workers fork from a server that has imported
    halfslip: fast start, and safe when this process has threads), else spawn."""
    import multiprocessing

    if "forkserver" in multiprocessing.get_all_start_methods():
        context = multiprocessing.get_context("forkserver")
        context.set_forkserver_preload(_PRELOAD)
        return context
    return multiprocessing.get_context("spawn")


def _run_processes(spec: Sweep, pending: list[int], keep_full: bool, on_result, workers: int) -> None:
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

    workers = min(workers, len(pending))
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=_process_context(),
                               initializer=_init_worker, initargs=(spec,))
    queue = iter(pending)
    running = set()
    depth = 4 * workers  # bounded queue: Ctrl-C has little to cancel, memory stays flat
    finished = False
    try:
        for index in queue:
            running.add(pool.submit(_run_in_worker, index, keep_full))
            if len(running) >= depth:
                break
        while running:
            completed, running = wait(running, return_when=FIRST_COMPLETED)
            for future in completed:
                on_result(future.result())
                for index in queue:
                    running.add(pool.submit(_run_in_worker, index, keep_full))
                    break
        finished = True
    finally:
        if finished:
            pool.shutdown(wait=True)
        else:  # interrupted or failed: drop what is queued, stop what runs
            processes = list((getattr(pool, "_processes", None) or {}).values())
            pool.shutdown(wait=False, cancel_futures=True)
            for process in processes:
                if process.is_alive():
                    process.terminate()


def _run_dask(spec: Sweep, pending: list[int], keep_full: bool, on_result, scheduler: Any) -> None:
    try:
        from distributed import Client, as_completed
    except ImportError:
        raise ImportError(
            "a dask scheduler needs dask.distributed: pip install 'halfslip[sweep]' (or 'dask[distributed]')"
        ) from None
    own = not isinstance(scheduler, Client)
    if own:
        import dask
        from dask.utils import parse_timedelta

        address = getattr(scheduler, "scheduler_address", scheduler)  # a cluster object or an address
        timeout = min(10.0, parse_timedelta(dask.config.get("distributed.comm.timeouts.connect"), "s"))
        try:
            client = Client(address, timeout=timeout, set_as_default=False)
        except (OSError, TimeoutError) as error:
            raise HalfslipInputError(f"cannot reach a dask scheduler at {scheduler!r}: {error}",
                                     field="scheduler") from None
    else:
        client = scheduler
    futures = []
    try:
        if pending:
            shared = client.scatter(spec, broadcast=True, hash=False)
            token = uuid.uuid4().hex[:12]
            futures = client.map(run_case, [shared] * len(pending), pending, keep_full=keep_full,
                                 pure=False, key=[f"halfslip-case-{token}-{i}" for i in pending])
            for future in as_completed(futures, loop=client.loop):
                on_result(future.result())
    finally:
        if futures:
            client.cancel(futures)
        if own:
            client.close()


# -- pictures -----------------------------------------------------------------


def plot_sweep(ds: xr.Dataset, path: str | os.PathLike | None = None):
    """Pictures of a sweep result: :func:`halfslip.plot.sweep_map`, saved to `path` if given.

    Kept here for scripts written against halfslip 0.1; the drawing lives in
    :mod:`halfslip.plot` (``halfslip plot MAP.h5`` draws it too).

    Parameters
    ----------
    ds : xarray.Dataset
        A result of :func:`sweep` (or read back from its file).
    path : path, optional
        Also save the figure there (format from the suffix).

    Returns
    -------
    matplotlib.figure.Figure
        Made without pyplot (no global state, Agg canvas).
    """
    from .plot import DPI, sweep_map

    fig = sweep_map(ds)
    if path is not None:
        fig.savefig(path, dpi=DPI)
    return fig
