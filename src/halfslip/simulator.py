"""The one time loop: method selection, marching, what to save.

``simulate(scene)`` owns the loop. A tangential method (``solvers/``) offers
``initial_state()`` and ``step(state, t1, loads1) -> (state, report)``; a step
never writes output. What is stored is decided here by :class:`SaveAt`.
"""
from __future__ import annotations

import contextlib
import dataclasses
import gc
import math
import threading
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import xarray as xr

from . import variables
from .cycles import CycleSkipper, SkipState, describe_skips, segment_table
from .geometry import NormalProblem
from .messages import MessageLog, checkpoint_problem
from .progress import progress_for
from .scene import FIELDS, METHODS, check_run_bytes  # FIELDS, METHODS: defined once, in scene.py
from .solvers.base import STATION_STATES
from .state import GROSS_SLIDING_MESSAGE, ContactState, Loads, Regime
CHUNK = 4096  # steps per call of a compiled marcher


class MethodError(ValueError):
    """A method was asked for that cannot serve the scene."""


def exact_method_reason(scene) -> str | None:
    """Why the exact memory method cannot serve ``scene`` (None when it can)."""
    h = scene.history
    if not scene.profile.symmetric:
        return "the profile is not symmetric"
    if np.any(h.M != 0.0):
        return "the moment M is not identically zero"
    if np.any(h.sigma != 0.0):
        return "the bulk tension sigma is not identically zero"
    return None


def choose_method(scene, method: str | None = None) -> str:
    """Resolve ``auto`` to the cheapest method that is exact for the scene."""
    method = method or scene.solver.method
    if method not in METHODS:
        raise MethodError(f"unknown method {method!r}; expected one of {', '.join(METHODS)}")
    reason = exact_method_reason(scene)
    if method == "exact":
        if reason is not None:
            raise MethodError(f"method 'exact' cannot serve this scene: {reason}")
        return "exact"
    if method == "auto":
        return "exact" if reason is None else "general"
    return "general"


@dataclass(frozen=True)
class SaveAt:
    """What the loop stores: every ``every``-th step (and the last), fields at ``x``.

    Attributes
    ----------
    every : int
    fields : tuple of str
        Subset of ('p', 'q', 'slip').
    x : ndarray, shape (nx,)
        Stations of the per-point fields (empty when no fields are stored).
    """

    every: int
    fields: tuple
    x: np.ndarray = field(repr=False)

    def stored(self, i: int, n: int) -> bool:
        return i % self.every == 0 or i == n


#: Most normal solutions contact_edges keeps for the general solver to reuse: about 0.9 kB each (90 MB at
#: most). A periodic history has a cycle's worth of distinct (P, M) (the dovetail 132); a load table up to
#: one per row, and beyond this many its later steps solve as before.
KEPT_NORMALS = 100_000


@dataclass(frozen=True, eq=False)
class ContactEdges:
    """Contact edges of a history's distinct loads (P, M) with P > 0, one normal solve each.

    Attributes
    ----------
    P, M : ndarray, shape (k,)
        The distinct (P, M) samples of the history with P > 0, in the order they first occur.
    left, right : ndarray, shape (k,)
        Contact edges under each of them [m].
    solutions : dict
        The normal solutions themselves, keyed by (P, M) as floats, for the
        first KEPT_NORMALS samples: the general solver takes them instead of
        solving again at the steps that end on them.
    """

    P: np.ndarray = field(repr=False)
    M: np.ndarray = field(repr=False)
    left: np.ndarray = field(repr=False)
    right: np.ndarray = field(repr=False)
    solutions: dict = field(default_factory=dict, repr=False)

    @property
    def extent(self) -> tuple[float, float]:
        """(leftmost left edge, rightmost right edge) over every sample [m]."""
        return float(np.min(self.left)), float(np.max(self.right))

    @property
    def widest(self) -> float:
        """The widest contact right - left over every sample [m]."""
        return float(np.max(self.right - self.left))


