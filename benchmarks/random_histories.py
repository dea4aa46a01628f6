"""Seeded random (P, Q, M, sigma) histories for the reference of issue 14.

    from random_histories import random_history
    scene, t, P, Q, M, sigma = random_history(seed, geometry="hertz" | "punch", ramps=14, steps_per_ramp=8)

Straight ramps between random load points, ``steps_per_ramp`` equal steps
each, from the unloaded state (point 0 is t = 0, all loads zero; the arrays
have ramps * steps_per_ramp + 1 entries). ``scene`` is a ``halfslip.Scene``
with the same samples (``LoadHistory.from_arrays``), so ``halfslip.simulate``
marches exactly these steps.

Load points (nominal load P_n; a = contact half-width at P, w = flat half-width):

* P uniform in [0.4, 1.6] P_n (always > 0);
* Q = v f P, v uniform in [-0.8, 0.8]; with probability 0.1 an excursion
  v = +-U[0.9, 0.97] (close to gross sliding, not beyond); straight ramps keep
  |Q| < f P between the points (both linear). ``gross`` in the info dict flags
  any sample with |Q| >= f P (none by construction);
* M moves the contact centre by a sizeable fraction of the half-width:
  Hertz M = m P a with m uniform in [-0.6, 0.6] (the centre moves by m a);
  punch M = m P w / 2, m uniform in [-1.25, 1.25] (|m| above ~1.05 lifts the flat at
  one end). Every point, and 8 points along each ramp to it, is checked with
  the normal solver: the contact must exist, be at least 0.35 of the nominal
  width wide (no near-separation) and the solver must converge; otherwise the
  point is drawn again;
* sigma = u * 4 f P / (pi a), u uniform in [-0.6, 0.6]: the tension term of
  (T2) at the contact edge, (pi/4) a sigma, reaches 0.6 f P, comparable to Q,
  so that slip reverses at one edge in many steps.

Hertz: steel (E = 200 GPa, nu = 0.3), f = 0.6, R = 50 mm, P_n = 1e5 N/m.
Punch: the dovetail template (examples/dovetail.yaml): Ti-6Al-4V (115 GPa,
0.3), f = 0.6, w = 2 mm, corner radius 10 mm, P_n = 2e5 N/m.
"""
from __future__ import annotations

import math

import numpy as np

import halfslip as hs
from halfslip.geometry import Hertz, Material, NormalProblem, RoundedPunch

GEOMETRIES = {
    "hertz": dict(material=(200e9, 0.3), friction=0.6, profile=lambda: Hertz(50e-3), P_nominal=1e5),
    "punch": dict(material=(115e9, 0.3), friction=0.6, profile=lambda: RoundedPunch(2e-3, 10e-3),
                  P_nominal=2e5),
}


def parts(geometry):
    """(NormalProblem, friction, Material, profile) of a named geometry."""
    g = GEOMETRIES[geometry]
    material = Material(*g["material"])
    profile = g["profile"]()
    return NormalProblem(profile, material.compliance), g["friction"], material, profile


def _contact_ok(problem, P, M, width0):
    try:
        sol = problem.solve(P, M)
    except (ValueError, RuntimeError, ArithmeticError):
        return False
    return (not sol.separated) and sol.right - sol.left >= 0.35 * width0


def random_history(seed, geometry="hertz", ramps=14, steps_per_ramp=8, info=None):
    """Scene and samples (t, P, Q, M, sigma) of one seeded random history (module docstring).

    ``info``, if a dict, receives ``problem``, ``friction``, ``gross`` (bool array of samples with
    |Q| >= f P) and ``resampled`` (load points drawn again).
    """
    if geometry not in GEOMETRIES:
        raise ValueError(f"geometry must be one of {sorted(GEOMETRIES)}, got {geometry!r}")
    rng = np.random.default_rng(seed)
    problem, f, material, profile = parts(geometry)
    Pn = GEOMETRIES[geometry]["P_nominal"]
    sol_n = problem.solve(Pn, 0.0)
    width0 = sol_n.right - sol_n.left
    points = [(0.0, 0.0, 0.0, 0.0)]
    resampled = 0
    while len(points) < ramps + 1:
        P = Pn * rng.uniform(0.4, 1.6)
        a = problem.solve(P, 0.0).half_width
        v = rng.uniform(-0.8, 0.8)
        if rng.random() < 0.1:
            v = math.copysign(rng.uniform(0.9, 0.97), rng.uniform(-1, 1))
        Q = v * f * P
        m = rng.uniform(-0.6, 0.6) if geometry == "hertz" else rng.uniform(-1.25, 1.25)
        M = m * P * (a if geometry == "hertz" else 0.5 * profile.flat_half_width)
        sigma = rng.uniform(-0.6, 0.6) * 4 * f * P / (math.pi * a)
        P0, _, M0, _ = points[-1]
        ok = all(_contact_ok(problem, P0 + lam * (P - P0), M0 + lam * (M - M0), width0)
                 for lam in np.linspace(0.0, 1.0, 9)[1:])
        if not ok:
            resampled += 1
            continue
        points.append((P, Q, M, sigma))
    pts = np.array(points)
    n = ramps * steps_per_ramp
    loads = np.zeros((n + 1, 4))
    for r in range(ramps):
        lam = np.arange(1, steps_per_ramp + 1) / steps_per_ramp
        loads[r * steps_per_ramp + 1:(r + 1) * steps_per_ramp + 1] = pts[r] + lam[:, None] * (pts[r + 1] - pts[r])
    t = np.arange(n + 1, dtype=float)
    P, Q, M, sigma = loads.T.copy()
    history = hs.LoadHistory.from_arrays(t, P, Q, M, sigma)
    scene = hs.Scene(name=f"random-{geometry}-{seed}", material=material, friction=f, profile=profile,
                     history=history, output=hs.OutputOptions(fields=(), every=1))
    if info is not None:
        info.update(problem=problem, friction=f, gross=np.abs(Q) >= f * P, resampled=resampled, points=pts)
    return scene, t, P, Q, M, sigma
