"""The stick-zone problem of one slipping step: slip zones, stick edges, q.

At the end of a step the contact [L, R] splits into a left slip zone [L, b1]
(q = s1 f p), a stick interval [b1, b2] and a right slip zone [b2, R]
(q = s2 f p); a zone of sign 0 is absent (b1 = L or b2 = R, that edge sticks).
Write

    q = f chi(x) p(x) + q*(x),

chi = s (the common sign) when the zones agree or one is absent, chi = 0 when
all sticks, and for opposite signs chi p = s2 p + (s1 - s2) k(x), with
k = p on [L, b1] and the ramp p(b1) (b2 - x) / (b2 - b1) on [b1, b2], so that
q* lives on the stick interval and vanishes at both of its ends. Every stuck
point keeps its locked-in strain E (T1), so on (b1, b2)

    (1/pi) PV int q*(xi) / (x - xi) dxi = G(x) = [E(x) - A sigma/4 - f T_chi(x)] / A,

with T_chi = (A/pi) PV int chi p / (x - xi) = s (h' + alpha) by (N1) for a
common sign. q* bounded at b1 and b2 (continuity with +-f p) and the
equilibrium int q = Q give the two equations

    gamma_0(b1, b2) = 0,      f int chi p + (pi/2) r gamma_1 = Q,        (*)

(``_general_sie``). For a common sign G is piecewise linear between the data
points of E and the breakpoints of h', and gamma_0, gamma_1 are integrated
exactly; (*) is solved by Newton's method to rounding.

When one edge sticks and advances, the strain its newly arrived points lock in
depends on how the shear force was shared during the step; it is carried as
E_arr + F e(x) (``_general_path.arrival_strains``), and the extra force F is
the second unknown in place of the missing stick edge. When all sticks, F
alone closes the equilibrium and gamma_0 is the discretisation residual
(reported as the error estimate).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..geometry import NormalSolution
from . import _general_sie as sie

#: Newton iterations for the stick edges.
MAX_NEWTON_ITER = 40
#: Gauss-Legendre points for the Hilbert transform of the ramp (opposite signs only).
RAMP_POINTS = 128

_GL_T, _GL_W = np.polynomial.legendre.leggauss(RAMP_POINTS)
_EPS = float(np.finfo(float).eps)


@dataclass(frozen=True)
class Config:
    """Slip sign of the left and right zones (+1, -1, or 0 for a stuck edge)."""

    left: int
    right: int

    @property
    def base(self) -> int:
        """Sign applied as ``base f p`` on the whole contact."""
        return self.right if self.right != 0 else self.left

    @property
    def opposite(self) -> bool:
        return self.left * self.right < 0


@dataclass(frozen=True)
class Shear:
    """The shear traction of a state: q = f chi p + q* (+ fixup) on the contact.

    Attributes
    ----------
    left, right : float
        Contact edges.
    stick_left, stick_right : float
        The interval [b1, b2] carrying q* (the whole contact when all sticks).
    config : Config
    coef : ndarray, shape (n,)
        gamma_k of q* = sqrt(1 - t^2) sum_{k>=1} gamma_k U_{k-1}(t), gamma_0 = 0.
    ramp : float
        p(b1) for opposite signs (the ramp height), else 0.
    fixup : float
        Force [N/m] added as (2 / (pi r^2)) sqrt(r^2 - (x - m)^2) on the stick
        interval when the extra force F could not close equilibrium (0 normally).
    knots : tuple of ndarray, shape (m,) each, or None
        (t_k, G_k): G piecewise linear on the stick interval in t = (x - m) / r,
        for the exact inversion (None for opposite signs, where G has the ramp term).
    """

    left: float
    right: float
    stick_left: float
    stick_right: float
    config: Config
    coef: np.ndarray
    ramp: float
    fixup: float
    knots: tuple | None = None

    @property
    def center(self) -> float:
        return 0.5 * (self.stick_left + self.stick_right)

    @property
    def radius(self) -> float:
        return 0.5 * (self.stick_right - self.stick_left)

    def chi_p(self, x: np.ndarray, p: np.ndarray) -> np.ndarray:
        """chi(x) p(x) (see module docstring), shape of x."""
        cfg = self.config
        out = cfg.base * p
        if cfg.opposite:
            extra = cfg.left - cfg.base
            b1, b2 = self.stick_left, self.stick_right
            ramp = self.ramp * np.clip((b2 - x) / (b2 - b1), 0.0, 1.0)
            out = out + extra * np.where(x <= b1, p, np.where(x < b2, ramp, 0.0))
        return out

    def evaluate(self, x: np.ndarray, p: np.ndarray, friction: float, exact: bool = False) -> np.ndarray:
        """q(x) given p(x), shape of x (0 outside the contact).

        ``exact`` inverts the piecewise-linear stick data in closed form
        (``sie.bounded_linear``, cost ~ points x knots) instead of summing the
        Chebyshev series (whose truncation error is largest next to a kink of G).
        """
        x = np.asarray(x, dtype=float)
        q = friction * self.chi_p(x, p)
        if self.radius == 0.0:  # gross sliding: no stick interval
            return np.where((x > self.left) & (x < self.right), q, 0.0)
        t = (x - self.center) / self.radius
        if exact and self.knots is not None:
            inside = np.abs(t) < 1.0
            star = np.zeros(t.shape)
            star[inside] = sie.bounded_linear(self.knots[0], self.knots[1], t[inside])
            q = q + star
        else:
            q = q + sie.bounded_inside(self.coef, t)
        if self.fixup:
            q = q + self.fixup * 2.0 / (math.pi * self.radius) * np.sqrt(np.maximum(1.0 - t * t, 0.0))
        return np.where((x > self.left) & (x < self.right), q, 0.0)


@dataclass(frozen=True)
class Solution:
    """Outcome of :meth:`StepProblem.solve` for one configuration."""

    config: Config
    stick_left: float
    stick_right: float
    gauge: float
    converged: bool
    iterations: int
    residual: float  # scaled max of (consistency, equilibrium) residuals


class StepProblem:
    """Equations (*) for the end state of one step.

    Parameters
    ----------
    normal : NormalSolution
        Contact and pressure at the end of the step.
    slope : callable
        h'(x), vectorised.
    breaks : ndarray, shape (k,)
        Breakpoints of h' (where it is not smooth); may be empty.
    X : ndarray, shape (n,)
        Data points of E on the contact, increasing, X[0] = L, X[-1] = R.
    E : ndarray, shape (n,)
        Locked-in strain at X for the gauge force F = 0.
    gauge : ndarray, shape (n,)
        dE/dF at X (nonzero at points arriving at a stuck edge).
    compliance, friction, sigma, force : float
        A, f, sigma and Q at the end of the step.
    nodes : int
        Chebyshev points for the representation of q*.
    """

    def __init__(self, normal: NormalSolution, slope, breaks, X, E, gauge, compliance, friction, sigma,
                 force, nodes):
        self.normal = normal
        self.L, self.R = normal.left, normal.right
        self.A, self.f = compliance, friction
        self.sigma, self.Q, self.P = sigma, force, normal.P
        self.nodes = nodes
        self.slope = slope
        self.X, self.E, self.gauge = X, E, gauge
        inner = breaks[(breaks > self.L) & (breaks < self.R)]
        Xa = np.union1d(X, inner)
        self._Xa = Xa
        self._Ya = np.stack(
            [np.interp(Xa, X, E), np.interp(Xa, X, gauge), slope(Xa) + normal.rotation, np.ones_like(Xa)], axis=1
        )
        self.has_gauge = bool(np.any(gauge != 0.0))
        self.width = self.R - self.L
        self.p_scale = self.f * max(float(np.max(normal.pressure(X))), 1e-300)
        self.evaluations = 0

    # -- the equations ------------------------------------------------------
    def _moments(self, b1: float, b2: float) -> np.ndarray:
        """(gamma_0, gamma_1) of [E, gauge, h' + alpha, 1] on [b1, b2], shape (4, 2)."""
        self.evaluations += 1
        g0, g1 = sie.linear_moments(self._Xa, self._Ya, b1, b2)
        return np.stack([g0, g1], axis=1)

    def _ramp_moments(self, b1: float, b2: float) -> tuple[np.ndarray, float]:
        """(gamma_0, gamma_1) of K = (1/pi) PV int k / (x - xi) on [b1, b2], and int k."""
        n = self.nodes
        t = sie.chebyshev_nodes(n)
        x = 0.5 * (b1 + b2) + 0.5 * (b2 - b1) * t
        K = ramp_hilbert(self.normal, b1, b2, x)
        g0 = float(np.mean(K))
        g1 = 2.0 * float(np.mean(K * t))
        L = self.L
        th = 0.5 * math.pi * (_GL_T + 1.0)
        xi = L + (b1 - L) * 0.5 * (1.0 - np.cos(th))
        integral = float(np.sum(_GL_W * self.normal.pressure(xi) * np.sin(th))) * 0.25 * math.pi * (b1 - L)
        p_b = float(self.normal.pressure(b1))
        return np.array([g0, g1]), integral + 0.5 * p_b * (b2 - b1)

    def gammas(self, cfg: Config, b1: float, b2: float, F: float) -> tuple[float, float, float]:
        """gamma_0, gamma_1 of G and f int chi p for configuration ``cfg``."""
        mom = self._moments(b1, b2)
        s = cfg.base
        weights = np.array([1.0, F, -s * self.f, -0.25 * self.A * self.sigma])
        g = weights @ mom / self.A
        force_chi = s * self.f * self.P
        if cfg.opposite:
            extra = cfg.left - cfg.base
            km, kint = self._ramp_moments(b1, b2)
            g = g - self.f * extra * km
            force_chi += self.f * extra * kint
        return float(g[0]), float(g[1]), force_chi

    def residuals(self, cfg: Config, b1: float, b2: float, F: float) -> np.ndarray:
        """Scaled (consistency, equilibrium) residuals of (*)."""
        g0, g1, force_chi = self.gammas(cfg, b1, b2, F)
        r = 0.5 * (b2 - b1)
        force = force_chi + 0.5 * math.pi * r * g1
        return np.array([g0 / self.p_scale, (force - self.Q) / (self.f * self.P)])

    def _gauge_for_equilibrium(self, cfg: Config, b1: float, b2: float) -> float:
        """F making the equilibrium exact at given edges (0 if the gauge is ineffective)."""
        if not self.has_gauge:
            return 0.0
        e0 = self.residuals(cfg, b1, b2, 0.0)[1]
        e1 = self.residuals(cfg, b1, b2, 1.0)[1]
        slope = e1 - e0
        if abs(slope) <= 1e-14 * (abs(e0) + 1e-300) or slope == 0.0:
            return 0.0
        return -e0 / slope

    # -- solving ------------------------------------------------------------
    def solve(self, cfg: Config, guess: tuple[float, float] | None = None) -> Solution:
        """Stick edges (and gauge force) satisfying (*) for configuration ``cfg``."""
        L, R = self.L, self.R
        if cfg.left == 0 and cfg.right == 0:
            F = self._gauge_for_equilibrium(cfg, L, R)
            res = self.residuals(cfg, L, R, F)
            return Solution(cfg, L, R, F, True, 0, float(np.max(np.abs(res))))
        if cfg.left == 0 or cfg.right == 0:
            return self._solve_one_edge(cfg, guess)
        return self._solve_two_edges(cfg, guess)

    def _solve_one_edge(self, cfg: Config, guess) -> Solution:
        """One free stick edge b, F from equilibrium: 1-D root of the consistency."""
        L, R = self.L, self.R
        free_left = cfg.left != 0

        def edges(b):
            return (b, R) if free_left else (L, b)

        def consistency(b):
            b1, b2 = edges(b)
            F = self._gauge_for_equilibrium(cfg, b1, b2)
            return self.residuals(cfg, b1, b2, F)[0], F

        # scan from the slipping edge inward for the first sign change
        lo_end, hi_end = (L, R) if free_left else (R, L)
        samples = [lo_end + (hi_end - lo_end) * u for u in (1e-9, 1e-4, 1e-3, 0.01, 0.03, 0.06, 0.1, 0.15,
                                                             0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.97,
                                                             1.0 - 1e-6)]
        if guess is not None:
            g = guess[0] if free_left else guess[1]
            if min(L, R) < g < max(L, R):
                samples = sorted(set(samples) | {g}, key=lambda b: abs(b - lo_end))
        prev_b, prev_c = None, None
        for b in samples:
            c, _ = consistency(b)
            if prev_c is not None and np.sign(c) != np.sign(prev_c):
                root, it = _brent(lambda z: consistency(z)[0], prev_b, b, prev_c, c, 1e-15 * self.width)
                F = consistency(root)[1]
                b1, b2 = edges(root)
                res = self.residuals(cfg, b1, b2, F)
                return Solution(cfg, b1, b2, F, True, it, float(np.max(np.abs(res))))
            prev_b, prev_c = b, c
        return Solution(cfg, L, R, 0.0, False, len(samples), math.inf)

    def _solve_two_edges(self, cfg: Config, guess) -> Solution:
        """Damped Newton on (b1, b2), from the guess and then from fallbacks."""
        L, R = self.L, self.R
        W = self.width
        starts = []
        if guess is not None and L <= guess[0] < guess[1] <= R:
            starts.append(guess)
        starts += [(L + 1e-3 * W, R - 1e-3 * W), (L + 0.05 * W, R - 0.05 * W), (L + 0.25 * W, R - 0.25 * W),
                   (L + 0.45 * W, R - 0.45 * W)]
        best = None
        for start in starts:
            sol = self._newton(cfg, start)
            if sol.converged:
                return sol
            if best is None or sol.residual < best.residual:
                best = sol
        return best

    def _newton(self, cfg: Config, start) -> Solution:
        L, R = self.L, self.R
        W = self.width
        z = np.array(start, dtype=float)
        F_res = self.residuals(cfg, *z, 0.0)
        norm = float(np.max(np.abs(F_res)))
        for it in range(1, MAX_NEWTON_ITER + 1):
            h = 1e-7 * W
            J = np.empty((2, 2))
            for j in range(2):
                dz = np.zeros(2)
                dz[j] = h if z[j] + h <= (R if j else z[1]) else -h
                J[:, j] = (self.residuals(cfg, *(z + dz), 0.0) - F_res) / dz[j]
            try:
                step = np.linalg.solve(J, -F_res)
            except np.linalg.LinAlgError:
                break
            lam = 1.0
            accepted = False
            while lam > 1e-6:
                trial = z + lam * step
                # keep L <= b1 < b2 <= R
                if trial[0] < L:
                    trial[0] = L
                if trial[1] > R:
                    trial[1] = R
                if trial[1] - trial[0] <= 1e-12 * W:
                    lam *= 0.5
                    continue
                F_try = self.residuals(cfg, *trial, 0.0)
                n_try = float(np.max(np.abs(F_try)))
                if n_try < (1.0 - 1e-4 * lam) * norm or n_try <= 1e-14:
                    accepted = True
                    break
                lam *= 0.5
            if not accepted:
                break
            moved = float(np.max(np.abs(trial - z)))
            z, F_res, norm = trial, F_try, n_try
            if norm <= 1e-13 or moved <= 4 * _EPS * W:
                return Solution(cfg, z[0], z[1], 0.0, norm <= 1e-9, it, norm)
        return Solution(cfg, z[0], z[1], 0.0, norm <= 1e-9, MAX_NEWTON_ITER, norm)

    # -- the solution's fields ----------------------------------------------
    def shear(self, sol: Solution) -> Shear:
        """The shear representation of a solved configuration."""
        cfg = sol.config
        b1, b2 = sol.stick_left, sol.stick_right
        n = self.nodes
        t = sie.chebyshev_nodes(n)
        x = 0.5 * (b1 + b2) + 0.5 * (b2 - b1) * t
        G = self.strain_data(sol, x)
        if cfg.opposite:
            G = G - self.f * (cfg.left - cfg.base) * ramp_hilbert(self.normal, b1, b2, x)
        coef = sie.coefficients(G)
        g0, g1, force_chi = self.gammas(cfg, b1, b2, sol.gauge)
        coef[0] = 0.0
        coef[1] = g1  # exact for the interpolated data
        r = 0.5 * (b2 - b1)
        fixup = self.Q - (force_chi + 0.5 * math.pi * r * g1)
        if abs(fixup) <= 1e-13 * self.f * self.P:
            fixup = 0.0
        ramp = float(self.normal.pressure(b1)) if cfg.opposite else 0.0
        knots = None
        if not cfg.opposite:
            inner = self._Xa[(self._Xa > b1) & (self._Xa < b2)]
            xk = np.concatenate(([b1], inner, [b2]))
            r = 0.5 * (b2 - b1)
            knots = (_frozen((xk - 0.5 * (b1 + b2)) / r), _frozen(self.strain_data(sol, xk)))
            knots[0].flags.writeable = True
            knots[0][0], knots[0][-1] = -1.0, 1.0
            knots[0].flags.writeable = False
        return Shear(self.L, self.R, b1, b2, cfg, _frozen(coef), ramp, fixup, knots)

    def strain_data(self, sol: Solution, x: np.ndarray) -> np.ndarray:
        """G without the ramp term: [E(x) + F e(x) - A sigma/4 - f s (h' + alpha)] / A."""
        s = sol.config.base
        E = np.interp(x, self.X, self.E) + sol.gauge * np.interp(x, self.X, self.gauge)
        return (E - 0.25 * self.A * self.sigma - s * self.f * (self.slope(x) + self.normal.rotation)) / self.A

    def strain(self, shear: Shear, x: np.ndarray, near: np.ndarray | None = None) -> np.ndarray:
        """Relative strain Delta-eps (T1) of the state at points ``x`` outside the stick interval.

        Points flagged in ``near`` (shape of x) use the closed-form outside
        Hilbert transform of the piecewise-linear stick data
        (``sie.hilbert_linear_outside``) instead of the Chebyshev series, which
        converges slowly right next to the stick edges.
        """
        cfg = shear.config
        t = (x - shear.center) / shear.radius
        out = cfg.base * self.f * (self.slope(x) + self.normal.rotation)
        if cfg.opposite:
            extra = cfg.left - cfg.base
            out = out + self.A * self.f * extra * ramp_hilbert(self.normal, shear.stick_left, shear.stick_right, x)
        hil = sie.hilbert_outside(shear.coef, t)
        if near is not None and shear.knots is not None and np.any(near):
            hil[near] = sie.hilbert_linear_outside(shear.knots[0], shear.knots[1], t[near])
        if shear.fixup:
            hil = hil + shear.fixup * 2.0 / (math.pi * shear.radius) * sie.rho(t)
        return out + self.A * hil + 0.25 * self.A * self.sigma


def _frozen(a: np.ndarray) -> np.ndarray:
    a.flags.writeable = False
    return a


def ramp_hilbert(normal: NormalSolution, b1: float, b2: float, x: np.ndarray) -> np.ndarray:
    """K(x) = (1/pi) PV int k(xi) / (x - xi) dxi for the opposite-sign function k.

    k = p on [L, b1], p(b1) (b2 - xi) / (b2 - b1) on [b1, b2], 0 beyond. The
    ramp part is closed form; the pressure part subtracts p at the nearest
    point of [L, b1] and integrates the bounded remainder by Gauss-Legendre in
    theta, xi = L + (b1 - L)(1 - cos theta)/2 (smooth at the square-root edge L).

    Parameters
    ----------
    normal : NormalSolution
    b1, b2 : float
    x : ndarray, shape (n,)

    Returns
    -------
    ndarray, shape (n,)
    """
    x = np.asarray(x, dtype=float)
    L = normal.left
    p_b = float(normal.pressure(b1))
    ell = (b2 - x) / (b2 - b1)
    with np.errstate(divide="ignore"):
        ramp = p_b * (ell * np.log(np.abs((x - b1) / (x - b2))) + 1.0)
    th = 0.5 * math.pi * (_GL_T + 1.0)
    xi = L + (b1 - L) * 0.5 * (1.0 - np.cos(th))
    jac = 0.25 * math.pi * (b1 - L) * np.sin(th) * _GL_W
    p_xi = normal.pressure(xi)
    anchor = np.clip(x, L, b1)
    p_anchor = normal.pressure(anchor)
    with np.errstate(divide="ignore", invalid="ignore"):
        diff = (p_xi[None, :] - p_anchor[:, None]) / (x[:, None] - xi[None, :])
        diff = np.where(np.isfinite(diff), diff, 0.0)
        logs = np.log(np.abs((x - L) / (x - b1)))
    logs = np.where(np.isfinite(logs), logs, 0.0)
    return (diff @ jac + p_anchor * logs + ramp) / math.pi


def _brent(fun, a, b, fa, fb, xtol, maxiter=100):
    """Brent's root of ``fun`` on a bracket [a, b] with known values; returns (root, iterations)."""
    from scipy.optimize import brentq

    if fa == 0.0:
        return a, 0
    if fb == 0.0:
        return b, 0
    lo, hi = (a, b) if a < b else (b, a)
    root, info = brentq(fun, lo, hi, xtol=max(xtol, 1e-300), rtol=4 * _EPS, maxiter=maxiter, full_output=True)
    return root, info.iterations
