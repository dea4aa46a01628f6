"""The contact state carried between steps, and what a step reports.

The state is immutable: a step returns a new :class:`ContactState` and never
modifies the one it was given. Solver-specific memory (the load-level function
w(P') of the exact method, the locked-in strains of the general solver) lives in
``memory``, itself immutable.
"""
from __future__ import annotations

import enum
import math
import re
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np


class Loads(NamedTuple):
    """The four loads of a half-plane contact, SI per unit depth."""

    P: float
    Q: float
    M: float
    sigma: float


GROSS_SLIDING_MESSAGE = "abs(Q) > f P: gross sliding, shear force carried limited to f P"
"""What a step reports when the applied shear exceeds what friction can carry."""

EDGE_PATH_MESSAGE = ("edge path: the contact edges along the step interpolated to {error:.3g} of the width only "
                     "(the path is not smooth: a contact edge crossing a kink of the profile); the locks of the material arriving in the "
                     "step are less accurate")
"""What a step of the general solver reports when its contact edges along the step (from which the material
arriving in it takes its locked displacement) could not be interpolated within their allowance
(_general_path.EdgePath._verify); ``error`` relative to the contact's width."""
EDGE_PATH_PATTERN = re.compile(re.escape(EDGE_PATH_MESSAGE.split("{")[0]) + r"(?P<v>\S+)"
                               + re.escape(EDGE_PATH_MESSAGE.split("}")[1]))
"""EDGE_PATH_MESSAGE with any number (group ``v``)."""


class Regime(enum.IntEnum):
    """What a step did; stored in the ``regime`` variable of the result."""

    SEPARATED = 0
    STICK = 1
    PARTIAL_SLIP = 2
    GROSS_SLIDING = 3

    @classmethod
    def flag_meanings(cls) -> str:
        """The CF ``flag_meanings`` of a stored regime: ``separated stick partial_slip gross_sliding``."""
        return " ".join(m.name.lower() for m in cls)

    @classmethod
    def flag_values(cls) -> np.ndarray:
        """The CF ``flag_values`` of a stored regime (int8, in the order of :meth:`flag_meanings`)."""
        return np.array([int(m) for m in cls], dtype=np.int8)


def frozen(a) -> np.ndarray:
    """``a`` as an array, made read-only in place (the one helper for immutable arrays of a state).

    Copy first (``frozen(np.array(a, float))``) when the caller's array must stay writable.
    """
    a = np.asarray(a)
    a.flags.writeable = False
    return a


@dataclass(frozen=True)
class StepReport:
    """What one step did.

    Attributes
    ----------
    regime : Regime
        Outcome of the step (state at its end).
    slipped : bool
        Whether any point slipped during the step (a slip solve was needed).
    normal_solved : bool
        Whether the normal problem was solved (False when P and M were unchanged
        or the method needs no normal solve).
    message : str
        Anything the user should hear about, e.g. a clamped shear force.
    converged : bool
        Whether the method met its own tolerance in this step. A step that did
        not is still returned (with the best state the method found) and is
        recorded as such in the result (``converged`` = 0); it never drives
        control flow through its message.
    residual : float
        The method's measure of how far the step's answer is from meeting its
        checks, relative to their tolerance (<= 1 when converged; 0 for an exact
        method).
    iterations : int
        Iterations of the method's solve (0 when it needs none).
    error_estimate : float
        The method's estimate of its discretisation error in the stick edges,
        relative to the contact width (NaN when it makes none; 0 for an exact method).
    shear_error_estimate : float
        The method's estimate of its discretisation error in the shear traction:
        int abs(q - q_exact) dx relative to f P (NaN when it makes none; 0 for an
        exact method).
    """

    regime: Regime
    slipped: bool
    normal_solved: bool
    message: str = ""
    converged: bool = True
    residual: float = 0.0
    iterations: int = 0
    error_estimate: float = math.nan
    shear_error_estimate: float = math.nan


@dataclass(frozen=True)
class ContactState:
    """State of the contact at the end of a step.

    Attributes
    ----------
    t : float
        Time [s].
    loads : Loads
        Applied loads at ``t``.
    contact_left, contact_right : float
        Contact edges [m]; NaN when separated.
    stick_left, stick_right : float
        Stick-zone edges [m]; NaN when nothing sticks.
    shift : float
        Rigid tangential displacement of pad relative to substrate [m], with the
        datum of the logarithmic kernel stated by the method.
    dissipation : float
        Frictional energy dissipated since the start [J/m].
    memory : Any
        Method-specific immutable memory.
    """

    t: float
    loads: Loads
    contact_left: float
    contact_right: float
    stick_left: float
    stick_right: float
    shift: float
    dissipation: float
    memory: Any = field(repr=False)


def as_float_array(x) -> np.ndarray:
    """Return ``x`` as a 1-D float array (a scalar becomes shape (1,))."""
    return np.atleast_1d(np.asarray(x, dtype=float))
