"""The general solver's fine windows at the contact edges (``edge_windows``, halfslip.solvers._windows) against
the lattice alone, on the random histories and on the dovetail.

    python benchmarks/bench_edge_windows.py                  # the tables in docs/benchmarks.md
    python benchmarks/bench_edge_windows.py --nodes 512 --geometries punch --no-doc

Random histories (seeds 0, 1): the outermost stick points against benchmarks/reference/random_reference.npz
(bench_general_random.compare), with and without windows, and the time per step (GeneralSolver.step alone).
The dovetail (examples/dovetail.yaml, every step marched): the last cycle's outermost stick points against the
lattice at ``--dovetail-reference`` nodes. ``--cells`` and ``--refine`` (a row for each value given) override the windows' size
(_windows.WINDOW_CELLS, REFINE) for a measurement.

What the design measured before it was built (2026-11-28, then benchmarks/experiment_edge_windows.py): without
the window's own history (locks from the lattice's state at every take) it is worse than the lattice alone
(5.5e-4 / 3.7e-4 at 512 nodes against 2.7e-4); with the window's rigid offset fixed to the lattice's shift (no
force condition) its history drifts from the lattice's (4.5e-3); with the offset kept by its stuck cells 8.1e-5
against 8.6e-5 on the punch but 1.1e-4 against 4.1e-5 on the dovetail. Windows of the same width at 2000 and
4000 nodes (32 and 64 cells) keep the dovetail's load maximum 3.0e-3 off (an ill-conditioned band, where the
lattice is 12.4 um off up to 8000 nodes).
"""
from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
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
#: The stick-edge accuracy the estimate is read against (the default solver.tol, a fraction of the width).
TOL = 1e-4


def _solver(problem, friction, nodes, width, windows, refine=None, cells=None):
    """A GeneralSolver with or without windows (their size _windows.window_size's, or ``cells`` x ``refine``)."""
    from halfslip.solvers import general
    from halfslip.solvers._windows import EdgeWindows

    solver = general.GeneralSolver(problem, friction, nodes, width=width, edge_windows=windows)
    if windows and (refine or cells):
        solver.windows = EdgeWindows(solver, general, refine, cells)
    return solver


def _counts(solver):
    return (0, 0) if solver.windows is None else (solver.windows.failed, solver.windows.solved)


def _label(solver):
    w = solver.windows
    return "-" if w is None else f"{w.cells} cells x {w.refine}"


def random_run(geometry, seed, nodes, windows, refine=None, cells=None):
    """One random history with or without windows: per-step records for compare()."""
    from halfslip.simulator import reference_width
    from halfslip.state import Loads

    info = {}
    scene, t, P, Q, M, S = random_history(seed, geometry, info=info)
    solver = _solver(info["problem"], info["friction"], nodes, reference_width(scene, info["problem"]), windows,
                     refine, cells)
    state = solver.initial_state(t[0])
    rec = {k: [] for k in ("stick_left", "stick_right", "contact_left", "contact_right", "dissipation", "intervals",
                           "error")}
    began = time.perf_counter()
    for i in range(1, t.size):
        state, report = solver.step(state, t[i], Loads(P[i], Q[i], M[i], S[i]))
        for k, v in (("stick_left", state.stick_left), ("stick_right", state.stick_right),
                     ("contact_left", state.contact_left), ("contact_right", state.contact_right),
                     ("dissipation", state.dissipation), ("intervals", solver.stick_intervals(state)),
                     ("error", report.error_estimate)):
            rec[k].append(v)
    wall = time.perf_counter() - began
    out = {k: np.asarray(v, dtype=float) for k, v in rec.items()}
    out["converged"] = np.ones(t.size - 1, bool)
    out["wall"], out["steps"] = wall, t.size - 1
    out["failed"], out["solved"] = _counts(solver)
    out["windows"] = _label(solver)
    return out


