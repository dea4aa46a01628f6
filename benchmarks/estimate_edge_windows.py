"""What refining only the cells at the contact edges would give on the random histories (issue 14, grading).

    python benchmarks/estimate_edge_windows.py                  # both geometries, 512 / 1024 against 2048
    python benchmarks/estimate_edge_windows.py --geometries punch --windows 8 16 --base 512 --fine 2048

The uniform lattice is run at the ``--base`` and ``--fine`` resolutions; every stick edge within W base
cells of its nearer contact edge is then taken from the fine run, every other edge from the base run, and
the 95th percentile of their errors over the edges the reference vouches for is printed
(bench_general_random.compare's measure): the accuracy a lattice of the base cells with windows of W cells
at both contact edges refined to the fine cells would reach if the windows placed their edges as the fine
lattice does. An estimate of what grading can give, not a run of it: the windows' own coupling to the
coarse cells is assumed to cost nothing in accuracy. With ``--coupling`` it also prints what that coupling
costs in the coarse lattice's solves (:func:`coupling_ranks`).
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


def coupling_ranks(window=16, refine=4, cells=512, tolerances=(1e-7, 1e-10)):
    """Numerical ranks of what a window's refinement adds, seen from the coarse cells beyond it: the
    displacements at the coarse centres outside a window of ``window`` cells at the contact's edge whose cells
    are each cut into ``refine`` sub-cells carrying zero-mean patterns (Haar-like: the (refine - 1) patterns
    per cell that a constant shear per coarse cell cannot carry), the log kernel integrated over each
    sub-cell (cells of width 1). Each such rank is a column more in every stick-set solve of the coarse
    lattice (a Woodbury or Schur-complement coupling). Returns {(first coarse cell beyond the window, tol):
    rank}. The entries are differences of terms about 1e-11 of them apart in rounding, so tolerances below
    ~1e-10 read the noise."""
    from halfslip.solvers._toeplitz import _G  # u ln|u| - u, the lattice kernel's antiderivative

    def integral(x, a, b):  # int_a^b ln|x - xi| dxi
        return _G(x[:, None] - a[None, :]) - _G(x[:, None] - b[None, :])

    sub = 1.0 / refine
    patterns = []
    for k in range(1, refine):  # zero-mean Haar-like patterns on the sub-cells
        p = np.zeros(refine)
        p[:k], p[k:] = 1.0 / k, -1.0 / (refine - k)
        patterns.append(p)
    out = {}
    for gap in (0, 2, 8, 16):
        x = np.arange(window + gap, cells) + 0.5
        columns = []
        for c in range(window):
            a = c + sub * np.arange(refine)
            block = integral(x, a, a + sub)
            columns += [block @ p for p in patterns]
        s = np.linalg.svd(np.column_stack(columns), compute_uv=False)
        for tol in tolerances:
            out[(window + gap, tol)] = int(np.sum(s > tol * s[0]))
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--geometries", nargs="+", default=["hertz", "punch"])
    ap.add_argument("--base", type=int, nargs="+", default=[512, 1024])
    ap.add_argument("--fine", type=int, default=2048)
    ap.add_argument("--windows", type=int, nargs="+", default=[0, 8, 16, 32])
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--coupling", action="store_true", help="also the ranks of a window's coupling (coupling_ranks)")
    args = ap.parse_args(argv)
    if args.coupling:
        ranks = coupling_ranks(window=max(args.windows), cells=min(args.base))
        print("| coarse centres from cell | tolerance | rank of a window's added patterns there |")
        print("|---:|---:|---:|")
        for (start, tol), rank in ranks.items():
            print(f"| {start} | {tol:g} | {rank} |")
        print()
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
