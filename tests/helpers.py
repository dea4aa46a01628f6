"""Helpers shared by the test files: bodies, solvers, marching, scene texts.

Imported as ``from helpers import ...`` (pytest puts this folder on the path,
as it does for conftest.py). Steel on steel, per unit depth:
A = 4 (1 - nu^2) / E with E = 200 GPa, nu = 0.3; f = 0.6; P0 = 1e5 N/m.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Callable, Iterable

import numpy as np

from halfslip.geometry import Hertz, NormalProblem, RoundedPunch
from halfslip.state import Loads

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
#: The smallest valid scene text (a Hertz pad loaded by P alone).
MINIMAL_SCENE = """\
material: {E: 200e9, nu: 0.3}
friction: 0.6
geometry: {kind: hertz, radius: 50e-3}
loads:
  - ramp: {to: {P: 1e5}, duration: 1, steps: 10}
"""
DATA = Path(__file__).resolve().parent / "data"

A = 4 * (1 - 0.3**2) / 200e9
"""Compliance 4(1 - nu^2)/E of steel on steel [1/Pa]."""
F = 0.6
P0 = 1.0e5
R_HERTZ = 50e-3
W_FLAT = 0.2e-3
R_CORNER = 10e-3

PROFILES = {
    "hertz": Hertz(radius=R_HERTZ),
    "punch": RoundedPunch(flat_half_width=W_FLAT, radius=R_CORNER),
}


def make(kind: str, method: str = "general", *, nodes: int = 256, P_max: float = P0, stations=None, **kw):
    """``(problem, solver)`` for profile `kind` ('hertz' or 'punch') and `method` ('exact' or 'general')."""
    problem = NormalProblem(PROFILES[kind], A)
    if method == "exact":
        from halfslip.solvers.exact import ExactMemory

        return problem, ExactMemory(problem, F, P_max, stations=stations, **kw)
    from halfslip.solvers.general import GeneralSolver

    return problem, GeneralSolver(problem, F, nodes, **kw)


def j3_stick_load(P: float, k: float, k_unload: float) -> float:
    """J3: loaded in proportion to (P0, k f P0), then unloaded to P along dQ = k_unload f dP; the stick zone
    is the contact of this load, P - abs(k_unload - k) (P0 - P) / (1 +- k) (+ for k_unload > k, where the
    edges slip backwards; the levels above it set to -+f)."""
    return P - abs(k_unload - k) * (P0 - P) / (1 + k if k_unload > k else 1 - k)


def march(solver, path: Iterable, state=None, t0: float = 0.0, check: Callable | None = None) -> list:
    """Step `solver` through `path` (tuples of up to four loads P, Q, M, sigma) at t0 + 1, t0 + 2, ...

    Returns the list of ``(state, report)``; ``check(previous, state, report)``
    is called after every step when given.
    """
    state = solver.initial_state() if state is None else state
    out = []
    for i, loads in enumerate(path):
        loads = tuple(loads) + (0.0,) * (4 - len(loads))
        previous = state
        state, report = solver.step(state, t0 + i + 1.0, Loads(*loads))
        if check is not None:
            check(previous, state, report)
        out.append((state, report))
    return out


def states(solver, path: Iterable, state=None, t0: float = 0.0) -> list:
    """The states of :func:`march`."""
    return [s for s, _ in march(solver, path, state, t0)]


def example_text(name: str, **replace: str) -> str:
    """The text of ``examples/<name>.yaml`` with each ``old=new`` of `replace` applied (keys: old text)."""
    text = (EXAMPLES / f"{name}.yaml").read_text()
    for old, new in replace.items():
        assert old in text, old
        text = text.replace(old, new)
    return text


def hertz_pad_text(count: int = 20, steps: int = 100, extra: str = "") -> str:
    """hertz_pad.yaml with another cycle count / resolution and extra top-level YAML."""
    text = (EXAMPLES / "hertz_pad.yaml").read_text()
    text = text.replace("count: 20", f"count: {count}").replace("steps_per_cycle: 100", f"steps_per_cycle: {steps}")
    return text + extra


def hertz_pad_segments(count: int = 20, steps: int = 100) -> list:
    """The ``loads`` of :func:`hertz_pad_text` as Python data (for ``LoadHistory.from_segments``)."""
    return [
        {"ramp": {"to": {"P": 1.0e5}, "duration": 1.0, "steps": 20}},
        {"cycles": {"count": count, "period": 1.0, "steps_per_cycle": steps, "Q": {"amplitude": 1.8e4}}},
    ]


#: A long Hertz motor-support history (16,010 steps, no skipping): a run of it is still going when
#: a test interrupts it or starts a second writer.
LONG_MOTOR_SCENE = """
name: long-motor
material: {E: 200.0e9, nu: 0.3}
friction: 0.6
geometry: {kind: hertz, radius: 50.0e-3}
loads:
  - ramp: {to: {P: 1.0e5, Q: 3.0e4}, duration: 1.0, steps: 10}
  - cycles:
      count: 40
      period: 1.0
      steps_per_cycle: 400
      P: {amplitude: 3.0e4}
      Q: {mean: 0.0, amplitude: 3.0e4, phase: 90.0}
