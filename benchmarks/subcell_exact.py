"""Slip zones narrower than a cell at the contact edges: where the general solver places them against the exact
method, and the dovetail's ill-conditioned receding edge (docs/general_solver.md, "Sub-cell zones").

    python benchmarks/subcell_exact.py                 # the closed forms, 256 / 512 / 1024 nodes
    python benchmarks/subcell_exact.py --dovetail      # the dovetail's left zone at steps 120-125 and 221-225

The closed forms (the exact level method, halfslip.solvers.exact, on both profiles with M = sigma = 0): J1 / J2
(constant P, Q to 0.6 f P and back in 30 steps each); J3, a proportional state (P0, 0.3 f P0) reached in 10
steps, then P falling in 20 steps fast (to P0 / 2) or slowly (to 0.99 P0) along dQ/dP = k' f, k' = 0.25, 0.29,
0.31, 0.35 (both edges recede while slipping); the motor loop (P = P0 + P1 sin, Q = Q1 cos). For each run, the
lattice alone and with its edge windows: the outermost stick points' error in units of the cell that placed them
(the lattice's, or the window's fine cell where a window reported the edge), over the edges whose exact and
computed slip zones are both under 1.5 of those cells; its 95th percentile and largest. These are what
general.SUBCELL_PLACEMENT (the estimate's floor for such zones) is set from.

--dovetail: examples/dovetail.yaml marched step by step with the lattice alone at 1000 .. 16000 nodes and with
windows (REFINE 4 and 6) at 1000: the left slip zone (stick_left - contact_left) in the windows' fine cells of the
1000-node lattice at steps where 4000 - 16000 nodes disagree (221 - 225) and where they agree (120 - 125).
"""
from __future__ import annotations

import argparse
import math
import os
import sys
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

#: Steps of the dovetail whose left zone the --dovetail table reads (the first cycle's agree at every resolution,
#: the second's do not).
DOVETAIL_STEPS = (120, 121, 122, 123, 124, 125, 221, 222, 223, 224, 225)
#: Edges whose exact and computed zones are narrower than this many placing cells are counted.
ZONE_CELLS = 1.5


def _march(solver, path):
    from halfslip.state import Loads

    state, out = solver.initial_state(0.0), []
    for i, (P, Q) in enumerate(path):
        state, _ = solver.step(state, float(i + 1), Loads(P, Q, 0.0, 0.0))
        out.append(state)
    return out


def paths(P0: float, F: float) -> dict:
    """The load paths (P, Q) of the module docstring."""
    out = {}
    j1 = [(P0, 0.0)] + [(P0, 0.6 * F * P0 * j / 30) for j in range(1, 31)]
    out["J1 / J2"] = j1 + [(P0, 0.6 * F * P0 * (1 - j / 30)) for j in range(1, 31)]
    for kp in (0.25, 0.29, 0.31, 0.35):
        for name, drop in (("fast", 0.5), ("slow", 0.01)):
            p = [(P0 * j / 10, 0.3 * F * P0 * j / 10) for j in range(1, 11)]
            out[f"J3 {name} k'={kp}"] = p + [(P0 * (1 - drop * j / 20), 0.3 * F * P0 - kp * F * drop * P0 * j / 20)
                                            for j in range(1, 21)]
    p = [(P0 * k / 20, 3e4 * k / 20) for k in range(1, 21)]
    for k in range(1, 65):
        w = 2 * math.pi * k / 64
        p.append((P0 + 3e4 * math.sin(w), 3e4 * math.cos(w)))
    out["motor loop"] = p
    return out


