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
    from halfslip.solvers._toeplitz import (GAP_CELLS, GAP_CUBE, GAPS, ISLAND_COST, ISLANDS, ToeplitzLattice,
                                            _gap_solve, _island_solve, route)

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=30)
    parser.add_argument("--no-doc", action="store_true")
    args = parser.parse_args(argv)
    lat = ToeplitzLattice(1e-6, 1800, 1e-11)
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
                way = route(runs)[0]
                chosen = "islands" if way == ISLANDS else "gaps" if way == GAPS else "CG"
                rows.append((longest, gap, islands, t_i, t_g, chosen, agree))
                print(f"longest {longest:4d}  gap {gap:4d}  islands {islands:3d}:  islands {t_i:.3f} ms  "
                      f"gaps {t_g:.3f} ms  -> {chosen}  (agree to {agree:.1e})")
    cg_rows = gaps_against_cg(lat, rng, args.repeat)
    if args.no_doc:
        return
    lines = [BEGIN, "",
             f"`python benchmarks/bench_solve_routes.py` ({platform.machine()}, {os.cpu_count()} cores, "
             f"Python {platform.python_version()}, numpy {np.__version__}; one run, best of {args.repeat}): "
             "a stick set of one island run and one run of `longest` cells, a column of ones and two "
             "right-hand sides (compiled), solved "
             "through the islands' Schur complement and through the gaps'. The solver takes the islands' "
             f"when the gaps hold at least ISLAND_COST = {ISLAND_COST} cells per island cell (or when the gaps' "
             "complement costs more than CG, below) (`_toeplitz.route`).", "",
             "| longest run | gap cells | island cells | islands [ms] | gaps [ms] | taken |",
             "|---:|---:|---:|---:|---:|---|"]
    for longest, gap, islands, t_i, t_g, chosen, _ in rows:
        lines.append(f"| {longest} | {gap} | {islands} | {t_i:.3f} | {t_g:.3f} | {chosen} |")
    lines += ["", "Two long runs and one gap (the split stick zones of the random histories at 2048 nodes: "
              "gaps of 180-350 cells in spans of about 1500 on Hertz), solved through the gaps' complement "
              "and by block-Jacobi CG: the solver takes the gaps' while they hold at most GAP_CELLS = "
              f"{GAP_CELLS} cells or (gap cells)^3 <= GAP_CUBE x span, GAP_CUBE = {GAP_CUBE:g}.", "",
              "| span | gap cells | gaps [ms] | CG [ms] | CG iterations | taken |",
              "|---:|---:|---:|---:|---:|---|"]
    for span, gap, t_g, t_c, it, chosen in cg_rows:
        lines.append(f"| {span} | {gap} | {t_g:.3f} | {t_c:.3f} | {it} | {chosen} |")
    lines += ["", END]
    write_section(DOC, BEGIN, END, "\n".join(lines), "Stick sets of several runs: the two Schur complements")


def gaps_against_cg(lat, rng, repeat):
    """Two runs split by one gap, across spans and gap sizes: the gaps' complement against CG, and the route
    the solver takes (_toeplitz.route)."""
    from halfslip.solvers._toeplitz import CG, GAPS, _cg_runs, _gap_solve, _with_ones, route

    rows = []
    for span in (800, 1600):
        for gap in (120, 160, 240, 320, 480):
            left = (span - gap) // 2
            runs = np.array([(0, left), (left + gap, span)], np.int64)
            m, spec = lat._circulant(span)
            rhs = rng.standard_normal((span - gap, 2))
            ones = _with_ones(rhs)
            by_gaps = _gap_solve(lat.tables, runs, rhs)
            by_cg, it = _cg_runs(lat.tables, spec, m, runs, ones, 1e-13, 200)
            agree = float(np.max(np.abs(by_cg - by_gaps)) / np.max(np.abs(by_gaps)))
            if not agree < 1e-11:
                raise SystemExit(f"the gaps' complement and CG disagree by {agree:.2e} at {runs.tolist()}")
            t_g = best_of(lambda: _gap_solve(lat.tables, runs, rhs), repeat)
            t_c = best_of(lambda: _cg_runs(lat.tables, spec, m, runs, ones, 1e-13, 200), repeat)
            way = route(runs)[0]
            chosen = "gaps" if way == GAPS else "CG" if way == CG else "other"
            rows.append((span, gap, t_g, t_c, it, chosen))
            print(f"span {span:5d}  gap {gap:4d}:  gaps {t_g:.3f} ms  CG {t_c:.3f} ms ({it} iterations)  -> "
                  f"{chosen}  (agree to {agree:.1e})")
    return rows


if __name__ == "__main__":
    main()
