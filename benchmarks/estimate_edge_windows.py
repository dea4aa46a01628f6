"""What refining only the cells at the contact edges would give on the random histories (issue 14, grading).

    python benchmarks/estimate_edge_windows.py                  # both geometries, 512 / 1024 against 2048
    python benchmarks/estimate_edge_windows.py --geometries punch --windows 8 16 --base 512 --fine 2048

The uniform lattice is run at the ``--base`` and ``--fine`` resolutions; every stick edge within W base
cells of its nearer contact edge is then taken from the fine run, every other edge from the base run, and
the 95th percentile of their errors over the edges the reference vouches for is printed
(bench_general_random.compare's measure): the accuracy a lattice of the base cells with windows of W cells
at both contact edges refined to the fine cells would reach if the windows placed their edges as the fine
lattice does. An estimate of what grading can give, not a run of it: the windows' own coupling to the
coarse cells is assumed to cost nothing in accuracy.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import bench_general_random as bench  # noqa: E402


def vouched_errors(runs, ref, geometry, base, fine, window):
    """Errors (/ width) of the composite edges over the vouched edges of both seeds and sides."""
    out = []
    for seed in sorted({s for _, s in runs}):
        key = f"{geometry}_{seed}_"
        left, right = ref[key + "contact_left"], ref[key + "contact_right"]
        width = right - left
        sure = bench.reference_error(ref, key)
        for side in ("stick_left", "stick_right"):
            r = ref[key + side]
            coarse, refined = runs[base, seed][side], runs[fine, seed][side]
            ok = np.isfinite(coarse) & np.isfinite(refined) & np.isfinite(r) & (sure[side] <= bench.VOUCH)
            cells = np.minimum(np.abs(r - left), np.abs(right - r)) / width * base
            edge = np.where(cells <= window, refined, coarse)
            out.append((np.abs(edge - r) / width)[ok])
    return np.concatenate(out)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--geometries", nargs="+", default=["hertz", "punch"])
    ap.add_argument("--base", type=int, nargs="+", default=[512, 1024])
    ap.add_argument("--fine", type=int, default=2048)
    ap.add_argument("--windows", type=int, nargs="+", default=[0, 8, 16, 32])
    ap.add_argument("--seeds", type=int, default=2)
    args = ap.parse_args(argv)
    ref = np.load(bench.REFERENCE)
    print("| geometry | base nodes | window (base cells at each contact edge) | as at | vouched 95th pct |")
    print("|---|---:|---:|---:|---:|")
    for g in args.geometries:
        runs = {(n, s): bench.run_solver(g, s, n) for n in {*args.base, args.fine} for s in range(args.seeds)}
        for base in args.base:
            for w in args.windows:
                e = vouched_errors(runs, ref, g, base, args.fine, w)
                print(f"| {g} | {base} | {w} | {args.fine} | {np.percentile(e, 95):.1e} |")
        e = vouched_errors(runs, ref, g, args.fine, args.fine, 0)
        print(f"| {g} | {args.fine} | - | - | {np.percentile(e, 95):.1e} |")


if __name__ == "__main__":
    main()
