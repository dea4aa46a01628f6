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

import functools
import math

import numba
import numpy as np
from numpy.polynomial import chebyshev as cheb

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
#: The lattice's own error in the shear of a fully stuck growing contact, times (W / h)^2: measured 3.8e-5 /
#: 9.3e-6 / 2.1e-6 of max q after the forming step at 1024 / 2048 / 4096 nodes (the random Hertz history's first
#: step, benchmarks/stuck_growth_exact.py): 40, 39, 35.
LATTICE_SHEAR_ERROR = 40.0
#: The part of the arrivals' shear error a step's edge path may add, at most, of the lattice's own (above). An
#: edge off by delta moves the arrival of the points it passes, and with it their locks by the inverse-square-root
#: strain's integral over that distance: about sqrt(delta / travel) of what a point locks in over the step
#: (travel: the edge's motion in it), and the shear of the arrived material follows its locks (at most one to
#: one; measured 0.03 of it for the single cubic on the history above). So a path with cells h of the contact
#: width W may be off by (PATH_SHARE LATTICE_SHEAR_ERROR (h / W)^2)^2 travel: 1.5e-11 travel at 1024 nodes.
PATH_SHARE = 0.1
#: The cell (h / W) a path is made for where no lattice is said (EdgePath's ``cell``): 2048 nodes'.
DEFAULT_CELL = 1.0 / 2048
#: An edge error that rounding alone can make, relative to the contact's width: the normal problem's edges
#: scatter about a smooth interpolant through them by up to 1.2e-13 of the width (the random histories, 33
#: points), the Newton of its contact equations stopping at the rounding of their residual.
PATH_ROUNDING = 1e-12
#: A level's error at most this times the one before's, twice the points: geometric convergence (an edge
#: analytic along the step) rather than algebraic (a kink in the path: 2^-1 to 2^-3 a doubling), so the next
#: level's error is extrapolated (EdgePath._verify).
GEOMETRIC_RATIO = 1e-3
#: Chebyshev-Lobatto nodes at most of a step's edge path (the levels 5, 9, 17, 33: each holds the one before).
PATH_NODES = 33
#: Cubic pieces at most of a step's edge table (EdgePath._verify; 8 bytes x 4 a piece).
TABLE_PIECES = 4096


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
    parent : (EdgePath, a, b), optional
        The verified path of a step of which this one is the part from fraction a to b (GeneralSolver's
        sub-steps): its accuracy is inherited, without normal solves (:meth:`_inherit`).
    cell : float, optional
        The cell of the lattice whose arrivals the path serves, relative to the contact's width at the end
        (its allowance, :func:`allowance`; default DEFAULT_CELL).
    lazy : bool
        Verify (or take the parent's part) on the first use of the edges rather than here.
    tally : dict, optional
        Counts the normal solves made for the path under "path_solves" (GeneralSolver's counters).

    Attributes
    ----------
    lam_lo : float
        Fraction of the step at which contact first exists (0 unless the step
        starts separated).
    solves : int
        Normal solves made here.
    error : float
        The estimated largest error of a growing edge along the path, relative to the contact's width at the
        end (0 where the path is exact or no edge grows; steps starting in contact only).
    excess : float
        That over the allowance (:meth:`_verify`; above 1 where PATH_NODES points or TABLE_PIECES pieces did
        not reach it: an edge crossing a kink of the profile, whose path is not smooth there). Above
        1 / PATH_SHARE^2 the path's part of the arrivals' shear error may exceed the lattice's own:
        :attr:`dominant`.

    Notes
    -----
    Four representations: the symmetric profiles with M = 0 all along use the
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
    inverse-square-root coefficient of the increment there, where one normal
    solve at mid-step finds it accurate enough for the arrivals' locks, and
    else a table of cubic pieces of an interpolant through normal solves
    (:meth:`_verify`; since 0.4.13: the cubic alone put a growing Hertz
    contact's locks 1.8e-3 of max q off at every cell size).
    """

    def __init__(self, problem: NormalProblem, start: NormalSolution | None, end: NormalSolution,
                 loads0: Loads, loads1: Loads, parent: tuple[EdgePath, float, float] | None = None,
                 cell: float | None = None, lazy: bool = False, tally: dict | None = None):
        self.problem = problem
        self._tally = tally
        self._pending: tuple | None = None  # what makes the path ready (lazy: on its first use)
        self.cell = DEFAULT_CELL if cell is None else float(cell)
        self.loads0, self.loads1 = loads0, loads1
        P0, P1 = loads0.P, loads1.P
        self.lam_lo = 0.0 if start is not None else max(0.0, P0 / (P0 - P1)) if P0 < P1 else 0.0
        self.solves = 0
        self.error = 0.0
        self.excess = 0.0
        self._tv = self._td = _NO_TABLE  # the table's offsets from the start edges and slopes (kind "table")
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
            self._count(n)
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
            self._pending = (start, end) if parent is None else parent
            if not lazy:
                self._ready()

    def _count(self, solves: int) -> None:
        self.solves += solves
        if self._tally is not None:
            self._tally["path_solves"] += solves

    def _ready(self) -> None:
        """Verify the path (:meth:`_verify`), or take its part of its parent's (:meth:`_inherit`), if that is
        still to be done: a lazy path (GeneralSolver's) does it on its first use, and a step in which no cell
        arrives never uses it."""
        if self._pending is None:
            return
        pending, self._pending = self._pending, None
        if isinstance(pending[0], EdgePath):
            pending[0]._ready()
            self._inherit(*pending)
        else:
            self._verify(*pending)

    @property
    def dominant(self) -> bool:
        """Whether the path's error may make more of the arrivals' shear error than the lattice's own (its
        :attr:`excess` above 1 / PATH_SHARE^2: the lock error goes as the square root of the path's; False for
        a lazy path not used yet: nothing took its edges)."""
        return self._pending is None and self.excess > 1.0 / PATH_SHARE**2

    def _PM(self, lam):
        l0, l1 = self.loads0, self.loads1
        return l0.P + lam * (l1.P - l0.P), l0.M + lam * (l1.M - l0.M)

    def edges(self, lam: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Left and right contact edges at fractions ``lam`` (any shape) of the step."""
        self._ready()
        lam = np.asarray(lam, dtype=float)
        if self._kind == "symmetric":
            P, _ = self._PM(lam)
            a = self.problem.half_width(np.maximum(P, 0.0))
            return -a, a
        if self._kind == "formation":
            mu = np.sqrt(np.clip((lam - self.lam_lo) / (1.0 - self.lam_lo), 0.0, 1.0))
            left, right = _barycentric(np.ascontiguousarray(mu).reshape(-1), self._mu, self._bary, self._edges)
            return left.reshape(lam.shape), right.reshape(lam.shape)
        if self._kind == "table":
            left, right = _table_edges(np.ascontiguousarray(lam).reshape(-1), self._h0, self._tv, self._td)
            return left.reshape(lam.shape), right.reshape(lam.shape)
        left, right = _hermite_edges(np.ascontiguousarray(lam).reshape(-1), self._h0, self._v0, self._h1, self._v1)
        return left.reshape(lam.shape), right.reshape(lam.shape)

    def _verify(self, start: NormalSolution, end: NormalSolution) -> None:
        """Keep the hermite cubic where it is accurate enough for the arrivals' locks, else a table of cubic
        pieces through an interpolant of normal solves (kind "table"); sets :attr:`error`.

        A growing edge may be off by :func:`allowance` (PATH_SHARE's comment), never less than PATH_ROUNDING of
        the width. The cubic's error, lam^2 (1 - lam)^2 / 24 times the edge's
        fourth derivative for a smooth edge, is largest at mid-step, where one normal solve measures it. Where
        it is too large, the edges are interpolated through normal solves at the Chebyshev-Lobatto points of
        the step, the levels of 5, 9, 17, 33 points each holding the one before: the points a level adds
        measure the error of the one before. A level is kept when that error is within half the allowance (its
        own is smaller still: Chebyshev interpolation of an edge analytic along the step converges
        geometrically) or when its own error, extrapolated geometrically from the two before (their ratio at
        most GEOMETRIC_RATIO: the decay established), is; else at PATH_NODES points, its own error measured by
        normal solves halfway between them (where an interpolant's error peaks), :attr:`excess` above 1. The
        compiled passes then read the edges from m equal cubic Hermite pieces of that interpolant
        (:meth:`_tabulate`): O(1) an edge, as the single cubic; m doubles until the pieces are within the other
        half of the allowance of the interpolant at their midpoints (where a piece's error is largest; within a
        tenth of the interpolant's own error where that is above the allowance), from m^4 = the single cubic's
        error over it."""
        width = end.right - end.left
        travel = np.array([start.left - end.left, end.right - start.right])
        grows = travel > 0.0
        if not grows.any():
            return
        allowed = allowance(travel[grows], width, self.cell)
        problem = self.problem

        def solve(lam):
            self._count(1)
            sol = problem.solve(*self._PM(lam), near=start)
            return sol.left, sol.right

        mid = solve(0.5)
        single = float(np.max(np.abs(np.array(self.edges(np.array([0.5])))[:, 0] - mid)[grows]))
        if single <= allowed:
            self.error, self.excess = single / width, single / allowed
            return
        coef, own = self._interpolate(solve, mid, grows, allowed)
        self._coef, self._rate, self._origin = coef, _lobatto_rate(coef.shape[0]) @ coef, self._h0  # d/dlam
        m = 1 << max(1, math.ceil(0.25 * math.log2(max(2.0 * single / allowed, 1.0))))
        while True:
            self._tabulate(0.0, 1.0, m)
            centres = (np.arange(m) + 0.5) / m
            pieces = np.array(_table_edges(centres, np.zeros(2), self._tv, self._td)).T
            table = float(np.max(np.abs(pieces - _series_at(coef, centres))[:, grows]))
            if table <= max(0.5 * allowed, 0.1 * own) or m >= TABLE_PIECES:
                break
            m *= 2
        self.error = (own + table) / width
        self.excess = (own + table) / allowed

    def _interpolate(self, solve, mid, grows, allowed: float) -> tuple[np.ndarray, float]:
        """The levels of :meth:`_verify` from the normal solution's edges ``mid`` at mid-step (``solve`` gives
        them at any fraction of the step): the Chebyshev series of the offsets from the start edges, (n, 2),
        and its error on the growing edges (``grows``), measured or extrapolated."""
        known = {0.0: (0.0, 0.0), 0.5: tuple(np.array(mid) - self._h0), 1.0: tuple(self._h1 - self._h0)}
        errors = []  # per level from 5 points on, its largest error
        coef = np.zeros((1, 2))  # the series of the level before (none before the first)
        n = 5
        while True:
            mu = _lobatto(n)
            new = [m for m in mu.tolist() if m not in known]
            values = np.array([solve(m) for m in new]) - self._h0  # offsets from the start
            if n > 5:  # the level before, at the points this one adds
                before = _series_at(coef, np.array(new))
                errors.append(float(np.max(np.abs(before - values)[:, grows])))
            known.update(zip(new, map(tuple, values)))
            coef = _lobatto_inverse(n) @ np.array([known[m] for m in mu.tolist()])  # (n, 2)
            if errors:
                own = errors[-1]
                if len(errors) > 1 and errors[-1] <= GEOMETRIC_RATIO * errors[-2]:
                    own = errors[-1] * (errors[-1] / errors[-2]) ** 2  # twice the points: the square of the ratio
                if own <= 0.5 * allowed:
                    return coef, own
                if n >= PATH_NODES:  # not within the allowance: this level's own error, measured between its points
                    between = 0.5 * (mu[1:] + mu[:-1])
                    solved = np.array([solve(m) for m in between.tolist()]) - self._h0
                    return coef, float(np.max(np.abs(_series_at(coef, between) - solved)[:, grows]))
            n = 2 * n - 1

    def _tabulate(self, a: float, b: float, m: int) -> None:
        """This path's table (kind "table"): m equal cubic Hermite pieces of the interpolant ``_coef`` (a
        Chebyshev series in 2 lam - 1 of the offsets from ``_origin``) over [a, b] of its step, which is this
        path's [0, 1]: values and slopes at the knots from the series, at the two ends this path's own edges
        and N3 rates (exact)."""
        tv, td = _series_table(self._coef, self._rate, a, b, m)
        tv += self._origin - self._h0
        tv[0], tv[-1] = 0.0, self._h1 - self._h0
        td[0], td[-1] = self._v0 / m, self._v1 / m
        self._kind = "table"
        self._m = m
        self._tv, self._td = np.ascontiguousarray(tv), np.ascontiguousarray(td)

    def _inherit(self, parent: EdgePath, a: float, b: float) -> None:
        """The part [a, b] of ``parent``'s step, whose path was verified (:meth:`_verify`): a table parent's
        interpolant tabulated over it with pieces no longer than the parent's, a hermite parent's accuracy
        by this path's own cubic (exact at the ends, over a fraction of the step: its error falls with the
        fourth power of that)."""
        self.error, self.excess = parent.error, parent.excess
        if parent._kind == "table":
            self._coef, self._rate, self._origin = parent._coef, parent._rate, parent._origin
            self._tabulate(a, b, max(1, math.ceil(parent._m * (b - a))))

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
        distance from the centre in the step). A table (:func:`_table_arrival`)
        bisects to a quarter of a piece and then takes Newton's steps on the
        piece, in the same offset form.
        """
        self._ready()
        x = np.asarray(x, dtype=float)
        if self._kind == "symmetric":
            P0, P1 = self.loads0.P, self.loads1.P
            Px = self.problem.load(np.abs(x))
            return np.clip((Px - P0) / (P1 - P0), self.lam_lo, 1.0)
        if self._kind == "hermite":
            lam = self._hermite_arrival(x, side)
        elif self._kind == "table":
            col = 0 if side < 0 else 1
            flat = np.ascontiguousarray(x, dtype=float).ravel()
            lam = _table_arrivals(flat, side, col, float(self._h0[col]), self.lam_lo, BISECTION_STEPS, self._tv,
                                  self._td).reshape(x.shape)
        else:
            lo, hi = self._bisect(x, side, np.full(x.shape, self.lam_lo), np.ones(x.shape), BISECTION_STEPS)
            lam = 0.5 * (lo + hi)
        left, right = self.start()
        return np.where((x > left) & (x < right), self.lam_lo, lam)

    @property
    def kind(self) -> str:
        """"symmetric", "formation", "hermite" or "table": how the edges are represented (the class's
        notes)."""
        self._ready()
        return self._kind

    def hermite_arguments(self, side: int) -> tuple:
        """The arguments of :func:`_hermite_strain` (and :func:`hermite_integrals`) from ``lam_lo`` to ``newton``
        for the ``side`` edge of a hermite path."""
        got = self._arguments.get(side)
        if got is None:  # asked by every take of the step and by its arrivals' fit: kept
            self._ready()
            (v0, dh, v1), h0, ext = self._side(side)
            left, right = self.start()
            got = self._arguments[side] = (self.lam_lo, left, right, self._h0, self._v0, self._h1, self._v1, h0, v0,
                                           dh, v1, ext, EXTREMUM_MARGIN, BISECTION_STEPS, NEWTON_STEPS, self._tv,
                                           self._td)
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


_NO_TABLE = np.zeros((0, 2))
_NO_TABLE.flags.writeable = False


def allowance(travel: np.ndarray, width: float, cell: float) -> float:
    """What a step's growing edges (``travel``: each one's motion in the step) may be off by along its path, for
    a lattice of cells ``cell`` of the contact ``width``: the smallest of (PATH_SHARE LATTICE_SHEAR_ERROR
    cell^2)^2 travel, never below PATH_ROUNDING width (the constants' comments)."""
    share = PATH_SHARE * LATTICE_SHEAR_ERROR * cell * cell
    return float(np.min(np.maximum(share * share * np.asarray(travel, dtype=float), PATH_ROUNDING * width)))


@numba.njit(cache=True)
def _series_table(coef, rate, a, b, m):  # pragma: no cover - compiled
    """The two Chebyshev series ``coef`` (n, 2) and ``rate`` (n - 1, 2), in t = 2 lam - 1, at the m + 1 equal
    knots of [a, b] in lam (Clenshaw): the values, and the rates times (b - a) / m (per piece's parameter)."""
    tv = np.empty((m + 1, 2))
    td = np.empty((m + 1, 2))
    scale = (b - a) / m
    for k in range(m + 1):
        t = 2.0 * (a + (b - a) * k / m) - 1.0
        for c in range(2):
            tv[k, c] = _clenshaw(coef[:, c], t)
            td[k, c] = _clenshaw(rate[:, c], t) * scale
    return tv, td


@numba.njit(cache=True)
def _clenshaw(c, t):  # pragma: no cover - compiled
    """sum c_j T_j(t)."""
    b1 = b2 = 0.0
    for j in range(c.size - 1, 0, -1):
        b1, b2 = 2.0 * t * b1 - b2 + c[j], b1
    return t * b1 - b2 + c[0]


@numba.njit(cache=True)
def _series_at(coef, lam):  # pragma: no cover - compiled
    """The two Chebyshev series ``coef`` (n, 2), in t = 2 lam - 1, at each of ``lam`` (flat): shape (size, 2)."""
    out = np.empty((lam.size, 2))
    for k in range(lam.size):
        for c in range(2):
            out[k, c] = _clenshaw(coef[:, c], 2.0 * lam[k] - 1.0)
    return out


@functools.cache
def _lobatto_rate(n: int) -> np.ndarray:
    """The matrix taking a Chebyshev series' n coefficients in t = 2 lam - 1 to its d/dlam's (n - 1)."""
    out = 2.0 * cheb.chebder(np.eye(n))
    out.flags.writeable = False
    return out


@functools.cache
def _lobatto(n: int) -> np.ndarray:
    """The n Chebyshev-Lobatto points of [0, 1], ascending (0, 1/2 and 1 exact; those of n also those of 2n - 1,
    to the bit: k pi / (n - 1) is (2k) pi / (2n - 2) in floating point)."""
    mu = 0.5 * (1.0 - np.cos(np.arange(n) * math.pi / (n - 1)))
    mu[0], mu[(n - 1) // 2], mu[-1] = 0.0, 0.5, 1.0
    mu.flags.writeable = False
    return mu


@functools.cache
def _lobatto_inverse(n: int) -> np.ndarray:
    """The matrix taking values at :func:`_lobatto` (n) to the coefficients of their Chebyshev series in
    2 lam - 1 (the inverse of its Vandermonde matrix there, whose condition number is below 2 for 5 to 33 points)."""
    out = np.linalg.inv(cheb.chebvander(2.0 * _lobatto(n) - 1.0, n - 1))
    out.flags.writeable = False
    return out


@numba.njit(cache=True)
def _piece(lam, m):  # pragma: no cover - compiled
    """The piece of m equal pieces of [0, 1] that holds ``lam`` and ``lam``'s parameter s in it."""
    p = min(max(int(lam * m), 0), m - 1)
    return p, lam * m - p


@numba.njit(cache=True)
def _table_at(lam, tv, td, col):  # pragma: no cover - compiled
    """Column ``col`` (0 left, 1 right) of the table at ``lam``: its cubic Hermite piece there (m equal pieces of
    [0, 1], knot values ``tv`` and slopes ``td`` per piece's parameter), in :func:`_depth`'s offset form."""
    p, s = _piece(lam, tv.shape[0] - 1)
    return _depth_c(td[p, col], tv[p + 1, col] - tv[p, col], td[p + 1, col], tv[p, col], s)


@numba.njit(cache=True)
def _table_edges(lam, h0, tv, td):  # pragma: no cover - compiled
    """Left and right edges at each of ``lam`` (flat) from a table of offsets from the start edges ``h0``."""
    left = np.empty(lam.size)
    right = np.empty(lam.size)
    for i in range(lam.size):
        left[i] = h0[0] + _table_at(lam[i], tv, td, 0)
        right[i] = h0[1] + _table_at(lam[i], tv, td, 1)
    return left, right


@numba.njit(cache=True)
def _table_slope(lam, tv, td, col):  # pragma: no cover - compiled
    """d/dlam of :func:`_table_at`."""
    m = tv.shape[0] - 1
    p, s = _piece(lam, m)
    return m * _slope_c(td[p, col], tv[p + 1, col] - tv[p, col], td[p + 1, col], s)


@numba.njit(cache=True)
def _table_arrival(x, side, col, h0, lam_lo, steps, tv, td):  # pragma: no cover - compiled
    """The limit of ``steps`` bisection steps on "x inside at lam" over [lam_lo, 1] (EdgePath.arrival) on the
    ``side`` edge of a table (column ``col``, start ``h0``), "inside" as g = r + side d(lam) > 0 with r = side
    (h0 - x) and d the table's offset (:func:`_depth`'s form: the rounding relative to the edge's motion).
    Where both ends of the bracket are on their sides of the edge (g <= 0 at lam_lo, > 0 at 1): bisection
    until the bracket is a quarter of a piece, then Newton kept in the bracket (the bisection would close in
    on the same crossing: the table is monotone within a piece unless the edge turns there) to the rounding of
    lam; else the bisection itself."""
    lo, hi = lam_lo, 1.0
    m = tv.shape[0] - 1
    r = side * (h0 - x)
    bracket = r + side * _table_at(lo, tv, td, col) <= 0.0 < r + side * _table_at(hi, tv, td, col)
    k = 0
    while k < steps and (not bracket or hi - lo > 0.25 / m):
        mid = 0.5 * (lo + hi)
        if r + side * _table_at(mid, tv, td, col) > 0.0:
            hi = mid
        else:
            lo = mid
        k += 1
    if k == steps:
        return 0.5 * (lo + hi)
    lam = 0.5 * (lo + hi)
    for _ in range(steps - k):
        g = r + side * _table_at(lam, tv, td, col)
        if g == 0.0:
            break
        lam, lo, hi, done = _newton_step(lam, g, side * _table_slope(lam, tv, td, col), lo, hi)
        if done:
            break
    return lam


@numba.njit(cache=True)
def _table_arrivals(x, side, col, h0, lam_lo, steps, tv, td):  # pragma: no cover - compiled
    """:func:`_table_arrival` at each of ``x`` (flat)."""
    out = np.empty(x.size)
    for i in range(x.size):
        out[i] = _table_arrival(x[i], side, col, h0, lam_lo, steps, tv, td)
    return out


@numba.njit(cache=True)
def _table_strain(x, side, A, lam_lo, start_left, start_right, h0, side_h0, steps, tv, td):  # pragma: no cover
    """:func:`_hermite_strain` on a table (see there)."""
    col = 0 if side < 0 else 1
    u = _U
    n, k = x.size, u.size
    span = np.empty(n)
    left = np.empty((n, k))
    right = np.empty((n, k))
    gl = np.empty((n, k))
    gr = np.empty((n, k))
    for i in range(n):
        xi = x[i]
        lam_x = lam_lo if start_left < xi < start_right else _table_arrival(xi, side, col, h0[col], lam_lo, steps,
                                                                             tv, td)
        span[i] = lam_x - lam_lo
        own = xi - side_h0
        for j in range(k):
            lam = lam_x - span[i] * u[j] ** 2
            dl = _table_at(lam, tv, td, 0)
            dr = _table_at(lam, tv, td, 1)
            left[i, j] = h0[0] + dl
            right[i, j] = h0[1] + dr
            gl[i, j] = own - dl if side < 0 else xi - left[i, j]
            gr[i, j] = own - dr if side > 0 else xi - right[i, j]
    return _strain_sum(x, left, right, gl, gr, span, u, _W, A * side)


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
            lam, lo, hi, done = _newton_step(lam, g, _slope_c(v0, dh, v1, lam), lo, hi)
            if done:
                break
        out[i] = lam
    return out


@numba.njit(cache=True)
def _newton_step(lam, g, slope, lo, hi):  # pragma: no cover - compiled
    """One Newton step on an edge crossing kept in its bracket [lo, hi] (narrowed by the sign of g at lam: g > 0
    inside, at and above the crossing): the new lam (the bracket's midpoint where the step leaves it or the slope
    is 0), the new bracket, and whether the step or the bracket is at the rounding of lam."""
    if g > 0.0:
        hi = lam
    else:
        lo = lam
    new = lam - g / slope if slope != 0.0 else 0.5 * (lo + hi)
    if not (lo < new < hi):
        new = 0.5 * (lo + hi)
    return new, lo, hi, abs(new - lam) <= 2e-16 or hi - lo <= 4e-16


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
    if path._kind in ("hermite", "table"):
        return _hermite_strain(np.ascontiguousarray(x), side, compliance, *path.hermite_arguments(side))
    lam_x = path.arrival(x, side)
    span = lam_x - path.lam_lo
    back = span[:, None] * _U**2
    lam = lam_x[:, None] - back  # (n, k)
    left, right = path.edges(lam)
    return _strain_sum(x, left, right, x[:, None] - left, x[:, None] - right, span, _U, _W, compliance * side)


@numba.njit(cache=True)
def _hermite_strain(x, side, A, lam_lo, start_left, start_right, h0, v0, h1, v1, side_h0, side_v0, side_dh,
                    side_v1, ext, margin, steps, newton, tv, td):  # pragma: no cover - compiled
    """:func:`arrival_strain_parts` on a hermite path in one pass: each point's arrival (the bisection's limit,
    :func:`_hermite_arrivals`; lam_lo inside the contact at the start, (start_left, start_right)), the edges at
    the nodes lam_x - span u^2, the gap to the arriving edge from its divided difference
    (:func:`_hermite_gap`) and the strain sums (:func:`_strain_sum`). ``h0`` .. ``v1`` the edges' ends and
    rates (left, right), ``side_h0`` .. ``side_v1`` the ``side`` edge's start, rate, motion and end rate, ``ext``
    its extrema (EdgePath.hermite_arguments). With a table (``tv`` of more than one row: kind "table") the edges
    are its pieces', each arrival the limit of ``steps`` bisection steps (EdgePath.arrival's reference) and the
    gap to the arriving edge its offset from the start less the table's."""
    if tv.shape[0] > 1:
        return _table_strain(x, side, A, lam_lo, start_left, start_right, h0, side_h0, steps, tv, td)
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
                      side_dh, side_v1, ext, margin, steps, newton, tv, td, gauss_t, gauss_w):  # pragma: no cover
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
                          side_v1, ext, margin, steps, newton, tv, td)
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
