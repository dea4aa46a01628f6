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

import math
import os
import re
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
_SOLVER_KEYS = ("method", "tol", "nodes", "skip_steady_cycles", "edge_travel", "edge_windows")

#: The general solver's stick edges are within about this many cells (contact width / nodes) of the
#: converged ones (random histories, docs/general_solver.md; the median until 0.3.6, the 95th percentile over
#: the edges the reference vouches for since 0.3.7): nodes = ceil(NODES_PER_TOL / tol).
NODES_PER_TOL = 0.1
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
        Resolution of the general solver, >= 8: cells across the widest contact
        of the history (the lower-level knob; when given it overrides ``tol``).
    skip_steady_cycles : bool
        Stop marching a periodic segment once its cycle repeats.
    edge_travel : float or None
        Step-size control of the general solver: a slipping step over which a
        contact edge travels more than this fraction of the contact width is
        taken in equal sub-steps (up to 64). None: the solver's default (0.01).
    tol : float
        Accuracy asked of the general solver: its stick edges, in units of the
        contact width (default 1e-4). It sets ``nodes`` when ``nodes`` is not
        given: nodes = ceil(NODES_PER_TOL / tol).
    edge_windows : bool
        Solve the first and last cells of the contact again on cells four
        times finer at every take of the general solver, for its outermost
        stick points, the slip and the dissipation there
        (halfslip.solvers._windows; default true since 0.4.6, false before).
    """

    method: str = "auto"
    nodes: int | None = None
    skip_steady_cycles: bool = True
    edge_travel: float | None = None
    tol: float = 1e-4
    edge_windows: bool = True

    def __post_init__(self) -> None:
        object.__setattr__(self, "method", check_choice(self.method, "solver.method", METHODS))
        object.__setattr__(self, "tol", check_number(self.tol, "solver.tol", positive=True))
        if not self.tol < 0.1:
            raise HalfslipInputError(f"must be below 0.1 (a fraction of the contact width), got {self.tol:g}",
                                     field="solver.tol")
        if self.nodes is None:
            object.__setattr__(self, "nodes", max(8, math.ceil(NODES_PER_TOL / self.tol)))
        object.__setattr__(self, "nodes", check_count(self.nodes, "solver.nodes", minimum=8))
        check_bool(self.skip_steady_cycles, "solver.skip_steady_cycles")
        check_bool(self.edge_windows, "solver.edge_windows")
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
        if not isinstance(self.profile, geometry.Profile):
            raise HalfslipInputError(f"expected a geometry profile (Hertz, RoundedPunch, TabulatedProfile), got "
                                     f"{type(self.profile).__name__}", field="geometry")
        if not isinstance(self.history, LoadHistory):
            raise HalfslipInputError(f"expected a LoadHistory, got {type(self.history).__name__}", field="loads")
        for name, kind in (("solver", SolverOptions), ("output", OutputOptions)):
            if not isinstance(getattr(self, name), kind):
                raise HalfslipInputError(f"expected {kind.__name__}, got {type(getattr(self, name)).__name__}",
                                         field=name)
        check_run_bytes(self)

    def __repr__(self) -> str:
        """A short description: name, material, friction, geometry, segments and steps.

        The scene text is not repeated (``scene.text`` holds it);
        :func:`scene_fingerprint` is the full form that identifies a scene.
        """
        history = self.history
        from .si import quantity

        return (f"Scene({self.name!r}, E={quantity(self.material.E, 'Pa')}, nu={self.material.nu:g}, "
                f"friction={self.friction:g}, {_profile_repr(self.profile)}, "
                f"{len(history.segments)} segments, {history.n_steps} steps, t = 0 .. {history.duration:g} s)")

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


def _profile_repr(profile: Any) -> str:
    from .si import quantity

    if isinstance(profile, geometry.Hertz):
        return f"hertz R={quantity(profile.radius, 'm')}"
    if isinstance(profile, geometry.RoundedPunch):
        return f"rounded_punch w={quantity(profile.flat_half_width, 'm')} R={quantity(profile.radius, 'm')}"
    if isinstance(profile, geometry.TabulatedProfile):
        return f"profile of {profile.x.size} samples"
    return type(profile).__name__


def scene_fingerprint(scene: Scene) -> str:
    """Every field of `scene` as text (the dataclass form, before ``repr`` was made short).

    What identifies a scene built in Python (``simulator.scene_hash``).
    """
    from dataclasses import fields

    return f"Scene({', '.join(f'{f.name}={getattr(scene, f.name)!r}' for f in fields(scene))})"


def run_bytes(scene: Scene, method: str | None = None) -> dict[str, int]:
    """Estimate the memory a run of `scene` surely needs, by part [bytes].

    A lower bound of what :func:`halfslip.simulate` allocates, so that a scene
    refused for it could not have run:

    - ``history``: the sampled times and four loads, 40 bytes a step;
    - ``records``: twelve numbers per stored step (about 32 bytes each while
      the run collects them) and the stored fields, ``len(fields) x points``
      floats per stored step, held twice when the result is assembled. With
      ``skip_steady_cycles`` a cycles segment stores at least two cycles;
    - ``solver``: the general solver's working set (a fit to measurements,
      :data:`halfslip.limits.GENERAL_BYTES_PER_NODE_PAIR`), when the general
      solver may be chosen.

    `method` overrides ``scene.solver.method`` ('auto', 'exact', 'general').

    Returns
    -------
    dict
        ``{"history": ..., "records": ..., "fields": ..., "solver": ...}``.
    """
    history = scene.history
    marched = 0
    for segment in history.segments:
        if segment.kind == "cycles" and scene.solver.skip_steady_cycles:
            marched += min(segment.count, 2) * segment.steps_per_cycle
        else:
            marched += segment.steps
    stored = -(-marched // scene.output.every) + 1
    method = method or scene.solver.method
    general = method == "general" or (
        method == "auto"
        and not (scene.profile.symmetric and not np.any(history.M) and not np.any(history.sigma))
    )
    return {
        "history": 40 * history.n_steps,
        "records": 12 * 32 * stored,
        "fields": 2 * 8 * len(scene.output.fields) * scene.output.points * stored,
        "solver": _general_bytes(scene.solver.nodes) if general else 0,
    }


def _general_bytes(nodes: int) -> int:
    """The general solver's working memory at `nodes` (halfslip.limits)."""
    return int(limits.GENERAL_KEPT_BYTES + limits.GENERAL_BYTES_PER_NODE * nodes
               + limits.GENERAL_BYTES_PER_NODE_PAIR * nodes * nodes)


