"""Running a sweep: one case, workers and backends, checkpoints of the output, signals."""
from __future__ import annotations

import contextlib
import json
import math
import os
import signal
import sys
import threading
import time
import uuid
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from ..errors import HalfslipInputError
from ..io import CONVENTIONS
from ..progress import interactive
from .spec import Sweep, load_sweep, parse_sweep
from .table import CaseResult, _CaseInterrupted, _Table, _empty_summaries, solve_case

CHECKPOINT_SECONDS = 5.0
"""Default interval between rewrites of the output file while a sweep runs."""

# -- one case ------------------------------------------------------------------


_WORKER_SWEEP: Sweep | None = None


def _init_worker(spec: Sweep) -> None:
    """Initializer of a local worker process: keep the sweep, leave Ctrl-C to the driver."""
    global _WORKER_SWEEP
    _WORKER_SWEEP = spec
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _run_in_worker(index: int, keep_full: bool) -> CaseResult:
    assert _WORKER_SWEEP is not None
    return run_case(_WORKER_SWEEP, index, keep_full=keep_full)


def run_case(spec: Sweep, index: int, *, keep_full: bool = False) -> CaseResult:
    """Build and solve case `index` of `spec`; never raises for a failing case.

    Parameters
    ----------
    spec : Sweep
    index : int
        Flat case index (C order over the grid).
    keep_full : bool
        Return the full dataset of the case (for ``cases_dir``).

    Returns
    -------
    CaseResult
        ``status`` is ``'ok'`` or the one-line error; summaries are NaN (and
        ``regime`` -1) for a failed case.

    Raises
    ------
    KeyboardInterrupt
        When interrupted, so that an interrupted case is never recorded.
    """
    started = time.perf_counter()
    method = ""
    try:
        scene = spec.case_scene(index)
        summaries, method, full = solve_case(scene, per_cycle=spec.per_cycle)
        status = "ok"
    except KeyboardInterrupt:
        raise
    except _CaseInterrupted:
        raise KeyboardInterrupt from None
    except Exception as error:  # a failing case is a result, not the end of the sweep
        summaries, full = _empty_summaries(), None
        status = _one_line(error)
    return CaseResult(index, summaries, status, method, time.perf_counter() - started, full if keep_full else None)


def _one_line(error: BaseException) -> str:
    text = str(error) if isinstance(error, HalfslipInputError) else f"{type(error).__name__}: {error}"
    return " ".join(text.split()) or type(error).__name__


# -- running -------------------------------------------------------------------


class _ProgressLine:
    """Cases done of all, failed, cases/s and time left: :class:`halfslip.progress.Progress`.

    A line on a terminal (stderr), a bar in a notebook; the rate is the
    recent one (an exponential mean), not the average since the start.
    """

    def __init__(self, enabled: bool, stream=None):
        from ..progress import Progress

        self.progress = Progress("case", "cases", enabled=enabled, file=stream)
        self.done = None

    def start(self, total: int, done: int) -> None:
        """Show the bar: `done` of `total` cases are done before this call runs any."""
        self.progress.start(total, done)
        self.done = done

    def __call__(self, done: int, failed: int, total: int, ran: int) -> None:
        if self.done is None:
            self.start(total, done - ran)
        self.progress.note(f"{failed} failed")
        self.progress.advance(done - self.done)
        self.done = done

    def close(self) -> None:
        self.progress.close()


