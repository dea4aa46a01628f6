"""Scenes: everything one run needs, read from YAML (docs/interface.md).

The YAML is read with PyYAML's safe loader, composed into nodes and walked
here, so that every error names the file, the line and the field path, e.g.
``dovetail.yaml:17: loads[1].cycles.Q.amplitude: expected a number, ...``.

Two details of the YAML reading:

- PyYAML reads an unquoted ``1e5`` as text (YAML 1.1 wants ``1.0e+5``);
  unquoted scalars that Python reads as a float are taken as numbers, so
  ``1e5`` works. Quoted numbers are rejected as text.
- Duplicate keys are an error (YAML would silently keep the last).

Paths inside a scene (table and profile files) are relative to the scene file.
"""
from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from . import geometry, io, limits
from .errors import (
    HalfslipInputError,
    check_bool,
    check_choice,
    check_count,
    check_list,
    check_mapping,
    check_number,
    check_string,
    excerpt,
    join,
)
from .histories import LoadHistory, check_column, read_csv_columns

METHODS = ("auto", "exact", "general")
"""Values of ``solver.method``."""

FIELDS = ("p", "q", "slip")
"""Per-point fields that ``output.fields`` may store."""

GEOMETRY_KINDS = ("hertz", "rounded_punch", "profile")
"""Values of ``geometry.kind``."""

_SCENE_KEYS = ("name", "material", "friction", "geometry", "loads", "solver", "output")
_REQUIRED_KEYS = ("material", "friction", "geometry", "loads")
_SOLVER_KEYS = ("method", "nodes", "skip_steady_cycles", "edge_travel")
_OUTPUT_KEYS = ("fields", "every", "points")


@dataclass(frozen=True)
class SolverOptions:
    """How to solve (the ``solver`` section of a scene).

    Attributes
    ----------
    method : {'auto', 'exact', 'general'}
        'exact' is the memory construction (symmetric profile, M = sigma = 0),
        'general' the discretised slip solver, 'auto' picks the exact one
        whenever it applies.
    nodes : int
        Resolution of the general solver, >= 8.
    skip_steady_cycles : bool
        Stop marching a periodic segment once its cycle repeats.
    edge_travel : float or None
        Step-size control of the general solver: a slipping step over which a
        stick edge travels more than this fraction of the contact width is
        taken in halves (up to 16 sub-steps). None (the default) is off.
    """

    method: str = "auto"
    nodes: int = 512
    skip_steady_cycles: bool = True
    edge_travel: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "method", check_choice(self.method, "solver.method", METHODS))
        object.__setattr__(self, "nodes", check_count(self.nodes, "solver.nodes", minimum=8))
        check_bool(self.skip_steady_cycles, "solver.skip_steady_cycles")
        if self.edge_travel is not None:
            object.__setattr__(self, "edge_travel", check_number(self.edge_travel, "solver.edge_travel",
                                                                 positive=True))


@dataclass(frozen=True)
class OutputOptions:
    """What to store (the ``output`` section of a scene).

    Attributes
    ----------
    fields : tuple of str
        Per-point fields to store, a subset of ('p', 'q', 'slip'); empty
        stores the loads and the zone extents only.
    every : int
        Store every n-th step (the last step is always stored).
    points : int
        Number of x stations of the stored fields, >= 2 (an extension of
        docs/interface.md).
    """

    fields: tuple[str, ...] = FIELDS
    every: int = 1
    points: int = 201

    def __post_init__(self) -> None:
        names = check_list(self.fields, "output.fields")
        chosen = [check_choice(name, f"output.fields[{index}]", FIELDS) for index, name in enumerate(names)]
        object.__setattr__(self, "fields", tuple(dict.fromkeys(chosen)))
        object.__setattr__(self, "every", check_count(self.every, "output.every"))
        object.__setattr__(self, "points", check_count(self.points, "output.points", minimum=2))


