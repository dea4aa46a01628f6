"""The ``halfslip`` command line, thin over the Python API.

Every command of the :func:`main` group inherits its error handling: a
:class:`~halfslip.errors.HalfslipInputError` anywhere below a command becomes
one line ``halfslip: <file>:<line>: <field>: <message>`` on stderr and exit
status 2 (:data:`EXIT_INPUT_ERROR`), never a traceback.
"""
from __future__ import annotations

from typing import Any

import click

from ._version import __version__
from .errors import HalfslipInputError, excerpt
from .geometry import Hertz, ProfileSpanError, RoundedPunch, TabulatedProfile
from .scene import Scene, load_scene, scene_error
from .si import interval, quantity

EXIT_INPUT_ERROR = 2
"""Exit status for bad input (the same status click uses for usage errors)."""

_UNITS = {"P": "N/m", "Q": "N/m", "M": "N", "sigma": "Pa"}


class HalfslipGroup(click.Group):
    """A click group whose commands report bad input in one line.

    Commands added with ``@main.command()`` need no error handling of their
    own: a :class:`HalfslipInputError` or a click usage error anywhere below a
    command becomes one line on stderr and exit status 2; an interrupt that
    reaches the top (Ctrl-C during start-up, a second Ctrl-C) one line and
    exit status 130. Never a traceback.
    """

    def invoke(self, ctx: click.Context) -> Any:
        """Run the subcommand; turn a HalfslipInputError into one line and exit 2."""
        try:
            return super().invoke(ctx)
        except HalfslipInputError as error:
            click.echo(f"halfslip: {error}", err=True)
            ctx.exit(EXIT_INPUT_ERROR)
        except KeyboardInterrupt:  # click would print an empty line first: the one line is main's
            raise click.Abort() from None

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):
        """Click's main, with usage errors and interrupts in the one-line form."""
        import sys

        if not standalone_mode:
            return super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        try:
            code = self._main(args, prog_name, complete_var, **extra)
        except _NO_ARGS_IS_HELP as error:  # bare ``halfslip``: the help, as --help
            click.echo(error.ctx.get_help())
            sys.exit(0)
        except click.UsageError as error:
            raw = list(sys.argv[1:] if args is None else args)
            click.echo(f"halfslip: {usage_error_line(error, raw)}", err=True)
            sys.exit(EXIT_INPUT_ERROR)
        except click.ClickException as error:
            click.echo(f"halfslip: {_one_line(error.format_message())}", err=True)
            sys.exit(error.exit_code)
        except (click.Abort, KeyboardInterrupt):
            click.echo("halfslip: interrupted", err=True)
            sys.exit(EXIT_INTERRUPTED)
        sys.exit(code if isinstance(code, int) else 0)

    def _main(self, args, prog_name, complete_var, **extra):
        return super().main(args, prog_name, complete_var, standalone_mode=False, **extra)


def run_as_program(prog_name: str = "halfslip") -> None:
    """The command line as a process of its own (console script, ``python -m``).

    Exits through :func:`main`; on the way out interrupts are ignored: what
    was written is written, and a further Ctrl-C while the interpreter shuts
    down (when Python has put the default action back) must not kill the
    process by the signal. In-process callers of ``main`` keep their handlers.
    """
    import signal

    try:
        main(prog_name=prog_name)
    finally:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        signal.signal(signal.SIGTERM, signal.SIG_IGN)


_NO_ARGS_IS_HELP = getattr(click.exceptions, "NoArgsIsHelpError", ())  # click >= 8.2

EXIT_INTERRUPTED = 130
"""Exit status of an interrupted command (128 + SIGINT, as a shell reports it)."""


def _one_line(text: str) -> str:
    return HalfslipInputError(" ".join(str(text).split())).__str__()


