"""The sweep file: its grammar, checks and the scene of each case (:class:`Sweep`)."""
from __future__ import annotations

import copy
import dataclasses
import hashlib
import json
import math
import os
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from ..errors import (
    check_string,
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
from .. import limits
from ..variables import SUMMARY
from ..io import PATH_CHARS, read_input_text
from ..scene import _line_of, _read_yaml, parse_scene

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
    names : tuple of str
        The short name of each path: the result's dimension (grid) or
        coordinate (cases), e.g. ``Q_amplitude`` for
        ``loads[1].cycles.Q.amplitude``; given in the sweep file
        (``vary: {Q_amp: {path: ..., values: [...]}}``) or derived
        (:func:`short_names`).
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
    names: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if not self.names:
            object.__setattr__(self, "names", short_names(self.paths))

    @property
    def shape(self) -> tuple[int, ...]:
        """Shape of the result arrays: one axis per path (grid) or (n_cases,)."""
        if self.kind == "grid":
            return tuple(len(values) for values in self.axes)
        return (len(self.cases),)

    @property
    def dims(self) -> tuple[str, ...]:
        """Dimension names of the result arrays: the short names (grid) or ('case',)."""
        return self.names if self.kind == "grid" else ("case",)

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
        paths, axes, names = [], [], []
        for key, spec in vary.items():
            field = f"vary.{key}"
            if isinstance(spec, Mapping) and "path" in spec:  # a named axis: {path: ..., values or linspace ...}
                names.append(_check_name(key, field, names))
                paths.append(_check_path(check_string(spec["path"], f"{field}.path"), f"{field}.path"))
                rest = {k: v for k, v in spec.items() if k != "path"}
                spec, field = (rest["values"], f"{field}.values") if set(rest) == {"values"} else (rest, field)
            else:
                names.append(None)
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
        derived = short_names(paths, taken=[n for n in names if n is not None])
        sweep = Sweep("grid", tuple(paths), tuple(axes), (), fixed, per_cycle, scene_path, scene_text,
                      scene_data, path, text, lines,
                      tuple(name if name is not None else short for name, short in zip(names, derived)))
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


RESERVED_NAMES = frozenset(SUMMARY) | {"done", "status", "case"}
"""Names a sweep axis cannot take: the result's variables and the case dimension."""

_GENERIC = frozenset({"amplitude", "mean", "phase", "count", "period", "steps", "steps_per_cycle", "duration"})
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")


def short_names(paths: Sequence[str], taken: Sequence[str] = ()) -> tuple[str, ...]:
    """A short, distinct name for each scene path: its last word, or more where needed.

    ``friction`` -> ``friction``, ``geometry.radius`` -> ``radius``,
    ``loads[1].cycles.Q.amplitude`` -> ``Q_amplitude`` (a word like
    amplitude, mean or phase says little alone); where two paths would share
    a name, or a name is taken (`taken`, :data:`RESERVED_NAMES`), more words
    of the path are joined, from the end (``loads1_cycles_Q_amplitude``).
    """
    words = [[re.sub(r"[\[\]]", "", w) for w in path.split(".") if w] for path in paths]
    used = set(RESERVED_NAMES) | set(taken)
    counts = [2 if w and w[-1] in _GENERIC and len(w) > 1 else 1 for w in words]
    while True:
        names = ["_".join(w[-n:]) for w, n in zip(words, counts)]
        clash = [i for i, name in enumerate(names)
                 if (names.count(name) > 1 or name in used) and counts[i] < len(words[i])]
        if not clash:
            return tuple(names)
        for i in clash:
            counts[i] += 1


def _check_name(name: Any, field: str, names: Sequence[Any]) -> str:
    """A sweep axis's given short name: an identifier, not a result variable, not given twice."""
    if not isinstance(name, str) or not _NAME.match(name):
        raise HalfslipInputError(f"a name is a word of letters, digits and _ (not first a digit), got {describe(name)}",
                                 field=field)
    if name in RESERVED_NAMES:
        raise HalfslipInputError(f"{name!r} names a variable of the sweep result; choose another name", field=field)
    if name in names:
        raise HalfslipInputError(f"the name {name!r} is given twice", field=field)
    return name


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
        named = f"vary.{sweep.names[sweep.paths.index(path)]}.path"  # vary: {name: {path: ..., values: ...}}
        return named if named in sweep.lines else f"vary.{path}"
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