def sweep(
    spec_or_path: Sweep | Mapping[str, Any] | str | os.PathLike,
    *,
    output: str | os.PathLike | None = None,
    workers: int | None = None,
    scheduler: Any = None,
    cases_dir: str | os.PathLike | None = None,
    progress: bool | Callable[[int, int, int], None] = True,
    checkpoint_seconds: float = CHECKPOINT_SECONDS,
) -> xr.Dataset:
    """Run every case of a sweep and return one dataset of per-case summaries.

    Parameters
    ----------
    spec_or_path : Sweep, mapping or path
        A sweep file, its plain data (scene path relative to the working
        directory) or a :class:`Sweep`.
    output : path, optional
        HDF5 file, rewritten atomically every `checkpoint_seconds` and at the
        end. If it already holds an unfinished run of the same sweep, only
        the cases not yet done run; a different sweep there is an error.
    workers : int, optional
        1 runs in this process; more run that many local worker processes
        (default: the number of cores). Ignored with `scheduler`.
    scheduler : str or distributed.Client, optional
        Address of a running ``dask.distributed`` scheduler (or a client
        connected to one); the cases run on its workers, which must be able
        to import the same halfslip and read files the scene names.
    cases_dir : path, optional
        Also write each case's full result (steady-state or simulation
        dataset) to ``case_<index>.h5`` in this folder.
    progress : bool or callable(done, failed, total)
        True shows a progress line on stderr when it is a terminal (a bar in
        a notebook, :mod:`halfslip.progress`); a
        callable is called in this process after every finished case.
        Raising KeyboardInterrupt from it stops the sweep like Ctrl-C.
    checkpoint_seconds : float
        Interval between rewrites of `output`.

    Returns
    -------
    xarray.Dataset
        Summaries (``SUMMARIES``) over the sweep's dimensions, with attributes
        ``sweep_hash``, ``sweep`` (the sweep file), ``scene`` (the base scene),
        ``complete`` (0 when interrupted), ``count_cases``, ``count_done``,
        ``count_failed``, ``count_run`` (cases run by this call), ``wall_time``,
        ``backend``.

    Raises
    ------
    HalfslipInputError
        For a bad sweep file, a bad base scene, or an `output` holding a
        different sweep.
    """
    from .._version import __version__
    from ..io import read_result, write_result

    if isinstance(spec_or_path, Sweep):
        spec = spec_or_path
    elif isinstance(spec_or_path, Mapping):
        spec = parse_sweep(spec_or_path)
    else:
        spec = load_sweep(spec_or_path)
    table = _Table(spec)
    out = Path(output) if output is not None else None
    if out is not None:
        if not out.parent.exists():
            raise HalfslipInputError(f"folder {str(out.parent)!r} does not exist", field="output")
        if out.exists():
            _restore(table, spec, out, read_result)
    cases = Path(cases_dir) if cases_dir is not None else None
    if cases is not None:
        cases.mkdir(parents=True, exist_ok=True)
    pending = [int(i) for i in np.flatnonzero(~table.done)]

    if scheduler is not None:
        backend = "dask"
    else:
        workers = int(workers) if workers is not None else (os.cpu_count() or 1)
        if workers < 1:
            raise HalfslipInputError(f"must be >= 1, got {workers}", field="workers")
        backend = "in-process" if min(workers, len(pending)) <= 1 else "processes"
    width = len(str(max(spec.n_cases - 1, 0)))
    show = _ProgressLine(progress is True and interactive())
    show.start(spec.n_cases, spec.n_cases - len(pending))
    callback = progress if callable(progress) else None
    attrs = {
        "title": f"halfslip sweep over {', '.join(spec.paths)}",
        "Conventions": CONVENTIONS,  # as written (io.write_run): the dataset and its file agree
        "halfslip_version": __version__,
        "sweep_hash": spec.hash,
        "sweep_kind": spec.kind,
        "sweep_paths": json.dumps(list(spec.paths)),
        "sweep_names": json.dumps(list(spec.names)),
        "sweep": spec.text,
        "sweep_file": str(spec.file) if spec.file is not None else "",
        "scene_file": str(spec.scene_path),
        "scene": spec.scene_text,
        "per_cycle": int(spec.per_cycle),
        "backend": backend,
    }
    state = {"ran": 0, "last_write": time.perf_counter(), "complete": 1}
    started = time.perf_counter()

    def finish_attrs() -> dict[str, Any]:
        done = int(table.done.sum())
        return {
            **attrs,
            "complete": int(state["complete"] and done == spec.n_cases),
            "count_cases": spec.n_cases,
            "count_done": done,
            "count_failed": table.failed,
            "count_run": state["ran"],
            "wall_time": time.perf_counter() - started,
        }

    def write(force: bool = False) -> None:
        now = time.perf_counter()
        if out is not None and (force or now - state["last_write"] >= checkpoint_seconds):
            with _signals_deferred():
                write_result(table.dataset(finish_attrs()), out)
            state["last_write"] = time.perf_counter()

    def on_result(result: CaseResult) -> None:
        if cases is not None and result.full is not None:  # first, so that a recorded case has its file
            full = result.full.assign_attrs(
                sweep_hash=spec.hash, sweep_case=result.index,
                sweep_overrides=json.dumps(spec.overrides(result.index), default=repr),
            )
            with _signals_deferred():
                write_result(full, cases / f"case_{result.index:0{width}d}.h5")
        table.record(result)
        state["ran"] += 1
        done = int(table.done.sum())
        show(done, table.failed, spec.n_cases, state["ran"])
        if callback is not None:
            callback(done, table.failed, spec.n_cases)
        write()

    keep_full = cases is not None
    try:
        if backend == "in-process":
            _run_here(spec, pending, keep_full, on_result)
        elif backend == "processes":
            _run_processes(spec, pending, keep_full, on_result, workers)
        else:
            _run_dask(spec, pending, keep_full, on_result, scheduler)
    except KeyboardInterrupt:  # like simulate: stop, keep what is done, say so in `complete`
        state["complete"] = 0
    except BaseException:
        show.close()
        with contextlib.suppress(Exception):  # keep the finished cases; never mask the error
            write(force=True)
        raise
    show.close()
    write(force=True)
    return table.dataset(finish_attrs())


