"""Linear-algebra strategies of the IC baseline, measured on the first steps of a random history.

    python benchmarks/bench_baseline_ic.py [--steps 24] [--n 1000 2000]

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


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--geometry", default="hertz")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--steps", type=int, default=24)
    ap.add_argument("--n", type=int, nargs="+", default=[1000, 2000])
    ap.add_argument("--strategies", nargs="+", default=["gs", "toeplitz", "dense", "lu"])
    args = ap.parse_args(argv)
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
