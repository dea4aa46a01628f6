"""Time per step of the general solver on the seeded random histories, this tree against a git revision in the
same run (the machines are shared and noisy: a ratio is only worth what was measured in one session).

    python benchmarks/bench_general_ab.py --against fd38b46            # 1024 nodes, with and without windows
    python benchmarks/bench_general_ab.py --against fd38b46 --nodes 512 1024 --repeat 3

Each (geometry, nodes, windows) runs both seeds of ``bench_general_random.run_solver`` (the stepping alone,
inside the heap freeze, the lattices set up before; best of two passes per history) in a fresh process per tree,
the trees alternating ``--repeat`` times; the table gives the median of the runs' ms per step, their ratio, and
the largest difference of the two trees' outermost stick edges (relative to the contact width) and final
dissipation, so that a speed-up is seen with what it changed. Writes the table between its markers in
docs/benchmarks.md.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _doc import machine, package_trees, write_section  # noqa: E402

DOC = HERE.parent / "docs" / "benchmarks.md"
BEGIN, END = "<!-- general_ab: begin -->", "<!-- general_ab: end -->"

#: What a worker runs: both seeds of one configuration, printed as JSON (ms per step; edges and dissipation).
_WORKER = """
import json, sys
sys.path.insert(0, sys.argv[1])
from bench_general_random import run_solver
geometry, nodes, windows = sys.argv[2], int(sys.argv[3]), sys.argv[4] == "on"
wall = steps = 0
edges, spent = [], []
for seed in (0, 1):
    out = run_solver(geometry, seed, nodes, 2, edge_windows=windows)
    wall += out["wall"]
    steps += out["steps"]
    width = out["contact_right"] - out["contact_left"]
    edges += [float(v) for v in (out["stick_left"] / width).tolist() + (out["stick_right"] / width).tolist()]
    spent.append(float(out["dissipation"][-1]))
print(json.dumps({"ms": 1e3 * wall / steps, "edges": edges, "dissipation": spent}))
"""


def _run(src: Path, geometry: str, nodes: int, windows: str) -> dict:
    env = dict(os.environ, PYTHONPATH=str(src), OPENBLAS_NUM_THREADS="1")
    out = subprocess.run([sys.executable, "-c", _WORKER, str(HERE), geometry, str(nodes), windows], env=env,
                         capture_output=True, text=True, check=True, cwd=str(HERE))
    return json.loads(out.stdout.strip().splitlines()[-1])


def _median(values: list[float]) -> float:
    values = sorted(values)
    mid = len(values) // 2
    return values[mid] if len(values) % 2 else 0.5 * (values[mid - 1] + values[mid])


def main(argv=None) -> None:
    import numpy as np

    argv = sys.argv[1:] if argv is None else argv
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--against", required=True, help="the git revision to time beside this tree")
    ap.add_argument("--nodes", type=int, nargs="+", default=[1024])
    ap.add_argument("--windows", nargs="+", choices=["off", "on"], default=["off", "on"])
    ap.add_argument("--geometries", nargs="+", default=["hertz", "punch"])
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--no-doc", action="store_true")
    args = ap.parse_args(argv)
    rows = []
    with package_trees(args.against) as trees:
        labels = list(trees)
        for geometry in args.geometries:
            for nodes in args.nodes:
                for windows in args.windows:
                    for src in trees.values():
                        _run(src, geometry, nodes, windows)  # numba compiles and caches; untimed
                    runs = {label: [] for label in labels}
                    for _ in range(args.repeat):
                        for label, src in trees.items():
                            runs[label].append(_run(src, geometry, nodes, windows))
                    ms = [_median([r["ms"] for r in runs[label]]) for label in labels]
                    a, b = (np.asarray(runs[label][-1]["edges"]) for label in labels)
                    edges = float(np.nanmax(np.abs(a - b))) if np.isfinite(a - b).any() else 0.0
                    da, db = (np.asarray(runs[label][-1]["dissipation"]) for label in labels)
                    spent = float(np.max(np.abs(da - db) / np.maximum(np.abs(db), 1e-300)))
                    rows.append(f"| {geometry} | {nodes} | {windows} | {ms[0]:.2f} | {ms[1]:.2f} | "
                                f"{ms[1] / ms[0]:.2f} | {edges:.1e} | {spent:.1e} |")
                    print(rows[-1], flush=True)
    text = "\n".join([
        BEGIN,
        (f"`python benchmarks/{Path(__file__).name} {' '.join(argv)}` ({time.strftime('%Y-%m-%d')}; {machine()}; "
         f"the trees alternating, median of {args.repeat} runs each; per run both seeds, best of two passes per "
         "history; edges: the largest difference of the two trees' outermost stick points over the width, "
         "dissipation: of the final dissipation, relative)"),
        "",
        (f"| geometry | nodes | windows | {labels[0]} [ms / step] | {labels[1]} [ms / step] | ratio | edges | "
         "dissipation |"),
        "|---|---:|---|---:|---:|---:|---:|---:|",
        *rows,
        END,
    ])
    if not args.no_doc:
        write_section(DOC, BEGIN, END, text, "The general solver against an earlier revision (random histories)")


if __name__ == "__main__":
    main()
