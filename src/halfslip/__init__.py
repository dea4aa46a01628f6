"""halfslip: frictional partial slip of elastic half-plane contacts.

Public names are listed here explicitly; see docs/interface.md for the
user-facing contract (scene YAML, command line, result files).
"""
from .errors import HalfslipInputError
from .geometry import Hertz, Material, NormalProblem, RoundedPunch, TabulatedProfile
from .histories import LoadHistory, Segment
from .scene import OutputOptions, Scene, SolverOptions, load_scene, parse_scene
from .simulator import simulate
from .steady import steady_state
from .sweep import sweep
from . import post  # registers the ds.halfslip accessor
from ._version import __version__

__all__ = [
    "HalfslipInputError",
    "Hertz",
    "LoadHistory",
    "Material",
    "NormalProblem",
    "OutputOptions",
    "RoundedPunch",
    "Scene",
    "Segment",
    "SolverOptions",
    "TabulatedProfile",
    "__version__",
    "load_scene",
    "parse_scene",
    "simulate",
    "steady_state",
    "sweep",
]
