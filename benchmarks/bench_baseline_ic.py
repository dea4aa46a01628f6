"""Linear-algebra strategies of the IC baseline, measured on the first steps of a random history.

    python benchmarks/bench_baseline_ic.py [--steps 24] [--n 1000 2000]
    python benchmarks/bench_baseline_ic.py --solves --n 1000 2000 4000 8000   # single solves

Runs benchmarks/baseline_ic.py with strategy 'gs' (Gohberg-Semencul inverse of each Toeplitz run from
one cached inverse Cholesky factor, FFT products), 'toeplitz' (the cached Cholesky factor of the
Toeplitz matrix, triangular sweeps over its leading block), 'dense' (LAPACK Cholesky of each stick
set, cached per set) and 'lu' (LU from scratch every solve, the old straw man) on the same steps
(split stick sets: block-Jacobi PCG with the run solves in the first two), and
prints the time per step and per stick-set solve, and the largest difference of the stick edges from
the 'toeplitz' run (the three must agree to rounding).
"""
from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # shared 2-core machine: threaded BLAS spins (10-100x slower)

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from baseline_ic import history_extent, run_history  # noqa: E402
from random_histories import random_history  # noqa: E402


def time_solves(ns):
    """Time of one run solve T_n^{-1} b (n = 0.7 N, a typical stick run) per strategy, and its residual."""
    from scipy.linalg import cho_factor, cho_solve

    from baseline_ic import ICBaseline
    from halfslip.geometry import Hertz, NormalProblem

    problem = NormalProblem(Hertz(0.05), 4 * 0.91 / 200e9)
    print("| N | run n | setup once per grid [s] (gs / sweeps) | gs [ms] | sweeps [ms] | dense Cholesky of the set "
          "[ms] | residual gs / sweeps |")
    print("|---:|---:|---:|---:|---:|---:|---:|")
    rng = np.random.default_rng(0)
    for N in ns:
        g = ICBaseline(problem, 0.6, N, (-1e-3, 1e-3), strategy="gs")
        c = ICBaseline(problem, 0.6, N, (-1e-3, 1e-3), strategy="toeplitz")
        t0 = time.perf_counter()
        g._gs(2)
        setup_g = time.perf_counter() - t0
        t0 = time.perf_counter()
        c._cholesky()
        c._run_solve(2, np.ones(2))
        setup_c = time.perf_counter() - t0
        n = int(0.7 * N)
        b = rng.random(n)
        g._run_solve(n, b)  # per-n data cached, as for repeated solves with one run length
        reps = 20
        t0 = time.perf_counter()
        for _ in range(reps):
            xg = g._run_solve(n, b)
        tg = (time.perf_counter() - t0) / reps
        t0 = time.perf_counter()
        for _ in range(3):
            xc = c._run_solve(n, b)
        tc = (time.perf_counter() - t0) / 3
        i = np.arange(n)
        T = -g.t[np.abs(i[:, None] - i[None, :])]
        if N <= 4000:
            t0 = time.perf_counter()
            cho_solve(cho_factor(T, lower=True, check_finite=False), b, check_finite=False)
            td = f"{1e3 * (time.perf_counter() - t0):.0f}"
        else:
            td = "–"
        rg = np.abs(T @ xg - b).max() / np.abs(b).max()
        rc = np.abs(T @ xc - b).max() / np.abs(b).max()
        print(f"| {N} | {n} | {setup_g:.1f} / {setup_c:.1f} | {1e3 * tg:.2f} | {1e3 * tc:.1f} | {td} | "
              f"{rg:.0e} / {rc:.0e} |", flush=True)
        del g, c, T


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--geometry", default="hertz")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--steps", type=int, default=24)
    ap.add_argument("--n", type=int, nargs="+", default=[1000, 2000])
    ap.add_argument("--strategies", nargs="+", default=["gs", "toeplitz", "dense", "lu"])
    ap.add_argument("--solves", action="store_true", help="time single run solves instead (N from --n)")
    args = ap.parse_args(argv)
    if args.solves:
        time_solves(args.n)
        return
    info = {}
    _, _, P, Q, M, S = random_history(args.seed, args.geometry, info=info)
    k = args.steps + 1
    P, Q, M, S = P[:k], Q[:k], M[:k], S[:k]
    ext = history_extent(info["problem"], P, M)
    print("| N | strategy | ms / step | ms / solve | solves | max edge difference / width |")
    print("|---:|---|---:|---:|---:|---:|")
    for n in args.n:
        ref = None
        for strat in args.strategies:
            t0 = time.perf_counter()
            out = run_history(info["problem"], info["friction"], n, P, Q, M, S, extent=ext, strategy=strat)
            wall = time.perf_counter() - t0
            W = out["contact_right"] - out["contact_left"]
            edges = np.concatenate([out["stick_left"] / W, out["stick_right"] / W])
            if ref is None:
                ref = edges
            diff = np.nanmax(np.abs(edges - ref))
            solves = int(out["solves"].sum())
            print(f"| {n} | {strat} | {1e3 * wall / args.steps:.1f} | {1e3 * out['time'].sum() / solves:.2f} | "
                  f"{solves} | {diff:.1e} |", flush=True)


if __name__ == "__main__":
    main()