def contact_edges(scene, problem: NormalProblem) -> ContactEdges | None:
    """Solve the normal problem once per distinct (P, M) sample of the history with P > 0.

    A periodic history repeats its samples, so this is about one cycle's worth
    of solves however many cycles it has. The samples are taken in the order
    in which they first occur, each solve warm-started from the previous one
    (consecutive samples of a history are close; ``NormalProblem.solve(near=)``
    starts cold by itself when the guess fails). None when the history never
    presses the bodies together.
    """
    h = scene.history
    loads = np.column_stack([np.asarray(h.P, float), np.asarray(h.M, float)])
    loads = loads[loads[:, 0] > 0.0]
    if not loads.size:
        return None
    _, first = np.unique(loads, axis=0, return_index=True)
    loads = loads[np.sort(first)]
    left, right = np.empty(len(loads)), np.empty(len(loads))
    solutions = {}
    sol = None
    for k, (P, M) in enumerate(loads):
        sol = problem.solve(P, M, near=sol)
        left[k], right[k] = sol.left, sol.right
        if k < KEPT_NORMALS:
            solutions[(float(P), float(M))] = sol
    return ContactEdges(loads[:, 0], loads[:, 1], left, right, solutions)


def _closed_form(scene) -> bool:
    """A symmetric profile under M = 0 throughout: the contact is [-a(P), a(P)], no solve needed."""
    return bool(scene.profile.symmetric and not np.any(scene.history.M))


def field_stations(scene, problem: NormalProblem, points: int, edges: ContactEdges | None = None) -> np.ndarray:
    """Evenly spaced stations covering the largest contact of the history, 2 % margin.

    ``edges`` (:func:`contact_edges` of the same scene and problem) saves the
    solves when the caller has it already; without it the profile is solved here
    (unless it is symmetric under M = 0: then a(max P) is the closed form).
    """
    h = scene.history
    P_max = float(np.max(h.P)) if h.P.size else 0.0
    if P_max <= 0:
        return np.linspace(-1.0, 1.0, points) * problem.profile.length_scale
    if _closed_form(scene):
        half = float(problem.half_width(P_max))
        return np.linspace(-1.02 * half, 1.02 * half, points)
    if edges is None:
        edges = contact_edges(scene, problem)
    left, right = edges.extent
    margin = 0.02 * (right - left)
    return np.linspace(left - margin, right + margin, points)


def build_method(scene, name: str, problem: NormalProblem, stations: np.ndarray | None,
                 edges: ContactEdges | None = None):
    """Instantiate the tangential method ``name`` for ``scene`` (``edges`` as in :func:`field_stations`)."""
    P_max = float(np.max(scene.history.P)) if scene.history.P.size else 0.0
    if name == "exact":
        from .solvers.exact import ExactMemory

        return ExactMemory(problem, scene.friction, P_max, stations=stations)
    from .solvers.general import GeneralSolver

    return GeneralSolver(problem, scene.friction, scene.solver.nodes, stations=stations,
                         width=reference_width(scene, problem, edges), travel=scene.solver.edge_travel,
                         normals=None if edges is None else edges.solutions, edge_windows=scene.solver.edge_windows)


def reference_width(scene, problem: NormalProblem, edges: ContactEdges | None = None) -> float | None:
    """The widest contact over every distinct (P, M) sample of the history [m].

    The general solver's lattice spacing is this width / solver.nodes for the
    whole run (None when the history never presses the bodies together). A
    symmetric profile under M = 0 needs no solve: the widest contact is
    2 a(max P). Otherwise the normal problem is solved once per distinct
    sample (:func:`contact_edges`; ``edges`` as in :func:`field_stations`).
    """
    h = scene.history
    P = np.asarray(h.P, float)
    if not np.any(P > 0.0):
        return None
    if _closed_form(scene):
        return 2.0 * float(problem.half_width(float(np.max(P))))
    if edges is None:
        edges = contact_edges(scene, problem)
    return edges.widest


