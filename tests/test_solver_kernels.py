"""Kernels of the general solver: arrival fractions on the edge path, and the Toeplitz lattice algebra.

EdgePath.arrival against the bisection it replaces, run here in exact
(rational) arithmetic on the same cubic, and in floating point on
``EdgePath.edges`` (the old algorithm, whose own rounding band
eps |edge| / |d edge / d lam| bounds the difference); arrival_strains against
its quadrature rule evaluated in 40 digits. ToeplitzLattice products and
solves against dense matrices.
"""
from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest

from halfslip.geometry import NormalProblem
from halfslip.solvers import _general_path as gp
from halfslip.solvers._general_path import EdgePath, arrival_strains
from halfslip.state import Loads

from helpers import A, P0, PROFILES

EPS = np.finfo(float).eps
#: (kind, short) of the random steps that give tables: Hertz's short steps keep their single cubic (within the
#: allowance: the first check of EdgePath._verify), the punch's need tables on short steps too.
TABLE_STEPS = [("hertz", False), ("punch", False), ("punch", True)]


# -- arrival fractions --------------------------------------------------------------------------------


def _hermite_paths(kind: str, count: int, seed: int, short: bool = False, table: bool = False) -> list[EdgePath]:
    """Hermite edge paths between real normal solutions: P and M changed at random (``short``: by ~1e-3),
    with Q and sigma changed too (they move no edge; the arrival strains are driven by them): dQ up to
    0.3 f P0, dsigma so that (pi/4) a dsigma <= 0.3 dQ (the two terms of the strain never cancel much).
    The single cubic is kept whatever its error (PATH_SHARE raised while they are made); with ``table``
    the paths as the solver makes them, each checked to be a table (EdgePath._verify)."""
    with pytest.MonkeyPatch.context() as mp:
        if not table:
            mp.setattr(gp, "PATH_SHARE", 1e9)
        return _random_paths(kind, count, seed, short, "table" if table else "hermite")


def _random_paths(kind, count, seed, short, want):
    problem = NormalProblem(PROFILES[kind], A)
    a = problem.solve(P0, 0.0).half_width
    rng = np.random.default_rng(seed)
    paths = []
    for _ in range(50 * count):
        if len(paths) == count:
            break
        P0_, M0 = P0 * rng.uniform(0.5, 1.5), rng.uniform(-0.2, 0.2) * P0 * a
        if short:
            P1, M1 = P0_ * (1.0 + rng.uniform(-2e-3, 2e-3)), M0 + rng.uniform(-2e-3, 2e-3) * P0 * a
        else:
            P1, M1 = P0 * rng.uniform(0.5, 1.5), rng.uniform(-0.2, 0.2) * P0 * a
        dQ = rng.uniform(0.1, 0.3) * 0.6 * P0
        dS = rng.uniform(-0.3, 0.3) * dQ * 4.0 / (math.pi * a)
        loads0, loads1 = Loads(P0_, 0.0, M0, 0.0), Loads(P1, dQ, M1, dS)
        path = EdgePath(problem, problem.solve(P0_, M0), problem.solve(P1, M1), loads0, loads1)
        if want == "table" and path._kind == "hermite":
            continue  # no edge grows, or the single cubic is within the allowance (short steps): no table
        assert path._kind == want, (path._kind, path.error)
        paths.append(path)
    assert len(paths) == count, f"{len(paths)} of {count} {want} paths"
    return paths


def _overshooting(path: EdgePath, factor: float) -> EdgePath:
    """The same path with end rates ``factor`` x the chord: each edge turns inside the step."""
    chord = path._h1 - path._h0
    path._v0 = factor * chord
    path._v1 = factor * chord
    path._sides.clear()
    return path


def _exact_edge(path: EdgePath, side: int):
    i = 0 if side < 0 else 1
    h0, v0, h1, v1 = (Fraction(float(c[i])) for c in (path._h0, path._v0, path._h1, path._v1))

    def edge(s: Fraction) -> Fraction:
        return (1 + 2 * s) * (1 - s) ** 2 * h0 + s * (1 - s) ** 2 * v0 + s * s * (3 - 2 * s) * h1 + s * s * (s - 1) * v1

    return edge


def _exact_bisection(path: EdgePath, x: np.ndarray, side: int) -> np.ndarray:
    """The reference: 60 bisection steps on "x inside at lam" in exact arithmetic on the hermite cubic."""
    edge, other = _exact_edge(path, side), _exact_edge(path, -side)
    lam_lo = Fraction(path.lam_lo)
    out = []
    for xf in x:
        xq = Fraction(float(xf))
        lo, hi = lam_lo, Fraction(1)
        for _ in range(60):
            mid = (lo + hi) / 2
            inside = xq > edge(mid) if side < 0 else xq < edge(mid)
            lo, hi = (lo, mid) if inside else (mid, hi)
        lam = (lo + hi) / 2
        left, right = (edge(lam_lo), other(lam_lo)) if side < 0 else (other(lam_lo), edge(lam_lo))
        out.append(float(lam_lo if left < xq < right else lam))
    return np.array(out)


def _float_bisection(path: EdgePath, x: np.ndarray, side: int) -> np.ndarray:
    """The old algorithm: the same bisection on ``path.edges`` in floating point."""
    lo, hi = np.full(x.shape, path.lam_lo), np.ones(x.shape)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        left, right = path.edges(mid)
        inside = (x > left) if side < 0 else (x < right)
        lo, hi = np.where(inside, lo, mid), np.where(inside, mid, hi)
    left, right = path.edges(np.full(x.shape, path.lam_lo))
    return np.where((x > left) & (x < right), path.lam_lo, 0.5 * (lo + hi))


