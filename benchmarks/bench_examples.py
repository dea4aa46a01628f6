"""Wall time of the examples as a user runs them, and against an earlier version in the same run.

    python benchmarks/bench_examples.py                       # this tree, 3 timed runs per example
    python benchmarks/bench_examples.py --against e72f96e     # and that git revision, alternating

Each example scene goes through ``halfslip.simulate`` (start-up, marching and
the stored fields, as ``halfslip run`` does, without writing the file), and the
solver's ``step()`` alone is timed over a second run in the same process (the
marching without start-up, numba's loading of its kernels and output): one
untimed run first (numba compiles and caches its kernels), then ``--repeat``
timed runs; the table gives the median and the time per marched step, and
the median wall time of the whole command, ``halfslip run SCENE -o OUT.h5``
through its entry point, in a fresh process after each timed run. With
``--against REV`` the same scenes run with the package of that revision (a
temporary ``git worktree``, in a subprocess), the two alternating run by run,
so that the ratio is measured in one session on one machine (the machines are
shared and noisy: absolute times move by 10-20 % between sessions). Writes the
table between the markers in docs/benchmarks.md.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
from _doc import machine, package_trees, write_section  # noqa: E402

DOC = ROOT / "docs" / "benchmarks.md"
BEGIN, END = "<!-- examples: begin -->", "<!-- examples: end -->"
EXAMPLES = ["dovetail", "hertz_pad", "motor", "tabulated"]

#: What a worker runs: one timed simulate of a scene, printed as JSON.
_WORKER = """
import json, sys, time
import halfslip
from halfslip.solvers.exact import ExactMemory
from halfslip.solvers.general import GeneralSolver
scene = halfslip.load_scene(sys.argv[1])
t = time.perf_counter()
result = halfslip.simulate(scene)
wall = time.perf_counter() - t
# the solver's step() alone, in the same process after that run: the marching without start-up and output
spent = [0.0, 0]
def timed(step):
    def wrapper(self, *args, **kwargs):
        t = time.perf_counter()
        try:
            return step(self, *args, **kwargs)
        finally:
            spent[0] += time.perf_counter() - t
            spent[1] += 1
    return wrapper
for cls in (ExactMemory, GeneralSolver):
    cls.step = timed(cls.step)
halfslip.simulate(scene)
print(json.dumps({"wall": wall, "steps": int(result.attrs["count_steps"]), "method": str(result.attrs["method"]),
                  "dissipation": float(result["dissipation"].values[-1]), "step": spent[0] / max(spent[1], 1)}))
