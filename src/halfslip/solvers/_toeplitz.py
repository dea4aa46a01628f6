"""Linear algebra of the lattice solver: the log kernel on a uniform lattice is Toeplitz.

Cells of width h, piecewise-constant shear q_j, the relative displacement
collocated at the cell centres (physics.md, T1 integrated):

    g_i = delta - sum_j t_(i-j) q_j + A sigma x_i / 4,
    t_k = -(A/pi) [G((k + 1/2) h) - G((k - 1/2) h) - h ln l],   G(v) = v ln|v| - v,

(the integral of -(A/pi) ln(|x_i - xi| / l) over cell j). T = (t_|i-j|) is
symmetric Toeplitz and positive definite when the datum l exceeds a quarter of
the lattice span (the logarithmic capacity of an interval is a quarter of its
length); the solver takes l = 2 N_max h.

The matrix of any contiguous run of n cells is the leading block T_n, whatever
the run's position. Levinson's recursion gives, in O(N^2) once per lattice,
the backward predictors b^(k) (T_(k+1) b^(k) = eps_k e_k, last entry 1) of
every leading block; the first column of T_n^-1 is x = J b^(n-1) / eps_(n-1),
and the Gohberg-Semencul formula

    T_n^-1 = (L(x) L(x)^T - L(u) L(u)^T) / x_0,   u = Z J x,

(L(v): lower-triangular Toeplitz with first column v, Z the down shift, J the
reversal) applies T_n^-1 with four FFT convolutions, O(n log n). Products with
T over the contact use the circulant embedding, also by FFT.
"""
from __future__ import annotations

import math

import numba
import numpy as np
from scipy import fft as sfft

try:  # scipy's pocketfft binding, without the per-call dispatch of scipy.fft (4 us a call, the cost of a
    # whole transform of 500 points): checked below against scipy.fft, which is used if this ever differs
    from scipy.fft._pocketfft import pypocketfft as _pocket
except ImportError:  # pragma: no cover - scipy without it
    _pocket = None


def _r2c_scipy(a: np.ndarray) -> np.ndarray:
    return sfft.rfft(a, axis=0)


def _c2r_scipy(a: np.ndarray, m: int) -> np.ndarray:
    return sfft.irfft(a, m, axis=0)


def _r2c_pocket(a: np.ndarray) -> np.ndarray:
    return _pocket.r2c(a, (0,), True, 0, None, 1)


def _c2r_pocket(a: np.ndarray, m: int) -> np.ndarray:
    return _pocket.c2r(a, (0,), m, False, 2, None, 1)


def _pocket_works() -> bool:
    if _pocket is None:  # pragma: no cover
        return False
    try:
        x = np.random.default_rng(1).standard_normal((30, 3))
        X = _r2c_pocket(x)
        return (np.array_equal(X, _r2c_scipy(x)) and np.array_equal(_c2r_pocket(X, 30), _c2r_scipy(X, 30))
                and np.array_equal(_c2r_pocket(X[:, 0].copy(), 30), _c2r_scipy(X[:, 0], 30)))
    except Exception:  # pragma: no cover - a changed private signature
        return False


#: rfft / irfft along axis 0 of an array of the full transform length (``_r2c(a)``, ``_c2r(A, m)``).
_r2c, _c2r = (_r2c_pocket, _c2r_pocket) if _pocket_works() else (_r2c_scipy, _c2r_scipy)


def kernel(u: np.ndarray, h: float, datum: float, compliance: float) -> np.ndarray:
    """t(u): minus the displacement at offset ``u`` from the centre of a unit-shear cell of width ``h``.

    Parameters
    ----------
    u : ndarray
        Offsets x_i - x_j [m] (any shape).
    h, datum, compliance : float
        Cell width, log datum l, composite compliance A.
    """
    u = np.asarray(u, dtype=float)
    return -(compliance / math.pi) * (_G(u + 0.5 * h) - _G(u - 0.5 * h) - h * math.log(datum))


