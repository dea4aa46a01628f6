"""SI prefixes for numbers people read: figure axes and the command line's summaries.

``unit_scale`` picks one prefix for a set of values (an axis);
``quantity`` writes one value with its prefix (``-240.7 µm``). No
dependency beyond numpy: the command line uses it without matplotlib.
"""
from __future__ import annotations

import math

import numpy as np

_PREFIXES = ((1e9, "G"), (1e6, "M"), (1e3, "k"), (1.0, ""), (1e-3, "m"), (1e-6, "µ"), (1e-9, "n"), (1e-12, "p"))


def unit_scale(values, unit: str) -> tuple[float, str]:
    """Factor and unit label so that the largest magnitude of `values` reads 1 .. 1000.

    Every figure scales its axes with this one helper: divide by the factor
    and write the label, e.g. ``unit_scale([2e-4], "m") == (1e-3, "mm")``,
    ``unit_scale([3e7], "Pa") == (1e6, "MPa")``. Forces per length read in
    N/m or kN/m (never mN/m), energies per area J/m² with a prefix.

    Parameters
    ----------
    values : array_like
        The values to be drawn (NaN ignored).
    unit : str
        Their SI unit (``m``, ``Pa``, ``N/m``, ``N``, ``J/m``, ``J/m^2``, ``s``).

    Returns
    -------
    (float, str)
    """
    values = np.asarray(values, float)
    finite = np.abs(values[np.isfinite(values)])
    top = float(finite.max()) if finite.size else 0.0
    pretty = unit.replace("^2", "²")
    if top == 0.0:
        return 1.0, pretty
    for factor, prefix in _PREFIXES:
        if top >= factor * (1 - 1e-12):
            break
    if unit.startswith("N/") or unit == "N":  # kN/m, not mN/m; forces read in N or kN
        factor, prefix = (1e3, "k") if top >= 1e3 else (1.0, "")
    if unit == "s":  # times read in s (ms for short runs)
        factor, prefix = (1e-3, "m") if top < 1.0 else (1.0, "")
    return factor, f"{prefix}{pretty}"


def quantity(value: float, unit: str, digits: int = 4) -> str:
    """`value` [SI `unit`] with the prefix :func:`unit_scale` picks, to `digits` significant digits.

    ``quantity(-2.40692e-4, "m") == "-240.7 µm"``, ``quantity(1.83e-4, "J/m") == "183 µJ/m"``;
    NaN is ``nan``, zero ``0 m``.
    """
    if not math.isfinite(value):
        return f"{value} {unit}".replace("^2", "²")
    factor, label = unit_scale([value], unit)
    return f"{value / factor:.{digits}g} {label}"


def interval(left: float, right: float, unit: str, digits: int = 4) -> str:
    """``[left, right] unit`` with one prefix for both: ``[-240.7, 240.7] µm``."""
    factor, label = unit_scale([left, right], unit)
    return f"[{left / factor:.{digits}g}, {right / factor:.{digits}g}] {label}"
