"""Regenerate the golden results of tests/test_golden.py, when a change of the numbers is intended.

    python tests/data/golden/regenerate.py

Runs ``exact.yaml`` and ``general.yaml`` (one run per method) and the sweep
``sweep.yaml`` and writes ``exact.h5``, ``general.h5``, ``sweep.h5`` next to
this script. Review the change (``git diff --stat``, the test's report) and
say in the commit why the numbers moved.
"""
from __future__ import annotations

from pathlib import Path

HERE = Path(__file__).resolve().parent
RUNS = ("exact", "general")


def main() -> None:
    import halfslip as hs
    from halfslip.io import write_result

    for name in RUNS:
        ds = hs.simulate(hs.load_scene(HERE / f"{name}.yaml"))
        write_result(ds, HERE / f"{name}.h5")
        print(HERE / f"{name}.h5")
    out = HERE / "sweep.h5"
    out.unlink(missing_ok=True)  # a sweep continues an unfinished file: start afresh
    hs.sweep(HERE / "sweep.yaml", output=out, workers=1, progress=False)
    print(out)


if __name__ == "__main__":
    main()
