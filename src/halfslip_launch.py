"""Entry point of the ``halfslip`` command: the CLI, with start-up interrupts handled.

Importing halfslip (numpy, scipy, xarray) takes about a second. An
interrupt in that second would end in a KeyboardInterrupt traceback from the
import, before :func:`halfslip.cli.main` could handle it; this module imports
nothing heavy itself, so it can: one line, exit status 130.

An interrupt can also land while Python runs a callback of its own (the import
system releases its module locks in weakref callbacks): Python then prints
"Exception ignored in ..." with the KeyboardInterrupt and carries on, and the
run went on to finish with status 0 as if no Ctrl-C had come (seen once in
CI, an interrupt 0.3 s into start-up). During the import such an interrupt is
recorded instead, and the command ends as interrupted once the import is done.

And an interrupt can land inside an extension module's own import, which turns
it into an ImportError (numpy importing datetime through PyCapsule_Import:
"PyCapsule_Import could not import module "datetime"", a traceback and status
1; seen once in about a dozen tries, 0.3 s into start-up). So the import runs
under a SIGINT handler that records the signal before it raises the
KeyboardInterrupt as Python's own does: whatever the import then ends in, a
recorded signal ends the command as interrupted.
"""
import gc
import signal
import sys


_lost = []
"""KeyboardInterrupts that Python could not raise during the import (they came inside a callback)."""

_signalled = []
"""SIGINTs received during the import."""


def _on_sigint(signum, frame):
    """SIGINT during the import: recorded, then raised as Python's default handler does."""
    _signalled.append(signum)
    raise KeyboardInterrupt


def _record_interrupts(unraisable) -> None:
    """sys.unraisablehook during the import: keep a KeyboardInterrupt Python could not raise; anything
    else as Python would."""
    if isinstance(unraisable.exc_value, KeyboardInterrupt):
        _lost.append(unraisable.exc_value)
        return
    sys.__unraisablehook__(unraisable)


def _interrupted() -> None:
    sys.stderr.write("halfslip: interrupted\n")
    sys.exit(130)


def main() -> None:
    sys.unraisablehook = _record_interrupts
    previous = signal.signal(signal.SIGINT, _on_sigint)
    gc.disable()  # (the import's objects are kept for the whole command: frozen below)
    try:
        from halfslip.cli import run_as_program
    except KeyboardInterrupt:
        _interrupted()
    except BaseException:
        if _signalled:  # the interrupt became another exception on its way out of the import
            _interrupted()
        raise
    finally:
        signal.signal(signal.SIGINT, previous)
        sys.unraisablehook = sys.__unraisablehook__
        _freeze_imports()
    if _lost or _signalled:
        _interrupted()
    run_as_program()


def _freeze_imports() -> None:
    """What the import made (about 140,000 objects: numpy's, scipy's, xarray's, numba's and llvmlite's) lives
    as long as the command: the garbage collector's full passes skip it (:func:`gc.freeze`), and it ran
    disabled during the import, which would otherwise have walked the growing heap three times over (the
    import leaves under a thousand unreachable objects, which stay). Measured on `halfslip run
    examples/dovetail.yaml`: 4 full passes of 25-93 ms, 210 ms in all (during the imports of scipy, xarray and
    numba, and one at exit) before, one of 15 ms after; the whole command 2.98 -> 2.58 s, the motor loop's
    1.69 -> 1.43 s (docs/benchmarks.md, bench_examples.py against 0.4.11). The command's own objects are
    collected as usual."""
    gc.freeze()
    gc.enable()


if __name__ == "__main__":
    main()
