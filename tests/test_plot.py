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


SMALL = {
    # each example with its history shortened (same segments, fewer steps and cycles) so that every
    # kind is drawn from a real run of it in a few seconds; the general solver (dovetail) at 128 nodes
    "hertz_pad": [("count: 20", "count: 3")],
    "motor": [("count: 10", "count: 3")],
    "tabulated": [("steps: 20", "steps: 4"), ("steps: 5", "steps: 2"), ("points: 161", "points: 41")],
    "dovetail": [("count: 20", "count: 2"), ("steps_per_cycle: 100", "steps_per_cycle: 16"), ("steps: 50", "steps: 6"),
                 ("tol: 1.0e-4", "nodes: 128")],
}
"""Text replacements that shorten each example of examples/ (every one is listed: see the test below)."""


def small_run(name: str):
    text = (EXAMPLES / f"{name}.yaml").read_text()
    for old, new in SMALL[name]:
        assert old in text, (name, old)
        text = text.replace(old, new)
    return hs.simulate(hs.parse_scene(text, base_dir=EXAMPLES))


def png_size(path: Path) -> tuple[int, int]:
    """Width and height from a PNG's IHDR chunk; raises if the file is not a PNG."""
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", f"{path} lacks the PNG signature"
    assert data[12:16] == b"IHDR", f"{path}: first chunk is not IHDR"
    assert data[-8:-4] == b"IEND", f"{path} is truncated"
    return struct.unpack(">II", data[16:24])


def check_png(path: Path) -> None:
    width, height = png_size(path)
    # figures are 7 - 10 in wide and 4.5 - 8 in high at 150 dpi
    assert 600 <= width <= 1600 and 500 <= height <= 1300, (path, width, height)
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


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    """Each example of examples/, shortened (:data:`SMALL`), run once and written, keyed by name (lazily)."""
    folder = tmp_path_factory.mktemp("small")
    cache = {}

    def get(name):
        if name not in cache:
            cache[name] = write_result(small_run(name), folder / f"{name}.h5")
        return cache[name]

    return get


def test_every_example_is_covered():
    scenes = {path.stem for path in EXAMPLES.glob("*.yaml")} - {"dovetail_sweep"}  # the sweep: test_cli_* below
    assert scenes == set(SMALL)


@pytest.mark.parametrize("example", sorted(SMALL))
def test_every_kind_for_every_example_is_a_real_png(example, small, tmp_path):
    ds = read_result(small(example))
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
    assert [Path(p).name for p in default.stdout.split()] == [
        "bare-trajectory.png", "bare-map.png", "bare-loop.png", "bare-loads.png"]
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


# ---------------------------------------------------------------------------
# halfslip plot on every kind of halfslip file (a real subprocess, as users run it)


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "halfslip.cli", *map(str, args)], capture_output=True, text=True,
                          timeout=300)


@pytest.fixture(scope="module")
def sweep_file(tmp_path_factory):
    from halfslip.sweep import load_sweep

    out = tmp_path_factory.mktemp("sweep") / "dovetail_sweep.h5"
    hs.sweep(load_sweep(EXAMPLES / "dovetail_sweep.yaml"), output=out, workers=1, progress=False)
    return out


@pytest.fixture(scope="module")
def steady_file(tmp_path_factory):
    out = tmp_path_factory.mktemp("steady") / "pad_steady.h5"
    write_result(hs.steady_state(hs.load_scene(EXAMPLES / "hertz_pad.yaml")), out)
    return out


def test_cli_plot_draws_a_run_a_sweep_and_a_steady_file(small, sweep_file, steady_file, tmp_path):
    for source, kinds in ((small("motor"), list(plot.KINDS)), (sweep_file, ["sweep"]), (steady_file, ["steady"])):
        outcome = run_cli("plot", source, "-o", tmp_path)
        assert outcome.returncode == 0, outcome.stderr
        printed = [Path(line) for line in outcome.stdout.split()]
        assert printed == [tmp_path / f"{source.stem}-{kind}.png" for kind in kinds]
        for path in printed:
            check_png(path)


