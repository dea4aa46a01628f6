"""``python -m halfslip``: the command line (halfslip.cli)."""
from halfslip.cli import main

if __name__ == "__main__":
    main(prog_name="halfslip")
