"""Run time against error for each method and resolution, on scenes with known answers.

Run:  python benchmarks/bench_accuracy.py [--quick]   (the full run took 8 min in 0.4.0, half an hour in 0.3)
Writes docs/benchmarks.md and docs/figures/pareto.png.

Scenes (all answers from physics.md closed forms, the direct steady state, or
a converged reference):

1. Cattaneo-Mindlin, Hertz (J1)          4. motor loop, a(P_T)
2. Jaeger-Ciavarella, rounded punch (J1) 5. Q and sigma together, moderate tension (Hertz)
3. Mindlin unloading, Hertz (J2)         6. in-phase dovetail steady state (SS1)
7. a long random (P, Q) history on Hertz against the exact method

Errors: stick-zone edges relative to the contact width, q(x) (L2 relative, on
the stored stations, where a closed form exists), dissipation per cycle
(relative, cyclic scenes). Time: wall time per marched step.
"""
from __future__ import annotations

import argparse
import dataclasses
import math
import platform
import sys
import textwrap
import time
from pathlib import Path

import numpy as np

import halfslip as hs

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _doc import write_section  # noqa: E402

#: this script's part of docs/benchmarks.md (the page's top; the other benchmarks write their sections below)
BEGIN, END = "<!-- accuracy: begin -->", "<!-- accuracy: end -->"

ROOT = Path(__file__).resolve().parents[1]
E, NU, F = 200e9, 0.3, 0.6
A = 4 * (1 - NU**2) / E
R = 50e-3
P0 = 1.0e5

HEAD = f"""
material: {{E: {E}, nu: {NU}}}
friction: {F}
"""


def scene(body: str, fields=("q",), points=401, skip=False) -> hs.Scene:
    text = HEAD + textwrap.dedent(body) + f"\noutput: {{fields: [{', '.join(fields)}], points: {points}}}\n" \
        + f"solver: {{skip_steady_cycles: {str(skip).lower()}}}\n"
    return hs.parse_scene(text)


def hertz(P):
    return math.sqrt(2 * A * R * P / math.pi)


def case_cattaneo():
    Q = 0.5 * F * P0
    sc = scene(f"""
        name: cattaneo-hertz
        geometry: {{kind: hertz, radius: {R}}}
        loads:
          - ramp: {{to: {{P: {P0}}}, duration: 1, steps: 4}}
          - ramp: {{to: {{Q: {Q}}}, duration: 1, steps: 20}}
        """)
    a, b = hertz(P0), hertz(P0 - Q / F)
    problem = hs.NormalProblem(sc.profile, A)

    def q_exact(x):
        return F * (problem.pressure(x, P0) - problem.pressure(x, P0 - Q / F))
    return sc, {"stick": (-b, b), "width": 2 * a, "q": q_exact}


def case_punch():
    Q = 0.5 * F * P0
    sc = scene(f"""
        name: jaeger-ciavarella-punch
        geometry: {{kind: rounded_punch, flat_half_width: 0.2e-3, radius: 10e-3}}
        loads:
          - ramp: {{to: {{P: {P0}}}, duration: 1, steps: 4}}
          - ramp: {{to: {{Q: {Q}}}, duration: 1, steps: 20}}
        """)
    problem = hs.NormalProblem(sc.profile, A)
    a, b = float(problem.half_width(P0)), float(problem.half_width(P0 - Q / F))

    def q_exact(x):
        return F * (problem.pressure(x, P0) - problem.pressure(x, P0 - Q / F))
    return sc, {"stick": (-b, b), "width": 2 * a, "q": q_exact}


