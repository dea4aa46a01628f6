"""Hostile result files, output paths and interrupts (issue 13, the run side).

Every bad input here is handed to the real command in a subprocess under a
memory limit (RLIMIT_AS 2 GiB: a run of these scenes needs about 400 MiB, so a
refusal that allocated the crafted sizes would die instead of answering) and
a time limit, and must end in exit status 2, one line on stderr naming the
file, no traceback, and no code executed (a canary file stays absent).
"""
from __future__ import annotations

import glob
import json
import os
import pickle
import random
import resource
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import h5py
import numpy as np
import pytest
import xarray as xr

import halfslip as hs
from helpers import LONG_MOTOR_SCENE, as_from_a_terminal
from halfslip import io
from halfslip.simulator import simulate

MEMORY_LIMIT = 2 * 2**30
TIME_LIMIT = 120  # s; every refusal here takes under 5 s on the CI machine, a run under 20 s

SCENE = (LONG_MOTOR_SCENE.replace("long-motor", "hostile-target")
         .replace("solver: {skip_steady_cycles: false}", "solver: {method: general, nodes: 64, skip_steady_cycles: false}")
         .replace("output: {fields: [p, q, slip], points: 81}", "output: {fields: [p, q], points: 41}"))
#: The general solver on a long history: minutes of marching, so that a run is still going when
#: it is interrupted or a second run starts; its checkpoint holds arrays (the locked-in strains).
SHORT_SCENE = SCENE.replace("count: 40", "count: 2").replace("steps_per_cycle: 400", "steps_per_cycle: 40")


def _limits():
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))
    as_from_a_terminal()


def start(*args):
    """Start a halfslip command as a terminal user would (console script, SIGINT not ignored)."""
    return subprocess.Popen([*console_script(), *map(str, args)], stderr=subprocess.PIPE, text=True,
                            preexec_fn=as_from_a_terminal)


def finish(proc):
    """stderr of ``proc`` once it ends; killed (and the test failed) if it outlives the time limit."""
    try:
        return proc.communicate(timeout=TIME_LIMIT)[1]
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.communicate()
        raise


def halfslip(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "halfslip", *map(str, args)], capture_output=True, text=True,
                          timeout=TIME_LIMIT, preexec_fn=_limits, cwd=cwd)


def assert_clean_refusal(done, file, *words):
    """Exit 2, one line 'halfslip: FILE...' on stderr, no traceback, with ``words`` in it."""
    lines = done.stderr.splitlines()
    assert done.returncode == 2, done.stderr
    assert len(lines) == 1, done.stderr
    assert lines[0].startswith(f"halfslip: {file}"), lines[0]
    assert "Traceback" not in done.stderr + done.stdout
    for word in words:
        assert word in lines[0], lines[0]


@pytest.fixture(scope="module")
def unfinished(tmp_path_factory):
    """A scene file and an unfinished run file of it with a checkpoint (stopped after 30 steps)."""
    folder = tmp_path_factory.mktemp("unfinished")
    scene_file = folder / "scene.yaml"
    scene_file.write_text(SHORT_SCENE)
    scene = hs.load_scene(scene_file)
    out = folder / "cut.h5"
    calls = []
    ds = simulate(scene, writer=io.RunFileWriter(out, min_interval=1e9),
                  stop_requested=lambda: calls.append(1) or len(calls) > 30)
    assert ds.attrs["complete"] == 0
    return scene_file, out


def crafted(unfinished, tmp_path, edit):
    """A copy of the unfinished run file, changed by ``edit(h5py.File)``."""
    scene_file, source = unfinished
    target = tmp_path / "crafted.h5"
    target.write_bytes(source.read_bytes())
    with h5py.File(target, "a") as f:
        edit(f)
    return scene_file, target


def set_tree(f, tree):
    f["checkpoint"].attrs["tree"] = json.dumps(tree) if not isinstance(tree, str) else tree


def canary_command(canary: Path) -> str:
    return f"touch {canary}"


