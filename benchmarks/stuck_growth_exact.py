"""The lattice and the IC baseline against the exact fully stuck shear on the random Hertz history's first steps
(seed 0: P, Q and sigma in proportion, Q = 0.9 f P, a large moment; every point sticks, the contact grows and
moves) (docs/general_solver.md, Limits, "Arrival locks on a moving contact").

    python benchmarks/stuck_growth_exact.py                 # steps 1-4, nodes 1024 2048 4096, IC 8000 16000
    python benchmarks/stuck_growth_exact.py --drop M        # the same with M = 0 (symmetric: exact edge path)
    python benchmarks/stuck_growth_exact.py --split 1 4 16  # each history step cut into that many steps
    python benchmarks/stuck_growth_exact.py --points 0      # the error at every cell, not at 150 points

While everything sticks, the shear is the sum of the fully stuck increments (physics.md, M1 with the sigma term)
over the contacts along the loading path: q(x) = sum over steps of int [Q' / (pi sqrt(d^2 - s^2)) + sigma' s /
(4 sqrt(d^2 - s^2))] dlam from x's arrival on (s = x - c(lam); the contact's centre c and half-width d from the
normal problem at every quadrature node; the inverse square root at arrival taken out by lam = lam_x + (1 -
lam_x) u^2; 40 Gauss points in u). Printed: max |q - exact| / max |exact| over the contact's inner 94 % (the
edges' own cells left out), per solver.
"""
from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "tests"))

import helpers  # noqa: E402
from baseline_ic import history_extent, run_history  # noqa: E402
from isolate_disagreement import history  # noqa: E402


class StuckHistory:
    """The history's loads and normal problem (isolate_disagreement.history), and the exact fully stuck q at any
    point after step K (tests/helpers.stuck_shear)."""

    def __init__(self, drop: str | None):
        self.problem, self.friction, self.width, self.P, self.Q, self.M, self.S = history("random", drop)

    def edges(self, K: int) -> tuple[float, float]:
        """The contact edges at the end of step K."""
        sol = self.problem.solve(self.P[K], self.M[K])
        return sol.left, sol.right

    def q(self, x: float, K: int) -> float:
        return helpers.stuck_shear(self.problem, list(zip(self.P[1:K + 1], self.Q[1:K + 1], self.M[1:K + 1],
                                                          self.S[1:K + 1])), x)

    def loads(self, K: int, split: int):
        """(P, Q, M, sigma) from the start to step K, each step cut into ``split`` equal steps."""
        out = [np.array([v[0]]) for v in (self.P, self.Q, self.M, self.S)]
        lam = np.arange(1, split + 1) / split
        for k in range(1, K + 1):
            for j, v in enumerate((self.P, self.Q, self.M, self.S)):
                out[j] = np.concatenate((out[j], v[k - 1] + lam * (v[k] - v[k - 1])))
        return out


def lattice_q(h: StuckHistory, nodes: int, K: int, split: int):
    from halfslip.solvers.general import GeneralSolver
    from halfslip.state import Loads
    solver = GeneralSolver(h.problem, h.friction, nodes, width=h.width, estimate=False, edge_windows=False)
    state = solver.initial_state(0.0)
    P, Q, M, S = h.loads(K, split)
    for i in range(1, P.size):
        state, report = solver.step(state, float(i), Loads(P[i], Q[i], M[i], S[i]))
        if report.regime.name != "STICK":
            raise SystemExit(f"the lattice slips at step {i}: not a fully stuck history")
    return np.asarray(state.memory.x), np.asarray(state.memory.q)


def ic_q(h: StuckHistory, n: int, K: int, split: int):
    P, Q, M, S = h.loads(K, split)
    out = run_history(h.problem, h.friction, n, P, Q, M, S, extent=history_extent(h.problem, h.P, h.M), keep_q=True)
    return out["x"], out["q"][-1]


def error(h: StuckHistory, K: int, x: np.ndarray, q: np.ndarray, points: int = 150) -> float:
    left, right = h.edges(K)
    W = right - left
    inner = np.flatnonzero((x > left + 0.03 * W) & (x < right - 0.03 * W))
    sel = inner[:: max(1, inner.size // points)] if points > 0 else inner
    exact = np.array([h.q(float(v), K) for v in x[sel]])
    return float(np.max(np.abs(q[sel] - exact)) / np.max(np.abs(exact)))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, nargs="+", default=[1, 2, 3, 4])
    ap.add_argument("--nodes", type=int, nargs="+", default=[1024, 2048, 4096])
    ap.add_argument("--ic", type=int, nargs="*", default=[8000, 16000])
    ap.add_argument("--split", type=int, nargs="+", default=[1])
    ap.add_argument("--drop", choices=["sigma", "M"])
    ap.add_argument("--points", type=int, default=150,
                    help="points of the inner contact the error is taken at (0: every cell centre there)")
    args = ap.parse_args(argv)
    h = StuckHistory(args.drop)
    for split in args.split:
        for K in args.steps:
            row = [f"L{n} {error(h, K, *lattice_q(h, n, K, split), args.points):.1e}" for n in args.nodes]
            row += [f"IC{n} {error(h, K, *ic_q(h, n, K, split), args.points):.1e}" for n in args.ic]
            print(f"step {K}, each step in {split}: max |q - exact| / max q: " + "  ".join(row), flush=True)


if __name__ == "__main__":
    main()
