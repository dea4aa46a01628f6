"""Parameter sweeps (halfslip.sweep): layout, values, backends, faults, restarts, bad files.

Tolerances: a sweep case runs the same deterministic code on the same scene
as a direct call, so sweep values are compared with direct ``steady_state``
values *exactly* (bitwise), and the backends (in-process, local processes,
dask) against each other exactly too. Only the marching fallback is compared
with the direct construction with a tolerance (stated at the test).
"""
from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from helpers import as_from_a_terminal

import halfslip as hs
from halfslip.errors import HalfslipInputError
from halfslip.io import read_result
from halfslip.sweep import (
    SUMMARIES,
    is_sweep_result,
    load_sweep,
    march_case,
    parse_sweep,
    plot_sweep,
    solve_case,
)

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
HERTZ = EXAMPLES / "hertz_pad.yaml"
Q_PATH = "loads[1].cycles.Q.amplitude"
Q_NAME = "Q_amplitude"  # its short name: the dimension of a result
NUMBERS = ["permanent_stick_left", "permanent_stick_right", "peak_slip_amplitude", "dissipation_per_cycle", "regime"]
SUMMARY = NUMBERS + ["status", "method", "done"]  # everything but run_time, which is a wall-clock time


def hertz_case(friction: float = 0.6, q_amplitude: float = 1.8e4, steps_per_cycle: int | None = None):
    """The hertz_pad scene with friction and Q amplitude replaced by *text* substitution.

    Deliberately another route than the sweep's (which edits parsed data), so
    that the comparison checks the sweep's case building too.
    """
    text = HERTZ.read_text()
    assert "friction: 0.6\n" in text and "Q: {amplitude: 1.8e4}" in text
    text = text.replace("friction: 0.6\n", f"friction: {friction!r}\n")
    text = text.replace("Q: {amplitude: 1.8e4}", f"Q: {{amplitude: {q_amplitude!r}}}")
    if steps_per_cycle is not None:
        text = text.replace("steps_per_cycle: 100", f"steps_per_cycle: {steps_per_cycle}")
    return hs.parse_scene(text, base_dir=EXAMPLES)


def direct(scene) -> dict:
    ds = hs.steady_state(scene)
    return {name: (int(ds[name]) if name == "regime" else float(ds[name])) for name in NUMBERS}


def write_sweep(tmp_path: Path, body: str, name: str = "sweep.yaml") -> Path:
    path = tmp_path / name
    path.write_text(f"scene: {HERTZ}\n{body}")
    return path


def summary(ds: xr.Dataset) -> xr.Dataset:
    """The deterministic part of a sweep result: summaries and coordinates, no attributes."""
    return ds[SUMMARY].drop_attrs()


GRID = "vary:\n  friction: [0.3, 0.6]\n  loads[1].cycles.Q.amplitude: [1.0e4, 2.0e4, 4.0e4]\n"


@pytest.fixture(scope="module")
def grid_serial(tmp_path_factory):
    path = write_sweep(tmp_path_factory.mktemp("grid"), GRID)
    return path, hs.sweep(path, workers=1, progress=False)


# -- layout and values ---------------------------------------------------------


