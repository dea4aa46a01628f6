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
the second unknown in place of the missing stick edge. When all sticks the
arrival strains are exact (M1): F = 0, gamma_0 is the discretisation residual
(reported as the error estimate) and the force the strain-based solution
misses is carried as a fix-up force (see :class:`Shear`). For opposite signs
the ramp term is not piecewise linear: its two moments are single integrals
over [L, b1] and the Jacobian is taken by differences.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..geometry import NormalSolution
from ..state import frozen as _frozen
from . import _general_sie as sie

#: Newton iterations for the stick edges.
MAX_NEWTON_ITER = 40
#: Newton stops when the scaled residuals of (*) are below this (their rounding floor is
#: about 1e-14; the edges then sit within ~1e-12 of the contact width of the root).
NEWTON_TOL = 1e-12
#: Gauss-Legendre points per panel of the quadratures over [L, b1] (opposite signs only).
RAMP_POINTS = 64
#: Knots graded by halving towards the stick edges for the ramp term (opposite signs only).
RAMP_GRADING = 24

_GL_PANEL = np.polynomial.legendre.leggauss(RAMP_POINTS)
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
        Force [N/m] that the strain-based solution misses (the discretisation
        residual of equilibrium), added as (2 / (pi r^2)) sqrt(r^2 - (x - m)^2)
        on the stick interval so that int q = Q exactly.
    knots : tuple of ndarray, shape (m,) each, or None
        (t_k, G_k): G piecewise linear on the stick interval in t = (x - m) / r,
        for the exact inversion (None in gross sliding). For opposite signs G
        includes the ramp term, sampled on knots graded towards the edges.
        ``coef`` serves the strain outside the stick interval far from its ends.
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

    def force(self, normal: NormalSolution, friction: float, breaks: np.ndarray) -> float:
        """int q dx of this representation: f int chi p + (pi/2) r gamma_1 + fixup [N/m]."""
        cfg = self.config
        total = cfg.base * friction * normal.P
        if cfg.opposite:
            b1, b2 = self.stick_left, self.stick_right
            xi, w = _ramp_rule(self.left, b1, breaks)
            k = float(np.dot(w, normal.pressure(xi))) + 0.5 * self.ramp * (b2 - b1)
            total += friction * (cfg.left - cfg.base) * k
        if self.radius > 0.0:
            total += 0.5 * math.pi * self.radius * float(self.coef[1]) + self.fixup
        return total

    def evaluate(self, x: np.ndarray, p: np.ndarray, friction: float) -> np.ndarray:
        """q(x) given p(x), shape of x (0 outside the contact).

        q* is the exact bounded inversion of the piecewise-linear stick data
        (``sie.bounded_linear``; cost ~ points x knots), not the truncated series,
        whose error is largest next to a kink or square-root point of G.
        """
        x = np.asarray(x, dtype=float)
        q = friction * self.chi_p(x, p)
        if self.radius > 0.0:  # (gross sliding has no stick interval)
            t = (x - self.center) / self.radius
            inside = np.abs(t) < 1.0
            star = np.zeros(t.shape)
            star[inside] = sie.bounded_linear(self.knots[0], self.knots[1], t[inside])
            q = q + star
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
    gauge : tuple of ndarray, shape (n,) each
        dE/dF at X for the points that arrived at the left and at the right edge;
        the extra force F acts on the side(s) whose edge sticks.
    compliance, friction, sigma, force : float
        A, f, sigma and Q at the end of the step.
    nodes : int
        Chebyshev points for the representation of q*.
    bias : float
        Force [N/m] the previous state carried as fix-up (the discretisation
        residual of its equilibrium). A configuration with a stuck edge aims
        the strain-based equilibrium at Q - bias, so that the extra force F
        answers for the change of the force sharing during the step only.
    singular : ndarray, shape (k,)
        Positions where E has a square-root onset (worth a Coulomb check).
    """

    def __init__(self, normal: NormalSolution, slope, breaks, X, E, gauge, compliance, friction, sigma,
                 force, nodes, bias=0.0, singular=np.zeros(0)):
        self.normal = normal
        self.L, self.R = normal.left, normal.right
        self.A, self.f = compliance, friction
        self.sigma, self.Q, self.P = sigma, force, normal.P
        self.bias = bias
        self.singular = singular
        self.nodes = nodes
        self.slope = slope
        self.X, self.E, self.gauge = X, E, gauge
        inner = breaks[(breaks > self.L) & (breaks < self.R)]
        self._breaks = inner
        Xa = np.union1d(X, inner)
        self._Xa = Xa
        self._Ya = np.stack(
            [np.interp(Xa, X, E), np.interp(Xa, X, gauge[0]), np.interp(Xa, X, gauge[1]),
             slope(Xa) + normal.rotation, np.ones_like(Xa)], axis=1
        )
        self.has_gauge = (bool(np.any(gauge[0] != 0.0)), bool(np.any(gauge[1] != 0.0)))
        self.width = self.R - self.L
        self.p_scale = self.f * max(float(np.max(normal.pressure(X))), 1e-300)
        self.evaluations = 0
        self._last = None

    # -- the equations ------------------------------------------------------
    def _moments(self, b1: float, b2: float):
        """gamma_0, gamma_1 of [E, gauge left, gauge right, h' + alpha, 1] on [b1, b2], shape (2, 5),
        and their derivatives with respect to (b1, b2), shape (2, 2, 5) (the last interval is cached:
        the residuals are affine in the gauge force F and are asked for several F in a row)."""
        if self._last is not None and self._last[0] == (b1, b2):
            return self._last[1]
        self.evaluations += 1
        out = sie.linear_moments(self._Xa, self._Ya, b1, b2, derivatives=True)
        self._last = ((b1, b2), out)
        return out

    def _ramp_moments(self, b1: float, b2: float) -> tuple[np.ndarray, float]:
        """(gamma_0, gamma_1) of K = (1/pi) PV int k / (x - xi) on [b1, b2], and int k.

        Exchanging the integrals, with m, r the centre and half-width of [b1, b2]
        and (1/pi) int_0^pi dth / (c + r cos th) = sgn(c) / sqrt(c^2 - r^2) for
        |c| > r (0 in the principal-value sense for |c| < r):

            gamma_0 = (1/pi) int_L^b1 p / sqrt((b1 - xi)(b2 - xi)) dxi,
            gamma_1 = (2/(pi r)) [int k - int_L^b1 p (m - xi) / sqrt((b1 - xi)(b2 - xi)) dxi],

        one quadrature over [L, b1] instead of K at every node.
        """
        m, r = 0.5 * (b1 + b2), 0.5 * (b2 - b1)
        p_b = float(self.normal.pressure(b1))
        if b1 <= self.L:
            kint = 0.5 * p_b * (b2 - b1)
            return np.array([0.0, 2.0 / (math.pi * r) * kint]), kint
        xi, w = _ramp_rule(self.L, b1, self._breaks)
        p = self.normal.pressure(xi)
        root = np.sqrt(np.maximum((b1 - xi) * (b2 - xi), 0.0))
        inv = np.divide(1.0, root, out=np.zeros_like(root), where=root > 0.0)
        kint = float(np.dot(w, p)) + 0.5 * p_b * (b2 - b1)
        g0 = float(np.dot(w, p * inv)) / math.pi
        g1 = 2.0 / (math.pi * r) * (kint - float(np.dot(w, p * (m - xi) * inv)))
        return np.array([g0, g1]), kint

    def gammas(self, cfg: Config, b1: float, b2: float, F: float, jacobian: bool = False):
        """gamma_0, gamma_1 of G and f int chi p for configuration ``cfg``.

        With ``jacobian``, also d(gamma_0, gamma_1)/d(b1, b2), shape (2, 2)
        (not for opposite signs, whose ramp term is differentiated by the caller).
        """
        mom, dmom = self._moments(b1, b2)
        s = cfg.base
        weights = np.array([1.0, F * (cfg.left == 0), F * (cfg.right == 0), -s * self.f,
                            -0.25 * self.A * self.sigma]) / self.A
        g = mom @ weights
        force_chi = s * self.f * self.P
        if cfg.opposite:
            extra = cfg.left - cfg.base
            km, kint = self._ramp_moments(b1, b2)
            g = g - self.f * extra * km
            force_chi += self.f * extra * kint
        if jacobian:
            return float(g[0]), float(g[1]), force_chi, dmom @ weights
        return float(g[0]), float(g[1]), force_chi

    def residuals(self, cfg: Config, b1: float, b2: float, F: float, jacobian: bool = False):
        """Scaled (consistency, equilibrium) residuals of (*); with ``jacobian`` also d/d(b1, b2)."""
        out = self.gammas(cfg, b1, b2, F, jacobian)
        g0, g1, force_chi = out[:3]
        r = 0.5 * (b2 - b1)
        force = force_chi + 0.5 * math.pi * r * g1
        target = self.Q - (self.bias if (cfg.left == 0 or cfg.right == 0) else 0.0)
        res = np.array([g0 / self.p_scale, (force - target) / (self.f * self.P)])
        if not jacobian:
            return res
        dg = out[3]
        J = np.array([
            dg[0] / self.p_scale,
            0.5 * math.pi * (np.array([-0.5, 0.5]) * g1 + r * dg[1]) / (self.f * self.P),
        ])
        return res, J

    def _gauge_for_equilibrium(self, cfg: Config, b1: float, b2: float) -> float:
        """F making the equilibrium exact at given edges (0 if the gauge is ineffective)."""
        if not ((cfg.left == 0 and self.has_gauge[0]) or (cfg.right == 0 and self.has_gauge[1])):
            return 0.0
        e0 = self.residuals(cfg, b1, b2, 0.0)[1]
        e1 = self.residuals(cfg, b1, b2, 1.0)[1]
        slope = e1 - e0
        if abs(slope) <= 1e-14 * (abs(e0) + 1e-300) or slope == 0.0:
            return 0.0
        return -e0 / slope

    # -- solving ------------------------------------------------------------
    def solve(self, cfg: Config, guess: tuple[float, float] | None = None,
              limits: tuple[float, float] | None = None) -> Solution:
        """Stick edges (and gauge force) satisfying (*) for configuration ``cfg``.

        ``limits`` (lo, hi) bound the stick edges: b1 >= lo, b2 <= hi (see
        ``general._limits``). Returns the first root found (see :meth:`roots`).
        """
        for sol in self.roots(cfg, guess, limits):
            return sol
        return Solution(cfg, self.L, self.R, 0.0, False, 0, math.inf)

    def roots(self, cfg: Config, guess: tuple[float, float] | None = None,
              limits: tuple[float, float] | None = None):
        """Distinct converged solutions of (*) for ``cfg``, most likely first (a generator).

        Discretised data can give (*) a spurious root next to the true one; the
        caller takes the first that passes its Coulomb and slip-direction checks.
        """
        self._lo, self._hi = limits if limits is not None else (self.L, self.R)
        L, R = self.L, self.R
        if cfg.left == 0 and cfg.right == 0:
            # every arrival stuck: its strain is exact (M1), F has no part to play; the
            # equilibrium residual (discretisation) is carried by the fix-up force
            res = self.residuals(cfg, L, R, 0.0)
            yield Solution(cfg, L, R, 0.0, True, 0, float(np.max(np.abs(res))))
            return
        if cfg.left == 0 or cfg.right == 0:
            sol = self._solve_one_edge(cfg, guess)
            if sol.converged:
                yield sol
            return
        yield from self._solve_two_edges(cfg, guess)

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
        lo_end, hi_end = (self._lo, R) if free_left else (self._hi, L)
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

    def _solve_two_edges(self, cfg: Config, guess):
        """Damped Newton on (b1, b2) from the guess and fallback starts, then bracketing."""
        L, R = self._lo, self._hi
        W = R - L
        starts = []
        if guess is not None and L <= guess[0] < guess[1] <= R:
            starts.append(guess)
        starts += [(L + u * W, R - u * W) for u in (1e-3, 1e-5, 0.05, 0.25, 0.45)]
        # Points locked near the slip limit make the equations flat between the contact
        # edges and an old stick edge (a singular point of E), beyond which they turn
        # steeply: a start just inside each singular point (as far from both edges), and a
        # finer spread, find roots there that the starts above can miss.
        inside = self.singular[(self.singular > L) & (self.singular < R)]
        depths = np.unique(np.minimum(inside - L, R - inside) * (1.0 + 1e-3))
        depths = depths[2 * depths < W][:SINGULAR_STARTS]  # the outermost: where the bands lie
        starts += [(L + d, R - d) for d in depths]
        starts += [(L + u * W, R - u * W) for u in (0.15, 0.3)]
        found = []
        for start in starts:
            sol = self._newton(cfg, start)
            if sol.converged and all(max(abs(sol.stick_left - o.stick_left), abs(sol.stick_right - o.stick_right))
                                     > 1e-9 * self.width for o in found):
                found.append(sol)
                yield sol
        if not found:
            sol = self._nested(cfg)
            if sol.converged:
                yield sol

    def _evaluate(self, cfg: Config, z: np.ndarray):
        """Residuals and Jacobian at z = (b1, b2): analytic, or inward differences for opposite signs."""
        if not cfg.opposite:
            return self.residuals(cfg, z[0], z[1], 0.0, jacobian=True)
        res = self.residuals(cfg, z[0], z[1], 0.0)
        h = 1e-7 * self.width
        J = np.empty((2, 2))
        for j, inward in ((0, h), (1, -h)):
            dz = np.zeros(2)
            dz[j] = inward
            J[:, j] = (self.residuals(cfg, *(z + dz), 0.0) - res) / inward
        return res, J

    def _newton(self, cfg: Config, start) -> Solution:
        """Damped Newton on (b1, b2) within the limits."""
        L, R = self._lo, self._hi
        W = self.width
        z = np.array(start, dtype=float)
        res, J = self._evaluate(cfg, z)
        norm = float(np.max(np.abs(res)))
        it = 0
        for it in range(1, MAX_NEWTON_ITER + 1):
            if norm <= NEWTON_TOL:
                break
            try:
                step = np.linalg.solve(J, -res)
            except np.linalg.LinAlgError:
                break
            if float(np.max(np.abs(step))) <= 4 * _EPS * W:
                break
            lam = 1.0
            accepted = False
            while lam > 1e-4:
                trial = z + lam * step
                trial[0] = min(max(trial[0], L), R)
                trial[1] = min(max(trial[1], L), R)
                if trial[1] - trial[0] > 1e-12 * W:
                    res_t, J_t = self._evaluate(cfg, trial)
                    n_t = float(np.max(np.abs(res_t)))
                    if n_t < (1.0 - 1e-4 * lam) * norm:
                        accepted = True
                        break
                lam *= 0.5
            if not accepted:
                break
            moved = float(np.max(np.abs(trial - z)))
            z, res, J, norm = trial, res_t, J_t, n_t
            if moved <= 4 * _EPS * W:
                break
        return Solution(cfg, z[0], z[1], 0.0, norm <= 1e-9, it, norm)

    def _nested(self, cfg: Config) -> Solution:
        """Bracketing fallback: for each b1, b2 from the consistency; then b1 from equilibrium."""
        L, R = self._lo, self._hi
        W = R - L
        grid = L + W * np.array([0.0, 1e-6, 1e-4, 1e-3, 0.01, 0.03, 0.06, 0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4,
                                 0.45, 0.49])

        def inner(b1):
            """(b2, equilibrium residual) with the consistency met, or None."""
            ups = R - (R - b1) * np.array([0.0, 1e-6, 1e-4, 1e-3, 0.01, 0.03, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7,
                                           0.8, 0.9, 0.99])
            prev = None
            for b2 in ups:
                if b2 - b1 <= 1e-9 * W:
                    continue
                c = self.residuals(cfg, b1, b2, 0.0)[0]
                if prev is not None and np.sign(c) != np.sign(prev[1]):
                    root, _ = _brent(lambda z: self.residuals(cfg, b1, z, 0.0)[0], prev[0], b2, prev[1], c,
                                     1e-15 * W)
                    return root, self.residuals(cfg, b1, root, 0.0)[1]
                prev = (b2, c)
            return None

        prev = None
        for b1 in grid:
            got = inner(b1)
            if got is None:
                continue
            if prev is not None and np.sign(got[1]) != np.sign(prev[1][1]):
                lo, hi, f_lo = prev[0], b1, prev[1][1]
                best = got if abs(got[1]) < abs(prev[1][1]) else prev[1]
                best_b1 = b1 if best is got else prev[0]
                for it in range(1, 200):
                    mid = 0.5 * (lo + hi)
                    here = inner(mid)
                    if here is None:
                        break
                    if abs(here[1]) < abs(best[1]):
                        best, best_b1 = here, mid
                    if np.sign(here[1]) == np.sign(f_lo):
                        lo, f_lo = mid, here[1]
                    else:
                        hi = mid
                    if hi - lo <= 4 * _EPS * W:
                        break
                res = self.residuals(cfg, best_b1, best[0], 0.0)
                norm = float(np.max(np.abs(res)))
                return Solution(cfg, best_b1, best[0], 0.0, norm <= 1e-9, it, norm)
            prev = (b1, got)
        return Solution(cfg, L, R, 0.0, False, 0, math.inf)

    # -- the solution's fields ----------------------------------------------
    def shear(self, sol: Solution) -> Shear:
        """The shear representation of a solved configuration.

        G on the stick interval is carried as knots (piecewise linear; for
        opposite signs the ramp term K is sampled on knots graded towards both
        ends and at the Chebyshev points) for the exact inversion, and as a
        Chebyshev series for the outside strain far from the edges. gamma_1 is
        that of the knots, and the fix-up force closes equilibrium exactly for
        the q actually returned.
        """
        cfg = sol.config
        b1, b2 = sol.stick_left, sol.stick_right
        m, r = 0.5 * (b1 + b2), 0.5 * (b2 - b1)
        t = sie.chebyshev_nodes(self.nodes)
        x = m + r * t
        inner = self._Xa[(self._Xa > b1) & (self._Xa < b2)]
        if cfg.opposite:
            # K behaves like (x - b) ln(x - b) at both ends: grade the knots there
            graded = r * 2.0 ** -np.arange(1, RAMP_GRADING + 1)
            inner = np.union1d(inner, np.concatenate((b1 + graded, b2 - graded, x)))
        xk = np.concatenate(([b1], inner, [b2]))
        gk = self.strain_data(sol, xk)
        if cfg.opposite:
            gk = gk - self.f * (cfg.left - cfg.base) * ramp_hilbert(self.normal, b1, b2, xk, self._breaks)
        tk = (xk - m) / r
        tk[0], tk[-1] = -1.0, 1.0
        coef = sie.coefficients(np.interp(t, tk, gk))
        coef[0] = 0.0
        coef[1] = float(sie.linear_moments(tk, gk, -1.0, 1.0)[1])
        force_chi = self.gammas(cfg, b1, b2, sol.gauge)[2]
        fixup = self.Q - (force_chi + 0.5 * math.pi * r * coef[1])
        if abs(fixup) <= 1e-13 * self.f * self.P:
            fixup = 0.0
        ramp = float(self.normal.pressure(b1)) if cfg.opposite else 0.0
        return Shear(self.L, self.R, b1, b2, cfg, _frozen(coef), ramp, fixup, (_frozen(tk), _frozen(gk)))

    def strain_data(self, sol: Solution, x: np.ndarray) -> np.ndarray:
        """G without the ramp term: [E(x) + F e(x) - A sigma/4 - f s (h' + alpha)] / A."""
        cfg = sol.config
        s = cfg.base
        E = np.interp(x, self.X, self.E)
        for stuck, g in zip((cfg.left == 0, cfg.right == 0), self.gauge):
            if stuck:
                E = E + sol.gauge * np.interp(x, self.X, g)
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
            K = ramp_hilbert(self.normal, shear.stick_left, shear.stick_right, x, self._breaks)
            out = out + self.A * self.f * extra * K
        hil = sie.hilbert_outside(shear.coef, t)
        if near is not None and shear.knots is not None and np.any(near):
            hil[near] = sie.hilbert_linear_outside(shear.knots[0], shear.knots[1], t[near])
        if shear.fixup:
            hil = hil + shear.fixup * 2.0 / (math.pi * shear.radius) * sie.rho(t)
        return out + self.A * hil + 0.25 * self.A * self.sigma



def _ramp_rule(L: float, b1: float, breaks: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Quadrature points and weights on [L, b1] for integrands ~ sqrt(xi - L) and 1/sqrt(b1 - xi).

    xi = L + (b1 - L)(1 - cos phi)/2 makes both ends smooth; the phi range is
    split at the breakpoints of h' inside (p has a weak kink there) and each
    panel gets RAMP_POINTS Gauss-Legendre points.
    """
    cuts = np.sort(breaks[(breaks > L) & (breaks < b1)])
    phis = np.concatenate(([0.0], np.arccos(np.clip(1.0 - 2.0 * (cuts - L) / (b1 - L), -1.0, 1.0)), [math.pi]))
    t, w = _GL_PANEL
    xs, ws = [], []
    for a, c in zip(phis[:-1], phis[1:]):
        phi = 0.5 * (a + c) + 0.5 * (c - a) * t
        xs.append(L + 0.5 * (b1 - L) * (1.0 - np.cos(phi)))
        ws.append(0.25 * (c - a) * (b1 - L) * np.sin(phi) * w)
    return np.concatenate(xs), np.concatenate(ws)


def ramp_hilbert(normal: NormalSolution, b1: float, b2: float, x: np.ndarray,
                 breaks: np.ndarray = np.zeros(0)) -> np.ndarray:
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
    breaks : ndarray, shape (k,)
        Breakpoints of h' (kinks of p), where the quadrature is split.

    Returns
    -------
    ndarray, shape (n,)
    """
    x = np.asarray(x, dtype=float)
    L = normal.left
    p_b = float(normal.pressure(b1))
    ell = (b2 - x) / (b2 - b1)
    xi, jac = _ramp_rule(L, b1, breaks)
    p_xi = normal.pressure(xi)
    right = x >= b1
    anchor = np.where(right, b1, np.maximum(x, L))
    p_anchor = np.where(right, p_b, normal.pressure(anchor))
    with np.errstate(divide="ignore", invalid="ignore"):
        diff = (p_xi[None, :] - p_anchor[:, None]) / (x[:, None] - xi[None, :])
    diff = np.where(np.isfinite(diff), diff, 0.0)
    # the logarithms of the two parts, combined so that those at b1 cancel analytically
    logs = np.where(
        right,
        _xlog(p_b, x - L) - _xlog(p_b * (x - b1) / (b2 - b1), x - b1) - _xlog(p_b * ell, x - b2),
        _xlog(p_anchor, x - L) - _xlog(p_anchor - p_b * ell, x - b1) - _xlog(p_b * ell, x - b2),
    )
    return (diff @ jac + logs + p_b) / math.pi


def _xlog(c, v):
    """c ln abs(v), 0 where c == 0."""
    c, v = np.broadcast_arrays(np.asarray(c, dtype=float), np.asarray(v, dtype=float))
    out = np.zeros(c.shape)
    nz = (c != 0.0) & (v != 0.0)
    out[nz] = c[nz] * np.log(np.abs(v[nz]))
    return out


#: Starts of the two-edge Newton laid just inside the outermost singular points of E (each
#: costs a Newton solve on a hard step; an under-resolved rounded punch has dozens).
SINGULAR_STARTS = 3


def _brent(fun, a, b, fa, fb, xtol, maxiter=100):
    """Brent's root of ``fun`` on a bracket [a, b] with known values; returns (root, iterations)."""
    from scipy.optimize import brentq

    if fa == 0.0:
        return a, 0
    if fb == 0.0:
        return b, 0
    lo, hi = (a, b) if a < b else (b, a)
    try:
        root, info = brentq(fun, lo, hi, xtol=max(xtol, 1e-300), rtol=4 * _EPS, maxiter=maxiter,
                            full_output=True, disp=False)
    except ValueError:  # a non-finite residual inside the bracket: give up on it
        return 0.5 * (lo + hi), -1
    return root, info.iterations
