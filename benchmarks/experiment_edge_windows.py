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
  they keep it, 8.1e-5 against 8.6e-5 on the punch below but 1.1e-4 against 4.1e-5 on the dovetail);
  cells that arrive in the step take M1's increments (GeneralSolver._arrivals) or, where the lattice's take
  slipped in part and sized its arrivals (_arrival_fit), the shape with the lattice's size there;
* the active set on the dense window (a pattern repeated or 60 iterations: counted as not converged, and
  that side keeps the lattice's edge);
* its outermost stick point on its side, placed by _run_edges on the fine cells, replaces the lattice's where
  the window has a stick cell.

What it measured (2026-11-28, issue 14's note; docs/general_solver.md): the rounded punch's random
histories at 512 nodes, 95th percentile of the vouched edges 2.7e-4 -> 8e-5 (the lattice at 1024 nodes:
7.9e-5, at 2048: 5.7e-5); Hertz unchanged (its 95th percentile is set inside the contact); the dovetail's
last cycle against 8000 nodes, 95th percentile 2.1e-4 -> 4e-5 at 1000 nodes. Without the window's own
history (locks from the lattice's state at every take, its displacement or its cell-centre values
interpolated) it is worse than the lattice alone (5.5e-4 / 3.7e-4 at 512 nodes); with the window's rigid
offset fixed to the lattice's shift (no force condition) its history drifts from the lattice's (4.5e-3).
Time: dense numpy and kernel logarithms, not what a built version would cost.
"""
from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from _doc import write_section  # noqa: E402
from bench_general_random import DOC, REFERENCE, VOUCH, compare, machine, reference_error  # noqa: E402
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
        cap = G._Load(N1, hf, S._kinks, S._graded_kinks).capacity(first_all, n_all, hf)[j0 - first_all:j1 - first_all + 1]
        qmax = S.f * cap
        outside = np.array(m1.q, dtype=float)
        outside[coarse] = 0.0
        gout = S._displacement(m1.shift, m1.x, outside, h, loads1.sigma, xf, N1)
        T = S._products(xf, xf, hf, np.eye(nf))
        # locks: the composite state's displacement at the start; arrivals M1's, or the lattice's size
        lock = self._displacement(mem0, state.loads, xf)
        arrived = ~((xf > N0.left) & (xf < N0.right))
        if np.any(arrived):
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
            lock[arrived] += inc
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
        stuck = np.flatnonzero(status == 0)
        if stuck.size == 0:
            return window, None
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
        qs, caps, st = np.insert(q, pad, 0.0), np.insert(qmax, pad, qmax[-1 if side < 0 else 0]), np.insert(status, pad, 1)
        if side > 0:
            i, k = i + 1, k + 1
        left, right, _ = G._run_edges(xs, qs, caps, st.astype(np.int8), N1, hf, i, k,
                                      (slipping[0], False) if side < 0 else (False, slipping[1]), drives)
        return window, (left if side < 0 else right)


def random_run(geometry, seed, nodes, refine, cells, offset=False):
    """One random history with (refine > 1) or without windows: per-step records for compare()."""
    from halfslip.simulator import reference_width
    from halfslip.solvers.general import GeneralSolver
    from halfslip.state import Loads

    info = {}
    scene, t, P, Q, M, S = random_history(seed, geometry, info=info)
    solver = GeneralSolver(info["problem"], info["friction"], nodes, width=reference_width(scene, info["problem"]))
    windows = Windows(solver, refine, cells, offset) if refine > 1 else None
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


def dovetail_run(nodes, refine, cells, offset=False):
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
    windows = Windows(solver, refine, cells, offset) if refine > 1 else None
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
    ap.add_argument("--dovetail", type=int, nargs="*", default=[1000, 2000], help="nodes (against --dovetail-reference)")
    ap.add_argument("--dovetail-reference", type=int, default=8000)
    ap.add_argument("--keep-offset", action="store_true",
                    help="the window's rigid offset stays with its stuck cells (default: their locks follow the lattice's shift)")
    ap.add_argument("--no-doc", action="store_true")
    args = ap.parse_args(argv)
    ref = np.load(REFERENCE)
    random_rows, dovetail_rows = [], []
    for g in args.geometries:
        random_run(g, 0, 64, 1, args.cells)  # numba loads its compiled functions at their first call
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
                random_rows.append((g, nodes, _windows(refine, args.cells), np.median(v), np.percentile(v, 95), np.percentile(e, 95), e.max(),
                                    failed, solved, 1e3 * wall / steps))
                print(_random_row(random_rows[-1]), flush=True)
    if args.dovetail:
        reference, width, *_ = dovetail_run(args.dovetail_reference, 1, args.cells)
        for nodes in args.dovetail:
            for refine in (1, args.refine):
                edges, _, wall, failed, solved = dovetail_run(nodes, refine, args.cells, args.keep_offset)
                err = np.abs(edges - reference) / width
                dovetail_rows.append((nodes, _windows(refine, args.cells), np.nanmedian(err), np.nanpercentile(err, 95), np.nanmax(err),
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
            "coupled to the lattice, against the lattice alone. Times are the experiment's (dense numpy, kernel "
            "logarithms), not a built version's.\n\n"
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