def pickled_command(canary: Path) -> bytes:
    """A pickle that runs ``touch canary`` when unpickled."""

    class Payload:
        def __reduce__(self):
            return (os.system, (canary_command(canary),))

    return pickle.dumps(Payload())


# -- the original defect and its relatives: names that would reach code -----------------------

def _routes(canary: Path):
    """Tree edits that would run ``touch canary`` on a decoder that resolved names."""
    command = canary_command(canary)
    return {
        # the reported route: a module-qualified name followed by attributes (old format's key)
        "module-qualified name": lambda t: {"__namedtuple__": "halfslip.io:os.system", "items": [command]},
        "record kind naming a module": lambda t: {"record": "halfslip.io:os.system", "items": [command]},
        "record kind with an attribute chain": lambda t: {"record": "ContactState.__init__.__globals__",
                                                          "items": [command]},
        "record kind naming a builtin": lambda t: {"record": "eval", "items": [f"__import__('os').system('{command}')"]},
        "dunder record fields": lambda t: {"record": "Loads", "fields": {"__class__": command}},
        "enum route of the old format": lambda t: {"__enum__": "halfslip.io:os.system", "value": command},
        "dataclass of the old format": lambda t: {"__dataclass__": "subprocess:Popen", "fields": {"args": command}},
    }


@pytest.mark.parametrize("route", sorted(_routes(Path("x"))))
def test_checkpoint_names_never_reach_code(unfinished, tmp_path, route):
    canary = tmp_path / "canary"
    edit = _routes(canary)[route]

    def replace_state(f):
        tree = json.loads(f["checkpoint"].attrs["tree"])
        tree["dict"] = [[k, edit(v) if k == "state" else v] for k, v in tree["dict"]]
        set_tree(f, tree)

    scene_file, target = crafted(unfinished, tmp_path, replace_state)
    done = halfslip("run", scene_file, "-o", target, "--resume", "--quiet")
    assert_clean_refusal(done, target, "--resume", "checkpoint")
    assert not canary.exists()


def test_a_pickle_is_never_unpickled(unfinished, tmp_path):
    canary = tmp_path / "canary"
    blob = np.frombuffer(pickled_command(canary), dtype=np.uint8)

    def add_pickles(f):
        f["checkpoint"].attrs["tree"] = np.void(blob.tobytes())  # the tree itself a pickle
        f["checkpoint"].create_dataset("pickle", data=np.void(blob.tobytes()))  # and an opaque dataset
        f.attrs["pickle"] = np.void(blob.tobytes())

    scene_file, target = crafted(unfinished, tmp_path, add_pickles)
    done = halfslip("run", scene_file, "-o", target, "--resume", "--quiet")
    assert_clean_refusal(done, target, "--resume")
    assert not canary.exists()


def test_pickles_in_plain_arrays_stay_numbers(unfinished, tmp_path):
    """A pickle stored as bytes in a numeric array is decoded as numbers, never loaded."""
    scene_file, source = unfinished
    with h5py.File(source, "r") as f:
        tree = json.loads(f["checkpoint"].attrs["tree"])
    canary = tmp_path / "canary"
    payload = np.frombuffer(pickled_command(canary), dtype=np.uint8)

    def swap_array(f):
        del f["checkpoint/a0"]
        f["checkpoint"].create_dataset("a0", data=payload)
        set_tree(f, tree)

    scene_file, target = crafted(unfinished, tmp_path, swap_array)
    checkpoint = io.read_checkpoint(target)  # in-process: the decoder returns data or refuses
    assert checkpoint is not None
    assert not canary.exists()
    done = halfslip("run", scene_file, "-o", target, "--resume", "--quiet")
    assert done.returncode in (0, 2) and "Traceback" not in done.stderr
    assert not canary.exists()