def usage_error_line(error: click.UsageError, args: list[str] = ()) -> str:
    """``FILE: --option: message`` for a click usage error, naming the command's file argument.

    The file is the command's file argument when click had read it, else the
    first of the raw ``args`` that names an existing file.
    """
    import os

    ctx = error.ctx
    file = None
    if ctx is not None:
        for name in ("scene_file", "result_file", "sweep_file"):
            if ctx.params.get(name):
                file = str(ctx.params[name])
                break
    if file is None:  # the bad option came before the file argument: find it in the raw arguments
        file = next((a for a in args if not a.startswith("-") and os.path.isfile(a)), None)
    field = None
    param = getattr(error, "param", None)
    if param is not None:
        field = param.opts[0] if getattr(param, "opts", None) else param.name
    message = error.format_message()
    if field and message.startswith("Invalid value for"):
        message = message.split(":", 1)[-1].strip()
    command = ctx.command_path if ctx is not None else "halfslip"
    return str(HalfslipInputError(f"{' '.join(message.split())} (see '{command} --help')", file=file, field=field))


INPUT_FILE = click.Path(path_type=str)
"""A file argument: shells complete file names (click.Path). Existence and kind are left to the
readers, whose one-line errors name the file ("halfslip: dd: is a directory, not a scene file");
click's own check (dir_okay=False) would say "scene_file: File 'dd' is a directory."."""

OUTPUT_PATH = click.Path(path_type=str)
"""An output path (a file, or a folder where a command takes one): checked by ``io.check_output``."""

QUIET = click.option("--quiet", is_flag=True, help="Print nothing but errors and warnings.")
"""The --quiet option of every command that prints."""


class Seconds(click.ParamType):
    """A finite, positive number of seconds."""

    name = "seconds"

    def convert(self, value, param, ctx):
        import math

        try:
            number = float(value)
        except (TypeError, ValueError):
            self.fail(f"expected a number of seconds, got {str(value)[:40]!r}", param, ctx)
        if not math.isfinite(number) or number <= 0:
            self.fail(f"must be a finite number of seconds > 0, got {str(value)[:40]!r}", param, ctx)
        return number


@click.group(cls=HalfslipGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="halfslip")
def main() -> None:
    """Frictional partial slip of elastic half-plane contacts, from YAML scenes."""


@main.command()
@click.argument("scene_file", metavar="SCENE.yaml", type=INPUT_FILE)
@QUIET
def validate(scene_file: str, quiet: bool) -> None:
    """Check a scene and print it resolved, with a summary of its load history.

    Warnings (|Q| > fP somewhere, loads that jump at the start of cycles) go
    to stderr; the exit status is 0 for a valid scene, 2 for bad input.
    """
    scene = load_scene(scene_file)
    if not quiet:
        click.echo("\n".join(describe_scene(scene)))
    for message in scene.warnings():
        click.echo(f"halfslip: warning: {message}", err=True)


def describe_scene(scene: Scene) -> list[str]:
    """Return the lines ``halfslip validate`` prints for `scene`."""
    material, solver, output = scene.material, scene.solver, scene.output
    lines = [
        f"scene      {scene.name}" + (f"  ({scene.path})" if scene.path is not None else ""),
        f"material   E = {material.E:.6g} Pa, nu = {material.nu:g}, A = 4(1 - nu^2)/E = {material.compliance:.6g} 1/Pa",
        f"friction   f = {scene.friction:g}",
        f"geometry   {describe_profile(scene.profile)}",
        f"solver     method = {solver.method}, tol = {solver.tol:g}, nodes = {solver.nodes}, "
        f"skip_steady_cycles = {str(solver.skip_steady_cycles).lower()}"
        + ("" if solver.edge_travel is None else f", edge_travel = {solver.edge_travel:g}")
        + ("" if solver.edge_windows else ", edge_windows = false"),
        f"output     fields = [{', '.join(output.fields)}], every = {output.every}, points = {output.points}",
        "",
    ]
    history = scene.history
    lines.append(
        f"history    {len(history.segments)} segments, {history.n_steps} steps, t = 0 .. {history.duration:g} s"
    )
    lines.append(f"  {'#':>3}  {'kind':<7} {'line':>5}  {'t from [s]':>11} {'t to [s]':>11} {'steps':>7}")
    for index, segment in enumerate(history.segments):
        line = str(segment.line) if segment.line is not None else "-"
        text = (
            f"  {index:>3}  {segment.kind:<7} {line:>5}  {segment.t_start:>11.6g} {segment.t_stop:>11.6g}"
            f" {segment.steps:>7}"
        )
        if segment.kind == "cycles":
            text += f"  {segment.count} x {segment.period:g} s, {segment.steps_per_cycle} steps per cycle"
        if segment.source is not None:
            text += f"  from {segment.source}"
        lines.append(text)
    lines.append(f"  {'load':<6} {'min':>12} {'max':>12}")
    for name, (low, high) in history.ranges().items():
        lines.append(f"  {name:<6} {low:>12.6g} {high:>12.6g}  {_UNITS[name]}")
    lines.append(f"  max |Q|/(fP) = {history.max_shear_ratio(scene.friction):.4g}")
    return lines


