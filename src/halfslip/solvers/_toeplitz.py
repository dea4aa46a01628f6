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

Since 0.4.0 the solves, the products and the general solver's active set that
calls them are compiled (numba; numpy.fft inside numba by rocket-fft), in this
one file (numba's cache checks only a compiled function's own file).
"""
from __future__ import annotations

import math

import llvmlite.binding as llvm
import numba
import numpy as np
from numba import types
from numba.extending import get_cython_function_address


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


#: Slots of the per-run-length caches of a lattice (the generators' spectra, 2 (1.5 size) complex numbers,
#: and T_n^-1 1, size numbers, each): about 1.9 kB per cell of the lattice.
SLOTS = 32

#: Runs of at most this many cells are solved with a cached dense T_n^-1 (n^2 numbers, at most
#: 8 DENSE_CELLS^3 / 3 bytes for all of them): a product of n^2 beats the four transforms and their
#: per-call costs up to here.
DENSE_CELLS = 128

#: Solve a stick set of several runs exactly through a Schur complement while the runs other than the
#: longest hold at most this many cells (one more column of a solve on the longest run per cell).
ISLAND_CELLS = 48

#: ... when the gaps between the runs hold at least this many cells per island cell (or more than
#: GAP_CELLS); otherwise through the gaps' complement (below). What each costs, compiled (0.4.0; one island
#: run beside a run of 200 / 440 / 800 cells, a column of ones and two right-hand sides,
#: benchmarks/bench_solve_routes.py): the islands' complement a column of a solve on the longest run per
#: island cell (0.007-0.03 ms each), the gaps' one solve per gap plus O(span) per gap cell and a Cholesky
#: factorisation (0.03-0.18 ms up to 20 gap cells, 0.18-0.45 ms at 93, 0.4-0.9 ms at 160). Equal cost at
#: about 5 gap cells per island cell (17 island cells beside 160 gap cells: 0.14 / 0.34 / 0.65 ms against
#: 0.45 / 0.63 / 0.89 ms by the gaps). In Python (0.3.6 - 0.3.9) the islands' columns cost more and the
#: rule was 20; until 0.3.6 the islands went first whenever they were fewer cells than the gaps.
ISLAND_COST = 5

#: ... or while the gaps between the runs hold at most this many cells: the complement is dense
#: (GAP_CELLS^2 numbers, a factorisation of GAP_CELLS^3 / 3 operations), its columns of the inverse of
#: the spanning run come from one solve per gap and the Gohberg-Semencul recursion (:func:`_next_columns`);
#: otherwise few, long runs far apart, for which block-Jacobi CG converges in five to seven iterations.
#: Measured on the random histories at 1024 nodes (ms per step, one session): 96 cells 21.0, 160 19.7,
#: 240 19.8; 48 (CG from there, before 0.3.5) 23.3.
GAP_CELLS = 160

#: ... or while (gap cells)^3 is at most GAP_CUBE times the span's cells: the complement's factorisation,
#: (gap cells)^3 / 3 operations, against CG's five to seven iterations of a solve per run and a product over
#: the span (0.4.3, with the gaps' second route below; two runs and one gap, a column of ones and one or two
#: right-hand sides, one process, benchmarks/bench_solve_routes.py): span 800, the same cost at 240 gap cells
#: (0.62 / 0.63 ms, 0.72 / 0.72 in another run), CG 2.2x faster at 320; span 1600, the gaps' 0.80 / 1.28 ms
#: against CG's 1.69 / 1.45 ms at 240 / 320 gap cells, CG 2.8x faster at 480. The cost model (gaps about
#: 2.7e-8 ms (gap cells)^3 + 0.4 us a span cell, CG about 1.2 us a span cell) has them equal at about 3e4;
#: 2e4 keeps to the side of CG where the two are close.
GAP_CUBE = 2.0e4

#: The gaps' complement from this many gap cells on takes the span inverse's columns on the gap rows only
#: (:func:`_gap_block`, O(gap cells^2)) and corrects the span's solution by a second solve, T^-1 (E_Z s), instead
#: of forming the columns over the whole span (O(span) each) and their product with s (0.4.3). Measured with
#: a column of ones and two right-hand sides beside runs of 200 / 440 / 800 cells (one process, best of 40):
#: the same cost at 48 gap cells, 0.76-0.82x at 64, 0.65-0.78x at 93, 0.5-0.67x at 160; 1.5-1.9x slower at 5.
#: (With it the islands' and the gaps' complements cost the same at about 5 gap cells per island cell beside
#: a run of 200 cells and about 8 beside 800, benchmarks/bench_solve_routes.py; ISLAND_COST was left at 5:
#: islands are 4 % of the random histories' takes with several runs and more.)
GAP_TWO_SOLVES = 48


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
        self._circ: dict[int, tuple] = {}
        self._t_ext = self.t
        # the compiled solves' caches, direct-mapped per run length n (slot n mod SLOTS; the contact moves
        # slowly, so recent lengths recur): the spectra of T_n^-1's generators and T_n^-1 1, with the length
        # each slot holds (-1: none). Plain arrays: numba's typed dicts cost seconds to compile.
        half = fast_len(2 * self.size) // 2 + 1
        keys = np.full((2, SLOTS), -1, np.int64)
        self.tables = (self.t, B, eps, keys, np.empty((SLOTS, 2, half), complex), np.empty((SLOTS, self.size)))

    # -- products ---------------------------------------------------------
    def matvec(self, v: np.ndarray) -> np.ndarray:
        """T_n v for v of shape (n,) or (n, k), n <= size (cells of one contiguous range)."""
        n = v.shape[0]
        m, spec = self._circulant(n)
        out = _runs_product(spec, m, np.array([[0, n]], np.int64), np.array([0, n], np.int64),
                            np.ascontiguousarray(v.reshape(n, -1), dtype=float))
        return out if v.ndim == 2 else out[:, 0]

    def _circulant(self, n: int):
        """(m, spectrum) of the circulant of length m = fast_len(2n) that embeds T_n, cached per m.

        The circulant of the whole kernel, c_k = c_(m-k) = t_k (k <= m/2), embeds every T_n with
        2n <= m: one spectrum serves all the n that share a transform length.
        """
        m = fast_len(2 * n)
        got = self._circ.get(m)
        if got is None:
            half = m // 2
            t = self._kernel_to(half + 1)
            c = np.empty(m)
            c[:half + 1] = t[:half + 1]
            c[half + 1:] = t[1:m - half][::-1]
            got = self._circ[m] = (m, np.fft.rfft(c))
        return got

    def _kernel_to(self, count: int) -> np.ndarray:
        """t_k for k < ``count`` (beyond ``size`` too: filler of the circulants)."""
        if count <= self.t.size:
            return self.t
        if self._t_ext.size < count:
            self._t_ext = kernel(self.h * np.arange(count), self.h, self.datum, self.compliance)
        return self._t_ext

    # -- solves (compiled, below) ------------------------------------------
    def solve(self, n: int, w: np.ndarray) -> np.ndarray:
        """T_n^-1 w for w of shape (n,) or (n, k) (Gohberg-Semencul, by FFT; dense up to DENSE_CELLS)."""
        out = gs_solve(self.tables, n, np.ascontiguousarray(w.reshape(n, -1), dtype=float))
        return out if w.ndim == 2 else out[:, 0]

    def solve_runs(self, runs, n: int, rhs: np.ndarray, tol: float = 1e-13, max_iter: int = 200,
                   ones: bool = False) -> tuple[np.ndarray, int]:
        """T_SS^-1 rhs on the stick set S = union of ``runs`` (half-open (start, stop) in 0..n; ``rhs`` of
        shape (|S|, k)); with ``ones``, T_SS^-1 [1, rhs] (a column of ones first). Routed by :func:`route`
        (see :func:`stick_solve`); returns the solution and the CG iterations (0 unless CG)."""
        m, spec = self._circulant(n)
        y, iterations = stick_solve(self.tables, spec, m, _run_array(runs), n, NO_COLUMNS, np.zeros((n, 0)),
                                    np.ascontiguousarray(rhs, dtype=float), tol, max_iter)
        return (y if ones else y[:, 1:]), iterations


#: no correction columns (a plain T)
NO_COLUMNS = np.zeros(0, np.int64)


def _run_array(runs) -> np.ndarray:
    """``runs`` as a (k, 2) int64 array."""
    return np.ascontiguousarray(np.asarray(runs, dtype=np.int64).reshape(-1, 2))


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


@numba.njit(cache=True)
def fast_len(n):  # pragma: no cover - compiled
    """The smallest 5-smooth number >= n (scipy.fft.next_fast_len(n, real=True))."""
    best = 1
    while best < n:
        best *= 2
    p5 = 1
    while p5 < best:
        p35 = p5
        while p35 < best:
            v = p35
            while v < n:
                v *= 2
            if v < best:
                best = v
            p35 *= 3
        p5 *= 5
    return best


@numba.njit(cache=True)
def _xu(B, eps, n):  # pragma: no cover - compiled
    """Gohberg-Semencul generators of T_n^-1 from the Levinson tables (ToeplitzLattice._xu)."""
    off = (n - 1) * n // 2
    e = eps[n - 1]
    x = np.empty(n)
    u = np.zeros(n)
    for i in range(n):
        x[i] = B[off + n - 1 - i] / e
    for i in range(1, n):
        u[i] = B[off + i - 1] / e
    return x, u


@numba.njit(cache=True)
def _dense(B, eps, n):  # pragma: no cover - compiled
    """T_n^-1, dense (n <= DENSE_CELLS): every column by the Gohberg-Semencul recursion (:func:`_next_columns`)
    from the first, x (O(n^2), cheaper than a cache)."""
    x, u = _xu(B, eps, n)
    return _next_columns(x, u, x.reshape((n, 1)), np.zeros(1, np.int64), np.full(1, n, np.int64))


@numba.njit(cache=True)
def _generator(tab, n):  # pragma: no cover - compiled
    """Rows (X, U): the spectra of the generators x, u of T_n^-1 at length fast_len(2 n), cached; and x_0."""
    B, eps, keys, gens = tab[1], tab[2], tab[3], tab[4]
    x, u = _xu(B, eps, n)
    m = fast_len(2 * n)
    slot = n % keys.shape[1]
    g = gens[slot]
    if keys[0, slot] != n:
        X = np.fft.rfft(x, n=m)
        U = np.fft.rfft(u, n=m)
        for i in range(X.size):
            g[0, i] = X[i]
            g[1, i] = U[i]
        keys[0, slot] = n
    return g, x[0]


@numba.njit(cache=True)
def _sub_product(Y, X, Z):  # pragma: no cover - compiled
    """Y -= X @ Z, in place. (Loops, not array expressions, throughout this module: each array expression
    costs numba about a third of a second to compile, and compilation is what a first run waits for.)"""
    for i in range(X.shape[0]):
        for j in range(X.shape[1]):
            x = X[i, j]
            if x != 0.0:
                for c in range(Z.shape[1]):
                    Y[i, c] -= x * Z[j, c]


@numba.njit(cache=True)
def gs_solve(tab, n, W):  # pragma: no cover - compiled
    """T_n^-1 W for W of shape (n, k) (ToeplitzLattice.solve); a new array."""
    t, B, eps = tab[0], tab[1], tab[2]
    k = W.shape[1]
    out = np.zeros((n, k))
    if n == 1:
        for c in range(k):
            out[0, c] = W[0, c] / t[0]
        return out
    if n <= DENSE_CELLS:
        _sub_product(out, _dense(B, eps, n), W)
        for i in range(n):
            for c in range(k):
                out[i, c] = -out[i, c]
        return out
    g, x0 = _generator(tab, n)
    m = fast_len(2 * n)
    F = np.fft.rfft(W, n=m, axis=0)
    h = F.shape[0]
    G = np.empty((h, 2 * k), np.complex128)
    for c in range(k):
        for i in range(h):
            G[i, c] = np.conj(g[0, i]) * F[i, c]
            G[i, k + c] = np.conj(g[1, i]) * F[i, c]
    ab = np.fft.irfft(G, n=m, axis=0)
    for i in range(n, m):
        for c in range(2 * k):
            ab[i, c] = 0.0
    AB = np.fft.rfft(ab, axis=0)
    H = np.empty((h, k), np.complex128)
    for c in range(k):
        for i in range(h):
            H[i, c] = (AB[i, c] * g[0, i] - AB[i, k + c] * g[1, i]) / x0
    full = np.fft.irfft(H, n=m, axis=0)
    for i in range(n):
        for c in range(k):
            out[i, c] = full[i, c]
    return out


@numba.njit(cache=True)
def _unit(tab, n):  # pragma: no cover - compiled
    """T_n^-1 1, cached (ToeplitzLattice.unit)."""
    units, slot = tab[5], _unit_slot(tab, n)
    if slot < 0:
        slot = _keep_unit(tab, n, gs_solve(tab, n, np.ones((n, 1))))
    return units[slot, :n]


@numba.njit(cache=True)
def _unit_slot(tab, n):  # pragma: no cover - compiled
    """The cache slot holding T_n^-1 1, -1 when it does not."""
    keys = tab[3]
    slot = n % keys.shape[1]
    return slot if keys[1, slot] == n else -1


@numba.njit(cache=True)
def _keep_unit(tab, n, Y):  # pragma: no cover - compiled
    """Cache T_n^-1 1, the first column of ``Y``; its slot."""
    keys, units = tab[3], tab[5]
    slot = n % keys.shape[1]
    for i in range(n):
        units[slot, i] = Y[i, 0]
    keys[1, slot] = n
    return slot


@numba.njit(cache=True)
def _end_matvec(spec, m, idx, C, v):  # pragma: no cover - compiled
    """T' v = T v + C v[idx] over n = v.size cells (_EndCellLattice.matvec): T by the circulant of length m,
    spectrum ``spec``."""
    V = np.fft.rfft(v, n=m)
    for i in range(V.size):
        V[i] *= spec[i]
    full = np.fft.irfft(V, n=m)
    n = v.size
    out = np.empty(n)
    for i in range(n):
        out[i] = full[i]
    for c in range(idx.size):
        w = v[idx[c]]
        for i in range(n):
            out[i] += C[i, c] * w
    return out


@numba.njit(cache=True)
def _stick_cells(runs):  # pragma: no cover - compiled
    """The cells of ``runs``, in order."""
    total = 0
    for r in range(runs.shape[0]):
        total += runs[r, 1] - runs[r, 0]
    cells = np.empty(total, np.int64)
    c = 0
    for r in range(runs.shape[0]):
        for j in range(runs[r, 0], runs[r, 1]):
            cells[c] = j
            c += 1
    return cells


@numba.njit(cache=True)
def _island_solve(tab, runs, longest, W):  # pragma: no cover - compiled
    """T_SS^-1 W by the Schur complement of the cells outside run ``longest`` (ToeplitzLattice._island_solve):
    with X = T_RR^-1 [T_RI, W_R], y_I = (T_II - T_IR X_1)^-1 (W_I - T_IR X_2), y_R = X_2 - X_1 y_I."""
    t = tab[0]
    cells = _stick_cells(runs)
    total = cells.size
    first = 0
    for r in range(longest):
        first += runs[r, 1] - runs[r, 0]
    nR = runs[longest, 1] - runs[longest, 0]
    nI = total - nR
    isl = np.empty(nI, np.int64)  # rows of S outside R
    c = 0
    for i in range(total):
        if i < first or i >= first + nR:
            isl[c] = i
            c += 1
    k = W.shape[1]
    rhs = np.empty((nR, nI + k))
    for i in range(nR):
        for j in range(nI):
            rhs[i, j] = t[abs(cells[first + i] - cells[isl[j]])]
        for j in range(k):
            rhs[i, nI + j] = W[first + i, j]
    X = gs_solve(tab, nR, rhs)
    S = np.empty((nI, nI))  # T_II - T_IR X_1
    b = np.empty((nI, k))  # W_I - T_IR X_2
    for i in range(nI):
        for j in range(nI):
            S[i, j] = t[abs(cells[isl[i]] - cells[isl[j]])]
        for j in range(k):
            b[i, j] = W[isl[i], j]
    for i in range(nI):
        for l in range(nR):
            a = rhs[l, i]  # T_RI[l, i]
            for j in range(nI):
                S[i, j] -= a * X[l, j]
            for j in range(k):
                b[i, j] -= a * X[l, nI + j]
    y_I = _spd_solve(S, b)
    out = np.empty(W.shape)
    for l in range(nR):
        for j in range(k):
            s = X[l, nI + j]
            for i in range(nI):
                s -= X[l, i] * y_I[i, j]
            out[first + l, j] = s
    for i in range(nI):
        for j in range(k):
            out[isl[i], j] = y_I[i, j]
    return out


@numba.njit(cache=True)
def _inverse_columns(tab, m, starts, lengths):  # pragma: no cover - compiled
    """The columns of T_m^-1 at the gaps (gap b: columns starts[b] .. starts[b] + lengths[b] - 1): each gap's
    first column by a solve, the others by the Gohberg-Semencul recursion from it (O(m) each); from the
    dense inverse for m <= DENSE_CELLS."""
    ng = 0
    for i in range(starts.size):
        ng += lengths[i]
    if m <= DENSE_CELLS:
        D = _dense(tab[1], tab[2], m)
        X = np.empty((m, ng))
        c = 0
        for g in range(starts.size):
            for j in range(lengths[g]):
                for i in range(m):
                    X[i, c] = D[i, starts[g] + j]
                c += 1
        return X
    E = np.zeros((m, starts.size))
    for g in range(starts.size):
        E[starts[g], g] = 1.0
    x, u = _xu(tab[1], tab[2], m)
    return _next_columns(x, u, gs_solve(tab, m, E), starts, lengths)


@numba.njit(cache=True)
def _gap_block(x, u, F, starts, lengths):  # pragma: no cover - compiled
    """T_m^-1 on the gap cells, rows and columns (the gaps starts[b] .. starts[b] + lengths[b] - 1 of the span),
    from each gap's first column F[:, b] and the generators x, u of T_m^-1: the Gohberg-Semencul recursion
    B(i, j) = B(i - 1, j - 1) + (x_i x_j - u_i u_j) / x_0 (B(0, j) = x_j) along the diagonals, on the rows it
    needs only, O(gap cells^2); the same numbers as :func:`_next_columns` there."""
    ng = 0
    for g in range(lengths.size):
        ng += lengths[g]
    out = np.empty((ng, ng))
    x0 = x[0]
    cb = 0
    for b in range(starts.size):
        sb, Lb = starts[b], lengths[b]
        ra = 0
        for a in range(starts.size):
            sa, La = starts[a], lengths[a]
            # column r of gap b is needed from row sa - (Lb - 1 - r): each column is the last moved down a row
            lo = max(0, sa - (Lb - 1))
            hi = sa + La
            col = np.empty(hi - lo)
            for i in range(lo, hi):
                col[i - lo] = F[i, b]
            for i in range(sa, hi):
                out[ra + i - sa, cb] = col[i - lo]
            for r in range(1, Lb):
                j = sb + r
                lo_r = max(0, sa - (Lb - 1 - r))
                new = np.empty(hi - lo_r)
                for i in range(lo_r, hi):
                    if i == 0:
                        new[0] = x[j]
                    else:
                        new[i - lo_r] = col[i - 1 - lo] + (x[i] * x[j] - u[i] * u[j]) / x0
                col, lo = new, lo_r
                for i in range(sa, hi):
                    out[ra + i - sa, cb + r] = col[i - lo]
            ra += La
        cb += Lb
    return out


@numba.njit(cache=True)
def _gap_solve(tab, runs, W):  # pragma: no cover - compiled
    """T_SS^-1 [1, W] by the Schur complement of the gaps in the spanning run (ToeplitzLattice._gap_solve):
    T_SS^-1 b = (T^-1 b~ - X C^-1 (T^-1 b~)_Z)_S, X = T^-1 E_Z, C = X_Z. From GAP_TWO_SOLVES gap cells on,
    C by :func:`_gap_block` and X C^-1 (...) as T^-1 (E_Z C^-1 (...)), a second solve; below, X's columns
    over the span (:func:`_inverse_columns`) and their product."""
    a, b = runs[0, 0], runs[-1, 1]
    m = b - a
    nr = runs.shape[0]
    starts = np.empty(nr - 1, np.int64)
    lengths = np.empty(nr - 1, np.int64)
    ng = 0
    for i in range(nr - 1):
        starts[i] = runs[i, 1] - a
        lengths[i] = runs[i + 1, 0] - runs[i, 1]
        ng += lengths[i]
    gaps = np.empty(ng, np.int64)
    c = 0
    for i in range(nr - 1):
        for j in range(lengths[i]):
            gaps[c] = starts[i] + j
            c += 1
    k = W.shape[1]
    cells = _stick_cells(runs)
    if ng >= GAP_TWO_SOLVES and m > DENSE_CELLS:
        # one solve of [1_S, W] on the span (zero on the gaps) and of each gap's first unit column
        wide = np.zeros((m, k + 1 + starts.size))
        for i in range(cells.size):
            wide[cells[i] - a, 0] = 1.0
            for j in range(k):
                wide[cells[i] - a, 1 + j] = W[i, j]
        for g in range(starts.size):
            wide[starts[g], k + 1 + g] = 1.0
        sol = gs_solve(tab, m, wide)
        x, u = _xu(tab[1], tab[2], m)
        XZ = _gap_block(x, u, sol[:, k + 1:], starts, lengths)
        YZ = np.empty((ng, k + 1))
        for i in range(ng):
            for j in range(k + 1):
                YZ[i, j] = sol[gaps[i], j]
        sz = _spd_solve(XZ, YZ)
        V = np.zeros((m, k + 1))
        for i in range(ng):
            for j in range(k + 1):
                V[gaps[i], j] = sz[i, j]
        corr = gs_solve(tab, m, V)
        out = np.empty((cells.size, k + 1))
        for i in range(cells.size):
            for j in range(k + 1):
                out[i, j] = sol[cells[i] - a, j] - corr[cells[i] - a, j]
        return out
    X = _inverse_columns(tab, m, starts, lengths)
    wide = np.zeros((m, k))
    for i in range(cells.size):
        for j in range(k):
            wide[cells[i] - a, j] = W[i, j]
    Yw = gs_solve(tab, m, wide)
    unit = _unit(tab, m)
    Y = np.empty((m, k + 1))
    for i in range(m):
        s = unit[i]
        for j in range(ng):
            s -= X[i, j]
        Y[i, 0] = s
        for j in range(k):
            Y[i, 1 + j] = Yw[i, j]
    XZ = np.empty((ng, ng))
    YZ = np.empty((ng, k + 1))
    for i in range(ng):
        for j in range(ng):
            XZ[i, j] = X[gaps[i], j]
        for j in range(k + 1):
            YZ[i, j] = Y[gaps[i], j]
    _sub_product(Y, X, _spd_solve(XZ, YZ))
    out = np.empty((cells.size, k + 1))
    for i in range(cells.size):
        for j in range(k + 1):
            out[i, j] = Y[cells[i] - a, j]
    return out


#: LAPACK's dposv (Cholesky factorisation and solve) from scipy's Cython LAPACK, called from compiled code by
#: its symbol (so that the compiled functions stay cacheable, which a ctypes pointer would not allow): as fast
#: as np.linalg.solve there (0.16 ms for 160 cells against 1.1 ms for the elimination of _lu_solve), without
#: the seconds numba takes to compile np.linalg in every function that uses it.
llvm.add_symbol("halfslip_dposv", get_cython_function_address("scipy.linalg.cython_lapack", "dposv"))
_DPOSV = types.ExternalFunction("halfslip_dposv", types.void(*(8 * [types.voidptr])))


@numba.njit(cache=True)
def _spd_solve(A, B):  # pragma: no cover - compiled
    """A^-1 B for a symmetric positive definite A (the Schur complements of the run solves): dposv; by
    Gaussian elimination (:func:`_lu_solve`) if the factorisation fails (A not positive definite to rounding,
    as np.linalg.solve did here until 0.4.0)."""
    n, k = B.shape
    a = np.ascontiguousarray(A).copy()  # symmetric: its rows are its columns
    b = np.ascontiguousarray(B.T).copy()  # LAPACK's column-major (n, k)
    uplo = np.array([76], np.uint8)  # 'L'
    ints = np.array([n, k, n, n, 0], np.int32)  # n, nrhs, lda, ldb, info
    _DPOSV(uplo.ctypes, ints[0:].ctypes, ints[1:].ctypes, a.ctypes, ints[2:].ctypes, b.ctypes, ints[3:].ctypes,
           ints[4:].ctypes)
    if ints[4] != 0:
        return _lu_solve(A, B)
    return np.ascontiguousarray(b.T)


@numba.njit(cache=True)
def _lu_solve(A, B):  # pragma: no cover - compiled
    """A^-1 B for the Woodbury capacitance (at most 2 x 2, not symmetric), the arrivals' sizes (active_set),
    and a Schur complement whose Cholesky factorisation failed: Gaussian elimination with partial pivoting;
    NaN where A is singular."""
    n = A.shape[0]
    a = A.copy()
    x = B.copy()
    for c in range(n):
        p = c
        for i in range(c + 1, n):
            if abs(a[i, c]) > abs(a[p, c]):
                p = i
        if p != c:
            for j in range(n):
                a[c, j], a[p, j] = a[p, j], a[c, j]
            for j in range(x.shape[1]):
                x[c, j], x[p, j] = x[p, j], x[c, j]
        if a[c, c] == 0.0:  # singular: NaN (the caller checks), not numba's ZeroDivisionError
            for i in range(n):
                for j in range(x.shape[1]):
                    x[i, j] = math.nan
            return x
        for i in range(c + 1, n):
            f = a[i, c] / a[c, c]
            if f != 0.0:
                for j in range(c + 1, n):
                    a[i, j] -= f * a[c, j]
                for j in range(x.shape[1]):
                    x[i, j] -= f * x[c, j]
    for c in range(n - 1, -1, -1):
        for j in range(x.shape[1]):
            s = x[c, j]
            for i in range(c + 1, n):
                s -= a[c, i] * x[i, j]
            x[c, j] = s / a[c, c]
    return x


@numba.njit(cache=True)
def _coldot(a, b):  # pragma: no cover - compiled
    """Column-wise dot products of two (n, k) arrays."""
    out = np.zeros(a.shape[1])
    for c in range(a.shape[1]):
        for i in range(a.shape[0]):
            out[c] += a[i, c] * b[i, c]
    return out


@numba.njit(cache=True)
def _block_solve(tab, runs, cuts, res):  # pragma: no cover - compiled
    """The block-Jacobi preconditioner: each run's rows solved by its own T_run^-1."""
    out = np.empty(res.shape)
    for r in range(runs.shape[0]):
        part = gs_solve(tab, cuts[r + 1] - cuts[r], np.ascontiguousarray(res[cuts[r]:cuts[r + 1]]))
        for i in range(part.shape[0]):
            for c in range(part.shape[1]):
                out[cuts[r] + i, c] = part[i, c]
    return out


