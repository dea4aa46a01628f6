"""Entry point of the ``halfslip`` command: the CLI, with start-up interrupts handled.

Importing halfslip (numpy, scipy, xarray) takes about a second. An interrupt
in that second would end in a KeyboardInterrupt traceback from the import,
before :func:`halfslip.cli.main` could handle it; this module imports nothing
heavy itself, so it can: one line, exit status 130.
"""
import sys


def main() -> None:
    try:
        from halfslip.cli import run_as_program
    except KeyboardInterrupt:
        sys.stderr.write("halfslip: interrupted\n")
        sys.exit(130)
    run_as_program()


if __name__ == "__main__":
    main()
