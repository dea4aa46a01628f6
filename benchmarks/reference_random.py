"""Self-converged IC reference on the random histories of issue 14, and the current general solver against it.

    python benchmarks/reference_random.py                       # 2 seeds per geometry, N = 1000..16000,
                                                                # the finest cut in 4 sub-steps a step
    python benchmarks/reference_random.py --seeds 1 --n 1000 2000 --no-general
    python benchmarks/reference_random.py --report-only         # rebuild npz + docs from the cached runs

Each run (geometry, seed, N) of benchmarks/baseline_ic.py is cached in
benchmarks/reference/runs/ (small .npz), so an interrupted session resumes
where it stopped. All N of one history share one grid extent (nested grids).

Outputs:
* benchmarks/reference/random_reference.npz: per history (key prefix
  ``{geometry}_{seed}_``) the loads, the finest run's contact and stick
  edges, stick-interval counts and cumulative dissipation per step, and the
  estimated error of the reference per step (edges) and per history
  (dissipation); scalars ``order_edges``, ``order_dissipation``, ``n_levels``.
* the block between the markers in docs/baseline_ic.md.

Error of the reference: with d_N = |x_N - x_2N| (stick edges / contact width,
per step and side) the observed order is p = log2(median d_N / median d_2N)
over the last two pairs; the finest run's error is estimated per step as
d / (2^p - 1) (Richardson), from the difference of the two finest runs.
Dissipation: the same on the final cumulative value (signed), the Richardson
value being the extrapolated estimate.

With ``--split K`` the reference is the finest N with every step cut into K
equal straight sub-steps (the single-increment runs take each history step as
one increment, split only at element arrivals, and on the punch's seed 1 that
is off by up to 1e-4 of the width at the 95th percentile): its error per step
is the larger of the space estimate above (from the single-increment levels)
and |x_K - x_1| / (K - 1) in time; its dissipation is extrapolated in space
by the single-increment levels' difference.
"""
from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # shared 2-core machine: threaded BLAS spins (10-100x slower)

import argparse
import math
import platform
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))

from baseline_ic import history_extent, run_history  # noqa: E402
from random_histories import random_history  # noqa: E402

RUNS = HERE / "reference" / "runs"
OUT = HERE / "reference" / "random_reference.npz"
DOC = ROOT / "docs" / "baseline_ic.md"
BEGIN, END = "<!-- reference_random: begin -->", "<!-- reference_random: end -->"
KEEP = ("contact_left", "contact_right", "stick_left", "stick_right", "stick_left_cell", "stick_right_cell",
        "main_left", "main_right", "island", "late",
        "intervals", "dissipation", "shift", "time", "iterations", "substeps", "converged", "gross")


def run_file(geometry, seed, n, split=1):
    return RUNS / (f"{geometry}_{seed}_{n}.npz" if split == 1 else f"{geometry}_{seed}_{n}_t{split}.npz")


def baseline_run(geometry, seed, n, split=1):
    path = run_file(geometry, seed, n, split)
    if path.exists():
        return dict(np.load(path))
    info = {}
    _, t, P, Q, M, S = random_history(seed, geometry, info=info)
    extent = history_extent(info["problem"], P, M)
    started = time.perf_counter()

    def progress(k, steps, rep):
        if (k + 1) % 28 == 0:
            print(f"    {geometry} seed {seed} N {n}: step {k + 1}/{steps}, {time.perf_counter() - started:.0f} s",
                  flush=True)

    out = run_history(info["problem"], info["friction"], n, P, Q, M, S, extent=extent, progress=progress,
                      time_split=split)
    data = {k: np.asarray(out[k]) for k in KEEP}
    data.update(t=t, P=P, Q=Q, M=M, sigma=S, extent=np.array(extent), wall=np.array(time.perf_counter() - started),
                messages=np.array(out["messages"], dtype=str))
    RUNS.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(path, **data)
    print(f"  {geometry} seed {seed} N {n} time split {split}: {data['wall']:.0f} s, {1e3 * data['wall'] / len(t[1:]):.0f} ms/step, "
          f"not converged {int((~data['converged']).sum())}, split steps {int((data['intervals'] > 1).sum())}",
          flush=True)
    return data