@numba.njit(cache=True)
def _runs_product(spec, m, runs, cuts, v):  # pragma: no cover - compiled
    """T_SS v over the cells of ``runs`` (rows cut at ``cuts``), by the circulant of the contact."""
    k = v.shape[1]
    buf = np.zeros((m, k))
    for r in range(runs.shape[0]):
        for i in range(cuts[r + 1] - cuts[r]):
            for c in range(k):
                buf[runs[r, 0] + i, c] = v[cuts[r] + i, c]
    V = np.fft.rfft(buf, axis=0)
    for i in range(V.shape[0]):
        for c in range(k):
            V[i, c] *= spec[i]
    full = np.fft.irfft(V, n=m, axis=0)
    out = np.empty(v.shape)
    for r in range(runs.shape[0]):
        for i in range(cuts[r + 1] - cuts[r]):
            for c in range(k):
                out[cuts[r] + i, c] = full[runs[r, 0] + i, c]
    return out


@numba.njit(cache=True)
def _cg_runs(tab, spec, m, runs, W, tol, max_iter):  # pragma: no cover - compiled
    """Block-Jacobi preconditioned CG on the union of ``runs`` (ToeplitzLattice._cg_runs); and its
    iterations."""
    nr = runs.shape[0]
    cuts = np.zeros(nr + 1, np.int64)
    for r in range(nr):
        cuts[r + 1] = cuts[r] + runs[r, 1] - runs[r, 0]
    size, k = W.shape
    y = _block_solve(tab, runs, cuts, W)
    Ay = _runs_product(spec, m, runs, cuts, y)
    res = np.empty(W.shape)
    for i in range(size):
        for c in range(k):
            res[i, c] = W[i, c] - Ay[i, c]
    z = _block_solve(tab, runs, cuts, res)
    p = z.copy()
    rz = _coldot(res, z)
    bound = _coldot(W, W)
    for c in range(k):
        bound[c] = tol * tol * (bound[c] if bound[c] != 0.0 else 1.0)  # |r| / |W| > tol, squared
    it = 0
    while it < max_iter:
        rr = _coldot(res, res)
        going = False
        for c in range(k):
            if rr[c] > bound[c]:
                going = True
        if not going:
            break
        Ap = _runs_product(spec, m, runs, cuts, p)
        pAp = _coldot(p, Ap)
        for c in range(k):
            # a column already solved (zero residual, e.g. a zero right-hand side) stays put
            alpha = rz[c] / pAp[c] if pAp[c] > 0.0 else 0.0
            for i in range(size):
                y[i, c] += alpha * p[i, c]
                res[i, c] -= alpha * Ap[i, c]
        z = _block_solve(tab, runs, cuts, res)
        rz_new = _coldot(res, z)
        for c in range(k):
            beta = rz_new[c] / rz[c] if rz[c] > 0.0 else 0.0
            for i in range(size):
                p[i, c] = beta * p[i, c] + z[i, c]
            rz[c] = rz_new[c]
        it += 1
    return y, it


