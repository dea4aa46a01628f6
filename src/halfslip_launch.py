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
"""
import sys


_lost = []
"""KeyboardInterrupts that Python could not raise during the import (they came inside a callback)."""


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
    try:
        from halfslip.cli import run_as_program
    except KeyboardInterrupt:
        _interrupted()
    finally:
        sys.unraisablehook = sys.__unraisablehook__
    if _lost:
        _interrupted()
    run_as_program()


if __name__ == "__main__":
    main()