def test_grid_has_one_dimension_per_path_and_the_values_of_direct_runs(grid_serial):
    path, ds = grid_serial
    assert is_sweep_result(ds)
    assert ds["done"].dims == ("friction", Q_NAME)
    assert ds.sizes == {"friction": 2, Q_NAME: 3}
    np.testing.assert_array_equal(ds["friction"], [0.3, 0.6])
    np.testing.assert_array_equal(ds[Q_NAME], [1.0e4, 2.0e4, 4.0e4])
    assert ds[Q_NAME].attrs["units"] == "N/m" and ds["friction"].attrs["units"] == "1"
    assert ds[Q_NAME].attrs["path"] == Q_PATH and json.loads(ds.attrs["sweep_names"]) == ["friction", Q_NAME]
    for name in list(ds.data_vars) + list(ds.coords):
        assert {"units", "long_name"} <= set(ds[name].attrs), name
    assert set(SUMMARIES) == set(ds.data_vars)
    assert ds.attrs["complete"] == 1 and ds.attrs["count_done"] == 6 and ds.attrs["count_failed"] == 0
    assert ds["done"].all() and (ds["status"] == "ok").all()
    for f in (0.3, 0.6):
        for q in (1.0e4, 2.0e4, 4.0e4):
            case = ds.sel({"friction": f, Q_NAME: q})
            expected = direct(hertz_case(f, q))
            for name in NUMBERS:  # exact: the same deterministic computation
                np.testing.assert_array_equal(case[name].values, expected[name], err_msg=f"{name} f={f} Q={q}")
            assert str(case["method"].values).startswith("steady: ")
    # 4.0e4 > 0.3 * 1.0e5: gross sliding, nothing sticks; the others slip partially
    assert int(ds["regime"].sel({"friction": 0.3, Q_NAME: 4.0e4})) == 3
    assert np.isnan(float(ds["permanent_stick_left"].sel({"friction": 0.3, Q_NAME: 4.0e4})))
    assert int((ds["regime"] == 2).sum()) == 5


def test_explicit_cases_have_a_case_dimension_with_the_values_as_coordinates(tmp_path):
    path = write_sweep(tmp_path, 'cases:\n  - {friction: 0.5}\n  - {friction: 0.7, "loads[1].cycles.Q.amplitude": 3.0e4}\n'
                                 "  - loads[1].cycles.Q.amplitude: 1.0e4\n")
    ds = hs.sweep(path, workers=1, progress=False)
    assert ds["done"].dims == ("case",) and ds.sizes["case"] == 3
    np.testing.assert_array_equal(ds["case"], [0, 1, 2])
    assert ds["friction"].dims == ("case",) and ds[Q_NAME].dims == ("case",)
    # cases that leave a path alone show the base scene's value there
    np.testing.assert_array_equal(ds["friction"], [0.5, 0.7, 0.6])
    np.testing.assert_array_equal(ds[Q_NAME], [1.8e4, 3.0e4, 1.0e4])
    for k, (f, q) in enumerate([(0.5, 1.8e4), (0.7, 3.0e4), (0.6, 1.0e4)]):
        expected = direct(hertz_case(f, q))
        for name in NUMBERS:  # exact
            np.testing.assert_array_equal(ds[name].values[k], expected[name], err_msg=f"{name} case {k}")


def test_linspace_and_logspace_give_the_numpy_values(tmp_path):
    spec = load_sweep(write_sweep(tmp_path, "vary:\n  friction: {logspace: [0.2, 0.8, 3]}\n"
                                            "  loads[1].cycles.Q.amplitude: {linspace: [1.0e4, 2.0e4, 5]}\n"))
    assert spec.shape == (3, 5) and spec.paths == ("friction", Q_PATH)
    np.testing.assert_array_equal(spec.axes[0], np.geomspace(0.2, 0.8, 3))  # exact
    np.testing.assert_array_equal(spec.axes[1], np.linspace(1.0e4, 2.0e4, 5))  # exact
    assert spec.overrides(7) == {"friction": spec.axes[0][1], Q_PATH: spec.axes[1][2]}  # C order


def test_the_file_holds_the_returned_dataset(tmp_path):
    path = write_sweep(tmp_path, "vary:\n  friction: [0.4, 0.6]\nper_cycle: false\n")
    out = tmp_path / "out.h5"
    ds = hs.sweep(path, output=out, workers=1, progress=False)
    back = read_result(out)
    xr.testing.assert_identical(summary(back), summary(ds))
    np.testing.assert_array_equal(back["run_time"], ds["run_time"])
    assert back.attrs["sweep_hash"] == ds.attrs["sweep_hash"] == load_sweep(path).hash
    assert back.attrs["scene"] == HERTZ.read_text()
    # per_cycle: false skips the marched cycles: no dissipation, the stick zone still there
    assert ds["dissipation_per_cycle"].isnull().all() and ds["permanent_stick_left"].notnull().all()


