"""Where the lattice and the IC reference disagree, with one load taken out (docs/general_solver.md, the
Hertz history's steps 72-76).

    python benchmarks/isolate_disagreement.py random --drop sigma      # seed 0 Hertz, steps 1..80, sigma = 0
    python benchmarks/isolate_disagreement.py random --drop M
    python benchmarks/isolate_disagreement.py short                     # a 22-step Hertz history, sigma alone
    python benchmarks/isolate_disagreement.py short --moment 0.3        # the same with M = 0.3 a P in phase with sigma
    python benchmarks/isolate_disagreement.py random --force --ic 8000 16000 --nodes 2048 4096
                                                 # the cumulative force int q apart, per step, and where

Runs the package's general solver (no windows, no estimate) at ``--nodes`` and the IC baseline at ``--ic``
(each step in four sub-steps, as the reference) on the same history, and prints per step the outermost
stick points' distance from the finest IC run, in contact widths: the lattices', then the coarser IC runs'
(their spread says how far the finest may be from its own limit). The IC at N = 16000 takes 10-30 minutes.
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

from baseline_ic import history_extent, run_history  # noqa: E402
from random_histories import random_history  # noqa: E402

KEYS = ("stick_left", "stick_right", "contact_left", "contact_right")


def history(kind: str, drop: str | None, moment: float = 0.0):
    """(problem, friction, reference width, P, Q, M, sigma) with point 0 the start."""
    if kind == "random":
        info = {}
        scene, _, P, Q, M, S = random_history(0, "hertz", info=info)
        P, Q, M, S = (v[:81].copy() for v in (P, Q, M, S))
        if drop == "sigma":
            S[:] = 0.0
        elif drop == "M":
            M[:] = 0.0
        from halfslip.simulator import reference_width
        return info["problem"], info["friction"], reference_width(scene, info["problem"]), P, Q, M, S
    from halfslip.geometry import Hertz, NormalProblem
    f, P0, A = 0.6, 1e5, 4 * (1 - 0.3**2) / 200e9  # (tests/helpers.py's steel pad)
    problem = NormalProblem(Hertz(radius=50e-3), A)
    a = float(problem.half_width(P0))
    s = f * 2 * P0 / (np.pi * a)  # f p0
    pts = [(0.0, 0.0, 0.0, 0.0)] + [(P0 * k / 4, 0.0, 0.0, 0.0) for k in range(1, 5)]
    # M (moment * a P) follows sigma: up with Q, down as Q reverses
    pts += [(P0, 0.5 * f * P0 * k / 6, moment * a * P0 * k / 6, 0.3 * s * k / 6) for k in range(1, 7)]
    pts += [(P0 * (1 + 0.3 * k / 12), 0.5 * f * P0 * (1 - 1.6 * k / 12), moment * a * P0 * (1 - 0.5 * k / 12),
             0.3 * s * (1 - 0.5 * k / 12)) for k in range(1, 13)]
    P, Q, M, S = (np.array(v, dtype=float) for v in zip(*pts))
    if drop == "sigma":
        S[:] = 0.0
    return problem, f, 2 * float(problem.half_width(1.3 * P0)), P, Q, M, S


def cumulative(x, q, h):
    """The cumulative force int q from the left at the cells' boundaries (x their centres, h their width)."""
    return np.concatenate((x - 0.5 * h, [x[-1] + 0.5 * h])), np.concatenate(([0.0], np.cumsum(q * h)))


def lattice(problem, f, width, nodes, P, Q, M, S):
    from halfslip.solvers.general import GeneralSolver
    from halfslip.state import Loads
    solver = GeneralSolver(problem, f, nodes, width=width, estimate=False, edge_windows=False)
    state = solver.initial_state(0.0)
    out = {k: [] for k in KEYS}
    forces = []
    for i in range(1, P.size):
        state, _ = solver.step(state, float(i), Loads(P[i], Q[i], M[i], S[i]))
        for k in KEYS:
            out[k].append(getattr(state, k))
        m = state.memory
        forces.append(cumulative(np.asarray(m.x), np.asarray(m.q), m.spacing))
    out = {k: np.asarray(v) for k, v in out.items()}
    out["force"] = forces
    return out


def ic(problem, f, n, P, Q, M, S, keep_q=False):
    """The IC run, each step in four sub-steps (the reference's); with ``keep_q`` in one (its q is kept per
    history step only then)."""
    out = run_history(problem, f, n, P, Q, M, S, extent=history_extent(problem, P, M), time_split=1 if keep_q else 4,
                      keep_q=keep_q)
    got = {k: np.asarray(out[k]) for k in KEYS}
    if keep_q:
        x = np.asarray(out["x"])
        got["force"] = [cumulative(x, q, x[1] - x[0]) for q in out["q"]]
    return got


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("kind", choices=["random", "short"])
    ap.add_argument("--drop", choices=["sigma", "M"])
    ap.add_argument("--nodes", type=int, nargs="+", default=[1024, 2048])
    ap.add_argument("--ic", type=int, nargs="+", default=[4000, 8000, 16000])
    ap.add_argument("--moment", type=float, default=0.0, help="short: M as a fraction of a P (0: none)")
    ap.add_argument("--from-step", type=int, default=1)
    ap.add_argument("--force", action="store_true",
                    help="print the cumulative force int q apart (largest, over f P, and where) instead of the edges")
    args = ap.parse_args(argv)
    problem, f, width, P, Q, M, S = history(args.kind, args.drop, args.moment)
    runs = {f"L{n}": lattice(problem, f, width, n, P, Q, M, S) for n in args.nodes}
    ics = {f"IC{n}": ic(problem, f, n, P, Q, M, S, keep_q=args.force) for n in sorted(args.ic)}
    finest = ics.pop(f"IC{max(args.ic)}")
    runs.update(ics)
    W = finest["contact_right"] - finest["contact_left"]
    if args.force:
        print("step  " + "  ".join(f"{k}: |dF| / f P at x [m]" for k in runs))
        for i in range(args.from_step - 1, W.size):
            grid = np.linspace(finest["contact_left"][i], finest["contact_right"][i], 4001)
            ref = np.interp(grid, *finest["force"][i])
            cells = []
            for r in runs.values():
                d = np.interp(grid, *r["force"][i]) - ref
                k = int(np.argmax(np.abs(d)))
                cells.append(f"{abs(d[k]) / (f * P[i + 1]):.1e} at {grid[k]:+.3e}")
            print(f"{i + 1:4d}  " + "  ".join(cells))
        return
    print("step  " + "  ".join(f"{side}: " + " ".join(f"{k:>8}" for k in runs) for side in ("left", "right")))
    for i in range(args.from_step - 1, W.size):
        cells = ["  ".join(" ".join(f"{(r[key][i] - finest[key][i]) / W[i]:+8.1e}" for r in runs.values())
                           for key in ("stick_left", "stick_right"))]
        print(f"{i + 1:4d}  " + cells[0])


if __name__ == "__main__":
    main()
