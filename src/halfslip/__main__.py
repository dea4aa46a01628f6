"""``python -m halfslip``: the command line."""
from .cli import main

main()