def test_a_mapping_works_like_a_file(tmp_path, grid_serial):
    path, serial = grid_serial
    ds = hs.sweep({"scene": str(HERTZ), "vary": {"friction": [0.3, 0.6], Q_PATH: [1.0e4, 2.0e4, 4.0e4]}},
                  workers=1, progress=False)
    xr.testing.assert_identical(summary(ds), summary(serial))
    assert ds.attrs["sweep_hash"] == serial.attrs["sweep_hash"]  # the hash ignores the file's layout


def test_cases_dir_holds_one_full_result_per_case(tmp_path):
    path = write_sweep(tmp_path, "vary:\n  friction: [0.4, 0.5, 0.6]\n")
    ds = hs.sweep(path, workers=1, cases_dir=tmp_path / "cases", progress=False)
    files = sorted((tmp_path / "cases").glob("*.h5"))
    assert [f.name for f in files] == ["case_0.h5", "case_1.h5", "case_2.h5"]
    for k, file in enumerate(files):
        full = read_result(file)
        assert full.attrs["sweep_case"] == k and json.loads(full.attrs["sweep_overrides"]) == {"friction": [0.4, 0.5, 0.6][k]}
        assert float(full["permanent_stick_right"]) == float(ds["permanent_stick_right"][k])
        assert "slip_amplitude" in full  # the steady dataset, with its per-point slip amplitude


# -- the marching fallback -----------------------------------------------------


@pytest.mark.parametrize("name", ["hertz_pad", "motor"])
def test_marching_summaries_agree_with_the_direct_steady_state(name):
    """Last marched cycle vs the direct construction, with and without cycle skipping.

    Tolerances: the stick edges from the marched steps differ from the closed
    form only by the sampling of the loop (rtol 1e-6; hertz_pad samples the
    peaks exactly); dissipation and slip amplitude are measured on a marched
    steady cycle in both (rtol 1e-10).
    """
    import dataclasses

    scene = hs.load_scene(EXAMPLES / f"{name}.yaml")
    steady, method = solve_case(scene)[:2]
    assert method.startswith("steady: ")
    no_skip = dataclasses.replace(scene, solver=dataclasses.replace(scene.solver, skip_steady_cycles=False))
    for marched_scene in (scene, no_skip):
        marched, method, ds = march_case(marched_scene)
        assert method == "march: exact"
        assert marched["regime"] == steady["regime"] == 2
        np.testing.assert_allclose(marched["permanent_stick_left"], steady["permanent_stick_left"], rtol=1e-6)
        np.testing.assert_allclose(marched["permanent_stick_right"], steady["permanent_stick_right"], rtol=1e-6)
        np.testing.assert_allclose(marched["dissipation_per_cycle"], steady["dissipation_per_cycle"], rtol=1e-10)
        np.testing.assert_allclose(marched["peak_slip_amplitude"], steady["peak_slip_amplitude"], rtol=1e-10)
    assert ds.attrs["skipped_cycles"] == 0