@dataclass(frozen=True)
class Scene:
    """Everything one run needs.

    Attributes
    ----------
    name : str
        Copied into the output.
    material : geometry.Material
        E > 0 [Pa], -1 < nu < 0.5.
    friction : float
        Coulomb coefficient f >= 0.
    profile : geometry profile
        ``Hertz``, ``RoundedPunch`` or ``TabulatedProfile``.
    history : LoadHistory
        The sampled loads.
    solver : SolverOptions
    output : OutputOptions
    text : str or None
        The scene file as read (None for a scene built in Python).
    path : pathlib.Path or None
        Where the scene was read from.
    """

    name: str
    material: geometry.Material
    friction: float
    profile: Any
    history: LoadHistory
    solver: SolverOptions = field(default_factory=SolverOptions)
    output: OutputOptions = field(default_factory=OutputOptions)
    text: str | None = None
    path: Path | None = None

    def __post_init__(self) -> None:
        check_string(self.name, "name")
        E = check_number(self.material.E, "material.E", positive=True)
        nu = check_number(self.material.nu, "material.nu")
        if not -1.0 < nu < 0.5:
            raise HalfslipInputError(f"Poisson's ratio must lie in (-1, 0.5), got {nu:g}", field="material.nu")
        object.__setattr__(self, "material", geometry.Material(E=E, nu=nu))
        object.__setattr__(self, "friction", check_number(self.friction, "friction", nonnegative=True))

    def warnings(self) -> tuple[str, ...]:
        """Return messages about legal but physically suspect input.

        Two kinds: a load that jumps at the start of a cycles segment (the
        first step bridges it with a straight line), and sampled points where
        |Q| > fP (the contact slides as a whole there).
        """
        messages = []
        for jump in self.history.jumps():
            segment = self.history.segments[jump.segment]
            where = f" (line {segment.line})" if segment.line is not None else ""
            messages.append(
                f"loads[{jump.segment}]{where}: {jump.load} jumps from {jump.before:g} to {jump.after:g} "
                f"at the start of the cycles (t = {jump.t:g} s); the first step bridges it with a straight line"
            )
        P, Q = self.history.P, self.history.Q
        sliding = np.abs(Q) > self.friction * np.maximum(P, 0.0)
        if np.any(sliding):
            first = float(self.history.t[np.argmax(sliding)])
            messages.append(
                f"|Q| > fP at {int(sliding.sum())} of {sliding.size} sampled points, first at t = {first:g} s "
                f"(max |Q|/(fP) = {self.history.max_shear_ratio(self.friction):.3g}): gross sliding"
            )
        return tuple(messages)


def load_scene(path: str | os.PathLike) -> Scene:
    """Read and check a scene file.

    Parameters
    ----------
    path : path
        The scene YAML file.

    Returns
    -------
    Scene

    Raises
    ------
    HalfslipInputError
        For a missing or unreadable file and for any bad content, with the
        file, line and field path.
    """
    path = Path(path)
    return parse_scene(read_input_text(path, "scene"), path=path)


def read_input_text(path: Path, what: str) -> str:
    """The UTF-8 text of a scene or sweep file, or a one-line HalfslipInputError naming it.

    :func:`halfslip.io.read_input_text` with the limit of YAML files
    (:data:`halfslip.limits.MAX_SCENE_BYTES`).
    """
    return io.read_input_text(path, what, limits.MAX_SCENE_BYTES)


def parse_scene(
    text: str,
    path: str | os.PathLike | None = None,
    base_dir: str | os.PathLike | None = None,
) -> Scene:
    """Build a scene from YAML text.

    Parameters
    ----------
    text : str
        The scene YAML.
    path : path, optional
        Where the text came from; named in errors and kept in the scene.
    base_dir : path, optional
        Directory that files named in the scene are relative to (default:
        the directory of `path`, else the working directory).

    Returns
    -------
    Scene

    Raises
    ------
    HalfslipInputError
        For any bad content, with the file, line and field path.
    """
    path = Path(path) if path is not None else None
    file = str(path) if path is not None else None
    if base_dir is not None:
        base = Path(base_dir)
    else:
        base = path.parent if path is not None else Path.cwd()
    try:
        data, lines = _read_yaml(text)
    except HalfslipInputError as error:
        raise error.located(file, None) from None
    try:
        return _build_scene(data, lines, base, text, path)
    except HalfslipInputError as error:
        raise error.located(file, _line_of(error.field, lines)) from None


