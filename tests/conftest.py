"""Shared fixtures."""
from __future__ import annotations

import inspect

import pytest
from click.testing import CliRunner, Result

from halfslip.cli import main


@pytest.fixture
def cli():
    """Run the halfslip command line in-process: ``cli("validate", path)``.

    The result has separate ``stdout`` and ``stderr``.
    """
    # click < 8.2 mixes stderr into stdout unless told not to
    separate = {"mix_stderr": False} if "mix_stderr" in inspect.signature(CliRunner).parameters else {}

    def invoke(*args: object) -> Result:
        return CliRunner(**separate).invoke(main, [str(arg) for arg in args])

    return invoke


def pytest_addoption(parser):
    parser.addoption("--runslow", action="store_true", default=False, help="also run the long stress variants")


def pytest_collection_modifyitems(config, items):
    if config.getoption("--runslow"):
        return
    skip = pytest.mark.skip(reason="long variant: run with --runslow")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip)


# CI runs the property tests on a fixed sequence of examples, so that a red CI
# always points at a change; locally they explore new examples every run.
import os  # noqa: E402

from hypothesis import settings  # noqa: E402

settings.register_profile("ci", derandomize=True)
if os.environ.get("CI"):
    settings.load_profile("ci")
