"""Contact edges along one straight load step, and the strain a point locks in on arrival.

A point x that enters the contact at load fraction lam_x of a step sticks from
that instant (physics.md, first trap) and keeps the relative strain it had on
arrival, Delta-eps(x, lam_x) (T1). While the step is fully stuck the shear
traction grows by flat-punch increments on the momentary contact (M1), whose
strain outside the contact [x0 - d, x0 + d] is

    d(Delta-eps)/dlam = A sgn(s) (Q'/pi + sigma' s / 4) / sqrt(s^2 - d^2),   s = x - x0,

(the (1/pi) PV integral of (Q' + (pi/4) sigma' s) / (pi sqrt(d^2 - s^2)), plus
A sigma'/4 from T1). Hence, exactly,

    E_arr(x) = Delta-eps_0(x) + int_{lam_lo}^{lam_x} A sgn(s)(Q'/pi + sigma' s/4) / sqrt((x - L)(x - R)) dlam,

where Delta-eps_0 is the strain at x at the start of the step (outside the
old contact). The integrand has an inverse square root at lam_x;
lam = lam_x - (lam_x - lam_lo) u^2 removes it and Gauss-Legendre in u does the
rest (tanh-sinh in u, for the weak singularity where contact forms). The same integral without (Q', sigma') and with 1/pi gives the strain a
unit of extra shear force, spread over the step, would lock in (the "gauge"
used when one edge sticks while the other slips).
"""
from __future__ import annotations

import math

import numpy as np

from ..geometry import NormalProblem, NormalSolution
from ..state import Loads

#: tanh-sinh points in u for the arrival integral (step 6 / (ARRIVAL_POINTS - 1) in t).
ARRIVAL_POINTS = 49
#: Normal solves per formation step (contact appearing from P <= 0), general profiles.
FORMATION_SOLVES = 9
#: Bisection steps for the arrival fraction lam_x.
BISECTION_STEPS = 60



def _tanh_sinh(n: int) -> tuple[np.ndarray, np.ndarray]:
    """tanh-sinh (double exponential) points and weights on [0, 1], shape (n,) each.

    Exact enough for integrands with algebraic singularities at either end:
    the edge path behaves like lam^(1/2) (Hertz) or lam^(2/3) (rounded punch)
    where contact forms.
    """
    t = np.linspace(-3.0, 3.0, n)
    step = t[1] - t[0]
    arg = 0.5 * math.pi * np.sinh(t)
    u = 0.5 * (1.0 + np.tanh(arg))
    w = 0.25 * math.pi * step * np.cosh(t) / np.cosh(arg) ** 2
    return u, w


_U, _W = _tanh_sinh(ARRIVAL_POINTS)


