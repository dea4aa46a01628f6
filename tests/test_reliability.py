"""Interrupted runs, resume, reproducibility (issue: reliability)."""
from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest
import xarray as xr
from helpers import LONG_MOTOR_SCENE, as_from_a_terminal

LONG_SCENE = LONG_MOTOR_SCENE


def run_cli(*args, **kwargs):
    return subprocess.run([sys.executable, "-m", "halfslip.cli", *args], capture_output=True, text=True, **kwargs)


def start_cli(*args):
    return subprocess.Popen([sys.executable, "-m", "halfslip.cli", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, preexec_fn=as_from_a_terminal)


SKIPPED_ATTRIBUTES = {
    "wall_time",  # the run's wall-clock time: the one timestamp-like value
    "DIMENSION_LIST", "REFERENCE_LIST",  # HDF5 object references: addresses, compared via the names below
}


def h5_contents(path):
    """Every dataset's bytes and dimensions, every attribute except the wall-clock time."""
    out = {}
    with h5py.File(path, "r") as f:
        def visit(name, obj):
            if isinstance(obj, h5py.Dataset):
                out[name] = obj[()].tobytes()
                out[f"{name}#dims"] = tuple(tuple(s.name for s in d.values()) for d in obj.dims)
            for k, v in obj.attrs.items():
                if k not in SKIPPED_ATTRIBUTES:
                    out[f"{name}@{k}"] = np.asarray(v).tobytes()
        f.visititems(visit)
        for k, v in f.attrs.items():
            if k not in SKIPPED_ATTRIBUTES:
                out[f"@{k}"] = np.asarray(v).tobytes()
    return out


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    folder = tmp_path_factory.mktemp("ref")
    scene = folder / "long.yaml"
    scene.write_text(LONG_SCENE)
    out = folder / "ref.h5"
    done = run_cli("run", str(scene), "-o", str(out), "--quiet")
    assert done.returncode == 0, done.stderr
    return scene, out


def test_same_scene_gives_bit_identical_files(reference, tmp_path):
    scene, ref = reference
    again = tmp_path / "again.h5"
    assert run_cli("run", str(scene), "-o", str(again), "--quiet").returncode == 0
    assert h5_contents(again) == h5_contents(ref)
    with xr.open_dataset(ref) as ds:
        import hashlib
        assert ds.attrs["scene_sha256"] == hashlib.sha256(scene.read_text().encode()).hexdigest()
        assert ds.attrs["complete"] == 1


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGKILL])
def test_interrupt_then_resume_equals_uninterrupted_run(reference, tmp_path, sig):
    scene, ref = reference
    out = tmp_path / "cut.h5"
    rng = random.Random(1234 + int(sig))
    proc = start_cli("run", str(scene), "-o", str(out), "--checkpoint-every", "0.1", "--quiet")
    # wait until the first partial file exists, then cut at a random later point
    deadline = time.time() + 60
    while not out.exists() and time.time() < deadline:
        time.sleep(0.05)
    assert out.exists(), "the run never wrote its file"
    time.sleep(rng.uniform(0.2, 1.0))
    proc.send_signal(sig)
    proc.wait(timeout=60)
    if sig == signal.SIGINT:
        assert proc.returncode == 130, proc.stderr.read()
    else:
        assert proc.returncode == -signal.SIGKILL
    with xr.open_dataset(out) as ds:  # the file stays readable
        assert ds.attrs["complete"] == 0
        n_cut = ds.sizes["t"]
    with xr.open_dataset(ref) as full:
        assert n_cut < full.sizes["t"], "interrupt came too late to test anything"
    resumed = run_cli("run", str(scene), "-o", str(out), "--resume", "--quiet")
    assert resumed.returncode == 0, resumed.stderr
    assert h5_contents(out) == h5_contents(ref)


def test_resume_of_a_finished_run_is_a_clean_error(reference, tmp_path):
    scene, ref = reference
    copy = tmp_path / "copy.h5"
    copy.write_bytes(ref.read_bytes())
    done = run_cli("run", str(scene), "-o", str(copy), "--resume")
    assert done.returncode == 2
    assert "nothing to resume" in done.stderr and "Traceback" not in done.stderr