def _hdf5_routes(tmp_path):
    other = tmp_path / "elsewhere.h5"
    with h5py.File(other, "w") as g:
        g["a0"] = np.zeros(3)
    raw = tmp_path / "raw.bin"
    raw.write_bytes(b"\0" * 800)

    def reference(f):
        f["checkpoint"].create_dataset("refs", data=[f["checkpoint"].ref], dtype=h5py.ref_dtype)

    def region_reference(f):
        f["checkpoint"].create_dataset("regions", data=[f["t"].regionref[0:1]], dtype=h5py.regionref_dtype)

    def external_link(f):
        del f["checkpoint/a0"]
        f["checkpoint/a0"] = h5py.ExternalLink(str(other), "a0")

    def soft_link(f):
        del f["checkpoint/a0"]
        f["checkpoint/a0"] = h5py.SoftLink("/t")

    def external_storage(f):
        del f["checkpoint/a0"]
        f["checkpoint"].create_dataset("a0", shape=(100,), dtype="f8", external=[(str(raw), 0, 800)])

    def virtual(f):
        layout = h5py.VirtualLayout(shape=(3,), dtype="f8")
        layout[:] = h5py.VirtualSource(str(other), "a0", shape=(3,))
        del f["checkpoint/a0"]
        f["checkpoint"].create_virtual_dataset("a0", layout)

    def whole_group_elsewhere(f):
        del f["checkpoint"]
        f["checkpoint"] = h5py.ExternalLink(str(other), "/")

    def oversized_array(f):  # 2**31 float64 = 16 GiB when read, a few kB on disk
        del f["checkpoint/a0"]
        f["checkpoint"].create_dataset("a0", shape=(2**31,), dtype="f8", chunks=(2**20,), compression="gzip",
                                       fillvalue=1.0)

    def oversized_variable(f):  # the same in the main dataset, which is read before the checkpoint
        f.create_dataset("ballast", shape=(2**31,), dtype="f8", chunks=(2**20,), compression="gzip")

    def object_strings(f):
        f["checkpoint"].create_dataset("a0x", data=np.array([b"x"], dtype=object), dtype=h5py.string_dtype())

    def deep_tree(f):
        set_tree(f, "[" * 200_000 + "]" * 200_000)

    def huge_tree(f):
        set_tree(f, json.dumps({"list": [0] * 3_000_000}))

    def wrong_format(f):
        f["checkpoint"].attrs["format"] = "halfslip-checkpoint-1"

    def no_format(f):
        del f["checkpoint"].attrs["format"]

    def tree_not_text(f):
        f["checkpoint"].attrs["tree"] = np.arange(10)

    return {name: fn for name, fn in locals().items() if callable(fn) and name not in ("other", "raw")}


@pytest.mark.parametrize("route", [
    "reference", "region_reference", "external_link", "soft_link", "external_storage", "virtual",
    "whole_group_elsewhere", "oversized_array", "oversized_variable", "object_strings", "deep_tree",
    "huge_tree", "wrong_format", "no_format", "tree_not_text"])
def test_crafted_hdf5_is_refused(unfinished, tmp_path, route):
    edit = _hdf5_routes(tmp_path)[route]
    scene_file, target = crafted(unfinished, tmp_path, edit)
    done = halfslip("run", scene_file, "-o", target, "--resume", "--quiet")
    assert_clean_refusal(done, target, "--resume")


