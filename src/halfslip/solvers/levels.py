"""Integrals over load levels for symmetric contacts with M = 0.

The exact memory method (``exact.py``) describes the shear traction as a sum of
flat-punch distributions, one per load level P' (physics.md, end of "Varying
P"). Its slip, rigid shift and dissipation need three primitives of
ln a(P') and one integral of arccosh(|x|/a(P')):

    Lambda(P) = int_0^P ln a(P') dP'
    Psi(P)    = int_0^P Lambda(P') dP'
    Xi(P)     = int_0^P P' ln a(P') dP'
    J(X; P_lo, P_hi) = int_{P_lo}^{P_hi} arccosh(X / a(P')) dP',   a(P_hi) <= X

Hertz has closed forms (a = alpha sqrt(P)); any other symmetric profile is
tabulated once, per cell, as a Chebyshev interpolant of ln a(P) on a graded
grid whose integrals are exact polynomial integrals.
"""
from __future__ import annotations

import math

import numpy as np
from numpy.polynomial import chebyshev as C

from ..geometry import Hertz, NormalProblem

TABLE_HEADROOM = 1.05
"""A tabulated profile's levels reach this multiple of the history's largest P (the
scene reader checks that the contact still fits the profile there)."""

_GL_NODES, _GL_WEIGHTS = np.polynomial.legendre.leggauss(24)


class LevelIntegrals:
    """Primitives of ln a(P) and the arccosh kernel for one symmetric profile.

    Parameters
    ----------
    problem : NormalProblem
        The normal problem of a symmetric profile (M = 0 paths are used).
    P_max : float
        Largest load the history reaches; the tabulation covers [0, 1.05 P_max].
    """

    def __init__(self, problem: NormalProblem, P_max: float):
        self.problem = problem
        self.P_max = float(P_max)

    # -- scalar primitives (hot path) -------------------------------------
    def lam(self, P: float) -> float:  # pragma: no cover - abstract
        raise NotImplementedError

    def psi(self, P: float) -> float:  # pragma: no cover - abstract
        raise NotImplementedError

    def xi(self, P: float) -> float:  # pragma: no cover - abstract
        raise NotImplementedError

    def ln_a(self, P: float) -> float:  # pragma: no cover - abstract
        raise NotImplementedError

    # -- vectorised arccosh kernel ----------------------------------------
    def arccosh_integral(self, X, P_X, P_lo, P_hi) -> np.ndarray:
        """J(X; P_lo, P_hi) for arrays X, P_X = load at which a(P_X) = X.

        Requires P_lo <= P_hi <= P_X. Gauss-Legendre in u = sqrt(P_X - P'),
        in which the integrand is smooth (arccosh ~ sqrt near a = X).
        """
        X, P_X, P_lo, P_hi = np.broadcast_arrays(*(np.asarray(v, float) for v in (X, P_X, P_lo, P_hi)))
        u_lo = np.sqrt(np.maximum(P_X - P_hi, 0.0))
        u_hi = np.sqrt(np.maximum(P_X - P_lo, 0.0))
        half = 0.5 * (u_hi - u_lo)
        mid = 0.5 * (u_hi + u_lo)
        u = mid[..., None] + half[..., None] * _GL_NODES
        a = self.problem.half_width(P_X[..., None] - u**2)
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where(a > 0, X[..., None] / a, np.inf)
        integrand = np.where(np.isfinite(ratio), np.arccosh(np.maximum(ratio, 1.0)), 0.0) * 2.0 * u
        return half * (integrand @ _GL_WEIGHTS)


class HertzLevels(LevelIntegrals):
    """Closed forms for a = alpha sqrt(P), alpha = sqrt(2 A R / pi)."""

    def __init__(self, problem: NormalProblem, P_max: float):
        super().__init__(problem, P_max)
        R = problem.profile.radius
        A = problem.compliance
        self.alpha = math.sqrt(2.0 * A * R / math.pi)
        self.ln_alpha = math.log(self.alpha)
        self._AR = A * R

    def ln_a(self, P):
        return self.ln_alpha + 0.5 * math.log(P)

    def lam(self, P):
        if P <= 0.0:
            return 0.0
        return P * self.ln_alpha + 0.5 * (P * math.log(P) - P)

    def psi(self, P):
        if P <= 0.0:
            return 0.0
        return 0.5 * P * P * self.ln_alpha + 0.25 * P * P * math.log(P) - 0.375 * P * P

    def xi(self, P):
        if P <= 0.0:
            return 0.0
        return 0.5 * P * P * self.ln_alpha + 0.25 * P * P * math.log(P) - 0.125 * P * P

    def arccosh_integral(self, X, P_X, P_lo, P_hi):
        # P = pi a^2 / (2 A R): int arccosh(X/a) dP = (pi / (A R)) int a arccosh(X/a) da,
        # primitive a^2/2 arccosh(X/a) - X/2 sqrt(X^2 - a^2).
        X, P_lo, P_hi = np.broadcast_arrays(*(np.asarray(v, float) for v in (X, P_lo, P_hi)))
        a_lo = self.alpha * np.sqrt(np.maximum(P_lo, 0.0))
        a_hi = self.alpha * np.sqrt(np.maximum(P_hi, 0.0))

        def F(a):
            with np.errstate(divide="ignore", invalid="ignore"):
                ach = np.where(a > 0, np.arccosh(np.maximum(X / np.where(a > 0, a, 1.0), 1.0)), 0.0)
            return 0.5 * a * a * ach - 0.5 * X * np.sqrt(np.maximum(X * X - a * a, 0.0))

        return (math.pi / self._AR) * (F(a_hi) - F(a_lo))


