"""Figures (halfslip.plot) and the ``halfslip plot`` command."""
from __future__ import annotations

import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import halfslip as hs
from halfslip import plot, post
from halfslip.errors import HalfslipInputError
from halfslip.io import read_result, write_result

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _general_available() -> bool:
    try:
        import halfslip.solvers.general  # noqa: F401
    except Exception:
        return False
    return True


RUNNABLE = [
    pytest.param("hertz_pad", id="hertz_pad"),
    pytest.param("motor", id="motor"),
    # 33 steps, but the tabulated profile's normal problem takes minutes on a loaded machine
    pytest.param("tabulated", id="tabulated", marks=pytest.mark.slow),
    pytest.param("dovetail", id="dovetail", marks=[
        pytest.mark.skipif(not _general_available(), reason="halfslip.solvers.general does not import yet"),
        pytest.mark.slow,  # 2050 general-solver steps: tens of minutes
    ]),
]


def png_size(path: Path) -> tuple[int, int]:
    """Width and height from a PNG's IHDR chunk; raises if the file is not a PNG."""
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", f"{path} lacks the PNG signature"
    assert data[12:16] == b"IHDR", f"{path}: first chunk is not IHDR"
    assert data[-8:-4] == b"IEND", f"{path} is truncated"
    return struct.unpack(">II", data[16:24])


def check_png(path: Path) -> None:
    width, height = png_size(path)
    assert width > 300 and height > 300, (path, width, height)
    assert path.stat().st_size > 10_000, (path, path.stat().st_size)


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    """Each runnable example run once and written, keyed by name (lazily)."""
    folder = tmp_path_factory.mktemp("runs")
    cache = {}

    def get(name):
        if name not in cache:
            ds = hs.simulate(hs.load_scene(EXAMPLES / f"{name}.yaml"))
            cache[name] = write_result(ds, folder / f"{name}.h5")
        return cache[name]

    return get


@pytest.mark.parametrize("example", RUNNABLE)
def test_every_kind_for_every_example_is_a_real_png(example, results, tmp_path):
    ds = read_result(results(example))
    paths = plot.plot_run(ds, tmp_path, kinds=None)
    assert [p.name for p in paths] == [f"{example}-{kind}.png" for kind in plot.KINDS]  # named after the file
    for path in paths:
        check_png(path)


def test_cli_writes_all_kinds_next_to_the_result(results, cli, tmp_path):
    source = results("hertz_pad")
    run = tmp_path / "pad.h5"
    run.write_bytes(source.read_bytes())
    outcome = cli("plot", run)
    assert outcome.exit_code == 0, outcome.stderr
    printed = [Path(line) for line in outcome.stdout.split()]
    assert printed == [tmp_path / f"pad-{kind}.png" for kind in plot.KINDS]
    for path in printed:
        check_png(path)


def test_cli_output_file_folder_kind_and_instants(results, cli, tmp_path):
    run = results("motor")
    one = cli("plot", run, "-o", tmp_path / "loads.png", "--kind", "trajectory")
    assert one.exit_code == 0, one.stderr
    assert one.stdout.split() == [str(tmp_path / "loads.png")]
    check_png(tmp_path / "loads.png")
    two = cli("plot", run, "-o", tmp_path / "fig.png", "--kind", "map", "--kind", "tractions", "--at", "1.185,1.19")
    assert two.exit_code == 0, two.stderr
    assert two.stdout.split() == [str(tmp_path / "fig-map.png"), str(tmp_path / "fig-tractions.png")]
    folder = tmp_path / "figures"
    three = cli("plot", run, "-o", folder, "--kind", "slip")
    assert three.exit_code == 0, three.stderr
    assert three.stdout.split() == [str(folder / "motor-slip.png")]


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda d: d / "missing.h5", "no such file"),
        (lambda d: (d / "text.h5").write_text("not hdf5") and d / "text.h5", "not a halfslip result"),
        (lambda d: d, "is not a file"),
    ],
    ids=["missing", "not-hdf5", "folder"],
)
def test_cli_bad_input_is_one_line_and_exit_2(make, message, cli, tmp_path):
    outcome = cli("plot", make(tmp_path))
    assert outcome.exit_code == 2
    assert message in outcome.stderr
    assert outcome.stderr.count("\n") == 1 and "Traceback" not in outcome.stderr


def test_cli_rejects_foreign_netcdf_and_missing_fields(cli, tmp_path):
    import xarray as xr

    xr.Dataset({"a": ("t", [1.0, 2.0])}).to_netcdf(tmp_path / "other.h5", engine="h5netcdf")
    foreign = cli("plot", tmp_path / "other.h5")
    assert foreign.exit_code == 2 and "not a halfslip result" in foreign.stderr
    scene = EXAMPLES / "hertz_pad.yaml"
    text = scene.read_text().replace("count: 20", "count: 2") + "output: {fields: []}\n"
    bare = write_result(hs.simulate(hs.parse_scene(text)), tmp_path / "bare.h5")
    wanted = cli("plot", bare, "--kind", "slip")
    assert wanted.exit_code == 2
    assert "bare.h5" in wanted.stderr and "slip, which this run did not store" in wanted.stderr
    assert wanted.stderr.count("\n") == 1
    default = cli("plot", bare)  # the kinds the run allows, and a note on the others
    assert default.exit_code == 0, default.stderr
    assert [Path(p).name for p in default.stdout.split()] == ["bare-trajectory.png", "bare-map.png"]
    assert "no tractions figure" in default.stderr and "no slip figure" in default.stderr
    outside = cli("plot", bare, "--kind", "trajectory", "--at", "1e6")
    assert outside.exit_code == 0  # --at only concerns tractions
    late = cli("plot", write_result(hs.simulate(hs.parse_scene(scene.read_text().replace("count: 20", "count: 2"))),
                                    tmp_path / "full.h5"), "--kind", "tractions", "--at", "1e6")
    assert late.exit_code == 2 and "outside the run" in late.stderr