def _restore(table: _Table, spec: Sweep, out: Path, read_result) -> None:
    try:
        previous = read_result(out)
    except Exception as error:
        raise HalfslipInputError(
            f"exists but is not a readable result file ({type(error).__name__}); choose another output",
            file=str(out), field="output",
        ) from None
    found = previous.attrs.get("sweep_hash")
    if found is None or "done" not in previous:
        raise HalfslipInputError(
            "exists and is not a sweep result; choose another output or remove the file",
            file=str(out), field="output",
        )
    if found != spec.hash:
        raise HalfslipInputError(
            f"holds a different sweep (sweep_hash {str(found)[:12]}..., this sweep {spec.hash[:12]}...): the "
            "scene, the values or the options differ; choose another output or remove the file to start over",
            file=str(out), field="output",
        )
    table.restore(previous)


@contextlib.contextmanager
def _signals_deferred():
    """Hold Ctrl-C and SIGTERM off while a file is written; raise KeyboardInterrupt after it.

    An interrupt inside h5netcdf/h5py would leave a half-closed file and a
    traceback on stderr; the write itself is atomic, so waiting for it is
    short and safe. Outside the main thread this does nothing.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught = []
    signals = [signal.SIGINT] + ([signal.SIGTERM] if hasattr(signal, "SIGTERM") else [])
    previous = {}
    for number in signals:
        previous[number] = signal.signal(number, lambda signum, frame: caught.append(signum))
    try:
        yield
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler if handler is not None else signal.SIG_DFL)
    if caught:
        raise KeyboardInterrupt


class _InterruptFlag:
    """While active (main thread only), note that Ctrl-C (or a SIGTERM mapped to it) came.

    Needed because :func:`~halfslip.simulator.simulate` swallows
    KeyboardInterrupt and returns a partial run: the flag tells the driver
    that the case that was running when the signal came is not to be
    recorded. Handlers set in Python (the default Ctrl-C handler, the CLI's
    SIGTERM handler) are wrapped and still run; others are left alone.
    """

    def __init__(self):
        self.raised = False
        self.previous = {}

    def __enter__(self):
        if threading.current_thread() is not threading.main_thread():
            return self
        for number in (signal.SIGINT, getattr(signal, "SIGTERM", None)):
            if number is None:
                continue
            handler = signal.getsignal(number)
            if callable(handler):
                def wrapped(signum, frame, handler=handler):
                    self.raised = True
                    handler(signum, frame)

                self.previous[number] = signal.signal(number, wrapped)
        return self

    def __exit__(self, *exc):
        for number, handler in self.previous.items():
            signal.signal(number, handler)
        return False


def _run_here(spec: Sweep, pending: list[int], keep_full: bool, on_result) -> None:
    with _InterruptFlag() as flag:
        for index in pending:
            result = run_case(spec, index, keep_full=keep_full)
            if flag.raised:
                raise KeyboardInterrupt
            on_result(result)


_PRELOAD = ["halfslip.sweep", "halfslip.steady", "halfslip.simulator", "halfslip.solvers", "dask.array"]
"""Modules the forkserver imports once for all workers (xarray imports dask.array on first use when
dask is installed; a module that fails to import is skipped)."""


def _process_context():
    """forkserver where there is one (workers fork from a server that has imported
    halfslip: fast start, and safe when this process has threads), else spawn."""
    import multiprocessing

    if "forkserver" in multiprocessing.get_all_start_methods():
        context = multiprocessing.get_context("forkserver")
        context.set_forkserver_preload(_PRELOAD)
        return context
    return multiprocessing.get_context("spawn")


def _run_processes(spec: Sweep, pending: list[int], keep_full: bool, on_result, workers: int) -> None:
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

    workers = min(workers, len(pending))
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=_process_context(),
                               initializer=_init_worker, initargs=(spec,))
    queue = iter(pending)
    running = set()
    depth = 4 * workers  # bounded queue: Ctrl-C has little to cancel, memory stays flat
    finished = False
    try:
        for index in queue:
            running.add(pool.submit(_run_in_worker, index, keep_full))
            if len(running) >= depth:
                break
        while running:
            completed, running = wait(running, return_when=FIRST_COMPLETED)
            for future in completed:
                on_result(future.result())
                for index in queue:
                    running.add(pool.submit(_run_in_worker, index, keep_full))
                    break
        finished = True
    finally:
        if finished:
            pool.shutdown(wait=True)
        else:  # interrupted or failed: drop what is queued, stop what runs
            processes = list((getattr(pool, "_processes", None) or {}).values())
            pool.shutdown(wait=False, cancel_futures=True)
            for process in processes:
                if process.is_alive():
                    process.terminate()


def _run_dask(spec: Sweep, pending: list[int], keep_full: bool, on_result, scheduler: Any) -> None:
    try:
        from distributed import Client, as_completed
    except ImportError:
        raise ImportError(
            "a dask scheduler needs dask.distributed: pip install 'halfslip[sweep]' (or 'dask[distributed]')"
        ) from None
    own = not isinstance(scheduler, Client)
    if own:
        import dask
        from dask.utils import parse_timedelta

        address = getattr(scheduler, "scheduler_address", scheduler)  # a cluster object or an address
        timeout = min(10.0, parse_timedelta(dask.config.get("distributed.comm.timeouts.connect"), "s"))
        try:
            client = Client(address, timeout=timeout, set_as_default=False)
        except (OSError, TimeoutError) as error:
            raise HalfslipInputError(f"cannot reach a dask scheduler at {scheduler!r}: {error}",
                                     field="scheduler") from None
    else:
        client = scheduler
    futures = []
    try:
        if pending:
            shared = client.scatter(spec, broadcast=True, hash=False)
            token = uuid.uuid4().hex[:12]
            futures = client.map(run_case, [shared] * len(pending), pending, keep_full=keep_full,
                                 pure=False, key=[f"halfslip-case-{token}-{i}" for i in pending])
            for future in as_completed(futures, loop=client.loop):
                on_result(future.result())
    finally:
        if futures:
            client.cancel(futures)
        if own:
            client.close()