def _structure_routes():
    def entry(tree, key):
        return next(v for k, v in tree["dict"] if k == key)

    def set_entry(tree, key, value):
        tree["dict"] = [[k, value if k == key else v] for k, v in tree["dict"]]

    def step_out_of_range(tree):
        set_entry(tree, "i", 10**12)

    def negative_step(tree):
        set_entry(tree, "i", -5)

    def state_not_a_state(tree):
        set_entry(tree, "state", {"list": [1, 2, 3]})

    def missing_entry(tree):
        tree["dict"] = [[k, v] for k, v in tree["dict"] if k != "counters"]

    def extra_record_field(tree):
        state = entry(tree, "state")
        state["fields"]["extra"] = None

    def wrong_item_count(tree):
        entry(tree, "state")["fields"]["loads"]["items"].append(1)

    def memory_of_the_other_method(tree):
        entry(tree, "state")["fields"]["memory"] = {"record": "Loads", "items": [1, 2, 3, 4]}

    def bad_dtype(tree):
        node = entry(tree, "state")["fields"]["memory"]
        for value in node["fields"].values():
            if isinstance(value, dict) and "array" in value:
                value["dtype"] = "|O"
                return
        raise AssertionError("no array in the memory")

    def array_index_out_of_range(tree):
        node = entry(tree, "state")["fields"]["memory"]
        for value in node["fields"].values():
            if isinstance(value, dict) and "array" in value:
                value["array"] = 10**9
                return
        raise AssertionError("no array in the memory")

    def float_not_a_number(tree):
        set_entry(tree, "elapsed", {"float": "__import__('os')"})

    def unhashable_key(tree):
        set_entry(tree, "counters", {"dict": [[[1], 2]]})

    def big_integer(tree):
        set_entry(tree, "i", 10**400)

    def state_at_another_time(tree):
        entry(tree, "state")["fields"]["t"] = {"float": "1e300"}

    return {name: fn for name, fn in locals().items() if callable(fn) and name not in ("entry", "set_entry")}


@pytest.mark.parametrize("route", sorted(_structure_routes()))
def test_checkpoint_structure_is_checked(unfinished, tmp_path, route):
    def edit(f):
        tree = json.loads(f["checkpoint"].attrs["tree"])
        _structure_routes()[route](tree)
        set_tree(f, tree)

    scene_file, target = crafted(unfinished, tmp_path, edit)
    done = halfslip("run", scene_file, "-o", target, "--resume", "--quiet")
    assert_clean_refusal(done, target, "--resume")


def test_the_untouched_file_still_resumes(unfinished, tmp_path):
    """The refusals above are not a refusal of everything: the file as written resumes."""
    scene_file, target = crafted(unfinished, tmp_path, lambda f: None)
    done = halfslip("run", scene_file, "-o", target, "--resume", "--quiet")
    assert done.returncode == 0, done.stderr
    with xr.open_dataset(target) as ds:
        assert ds.attrs["complete"] == 1


def test_a_file_from_before_the_shear_estimate_resumes(unfinished, tmp_path):
    """A 0.3.0 run file has no per-step shear_error_estimate (added in 0.3.1): it resumes, the steps
    it stored get NaN there (nothing was estimated), the steps marched after the resume a value."""
    scene_file, target = crafted(unfinished, tmp_path, lambda f: f.__delitem__("shear_error_estimate"))
    with xr.open_dataset(target) as ds:
        assert "shear_error_estimate" not in ds
        stored = ds.sizes["t"]
    done = halfslip("run", scene_file, "-o", target, "--resume", "--quiet")
    assert done.returncode == 0, done.stderr
    with xr.open_dataset(target) as ds:
        assert ds.attrs["complete"] == 1
        estimate = ds["shear_error_estimate"].values
        assert np.all(np.isnan(estimate[:stored])) and np.all(np.isfinite(estimate[stored:]))


def test_another_scenes_file_is_refused_before_its_checkpoint_is_read(unfinished, tmp_path):
    scene_file, target = crafted(unfinished, tmp_path, lambda f: set_tree(f, "not json"))
    other = tmp_path / "other.yaml"
    other.write_text(SHORT_SCENE.replace("hostile-target", "another"))
    done = halfslip("run", other, "-o", target, "--resume", "--quiet")
    assert_clean_refusal(done, target, "different scene")


def test_encoding_refuses_what_it_could_not_read_back():
    class Stranger:
        pass

    with pytest.raises(TypeError):
        io.encode_tree({"x": Stranger()}, [])
    with pytest.raises(TypeError):
        io.encode_tree(np.array([object()], dtype=object), [])


# -- output paths ------------------------------------------------------------------------------