def describe_profile(profile: Any) -> str:
    """Return ``kind: parameter = value, ...`` for a geometry profile."""
    if isinstance(profile, Hertz):
        return f"hertz: radius = {profile.radius:.6g} m"
    if isinstance(profile, RoundedPunch):
        return f"rounded_punch: flat_half_width = {profile.flat_half_width:.6g} m, radius = {profile.radius:.6g} m"
    if isinstance(profile, TabulatedProfile):
        shape = "symmetric" if profile.symmetric else "asymmetric"
        return (
            f"profile: {profile.x.size} samples, x in [{profile.x[0]:.6g}, {profile.x[-1]:.6g}] m, "
            f"h up to {profile.h.max():.6g} m, {shape}"
        )
    return repr(profile)


def _note_first_compilation(scene, method) -> None:
    """Say so when the general solver's compiled kernels are not in numba's cache yet (the first general run
    after installing compiles them, 45-55 s on a 2-core Xeon, and shows no progress meanwhile)."""
    from .simulator import MethodError, choose_method
    from .solvers._toeplitz import compiled_and_cached

    try:
        general = choose_method(scene, method) == "general"
    except MethodError:
        return  # simulate says what is wrong
    if general and not compiled_and_cached():
        click.echo("halfslip: note: compiling the general solver's kernels (once after installing, about a minute)",
                   err=True)


@main.command()
@click.argument("scene_file", metavar="SCENE.yaml", type=INPUT_FILE)
@click.option("-o", "--output", "output", metavar="OUT.h5", type=OUTPUT_PATH, help="Result file (default: the scene name with .h5, here).")
@click.option("--method", type=click.Choice(["auto", "exact", "general"]), help="Override solver.method.")
@click.option("--nodes", type=click.IntRange(min=8), help="Override solver.nodes (general solver).")
@click.option("--resume", is_flag=True, help="Continue the unfinished run in OUT.h5.")
@click.option("--overwrite", is_flag=True, help="Replace OUT.h5 even when it is not a halfslip result.")
@click.option("--checkpoint-every", type=Seconds(), default=2.0, show_default=True,
              help="Seconds between rewrites of OUT.h5 during the run (at least; > 0).")
