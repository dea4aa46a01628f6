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
rest (tanh-sinh in u, for the weak singularity where contact forms).
"""
from __future__ import annotations

import math

import numba
import numpy as np

from ..geometry import NormalProblem, NormalSolution
from ..state import Loads

#: tanh-sinh points in u for the arrival integral (step 6 / (ARRIVAL_POINTS - 1) in t).
ARRIVAL_POINTS = 49
#: Normal solves per formation step (contact appearing from P <= 0), general profiles.
FORMATION_SOLVES = 9
#: Bisection steps for the arrival fraction lam_x (formation steps; the reference the hermite roots reproduce).
BISECTION_STEPS = 60
#: Newton iterations at most for the arrival fraction on a monotone piece of a hermite edge path
#: (quadratic convergence: 4 to 6 from the secant start; a step leaving the bracket bisects instead).
NEWTON_STEPS = 60
#: Half-width (in lam) of the neighbourhood of an extremum of a hermite edge in which the bisection is
#: followed step by step rather than replaced by Newton (the edge is not safely monotone there).
EXTREMUM_MARGIN = 1e-9



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
# read-only, as compiled code sees module arrays: _strain_sum is then compiled once for its Python and compiled callers
_U.flags.writeable = _W.flags.writeable = False


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
    vectorised a(P) and P(a) of the normal problem (exact; since 0.4.5 only
    where they are closed forms, or where the step starts separated: a
    symmetric tabulated profile's steps in contact take the hermite form,
    its a(P) costing a root-finding over the profile's moments at every
    arrival point, 0.8 ms each); a step starting
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
        self._sides: dict[int, tuple] = {}
        self._arguments: dict[int, tuple] = {}  # hermite_arguments per side
        #: arrival integrals already taken along this step (GeneralSolver's _integrate): another take of the
        #: same step asks for the same ones
        self.integrals: dict[tuple, np.ndarray] = {}
        self._start: tuple[float, float] | None = None  # the edges at lam_lo
        # (a symmetric tabulated profile's a(P) is a root-finding over its moments, 0.8 ms a point: its steps that
        # do not start separated take the hermite form, whose edges are exact at the ends)
        self._symmetric = (problem.profile.symmetric and loads0.M == 0.0 and loads1.M == 0.0
                           and (problem.cheap_half_width or start is None))
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
            # the edges at lam_lo = 0: the interpolant's first end, exactly (its basis there is 1, 0, 0, -0)
            self._start = float(start.left), float(start.right)
            self._v0 = np.array(start.edge_rates(dP, dM))
            self._v1 = np.array(end.edge_rates(dP, dM))

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
            left, right = _barycentric(np.ascontiguousarray(mu).reshape(-1), self._mu, self._bary, self._edges)
            return left.reshape(lam.shape), right.reshape(lam.shape)
        left, right = _hermite_edges(np.ascontiguousarray(lam).reshape(-1), self._h0, self._v0, self._h1, self._v1)
        return left.reshape(lam.shape), right.reshape(lam.shape)

    def arrival(self, x: np.ndarray, side: int) -> np.ndarray:
        """Fraction lam_x at which each point of ``x`` (shape (n,)) enters the contact.

        ``side`` is -1 for points arriving at the left edge, +1 at the right.
        Points already in contact at lam_lo get lam_lo.

        Notes
        -----
        The answer is the limit of ``BISECTION_STEPS`` bisection steps on "x
        is inside at lam" over [lam_lo, 1], which formation steps take as
        such. A hermite edge is a cubic in lam: away from its extrema (found
        once per side) it is monotone, and there the bisection converges to
        the crossing clamped to the bracket (edge moving outwards) or to the
        end of the bracket its first midpoint picks (moving inwards); Newton,
        kept in the bracket, gives the crossing in a few iterations. Bisection
        steps are taken only while the bracket holds an extremum (within
        ``EXTREMUM_MARGIN``). The cubic is evaluated in an offset form whose
        rounding is relative to the motion of the edge (:func:`_depth`): the
        result is that of the bisection in exact arithmetic to a few 1e-16,
        where the bisection on :meth:`edges` in floating point is off by up to
        eps |edge| / |d edge/d lam| (1e-12 for an edge moving 1e-4 of its
        distance from the centre in the step).
        """
        x = np.asarray(x, dtype=float)
        if self._kind == "symmetric":
            P0, P1 = self.loads0.P, self.loads1.P
            Px = self.problem.load(np.abs(x))
            return np.clip((Px - P0) / (P1 - P0), self.lam_lo, 1.0)
        if self._kind == "hermite":
            lam = self._hermite_arrival(x, side)
        else:
            lo, hi = self._bisect(x, side, np.full(x.shape, self.lam_lo), np.ones(x.shape), BISECTION_STEPS)
            lam = 0.5 * (lo + hi)
        left, right = self.start()
        return np.where((x > left) & (x < right), self.lam_lo, lam)

    @property
    def kind(self) -> str:
        """"symmetric", "formation" or "hermite": how the edges are represented (the class's notes)."""
        return self._kind

    def hermite_arguments(self, side: int) -> tuple:
        """The arguments of :func:`_hermite_strain` (and :func:`hermite_integrals`) from ``lam_lo`` to ``newton``
        for the ``side`` edge of a hermite path."""
        got = self._arguments.get(side)
        if got is None:  # asked by every take of the step and by its arrivals' fit: kept
            (v0, dh, v1), h0, ext = self._side(side)
            left, right = self.start()
            got = self._arguments[side] = (self.lam_lo, left, right, self._h0, self._v0, self._h1, self._v1, h0, v0,
                                           dh, v1, ext, EXTREMUM_MARGIN, BISECTION_STEPS, NEWTON_STEPS)
        return got

    def start(self) -> tuple[float, float]:
        """The edges at lam_lo (points strictly between them are in contact from the start)."""
        if self._start is None:
            left, right = self.edges(np.array(self.lam_lo))
            self._start = float(left), float(right)
        return self._start

    def _bisect(self, x, side, lo, hi, steps):
        """``steps`` bisection steps on "x inside at lam" (the reference algorithm of :meth:`arrival`)."""
        for _ in range(steps):
            mid = 0.5 * (lo + hi)
            left, right = self.edges(mid)
            inside = (x > left) if side < 0 else (x < right)
            hi = np.where(inside, mid, hi)
            lo = np.where(inside, lo, mid)
        return lo, hi

    # -- hermite: one side of the cubic -----------------------------------------------
    def _side(self, side: int):
        """(v0, h1 - h0, v1) of the ``side`` edge, its start h0, and its extrema near [lam_lo, 1]."""
        got = self._sides.get(side)
        if got is None:
            i = 0 if side < 0 else 1
            h0, v0, h1, v1 = (float(self._h0[i]), float(self._v0[i]), float(self._h1[i]), float(self._v1[i]))
            dh = h1 - h0
            # e'(s) = a s^2 + b s + c
            a, b, c = 3.0 * (v0 + v1) - 6.0 * dh, 6.0 * dh - 4.0 * v0 - 2.0 * v1, v0
            ext = np.array([e for e in _quadratic_roots(a, b, c)
                            if self.lam_lo - EXTREMUM_MARGIN < e < 1.0 + EXTREMUM_MARGIN])
            got = self._sides[side] = ((v0, dh, v1), h0, ext)
        return got

    def _hermite_arrival(self, x: np.ndarray, side: int) -> np.ndarray:
        (v0, dh, v1), h0, ext = self._side(side)
        r = np.ascontiguousarray(side * (h0 - x), dtype=float).ravel()
        lam = _hermite_arrivals(side * v0, side * dh, side * v1, r, self.lam_lo, ext,
                                EXTREMUM_MARGIN, BISECTION_STEPS, NEWTON_STEPS)
        return lam.reshape(x.shape)


def _depth(v0, dh, v1, r, s):
    """g(s) = side (e(s) - x) of a hermite edge, given r = side (h0 - x) and side (v0, h1 - h0, v1).

    The offset form h0 + h10 v0 + h01 (h1 - h0) + h11 v1 of the edge: its
    rounding error is relative to the motion of the edge, not to the edge (the
    form of :meth:`EdgePath.edges` puts the crossing of an edge that moves
    1e-4 of its distance from the centre in a band of ~1e-12 in lam).
    """
    t = 1.0 - s
    return r + s * (t * t * v0 + s * ((3.0 - 2.0 * s) * dh - t * v1))


def _slope(v0, dh, v1, s):
    """dg/ds of :func:`_depth`."""
    return 6.0 * s * (1.0 - s) * dh + (s - 1.0) * (3.0 * s - 1.0) * v0 + s * (3.0 * s - 2.0) * v1


_depth_c = numba.njit(cache=True)(_depth)
_slope_c = numba.njit(cache=True)(_slope)


@numba.njit(cache=True)
def _hermite_edges(lam, h0, v0, h1, v1):  # pragma: no cover - compiled
    """Left and right edges at each of ``lam`` (flat): the cubic Hermite interpolant of the ends ``h0``,
    ``h1`` (left, right) and rates ``v0``, ``v1``."""
    left = np.empty(lam.size)
    right = np.empty(lam.size)
    for i in range(lam.size):
        s = lam[i]
        h00 = (1 + 2 * s) * (1 - s) ** 2
        h10 = s * (1 - s) ** 2
        h01 = s * s * (3 - 2 * s)
        h11 = s * s * (s - 1)
        left[i] = h00 * h0[0] + h10 * v0[0] + h01 * h1[0] + h11 * v1[0]
        right[i] = h00 * h0[1] + h10 * v0[1] + h01 * h1[1] + h11 * v1[1]
    return left, right


@numba.njit(cache=True)
def _hermite_gap(x, lam_x, back, side, h0, v0, dh, v1):  # pragma: no cover - compiled
    """x - e(lam_x - back) of the ``side`` hermite edge e (start h0, rates v0, v1, motion dh), shape (n, k),
    lam_x the arrival of x.

    As (x - e(lam_x)) + back D, D the divided difference of the cubic
    between lam_x - back and lam_x, with x - e(lam_x) = 0 where lam_x is a
    crossing: relative accuracy up to lam_x, where :meth:`EdgePath.edges`
    (and lam_x - back rounded) leave an error of eps |e| that the arrival
    integral (inverse square root at lam_x) felt at 1e-6.
    """
    c2, c3 = 3.0 * dh - 2.0 * v0 - v1, v0 - 2.0 * dh + v1
    noise0 = 16.0 * np.finfo(np.float64).eps
    out = np.empty(back.shape)
    for i in range(x.size):
        a = lam_x[i]
        at = side * (h0 - x[i])
        gx = _depth_c(side * v0, side * dh, side * v1, at, a)
        if abs(gx) <= noise0 * (abs(at) + abs(v0) + abs(dh) + abs(v1)):
            gx = 0.0
        for j in range(back.shape[1]):
            b = a - back[i, j]
            out[i, j] = -side * gx + back[i, j] * (v0 + c2 * (a + b) + c3 * (a * a + a * b + b * b))
    return out


@numba.njit(cache=True)
def _strain_sum(x, left, right, gl, gr, span, u, w, side_A):  # pragma: no cover - compiled
    """The arrival integral at each of ``x`` per unit Q' and per unit sigma' (columns 0 and 1: the integral is
    linear in the two), from the edges (n, k) at the nodes lam_x - span u^2 and the gaps gl = x - left,
    gr = x - right there (see :func:`arrival_strains`)."""
    out = np.zeros((x.size, 2))
    for i in range(x.size):
        tq = 0.0
        ts = 0.0
        for j in range(u.size):
            root = math.sqrt(abs(gl[i, j] * gr[i, j]))
            if root > 0.0:
                s = x[i] - 0.5 * (left[i, j] + right[i, j])
                v = 2.0 * span[i] * u[j] * w[j] / root
                tq += v / math.pi
                ts += v * 0.25 * s
        out[i, 0] = side_A * tq
        out[i, 1] = side_A * ts
    return out


@numba.njit(cache=True)
def _hermite_arrivals(v0, dh, v1, r, lam_lo, ext, margin, steps, newton):  # pragma: no cover - compiled
    """The limit of ``steps`` bisection steps on "g(lam) > 0" over [lam_lo, 1], for each r (see
    :meth:`EdgePath.arrival`); ``ext`` the extrema of the edge."""
    out = np.empty(r.size)
    for i in range(r.size):
        ri = r[i]
        lo = lam_lo
        hi = 1.0
        k = 0
        while k < steps:  # the bisection itself while an extremum lies in the bracket
            held = False
            for e in ext:
                if lo < e + margin and hi > e - margin:
                    held = True
            if not held:
                break
            mid = 0.5 * (lo + hi)
            if _depth_c(v0, dh, v1, ri, mid) > 0.0:
                hi = mid
            else:
                lo = mid
            k += 1
        mid = 0.5 * (lo + hi)
        if k == steps:
            out[i] = mid
            continue
        if _slope_c(v0, dh, v1, mid) < 0.0:
            # edge moving inwards: inside below the crossing, so the bisection runs to the end its
            # first midpoint picks
            out[i] = lo if _depth_c(v0, dh, v1, ri, mid) > 0.0 else hi
            continue
        # edge moving outwards: the crossing, clamped to the bracket
        glo = _depth_c(v0, dh, v1, ri, lo)
        ghi = _depth_c(v0, dh, v1, ri, hi)
        if glo > 0.0:
            out[i] = lo
            continue
        if ghi <= 0.0:
            out[i] = hi
            continue
        lam = lo - glo * (hi - lo) / (ghi - glo)  # secant start, then Newton kept in the bracket
        if not (lo < lam < hi):
            lam = mid
        for _ in range(newton):
            g = _depth_c(v0, dh, v1, ri, lam)
            if g == 0.0:  # on the crossing: the bisection's limit is lam itself
                break
            if g > 0.0:
                hi = lam
            else:
                lo = lam
            new = lam - g / _slope_c(v0, dh, v1, lam)
            if not (lo < new < hi):
                new = 0.5 * (lo + hi)
            step = abs(new - lam)
            lam = new
            if step <= 2e-16 or hi - lo <= 4e-16:
                break
        out[i] = lam
    return out


@numba.njit(cache=True)
def _barycentric(mu, nodes, weights, values):  # pragma: no cover - compiled
    """The barycentric interpolant through (``nodes``, ``values`` (n, 2)) at each of ``mu`` (flat): the
    formation path's left and right edges (a node within 1e-15 takes its value)."""
    left = np.empty(mu.size)
    right = np.empty(mu.size)
    for i in range(mu.size):
        at = -1
        for j in range(nodes.size):
            if abs(mu[i] - nodes[j]) <= 1e-15:
                at = j
                break
        if at >= 0:
            left[i] = values[at, 0]
            right[i] = values[at, 1]
            continue
        num0 = num1 = den = 0.0
        for j in range(nodes.size):
            w = weights[j] / (mu[i] - nodes[j])
            num0 += w * values[j, 0]
            num1 += w * values[j, 1]
            den += w
        left[i] = num0 / den
        right[i] = num1 / den
    return left, right


def _quadratic_roots(a: float, b: float, c: float) -> list[float]:
    """Real roots of a s^2 + b s + c (the stable pair of formulas; a linear or constant one too)."""
    if a == 0.0:
        return [-c / b] if b != 0.0 else []
    disc = b * b - 4.0 * a * c
    if disc < 0.0:
        return []
    q = -0.5 * (b + math.copysign(math.sqrt(disc), b))
    return sorted([q / a, c / q] if q != 0.0 else [0.0])


def arrival_strains(path: EdgePath, x: np.ndarray, side: int, compliance: float, change=None) -> np.ndarray:
    """Strain locked in by the stuck increments of the step.

    Parameters
    ----------
    path : EdgePath
    x : ndarray, shape (n,)
        Points arriving at the ``side`` edge (-1 left, +1 right) during the step.
    compliance : float
        A.
    change : (dQ, dsigma), optional
        The load changes whose increments are integrated (default: the path's own).

    Returns
    -------
    ndarray, shape (n,)
        int A sgn(s)(Q'/pi + sigma' s/4) / sqrt(s^2 - d^2) dlam from lam_lo to lam_x.
    """
    l0, l1 = path.loads0, path.loads1
    dQ, dS = (l1.Q - l0.Q, l1.sigma - l0.sigma) if change is None else change
    return arrival_strain_parts(path, x, side, compliance) @ np.array([dQ, dS], dtype=float)


def arrival_strain_parts(path: EdgePath, x: np.ndarray, side: int, compliance: float) -> np.ndarray:
    """:func:`arrival_strains` per unit Q' and per unit sigma', shape (n, 2): the strain of any (dQ, dsigma)
    is their combination (one pass serves M1's increments and the arrivals' shape, a unit shear force)."""
    x = np.asarray(x, dtype=float)
    if x.size == 0:
        return np.zeros((0, 2))
    if path._kind == "hermite":
        return _hermite_strain(np.ascontiguousarray(x), side, compliance, *path.hermite_arguments(side))
    lam_x = path.arrival(x, side)
    span = lam_x - path.lam_lo
    back = span[:, None] * _U**2
    lam = lam_x[:, None] - back  # (n, k)
    left, right = path.edges(lam)
    return _strain_sum(x, left, right, x[:, None] - left, x[:, None] - right, span, _U, _W, compliance * side)


@numba.njit(cache=True)
def _hermite_strain(x, side, A, lam_lo, start_left, start_right, h0, v0, h1, v1, side_h0, side_v0, side_dh,
                    side_v1, ext, margin, steps, newton):  # pragma: no cover - compiled
    """:func:`arrival_strain_parts` on a hermite path in one pass: each point's arrival (the bisection's limit,
    :func:`_hermite_arrivals`; lam_lo inside the contact at the start, (start_left, start_right)), the edges at
    the nodes lam_x - span u^2, the gap to the arriving edge from its divided difference
    (:func:`_hermite_gap`) and the strain sums (:func:`_strain_sum`). ``h0`` .. ``v1`` the edges' ends and
    rates (left, right), ``side_h0`` .. ``side_v1`` the ``side`` edge's start, rate, motion and end rate, ``ext``
    its extrema (EdgePath.hermite_arguments)."""
    r = np.empty(x.size)
    for k in range(x.size):
        r[k] = side * (side_h0 - x[k])
    lam_x = _hermite_arrivals(side * side_v0, side * side_dh, side * side_v1, r, lam_lo, ext, margin, steps, newton)
    for k in range(x.size):
        if start_left < x[k] < start_right:
            lam_x[k] = lam_lo
    u = _U
    span = np.empty(x.size)
    back = np.empty((x.size, u.size))
    lam = np.empty(x.size * u.size)
    for k in range(x.size):
        span[k] = lam_x[k] - lam_lo
        for j in range(u.size):
            back[k, j] = span[k] * u[j] ** 2
            lam[k * u.size + j] = lam_x[k] - back[k, j]
    left, right = _hermite_edges(lam, h0, v0, h1, v1)
    left = left.reshape((x.size, u.size))
    right = right.reshape((x.size, u.size))
    gl = np.empty((x.size, u.size))
    gr = np.empty((x.size, u.size))
    for k in range(x.size):
        for j in range(u.size):
            gl[k, j] = x[k] - left[k, j]
            gr[k, j] = x[k] - right[k, j]
    gap = _hermite_gap(x, lam_x, back, side, side_h0, side_v0, side_dh, side_v1)
    return _strain_sum(x, left, right, gap if side < 0 else gl, gr if side < 0 else gap, span, u, _W, A * side)


@numba.njit(cache=True)
def hermite_integrals(xs, edge, side, A, lam_lo, start_left, start_right, h0, v0, h1, v1, side_h0, side_v0,
                      side_dh, side_v1, ext, margin, steps, newton, gauss_t, gauss_w):  # pragma: no cover - compiled
    """The arrival integrals of a hermite path from ``edge`` to each of ``xs`` (sorted outward on ``side``), per
    unit Q' and sigma', and the distance from the edge (columns 0, 1, 2; GeneralSolver's _integrate): on each
    segment between consecutive points the Gauss-Legendre points ``gauss_t`` (weights ``gauss_w``) of the
    strain (:func:`_hermite_strain`, whose arguments these are), summed outward."""
    n, g = xs.size, gauss_t.size
    pts = np.empty(n * g)
    widths = np.empty(n)
    a = edge
    for i in range(n):
        b = xs[i]
        for j in range(g):
            pts[i * g + j] = a + (b - a) * gauss_t[j]
        widths[i] = abs(b - a)
        a = b
    inc = _hermite_strain(pts, side, A, lam_lo, start_left, start_right, h0, v0, h1, v1, side_h0, side_v0, side_dh,
                          side_v1, ext, margin, steps, newton)
    out = np.empty((n, 3))
    c0 = c1 = c2 = 0.0
    for i in range(n):
        s0 = s1 = 0.0
        for j in range(g):
            s0 += inc[i * g + j, 0] * gauss_w[j]
            s1 += inc[i * g + j, 1] * gauss_w[j]
        c0 += s0 * widths[i]
        c1 += s1 * widths[i]
        c2 += widths[i]
        out[i, 0] = c0
        out[i, 1] = c1
        out[i, 2] = c2
    return out
