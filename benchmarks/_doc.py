"""Writing a benchmark's table into a page of docs/ between its markers."""
from __future__ import annotations

from pathlib import Path


def write_section(page: Path, begin: str, end: str, text: str, heading: str) -> None:
    """Replace what lies between ``begin`` and ``end`` in ``page`` (markers included; ``text`` carries
    them) with ``text``, or append it under ``heading`` when the page has no such markers yet."""
    doc = page.read_text()
    if begin in doc:
        doc = doc[:doc.index(begin)] + text + doc[doc.index(end) + len(end):]
    else:
        doc = doc.rstrip() + f"\n\n## {heading}\n\n" + text + "\n"
    page.write_text(doc)