def _test_points(path: EdgePath, side: int, rng) -> np.ndarray:
    """Points the ``side`` edge sweeps, points inside at the start, exactly on the end edge and beyond it."""
    i = 0 if side < 0 else 1
    lam = np.linspace(0.0, 1.0, 2001)
    left, right = path.edges(lam)
    edge = left if side < 0 else right
    outer = edge.min() if side < 0 else edge.max()  # outermost reach of the edge in the step
    start, end = float(path._h0[i]), float(path._h1[i])
    centre = 0.5 * (path._h0[0] + path._h0[1])
    swept = rng.uniform(min(start, outer), max(start, outer), 24)
    return np.concatenate((swept, [end, start, 0.5 * (start + centre), centre, outer + side * 1e-6 * abs(outer)]))


@pytest.mark.parametrize("kind", ["hertz", "punch"])
@pytest.mark.parametrize("short", [False, True])
def test_arrival_matches_the_exact_bisection_on_real_hermite_paths(kind, short):
    rng = np.random.default_rng(7)
    for path in _hermite_paths(kind, 6, seed=11 if short else 3, short=short):
        for side in (-1, 1):
            x = _test_points(path, side, rng)
            got = path.arrival(x, side)
            ref = _exact_bisection(path, x, side)
            assert np.max(np.abs(got - ref)) <= 1e-14, (kind, side, x[np.argmax(np.abs(got - ref))])
            i = 0 if side < 0 else 1
            assert got[-5] == pytest.approx(1.0, abs=1e-15) or path._h1[i] * side < path._h0[i] * side
            assert got[-1] == pytest.approx(1.0, abs=1e-15)  # beyond the reach of the edge: never arrives
            assert got[-3] == path.lam_lo and got[-2] == path.lam_lo  # inside at the start


@pytest.mark.parametrize("factor", [-3.0, 6.0])
def test_arrival_matches_the_exact_bisection_where_the_edge_turns(factor):
    """End rates against (-3) or far beyond (6) the chord: every edge has extrema inside the step, and
    points swept twice arrive where the bisection puts them."""
    rng = np.random.default_rng(5)
    for path in _hermite_paths("hertz", 3, seed=21):
        path = _overshooting(path, factor)
        for side in (-1, 1):
            assert path._side(side)[2].size > 0
            x = _test_points(path, side, rng)
            got = path.arrival(x, side)
            ref = _exact_bisection(path, x, side)
            assert np.max(np.abs(got - ref)) <= 1e-14, (factor, side, x[np.argmax(np.abs(got - ref))])


@pytest.mark.parametrize("short", [False, True])
def test_arrival_agrees_with_the_floating_point_bisection_within_its_rounding_band(short):
    """The old bisection on ``edges`` is right to eps |edge| / |edge'| only (1e-12 on a short step)."""
    rng = np.random.default_rng(9)
    for path in _hermite_paths("hertz", 6, seed=5, short=short):
        for side in (-1, 1):
            x = _test_points(path, side, rng)
            got = path.arrival(x, side)
            old = _float_bisection(path, x, side)
            (v0, dh, v1), h0, _ = path._side(side)
            rate = np.abs(gp._slope(v0, dh, v1, got))
            scale = np.maximum(np.abs(path._h0).max(), np.abs(path._h1).max())
            with np.errstate(divide="ignore"):
                band = 1e-14 + 16.0 * EPS * scale / rate
            assert np.all(np.abs(got - old) <= band)


@pytest.mark.parametrize("short", [False, True])
def test_arrival_strains_is_its_quadrature_rule_to_rounding(short):
    """The strain int_lam_lo^lam_x A sgn(s) (Q'/pi + sigma' s/4) / sqrt|(x - L)(x - R)| dlam through the same
    49-point rule, in 40 digits on the exact cubic: the inverse square root at lam_x makes the integral
    sensitive to x - L there, which ``edges`` carries with an error of eps |L| (1e-6 of the strain on a
    short step)."""
    import mpmath as mp  # a test dependency (pyproject: test extra)
    mp.mp.dps = 40
    rng = np.random.default_rng(4)
    for path in _hermite_paths("hertz", 2, seed=13, short=short):
        for side in (-1, 1):
            i = 0 if side < 0 else 1
            if side * (path._h1[i] - path._h0[i]) <= 0.0:
                continue  # this edge recedes: nothing arrives
            x = path._h0[i] + (path._h1[i] - path._h0[i]) * rng.uniform(0.05, 0.95, 3)
            strain, lam_x = arrival_strains(path, x, side, A), path.arrival(x, side)
            dQ, dS = path.loads1.Q - path.loads0.Q, path.loads1.sigma - path.loads0.sigma
            coef = [[mp.mpf(float(c[j])) for c in (path._h0, path._v0, path._h1, path._v1)] for j in (0, 1)]

            def edge(j, s):
                h0, v0, h1, v1 = coef[j]
                return (1 + 2 * s) * (1 - s) ** 2 * h0 + s * (1 - s) ** 2 * v0 + s * s * (3 - 2 * s) * h1 \
                    + s * s * (s - 1) * v1

            for xk, lk, gk in zip(x, lam_x, strain):
                X = mp.mpf(float(xk))
                lx = mp.findroot(lambda s: edge(i, s) - X, mp.mpf(float(lk)))
                assert abs(float(lx) - lk) <= 1e-15
                ref = 0
                for u, w in zip(gp._U, gp._W):
                    u, w = mp.mpf(float(u)), mp.mpf(float(w))
                    s = lx - lx * u * u
                    # x - e_i(s) from the exact difference e_i(lx) - e_i(s) (lx - s = lx u^2 exactly)
                    near = (edge(i, lx) - edge(i, s)) if u > 0 else 0
                    root = mp.sqrt(abs(near * (X - edge(1 - i, s))))
                    offset = X - (edge(0, s) + edge(1, s)) / 2  # s of the module: x - contact centre
                    if root > 0:
                        ref += 2 * lx * u * w / root * (mp.mpf(dQ) / mp.pi + mp.mpf(dS) * offset / 4)
                ref = float(ref * A * side)
                assert gk == pytest.approx(ref, rel=1e-12, abs=0.0)