@pytest.fixture
def quick_scene(tmp_path):
    scene = tmp_path / "quick.yaml"
    scene.write_text(SHORT_SCENE.replace("count: 2", "count: 1").replace("method: general", "method: auto"))
    return scene


def test_output_naming_the_scene_keeps_the_scene(quick_scene):
    before = quick_scene.read_bytes()
    done = halfslip("run", quick_scene, "-o", quick_scene)
    assert_clean_refusal(done, quick_scene, "input")
    assert quick_scene.read_bytes() == before


def test_output_naming_a_load_table_keeps_it(tmp_path):
    table = tmp_path / "loads.csv"
    table.write_text("t,P,Q\n0.5,1.0e5,1.0e4\n1.0,1.0e5,2.0e4\n")
    scene = tmp_path / "table.yaml"
    scene.write_text(textwrap.dedent("""
        name: table
        material: {E: 200.0e9, nu: 0.3}
        friction: 0.6
        geometry: {kind: hertz, radius: 50.0e-3}
        loads:
          - table: {file: loads.csv}
    """))
    before = table.read_bytes()
    done = halfslip("run", scene, "-o", table)
    assert_clean_refusal(done, table, "input")
    assert table.read_bytes() == before


def test_output_naming_a_profile_keeps_it(tmp_path):
    profile = tmp_path / "profile.csv"
    x = np.linspace(-1e-3, 1e-3, 41)
    profile.write_text("x,h\n" + "".join(f"{float(a)!r},{float(a * a / 0.1)!r}\n" for a in x))
    scene = tmp_path / "profile.yaml"
    scene.write_text(textwrap.dedent("""
        name: profile
        material: {E: 200.0e9, nu: 0.3}
        friction: 0.6
        geometry: {kind: profile, file: profile.csv}
        loads:
          - ramp: {to: {P: 1.0e4, Q: 1.0e3}, duration: 1.0, steps: 4}
    """))
    before = profile.read_bytes()
    done = halfslip("run", scene, "-o", profile)
    assert_clean_refusal(done, profile, "input")
    assert profile.read_bytes() == before


@pytest.mark.parametrize("where", ["folder", "proc", "missing folder"])
def test_unwritable_outputs_fail_before_computing(quick_scene, tmp_path, where):
    target = {"folder": tmp_path, "proc": Path("/proc/halfslip-x.h5"),
              "missing folder": tmp_path / "nowhere" / "x.h5"}[where]
    started = time.perf_counter()
    done = halfslip("run", quick_scene, "-o", target)
    assert_clean_refusal(done, target, "-o")
    assert not glob.glob(str(tmp_path / ".*.partial"))
    assert time.perf_counter() - started < 60


def test_a_file_that_is_not_a_result_is_kept_unless_overwrite(quick_scene, tmp_path):
    precious = tmp_path / "thesis.h5"
    precious.write_text("years of work\n")
    done = halfslip("run", quick_scene, "-o", precious, "--quiet")
    assert_clean_refusal(done, precious, "--overwrite")
    assert precious.read_text() == "years of work\n"
    done = halfslip("run", quick_scene, "-o", precious, "--quiet", "--overwrite")
    assert done.returncode == 0, done.stderr
    with xr.open_dataset(precious) as ds:
        assert ds.attrs["complete"] == 1


def test_an_hdf5_file_of_another_program_is_kept(quick_scene, tmp_path):
    foreign = tmp_path / "foreign.h5"
    with h5py.File(foreign, "w") as f:
        f["data"] = np.arange(5)
    before = foreign.read_bytes()
    done = halfslip("steady", quick_scene, "-o", foreign)
    assert_clean_refusal(done, foreign, "not a halfslip result")
    assert foreign.read_bytes() == before


def test_a_halfslip_result_is_replaced_and_steady_says_where(quick_scene, tmp_path):
    out = tmp_path / "steady.h5"
    first = halfslip("steady", quick_scene, "-o", out)
    assert first.returncode == 0, first.stderr
    again = halfslip("steady", quick_scene, "-o", out)
    assert again.returncode == 0, again.stderr
    assert f"written to {out}" in again.stdout