@QUIET
def run(scene_file: str, output: str | None, method: str | None, nodes: int | None, resume: bool,
        overwrite: bool, checkpoint_every: float, quiet: bool) -> None:
    """March a scene's load history and write the result dataset (HDF5).

    The file is rewritten atomically every few seconds with every completed
    step and a checkpoint, so a killed run loses at most the last interval.
    Ctrl-C or SIGTERM stops the run and writes every completed step, marked
    incomplete (attribute complete = 0); the exit status is then 130, and
    --resume continues it to the same result as an uninterrupted run. A
    second Ctrl-C stops at once and keeps the file last written.

    OUT.h5 is checked before anything is computed: it must not be an input
    of the run, and an existing file that is not a halfslip result is
    replaced only with --overwrite. One process at a time writes a file.
    """
    import signal
    import sys
    from pathlib import Path

    from .io import OutputLock, RunFileWriter, check_output
    from .progress import Progress
    from .simulator import MethodError, simulate

    scene = load_scene(scene_file)
    out = check_output(Path(output) if output else Path(f"{Path(scene_file).stem}.h5"),
                       inputs=scene_inputs(scene), overwrite=overwrite or resume)
    stop = []

    def _request_stop(signum, frame):
        # first SIGINT / SIGTERM: finish the current step, write, exit; a second one: stop at once,
        # keeping the file as last written (a write under way is abandoned, its temporary removed)
        if stop:
            stop_now(out)
        stop.append(signum)

    with OutputLock(out):
        previous_run = read_unfinished_run(out, scene) if resume else None
        # SIGINT ignored by whoever started us (a background job of a script) stays ignored
        handlers = {sig: signal.signal(sig, _request_stop) for sig in (signal.SIGINT, signal.SIGTERM)
                    if signal.getsignal(sig) is not signal.SIG_IGN}
        progress = Progress("step", scene.name, enabled=not quiet and sys.stderr.isatty(), delay=1.0)
        if not quiet:
            _note_first_compilation(scene, method)
        try:
            result = simulate(scene, method=method, nodes=nodes, progress=progress,
                              writer=RunFileWriter(out, min_interval=checkpoint_every), resume=previous_run,
                              stop_requested=lambda: bool(stop))
        except MethodError as error:
            raise HalfslipInputError(str(error), file=str(scene.path) if scene.path else None,
                                     field="solver.method") from None
        except ProfileSpanError as error:  # loads the scene check did not foresee (check_contacts)
            raise scene_error(scene, f"the profile cannot carry the loads: {error}", "geometry") from None
        except HalfslipInputError as error:
            if error.field == "--resume":  # the run file refused on resuming names that file
                raise error.located(str(out), None) from None
            if error.file is not None:
                raise
            raise scene_error(scene, error.message, error.field or "") from None  # e.g. --nodes too large
        finally:
            progress.close()
            for sig, handler in handlers.items():
                signal.signal(sig, handler)
    if not quiet:
        click.echo("\n".join(summarize(result, out)))
    if not result.attrs["complete"]:
        click.echo(f"halfslip: interrupted after step {result.attrs['steps_done']}; "
                   f"{result.sizes['t']} stored steps written to {out} (continue with --resume)", err=True)
        sys.exit(EXIT_INTERRUPTED)


def stop_now(out) -> None:
    """Exit at once with status 130 (a second Ctrl-C), leaving ``out`` as last written."""
    import os
    import sys

    from .io import remove_temporaries_being_written

    remove_temporaries_being_written()
    sys.stderr.write(f"halfslip: stopped at once; {out} holds what was last written\n")
    sys.stderr.flush()
    os._exit(EXIT_INTERRUPTED)


#: Figure formats ``halfslip plot -o`` writes (matplotlib's, by the file's ending).
FIGURE_FORMATS = ("png", "pdf", "svg", "eps", "ps", "jpg", "jpeg", "tif", "tiff", "webp")


def check_figure_output(target, source) -> None:
    """Refuse, before drawing, a figure path that is not a figure format or is the result itself."""
    from .io import same_file

    if target.is_dir() or not target.suffix or str(target).endswith(("/", "\\")):
        return  # a folder, made by write_figures (plot.py: a path without an ending is a folder)
    suffix = target.suffix.lower().lstrip(".")
    if suffix not in FIGURE_FORMATS:
        raise HalfslipInputError(f"a figure is written as {', '.join(FIGURE_FORMATS)} (by its ending); "
                                 f"got {excerpt(target.name)}", file=str(target), field="-o")
    if same_file(target, source):
        raise HalfslipInputError("is the result file itself; name a figure file", file=str(target), field="-o")


def scene_inputs(scene: Scene) -> list:
    """The files a scene was read from: the scene file, its profile table and its load tables."""
    files = [scene.path, getattr(scene.profile, "source", None)]
    files += [segment.source for segment in scene.history.segments if segment.source is not None]
    return [f for f in files if f is not None]


