"""What a run has to say, as data: step, time, kind, value and text.

A method's step reports a message text (``StepReport.message``); the
simulator files it here under a short, stable kind code with the number it
carries, so that a result says *when* and *how badly*, and a summary can
group a thousand similar notes into one line. The result stores the records
along a dimension ``message`` (docs/interface.md, "Messages").
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from .state import EDGE_PATH_PATTERN, GROSS_SLIDING_MESSAGE


@dataclass(frozen=True)
class Kind:
    """A kind of message: what its value is and which value is the worst."""

    code: str
    value: str
    units: str
    worst: str  # "max" or "min": the worst record has the largest (smallest) value
    label: str = "value"  # the value's name in a summary line


KINDS = {
    kind.code: kind for kind in (
        Kind("gross_sliding", "abs(Q)/(f P), the shear asked for over what friction carries", "1", "max",
             "abs(Q)/(f P)"),
        Kind("separated_shear", "abs(Q), the shear force not carried by a separated contact", "N/m", "max",
             "abs(Q) [N/m]"),
        Kind("slip_solve_kept_stick", "Coulomb excess of the full-stick answer kept, of f max p", "1", "max",
             "Coulomb excess"),
        Kind("slip_solve_closest", "violation of the closest slip-zone answer kept, x tolerance", "1", "max",
             "violation"),
        Kind("slip_zone_resolution", "widest slip zone in lattice spacings (contact width / nodes)", "1", "min",
             "spacings"),
        Kind("edge_path", "error of the contact edges interpolated along the step, of the contact width", "1",
             "max", "edge error"),
        Kind("note", "none (NaN)", "1", "max"),
    )
}
"""Every message kind, by its code (the values of ``message_kind``)."""

MAX_RECORDS_PER_KIND = 100
"""Records kept of one kind: the first 99 and the worst; ``message_count`` counts them all."""

_PATTERNS = (
    ("gross_sliding", re.compile(re.escape(GROSS_SLIDING_MESSAGE)), None),
    ("separated_shear", re.compile(r"separated \(P <= 0\): shear force Q = (?P<v>\S+) N/m not carried"), abs),
    ("slip_solve_kept_stick", re.compile(r"slip solve: no slip-zone configuration converged; kept full stick "
                                         r"\(Coulomb excess (?P<v>\S+) of f max p\)"), None),
    ("slip_solve_closest", re.compile(r"slip solve: no slip-zone configuration met the Coulomb and slip-direction "
                                      r"checks; kept the closest \(violation (?P<v>\S+) x tolerance\)"), None),
    ("edge_path", EDGE_PATH_PATTERN, None),
)


def classify(text: str) -> list[tuple[str, float, str]]:
    """``(kind, value, text)`` of each message in a step's text.

    A step taken in halves joins its halves' messages with ``"; "``; each
    known message found is one entry, and text that matches none is one
    ``note`` (value NaN).
    """
    found, rest = [], text
    for kind, pattern, transform in _PATTERNS:
        for match in pattern.finditer(text):
            value = math.nan
            if "v" in pattern.groupindex:
                try:
                    value = float(match.group("v"))
                except ValueError:
                    pass
                if transform is not None:
                    value = transform(value)
            found.append((match.start(), kind, value, match.group(0)))
            rest = rest.replace(match.group(0), "")
    found.sort()
    entries = [(kind, value, words) for _, kind, value, words in found]
    rest = rest.strip("; ").strip()
    if rest:
        entries.append(("note", math.nan, rest))
    return entries


class MessageLog:
    """The messages of one run, at most MAX_RECORDS_PER_KIND records per kind, every one counted."""

    def __init__(self):
        self.records: list[tuple[int, float, str, float, str]] = []  # (step, t, kind, value, text)
        self.counts: dict[str, int] = {}

    def add(self, step: int, t: float, kind: str, value: float, text: str) -> None:
        """Record one message; beyond the cap, only a worse one replaces the kind's last record."""
        self.counts[kind] = self.counts.get(kind, 0) + 1
        record = (int(step), float(t), kind, float(value), text)
        mine = [k for k, r in enumerate(self.records) if r[2] == kind]
        if len(mine) < MAX_RECORDS_PER_KIND:
            self.records.append(record)
            return
        if _worse(kind, record[3], max((self.records[k][3] for k in mine), key=_rank(kind))):
            self.records[mine[-1]] = record

    def add_text(self, step: int, t: float, text: str, values: dict | None = None) -> None:
        """Record a step's message text; `values` gives a kind's value where the text carries none."""
        for kind, value, words in classify(text):
            if values and kind in values and math.isnan(value):
                value = values[kind]
            self.add(step, t, kind, value, words)

    def add_many(self, kind: str, steps: np.ndarray, t: np.ndarray, values: np.ndarray, text: str) -> None:
        """Record one kind of message at many steps (a compiled chunk): the first ones and the worst."""
        room = max(MAX_RECORDS_PER_KIND - sum(r[2] == kind for r in self.records), 1)
        for k in range(min(room, len(steps))):
            self.add(int(steps[k]), float(t[k]), kind, float(values[k]), text)
        if len(steps) > room:
            rest = np.arange(room, len(steps))
            ranked = [_rank(kind)(float(v)) for v in values[rest]]
            worst = int(rest[int(np.argmax(ranked))])
            self.add(int(steps[worst]), float(t[worst]), kind, float(values[worst]), text)
            self.counts[kind] += len(rest) - 1

    def copy(self) -> MessageLog:
        log = MessageLog()
        log.records, log.counts = list(self.records), dict(self.counts)
        return log

    def texts(self) -> list[str]:
        """The distinct texts, in order of first appearance (the ``messages`` attribute of 0.1)."""
        return list(dict.fromkeys(r[4] for r in self.records))

    def variables(self) -> dict:
        """The result variables along the dimension ``message``."""
        step, t, kind, value, text = zip(*self.records) if self.records else ((),) * 5
        # an empty object array would be written as numbers: empty text columns are typed as text
        kinds = np.array(kind, dtype=object) if kind else np.zeros(0, dtype=str)
        texts = np.array(text, dtype=object) if text else np.zeros(0, dtype=str)
        counts = np.array([self.counts[k] for k in kind], dtype=np.int64)
        return {
            "message_step": ("message", np.array(step, dtype=np.int64),
                             {"units": "1", "long_name": "step of the history that gave the message"}),
            "message_t": ("message", np.array(t, dtype=float),
                          {"units": "s", "long_name": "time of the step that gave the message"}),
            "message_kind": ("message", kinds,
                             {"long_name": "kind of message (halfslip.messages.KINDS)"}),
            "message_value": ("message", np.array(value, dtype=float),
                              {"units": "1", "long_name": "the number the message carries (units by kind: "
                               "halfslip.messages.KINDS; NaN when none)"}),
            "message_text": ("message", texts, {"long_name": "the message"}),
            "message_count": ("message", counts,
                              {"units": "1", "long_name": "messages of this kind in the whole run, stored or not"}),
        }

    def checkpoint(self) -> dict:
        return {"records": [list(r) for r in self.records], "counts": dict(self.counts)}

    @classmethod
    def from_checkpoint(cls, data) -> MessageLog:
        """From :meth:`checkpoint`, or from the list of texts a 0.1 checkpoint holds."""
        log = cls()
        if isinstance(data, list):  # halfslip 0.1: distinct texts, no step
            for text in data:
                log.add_text(-1, math.nan, text)
            return log
        log.records = [(int(s), float(t), str(k), float(v), str(x)) for s, t, k, v, x in data["records"]]
        log.counts = {str(k): int(v) for k, v in data["counts"].items()}
        return log