def test_two_runs_on_one_output_the_second_is_refused(tmp_path):
    scene = tmp_path / "scene.yaml"
    scene.write_text(SCENE)
    out = tmp_path / "shared.h5"
    first = start("run", scene, "-o", out, "--quiet")
    try:
        deadline = time.time() + 60
        while not out.exists() and time.time() < deadline:
            time.sleep(0.05)
        assert out.exists(), "the first run never wrote"
        second = halfslip("run", scene, "-o", out, "--quiet")
        assert_clean_refusal(second, out, "another halfslip process")
    finally:
        first.send_signal(signal.SIGINT)
        first.wait(timeout=60)
    assert first.returncode == 130
    assert not glob.glob(str(tmp_path / ".shared.h5*"))


# -- command-line options ----------------------------------------------------------------------

@pytest.mark.parametrize("args, field", [
    (["steady", "{scene}", "--segment", "99"], "--segment"),
    (["steady", "{scene}", "--segment", "-1"], "--segment"),
    (["steady", "{scene}", "--segment", "0"], "loads[0]"),
    (["run", "{scene}", "--checkpoint-every", "nan"], "--checkpoint-every"),
    (["run", "{scene}", "--checkpoint-every", "inf"], "--checkpoint-every"),
    (["run", "{scene}", "--checkpoint-every", "0"], "--checkpoint-every"),
    (["run", "--checkpoint-every", "-1", "{scene}"], "--checkpoint-every"),
    (["run", "{scene}", "--nodes", "3"], "--nodes"),
    (["run", "{scene}", "--method", "magic"], "--method"),
    (["run", "{scene}", "--no-such-option"], "No such option"),
])
def test_bad_options_give_one_line_naming_the_scene(quick_scene, args, field):
    done = halfslip(*[a.format(scene=quick_scene) for a in args])
    assert_clean_refusal(done, quick_scene, field)


def test_usage_errors_without_a_file_are_one_line_too():
    for args in (["run"], ["frobnicate"], ["plot", "--kind"]):
        done = halfslip(*args)
        assert done.returncode == 2, done.stderr
        assert len(done.stderr.splitlines()) == 1 and done.stderr.startswith("halfslip: "), done.stderr


def test_h_is_help():
    done = halfslip("run", "-h")
    assert done.returncode == 0 and "--resume" in done.stdout


# -- interrupts --------------------------------------------------------------------------------

def console_script() -> list[str]:
    """The installed ``halfslip`` script (it handles start-up interrupts), run by this Python."""
    script = Path(sys.executable).with_name("halfslip")
    if script.is_file() and script.read_bytes()[:2] == b"#!":
        return [sys.executable, str(script)]
    return [sys.executable, "-c", "import halfslip_launch; halfslip_launch.main()"]


def no_temporaries(folder: Path) -> bool:
    return not glob.glob(str(folder / ".*.partial"))


def valid_or_absent(out: Path) -> str:
    """'absent', 'incomplete' or 'complete'; fails on a file that does not open."""
    if not out.exists():
        return "absent"
    with xr.open_dataset(out) as ds:
        return "complete" if ds.attrs["complete"] else "incomplete"


@pytest.fixture(scope="module")
def interpreter_start_up():
    """Seconds this Python takes to start (site and .pth files) before any halfslip code runs."""
    times = []
    for _ in range(3):
        started = time.perf_counter()
        subprocess.run([sys.executable, "-c", "pass"], check=True)
        times.append(time.perf_counter() - started)
    return max(times)