#: A slip zone narrower than this many cells (contact width / nodes) leaves slip and dissipation
#: under-resolved: on the dovetail example (widest zone 1.2 % of the contact) the dissipation per
#: cycle is 2.2 % off at 500 nodes (5.8 cells), 0.24 % at 1000 (11.9 cells), 0.07 % at 2000,
#: against 4000 nodes (docs/general_solver.md); the slip amplitude read at stations is worse
#: (17 % high at its peak at 1000 nodes, docs/user_guide.md). With solver.edge_windows a slip zone at a contact
#: edge within the windows' reach is resolved on their cells, REFINE times finer: the dovetail's dissipation per
#: cycle is then 0.09 % off at 500 nodes and 0.06 % at 1000, against 16000 (docs/general_solver.md).
RESOLVED_SPACINGS = 16.0


def resolving_spacings(spacings: float, windows: bool, nodes: int) -> float:
    """A slip zone at a contact edge of ``spacings`` lattice spacings in the spacings that resolve it: the windows'
    (refine to a lattice spacing) with ``windows`` where it lies within their reach (their cells less BUFFER)."""
    from .solvers._windows import BUFFER, window_size

    cells, refine = window_size(nodes)
    return refine * spacings if windows and refine >= 2 and spacings <= cells - BUFFER else spacings


def slip_zone_spacings(ds: xr.Dataset, nodes: int) -> float:
    """Widest slip zone of the stored steps in lattice spacings W / nodes (0 when nothing slipped)."""
    slipping = ds["regime"].values == int(Regime.PARTIAL_SLIP)
    if not np.any(slipping):
        return 0.0
    L, R = ds["contact_left"].values[slipping], ds["contact_right"].values[slipping]
    b1, b2 = ds["stick_left"].values[slipping], ds["stick_right"].values[slipping]
    zones = np.maximum(b1 - L, R - b2) / ((R - L) / nodes)
    return float(np.nanmax(zones)) if np.isfinite(zones).any() else 0.0


def _dtype(name: str):
    """Storage type of a per-step column: the regime code, the converged flag and the stick-interval count
    are int8, the step index int64, the rest float."""
    if name == "step":
        return np.int64
    return np.int8 if name in ("regime", "converged", "stick_intervals") else float


class _Records:
    """Column buffers of the stored steps.

    Single steps go to a scalar buffer; chunks of steps from a compiled marcher
    are kept as arrays. ``column(name)`` joins both in order.
    """

    names = ("t", "step", "P", "Q", "M", "sigma", "contact_left", "contact_right",
             "stick_left", "stick_right", "regime", "rigid_shift", "dissipation", "converged", "residual",
             "error_estimate", "shear_error_estimate", "stick_intervals")

    def __init__(self):
        self.chunks = {k: [] for k in self.names}
        self.buffer = {k: [] for k in self.names}
        self.fields = {}

    def _flush(self):
        if self.buffer["t"]:
            for k in self.names:
                self.chunks[k].append(np.asarray(self.buffer[k], _dtype(k)))
                self.buffer[k] = []

    def add(self, step: int, state: ContactState, regime: Regime, converged: bool = True, residual: float = 0.0,
            stick_intervals: int = 1, error_estimate: float = 0.0, shear_error_estimate: float = 0.0):
        c = self.buffer
        c["t"].append(state.t)
        c["step"].append(step)
        for k, v in zip(("P", "Q", "M", "sigma"), state.loads):
            c[k].append(v)
        c["contact_left"].append(state.contact_left)
        c["contact_right"].append(state.contact_right)
        c["stick_left"].append(state.stick_left)
        c["stick_right"].append(state.stick_right)
        c["regime"].append(int(regime))
        c["rigid_shift"].append(state.shift)
        c["dissipation"].append(state.dissipation)
        c["converged"].append(int(converged))
        c["residual"].append(residual)
        c["error_estimate"].append(error_estimate)
        c["shear_error_estimate"].append(shear_error_estimate)
        c["stick_intervals"].append(stick_intervals)

    def add_steps(self, steps: dict, mask: np.ndarray):
        """Append the masked entries of per-step arrays (keys as ``names``)."""
        self._flush()
        n = len(mask)
        defaults = {"converged": np.ones(n, np.int8), "residual": np.zeros(n),  # an exact marcher: always met
                    "error_estimate": np.zeros(n), "shear_error_estimate": np.zeros(n),
                    "stick_intervals": np.isfinite(np.asarray(steps["stick_left"], float)).astype(np.int8)}
        for k in self.names:
            self.chunks[k].append(np.asarray(steps.get(k, defaults.get(k)), _dtype(k))[mask])

    def add_fields(self, values: dict):
        for k, v in values.items():
            self.fields.setdefault(k, []).append(v)

    def column(self, name: str) -> np.ndarray:
        self._flush()
        parts = self.chunks[name]
        return np.concatenate(parts) if parts else np.zeros(0, _dtype(name))

    def load(self, ds: xr.Dataset, fields) -> None:
        """Start from the stored steps of an unfinished run."""
        n = ds.sizes["t"]
        for k in self.names:
            # a run written before the variable existed (0.3.0: shear_error_estimate) resumes with NaN there
            self.chunks[k] = [np.asarray(ds[k].values if k in ds else np.full(n, np.nan), _dtype(k))]
            self.buffer[k] = []
        for k in (*fields, "state") if fields else ():
            self.fields[k] = list(np.asarray(ds[k].values, np.int8 if k == "state" else float))