@numba.njit(cache=True)
def _with_ones(W):  # pragma: no cover - compiled
    """[1, W]."""
    out = np.empty((W.shape[0], W.shape[1] + 1))
    for i in range(W.shape[0]):
        out[i, 0] = 1.0
        for c in range(W.shape[1]):
            out[i, c + 1] = W[i, c]
    return out


#: the routes of :func:`stick_solve`
ONE_RUN, ISLANDS, GAPS, CG = 0, 1, 2, 3


@numba.njit(cache=True)
def route(runs):  # pragma: no cover - compiled
    """How :func:`stick_solve` solves on ``runs``: ONE_RUN, ISLANDS, GAPS or CG; and the longest run."""
    size = 0
    longest, most = 0, -1
    for r in range(runs.shape[0]):
        length = runs[r, 1] - runs[r, 0]
        size += length
        if length > most:
            longest, most = r, length
    if runs.shape[0] == 1:
        return ONE_RUN, 0
    span = runs[-1, 1] - runs[0, 0]
    gaps = span - size
    islands = size - most
    affordable = gaps <= GAP_CELLS or float(gaps) ** 3 <= GAP_CUBE * span  # the gaps' complement
    if islands <= ISLAND_CELLS and (ISLAND_COST * islands <= gaps or not affordable):
        return ISLANDS, longest
    if affordable:
        return GAPS, longest
    return CG, longest