def test_trajectory_marks_point_T_where_the_theory_puts_it(results):
    # hertz_pad: constant P = 1e5, Q = +-1.8e4: T = (P - Qa/f, 0) = (7e4, 0) N/m,
    # drawn in kN/m; the permanent stick zone is a(P_T).
    ds = read_result(results("hertz_pad"))
    fig = plot.trajectory(ds)
    ax = fig.axes[0]
    markers = [line for line in ax.get_lines() if line.get_marker() == "D"]
    assert len(markers) == 1
    assert markers[0].get_xdata()[0] == pytest.approx(70.0, rel=1e-9)
    assert markers[0].get_ydata()[0] == pytest.approx(0.0, abs=1e-9)
    assert "kN/m" in ax.get_xlabel()
    # the +-f lines: Q = +-0.6 P
    slopes = sorted(
        round((line.get_ydata()[-1] - line.get_ydata()[0]) / (line.get_xdata()[-1] - line.get_xdata()[0]), 9)
        for line in ax.get_lines() if line.get_linestyle() in ("-", "--") and len(line.get_xdata()) == 2
    )
    assert slopes.count(0.6) >= 2 and slopes.count(-0.6) >= 2


def test_map_and_slip_show_the_permanent_stick_zone(results):
    ds = read_result(results("hertz_pad"))
    c = float(post.permanent_stick(ds).half_width)
    fig = plot.stick_slip_map(ds)
    dashed = [seg for coll in fig.axes[1].collections for seg in getattr(coll, "get_segments", lambda: [])()
              if coll.get_linestyle()[0][1] is not None]
    levels = sorted({round(float(seg[0][1]), 6) for seg in dashed})
    assert levels == pytest.approx([-c * 1e6, c * 1e6], rel=1e-6)  # drawn in micrometres
    fig = plot.slip(ds)
    assert "nm" in fig.axes[0].get_ylabel()  # slip amplitudes of tens of nanometres
    line = fig.axes[0].get_lines()[0]
    amplitude = post.slip_amplitude(ds).values
    np.testing.assert_allclose(line.get_ydata(), amplitude * 1e9)


def test_tractions_default_instants_are_the_quarters_of_the_last_cycle(results):
    ds = read_result(results("hertz_pad"))
    fig = plot.tractions(ds)
    labels = [text.get_text() for text in fig.axes[0].get_legend().get_texts()]
    table = post.cycles(ds)
    t0, t1 = float(table.t_start[-1]), float(table.t_stop[-1])
    for k, fraction in enumerate((0.0, 0.25, 0.5, 0.75)):
        assert labels[k].startswith(f"t = {t0 + fraction * (t1 - t0):.4g} s")
    with pytest.raises(HalfslipInputError, match="outside the run"):
        plot.tractions(ds, at=[-5.0])


def test_no_pyplot_state():
    # Drawing must not import pyplot (no global figure manager, no backend switch).
    code = (
        "import sys, halfslip as hs\n"
        "from halfslip import plot\n"
        "ds = hs.simulate(hs.parse_scene(open(sys.argv[1]).read().replace('count: 20', 'count: 2')))\n"
        "[plot.figure(ds, k) for k in plot.KINDS]\n"
        "assert 'matplotlib.pyplot' not in sys.modules, 'pyplot was imported'\n"
    )
    subprocess.run([sys.executable, "-c", code, str(EXAMPLES / "hertz_pad.yaml")], check=True)


def test_thin_slip_zones_get_a_zoom_on_each_edge(tmp_path):
    # Q amplitude 2 % of fP: the slip zones are a(P) (1 - sqrt(0.98)) = 1 % of the
    # half-width, invisible at full scale; map and slip figures split per edge.
    text = (EXAMPLES / "hertz_pad.yaml").read_text().replace("count: 20", "count: 2").replace(
        "Q: {amplitude: 1.8e4}", "Q: {amplitude: 1.2e3}")
    ds = hs.simulate(hs.parse_scene(text + "output: {points: 801}\n"))
    c = float(post.permanent_stick(ds).half_width)
    a = float(ds.contact_right[-1])
    assert (a - c) < plot.THIN_SLIP * 2 * a
    fig = plot.stick_slip_map(ds)
    assert len(fig.axes) == 3
    top, bottom = fig.axes[1].get_ylim(), fig.axes[2].get_ylim()
    assert top[0] < c * 1e6 < a * 1e6 < top[1] and bottom[0] < -a * 1e6 < -c * 1e6 < bottom[1]
    assert top[1] - top[0] < 0.2 * a * 1e6  # zoomed
    fig = plot.slip(ds)
    assert len(fig.axes) == 4
    left, right = fig.axes[0].get_xlim(), fig.axes[1].get_xlim()
    assert left[1] < 0 < right[0]
    for path in plot.plot_run(ds, tmp_path, kinds=["map", "slip"]):
        check_png(path)