def dovetail_run(nodes, windows, refine=None, cells=None, every=False):
    """examples/dovetail.yaml marched step by step (no cycle skipped): the outermost stick points of the last
    cycle's steps (``every``: of every step), the contact width at each, time per step, window solves not
    converged, window solves, the last cycle's dissipation, the windows' size and those steps' error
    estimates."""
    import halfslip as hs
    from halfslip.geometry import NormalProblem
    from halfslip.simulator import reference_width
    from halfslip.state import Loads

    sc = hs.load_scene(HERE.parent / "examples" / "dovetail.yaml")
    h = sc.history
    problem = NormalProblem(sc.profile, sc.material.compliance)
    solver = _solver(problem, sc.friction, nodes, reference_width(sc, problem), windows, refine, cells)
    state = solver.initial_state(h.t[0])
    last = h.t >= h.t[-1] - 1.0 - 1e-12
    edges, widths, estimates = [], [], []
    began = time.perf_counter()
    for i in range(1, h.t.size):
        state, report = solver.step(state, h.t[i], Loads(h.P[i], h.Q[i], h.M[i], h.sigma[i]))
        if last[i] or every:
            edges.append((state.stick_left, state.stick_right))
            widths.append(state.contact_right - state.contact_left)
            estimates.append(report.error_estimate)
        if last[i] and not last[i - 1]:  # the last cycle starts at the end of this step
            start = state.dissipation
    wall = (time.perf_counter() - began) / (h.t.size - 1)
    return (np.array(edges), np.array(widths), wall) + _counts(solver) + (
        state.dissipation - start, _label(solver), np.array(estimates))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--nodes", type=int, nargs="*", default=[512, 1024], help="random histories at these nodes (none: the dovetail only)")
    ap.add_argument("--geometries", nargs="+", default=["punch", "hertz"])
    ap.add_argument("--refine", type=int, nargs="+", default=[None],
                    help="fine cells per lattice cell, one row each (default: _windows.window_size's)")
    ap.add_argument("--cells", type=int, help="lattice cells per window (default: _windows.window_size's)")
    ap.add_argument("--dovetail", type=int, nargs="*", default=[500, 1000, 2000, 4000],
                    help="nodes (against --dovetail-reference)")
    ap.add_argument("--dovetail-reference", type=int, default=16000)
    ap.add_argument("--every-step", action="store_true",
                    help="the dovetail's edges and estimates at every marched step (2050), not its last cycle's")
    ap.add_argument("--repeat", type=int, default=1,
                    help="passes per run, with and without windows in turn; the best time counts (the same numbers)")
    ap.add_argument("--no-doc", action="store_true")
    args = ap.parse_args(argv)
    ref = np.load(REFERENCE)
    random_rows, dovetail_rows = [], []
    for g in args.geometries:  # numba compiles or loads its functions at their first call: not in a timed run
        random_run(g, 0, 64, True)
    for nodes in args.nodes:
        for g in args.geometries:
            for windows, refine in [(False, None)] + [(True, r) for r in args.refine]:
                vouched, every, failed, solved, wall, steps = [], [], 0, 0, 0.0, 0
                estimates, misses, edges = [], 0, 0
                for seed in (0, 1):
                    run = _best(lambda: random_run(g, seed, nodes, windows, refine, args.cells), args.repeat,
                                lambda r: r["wall"])
                    e, v, *_ = compare(run, ref, f"{g}_{seed}_")
                    vouched.append(v)
                    every.append(e)
                    estimates.append(run["error"])
                    m, n = _misses(run, ref, f"{g}_{seed}_")
                    misses, edges = misses + m, edges + n
                    failed, solved = failed + run["failed"], solved + run["solved"]
                    wall, steps = wall + run["wall"], steps + run["steps"]
                v, e, est = np.concatenate(vouched), np.concatenate(every), np.concatenate(estimates)
                random_rows.append((g, nodes, run["windows"], np.median(v), np.percentile(v, 95),
                                    np.percentile(e, 95), e.max(), np.nanmedian(est),
                                    100.0 * np.mean(est[np.isfinite(est)] > TOL), f"{misses} of {edges}",
                                    failed, solved, 1e3 * wall / steps))
                print(_random_row(random_rows[-1]), flush=True)
    if args.dovetail:
        reference, width, *_, spent, _, sure = dovetail_run(args.dovetail_reference, False, every=args.every_step)
        for nodes in args.dovetail:
            for windows, refine in [(False, None)] + [(True, r) for r in args.refine]:
                edges, _, wall, failed, solved, cycle, label, est = _best(
                    lambda: dovetail_run(nodes, windows, refine, args.cells, args.every_step), args.repeat,
                    lambda r: r[2])
                err = np.abs(edges - reference) / width[:, None]
                # (an edge the estimate misses: off by more than the estimate and the reference's own together)
                worst = np.nanmax(err, axis=1)
                missed = int(np.sum(worst > est + sure))
                dovetail_rows.append((nodes, label, np.nanmedian(err),
                                      np.nanpercentile(err, 95), np.nanmax(err), cycle / spent - 1.0,
                                      np.nanmedian(est), 100.0 * np.mean(est[np.isfinite(est)] > TOL),
                                      f"{missed} of {est.size}", failed, solved, 1e3 * wall))
                print(_dovetail_row(dovetail_rows[-1]), flush=True)
    if not args.no_doc:
        write_doc(random_rows, dovetail_rows, args, " ".join(sys.argv[1:] if argv is None else argv))