def test_cli_plot_rejects_a_foreign_hdf5_file_in_one_line(tmp_path):
    import xarray as xr

    xr.Dataset({"a": ("t", [1.0, 2.0])}, attrs={"title": "not ours"}).to_netcdf(tmp_path / "other.h5", engine="h5netcdf")
    outcome = run_cli("plot", tmp_path / "other.h5")
    assert outcome.returncode == 2
    assert outcome.stderr.startswith("halfslip: ") and "not a halfslip result" in outcome.stderr
    assert outcome.stderr.count("\n") == 1 and "Traceback" not in outcome.stderr
    assert outcome.stdout == ""


def test_kinds_that_do_not_fit_the_file_are_one_line_errors(sweep_file, cli):
    outcome = cli("plot", sweep_file, "--kind", "loop")
    assert outcome.exit_code == 2 and "sweep file has the one figure kind 'sweep'" in outcome.stderr


def test_result_kind_tells_the_files_apart(small, sweep_file, steady_file):
    import xarray as xr

    assert post.result_kind(read_result(small("hertz_pad"))) == "run"
    assert post.result_kind(read_result(sweep_file)) == "sweep"
    assert post.result_kind(read_result(steady_file)) == "steady"
    assert post.result_kind(xr.Dataset({"a": ("t", [1.0])})) is None


# ---------------------------------------------------------------------------
# drawing on the caller's Axes


SINGLE = ("trajectory", "tractions", "loop")
MULTI = ("map", "slip", "stress", "ruiz", "loads")


@pytest.mark.parametrize("kind", SINGLE)
def test_single_panel_kinds_draw_on_the_given_axes(kind, results):
    from matplotlib.figure import Figure

    ds = read_result(results("hertz_pad"))
    fig = Figure()
    ax = fig.add_subplot()
    returned = plot.DRAW[kind](ds, ax=ax)
    assert returned is fig and fig.axes[0] is ax
    assert ax.lines or ax.collections
    assert ax.get_title()


@pytest.mark.parametrize("kind", MULTI)
def test_multi_panel_kinds_draw_into_a_given_figure_or_axes(kind, results):
    from matplotlib.figure import Figure

    ds = read_result(results("hertz_pad"))
    fig = Figure()
    assert plot.DRAW[kind](ds, axes=fig) is fig
    drawn = [ax for ax in fig.axes if ax.lines or ax.collections]
    assert len(drawn) >= 2
    # the same panels on Axes the caller made (e.g. in a bigger figure of his own)
    other = Figure()
    count = len([ax for ax in fig.axes if ax.get_label() != "<colorbar>"])
    axes = [other.add_subplot(count + 1, 1, k + 1) for k in range(count)]
    assert plot.DRAW[kind](ds, axes=axes) is other
    assert all(ax.lines or ax.collections for ax in axes)
    with pytest.raises(ValueError, match="pass"):
        plot.DRAW[kind](ds, axes=axes[:-1] + [other.add_subplot(count + 1, 1, count + 1)] * 2)


def test_sweep_and_steady_draw_on_the_given_axes(sweep_file, steady_file):
    from matplotlib.figure import Figure

    fig = Figure()
    assert plot.sweep_map(read_result(sweep_file), axes=fig) is fig and fig.axes[0].collections
    fig = Figure()
    ax = fig.add_subplot()
    assert plot.steady(read_result(steady_file), ax=ax) is fig and ax.lines


# ---------------------------------------------------------------------------
# what the new figures show


