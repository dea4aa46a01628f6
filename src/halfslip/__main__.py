"""``python -m halfslip``: the command line (halfslip.cli)."""
import gc

from halfslip.cli import run_as_program

if __name__ == "__main__":
    # what the import made lives as long as the command: out of the collector's full passes, as the
    # ``halfslip`` script's (halfslip_launch._freeze_imports; here the import has run with the collector on)
    gc.freeze()
    run_as_program()