def _best(run, repeat, wall):
    """``run()`` ``repeat`` times: the first pass's answer (every pass gives the same numbers) with the least wall
    time of all (``wall`` reads it from an answer; a dict's "wall" or a tuple's third item)."""
    first = run()
    least = wall(first)
    for _ in range(repeat - 1):
        least = min(least, wall(run()))
    if isinstance(first, dict):
        return dict(first, wall=least)
    return first[:2] + (least,) + first[3:]


def _misses(run, ref, key):
    """(how many of the run's outermost stick points are farther from the reference's than the step's error
    estimate and the reference's own error together, how many there are)."""
    sure = reference_error(ref, key)
    W = ref[key + "contact_right"] - ref[key + "contact_left"]
    missed = count = 0
    for side in ("stick_left", "stick_right"):
        a, b = run[side], ref[key + side]
        ok = np.isfinite(a) & np.isfinite(b) & np.isfinite(run["error"])
        missed += int(np.sum(np.abs(a - b)[ok] / W[ok] > run["error"][ok] + sure[side][ok]))
        count += int(np.sum(ok))
    return missed, count


def _random_row(r):
    g, nodes, windows, med, p95, all95, top, est, above, missed, failed, solved, ms = r
    return (f"| {g} | {nodes} | {windows} | {med:.1e} | {p95:.1e} | {all95:.1e} | {top:.1e} | {est:.1e} | "
            f"{above:.0f} % | {missed} | {failed} of {solved} | {ms:.2f} |")


def _dovetail_row(r):
    nodes, windows, med, p95, top, spent, est, above, missed, failed, solved, ms = r
    return (f"| {nodes} | {windows} | {med:.1e} | {p95:.1e} | {top:.1e} | {100 * spent:+.3f} % | {est:.1e} | "
            f"{above:.0f} % | {missed} | {failed} of {solved} | {ms:.2f} |")



def write_doc(random_rows, dovetail_rows, args, argv):
    text = (f"{BEGIN}\nMeasured with `python benchmarks/bench_edge_windows.py {argv}` on "
            f"{time.strftime('%Y-%m-%d')}; machine: {machine()}. The general solver's outermost stick points with "
            "its fine windows at the contact edges (`solver.edge_windows`, halfslip.solvers._windows: one-way "
            "coupled to the lattice) against the lattice alone; ms / step: GeneralSolver.step alone, the best of "
            f"{args.repeat} pass{'es' if args.repeat > 1 else ''}.\n\n"
            "Random histories (seeds 0, 1), stick edges against benchmarks/reference/random_reference.npz, relative to "
            f"the contact width; vouched: the reference's own estimate at most {VOUCH:g}:\n\n"
            f"The estimate: the steps' error_estimate, its median, the share of steps above {TOL:g} of the width "
            "(the default solver.tol), and the edges farther from the reference's than the estimate and the "
            "reference's own error together.\n\n"
            "| geometry | nodes | windows | vouched: median | vouched: 95th pct | all: 95th pct | max | estimate: "
            f"median | estimate above {TOL:g} | edges it misses | window solves "
            "not converged | ms / step |\n|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n"
            + "\n".join(_random_row(r) for r in random_rows)
            + (f"\n\nexamples/dovetail.yaml, every step marched, "
               f"{'every step' if args.every_step else 'the last cycle'}'s outermost stick points and "
               f"dissipation against the lattice at {args.dovetail_reference} nodes (steps the estimate misses: the "
               "larger edge error above the estimate and the reference's own together):\n\n| nodes | windows | "
               "median | 95th pct | max | dissipation per cycle | estimate: median | estimate above "
               f"{TOL:g} | steps it misses | window solves not converged | ms / step |\n"
               "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n"
               + "\n".join(_dovetail_row(r) for r in dovetail_rows) if dovetail_rows else "")
            + f"\n{END}")
    write_section(DOC, BEGIN, END, text, "Fine windows at the contact edges (solver.edge_windows)")


if __name__ == "__main__":
    main()
