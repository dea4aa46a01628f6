"""The J1 / J2 table of docs/general_solver.md ("Accuracy"): stick-edge errors of the general solver.

    python benchmarks/table_j1_j2.py      # prints the table rows (about a minute)

One history per profile and resolution, steel on steel, f = 0.6, P0 = 1e5 N/m
(tests/helpers.py): P0, then Q = 0.1 ... 0.9 f P0 (each step is J1 at its Q:
b = a(P0 - Q/f)), then back in steps of 0.2 f P0 to -0.9 f P0 (J2, unloading
from Q_max = 0.9 f P0: c = a(P0 - (Q_max - Q)/(2 f))). Columns: largest and
mean of max(|left - exact|, |right - exact|) / W over the J1 and the J2 steps,
and the largest error estimate over both.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import helpers  # noqa: E402
from helpers import F, P0  # noqa: E402


def rows():
    for kind in ("hertz", "punch"):
        for nodes in (128, 256, 512, 1024, 2048, 4096):
            problem, solver = helpers.make(kind, "general", nodes=nodes)
            up = [(P0, k * 0.1 * F * P0) for k in range(1, 10)]
            down = [(P0, (0.9 - k * 0.2) * F * P0) for k in range(1, 10)]
            out = helpers.march(solver, [(P0, 0.0)] + up + down)
            W = 2 * float(problem.half_width(P0))
            j1, j2, estimates = [], [], []
            for (state, report), (_, Q) in zip(out[1:10], up):
                b = float(problem.half_width(P0 - Q / F))
                j1.append(max(abs(state.stick_right - b), abs(state.stick_left + b)) / W)
                estimates.append(report.error_estimate)
            for (state, report), (_, Q) in zip(out[10:], down):
                c = float(problem.half_width(P0 - (0.9 * F * P0 - Q) / (2 * F)))
                j2.append(max(abs(state.stick_right - c), abs(state.stick_left + c)) / W)
                estimates.append(report.error_estimate)
            name = "Hertz" if kind == "hertz" else "punch"
            yield (f"| {name} | {nodes} | {max(j1):.1e} | {np.mean(j1):.1e} | {max(j2):.1e} | {np.mean(j2):.1e} "
                   f"| {np.nanmax(estimates):.1e} |")


if __name__ == "__main__":
    for row in rows():
        print(row, flush=True)