def general_run(geometry, seed):
    """The package's general solver (default nodes) on one history; cached like the baseline runs."""
    path = RUNS / f"{geometry}_{seed}_general.npz"
    if path.exists():
        return dict(np.load(path))
    import halfslip as hs

    scene, t, P, Q, M, S = random_history(seed, geometry)
    started = time.perf_counter()
    ds = hs.simulate(scene)
    wall = time.perf_counter() - started
    messages = ds.attrs.get("messages", [])
    if isinstance(messages, str):
        messages = [messages] if messages else []
    messages = [str(m) for m in np.atleast_1d(messages)]
    # stored steps: every step (output.every = 1); the first stored point may be t = 0
    times = ds["t"].values
    sel = np.searchsorted(times, t[1:])
    take = lambda name: ds[name].values[sel].astype(float)  # noqa: E731
    data = dict(t=t, contact_left=take("contact_left"), contact_right=take("contact_right"),
                stick_left=take("stick_left"), stick_right=take("stick_right"), dissipation=take("dissipation"),
                regime=ds["regime"].values[sel], wall=np.array(wall), messages=np.array(messages, dtype=str),
                nodes=np.array(int(scene.solver.nodes)), method=np.array(str(ds.attrs.get("method"))))
    RUNS.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(path, **data)
    print(f"  general solver {geometry} seed {seed}: {wall:.0f} s, {len(messages)} messages", flush=True)
    return data


# -- comparison ------------------------------------------------------------------------------------
def edge_diffs(a, b, width, sides=("stick_left", "stick_right"), same_count=False):
    """|a - b| / width for both edges at the steps where both have a stick zone (pooled); ``same_count``:
    only steps where both runs have the same number of stick intervals."""
    out = []
    for side in sides:
        x, y = a[side], b[side]
        ok = np.isfinite(x) & np.isfinite(y)
        if same_count:
            ok &= a["intervals"] == b["intervals"]
        out.append(np.abs(x[ok] - y[ok]) / width[ok])
    return np.concatenate(out)


MAIN = ("main_left", "main_right")


def stats(v):
    if v.size == 0:
        return (math.nan,) * 3
    return float(np.median(v)), float(np.percentile(v, 95)), float(np.max(v))


def nan_mismatch(a, b):
    """Steps where one has a stick zone and the other none."""
    return int(np.sum(np.isfinite(a["stick_left"]) != np.isfinite(b["stick_left"])))


def machine():
    try:
        lscpu = subprocess.run(["lscpu"], capture_output=True, text=True, check=True).stdout.splitlines()[:10]
    except (OSError, subprocess.CalledProcessError):
        lscpu = [platform.processor()]
    import scipy

    return lscpu, (f"Python {platform.python_version()}, numpy {np.__version__}, scipy {scipy.__version__}, "
                   f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}")


