"""Compiled marching of the exact level memory for a Hertz contact, extents only.

The same arithmetic as ``ExactMemory.advance_memory`` with the closed-form
level integrals of ``levels.HertzLevels``, on preallocated knot arrays, so a
long fretting history costs a fraction of a microsecond per step. Used by the
simulator when numba is installed, the profile is Hertz and no per-point field
is stored; the Python path is the reference and the tests hold the two to
1e-12.
"""
from __future__ import annotations

import math

import numpy as np

try:
    from numba import njit
except ImportError:  # pragma: no cover - numba is a dependency; keep the Python path usable without it
    njit = None

_EPS = float(np.finfo(float).eps)


def _lam(P, ln_alpha):
    if P <= 0.0:
        return 0.0
    return P * ln_alpha + 0.5 * (P * math.log(P) - P)


def _psi(P, ln_alpha):
    if P <= 0.0:
        return 0.0
    return 0.5 * P * P * ln_alpha + 0.25 * P * P * math.log(P) - 0.375 * P * P


def _xi(P, ln_alpha):
    if P <= 0.0:
        return 0.0
    return 0.5 * P * P * ln_alpha + 0.25 * P * P * math.log(P) - 0.125 * P * P


def _kernel_integral(alpha, beta, lo, hi, ln_alpha):
    width = hi - lo
    if abs(beta) * width > 1e-7 * max(abs(alpha), hi):
        t1 = (_psi(alpha + beta * hi, ln_alpha) - _psi(alpha + beta * lo, ln_alpha)) / beta
    else:
        t1 = _lam(alpha + beta * 0.5 * (lo + hi), ln_alpha) * width
    return (t1 - (_psi(hi, ln_alpha) - _psi(lo, ln_alpha))
            - alpha * (_lam(hi, ln_alpha) - _lam(lo, ln_alpha))
            - (beta - 1.0) * (_xi(hi, ln_alpha) - _xi(lo, ln_alpha)))


def _dissipation(P, W, n, P1, Q1, s, f, A, ln_alpha):
    P0 = P[n - 1]
    Q0 = W[n - 1]
    dP = P1 - P0
    c0 = s * Q0 - f * P0
    c1 = s * Q1 - f * P1
    dc = c1 - c0
    if dc <= 0.0:
        return 0.0
    c_end = min(c1, 0.0)
    total = 0.0
    for j in range(n - 2, -1, -1):
        Pa = P[j]
        Pb = P[j + 1]
        if s * W[j + 1] - f * Pb >= c_end:
            break
        if Pb <= Pa:
            continue
        w = (W[j + 1] - W[j]) / (Pb - Pa)
        slope = f - s * w
        if slope <= 1e-12 * f:
            continue
        Ha = s * W[j] - f * Pa
        lo = max(Pa, Pa + (Ha - c_end) / slope)
        hi = min(Pb, Pa + (Ha - c0) / slope)
        if lo >= hi:
            continue
        beta = -dP * slope / dc
        alpha = P0 + dP * (Ha + slope * Pa - c0) / dc
        if dP < 0.0:
            if beta < 1.0:
                hi = min(hi, alpha / (1.0 - beta))
            elif beta > 1.0:
                lo = max(lo, alpha / (1.0 - beta))
            elif alpha <= 0.0:
                continue
            if lo >= hi:
                continue
        total += f * slope * max(_kernel_integral(alpha, beta, lo, hi, ln_alpha), 0.0)
    return A / math.pi * total


