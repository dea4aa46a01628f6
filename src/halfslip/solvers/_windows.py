"""Fine windows at the contact edges of the general solver (``edge_windows``; docs/general_solver.md).

After every fine take of :class:`~halfslip.solvers.general.GeneralSolver` (a step or a sub-step), the first and
the last :data:`WINDOW_CELLS` lattice cells of the contact are solved again on cells :data:`REFINE` times finer,
on their own (a sub-model, one-way coupled to the lattice):

* unknowns: the fine cells' shear (cells fixed in space, aligned with the lattice's) and a rigid offset c of
  the window; bounds f x each fine cell's load (the pressure integrated over it; the end cell reaches to the
  contact edge);
* driven by the lattice's answer outside the window (its shear there, its rigid shift and the bulk term),
  fixed; the window carries the force the lattice's cells carry there, so c is free and not kept;
* locks: each fine cell's displacement at the take's start from the composite state (the lattice's shear
  outside the windows the state carries, those windows' own fine shear inside them: the windows keep their
  history, :attr:`GeneralMemory.windows`); cells that arrive in the take lock M1's increments, or, where the
  lattice's take slipped in part and sized its arrivals, the arrivals' shape with the lattice's size there;
* the active set on the dense window (_toeplitz.window_active_set: its stuck cells solved by the fine kernel's
  Toeplitz tables where they are one run, by LU otherwise; a pattern repeated or :data:`WINDOW_ITERATIONS`
  iterations: not converged, and that side keeps the lattice's edge);
* its outermost stick point on its side, placed by the lattice's own rule (_run_edges) on the fine cells,
  replaces the lattice's, unless it falls within :data:`BUFFER` lattice cells of the window's inner end (there
  the window's cut-off boundary, not the contact, sets it);
* its slip and dissipation: each fine cell's slip in the take (its displacement less its lock, 0 where stuck)
  accumulates as the lattice's cells' does, and the take's dissipation takes the fine cells' f (cap0 + cap) / 2
  |slip| hf in place of the lattice's cells under the window (the end cell's cap0 reaching to where the
  contact was, as the lattice's end cell carries the material that leaves in the take; the lattice's cells that
  leave keep theirs). Where the window's cells within BUFFER lattice cells of its inner end slip (a slip zone
  reaching the cut) the lattice's slip and dissipation stand.

The windows change the reported outermost stick points, the shear, slip and station states at the stations on
their cells (GeneralSolver.tractions, slip, station_states) and the dissipation; the lattice's own state (its
cells, its sub-steps, its estimate) is the same with or without them. Measured (2026-11-29,
benchmarks/bench_edge_windows.py, docs/benchmarks.md): the rounded punch's random histories at 512 nodes, 95th
percentile of the vouched stick edges 2.7e-4 -> 9.6e-5 of the width (Hertz 6.1e-5 -> 6.0e-5: set inside the
contact), 5.0 -> 7.6 ms a step; the dovetail (every step marched) at 1000 nodes against 16000, 95th percentile
2.1e-4 -> 6.1e-5, 1.14 -> 1.89 ms a step (its largest, 3.4e-3, is the load maximum's ill-conditioned band, which
they leave as it is), dissipation per cycle 0.31 % -> 0.06 % off (against 16000 nodes). (Times on a slower
machine than 0.4.6's 2.6 -> 4.9 and 0.57 -> 1.21.)

A window is a handful of compiled calls (since 0.4.7; the same numbers as the numpy they replaced, to the last
bit): :func:`_prologue` (bounds, pattern, centres, force), :func:`_drive_and_locks` (drive and locks as
displacements at the fine centres, :func:`_field`), _toeplitz.window_active_set (since 0.4.10, in place of a dense
LU in each iteration: the same answers to rounding), :func:`_window_slip`, :func:`_slip_parts` (dissipation, accumulated
slip), :func:`_padded` and the lattice's _run_edges (the edge), general._fine_cell_loads (the loads, kept per
contact, as are the end cells' columns at the fine centres); the dovetail's windows 0.86 -> 0.53 ms a step
against 0.4.6 (A/B, one session).

The estimate: where both outermost stick points are the windows' (and bound the lattice's widest stick interval),
the step's error estimate is the windows' own (:meth:`EdgeWindows._own_error`: each edge's distance from the
lattice's, its placement on the fine cells, the floor of a fine cell); elsewhere the lattice's, at least the
windows' distance from it. Either way a window's edge far from the lattice's says so.

Check windows (since 0.4.11, :data:`CHECKS`): where a side's outermost stick point stays the lattice's (inside the
contact, beyond the windows' reach), a window of the same cells is solved around it (:meth:`EdgeWindows._check`:
both its ends cuts, its stuck cells' locks from the state at the take's start with the lattice cells' wiggle taken
out, :func:`_smooth_locks`) and not kept: it measures where the lattice put its edge. That side's estimate is then
the check's distance from the lattice's edge and its own placement together, at least the two lattices' distance
on that side (GeneralSolver._finish), in place of the lattice's placement floor (EDGE_PLACEMENT of a lattice
cell), which set 90 % of the random histories' estimates above `solver.tol` at the default resolution. Kept as
moving windows (their edges reported, the first design) they came out worse than the lattice on the rounded punch
(docs/general_solver.md, "Check windows"): a window that moves inherits the lattice's history, so it can check
its edge but not improve on it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from .._geometry_kernels import pairwise_sum
from ._toeplitz import ToeplitzLattice, kernel, window_active_set

#: Fine cells per lattice cell in a window (fewer where a window would have more than MAX_FINE_CELLS). Since 0.4.10
#: 6 (4 before): at the default 1000 nodes (solver.tol 1e-4) half a fine cell, where an edge is only bracketed,
#: is 8.3e-5 of the reference width, below the tolerance (1.25e-4 with 4). With the estimate's distance counted
#: beyond the lattice's own placement (EdgeWindows._own_error) 1 % of the dovetail's marched steps report an
#: estimate above it, 23 % with 4 (docs/general_solver.md, "Windows at the tolerance").
REFINE = 6
#: Lattice cells a window spans at each contact edge (the first and last cells of the contact), at least: a
#: window spans WINDOW_WIDTH of the reference width (window_size).
WINDOW_CELLS = 16
#: The width a window spans, as a fraction of the reference width (the solver's ``width``: nodes cells): its
#: reach, less BUFFER cells, is to cover the slip zones it resolves, and the dovetail's are 1.2 % of the contact
#: (docs/general_solver.md): 16 cells at 1000 nodes reach 12. Sized in cells instead, 16 cells at 2000 nodes
#: stopped short of them (edges 1.1e-4 of the width at the 95th percentile against 7.8e-6 with 32 cells).
WINDOW_WIDTH = 0.016
#: Fine cells a window has at most: its dense active set costs their cube (REFINE is lowered to keep within it,
#: and at REFINE 1 there is no window: from 8000 nodes the lattice is as fine as the windows at 2000).
MAX_FINE_CELLS = 128
#: A window's stick edge within this many lattice cells of its inner end is left to the lattice: the window is
#: cut off there (the lattice's shear held fixed beyond it), so an edge there is the cut's, not the contact's
#: (tests/test_windows.py: without it the J1/J2 edges at 256 nodes come out worse than the lattice's).
BUFFER = 4
#: A window whose lattice cells all slip is not solved where the lattice's outermost stick point on its side lies
#: farther from the contact edge than the window's reach (WINDOW_CELLS - BUFFER cells) and this many cells more
#: (half a cell: where the lattice brackets an edge, it puts it to half a cell): its edge would fall within BUFFER
#: cells of its cut and its slip zone reach the cut, and the lattice's edge, slip and dissipation would stand; its
#: fine cells are put at their bounds (EdgeWindows._slipping), the history its next solve locks from (without
#: it, restarting from the lattice's shear, the punch's J2 edge 1.3 cells from the contact edge came out 2.2e-4
#: of the width off against the lattice's 3.2e-5).
REACH_MARGIN = 0.5
#: A window solved around the lattice's outermost stick point where it lies beyond the contact edges' windows'
#: reach, to check the lattice's edge (EdgeWindows._check; since 0.4.11).
CHECKS = True
#: Active-set iterations at most for a window.
WINDOW_ITERATIONS = 60
#: The rounding a window's cell loads may take from _Load's closed form, relative to a fine cell's mean load
#: (the lattice's LOAD_ROUNDING is 1e-11, for its gross sliding q = f p and int q = Q to rounding): on the rounded
#: punch's random histories the closed form rounds to 1.5e-11 of a fine cell's load in the median, 5e-10 at most,
#: and the lattice's limit sent all but 3 % of its windows to the quadrature (0.1 ms a window); a window's bounds
#: need no more (its active set's Coulomb tolerance is 1e-10 of its largest bound, its edges and slip are placed
#: to a thousandth of a cell at best).
WINDOW_LOAD_ROUNDING = 1e-9


@dataclass(frozen=True)
class EdgeWindow:
    """The fine shear of one window after a take.

    Attributes
    ----------
    side : int
        -1 at the left contact edge, +1 at the right one.
    first : int
        Fine index of its first cell (centres at (first + k + 1/2) spacing).
    spacing : float
        Fine cell width [m] (the lattice's / REFINE).
    q : ndarray
        Shear of each fine cell [Pa] (its mean over the cell: spacing sum q is the force it carries).
    capacity : ndarray
        Mean pressure over each fine cell [Pa] (the end cell's over the cell reaching to the contact edge).
    status : ndarray of int8
        0 stuck, +1 / -1 slipping forward / backward in the take (unconverged: the last iterate's).
    G : ndarray
        Slip accumulated since each fine cell entered contact [m] (the lattice's as it reads at the cell's centre
        until a window first covered it, and where the window falls back to the lattice's slip).
    lo, hi : int
        The memory's cells (lo .. hi - 1, as indices of its arrays) the window stands in for.
    lattice_edge : float
        The lattice's own outermost stick point on this side after the take [m] (what the solver's step-size
        control measures the travel of stick edges from: the windows leave the lattice as it is).
    dissipation : float
        What the window changed the take's dissipation by [J/m]: its fine cells' f (cap0 + cap) / 2 |slip|
        hf in place of the lattice's cells lo .. hi - 1 (0 where it did not converge or a slip zone reaches
        its cut: EdgeWindows._slip).
    lattice_placement : float
        How far the lattice's edge ``lattice_edge`` may be from where the lattice put it, in lattice cells
        (_run_edges' placement: 0 placed by its rule, 0.3 a slip zone inside its end cell, 0.5 bracketed): the
        window's error estimate counts its distance from that edge beyond it (EdgeWindows._own_error; since
        0.4.10, 0 in a checkpoint from before, where the whole distance counted).
    """

    side: int
    first: int
    spacing: float
    q: np.ndarray
    capacity: np.ndarray
    status: np.ndarray
    G: np.ndarray
    lo: int
    hi: int
    lattice_edge: float
    dissipation: float
    lattice_placement: float = 0.0

    def at(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(inside, j): which of the points ``x`` lie on the window's cells (its end cell reaching to the contact
        edge, the points in contact there being the caller's) and the fine cell of each (clipped)."""
        n = self.q.size
        j = np.floor(x / self.spacing).astype(np.int64) - self.first
        return (j < n if self.side < 0 else j >= 0), np.clip(j, 0, n - 1)


def window_size(nodes: int) -> tuple[int, int]:
    """(cells, refine) of the windows of a solver of ``nodes`` cells across its reference width: WINDOW_WIDTH of
    it, at least WINDOW_CELLS cells, refined REFINE times or as much as MAX_FINE_CELLS allows (refine < 2: no
    windows)."""
    cells = max(WINDOW_CELLS, math.ceil(WINDOW_WIDTH * nodes - 1e-9))
    return cells, min(REFINE, MAX_FINE_CELLS // cells)


class EdgeWindows:
    """The windows of one :class:`GeneralSolver`: kernel tables per lattice spacing and :meth:`solve`; ``refine``
    and ``cells`` by default from the solver's nodes (:func:`window_size`). ``general`` is the solver's module
    (halfslip.solvers.general, which imports this one): its lattice's parts, taken as they are."""

    def __init__(self, solver, general, refine: int | None = None, cells: int | None = None):
        sized_cells, sized_refine = window_size(solver.nodes)
        refine = sized_refine if refine is None else refine
        cells = sized_cells if cells is None else cells
        self.G, self.solver, self.refine, self.cells = general, solver, int(refine), int(cells)
        self._tables: dict = {}
        # the fine cells' loads per contact (a take's are the next take's start loads; a step that changes
        # neither P nor M keeps its contact): the solver's own kind of store, as many as its loads
        self._cell_loads = general._Kept(general.LOADS_KEPT)
        self._columns = general._Kept(general.LOADS_KEPT)  # the end cells' columns at a window's fine centres
        self.solved = self.failed = self.skipped = self.checked = 0

    # -- one take ---------------------------------------------------------------------------------------------
    def solve(self, state, loads1, ctx, fine, check=True) -> tuple[tuple, list, list, list]:
        """The windows after the fine take ``fine`` from ``state`` (``ctx`` its _Context): (windows, edges, errors,
        checks) with edges [left, right] the outermost stick points, the lattice's where a window has none of its
        own, errors [left, right] how far each window's own edge may be from the converged one [m]
        (:meth:`_own_error`; None where the edge is the lattice's), and checks [left, right] where the lattice's
        edge stands, the outermost stick point of a window solved around it (:meth:`_check`, where ``check``) and
        how far its placement on the fine cells may leave it [m], else None."""
        windows, edges, errors, checks = [], [fine.stick[0], fine.stick[1]], [None, None], [None, None]
        m1, mem0 = fine.memory, state.memory
        if m1.q.size < 2 * self.cells + 4 or mem0.normal is None or mem0.spacing != ctx.h:
            return (), edges, errors, checks
        old = _Old(tuple(w for w in state.memory.windows if w.spacing == ctx.h / self.refine))
        WC = self.cells
        for s, side in enumerate((-1, 1)):
            window, edge, error = self._window(state, loads1, ctx, fine, side, old,
                                               *((0, WC) if side < 0 else (m1.q.size - WC, m1.q.size)))
            windows.append(window)
            if edge is not None:
                edges[s], errors[s] = edge, error
            elif check and CHECKS:
                checks[s] = self._check(state, loads1, ctx, fine, side, old)
        return tuple(windows), edges, errors, checks

    def _check(self, state, loads1, ctx, fine, side, old):
        """Where the contact edge's window gives no outermost stick point on ``side`` (the lattice's beyond its reach,
        or within BUFFER cells of its cut), a window of WINDOW_CELLS cells centred on the lattice's cell of it,
        inside the contact by a cell at both ends of the take (its ends both cuts; its stuck fine cells' locks
        smoothed, :func:`_smooth_locks`): (its outermost stick point, how far its placement on the fine cells may
        leave it [m], :meth:`_placement`), None where it has none away from its cuts, did not converge or there is
        no room, or the lattice left cells beside its edge undecided (a load extreme, whose band the lattice's
        estimate speaks for). Not kept: it checks the lattice's edge, whose history it inherits (the step's
        estimate, GeneralSolver._finish)."""
        WC, h, N1, m1, N0 = self.cells, ctx.h, ctx.N1, fine.memory, state.memory.normal
        n = m1.q.size
        edge = fine.stick[(side + 1) // 2]
        if (fine.regime != self.G.Regime.PARTIAL_SLIP or not math.isfinite(edge)
                or fine.undecided[(side + 1) // 2] > 0.0):
            return None
        c = math.floor(edge / h) - m1.first  # the lattice's cell of its edge
        lo = c - WC // 2 + (1 if side > 0 else 0)
        hi = lo + WC
        if not (1 <= lo and hi <= n - 1 and (m1.first + lo) * h >= max(N0.left, N1.left) + h
                and (m1.first + hi) * h <= min(N0.right, N1.right) - h):
            return None
        self.checked += 1
        _, edge, error = self._window(state, loads1, ctx, fine, side, old, lo, hi, interior=True)
        return None if edge is None else (edge, error)

    def _window(self, state, loads1, ctx, fine, side, old, lo, hi, interior=False):
        """The window over the lattice's cells lo .. hi - 1 at the left (side -1) or right contact edge, or, where
        ``interior``, a check window around the outermost stick point on that side (:meth:`_check`: both its ends
        cuts, its locks smoothed, not kept, its error its own placement) after the take ``fine`` (``old``: the state's
        windows on the same fine cells, :class:`_Old`): (its EdgeWindow (None for a check), its outermost stick
        point or None, that point's own error estimate [m] or None); at a contact edge where all its lattice cells
        slip and the lattice's edge on its side lies beyond its reach (REACH_MARGIN), not solved
        (:meth:`_slipping`)."""
        S, R, WC = self.solver, self.refine, self.cells
        h, N1, m1, mem0 = ctx.h, ctx.N1, fine.memory, state.memory
        n = m1.q.size
        hf = h / R
        j0 = R * (m1.first + lo) if interior or side > 0 else math.ceil(N1.left / hf - 0.5)
        j1 = R * (m1.first + hi) - 1 if interior or side < 0 else math.floor(N1.right / hf - 0.5)
        nf = j1 - j0 + 1
        cap = self._loads(N1, hf, j0, j1)
        qmax, status, xf, force, top, all_slip = _prologue(S.f, cap, R, j0, j1, hf, h, m1.first, lo, hi, m1.status,
                                                           m1.q)
        lattice_edge, placed = float(fine.stick[(side + 1) // 2]), fine.placed[(side + 1) // 2]
        if not interior and all_slip and not abs(lattice_edge - (N1.left if side < 0 else N1.right)) <= (
                WC - BUFFER + REACH_MARGIN) * h:
            return self._slipping(m1, side, j0, hf, cap, qmax, status, xf, lo, hi, lattice_edge, placed), None, None
        span = max(n, mem0.q.size) + abs(m1.first - mem0.first) + 2 * WC + 4
        tabs, span, tf, fine_tab, datum_shift = self._kernel_tables(h, span)
        ends1 = self._ends(m1, xf, ((lo, hi),))
        ends0 = self._ends(mem0, xf, old.ranges)
        arrivals = self._arrivals(state, ctx, fine, side, xf, lo, hi)
        qtol, stol = 1e-10 * top, 1e-10 * S.A * top * hf
        if not interior:  # (a check counts in ``checked``, EdgeWindows._check)
            self.solved += 1
        cut = (nf - BUFFER * R, nf) if side < 0 else (0, BUFFER * R)
        gout, lock = _drive_and_locks(tabs, span, R, tf, j0, xf, m1.first, m1.q, lo, hi, m1.shift,
                                      0.25 * S.A * loads1.sigma, ends1, mem0.first, mem0.q, old.exclude, mem0.shift,
                                      0.25 * S.A * state.loads.sigma, old.first, old.start, old.q, ends0, arrivals)
        if interior:
            lock = _smooth_locks(lock, j0, R, mem0.first, mem0.q.size, old.first, old.start)
        q, c, status, converged = window_active_set(fine_tab, datum_shift, tf, gout, lock, qmax, force, hf, status,
                                                    qtol, stol, WINDOW_ITERATIONS)
        slip, cut_slips = _window_slip(tf, j0, q, c, status, gout, lock, *cut)
        window = None  # (a check's is not kept)
        if not interior:
            spent, G = self._slip(state, fine, side, converged and not cut_slips, status, slip, cap, old, j0, xf,
                                  lo, hi)
            for a in (q, cap, status, G):
                a.flags.writeable = False
            window = EdgeWindow(side, j0, hf, q, cap, status, G, lo, hi, lattice_edge, spent, placed)
        if not converged:
            if not interior:
                self.failed += 1
            return window, None, None
        if fine.undecided[(side + 1) // 2] > 0.0:
            # the lattice left cells beside its edge undecided (at their bound, not slipping: a load extreme): the
            # edge lies anywhere across them, and the window, whose cells are as near their bounds, picks one end
            # of that band by its coupling to the lattice as much as by its cells (a rounded punch's SS1 cycle at
            # 1024 nodes: 4 cells farther in than the lattice's edge and SS1's); the lattice's edge and estimate
            # stand, which say so
            return window, None, None
        edge, reach = self._edge(xf, hf, status, q, qmax, slip, qtol, stol, ctx, fine, side, interior)
        inner = (m1.first + hi) * h if side < 0 else (m1.first + lo) * h
        outer = (m1.first + lo) * h if side < 0 else (m1.first + hi) * h
        # (within BUFFER cells of the inner end, or of a check window's outer end: the cut's)
        if edge is None or side * (inner - edge) > -BUFFER * h or (interior and side * (edge - outer) > -BUFFER * h):
            return window, None, None
        if interior:  # (a check of the lattice's edge: its own placement; GeneralSolver._finish adds the distance)
            return window, edge, self._placement(reach, hf, fine, placed)
        return window, edge, self._own_error(edge, reach, hf, fine, lattice_edge, placed, h)

    # -- the parts ------------------------------------------------------------------------------------------
    def _slipping(self, m1, side, j0, hf, cap, qmax, status, xf, lo, hi, lattice_edge, placed):
        """The window over lattice cells lo .. hi - 1 that all slip, the lattice's outermost stick point on its side
        beyond the window's reach (REACH_MARGIN): not solved. Its fine cells slip the way of their lattice cell at
        their bound, the history the next take's window on this side locks from (a solve's answer but where the
        window's own active set would stick a fine cell, whose edge would fall within BUFFER cells of the cut and
        be the lattice's); the lattice's slip and dissipation stand (as where a solved window's slip zone reaches
        its cut)."""
        self.skipped += 1
        q = status * qmax
        G = np.interp(xf, m1.x, m1.G)
        for a in (q, cap, status, G):
            a.flags.writeable = False
        return EdgeWindow(side, j0, hf, q, cap, status, G, lo, hi, lattice_edge, 0.0, placed)

    def _slip(self, state, fine, side, kept, status, slip, cap, old, j0, xf, lo, hi):
        """(what the window changes the take's dissipation by, the slip accumulated at its fine cells): its fine
        cells' slip in the take (their displacement less their lock, 0 where stuck) added to the slip before it
        (the lattice's as it reads there, the old windows' own where they had the cell), and their f (cap0 +
        cap) / 2 |slip| hf in place of the lattice's cells lo .. hi - 1. Where the window did not converge or
        its cells within BUFFER lattice cells of its inner end slip (the cut, not the contact, would set their
        slip; ``kept`` False for either): (0, the lattice's slip as it reads at the fine centres)."""
        S, R, m1, mem0 = self.solver, self.refine, fine.memory, state.memory
        nf, h = xf.size, m1.spacing
        hf = h / R
        if not kept:
            return 0.0, np.interp(xf, m1.x, m1.G)
        N0 = mem0.normal
        cap0 = self._start_loads(N0, hf, j0, j0 + nf - 1, side, R * m1.first, R * (m1.first + m1.q.size) - 1)
        return _slip_parts(S.f, hf, h, status, slip, cap0, cap, m1.status[lo:hi], fine.cap0[lo:hi],
                           m1.capacity[lo:hi], fine.slip[lo:hi], xf, N0.left, N0.right, mem0.x, mem0.G, j0,
                           old.first, old.start, old.G)

    def _kernel_tables(self, h, span):
        """(tabs, span, tf, fine tables, datum shift): the lattice's kernel at the REFINE fine offsets within a cell
        over +- span cells (``tabs[m, span + k]`` = t(k h + (m + 1/2) h / R - h / 2)), the fine kernel over R (span
        + cells) fine cells (package datum), and the Levinson tables of the fine kernel in the internal datum of a
        ToeplitzLattice of as many cells as a window has at most, with tf - t_int (the datums' constant) for the
        window's active set (_toeplitz.window_active_set)."""
        got = self._tables.get(h)
        if got is None or got[1] < span:
            S, R = self.solver, self.refine
            span = max(span, 2 * (got[1] if got else 0))
            k = np.arange(-span, span + 1)
            hf = h / R
            tabs = np.array([kernel(k * h + (m + 0.5) * hf - 0.5 * h, h, S.datum, S.A) for m in range(R)])
            tf = kernel(np.arange(R * (span + self.cells) + 2) * hf, hf, S.datum, S.A)
            fine = got[3] if got is not None else ToeplitzLattice(hf, R * (self.cells + 1) + 2, S.A)
            got = self._tables[h] = (tabs, span, tf, fine, float(tf[0] - fine.t[0]))
        tabs, span, tf, fine, shift = got
        return tabs, span, tf, fine.tables, shift

    def _loads(self, N, hf, j0, j1):
        """(1/hf) int p over the fine cells j0 .. j1, the one at a contact edge reaching to it: _Load's closed form
        (where it rounds to WINDOW_LOAD_ROUNDING at most) or its quadrature, over these cells only; kept per
        contact (read only)."""
        got = self._cell_loads.get((hf, j0, j1), (N,))
        if got is None:
            got = self._new_loads(N, hf, j0, j1)
            got.flags.writeable = False
            self._cell_loads.put((hf, j0, j1), (N,), got)
        return got

    def _new_loads(self, N, hf, j0, j1):
        """:meth:`_loads` worked out."""
        G, S = self.G, self.solver
        L, R_ = N.left, N.right
        first, n = G._cells(L, R_, hf)
        at_left, at_right = j0 <= first, j1 >= first + n - 1
        limit = WINDOW_LOAD_ROUNDING * N.P * hf / (R_ - L)
        loads = G._fine_cell_loads(L, R_, hf, j0, j1, N.P, *N.pressure_arguments(), limit, at_left, at_right)
        if loads.size:
            return loads
        xa = L if at_left else j0 * hf
        xb = R_ if at_right else (j1 + 1) * hf
        inner = np.arange(j0 + 1, j1 + 1) * hf
        inner = inner[(inner > L) & (inner < R_)]
        return np.diff(G._quadrature_loads(N, xa, xb, inner, S._kinks, S._graded_kinks, hf)) / hf

    def _loads_over(self, N, hf, j0, j1):
        """:meth:`_loads` of the fine cells j0 .. j1 under the contact ``N``, 0 on those outside it."""
        first, n = self.G._cells(N.left, N.right, hf)
        out = np.zeros(j1 - j0 + 1)
        a, b = max(j0, first), min(j1, first + n - 1)
        if a <= b:
            out[a - j0:b - j0 + 1] = self._loads(N, hf, a, b)
        return out

    def _start_loads(self, N0, hf, j0, j1, side, lat0, lat1):
        """The loads at the take's start (contact ``N0``) of the fine cells j0 .. j1, the end cell's reaching to
        the old contact edge where the contact receded, but not beyond the lattice's cells at the end (fine
        indices lat0 .. lat1): as the lattice's end cell, it carries the material that left in the take (whose
        slip it has), the cells the lattice lost carry theirs (GeneralSolver._leaving)."""
        first, n = self.G._cells(N0.left, N0.right, hf)
        if side < 0:
            a = min(j0, max(lat0, first))
            loads = self._loads_over(N0, hf, a, j1)
            loads[j0 - a] += float(np.sum(loads[:j0 - a]))
            return loads[j0 - a:]
        b = max(j1, min(lat1, first + n - 1))
        loads = self._loads_over(N0, hf, j0, b)
        loads[j1 - j0] += float(np.sum(loads[j1 - j0 + 1:]))
        return loads[:j1 - j0 + 1]

    def _ends(self, mem, xs, exclude):
        """What a state's end cells outside the ``exclude`` ranges of its cells take off the displacement at the
        fine centres ``xs`` beyond its cells' shear (_end_columns times their shear; the datum cancels), or an
        empty array where there are none (_solve_window's field)."""
        ends = [e for e in self.G._end_supports(mem.normal, mem.first, mem.q.size, mem.spacing)
                if not any(lo <= e[0] < hi for lo, hi in exclude)]
        if not ends:
            return _NO_CELLS
        key = (mem.first, mem.q.size, mem.spacing, float(xs[0]), xs.size, tuple(k for k, _, _ in ends))
        C = self._columns.get(key, (mem.normal,))
        if C is None:  # (a take's are the next take's where the contact stays: a step that changes neither P nor M)
            C = self._columns.put(key, (mem.normal,), self.solver._end_columns(mem.normal, mem.first, mem.spacing,
                                                                                ends, xs))
        return C @ mem.q[[k for k, _, _ in ends]]

    def _arrivals(self, state, ctx, fine, side, xf, lo, hi):
        """What the fine cells centred at ``xf`` that arrive in the take add to their locks (0 elsewhere; an empty
        array where none arrives): M1's increments, or where the lattice's take slipped in part and has a stuck
        arrived cell among its cells lo .. hi - 1 (those under the window), the arrivals' shape with the
        lattice's size there."""
        S, G = self.solver, self.G
        m1, mem0 = fine.memory, state.memory
        N0 = mem0.normal
        if N0.left < xf[0] and xf[-1] < N0.right:
            return _NO_CELLS
        out = np.zeros(xf.size)
        arrived = ~((xf > N0.left) & (xf < N0.right))
        edge = N0.left if side < 0 else N0.right
        xe = xf[arrived]
        inc = side * G._integrate(ctx.path, xe, edge, side, S.A, None)
        xc = m1.x[lo:hi]
        stuck = ((xc < N0.left) | (xc > N0.right)) & (m1.status[lo:hi] == 0)
        if fine.regime == G.Regime.PARTIAL_SLIP and np.any(stuck):
            k = np.flatnonzero(stuck)[0 if side < 0 else -1]
            g0 = S._displacement(mem0.shift, mem0.x, mem0.q, mem0.spacing, state.loads.sigma, xc[k:k + 1], N0)[0]
            unit = side * G._integrate(ctx.path, xc[k:k + 1], edge, side, S.A, None, G.ARRIVAL_SHAPE)[0]
            if unit != 0.0:
                inc = (m1.g[lo + k] - g0) / unit * side * G._integrate(ctx.path, xe, edge, side, S.A, None,
                                                                       G.ARRIVAL_SHAPE)
        out[arrived] = inc
        return out

    def _edge(self, xf, hf, status, q, qmax, slip, qtol, stol, ctx, fine, side, interior):
        """The window's outermost stick point on its side and how far from it, in fine cells, its placement on
        the fine cells may leave it (_run_edges' placement, and _undecided_reach's for cells its active set left
        undecided at its tolerances ``qtol`` and ``stol``; ``slip`` the fine cells' slip in the take): (None, 0)
        where no cell sticks. (S1) as the lattice's take found it (``fine.slipping``, ``fine.drives``); an
        ``interior`` window has no contact edge (its outer end is a cut: an edge there is rejected, _window)."""
        G, N1 = self.G, ctx.N1
        # the stick run nearest the contact edge (the window's inner end is no contact edge: _padded)
        found, i, k, xs, qs, caps, st, ss = _padded(side, xf, hf, q, status, qmax, slip)
        if not found:
            return None, 0.0
        slipping, drives = fine.slipping, fine.drives
        one_side = (False, False) if interior else (slipping[0], False) if side < 0 else (False, slipping[1])
        at = (side + 1) // 2
        left, right, placement = G._run_edges(xs, qs, caps, st, N1, hf, i, k, one_side, drives, at)
        edge = left if side < 0 else right
        # (the padded cell slips: its slip is no undecided band's)
        undecided = G._undecided_reach(xs, qs, caps, ss, st, N1, hf, i, k, one_side, drives,
                                       (left, right), qtol, stol, (at,))
        return edge, max(placement, undecided)

    def _own_error(self, edge, reach, hf, fine, lattice_edge, placed, h):
        """How far the window's edge ``edge`` may be from the converged one [m]: the larger of its distance from
        the lattice's edge ``lattice_edge`` beyond how far that edge may be from where the lattice put it
        (``placed`` lattice cells of ``h``: _run_edges' placement of it), its placement on the fine cells
        (``reach`` fine cells, _run_edges' placement and the undecided bands) and the placement floor
        EDGE_PLACEMENT of a fine cell (the two can agree by chance), half a fine cell where the lattice's edge
        is bracketed.

        The distance is not divided by REFINE - 1, as Richardson's estimate of the finer of two first-order
        solutions would be: the window is not always the better one (an arrived fine cell that sticks as an
        island at the contact edge, a take's time step they share), and only their whole distance says so
        (measured on the random histories at 1024 nodes: a Hertz step 2.9e-4 of the width off where the
        lattice was exact, covered by the distance, not by a third of it). But the lattice's edge says where
        the converged one is only to its own placement: half a cell where it is bracketed, 0.3 of a cell where
        a slip zone is placed inside its end cell; a window's edge within that says nothing against the window
        (until 0.4.10 the whole distance counted: on the dovetail 44 of the 74 stored steps above `solver.tol`
        were a window's edge within the lattice's bracket, 15 of them one fine cell from its midpoint).

        Where the lattice brackets its edge (placement half a cell: a band of cells near their bound, whose
        margin does not grow like the square root, or an outermost stick cell within END_RATIO_ERROR of its
        bound) the band is the state's, and the window's cells in it are as near their bounds: its edge is
        placed to half a fine cell at best, whatever its own rule says (on the punch's random histories two
        window edges placed to the floor there were 0.2 and 0.4 of a fine cell off)."""
        apart = max(abs(edge - lattice_edge) - placed * h, 0.0)
        return max(apart, self._placement(reach, hf, fine, placed))

    def _placement(self, reach, hf, fine, placed):
        """How far a window's edge may be from where its fine cells put it [m] (:meth:`_own_error` but for the
        distance from the lattice's edge): its placement (``reach`` fine cells of ``hf``), at least the floor
        EDGE_PLACEMENT of a fine cell in a partial slip, half a fine cell where the lattice brackets its edge
        (``placed`` >= 0.5)."""
        G = self.G
        floor = G.EDGE_PLACEMENT * hf if fine.regime == G.Regime.PARTIAL_SLIP else 0.0
        if placed >= 0.5:
            floor = max(floor, 0.5 * hf)
        return max(reach * hf, floor)


class _Old:
    """A state's windows on the fine cells of a take's (EdgeWindows.solve), as the compiled calls take them:
    ``ranges`` (the lattice cells each stands in for) and ``exclude`` the same as a (k, 2) array, ``first`` their
    first fine indices, and their shear ``q`` and accumulated slip ``G`` end to end (window w's from
    ``start[w]`` to ``start[w + 1]``)."""

    def __init__(self, windows: tuple):
        self.ranges = tuple((w.lo, w.hi) for w in windows)
        self.exclude = np.array(self.ranges, np.int64).reshape(-1, 2)
        self.first = np.array([w.first for w in windows], np.int64)
        self.start = np.cumsum([0] + [w.q.size for w in windows]).astype(np.int64)
        self.q = np.concatenate([w.q for w in windows]) if windows else _NO_CELLS
        self.G = np.concatenate([w.G for w in windows]) if windows else _NO_CELLS


def same_windows(a: tuple, b: tuple) -> bool:
    """Whether two states' windows stand on the same fine cells."""
    return len(a) == len(b) and all((u.side, u.first, u.spacing, u.q.size, u.lo, u.hi)
                                    == (v.side, v.first, v.spacing, v.q.size, v.lo, v.hi) for u, v in zip(a, b))


#: No cells (an empty float array: no end cells' term, no arrivals, no old windows).
_NO_CELLS = np.zeros(0)


@numba.njit(cache=True)
def _prologue(f, cap, R, j0, j1, hf, h, first, lo, hi, lattice_status, lattice_q):  # pragma: no cover - compiled
    """What a window over the lattice's cells lo .. hi - 1 (from lattice index ``first``) on the fine cells
    j0 .. j1 starts from (EdgeWindows._window): the fine cells' bounds f cap, the pattern (each one's lattice
    cell's among lo .. hi - 1; those in contact beyond the window's end cell are its), their centres, the force
    the lattice's cells carry there (h times numpy's sum), the largest bound and whether all those lattice cells
    slip."""
    nf = j1 - j0 + 1
    cells = hi - lo
    qmax = np.empty(nf)
    status = np.empty(nf, np.int8)
    xf = np.empty(nf)
    top = -np.inf
    for i in range(nf):
        qmax[i] = f * cap[i]
        top = max(top, qmax[i])
        status[i] = lattice_status[lo + min(max((j0 + i) // R - (first + lo), 0), cells - 1)]
        xf[i] = (j0 + i + 0.5) * hf
    all_slip = True
    for j in range(lo, hi):
        all_slip = all_slip and lattice_status[j] != 0
    return qmax, status, xf, h * pairwise_sum(lattice_q, lo, hi - lo), top, all_slip


@numba.njit(cache=True)
def _padded(side, xf, hf, q, status, qmax, slip):  # pragma: no cover - compiled
    """The window's stick run nearest its contact edge (EdgeWindows._edge), as _run_edges reads it: whether any
    fine cell sticks, its first and last cells i, k and the window's centres, shear, bounds, pattern and slip
    with one slipping cell more beyond its inner end (no contact edge: it keeps _run_edges from reading one
    there; its slip infinite, no undecided band's), i and k counted with it."""
    nf = xf.size
    xs = np.empty(nf + 1)
    qs = np.empty(nf + 1)
    caps = np.empty(nf + 1)
    st = np.empty(nf + 1, np.int8)
    ss = np.empty(nf + 1)
    at = 0 if side < 0 else 1  # the window's first cell among the padded ones
    for j in range(nf):
        xs[at + j], qs[at + j], caps[at + j] = xf[j], q[j], qmax[j]
        st[at + j], ss[at + j] = status[j], slip[j]
    pad = nf if side < 0 else 0
    xs[pad] = xf[nf - 1] + hf if side < 0 else xf[0] - hf
    qs[pad], caps[pad], st[pad], ss[pad] = 0.0, qmax[nf - 1] if side < 0 else qmax[0], 1, np.inf
    end, step = (0, 1) if side < 0 else (nf - 1, -1)  # from the contact edge inwards
    j = end
    while 0 <= j < nf and status[j] != 0:
        j += step
    if not 0 <= j < nf:
        return False, -1, -1, xs, qs, caps, st, ss
    e = j
    while 0 <= e + step < nf and status[e + step] == 0:
        e += step
    i, k = min(j, e) + at, max(j, e) + at
    return True, i, k, xs, qs, caps, st, ss


@numba.njit(cache=True)
def _field(tabs, span, R, tf, j0, xf, first, q, exclude, shift, bulk, wfirst, wstart, wq,
           ends):  # pragma: no cover - compiled
    """The displacement at the fine centres ``xf`` (fine indices from j0) of a state: shift + bulk x less its
    lattice shear's outside the ``exclude`` ranges ((k, 2), of its cells from lattice index ``first``:
    _far_field), the fine shear of its windows (``wq[wstart[w]:wstart[w + 1]]`` from fine index ``wfirst[w]``:
    _fine_products) and its end cells' term ``ends`` (EdgeWindows._ends; empty: none), in that order."""
    nf = xf.size
    lattice = q.copy()
    for r in range(exclude.shape[0]):
        for j in range(exclude[r, 0], exclude[r, 1]):
            lattice[j] = 0.0
    far = _far_field(tabs, span, R, j0, nf, first, lattice)
    out = np.empty(nf)
    for i in range(nf):
        out[i] = (shift + bulk * xf[i]) - far[i]
    for w in range(wfirst.size):
        fine = _fine_products(tf, j0, nf, wfirst[w], wq[wstart[w]:wstart[w + 1]])
        for i in range(nf):
            out[i] -= fine[i]
    if ends.size:
        for i in range(nf):
            out[i] -= ends[i]
    return out


@numba.njit(cache=True)
def _drive_and_locks(tabs, span, R, tf, j0, xf, first1, q1, lo, hi, shift1, bulk1, ends1, first0, q0, exclude0,
                     shift0, bulk0, wfirst, wstart, wq, ends0, arrivals):  # pragma: no cover - compiled
    """A window's drive (the take's state, its own cells lo .. hi - 1 left out: :func:`_field`) and locks (the
    state at the take's start with its old windows, plus the ``arrivals``' increments where given), as
    displacements at the fine centres ``xf`` (EdgeWindows._window; its active set is _toeplitz's
    window_active_set, then :func:`_window_slip`)."""
    nf = xf.size
    gout = _field(tabs, span, R, tf, j0, xf, first1, q1, np.array([[lo, hi]], np.int64), shift1, bulk1, wfirst[:0],
                  wstart[:1], wq[:0], ends1)
    lock = _field(tabs, span, R, tf, j0, xf, first0, q0, exclude0, shift0, bulk0, wfirst, wstart, wq, ends0)
    if arrivals.size:
        for i in range(nf):
            lock[i] += arrivals[i]
    return gout, lock


@numba.njit(cache=True)
def _smooth_locks(lock, j0, R, first0, n0, wfirst, wstart):  # pragma: no cover - compiled
    """The locks of the fine cells j0 .. j0 + lock.size - 1 that lay on the lattice's own cells at the take's start
    (its interior cells first0 + 1 .. first0 + n0 - 2, none of its windows' fine cells ``wfirst``/``wstart``) as
    the cubic through the locks at the nearest four lattice centres on the window (each the mean of the two fine
    centres beside it, R even, or the fine centre on it): a lattice cell's constant shear moves the points
    within it by a wiggle the smooth shear it stands for does not (the lattice holds its cells at their centres
    only), and a window's stuck fine cells locked to it reproduce it as an oscillation of their shear."""
    nf = lock.size
    # the lattice cells wholly on the window, interior to the state's cells: their centre values
    a = max((j0 + R - 1) // R, first0 + 1)
    b = min((j0 + nf) // R - 1, first0 + n0 - 2)
    out = lock.copy()
    if b - a + 1 < 4:
        return out
    centre = np.empty(b - a + 1)
    for J in range(a, b + 1):
        i = R * J + R // 2 - j0
        centre[J - a] = 0.5 * (lock[i - 1] + lock[i]) if R % 2 == 0 else lock[i]
    for i in range(nf):
        j = j0 + i
        J = j // R
        if J < first0 + 1 or J > first0 + n0 - 2:
            continue
        fine = False
        for w in range(wfirst.size):
            if wfirst[w] <= j < wfirst[w] + wstart[w + 1] - wstart[w]:
                fine = True
        if fine:
            continue
        u = (j + 0.5) / R - 0.5  # in lattice cells, centre J at u = J
        s = min(max(math.floor(u) - 1, a), b - 3)
        total = 0.0
        for m in range(4):
            weight = 1.0
            for k in range(4):
                if k != m:
                    weight *= (u - (s + k)) / (m - k)
            total += weight * centre[s + m - a]
        out[i] = total
    return out


@numba.njit(cache=True)
def _window_slip(tf, j0, q, c, status, gout, lock, cut0, cut1):  # pragma: no cover - compiled
    """Each fine cell's slip in the take after the window's active set (its displacement less its lock, 0 where
    it sticks) and whether any of the fine cells cut0 .. cut1 - 1 (those within BUFFER lattice cells of the
    window's inner end) slips."""
    nf = q.size
    own = _fine_products(tf, j0, nf, j0, q)
    slip = np.zeros(nf)
    for i in range(nf):
        if status[i] != 0:
            slip[i] = gout[i] + c - own[i] - lock[i]
    cut_slips = False
    for i in range(cut0, cut1):
        cut_slips = cut_slips or status[i] != 0
    return slip, cut_slips


@numba.njit(cache=True)
def _slip_parts(f, hf, h, status, slip, cap0, cap, lattice_status, lattice_cap0, lattice_cap, lattice_slip, xf,
                left0, right0, x0, G0, j0, wfirst, wstart, wG):  # pragma: no cover - compiled
    """EdgeWindows._slip where the window converged and its cut does not slip: (what it changes the take's
    dissipation by, its fine cells' accumulated slip). The dissipation: f hf sum (cap0 + cap) / 2 |slip| over
    its slipping fine cells less f h times the same over the lattice's cells it covers (numpy's sums: pairwise);
    the slip before the take: the old windows' own (``wG[wstart[w]:wstart[w + 1]]`` from fine index
    ``wfirst[w]``) where they had the cell, elsewhere the lattice's as it reads there (``x0``, ``G0``), 0 for
    the cells that arrived in the take (outside (left0, right0))."""
    nf = xf.size
    terms = np.empty(nf)
    count = 0
    for i in range(nf):
        if status[i] != 0:
            terms[count] = 0.5 * (cap0[i] + cap[i]) * abs(slip[i])
            count += 1
    spent = f * hf * pairwise_sum(terms, 0, count)
    terms = np.empty(lattice_status.size)
    count = 0
    for i in range(lattice_status.size):
        if lattice_status[i] != 0:
            terms[count] = 0.5 * (lattice_cap0[i] + lattice_cap[i]) * abs(lattice_slip[i])
            count += 1
    spent -= f * h * pairwise_sum(terms, 0, count)
    G = np.zeros(nf)
    kept = np.empty(nf, np.bool_)
    for i in range(nf):
        kept[i] = left0 < xf[i] < right0
    G[kept] = np.interp(xf[kept], x0, G0)
    for w in range(wfirst.size):
        size = wstart[w + 1] - wstart[w]
        for i in range(nf):
            k = j0 + i - wfirst[w]
            if 0 <= k < size and kept[i]:
                G[i] = wG[wstart[w] + k]
    out = np.empty(nf)
    for i in range(nf):
        out[i] = G[i] + slip[i]
    return spent, out


@numba.njit(cache=True)
def _far_field(tabs, span, R, jf0, nf, first, q):  # pragma: no cover - compiled
    """sum_j t(x_i - x_j) q_j at the fine centres i (fine indices jf0 .. jf0 + nf - 1) over the lattice's cells
    j (from lattice index ``first``) carrying ``q``; ``tabs[m, span + k]`` = t(k h + (m + 1/2) h / R - h / 2).

    The fine centres at the same offset m in their cells (every R-th) read consecutive entries of tabs[m]: their
    sums run together, cell j after cell j, each in the order of j from 0 (the same operations, in the same order
    per centre, as one sum per centre; 1.4x faster at 64 fine centres and 1000 cells), four cells at a time for
    each centre's running sum (kept in a register through the four, in the same order: 1.5x faster again,
    2026-11-29)."""
    out = np.zeros(nf)
    n = q.size
    for offset in range(R):
        i0 = (offset - jf0) % R  # the first fine centre with this offset
        if i0 >= nf:
            continue
        c0 = (jf0 + i0) // R
        m = jf0 + i0 - c0 * R
        count = (nf - 1 - i0) // R + 1
        row = tabs[m]
        base = span + c0 - first
        acc = np.zeros(count)
        j = 0
        while j + 4 <= n:
            q0, q1, q2, q3 = q[j], q[j + 1], q[j + 2], q[j + 3]
            b = base - j
            for k in range(count):
                a = acc[k]
                a += row[b + k] * q0
                a += row[b - 1 + k] * q1
                a += row[b - 2 + k] * q2
                a += row[b - 3 + k] * q3
                acc[k] = a
            j += 4
        while j < n:
            qj = q[j]
            b = base - j
            for k in range(count):
                acc[k] += row[b + k] * qj
            j += 1
        for k in range(count):
            out[i0 + k * R] = acc[k]
    return out


@numba.njit(cache=True)
def _fine_products(tf, rows0, n_rows, cols0, q):  # pragma: no cover - compiled
    """sum_j tf[|i - j|] q_j between fine cells (rows from fine index rows0, the shear's cells from cols0)."""
    out = np.zeros(n_rows)
    for i in range(n_rows):
        total = 0.0
        for j in range(q.size):
            total += tf[abs(rows0 + i - cols0 - j)] * q[j]
        out[i] = total
    return out