@pytest.mark.parametrize(("kind", "short", "table"), [(k, s, False) for k in ("hertz", "punch") for s in (False, True)]
                         + [(k, s, True) for k, s in TABLE_STEPS])
def test_the_compiled_arrival_integrals_are_the_array_route(kind, short, table):
    """GeneralSolver's _integrate on a hermite path (the integrals from an edge out to arriving points, per unit
    Q' and sigma', and the distance) in one compiled pass (_general_path.hermite_integrals, since 0.4.3) against
    the array route it replaced (arrival_strain_parts at the Gauss points of each segment, summed outward by
    numpy): the same quadrature in another order of summation, so equal to rounding (1e-13 of the largest
    integral; measured 0); points inside at the start, on the end edge and beyond the edge's reach included.
    (The strain itself, one compiled function for both since 0.4.3, is checked against 40 digits above.)
    With ``table``: the same on the paths' tables (since 0.4.13)."""
    from halfslip.solvers import general as gm

    rng = np.random.default_rng(17)
    for path in _hermite_paths(kind, 4, seed=31 if short else 8, short=short, table=table):
        for side in (-1, 1):
            i = 0 if side < 0 else 1
            x = np.sort(_test_points(path, side, rng))[::side]
            edge = float(path._h0[i])
            got = gm._integrate(path, x, edge, side, A, None, (1.0, 0.0)), gm._integrate(path, x, edge, side, A,
                                                                                        None, (0.0, 1.0))
            order = np.argsort(side * x)
            ends = np.concatenate(([edge], x[order]))
            a, b = ends[:-1], ends[1:]
            pts = a[:, None] + (b - a)[:, None] * gm._GL_T[None, :]
            inc = gp.arrival_strain_parts(path, pts.ravel(), side, A).reshape(pts.shape + (2,))
            seg = np.einsum("ijc,j->ic", inc, gm._GL_W) * np.abs(b - a)[:, None]
            ref = np.empty((x.size, 2))
            ref[order] = np.cumsum(seg, axis=0)
            for c in (0, 1):
                scale = float(np.max(np.abs(ref[:, c])))
                assert np.max(np.abs(got[c] - ref[:, c])) <= 1e-13 * scale, (kind, short, side, c)


# -- edge tables (EdgePath._verify, since 0.4.13) ------------------------------------------------------------


def _growing(path: EdgePath) -> np.ndarray:
    return np.array([path._h0[0] - path._h1[0], path._h1[1] - path._h0[1]]) > 0.0


def _allowance(path: EdgePath) -> float:
    """What EdgePath._verify lets a growing edge be off by (its rule, restated)."""
    width = path._h1[1] - path._h1[0]
    travel = np.abs(path._h1 - path._h0)[_growing(path)]
    return gp.allowance(travel, width, path.cell)


def _solved_edges(path: EdgePath, lam: np.ndarray) -> np.ndarray:
    start = path.problem.solve(path.loads0.P, path.loads0.M)
    return np.array([[s.left, s.right] for s in (path.problem.solve(*path._PM(v), near=start) for v in lam)])


@pytest.mark.parametrize(("kind", "short"), TABLE_STEPS)
def test_a_table_path_is_the_normal_problem_to_its_allowance(kind, short):
    """Random steps (P, M changed, some edge growing) as the solver makes their paths: the table's edges at
    201 points of the step against the normal problem's own there. The growing edges within the allowance
    (gp.allowance: for the default cell, 1/2048 of the width, 9e-13 of their travel, at least PATH_ROUNDING of
    the width), and within the path's own error estimate (``error``) and the normal solver's rounding (the
    allowance's floor): both the rule and
    the estimate can fail, a path off by its cubic's error (1e-6 to 1e-4 of the width on the long steps)
    fails both. (The random moments stay below 0.2 a P0: no edge crosses the punch's flat end, where the path
    has a kink; docs/general_solver.md, Limits.)"""
    lam = np.linspace(0.0, 1.0, 201)
    for path in _hermite_paths(kind, 4, seed=41 if short else 43, short=short, table=True):
        grow = _growing(path)
        width = path._h1[1] - path._h1[0]
        solved = _solved_edges(path, lam)
        off = np.abs(np.array(path.edges(lam)).T - solved)[:, grow].max()
        assert off <= _allowance(path), (off / width, path.solves, path.error)
        assert off <= path.error * width + gp.PATH_ROUNDING * width, (off / width, path.error)
        with pytest.MonkeyPatch.context() as mp:  # the same step's single cubic: off by far more
            mp.setattr(gp, "PATH_SHARE", 1e9)
            cubic = EdgePath(path.problem, path.problem.solve(path.loads0.P, path.loads0.M),
                             path.problem.solve(path.loads1.P, path.loads1.M), path.loads0, path.loads1)
        assert np.abs(np.array(cubic.edges(lam)).T - solved)[:, grow].max() > 10.0 * off


def _table_bisection(path: EdgePath, x: np.ndarray, side: int) -> np.ndarray:
    """The reference: 60 bisection steps on "x inside at lam" on the table's own edges, in the offset form
    (side (h0 - x) + side d(lam) > 0, d the table's offset from the start h0)."""
    col = 0 if side < 0 else 1
    out = []
    for xk in x:
        lo, hi = path.lam_lo, 1.0
        r = side * (path._h0[col] - xk)
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            inside = r + side * gp._table_at(mid, path._tv, path._td, col) > 0.0
            lo, hi = (lo, mid) if inside else (mid, hi)
        out.append(0.5 * (lo + hi))
    left, right = path.start()
    return np.where((x > left) & (x < right), path.lam_lo, np.array(out))