_RUN_PART_FIELDS = {"history": "loads", "records": "loads", "fields": "output.points", "solver": "solver.nodes"}


def check_run_bytes(scene: Scene, method: str | None = None) -> None:
    """Refuse a scene whose run would need more than :data:`halfslip.limits.MAX_RUN_BYTES`.

    The error names the field of the largest part of :func:`run_bytes` and
    gives the estimate.
    """
    parts = run_bytes(scene, method)
    total = sum(parts.values())
    if total <= limits.MAX_RUN_BYTES:
        return
    largest = max(parts, key=parts.__getitem__)
    detail = ", ".join(f"{name} {_bytes_text(size)}" for name, size in parts.items() if size)
    hint = {
        "loads": "fewer steps, or output.every > 1",
        "output.points": "fewer output.points, fewer output.fields, or output.every > 1",
        "solver.nodes": "fewer solver.nodes",
    }[_RUN_PART_FIELDS[largest]]
    raise HalfslipInputError(
        f"the run would need about {_bytes_text(total)} of memory ({detail}); at most "
        f"{_bytes_text(limits.MAX_RUN_BYTES)} (halfslip.limits.MAX_RUN_BYTES): use {hint}",
        field=_RUN_PART_FIELDS[largest],
    )


def _bytes_text(size: float) -> str:
    """A byte count for messages: ``3.2 GB``."""
    for unit, scale in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if size >= scale:
            return f"{size / scale:.3g} {unit}"
    return f"{int(size)} B"


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
    scene = Scene(
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
    check_contacts(scene)
    return scene


def check_contacts(scene: Scene) -> None:
    """Check that the contact fits a tabulated profile under the history's extreme loads.

    The normal problem is solved at the sampled points of largest P, largest
    and smallest M and largest and smallest M/P (and, when the exact method
    may serve the scene, at the 5 % higher load up to which it tabulates the
    contact). A contact that would leave the tabulated span, or none found,
    is an error of ``geometry``, foreseen here instead of in the middle of a
    run. Analytic profiles extend without end and are not checked.
    """
    profile = scene.profile
    if not isinstance(profile, geometry.TabulatedProfile):
        return
    history = scene.history
    P, M = history.P, history.M
    loaded = np.flatnonzero(P > 0.0)
    if loaded.size == 0:
        return
    ratio = M[loaded] / P[loaded]
    candidates = dict.fromkeys(
        int(index) for index in (
            loaded[np.argmax(P[loaded])], loaded[np.argmax(M[loaded])], loaded[np.argmin(M[loaded])],
            loaded[np.argmax(ratio)], loaded[np.argmin(ratio)],
        )
    )
    from .solvers.levels import TABLE_HEADROOM

    problem = geometry.NormalProblem(profile, scene.material.compliance)
    try:
        for index in candidates:
            at = f"P = {P[index]:g} N/m, M = {M[index]:g} N (t = {history.t[index]:g} s)"
            problem.solve(float(P[index]), float(M[index]))
        if scene.solver.method != "general" and profile.symmetric and not np.any(M) and not np.any(history.sigma):
            top = TABLE_HEADROOM * float(np.max(P))
            at = f"P = {top:g} N/m ({TABLE_HEADROOM:g} x the largest P, to which the exact method tabulates)"
            problem.half_width(np.array([top]))
    except geometry.ProfileSpanError as error:
        source = scene_profile_source(scene)
        source = f" {source}" if source else ""
        raise HalfslipInputError(
            f"the profile{source} cannot carry {at}: {error}", field="geometry"
        ) from None


def scene_error(scene: Scene, message: str, field: str) -> HalfslipInputError:
    """An error of `field` of a loaded scene, located at its file and line."""
    line = None
    if scene.text is not None:
        try:
            line = _line_of(field, _read_yaml(scene.text)[1])
        except HalfslipInputError:
            pass
    return HalfslipInputError(message, file=str(scene.path) if scene.path is not None else None, line=line,
                              field=field)


def scene_profile_source(scene: Scene) -> str | None:
    """The profile file named by the scene's text, if any (for messages)."""
    if scene.text is None:
        return None
    try:
        data, _ = _read_yaml(scene.text)
        name = data["geometry"]["file"]
    except (HalfslipInputError, KeyError, TypeError):
        return None
    return excerpt(name, io.PATH_CHARS) if isinstance(name, str) else None


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
        path = base / name
        columns, row_lines = read_csv_columns(path, ("x", "h"), ("x", "h"), "geometry", what="profile",
                                              max_rows=limits.MAX_PROFILE_ROWS)

        def at_row(message: str, column: str, row: int) -> HalfslipInputError:
            return HalfslipInputError(message, file=str(path), line=row_lines[row], field=f"geometry.{column}")

        profile = _profile_from_samples(columns["x"], columns["h"], at_row, "geometry.file")
        profile.source = str(path)  # an input of the run: never an output (cli.scene_inputs)
        return profile
    check_mapping(spec, "geometry", ("kind", "x", "h"), ("x", "h"))
    for column in ("x", "h"):
        if isinstance(spec[column], list) and len(spec[column]) > limits.MAX_PROFILE_ROWS:
            raise HalfslipInputError(
                f"has {len(spec[column]):,} values; a profile has at most {limits.MAX_PROFILE_ROWS:,} samples "
                "(halfslip.limits.MAX_PROFILE_ROWS)", field=f"geometry.{column}")
    x, h = check_column(spec["x"], "geometry.x"), check_column(spec["h"], "geometry.h")
    if x.size != h.size:
        raise HalfslipInputError(f"has {h.size} values but x has {x.size}", field="geometry.h")

    def at_item(message: str, column: str, row: int) -> HalfslipInputError:
        return HalfslipInputError(message, field=f"geometry.{column}[{row}]")

    return _profile_from_samples(x, h, at_item, "geometry")


PROFILE_DIP_RTOL = 1e-6
"""How far below h(0) a profile sample may lie, relative to the profile's height
range: a measured profile's lowest point may sit a little off x = 0 within its
noise; deeper, the first contact would start away from x = 0 (or nowhere, for a
concave profile), which the normal problem cannot solve."""


def _profile_from_samples(x: np.ndarray, h: np.ndarray, at_row: Any, field: str) -> geometry.TabulatedProfile:
    """Build a tabulated profile, naming the offending row of a bad sample.

    ``at_row(message, column, row)`` makes the located error. Beyond the
    checks of :class:`~halfslip.geometry.TabulatedProfile` the gap must be
    lowest at x = 0, where the pad first touches (within PROFILE_DIP_RTOL).
    """
    if x.size >= 2:
        falling = np.flatnonzero(np.diff(x) <= 0.0)
        if falling.size:
            row = int(falling[0]) + 1
            raise at_row(f"x must increase strictly; {x[row]:g} follows {x[row - 1]:g}", "x", row)
        if not x[0] < 0.0:
            raise at_row(f"the samples must reach both sides of x = 0; the first x is {x[0]:g}", "x", 0)
        if not x[-1] > 0.0:
            raise at_row(f"the samples must reach both sides of x = 0; the last x is {x[-1]:g}", "x", x.size - 1)
    profile = _make(geometry.TabulatedProfile, field, x, h)
    height = float(np.max(profile.h) - np.min(profile.h))
    lowest = int(np.argmin(profile.h))
    if profile.h[lowest] < -PROFILE_DIP_RTOL * height:
        raise at_row(
            f"the gap at x = {x[lowest]:g} m is {-profile.h[lowest]:g} m below its value at x = 0; the profile "
            "must be lowest at x = 0, where it first touches (a convex pad: shift x so that its lowest point is at 0)",
            "h", lowest,
        )
    return profile


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
    if isinstance(value, str) and node.style is None:
        if len(value) > limits.MAX_NUMBER_DIGITS:
            if _LONG_NUMBER.fullmatch(value):
                raise HalfslipInputError(
                    f"a number of {len(value):,} characters: at most {limits.MAX_NUMBER_DIGITS} are read "
                    "(the largest number is 1.8e308)", line=line, field=path or None)
            return value
        try:
            return float(value)
        except ValueError:
            return value
    return value


_LONG_NUMBER = re.compile(r"[-+]?[0-9_]*\.?[0-9_]*(?:[eE][-+]?[0-9]+)?")


def _line_of(field: str | None, lines: Mapping[str, int]) -> int | None:
    """Line of `field`, or of its nearest recorded ancestor."""
    field = field or ""
    while field not in lines and field:
        cut = max(field.rfind("."), field.rfind("["))
        field = field[:cut] if cut > 0 else ""
    return lines.get(field)
