"""Compiled kernels of the normal problem (halfslip.geometry), imported where first used: importing numba
and loading the kernels takes about 0.3 s, which commands that never solve a contact (validate, plot,
--help) do not pay. Each is the one implementation of its formula; geometry's docstrings give the maths.
"""
from __future__ import annotations

import math

import numba
import numpy as np


@numba.njit(cache=True)
def pairwise_sum(a, lo, n):  # pragma: no cover - compiled
    """numpy.sum of the n contiguous float64 values of ``a`` from ``lo``, to the last bit: numpy's pairwise
    summation (blocks of at most 128 in eight accumulators, :func:`_pairwise_block`, split in halves at
    multiples of eight above that and added back up the same tree), for compiled code whose sums must stay
    numpy's. Without recursion (numba cannot load a recursive function called from another one from its
    cache), the halves on a stack."""
    if n <= 128:
        return _pairwise_block(a, lo, n)
    todo = np.empty((192, 3), np.int64)  # (start, count, 0: to split or sum / 1: to add up), depth <= 64
    done = np.empty(64)
    top = 0
    count = 0
    todo[0, 0], todo[0, 1], todo[0, 2] = lo, n, 0
    top = 1
    while top > 0:
        top -= 1
        start, m, add = todo[top, 0], todo[top, 1], todo[top, 2]
        if add:
            count -= 1
            done[count - 1] = done[count - 1] + done[count]
        elif m <= 128:
            done[count] = _pairwise_block(a, start, m)
            count += 1
        else:
            half = m // 2
            half -= half % 8
            todo[top, 0], todo[top, 1], todo[top, 2] = start, m, 1  # then the two halves' sums are added
            todo[top + 1, 0], todo[top + 1, 1], todo[top + 1, 2] = start + half, m - half, 0
            todo[top + 2, 0], todo[top + 2, 1], todo[top + 2, 2] = start, half, 0  # the first half first
            top += 3
    return done[0]