@numba.njit(cache=True)
def table_products(t, rows, cols, q):  # pragma: no cover - compiled
    """sum_m t[|rows_i - cols_m|] q_m: products of T with the shear ``q`` (k columns) on the cells ``cols``
    at the cells ``rows`` (lattice indices, any cells), from the kernel's table ``t`` (long enough for
    every offset): the displacement at a few cells without forming their rows of T."""
    out = np.zeros((rows.size, q.shape[1]))
    for i in range(rows.size):
        for m in range(cols.size):
            tk = t[abs(rows[i] - cols[m])]
            for c in range(q.shape[1]):
                out[i, c] += tk * q[m, c]
    return out


def _G(v: np.ndarray) -> np.ndarray:
    a = np.abs(v)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(a > 0.0, v * np.log(np.where(a > 0.0, a, 1.0)) - v, 0.0)


@numba.njit(cache=True)
def _levinson(t: np.ndarray, n: int):  # pragma: no cover - compiled
    """Backward predictors of every leading block, packed by rows, and the prediction errors."""
    B = np.zeros(n * (n + 1) // 2)
    eps = np.empty(n)
    b = np.zeros(n)
    new = np.zeros(n)
    b[0] = 1.0
    eps[0] = t[0]
    B[0] = 1.0
    for k in range(n - 1):
        g = 0.0
        for i in range(k + 1):
            g += t[i + 1] * b[i]
        r = g / eps[k]
        new[0] = -r * b[k]
        for i in range(1, k + 1):
            new[i] = b[i - 1] - r * b[k - i]
        new[k + 1] = b[k]
        for i in range(k + 2):
            b[i] = new[i]
        eps[k + 1] = eps[k] - g * r
        if not eps[k + 1] > 0.0:
            eps[k + 1] = -1.0
            return B, eps
        off = (k + 1) * (k + 2) // 2
        for i in range(k + 2):
            B[off + i] = b[i]
    return B, eps


def _padded(v: np.ndarray, m: int) -> np.ndarray:
    """``v`` (n,) or (n, k) followed by zeros to m rows."""
    out = np.zeros((m,) + v.shape[1:])
    out[:v.shape[0]] = v
    return out


def _lower_toeplitz(c: np.ndarray) -> np.ndarray:
    """The lower-triangular Toeplitz matrix with first column ``c``."""
    n = c.size
    i = np.arange(n)
    d = i[:, None] - i[None, :]
    return np.where(d >= 0, c[np.clip(d, 0, None)], 0.0)


#: Spectra of T_n^-1 generators kept per lattice (4 columns of m/2 + 1 complex numbers each).
GENERATORS = 256

#: Runs of at most this many cells are solved with a cached dense T_n^-1 (n^2 numbers, at most
#: 8 DENSE_CELLS^3 / 3 bytes for all of them): a product of n^2 beats the four transforms and their
#: per-call costs up to here.
DENSE_CELLS = 128

#: Solve a stick set of several runs exactly through a Schur complement while the runs other than the
#: longest hold at most this many cells (one more column of a solve on the longest run per cell).
ISLAND_CELLS = 48

#: ... when the gaps between the runs hold at least this many cells per island cell (or more than
#: GAP_CELLS); otherwise through the gaps' complement (below). What each costs, measured (one island run
#: beside a run of 200 / 440 / 800 cells, two right-hand sides, benchmarks/bench_solve_routes.py): the
#: islands' complement a column of a solve on the longest run per island cell (0.03-0.07 ms each), the gaps'
#: one solve per gap plus O(span) per gap cell and a dense factorisation (0.08-0.2 ms up to 20 gap cells,
#: 0.2-0.4 ms at 93, 0.5-0.8 ms at 160). Equal cost at about 20 gap cells per island cell. Until 0.3.6 the
#: islands went first whenever they were fewer cells than the gaps (17 island cells beside 93 gap cells:
#: 1.4 ms against 0.4 ms by the gaps, at a run of 800 cells).
ISLAND_COST = 20

#: ... or while the gaps between the runs hold at most this many cells: the complement is dense
#: (GAP_CELLS^2 numbers, a factorisation of GAP_CELLS^3 / 3 operations), its columns of the inverse of
#: the spanning run come from one solve per gap and the Gohberg-Semencul recursion (:func:`_next_columns`);
#: otherwise few, long runs far apart, for which block-Jacobi CG converges in five to seven iterations.
#: Measured on the random histories at 1024 nodes (ms per step, one session): 96 cells 21.0, 160 19.7,
#: 240 19.8; 48 (CG from there, before 0.3.5) 23.3.
GAP_CELLS = 160


class ToeplitzLattice:
    """T of a uniform lattice of ``size`` cells: products, and solves on contiguous runs.

    Parameters
    ----------
    h : float
        Cell width [m].
    size : int
        Largest number of cells a run (or the contact) may have.
    compliance : float
        A.
    """

    def __init__(self, h: float, size: int, compliance: float):
        self.h = float(h)
        self.size = int(size)
        self.datum = 2.0 * self.size * self.h
        self.compliance = float(compliance)
        self.t = kernel(self.h * np.arange(self.size), self.h, self.datum, self.compliance)
        B, eps = _levinson(self.t, self.size)
        if not eps[-1] > 0.0:
            raise ArithmeticError("the lattice kernel is not positive definite (datum too short)")
        self._B, self._eps = B, eps
        self._gs: dict[int, tuple] = {}
        self._circ: dict[int, tuple] = {}
        self._inv: dict[int, np.ndarray] = {}
        self._unit: dict[int, np.ndarray] = {}
        self._t_ext = self.t

    # -- products ---------------------------------------------------------
    def matvec(self, v: np.ndarray) -> np.ndarray:
        """T_n v for v of shape (n,) or (n, k), n <= size (cells of one contiguous range)."""
        n = v.shape[0]
        m, spec = self._circulant(n)
        V = _r2c(_padded(v, m))
        if v.ndim == 2:
            return _c2r(V * spec[:, None], m)[:n]
        return _c2r(V * spec, m)[:n]

    def _circulant(self, n: int):
        """(m, spectrum) of the circulant of length m = next_fast_len(2n) that embeds T_n, cached per m.

        The circulant of the whole kernel, c_k = c_(m-k) = t_k (k <= m/2), embeds every T_n with
        2n <= m: one spectrum serves all the n that share a transform length.
        """
        m = sfft.next_fast_len(2 * n, real=True)
        got = self._circ.get(m)
        if got is None:
            half = m // 2
            t = self._kernel_to(half + 1)
            c = np.empty(m)
            c[:half + 1] = t[:half + 1]
            c[half + 1:] = t[1:m - half][::-1]
            got = self._circ[m] = (m, _r2c(c))
        return got

    def _kernel_to(self, count: int) -> np.ndarray:
        """t_k for k < ``count`` (beyond ``size`` too: filler of the circulants)."""
        if count <= self.t.size:
            return self.t
        if self._t_ext.size < count:
            self._t_ext = kernel(self.h * np.arange(count), self.h, self.datum, self.compliance)
        return self._t_ext

    # -- solves -------------------------------------------------------------
    def solve(self, n: int, w: np.ndarray) -> np.ndarray:
        """T_n^-1 w for w of shape (n,) or (n, k) (Gohberg-Semencul, by FFT)."""
        if n == 1:
            return w / self.t[0]
        if n <= DENSE_CELLS:
            return self._inverse(n) @ w
        m, Xc, Uc, Xs, Us = self._generator(n)
        twod = w.ndim == 2
        W = w if twod else w[:, None]
        k = W.shape[1]
        # L(v)^T w is the correlation of v and w: irfft(conj(V) W), no wrap-around for m >= 2n - 1
        F = _r2c(_padded(W, m))
        G = np.empty((F.shape[0], 2 * k), complex)
        np.multiply(Xc, F, out=G[:, :k])
        np.multiply(Uc, F, out=G[:, k:])
        ab = _c2r(G, m)
        ab[n:] = 0.0
        AB = _r2c(ab)
        # (L(x) a - L(u) b) / x0 in one inverse transform (1/x0 is in Xs, Us)
        out = _c2r(AB[:, :k] * Xs - AB[:, k:] * Us, m)[:n]
        return out if twod else out[:, 0]

    def _xu(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """The Gohberg-Semencul generators of the leading block T_n from the Levinson tables:
        x = T_n^-1 e_1 and u = (0, x_(n-1), ..., x_1)."""
        off = (n - 1) * n // 2
        b = self._B[off:off + n]
        e = self._eps[n - 1]
        x = b[::-1] / e
        u = np.zeros(n)
        u[1:] = b[:-1] / e
        return x, u

    def _inverse(self, n: int) -> np.ndarray:
        """T_n^-1, dense, from the Gohberg-Semencul formula (n <= DENSE_CELLS), cached."""
        got = self._inv.get(n)
        if got is None:
            x, u = self._xu(n)
            Lx, Lu = _lower_toeplitz(x), _lower_toeplitz(u)
            got = self._inv[n] = (Lx @ Lx.T - Lu @ Lu.T) / x[0]
        return got

    def _generator(self, n: int):
        """(m, conj X, conj U, X / x0, U / x0), the spectra of the Gohberg-Semencul generators of T_n^-1,
        as columns."""
        got = self._gs.get(n)
        if got is None:
            x, u = self._xu(n)
            m = sfft.next_fast_len(2 * n, real=True)
            X, U = _r2c(_padded(x, m))[:, None], _r2c(_padded(u, m))[:, None]
            got = (m, np.conj(X), np.conj(U), X / x[0], U / x[0])
            if len(self._gs) >= GENERATORS:  # the oldest goes (the contact moves slowly: recent n recur)
                del self._gs[next(iter(self._gs))]
            self._gs[n] = got
        return got

    def unit(self, n: int) -> np.ndarray:
        """T_n^-1 1 (read only), cached per n: the active set needs it at every solve (the rigid shift's
        column), and it depends on the run's length only."""
        got = self._unit.get(n)
        if got is None:
            got = self.solve(n, np.ones(n))
            got.flags.writeable = False
            if len(self._unit) >= GENERATORS:
                del self._unit[next(iter(self._unit))]
            self._unit[n] = got
        return got

    def solve_runs(self, runs: list[tuple[int, int]], n: int, rhs: np.ndarray, tol: float = 1e-13,
                   max_iter: int = 200, ones: bool = False) -> tuple[np.ndarray, int]:
        """T_SS^-1 rhs on the stick set S = union of ``runs`` (half-open (start, stop) in 0..n); with
        ``ones``, T_SS^-1 [1, rhs] (a column of ones first), the ones' column from :meth:`unit` where S is
        one run or is solved through its gaps (T_m^-1 of ones on S is T_m^-1 1 less the columns of T_m^-1 at
        the gaps, which that route has): a column less to solve.

        One run: a direct Gohberg-Semencul solve. Several runs: exactly,
        through a Schur complement, whichever applies first of

        * the cells I of the runs other than the longest run R (islands beside
          a stick zone), at most ISLAND_CELLS, when the gaps hold ISLAND_COST
          times as many cells or more than GAP_CELLS:
          with X = T_RR^-1 [T_RI, b_R] (one solve on R),
          y_I = (T_II - T_IR X_1)^-1 (b_I - T_IR X_2), y_R = X_2 - X_1 y_I;
        * the gaps Z between the runs, at most GAP_CELLS, in the spanning run
          (T_SS^-1 b = (T^-1 b~ - X C^-1 (T^-1 b~)_Z)_S, X = T^-1 E_Z, C = X_Z;
          X's columns by :meth:`_inverse_columns`).

        Otherwise: conjugate gradients preconditioned with the exact solve of
        every run (block Jacobi; the runs are then few, long and far apart, so
        few iterations), the products with T over the n cells by FFT. ``rhs``
        has shape (|S|, k).
"""
        if len(runs) == 1:
            m = runs[0][1] - runs[0][0]
            y = self.solve(m, rhs)
            return (np.column_stack((self.unit(m), y)) if ones else y), 0
        a, b = runs[0][0], runs[-1][1]
        gaps = np.concatenate([np.arange(runs[i][1], runs[i + 1][0]) for i in range(len(runs) - 1)]) - a
        lengths = [stop - start for start, stop in runs]
        longest = int(np.argmax(lengths))
        islands = sum(lengths) - lengths[longest]
        if islands <= ISLAND_CELLS and (ISLAND_COST * islands <= gaps.size or gaps.size > GAP_CELLS):
            return self._island_solve(runs, longest, _with_ones(rhs, ones)), 0
        if gaps.size <= GAP_CELLS:
            return self._gap_solve(runs, gaps, rhs, ones), 0
        return self._cg_runs(runs, n, _with_ones(rhs, ones), tol, max_iter)

    def _gap_solve(self, runs, gaps, rhs, ones=False):
        """T_SS^-1 rhs (with ``ones``: T_SS^-1 [1, rhs]) by the Schur complement of the ``gaps`` (cells counted
        from the first run's start) in the spanning run (see :meth:`solve_runs`)."""
        a, b = runs[0][0], runs[-1][1]
        m = b - a
        stick = np.ones(m, bool)
        stick[gaps] = False
        X = self._inverse_columns(m, runs, a, gaps)
        k = rhs.shape[1]
        Y = np.empty((m, k + 1) if ones else (m, k))
        wide = np.zeros((m, k))
        wide[stick] = rhs
        Y[:, -k:] = self.solve(m, wide)
        if ones:  # T_m^-1 of ones on the stick cells: T_m^-1 1 less T_m^-1 of ones on the gaps
            Y[:, 0] = self.unit(m) - X.sum(axis=1)
        Y = Y - X @ np.linalg.solve(X[gaps], Y[gaps])
        return Y[stick]

    def _inverse_columns(self, m: int, runs, a: int, gaps: np.ndarray) -> np.ndarray:
        """The columns of T_m^-1 at the gaps between ``runs`` (``gaps``, their cells counted from ``a``): each
        gap's first column by a solve, the others by the Gohberg-Semencul recursion from it (O(m) each)."""
        if m <= DENSE_CELLS:
            return self._inverse(m)[:, gaps]
        starts = np.array([runs[i][1] - a for i in range(len(runs) - 1)], np.int64)
        lengths = np.array([runs[i + 1][0] - runs[i][1] for i in range(len(runs) - 1)], np.int64)
        E = np.zeros((m, starts.size))
        E[starts, np.arange(starts.size)] = 1.0
        x, u = self._xu(m)
        return _next_columns(x, u, self.solve(m, E), starts, lengths)

    def _island_solve(self, runs, longest, rhs):
        """T_SS^-1 rhs by the Schur complement of the cells outside run ``longest`` (see :meth:`solve_runs`)."""
        cells = np.concatenate([np.arange(start, stop) for start, stop in runs])
        start, stop = runs[longest]
        first = sum(b - a for a, b in runs[:longest])  # the rows of R in S
        rows = np.arange(first, first + stop - start)
        others = np.setdiff1d(np.arange(cells.size), rows, assume_unique=True)
        inner = self._kernel_to(int(np.max(cells) - np.min(cells)) + 1)
        main, isl = cells[rows], cells[others]
        T_RI = inner[np.abs(main[:, None] - isl[None, :])]
        T_II = inner[np.abs(isl[:, None] - isl[None, :])]
        k = isl.size
        X = self.solve(main.size, np.concatenate((T_RI, rhs[rows]), axis=1))
        X1, X2 = X[:, :k], X[:, k:]
        y_I = np.linalg.solve(T_II - T_RI.T @ X1, rhs[others] - T_RI.T @ X2)
        out = np.empty(rhs.shape)
        out[rows] = X2 - X1 @ y_I
        out[others] = y_I
        return out

    def _cg_runs(self, runs, n, rhs, tol, max_iter):
        """Block-Jacobi preconditioned CG on the union of ``runs`` (see :meth:`solve_runs`).

        Returns
        -------
        y : ndarray, shape (|S|, k)
        iterations : int
            CG iterations (0 for one run).
        """
        cuts = np.cumsum([0] + [b - a for a, b in runs]).tolist()
        pieces = list(zip(cuts[:-1], cuts[1:]))
        places = [(slice(a, b), slice(c, d)) for (a, b), (c, d) in zip(runs, pieces)]  # (cells, rows of S)
        m, spec = self._circulant(n)
        spec = spec[:, None]
        buf = np.zeros((m, rhs.shape[1]))  # T over the n cells, padded: only the rows of S are ever written

        def prec(r):
            out = np.empty_like(r)
            for a, b in pieces:
                out[a:b] = self.solve(b - a, r[a:b])
            return out

        def op(v):
            for cells, rows in places:
                buf[cells] = v[rows]
            V = _r2c(buf)
            V *= spec
            full = _c2r(V, m)
            return np.concatenate([full[cells] for cells, _ in places])

        y = prec(rhs)
        r = rhs - op(y)
        z = prec(r)
        p = z.copy()
        rz = _coldot(r, z)
        norm = _coldot(rhs, rhs)
        norm[norm == 0.0] = 1.0
        bound = tol * tol * norm  # |r| / |rhs| > tol, squared
        zero = np.zeros_like(rz)
        it = 0
        while it < max_iter and np.any(_coldot(r, r) > bound):
            Ap = op(p)
            pAp = _coldot(p, Ap)
            # a column already solved (zero residual, e.g. a zero right-hand side) stays put
            alpha = np.divide(rz, pAp, out=zero.copy(), where=pAp > 0.0)
            y += alpha * p
            r -= alpha * Ap
            z = prec(r)
            rz_new = _coldot(r, z)
            p *= np.divide(rz_new, rz, out=zero.copy(), where=rz > 0.0)
            p += z
            rz = rz_new
            it += 1
        return y, it


def _with_ones(rhs: np.ndarray, ones: bool) -> np.ndarray:
    """[1, rhs] with ``ones``, else ``rhs``."""
    return np.column_stack((np.ones(rhs.shape[0]), rhs)) if ones else rhs


@numba.njit(cache=True)
def _next_columns(x, u, first, starts, lengths):  # pragma: no cover - compiled
    """Columns starts[b] .. starts[b] + lengths[b] - 1 of B = T_m^-1, given column starts[b] in first[:, b]:
    from the Gohberg-Semencul formula B = (L(x) L(x)^T - L(u) L(u)^T) / x_0,
    B_(0, j) = x_j and B_(i, j) = B_(i-1, j-1) + (x_i x_j - u_i u_j) / x_0."""
    m = x.size
    out = np.empty((m, lengths.sum()))
    c = 0
    for k in range(starts.size):
        j = starts[k]
        for i in range(m):
            out[i, c] = first[i, k]
        for r in range(1, lengths[k]):
            j += 1
            out[0, c + r] = x[j]
            for i in range(1, m):
                out[i, c + r] = out[i - 1, c + r - 1] + (x[i] * x[j] - u[i] * u[j]) / x[0]
        c += lengths[k]
    return out


if hasattr(np, "vecdot"):
    def _coldot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Column-wise dot products of two (n, k) arrays."""
        return np.vecdot(a.T, b.T)
else:  # pragma: no cover - numpy < 2
    def _coldot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Column-wise dot products of two (n, k) arrays."""
        return np.einsum("ij,ij->j", a, b)