def test_a_scene_without_cycles_is_marched(tmp_path):
    scene = tmp_path / "no_cycles.yaml"
    scene.write_text(
        "material: {E: 200.0e9, nu: 0.3}\nfriction: 0.6\ngeometry: {kind: hertz, radius: 50.0e-3}\nloads:\n"
        "  - ramp: {to: {P: 1.0e5}, duration: 1.0, steps: 10}\n"
        "  - ramp: {to: {Q: 3.0e4}, duration: 1.0, steps: 10}\n"
        "  - hold: {duration: 0.5, steps: 2}\n"
    )
    path = tmp_path / "sweep.yaml"
    path.write_text("scene: no_cycles.yaml\nvary:\n  friction: [0.6]\n")
    ds = hs.sweep(path, workers=1, progress=False)
    assert str(ds["method"].values[0]) == "march: exact" and str(ds["status"].values[0]) == "ok"
    assert ds["dissipation_per_cycle"].isnull().all() and ds["peak_slip_amplitude"].isnull().all()
    # the window is the hold, which begins at the end of the shear ramp: Cattaneo's stick zone
    # b = a sqrt(1 - Q/(fP)) with Q/(fP) = 0.5 (rtol 1e-12: both from the exact method)
    result = hs.simulate(hs.load_scene(scene))
    a = float(result["contact_right"][-1])
    np.testing.assert_allclose(float(ds["permanent_stick_right"][0]), a * np.sqrt(0.5), rtol=1e-12)
    assert int(ds["regime"][0]) == 1  # nothing slips during the hold


# -- backends --------------------------------------------------------------------


def test_local_processes_give_the_serial_numbers_exactly(grid_serial):
    path, serial = grid_serial
    ds = hs.sweep(path, workers=2, progress=False)
    assert ds.attrs["backend"] == "processes"
    xr.testing.assert_identical(summary(ds), summary(serial))


def test_a_dask_cluster_gives_the_serial_numbers_exactly(grid_serial, tmp_path):
    from distributed import Client, LocalCluster

    path, serial = grid_serial
    with LocalCluster(n_workers=2, processes=True, threads_per_worker=1, dashboard_address=None) as cluster:
        ds = hs.sweep(path, scheduler=cluster.scheduler_address, progress=False, cases_dir=tmp_path / "cases")
        with Client(cluster) as client:  # a client object is accepted too
            again = hs.sweep(path, scheduler=client, progress=False)
            assert len(client.scheduler_info()["workers"]) == 2
    assert ds.attrs["backend"] == "dask"
    xr.testing.assert_identical(summary(ds), summary(serial))
    xr.testing.assert_identical(summary(again), summary(serial))
    assert len(list((tmp_path / "cases").glob("case_*.h5"))) == 6  # written by this process


def test_an_unreachable_scheduler_is_one_line(cli, tmp_path):
    import dask

    path = write_sweep(tmp_path, "vary:\n  friction: [0.5]\n")
    with dask.config.set({"distributed.comm.timeouts.connect": "1s"}):
        result = cli("sweep", path, "-o", tmp_path / "o.h5", "--scheduler", "tcp://127.0.0.1:9")
    assert result.exit_code == 2, result.output
    assert result.stderr.startswith("halfslip: scheduler: cannot reach a dask scheduler at 'tcp://127.0.0.1:9'")


# -- faults and restarts ---------------------------------------------------------


def test_an_invalid_value_fails_its_cases_only(tmp_path, grid_serial):
    path = write_sweep(tmp_path, "vary:\n  friction: [0.3, -0.1, 0.6]\n  loads[1].cycles.Q.amplitude: [1.0e4, 2.0e4, 4.0e4]\n")
    ds = hs.sweep(path, workers=2, progress=False)
    status = ds["status"].sel(friction=-0.1).values
    assert list(status) == [f"{path}:3: vary.friction[1]: must be >= 0, got -0.1"] * 3
    assert ds["done"].all() and ds.attrs["count_failed"] == 3 and ds.attrs["complete"] == 1
    assert (ds["regime"].sel(friction=-0.1) == -1).all() and ds["permanent_stick_left"].sel(friction=-0.1).isnull().all()
    # the others ran and have the numbers of the sweep without the bad value, exactly
    good = ds.sel(friction=[0.3, 0.6])
    xr.testing.assert_identical(summary(good), summary(grid_serial[1]))