class EdgePath:
    """Contact edges L(lam), R(lam) along the straight step from ``loads0`` to ``loads1``.

    Parameters
    ----------
    problem : NormalProblem
    start : NormalSolution or None
        Solution at the start (None when separated).
    end : NormalSolution
        Solution at the end (in contact).
    loads0, loads1 : Loads

    Attributes
    ----------
    lam_lo : float
        Fraction of the step at which contact first exists (0 unless the step
        starts separated).
    solves : int
        Normal solves made here.

    Notes
    -----
    Three representations: the symmetric profiles with M = 0 all along use the
    vectorised a(P) and P(a) of the normal problem (exact); a step starting
    separated interpolates ``FORMATION_SOLVES`` solutions in mu =
    sqrt((lam - lam_lo) / (1 - lam_lo)) (a ~ sqrt(P) for Hertz is linear in
    mu); any other step uses the cubic Hermite interpolant of the end edges
    and their rates, the rates from the flat-punch increment (N3): an edge
    where the pressure behaves as k sqrt(dist) moves at 2 c / k, c the
    inverse-square-root coefficient of the increment there.
    """

    def __init__(self, problem: NormalProblem, start: NormalSolution | None, end: NormalSolution,
                 loads0: Loads, loads1: Loads):
        self.problem = problem
        self.loads0, self.loads1 = loads0, loads1
        P0, P1 = loads0.P, loads1.P
        self.lam_lo = 0.0 if start is not None else max(0.0, P0 / (P0 - P1)) if P0 < P1 else 0.0
        self.solves = 0
        self._symmetric = problem.profile.symmetric and loads0.M == 0.0 and loads1.M == 0.0
        if self._symmetric:
            self._kind = "symmetric"
        elif start is None:
            self._kind = "formation"
            n = FORMATION_SOLVES
            mu = 0.5 * (1.0 + np.cos((np.arange(n) + 0.5) * math.pi / n))
            lam = self.lam_lo + (1.0 - self.lam_lo) * mu**2
            edges = []
            for li in lam:
                sol = problem.solve(*self._PM(li))
                edges.append((sol.left, sol.right))
            self.solves = n
            self._mu = mu
            self._edges = np.array(edges)  # (n, 2)
            self._bary = (-1.0) ** np.arange(n) * np.sin((np.arange(n) + 0.5) * math.pi / n)
        else:
            self._kind = "hermite"
            dP, dM = P1 - P0, loads1.M - loads0.M
            self._h0 = np.array([start.left, start.right])
            self._h1 = np.array([end.left, end.right])
            self._v0 = _edge_rates(start, dP, dM)
            self._v1 = _edge_rates(end, dP, dM)

    def _PM(self, lam):
        l0, l1 = self.loads0, self.loads1
        return l0.P + lam * (l1.P - l0.P), l0.M + lam * (l1.M - l0.M)

    def edges(self, lam: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Left and right contact edges at fractions ``lam`` (any shape) of the step."""
        lam = np.asarray(lam, dtype=float)
        if self._kind == "symmetric":
            P, _ = self._PM(lam)
            a = self.problem.half_width(np.maximum(P, 0.0))
            return -a, a
        if self._kind == "formation":
            mu = np.sqrt(np.clip((lam - self.lam_lo) / (1.0 - self.lam_lo), 0.0, 1.0))
            diff = mu[..., None] - self._mu
            exact = np.isclose(diff, 0.0, atol=1e-15)
            with np.errstate(divide="ignore", invalid="ignore"):
                w = self._bary / diff
            w = np.where(exact.any(axis=-1, keepdims=True), exact.astype(float), w)
            out = (w @ self._edges) / w.sum(axis=-1, keepdims=True)
            return out[..., 0], out[..., 1]
        s = lam[..., None]
        h00 = (1 + 2 * s) * (1 - s) ** 2
        h10 = s * (1 - s) ** 2
        h01 = s * s * (3 - 2 * s)
        h11 = s * s * (s - 1)
        out = h00 * self._h0 + h10 * self._v0 + h01 * self._h1 + h11 * self._v1
        return out[..., 0], out[..., 1]

    def arrival(self, x: np.ndarray, side: int) -> np.ndarray:
        """Fraction lam_x at which each point of ``x`` (shape (n,)) enters the contact.

        ``side`` is -1 for points arriving at the left edge, +1 at the right.
        Points already in contact at lam_lo get lam_lo.
        """
        x = np.asarray(x, dtype=float)
        lo = np.full(x.shape, self.lam_lo)
        if self._kind == "symmetric":
            P0, P1 = self.loads0.P, self.loads1.P
            Px = self.problem.load(np.abs(x))
            return np.clip((Px - P0) / (P1 - P0), self.lam_lo, 1.0)
        hi = np.ones(x.shape)
        for _ in range(BISECTION_STEPS):
            mid = 0.5 * (lo + hi)
            left, right = self.edges(mid)
            inside = (x > left) if side < 0 else (x < right)
            hi = np.where(inside, mid, hi)
            lo = np.where(inside, lo, mid)
        lam = 0.5 * (lo + hi)
        left, right = self.edges(np.full(x.shape, self.lam_lo))
        already = (x > left) & (x < right)
        return np.where(already, self.lam_lo, lam)


def _edge_rates(sol: NormalSolution, dP: float, dM: float) -> np.ndarray:
    """(dL/dlam, dR/dlam) on the contact of ``sol`` for load rates (dP, dM) (N3)."""
    d = sol.half_width
    dM0 = dM - dP * sol.center
    eps = 1e-9 * d
    k_left = float(sol.pressure(sol.left + eps)) / math.sqrt(eps)
    k_right = float(sol.pressure(sol.right - eps)) / math.sqrt(eps)
    c_left = (dP - 2.0 * dM0 / d) / (math.pi * math.sqrt(2.0 * d))
    c_right = (dP + 2.0 * dM0 / d) / (math.pi * math.sqrt(2.0 * d))
    return np.array([-2.0 * c_left / k_left, 2.0 * c_right / k_right])


def arrival_strains(path: EdgePath, x: np.ndarray, side: int, compliance: float
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Strain locked in by the stuck increments of the step, and by a unit gauge force.

    Parameters
    ----------
    path : EdgePath
    x : ndarray, shape (n,)
        Points arriving at the ``side`` edge (-1 left, +1 right) during the step.
    compliance : float
        A.

    Returns
    -------
    increment : ndarray, shape (n,)
        int A sgn(s)(Q'/pi + sigma' s/4) / sqrt(s^2 - d^2) dlam from lam_lo to lam_x.
    gauge : ndarray, shape (n,)
        int A sgn(s) / (pi sqrt(s^2 - d^2)) dlam over the same range (per unit of
        shear force added uniformly over the step).
    """
    x = np.asarray(x, dtype=float)
    if x.size == 0:
        return np.zeros(0), np.zeros(0)
    l0, l1 = path.loads0, path.loads1
    dQ, dS = l1.Q - l0.Q, l1.sigma - l0.sigma
    lam_x = path.arrival(x, side)
    span = lam_x - path.lam_lo
    lam = lam_x[:, None] - span[:, None] * _U**2  # (n, k)
    left, right = path.edges(lam)
    root = np.sqrt(np.abs((x[:, None] - left) * (x[:, None] - right)))
    s = x[:, None] - 0.5 * (left + right)
    weight = 2.0 * span[:, None] * _U * _W
    with np.errstate(divide="ignore", invalid="ignore"):
        kernel = np.where(root > 0.0, weight / root, 0.0) * (compliance * side)
    increment = kernel @ np.full(_U.shape, dQ / math.pi) + (kernel * s).sum(axis=1) * (0.25 * dS)
    gauge = kernel.sum(axis=1) / math.pi
    return increment, gauge
