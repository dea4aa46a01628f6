"""Benchmark of parameter sweeps: cases per second by backend, and the per-case overhead.

Run:  python benchmarks/bench_sweep.py [--grid 40x25]
Rewrites the benchmark section of docs/sweeps.md (between its
``<!-- bench:start -->`` and ``<!-- bench:end -->`` markers).

In one run, on examples/hertz_pad.yaml over friction x Q amplitude:

1. the full cases (direct steady state SS2 plus the two marched cycles for
   dissipation and slip amplitude, ~0.2 s each): in-process (1 worker), 2 local
   worker processes, and a dask LocalCluster of 2 single-threaded worker
   processes reached by address (as ``--scheduler`` does);
2. the same grid with ``per_cycle: false`` (the closed form alone, ~5 ms of
   parsing and solving per case), where what a backend adds per case shows:
   overhead per case = wall time x workers / cases - the in-process time per case.
"""
from __future__ import annotations

import argparse
import os
import platform
import re
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import xarray as xr

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "sweeps.md"
START, END = "<!-- bench:start -->", "<!-- bench:end -->"
SUMMARY = ["permanent_stick_left", "permanent_stick_right", "peak_slip_amplitude", "dissipation_per_cycle",
           "regime", "status", "method", "done"]


def sweep_file(folder: Path, n_friction: int, n_q: int, per_cycle: bool) -> Path:
    path = folder / f"bench_{n_friction}x{n_q}_{'full' if per_cycle else 'direct'}.yaml"
    path.write_text(
        f"scene: {ROOT / 'examples' / 'hertz_pad.yaml'}\n"
        "vary:\n"
        f"  friction: {{linspace: [0.3, 0.9, {n_friction}]}}\n"
        f"  loads[1].cycles.Q.amplitude: {{linspace: [5.0e3, 3.0e4, {n_q}]}}\n"
        f"per_cycle: {str(per_cycle).lower()}\n"
    )
    return path


def timed(run):
    start = time.perf_counter()
    result = run()
    return time.perf_counter() - start, result


def load_average() -> float:
    return os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")