def case_mindlin():
    Qmax, Q = 0.6 * F * P0, 0.0
    sc = scene(f"""
        name: mindlin-unloading
        geometry: {{kind: hertz, radius: {R}}}
        loads:
          - ramp: {{to: {{P: {P0}}}, duration: 1, steps: 4}}
          - ramp: {{to: {{Q: {Qmax}}}, duration: 1, steps: 20}}
          - ramp: {{to: {{Q: {Q}}}, duration: 1, steps: 20}}
        """)
    problem = hs.NormalProblem(sc.profile, A)
    c = hertz(P0 - (Qmax - Q) / (2 * F))

    def q_exact(x):
        return (-F * problem.pressure(x, P0) + 2 * F * problem.pressure(x, P0 - (Qmax - Q) / (2 * F))
                - F * problem.pressure(x, P0 - Qmax / F))
    return sc, {"stick": (-c, c), "width": 2 * hertz(P0), "q": q_exact}


def case_motor(spc=200):
    Pa, Qa = 0.3 * P0, 0.3 * P0
    sc = scene(f"""
        name: motor-loop
        geometry: {{kind: hertz, radius: {R}}}
        loads:
          - ramp: {{to: {{P: {P0}, Q: {Qa}}}, duration: 1, steps: 10}}
          - cycles:
              count: 3
              period: 1
              steps_per_cycle: {spc}
              P: {{amplitude: {Pa}}}
              Q: {{mean: 0.0, amplitude: {Qa}, phase: 90}}
        """)
    P_T = P0 - math.sqrt(Qa**2 + (F * Pa) ** 2) / F
    d = hertz(P_T)
    return sc, {"permanent": (-d, d), "width": 2 * hertz(P0 - Pa)}


def case_tension():
    Q, sigma = 0.4 * F * P0, 2.0e7
    sc = scene(f"""
        name: shear-and-tension
        geometry: {{kind: hertz, radius: {R}}}
        loads:
          - ramp: {{to: {{P: {P0}}}, duration: 1, steps: 4}}
          - ramp: {{to: {{Q: {Q}, sigma: {sigma}}}, duration: 1, steps: 20}}
        """)
    a = hertz(P0)
    b = a * math.sqrt(1 - Q / (F * P0))
    e = -A * R * sigma / (4 * F)
    return sc, {"stick": (e - b, e + b), "width": 2 * a}


def case_dovetail(spc=None):
    sc = hs.load_scene(ROOT / "examples" / "dovetail.yaml")
    if spc is not None:
        sc = hs.parse_scene(sc.text.replace("steps_per_cycle: 100", f"steps_per_cycle: {spc}"), path=sc.path)
    sc = dataclasses.replace(sc, output=dataclasses.replace(sc.output, fields=(), points=401),
                             solver=dataclasses.replace(sc.solver, skip_steady_cycles=False))
    h = sc.history
    seg = h.segments[-1]
    short = hs.LoadHistory.from_arrays(h.t[: seg.start + 3 * seg.steps_per_cycle + 1],
                                       h.P[: seg.start + 3 * seg.steps_per_cycle + 1],
                                       h.Q[: seg.start + 3 * seg.steps_per_cycle + 1],
                                       h.M[: seg.start + 3 * seg.steps_per_cycle + 1],
                                       h.sigma[: seg.start + 3 * seg.steps_per_cycle + 1])
    steady = hs.steady_state(sc, per_cycle=False)
    sc = dataclasses.replace(sc, history=short, name="dovetail-steady")
    solution = hs.NormalProblem(sc.profile, A).solve(float(np.min(h.P[seg.start:])), 0.0)
    return sc, {"permanent": (float(steady.permanent_stick_left), float(steady.permanent_stick_right)),
                "width": 2 * solution.half_width, "steps_per_cycle": seg.steps_per_cycle}


def case_random(n=2000, seed=3):
    rng = np.random.default_rng(seed)
    t = np.arange(n + 1, dtype=float)
    P = P0 * (1 + 0.3 * np.cumsum(rng.standard_normal(n + 1)) / math.sqrt(n))
    P = np.clip(P, 0.3 * P0, 1.7 * P0)
    Q = 0.6 * F * P * np.sin(np.cumsum(rng.uniform(0, 0.3, n + 1)))
    P[0] = Q[0] = 0.0
    base = scene(f"""
        name: random-history
        geometry: {{kind: hertz, radius: {R}}}
        loads:
          - hold: {{duration: 1}}
        """)
    sc = dataclasses.replace(base, history=hs.LoadHistory.from_arrays(t, P, Q))
    return sc, {"reference": "exact", "width": 2 * hertz(P0)}