def test_loop_area_equals_the_solvers_dissipation_per_cycle():
    # hertz_pad (constant P, Q the only load that works): over a closed steady cycle the elastic energy
    # returns to its start, so the area of the Q - shift loop is the energy dissipated in the cycle.
    # The loop integral is a trapezoid over the stored steps (error O(1/n^2)); the solver's dissipation
    # is exact per step. Measured: 0.07 % at 100 steps per cycle, 0.27 % at 50 (ratio 4: second order).
    # Tolerance 0.2 % at 100 steps, and the error must fall at least 3x when the steps double.
    errors = []
    for steps in (50, 100):
        text = (EXAMPLES / "hertz_pad.yaml").read_text().replace("count: 20", "count: 3").replace(
            "steps_per_cycle: 100", f"steps_per_cycle: {steps}")
        ds = hs.simulate(hs.parse_scene(text))
        loops = post.hysteresis_loops(ds)
        dissipated = float(post.dissipation_per_cycle(ds)["dissipation"][-1])
        errors.append(abs(float(loops["work"][-1]) / dissipated - 1))
        # removing the elastic part C Q does not change the area
        assert post.loop_integral(loops["Q"].values[-1], loops["shift_slip"].values[-1]) == pytest.approx(
            float(loops["work"][-1]), rel=1e-9)
    assert errors[1] < 2e-3, errors
    assert errors[0] / errors[1] > 3.0, errors
    fig = plot.loop(ds)
    text = fig.axes[0].get_legend().get_title().get_text()
    assert "loop area" in text and "solver's dissipation" in text


def test_loop_opens_the_loop_with_the_fitted_elastic_compliance(results):
    ds = read_result(results("hertz_pad"))
    loops = post.hysteresis_loops(ds)
    Q, shift, slip_shift = (loops[k].values[-1] for k in ("Q", "shift", "shift_slip"))
    # the raw loop is nearly straight; less C Q its width is a large part of its extent
    assert np.ptp(slip_shift) < 0.1 * np.ptp(shift)
    up = Q > 0.5 * np.nanmax(Q)  # at the same Q the loading and unloading branches differ
    assert np.nanmax(slip_shift[up]) - np.nanmin(slip_shift[up]) > 0.2 * np.ptp(slip_shift[np.isfinite(slip_shift)])
    C = float(loops["compliance"][-1])
    first_steps = np.diff(shift) / np.diff(Q)
    assert C == pytest.approx(np.nanmin(np.abs(first_steps)), rel=2e-3)  # the elastic slope at the reversals
    fig = plot.loop(ds)
    assert "δ − C·Q" in fig.axes[0].get_xlabel() and "nm" in fig.axes[0].get_xlabel()


def test_stress_and_ruiz_figures_draw_posts_numbers(results):
    ds = read_result(results("hertz_pad"))
    envelope = post.stress_range(ds)
    fig = plot.stress(ds)
    bottom = fig.axes[1]
    ranges = [line for line in bottom.get_lines() if line.get_color() == "#a50f15" and len(line.get_xdata()) > 1]
    np.testing.assert_allclose(ranges[0].get_ydata(), envelope["range"].values / 1e6)  # MPa
    assert "MPa" in bottom.get_ylabel() and "σxx(x, 0)" in bottom.get_ylabel()
    values = post.ruiz(ds)
    fig = plot.ruiz(ds)
    two, three = (ax.get_lines()[0].get_ydata() for ax in fig.axes[:2])
    np.testing.assert_allclose(two, values["shear_slip"].values)  # J/m^2 (peak ~1.2 J/m^2)
    assert fig.axes[0].get_ylabel() == "τ·δ [J/m²]" and fig.axes[1].get_ylabel().startswith("σ·τ·δ [MPa·")
    assert np.nanmax(three) > 0


