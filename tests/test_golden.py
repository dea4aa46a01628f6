"""Stored golden results (tests/data/golden): a run of each method and a sweep, compared value by value.

When a change of the numbers is intended, run ``python tests/data/golden/regenerate.py``
and say in the commit why they moved.

Tolerance: floats agree to ``RTOL`` = 1e-9 relative to each value, plus
``ATOL_SCALE`` = 1e-12 of the largest magnitude of the variable (for values
that pass through zero, e.g. Q, q, shift). On one machine a run is
bit-identical (test_reliability); across machines the last bits of sums and
LAPACK solves move with the BLAS build and the CPU's vector instructions.
1e-9 is far above that rounding and far below anything physical (the exact
method's own tolerance on a repeated state is 1e-12 of the memory, the
general solver's 1e-4 of the contact width), so any change of algorithm,
step selection, storage or cycle accounting shows. Integers, text, NaN
positions, dimensions and the names of variables and attributes agree exactly.
The step residual, itself a rounding-level diagnostic, is compared in its own units (``ABSOLUTE``).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import halfslip as hs
from halfslip.io import read_result

GOLDEN = Path(__file__).resolve().parent / "data" / "golden"
RTOL = 1e-9
ATOL_SCALE = 1e-12
#: Variables compared to an absolute tolerance in their own units instead: ``residual`` is the step's largest
#: check violation over the check tolerance (general.CHECK_TOL = 1e-7 of the scales); a solve exact to rounding
#: leaves 1e-9 .. 1e-6 of it, which moves with the order of any sum (compiling a kernel moved it by 4e-8).
#: 1e-3 of the tolerance is far above that rounding and far below a check that fails (1).
ABSOLUTE = {"residual": 1e-3}
VOLATILE = {"wall_time", "halfslip_version", "run_time", "count_run", "scene", "sweep_file", "scene_file"}
"""Attributes and variables that depend on the machine, the version or where the files are."""


def assert_same(actual, expected, what: str) -> None:
    assert set(actual.variables) == set(expected.variables), what
    assert dict(actual.sizes) == dict(expected.sizes), what
    for name, variable in expected.variables.items():
        if name in VOLATILE:
            continue
        got, want = actual[name].values, variable.values
        assert got.shape == want.shape, f"{what}: {name}"
        assert actual[name].dims == variable.dims, f"{what}: {name}"
        if want.dtype.kind == "f":
            np.testing.assert_array_equal(np.isnan(got), np.isnan(want), err_msg=f"{what}: {name} (NaN)")
            scale = float(np.nanmax(np.abs(want))) if np.any(np.isfinite(want)) else 0.0
            rtol, atol = (0.0, ABSOLUTE[name]) if name in ABSOLUTE else (RTOL, ATOL_SCALE * scale)
            np.testing.assert_allclose(got, want, rtol=rtol, atol=atol, equal_nan=True, err_msg=f"{what}: {name}")
        else:
            np.testing.assert_array_equal(got, want, err_msg=f"{what}: {name}")
        for key, value in variable.attrs.items():
            np.testing.assert_array_equal(actual[name].attrs[key], value, err_msg=f"{what}: {name}@{key}")
    assert set(actual.attrs) - VOLATILE == set(expected.attrs) - VOLATILE, what
    for key, value in expected.attrs.items():
        if key in VOLATILE:
            continue
        if isinstance(value, (float, np.floating)) and not isinstance(value, bool):
            assert float(actual.attrs[key]) == pytest.approx(float(value), rel=RTOL, nan_ok=True), f"{what}: @{key}"
        else:
            np.testing.assert_array_equal(actual.attrs[key], value, err_msg=f"{what}: @{key}")


@pytest.mark.parametrize("name", ["exact", "general"])
def test_a_run_reproduces_its_golden_result(name):
    expected = read_result(GOLDEN / f"{name}.h5")
    assert expected.attrs["method"] == name
    assert_same(hs.simulate(hs.load_scene(GOLDEN / f"{name}.yaml")), expected, name)


def test_the_golden_exact_run_skips_cycles_as_data():
    """The golden exact run has skipped cycles: the layout they are stored in is part of what is pinned."""
    ds = read_result(GOLDEN / "exact.h5")
    assert int(ds.segment_cycles_skipped.sum()) == ds.attrs["skipped_cycles"] > 0
    assert np.all(np.diff(ds.t.values) > 0)


def test_a_sweep_reproduces_its_golden_result(tmp_path):
    expected = read_result(GOLDEN / "sweep.h5")
    assert set(expected["method"].values) >= {"march: general"}  # direct and marched cases both pinned
    assert_same(hs.sweep(GOLDEN / "sweep.yaml", workers=1, progress=False), expected, "sweep")
