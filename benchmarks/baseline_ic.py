"""An independent influence-coefficient (IC) slip solver: the reference baseline of issue 14.

Independent of ``halfslip.solvers``: it uses only ``NormalProblem`` (contact
edges and the pressure at element centres) and the formulation of
docs/physics.md.

Discretisation
--------------
N equal elements of width h on a fixed grid [x_lo, x_hi] spanning every
contact of the history (plus a margin); piecewise-constant shear q_j,
collocation at the centres x_i. The relative tangential displacement (T1
integrated) is

    g_i = delta + sum_j C_ij q_j + A sigma x_i / 4,
    C_ij = (A/pi) int_{elem j} ln(|x_i - xi| / l) dxi      (closed form),

with the internal datum l = the grid length (then -C is positive definite:
the logarithmic capacity of the grid, L/4, is below l). The reported rigid
shift is converted to the datum ``shift_datum`` (default: the profile's
length scale, as the package): delta_l' = delta_l + (A/pi) ln(l'/l) Q.

Per element the state is a sign s in {-1, 0, +1} (0 = stick) and the locked
relative displacement g_lock (NaN = out of contact, no memory). A step (or
sub-step) to loads L solves

    stick (s = 0):  g_i(q, delta) = g_lock_i          (slip increment zero)
    slip  (s = +-1): q_i = s f p_i,  s (g_i - g_lock_i) >= 0
    Coulomb:        |q_i| <= f p_i,  equilibrium  h sum q_j = Q

by a primal-dual active set (semismooth Newton) iteration warm-started from
the previous (sub)step's signs: s_i <- sign(z_i) if |z_i| > f p_i else 0 with
z = q + c (g - g_lock), c = 2 / (pi A h) (the local stiffness of one
element). It stops when the signs repeat; a repeated earlier pattern or
MAX_ITER iterations is reported as not converged. Slipping elements then
take g_lock = g (their new position).

Linear algebra (the "cached factorisation")
--------------------------------------------
C is symmetric Toeplitz on the uniform grid, so the matrix of any contiguous
run of n stick elements is the *leading* n x n block T_n of T = -C, whose
Cholesky factor is the leading block of the Cholesky factor of T. One
Cholesky of T per grid (computed once) therefore serves every single-run
stick set: two triangular sweeps over the leading block (numba, O(n^2)), no
refactorisation when the set changes. The vector T_n^{-1} 1 depends on n only
and is cached. Stick sets of several runs (split stick zones) are solved by
conjugate gradients preconditioned with the exact per-run solves (block
Jacobi), products with T by FFT (circulant embedding). ``strategy='dense'``
(factorise each stick set with LAPACK, cache the factor per set) and
``strategy='lu'`` (the old straw man: LU from scratch every solve) are kept
for the measurement in docs/baseline_ic.md.

Contact arrival (physics.md, first trap)
----------------------------------------
The contact edges along the straight step are interpolated by a cubic spline
through normal solves at NODES points (graded like s^2 when the step starts
from P = 0, where the edges grow like sqrt(P)); the fraction at which each
element centre enters contact is the root of the spline. The step is split at
every arrival: each sub-step is solved at its exact loads (a true normal
solve), and the arriving elements then lock the g they have at that instant.
Elements leaving contact forget their memory.

Stick edges
-----------
``stick_left/right``: inside the outermost stick element next to a slip zone
the Coulomb margin m = 1 - s q/(f p) vanishes like sqrt(distance to the edge),
so m^2 is extrapolated linearly from the two outermost stick elements to
zero, the result clipped to [centre of the stick element, centre of the
slipping neighbour]. Where the stick zone reaches the contact edge the stick
edge is the contact edge. ``stick_left_cell/right_cell`` give the element
boundaries instead.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numba
import numpy as np
import scipy.fft as sfft
from scipy.interpolate import CubicSpline
from scipy.linalg import cho_factor, cho_solve, cholesky, lu_factor, lu_solve
from scipy.linalg.lapack import dtrtri

from halfslip.geometry import Hertz, NormalProblem

#: Active-set iterations per (sub)step before giving up.
MAX_ITER = 60
#: Normal solves along a step for the edge spline: closed-form normal problems (Hertz, any M) / others.
#: Worst spline error of the edges on random histories (seed 0): Hertz 33 nodes 2.7e-10 of the width
#: (17: 5e-6), punch 17 nodes 3.9e-7 (33: 4.8e-9); h is 1.3e-4 of the width at 8000 elements.
NODES_CHEAP, NODES_COSTLY = 33, 17
#: Coulomb tolerance of the active-set update, relative to f max p.
COULOMB_TOL = 1e-10
#: PCG relative tolerance (multi-run stick sets).
CG_TOL = 1e-13


# -- triangular sweeps over the leading block of a cached Cholesky factor ------
@numba.njit(cache=True)
def _leading_cho_solve(L, b):
    """Solve (L_n L_n^T) x = b with L_n the leading n x n block of the lower factor L (F-ordered)."""
    n = b.shape[0]
    y = b.copy()
    for j in range(n):  # forward: L y = b, column oriented (columns contiguous)
        y[j] /= L[j, j]
        yj = y[j]
        for i in range(j + 1, n):
            y[i] -= L[i, j] * yj
    for j in range(n - 1, -1, -1):  # backward: L^T x = y, dot with column j
        s = y[j]
        for i in range(j + 1, n):
            s -= L[i, j] * y[i]
        y[j] = s / L[j, j]
    return y


def _prim(u, datum):
    """int ln(|u|/l) du = u ln(|u|/l) - u (0 at u = 0)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(u == 0.0, 0.0, u * np.log(np.abs(u) / datum) - u)