def test_skipped_cycles_are_a_thin_band_in_map_and_loads(results):
    ds = read_result(results("hertz_pad"))  # 18 of 20 cycles skipped: t jumps from 3 s to 21 s
    assert int(ds.attrs["skipped_cycles"]) == 18
    for fig in (plot.stick_slip_map(ds), plot.loads(ds)):
        ax = fig.axes[0]
        low, high = ax.get_xlim()
        hatched = [patch for patch in ax.patches if patch.get_hatch()]
        assert len(hatched) == 1
        x0, x1 = (hatched[0].get_x(), hatched[0].get_x() + hatched[0].get_width())
        assert 0 < (x1 - x0) < 0.06 * (high - low)  # a thin band, not most of the panel
        labels = ax.xaxis.get_major_formatter().format_ticks(ax.get_xticks())
        assert labels[-1] == "21" and "3" in labels  # real times on both sides


def test_axes_carry_no_offset_or_power_of_ten(sweep_file):
    fig = plot.sweep_map(read_result(sweep_file))
    fig.canvas.draw()
    for ax in fig.axes:
        assert ax.xaxis.get_offset_text().get_text() == "" and ax.yaxis.get_offset_text().get_text() == ""
    main = fig.axes[0]
    assert "[MPa]" in main.get_xlabel() and "[kN/m]" in main.get_ylabel()
    assert "partial slip in every case" in fig.get_suptitle()  # no single-colour regime panel
    assert plot.unit_scale([3e7], "Pa") == (1e6, "MPa")
    assert plot.unit_scale([2e-4], "m") == (1e-6, "µm")
    assert plot.unit_scale([5e4], "N/m") == (1e3, "kN/m")
    assert plot.unit_scale([2e-3], "m") == (1e-3, "mm")


def test_slip_shading_stops_at_the_last_point_and_notes_sit_where_slip_is(tmp_path):
    text = (EXAMPLES / "hertz_pad.yaml").read_text().replace("count: 20", "count: 2").replace(
        "Q: {amplitude: 1.8e4}", "Q: {amplitude: 1.2e3}")
    ds = hs.simulate(hs.parse_scene(text + "output: {points: 801}\n"))
    fig = plot.slip(ds)
    x = ds["x"].values * 1e6
    amplitude = post.slip_amplitude(ds).values
    for ax in fig.axes[:2]:
        for collection in ax.collections:
            for path in collection.get_paths():
                xs = path.vertices[:, 0]
                assert xs.min() >= x[np.isfinite(amplitude)].min() - 1e-9
                assert xs.max() <= x[np.isfinite(amplitude)].max() + 1e-9
    energy_notes = [t.get_text() for ax in fig.axes for t in ax.texts if "solver's energy" in t.get_text()]
    assert len(energy_notes) == 1


# ---------------------------------------------------------------------------
# the package's import graph


def import_graph() -> dict[str, set[str]]:
    """Module -> halfslip modules it imports anywhere (top level or inside functions), from the source."""
    import ast

    root = Path(__file__).resolve().parents[1] / "src" / "halfslip"
    modules = {}
    for path in root.rglob("*.py"):
        parts = list(path.relative_to(root.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        modules[".".join(parts)] = path
    graph = {name: set() for name in modules}
    for name, path in modules.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                    target = ".".join(base + ([node.module] if node.module else []))
                else:
                    target = node.module or ""
                # `from . import post` imports the module post; `from . import __version__` the package
                names = [f"{target}.{alias.name}" for alias in node.names]
                found = [n for n in names if n in modules]
                targets = found if len(found) == len(names) else found + [target]
            elif isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            else:
                continue
            graph[name].update(t for t in targets if t in modules and t != name)
    return graph


def import_cycles(graph) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                out.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


KNOWN_CYCLES = []
"""Import cycles outside plot/post that remain (each a sorted list of modules); none is allowed to grow."""


def test_no_import_cycles_in_the_package():
    graph = import_graph()
    assert "halfslip.plot" in graph["halfslip.cli"] and "halfslip.post" in graph["halfslip.plot"]  # the walk sees edges
    assert "halfslip.plot" not in graph["halfslip.post"]  # post computes, plot draws
    cycles = import_cycles(graph)
    assert not [c for c in cycles if {"halfslip.plot", "halfslip.post"} & set(c)], cycles
    assert cycles == KNOWN_CYCLES
