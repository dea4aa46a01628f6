"""Material points that carry the locked-in strain E(x), and how E is interpolated between them.

The points are of five kinds: the two contact EDGEs, the LATTICE (uniform,
between ``nodes`` and 2 ``nodes`` points per contact width), the BREAKpoints
of h' (E has kinks there), and points laid where E is singular: a stick edge
at which a slip zone stopped, or an old contact edge the contact grew past
after a change of loading ratio. On the open side of such a SINGULAR point b
(the old slip zone, or the arrival strip) E rises like a square root,

    E(b + side d) = E(b) + kappa sqrt(d) + lambda d + ...,

which linear interpolation between lattice points misses by O(sqrt(h)) (an
O(1) error in q next to b). So each singular point stores kappa, fitted from
exact values at a CLUSTER of points laid at b + side CLUSTER_SPAN h (k/K)^2
when it was created, and within CLUSTER_SPAN h of b (up to the next singular
point that way, beyond which a later slip zone wrote other data) E is
interpolated as

    E(x) = lin[E - kappa sqrt(|. - b|)](x) + kappa sqrt(|x - b|),

exact for the square root and the linear trend alike. :func:`augment` carries
this to the piecewise-linear machinery with virtual points graded
geometrically towards b. Clusters are dropped where a later slip zone passes
(their strain is overwritten) and thinned where linear interpolation
reproduces them (:func:`prune`); weak singular points revert to plain ones.
"""
from __future__ import annotations

import math

import numpy as np

LATTICE, EDGE, BREAK, CLUSTER, SINGULAR_LEFT, SINGULAR_RIGHT = range(6)

#: Points of the cluster laid on the open side of a new singular point, at b +- CLUSTER_SPAN h (k/K)^2.
CLUSTER_POINTS = 12
#: Extent of a cluster and of the square-root region, in lattice spacings h.
CLUSTER_SPAN = 16.0
#: Virtual points of a region are graded geometrically by this ratio, from CLUSTER_SPAN h down to ...
GRADING = 1.25
#: ... this fraction of h.
GRADING_FLOOR = 1e-5
#: Points are dropped, and singular points revert, where the change in E is below this
#: fraction of max abs(E) (the lattice's own interpolation error is about 1e-5 of it).
PRUNE_TOL = 1e-6
#: At most this many singular points are kept (the strongest, by kappa sqrt(h)).
MAX_SINGULAR = 24

_VIRTUAL = CLUSTER_SPAN * GRADING ** -np.arange(0, int(math.log(CLUSTER_SPAN / GRADING_FLOOR) / math.log(GRADING)) + 1)


def cluster_offsets(h: float) -> np.ndarray:
    """Distances of a cluster's points from its singular point, shape (CLUSTER_POINTS,)."""
    return CLUSTER_SPAN * h * (np.arange(1, CLUSTER_POINTS + 1) / CLUSTER_POINTS) ** 2


def anchors(X: np.ndarray, kind: np.ndarray, h: float) -> np.ndarray:
    """Index of the singular point whose square-root region holds each point (-1: none).

    The region of a singular point b runs CLUSTER_SPAN h from it on its open
    side, but stops short of the next singular point that way: that one marks
    where a later slip zone overwrote the strain. A singular point anchors itself.

    Parameters
    ----------
    X : ndarray, shape (n,)
    kind : ndarray of int, shape (n,)
    h : float

    Returns
    -------
    ndarray of int, shape (n,)
    """
    anchor = np.full(X.size, -1)
    dist = np.full(X.size, np.inf)
    span = CLUSTER_SPAN * h
    sing = np.flatnonzero(kind >= SINGULAR_LEFT)
    for i in sing:
        if kind[i] == SINGULAR_LEFT:
            d = X[i] - X
            stop = sing[sing < i]
            limit = X[i] - X[stop[-1]] if stop.size else math.inf
        else:
            d = X - X[i]
            stop = sing[sing > i]
            limit = X[stop[0]] - X[i] if stop.size else math.inf
        inside = (d >= 0.0) & (d <= span) & (d < limit) & (d < dist)
        anchor[inside] = i
        dist[inside] = d[inside]
    return anchor


def fit_kappa(X: np.ndarray, kind: np.ndarray, h: float, E: np.ndarray, which: np.ndarray) -> np.ndarray:
    """Square-root coefficients of E at the singular points ``which``.

    Least squares of E(b + side d) - E(b) = kappa sqrt(d) + lambda d over the
    (up to three) nearest points of the region; with a single point, lambda is
    taken from the slope on the closed side.

    Parameters
    ----------
    X, kind, E : ndarray, shape (n,)
    h : float
    which : ndarray of int, shape (m,)
        Indices of singular points.

    Returns
    -------
    ndarray, shape (m,)
    """
    anchor = anchors(X, kind, h)
    out = np.zeros(which.size)
    for k, i in enumerate(which):
        side = -1 if kind[i] == SINGULAR_LEFT else 1
        mine = np.flatnonzero((anchor == i) & (np.arange(X.size) != i))
        mine = mine[np.argsort(np.abs(X[mine] - X[i]))][:3]
        if mine.size == 0:
            continue
        d = np.abs(X[mine] - X[i])
        y = E[mine] - E[i]
        if mine.size >= 2:
            basis = np.stack([np.sqrt(d), d], axis=1)
            out[k] = np.linalg.lstsq(basis, y, rcond=None)[0][0]
        else:
            j = i - side
            slope = side * (E[i] - E[j]) / (X[i] - X[j]) if 0 <= j < X.size else 0.0
            out[k] = (y[0] - slope * d[0]) / math.sqrt(d[0])
    return out