def subcell_errors(run, exact, windows: bool) -> np.ndarray:
    """Errors of the outermost stick points of ``run`` against ``exact`` (lists of states) in placing cells, over the
    edges whose zones are under ZONE_CELLS of them."""
    errors = []
    for s, e in zip(run, exact):
        if not (np.isfinite(e.stick_left) and np.isfinite(s.stick_left)):
            continue
        for side, got, want, edge in ((-1, s.stick_left, e.stick_left, e.contact_left),
                                      (1, s.stick_right, e.stick_right, e.contact_right)):
            cell = s.memory.spacing
            if windows:  # (the window's fine cell where its edge is the one reported, not the lattice's)
                cell = next((w.spacing for w in s.memory.windows if w.side == side and got != w.lattice_edge), cell)
            if abs(want - edge) < ZONE_CELLS * cell and abs(got - edge) < ZONE_CELLS * cell:
                errors.append(abs(got - want) / cell)
    return np.array(errors)


def closed_forms(nodes_list) -> list[str]:
    from helpers import P0, PROFILES, A, F

    from halfslip.geometry import NormalProblem
    from halfslip.solvers.exact import ExactMemory
    from halfslip.solvers.general import GeneralSolver

    rows = ["| profile | path | nodes | cells | edges | 95th pct | largest |", "|---|---|---:|---|---:|---:|---:|"]
    worst = {False: 0.0, True: 0.0}
    for kind in ("hertz", "punch"):
        problem = NormalProblem(PROFILES[kind], A)
        for name, path in paths(P0, F).items():
            exact = _march(ExactMemory(problem, F, 1.3 * P0), path)
            for nodes in nodes_list:
                for windows in (False, True):
                    e = subcell_errors(_march(GeneralSolver(problem, F, nodes, edge_windows=windows), path), exact,
                                       windows)
                    if e.size:
                        worst[windows] = max(worst[windows], float(e.max()))
                        rows.append(f"| {kind} | {name} | {nodes} | {'windows (fine)' if windows else 'lattice'} | "
                                    f"{e.size} | {np.percentile(e, 95):.3f} | {e.max():.3f} |")
                        print(rows[-1], flush=True)
    rows.append(f"\nLargest: lattice {worst[False]:.3f} of a cell, windows {worst[True]:.3f} of a fine cell.")
    return rows


def dovetail() -> list[str]:
    import halfslip as hs
    from halfslip.geometry import NormalProblem
    from halfslip.simulator import reference_width
    from halfslip.solvers import general
    from halfslip.solvers._windows import EdgeWindows
    from halfslip.state import Loads

    scene = hs.load_scene(HERE.parent / "examples" / "dovetail.yaml")
    h = scene.history
    problem = NormalProblem(scene.profile, scene.material.compliance)
    width = reference_width(scene, problem)
    fine = width / 1000 / 4
    rows = ["| run | " + " | ".join(str(i) for i in DOVETAIL_STEPS) + " |",
            "|---|" + "---:|" * len(DOVETAIL_STEPS)]
    for nodes, refine in ((1000, None), (2000, None), (4000, None), (8000, None), (16000, None), (1000, 4),
                          (1000, 6)):
        solver = general.GeneralSolver(problem, scene.friction, nodes, width=width, edge_windows=refine is not None)
        if refine:
            solver.windows = EdgeWindows(solver, general, refine, None)
        state, zones = solver.initial_state(h.t[0]), {}
        for i in range(1, max(DOVETAIL_STEPS) + 1):
            state, _ = solver.step(state, h.t[i], Loads(h.P[i], h.Q[i], h.M[i], h.sigma[i]))
            if i in DOVETAIL_STEPS:
                zones[i] = (state.stick_left - state.contact_left) / fine
        label = f"lattice {nodes}" if refine is None else f"windows x {refine} ({nodes})"
        rows.append(f"| {label} | " + " | ".join(f"{zones[i]:.2f}" for i in DOVETAIL_STEPS) + " |")
        print(rows[-1], flush=True)
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--nodes", type=int, nargs="+", default=[256, 512, 1024])
    ap.add_argument("--dovetail", action="store_true", help="the dovetail's left zone instead of the closed forms")
    args = ap.parse_args(argv)
    rows = dovetail() if args.dovetail else closed_forms(args.nodes)
    print("\n".join(rows))


if __name__ == "__main__":
    main()