@numba.njit(cache=True)
def stick_solve(tab, spec, m, runs, n, idx, C, W, cg_tol, cg_max):  # pragma: no cover - compiled
    """T'_SS^-1 [1, W] on the stick set S of ``runs`` ((k, 2) half-open in the n cells of the circulant
    (m, spec)), W of shape (|S|, k), T' = T + C at the columns ``idx`` (the end cells'; none: idx empty);
    and the CG iterations.

    Where an end cell of ``idx`` sticks, by Woodbury: (T + U V^T)^-1 y = T^-1 y - T^-1 U (I + V^T T^-1 U)^-1
    V^T T^-1 y, the columns U as more right-hand sides. The solve with T: on one run a direct
    Gohberg-Semencul solve (T_n^-1 1 from the cache); on several runs exactly, through a Schur complement,
    whichever applies first (:func:`route`) of

    * the cells I of the runs other than the longest run R (islands beside
      a stick zone), at most ISLAND_CELLS, when the gaps hold ISLAND_COST
      times as many cells or more than GAP_CELLS:
      with X = T_RR^-1 [T_RI, b_R] (one solve on R),
      y_I = (T_II - T_IR X_1)^-1 (b_I - T_IR X_2), y_R = X_2 - X_1 y_I;
    * the gaps Z between the runs, at most GAP_CELLS, in the spanning run
      (T_SS^-1 b = (T^-1 b~ - X C^-1 (T^-1 b~)_Z)_S, X = T^-1 E_Z, C = X_Z;
      X's columns by :func:`_inverse_columns`).

    Otherwise: conjugate gradients preconditioned with the exact solve of
    every run (block Jacobi; the runs are then few, long and far apart, so
    few iterations), the products with T over the n cells by FFT.

    (One function for the routes and Woodbury: numba re-optimises the code a function calls in every caller,
    so each level of calls over these solves cost about 3 s of compilation.)"""
    cells = _stick_cells(runs)
    size = cells.size
    # the end cells stick when the first run starts at the first cell, the last ends at the last
    sel = np.empty(idx.size, np.int64)
    pos = np.empty(idx.size, np.int64)
    ns = 0
    for c in range(idx.size):
        kc = idx[c]
        if kc == 0 and runs[0, 0] == 0:
            sel[ns], pos[ns] = c, 0
            ns += 1
        elif kc == n - 1 and kc > 0 and runs[-1, 1] == n:
            sel[ns], pos[ns] = c, size - 1
            ns += 1
    k = W.shape[1]
    ext = np.empty((size, k + ns))  # [W, U]
    for i in range(size):
        for c in range(k):
            ext[i, c] = W[i, c]
        for c in range(ns):
            ext[i, k + c] = C[cells[i], sel[c]]
    way, longest = route(runs)
    cg = 0
    if way == ONE_RUN:
        slot = _unit_slot(tab, size)
        if slot >= 0:  # T_n^-1 1 cached
            y = gs_solve(tab, size, ext)
            Y = np.empty((size, k + ns + 1))
            for i in range(size):
                Y[i, 0] = tab[5][slot, i]
                for c in range(k + ns):
                    Y[i, c + 1] = y[i, c]
        else:  # the column of ones in the same solve (a column more costs less than a solve of its own), kept
            Y = gs_solve(tab, size, _with_ones(ext))
            _keep_unit(tab, size, Y)
    elif way == ISLANDS:
        Y = _island_solve(tab, runs, longest, _with_ones(ext))
    elif way == GAPS:
        Y = _gap_solve(tab, runs, ext)
    else:
        Y, cg = _cg_runs(tab, spec, m, runs, _with_ones(ext), cg_tol, cg_max)
    if ns == 0:
        return Y, cg
    y = np.ascontiguousarray(Y[:, :k + 1])
    Z = np.ascontiguousarray(Y[:, k + 1:])
    cap = np.zeros((ns, ns))
    ypos = np.empty((ns, k + 1))
    for i in range(ns):
        cap[i, i] = 1.0
        for j in range(ns):
            cap[i, j] += Z[pos[i], j]
        for j in range(k + 1):
            ypos[i, j] = y[pos[i], j]
    _sub_product(y, Z, _lu_solve(cap, ypos))
    return y, cg