def read_unfinished_run(out, scene: Scene):
    """The stored steps and checkpoint of the unfinished run in ``out``, for ``--resume``.

    The file is inspected as untrusted data (``io.check_result_file``) and
    must belong to ``scene`` (its scene hash) before its checkpoint is
    decoded; the checkpoint is pure data (``io.read_checkpoint``).
    """
    from .io import CheckpointError, UnsafeFileError, read_checkpoint, read_result
    from .simulator import scene_hash

    if not out.exists():
        raise HalfslipInputError("does not exist: nothing to resume", file=str(out), field="--resume")
    try:
        ds = read_result(out)
    except UnsafeFileError as error:
        raise HalfslipInputError(f"not a halfslip run file: {error}", file=str(out), field="--resume") from None
    except (OSError, ValueError, KeyError, TypeError) as error:
        raise HalfslipInputError(f"not a halfslip run file (cannot read it: {type(error).__name__})",
                                 file=str(out), field="--resume") from None
    if ds.attrs.get("scene_sha256") != scene_hash(scene):
        raise HalfslipInputError("the file to resume was written by a different scene", file=str(out),
                                 field="--resume")
    try:
        checkpoint = read_checkpoint(out)
    except CheckpointError as error:
        raise HalfslipInputError(f"its checkpoint is refused: {error}", file=str(out), field="--resume") from None
    except (OSError, ValueError, KeyError, TypeError) as error:
        raise HalfslipInputError(f"its checkpoint cannot be read ({type(error).__name__})", file=str(out),
                                 field="--resume") from None
    return ds, checkpoint


def summarize(result, path) -> list[str]:
    """The lines ``halfslip run`` prints when done.

    Regimes met and their share of the stored steps, the final contact and
    stick zone, for cyclic runs the permanent stick zone (intersection of the
    stick zones over the last full cycle) and the dissipation per cycle, the
    speed and the output path. Derived quantities come from
    :mod:`halfslip.post`; a line that cannot be derived (e.g. an interrupted
    run without a full cycle) is left out.
    """
    import numpy as np

    from . import post
    from .messages import summary as message_summary
    from .state import Regime

    regime = result["regime"].values[1:] if result.sizes["t"] > 1 else result["regime"].values
    steps = int(result.attrs["count_steps"])
    wall = float(result.attrs["wall_time"])
    skipped = int(result.attrs.get("skipped_cycles", 0))
    marched = f"{steps} steps marched" + (f", {skipped} steady cycles skipped as repeats" if skipped else "")
    lines = [
        f"halfslip run of {result.attrs['scene_name']}: {marched}, method {result.attrs['method']}, "
        f"{wall:.3g} s ({steps / wall if wall > 0 else float('inf'):,.0f} steps/s)",
        "  regimes of stored steps: "
        + ", ".join(
            f"{r.name.lower().replace('_', ' ')} {100 * np.mean(regime == r):.1f} %"
            for r in Regime
            if np.any(regime == r)
        ),
    ]
    last = result.isel(t=-1)
    lines.append(
        f"  final contact {interval(float(last.contact_left), float(last.contact_right), 'm')}, "
        f"stick zone {interval(float(last.stick_left), float(last.stick_right), 'm')}"
    )
    try:
        table = post.cycles(result)
    except HalfslipInputError:
        table = None
    if table is not None and table.sizes["cycle"]:
        zone = post.permanent_stick(result)
        row = table.isel(cycle=-1)
        where = f"last full cycle, t = {float(row.t_start):g} .. {float(row.t_stop):g} s"
        if np.isfinite(float(zone["left"])):
            errors = (float(zone["left_error"]), float(zone["right_error"]))
            if all(np.isfinite(errors)) and max(errors) > 0.0:
                # the ends come from single instants, often load extremes: say how well they are placed
                where += (f"; ends set at t = {float(zone['t_left']):g} / {float(zone['t_right']):g} s, "
                          f"edge error estimates {quantity(errors[0], 'm')} / {quantity(errors[1], 'm')}")
            lines.append(f"  permanent stick zone {interval(float(zone['left']), float(zone['right']), 'm')} ({where})")
        else:
            lines.append(f"  permanent stick zone: none, no point sticks throughout the {where}")
        energy = post.dissipation_per_cycle(result)["dissipation"].values
        first = f", first cycle {quantity(energy[0], 'J/m')}" if energy.size > 1 else ""
        lines.append(f"  dissipation per cycle {quantity(energy[-1], 'J/m')} (last full cycle){first}")
    total = result["final_dissipation"] if "final_dissipation" in result else last.dissipation  # skipped cycles too
    lines.append(f"  dissipated {quantity(float(total), 'J/m')} in total")
    failed = int(result.attrs.get("count_failed_steps", 0))
    if failed and "converged" in result:
        bad = result["converged"].values == 0
        t_bad, residual = result["t"].values[bad], result["residual"].values[bad]
        worst = int(np.argmax(np.where(np.isfinite(residual), residual, np.inf)))
        lines.append(f"  NOT CONVERGED: {failed} of {steps} steps did not meet the solver's tolerance "
                     f"(first at t = {t_bad[0]:.6g} s, worst at t = {t_bad[worst]:.6g} s, residual "
                     f"{residual[worst]:.3g} x tolerance); their results are the closest found "
                     "(variables converged, residual)")
    if result.attrs.get("method") == "general" and "error_estimate" in result:
        est = result["error_estimate"].values
        est = est[np.isfinite(est)]
        if est.size:
            tol = result.attrs.get("solver_tol")
            over = int(np.sum(est > tol)) if tol is not None else 0
            lines.append(f"  stick-edge error estimate: median {np.median(est):.2g}, 95th percentile "
                         f"{np.percentile(est, 95):.2g}, largest {est.max():.2g} of the contact width"
                         + (f" (solver.tol {tol:g}: {over} of {est.size} stored steps above)" if tol is not None
                            else ""))
    if result.attrs.get("method") == "general" and "shear_error_estimate" in result:
        est = result["shear_error_estimate"].values
        est = est[np.isfinite(est)]
        if est.size:
            lines.append(f"  shear error estimate (int |q - q_exact| dx): median {np.median(est):.2g}, 95th "
                         f"percentile {np.percentile(est, 95):.2g}, largest {est.max():.2g} of f P")
    # one note per kind of solver message: how many, the first and the worst step (halfslip.messages)
    for line in message_summary(result):
        lines.append(f"  note: {line}")
    lines.append(f"  written to {path}")
    return lines