def machine(load_before: float) -> str:
    import dask
    import distributed

    cpu = f"{platform.machine()} {platform.processor() or ''}".rstrip()
    return (f"{platform.platform()}, {cpu}, {os.cpu_count()} CPUs (1-minute load average {load_before:.1f} "
            f"before and {load_average():.1f} after the timed runs: other work on the machine shares the CPUs); "
            f"Python {platform.python_version()}, numpy {np.__version__}, xarray {xr.__version__}, "
            f"dask {dask.__version__}, distributed {distributed.__version__}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--grid", default="40x25", help="friction x Q-amplitude values (default 40x25 = 1000 cases)")
    args = parser.parse_args()
    n_friction, n_q = (int(v) for v in args.grid.lower().split("x"))
    n = n_friction * n_q

    import halfslip as hs
    from distributed import LocalCluster

    rows, identical = [], True
    load_before = load_average()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        hs.steady_state(hs.load_scene(ROOT / "examples" / "hertz_pad.yaml"))  # warm this process (imports, kernels)
        small = sweep_file(folder, 2, 2, True)
        fork_start, _ = timed(lambda: hs.sweep(small, workers=2, progress=False))
        start = time.perf_counter()
        cluster = LocalCluster(n_workers=2, processes=True, threads_per_worker=1, dashboard_address=None)
        cluster_start = time.perf_counter() - start
        try:
            dask_first, _ = timed(lambda: hs.sweep(small, scheduler=cluster.scheduler_address, progress=False))
            for per_cycle in (True, False):
                path = sweep_file(folder, n_friction, n_q, per_cycle)
                label = "full (SS2 + 2 marched cycles)" if per_cycle else "direct only (per_cycle: false)"
                print(f"{label}: {n} cases", file=sys.stderr)
                t1, serial = timed(lambda: hs.sweep(path, workers=1, progress=False))
                print(f"  in-process {t1:.1f} s", file=sys.stderr)
                t2, local = timed(lambda: hs.sweep(path, workers=2, progress=False))
                print(f"  2 processes {t2:.1f} s", file=sys.stderr)
                td, dask = timed(lambda: hs.sweep(path, scheduler=cluster.scheduler_address, progress=False))
                print(f"  dask, 2 workers {td:.1f} s", file=sys.stderr)
                for other in (local, dask):
                    try:
                        xr.testing.assert_identical(other[SUMMARY].drop_attrs(), serial[SUMMARY].drop_attrs())
                    except AssertionError:
                        identical = False
                ok = int((serial["status"] == "ok").sum())
                regimes = {int(r): int((serial["regime"] == r).sum()) for r in (1, 2, 3)}
                results = []
                for name, workers, wall, ds in (("in-process (1 worker)", 1, t1, serial),
                                                ("2 local processes", 2, t2, local),
                                                ("dask LocalCluster, 2 workers", 2, td, dask)):
                    run = float(ds["run_time"].mean())  # measured around each case, where it ran
                    results.append((name, workers, wall, run, wall * workers / n - run))
                rows.append((label, n, ok, regimes, results))
        finally:
            cluster.close()

    lines = [
        START,
        "## Benchmark",
        "",
        f"Measured by `python benchmarks/bench_sweep.py --grid {args.grid}` on {machine(load_before)}.",
        "",
        f"{n} cases of examples/hertz_pad.yaml: friction linspace(0.3, 0.9, {n_friction}) x "
        f"Q amplitude linspace(5e3, 3e4, {n_q}) N/m. Wall time of `hs.sweep` (parsing and checking the "
        "sweep, starting the local worker pool, running, no output file). One-time costs, paid before the "
        f"timed runs: the first local pool of a process starts the forkserver, which imports halfslip once for "
        f"all later workers (a 4-case sweep with it took {fork_start:.2f} s); the dask LocalCluster (2 worker "
        f"processes, 1 thread each) started in {cluster_start:.2f} s and its first 4-case sweep took "
        f"{dask_first:.2f} s (workers importing halfslip); it is then reached by address as `--scheduler` does. "
        "Case time = mean `run_time` (measured around each case where it ran: building and checking its "
        "scene, solving); overhead per case = wall time x workers / cases - case time: the worker-seconds "
        "a backend adds to each case besides running it (transport, scheduling, idle workers, the driver's "
        "bookkeeping). Case times above the in-process one show CPU contention (2 workers on 2 CPUs, plus "
        "the driver, dask's scheduler and nannies, and any other load).",
        "",
    ]
    for label, n_cases, ok, regimes, results in rows:
        lines += [
            f"### {label}",
            "",
            f"{ok} of {n_cases} cases ok; regimes: {regimes[1]} full stick, {regimes[2]} partial slip, "
            f"{regimes[3]} gross sliding.",
            "",
            "| backend | workers | wall [s] | cases/s | case time [ms] | overhead per case [ms] |",
            "|---|---|---|---|---|---|",
        ]
        for name, workers, wall, run, overhead in results:
            lines.append(f"| {name} | {workers} | {wall:.2f} | {n_cases / wall:.1f} | {1e3 * run:.2f} | "
                         f"{1e3 * overhead:.2f} |")
        dask_vs_local = results[2][4] - results[1][4]
        lines += ["", f"Per-case overhead of the dask path versus local processes: {1e3 * dask_vs_local:+.2f} ms.",
                  ""]
    lines += [
        "All three backends gave identical summaries (xarray `assert_identical`, run_time excluded): "
        + ("yes." if identical else "**NO**."),
        END,
    ]
    section = "\n".join(lines)
    text = DOC.read_text() if DOC.exists() else f"# Parameter sweeps\n\n{START}\n{END}\n"
    if START not in text:
        text = text.rstrip("\n") + f"\n\n{START}\n{END}\n"
    text = re.sub(re.escape(START) + ".*?" + re.escape(END), lambda _: section, text, flags=re.S)
    DOC.write_text(text)
    print(section)


if __name__ == "__main__":
    main()