CASES = {
    "Cattaneo-Mindlin, Hertz": case_cattaneo,
    "Jaeger-Ciavarella, rounded punch": case_punch,
    "Mindlin unloading, Hertz": case_mindlin,
    "motor loop, a(P_T)": case_motor,
    "Q and sigma, moderate tension": case_tension,
    "in-phase dovetail steady state (SS1)": case_dovetail,
    "long random history": case_random,
}


def last_cycle(ds, sc, steps_per_cycle=None):
    seg = sc.history.segments[-1]
    spc = steps_per_cycle or seg.steps_per_cycle
    t0 = sc.history.t[seg.stop - spc]
    return ds.sel(t=slice(t0, None))


def measure(sc, known, method, nodes, reference=None) -> dict:
    """Run once; errors against the known answer (or the reference run)."""
    start = time.perf_counter()
    ds = hs.simulate(sc, method=method, nodes=nodes)
    wall = time.perf_counter() - start
    width = known["width"]
    out = {"time": wall / ds.attrs["count_steps"], "edge": float("nan"), "q": float("nan"), "D": float("nan")}
    if "stick" in known:
        left, right = known["stick"]
        out["edge"] = max(abs(float(ds.stick_left[-1]) - left), abs(float(ds.stick_right[-1]) - right)) / width
    if "permanent" in known:
        cyc = last_cycle(ds, sc, known.get("steps_per_cycle"))
        left, right = known["permanent"]
        out["edge"] = max(abs(float(cyc.stick_left.max()) - left), abs(float(cyc.stick_right.min()) - right)) / width
        out["D"] = float(cyc.dissipation[-1] - cyc.dissipation[0])
    if "q" in known and "q" in ds:
        x = ds.x.values
        q_ref = known["q"](x)
        out["q"] = float(np.sqrt(np.trapezoid((ds.q[-1].values - q_ref) ** 2, x) / np.trapezoid(q_ref**2, x)))
    if reference is not None:
        deviation = np.abs(np.concatenate([ds.stick_left.values - reference.stick_left.values,
                                           ds.stick_right.values - reference.stick_right.values])) / width
        out["edge"] = float(np.nanmax(deviation))
        out["note"] = (f"edge error over all steps: median {np.nanmedian(deviation):.1e}, "
                       f"95th percentile {np.nanpercentile(deviation, 95):.1e}; regime differs at "
                       f"{int(np.count_nonzero(ds.regime.values != reference.regime.values))} of {ds.sizes['t']} steps")
        out["D"] = float(ds.final_dissipation)
        if "q" in ds and "q" in reference:
            diff = ds.q.values - reference.q.values
            out["q"] = float(np.sqrt(np.sum(diff**2) / np.sum(reference.q.values ** 2)))
            # is the worst edge a different answer, or an ill-determined edge under the same q?
            worst = int(np.nanargmax(deviation)) % ds.sizes["t"]
            q_ref = reference.q.values[worst]
            q_err = float(np.sqrt(np.sum(diff[worst] ** 2) / max(np.sum(q_ref**2), 1e-300)))
            out["note"] += f"; at the worst step (t = {float(ds.t[worst]):g}) q differs by {q_err:.1e} (L2)"
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="fewer resolutions (a smoke run)")
    parser.add_argument("--replot", action="store_true", help="redraw the page and plot from docs/benchmarks.md")
    args = parser.parse_args()
    if args.replot:
        write(*read_tables(ROOT / "docs" / "benchmarks.md"))
        return
    resolutions = [64, 128, 256] if args.quick else [64, 128, 256, 512, 1024]
    # load every compiled kernel once before anything is timed (numba loads them from its cache on the first
    # call, or compiles them: that made the first general run's time per step several times its own)
    for case in ("Cattaneo-Mindlin, Hertz", "Jaeger-Ciavarella, rounded punch"):
        for method in ("exact", "general"):
            hs.simulate(CASES[case]()[0], method=method, nodes=64)
    rows = []
    for name, make in CASES.items():
        sc, known = make()
        reference = hs.simulate(sc, method="exact") if known.get("reference") == "exact" else None
        runs = [("exact", None)] if hs.simulator.exact_method_reason(sc) is None else []
        runs += [("general", n) for n in resolutions]
        results = []
        for method, nodes in runs:
            try:
                m = measure(sc, known, method, nodes, reference)
                m.setdefault("note", "")
            except Exception as error:  # a benchmark reports failures, it does not hide them
                m = {"time": float("nan"), "edge": float("nan"), "q": float("nan"), "D": float("nan"),
                     "note": f"failed: {type(error).__name__}: {error}"[:120]}
            results.append((method, nodes, m))
        # dissipation: against the exact method (or its reference run), else the finest general run
        D_ref = float(reference.final_dissipation) if reference is not None else next(
            (m["D"] for method, _, m in results if method == "exact"), results[-1][2]["D"])
        for method, nodes, m in results:
            finest = method == "general" and nodes == resolutions[-1] and not any(r[0] == "exact" for r in results)
            m["D_err"] = float("nan") if finest and reference is None else abs(m["D"] - D_ref) / abs(D_ref)
            rows.append((name, method, nodes, m))
        print(name, "done", flush=True)
    steps = step_size_study([25, 50, 100] if args.quick else [25, 50, 100, 200, 400])
    steps += substep_study([1, 2, 4] if args.quick else [1, 2, 4, 8])
    write(rows, steps)


