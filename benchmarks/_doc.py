"""Writing a benchmark's table into a page of docs/ between its markers, and the package trees an A/B run
times (this tree and a git revision's, in a temporary worktree)."""
from __future__ import annotations

import contextlib
import os
import platform
import subprocess
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def machine() -> str:
    """The machine and the numerical stack, as a benchmark's table states them."""
    import numba
    import numpy
    import scipy
    return (f"{platform.system()} {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
            f"numpy {numpy.__version__}, scipy {scipy.__version__}, numba {numba.__version__}")


@contextlib.contextmanager
def package_trees(against: str | None):
    """{label: src folder}: this tree's, and with ``against`` first that git revision's (a temporary ``git
    worktree``, removed after)."""
    trees = {"this tree": ROOT / "src"}
    if not against:
        yield trees
        return
    rev = subprocess.run(["git", "rev-parse", "--short", against], cwd=ROOT, capture_output=True, text=True,
                         check=True).stdout.strip()
    with tempfile.TemporaryDirectory() as tmp:
        where = Path(tmp) / rev
        subprocess.run(["git", "worktree", "add", "--detach", str(where), rev], cwd=ROOT, check=True,
                       capture_output=True)
        try:
            yield {rev: where / "src", "this tree": ROOT / "src"}
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(where)], cwd=ROOT, check=False,
                           capture_output=True)


def write_section(page: Path, begin: str, end: str, text: str, heading: str) -> None:
    """Replace what lies between ``begin`` and ``end`` in ``page`` (markers included; ``text`` carries
    them) with ``text``, or append it under ``heading`` when the page has no such markers yet."""
    doc = page.read_text()
    if begin in doc:
        doc = doc[:doc.index(begin)] + text + doc[doc.index(end) + len(end):]
    else:
        doc = doc.rstrip() + f"\n\n## {heading}\n\n" + text + "\n"
    page.write_text(doc)
