"""The numbers docs/user_guide.md quotes are those of a fresh run (docs/make_guide_numbers.py).

The cheap examples (exact method) are run afresh and must give the strings
stored in docs/guide_numbers.json; every stored string, the dovetail's too,
must appear verbatim in the guide. The dovetail (general solver, about a
minute) is checked on a shortened run for the structure of its result.
"""
from __future__ import annotations

import dataclasses
import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

import halfslip as hs

DOCS = Path(__file__).resolve().parents[1] / "docs"
GUIDE = (DOCS / "user_guide.md").read_text()
STORED = json.loads((DOCS / "guide_numbers.json").read_text())


def _script():
    spec = importlib.util.spec_from_file_location("make_guide_numbers", DOCS / "make_guide_numbers.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("example", ["hertz_pad", "motor", "dovetail", "tabulated"])
def test_every_stored_number_is_quoted_in_the_guide(example):
    stored = STORED[example]
    missing = [line for line in stored["summary"] if line not in GUIDE]
    assert not missing, f"summary lines of {example} not in the guide: {missing}"
    missing = {name: text for name, text in stored["quoted"].items() if text not in GUIDE}
    assert not missing, f"numbers of {example} not in the guide: {missing}"


@pytest.mark.parametrize("example", ["hertz_pad", "motor"])
def test_a_fresh_run_gives_the_stored_numbers(example):
    script = _script()
    assert example in script.CHEAP
    fresh = script.EXAMPLE_NUMBERS[example]()
    assert fresh == STORED[example], "run python docs/make_guide_numbers.py and update the guide"


def test_a_shortened_dovetail_run_has_the_structure_the_guide_describes():
    """Three cycles of 25 steps at 128 nodes: general solver, partial slip, a permanent stick zone inside
    the contact near the stored one, messages as data, and the summary lines the guide shows."""
    scene = hs.load_scene(DOCS.parent / "examples" / "dovetail.yaml")
    text = scene.text.replace("count: 20", "count: 3").replace("steps_per_cycle: 100", "steps_per_cycle: 25")
    short = hs.parse_scene(text, path=scene.path)
    short = dataclasses.replace(short, solver=dataclasses.replace(short.solver, nodes=128))
    ds = hs.simulate(short)
    assert ds.attrs["method"] == "general" and ds.attrs["complete"] == 1
    regimes = set(np.unique(ds["regime"].values[1:]))
    assert regimes <= {1, 2} and 2 in regimes
    left, right = float(ds.permanent_stick_left), float(ds.permanent_stick_right)
    assert ds.contact_left.values[-1] < left < right < ds.contact_right.values[-1]
    stored = STORED["dovetail"]["values"]  # of the full run: 20 cycles of 100 steps at 1000 nodes (solver.tol 1e-4)
    assert left == pytest.approx(stored["permanent_stick_left"], rel=0.01)
    assert right == pytest.approx(stored["permanent_stick_right"], rel=0.01)
    assert "message_kind" in ds and ds["message_kind"].dims == ("message",)
    script = _script()
    lines = script.summary_lines(ds)
    assert lines[0].startswith("halfslip run of dovetail-root: ") and "method general" in lines[0]
    assert [line.split()[0] for line in lines[1:5]] == \
        [line.split()[0] for line in STORED["dovetail"]["summary"][1:5]]