@pytest.mark.parametrize("delay", [0.05, 0.3, 0.6, 0.9])
def test_ctrl_c_during_start_up(tmp_path, delay, interpreter_start_up):
    """Interpreter start-up belongs to Python; from the first line of halfslip on it is one line.

    The interrupt comes ``delay`` after the interpreter's own start-up time (measured); where the
    machine was slower than measured and it still landed in the interpreter's start-up (Python's
    'init_import_site' failure), it is sent again later, at most twice.
    """
    scene = tmp_path / "scene.yaml"
    scene.write_text(SCENE)
    out = tmp_path / "out.h5"
    for retry in range(3):
        proc = start("run", scene, "-o", out, "--quiet")
        time.sleep(interpreter_start_up + delay + 0.2 * retry)
        proc.send_signal(signal.SIGINT)
        err = finish(proc)
        if "Fatal Python error" not in err:  # it landed in the interpreter's own start-up
            break
    assert proc.returncode == 130, err
    assert len(err.splitlines()) == 1 and err.startswith("halfslip: ") and "Traceback" not in err, err
    assert valid_or_absent(out) in ("absent", "incomplete")
    assert no_temporaries(tmp_path)


@pytest.mark.parametrize("gap", [0.05, 0.2, 0.6])
def test_double_ctrl_c(tmp_path, gap):
    scene = tmp_path / "scene.yaml"
    scene.write_text(SCENE)
    out = tmp_path / "out.h5"
    proc = start("run", scene, "-o", out, "--quiet", "--checkpoint-every", "0.1")
    deadline = time.time() + 60
    while not out.exists() and time.time() < deadline:
        time.sleep(0.02)
    proc.send_signal(signal.SIGINT)
    time.sleep(gap)
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
    err = finish(proc)
    assert proc.returncode == 130, err
    assert "Traceback" not in err and "Exception" not in err and len(err.splitlines()) <= 2, err
    assert valid_or_absent(out) == "incomplete"
    assert no_temporaries(tmp_path)


def test_sigkill_with_checkpoints_leaves_a_valid_file_or_none(tmp_path):
    """Killed at random times: the file is absent or a valid unfinished run that resumes.

    A temporary can outlive a SIGKILL only when the kill lands in the byte copy of a
    write (a few ms per checkpoint); the next run on the output removes it.
    """
    scene = tmp_path / "scene.yaml"
    scene.write_text(SCENE.replace("method: general", "method: exact"))  # 16,000 steps in a few seconds
    rng = random.Random(13)
    for attempt in range(3):
        out = tmp_path / f"killed{attempt}.h5"
        proc = start("run", scene, "-o", out, "--quiet", "--checkpoint-every", "0.1")
        time.sleep(rng.uniform(0.8, 2.0))
        proc.kill()
        proc.wait(timeout=60)
        state = valid_or_absent(out)
        assert state in ("absent", "incomplete")
        done = halfslip("run", scene, "-o", out, "--quiet", *(["--resume"] if state == "incomplete" else []))
        assert done.returncode == 0, done.stderr
        assert valid_or_absent(out) == "complete"
        assert no_temporaries(tmp_path)


# -- halfslip plot on untrusted files --------------------------------------------------------

def test_plot_never_writes_over_the_result(unfinished, tmp_path):
    scene_file, source = unfinished
    target = tmp_path / "run.h5"
    target.write_bytes(source.read_bytes())
    before = target.read_bytes()
    for out in (target, tmp_path / "figure.h5"):
        done = halfslip("plot", target, "-o", out)
        assert_clean_refusal(done, out, "-o")
    assert target.read_bytes() == before


@pytest.mark.parametrize("route", ["oversized_variable", "external_link", "reference"])
def test_plot_refuses_crafted_files(unfinished, tmp_path, route):
    edit = _hdf5_routes(tmp_path)[route]
    _, target = crafted(unfinished, tmp_path, edit)
    done = halfslip("plot", target, "-o", tmp_path)
    if route == "reference":  # a reference dataset in the checkpoint group
        assert_clean_refusal(done, target, "neither numbers nor text")
    else:
        assert_clean_refusal(done, target, "not a halfslip result")


