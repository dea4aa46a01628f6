"""The general solver's active set, compiled: the iterations of a take in one numba function.

Primal-dual active set for the step problem (docs/general_solver.md, "Solving it"): each iteration fixes
the slipping cells at their bounds, solves the stick set S for its shear and the rigid shift (one solve of
T'_SS on [1, rhs], _toeplitz.stick_solve with the end cells by Woodbury), and flips the cells that
violate their bound or slip against their shear (to the tolerances of general._decision_tolerances). The
solution is unique; the start (the memory's pattern) only sets how many iterations it takes. A pattern
that comes back, or MAX_ACTIVE_SET iterations, returns REPEATED: the caller restarts from the projected
gradient's pattern.

Compiled (0.4.0) because an iteration is two products with T' and one stick-set solve, and in Python each
of those was a dozen small numpy calls whose dispatch cost more than their transforms (numpy.fft inside
numba, by rocket-fft).
"""
from __future__ import annotations

import numba
import numpy as np

from ._toeplitz import _end_matvec, _stick_cells, stick_solve


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
    """The active set's rule: the stick cells whose shear q is over its bound by more than ``qtol``, and the
    slipping cells whose increment s opposes their direction by more than ``stol``, as two masks."""
    over = np.zeros(q.size, np.bool_)
    back = np.zeros(q.size, np.bool_)
    for i in range(q.size):
        if status[i] == 0:
            over[i] = abs(q[i]) > qmax[i] + qtol
        else:
            back[i] = status[i] * s[i] < -stol
    return over, back


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
def active_set(tab, spec, m, idx, C, r, qmax, total, status, qtol, stol,
               max_iter, cg_tol, cg_max):  # pragma: no cover - compiled
    """Primal-dual active set for min 1/2 q^T T' q + q^T r, |q| <= qmax, sum q = total, from ``status``
    (the module's docstring; T' = T + the end cells' columns C at the cells ``idx``, T by the circulant
    (m, spec) of the n = r.size cells, ``tab`` the lattice's tables). Returns q, delta, the last pattern, T' q, the iterations, the CG
    iterations and CONVERGED or REPEATED (a pattern came back, or ``max_iter`` iterations)."""
    n = r.size
    status = status.copy()
    seen = np.empty((max(max_iter, 1), n), np.int8)  # the patterns tried
    count = 0
    iterations = 0
    cg_total = 0
    qz = np.empty(n)
    stick = np.empty(n, np.bool_)
    while True:
        iterations += 1
        free = 0
        for i in range(n):
            if status[i] == 0:
                free += 1
        if free == 0:
            status = _reopen(status, qmax, total)
        for i in range(n):
            stick[i] = status[i] == 0
            qz[i] = 0.0 if stick[i] else status[i] * qmax[i]
        runs = _run_bounds(stick)
        Tz = _end_matvec(spec, m, idx, C, qz)
        cells = _stick_cells(runs)
        rhs = np.empty((cells.size, 1))
        for i in range(cells.size):
            rhs[i, 0] = -(r[cells[i]] + Tz[cells[i]])
        Y, cg = stick_solve(tab, spec, m, runs, n, idx, C, rhs, cg_tol, cg_max)
        cg_total += cg
        rest, ones, part = total, 0.0, 0.0
        for i in range(n):
            rest -= qz[i]
        for i in range(cells.size):
            part += Y[i, 1]
            ones += Y[i, 0]
        delta = (rest - part) / ones
        q = qz.copy()
        for i in range(cells.size):
            q[cells[i]] = delta * Y[i, 0] + Y[i, 1]
        Tq = _end_matvec(spec, m, idx, C, q)
        s = np.empty(n)  # the slip increment g - g_lock (internal datum)
        for i in range(n):
            s[i] = delta - Tq[i] - r[i]
        over, back = flips(q, s, status, qmax, qtol, stol)
        new = status.copy()
        same = True
        for i in range(n):
            if over[i]:
                new[i] = 1 if q[i] > 0 else -1
                same = False
            elif back[i]:
                new[i] = 0
                same = False
        if same:
            return q, delta, status, Tq, iterations, cg_total, CONVERGED
        repeated = False
        for j in range(count):
            if np.array_equal(seen[j], new):
                repeated = True
                break
        if repeated or iterations >= max_iter:
            return q, delta, status, Tq, iterations, cg_total, REPEATED
        seen[count] = new
        count += 1
        status = new