solver: {skip_steady_cycles: false}
output: {fields: [p, q, slip], points: 81}
"""

#: A rounded punch (the dovetail's) pressed, then Q and sigma raised together: slip zones that grow from a
#: fraction of a cell to about one cell at 64 .. 128 nodes, within about 1 % of the width.
NARROW_SLIP_SCENE = """
name: narrow-slip
material: {E: 115.0e9, nu: 0.3}
friction: 0.6
geometry: {kind: rounded_punch, flat_half_width: 2.0e-3, radius: 10.0e-3}
loads:
  - ramp: {to: {P: 2.0e5}, duration: 1.0, steps: 4}
  - ramp: {to: {Q: 6.0e4, sigma: 1.0e7}, duration: 1.0, steps: 8}
solver: {method: general}
output: {fields: []}
"""


def as_from_a_terminal() -> None:
    """In a child process (``preexec_fn``): Ctrl-C delivered as at a terminal.

    A background job of a non-interactive shell starts with SIGINT ignored, and
    its children inherit that; a test that interrupts a child must undo it.
    """
    import signal

    signal.signal(signal.SIGINT, signal.SIG_DFL)


_GAUSS_U, _GAUSS_W = np.polynomial.legendre.leggauss(40)


def stuck_shear(problem, path, x):
    """The exact shear at ``x`` after the straight steps ``path`` (tuples P, Q, M, sigma from zero) while every
    point sticks: by (M1) with the sigma term, the fully stuck increments dQ / (pi sqrt(d^2 - s^2)) + dsigma s /
    (4 sqrt(d^2 - s^2)) (s = x - c) over the contacts (centre c, half-width d: the normal problem's at each
    node) from x's arrival on (found by bisection), the inverse square root there taken out by lam = lam_x + (1 -
    lam_x) u^2, 40 Gauss points in u."""
    loads = [(0.0, 0.0, 0.0, 0.0), *path]

    def edges(k, lam):
        (Pa, _, Ma, _), (Pb, _, Mb, _) = loads[k - 1], loads[k]
        sol = problem.solve(Pa + lam * (Pb - Pa), Ma + lam * (Mb - Ma))
        return sol.left, sol.right

    total = 0.0
    u, w = 0.5 * (_GAUSS_U + 1.0), 0.5 * _GAUSS_W
    for k in range(1, len(loads)):
        start = edges(k, 0.0) if loads[k - 1][0] > 0.0 else None
        if start is not None and start[0] < x < start[1]:
            arrival = 0.0
        else:
            left, right = edges(k, 1.0)
            if not left < x < right:
                continue
            lo, hi = 0.0, 1.0
            for _ in range(50):
                mid = 0.5 * (lo + hi)
                left, right = edges(k, mid)
                lo, hi = (lo, mid) if left < x < right else (mid, hi)
            arrival = hi
        dQ, dS = loads[k][1] - loads[k - 1][1], loads[k][3] - loads[k - 1][3]
        for ui, wi in zip(u, w):
            lam = arrival + (1.0 - arrival) * ui * ui
            left, right = edges(k, lam)
            c, d = 0.5 * (left + right), 0.5 * (right - left)
            root = math.sqrt(max(d * d - (x - c) ** 2, 1e-300))
            total += wi * 2.0 * (1.0 - arrival) * ui * (dQ / (math.pi * root) + dS * (x - c) / (4.0 * root))
    return total