def test_a_case_that_raises_at_run_time_is_recorded_and_the_rest_go_on(tmp_path, monkeypatch):
    sweep_module = sys.modules["halfslip.sweep.run"]  # where run_case looks solve_case up (`halfslip.sweep` is the function)

    real = sweep_module.solve_case

    def flaky(scene, per_cycle=True):
        if scene.friction == 0.5:
            raise RuntimeError("solver diverged")
        return real(scene, per_cycle=per_cycle)

    monkeypatch.setattr(sweep_module, "solve_case", flaky)
    path = write_sweep(tmp_path, "vary:\n  friction: [0.4, 0.5, 0.6]\nper_cycle: false\n")
    ds = hs.sweep(path, workers=1, progress=False)  # in-process: the patch is seen
    assert list(ds["status"].values) == ["ok", "RuntimeError: solver diverged", "ok"]
    assert list(ds["done"].values) == [True, True, True] and ds.attrs["count_failed"] == 1
    np.testing.assert_array_equal(ds["regime"].values, [2, -1, 2])


class StopAfter:
    """A progress callback that raises KeyboardInterrupt after `k` finished cases."""

    def __init__(self, k: int | None):
        self.k = k
        self.calls = 0

    def __call__(self, done: int, failed: int, total: int) -> None:
        self.calls += 1
        if self.k is not None and self.calls == self.k:
            raise KeyboardInterrupt


@pytest.mark.parametrize("workers", [1, 2])
def test_an_interrupted_sweep_resumes_with_only_the_missing_cases(tmp_path, grid_serial, workers):
    path, serial = grid_serial
    out = tmp_path / "out.h5"
    stop = StopAfter(2)
    first = hs.sweep(path, output=out, workers=workers, progress=stop, checkpoint_seconds=0.0)
    assert first.attrs["complete"] == 0
    done = int(first["done"].sum())
    assert done == 2 and first.attrs["count_run"] == 2  # the callback stops the driver at once
    partial = read_result(out)
    assert partial.attrs["complete"] == 0 and int(partial["done"].sum()) == 2
    assert (partial["status"].values[~partial["done"].values] == "not run").all()
    assert partial["permanent_stick_left"].values[~partial["done"].values].size == 4
    assert np.isnan(partial["run_time"].values[~partial["done"].values]).all()

    count = StopAfter(None)
    final = hs.sweep(path, output=out, workers=workers, progress=count)
    assert final.attrs["count_run"] == count.calls == 6 - done  # only the missing cases ran
    assert final.attrs["complete"] == 1 and final.attrs["count_done"] == 6
    xr.testing.assert_identical(summary(final), summary(serial))
    xr.testing.assert_identical(summary(read_result(out)), summary(serial))

    again = hs.sweep(path, output=out, workers=workers, progress=False)
    assert again.attrs["count_run"] == 0  # nothing left to do


def test_the_command_line_stops_on_sigint_and_the_same_command_finishes(tmp_path):
    """A real Ctrl-C to ``halfslip sweep`` in a subprocess, with 2 worker processes.

    The cases are made slow (1000 steps per cycle, ~1.5 s each) so that the
    signal comes while cases are left, even when this test process is starved
    by a loaded machine (at 400 steps per cycle the sweep once finished before
    the watcher saw two case files); its arrival is timed by the per-case
    files appearing in --cases-dir.
    """
    body = ("vary:\n  friction: [0.4, 0.5, 0.6, 0.7]\n  loads[1].cycles.Q.amplitude: [1.0e4, 2.0e4]\n"
            "set:\n  loads[1].cycles.steps_per_cycle: 1000\n")
    path = write_sweep(tmp_path, body)
    out, cases = tmp_path / "out.h5", tmp_path / "cases"
    command = [sys.executable, "-c", "from halfslip.cli import main; main()", "sweep", str(path), "-o", str(out), "--workers", "2",
               "--cases-dir", str(cases), "--quiet"]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               preexec_fn=as_from_a_terminal)
    deadline = time.monotonic() + 120
    while len(list(cases.glob("case_*.h5"))) < 2 and time.monotonic() < deadline and process.poll() is None:
        time.sleep(0.01)
    process.send_signal(signal.SIGINT)
    stdout, stderr = process.communicate(timeout=120)
    assert process.returncode == 130, stderr
    assert "interrupted;" in stderr and "Traceback" not in stderr
    partial = read_result(out)
    done = int(partial["done"].sum())
    assert 2 <= done < 8 and partial.attrs["complete"] == 0

    rerun = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert rerun.returncode == 0, rerun.stderr
    final = read_result(out)
    assert final.attrs["count_run"] == 8 - done and final.attrs["complete"] == 1
    assert len(list(cases.glob("case_*.h5"))) == 8
    reference = hs.sweep(path, workers=2, progress=False)
    xr.testing.assert_identical(summary(final), summary(reference))