"""


def _run(src: Path, scene: Path) -> dict:
    env = dict(os.environ, PYTHONPATH=str(src), OPENBLAS_NUM_THREADS="1")
    out = subprocess.run([sys.executable, "-c", _WORKER, str(scene)], env=env, capture_output=True, text=True,
                         check=True, cwd=str(src.parent))
    return json.loads(out.stdout.strip().splitlines()[-1])


#: What the command runs: ``halfslip run`` through its entry point (halfslip_launch), as the installed script does.
_COMMAND = "import sys; from halfslip_launch import main; sys.argv = ['halfslip', 'run'] + sys.argv[1:]; main()"


def _command(src: Path, scene: Path) -> float:
    """The wall time of the whole ``halfslip run SCENE -o OUT.h5`` in a fresh process (interpreter, import,
    run, the file written), with the package of ``src``."""
    env = dict(os.environ, PYTHONPATH=str(src), OPENBLAS_NUM_THREADS="1")
    with tempfile.TemporaryDirectory() as tmp:
        began = time.perf_counter()
        subprocess.run([sys.executable, "-c", _COMMAND, str(scene), "-o", str(Path(tmp) / "out.h5")], env=env,
                       capture_output=True, text=True, check=True, cwd=str(src.parent))
        return time.perf_counter() - began


def _median(values: list[float]) -> float:
    values = sorted(values)
    mid = len(values) // 2
    return values[mid] if len(values) % 2 else 0.5 * (values[mid - 1] + values[mid])


def measure(trees: dict[str, Path], repeat: int, examples: list[str]) -> dict:
    """{example: {tree: {"wall": median s, "steps", "method", "dissipation"}}}, the trees alternating."""
    out: dict = {}
    for name in examples:
        scene = ROOT / "examples" / f"{name}.yaml"
        for src in trees.values():
            _run(src, scene)  # compile and cache the kernels; warm the file cache
        walls: dict[str, list[float]] = {label: [] for label in trees}
        steps: dict[str, list[float]] = {label: [] for label in trees}
        commands: dict[str, list[float]] = {label: [] for label in trees}
        last: dict[str, dict] = {}
        for _ in range(repeat):
            for label, src in trees.items():
                got = _run(src, scene)
                walls[label].append(got["wall"])
                steps[label].append(got["step"])
                last[label] = got
                commands[label].append(_command(src, scene))
        out[name] = {label: dict(last[label], wall=_median(walls[label]), walls=walls[label],
                                 step=_median(steps[label]), command=_median(commands[label]))
                     for label in trees}
        line = "; ".join(f"{label} {out[name][label]['wall']:.3f} s" for label in trees)
        print(f"{name}: {line}", flush=True)
    return out


def write_doc(results: dict, trees: dict[str, Path], argv: list[str]) -> None:
    labels = list(trees)
    head = "| example | method | steps | " + " | ".join(
        f"{label} [s] | {label} [ms / step] | {label}: step() alone [ms / step] | {label}: `halfslip run` [s]"
        for label in labels)
    sep = "|---|---|---:|" + "---:|---:|---:|---:|" * len(labels)
    if len(labels) == 2:
        head += (f" | speed-up ({labels[0]} / {labels[1]}) | `halfslip run`, speed-up | dissipation, relative "
                 "difference")
        sep += "---:|---:|---:|"
    rows = [head + " |", sep]
    for name, by in results.items():
        first = by[labels[0]]
        cells = [name, first["method"], str(first["steps"])]
        for label in labels:
            cells += [f"{by[label]['wall']:.3f}", f"{1e3 * by[label]['wall'] / by[label]['steps']:.2f}",
                      f"{1e3 * by[label]['step']:.2f}", f"{by[label]['command']:.2f}"]
        if len(labels) == 2:
            a, b = by[labels[0]], by[labels[1]]
            cells.append(f"{a['wall'] / b['wall']:.2f}x")
            cells.append(f"{a['command'] / b['command']:.2f}x")
            rel = abs(a["dissipation"] - b["dissipation"]) / max(abs(b["dissipation"]), 1e-300)
            cells.append(f"{rel:.1e}")
        rows.append("| " + " | ".join(cells) + " |")
    text = "\n".join([
        BEGIN,
        f"`python benchmarks/{Path(__file__).name} {' '.join(argv)}`".replace(" `", "`"),
        f"({time.strftime('%Y-%m-%d')}; {machine()}; median of the timed runs, each a whole "
        "`halfslip.simulate` with start-up and stored fields in a fresh process"
        + (", the trees alternating run by run" if len(labels) == 2 else "")
        + "; step() alone: the solver's steps of a second run in the same process, per marched step; "
        "`halfslip run`: the whole command in a fresh process, interpreter and import to the file written, "
        "the median of as many runs)",
        "",
        *rows,
        END,
    ])
    write_section(DOC, BEGIN, END, text, "Examples, wall time")


def main(argv=None) -> None:
    argv = sys.argv[1:] if argv is None else argv
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--against", help="a git revision to time in the same run")
    ap.add_argument("--examples", nargs="+", default=EXAMPLES, choices=EXAMPLES)
    ap.add_argument("--no-doc", action="store_true")
    args = ap.parse_args(argv)
    with package_trees(args.against) as trees:
        results = measure(trees, args.repeat, args.examples)
    if not args.no_doc:
        write_doc(results, trees, argv)


if __name__ == "__main__":
    main()
