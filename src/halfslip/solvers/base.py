"""The step contract every tangential method keeps.

A method (``ExactMemory``, ``GeneralSolver``) is a :class:`TangentialSolver`:
``initial_state(t0)`` and ``step(state, t1, loads1) -> (state, report)``. The
step is a function of its arguments; it never writes output, and its
:class:`~halfslip.state.StepReport` says what happened *and whether the
method met its own tolerance* (``converged``), with the numbers behind that
verdict (``iterations``, ``residual``, ``error_estimate``). What to do with a
step that did not converge is the simulator's decision (it records it, counts
it and says so in the summary); no message text drives control flow.

The optional capabilities are attributes with a default here, so that the
simulator asks the base class, never ``getattr`` with a string:

- ``can_march``: a compiled ``march`` of many steps (extents only) is offered;
- ``same_state(a, b)``: two states are the same to the method's tolerance
  (cycle skipping); the default is bit-identical memories;
- ``cycle_tolerance``: None, or a method ``cycle_tolerance(state)`` giving
  the tolerance [m] to which the stick edges of every step of a cycle must
  also repeat (a method whose states agree only to a tolerance).
"""
from __future__ import annotations

import abc

import numpy as np

from ..state import ContactState, Loads, StepReport


class TangentialSolver(abc.ABC):
    """A tangential method: marches the contact state through straight load steps.

    Attributes
    ----------
    name : str
        The method's name in results (``method`` attribute).
    datum : float
        Length l of the log-kernel datum of the rigid shift [m].
    can_march : bool
        Whether :meth:`march` is available (compiled marching, extents only).
    """

    name: str = ""
    datum: float = float("nan")
    can_march: bool = False

    @abc.abstractmethod
    def initial_state(self, t0: float = 0.0) -> ContactState:
        """The unloaded state at time ``t0``."""

    @abc.abstractmethod
    def step(self, state: ContactState, t1: float, loads1: Loads) -> tuple[ContactState, StepReport]:
        """Advance ``state`` along the straight line to ``loads1`` at ``t1``; ``state`` is not modified."""

    @abc.abstractmethod
    def tractions(self, memory, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Pressure p and shear q at surface points ``x`` [Pa]."""

    @abc.abstractmethod
    def slip(self, memory) -> np.ndarray:
        """Accumulated slip at the solver's stations [m]."""

    def same_state(self, a: ContactState, b: ContactState) -> bool:
        """Whether two states are the same to the method's tolerance (default: identical memory)."""
        return _identical(a.memory, b.memory)

    #: None, or ``cycle_tolerance(state) -> float`` [m]: see the module notes.
    cycle_tolerance = None

    def stick_intervals(self, state: ContactState) -> int:
        """Number of stick intervals of the state (a method that represents one interval: 0 or 1)."""
        return 0 if np.isnan(state.stick_left) else 1

    def station_states(self, state: ContactState, x: np.ndarray, q: np.ndarray) -> np.ndarray:
        """What each surface station did in the step that ended in ``state`` (STATION_STATES codes).

        Outside the contact: out of contact; inside the stick zone: stick;
        elsewhere in the contact the point slipped in the step, in the
        direction of q (friction opposes the slip of the substrate, so q has
        the sign of the pad's slip, physics.md). A station in a slip zone
        where q is zero (at a contact edge) takes the direction of its nearest
        slipping neighbour.
        """
        codes = np.zeros(x.shape, np.int8)
        if np.isnan(state.contact_left):
            return codes
        inside = (x >= state.contact_left) & (x <= state.contact_right)
        stuck = inside & (x >= state.stick_left) & (x <= state.stick_right)
        slipping = inside & ~stuck
        direction = np.sign(q)
        known = slipping & (direction != 0)
        if np.any(slipping & ~known) and np.any(known):
            idx = np.flatnonzero(known)
            fill = idx[np.abs(np.arange(x.size)[:, None] - idx[None, :]).argmin(axis=1)]
            direction = np.where(known, direction, direction[fill])
        codes[stuck] = STICK
        codes[slipping & (direction >= 0)] = FORWARD_SLIP
        codes[slipping & (direction < 0)] = BACKWARD_SLIP
        return codes


#: Codes of the per-station ``state`` field.
OUT_OF_CONTACT, STICK, FORWARD_SLIP, BACKWARD_SLIP = 0, 1, 2, 3
STATION_STATES = "out_of_contact stick forward_slip backward_slip"


def _identical(a, b) -> bool:
    """Field-by-field identity of two memories (arrays compared exactly)."""
    import dataclasses

    if type(a) is not type(b):
        return False
    if dataclasses.is_dataclass(a):
        return all(_identical(getattr(a, f.name), getattr(b, f.name)) for f in dataclasses.fields(a))
    if isinstance(a, np.ndarray):
        return a.shape == b.shape and bool(np.array_equal(a, b, equal_nan=True))
    if isinstance(a, (tuple, list)):
        return len(a) == len(b) and all(_identical(u, v) for u, v in zip(a, b))
    if isinstance(a, float) and a != a:
        return b != b
    return a == b
