"""Chebyshev tools for the Cauchy singular integral equation of the stick zone.

On an interval [b1, b2] = [m - r, m + r], x = m + r t, the dominant equation

    (1/pi) PV int_{-1}^{1} phi(tau) / (t - tau) dtau = G(t),   -1 < t < 1,

has a solution bounded at both ends only if gamma_0 = 0, and then

    phi(t) = sqrt(1 - t^2) sum_{k>=1} gamma_k U_{k-1}(t),
    int phi dt = (pi/2) gamma_1,

where gamma_k are the Chebyshev coefficients of G = sum gamma_k T_k, i.e.

    gamma_0 = (1/pi) int_0^pi G(cos th) dth,
    gamma_k = (2/pi) int_0^pi G(cos th) cos(k th) dth.

The identities used (k >= 0):

    (1/pi) PV int sqrt(1 - tau^2) U_k(tau) / (t - tau) dtau = T_{k+1}(t)     |t| < 1
                                                           = rho^{k+1}      |t| > 1
    rho = t - sgn(t) sqrt(t^2 - 1)                          (|rho| < 1)

    (1/pi) int sqrt(1 - tau^2) U_k(tau) ln|t - tau| dtau = Lambda_k(t),
    Lambda_0 = T_2/4 - ln2/2,  Lambda_k = T_{k+2}/(2(k+2)) - T_k/(2k)   |t| <= 1
    Lambda_0 = rho^2/4 - ln|rho|/2 - ln2/2,
    Lambda_k = -(rho^k/k - rho^{k+2}/(k+2))/2                           |t| > 1.

The consistency condition gamma_0 = 0 and the force (pi/2) gamma_1 are the
two equations that fix the stick-zone edges; for a G that is piecewise linear
in x they are evaluated exactly (:func:`linear_moments`), so the edges come
out to rounding for the interpolated data. For such a G the bounded solution
and its Hilbert transform outside the interval are also closed forms
(:func:`bounded_linear`, :func:`hilbert_linear_outside`); the series serves
the outside strain away from the interval's ends, where it converges fast.
"""
from __future__ import annotations

import math

import numpy as np
from scipy import fft

_LN2 = math.log(2.0)


def chebyshev_nodes(n: int) -> np.ndarray:
    """First-kind Chebyshev points t_i = cos((2i - 1) pi / (2n)), i = 1..n, shape (n,), decreasing."""
    return np.cos((np.arange(n) + 0.5) * math.pi / n)


def coefficients(values: np.ndarray) -> np.ndarray:
    """Chebyshev coefficients gamma_k, k = 0..n-1, of samples at :func:`chebyshev_nodes`.

    Parameters
    ----------
    values : ndarray, shape (n,)

    Returns
    -------
    ndarray, shape (n,)
    """
    n = values.size
    gamma = fft.dct(values, type=2) / n
    gamma[0] *= 0.5
    return gamma


def linear_moments(x: np.ndarray, y: np.ndarray, b1: float, b2: float, derivatives: bool = False):
    """Exact (gamma_0, gamma_1) of the piecewise-linear interpolant of (x, y) on [b1, b2].

    With x = m + r cos th, and G' = sigma_j on piece j,

        d gamma_0 / d b1,2 = (1/2pi) int G' (1 -+ cos th) dth,
        d gamma_1 / d b1,2 = (1/pi)  int G' (1 -+ cos th) cos th dth

    (the interval [0, pi] in th does not move), evaluated in the same pass.

    Parameters
    ----------
    x : ndarray, shape (n,)
        Increasing abscissae with x[0] <= b1 < b2 <= x[-1].
    y : ndarray, shape (n,) or (n, k)
        Values (k functions at once).
    b1, b2 : float
        The interval.
    derivatives : bool
        Also return the derivatives with respect to b1 and b2.

    Returns
    -------
    gamma : ndarray, shape (2,) or (2, k)
        gamma_0 = (1/pi) int G dth and gamma_1 = (2/pi) int G cos th dth.
    d_gamma : ndarray, shape (2, 2) or (2, 2, k), only with ``derivatives``
        d_gamma[i, j] = d gamma_i / d b_{j+1}.
    """
    lo = int(np.searchsorted(x, b1, side="right"))
    hi = int(np.searchsorted(x, b2, side="left"))
    xs = np.concatenate(([b1], x[lo:hi], [b2]))
    ys = np.concatenate(([_lerp(x, y, b1, lo)], y[lo:hi], [_lerp(x, y, b2, hi)]))
    m = 0.5 * (b1 + b2)
    r = 0.5 * (b2 - b1)
    sin_th = np.sqrt(np.maximum((xs - b1) * (b2 - xs), 0.0)) / r
    cos_th = np.clip((xs - m) / r, -1.0, 1.0)
    th = np.arctan2(sin_th, cos_th)
    dx = np.diff(xs)
    # piece j runs from th[j] (its left end, the larger angle) down to th[j + 1]
    d_th = th[:-1] - th[1:]
    d_sin = sin_th[:-1] - sin_th[1:]
    sin2 = sin_th * cos_th
    d_half = 0.5 * d_th + 0.5 * (sin2[:-1] - sin2[1:])  # int cos^2
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = np.where(dx > 0.0, 1.0 / dx, 0.0)
    slope = (np.diff(ys, axis=0).T * inv).T
    alpha = ys[:-1] + (slope.T * (m - xs[:-1])).T
    w = np.stack([d_th, d_sin, d_half])  # (3, pieces)
    A = w @ alpha  # (3,) or (3, k): int alpha, int alpha cos, int alpha cos^2
    S = w @ slope  # the same with sigma
    gamma = np.stack([A[0] + r * S[1], 2.0 * (A[1] + r * S[2])]) / math.pi
    if not derivatives:
        return gamma
    d_gamma = np.stack([
        np.stack([S[0] - S[1], S[0] + S[1]]) / (2.0 * math.pi),
        np.stack([S[1] - S[2], S[1] + S[2]]) / math.pi,
    ])
    return gamma, d_gamma


