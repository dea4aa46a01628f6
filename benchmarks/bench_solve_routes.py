"""Stick sets of two runs (an island beside a stick zone): the islands' Schur complement against the gaps'.

    python benchmarks/bench_solve_routes.py            # writes its table to docs/benchmarks.md

_toeplitz.stick_solve (compiled since 0.4.0) solves a stick set of several runs exactly by
one of two Schur complements: of the cells of the runs other than the
longest (the islands: one more column of a solve on the longest run per
island cell), or of the gaps between the runs within the spanning run (one
solve per gap, O(span) per gap cell, a dense factorisation of the gaps).
This times both, on the same systems, in one process, over island and gap
sizes as the random histories have them (island cells: median 17, 90th
percentile 40; gaps: median 93, 90th percentile 219, at 1024 nodes), and
checks that they agree. _toeplitz.ISLAND_COST, the gap cells per island cell
at which the two cost the same, is read from it.
"""
from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import platform
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from _doc import write_section  # noqa: E402

DOC = HERE.parent / "docs" / "benchmarks.md"
BEGIN, END = "<!-- solve_routes: begin -->", "<!-- solve_routes: end -->"


def best_of(f, repeat):
    """The least wall time of ``repeat`` calls of ``f`` [ms] (after one to warm up)."""
    f()
    best = float("inf")
    for _ in range(repeat):
        started = time.perf_counter()
        f()
        best = min(best, time.perf_counter() - started)
    return 1e3 * best


def main(argv=None):
    from halfslip.solvers._toeplitz import GAP_CELLS, ISLAND_COST, ToeplitzLattice, _gap_solve, _island_solve

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=30)
    parser.add_argument("--no-doc", action="store_true")
    args = parser.parse_args(argv)
    lat = ToeplitzLattice(1e-6, 1600, 1e-11)
    rng = np.random.default_rng(0)
    rows = []
    for longest in (200, 440, 800):
        for gap in (5, 20, 93, 160):
            for islands in (1, 4, 17, 40):
                runs = np.array([(0, islands), (islands + gap, islands + gap + longest)], np.int64)
                rhs = rng.standard_normal((islands + longest, 2))
                ones = np.column_stack((np.ones(islands + longest), rhs))  # with the rigid shift's column, as
                by_islands = _island_solve(lat.tables, runs, 1, ones)   # the active set solves
                by_gaps = _gap_solve(lat.tables, runs, rhs)
                agree = float(np.max(np.abs(by_islands - by_gaps)) / np.max(np.abs(by_gaps)))
                if not agree < 1e-11:
                    raise SystemExit(f"the two routes disagree by {agree:.2e} at {runs.tolist()}")
                t_i = best_of(lambda: _island_solve(lat.tables, runs, 1, ones), args.repeat)
                t_g = best_of(lambda: _gap_solve(lat.tables, runs, rhs), args.repeat)
                chosen = "islands" if ISLAND_COST * islands <= gap or gap > GAP_CELLS else "gaps"
                rows.append((longest, gap, islands, t_i, t_g, chosen, agree))
                print(f"longest {longest:4d}  gap {gap:4d}  islands {islands:3d}:  islands {t_i:.3f} ms  "
                      f"gaps {t_g:.3f} ms  -> {chosen}  (agree to {agree:.1e})")
    if args.no_doc:
        return
    lines = [BEGIN, "",
             f"`python benchmarks/bench_solve_routes.py` ({platform.machine()}, {os.cpu_count()} cores, "
             f"Python {platform.python_version()}, numpy {np.__version__}; one run, best of {args.repeat}): "
             "a stick set of one island run and one run of `longest` cells, a column of ones and two "
             "right-hand sides (compiled), solved "
             "through the islands' Schur complement and through the gaps'. The solver takes the islands' "
             f"when the gaps hold at least ISLAND_COST = {ISLAND_COST} cells per island cell (or more than "
             f"GAP_CELLS = {GAP_CELLS}).", "",
             "| longest run | gap cells | island cells | islands [ms] | gaps [ms] | taken |",
             "|---:|---:|---:|---:|---:|---|"]
    for longest, gap, islands, t_i, t_g, chosen, _ in rows:
        lines.append(f"| {longest} | {gap} | {islands} | {t_i:.3f} | {t_g:.3f} | {chosen} |")
    lines += ["", END]
    write_section(DOC, BEGIN, END, "\n".join(lines), "Stick sets of several runs: the two Schur complements")


if __name__ == "__main__":
    main()