def simulate(
    scene,
    *,
    method: str | None = None,
    nodes: int | None = None,
    progress: bool | Callable[[int, int], None] | None = None,
    writer=None,
    resume=None,
    stop_requested: Callable[[], bool] | None = None,
) -> xr.Dataset:
    """March ``scene``'s load history and return the result dataset of interface.md.

    Parameters
    ----------
    scene : Scene
    method : {'auto', 'exact', 'general'}, optional
        Overrides ``scene.solver.method``.
    nodes : int, optional
        Overrides ``scene.solver.nodes`` (general solver resolution).
    progress : bool, callable(i, n) or progress.Progress, optional
        True shows a progress bar (on a terminal or in a notebook,
        :mod:`halfslip.progress`): its total drops when steady cycles are
        skipped, and its time left follows the recent rate. A callable is
        called after each step (or skip) with the step index reached and the
        number of steps.
    writer : io.RunFileWriter, optional
        Receives the partial result and a checkpoint whenever it is due, and the
        final result; a killed process loses at most what came after the last write.
    resume : tuple (Dataset, checkpoint), optional
        An unfinished run (``io.read_result`` and ``io.read_checkpoint`` of its
        file) to continue; the final result equals an uninterrupted run's.
    stop_requested : callable() -> bool, optional
        Polled between steps; when it returns True the run stops as if
        interrupted (the command line sets it from SIGINT / SIGTERM, so a step
        is never cut in half).

    Returns
    -------
    xarray.Dataset
        Variables of interface.md; attribute ``complete`` is 0 when the run was
        interrupted (KeyboardInterrupt), in which case every completed stored step
        is present.
    """
    if nodes is not None:
        scene = dataclasses.replace(scene, solver=dataclasses.replace(scene.solver, nodes=int(nodes)))
    name = choose_method(scene, method)
    check_run_bytes(scene, name)  # the scene was checked for its own method; this one may differ
    run = _Run(scene, name)
    if resume is not None:
        run.restore(*resume)
    h = scene.history
    n = h.n_steps
    started = time.perf_counter()
    bar = progress_for(progress, "step", scene.name)
    skipped = run.skipped_steps()
    bar.start(n - skipped, run.i - skipped)
    with _heap_frozen():
        try:
            while run.i < n:
                if stop_requested is not None and stop_requested():
                    raise KeyboardInterrupt
                before = run.i
                if resume is not None and run.i == int(resume[1]["i"]):
                    _first_step_after_resume(run)
                else:
                    run.advance()
                skipped, newly = run.skipped_steps(), run.skipped_steps() - skipped
                bar.advance(run.i - before - newly, newly)
                if writer is not None and writer.due():
                    writer.write(run.dataset(complete=0, elapsed=time.perf_counter() - started), run.checkpoint(
                        time.perf_counter() - started))
        except KeyboardInterrupt:
            ds = run.dataset(complete=0, elapsed=time.perf_counter() - started)
            if writer is not None:
                writer.write(ds, run.checkpoint(time.perf_counter() - started))
            return ds
        finally:
            bar.close()
    ds = run.dataset(complete=1, elapsed=time.perf_counter() - started)
    _add_permanent_stick(ds)
    if writer is not None:
        writer.write(ds)
    return ds