@dataclass
class StepReport:
    converged: bool = True
    iterations: int = 0
    substeps: int = 0
    solves: int = 0
    cg_iterations: int = 0
    time: float = 0.0
    gross: bool = False
    late: int = 0  # elements found in contact at the step's end without an arrival event
    messages: list = field(default_factory=list)


class ICBaseline:
    """Influence-coefficient marching solver (see module docstring).

    Parameters
    ----------
    problem : NormalProblem
    friction : float
    n : int
        Number of elements over ``extent``.
    extent : (float, float)
        Grid [x_lo, x_hi] covering every contact of the history [m].
    strategy : {'toeplitz', 'dense', 'lu'}
        Linear algebra of the stick-set solves (module docstring).
    shift_datum : float, optional
        Datum length of the reported rigid shift (default: profile length scale).
    """

    def __init__(self, problem: NormalProblem, friction: float, n: int, extent, strategy="gs",
                 shift_datum=None, pdas_c=0.0, exact_arrivals=True):
        self.problem = problem
        self.f = float(friction)
        self.A = problem.compliance
        lo, hi = map(float, extent)
        self.n = int(n)
        self.edges = np.linspace(lo, hi, self.n + 1)
        self.x = 0.5 * (self.edges[:-1] + self.edges[1:])
        self.h = (hi - lo) / self.n
        self.datum = hi - lo
        self.shift_datum = float(shift_datum if shift_datum is not None else problem.profile.length_scale)
        self.strategy = strategy
        self.exact_arrivals = bool(exact_arrivals)
        k = np.arange(self.n) * self.h
        self.t = self.A / math.pi * (_prim(k + 0.5 * self.h, self.datum) - _prim(k - 0.5 * self.h, self.datum))
        # circulant embedding of C for FFT products
        col = np.concatenate([self.t, [0.0], self.t[:0:-1]])
        self._m = col.size
        self._fft = sfft.rfft(col)
        self._chol = None
        self._linv = None
        self._gs_cache: dict = {}
        self._ones_cache: dict[int, np.ndarray] = {}
        self._dense_cache: dict = {}
        self.c_pdas = pdas_c * 2.0 / (math.pi * self.A * self.h)
        # state
        self.P = self.Q = self.M = self.sigma = 0.0
        self.g_lock = np.full(self.n, np.nan)
        self.sign = np.zeros(self.n)
        self.q = np.zeros(self.n)
        self.p = np.zeros(self.n)
        self.delta = 0.0
        self.dissipation = 0.0
        self.contact = (0.0, 0.0)
        self.counters = dict(solves=0, cg=0, normal=0)

    # -- linear algebra ----------------------------------------------------------
    def matvec(self, q):
        """C @ q on the whole grid (FFT)."""
        return sfft.irfft(self._fft * sfft.rfft(q, self._m), self._m)[: self.n]

    def _cholesky(self):
        if self._chol is None:
            i = np.arange(self.n)
            T = -self.t[np.abs(i[:, None] - i[None, :])]
            self._chol = np.asfortranarray(cholesky(T, lower=True, overwrite_a=True, check_finite=False))
        return self._chol

    def _inverse_factor(self):
        """L^{-1} (lower) of the cached Cholesky factor: row n-1 gives the last column of T_n^{-1}."""
        if self._linv is None:
            L = self._cholesky()
            linv, info = dtrtri(L, lower=1, overwrite_c=0)
            if info != 0:
                raise np.linalg.LinAlgError(f"dtrtri failed ({info})")
            self._linv = np.ascontiguousarray(linv)
            if self.strategy == "gs":
                self._chol = None  # only the inverse factor is needed
        return self._linv

    def _gs(self, n):
        """Gohberg-Semencul data of T_n^{-1} (cached per n)."""
        d = self._gs_cache.get(n)
        if d is None:
            linv = self._inverse_factor()
            y = linv[n - 1, :n] * linv[n - 1, n - 1]  # T_n^{-1} e_n
            x = y[::-1].copy()  # T_n^{-1} e_1 (persymmetry)
            u = np.concatenate([[0.0], y[:-1]])  # Z J x
            m = sfft.next_fast_len(2 * n, real=True)
            d = (m, sfft.rfft(x, m), sfft.rfft(u, m), x[0])
            if len(self._gs_cache) > 256:
                self._gs_cache.pop(next(iter(self._gs_cache)))
            self._gs_cache[n] = d
        return d

    def _run_solve(self, n, b):
        """T_n^{-1} b for a contiguous run of n elements.

        'gs': Gohberg-Semencul, T_n^{-1} = (L(x) L(x)^T - L(u) L(u)^T) / x_0 with x = T_n^{-1} e_1,
        u = Z J x and L(v) the lower triangular Toeplitz matrix of first column v: four FFT products,
        O(n log n). x comes from one row of the inverse Cholesky factor of T (T_n's factor is the
        leading block). 'toeplitz': two triangular sweeps over the leading block, O(n^2).
        """
        if self.strategy != "gs":
            return _leading_cho_solve(self._cholesky(), b)
        m, fx, fu, x0 = self._gs(n)
        rb = sfft.rfft(b[::-1], m)
        ltx = sfft.irfft(fx * rb, m)[:n][::-1]  # L(x)^T b
        ltu = sfft.irfft(fu * rb, m)[:n][::-1]  # L(u)^T b
        return sfft.irfft(fx * sfft.rfft(ltx, m) - fu * sfft.rfft(ltu, m), m)[:n] / x0

    def _run_ones(self, n):
        u = self._ones_cache.get(n)
        if u is None:
            u = self._run_solve(n, np.ones(n))
            self._ones_cache[n] = u
        return u

    def _solve_stick(self, stick, rhs, report):
        """Solve -C_SS q = rhs_S (two right-hand sides packed as columns: rhs shape (ns, k))."""
        self.counters["solves"] += 1
        report.solves += 1
        if self.strategy == "lu":
            T = -self.t[np.abs(stick[:, None] - stick[None, :])]
            return lu_solve(lu_factor(T, check_finite=False), rhs, check_finite=False)
        if self.strategy == "dense":
            key = (stick[0], stick.size, hash(stick.tobytes()))
            fac = self._dense_cache.get(key)
            if fac is None:
                T = -self.t[np.abs(stick[:, None] - stick[None, :])]
                fac = cho_factor(T, lower=True, check_finite=False)
                if len(self._dense_cache) > 8:
                    self._dense_cache.pop(next(iter(self._dense_cache)))
                self._dense_cache[key] = fac
            return cho_solve(fac, rhs, check_finite=False)
        # toeplitz: runs
        breaks = np.flatnonzero(np.diff(stick) > 1) + 1
        starts = np.concatenate([[0], breaks])
        stops = np.concatenate([breaks, [stick.size]])
        out = np.empty_like(rhs)
        if starts.size == 1:
            n = stick.size
            out[:, 0] = self._run_ones(n)
            for k in range(1, rhs.shape[1]):
                out[:, k] = self._run_solve(n, np.ascontiguousarray(rhs[:, k]))
            return out

        def prec(r):
            z = np.empty_like(r)
            for a, b in zip(starts, stops):
                z[a:b] = self._run_solve(b - a, np.ascontiguousarray(r[a:b]))
            return z

        def op(v):
            full = np.zeros(self.n)
            full[stick] = v
            return -self.matvec(full)[stick]

        for k in range(rhs.shape[1]):
            b = rhs[:, k]
            x = prec(b)
            r = b - op(x)
            z = prec(r)
            d = z.copy()
            rz = r @ z
            bn = math.sqrt(b @ b)
            it = 0
            while math.sqrt(r @ r) > CG_TOL * bn and it < 200:
                Ad = op(d)
                alpha = rz / (d @ Ad)
                x += alpha * d
                r -= alpha * Ad
                z = prec(r)
                rz_new = r @ z
                d = z + (rz_new / rz) * d
                rz = rz_new
                it += 1
            report.cg_iterations += it
            self.counters["cg"] += it
            out[:, k] = x
        return out

    # -- normal problem ------------------------------------------------------------
    def _normal(self, P, M):
        self.counters["normal"] += 1
        if P <= 0.0:
            return None
        return self.problem.solve(P, M)

    def _edges_along(self, l0, l1):
        """Cubic splines left(lam), right(lam) along the straight step, and the parameter map."""
        graded = l0[0] <= 0.0
        nodes = NODES_CHEAP if isinstance(self.problem.profile, Hertz) else NODES_COSTLY
        s = np.linspace(0.0, 1.0, nodes)
        if graded:  # the contact forms at lam = 0+: the first node just after it
            s[0] = 1e-6
        left, right = np.empty(nodes), np.empty(nodes)
        for k in range(nodes):
            while True:
                la = s[k] ** 2 if graded else s[k]
                P = l0[0] + la * (l1[0] - l0[0])
                M = l0[2] + la * (l1[2] - l0[2])
                try:
                    sol = self._normal(P, M)
                    break
                except ValueError:  # the general normal solver fails at tiny P with M != 0 (punch)
                    if not (graded and k == 0 and s[0] < 0.25 * s[1]):
                        raise
                    s[0] *= 10.0
            left[k], right[k] = (sol.left, sol.right) if sol is not None else (0.0, 0.0)
        return s, CubicSpline(s, left), CubicSpline(s, right), graded

    def _arrivals(self, l0, l1):
        """[(lam, element indices)] of elements entering contact during the step, sorted.

        Also keeps the splines: within the step, membership of the contact is decided by them, so that
        it agrees with the events (a true normal solve could put a just-arrived centre a rounding
        outside and forget its memory).
        """
        s, sl, sr, graded = self._edges_along(l0, l1)
        self._spline = (sl, sr, graded)
        fine = np.linspace(0.0, 1.0, 1025)
        L, R = sl(fine), sr(fine)
        lo, hi = L.min(), R.max()
        cand = np.flatnonzero((self.x > lo) & (self.x < hi))
        if cand.size == 0:
            return []
        xs = self.x[cand][:, None]
        phi = np.minimum(xs - L[None, :], R[None, :] - xs)  # > 0 inside
        inside = phi > 0.0
        end_in = inside[:, -1]
        # last crossing outside -> inside
        out_cols = np.where(~inside, np.arange(fine.size)[None, :], -1).max(axis=1)
        events = {}
        # inside throughout but without memory: the contact forms at lam = 0+ (first step from P = 0)
        first = cand[end_in & (out_cols < 0) & np.isnan(self.g_lock[cand])]
        if first.size:
            events[0.0] = list(first)
        rows = np.flatnonzero(end_in & (out_cols >= 0))  # inside at the end, outside somewhere before
        if rows.size == 0:
            return sorted(((lam, np.array(idx)) for lam, idx in events.items()), key=lambda e: e[0])
        k = out_cols[rows]
        xi = self.x[cand[rows]]
        a, b = fine[k], fine[np.minimum(k + 1, fine.size - 1)]
        for _ in range(44):  # bisection on the splines, all elements at once
            m = 0.5 * (a + b)
            ins = np.minimum(xi - sl(m), sr(m) - xi) > 0.0
            b = np.where(ins, m, b)
            a = np.where(ins, a, m)
        lam = b**2 if graded else b
        order = np.argsort(lam, kind="stable")
        lam, elems = lam[order], cand[rows][order]
        groups = np.flatnonzero(np.diff(lam) > 1e-12) + 1  # events closer than 1e-12 are one event
        for la, idx in zip(np.split(lam, groups), np.split(elems, groups)):
            events.setdefault(float(la[-1]), []).extend(idx)
        return sorted(((lam, np.array(idx)) for lam, idx in events.items()), key=lambda e: e[0])

    # -- marching ------------------------------------------------------------------
    def step(self, P, Q, M, sigma):
        """March along the straight line from the current loads to (P, Q, M, sigma)."""
        started = time.perf_counter()
        report = StepReport()
        l0 = (self.P, self.Q, self.M, self.sigma)
        l1 = (float(P), float(Q), float(M), float(sigma))
        self._spline = None
        if not self.exact_arrivals:  # the trap, kept for the tests: arrivals pinned at the step's start
            sol = self._normal(l1[0], l1[2])
            if sol is not None:
                new = (self.x > sol.left) & (self.x < sol.right) & np.isnan(self.g_lock)
                self.g_lock[new] = self._g(l0[3])[new]
                self.sign[new] = 0.0
            events = []
        else:
            events = self._arrivals(l0, l1) if l1[0] > 0.0 else []
        self._lam = None
        for lam, idx in events + [(1.0, np.zeros(0, dtype=int))]:
            loads = tuple(a + lam * (b - a) for a, b in zip(l0, l1))
            self._lam = lam
            self._substep(loads, idx, report, final=(lam == 1.0))
        self.P, self.Q, self.M, self.sigma = l1
        report.time = time.perf_counter() - started
        return report

    def _substep(self, loads, arriving, report, final):
        P, Q, M, sigma = loads
        report.substeps += 1
        f, A, h = self.f, self.A, self.h
        sol = self._normal(P, M)
        p_old = self.p
        if sol is None:  # separated: no memory; arrivals at lam = 0+ lock the unloaded g
            self.g_lock[:] = np.nan
            self.q[:] = 0.0
            self.sign[:] = 0.0
            self.p = np.zeros(self.n)
            self.contact = (0.0, 0.0)
            if len(arriving):
                self.g_lock[arriving] = self._g(sigma)[arriving]
            return
        self.contact = (sol.left, sol.right)
        inside = (self.x > sol.left) & (self.x < sol.right)
        if self._spline is not None and self._lam is not None:  # membership from the event splines
            sl, sr, graded = self._spline
            u = math.sqrt(self._lam) if graded else self._lam
            if not graded or u >= 1e-6:
                inside = (self.x > float(sl(u))) & (self.x < float(sr(u)))
        p = np.where(inside, sol.pressure(self.x), 0.0)
        self.g_lock[~inside] = np.nan
        self.sign[~inside] = 0.0
        self.q[~inside] = 0.0
        active = inside & ~np.isnan(self.g_lock)
        self._solve(active, p, Q, sigma, p_old, report)
        new = inside & np.isnan(self.g_lock)
        new[arriving] = True
        if np.any(new):
            g = self._g(sigma)
            self.g_lock[new] = g[new]
            self.sign[new] = 0.0
            if final and np.any(new & inside):  # arrivals at lam = 1 (or missed): carry them in the final state
                report.late += int(np.count_nonzero(new & inside)) - len(arriving)
                self._solve(inside & ~np.isnan(self.g_lock), p, Q, sigma, p, report)
        self.p = p

    def _g(self, sigma):
        return self.delta + self.matvec(self.q) + 0.25 * self.A * sigma * self.x

    def _solve(self, active, p, Q, sigma, p_old, report):
        f, A, h = self.f, self.A, self.h
        idx = np.flatnonzero(active)
        if idx.size == 0:
            self.q[:] = 0.0
            return
        pm = f * p[idx].max()
        g_lock = self.g_lock[idx]
        if abs(Q) >= f * h * p[idx].sum():  # gross sliding on the discrete contact
            report.gross = True
            s = math.copysign(1.0, Q)
            q = np.zeros(self.n)
            q[idx] = s * f * p[idx]
            # the shift: the middle element keeps its position (datum of a gross slide)
            g0 = self.matvec(q) + 0.25 * A * sigma * self.x
            mid = idx[idx.size // 2]
            self.delta = self.g_lock[mid] - g0[mid]
            self._finish(idx, q, s * np.ones(idx.size), p, p_old, sigma)
            return
        sign = self.sign[idx].copy()
        seen = set()
        converged = False
        xs = 0.25 * A * sigma * self.x
        for it in range(1, MAX_ITER + 1):
            report.iterations += 1
            st = sign == 0.0
            if not st.any():  # keep equilibrium solvable: the element of largest pressure sticks
                j = int(np.argmax(p[idx]))
                st[j] = True
                sign[j] = 0.0
            q = np.zeros(self.n)
            q[idx[~st]] = sign[~st] * f * p[idx[~st]]
            stick = idx[st]
            r = g_lock[st] - xs[stick] - self.matvec(q)[stick]
            sol = self._solve_stick(stick, np.column_stack([np.ones(stick.size), -r]), report)
            u, w = sol[:, 0], sol[:, 1]
            # q_S = delta u + w  (from -C q = delta 1 - r), equilibrium fixes delta
            Qs = Q / h - q[idx[~st]].sum()
            delta = (Qs - w.sum()) / u.sum()
            q[stick] = delta * u + w
            g = delta + self.matvec(q) + xs
            dg = g[idx] - g_lock
            new = self._update(sign, q[idx], dg, f * p[idx], COULOMB_TOL * pm)
            if np.array_equal(new, sign):
                converged = True
                break
            key = new.tobytes()
            if key in seen:
                report.messages.append(f"active set cycles after {it} iterations")
                break
            seen.add(key)
            sign = new
        if not converged:
            report.converged = False
            if not report.messages:
                report.messages.append(f"no convergence in {MAX_ITER} iterations")
        self.delta = delta
        self._finish(idx, q, sign, p, p_old, sigma)

    def _update(self, sign, q, dg, fp, tol):
        """New signs. c = 0: a stick element whose |q| exceeds f p slips with the sign of q, a slip
        element whose increment opposes its sign sticks. c > 0: the semismooth-Newton rule
        sign(z) where |z| > f p, z = q + c dg (it may reverse a slip element directly)."""
        if self.c_pdas > 0.0:
            z = q + self.c_pdas * dg
            return np.where(np.abs(z) > fp + tol, np.sign(z), 0.0)
        new = sign.copy()
        st = sign == 0.0
        over = st & (np.abs(q) > fp + tol)
        new[over] = np.sign(q[over])
        back = ~st & (sign * dg < 0.0)
        new[back] = 0.0
        return new

    def _finish(self, idx, q, sign, p, p_old, sigma):
        g = self._g_from(q, sigma)
        slip = idx[sign != 0.0]
        dg = g[slip] - self.g_lock[slip]
        self.dissipation += self.f * self.h * float(np.sum(0.5 * (p[slip] + p_old[slip]) * np.abs(dg)))
        self.g_lock[slip] = g[slip]
        self.q = q
        self.sign[:] = 0.0
        self.sign[idx] = sign

    def _g_from(self, q, sigma):
        return self.delta + self.matvec(q) + 0.25 * self.A * sigma * self.x

    # -- outputs -------------------------------------------------------------------
    @property
    def shift(self):
        """Rigid shift with the datum ``shift_datum`` (module docstring)."""
        return self.delta + self.A / math.pi * math.log(self.shift_datum / self.datum) * self.h * self.q.sum()

    def zones(self):
        """Stick intervals [(left, right)] (interpolated edges) and the outermost edges, both forms."""
        inside = ~np.isnan(self.g_lock) & (self.p > 0.0)
        idx = np.flatnonzero(inside)
        nan = (math.nan, math.nan)
        if idx.size == 0:
            return dict(count=0, stick=nan, cell=nan, main=nan, island=0.0)
        st = idx[self.sign[idx] == 0.0]
        if st.size == 0:
            return dict(count=0, stick=nan, cell=nan, main=nan, island=0.0)
        breaks = np.flatnonzero(np.diff(st) > 1) + 1
        count = breaks.size + 1
        i0, i1 = st[0], st[-1]
        left = self._edge(i0, -1, idx)
        right = self._edge(i1, +1, idx)
        cell = (self.edges[i0] if i0 != idx[0] else self.contact[0],
                self.edges[i1 + 1] if i1 != idx[-1] else self.contact[1])
        runs = np.split(st, breaks)
        edges = [(self._edge(r[0], -1, idx), self._edge(r[-1], +1, idx)) for r in runs]
        widths = [b - a for a, b in edges]
        k = int(np.argmax(widths))
        others = max([w for j, w in enumerate(widths) if j != k], default=0.0)
        return dict(count=count, stick=(left, right), cell=cell, main=edges[k], island=others)

    def _edge(self, i, outward, idx):
        if (outward < 0 and i == idx[0]) or (outward > 0 and i == idx[-1]):
            return self.contact[0] if outward < 0 else self.contact[1]
        j = i + outward
        s = self.sign[j]
        fp = self.f * self.p
        m1 = max(1.0 - s * self.q[i] / fp[i], 0.0)
        k = i - outward
        x1, xj = self.x[i], self.x[j]
        if self.sign[k] != 0.0 or not self.p[k] > 0.0:
            return 0.5 * (x1 + xj)
        m2 = max(1.0 - s * self.q[k] / fp[k], 0.0)
        if m2 <= m1:
            return 0.5 * (x1 + xj)
        b = x1 + m1 * m1 * (x1 - self.x[k]) / (m2 * m2 - m1 * m1)
        return float(np.clip(b, min(x1, xj), max(x1, xj)))


def history_extent(problem, P, M, margin=0.03, sub=8):
    """Grid covering every contact along the straight steps of (P, M) (edges sampled ``sub`` times a step)."""
    lo, hi = math.inf, -math.inf
    for k in range(1, len(P)):
        for lam in np.linspace(0.0, 1.0, sub + 1)[1:]:
            Pl = P[k - 1] + lam * (P[k] - P[k - 1])
            if Pl <= 0.0:
                continue
            sol = problem.solve(Pl, M[k - 1] + lam * (M[k] - M[k - 1]))
            lo, hi = min(lo, sol.left), max(hi, sol.right)
    w = hi - lo
    return lo - margin * w, hi + margin * w


def run_history(problem, friction, n, P, Q, M, sigma, extent=None, strategy="gs", keep_q=False,
                progress=None, time_split=1, **options):
    """March the samples (P[0..], ...) with point 0 the start (normally all zero). Returns a dict of arrays."""
    P, Q, M, sigma = (np.asarray(v, dtype=float) for v in (P, Q, M, sigma))
    if extent is None:
        extent = history_extent(problem, P, M)
    solver = ICBaseline(problem, friction, n, extent, strategy=strategy, **options)
    solver.P, solver.Q, solver.M, solver.sigma = P[0], Q[0], M[0], sigma[0]
    steps = len(P) - 1
    out = {k: np.full(steps, np.nan) for k in (
        "contact_left", "contact_right", "stick_left", "stick_right", "stick_left_cell", "stick_right_cell",
        "main_left", "main_right", "island", "late",
        "shift", "dissipation", "dissipation_increment", "time", "iterations", "substeps", "solves",
        "cg_iterations")}
    out["intervals"] = np.zeros(steps, dtype=int)
    out["converged"] = np.zeros(steps, dtype=bool)
    out["gross"] = np.zeros(steps, dtype=bool)
    qs = []
    messages = []
    for k in range(steps):
        before = solver.dissipation
        if time_split > 1:  # equal straight sub-steps (a check of the time discretisation)
            reps = [solver.step(*(v[k] + j / time_split * (v[k + 1] - v[k]) for v in (P, Q, M, sigma)))
                    for j in range(1, time_split + 1)]
            rep = StepReport(converged=all(r.converged for r in reps), iterations=sum(r.iterations for r in reps),
                             substeps=sum(r.substeps for r in reps), solves=sum(r.solves for r in reps),
                             cg_iterations=sum(r.cg_iterations for r in reps), time=sum(r.time for r in reps),
                             gross=any(r.gross for r in reps), messages=sum((r.messages for r in reps), []))
        else:
            rep = solver.step(P[k + 1], Q[k + 1], M[k + 1], sigma[k + 1])
        z = solver.zones()
        out["contact_left"][k], out["contact_right"][k] = solver.contact
        out["stick_left"][k], out["stick_right"][k] = z["stick"]
        out["stick_left_cell"][k], out["stick_right_cell"][k] = z["cell"]
        out["intervals"][k] = z["count"]
        out["main_left"][k], out["main_right"][k] = z["main"]
        out["island"][k] = z["island"]
        out["late"][k] = rep.late
        out["shift"][k] = solver.shift
        out["dissipation"][k] = solver.dissipation
        out["dissipation_increment"][k] = solver.dissipation - before
        out["time"][k] = rep.time
        out["iterations"][k] = rep.iterations
        out["substeps"][k] = rep.substeps
        out["solves"][k] = rep.solves
        out["cg_iterations"][k] = rep.cg_iterations
        out["converged"][k] = rep.converged
        out["gross"][k] = rep.gross
        messages += [f"step {k + 1}: {m}" for m in rep.messages]
        if keep_q:
            qs.append(solver.q.copy())
        if progress is not None:
            progress(k, steps, rep)
    out["messages"] = messages
    out["x"] = solver.x
    if keep_q:
        out["q"] = np.array(qs)
    out["solver"] = solver
    return out