# -- the active set (general.GeneralSolver._active_set) ----------------------------------------------------
# Here, beside the solves it calls, and not in a module of its own: numba's cache checks only the file a
# compiled function is defined in, so a function that called these solves from another file kept the solves
# compiled into it after they changed (a stale copy beside the new one in one process: "NRT_adapt_ndarray_to_
# python: descr is NULL" in 0.4.0's development).
#
# The general solver's active set, compiled: the iterations of a take in one numba function.
#
# Primal-dual active set for the step problem (docs/general_solver.md, "Solving it"): each iteration fixes
# the slipping cells at their bounds, solves the stick set S for its shear and the rigid shift (one solve of
# T'_SS on [1, rhs], stick_solve above, with the end cells by Woodbury), and flips the cells that
# violate their bound or slip against their shear (to the tolerances of general._decision_tolerances). The
# solution is unique; the start (the memory's pattern) only sets how many iterations it takes. A pattern
# that comes back, or MAX_ACTIVE_SET iterations, returns REPEATED: the caller restarts from the projected
# gradient's pattern.
#
# Compiled (0.4.0) because an iteration is two products with T' and one stick-set solve, and in Python each
# of those was a dozen small numpy calls whose dispatch cost more than their transforms (numpy.fft inside
# numba, by rocket-fft).


