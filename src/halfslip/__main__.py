"""``python -m halfslip``: the command line (halfslip.cli)."""
from halfslip.cli import run_as_program

if __name__ == "__main__":
    run_as_program()