def augment(X: np.ndarray, kind: np.ndarray, h: float, fields):
    """Insert virtual points that carry the square-root interpolation of each field.

    Parameters
    ----------
    X, kind : ndarray, shape (n,)
    h : float
    fields : sequence of (values, kappa), each ndarray of shape (n,)
        kappa is the square-root coefficient at singular points (0 elsewhere).

    Returns
    -------
    Xa : ndarray, shape (m,)
    values : list of ndarray, shape (m,) each
    """
    sing = np.flatnonzero(kind >= SINGULAR_LEFT)
    if sing.size == 0:
        return X, [v for v, _ in fields]
    anchor = anchors(X, kind, h)
    xs = [X]
    vs = [[v] for v, _ in fields]
    for i in sing:
        mine = np.flatnonzero(anchor == i)
        if mine.size < 2:
            continue
        side = -1 if kind[i] == SINGULAR_LEFT else 1
        reach = float(np.max(np.abs(X[mine] - X[i])))
        d = h * _VIRTUAL
        d = d[d < reach]
        xv = X[i] + side * d
        xs.append(xv)
        root_data = np.sqrt(np.abs(X[mine] - X[i]))
        order = np.argsort(X[mine])
        for (values, kappa), out in zip(fields, vs):
            corrected = values[mine] - kappa[i] * root_data
            out.append(np.interp(xv, X[mine][order], corrected[order]) + kappa[i] * np.sqrt(d))
    Xa = np.concatenate(xs)
    order = np.argsort(Xa, kind="stable")
    return Xa[order], [np.concatenate(v)[order] for v in vs]


def prune(X, kind, h, E, kappa, G):
    """Drop extra points the interpolation reproduces; revert weak singular points.

    A singular point reverts to a plain CLUSTER point when kappa sqrt(h) is
    below PRUNE_TOL max abs(E), or when it is not among the MAX_SINGULAR
    strongest; a CLUSTER point is dropped when the interpolation of its kept
    left and its right neighbour (corrected by the square root inside a
    region) matches its E to PRUNE_TOL max abs(E).

    Parameters
    ----------
    X, kind, E, kappa, G : ndarray, shape (n,)
    h : float

    Returns
    -------
    X, kind, E, kappa, G : ndarray, shape (m,) each
    """
    if not np.any(kind >= CLUSTER):
        return X, kind, E, kappa, G
    tol = PRUNE_TOL * float(np.max(np.abs(E)))
    kind = kind.copy()
    kappa = kappa.copy()
    sing = np.flatnonzero(kind >= SINGULAR_LEFT)
    if sing.size:
        strength = np.abs(kappa[sing]) * math.sqrt(h)
        weak = strength <= tol
        if sing.size - np.sum(weak) > MAX_SINGULAR:
            weak |= strength < np.sort(strength[~weak])[-MAX_SINGULAR]
        kind[sing[weak]] = CLUSTER
        kappa[sing[weak]] = 0.0
    anchor = anchors(X, kind, h)
    root = np.zeros(X.size)
    inside = anchor >= 0
    root[inside] = kappa[anchor[inside]] * np.sqrt(np.abs(X[inside] - X[anchor[inside]]))
    C = E - root
    keep = np.ones(X.size, dtype=bool)
    last = -1
    for i in range(X.size):
        if kind[i] == CLUSTER and last >= 0 and i + 1 < X.size and anchor[last] == anchor[i] == anchor[i + 1]:
            nxt = i + 1
            w = (X[i] - X[last]) / (X[nxt] - X[last])
            if abs(C[i] - (C[last] + w * (C[nxt] - C[last]))) <= tol:
                keep[i] = False
                continue
        last = i
    return X[keep], kind[keep], E[keep], kappa[keep], G[keep]


def merge(X, kind, tol, *values):
    """Sort points and drop near-duplicates (within ``tol``), keeping edges, then the higher kind.

    No point may sit on or beyond an edge except the edges themselves.

    Returns
    -------
    X, kind, values : ndarray (m,), ndarray (m,), tuple of ndarray (m,)
    """
    priority = np.where(kind == EDGE, 10, kind)
    order = np.lexsort((-priority, X))
    X, kind, priority = X[order], kind[order], priority[order]
    values = tuple(v[order] for v in values)
    keep = np.ones(X.size, dtype=bool)
    last = 0
    for i in range(1, X.size):
        if X[i] - X[last] <= tol:
            if priority[i] > priority[last]:
                keep[last] = False
                last = i
            else:
                keep[i] = False
        else:
            last = i
    edges = kind == EDGE
    lo, hi = X[edges].min(), X[edges].max()
    keep &= edges | ((X > lo + tol) & (X < hi - tol))
    return X[keep], kind[keep], tuple(v[keep] for v in values)
