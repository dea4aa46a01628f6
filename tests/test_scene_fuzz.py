"""Mutated scenes: the loader accepts them or fails with the clean one-line error."""
from __future__ import annotations

from pathlib import Path

import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import halfslip as hs
from halfslip.errors import HalfslipInputError

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
TEXTS = {p.name: p.read_text() for p in sorted(EXAMPLES.glob("*.yaml")) if "sweep" not in p.name}

VALUES = st.one_of(
    st.none(), st.booleans(), st.integers(-10**6, 10**6), st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=8), st.lists(st.integers(-3, 3), max_size=3), st.dictionaries(st.text(max_size=4), st.integers(), max_size=2),
    st.sampled_from(["2e5 N", "1e5", "-1", "nan", "hertz", "rounded_punch", "profile", ""]),
)


def _paths(node, prefix=()):
    yield prefix
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _paths(v, prefix + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _paths(v, prefix + (i,))


def _set(node, path, value):
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value


def _delete(node, path):
    for key in path[:-1]:
        node = node[key]
    del node[path[-1]]


def assert_clean(text: str, base_dir: Path) -> None:
    try:
        hs.parse_scene(text, path=base_dir / "mutant.yaml", base_dir=base_dir)
    except HalfslipInputError as error:
        message = str(error)
        assert "\n" not in message and message, message


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(name=st.sampled_from(sorted(TEXTS)), data=st.data())
def test_structural_mutations_fail_cleanly(name, data):
    tree = yaml.safe_load(TEXTS[name])
    paths = [p for p in _paths(tree) if p]
    for _ in range(data.draw(st.integers(1, 3))):
        path = data.draw(st.sampled_from(paths))
        try:
            if data.draw(st.booleans()):
                _set(tree, path, data.draw(VALUES))
            else:
                _delete(tree, path)
        except (KeyError, IndexError, TypeError):
            pass  # the path vanished with an earlier mutation
        paths = [p for p in _paths(tree) if p] or [("name",)]
    assert_clean(yaml.safe_dump(tree), EXAMPLES)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(name=st.sampled_from(sorted(TEXTS)), data=st.data())
def test_textual_mutations_fail_cleanly(name, data):
    text = TEXTS[name]
    for _ in range(data.draw(st.integers(1, 4))):
        i = data.draw(st.integers(0, len(text) - 1))
        op = data.draw(st.sampled_from(["delete", "insert", "replace"]))
        ch = data.draw(st.sampled_from(list(":{}[],-#'\"\t\n 0123456789.eE!&*|>%@`xyz")))
        if op == "delete":
            text = text[:i] + text[i + 1:]
        elif op == "insert":
            text = text[:i] + ch + text[i:]
        else:
            text = text[:i] + ch + text[i + 1:]
    assert_clean(text, EXAMPLES)


def test_a_key_with_a_line_break_still_gives_one_line():
    """Found by the structural fuzzer: a mapping key '\\n' was echoed into the message."""
    tree = yaml.safe_load(TEXTS["hertz_pad.yaml"])
    tree["material"] = {"\n": 0}
    text = yaml.safe_dump(tree)
    assert_clean(text, EXAMPLES)
    try:
        hs.parse_scene(text, path=EXAMPLES / "mutant.yaml", base_dir=EXAMPLES)
    except HalfslipInputError as error:
        assert "\\n" in str(error)  # shown escaped, on the one line
    else:
        raise AssertionError("a material with an unknown key must be refused")