@pytest.mark.parametrize(("kind", "short"), TABLE_STEPS)
def test_a_table_arrival_is_the_bisection_on_the_table(kind, short):
    """EdgePath.arrival on a table (bisection to a quarter of a piece, then Newton on the piece) against the
    bisection itself on the same table: equal to the rounding of the offset form, 16 eps of the edge's travel
    over its rate (and 1e-15 in lam); points inside at the start and beyond the edge's reach included."""
    rng = np.random.default_rng(19)
    for path in _hermite_paths(kind, 4, seed=45, short=short, table=True):
        for side in (-1, 1):
            x = _test_points(path, side, rng)
            got = path.arrival(x, side)
            ref = _table_bisection(path, x, side)
            col = 0 if side < 0 else 1
            rate = np.abs([gp._table_slope(v, path._tv, path._td, col) for v in got])
            travel = abs(path._h1[col] - path._h0[col])
            with np.errstate(divide="ignore"):
                band = 1e-15 + 16.0 * EPS * travel / rate
            assert np.all(np.abs(got - ref) <= band), np.max(np.abs(got - ref) - band)


def test_a_sub_step_path_is_its_part_of_the_step_path():
    """A sub-step's path made from its step's (GeneralSolver's sub-steps; ``parent``): no normal solve, its
    edges at lam' those of the step's at a + (b - a) lam' to the step's allowance, its own ends exact."""
    lam = np.linspace(0.0, 1.0, 101)
    for path in _hermite_paths("hertz", 3, seed=47, table=True):
        problem = path.problem
        for a, b in ((0.0, 0.25), (0.25, 0.5), (0.6, 1.0)):
            loads = [Loads(*(u + t * (v - u) for u, v in zip(path.loads0, path.loads1))) for t in (a, b)]
            ends = [problem.solve(v.P, v.M) for v in loads]
            part = EdgePath(problem, *ends, *loads, parent=(path, a, b))
            assert part.solves == 0 and part.kind == "table" and part.error == path.error
            whole = np.array(path.edges(a + (b - a) * lam)).T
            mine = np.array(part.edges(lam)).T
            assert np.abs(mine - whole)[:, _growing(path)].max() <= 2.0 * _allowance(path)
            assert tuple(mine[0]) == (ends[0].left, ends[0].right)
            assert tuple(mine[-1]) == (ends[1].left, ends[1].right)


#: A step of the random punch history (benchmarks/random_histories.py, seed 1, step 41: its compliance and
#: friction) whose left contact edge crosses the punch's flat end (-2e-3 m) at lam = 0.526: the path has a kink
#: there (the pressure's x ln x at the flat's end), which no interpolant on the whole step resolves.
KINKED_STEP = ((260087.52143121266, -54828.42418887594, 312.5843668902145, 52482879.35449438),
               (259320.2794755171, -46718.52601852457, 246.58092046370382, 52447511.70188236))
KINKED_COMPLIANCE = 3.165217391304348e-11


def test_a_path_through_a_kink_says_it_is_not_within_its_allowance():
    """KINKED_STEP: the path is a table, not within the allowance (``excess`` above 1 and ``dominant``: its
    part of the arrivals' shear error may outweigh the lattice's), its error estimate (the last interpolant's,
    measured by normal solves halfway between its points) 1.38e-3 of the width against 1.53e-3 measured at
    2001 points (asserted: within a factor 2 of that, and far above the allowance); the single cubic is off by
    2.7e-2. A general solver's step along it says so in its message, which the result files as kind
    ``edge_path`` with the estimate as its value (halfslip.messages)."""
    import helpers

    from halfslip.geometry import RoundedPunch
    from halfslip.messages import classify
    from halfslip.solvers.general import GeneralSolver

    problem = NormalProblem(RoundedPunch(2e-3, 10e-3), KINKED_COMPLIANCE)
    loads0, loads1 = (Loads(*v) for v in KINKED_STEP)
    path = EdgePath(problem, problem.solve(loads0.P, loads0.M), problem.solve(loads1.P, loads1.M), loads0, loads1)
    assert path.kind == "table" and path.excess > 1.0 and path.dominant
    lam = np.linspace(0.0, 1.0, 2001)
    width = path._h1[1] - path._h1[0]
    off = np.abs(np.array(path.edges(lam)).T - _solved_edges(path, lam))[:, 0].max() / width
    assert 0.5 * off <= path.error <= 2.0 * off
    assert path.error * width > 1e6 * _allowance(path)
    out = helpers.march(GeneralSolver(problem, 0.6, 512), list(KINKED_STEP))
    entries = classify(out[-1][1].message)
    assert [kind for kind, _, _ in entries] == ["edge_path"] and entries[0][1] == pytest.approx(path.error, rel=1e-2)
    assert out[0][1].message == ""


# -- the Toeplitz lattice -------------------------------------------------------------------------------

from scipy.linalg import toeplitz  # noqa: E402

from halfslip.solvers import _toeplitz as tz  # noqa: E402
from halfslip.solvers._toeplitz import ToeplitzLattice  # noqa: E402

SIZE = 500
H = 1e-6


@pytest.fixture(scope="module")
def lattice():
    return ToeplitzLattice(H, SIZE, A)


def _dense(lat: ToeplitzLattice, n: int) -> np.ndarray:
    return toeplitz(lat.t[:n])


def _rel(a, b) -> float:
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


# n sharing one transform length (140, 150), n = size (the circulant needs the kernel beyond the lattice),
# the smallest
MATVEC_N = [1, 2, 7, 140, 150, 257, SIZE - 1, SIZE]


@pytest.mark.parametrize("n", MATVEC_N)
def test_matvec_is_the_dense_toeplitz_product(lattice, n):
    rng = np.random.default_rng(n)
    T = _dense(lattice, n)
    for v in (rng.standard_normal(n), rng.standard_normal((n, 3))):
        got = lattice.matvec(v)
        assert got.shape == v.shape
        assert _rel(got, T @ v) <= 1e-14


def test_matvec_after_other_sizes_share_a_spectrum(lattice):
    """The spectra are cached per transform length: a product of one size after another of the same
    length is still right."""
    rng = np.random.default_rng(1)
    fresh = ToeplitzLattice(H, SIZE, A)
    for n in (150, 140, 149, 141, 150):
        v = rng.standard_normal(n)
        assert _rel(fresh.matvec(v), _dense(fresh, n) @ v) <= 1e-14


