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
out to rounding for the interpolated data.
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


def linear_moments(x: np.ndarray, y: np.ndarray, b1: float, b2: float) -> tuple[float, float]:
    """Exact (gamma_0, gamma_1) of the piecewise-linear interpolant of (x, y) on [b1, b2].

    Parameters
    ----------
    x : ndarray, shape (n,)
        Increasing abscissae with x[0] <= b1 < b2 <= x[-1].
    y : ndarray, shape (n,)
        Values.
    b1, b2 : float
        The interval.

    Returns
    -------
    gamma0, gamma1 : float
        (1/pi) int G dth and (2/pi) int G cos th dth, x = m + r cos th.
    """
    lo = np.searchsorted(x, b1, side="right")
    hi = np.searchsorted(x, b2, side="left")
    y1 = np.interp(b1, x, y)
    y2 = np.interp(b2, x, y)
    xs = np.concatenate(([b1], x[lo:hi], [b2]))
    ys = np.concatenate(([y1], y[lo:hi], [y2]))
    m = 0.5 * (b1 + b2)
    r = 0.5 * (b2 - b1)
    sin_th = np.sqrt(np.maximum((xs - b1) * (b2 - xs), 0.0)) / r
    cos_th = np.clip((xs - m) / r, -1.0, 1.0)
    th = np.arctan2(sin_th, cos_th)
    dx = np.diff(xs)
    keep = dx > 0.0
    slope = np.where(keep, np.diff(ys) / np.where(keep, dx, 1.0), 0.0)
    alpha = ys[:-1] + slope * (m - xs[:-1])
    beta = slope * r
    # piece j runs from th[j] (left end, larger angle) down to th[j + 1]
    d_th = th[:-1] - th[1:]
    d_sin = sin_th[:-1] - sin_th[1:]
    sin2 = 2.0 * sin_th * cos_th
    d_sin2 = sin2[:-1] - sin2[1:]
    gamma0 = float(np.sum(alpha * d_th + beta * d_sin)) / math.pi
    gamma1 = 2.0 * float(np.sum(alpha * d_sin + beta * (0.5 * d_th + 0.25 * d_sin2))) / math.pi
    return gamma0, gamma1


def bounded_inside(gamma: np.ndarray, t: np.ndarray) -> np.ndarray:
    """phi(t) = sqrt(1 - t^2) sum_{k>=1} gamma_k U_{k-1}(t) for |t| <= 1 (0 beyond).

    Parameters
    ----------
    gamma : ndarray, shape (n,)
        Coefficients gamma_0..gamma_{n-1} (gamma_0 is ignored).
    t : ndarray, any shape

    Returns
    -------
    ndarray, shape of t
    """
    t = np.asarray(t, dtype=float)
    th = np.arccos(np.clip(t, -1.0, 1.0))
    c = np.array(gamma, dtype=float)
    c[0] = 0.0
    # sum gamma_k sin(k th) = Im sum gamma_k z^k, z = exp(i th)
    out = np.polynomial.polynomial.polyval(np.exp(1j * th), c).imag
    return np.where(np.abs(t) <= 1.0, out, 0.0)


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
    c = np.array(gamma, dtype=float)
    c[0] = 0.0
    return np.polynomial.polynomial.polyval(_rho(t), c)


def _rho(t: np.ndarray) -> np.ndarray:
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
        rho = float(_rho(np.array(t)))
        lam0 = 0.25 * rho * rho - 0.5 * math.log(abs(rho)) - 0.5 * _LN2
        lam = -0.5 * (rho**k / k - rho ** (k + 2) / (k + 2))
    return float(a[0] * lam0 + np.dot(a[1:], lam))