def report(geometries, seeds, ns, general, command, time_split=1):
    hist = {}
    for g in geometries:
        for s in range(seeds):
            runs = {n: dict(np.load(run_file(g, s, n))) for n in ns if run_file(g, s, n).exists()}
            if runs:
                hist[(g, s)] = runs
    if not hist:
        print("no runs cached")
        return
    levels = sorted(set.intersection(*(set(r) for r in hist.values())))
    fine = levels[-1]
    lines = [BEGIN, "", f"Measured by `{command}` on {time.strftime('%Y-%m-%d')}.", ""]
    lscpu, versions = machine()
    lines += ["Machine (`lscpu | head`):", "", "```", *lscpu, "```", "", versions + ".", ""]
    lines += [f"Histories: {', '.join(f'{g} seed {s}' for g, s in sorted(hist))} "
              f"({len(next(iter(hist.values()))[fine]['t']) - 1} steps each); levels N = {levels}.", ""]
    # convergence per geometry
    order_rows = {}
    npz = {}
    for g in geometries:
        keys = [k for k in sorted(hist) if k[0] == g]
        if not keys:
            continue
        lines += [f"**{g}** (errors against N = {fine}, pooled over seeds and both stick edges; "
                  "edges relative to the contact width)", "",
                  "| N | ms / step | outermost edges: median | 95th | max | max, steps with equal interval "
                  "counts | widest stick interval's edges: median / 95th / max | steps whose interval count "
                  "differs | dissipation error (final, rel.) | steps with split stick zones | not converged |",
                  "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
        for n in levels:
            ms = np.mean([1e3 * float(hist[k][n]["wall"]) / (len(hist[k][n]["t"]) - 1) for k in keys])
            split = sum(int((hist[k][n]["intervals"] > 1).sum()) for k in keys)
            total = sum(len(hist[k][n]["intervals"]) for k in keys)
            nc = sum(int((~hist[k][n]["converged"].astype(bool)).sum()) for k in keys)
            if n == fine:
                lines.append(f"| {n} | {ms:.0f} | – | – | – | – | – | – | – | {split} / {total} | {nc} |")
                continue
            width = {k: hist[k][fine]["contact_right"] - hist[k][fine]["contact_left"] for k in keys}
            d = np.concatenate([edge_diffs(hist[k][n], hist[k][fine], width[k]) for k in keys])
            d_same = np.concatenate([edge_diffs(hist[k][n], hist[k][fine], width[k], same_count=True)
                                     for k in keys])
            d_main = np.concatenate([edge_diffs(hist[k][n], hist[k][fine], width[k], sides=MAIN) for k in keys])
            mism = sum(int(np.sum(hist[k][n]["intervals"] != hist[k][fine]["intervals"])) for k in keys)
            de = max(abs(hist[k][n]["dissipation"][-1] / hist[k][fine]["dissipation"][-1] - 1) for k in keys)
            m, p95, mx = stats(d)
            mm = stats(d_main)
            lines.append(f"| {n} | {ms:.0f} | {m:.1e} | {p95:.1e} | {mx:.1e} | {stats(d_same)[2]:.1e} | "
                         f"{mm[0]:.1e} / {mm[1]:.1e} / {mm[2]:.1e} | {mism} | {de:.1e} | {split} / {total} | {nc} |")
        # observed orders from successive differences
        meds, dis = [], []
        for lo, hi in zip(levels[:-1], levels[1:]):
            d = np.concatenate([edge_diffs(hist[k][lo], hist[k][hi],
                                           hist[k][hi]["contact_right"] - hist[k][hi]["contact_left"]) for k in keys])
            meds.append(stats(d))
            dis.append(np.median([abs(hist[k][lo]["dissipation"][-1] - hist[k][hi]["dissipation"][-1])
                                  / hist[k][hi]["dissipation"][-1] for k in keys]))
        lines += ["", "Successive differences |x_N - x_2N| (median / 95th / max of the stick edges; median over "
                  "seeds of the final dissipation, relative) and observed orders log2(d_N / d_2N):", "",
                  "| N vs 2N | edges median | 95th | max | order (median) | dissipation | order |",
                  "|---|---:|---:|---:|---:|---:|---:|"]
        for i, (lo, hi) in enumerate(zip(levels[:-1], levels[1:])):
            oe = f"{math.log2(meds[i - 1][0] / meds[i][0]):.2f}" if i else ""
            od = f"{math.log2(dis[i - 1] / dis[i]):.2f}" if i and dis[i] > 0 else ""
            lines.append(f"| {lo} vs {hi} | {meds[i][0]:.1e} | {meds[i][1]:.1e} | {meds[i][2]:.1e} | {oe} | "
                         f"{dis[i]:.1e} | {od} |")
        pe = math.log2(meds[-2][0] / meds[-1][0]) if len(meds) > 1 else 1.0
        pd = math.log2(dis[-2] / dis[-1]) if len(dis) > 1 and dis[-1] > 0 else 1.0
        pe_used, pd_used = max(min(pe, 3.0), 0.5), max(min(pd, 3.0), 0.5)
        fac_e, fac_d = 1 / (2**pe_used - 1), 1 / (2**pd_used - 1)
        est = stats(np.concatenate([edge_diffs(hist[k][levels[-2]], hist[k][fine],
                                               hist[k][fine]["contact_right"] - hist[k][fine]["contact_left"])
                                    for k in keys]) * fac_e)
        lines += ["", f"Estimated error of the reference (N = {fine}; Richardson with the observed order "
                  f"{pe:.2f} for edges, {pd:.2f} for dissipation, clipped to [0.5, 3]): stick edges median "
                  f"{est[0]:.1e}, 95th {est[1]:.1e}, max {est[2]:.1e} of the width; final dissipation "
                  f"{dis[-1] * fac_d:.1e} relative.", ""]
        order_rows[g] = (pe, pd)
        timed = time_split > 1 and all(run_file(k[0], k[1], fine, time_split).exists() for k in keys)
        if timed:
            lines += [f"The reference is N = {fine} with every step cut into {time_split} equal sub-steps (`baseline_run(..., "
                      f"split={time_split})`): its own error per step is the larger of the Richardson estimate in space above "
                      f"(from the single-increment runs) and the one in time, |x_{time_split} - x_1| / ({time_split} - 1) (first "
                      "order in time: at N = 2000, 4 against 16 sub-steps differ 6-18x less than 1 against 4 at the 95th "
                      "percentile, docs/baseline_ic.md).", ""]
        for k in keys:
            r1, r2 = hist[k][fine], hist[k][levels[-2]]
            r = dict(np.load(run_file(k[0], k[1], fine, time_split))) if timed else r1
            W = r["contact_right"] - r["contact_left"]
            pre = f"{k[0]}_{k[1]}_"
            for name in ("t", "P", "Q", "M", "sigma", "contact_left", "contact_right", "stick_left", "stick_right",
                         "intervals", "dissipation"):
                npz[pre + name] = r[name]
            for side in ("stick_left", "stick_right"):
                space = np.abs(r1[side] - r2[side]) / W * fac_e
                in_time = np.zeros_like(space)
                if timed:
                    in_time = np.abs(r[side] - r1[side]) / W / (time_split - 1)
                    in_time[np.isfinite(r[side]) != np.isfinite(r1[side])] = np.inf  # a stick zone in one only
                npz[pre + side + "_err"] = np.maximum(space, in_time)  # (NaN where the space estimate has none)
                npz[pre + side + "_err_time"] = in_time
            space = np.abs(r1["dissipation"] - r2["dissipation"]) * fac_d
            in_time = np.abs(r["dissipation"] - r1["dissipation"]) / (time_split - 1) if timed else 0.0 * space
            npz[pre + "dissipation_err"] = space + in_time
            # Richardson in space on the reference's own value (the space error taken as the single-increment runs')
            npz[pre + "dissipation_extrapolated"] = r["dissipation"] + (r1["dissipation"] - r2["dissipation"]) * fac_d
            npz[pre + "order_edges"] = np.array(pe)
            npz[pre + "order_dissipation"] = np.array(pd)
            npz[pre + "n"] = np.array(fine)
            npz[pre + "split"] = np.array(time_split if timed else 1)
    npz["levels"] = np.array(levels)
    OUT.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(OUT, **npz)
    lines += [f"Reference stored in `{OUT.relative_to(ROOT)}` ({OUT.stat().st_size / 1e3:.0f} kB).", ""]
    # the general solver
    if general:
        lines += ["**The package's current general solver** (`halfslip.simulate(scene)`, default nodes) against the "
                  f"reference (N = {fine}{f', {time_split} sub-steps a step' if time_split > 1 else ''}); one history per "
                  "geometry (the dataset has the outermost stick points, not the "
                  "widest interval's: bench_general_random.py compares those):", "",
                  "| history | nodes | ms / step (the whole simulate) | outermost edge error median | 95th | max | same, steps where "
                  "the reference has one stick interval: median / 95th / max | steps with a stick zone in one "
                  "only | dissipation error (final, rel.) | step messages | steps with 'kept the closest' (occurrences) |",
                  "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
        for g in geometries:
            path = RUNS / f"{g}_0_general.npz"
            if not path.exists() or (g, 0) not in hist:
                continue
            gen = dict(np.load(path))
            timed = time_split > 1 and run_file(g, 0, fine, time_split).exists()
            ref = dict(np.load(run_file(g, 0, fine, time_split))) if timed else hist[(g, 0)][fine]
            W = ref["contact_right"] - ref["contact_left"]
            m, p95, mx = stats(edge_diffs(gen, ref, W))
            m1 = stats(edge_diffs(dict(gen, intervals=np.ones_like(ref["intervals"])), ref, W, same_count=True))
            de = abs(gen["dissipation"][-1] / ref["dissipation"][-1] - 1)
            # the simulator keeps each distinct step message once, one line per step message
            msgs = [line for x in np.atleast_1d(gen["messages"]) for line in str(x).split("\n") if line]
            kept = sum("kept the closest" in x for x in msgs)
            kept_total = sum(x.count("kept the closest") for x in msgs)
            lines.append(f"| {g} seed 0 | {int(gen['nodes'])} | {1e3 * float(gen['wall']) / (len(gen['t']) - 1):.1f} | "
                         f"{m:.1e} | {p95:.1e} | {mx:.1e} | {m1[0]:.1e} / {m1[1]:.1e} / {m1[2]:.1e} | "
                         f"{nan_mismatch(gen, ref)} | {de:.1e} | {len(msgs)} | "
                         f"{kept} ({kept_total}) |")
        lines.append("")
    # time discretisation: equal sub-steps of every step at one N
    rows = []
    for g in geometries:
        for path in sorted(RUNS.glob(f"{g}_0_*_t*.npz")):
            n, split = path.stem.split("_")[2], int(path.stem.split("_t")[-1])
            a, b = dict(np.load(run_file(g, 0, int(n)))), dict(np.load(path))
            W = a["contact_right"] - a["contact_left"]
            d = stats(edge_diffs(b, a, W, same_count=True))
            dm = stats(edge_diffs(b, a, W, sides=MAIN))
            rows.append(f"| {g} seed 0 | {n} | {split} | {d[0]:.1e} / {d[1]:.1e} / {d[2]:.1e} | "
                        f"{dm[0]:.1e} / {dm[1]:.1e} / {dm[2]:.1e} | "
                        f"{int(np.sum(a['intervals'] != b['intervals']))} | "
                        f"{abs(b['dissipation'][-1] / a['dissipation'][-1] - 1):.1e} |")
    if rows:
        lines += ["**Time discretisation of the reference**: every step cut into k equal straight sub-steps "
                  "(`run_history(..., time_split=k)`), against k = 1 at the same N:", "",
                  "| history | N | k | outermost edges, equal interval counts: median / 95th / max | widest "
                  "interval's edges: median / 95th / max | steps whose interval count differs | final "
                  "dissipation (rel.) |", "|---|---:|---:|---:|---:|---:|---:|", *rows, ""]
    lines.append(END)
    block = "\n".join(lines)
    print(block)
    text = DOC.read_text() if DOC.exists() else f"# IC baseline\n\n{BEGIN}\n{END}\n"
    if BEGIN not in text:
        text += f"\n{BEGIN}\n{END}\n"
    text = re.sub(re.escape(BEGIN) + ".*?" + re.escape(END), lambda _: block, text, flags=re.S)
    DOC.write_text(text)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=2, help="seeds 0 .. SEEDS-1 per geometry")
    ap.add_argument("--n", type=int, nargs="+", default=[1000, 2000, 4000, 8000, 16000])
    ap.add_argument("--geometries", nargs="+", default=["hertz", "punch"])
    ap.add_argument("--no-general", action="store_true", help="skip the package's general solver")
    ap.add_argument("--report-only", action="store_true", help="use the cached runs only")
    ap.add_argument("--split", type=int, default=4,
                    help="the reference: the finest N with every step cut into SPLIT sub-steps (its runs are made too)")
    ap.add_argument("--time-check", type=int, nargs=2, metavar=("N", "K"),
                    help="also run seed 0 of each geometry at N with every step cut into K sub-steps")
    args = ap.parse_args(argv)
    command = "python benchmarks/reference_random.py " + " ".join(argv if argv is not None else sys.argv[1:])
    if not args.report_only:
        for n in sorted(args.n):
            for g in args.geometries:
                for s in range(args.seeds):
                    baseline_run(g, s, n)
        if args.split > 1:
            for g in args.geometries:
                for s in range(args.seeds):
                    baseline_run(g, s, max(args.n), split=args.split)
        if not args.no_general:
            for g in args.geometries:
                general_run(g, 0)
        if args.time_check:
            for g in args.geometries:
                baseline_run(g, 0, args.time_check[0])
                baseline_run(g, 0, args.time_check[0], split=args.time_check[1])
    report(args.geometries, args.seeds, sorted(args.n), not args.no_general, command.strip(), args.split)


if __name__ == "__main__":
    main()