@numba.njit(cache=True)
def _pairwise_block(a, lo, n):  # pragma: no cover - compiled
    """numpy's pairwise sum of at most 128 values: fewer than eight in order from 0.0, else eight
    accumulators over the multiples of eight, combined in pairs, and the rest in order."""
    if n < 8:
        res = 0.0
        for i in range(lo, lo + n):
            res += a[i]
        return res
    r0, r1, r2, r3 = a[lo], a[lo + 1], a[lo + 2], a[lo + 3]
    r4, r5, r6, r7 = a[lo + 4], a[lo + 5], a[lo + 6], a[lo + 7]
    i = 8
    while i < n - (n % 8):
        j = lo + i
        r0 += a[j]
        r1 += a[j + 1]
        r2 += a[j + 2]
        r3 += a[j + 3]
        r4 += a[j + 4]
        r5 += a[j + 5]
        r6 += a[j + 6]
        r7 += a[j + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[lo + i]
        i += 1
    return res


@numba.njit(cache=True, error_model="numpy")
def _log_term(x, knot, left, right, d):  # pragma: no cover - compiled
    """L = ln| (1 - s t + sqrt(1 - s^2) sqrt(1 - t^2)) / (t - s) |, s and t the normalised x and knot.

    -L / sqrt(1 - s^2) is an antiderivative in t of 1 / ((t - s) sqrt(1 - t^2))
    that vanishes at t = +-1. Written as log1p of a non-negative argument (no
    cancellation when the contact barely passes a knot). Infinite where
    x == knot.
    """
    root = math.sqrt((right - x) * (x - left) * (right - knot) * (knot - left))
    near = (right - knot) * (x - left) if knot > x else (knot - left) * (right - x)
    return math.log1p((near + root) / (d * abs(knot - x)))


@numba.vectorize(cache=True)
def _log_ufunc(x, knot, left, right, d):  # pragma: no cover - compiled
    return _log_term(x, knot, left, right, d)


@numba.njit(cache=True)
def _load_to_terms(x, x0, d, c0, c1, knots, jumps, magnitude):  # pragma: no cover - compiled
    """The sum (and with ``magnitude`` the sum of the absolute values) of the terms of
    ``_ContactPressure.load_to`` at each of ``x`` (flat), before the factor d / (pi A); see there."""
    n, K = x.size, knots.size
    left, right = x0 - d, x0 + d
    total = np.empty(n)
    size = np.zeros(n)
    # the knots' coefficients: V / v = b0 + b1 s + b2 s^2, sqrt(1 - t^2) from the distances to the edges (1 - t^2
    # cancels for a knot near an edge: a lightly loaded punch's flat ends)
    a0 = np.empty(K)
    a1 = np.empty(K)
    a2 = np.empty(K)
    b0 = np.empty(K)
    b1 = np.empty(K)
    b2 = np.empty(K)
    root_k = np.empty(K)
    for k in range(K):
        t = (knots[k] - x0) / d
        a0[k] = jumps[k, 0]
        a1[k] = jumps[k, 1] * d
        a2[k] = jumps[k, 2] * d * d
        b0[k] = a0[k] - 0.5 * a1[k] * t + a2[k] * t * t / 3.0
        b1[k] = 0.5 * a1[k] - 2.0 * a2[k] * t / 3.0
        b2[k] = a2[k] / 3.0
        root_k[k] = math.sqrt(max((right - knots[k]) * (knots[k] - left), 0.0)) / d
    for i in range(n):
        xc = min(max(x[i], left), right)
        legs_r = math.sqrt(max(right - xc, 0.0))
        legs_l = math.sqrt(max(xc - left, 0.0))
        theta = 2.0 * math.atan2(legs_l, legs_r)  # arccos(-s), accurate at both edges
        sin = legs_l * legs_r / d  # sqrt(1 - s^2)
        cos = -(xc - x0) / d
        tot = c0 * 0.5 * (theta - cos * sin) - c1 * sin ** 3 / 3.0
        if magnitude:
            size[i] = abs(c0 * 0.5 * theta) + abs(c0 * 0.5 * cos * sin) + abs(c1 * sin ** 3 / 3.0)
        second = 0.5 * (theta + cos * sin)
        for k in range(K):
            kn = knots[k]
            v = (xc - kn) / d
            LV = 0.0
            if v != 0.0:
                V = v * (a0[k] + v * (0.5 * a1[k] + v * a2[k] / 3.0))
                LV = _log_term(xc, kn, left, right, d) * V
            moments = b0[k] * theta - b1[k] * sin + b2[k] * second
            tot += LV + root_k[k] * moments
            if magnitude:
                size[i] += abs(LV) + root_k[k] * (abs(b0[k] * theta) + abs(b1[k] * sin) + abs(b2[k] * second))
        total[i] = tot
    return total, size


@numba.njit(cache=True)
def _pressure_terms(x, x0, d, c0, c1, knots, jumps):  # pragma: no cover - compiled
    """pi A p at each of ``x`` (inside the contact): sqrt(1 - s^2) (c0 + c1 s) + sum_k L(x, knot_k) jump_k(x)
    (see ``_ContactPressure``; a knot's own term is 0 on it, where L is infinite)."""
    left, right = x0 - d, x0 + d
    out = np.empty(x.size)
    for i in range(x.size):
        xi = x[i]
        tot = math.sqrt((right - xi) * (xi - left)) / d * (c0 + c1 * (xi - x0) / d)
        for k in range(knots.size):
            u = xi - knots[k]
            if u != 0.0:
                tot += (jumps[k, 0] + u * (jumps[k, 1] + u * jumps[k, 2])) * _log_term(xi, knots[k], left, right, d)
        out[i] = tot
    return out


@numba.njit(cache=True)
def _pressure_at(x, x0, d, c0, c1, knots, jumps, piA):  # pragma: no cover - compiled
    """p at each of ``x`` (flat): :func:`_pressure_terms` / ``piA`` (pi A) strictly inside the contact
    [x0 - d, x0 + d], 0 elsewhere (``_ContactPressure.__call__`` in one pass)."""
    left, right = x0 - d, x0 + d
    count = 0
    for i in range(x.size):
        if left < x[i] < right:
            count += 1
    inside = np.empty(count)
    c = 0
    for i in range(x.size):
        if left < x[i] < right:
            inside[c] = x[i]
            c += 1
    total = _pressure_terms(inside, x0, d, c0, c1, knots, jumps)
    out = np.zeros(x.size)
    c = 0
    for i in range(x.size):
        if left < x[i] < right:
            out[i] = total[c] / piA
            c += 1
    return out


@numba.njit(cache=True, error_model="numpy")
def _cos_integrals(left, right, lower, upper):  # pragma: no cover - compiled
    """int cos(m theta) dtheta, m = 0..5, over each piece [lower_j, upper_j] met by each contact
    [left_b, right_b] (x = x0 + d cos(theta)), shape (B, J, 6).

    With the half-angle legs (y, x) = (sqrt(right - xi), sqrt(xi - left)) of the piece's ends, theta(xi) / 2
    = atan2(y, x) and y^2 + x^2 = 2 d: the piece's width w = theta(lower) - theta(upper) is one atan2 of
    non-negative legs (no cancellation on thin pieces), and the integrals (2 / m) cos(m mid) sin(m w / 2),
    mid = theta(lower) + theta(upper) over 2, come from the unit vectors of mid and w / 2 raised to the m-th
    power: one transcendental per piece instead of thirteen.
    """
    B, J = left.size, lower.size
    out = np.zeros((B, J, 6))
    for b in range(B):
        lo_b, hi_b = left[b], right[b]
        two_d = hi_b - lo_b
        for j in range(J):
            lower_j = min(max(lower[j], lo_b), hi_b)
            upper_j = min(max(upper[j], lo_b), hi_b)
            if not upper_j > lower_j:
                continue
            y_lo, x_lo = math.sqrt(max(hi_b - lower_j, 0.0)), math.sqrt(max(lower_j - lo_b, 0.0))
            y_up, x_up = math.sqrt(max(hi_b - upper_j, 0.0)), math.sqrt(max(upper_j - lo_b, 0.0))
            cross = two_d * (upper_j - lower_j) / (y_lo * x_up + x_lo * y_up)
            dot = x_lo * x_up + y_lo * y_up
            # unit vectors: mid = atan2(y_lo, x_lo) + atan2(y_up, x_up), half = atan2(cross, dot)
            half = math.atan2(cross, dot)
            out[b, j, 0] = 2.0 * half
            norm = math.sqrt((y_lo * y_lo + x_lo * x_lo) * (y_up * y_up + x_up * x_up))
            rho = math.hypot(cross, dot)
            if norm > 0.0 and math.isfinite(norm) and rho > 0.0 and math.isfinite(rho):
                cm, sm = (x_lo * x_up - y_lo * y_up) / norm, (y_lo * x_up + x_lo * y_up) / norm
                ch, sh = dot / rho, cross / rho
            else:  # legs that under- or overflow (a contact of 1e-300 P): the angles themselves
                mid = math.atan2(y_lo, x_lo) + math.atan2(y_up, x_up)
                cm, sm, ch, sh = math.cos(mid), math.sin(mid), math.cos(half), math.sin(half)
            c, sn = cm, sm  # cos, sin of m mid
            ck, sk = ch, sh  # cos, sin of m half
            for m in range(1, 6):
                out[b, j, m] = (2.0 / m) * c * sk
                c, sn = c * cm - sn * sm, sn * cm + c * sm
                ck, sk = ck * ch - sk * sh, sk * ch + ck * sh
    return out


@numba.njit(cache=True)
def _moments_kernel(D, value, curvature, c2, d, slope_moments, curvature_moments):  # pragma: no cover - compiled
    """On each piece h'(x0 + d cos t) = sum_k a_k cos(k t), a = (value + c2 d^2 / 2, curvature d, c2 d^2 / 2),
    and h'' = b_0 + b_1 cos t, b = (curvature, 2 c2 d): their products with ``D`` (the pieces' cos integrals,
    (B, J, 6)) summed over the pieces, then mapped to the moments by the product-to-sum matrices; the
    magnitude with every term taken positive. Shapes (B, 3), (B, 4), (B, 3)."""
    B, J = value.shape
    slope = np.zeros((B, slope_moments.shape[0]))
    curv = np.zeros((B, curvature_moments.shape[0]))
    magnitude = np.zeros((B, slope_moments.shape[0]))
    A = np.empty(18)
    C = np.empty(12)
    M = np.empty(18)
    a = np.empty(3)
    c = np.empty(2)
    for i in range(B):
        A[:] = 0.0
        C[:] = 0.0
        M[:] = 0.0
        for j in range(J):
            if D[i, j, 0] == 0.0:  # a piece the contact does not meet (every integral is 0)
                continue
            half = 0.5 * c2[i, j] * d[i] * d[i]
            a[0] = value[i, j] + half
            a[1] = curvature[i, j] * d[i]
            a[2] = half
            c[0] = curvature[i, j]
            c[1] = 2.0 * c2[i, j] * d[i]
            for m in range(6):
                Dm = D[i, j, m]
                for k in range(3):
                    A[k * 6 + m] += a[k] * Dm
                    M[k * 6 + m] += abs(a[k]) * abs(Dm)
                for k in range(2):
                    C[k * 6 + m] += c[k] * Dm
        for n in range(slope_moments.shape[0]):
            for q in range(18):
                slope[i, n] += slope_moments[n, q] * A[q]
                magnitude[i, n] += slope_moments[n, q] * M[q]
        for n in range(curvature_moments.shape[0]):
            for q in range(12):
                curv[i, n] += curvature_moments[n, q] * C[q]
    return slope, curv, magnitude


@numba.njit(cache=True)
def _piece_polynomials(center, origins, coeffs):  # pragma: no cover - compiled
    """Per contact centre x0 and piece j (u = x0 - origins[j], coefficients ``coeffs[j]``): the piece's
    polynomial extended to x0 (h'_j(x0)), its derivative there (h''_j(x0)) and h'''_j / 2, shapes (B, J)."""
    B, J = center.size, origins.size
    value = np.empty((B, J))
    curvature = np.empty((B, J))
    c2 = np.empty((B, J))
    for b in range(B):
        for j in range(J):
            e = center[b] - origins[j]
            a0, a1, a2 = coeffs[j, 0], coeffs[j, 1], coeffs[j, 2]
            value[b, j] = a0 + e * (a1 + e * a2)
            curvature[b, j] = a1 + 2.0 * e * a2
            c2[b, j] = a2
    return value, curvature, c2


@numba.njit(cache=True)
def _contact_moments(x0, d, breaks, lower, upper, coeffs, origins, slope_moments,
                     curvature_moments):  # pragma: no cover - compiled
    """geometry._chebyshev_moments of the one contact [x0 - d, x0 + d] in one call (its _piece_integrals
    and _moments_from, the same operations): the slope moments (3,), the curvature moments (4,) and the
    slope moments' magnitude (3,). The normal problem's Newton iteration asks for them at every trial
    point, where the dozen numpy calls around the two kernels cost more than the kernels."""
    D, value, curvature, c2, _, _ = _contact_pieces(x0, d, breaks, lower, upper, coeffs, origins)
    slope, curv, magnitude = _moments_kernel(D, value, curvature, c2, np.full(1, d), slope_moments,
                                             curvature_moments)
    return slope[0], curv[0], magnitude[0]


@numba.njit(cache=True)
def _contact_pieces(x0, d, breaks, lower, upper, coeffs, origins):  # pragma: no cover - compiled
    """geometry._piece_integrals of the one contact [x0 - d, x0 + d]: the cos integrals (1, J, 6) and the
    polynomials' value, curvature and c2 (1, J) on the J pieces it meets, pieces first .. last - 1 (the breaks
    strictly inside it are first .. last - 2)."""
    left, right = x0 - d, x0 + d
    first = np.searchsorted(breaks, left, side="right")
    last = np.searchsorted(breaks, right, side="left") + 1
    D = _cos_integrals(np.full(1, left), np.full(1, right), lower[first:last], upper[first:last])
    value, curvature, c2 = _piece_polynomials(np.full(1, x0), origins[first:last], coeffs[first:last])
    return D, value, curvature, c2, first, last


@numba.njit(cache=True)
def _contact_solution(x0, d, breaks, lower, upper, coeffs, origins, slope_moments,
                      curvature_moments):  # pragma: no cover - compiled
    """What NormalProblem._solution needs of the one contact [x0 - d, x0 + d] in one call (the same operations
    as _piece_integrals, _moments_from and _ContactPressure.from_integrals): the slope moment I_0, the sums
    of the terms of the pressure's smooth coefficients over the pieces met (c0 = d sum terms0, c1 = d^2 sum
    terms1; summed as numpy does, :func:`pairwise_sum`) and the range [klo, khi) of the breaks strictly
    inside the contact."""
    D, value, curvature, c2, first, last = _contact_pieces(x0, d, breaks, lower, upper, coeffs, origins)
    slope, _, _ = _moments_kernel(D, value, curvature, c2, np.full(1, d), slope_moments, curvature_moments)
    J = value.shape[1]
    terms0 = np.empty(J)
    terms1 = np.empty(J)
    for j in range(J):
        terms0[j] = curvature[0, j] * D[0, j, 0] + c2[0, j] * d * D[0, j, 1]
        terms1[j] = c2[0, j] * D[0, j, 0]
    return slope[0, 0], pairwise_sum(terms0, 0, J), pairwise_sum(terms1, 0, J), first, last - 1


_EPS = float(np.finfo(np.float64).eps)


@numba.njit(cache=True)
def _contact_equations(x0, d, P, M, A, scale0, scale1, breaks, lower, upper, coeffs, origins, slope_moments,
                       curvature_moments):  # pragma: no cover - compiled
    """geometry._ContactEquations at (x0, d): the scaled residuals F (2,), their Jacobian in (x0, d) (2, 2)
    and their rounding level (2,); ``scale0``, ``scale1`` the residuals' scales."""
    slope, curv, mag = _contact_moments(x0, d, breaks, lower, upper, coeffs, origins, slope_moments,
                                        curvature_moments)
    I1, I2 = slope[1], slope[2]
    K0, K1, K2, K3 = curv[0], curv[1], curv[2], curv[3]
    F = np.empty(2)
    J = np.empty((2, 2))
    noise = np.empty(2)
    F[0] = (d * I1 / A - P) / scale0
    F[1] = (d * d * I2 / (2.0 * A) + P * x0 - M) / scale1
    J[0, 0] = d * K1 / A / scale0
    J[0, 1] = (I1 / A + d * (K0 + K2) / (2.0 * A)) / scale0
    J[1, 0] = (d * d * K2 / (2.0 * A) + P) / scale1
    J[1, 1] = (d * I2 / A + d * d * (K1 + K3) / (4.0 * A)) / scale1
    terms0 = (d * mag[1] / A + P) / scale0
    terms1 = (d * d * mag[2] / (2.0 * A) + P * abs(x0) + abs(M)) / scale1
    noise[0] = 4.0 * _EPS * (terms0 + (abs(J[0, 0]) * abs(x0) + abs(J[0, 1]) * d))
    noise[1] = 4.0 * _EPS * (terms1 + (abs(J[1, 0]) * abs(x0) + abs(J[1, 1]) * d))
    return F, J, noise


@numba.njit(cache=True)
def _solve2(J, r0, r1):  # pragma: no cover - compiled
    """J^-1 (r0, r1) for a 2 x 2 J by elimination with partial pivoting (as LAPACK's dgesv); ok False where a
    pivot is exactly zero (np.linalg.solve's LinAlgError)."""
    a, b, c, e = J[0, 0], J[0, 1], J[1, 0], J[1, 1]
    if abs(c) > abs(a):
        a, b, c, e = c, e, a, b
        r0, r1 = r1, r0
    if a == 0.0:
        return False, 0.0, 0.0
    f = c / a
    u = e - f * b
    if u == 0.0:
        return False, 0.0, 0.0
    y1 = (r1 - f * r0) / u
    return True, (r0 - b * y1) / a, y1


@numba.njit(cache=True)
def _contact_newton(x0, d, tol, max_iter, P, M, A, scale0, scale1, breaks, lower, upper, coeffs, origins,
                    slope_moments, curvature_moments):  # pragma: no cover - compiled
    """geometry._solve_contact_equations' iteration from (x0, d): Newton on the contact equations, damped by
    the natural monotonicity test (see there). Returns (converged, iterations, residual, x0, d)."""
    F, J, noise = _contact_equations(x0, d, P, M, A, scale0, scale1, breaks, lower, upper, coeffs, origins,
                                     slope_moments, curvature_moments)
    iteration = 0
    norm = math.inf
    while True:
        norm = max(abs(F[0]), abs(F[1]))
        if abs(F[0]) <= max(tol, noise[0]) and abs(F[1]) <= max(tol, noise[1]):
            return True, iteration, norm, x0, d
        if iteration == max_iter:
            break
        ok, n0, n1 = _solve2(J, -F[0], -F[1])
        if not ok:
            break
        size = max(abs(n0), abs(n1))
        step = 1.0
        accepted = False
        x_try, d_try = x0, d
        F_try, J_try, noise_try = F, J, noise
        while step > 1e-10:
            x_try, d_try = x0 + step * n0, d + step * n1
            if d_try > 0.25 * d and abs(x_try - x0) <= 2.0 * d:
                F_try, J_try, noise_try = _contact_equations(x_try, d_try, P, M, A, scale0, scale1, breaks, lower,
                                                             upper, coeffs, origins, slope_moments,
                                                             curvature_moments)
                if abs(F_try[0]) <= max(tol, noise_try[0]) and abs(F_try[1]) <= max(tol, noise_try[1]):
                    accepted = True  # converged; at rounding level the monotonicity test is noise
                    break
                ok, m0, m1 = _solve2(J, -F_try[0], -F_try[1])
                if ok and max(abs(m0), abs(m1)) <= (1.0 - 0.25 * step) * size:
                    accepted = True
                    break
            step *= 0.5
        if not accepted:
            break
        x0, d, F, J, noise = x_try, d_try, F_try, J_try, noise_try
        iteration += 1
    return False, iteration, norm, x0, d