def _build_scene(data: Any, lines: Mapping[str, int], base: Path, text: str, path: Path | None) -> Scene:
    """Turn the plain data of a scene into a :class:`Scene`."""
    if data is None:
        raise HalfslipInputError("the scene is empty")
    check_mapping(data, "", _SCENE_KEYS, _REQUIRED_KEYS)
    material = check_mapping(data["material"], "material", ("E", "nu"), ("E", "nu"))
    segments = data["loads"]
    segment_lines = (
        [lines.get(f"loads[{index}]") for index in range(len(segments))] if isinstance(segments, list) else None
    )
    return Scene(
        name=data.get("name", path.stem if path is not None else "scene"),
        material=geometry.Material(E=material["E"], nu=material["nu"]),
        friction=data["friction"],
        profile=_build_profile(data["geometry"], base),
        history=LoadHistory.from_segments(segments, base_dir=base, lines=segment_lines),
        solver=SolverOptions(**check_mapping(data.get("solver", {}), "solver", _SOLVER_KEYS)),
        output=OutputOptions(**check_mapping(data.get("output", {}), "output", _OUTPUT_KEYS)),
        text=text,
        path=path,
    )


def _build_profile(spec: Any, base: Path) -> Any:
    """Build the geometry profile from the ``geometry`` section."""
    check_mapping(spec, "geometry", ("kind", "radius", "flat_half_width", "file", "x", "h"), ("kind",))
    kind = check_choice(spec["kind"], "geometry.kind", GEOMETRY_KINDS)
    if kind == "hertz":
        check_mapping(spec, "geometry", ("kind", "radius"), ("radius",))
        radius = check_number(spec["radius"], "geometry.radius", positive=True)
        return _make(geometry.Hertz, "geometry", radius)
    if kind == "rounded_punch":
        check_mapping(spec, "geometry", ("kind", "flat_half_width", "radius"), ("flat_half_width", "radius"))
        half_width = check_number(spec["flat_half_width"], "geometry.flat_half_width", nonnegative=True)
        radius = check_number(spec["radius"], "geometry.radius", positive=True)
        return _make(geometry.RoundedPunch, "geometry", half_width, radius)
    if "file" in spec:
        check_mapping(spec, "geometry", ("kind", "file"))
        name = check_string(spec["file"], "geometry.file")
        columns, _ = read_csv_columns(base / name, ("x", "h"), ("x", "h"), "geometry", what="profile",
                                      max_rows=limits.MAX_PROFILE_ROWS)
        return _make(geometry.TabulatedProfile, "geometry.file", columns["x"], columns["h"])
    check_mapping(spec, "geometry", ("kind", "x", "h"), ("x", "h"))
    x, h = check_column(spec["x"], "geometry.x"), check_column(spec["h"], "geometry.h")
    if x.size != h.size:
        raise HalfslipInputError(f"has {h.size} values but x has {x.size}", field="geometry.h")
    return _make(geometry.TabulatedProfile, "geometry", x, h)


def _make(factory: Any, field: str, *parameters: Any) -> Any:
    """Call a geometry constructor, turning its ValueError into an input error."""
    try:
        return factory(*parameters)
    except ValueError as error:
        raise HalfslipInputError(f"bad geometry: {error}", field=field) from None


# -- YAML with line numbers ------------------------------------------------

_INT_TAG = "tag:yaml.org,2002:int"
_FLOAT_TAG = "tag:yaml.org,2002:float"
_MERGE_TAG = "tag:yaml.org,2002:merge"
_FLOAT_BITS = 1024  # 2**1024 is the first integer beyond the largest float (1.8e308)


def _yaml_error(message: str, mark: Any) -> HalfslipInputError:
    """An error of the YAML text at `mark` (a PyYAML mark or None)."""
    return HalfslipInputError(message, line=mark.line + 1 if mark is not None else None)