SOLVE_N = [1, 2, 5, tz.DENSE_CELLS, tz.DENSE_CELLS + 1, 200, SIZE]


@pytest.mark.parametrize("n", SOLVE_N)
def test_solve_is_the_dense_solve(lattice, n):
    rng = np.random.default_rng(100 + n)
    T = _dense(lattice, n)
    for w in (rng.standard_normal(n), rng.standard_normal((n, 3))):
        got = lattice.solve(n, w)
        assert got.shape == w.shape
        assert _rel(got, np.linalg.solve(T, w)) <= 1e-12


def _stick_solve(lat: ToeplitzLattice, runs, n: int, rhs: np.ndarray) -> np.ndarray:
    S = np.concatenate([np.arange(a, b) for a, b in runs])
    T = _dense(lat, n)
    return np.linalg.solve(T[np.ix_(S, S)], rhs)


RUNS = {
    "one": [(10, 90)],
    "gaps": [(0, 40), (50, 120), (130, 131), (140, 200)],            # gaps of 28 cells: Schur complement
    "gaps-dense": [(0, 20), (30, 60), (70, 100)],                     # span within DENSE_CELLS: its inverse
    "gaps-wide": [(0, 30), (100, 229), (260, 290)],                   # gaps of 101, 60 other cells: two solves
    "gaps-long": [(0, 140), (200, 300)],                              # one gap of 60 between long runs: two
    "islands": [(0, 5), (100, 229), (290, 291)],                      # 6 cells beside the longest run: Schur
    "island-gap": [(0, 20), (110, 400)],                              # 20 island cells, 90 gap cells: the gaps'
    "cg": [(0, 30), (200, 229), (400, 430)],                          # gaps of 341 > GAP_CELLS: CG, runs dense
    "cg-long": [(0, 140), (400, 490)],                                # CG with FFT solves on both runs
    "gaps-cubic": [(0, 140), (310, 480)],                             # 170 gap cells, 170^3 <= GAP_CUBE x 480
}


def test_the_inverse_columns_are_the_dense_inverse(lattice):
    """The columns of T_m^-1 at the gaps (a solve for each gap's first, the Gohberg-Semencul recursion for
    the rest) against the dense inverse, for gaps deep inside a span beyond DENSE_CELLS."""
    m = 500
    cells = np.r_[100:260, 300:420]
    got = tz._inverse_columns(lattice.tables, m, np.array([100, 300]), np.array([160, 120]))
    ref = np.linalg.inv(_dense(lattice, m))[:, cells]
    assert got.shape == ref.shape
    assert _rel(got, ref) <= 1e-11
    # a span within DENSE_CELLS: from the dense inverse
    got = tz._inverse_columns(lattice.tables, 100, np.array([10, 60]), np.array([5, 1]))
    assert _rel(got, np.linalg.inv(_dense(lattice, 100))[:, np.r_[10:15, 60]]) <= 1e-11


def test_the_gap_block_is_the_dense_inverse_there(lattice):
    """T_m^-1 on the gap cells only (rows and columns, from each gap's first column and the generators:
    _toeplitz._gap_block, the gaps' route from GAP_TWO_SOLVES gap cells on) against the dense inverse, for
    gaps deep inside a span beyond DENSE_CELLS and a gap near its start (the recursion's rows reach row 0,
    where B(0, j) = x_j); the same numbers as the columns over the whole span (_inverse_columns) there."""
    m = 500
    starts, lengths = np.array([10, 150, 300]), np.array([60, 1, 120])
    gaps = np.concatenate([np.arange(a, a + n) for a, n in zip(starts, lengths)])
    first = np.linalg.inv(_dense(lattice, m))[:, starts]
    x, u = tz._xu(lattice.tables[1], lattice.tables[2], m)
    got = tz._gap_block(x, u, np.ascontiguousarray(first), starts, lengths)
    assert _rel(got, np.linalg.inv(_dense(lattice, m))[np.ix_(gaps, gaps)]) <= 1e-11
    columns = tz._inverse_columns(lattice.tables, m, starts, lengths)
    exact = tz._gap_block(x, u, np.ascontiguousarray(columns[:, np.r_[0, 60, 61]]), starts, lengths)
    assert np.array_equal(exact, columns[gaps])
    assert tz.GAP_TWO_SOLVES <= 60 + 31  # RUNS["gaps-wide"] takes it, RUNS["gaps"] (28 gap cells) does not


@pytest.mark.parametrize("case", sorted(RUNS))
def test_solve_runs_is_the_dense_solve_on_the_stick_set(lattice, case):
    runs = RUNS[case]
    cells = sum(b - a for a, b in runs)
    rng = np.random.default_rng(len(case))
    rhs = rng.standard_normal((cells, 3))
    rhs[:, 2] = 0.0  # a zero column stays zero
    got, iterations = lattice.solve_runs(runs, SIZE, rhs)
    ref = _stick_solve(lattice, runs, SIZE, rhs)
    assert got.shape == rhs.shape
    assert np.all(got[:, 2] == 0.0)
    assert _rel(got[:, :2], ref[:, :2]) <= 1e-11
    assert (iterations > 0) == case.startswith("cg")
    # with a column of ones first (the rigid shift's), which one run and the gaps' route take from the cached
    # T_n^-1 1: the same as solving it
    got, _ = lattice.solve_runs(runs, SIZE, rhs[:, :2], ones=True)
    ref = _stick_solve(lattice, runs, SIZE, np.column_stack((np.ones(cells), rhs[:, :2])))
    assert got.shape == (cells, 3)
    assert _rel(got, ref) <= 1e-11