def substep_study(factors, spc=25, nodes=256) -> list:
    """Would a step-size controller help? The same polygonal path, each step cut into k equal parts.

    The exact method is exact on the polygon, so the general solver's own
    time-discretisation error is what remains: dissipation per cycle of the
    motor loop against the exact method on the same path.
    """
    sc, known = case_motor(spc=spc)
    h = sc.history
    exact = hs.simulate(sc, method="exact")
    t0, t1 = h.t[-1] - 1.0, h.t[-1]
    D_ref = float(np.interp(t1, exact.t, exact.dissipation) - np.interp(t0, exact.t, exact.dissipation))
    def row(scene, label, steps):
        began = time.perf_counter()
        ds = hs.simulate(scene, method="general", nodes=nodes)
        wall = time.perf_counter() - began
        D = float(np.interp(t1, ds.t, ds.dissipation) - np.interp(t0, ds.t, ds.dissipation))
        cyc = ds.sel(t=slice(t0, t1))
        edge = max(abs(float(cyc.stick_left.max()) - known["permanent"][0]),
                   abs(float(cyc.stick_right.min()) - known["permanent"][1])) / known["width"]
        print(label, "done", flush=True)
        # time per step of the history run (the control's sub-steps are inside its steps)
        return (label, steps, nodes, {"time": wall / ds.attrs["count_steps"], "edge": edge,
                                      "D_err": abs(D - D_ref) / D_ref})

    out = []
    for k in factors:
        t = np.interp(np.arange((h.t.size - 1) * k + 1) / k, np.arange(h.t.size), h.t)
        fine = dataclasses.replace(sc, history=hs.LoadHistory.from_arrays(t, np.interp(t, h.t, h.P),
                                                                          np.interp(t, h.t, h.Q)))
        out.append(row(fine, f"motor loop, {spc} steps per cycle, each cut in {k}", spc * k))
    for travel in (0.01, 0.005):  # the step-size control: sub-steps only where the stick edges travel
        controlled = dataclasses.replace(sc, solver=dataclasses.replace(sc.solver, edge_travel=travel))
        out.append(row(controlled, f"motor loop, {spc} steps per cycle, edge_travel {travel}", spc))
    return out