@main.command()
@click.argument("scene_file", metavar="SCENE.yaml", type=INPUT_FILE)
@click.option("--segment", type=int, help="Index of the cycles segment (default: the last one).")
@click.option("-o", "--output", "output", metavar="OUT.h5", type=OUTPUT_PATH, help="Also write the steady-state dataset.")
@click.option("--overwrite", is_flag=True, help="Replace OUT.h5 even when it is not a halfslip result.")
@QUIET
def steady(scene_file: str, segment: int | None, output: str | None, overwrite: bool, quiet: bool) -> None:
    """Permanent stick zone of the cyclic part of a scene, found directly.

    Prints the zone, the regime and, with -o, the file written; a warning
    (e.g. a tension range the closed form does not cover) goes to stderr.
    """
    from contextlib import nullcontext

    from .io import OutputLock, check_output
    from .steady import steady_state

    scene = load_scene(scene_file)
    out = check_output(output, inputs=scene_inputs(scene), overwrite=overwrite) if output else None
    with OutputLock(out) if out is not None else nullcontext():
        _steady(scene, segment, out, steady_state, quiet)


def _steady(scene: Scene, segment: int | None, out, steady_state, quiet: bool = False) -> None:
    try:
        ds = steady_state(scene, segment)
    except ProfileSpanError as error:
        raise scene_error(scene, f"the profile cannot carry the loads: {error}", "geometry") from None
    except HalfslipInputError as error:
        raise error.located(str(scene.path) if scene.path else None, None) from None
    regime = int(ds["regime"])
    names = {1: "full stick (shakedown)", 2: "partial slip", 3: "gross sliding"}
    rows = [
        ("scene", scene.name),
        ("method", ds.attrs["method"]),
        ("regime", names.get(regime, str(regime))),
        ("permanent stick zone", interval(float(ds.permanent_stick_left), float(ds.permanent_stick_right), "m")),
    ]
    if "dissipation_per_cycle" in ds:
        rows.append(("dissipation per cycle", quantity(float(ds.dissipation_per_cycle), "J/m")))
        rows.append(("peak slip amplitude", quantity(float(ds.peak_slip_amplitude), "m")))
    width = max(len(k) for k, _ in rows)
    if not quiet:
        for key, value in rows:
            click.echo(f"{key:<{width}}  {value}")
        click.echo(f"note: {ds.attrs['note']}")
    if ds.attrs.get("warning"):
        click.echo(f"halfslip: warning: {ds.attrs['warning']}", err=True)
    if out is not None:
        from .io import write_result

        write_result(ds, out)
        if not quiet:
            click.echo(f"written to {out}")


