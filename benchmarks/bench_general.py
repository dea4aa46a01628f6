"""Convergence and speed of the general slip solver; writes the results into docs/general_solver.md.

    python benchmarks/bench_general.py            # full run (about 10 minutes)
    python benchmarks/bench_general.py --quick    # fewer resolutions, small baseline

Four histories, errors against a reference at each resolution ``nodes``:

1. Cattaneo-Mindlin on Hertz: P, then two cycles of Q = 0.6 f P sin (exact method);
2. Jaeger-Ciavarella on the rounded punch: the same Q cycles (exact method);
3. varying P with phase, the motor loop P = P0 + P1 sin wt, Q = Q1 sin(wt + 90 deg)
   (exact method; steps whose path runs parallel to a slip line, |dQ/dP| within 1%
   of f, are left out of the edge error: the edge is ill-conditioned there);
4. the dovetail scene (rounded punch, P, Q, M, sigma in phase; examples/dovetail.yaml)
   against the general solver at REFERENCE_NODES.

Errors: the largest over the steps of |stick edge - reference| / contact width,
and of the L2 error of q(x) on 401 points relative to the L2 norm of f p(x)
(the traction scale: q itself passes through zero when Q does); observed order
log2(err[:-1] / err[1:]) per doubling of ``nodes``.

Speed: the Cattaneo-Mindlin history run by the influence-coefficient baseline
(benchmarks/baseline_ic.py, which replaced the dense straw man baseline_dense.py)
at increasing cell counts; the ratio of run times is taken at the finest
stick-edge error both reach.
"""
from __future__ import annotations

import argparse
import math
import os
import platform
import re
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(0, str(ROOT / "benchmarks"))

from baseline_ic import ICBaseline  # noqa: E402

from halfslip.geometry import Hertz, Material, NormalProblem, RoundedPunch  # noqa: E402
from halfslip.histories import LoadHistory  # noqa: E402
from halfslip.solvers.exact import ExactMemory  # noqa: E402
from halfslip.solvers.general import GeneralSolver  # noqa: E402
from halfslip.state import Loads  # noqa: E402

DOC = ROOT / "docs" / "general_solver.md"
BEGIN, END = "<!-- bench_general: begin -->", "<!-- bench_general: end -->"
REFERENCE_NODES = 2048
F = 0.6


# -- histories -----------------------------------------------------------------
def cm_history(P0, cycles=2, steps=40):
    path = [(P0, 0.0, 0.0, 0.0)]
    for k in range(1, cycles * steps + 1):
        path.append((P0, 0.6 * F * P0 * math.sin(2 * math.pi * k / steps), 0.0, 0.0))
    return path


def motor_history(P0=1e5, P1=3e4, Q1=3e4, cycles=2, steps=64):
    path = [(P0 * k / 20, Q1 * k / 20, 0.0, 0.0) for k in range(1, 21)]
    for _ in range(cycles):
        for k in range(1, steps + 1):
            w = 2 * math.pi * k / steps
            path.append((P0 + P1 * math.sin(w), Q1 * math.cos(w), 0.0, 0.0))
    return path


def dovetail_history(cycles=2):
    h = LoadHistory.from_segments([
        {"ramp": {"to": {"P": 2e5, "Q": 2e4, "M": 5.0, "sigma": 2e7}, "duration": 1.0, "steps": 50}},
        {"cycles": {"count": cycles, "period": 1.0, "steps_per_cycle": 100, "P": {"amplitude": 2e4},
                    "Q": {"amplitude": 3e4}, "M": {"amplitude": 5.0}, "sigma": {"amplitude": 2e7}}},
    ])
    return [(h.P[i], h.Q[i], h.M[i], h.sigma[i]) for i in range(1, h.n_steps + 1)]


