"""The general solver's error in time on the seeded random (P, Q, M, sigma) histories: its own runs with the
sub-step rules scaled, against its run with the finest rules at the same nodes (the same lattice, so only
the time discretisation differs).

    python benchmarks/time_convergence.py                     # nodes 512 1024 2048, both geometries, 2 seeds
    python benchmarks/time_convergence.py --nodes 1024 --no-doc

The rules (GeneralSolver._pieces) are scaled together by a factor k: a contact edge's travel per slipping
sub-step DEFAULT_TRAVEL x k of the width, a stick edge's DEFAULT_STICK_TRAVEL x k, the arrivals'
ARRIVAL_CELLS x k cells (k = 1: the defaults). The finest run takes k = FINEST (MAX_SUBSTEPS raised so that
no step is capped). What is compared: the outermost stick edges at every step (relative to the contact
width; steps where both have a stick zone), the final cumulative dissipation (relative), and the work
(fine and shadow takes per step, counted; ms per step, one pass, indicative). The observed order is
log2 of the ratio of the 95th percentiles at k and k / 2.

What it showed (docs/general_solver.md, "Sub-steps"): the default rules' error in time is several times
below the lattice's own at the 95th percentile and falls with the cell (it is where in its cell an edge
sits, not where the edge is), so the edges do not ask for more sub-steps; the dissipation does
(tests/test_general.py: a reversal step while the contact recedes ends in the same state whatever its
sub-steps, while its dissipation needs them).
Writes the table between the markers in docs/benchmarks.md.
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
from bench_general_random import DOC, machine, run_solver  # noqa: E402

BEGIN, END = "<!-- time_convergence: begin -->", "<!-- time_convergence: end -->"
#: The finest scale of the rules (the reference run's); the others are compared with it.
FINEST = 0.25
SCALES = (4.0, 2.0, 1.0, 0.5)


def run(geometry, seed, nodes, k):
    """One history with the sub-step rules scaled by ``k`` (module constants restored afterwards)."""
    from halfslip.solvers import general

    kept = general.ARRIVAL_CELLS, general.MAX_SUBSTEPS
    try:
        # ARRIVAL_CELLS and MAX_SUBSTEPS are module constants, read at each step
        general.ARRIVAL_CELLS = max(1, round(kept[0] * k))
        general.MAX_SUBSTEPS = max(kept[1], round(kept[1] / k))
        return run_solver(geometry, seed, nodes, travel=general.DEFAULT_TRAVEL * k,
                          stick_travel=general.DEFAULT_STICK_TRAVEL * k)
    finally:
        general.ARRIVAL_CELLS, general.MAX_SUBSTEPS = kept


def compare(runs, finest):
    """Edge differences (pooled over seeds and both sides, / width) and the largest relative difference of
    the final dissipation, of ``runs`` against ``finest`` (lists over the seeds)."""
    errors, dissipation = [], 0.0
    for a, b in zip(runs, finest):
        W = b["contact_right"] - b["contact_left"]
        for side in ("stick_left", "stick_right"):
            e = np.abs(a[side] - b[side]) / W
            errors.append(e[np.isfinite(e)])
        dissipation = max(dissipation, abs(a["dissipation"][-1] - b["dissipation"][-1]) / b["dissipation"][-1])
    return np.concatenate(errors), dissipation


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--nodes", type=int, nargs="+", default=[512, 1024, 2048])
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--geometries", nargs="+", default=["hertz", "punch"])
    ap.add_argument("--no-doc", action="store_true")
    args = ap.parse_args(argv)
    for g in args.geometries:  # numba loads its compiled functions at their first call: not in a timed run
        run_solver(g, 0, 64)
    rows = []
    for nodes in args.nodes:
        for g in args.geometries:
            finest = [run(g, s, nodes, FINEST) for s in range(args.seeds)]
            before = None
            for k in SCALES:
                runs = [run(g, s, nodes, k) for s in range(args.seeds)]
                e, d = compare(runs, finest)
                steps = sum(r["steps"] for r in runs)
                p95 = float(np.percentile(e, 95))
                order = np.log2(before / p95) if before and p95 > 0 else np.nan
                before = p95
                rows.append((g, nodes, k, float(np.median(e)), p95, float(np.percentile(e, 99)), float(e.max()),
                             order, d, sum(r["takes"] for r in runs) / steps,
                             sum(r["shadow_takes"] for r in runs) / steps, 1e3 * sum(r["wall"] for r in runs) / steps))
                print(_fmt(rows[-1]), flush=True)
    if not args.no_doc:
        write_doc(rows, args, " ".join(sys.argv[1:] if argv is None else argv))


def _fmt(r):
    g, nodes, k, med, p95, p99, top, order, d, takes, shadow, ms = r
    order = "" if not np.isfinite(order) else f"{order:.2f}"
    label = f"{k:g}" + (" (default)" if k == 1.0 else "")
    return (f"| {g} | {nodes} | {label} | {med:.1e} | {p95:.1e} | {order} | {p99:.1e} | {top:.1e} | "
            f"{100 * d:.3f} % | {takes:.2f} | {shadow:.2f} | {ms:.2f} |")


def write_doc(rows, args, argv):
    head = ("| geometry | nodes | rules x k | stick edges against the finest rules: median | 95th pct | observed "
            "order (95th pct, k against 2k) | 99th pct | max | final dissipation | fine takes / step | shadow takes "
            "/ step | ms / step |\n|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    from halfslip.solvers import general

    text = (f"{BEGIN}\nMeasured with `python benchmarks/time_convergence.py {argv}` on {time.strftime('%Y-%m-%d')}; "
            f"machine: {machine()}. Each run against the same solver at the same nodes with the sub-step rules x "
            f"{FINEST:g} (a contact edge's travel {FINEST:g} x {general.DEFAULT_TRAVEL:g} of the width per slipping "
            f"sub-step, a stick edge's {FINEST:g} x {general.DEFAULT_STICK_TRAVEL:g}, arrivals {FINEST:g} x "
            f"{general.ARRIVAL_CELLS} cells), seeds 0..{args.seeds - 1}; edges relative to "
            f"the contact width; times one pass, indicative (the takes are counted).\n\n{head}\n"
            + "\n".join(_fmt(r) for r in rows) + f"\n{END}")
    write_section(DOC, BEGIN, END, text, "The general solver's error in time (sub-step rules)")


if __name__ == "__main__":
    main()