def test_in_process_commands_leave_the_signal_handlers_alone(cli, tmp_path):
    """Only the program (console script, python -m) ignores interrupts on its way out; a caller of
    ``main`` in its own process (CliRunner, a notebook) keeps its handlers."""
    before = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}
    cli("validate", tmp_path / "missing.yaml")
    cli("frobnicate")
    assert {sig: signal.getsignal(sig) for sig in before} == before


_CALLBACK_INTERRUPT = """
import sys, time, weakref
if sys.argv[1] == "hook":
    import halfslip_launch
    sys.unraisablehook = halfslip_launch._record_interrupts
class Held:
    pass
held = Held()
def callback(ref):
    raise KeyboardInterrupt  # as a Ctrl-C that lands in a callback (the import system's module locks)
ref = weakref.ref(held, callback)
try:
    del held
    for _ in range(200):
        time.sleep(0.001)
    print("recorded" if sys.argv[1] == "hook" and halfslip_launch._lost else "carried on")
except KeyboardInterrupt:
    print("raised")
"""


@pytest.mark.parametrize("hook", ["hook", "python"])
def test_an_interrupt_inside_a_callback_is_not_lost(hook):
    """Python prints a KeyboardInterrupt raised inside a callback as 'Exception ignored' and carries on
    (a Ctrl-C 0.3 s into start-up once finished the run with status 0); while the command imports, its
    hook records it silently, and the command then ends as interrupted. The 'python' case shows what
    happens without the hook, so that the test can fail."""
    done = subprocess.run([sys.executable, "-c", _CALLBACK_INTERRUPT, hook], capture_output=True, text=True,
                          timeout=60)
    if hook == "hook":
        assert done.stdout.strip() == "recorded", done.stderr
        assert done.stderr == ""
    else:
        assert done.stdout.strip() == "carried on"
        assert "KeyboardInterrupt" in done.stderr


_CONVERTED_INTERRUPT = """
import os, signal, sys
sys.path.insert(0, sys.argv[1])  # a stand-in halfslip whose cli import meets a Ctrl-C
sys.modules.pop("halfslip", None)
import halfslip_launch
halfslip_launch.main()
print("ran on")
"""

_FAKE_CLI = """
import os, signal
try:
    os.kill(os.getpid(), signal.SIGINT)  # a Ctrl-C inside an extension's import ...
    for _ in range(1000):
        pass
except KeyboardInterrupt:
    # ... which turns it into an ImportError, as PyCapsule_Import did for numpy's datetime
    raise ImportError('PyCapsule_Import could not import module "datetime"')


def run_as_program():
    print("ran")
"""


def test_an_interrupt_turned_into_an_import_error_ends_as_interrupted(tmp_path):
    """A Ctrl-C inside an extension module's import can come out as an ImportError (numpy importing
    datetime; once in about a dozen tries 0.3 s into start-up: a traceback, status 1). The launcher
    records the signal and ends as interrupted: one line, status 130. Without a signal the same
    ImportError is the error it is (the second case)."""
    fake = tmp_path / "fake"
    (fake / "halfslip").mkdir(parents=True)
    (fake / "halfslip" / "__init__.py").write_text("")
    (fake / "halfslip" / "cli.py").write_text(_FAKE_CLI)
    launcher = str(Path(__file__).resolve().parents[1] / "src")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in (launcher, os.environ.get("PYTHONPATH")) if p))
    done = subprocess.run([sys.executable, "-c", _CONVERTED_INTERRUPT, str(fake)], capture_output=True, text=True,
                          timeout=60, env=env)
    assert done.returncode == 130, done.stderr
    assert done.stderr == "halfslip: interrupted\n"
    assert done.stdout == ""
    (fake / "halfslip" / "cli.py").write_text("raise ImportError('a real one')\n")
    done = subprocess.run([sys.executable, "-c", _CONVERTED_INTERRUPT, str(fake)], capture_output=True, text=True,
                          timeout=60, env=env)
    assert done.returncode == 1 and "ImportError: a real one" in done.stderr