def step_size_study(spcs, nodes=256) -> list:
    """Error of the general solver against steps per cycle at fixed nodes (non-proportional paths).

    The motor loop (P and Q 90 degrees apart) and the in-phase dovetail (straight
    path, but sigma and M move the slip zones): permanent stick zone against its
    known answer, dissipation per cycle against the finest step.
    """
    out = []
    for name, make in (("motor loop, a(P_T)", case_motor), ("in-phase dovetail steady state (SS1)", case_dovetail)):
        results = []
        for spc in spcs:
            sc, known = make(spc=spc)
            m = measure(sc, known, "general", nodes)
            results.append((spc, m))
            print(name, spc, "steps per cycle done", flush=True)
        D_ref = results[-1][1]["D"]
        for spc, m in results:
            m["D_err"] = abs(m["D"] - D_ref) / abs(D_ref) if spc != spcs[-1] else float("nan")
            out.append((name, spc, nodes, m))
    return out


FLOOR = 1e-13  # an edge error at or below this fraction of the width is rounding (marked, not plotted)


def read_tables(path):
    """The rows of a page this script wrote (to redraw it without rerunning)."""
    rows, steps = [], []
    text = Path(path).read_text()
    # its own part only: the other benchmarks' tables follow it (between their markers)
    stop = text.find(END) if BEGIN in text else text.find("\n## The general solver on random histories")
    for line in (text[:stop] if stop >= 0 else text).splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if not line.startswith("| ") or cells[0] == "scene" or set(cells[0]) <= {"-"}:
            continue
        if len(cells) == 8:
            name, method, nodes, t, edge, q, D, note = cells
            rows.append((name, method, None if nodes == "-" else int(nodes),
                         {"time": float(t) / 1e3, "edge": float(edge), "q": float(q), "D_err": float(D), "note": note}))
        elif len(cells) == 6:
            name, spc, nodes, t, edge, D = cells
            steps.append((name, int(spc), int(nodes), {"time": float(t) / 1e3, "edge": float(edge), "D_err": float(D)}))
    return rows, steps