@main.command()
@click.argument("result_file", metavar="OUT.h5", type=INPUT_FILE)
@click.option("-o", "--output", "output", metavar="FIG.png|FOLDER", type=OUTPUT_PATH,
              help="A figure file (one kind, or several as FIG-<kind>.png) or a folder; "
                   "default: OUT-<kind>.png next to OUT.h5.")
@click.option("--kind", "kinds", multiple=True,
              type=click.Choice(["trajectory", "map", "tractions", "slip", "loop", "stress", "ruiz", "loads",
                                 "sweep", "steady"]),
              help="Figure kind (repeat for several; default: all the file allows). Runs: trajectory, map, "
                   "tractions, slip, loop, stress, ruiz, loads; a sweep file: sweep; a steady file: steady.")
@click.option("--at", "at", multiple=True, metavar="T",
              help="Time [s] of a tractions / stress snapshot (repeat, or separate with commas).")
@QUIET
def plot(result_file: str, output: str | None, kinds: tuple, at: tuple, quiet: bool) -> None:
    """Pictures of a halfslip file: a run, a sweep result or a steady-state file.

    The file's kind is read from its variables and attributes. A run gets
    the loading path, stick-slip map, tractions, slip and energy, Q-delta
    loop, surface stress, Ruiz parameters and loads; a sweep result its maps
    (or curves) over the varied fields; a steady-state file (written by
    halfslip steady -o) its permanent stick zone and slip amplitude. Prints
    the path of every figure written. Bad input (missing file, not a halfslip file, a
    kind the file cannot give) exits 2 with one line.
    """
    from pathlib import Path

    from . import plot as plots
    from .io import UnsafeFileError, read_result
    from .post import check_result, result_kind

    source = Path(result_file)
    if not source.is_file():
        raise HalfslipInputError("no such file" if not source.exists() else "is not a file", file=result_file)
    if output:
        check_figure_output(Path(output), source)
    try:
        ds = read_result(source)
    except UnsafeFileError as error:  # a file that is not plain bounded data (io.check_result_file)
        raise HalfslipInputError(f"not a halfslip result: {error}", file=result_file) from None
    except Exception as error:  # h5py / h5netcdf raise OSError, ValueError, KeyError ...
        raise HalfslipInputError(f"not a halfslip result (cannot read it: {type(error).__name__})",
                                 file=result_file) from None
    ds.encoding["source"] = str(source)
    kind = result_kind(ds)
    if kind is None:
        try:
            check_result(ds)
        except HalfslipInputError as error:
            raise error.located(result_file, None) from None
        raise HalfslipInputError("not a halfslip result", file=result_file)
    times = []
    for text in at:
        for part in filter(None, (piece.strip() for piece in text.split(","))):
            try:
                times.append(float(part))
            except ValueError:
                raise HalfslipInputError(f"expected a time in seconds, got {part!r}", field="--at") from None
    chosen = list(kinds) if kinds else None
    if chosen is None and kind == "run" and not quiet:
        for name in plots.KINDS:
            missing = [field for field in plots.NEEDS[name] if field not in ds.data_vars]
            if missing:
                click.echo(f"halfslip: note: no {name} figure: the run did not store {', '.join(missing)}", err=True)
    if not ds.attrs.get("complete", 1) and not quiet:
        click.echo(f"halfslip: note: the {kind} is unfinished; the figures show what is done", err=True)
    out = Path(output) if output else source.parent
    try:
        written = plots.write_figures(ds, out, kinds=chosen, at=times or None)
    except HalfslipInputError as error:
        raise error.located(result_file, None) from None
    if not quiet:
        for path in written:
            click.echo(str(path))