def test_one_run_solves_the_ones_column_with_the_rest_then_keeps_it():
    """On one run, T_n^-1 1 not yet cached is solved as one more column of the same solve and kept: the
    first solve (not cached) and the second (cached) both give the dense answer, and the kept column is
    T_n^-1 1 (a fresh lattice: nothing cached before)."""
    fresh = ToeplitzLattice(H, SIZE, A)
    runs, n = [(10, 290)], 280
    assert tz._unit_slot(fresh.tables, n) == -1
    rhs = np.random.default_rng(5).standard_normal((n, 2))
    ref = _stick_solve(fresh, runs, SIZE, np.column_stack((np.ones(n), rhs)))
    first, _ = fresh.solve_runs(runs, SIZE, rhs, ones=True)
    slot = tz._unit_slot(fresh.tables, n)
    assert slot >= 0
    assert _rel(fresh.tables[5][slot, :n], np.linalg.solve(_dense(fresh, n), np.ones(n))) <= 1e-11
    second, _ = fresh.solve_runs(runs, SIZE, rhs, ones=True)
    assert _rel(first, ref) <= 1e-11 and _rel(second, ref) <= 1e-11
    assert np.array_equal(first[:, 0], second[:, 0])


@pytest.mark.parametrize("runs,way", [
    ([(0, 5), (100, 229), (290, 291)], tz.ISLANDS),   # 6 island cells, 156 gap cells: 5 x 6 <= 156
    ([(0, 17), (110, 400)], tz.ISLANDS),               # 17 island cells, 93 gap cells: 5 x 17 <= 93
    ([(0, 20), (110, 400)], tz.GAPS),                  # 20 island cells, 90 gap cells: 5 x 20 > 90
    ([(0, 4), (200, 460)], tz.ISLANDS),                # gaps beyond GAP_CELLS: the islands' whatever
    ([(0, 40), (50, 120), (130, 131), (140, 200)], tz.GAPS),  # more island cells than gap cells
    ([(0, 30), (200, 229), (400, 430)], tz.CG),        # 341 gap cells, 59 island cells
    ([(0, 140), (310, 480)], tz.GAPS),                 # 170 gap cells > GAP_CELLS, but 170^3 <= GAP_CUBE x 480
    ([(0, 140), (400, 490)], tz.CG),                   # 260^3 > GAP_CUBE x 490
    ([(3, 90)], tz.ONE_RUN),
])
def test_solve_runs_takes_the_cheaper_schur_complement(lattice, runs, way):
    """The islands' complement costs a column of a solve on the longest run per island cell, the gaps' a
    solve per gap and O(span) per gap cell (benchmarks/bench_solve_routes.py: equal at about ISLAND_COST = 5
    gap cells per island cell): the route is the one so chosen, and both Schur complements give the dense
    solve's answer on any runs."""
    array = tz._run_array(runs)
    assert tz.route(array)[0] == way
    cells = sum(b - a for a, b in runs)
    rhs = np.random.default_rng(3).standard_normal((cells, 2))
    got, _ = lattice.solve_runs(runs, SIZE, rhs)
    assert _rel(got, _stick_solve(lattice, runs, SIZE, rhs)) <= 1e-11
    if len(runs) > 1:
        ref = _stick_solve(lattice, runs, SIZE, np.column_stack((np.ones(cells), rhs)))
        ones = np.column_stack((np.ones(cells), rhs))
        assert _rel(tz._island_solve(lattice.tables, array, tz.route(array)[1], ones), ref) <= 1e-11
        assert _rel(tz._gap_solve(lattice.tables, array, rhs), ref) <= 1e-11


def test_displacements_from_the_kernel_table_are_the_kernel_products():
    """GeneralSolver._products (the displacement of a cell range's shear at a few points) against the rows of
    T formed by kernel(): at cell centres of the fine and the shadow lattice, from the lattices' tables in
    their own datum converted to the package's (points left of the first cell and beyond the contact,
    one and three columns), and off the lattice (kernel() itself). 1e-12: the table's offsets are k h
    exactly, the formed rows' (j + 1/2) h - (i + 1/2) h, which round differently; measured 1.8e-14."""
    from halfslip.solvers._toeplitz import kernel

    from helpers import make

    problem, solver = make("hertz", "general", nodes=256)
    half = float(problem.half_width(P0))
    rng = np.random.default_rng(7)
    for h in (2 * half / 256, 4 * half / 256):
        solver._lattice(h, 300)
        first = -int(round(half / h))
        xc = (first + 0.5 + np.arange(int(round(2 * half / h)))) * h
        q = rng.standard_normal((xc.size, 3))
        for xs in ((first - 3.5 + np.array([0.0, 1.0, 40.0, xc.size + 5.0])) * h,  # on the lattice
                   np.array([xc[0] - 0.3 * h, 0.123 * h, xc[-1] + 2.7 * h])):       # off it
            ref = kernel(xs[:, None] - xc[None, :], h, solver.datum, solver.A) @ q
            assert _rel(solver._products(xs, xc, h, q), ref) <= 1e-12
            assert _rel(solver._products(xs, xc, h, q[:, 0]), ref[:, 0]) <= 1e-12


@pytest.mark.parametrize("kind", ["hertz", "punch"])
def test_a_states_displacement_in_one_compiled_pass_is_the_general_path(kind):
    """GeneralSolver._displacement of a state's shear at lattice points (the arrived and leaving cells and the
    match points beside its contact), in one compiled pass since 0.4.3 (_displaced: the kernel table's
    products, the datum, the bulk term and the end cells' corrections), against the general path it keeps
    for other points (_products, _end_columns and their product): equal to rounding (1e-13 of the largest
    displacement; measured 0); a point off the lattice (inside an end cell's support) takes the
    general path."""
    from halfslip.solvers import general as gm

    from helpers import make

    problem, solver = make(kind, "general", nodes=256)
    N = problem.solve(P0, 0.05 * P0 * float(problem.half_width(P0)))
    h = 2.2 * N.half_width / 256
    solver._lattice(h, 300)
    first, n = gm._cells(N.left, N.right, h)
    xc = (first + 0.5 + np.arange(n)) * h
    q = np.random.default_rng(3).standard_normal(n) * 1e6
    xs = (first + 0.5 + np.array([-9, -3, -1, 0, 5, n - 1, n, n + 2, n + 11])) * h

    def general_path(xs):
        ends = gm._end_supports(N, first, n, h)
        out = 1e-7 - solver._products(xs, xc, h, q) + 0.25 * solver.A * 3e7 * xs
        return out - solver._end_columns(N, first, h, ends, xs) @ q[[k for k, _, _ in ends]]

    got = solver._displacement(1e-7, xc, q, h, 3e7, xs, N)
    ref = general_path(xs)
    assert _rel(got, ref) <= 1e-13
    inside = np.array([0.5 * (N.left + xc[0])])  # inside the first end cell's support, not its centre
    assert _rel(solver._displacement(1e-7, xc, q, h, 3e7, inside, N), general_path(inside)) <= 1e-13