def write(rows, steps=()):
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure
    from matplotlib.ticker import LogLocator, NullFormatter

    scenes = list(dict.fromkeys(name for name, *_ in rows))
    ncol = 3
    nrow = -(-len(scenes) // ncol)
    fig = Figure(figsize=(4.4 * ncol, 3.8 * nrow), layout="constrained")
    axes = fig.subplots(nrow, ncol, squeeze=False).ravel()
    for ax, name in zip(axes, scenes):
        rounding = []  # times of the runs whose error equals rounding: no point on a log axis
        for method, style in (("general", "o-"), ("exact", "s")):
            pts = [(m["time"] * 1e6, m["edge"], nodes) for sc_, meth, nodes, m in rows if sc_ == name and meth == method]
            pts = [(t, e, n) for t, e, n in pts if math.isfinite(t) and math.isfinite(e)]
            rounding += [t for t, e, _ in pts if e <= FLOOR]
            pts = [p for p in pts if p[1] > FLOOR]
            if not pts:
                continue
            x, y, labels = zip(*sorted(pts, key=lambda p: (p[2] or 0, p[0])))  # along the resolutions
            ax.loglog(x, y, style, label=method)
            if method == "general":
                for xi, yi, n in zip(x, y, labels):
                    ax.annotate(str(n), (xi, yi), fontsize=7, xytext=(3, 3), textcoords="offset points")
        ax.set_xscale("log")
        if ax.lines:
            ax.set_yscale("log")
            ax.yaxis.set_major_locator(LogLocator(numticks=5))
            ax.yaxis.set_minor_formatter(NullFormatter())
            ax.set_ylabel("stick-edge error / width", fontsize=8)
            ax.legend(fontsize=7)
        else:
            ax.set_yticks([])
            ax.text(0.5, 0.6, f"every error at rounding level\n(< {FLOOR:.0e} of the width)", transform=ax.transAxes,
                    ha="center", va="center", fontsize=8)
        if rounding:  # where they are on the time axis
            ax.plot(rounding, [0.04] * len(rounding), "v", color="0.4", ms=5, transform=ax.get_xaxis_transform(),
                    label=None)
            low, high = min(rounding), max(rounding)
            xl = ax.get_xlim() if len(ax.lines) > 1 else (low, high)
            ax.set_xlim(min(xl[0], low) / 1.5, max(xl[1], high) * 1.5)
        ax.xaxis.set_major_locator(LogLocator(numticks=5))  # decades only: labels never overlap
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.tick_params(labelsize=7)
        ax.set_title(name, fontsize=9)
        ax.grid(True, which="major", alpha=0.3)
        ax.set_xlabel("time per step [µs]  (▼ error at rounding level)", fontsize=8)
    for ax in axes[len(scenes):]:
        ax.set_visible(False)
    fig.suptitle("halfslip: error against time per step (general solver labelled by nodes)")
    (ROOT / "docs" / "figures").mkdir(parents=True, exist_ok=True)
    fig.savefig(ROOT / "docs" / "figures" / "pareto.png", dpi=100)
    lines = [
        "# Benchmarks: run time against error",
        "",
        "*Generated by `python benchmarks/bench_accuracy.py`; edit the script, not this page.*",
        "",
        f"Machine: {platform.platform()}, {platform.machine()}, Python {platform.python_version()}, "
        f"{__import__('os').cpu_count()} cores (shared; times are indicative, ratios within one run are what count).",
        "",
        "Errors: stick-zone edges relative to the contact width (for cyclic scenes, the permanent stick zone of the",
        "last marched cycle; for the random history, the largest deviation over all steps from the exact method);",
        "q(x) L2-relative on the stored stations; dissipation per cycle relative to the exact method, or to the",
        "finest general run when the exact method does not apply (random history: total dissipation).",
        "An edge error below 1e-13 of the width is rounding: printed as it is, marked ▼ on the time axis of its panel.",
        "",
        "| scene | method | nodes | time/step [ms] | edge error | q error (L2) | dissipation error | note |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for name, method, nodes, m in rows:
        lines.append(f"| {name} | {method} | {nodes or '-'} | {1e3 * m['time']:.3g} | {m['edge']:.2e} | "
                     f"{m['q']:.2e} | {m['D_err']:.2e} | {m['note']} |")
    lines += ["", "![error against time per step](figures/pareto.png)", ""]
    if steps:
        lines += [
            "## Step size (general solver, non-proportional and moving-zone paths)",
            "",
            "Same scenes at a fixed resolution, steps per cycle varied: the permanent stick zone against its",
            "known answer, the dissipation per cycle against the finest step. The last rows keep the motor",
            "loop's 25-step polygon and cut each step into k equal sub-steps (what a step-size controller",
            "would do): their dissipation is compared with the exact method on the same polygon, so only the",
            "general solver's own time-discretisation error is left. The edge_travel rows set the step-size",
            "control (sub-steps where a contact edge travels more than that fraction of the width, or a stick",
            "edge more than 0.02; time per step of the 25-step history).",
            "",
            "| scene | steps per cycle | nodes | time/step [ms] | edge error | dissipation error |",
            "|---|---|---|---|---|---|",
        ]
        for name, spc, nodes, m in steps:
            lines.append(f"| {name} | {spc} | {nodes} | {1e3 * m['time']:.3g} | {m['edge']:.2e} | {m['D_err']:.2e} |")
        lines.append("")
    text = "\n".join(lines)
    print(text)
    text = f"{BEGIN}\n{text.rstrip()}\n{END}"
    doc = ROOT / "docs" / "benchmarks.md"
    old = doc.read_text() if doc.exists() else ""
    if BEGIN in old:
        write_section(doc, BEGIN, END, text, "")
        return
    # the page as this script wrote it until 0.4.0, whole: keep the sections the other benchmarks write into
    # it (random histories, examples, solve routes), which follow its own
    rest = old.find("\n## The general solver on random histories")
    doc.write_text(text + "\n" + (old[rest:] if rest >= 0 else ""))


if __name__ == "__main__":
    main()