# -- running -------------------------------------------------------------------
def run(method, path):
    """States of ``method`` along ``path`` and the wall time [s]."""
    state = method.initial_state()
    states = []
    started = time.perf_counter()
    for i, loads in enumerate(path):
        state, _ = method.step(state, i + 1.0, Loads(*loads))
        states.append(state)
    return states, time.perf_counter() - started


def errors(method, states, ref_method, ref_states, path, skip_parallel=False):
    """Largest stick-edge error / contact width and largest L2 error of q (/ L2 of f p) over the steps."""
    edge = q_err = 0.0
    prev = (0.0, 0.0)
    for loads, s, r in zip(path, states, ref_states):
        P, Q = loads[0], loads[1]
        W = r.contact_right - r.contact_left
        parallel = skip_parallel and P != prev[0] and abs(abs((Q - prev[1]) / (P - prev[0])) - F) < 0.01 * F
        prev = (P, Q)
        if not math.isnan(r.stick_left) and not parallel:
            edge = max(edge, abs(s.stick_left - r.stick_left) / W, abs(s.stick_right - r.stick_right) / W)
        x = np.linspace(r.contact_left, r.contact_right, 401)
        q = method.tractions(s.memory, x)[1]
        p, q_ref = ref_method.tractions(r.memory, x)
        scale = F * math.sqrt(float(np.mean(p**2)))
        if scale > 0.0:
            q_err = max(q_err, math.sqrt(float(np.mean((q - q_ref) ** 2))) / scale)
    return edge, q_err


def convergence(name, problem, path, nodes_list, reference, skip_parallel=False):
    """Rows (nodes, edge error, q error, ms per step) for one history."""
    ref_method = (ExactMemory(problem, F, max(p[0] for p in path)) if reference == "exact"
                  else GeneralSolver(problem, F, REFERENCE_NODES))
    ref_states, _ = run(ref_method, path)
    rows = []
    for nodes in nodes_list:
        method = GeneralSolver(problem, F, nodes)
        states, wall = run(method, path)
        edge, q_err = errors(method, states, ref_method, ref_states, path, skip_parallel)
        rows.append((nodes, edge, q_err, 1e3 * wall / len(path)))
        print(f"  {name}: nodes {nodes}: edge {edge:.2e}, q {q_err:.2e}, {rows[-1][3]:.1f} ms/step", flush=True)
    return rows


def speed(problem, path, cells_list, general_rows):
    """Baseline rows (cells, edge error, wall) and the ratio at the finest common edge error."""
    exact = ExactMemory(problem, F, path[0][0])
    ref_states, _ = run(exact, path)
    a = ref_states[0].contact_right
    rows = []
    for n in cells_list:
        base = ICBaseline(problem, F, n, (-1.01 * a, 1.01 * a))
        edge = 0.0
        started = time.perf_counter()
        for loads, r in zip(path, ref_states):
            base.step(*loads)
            stick = base.zones()["stick"]
            if not math.isnan(r.stick_left):
                W = r.contact_right - r.contact_left
                edge = max(edge, abs(stick[0] - r.stick_left) / W, abs(stick[1] - r.stick_right) / W)
        wall = time.perf_counter() - started
        rows.append((n, edge, wall))
        print(f"  baseline: {n} cells: edge {edge:.2e}, {wall:.1f} s", flush=True)
    target = min(e for _, e, _ in rows)
    base_n, base_e, base_wall = min((r for r in rows if r[1] <= target * 1.0000001), key=lambda r: r[2])
    mine = [r for r in general_rows if r[1] <= base_e]
    nodes, edge, _, ms = min(mine, key=lambda r: r[3]) if mine else general_rows[-1]
    wall = ms * len(path) / 1e3
    return rows, (base_n, base_e, base_wall, nodes, edge, wall, base_wall / wall)


