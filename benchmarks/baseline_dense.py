"""A straightforward dense influence-coefficient solver: the baseline of bench_general.py.

Fixed material grid of ``n`` equal cells over ``extent``; piecewise-constant
shear q_j on the cells in contact, collocation at the cell centres. The
relative tangential displacement of surface point x is (physics.md, T1
integrated)

    g(x) = delta + sum_j K(x, j) q_j + A sigma x / 4,
    K(x, j) = (A/pi) int_{cell j} ln|x - xi| dxi          (closed form),

and a stuck cell keeps the g it had when it last stuck. Each step (and each
part of a step, see below) solves, by a dense LU of the whole system rebuilt
from scratch:

    stuck cells i:   sum_j K_ij q_j + delta = g_lock_i - A sigma x_i / 4
    slipping cells:  q_i = s_i f p_i
    equilibrium:     sum_j q_j dx = Q

iterating the active set until it no longer changes, starting from the last
step's pattern: a stuck cell with |q| > f p starts to slip with the sign of
q; a slipping cell whose slip increment opposes s_i sticks again. A cell that enters contact during a step
sticks at the relative displacement it has on arrival (physics.md, first
trap): the step is split at the load where each cell arrives. Stick edges are
placed inside the last stuck cell by extrapolating the Coulomb margin
m = f p - s q, which vanishes like the square root of the distance to the
edge (m^2 linear).

No memory other than (g_lock, q, delta) is kept; nothing is reused between
steps. The normal problem is the project's (exact pressure at the centres).
"""
from __future__ import annotations

import math

import numpy as np
from scipy.linalg import lu_factor, lu_solve

from halfslip.geometry import NormalProblem
from halfslip.state import Loads

#: Active-set sweeps before giving up on a (sub)step.
MAX_SWEEPS = 60