def _march(P, W, L, C, n, loads_P, loads_Q, f, A, ln_alpha, D, out_level, out_regime, out_D, out_top_W,
           out_top_C):
    """March knot arrays (P, W, L, C; first n valid) through the loads; returns n.

    Per step writes the stick level, the regime (0..3), the cumulative
    dissipation (from D), and W, C at the top (for the shift). The arrays must
    hold n + 2 len(loads) knots.
    """
    for i in range(loads_P.shape[0]):
        P1 = max(loads_P[i], 0.0)
        Q1 = loads_Q[i]
        P0 = P[n - 1]
        Q0 = W[n - 1]
        # trial value at P1 without slip (extension or truncation), not yet applied
        m = n
        if P1 > P0:
            k = (Q1 - Q0) / (P1 - P0)
            w = min(max(k, -f), f)
            W_trial = Q0 + w * (P1 - P0)
        elif P1 < P0:
            while m > 1 and P[m - 2] >= P1:
                m -= 1
            if m == 1:
                W_trial = W[0]
            else:
                w = (W[m - 1] - W[m - 2]) / (P[m - 1] - P[m - 2])
                W_trial = W[m - 2] + w * (P1 - P[m - 2])
        else:
            W_trial = Q0
        scale = f * max(P0, P1) + abs(Q1) + abs(Q0)
        mismatch = Q1 - W_trial
        slipping = abs(mismatch) > 16 * _EPS * scale
        s = 1.0 if mismatch > 0 else -1.0
        dissipated = _dissipation(P, W, n, P1, Q1, s, f, A, ln_alpha) if slipping else 0.0
        # apply the extension / truncation
        if P1 > P0:
            L1 = _lam(P1, ln_alpha)
            through = W[n - 2] + (W_trial - W[n - 2]) * (P0 - P[n - 2]) / (P1 - P[n - 2]) if n > 1 else math.inf
            if abs(through - Q0) <= 64 * _EPS * (f * P1 + abs(W_trial) + abs(Q0)):
                P[n - 1] = P1
                W[n - 1] = W_trial
                L[n - 1] = L1
                C[n - 1] = C[n - 2] + (W_trial - W[n - 2]) / (P1 - P[n - 2]) * (L1 - L[n - 2])
            else:
                P[n] = P1
                W[n] = W_trial
                C[n] = C[n - 1] + w * (L1 - L[n - 1])
                L[n] = L1
                n += 1
        elif P1 < P0:
            n = m
            if n > 1:
                wt = (W[n - 1] - W[n - 2]) / (P[n - 1] - P[n - 2])
                L1 = _lam(P1, ln_alpha)
                W[n - 1] = W[n - 2] + wt * (P1 - P[n - 2])
                C[n - 1] = C[n - 2] + wt * (L1 - L[n - 2])
                L[n - 1] = L1
                P[n - 1] = P1
        if not slipping:
            W[n - 1] = Q1 if n > 1 else 0.0
            level = P1
            regime = 1 if P1 > 0 else 0
        elif s * Q1 >= f * P1:  # gross sliding
            if P1 > 0:
                L1 = _lam(P1, ln_alpha)
                P[1] = P1
                W[1] = s * f * P1
                L[1] = L1
                C[1] = s * f * L1
                n = 2
            else:
                n = 1
            level = 0.0
            regime = 3
        else:
            c1 = s * Q1 - f * P1
            tol = 64 * _EPS * (f * P1 + abs(Q1))
            while n > 1 and s * W[n - 2] - f * P[n - 2] < c1 - tol:
                n -= 1
            j = n - 2
            Pa = P[j]
            Wa = W[j]
            Pb = P[n - 1]
            Wb = W[n - 1]
            w = (Wb - Wa) / (Pb - Pa) if Pb > Pa else s * f
            Ha = s * Wa - f * Pa
            denom = f - s * w
            y = Pa + (Ha - c1) / denom if denom > 0 else Pa
            y = min(max(y, Pa), P1)
            n = j + 1
            if y > Pa * (1 + 4 * _EPS) and y > 0:
                Ly = _lam(y, ln_alpha)
                P[n] = y
                W[n] = Wa + w * (y - Pa)
                C[n] = C[n - 1] + w * (Ly - L[n - 1])
                L[n] = Ly
                n += 1
            L1 = _lam(P1, ln_alpha)
            P[n] = P1
            W[n] = Q1
            C[n] = C[n - 1] + s * f * (L1 - L[n - 1])
            L[n] = L1
            n += 1
            level = y
            regime = 2
        if P1 <= 0.0:
            n = 1
            regime = 0
            level = 0.0
        out_level[i] = level
        out_regime[i] = regime
        D = D + dissipated
        out_D[i] = D
        out_top_W[i] = W[n - 1]
        out_top_C[i] = C[n - 1]
    return n


if njit is not None:
    _lam = njit(cache=True)(_lam)
    _psi = njit(cache=True)(_psi)
    _xi = njit(cache=True)(_xi)
    _kernel_integral = njit(cache=True)(_kernel_integral)
    _dissipation = njit(cache=True)(_dissipation)
    march_hertz = njit(cache=True)(_march)
else:  # pragma: no cover
    march_hertz = None