_FROZEN_LOCK = threading.Lock()
_frozen = {"marches": 0, "ours": False}
"""The marches inside :func:`_heap_frozen` (several at once where simulate runs in threads, as on a dask
worker), and whether the freeze is theirs to undo: the count is changed under the lock, so that the last one
out unfreezes exactly when the first one in froze an unfrozen heap."""


@contextlib.contextmanager
def _heap_frozen():
    """The objects that exist before the march are left out of the garbage collector's passes while it runs
    (:func:`gc.freeze`; :func:`gc.unfreeze` after, so that they are collected as before). A full pass otherwise
    walks every object the imports made (about 140,000: numpy's, scipy's, xarray's, numba's and llvmlite's):
    `halfslip run examples/dovetail.yaml` in one process, the command's own freeze (halfslip_launch) left
    out, had one full pass of 73 ms during the march without it and none with it. Objects made during the
    march are collected as usual; a cycle among the older ones that becomes garbage meanwhile waits to the
    end of the run. Where objects are frozen already (the ``halfslip`` command froze its imports) the freeze
    is theirs to undo: it is kept; where marches overlap (threads) the last one out undoes it."""
    with _FROZEN_LOCK:
        if _frozen["marches"] == 0:
            _frozen["ours"] = gc.get_freeze_count() == 0
        _frozen["marches"] += 1
        gc.freeze()
    try:
        yield
    finally:
        with _FROZEN_LOCK:
            _frozen["marches"] -= 1
            if _frozen["marches"] == 0 and _frozen["ours"]:
                gc.unfreeze()


def _first_step_after_resume(run: _Run) -> None:
    """The first step from a checkpoint read back from a file.

    The checkpoint is pure data of the right record kinds and shape
    (``_Run.restore``), but a file edited by hand can still hold a memory whose
    arrays do not fit together; the first step is where that shows. It is
    reported as a refused checkpoint, not a traceback: an unedited checkpoint
    is a state the uninterrupted run had, so its first step cannot fail here.
    """
    from .errors import HalfslipInputError

    try:
        run.advance()
    except (ValueError, IndexError, TypeError, KeyError, AttributeError, ZeroDivisionError,
            FloatingPointError) as error:
        raise HalfslipInputError(f"the run cannot continue from its checkpoint ({type(error).__name__}); "
                                 "the file was changed after halfslip wrote it", field="--resume") from None


def _add_permanent_stick(ds: xr.Dataset) -> None:
    """Scalars permanent_stick_left/right of the last full cycle (cyclic histories only)."""
    from . import post
    from .errors import HalfslipInputError

    try:
        zone = post.permanent_stick(ds)
    except HalfslipInputError:  # no cycles segment, or no full cycle stored
        return
    for side in ("left", "right"):
        ds[f"permanent_stick_{side}"] = ((), float(zone[side]), variables.attrs(f"permanent_stick_{side}"))


def scene_hash(scene) -> str:
    """SHA-256 of the scene text (of its repr for a scene built in Python)."""
    import hashlib

    from .scene import scene_fingerprint

    text = scene.text if scene.text is not None else scene_fingerprint(scene)
    return hashlib.sha256(text.encode()).hexdigest()


