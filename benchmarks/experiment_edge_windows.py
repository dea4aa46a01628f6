"""Experiment (issue 14, resolution where it matters): fine windows at the contact edges, one-way coupled
to the uniform lattice, measured on the random histories and on the dovetail.

    python benchmarks/experiment_edge_windows.py                  # the tables in docs/benchmarks.md
    python benchmarks/experiment_edge_windows.py --nodes 512 --geometries punch --no-doc

Not the package's solver: a measurement of a design before it is built (docs/general_solver.md, "Limits that
remain", uniform lattice). After every fine take of the general solver (a step or a sub-step;
GeneralSolver._finish is wrapped), the first and the last ``--cells`` lattice cells of the contact are solved
again on a lattice ``--refine`` times finer, on their own (a sub-model):

* unknowns: the fine cells' shear (cells fixed in space, aligned with the lattice's) and a rigid offset c of
  the window; bounds f x each fine cell's load (_Load of the fine spacing; the end cell reaches to the
  contact edge and carries a cell-wide shear: shaped like the pressure it changed nothing measurable here);
* driven by the lattice's answer outside the window (its shear there, its rigid shift and the bulk term),
  fixed; the window carries the force the lattice's cells carry there (h sum q over them), so c is free;
* locks: each fine cell's displacement at the step's start from the composite state (the lattice's shear and
  shift outside the last window, the window's own fine shear inside it: the window keeps its history; its
  offset c is not kept, so its stuck cells follow the lattice's shift between takes: with ``--keep-offset``
  they keep it, 8.1e-5 against 8.6e-5 on the punch below but 1.1e-4 against 4.1e-5 on the dovetail, against
  8000 nodes);
  cells that arrive in the step take M1's increments (GeneralSolver._arrivals) or, where the lattice's take
  slipped in part and sized its arrivals (_arrival_fit), the shape with the lattice's size there;
* the active set on the dense window (a pattern repeated or 60 iterations: counted as not converged, and
  that side keeps the lattice's edge);
* its outermost stick point on its side, placed by _run_edges on the fine cells, replaces the lattice's where
  the window has a stick cell.

What it measured (2026-11-28, issue 14's note; docs/general_solver.md): the rounded punch's random
histories at 512 nodes, 95th percentile of the vouched edges 2.7e-4 -> 8e-5 (the lattice at 1024 nodes:
7.9e-5, at 2048: 5.7e-5); Hertz unchanged (its 95th percentile is set inside the contact); the dovetail's
last cycle against 16000 nodes, 95th percentile 2.1e-4 -> 5.9e-5 at 1000 nodes, largest 3.4e-3 -> 1.3e-4 (the
load maximum's ill-conditioned band, where the lattice is 12.4 um off up to 8000 nodes: by chance, windows of the
same width at 2000 and 4000 nodes keep that step off). Without the window's own
history (locks from the lattice's state at every take, its displacement or its cell-centre values
interpolated) it is worse than the lattice alone (5.5e-4 / 3.7e-4 at 512 nodes); with the window's rigid
offset fixed to the lattice's shift (no force condition) its history drifts from the lattice's (4.5e-3).
Time: :class:`FastWindows` (the default; the same windows as :class:`Windows` to 8e-13 of the width) takes
the far field and the window's matrix from kernel tables, integrates the loads of the window's own cells and
runs a compiled active set, but is orchestrated in Python: about 0.3 ms a window at 512 nodes (Windows, kernel
logarithms and the whole contact's loads: 1.5 ms), an upper bound of what a built version would cost.
"""
from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import math
import sys
import time
from pathlib import Path

import numba
import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from _doc import write_section  # noqa: E402
from bench_general_random import DOC, REFERENCE, VOUCH, compare, machine  # noqa: E402
from random_histories import random_history  # noqa: E402

BEGIN, END = "<!-- edge_windows: begin -->", "<!-- edge_windows: end -->"
#: Active-set iterations at most for a window.
WINDOW_ITERATIONS = 60


