"""``halfslip validate``: good scenes print their summary, bad ones one line and exit 2.

Each file in tests/data/bad/ starts with a comment saying what the error must
name, e.g. ``# expect: file=malformed.csv line=5 field=loads[1].table``
(``file`` defaults to the scene itself; ``message=`` is a phrase of the text,
and takes the rest of the line).
"""
from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from halfslip import __version__

BAD = Path(__file__).resolve().parent / "data" / "bad"
EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def expectation(path: Path) -> dict[str, str]:
    """Parse the ``# expect:`` header of a bad scene."""
    header = path.read_text().splitlines()[0]
    match = re.fullmatch(r"# expect: (.*)", header)
    assert match, f"{path.name} lacks its '# expect:' header"
    text, _, message = match.group(1).partition("message=")
    expected = dict(item.split("=", 1) for item in text.split())
    expected.setdefault("file", path.name)
    if message:
        expected["message"] = message.strip()
    return expected


def assert_one_line_error(result, file: str, line: str | None, field: str | None) -> str:
    assert result.exit_code == 2, result.output
    assert isinstance(result.exception, SystemExit)  # not an unexpected exception
    assert result.stdout == ""
    assert "Traceback" not in result.output
    (text,) = result.stderr.splitlines()
    location = f"{file}:{line}: " if line else f"{file}: "
    assert text.startswith("halfslip: ") and location in text, text
    if field:
        assert f": {field}: " in text, text
    return text


def test_there_are_enough_distinct_bad_scenes():
    assert len(list(BAD.glob("*.yaml"))) >= 15


@pytest.mark.parametrize("path", sorted(BAD.glob("*.yaml")), ids=lambda path: path.stem)
def test_bad_scene_fails_with_file_line_and_field(cli, path):
    expected = expectation(path)
    text = assert_one_line_error(cli("validate", path), expected["file"], expected["line"], expected.get("field"))
    assert expected.get("message", "") in text


@pytest.mark.parametrize("path", sorted(p for p in EXAMPLES.glob("*.yaml") if "sweep" not in p.name), ids=lambda path: path.name)
def test_examples_validate(cli, path):
    result = cli("validate", path)
    assert result.exit_code == 0, result.output
    assert result.stderr == ""  # no warnings
    out = result.stdout
    for word in ("material", "friction", "geometry", "solver", "output", "history", "max |Q|/(fP)"):
        assert word in out


def test_validate_prints_the_resolved_scene(cli):
    out = cli("validate", EXAMPLES / "dovetail.yaml").stdout
    assert "dovetail-root" in out
    assert "E = 1.15e+11 Pa, nu = 0.3, A = 4(1 - nu^2)/E = 3.16522e-11 1/Pa" in out
    assert "rounded_punch: flat_half_width = 0.002 m, radius = 0.01 m" in out
    assert "method = auto, tol = 0.0001, nodes = 1000, skip_steady_cycles = true" in out
    assert "fields = [p, q, slip], every = 1, points = 201" in out
    assert "2 segments, 2050 steps, t = 0 .. 21 s" in out
    ramp_line, cycles_line = (line.split() for line in out.splitlines() if re.match(r"\s+[01]\s+(ramp|cycles)", line))
    assert ramp_line[:6] == ["0", "ramp", "14", "0", "1", "50"]
    assert cycles_line[:6] == ["1", "cycles", "18", "1", "21", "2000"]
    assert re.search(r"sigma\s+0\s+4e\+07\s+Pa", out)
    assert "max |Q|/(fP) = 0.3788" in out


def test_validate_warns_on_stderr_but_succeeds(cli, tmp_path):
    path = tmp_path / "sliding.yaml"
    path.write_text(
        "material: {E: 200e9, nu: 0.3}\nfriction: 0.3\ngeometry: {kind: hertz, radius: 0.05}\nloads:\n"
        "  - ramp: {to: {P: 1e5}, duration: 1}\n"
        "  - cycles: {count: 1, period: 1, Q: {amplitude: 4e4, phase: 90}}\n"
    )
    result = cli("validate", path)
    assert result.exit_code == 0
    warnings = result.stderr.splitlines()
    assert len(warnings) == 2 and all(line.startswith("halfslip: warning: ") for line in warnings)
    assert "loads[1] (line 6): Q jumps from 0 to 40000" in warnings[0]
    assert "|Q| > fP" in warnings[1]


def test_missing_file_and_directory(cli, tmp_path):
    missing = tmp_path / "nowhere.yaml"
    assert "no such file" in assert_one_line_error(cli("validate", missing), str(missing), None, None)
    assert "directory" in assert_one_line_error(cli("validate", tmp_path), str(tmp_path), None, None)


def test_version(cli):
    result = cli("--version")
    assert result.exit_code == 0 and __version__ in result.stdout


def test_real_process_prints_one_line_and_exits_2():
    path = BAD / "unit_string.yaml"
    result = subprocess.run(
        [sys.executable, "-c", "from halfslip.cli import main; main()", "validate", str(path)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode == 2
    assert result.stdout == ""
    assert result.stderr == (
        f"halfslip: {path}:8: loads[0].ramp.to.P: '2e5 N' carries a unit; "
        "give the number in SI units without a unit\n"
    )