class _Run:
    """Everything one march carries: solver, state, stored records, counters.

    Only :func:`simulate` drives it; ``advance`` takes one step (or skips the
    rest of a steady periodic segment).
    """

    def __init__(self, scene, name: str):
        self.scene = scene
        self.name = name
        self.problem = NormalProblem(scene.profile, scene.material.compliance)
        fields = tuple(f for f in FIELDS if f in scene.output.fields)
        # the contact edges of every distinct load, solved once for the stations and the general solver's width
        edges = None if _closed_form(scene) else contact_edges(scene, self.problem)
        x = field_stations(scene, self.problem, scene.output.points, edges) if fields else np.zeros(0)
        self.save = SaveAt(scene.output.every, fields, x)
        self.solver = build_method(scene, name, self.problem, x if "slip" in fields else None, edges)
        h = scene.history
        self.i = 0
        self.state = self.solver.initial_state(float(h.t[0]))
        self.rec = _Records()
        self.counters = {"steps": 0, "stick_steps": 0, "slip_solves": 0, "normal_solves": 0, "failed_steps": 0}
        self.log = MessageLog()
        self.skipper = CycleSkipper(h, self.solver) if scene.solver.skip_steady_cycles else None
        self.skip = SkipState()  # what the skipper has seen: replaced, never changed, and checkpointed
        self.elapsed_before = 0.0
        # compiled marching of many steps at once where the solver offers it (extents only)
        self.chunked = not fields and self.solver.can_march
        self._store(0, self.state, Regime.SEPARATED)

    def skipped_steps(self) -> int:
        """Steps of the history skipped so far as repeats of a steady cycle."""
        segments = self.scene.history.segments
        return sum(skip.count * segments[k].steps_per_cycle for k, skip in self.skip.skipped.items())

    def _store(self, i: int, state: ContactState, regime: Regime, converged: bool = True,
               residual: float = 0.0, error_estimate: float = 0.0, shear_error_estimate: float = 0.0) -> None:
        self.rec.add(i, state, regime, converged, residual, self.solver.stick_intervals(state), error_estimate,
                     shear_error_estimate)
        if self.save.fields:
            self.rec.add_fields(_fields(self.solver, state, self.save))

    def advance(self) -> None:
        """One step, or with a compiled solver a chunk of steps up to the next cycle end."""
        if self.chunked:
            self._advance_chunk()
            return
        h = self.scene.history
        n = h.n_steps
        i = self.i + 1
        loads1 = Loads(float(h.P[i]), float(h.Q[i]), float(h.M[i]), float(h.sigma[i]))
        state, report = self.solver.step(self.state, float(h.t[i]), loads1)
        c = self.counters
        c["steps"] += 1
        c["slip_solves"] += report.slipped
        c["stick_steps"] += report.regime == Regime.STICK
        c["normal_solves"] += report.normal_solved
        c["failed_steps"] += not report.converged
        if report.message:
            self.log.add_text(i, float(h.t[i]), report.message, {"gross_sliding": _shear_ratio(loads1, self.scene.friction)})
        jump = None
        if self.skipper is not None:
            self.skip = self.skipper.observe(self.skip, i, state)
            self.skip, jump = self.skipper.check(self.skip, i, state)
        # a failed step is always stored, and so is the last marched step before a skip
        if self.save.stored(i, n) or jump is not None or not report.converged:
            self._store(i, state, report.regime, report.converged, report.residual, report.error_estimate,
                        report.shear_error_estimate)
        self.i, self.state = (i, state) if jump is None else jump

    def _advance_chunk(self) -> None:
        h = self.scene.history
        n = h.n_steps
        i0 = self.i
        stop = min(n, i0 + CHUNK)
        if self.skipper is not None:
            stop = min(stop, self.skipper.next_end(i0))
        idx = np.arange(i0 + 1, stop + 1)
        state, steps = self.solver.march(self.state, h.t[idx], h.P[idx], h.Q[idx])
        regime = steps["regime"]
        c = self.counters
        c["steps"] += len(idx)
        c["slip_solves"] += int(np.count_nonzero(regime >= Regime.PARTIAL_SLIP))
        c["stick_steps"] += int(np.count_nonzero(regime == Regime.STICK))
        c["normal_solves"] += int(np.count_nonzero(steps["normal_solved"]))
        gross = (regime == Regime.GROSS_SLIDING) & (np.abs(h.Q[idx]) > self.scene.friction * h.P[idx] * (1 + 1e-12))
        if gross.any():
            at = idx[gross]
            ratio = np.abs(h.Q[at]) / (self.scene.friction * h.P[at])
            self.log.add_many("gross_sliding", at, h.t[at], ratio, GROSS_SLIDING_MESSAGE)
        mask = (idx % self.save.every == 0) | (idx == n)
        jump = None
        if self.skipper is not None:
            self.skip, jump = self.skipper.check(self.skip, stop, state)
        if jump is not None:
            mask[-1] = True  # the last marched step before a skip is stored, as in the step path
        steps.update(t=h.t[idx], step=idx, P=h.P[idx], Q=h.Q[idx], M=h.M[idx], sigma=h.sigma[idx])
        steps["rigid_shift"] = steps.pop("shift")
        self.rec.add_steps(steps, mask)
        self.i, self.state = (stop, state) if jump is None else jump

    def dataset(self, complete: int, elapsed: float) -> xr.Dataset:
        from ._version import __version__

        ds = _dataset(self.rec, self.save)
        scene = self.scene
        log = self.log.copy()
        skip = None if self.skipper is None else self.skip
        ds = ds.assign(segment_table(scene.history, skip))
        for name, value in (("final_t", self.state.t), ("final_dissipation", self.state.dissipation)):
            ds[name] = ((), float(value), variables.attrs(name))
        ds.attrs.update(
            {
                "title": f"halfslip run of {scene.name}",
                "scene": scene.text if scene.text is not None else "",
                "scene_sha256": scene_hash(scene),
                "scene_name": scene.name,
                "method": self.name,
                "halfslip_version": __version__,
                "complete": complete,
                "steps_done": self.i,
                "friction": scene.friction,
                "compliance": scene.material.compliance,
                "shift_datum": self.solver.datum,
                "wall_time": self.elapsed_before + elapsed,
                "messages": "",
                "output_every": scene.output.every,
                "skipped_cycles": self.skip.total,
                "skipped_cycles_per_segment": describe_skips(skip),
                **{f"count_{k}": v for k, v in self.counters.items()},
            }
        )
        if self.name == "general":
            ds.attrs["solver_tol"] = scene.solver.tol
            ds.attrs["solver_nodes"] = scene.solver.nodes
            ds.attrs["solver_edge_windows"] = int(scene.solver.edge_windows)
            spacings = slip_zone_spacings(ds, scene.solver.nodes)
            ds.attrs["widest_slip_zone_spacings"] = spacings
            if 0.0 < resolving_spacings(spacings, scene.solver.edge_windows, scene.solver.nodes) < RESOLVED_SPACINGS:
                note = (f"the widest slip zone spans only {spacings:.3g} lattice spacings: slip and dissipation are "
                        f"resolved to a few per cent (raise solver.nodes towards "
                        f"{int(math.ceil(RESOLVED_SPACINGS / spacings * scene.solver.nodes))})")
                log.add(self.i, float(scene.history.t[self.i]), "slip_zone_resolution", spacings, note)
        # the 0.1 form, kept for one release: the distinct texts, one a line (read message_* instead)
        ds.attrs["messages"] = "\n".join(log.texts())
        return ds.assign(log.variables())

    def checkpoint(self, elapsed: float) -> dict:
        return {
            "i": self.i,
            "state": self.state,
            "counters": dict(self.counters),
            "messages": self.log.checkpoint(),
            "elapsed": self.elapsed_before + elapsed,
            "skipper": None if self.skipper is None else self.skip.to_tree(),
        }

    def restore(self, ds: xr.Dataset, checkpoint: dict) -> None:
        """Continue from an unfinished run: its stored records and its checkpoint."""
        from .errors import HalfslipInputError

        if ds.attrs.get("scene_sha256") != scene_hash(self.scene):
            raise HalfslipInputError("the file to resume was written by a different scene", field="--resume")
        if ds.attrs.get("method") != self.name:
            raise HalfslipInputError(f"the file to resume was run with method {ds.attrs.get('method')!r}",
                                     field="--resume")
        if checkpoint is None:
            raise HalfslipInputError("the file holds a finished run: nothing to resume", field="--resume")
        problem = self._checkpoint_problem(ds, checkpoint)
        if problem is not None:
            raise HalfslipInputError(f"its checkpoint does not fit this run: {problem}", field="--resume")
        self.rec = _Records()
        self.rec.load(ds, self.save.fields)
        self.i = int(checkpoint["i"])
        self.state = checkpoint["state"]
        self.counters = dict(checkpoint["counters"])
        self.log = MessageLog.from_checkpoint(checkpoint["messages"])
        self.elapsed_before = float(checkpoint["elapsed"])
        if self.skipper is not None and checkpoint["skipper"] is not None:
            self.skip = SkipState.from_tree(checkpoint["skipper"])

    def _checkpoint_problem(self, ds: xr.Dataset, checkpoint) -> str | None:
        """What is wrong with a decoded checkpoint for this run (None when it fits).

        The decoder guarantees pure data of known record kinds; this checks the
        shape a run writes, so that a file edited by hand is refused here
        rather than failing somewhere in the march.
        """
        keys = {"i", "state", "counters", "messages", "elapsed", "skipper"}
        if not isinstance(checkpoint, dict) or set(checkpoint) != keys:
            return f"expected the entries {sorted(keys)}"
        i = checkpoint["i"]
        if not isinstance(i, int) or not 0 <= i <= self.scene.history.n_steps:
            return f"step {i!r} is not a step of this history"
        state = checkpoint["state"]
        memory_type = type(self.state.memory)
        if not isinstance(state, ContactState) or not isinstance(state.memory, memory_type):
            return f"its state is not a {memory_type.__name__} state of method {self.name}"
        if state.t != float(self.scene.history.t[i]):
            return f"its state is at t = {state.t!r}, not at step {i}"
        counters = checkpoint["counters"]
        if not (isinstance(counters, dict) and set(counters) == set(self.counters)
                and all(isinstance(v, int) and v >= 0 for v in counters.values())):
            return "its counters are malformed"
        problem = checkpoint_problem(checkpoint["messages"])
        if problem is not None:
            return problem
        if not isinstance(checkpoint["elapsed"], float):
            return "its elapsed time is not a number"
        if "step" not in ds.variables or "segment_kind" not in ds.variables:
            return "the file was written by halfslip 0.2 or older (no step index, no segment table); run it again"
        skipper = checkpoint["skipper"]
        if skipper is not None:
            try:
                skip = SkipState.from_tree(skipper)
            except (TypeError, ValueError, KeyError, AttributeError):
                return "its cycle skipper state is malformed"
            segments = range(len(self.scene.history.segments))
            if not all(k in segments for k in (*skip.previous, *skip.skipped, *skip.traces)):
                return "its cycle skipper names segments this history does not have"
            if not all(isinstance(s, ContactState) and isinstance(s.memory, memory_type) for s in skip.previous.values()):
                return f"its cycle skipper holds states that are not {memory_type.__name__} states"
        if int(ds.sizes.get("t", 0)) > i + 1:
            return "the file stores more steps than the checkpoint has marched"
        return None