@main.command(name="sweep")
@click.argument("sweep_file", metavar="SWEEP.yaml", type=INPUT_FILE)
@click.option("-o", "--output", "output", metavar="OUT.h5", type=OUTPUT_PATH,
              help="Result file (default: the sweep file's name with .h5, here). Rerun with the same "
                   "file to finish an interrupted sweep.")
@click.option("--workers", type=click.IntRange(min=1), metavar="N",
              help="Local worker processes (default: the number of cores; 1 runs in this process).")
@click.option("--scheduler", metavar="ADDRESS", help="Run the cases on this dask.distributed scheduler.")
@click.option("--cases-dir", "cases_dir", metavar="DIR", type=click.Path(file_okay=False, path_type=str), help="Also write each case's full result to DIR.")
@click.option("--overwrite", is_flag=True, help="Replace OUT.h5 even when it is not a halfslip result.")
@QUIET
def sweep_command(sweep_file: str, output: str | None, workers: int | None, scheduler: str | None,
                  cases_dir: str | None, overwrite: bool, quiet: bool) -> None:
    """Run every case of a sweep file and write one dataset of per-case summaries.

    Ctrl-C or SIGTERM stops the sweep and writes the finished cases (exit
    status 130); the same command then runs only the cases not yet done.
    Failing cases are recorded in the status variable and do not stop the
    sweep.
    """
    import signal
    import sys
    from pathlib import Path

    from .sweep import load_sweep
    from .sweep import sweep as run_sweep

    from .io import OutputLock, check_output

    spec = load_sweep(sweep_file)
    out = check_output(Path(output) if output else Path(f"{Path(sweep_file).stem}.h5"),
                       inputs=[spec.file, spec.scene_path], overwrite=overwrite)
    if not quiet and spec.n_cases:
        try:
            first = spec.case_scene(0)
        except HalfslipInputError:
            first = None  # the sweep records the case as failed
        if first is not None:
            _note_first_compilation(first, None)

    def _terminate(signum, frame):  # SIGTERM behaves like Ctrl-C: stop and keep what is done
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, _terminate)
    try:
        with OutputLock(out):
            result = run_sweep(spec, output=out, workers=workers, scheduler=scheduler, cases_dir=cases_dir,
                               progress=not quiet)
    except ImportError as error:
        raise click.ClickException(str(error)) from None
    finally:
        signal.signal(signal.SIGTERM, previous)
    done, total = int(result.attrs["count_done"]), int(result.attrs["count_cases"])
    failed = int(result.attrs["count_failed"])
    if not quiet:
        click.echo(
            f"halfslip sweep of {spec.scene_path.name}: {total} cases over {', '.join(spec.paths)}; "
            f"ran {result.attrs['count_run']} ({result.attrs['backend']}) in {float(result.attrs['wall_time']):.3g} s; "
            f"{done - failed} ok, {failed} failed; written to {out}"
        )
    if failed:
        statuses = result["status"].values.reshape(-1)
        first = next(s for s in statuses if s not in ("ok", "not run"))
        click.echo(f"halfslip: warning: {failed} of {total} cases failed (see the status variable); "
                   f"first: {first}", err=True)
    if not result.attrs["complete"]:
        click.echo(f"halfslip: interrupted; {done} of {total} cases written to {out}; "
                   "run the same command again to finish", err=True)
        sys.exit(130)


if __name__ == "__main__":
    run_as_program()
