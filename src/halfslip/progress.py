"""One progress display for runs and sweeps, on a terminal or in a notebook.

A thin layer over tqdm (``tqdm.auto``: a text line on a terminal, a widget
in Jupyter when ipywidgets is installed, text otherwise). tqdm brings what a
hand-written line lacked: a rate that is an exponentially weighted mean
(:data:`SMOOTHING`), so that uneven step costs move the estimate instead of
the run's average; a total that may change while running; rate limiting;
and a notebook display. halfslip adds the one thing tqdm cannot know: steps
skipped as repeats of a steady cycle are taken off the total, so the
estimate never counts on marching them and the bar does not jump to the end.
"""
from __future__ import annotations

import sys
from typing import Any, Callable

SMOOTHING = 0.3
"""Weight of the newest rate in tqdm's exponential mean (tqdm's default). Measured on
examples/tabulated.yaml, whose steps grow from 0.24 s to 3.5 s: at step 22 of 33 it
estimates 17 s left of a true 28 s, against 11 s with 0.1 and 9 s with the run's mean rate."""

MIN_INTERVAL = 0.2
"""Seconds between updates of the display, at least."""


def interactive(stream: Any = None) -> bool:
    """Whether someone watches `stream` (default stderr): a terminal, or a Jupyter kernel."""
    stream = sys.stderr if stream is None else stream
    try:
        if stream.isatty():
            return True
    except (AttributeError, ValueError):
        pass
    return "ipykernel" in sys.modules


class Progress:
    """A progress bar of steps (or cases) that knows about skipped work.

    Parameters
    ----------
    unit : str
        What is counted: "step" or "case".
    desc : str, optional
        Text before the bar (e.g. the scene name).
    enabled : bool
        False shows nothing (every method is then a no-op).
    delay : float
        Seconds before anything is shown (a short run shows nothing).
    file : text stream, optional
        Where to write (default stderr).

    Call :meth:`start` once with the total, then :meth:`advance` and
    :meth:`close` (or use it as a context manager).
    """

    def __init__(self, unit: str = "step", desc: str | None = None, *, enabled: bool = True, delay: float = 0.0,
                 file: Any = None):
        self.unit, self.desc, self.enabled, self.delay, self.file = unit, desc, enabled, delay, file
        self.bar = None
        self.skipped = 0

    def start(self, total: int, initial: int = 0) -> Progress:
        """Show a bar from `initial` done to `total` (both in units)."""
        if not self.enabled or self.bar is not None:
            return self
        from tqdm.auto import tqdm

        self.bar = tqdm(total=total, initial=initial, unit=self.unit, desc=self.desc, delay=self.delay,
                        file=self.file if self.file is not None else sys.stderr, smoothing=SMOOTHING,
                        mininterval=MIN_INTERVAL, dynamic_ncols=True)
        return self

    def advance(self, done: int = 1, skipped: int = 0) -> None:
        """`done` more units finished; `skipped` units of the total will never be worked (steady cycles)."""
        if self.bar is None:
            return
        if skipped:
            self.skipped += skipped
            self.bar.total = max(self.bar.total - skipped, self.bar.n + done)
            self.bar.set_postfix_str(f"{self.skipped:,} {self.unit}s skipped as steady cycles", refresh=False)
        self.bar.update(done)

    def note(self, text: str) -> None:
        """Text after the counts, e.g. ``1 failed``."""
        if self.bar is not None:
            self.bar.set_postfix_str(text, refresh=False)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


class _Callback(Progress):
    """A user's ``callable(i, n)``: called after each advance with the step index and the step count."""

    def __init__(self, function: Callable[[int, int], None]):
        super().__init__(enabled=False)
        self.function = function
        self.i = 0
        self.n = 0

    def start(self, total: int, initial: int = 0) -> Progress:
        self.n, self.i = total, initial
        return self

    def advance(self, done: int = 1, skipped: int = 0) -> None:
        self.i += done + skipped
        self.function(self.i, self.n)


def progress_for(progress: Any, unit: str = "step", desc: str | None = None) -> Progress:
    """The :class:`Progress` that a ``progress=`` argument asks for.

    True shows a bar (tqdm.auto), False or None nothing, a :class:`Progress`
    is used as given, and a callable is called as ``progress(i, n)`` with the
    step index reached and the number of steps of the history (the form
    ``simulate`` always took).
    """
    if isinstance(progress, Progress):
        return progress
    if progress is True:
        return Progress(unit, desc)
    if callable(progress):
        return _Callback(progress)
    return Progress(unit, desc, enabled=False)