def test_an_output_holding_another_sweep_is_refused(tmp_path, cli):
    out = tmp_path / "out.h5"
    one = write_sweep(tmp_path, "vary:\n  friction: [0.4, 0.6]\nper_cycle: false\n", "one.yaml")
    two = write_sweep(tmp_path, "vary:\n  friction: [0.4, 0.5]\nper_cycle: false\n", "two.yaml")
    hs.sweep(one, output=out, workers=1, progress=False)
    with pytest.raises(HalfslipInputError, match="holds a different sweep"):
        hs.sweep(two, output=out, workers=1, progress=False)
    result = cli("sweep", two, "-o", out)
    assert result.exit_code == 2
    assert result.stderr.startswith(f"halfslip: {out}: output: holds a different sweep (sweep_hash ")
    from halfslip.io import write_result

    write_result(read_result(out).drop_attrs(), tmp_path / "plain.h5")
    with pytest.raises(HalfslipInputError, match="is not a sweep result"):
        hs.sweep(one, output=tmp_path / "plain.h5", workers=1, progress=False)


def test_the_progress_line_counts_cases_and_time_left(monkeypatch):
    import io

    import tqdm.std

    from halfslip.sweep import _ProgressLine

    clock = [100.0]
    monkeypatch.setattr(tqdm.std, "time", lambda: clock[0])
    stream = io.StringIO()
    line = _ProgressLine(True, stream)
    line.start(10, 0)
    for done in (1, 2, 3):
        clock[0] += 2.0 / 3  # three cases in two seconds
        line(done, 1, 10, done)
    line.close()
    text = stream.getvalue()
    last = text.rstrip("\n").split("\r")[-1]
    assert "cases" in last and " 3/10 " in last and "1 failed" in last, last
    assert "1.50case/s" in last and "<00:04" in last, last  # 7 cases left at 1.5 cases/s: 4.7 s
    assert text.endswith("\n")
    quiet = io.StringIO()
    off = _ProgressLine(False, quiet)
    off.start(10, 0)
    off(3, 1, 10, 3)
    off.close()
    assert quiet.getvalue() == ""


# -- bad sweep files -------------------------------------------------------------