class TabulatedLevels(LevelIntegrals):
    """Piecewise Chebyshev interpolants of ln a(P) on a graded grid.

    Cells double in width from 1e-12 P_top up to P_top / 64, then are uniform;
    each carries a degree-``degree`` interpolant, integrated exactly, so the
    primitives are accurate to the interpolation error of ln a (about 1e-12
    relative for the analytic pieces of a rounded punch; the first cell, where
    a(P) - a(0) behaves like a fractional power, contributes at most
    P_min |ln a| ~ 1e-12 P_top).
    """

    def __init__(self, problem: NormalProblem, P_max: float, degree: int = 16, cells: int = 128):
        super().__init__(problem, P_max)
        top = TABLE_HEADROOM * max(P_max, 1e-300)
        graded = top / 64.0 * 0.5 ** np.arange(0, 40)[::-1]
        edges = np.concatenate([[0.0], graded, np.linspace(top / 64.0, top, cells + 1)[1:]])
        self.edges = edges
        self.top = top
        nodes = np.cos(np.pi * (np.arange(degree + 1) + 0.5) / (degree + 1))  # Chebyshev points on [-1, 1]
        lo, hi = edges[:-1], edges[1:]
        P_nodes = 0.5 * (lo + hi)[:, None] + 0.5 * (hi - lo)[:, None] * nodes
        ln_a = np.log(problem.half_width(P_nodes))
        coef = np.array([C.chebfit(nodes, row, degree) for row in ln_a])  # ln a per cell, in s in [-1, 1]
        # y ln a(y) with y = m + h s:  coefficients of (m + h s) * series
        mid, h = 0.5 * (lo + hi), 0.5 * (hi - lo)
        s_coef = np.array([C.chebmulx(c) for c in coef])  # s * series (degree + 1)
        y_ln = mid[:, None] * np.pad(coef, ((0, 0), (0, 1))) + h[:, None] * s_coef
        self._h = h
        self._mid = mid
        self._lo = lo
        self._coef_ln = coef
        self._coef_lam = np.array([C.chebint(c, lbnd=-1.0) for c in coef]) * h[:, None]  # int_lo^y ln a
        self._coef_xi = np.array([C.chebint(c, lbnd=-1.0) for c in y_ln]) * h[:, None]
        cell_lam = np.array([C.chebval(1.0, c) for c in self._coef_lam])
        self._lam0 = np.concatenate([[0.0], np.cumsum(cell_lam)])[:-1]  # Lambda at the cell's left edge
        # Psi(y) = Psi(lo) + Lambda(lo) (y - lo) + int_lo^y int_lo^z ln a
        self._coef_psi2 = np.array([C.chebint(c, lbnd=-1.0) for c in self._coef_lam]) * h[:, None]
        cell_psi = self._lam0 * (hi - lo) + np.array([C.chebval(1.0, c) for c in self._coef_psi2])
        self._psi0 = np.concatenate([[0.0], np.cumsum(cell_psi)])[:-1]
        cell_xi = np.array([C.chebval(1.0, c) for c in self._coef_xi])
        self._xi0 = np.concatenate([[0.0], np.cumsum(cell_xi)])[:-1]

    def _locate(self, P):
        if P > self.top * (1 + 1e-12):
            raise ValueError(f"load level {P!r} beyond the tabulated range {self.top!r}")
        i = int(np.searchsorted(self.edges, P, side="right")) - 1
        i = min(max(i, 0), len(self._lo) - 1)
        return i, (P - self._mid[i]) / self._h[i]

    def ln_a(self, P):
        i, s = self._locate(P)
        return float(C.chebval(s, self._coef_ln[i]))

    def lam(self, P):
        if P <= 0.0:
            return 0.0
        i, s = self._locate(P)
        return float(self._lam0[i] + C.chebval(s, self._coef_lam[i]))

    def psi(self, P):
        if P <= 0.0:
            return 0.0
        i, s = self._locate(P)
        return float(self._psi0[i] + self._lam0[i] * (P - self._lo[i]) + C.chebval(s, self._coef_psi2[i]))

    def xi(self, P):
        if P <= 0.0:
            return 0.0
        i, s = self._locate(P)
        return float(self._xi0[i] + C.chebval(s, self._coef_xi[i]))


def level_integrals(problem: NormalProblem, P_max: float) -> LevelIntegrals:
    """The cheapest exact-enough level integrals for ``problem``'s profile."""
    if isinstance(problem.profile, Hertz):
        return HertzLevels(problem, P_max)
    return TabulatedLevels(problem, P_max)