# the reference's adaptive quadrature meets rounding at 1e-13 on the 1e-12 P0 punch (its pressure is a small
# difference of large terms) and says so: the test's tolerance there is 1e5 above that
@pytest.mark.filterwarnings("ignore::scipy.integrate.IntegrationWarning")
@pytest.mark.parametrize("kind,load", [("hertz", 1.0), ("punch", 1.0), ("punch", 1e-12)])
def test_end_cell_columns_are_the_pressure_shaped_force(kind, load):
    """The end cells' correction columns of T (their shear spread like the pressure over their supports,
    which reach to the contact's edges, less the same force over the cell) against adaptive quadrature of
    the log kernel, at cells next to the end cells (the graded Gauss rule in theta, the singularity at the
    own centre taken out) and beyond END_CELL_NEAR cells (the multipole series): 1e-11 of t_0 (measured
    7e-15 at P0; a wrong moment, sign or term of the series is off by 1e-4 or more). Also a punch at 1e-12
    P0, whose pressure is the flat punch's inverse square root at the edges and whose kink lies 4e-9 of the
    flat beyond its edge, a near-singularity for the rule: 1e-8 of t_0 there (measured 2e-9; without the
    cut at the kink 1.6e-5, with the cubic smoothstep of 24 points 5e-7)."""
    from scipy.integrate import quad

    import halfslip.solvers.general as G
    from halfslip.geometry import NormalProblem
    from halfslip.solvers._toeplitz import kernel

    from helpers import A as A_STEEL
    from helpers import PROFILES, W_FLAT

    problem = NormalProblem(PROFILES[kind], A_STEEL)
    N = problem.solve(load * P0, 0.0)
    h = (N.right - N.left) / 64 * 1.013
    first, n = G._cells(N.left, N.right, h)
    x = (first + 0.5 + np.arange(n)) * h
    solver = G.GeneralSolver(problem, 0.6, 64)
    ends = G._end_supports(N, first, n, h)
    C = solver._end_columns(N, first, h, ends, x)
    t0 = abs(kernel(np.array([0.0]), h, 1.0, A_STEEL)[0])
    c0, d0 = N.center, N.half_width

    def in_theta(g, a, b, at=None):
        """int_a^b g(xi) p(xi) dxi in theta (xi = c - d cos theta: smooth where p has an edge's root), cut at
        ``at`` and at the ends of the punch's flat (p's x ln x kinks)."""
        cuts = sorted({a, b} | {v for v in (at, -W_FLAT, W_FLAT) if v is not None and a < v < b})
        ts = [math.acos(min(1.0, max(-1.0, (c0 - v) / d0))) for v in cuts]
        return sum(quad(lambda t: g(c0 - d0 * math.cos(t)) * N.pressure(np.array([c0 - d0 * math.cos(t)]))[0]
                        * d0 * math.sin(t), t0, t1, limit=400, epsabs=0.0, epsrel=1e-13)[0]
                   for t0, t1 in zip(ts[:-1], ts[1:]))

    for c, (k, a, b) in enumerate(ends):
        force = in_theta(lambda v: 1.0, a, b)
        lo = (first + k) * h
        for i in sorted({0, 1, 2, 7, 8, 9, 10, n // 2, n - 9, n - 2, n - 1}):
            xi = x[i]
            shaped = in_theta(lambda v: math.log(abs(xi - v)), a, b, xi) * h / force
            inner = [xi] if lo < xi < lo + h else None
            cell = quad(lambda v: math.log(abs(xi - v)), lo, lo + h, points=inner, limit=400, epsabs=0.0,
                        epsrel=1e-13)[0]
            ref = -(A_STEEL / math.pi) * (shaped - cell)
            assert abs(C[i, c] - ref) <= (1e-11 if load == 1.0 else 1e-8) * t0, (k, i, C[i, c], ref)
        # a point inside the support other than the cell's centre (the rule cut there too)
        xi = 0.5 * (a + lo + 0.5 * h) if k == 0 else 0.5 * (b + lo + 0.5 * h)
        shaped = in_theta(lambda v: math.log(abs(xi - v)), a, b, xi) * h / force
        cell = quad(lambda v: math.log(abs(xi - v)), lo, lo + h, points=[xi], limit=400, epsabs=0.0,
                    epsrel=1e-13)[0]
        got = solver._end_columns(N, first, h, ends, np.array([xi]))[0, c]
        assert abs(got - (-(A_STEEL / math.pi) * (shaped - cell))) <= (1e-11 if load == 1.0 else 1e-8) * t0


@pytest.mark.parametrize("kind", ["hertz", "punch"])
def test_two_new_end_cells_in_one_call_are_the_cell_by_cell_route(kind):
    """A take's two new end cells set up and evaluated at its cells in one compiled call (general._end_pair,
    since 0.4.4) give the numbers of each _EndCell set up and evaluated on its own, to the last bit: its
    rule, weights, moments and own-centre value, and its columns at the cells and at points inside either
    support other than its centre (where the rule is cut at the point, _EndCell._inside)."""
    import halfslip.solvers.general as G
    from halfslip.geometry import NormalProblem

    from helpers import A as A_STEEL
    from helpers import PROFILES

    problem = NormalProblem(PROFILES[kind], A_STEEL)
    N = problem.solve(P0, 0.0)
    h = (N.right - N.left) / 64 * 1.013
    first, n = G._cells(N.left, N.right, h)
    x = (first + 0.5 + np.arange(n)) * h
    ends = G._end_supports(N, first, n, h)
    inside = [0.5 * (ends[0][1] + x[0]), 0.5 * (ends[1][2] + x[-1])]
    xs = np.concatenate([x, inside])
    solver = G.GeneralSolver(problem, 0.6, 64)
    fused = solver._end_columns(N, first, h, ends, xs)
    for c, (k, a, b) in enumerate(ends):
        kept = solver._end_cells.get((a, b, first + k, h), (N,))
        alone = G._EndCell(N, a, b, (first + k) * h, h, solver._kinks)
        for name in ("xi", "w", "series"):
            assert np.array_equal(getattr(kept, name), getattr(alone, name)), name
        assert kept.scale == alone.scale and kept.own == alone.own
        assert np.array_equal(fused[:, c], -(A_STEEL / math.pi) * alone.potential(xs))

def test_end_cell_lattice_solves_and_products_are_the_dense_ones():
    """_EndCellLattice: T' = T + the two correction columns; its products and its stick-set solves (Woodbury
    where an end cell sticks, with and without the column of ones, over the routes of solve_runs) against
    the dense T' (1e-11; measured 1e-15)."""
    import halfslip.solvers.general as G
    from halfslip.geometry import NormalProblem

    from helpers import A as A_STEEL
    from helpers import PROFILES

    problem = NormalProblem(PROFILES["punch"], A_STEEL)
    N = problem.solve(P0, 0.0)
    h = (N.right - N.left) / 300 * 1.013
    first, n = G._cells(N.left, N.right, h)
    x = (first + 0.5 + np.arange(n)) * h
    solver = G.GeneralSolver(problem, 0.6, 300)
    lat = solver._lattice(h, n)
    ends = G._end_supports(N, first, n, h)
    C = solver._end_columns(N, first, h, ends, x)
    W = G._EndCellLattice(lat, ends, C, N)
    T = lat.t[np.abs(np.arange(n)[:, None] - np.arange(n)[None, :])]
    Tp = T.copy()
    Tp[:, 0] += C[:, 0]
    Tp[:, n - 1] += C[:, 1]
    rng = np.random.default_rng(0)
    v = rng.standard_normal(n)
    assert _rel(W.matvec(v), Tp @ v) <= 1e-11
    for runs in ([(0, n)], [(0, 10), (20, n)], [(3, 10), (20, n - 1)], [(0, 5), (30, 40), (50, n)],
                 [(0, 140), (n - 5, n)]):
        stick = np.zeros(n, bool)
        for a, b in runs:
            stick[a:b] = True
        rhs = rng.standard_normal((int(stick.sum()), 2))
        got, _ = W.solve_runs(runs, n, rhs)
        assert _rel(got, np.linalg.solve(Tp[np.ix_(stick, stick)], rhs)) <= 1e-11
        got, _ = W.solve_runs(runs, n, rhs, ones=True)
        full = np.column_stack((np.ones(int(stick.sum())), rhs))
        assert _rel(got, np.linalg.solve(Tp[np.ix_(stick, stick)], full)) <= 1e-11


def test_the_compiled_small_solves_and_transform_lengths():
    """The compiled helpers of the stick-set solves: LAPACK's dposv by symbol (_spd_solve) is the dense solve
    on a symmetric positive definite matrix, and on one that is not it falls back to the elimination
    (1e-10: the indefinite matrix's condition); the elimination of the Woodbury
    capacitance (_lu_solve) pivots (a zero first pivot); fast_len is scipy's next_fast_len(n, real=True),
    the transform lengths of the products and of the Gohberg-Semencul generators."""
    from scipy import fft as sfft

    rng = np.random.default_rng(5)
    M = rng.standard_normal((40, 40))
    S = M @ M.T + np.eye(40)
    B = rng.standard_normal((40, 3))
    assert _rel(tz._spd_solve(S, B), np.linalg.solve(S, B)) <= 1e-12
    indefinite = S - 10.0 * np.eye(40)  # dposv refuses it: solved by elimination instead
    assert np.min(np.linalg.eigvalsh(indefinite)) < 0.0
    assert _rel(tz._spd_solve(indefinite, B), np.linalg.solve(indefinite, B)) <= 1e-10
    C = np.array([[0.0, 2.0], [3.0, 1.0]])
    y = rng.standard_normal((2, 2))
    assert _rel(tz._lu_solve(C, y), np.linalg.solve(C, y)) <= 1e-14
    for n in list(range(1, 300)) + [1023, 2049, 4097, 12289, 30001]:
        assert tz.fast_len(n) == sfft.next_fast_len(n, real=True), n


def test_the_compiled_pairwise_sum_is_numpys_to_the_last_bit():
    """_geometry_kernels.pairwise_sum (since 0.4.4: the sums a take's compiled end returns, sum q and the
    slipping cells' dissipation) is numpy.sum of a contiguous float64 array to the last bit: the same
    pairwise blocks, accumulators and splits. Every length up to 300 (the block edges at 8 and 128 and
    their multiples), and longer ones through several splits, values over ten decades of both signs, a
    slice from an offset, and zeros of either sign."""
    from halfslip._geometry_kernels import pairwise_sum

    rng = np.random.default_rng(5)
    for n in list(range(301)) + [511, 512, 513, 1000, 1024, 2047, 4097]:
        a = rng.standard_normal(n + 3) * 10.0 ** rng.uniform(-5, 5, n + 3)
        assert pairwise_sum(a, 3, n) == float(np.sum(a[3:])), n
    for a in (np.array([-0.0]), np.array([-0.0, -0.0]), np.zeros(0)):
        assert math.copysign(1.0, pairwise_sum(a, 0, a.size)) == math.copysign(1.0, float(np.sum(a)))