# -- report --------------------------------------------------------------------
def orders(values):
    v = np.asarray(values, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.log2(v[:-1] / v[1:])


def table(name, rows):
    lines = [f"**{name}**", "", "| nodes | stick-edge error / width | order | q error (L2 / f p) | order | ms / step |",
             "|---:|---:|---:|---:|---:|---:|"]
    oe, oq = orders([r[1] for r in rows]), orders([r[2] for r in rows])
    for i, (n, e, q, ms) in enumerate(rows):
        o1 = f"{oe[i - 1]:.2f}" if i else ""
        o2 = f"{oq[i - 1]:.2f}" if i else ""
        lines.append(f"| {n} | {e:.2e} | {o1} | {q:.2e} | {o2} | {ms:.1f} |")
    return "\n".join(lines)


def machine():
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as fh:
            names = [line.split(":", 1)[1].strip() for line in fh if line.startswith("model name")]
        if names:
            cpu = f"{names[0]} ({len(names)} logical CPUs)"
    except OSError:
        pass
    return f"{cpu}; Python {platform.python_version()}, numpy {np.__version__}, {platform.system()} {platform.release()}"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer resolutions and a small baseline")
    parser.add_argument("--no-write", action="store_true", help="print the report, leave the docs alone")
    args = parser.parse_args(argv)
    nodes_list = [64, 128, 256, 512] if args.quick else [64, 128, 256, 512, 1024]
    cells_list = [250, 500, 1000] if args.quick else [250, 500, 1000, 2000, 4000, 8000]

    steel = 4 * (1 - 0.3**2) / 200e9
    hertz = NormalProblem(Hertz(50e-3), steel)
    ti = Material(115e9, 0.3).compliance
    punch = NormalProblem(RoundedPunch(2e-3, 10e-3), ti)

    print("convergence", flush=True)
    cm_path = cm_history(1e5)
    results = [
        ("(1) Cattaneo-Mindlin on Hertz, two Q cycles, against the exact method",
         convergence("CM", hertz, cm_path, nodes_list, "exact")),
        ("(2) Jaeger-Ciavarella on the rounded punch, two Q cycles, against the exact method",
         convergence("JC", punch, cm_history(2e5), nodes_list, "exact")),
        ("(3) varying P with phase (motor loop), against the exact method",
         convergence("motor", hertz, motor_history(), nodes_list, "exact", skip_parallel=True)),
        (f"(4) dovetail, P Q M sigma in phase on the rounded punch, against {REFERENCE_NODES} nodes",
         convergence("dovetail", punch, dovetail_history(), nodes_list, "self")),
    ]
    print("speed", flush=True)
    base_rows, (bn, be, bw, gn, ge, gw, ratio) = speed(hertz, cm_path, cells_list, results[0][1])

    out = [BEGIN, "", f"Measured by `python benchmarks/bench_general.py{' --quick' if args.quick else ''}` "
           f"on {time.strftime('%Y-%m-%d')}; machine: {machine()}.", ""]
    for name, rows in results:
        out += [table(name, rows), ""]
    out += ["**Speed: the IC baseline (benchmarks/baseline_ic.py) on history (1)**", "",
            "| cells | stick-edge error / width | run time [s] |", "|---:|---:|---:|"]
    out += [f"| {n} | {e:.2e} | {w:.1f} |" for n, e, w in base_rows]
    out += ["", f"At the finest stick-edge error the baseline reached ({be:.1e}, {bn} cells, {bw:.1f} s), "
            f"the general solver needs {gn} nodes ({ge:.1e}) and {gw:.2f} s: **{ratio:.0f}x faster**, "
            f"measured in this run ({len(cm_path)} steps).", "", END]
    report = "\n".join(out)
    print(report)
    if not args.no_write:
        text = DOC.read_text() if DOC.exists() else f"{BEGIN}\n{END}\n"
        text = re.sub(re.escape(BEGIN) + ".*?" + re.escape(END), lambda _: report, text, flags=re.S)
        DOC.write_text(text)
        print(f"wrote {os.path.relpath(DOC, Path.cwd())}")


if __name__ == "__main__":
    main()