def _shear_ratio(loads: Loads, friction: float) -> float:
    """abs(Q) / (f P): above 1 the contact slides as a whole."""
    carried = friction * loads.P
    return abs(loads.Q) / carried if carried > 0 else math.inf


def _fields(solver, state: ContactState, save: SaveAt) -> dict:
    out = {}
    mem = state.memory
    p, q = solver.tractions(mem, save.x)
    out["state"] = solver.station_states(state, save.x, q)  # whenever fields are stored
    if "p" in save.fields:
        out["p"] = p
    if "q" in save.fields:
        out["q"] = q
    if "slip" in save.fields:
        out["slip"] = solver.slip(mem)
    return out




def _dataset(rec: _Records, save: SaveAt) -> xr.Dataset:
    t = rec.column("t")
    data = {}
    for k in rec.names[1:]:
        data[k] = ("t", rec.column(k))
    coords = {"t": t}
    if save.fields:
        coords["x"] = save.x
        for k, rows in rec.fields.items():
            data[k] = (("t", "x"), np.asarray(rows, np.int8 if k == "state" else float))
    ds = xr.Dataset(data, coords=coords)
    for k in ds.variables:
        ds[k].attrs.update(variables.attrs(k))
    ds["t"].attrs["axis"] = "T"
    if "x" in ds.coords:
        ds["x"].attrs["axis"] = "X"
    ds.attrs["Conventions"] = "CF-1.10"
    ds["regime"].attrs.update(flag_values=Regime.flag_values(), flag_meanings=Regime.flag_meanings())
    if "state" in ds:
        ds["state"].attrs.update(flag_values=np.arange(4, dtype=np.int8), flag_meanings=STATION_STATES)
    return ds