class Windows:
    """The windows of one run: wraps ``solver``'s _finish; ``edges(state)`` gives a state's outermost stick
    points with the windows' in place, ``failed`` counts window solves that did not converge."""

    def __init__(self, solver, refine: int, cells: int, offset: bool = False):
        from halfslip.solvers import general

        self.G, self.solver, self.refine, self.cells, self.offset = general, solver, refine, cells, offset
        self.kept = {}  # id(memory.q) -> (memory.q, {side: window}, edges)
        self.failed = self.solved = 0
        finish = solver._finish

        def wrapped(state, t1, loads1, ctx, fine, rough):
            new, report, spread = finish(state, t1, loads1, ctx, fine, rough)
            windows, edges = {}, [new.stick_left, new.stick_right]
            if fine.regime in (general.Regime.PARTIAL_SLIP, general.Regime.STICK):
                for s, side in enumerate((-1, 1)):
                    got = self._window(state, loads1, ctx, fine, side)
                    if got is not None:
                        windows[side], edge = got
                        if edge is not None:
                            edges[s] = edge
            self.kept[id(new.memory.q)] = (new.memory.q, windows, tuple(edges))
            return new, report, spread

        solver._finish = wrapped

    def edges(self, state):
        got = self.kept.get(id(state.memory.q))
        if got is None or got[0] is not state.memory.q:
            return state.stick_left, state.stick_right
        return got[2]

    def _displacement(self, mem, loads, xs):
        """The composite state's displacement at ``xs``: the lattice's shear and shift outside its windows, the
        windows' own fine shear inside them (and, with ``offset``, their rigid offset)."""
        S = self.solver
        got = self.kept.get(id(mem.q))
        q = np.array(mem.q, dtype=float)
        extra = np.zeros(xs.size)
        if got is not None and got[0] is mem.q:
            for w in got[1].values():
                q[w["coarse"]] = 0.0
                extra += S._products(xs, w["x"], w["h"], w["q"])
                if self.offset:
                    inside = (xs >= w["x"][0] - 0.5 * w["h"]) & (xs <= w["x"][-1] + 0.5 * w["h"])
                    extra[inside] -= w["c"]
        return S._displacement(mem.shift, mem.x, q, mem.spacing, loads.sigma, xs, mem.normal) - extra

    def _window(self, state, loads1, ctx, fine, side):
        """The window at the left (side -1) or right contact edge after the take ``fine``: (its state, its
        outermost stick point or None), None where the contact is too small or new."""
        S, G, R, WC = self.solver, self.G, self.refine, self.cells
        h, N1, m1, mem0 = ctx.h, ctx.N1, fine.memory, state.memory
        n, N0 = m1.q.size, mem0.normal
        if n < 2 * WC + 4 or N0 is None:
            return None
        hf = h / R
        if side < 0:
            coarse = np.arange(0, WC)
            j0, j1 = math.ceil(N1.left / hf - 0.5), R * (m1.first + WC) - 1
        else:
            coarse = np.arange(n - WC, n)
            j0, j1 = R * (m1.first + n - WC), math.floor(N1.right / hf - 0.5)
        xf = (np.arange(j0, j1 + 1) + 0.5) * hf
        nf = xf.size
        first_all, n_all = G._cells(N1.left, N1.right, hf)
        cap = G._Load(N1, hf, S._kinks, S._graded_kinks).capacity(first_all, n_all, hf)
        cap = cap[j0 - first_all:j1 - first_all + 1]
        qmax = S.f * cap
        outside = np.array(m1.q, dtype=float)
        outside[coarse] = 0.0
        gout = S._displacement(m1.shift, m1.x, outside, h, loads1.sigma, xf, N1)
        T = S._products(xf, xf, hf, np.eye(nf))
        # locks: the composite state's displacement at the start; arrivals M1's, or the lattice's size
        lock = self._displacement(mem0, state.loads, xf)
        lock += self._arrivals(state, ctx, fine, side, xf, coarse)
        # the active set: g = gout + c - T q; stick g = lock; slip q = s f cap with s (g - lock) >= 0;
        # h_f sum q = the lattice's force over its window cells
        force = h * float(np.sum(np.asarray(m1.q)[coarse]))
        cidx = np.clip(np.arange(j0, j1 + 1) // R - (m1.first + coarse[0]), 0, WC - 1)
        status = np.asarray(m1.status)[coarse][cidx].astype(np.int8)
        qtol, stol = 1e-10 * float(np.max(qmax)), 1e-10 * S.A * float(np.max(qmax)) * hf
        seen, c, converged = set(), 0.0, False
        self.solved += 1
        for _ in range(WINDOW_ITERATIONS):
            stick = status == 0
            q = np.where(stick, 0.0, status * qmax)
            k = int(stick.sum())
            if k:
                M = np.zeros((k + 1, k + 1))
                M[:k, :k] = T[np.ix_(stick, stick)]
                M[:k, k] = -1.0
                M[k, :k] = hf
                b = np.append(gout[stick] - lock[stick] - T[np.ix_(stick, ~stick)] @ q[~stick],
                              force - hf * q[~stick].sum())
                sol = np.linalg.solve(M, b)
                q[stick], c = sol[:k], sol[k]
            s = gout + c - T @ q - lock
            new = status.copy()
            over = stick & (np.abs(q) > qmax + qtol)
            new[over] = np.sign(q[over]).astype(np.int8)
            new[~stick & (status * s < -stol)] = 0
            if np.array_equal(new, status):
                converged = True
                break
            if new.tobytes() in seen:
                break
            seen.add(new.tobytes())
            status = new
        window = {"x": xf, "h": hf, "q": q, "c": c, "coarse": coarse}
        if not converged:
            self.failed += 1
            return window, None
        return window, self._edge(window, status, q, qmax, state, loads1, ctx, side)

    def _arrivals(self, state, ctx, fine, side, xf, coarse):
        """What the fine cells centred at ``xf`` that arrive in the take add to their locks (0 elsewhere): M1's
        increments, or where the lattice's take slipped in part and has a stuck arrived cell on this side
        (``coarse``: the lattice cells under the window), the arrivals' shape with the lattice's size there."""
        S, G = self.solver, self.G
        m1, mem0 = fine.memory, state.memory
        N0 = mem0.normal
        out = np.zeros(xf.size)
        arrived = ~((xf > N0.left) & (xf < N0.right))
        if not np.any(arrived):
            return out
        edge = N0.left if side < 0 else N0.right
        xe = xf[arrived]
        inc = side * G._integrate(ctx.path, xe, edge, side, S.A, None)
        xc = m1.x[coarse]
        stuck = ((xc < N0.left) | (xc > N0.right)) & (np.asarray(m1.status)[coarse] == 0)
        if fine.regime == G.Regime.PARTIAL_SLIP and np.any(stuck):
            k = np.flatnonzero(stuck)[0 if side < 0 else -1]
            g0 = S._displacement(mem0.shift, mem0.x, mem0.q, mem0.spacing, state.loads.sigma, xc[k:k + 1], N0)[0]
            unit = side * G._integrate(ctx.path, xc[k:k + 1], edge, side, S.A, None, G.ARRIVAL_SHAPE)[0]
            if unit != 0.0:
                inc = (m1.g[coarse[k]] - g0) / unit * side * G._integrate(ctx.path, xe, edge, side, S.A, None,
                                                                          G.ARRIVAL_SHAPE)
        out[arrived] = inc
        return out

    def _edge(self, window, status, q, qmax, state, loads1, ctx, side):
        """The window's outermost stick point on its side (None: no stick cell)."""
        G, S = self.G, self.solver
        N1, hf, xf, nf = ctx.N1, window["h"], window["x"], window["x"].size
        stuck = np.flatnonzero(status == 0)
        if stuck.size == 0:
            return None
        drives = G._edge_drives(N1, state.loads, loads1)
        slipping = G._slipping_edges(drives, state.loads, loads1, S.f)
        drives = tuple((u / S.f, v) for u, v in drives) if any(slipping) else None
        # the stick run nearest the contact edge; the window's inner end is no contact edge: a slipping cell
        # beyond it keeps _run_edges from reading it as one
        i = k = stuck[0] if side < 0 else stuck[-1]
        while side < 0 and k + 1 < nf and status[k + 1] == 0:
            k += 1
        while side > 0 and i > 0 and status[i - 1] == 0:
            i -= 1
        pad = nf if side < 0 else 0
        xs = np.insert(xf, pad, xf[-1] + hf if side < 0 else xf[0] - hf)
        qs, st = np.insert(q, pad, 0.0), np.insert(status, pad, 1)
        caps = np.insert(qmax, pad, qmax[-1 if side < 0 else 0])
        if side > 0:
            i, k = i + 1, k + 1
        left, right, _ = G._run_edges(xs, qs, caps, st.astype(np.int8), N1, hf, i, k,
                                      (slipping[0], False) if side < 0 else (False, slipping[1]), drives)
        return left if side < 0 else right


@numba.njit(cache=True)
def _far_field(tabs, span, R, jf0, nf, first, q):  # pragma: no cover - compiled
    """sum_j t(x_i - x_j) q_j at the fine centres i (fine indices jf0 .. jf0 + nf - 1) over the lattice's cells
    j (from lattice index ``first``) carrying ``q``; ``tabs[m, span + k]`` = t(k h + (m + 1/2) h / R - h / 2)."""
    out = np.zeros(nf)
    for i in range(nf):
        jf = jf0 + i
        c = jf // R
        m = jf - c * R
        total = 0.0
        for j in range(q.size):
            total += tabs[m, span + c - first - j] * q[j]
        out[i] = total
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


@numba.njit(cache=True)
def _window_active_set(tf, gout, lock, qmax, force, hf, status, qtol, stol, max_iter):  # pragma: no cover
    """The window's active set (dense): g = gout + c - T q with T[i, j] = tf[|i - j|]; stuck cells g = lock,
    slipping ones q = s qmax with s (g - lock) >= 0; hf sum q = force, the offset c free. Returns q, c, the
    pattern and whether it converged (a pattern repeated or max_iter iterations: not)."""
    n = gout.size
    status = status.copy()
    seen = np.empty((max_iter, n), np.int8)
    q = np.zeros(n)
    c = 0.0
    for it in range(max_iter):
        k = 0
        for i in range(n):
            if status[i] == 0:
                k += 1
        idx = np.empty(k, np.int64)
        k = 0
        for i in range(n):
            q[i] = 0.0 if status[i] == 0 else status[i] * qmax[i]
            if status[i] == 0:
                idx[k] = i
                k += 1
        if k > 0:
            M = np.zeros((k + 1, k + 1))
            b = np.empty(k + 1)
            rest = force
            for i in range(n):
                rest -= hf * q[i]
            for a in range(k):
                i = idx[a]
                acc = gout[i] - lock[i]
                for j in range(n):
                    if status[j] != 0:
                        acc -= tf[abs(i - j)] * q[j]
                b[a] = acc
                for e in range(k):
                    M[a, e] = tf[abs(i - idx[e])]
                M[a, k] = -1.0
                M[k, a] = hf
            b[k] = rest
            sol = np.linalg.solve(M, b)
            for a in range(k):
                q[idx[a]] = sol[a]
            c = sol[k]
        new = status.copy()
        same = True
        for i in range(n):
            if status[i] == 0:
                if abs(q[i]) > qmax[i] + qtol:
                    new[i] = 1 if q[i] > 0 else -1
                    same = False
            else:
                g = gout[i] + c - lock[i]
                for j in range(n):
                    g -= tf[abs(i - j)] * q[j]
                if status[i] * g < -stol:
                    new[i] = 0
                    same = False
        if same:
            return q, c, status, True
        for r in range(it):
            if np.array_equal(seen[r], new):
                return q, c, status, False
        seen[it] = new
        status = new
    return q, c, status, False


class FastWindows(Windows):
    """:class:`Windows` with the far field and the window's matrix from kernel tables, its cell loads over its
    own cells and a compiled active set: what a built version would cost (the same windows to rounding)."""

    def __init__(self, solver, refine, cells, offset=False):
        super().__init__(solver, refine, cells, offset)
        self.tables = {}

    def _tables(self, h, span):
        """(tabs, span, tf): the lattice's kernel at the R fine offsets within a cell, over +-span cells, and the
        fine kernel over R (span + cells) fine cells (package datum)."""
        got = self.tables.get(h)
        if got is None or got[1] < span:
            from halfslip.solvers._toeplitz import kernel

            S, R = self.solver, self.refine
            span = max(span, 2 * (got[1] if got else 0))
            k = np.arange(-span, span + 1)
            hf = h / R
            tabs = np.array([kernel(k * h + (m + 0.5) * hf - 0.5 * h, h, S.datum, S.A) for m in range(R)])
            tf = kernel(np.arange(R * (span + self.cells) + 2) * hf, hf, S.datum, S.A)
            got = self.tables[h] = (tabs, span, tf)
        return got

    def _loads(self, N, hf, j0, j1):
        """(1/hf) int p over the fine cells j0 .. j1, the one at a contact edge reaching to it (_Load's
        quadrature over these cells only)."""
        G, S = self.G, self.solver
        L, R_, c, d = N.left, N.right, N.center, N.half_width
        first, n = G._cells(L, R_, hf)
        xa = L if j0 <= first else j0 * hf
        xb = R_ if j1 >= first + n - 1 else (j1 + 1) * hf
        inner = np.arange(j0 + 1, j1 + 1) * hf
        inner = inner[(inner > L) & (inner < R_)]
        kinks = S._kinks[(S._kinks > L) & (S._kinks < R_)]
        extra = [kinks]
        if S._graded_kinks and kinks.size:
            step = min(hf, d) * 0.25 ** np.arange(1, G.KINK_GRADING + 1)
            extra += [kinks[:, None] - step[None, :], kinks[:, None] + step[None, :], L + step, R_ - step]
        extra = np.concatenate([e.ravel() for e in extra])
        extra = extra[(extra > xa) & (extra < xb)]
        pts = np.unique(np.concatenate((inner, extra)))
        bounds = np.concatenate(([xa], pts, [xb]))
        th = np.arccos(np.clip((c - bounds) / d, -1.0, 1.0))
        near = np.zeros(bounds.size - 1, bool)
        if extra.size:
            at = np.searchsorted(bounds, extra)
            near[at - 1] = near[np.minimum(at, bounds.size - 2)] = True
        if xa == L:
            near[:2] = True
        if xb == R_:
            near[-2:] = True
        part = G._interval_loads(th[:-1], np.diff(th), near, c, d, G._GL_T, G._GL_W, G._KINK_T, G._KINK_W, G._FAR_T,
                                 G._FAR_W, G.FAR_SPANS, N.pressure_arguments())
        cum = np.concatenate(([0.0], np.cumsum(part)))
        at = np.concatenate(([0], np.searchsorted(bounds, inner), [bounds.size - 1]))
        return np.diff(cum[at]) / hf

    def _field(self, mem, loads, tabs, span, tf, jf0, nf, windows, exclude):
        """The displacement at the fine centres jf0 .. jf0 + nf - 1 of a state: its lattice shear outside the
        ``exclude`` ranges of its cells, ``windows``' fine shear, its shift, bulk term and the end cells outside
        those ranges."""
        S, R = self.solver, self.refine
        h = mem.spacing
        xs = (jf0 + np.arange(nf) + 0.5) * (h / R)
        q = np.array(mem.q, dtype=float)
        for lo, hi in exclude:
            q[lo:hi] = 0.0
        out = mem.shift + 0.25 * S.A * loads.sigma * xs - _far_field(tabs, span, R, jf0, nf, mem.first, q)
        for w in windows:
            out -= _fine_products(tf, jf0, nf, w["first"], w["q"])
        ends = [e for e in self.G._end_supports(mem.normal, mem.first, q.size, h)
                if not any(lo <= e[0] < hi for lo, hi in exclude)]
        if ends:
            C = S._end_columns(mem.normal, mem.first, h, ends, xs)
            out -= C @ q[[k for k, _, _ in ends]]
        return out

    def _window(self, state, loads1, ctx, fine, side):
        S, R, WC = self.solver, self.refine, self.cells
        h, N1, m1, mem0 = ctx.h, ctx.N1, fine.memory, state.memory
        n, N0 = m1.q.size, mem0.normal
        if n < 2 * WC + 4 or N0 is None or mem0.spacing != h:
            return None
        hf = h / R
        if side < 0:
            lo, hi = 0, WC
            j0, j1 = math.ceil(N1.left / hf - 0.5), R * (m1.first + WC) - 1
        else:
            lo, hi = n - WC, n
            j0, j1 = R * (m1.first + n - WC), math.floor(N1.right / hf - 0.5)
        nf = j1 - j0 + 1
        span = max(n, mem0.q.size) + abs(m1.first - mem0.first) + 2 * WC + 4
        tabs, span, tf = self._tables(h, span)
        qmax = S.f * self._loads(N1, hf, j0, j1)
        gout = self._field(m1, loads1, tabs, span, tf, j0, nf, (), [(lo, hi)])
        got = self.kept.get(id(mem0.q))
        old = list(got[1].values()) if got is not None and got[0] is mem0.q else []
        # the old state's lattice cells under its windows left out, its windows' own shear put in
        lock = self._field(mem0, state.loads, tabs, span, tf, j0, nf, old, [w["coarse_range"] for w in old])
        xf = (j0 + np.arange(nf) + 0.5) * hf
        coarse = np.arange(lo, hi)
        lock += self._arrivals(state, ctx, fine, side, xf, coarse)
        force = h * float(np.sum(np.asarray(m1.q)[lo:hi]))
        cidx = np.clip(np.arange(j0, j1 + 1) // R - (m1.first + lo), 0, WC - 1)
        status = np.asarray(m1.status)[lo:hi][cidx].astype(np.int8)
        qtol, stol = 1e-10 * float(np.max(qmax)), 1e-10 * S.A * float(np.max(qmax)) * hf
        self.solved += 1
        q, c, status, converged = _window_active_set(tf, gout, lock, qmax, force, hf, status, qtol, stol,
                                                     WINDOW_ITERATIONS)
        window = {"x": xf, "h": hf, "q": q, "c": c, "coarse": coarse, "first": j0, "coarse_range": (lo, hi)}
        if not converged:
            self.failed += 1
            return window, None
        return window, self._edge(window, status, q, qmax, state, loads1, ctx, side)


def random_run(geometry, seed, nodes, refine, cells, offset=False, kind=None):
    """One random history with (refine > 1) or without windows: per-step records for compare()."""
    from halfslip.simulator import reference_width
    from halfslip.solvers.general import GeneralSolver
    from halfslip.state import Loads

    info = {}
    scene, t, P, Q, M, S = random_history(seed, geometry, info=info)
    solver = GeneralSolver(info["problem"], info["friction"], nodes, width=reference_width(scene, info["problem"]))
    windows = (kind or FastWindows)(solver, refine, cells, offset) if refine > 1 else None
    state = solver.initial_state(t[0])
    rec = {k: [] for k in ("stick_left", "stick_right", "contact_left", "contact_right", "dissipation", "intervals")}
    began = time.perf_counter()
    for i in range(1, t.size):
        state, _ = solver.step(state, t[i], Loads(P[i], Q[i], M[i], S[i]))
        left, right = windows.edges(state) if windows else (state.stick_left, state.stick_right)
        for k, v in (("stick_left", left), ("stick_right", right), ("contact_left", state.contact_left),
                     ("contact_right", state.contact_right), ("dissipation", state.dissipation),
                     ("intervals", solver.stick_intervals(state))):
            rec[k].append(v)
    out = {k: np.asarray(v, dtype=float) for k, v in rec.items()}
    out["converged"] = np.ones(t.size - 1, bool)
    out["wall"], out["steps"] = time.perf_counter() - began, t.size - 1
    out["failed"] = windows.failed if windows else 0
    out["solved"] = windows.solved if windows else 0
    return out


def dovetail_run(nodes, refine, cells, offset=False, kind=None):
    """examples/dovetail.yaml marched step by step (no cycle skipped): the outermost stick points of the last
    cycle's steps, the contact width there, time per step, window solves and failures."""
    import halfslip as hs
    from halfslip.geometry import NormalProblem
    from halfslip.simulator import reference_width
    from halfslip.solvers.general import GeneralSolver
    from halfslip.state import Loads

    sc = hs.load_scene(HERE.parent / "examples" / "dovetail.yaml")
    h = sc.history
    problem = NormalProblem(sc.profile, sc.material.compliance)
    solver = GeneralSolver(problem, sc.friction, nodes, width=reference_width(sc, problem))
    windows = (kind or FastWindows)(solver, refine, cells, offset) if refine > 1 else None
    state = solver.initial_state(h.t[0])
    last = h.t >= h.t[-1] - 1.0 - 1e-12
    edges = []
    began = time.perf_counter()
    for i in range(1, h.t.size):
        state, _ = solver.step(state, h.t[i], Loads(h.P[i], h.Q[i], h.M[i], h.sigma[i]))
        if last[i]:
            edges.append(windows.edges(state) if windows else (state.stick_left, state.stick_right))
    wall = (time.perf_counter() - began) / (h.t.size - 1)
    return (np.array(edges), state.contact_right - state.contact_left, wall,
            windows.failed if windows else 0, windows.solved if windows else 0)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--nodes", type=int, nargs="+", default=[512, 1024])
    ap.add_argument("--geometries", nargs="+", default=["punch", "hertz"])
    ap.add_argument("--refine", type=int, default=4)
    ap.add_argument("--cells", type=int, default=16, help="lattice cells per window")
    ap.add_argument("--dovetail", type=int, nargs="*", default=[1000, 2000],
                    help="nodes (against --dovetail-reference)")
    ap.add_argument("--dovetail-reference", type=int, default=16000)
    ap.add_argument("--keep-offset", action="store_true",
                    help="the window's rigid offset stays with its stuck cells (default: their locks follow the "
                         "lattice's shift)")
    ap.add_argument("--no-doc", action="store_true")
    args = ap.parse_args(argv)
    ref = np.load(REFERENCE)
    random_rows, dovetail_rows = [], []
    for g in args.geometries:  # numba compiles or loads its functions at their first call: not in a timed run
        random_run(g, 0, 4 * args.cells, args.refine, args.cells)
    for nodes in args.nodes:
        for g in args.geometries:
            for refine in (1, args.refine):
                vouched, every, failed, solved, wall, steps = [], [], 0, 0, 0.0, 0
                for seed in (0, 1):
                    run = random_run(g, seed, nodes, refine, args.cells, args.keep_offset)
                    e, v, *_ = compare(run, ref, f"{g}_{seed}_")
                    vouched.append(v)
                    every.append(e)
                    failed, solved = failed + run["failed"], solved + run["solved"]
                    wall, steps = wall + run["wall"], steps + run["steps"]
                v, e = np.concatenate(vouched), np.concatenate(every)
                random_rows.append((g, nodes, _windows(refine, args.cells), np.median(v), np.percentile(v, 95),
                                    np.percentile(e, 95), e.max(),
                                    failed, solved, 1e3 * wall / steps))
                print(_random_row(random_rows[-1]), flush=True)
    if args.dovetail:
        reference, width, *_ = dovetail_run(args.dovetail_reference, 1, args.cells)
        for nodes in args.dovetail:
            for refine in (1, args.refine):
                edges, _, wall, failed, solved = dovetail_run(nodes, refine, args.cells, args.keep_offset)
                err = np.abs(edges - reference) / width
                dovetail_rows.append((nodes, _windows(refine, args.cells), np.nanmedian(err),
                                      np.nanpercentile(err, 95), np.nanmax(err),
                                      failed, solved, 1e3 * wall))
                print(_dovetail_row(dovetail_rows[-1]), flush=True)
    if not args.no_doc:
        write_doc(random_rows, dovetail_rows, args, " ".join(sys.argv[1:] if argv is None else argv))


def _windows(refine, cells):
    return "-" if refine == 1 else f"{cells} cells x {refine}"


def _random_row(r):
    g, nodes, windows, med, p95, all95, top, failed, solved, ms = r
    return (f"| {g} | {nodes} | {windows} | {med:.1e} | {p95:.1e} | {all95:.1e} | {top:.1e} | "
            f"{failed} of {solved} | {ms:.2f} |")


def _dovetail_row(r):
    nodes, windows, med, p95, top, failed, solved, ms = r
    return (f"| {nodes} | {windows} | {med:.1e} | {p95:.1e} | {top:.1e} | {failed} of {solved} | "
            f"{ms:.2f} |")



def write_doc(random_rows, dovetail_rows, args, argv):
    text = (f"{BEGIN}\nMeasured with `python benchmarks/experiment_edge_windows.py {argv}` on "
            f"{time.strftime('%Y-%m-%d')}; machine: {machine()}. A design measured before it is built (the "
            "script's docstring): the outermost stick points with fine windows at the contact edges, one-way "
            "coupled to the lattice, against the lattice alone. Times are the experiment's (FastWindows: kernel tables "
            "and a compiled active set, orchestrated in Python), an upper bound of a built version's.\n\n"
            "Random histories (seeds 0, 1), stick edges against benchmarks/reference/random_reference.npz, relative to "
            f"the contact width; vouched: the reference's own estimate at most {VOUCH:g}:\n\n"
            "| geometry | nodes | windows | vouched: median | vouched: 95th pct | all: 95th pct | max | window solves "
            "not converged | ms / step |\n|---|---:|---|---:|---:|---:|---:|---:|---:|\n"
            + "\n".join(_random_row(r) for r in random_rows)
            + (f"\n\nexamples/dovetail.yaml, every step marched, the last cycle's outermost stick points against the "
               f"lattice at {args.dovetail_reference} nodes:\n\n| nodes | windows | median | 95th pct | max | window "
               "solves not converged | ms / step |\n|---:|---|---:|---:|---:|---:|---:|\n"
               + "\n".join(_dovetail_row(r) for r in dovetail_rows) if dovetail_rows else "")
            + f"\n{END}")
    write_section(DOC, BEGIN, END, text, "Fine windows at the contact edges (experiment, issue 14)")


if __name__ == "__main__":
    main()