BAD = {
    "reserved_name": ("vary:\n  regime: {path: friction, values: [0.3]}\n", 3, "vary.regime",
                      "'regime' names a variable of the sweep result"),
    "bad_name": ("vary:\n  2f: {path: friction, values: [0.3]}\n", 3, "vary.2f", "a name is a word"),
    "named_unknown_path": ("vary:\n  f:\n    path: frcition\n    values: [0.3]\n", 4, "vary.f.path",
                           "unknown key 'frcition'"),
    "unknown_path": ("vary:\n  frcition: [0.3, 0.6]\n", 3, "vary.frcition", "unknown key 'frcition'; did you mean 'friction'?"),
    "non_list_values": ("vary:\n  friction: 0.5\n", 3, "vary.friction", "expected a list of values"),
    "bad_linspace": ("vary:\n  friction: {linspace: [0.1, 0.5]}\n", 3, "vary.friction.linspace",
                     "expected [start, stop, count], got 2 values"),
    "linspace_count": ("vary:\n  friction:\n    linspace: [0.1, 0.5, 2.5]\n", 4, "vary.friction.linspace[2]",
                       "must be an integer >= 1"),
    "missing_scene": ("vary:\n  friction: [0.5]\n", 1, "scene", "no such scene file"),
    "vary_and_cases": ("vary:\n  friction: [0.5]\ncases:\n  - {friction: 0.4}\n", 4, "cases", "not both"),
    "neither": ("per_cycle: true\n", 1, "vary", "give vary (a grid of values) or cases"),
    "no_such_item": ("vary:\n  loads[4].cycles.Q.amplitude: [1.0]\n", 3, "vary.loads[4].cycles.Q.amplitude",
                     "loads has 2 items; there is no item [4]"),
    "into_a_number": ("cases:\n  - {geometry.radius: 0.02}\n  - {friction.value: 0.3}\n", 4, "cases[1].friction.value",
                      "friction is the number 0.6, not a mapping"),
    "bad_path_syntax": ("vary:\n  loads.1.cycles: [1]\n", 3, "vary.loads.1.cycles", "is not a scene path"),
    "duplicate_value": ("vary:\n  friction:\n    - 0.3\n    - 0.30\n", 5, "vary.friction[1]", "listed twice"),
    "overlap": ("vary:\n  geometry: [{kind: hertz, radius: 0.1}]\n  geometry.radius: [0.2]\n", 4,
                "vary.geometry.radius", "overlaps 'geometry'"),
    "logspace_exponents": ("vary:\n  friction: {logspace: [-3, 0, 4]}\n", 3, "vary.friction.logspace",
                           "logspace takes the end values themselves"),
    "unknown_top_key": ("vary:\n  friction: [0.5]\nworkers: 3\n", 4, "workers", "unknown key 'workers'"),
    "flow_path_unquoted": ("cases:\n  - {loads[1].cycles.Q.amplitude: 1.0}\n", 3, None, "quote a path that has [i]"),
}


@pytest.mark.parametrize("name", sorted(BAD))
def test_a_bad_sweep_file_is_one_line_with_file_line_and_field(cli, tmp_path, name):
    body, line, field, message = BAD[name]
    if name == "missing_scene":
        path = tmp_path / "sweep.yaml"
        path.write_text(f"scene: nothere.yaml\n{body}")
    else:
        path = write_sweep(tmp_path, body)
    out = tmp_path / "out.h5"
    result = cli("sweep", path, "-o", out, "--workers", "1")
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.output and result.stdout == ""
    (text,) = result.stderr.splitlines()
    prefix = f"halfslip: {path}:{line}: " + (f"{field}: " if field else "")
    assert text.startswith(prefix), text
    assert message in text, text
    assert not out.exists()  # nothing ran, nothing written


def test_an_invalid_base_scene_names_the_scene_file(cli, tmp_path):
    scene = tmp_path / "scene.yaml"
    scene.write_text(HERTZ.read_text().replace("friction: 0.6", "friction: -0.6"))
    path = tmp_path / "sweep.yaml"
    path.write_text("scene: scene.yaml\nvary:\n  geometry.radius: [0.01]\n")
    result = cli("sweep", path)
    assert result.exit_code == 2
    line = scene.read_text().splitlines().index("friction: -0.6") + 1
    assert result.stderr.startswith(f"halfslip: {scene}:{line}: friction: must be >= 0")