@numba.njit(cache=True)
def _run_bounds(mask):  # pragma: no cover - compiled
    """(runs, 2) array of the half-open (start, stop) of the runs of True in ``mask``."""
    out = np.empty((mask.size // 2 + 1, 2), np.int64)
    k = 0
    inside = False
    for i in range(mask.size):
        if mask[i] and not inside:
            out[k, 0] = i
            inside = True
        elif not mask[i] and inside:
            out[k, 1] = i
            k += 1
            inside = False
    if inside:
        out[k, 1] = mask.size
        k += 1
    return out[:k]


def compiled_and_cached() -> bool:
    """Whether numba's cache holds a compiled :func:`active_set` for this source (read from numba's cache
    index, a private interface: True when it cannot be read, so that a caller says nothing then)."""
    try:
        return bool(active_set._cache._cache_file._load_index())
    except Exception:  # pragma: no cover - another numba
        return True


@numba.njit(cache=True)
def flips(q, s, status, qmax, qtol, stol):  # pragma: no cover - compiled
    """The active set's rule: (the next pattern, whether it is ``status`` unchanged). A stick cell whose shear q
    is over its bound by more than ``qtol`` slips the way of q; a slipping cell whose increment s opposes its
    direction by more than ``stol`` sticks."""
    new = status.copy()
    same = True
    for i in range(q.size):
        if status[i] == 0:
            if abs(q[i]) > qmax[i] + qtol:
                new[i] = 1 if q[i] > 0 else -1
                same = False
        elif status[i] * s[i] < -stol:
            new[i] = 0
            same = False
    return new, same


#: outcome codes of :func:`active_set`
CONVERGED, REPEATED = 0, 1


@numba.njit(cache=True)
def _reopen(status, qmax, total):  # pragma: no cover - compiled
    """All cells slip but the bounds cannot carry ``total`` with these signs: stick the middle one of the cells
    whose direction carries the excess (equilibrium needs a free cell)."""
    excess = -total
    for i in range(status.size):
        excess += status[i] * qmax[i]
    want = 1 if excess > 0 else -1
    count = 0
    for i in range(status.size):
        if status[i] == want:
            count += 1
    out = status.copy()
    if count == 0:
        out[status.size // 2] = 0
        return out
    c = 0
    for i in range(status.size):
        if status[i] == want:
            if c == count // 2:
                out[i] = 0
                return out
            c += 1
    return out


@numba.njit(cache=True)
def _sizes(Y, sums, rest, K, e, m1, act, qz, cells):  # pragma: no cover - compiled
    """delta and the sizes of the fitted sides ``act`` (:func:`active_set`), from the stick-set solve Y = [y1,
    y_rhs, y_phi...] (``sums`` its column sums; ``rest`` the force the stick cells carry): equilibrium, and
    each side a's match, delta (1 - K_a y1) + sum_b size_b K_a y_b - size_a m1_a = K_a qz + K_a y_rhs - e_a.
    NaN where the system is singular."""
    ka = act.size
    A = np.zeros((1 + ka, 1 + ka))
    b = np.zeros((1 + ka, 1))
    A[0, 0] = sums[0]
    b[0, 0] = rest - sums[1]
    ky = np.empty(2 + ka)
    for a in range(ka):
        A[0, 1 + a] = -sums[2 + a]
        j = act[a]
        kq = 0.0
        for i in range(qz.size):
            kq += K[j, i] * qz[i]
        for c in range(2 + ka):
            ky[c] = 0.0
        for i in range(cells.size):
            kc = K[j, cells[i]]
            for c in range(2 + ka):
                ky[c] += kc * Y[i, c]
        A[1 + a, 0] = 1.0 - ky[0]
        for c in range(ka):
            A[1 + a, 1 + c] = ky[2 + c]
        A[1 + a, 1 + a] -= m1[j]
        b[1 + a, 0] = kq + ky[1] - e[j]
    x = _lu_solve(A, b)
    return x[:, 0].copy()


@numba.njit(cache=True)
def active_set(tab, spec, m, idx, C, r, qmax, total, status, qtol, stol,
               max_iter, cg_tol, cg_max, side_of, now, phi, K, e, m1):  # pragma: no cover - compiled
    """Primal-dual active set for min 1/2 q^T T' q + q^T r, |q| <= qmax, sum q = total, from ``status``
    (the section's comment above; T' = T + the end cells' columns C at the cells ``idx``, T by the
    circulant (m, spec) of the n = r.size cells, ``tab`` the lattice's tables), with the arrivals' sizes
    found in the same iterations (below). Returns q, delta, the last pattern, T' q, the iterations, the CG
    iterations, CONVERGED or REPEATED (a pattern came back, or ``max_iter`` iterations), the sizes and
    which sides were fitted.

    The arrivals (general.GeneralSolver._take): side j's arrived cells are those with side_of = j; r
    holds their locks as M1 took them, of which ``now[j]`` is the increment. In an iteration whose
    pattern has part of the contact slipping and some of side j's arrived cells sticking, that increment
    becomes size_j phi[j] (the shape), with size_j such that the displacement at the match point,
    delta + e_j - K_j q, is size_j m1_j (K_j: T' at that point, e_j its constants): one more unknown and
    one more equation per fitted side, beside delta and equilibrium, for a pattern; the pattern and the
    sizes are found together (until 0.4.1 a fit after the active set, and a take again where the sizes
    changed the pattern). Where every arrived cell of a side slips, its locks stay M1's (fitted there, a
    contact growing with slipping edges lost 1.9 % of its dissipation against the exact method) - until
    a pattern comes back: the sized locks can make the arrived cells slip and M1's make them stick, and
    from then on a side once fitted stays fitted (its size still set by the match; the take did that
    before 0.4.1 by keeping the sizes of the round before)."""
    n = r.size
    sides = m1.size
    status = status.copy()
    seen = np.empty((max(max_iter, 1), n), np.int8)  # the patterns tried
    count = 0
    iterations = 0
    cg_total = 0
    qz = np.empty(n)
    stick = np.empty(n, np.bool_)
    reff = np.empty(n)
    sizes = np.ones(sides)
    fitted = np.zeros(sides, np.bool_)
    usable = True  # False once a fit's system is singular: the sizes stay M1's
    hold = False  # True once a pattern came back with sides switching: a fitted side stays fitted
    while True:
        iterations += 1
        free = 0
        for i in range(n):
            if status[i] == 0:
                free += 1
        if free == 0:
            status = _reopen(status, qmax, total)
            free = 1
        if not hold or not usable:
            for j in range(sides):
                fitted[j] = False
        if usable and free < n:
            for i in range(n):
                if side_of[i] >= 0 and status[i] == 0:
                    fitted[side_of[i]] = True
        act = np.empty(sides, np.int64)
        ka = 0
        for j in range(sides):
            if fitted[j]:
                act[ka] = j
                ka += 1
        for i in range(n):
            stick[i] = status[i] == 0
            qz[i] = 0.0 if stick[i] else status[i] * qmax[i]
            reff[i] = r[i]
        for a in range(ka):
            for i in range(n):
                reff[i] -= now[act[a], i]
        runs = _run_bounds(stick)
        Tz = _end_matvec(spec, m, idx, C, qz)
        cells = _stick_cells(runs)
        rhs = np.empty((cells.size, 1 + ka))
        for i in range(cells.size):
            rhs[i, 0] = -(reff[cells[i]] + Tz[cells[i]])
            for a in range(ka):
                rhs[i, 1 + a] = phi[act[a], cells[i]]
        Y, cg = stick_solve(tab, spec, m, runs, n, idx, C, rhs, cg_tol, cg_max)
        cg_total += cg
        rest = total
        for i in range(n):
            rest -= qz[i]
        sums = np.zeros(2 + ka)
        for i in range(cells.size):
            for c in range(2 + ka):
                sums[c] += Y[i, c]
        if ka > 0:
            sol = _sizes(Y, sums, rest, K, e, m1, act[:ka], qz, cells)
            if not math.isfinite(sol.sum()):  # the sizes are not determined by this pattern: M1's, from here on
                usable = False
                iterations -= 1
                continue
        else:
            sol = np.full(1, (rest - sums[1]) / sums[0])
        delta = sol[0]
        q = qz.copy()
        for i in range(cells.size):
            v = delta * Y[i, 0] + Y[i, 1]
            for a in range(ka):
                v -= sol[1 + a] * Y[i, 2 + a]
            q[cells[i]] = v
        Tq = _end_matvec(spec, m, idx, C, q)
        s = np.empty(n)  # the slip increment g - g_lock (internal datum)
        for i in range(n):
            s[i] = delta - Tq[i] - reff[i]
        for a in range(ka):
            j = act[a]
            sizes[j] = sol[1 + a]
            for i in range(n):
                s[i] -= sol[1 + a] * phi[j, i]
        new, same = flips(q, s, status, qmax, qtol, stol)
        if same:
            return q, delta, status, Tq, iterations, cg_total, CONVERGED, sizes, fitted
        repeated = False
        for j in range(count):
            if np.array_equal(seen[j], new):
                repeated = True
                break
        if repeated and sides > 0 and not hold:
            hold = True
            count = 0
        elif repeated or iterations >= max_iter:
            return q, delta, status, Tq, iterations, cg_total, REPEATED, sizes, fitted
        seen[count] = new
        count += 1
        status = new


# -- the edge windows' active set (halfslip.solvers._windows) ------------------------------------------------
# Here, beside gs_solve, for the reason active_set is (numba's cache checks only the file a compiled function is
# defined in); _windows calls it from Python between its compiled drive and slip.
@numba.njit(cache=True)
def window_active_set(tab, shift, tf, gout, lock, qmax, force, hf, status, qtol, stol,
                      max_iter):  # pragma: no cover - compiled
    """An edge window's active set (dense; _windows.EdgeWindows._window): g = gout + c - T q with T[i, j] =
    tf[|i - j|]; stuck cells g = lock, slipping ones q = s qmax with s (g - lock) >= 0; hf sum q = force, the
    offset c free. Returns q, c, the pattern and whether it converged (a pattern repeated or max_iter
    iterations: not).

    Each iteration solves the bordered system [T_SS, -1; hf 1^T, 0] on the stuck cells S. Where they are one
    run (almost always: the stick zone beside a window's slip zone), T_SS is the leading block of the fine
    kernel's Toeplitz matrix, and ``tab`` are the Levinson tables of that kernel in an internal datum
    (ToeplitzLattice of the fine cell, positive definite), T = T_int + ``shift`` (every entry: the datum's
    constant): with s = sum_S q, T_int q_S - (c - shift s) 1 = b, so q_S = y_b + c_int y_1 with [y_b, y_1] =
    T_int^-1 [b, 1] (:func:`gs_solve`, dense Gohberg-Semencul up to DENSE_CELLS), c_int from sum q_S = s and
    c = c_int + shift s: O(|S|^2) in place of an LU factorisation of |S|^3 (since 0.4.10; on the dovetail's
    window solves 99.5 -> 53.4 us an active set, the same patterns, q within 2.5e-13 of f p). Several runs:
    LU of the bordered system, as before."""
    n = gout.size
    status = status.copy()
    seen = np.empty((max_iter, n), np.int8)
    q = np.zeros(n)
    c = 0.0
    for it in range(max_iter):
        k = 0
        first, last = -1, -1
        for i in range(n):
            if status[i] == 0:
                k += 1
                if first < 0:
                    first = i
                last = i
        idx = np.empty(k, np.int64)
        k = 0
        for i in range(n):
            q[i] = 0.0 if status[i] == 0 else status[i] * qmax[i]
            if status[i] == 0:
                idx[k] = i
                k += 1
        if k > 0:
            rest = force
            for i in range(n):
                rest -= hf * q[i]
            b = np.empty(k)
            for a in range(k):
                i = idx[a]
                acc = gout[i] - lock[i]
                for j in range(n):
                    if status[j] != 0:
                        acc -= tf[abs(i - j)] * q[j]
                b[a] = acc
            if last - first + 1 == k:  # one run: the Toeplitz solve
                W = np.empty((k, 2))
                for a in range(k):
                    W[a, 0] = b[a]
                    W[a, 1] = 1.0
                Y = gs_solve(tab, k, W)
                s = rest / hf
                sum_b = 0.0
                sum_1 = 0.0
                for a in range(k):
                    sum_b += Y[a, 0]
                    sum_1 += Y[a, 1]
                c_int = (s - sum_b) / sum_1
                for a in range(k):
                    q[idx[a]] = Y[a, 0] + c_int * Y[a, 1]
                c = c_int + shift * s
            else:  # several runs: LU of the bordered system
                M = np.zeros((k + 1, k + 1))
                rhs = np.empty(k + 1)
                for a in range(k):
                    i = idx[a]
                    rhs[a] = b[a]
                    for e in range(k):
                        M[a, e] = tf[abs(i - idx[e])]
                    M[a, k] = -1.0
                    M[k, a] = hf
                rhs[k] = rest
                sol = np.linalg.solve(M, rhs)
                for a in range(k):
                    q[idx[a]] = sol[a]
                c = sol[k]
        s = np.zeros(n)  # the slipping cells' slip g - lock (the stuck cells' is not read)
        for i in range(n):
            if status[i] != 0:
                g = gout[i] + c - lock[i]
                for j in range(n):
                    g -= tf[abs(i - j)] * q[j]
                s[i] = g
        new, same = flips(q, s, status, qmax, qtol, stol)  # (the lattice's rule)
        if same:
            return q, c, status, True
        for r in range(it):
            if np.array_equal(seen[r], new):
                return q, c, status, False
        seen[it] = new
        status = new
    return q, c, status, False
