"""The installed version of halfslip, in a module of its own.

Modules inside the package read it from here rather than from the package
``__init__`` (which imports them), so that no import cycle runs through it.
"""
from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("halfslip")
except PackageNotFoundError:
    __version__ = "0.4.13"