def _lerp(x: np.ndarray, y: np.ndarray, at: float, i: int) -> np.ndarray:
    """Linear interpolation of rows of y at ``at``, x[i - 1] <= at <= x[i]."""
    i = min(max(i, 1), x.size - 1)
    w = (at - x[i - 1]) / (x[i] - x[i - 1])
    return y[i - 1] + w * (y[i] - y[i - 1])


def bounded_linear(s: np.ndarray, g: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Exact bounded solution phi(t) for G piecewise linear through (s, g) on [-1, 1].

    With G(s) = a + b s + sum_k c_k abs(s - s_k) (c_k half the slope jumps at
    the interior knots) and t = cos th0, s_k = cos th_k,

        phi(t) = b sin th0 + sum_k c_k [ sin th0 (2 th_k - pi) / pi
                 + (2/pi) (t - s_k) ln abs(sin((th0 + th_k)/2) / sin((th0 - th_k)/2)) ],

    which is (sqrt(1 - t^2)/pi) PV int G(s) / (sqrt(1 - s^2)(s - t)) ds: the
    solution bounded at both ends for G - gamma_0.

    Parameters
    ----------
    s : ndarray, shape (m,)
        Knots, increasing, s[0] = -1, s[-1] = 1.
    g : ndarray, shape (m,)
        G at the knots.
    t : ndarray, shape (n,)
        Points in [-1, 1].

    Returns
    -------
    ndarray, shape (n,)
    """
    t = np.clip(np.asarray(t, dtype=float), -1.0, 1.0)
    ds = np.diff(s)
    keep = ds > 0.0
    slope = np.diff(g)[keep] / ds[keep]
    knots = s[:-1][keep][1:]
    c = 0.5 * np.diff(slope)
    b = slope[0] + np.sum(c)
    sin0 = np.sqrt(np.maximum(1.0 - t * t, 0.0))
    thk = np.arccos(knots)
    sink = np.sqrt(np.maximum(1.0 - knots * knots, 0.0))
    out = sin0 * (b + np.sum(c * (2.0 * thk - math.pi)) / math.pi)
    # ln|sin((th0 + thk)/2) / sin((th0 - thk)/2)| = ln|(1 - t s_k + sin th0 sin thk) / (t - s_k)|
    diff = t[:, None] - knots
    with np.errstate(divide="ignore", invalid="ignore"):
        term = diff * np.log(np.abs((1.0 - t[:, None] * knots + sin0[:, None] * sink) / diff))
    term = np.where(np.isfinite(term), term, 0.0)
    return out + (2.0 / math.pi) * (term @ c)


def hilbert_linear_outside(s: np.ndarray, g: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Exact sum_{k>=1} gamma_k rho^k for G piecewise linear through (s, g), abs(t) > 1.

    For t > 1, with G = a + b s + sum_k c_k abs(s - s_k) and s_k = cos th_k,

        sgn(t) sqrt(t^2 - 1) (1/pi) int G(s) / (sqrt(1 - s^2)(t - s)) ds
            = a + b rho + sum_k c_k [ sqrt(t^2 - 1)(pi - 2 th_k)/pi
                                      + (t - s_k)(4 atan(sqrt((t+1)/(t-1)) tan(th_k/2)) - pi)/pi ],

    which equals gamma_0 + sum_{k>=1} gamma_k rho^k; gamma_0 is subtracted.
    t < -1 follows by reflection (s -> -s). This is the outside strain of the
    bounded solution, accurate right up to the interval's end where the
    Chebyshev series converges slowly.

    Parameters
    ----------
    s, g : ndarray, shape (m,)
        Knots (s[0] = -1, s[-1] = 1) and values.
    t : ndarray, shape (n,), abs(t) > 1

    Returns
    -------
    ndarray, shape (n,)
    """
    t = np.asarray(t, dtype=float)
    out = np.empty(t.shape)
    right = t > 0.0
    if np.any(right):
        out[right] = _outside_right(s, g, t[right])
    if np.any(~right):
        out[~right] = _outside_right(-s[::-1], g[::-1], -t[~right])
    return out


def _outside_right(s, g, t):
    ds = np.diff(s)
    keep = ds > 0.0
    slope = np.diff(g)[keep] / ds[keep]
    knots = s[:-1][keep][1:]
    c = 0.5 * np.diff(slope)
    b = slope[0] + np.sum(c)
    a = g[0] + b - np.sum(c * (knots + 1.0))
    thk = np.arccos(knots)
    # gamma_0 of G: (1/pi) int (a + b cos th + sum c_k abs(cos th - s_k)) dth
    gamma0 = a + np.sum(c * (2.0 * np.sin(thk) + (math.pi - 2.0 * thk) * knots)) / math.pi
    root = np.sqrt(np.maximum(t * t - 1.0, 0.0))
    with np.errstate(divide="ignore"):
        stretch = np.sqrt((t + 1.0) / np.maximum(t - 1.0, 0.0))
    hinge = root[:, None] * (math.pi - 2.0 * thk) / math.pi + (t[:, None] - knots) * (
        4.0 * np.arctan(stretch[:, None] * np.tan(0.5 * thk)) - math.pi
    ) / math.pi
    return a + b / (t + root) + hinge @ c - gamma0


def hilbert_outside(gamma: np.ndarray, t: np.ndarray) -> np.ndarray:
    """(1/pi) int phi(tau) / (t - tau) dtau = sum_{k>=1} gamma_k rho^k for |t| >= 1.

    Parameters
    ----------
    gamma : ndarray, shape (n,)
    t : ndarray, any shape, abs(t) >= 1

    Returns
    -------
    ndarray, shape of t
    """
    r = rho(t)
    big = float(np.max(np.abs(r), initial=0.0))
    terms = gamma.size if big >= 1.0 else min(gamma.size, 2 + int(math.log(1e-17) / math.log(max(big, 1e-300))))
    c = np.array(gamma[:terms], dtype=float)
    c[0] = 0.0
    return np.polynomial.polynomial.polyval(r, c)


def rho(t: np.ndarray) -> np.ndarray:
    """rho = t - sgn(t) sqrt(t^2 - 1) for abs(t) >= 1, computed without cancellation."""
    t = np.asarray(t, dtype=float)
    root = np.sqrt(np.maximum(t * t - 1.0, 0.0))
    # t - sgn(t) sqrt(t^2 - 1) = sgn(t) / (|t| + sqrt(t^2 - 1)), without cancellation
    return np.sign(t) / (np.abs(t) + root)


def u_coefficients(values: np.ndarray) -> np.ndarray:
    """a_k with phi(cos th_j) = sum_k a_k sin((k + 1) th_j), th_j = j pi / (n + 1), j = 1..n.

    That is phi(t) = sqrt(1 - t^2) sum_k a_k U_k(t) interpolated at the
    second-kind points :func:`u_nodes`.

    Parameters
    ----------
    values : ndarray, shape (n,)
        phi at ``u_nodes(n)``.

    Returns
    -------
    ndarray, shape (n,)
    """
    n = values.size
    return fft.dst(values, type=1) / (n + 1)


def u_nodes(n: int) -> np.ndarray:
    """Second-kind Chebyshev points cos(j pi / (n + 1)), j = 1..n, shape (n,), decreasing."""
    return np.cos(np.arange(1, n + 1) * math.pi / (n + 1))


def log_potential(a: np.ndarray, t: float) -> float:
    """(1/pi) int sqrt(1 - tau^2) sum_k a_k U_k(tau) ln|t - tau| dtau, any real t.

    Parameters
    ----------
    a : ndarray, shape (n,)
    t : float

    Returns
    -------
    float
    """
    k = np.arange(1, a.size)
    if abs(t) <= 1.0:
        th = math.acos(t)
        lam0 = 0.5 * t * t - 0.25 - 0.5 * _LN2
        lam = np.cos((k + 2) * th) / (2.0 * (k + 2)) - np.cos(k * th) / (2.0 * k)
    else:
        r = float(rho(np.array(t)))
        lam0 = 0.25 * r * r - 0.5 * math.log(abs(r)) - 0.5 * _LN2
        lam = -0.5 * (r**k / k - r ** (k + 2) / (k + 2))
    return float(a[0] * lam0 + np.dot(a[1:], lam))