class _BoundedLoader(yaml.SafeLoader):
    """PyYAML's safe loader, composing within :mod:`halfslip.limits`.

    While the node tree is composed it counts the nodes the tree expands to
    (an alias counts as the whole of its anchor, so "billion laughs" is
    refused after MAX_YAML_NODES nodes, not after gigabytes), the depth of
    nesting (aliases counted expanded; checked before each level is entered,
    so the recursion never goes deeper than MAX_YAML_DEPTH), and refuses an
    alias to a node that contains it (a cycle, which the walk in
    :func:`_plain` would follow forever).
    """

    def __init__(self, text: str) -> None:
        super().__init__(text)
        self.expanded = 0  # nodes the tree expands to, so far
        self.depth = 0  # nesting of the node being composed
        self.deepest = 0  # deepest (expanded) level met in the current subtree
        self.open_anchors: set[str] = set()
        self.anchor_sizes: dict[str, tuple[int, int]] = {}  # anchor -> (expanded nodes, height)

    def _grow(self, nodes: int, depth: int, mark: Any) -> None:
        self.expanded += nodes
        self.deepest = max(self.deepest, depth)
        if self.expanded > limits.MAX_YAML_NODES:
            raise _yaml_error(
                f"the YAML expands to more than {limits.MAX_YAML_NODES:,} values (every alias counted in full); "
                "a scene needs a few hundred (halfslip.limits.MAX_YAML_NODES)", mark)
        if depth > limits.MAX_YAML_DEPTH:
            raise _yaml_error(
                f"lists and mappings nest deeper than {limits.MAX_YAML_DEPTH} levels (aliases counted expanded); "
                "a scene nests 5 (halfslip.limits.MAX_YAML_DEPTH)", mark)

    def compose_node(self, parent: Any, index: Any) -> Any:
        event = self.peek_event()
        if isinstance(event, yaml.AliasEvent):
            if event.anchor in self.open_anchors:
                raise _yaml_error(f"the alias *{excerpt(event.anchor)[1:-1]} refers to a node that contains it "
                                  "(a cycle)", event.start_mark)
            node = super().compose_node(parent, index)  # PyYAML refuses an undefined alias
            nodes, height = self.anchor_sizes.get(event.anchor, (1, 1))
            self._grow(nodes, self.depth + height, event.start_mark)
            return node
        anchor = getattr(event, "anchor", None)
        before, outer_deepest = self.expanded, self.deepest
        self.depth += 1
        self.deepest = self.depth
        self._grow(1, self.depth, event.start_mark)
        if anchor is not None:
            self.open_anchors.add(anchor)
        node = super().compose_node(parent, index)
        if anchor is not None:
            self.open_anchors.discard(anchor)
            self.anchor_sizes[anchor] = (self.expanded - before, self.deepest - self.depth + 1)
        self.depth -= 1
        self.deepest = max(outer_deepest, self.deepest)
        return node


def _read_yaml(text: str) -> tuple[Any, dict[str, int]]:
    """Parse YAML safely into plain data and a table field path -> line.

    The line of a mapping entry is the line of its key; of a list item, the
    line where the item starts; the top level is ``""``. The YAML may use
    anchors, aliases and merge keys (``<<: *defaults``) within the limits of
    :class:`_BoundedLoader`; every failure is a one-line HalfslipInputError.
    """
    loader = None
    try:
        loader = _BoundedLoader(text)  # the reader refuses non-printable characters here already
        root = loader.get_single_node()
        lines: dict[str, int] = {}
        if root is None:
            return None, lines
        lines[""] = root.start_mark.line + 1
        return _plain(root, "", lines, loader), lines
    except yaml.reader.ReaderError as error:
        where = text.count("\n", 0, error.position) + 1 if isinstance(error.position, int) else None
        character = chr(error.character) if isinstance(error.character, int) else str(error.character)
        raise HalfslipInputError(
            f"invalid YAML: the character {excerpt(character)} (#x{ord(character[:1] or ' '):04x}) is not allowed "
            "in a YAML file; remove it", line=where) from None
    except yaml.MarkedYAMLError as error:
        mark = error.problem_mark or error.context_mark
        reason = "; ".join(part for part in (error.context, error.problem) if part)
        if error.context_mark is not None and mark is not None and error.context_mark.line != mark.line:
            reason += f" (the construct began on line {error.context_mark.line + 1})"
        raise HalfslipInputError(f"invalid YAML: {excerpt(reason, 200)[1:-1]}",
                                 line=mark.line + 1 if mark else None) from None
    except yaml.YAMLError as error:
        raise HalfslipInputError(f"invalid YAML: {excerpt(error, 200)[1:-1]}") from None
    finally:
        if loader is not None:
            loader.dispose()