class DenseBaseline:
    """Dense influence-coefficient marching solver (see module docstring).

    Parameters
    ----------
    problem : NormalProblem
    friction : float
    n : int
        Cells over ``extent``.
    extent : tuple of float
        (x_min, x_max) covering every contact of the history [m].
    """

    def __init__(self, problem: NormalProblem, friction: float, n: int, extent: tuple[float, float]):
        self.problem = problem
        self.f = float(friction)
        self.A = problem.compliance
        lo, hi = extent
        self.edges = np.linspace(lo, hi, n + 1)
        self.x = 0.5 * (self.edges[:-1] + self.edges[1:])
        self.dx = (hi - lo) / n
        self.loads = Loads(0.0, 0.0, 0.0, 0.0)
        self.g_lock = np.full(n, np.nan)  # NaN: out of contact
        self.q = np.zeros(n)
        self.sign = np.zeros(n)  # slip sign of each cell at the end of the last (sub)step
        self.delta = 0.0
        self.stick = (math.nan, math.nan)
        self.solves = 0

    # -- kernel ---------------------------------------------------------------
    def kernel(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """K(x_rows, cell cols), shape (len(rows), len(cols))."""
        x = self.x[rows][:, None]
        a = self.edges[cols][None, :] - x
        b = self.edges[cols + 1][None, :] - x

        def prim(u):
            with np.errstate(divide="ignore", invalid="ignore"):
                return np.where(u == 0.0, 0.0, u * np.log(np.abs(u)) - u)

        return self.A / math.pi * (prim(b) - prim(a))

    def displacement(self, at: np.ndarray, sigma: float) -> np.ndarray:
        """g at cell centres ``at`` from the current q and delta."""
        cells = np.flatnonzero(self.q != 0.0)
        g = np.full(at.size, self.delta) + 0.25 * self.A * sigma * self.x[at]
        if cells.size:
            g += self.kernel(at, cells) @ self.q[cells]
        return g

    # -- marching -------------------------------------------------------------
    def step(self, loads1: Loads) -> None:
        """March from the current loads to ``loads1`` along the straight line."""
        l0 = self.loads
        fractions = self._arrivals(l0, loads1)
        for lam in list(fractions) + [1.0]:
            sub = Loads(*(a + lam * (b - a) for a, b in zip(l0, loads1)))
            self._solve(sub)
        self.loads = loads1

    def _contact(self, loads: Loads) -> tuple[np.ndarray, np.ndarray]:
        """Cells in contact and the pressure at all centres."""
        if loads.P <= 0.0:
            return np.zeros(self.x.size, dtype=bool), np.zeros(self.x.size)
        sol = self.problem.solve(loads.P, loads.M)
        return (self.x > sol.left) & (self.x < sol.right), sol.pressure(self.x)

    def _arrivals(self, l0: Loads, l1: Loads) -> np.ndarray:
        """Fractions of the step at which cells enter contact (sorted, unique)."""
        inside1, _ = self._contact(l1)
        new = np.flatnonzero(inside1 & np.isnan(self.g_lock))
        if new.size == 0 or l1.P <= 0.0:
            return np.zeros(0)
        fracs = []
        for i in new:
            lo, hi = 0.0, 1.0
            for _ in range(50):
                mid = 0.5 * (lo + hi)
                sub = Loads(*(a + mid * (b - a) for a, b in zip(l0, l1)))
                if sub.P > 0.0:
                    sol = self.problem.solve(sub.P, sub.M)
                    inside = sol.left < self.x[i] < sol.right
                else:
                    inside = False
                lo, hi = (lo, mid) if inside else (mid, hi)
            fracs.append(hi)
        return np.unique(np.round(np.array(fracs), 12))

    def _solve(self, loads: Loads) -> None:
        f = self.f
        inside, p = self._contact(loads)
        gone = ~inside & ~np.isnan(self.g_lock)
        self.g_lock[gone] = np.nan
        self.q[~inside] = 0.0
        self.sign[~inside] = 0.0
        cells = np.flatnonzero(inside)
        if cells.size == 0:
            self.stick = (math.nan, math.nan)
            return
        arrived = cells[np.isnan(self.g_lock[cells])]
        if arrived.size:
            self.g_lock[arrived] = self.displacement(arrived, loads.sigma)
        if abs(loads.Q) >= f * loads.P:
            self.q[cells] = math.copysign(f, loads.Q) * p[cells]
            self.sign[:] = 0.0
            self.sign[cells] = math.copysign(1.0, loads.Q)
            self.g_lock[cells] = self.displacement(cells, loads.sigma)
            self.stick = (math.nan, math.nan)
            return
        K = self.kernel(cells, cells)
        sign = self.sign[cells].copy()
        g_old = self.g_lock[cells].copy()
        for _ in range(MAX_SWEEPS):
            stuck = sign == 0
            s_idx = np.flatnonzero(stuck)
            q = sign * f * p[cells]
            n_s = s_idx.size
            M = np.zeros((n_s + 1, n_s + 1))
            M[:n_s, :n_s] = K[np.ix_(s_idx, s_idx)]
            M[:n_s, n_s] = 1.0
            M[n_s, :n_s] = self.dx
            rhs = np.empty(n_s + 1)
            rhs[:n_s] = g_old[s_idx] - 0.25 * self.A * loads.sigma * self.x[cells[s_idx]] - K[np.ix_(s_idx, ~stuck)] @ q[~stuck]
            rhs[n_s] = loads.Q - self.dx * q[~stuck].sum()
            sol = lu_solve(lu_factor(M), rhs)
            self.solves += 1
            q[s_idx] = sol[:n_s]
            delta = sol[n_s]
            g_new = K @ q + delta + 0.25 * self.A * loads.sigma * self.x[cells]
            changed = False
            over = stuck & (np.abs(q) > f * p[cells])
            if np.any(over):
                sign[over] = np.sign(q[over])
                changed = True
            back = ~stuck & (sign * (g_new - g_old) < 0.0)
            if np.any(back):
                sign[back] = 0.0
                changed = True
            if not changed:
                break
        self.q[cells] = q
        self.delta = delta
        self.sign[:] = 0.0
        self.sign[cells] = sign
        slipping = sign != 0
        self.g_lock[cells[slipping]] = g_new[slipping]
        self.stick = self._stick_edges(cells, q, p[cells], sign)

    def _stick_edges(self, cells, q, p, sign) -> tuple[float, float]:
        """Stick edges from the Coulomb margin in the outermost stuck cells (m^2 linear)."""
        stuck = np.flatnonzero(sign == 0)
        if stuck.size == 0:
            return math.nan, math.nan
        out = []
        for end, outward in ((stuck[0], -1), (stuck[-1], 1)):
            x1 = self.x[cells[end]]
            j = end + outward
            if j < 0 or j >= cells.size:  # stuck up to the contact edge
                sol_edge = self.edges[cells[end] + (1 if outward > 0 else 0)]
                out.append(sol_edge)
                continue
            s = sign[j]
            k = end - outward
            m1 = max(self.f * p[end] - s * q[end], 0.0)
            if 0 <= k < cells.size and sign[k] == 0:
                m2 = max(self.f * p[k] - s * q[k], 0.0)
                x2 = self.x[cells[k]]
                if m2 > m1:
                    b = x1 - m1 * m1 * (x2 - x1) / (m2 * m2 - m1 * m1)
                    out.append(float(np.clip(b, x1 - 0.5 * self.dx, x1 + 0.5 * self.dx) if outward < 0 else
                                     np.clip(b, x1 - 0.5 * self.dx, x1 + 0.5 * self.dx)))
                    continue
            out.append(x1 + 0.5 * outward * self.dx)
        return out[0], out[1]

    def tractions(self, x: np.ndarray) -> np.ndarray:
        """Piecewise-constant q at points ``x``."""
        idx = np.clip(np.searchsorted(self.edges, x) - 1, 0, self.x.size - 1)
        inside = (x > self.edges[0]) & (x < self.edges[-1])
        return np.where(inside, self.q[idx], 0.0)
