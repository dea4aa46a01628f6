"""End to end: scene -> simulate -> HDF5 -> xarray / h5py, and the run command."""
from __future__ import annotations

import gc
import subprocess
import sys
import threading
from pathlib import Path

import h5py
import numpy as np
import pytest
import xarray as xr
from click.testing import CliRunner

import halfslip as hs
from halfslip.cli import main

from helpers import NARROW_SLIP_SCENE

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
INTERFACE_VARIABLES = [
    "P", "Q", "M", "sigma", "contact_left", "contact_right", "stick_left", "stick_right",
    "regime", "rigid_shift", "dissipation", "p", "q", "slip",
]


def test_run_hertz_example_writes_every_interface_variable(tmp_path):
    out = tmp_path / "hertz.h5"
    result = CliRunner().invoke(main, ["run", str(EXAMPLES / "hertz_pad.yaml"), "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert "partial slip" in result.output and str(out) in result.output
    with xr.open_dataset(out) as ds:
        for name in INTERFACE_VARIABLES + ["t", "x"]:
            assert name in ds.variables, name
            assert ds[name].attrs["units"] and ds[name].attrs["long_name"], name
        assert ds.attrs["method"] == "exact"
        assert ds.attrs["halfslip_version"] == hs.__version__
        assert "hertz-pad" in ds.attrs["scene"]
        assert ds["regime"].attrs["flag_meanings"].split() == ["separated", "stick", "partial_slip", "gross_sliding"]
        # the cycle repeats after the second one: 18 of 20 cycles are skipped
        assert ds.attrs["skipped_cycles"] == 18
        assert ds.sizes["t"] == 1 + 20 + 2 * 100
        # constant P after the ramp: the normal problem is solved on the ramp steps only
        assert ds.attrs["count_normal_solves"] == 20
        assert ds.attrs["count_stick_steps"] == 20
    with h5py.File(out, "r") as f:
        assert f["q"].shape == (221, 201)


def test_output_every_and_fields_control_storage(tmp_path):
    scene = hs.load_scene(EXAMPLES / "hertz_pad.yaml")
    import dataclasses

    scene = dataclasses.replace(scene, output=dataclasses.replace(scene.output, fields=("q",), every=7),
                                solver=dataclasses.replace(scene.solver, skip_steady_cycles=False))
    ds = hs.simulate(scene)
    n = scene.history.n_steps
    assert ds.sizes["t"] == 1 + n // 7 + (n % 7 != 0)
    assert "q" in ds and "p" not in ds and "slip" not in ds
    extents = hs.simulate(dataclasses.replace(scene, output=dataclasses.replace(scene.output, fields=())))
    assert "x" not in extents.dims
    # storing fields or not changes nothing in the extents
    np.testing.assert_array_equal(extents["stick_right"].values, ds["stick_right"].values)
    np.testing.assert_array_equal(extents["dissipation"].values, ds["dissipation"].values)


def test_exact_method_on_a_scene_it_cannot_serve_is_a_clear_error(tmp_path):
    result = CliRunner().invoke(main, ["run", str(EXAMPLES / "dovetail.yaml"), "--method", "exact",
                                       "-o", str(tmp_path / "d.h5")])
    assert result.exit_code == 2
    assert "method 'exact' cannot serve this scene" in result.output
    assert "moment" in result.output
    assert "Traceback" not in result.output
    assert not (tmp_path / "d.h5").exists()


def test_auto_picks_exact_for_symmetric_scene_without_moment_or_tension():
    scene = hs.load_scene(EXAMPLES / "motor.yaml")
    assert hs.simulate(scene).attrs["method"] == "exact"


def test_cyclic_run_carries_the_permanent_stick_zone():
    """hertz_pad: the run's scalars equal a(P - dQ/(2f)) (turning points sampled: 1e-10)."""
    ds = hs.simulate(hs.load_scene(EXAMPLES / "hertz_pad.yaml"))
    scene = hs.load_scene(EXAMPLES / "hertz_pad.yaml")
    problem = hs.NormalProblem(scene.profile, scene.material.compliance)
    c = float(problem.half_width(1e5 - 2 * 1.8e4 / (2 * 0.6)))
    assert float(ds.permanent_stick_right) == pytest.approx(c, rel=1e-10)
    assert float(ds.permanent_stick_left) == pytest.approx(-c, rel=1e-10)
    assert ds.permanent_stick_right.attrs["units"] == "m"


def test_general_run_says_when_its_slip_zones_are_under_resolved():
    """A slip zone narrower than a cell is said through the error estimate; a narrow one in the messages.

    The rounded punch's slip zones stay within about 1 % of the contact width
    (a(P - Q/f) of J1: 0.5 % at the end of this ramp). At 64 nodes (1.6 % a cell)
    no cell slips, but (S1) fails at both edges: every step of the Q ramp is a
    partial slip whose slip zones lie within the end cells (placed there since
    0.3.2; until then the steps said "stick") and reports an error estimate of at
    least SUBCELL_PLACEMENT of a cell (half of 1/64 of the width; a whole cell until
    0.3.3) although the two lattices agree. At 512 nodes the zones span 2-5 cells, below
    RESOLVED_SPACINGS: the widest is recorded and the messages say so; at 1024
    it spans twice as many cells (the edges are placed to ~0.1 cell: 10 %).

    All that is the lattice alone (``edge_windows: false``). With the edge windows (the default since 0.4.6)
    the 64-node run's windows see slip inside the end cells (it dissipates), and at 512 nodes their cells,
    four times finer, resolve the zones: no message.
    """
    from halfslip.simulator import RESOLVED_SPACINGS
    from halfslip.solvers.general import SUBCELL_PLACEMENT

    lattice = NARROW_SLIP_SCENE.replace("{method: general}", "{method: general, edge_windows: false}")
    assert lattice != NARROW_SLIP_SCENE
    windowed = hs.simulate(hs.parse_scene(NARROW_SLIP_SCENE), nodes=64)
    assert float(windowed.dissipation[-1]) > 0.0
    windowed = hs.simulate(hs.parse_scene(NARROW_SLIP_SCENE), nodes=512)
    assert "lattice spacings" not in windowed.attrs["messages"]
    blind = hs.simulate(hs.parse_scene(lattice), nodes=64)
    ramp = blind.step.values > 4
    assert np.all(blind.regime.values[1:][~ramp[1:]] == 1)  # Regime.STICK while P rises alone
    assert np.all(blind.regime.values[ramp] == 2)  # Regime.PARTIAL_SLIP
    assert np.all((blind.stick_left.values[ramp] > blind.contact_left.values[ramp])
                  & (blind.stick_right.values[ramp] < blind.contact_right.values[ramp]))
    assert np.all(blind.dissipation.values == 0.0)  # no cell slipped
    assert np.all(blind.error_estimate.values[ramp] >= SUBCELL_PLACEMENT / 64)
    assert np.all(blind.error_estimate.values[~ramp] == 0.0)
    coarse = hs.simulate(hs.parse_scene(lattice), nodes=512)
    fine = hs.simulate(hs.parse_scene(lattice), nodes=1024)
    spacings = coarse.attrs["widest_slip_zone_spacings"]
    assert 0.0 < spacings < RESOLVED_SPACINGS
    assert "lattice spacings" in coarse.attrs["messages"]
    assert fine.attrs["widest_slip_zone_spacings"] == pytest.approx(2 * spacings, rel=0.1)


def _oldest_during(scene) -> tuple[list, int]:
    """simulate(scene) with, after every step, the number of objects in the collector's oldest generation
    (what a full pass walks; frozen objects are not in it), and the freeze count after the run."""
    walked = []
    hs.simulate(scene, progress=lambda i, n: walked.append(len(gc.get_objects(generation=2))))
    return walked, gc.get_freeze_count()


def test_simulate_keeps_the_older_objects_out_of_the_collectors_passes_and_gives_them_back():
    """While a run marches, what existed before it is frozen (simulator._heap_frozen): a full pass would walk
    only what the run made (fewer than a tenth of the objects there were before: measured none at any of
    the motor loop's 276 steps against about 107,000 before, and all of them without the freeze), and after
    the run it is unfrozen as it was (a library call must not change the collector's state for its caller)."""
    scene = hs.load_scene(EXAMPLES / "motor.yaml")
    hs.simulate(scene)  # (the first run's compiled code loaded)
    gc.collect()
    before = len(gc.get_objects())
    assert gc.get_freeze_count() == 0
    walked, frozen_after = _oldest_during(scene)
    assert frozen_after == 0
    assert walked and max(walked) < before / 10, (max(walked), before)
    assert len(gc.get_objects(generation=2)) > before / 2  # given back


def test_simulate_leaves_a_freeze_it_did_not_make():
    """The ``halfslip`` command freezes its imports (halfslip_launch._freeze_imports); simulate then does not
    unfreeze them when it ends."""
    gc.freeze()
    try:
        count = gc.get_freeze_count()
        _, after = _oldest_during(hs.load_scene(EXAMPLES / "motor.yaml"))
        assert after >= count > 0
    finally:
        gc.unfreeze()


def test_the_command_freezes_its_imports_and_collects_its_own_objects():
    """halfslip_launch.main: after the import the command's objects are frozen (the module is imported first
    here, so that the program can be replaced by a probe) and the collector is on for the command itself
    (its own garbage is collected)."""
    code = ("import gc, halfslip.cli, halfslip_launch\n"
            "probe = lambda: print(gc.isenabled(), gc.get_freeze_count() > len(gc.get_objects()))\n"
            "halfslip.cli.run_as_program = probe\n"
            "halfslip_launch.main()\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=False)
    assert done.stdout.split() == ["True", "True"], done.stderr


def test_overlapping_marches_give_the_heap_back_once_the_last_one_ends():
    """simulate in several threads at once (a dask worker runs its tasks so): the marches overlap in any
    order, and the heap stays frozen until the last one ends, then is given back (a freeze undone by whichever
    march had found the heap unfrozen, as before the lock, gave it back while another still marched; and a
    check-then-freeze that interleaved with an unfreeze could leave it frozen for good)."""
    from halfslip.simulator import _heap_frozen

    assert gc.get_freeze_count() == 0
    for order in ("first in, first out", "first in, last out"):
        one, two = _heap_frozen(), _heap_frozen()
        one.__enter__()
        two.__enter__()
        first, second = (one, two) if order == "first in, first out" else (two, one)
        first.__exit__(None, None, None)
        assert gc.get_freeze_count() > 0, order  # the other still marches
        second.__exit__(None, None, None)
        assert gc.get_freeze_count() == 0, order
    # and real runs in threads
    scene = hs.load_scene(EXAMPLES / "motor.yaml")
    done = []
    threads = [threading.Thread(target=lambda: done.append(hs.simulate(scene).attrs["complete"])) for _ in range(3)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert done == [1, 1, 1]
    assert gc.get_freeze_count() == 0