def _plain(node: yaml.Node, path: str, lines: dict[str, int], loader: yaml.SafeLoader) -> Any:
    """Convert a YAML node to plain Python, recording the line of every field.

    The recursion is as deep as the nesting, which the loader has bounded.
    """
    if isinstance(node, yaml.MappingNode):
        result = {}
        merged = []
        for key_node, value_node in node.value:
            line = key_node.start_mark.line + 1
            if not isinstance(key_node, yaml.ScalarNode):
                raise HalfslipInputError("keys must be plain names", line=line, field=path or None)
            if key_node.tag == _MERGE_TAG:
                merged.append((value_node, line))
                continue
            key = key_node.value
            child = join(path, key)
            if key in result:
                raise HalfslipInputError(f"duplicate key {excerpt(key)}", line=line, field=child)
            lines[child] = line
            result[key] = _plain(value_node, child, lines, loader)
        for value_node, line in merged:  # '<<: *a' or '<<: [*a, *b]': keys not given explicitly, first wins
            sources = value_node.value if isinstance(value_node, yaml.SequenceNode) else [value_node]
            for source in sources:
                if not isinstance(source, yaml.MappingNode):
                    raise HalfslipInputError("a merge key (<<) takes a mapping or a list of mappings",
                                             line=line, field=path or None)
                for key, value in _plain(source, path, {}, loader).items():
                    if key not in result:
                        lines.setdefault(join(path, key), line)
                        result[key] = value
        return result
    if isinstance(node, yaml.SequenceNode):
        items = []
        for index, item in enumerate(node.value):
            child = f"{path}[{index}]"
            lines[child] = item.start_mark.line + 1
            items.append(_plain(item, child, lines, loader))
        return items
    return _scalar(node, path, loader)


def _scalar(node: yaml.ScalarNode, path: str, loader: yaml.SafeLoader) -> Any:
    """A scalar node's value; numbers out of the float range are refused here."""
    line = node.start_mark.line + 1
    if node.tag in (_INT_TAG, _FLOAT_TAG) and len(node.value) > limits.MAX_NUMBER_DIGITS:
        raise HalfslipInputError(
            f"a number of {len(node.value):,} characters: at most {limits.MAX_NUMBER_DIGITS} are read "
            "(the largest number is 1.8e308)", line=line, field=path or None)
    try:
        value = loader.construct_object(node)
    except (ValueError, OverflowError, ArithmeticError) as error:  # e.g. the date 2024-13-45
        raise HalfslipInputError(f"cannot read {excerpt(node.value)}: {excerpt(error, 80)[1:-1]}",
                                 line=line, field=path or None) from None
    if isinstance(value, int) and not isinstance(value, bool) and abs(value).bit_length() > _FLOAT_BITS:
        raise HalfslipInputError(f"{excerpt(node.value)} is out of range; the largest number is 1.8e308",
                                 line=line, field=path or None)
    if isinstance(value, str) and node.style is None and len(value) <= limits.MAX_NUMBER_DIGITS:
        try:
            return float(value)
        except ValueError:
            return value
    return value


def _line_of(field: str | None, lines: Mapping[str, int]) -> int | None:
    """Line of `field`, or of its nearest recorded ancestor."""
    field = field or ""
    while field not in lines and field:
        cut = max(field.rfind("."), field.rfind("["))
        field = field[:cut] if cut > 0 else ""
    return lines.get(field)
