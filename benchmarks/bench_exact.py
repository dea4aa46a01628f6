"""Benchmark of the exact memory method: a 10^6-step Hertz fretting history.

Run:  python benchmarks/bench_exact.py [--steps N]
Writes docs/bench_exact.md. Reports microseconds per step of ``hs.simulate``
(extents only: no per-point fields; the compiled marcher of solvers/_exact_kernel.py)
and, measured in the same run, the ratio to a bare Python loop that only
evaluates b = a sqrt(1 - abs(Q)/(f P)) at each step; also the Python step path
that runs whenever a per-point field is stored.
"""
from __future__ import annotations

import argparse
import dataclasses
import math
import platform
import time
from pathlib import Path

import numpy as np

import halfslip as hs
from halfslip.histories import LoadHistory

ROOT = Path(__file__).resolve().parents[1]


def fretting_scene(n_steps: int):
    base = hs.load_scene(ROOT / "examples" / "hertz_pad.yaml")
    per_cycle = 100
    ramp = 20
    t = np.arange(n_steps + 1, dtype=float) / per_cycle
    P = np.minimum(np.arange(n_steps + 1) / ramp, 1.0) * 1.0e5
    Q = np.where(np.arange(n_steps + 1) > ramp, 1.8e4 * np.sin(2 * np.pi * (np.arange(n_steps + 1) - ramp) / per_cycle), 0.0)
    history = LoadHistory.from_arrays(t, P, Q)
    return dataclasses.replace(base, history=history, output=dataclasses.replace(base.output, fields=()))


def bare_loop(P: np.ndarray, Q: np.ndarray, f: float, a: float) -> float:
    P_list, Q_list = P.tolist(), Q.tolist()
    start = time.perf_counter()
    for p, q in zip(P_list, Q_list):
        b = a * math.sqrt(1.0 - abs(q) / (f * p)) if p > 0 else 0.0  # noqa: F841
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--steps", type=int, default=1_000_000)
    args = parser.parse_args()
    scene = fretting_scene(args.steps)
    h = scene.history
    a = float(hs.NormalProblem(scene.profile, scene.material.compliance).half_width(1.0e5))
    t_bare = min(bare_loop(h.P, h.Q, scene.friction, a) for _ in range(3))
    start = time.perf_counter()
    hs.simulate(scene)  # first call in the process: imports numba, loads (or compiles) the kernel
    t_first = time.perf_counter() - start
    start = time.perf_counter()
    ds = hs.simulate(scene)
    t_sim = time.perf_counter() - start
    fields_scene = dataclasses.replace(scene, output=dataclasses.replace(scene.output, fields=("q",), every=1000))
    n_py = min(h.n_steps, 100_000)
    short = dataclasses.replace(fields_scene, history=LoadHistory.from_arrays(h.t[: n_py + 1], h.P[: n_py + 1], h.Q[: n_py + 1]))
    start = time.perf_counter()
    hs.simulate(short)  # a stored field forces the Python step path
    t_py = time.perf_counter() - start
    n = h.n_steps
    us_sim, us_bare, us_py = 1e6 * t_sim / n, 1e6 * t_bare / n, 1e6 * t_py / n_py
    lines = [
        "# Exact memory method: speed",
        "",
        f"Measured by `python benchmarks/bench_exact.py --steps {n}` on {platform.platform()}, "
        f"{platform.processor() or platform.machine()}, Python {platform.python_version()}, numpy {np.__version__}.",
        "",
        f"Hertz fretting pad (examples/hertz_pad.yaml loads), {n} steps, 100 steps per cycle, extents only.",
        "",
        "| what | time per step [us] | ratio to bare loop |",
        "|---|---|---|",
        f"| `hs.simulate`, exact method, extents only (compiled kernel), warm | {us_sim:.3f} | {us_sim / us_bare:.2f} |",
        f"| the same, first call in a process (numba import, kernel load) | {1e6 * t_first / n:.3f} | {1e6 * t_first / n / us_bare:.2f} |",
        f"| `hs.simulate`, Python step path (a field stored every 1000 steps; {n_py} steps) | {us_py:.2f} | {us_py / us_bare:.1f} |",
        f"| bare Python loop b = a sqrt(1 - abs(Q)/(fP)) | {us_bare:.3f} | 1 |",
        "",
        f"Slip solves {ds.attrs['count_slip_solves']}, normal solves {ds.attrs['count_normal_solves']}, "
        f"final dissipation {float(ds.dissipation[-1]):.6g} J/m.",
    ]
    text = "\n".join(lines) + "\n"
    print(text)
    (ROOT / "docs").mkdir(exist_ok=True)
    (ROOT / "docs" / "bench_exact.md").write_text(text)


if __name__ == "__main__":
    main()