def checkpoint_problem(data) -> str | None:
    """What is wrong with the messages of a decoded checkpoint (None when they fit)."""
    if isinstance(data, list):
        return None if all(isinstance(m, str) for m in data) else "its messages are not text"
    if not (isinstance(data, dict) and set(data) == {"records", "counts"} and isinstance(data["records"], list)
            and isinstance(data["counts"], dict)):
        return "its messages are malformed"
    for record in data["records"]:
        if not (isinstance(record, list) and len(record) == 5 and isinstance(record[0], int)
                and isinstance(record[1], float) and isinstance(record[2], str) and isinstance(record[3], float)
                and isinstance(record[4], str)):
            return "its messages are malformed"
    if not all(isinstance(k, str) and isinstance(v, int) for k, v in data["counts"].items()):
        return "its message counts are malformed"
    return None


def _rank(kind: str):
    sign = -1.0 if KINDS.get(kind, KINDS["note"]).worst == "min" else 1.0
    return lambda value: -math.inf if math.isnan(value) else sign * value


def _worse(kind: str, value: float, than: float) -> bool:
    rank = _rank(kind)
    return rank(value) > rank(than)


def summary(ds) -> list[str]:
    """One line per kind of message of a result: count, first and worst step, the first text.

    Reads the ``message_*`` variables; a result of 0.1 (the ``messages``
    attribute only) gives one line per distinct text.
    """
    if "message_kind" not in ds.variables:
        return [text for text in str(ds.attrs.get("messages", "")).split("\n") if text]
    kinds = [str(k) for k in ds["message_kind"].values]
    step, t = ds["message_step"].values, ds["message_t"].values
    value, text, count = ds["message_value"].values, ds["message_text"].values, ds["message_count"].values
    lines = []
    for kind in dict.fromkeys(kinds):
        rows = [k for k, name in enumerate(kinds) if name == kind]
        first = rows[0]
        worst = max(rows, key=lambda k: _rank(kind)(float(value[k])))
        where = f"first at step {step[first]} (t = {t[first]:.6g} s)"
        if len(rows) > 1 or int(count[first]) > 1:
            if not math.isnan(float(value[worst])):
                where += (f", worst at step {step[worst]} (t = {t[worst]:.6g} s, "
                          f"{KINDS.get(kind, KINDS['note']).label} = {float(value[worst]):.4g})")
        lines.append(f"{kind} x {int(count[first])}, {where}: {text[first]}")
    return lines