def test_sweep_axes_have_short_names_given_or_derived_and_keep_their_path(tmp_path):
    """Dimensions are short names (xarray-friendly: ds.Q_amp.sel(...)); the scene path is an attribute."""
    body = ("vary:\n  Q_amp:\n    path: loads[1].cycles.Q.amplitude\n    linspace: [1.0e4, 2.0e4, 2]\n"
            "  geometry.radius: [0.05]\n")
    spec = parse_sweep(f"scene: {HERTZ}\n{body}", path=tmp_path / "s.yaml")
    assert spec.paths == (Q_PATH, "geometry.radius") and spec.names == ("Q_amp", "radius")
    ds = hs.sweep(spec, workers=1, progress=False)
    assert ds["done"].dims == ("Q_amp", "radius") and ds["Q_amp"].attrs["path"] == Q_PATH
    assert float(ds.Q_amp.sel(Q_amp=2.0e4)) == 2.0e4 and (ds["status"] == "ok").all()
    same = parse_sweep(f"scene: {HERTZ}\nvary:\n  Q_amp:\n    path: {Q_PATH}\n    values: [1.0e4, 2.0e4]\n"
                       "  geometry.radius: [0.05]\n")
    assert same.hash == spec.hash  # a name does not change what is computed: a result file continues
    cases = parse_sweep(f"scene: {HERTZ}\ncases:\n  - {{friction: 0.5, solver.method: exact}}\n")
    assert cases.names == ("friction", "solver_method")  # 'method' is a variable of the result


def test_sweep_errors_carry_the_field_for_python_callers(tmp_path):
    with pytest.raises(HalfslipInputError) as caught:
        parse_sweep(f"scene: {HERTZ}\nvary:\n  friction: []\n", path="s.yaml")
    assert (caught.value.file, caught.value.line, caught.value.field) == ("s.yaml", 3, "vary.friction")


# -- the dovetail example and pictures -------------------------------------------


def test_the_dovetail_example_maps_the_stick_zone(tmp_path):
    """Runs the whole example (44 direct SS1 cases, a few seconds)."""
    spec = load_sweep(EXAMPLES / "dovetail_sweep.yaml")
    assert spec.paths == (Q_PATH, "loads[1].cycles.sigma.amplitude") and spec.shape == (11, 4)
    assert spec.per_cycle is False  # direct cases only: the example stays quick
    ds = hs.sweep(spec, output=tmp_path / "dovetail.h5", workers=1, progress=False)
    assert (ds["status"] == "ok").all() and (ds["method"] == "steady: SS1").all()
    width = ds["permanent_stick_right"] - ds["permanent_stick_left"]
    # a larger shear range leaves a smaller permanent stick zone, at every tension range
    assert (width.diff(Q_NAME) < 0).all()
    assert (width > 0).all() and (ds["regime"] == 2).all()
    figure = plot_sweep(read_result(tmp_path / "dovetail.h5"), tmp_path / "map.png")
    assert (tmp_path / "map.png").stat().st_size > 10_000
    assert any(ax.collections for ax in figure.axes)  # pcolormesh maps


def test_plot_sweep_draws_curves_and_cases(tmp_path, grid_serial):
    path, serial = grid_serial
    figure = plot_sweep(serial.isel(friction=0))  # one dimension: curves
    assert len(figure.axes) == 4 and figure.axes[0].lines
    cases = hs.sweep(write_sweep(tmp_path, "cases:\n  - {friction: 0.5}\n  - {friction: 0.7}\n"),
                     workers=1, progress=False)
    figure = plot_sweep(cases, tmp_path / "cases.png")
    assert figure.axes[0].get_xlabel() == "case" and (tmp_path / "cases.png").exists()
    with pytest.raises(ValueError, match="not a sweep result"):
        plot_sweep(hs.steady_state(hs.load_scene(HERTZ), per_cycle=False))


def test_the_cli_writes_a_summary_and_warns_about_failures(cli, tmp_path):
    path = write_sweep(tmp_path, "vary:\n  friction: [0.6, -1.0]\nper_cycle: false\n")
    out = tmp_path / "out.h5"
    result = cli("sweep", path, "-o", out, "--workers", "1")
    assert result.exit_code == 0, result.output
    assert "2 cases over friction" in result.stdout and "1 ok, 1 failed" in result.stdout
    assert result.stderr.startswith("halfslip: warning: 1 of 2 cases failed")
    assert read_result(out).attrs["count_done"] == 2

