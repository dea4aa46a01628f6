"""Profiles and the normal contact problem (physics.md N1-N3).

API CONTRACT (filled in by the geometry work; other modules rely on these names):

Material(E, nu)                      .compliance -> A = 4 (1 - nu^2) / E
Profile (abstract)
    .symmetric: bool                 h(x) == h(-x)
    .length_scale: float             a representative length (datum of the log kernel)
    .gap(x), .slope(x)               h(x), h'(x), vectorised
Hertz(radius), RoundedPunch(flat_half_width, radius), TabulatedProfile(x, h)

NormalProblem(profile, compliance)
    .solve(P, M=0.0, near=None) -> NormalSolution   (near: a solution at nearby loads, a warm start)
    # fast symmetric paths, M = 0, vectorised over P / a:
    .half_width(P)  -> a(P)          (0 where P <= 0; rounded punch -> w as P -> 0+)
    .load(a)        -> P(a)
    .pressure(x, P) -> p(x, P), broadcast over x and P, 0 outside |x| < a(P)

NormalSolution (frozen)
    P, M, left, right, rotation, separated
    .center, .half_width
    .pressure(x) -> p(x) (0 outside [left, right])

Formulation
-----------
Write the contact as [x0 - d, x0 + d] and x = x0 + d cos(theta). The
pressure bounded at both edges exists only if the T_0 Chebyshev coefficient
of h' + rotation vanishes, and then (N1)-(N2) reduce to

    P         = (d / A)        I_1(x0, d)
    M - P x0  = (d^2 / (2 A))  I_2(x0, d)
    rotation  = -I_0(x0, d) / pi
    I_n(x0, d) = int_0^pi h'(x0 + d cos theta) cos(n theta) dtheta

(the pressure is sqrt(1 - s^2) sum_n c_n U_{n-1}(s) with A c_n the
Chebyshev coefficients of h' + rotation; only c_1 and c_2 carry load and
moment). Every profile here has a slope h' that is piecewise polynomial of
degree <= 2 (a cubic spline for tabulated gaps), so on each piece the
integrand is a short cosine series and I_n is evaluated in closed form, with
no quadrature and no truncated series. The pressure is evaluated exactly as
well, from the inversion of (N1) bounded at both edges,

    p(x) = sqrt(d^2 - s^2) / (pi A) PV int h'(xi) / (sqrt(d^2 - (xi - x0)^2) (xi - x)) dxi,

s = x - x0: on each piece h'(xi) = h'(x) + (xi - x) r(xi) with r a
polynomial, the first part integrates to logarithms at the breakpoints and
the second to elementary functions, so that

    p(x) = (1 / (pi A)) [ sum_k L_k(x) [h']_k(x) + sqrt(1 - s^2 / d^2) (c_0 + c_1 s / d) ],

with [h']_k the change of the slope polynomial across breakpoint k inside the
contact and L_k a logarithm (see ``_log_kernel``).
"""
from __future__ import annotations

import abc
import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.interpolate import CubicSpline

from .errors import HalfslipInputError, check_number

__all__ = ["Material", "Profile", "Hertz", "RoundedPunch", "TabulatedProfile", "NormalSolution", "NormalProblem"]

_MAX_NEWTON_ITER = 60  # caps of the nonlinear iterations, which converge in far fewer
_MAX_BRACKET_ITER = 200
_MAX_WARM_ITER = 12  # a warm start that needs more falls back to the cold start
_WARM_REACH = 0.25  # largest edge move (relative to d) taken from the first-order prediction
_SYMMETRY_RTOL = 1e-12
_EPS = float(np.finfo(float).eps)

FloatArray = NDArray[np.float64]


class ProfileSpanError(ValueError):
    """No contact carries the loads within the profile: a contact that would leave a
    tabulated profile's span, or no single contact found (a profile not lowest at 0).

    Raised by the normal problem; the scene reader checks the history's extreme
    loads for it, and the command line reports it as an error of the scene's
    ``geometry``.
    """


@dataclass(frozen=True)
class Material:
    """Elastically similar bodies in plane strain.

    Parameters
    ----------
    E : float
        Young's modulus [Pa], > 0.
    nu : float
        Poisson's ratio, -1 < nu < 0.5.

    Raises
    ------
    HalfslipInputError
        For anything else, naming the field (``material.E``, ``material.nu``)
        as a scene file's error does: the same checks as the YAML reader.
    """

    E: float
    nu: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "E", check_number(self.E, "material.E", positive=True))
        nu = check_number(self.nu, "material.nu")
        if not -1.0 < nu < 0.5:
            raise HalfslipInputError(f"Poisson's ratio must lie in (-1, 0.5), got {nu:g}", field="material.nu")
        object.__setattr__(self, "nu", nu)

    @property
    def compliance(self) -> float:
        """Composite compliance A = 4 (1 - nu^2) / E  [1/Pa]."""
        return 4.0 * (1.0 - self.nu**2) / self.E


def _require_positive(name: str, value: float) -> float:
    value = float(value)
    if not math.isfinite(value) or value <= 0.0:
        raise ValueError(f"{name} must be positive and finite, got {value!r}")
    return value


# ---------------------------------------------------------------------------
# Piecewise-quadratic slope
# ---------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class _SlopePieces:
    """The slope h'(x) as a piecewise polynomial of degree <= 2.

    Piece ``j`` covers ``[lower[j], upper[j]]`` (``breaks`` with -inf and +inf
    added) and is ``coeffs[j, 0] + coeffs[j, 1] u + coeffs[j, 2] u**2`` with
    ``u = x - origins[j]``. ``jumps[k]`` holds the coefficients, in powers of
    ``x - breaks[k]``, of (piece k + 1) - (piece k); h' is continuous, so
    ``jumps[:, 0]`` is zero up to rounding.

    Shapes: breaks (K,), origins (K + 1,), coeffs (K + 1, 3), jumps (K, 3).
    """

    breaks: FloatArray
    origins: FloatArray
    coeffs: FloatArray
    lower: FloatArray = field(init=False)
    upper: FloatArray = field(init=False)
    jumps: FloatArray = field(init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "lower", np.concatenate(([-np.inf], self.breaks)))
        object.__setattr__(self, "upper", np.concatenate((self.breaks, [np.inf])))
        left = _taylor_at(self.coeffs[:-1], self.breaks - self.origins[:-1])
        right = _taylor_at(self.coeffs[1:], self.breaks - self.origins[1:])
        object.__setattr__(self, "jumps", right - left)

    def slope(self, x: FloatArray) -> FloatArray:
        j = np.searchsorted(self.breaks, x, side="right")
        u = x - self.origins[j]
        c = self.coeffs[j]
        return c[..., 0] + u * (c[..., 1] + u * c[..., 2])


def _taylor_at(coeffs: FloatArray, delta: FloatArray) -> FloatArray:
    """Re-expand the quadratics ``coeffs`` (n, 3) about the points ``delta`` (n,) from their origins."""
    c0, c1, c2 = coeffs.T
    return np.stack([c0 + delta * (c1 + delta * c2), c1 + 2.0 * delta * c2, c2], axis=-1)


def _parabola_pieces(radius: float) -> _SlopePieces:
    return _SlopePieces(breaks=np.empty(0), origins=np.zeros(1), coeffs=np.array([[0.0, 1.0 / radius, 0.0]]))


# ---------------------------------------------------------------------------
# Profiles
# ---------------------------------------------------------------------------


class Profile(abc.ABC):
    """Initial gap h(x) >= 0 of the pad, h(0) = 0 (physics.md, "The scene")."""

    @property
    @abc.abstractmethod
    def symmetric(self) -> bool:
        """Whether h(x) == h(-x)."""

    @property
    @abc.abstractmethod
    def length_scale(self) -> float:
        """A representative length [m] (the datum of the logarithmic kernel)."""

    @abc.abstractmethod
    def gap(self, x: ArrayLike) -> FloatArray:
        """Gap h(x) [m]; ``x`` of any shape, result of the same shape."""

    def slope(self, x: ArrayLike) -> FloatArray:
        """Slope h'(x) [-]; ``x`` of any shape, result of the same shape."""
        return self._slope_pieces.slope(np.asarray(x, dtype=float))

    @property
    @abc.abstractmethod
    def _slope_pieces(self) -> _SlopePieces:
        """h' as a piecewise quadratic: what the normal solver works on."""


@dataclass(frozen=True)
class Hertz(Profile):
    """Cylinder of radius R: h(x) = x^2 / (2R).

    Parameters
    ----------
    radius : float
        R [m], positive.
    """

    radius: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", check_number(self.radius, "geometry.radius", positive=True))

    @property
    def symmetric(self) -> bool:
        return True

    @property
    def length_scale(self) -> float:
        return self.radius

    def gap(self, x: ArrayLike) -> FloatArray:
        x = np.asarray(x, dtype=float)
        return x * x / (2.0 * self.radius)

    @cached_property
    def _slope_pieces(self) -> _SlopePieces:
        return _parabola_pieces(self.radius)


@dataclass(frozen=True)
class RoundedPunch(Profile):
    """Flat of half-width w with corners of radius R.

    h(x) = 0 for |x| <= w and (|x| - w)^2 / (2R) beyond.

    Parameters
    ----------
    flat_half_width : float
        w [m], >= 0 (w = 0 is the Hertz cylinder).
    radius : float
        R [m], positive.
    """

    flat_half_width: float
    radius: float

    def __post_init__(self) -> None:
        w = check_number(self.flat_half_width, "geometry.flat_half_width", nonnegative=True)
        object.__setattr__(self, "flat_half_width", w)
        object.__setattr__(self, "radius", check_number(self.radius, "geometry.radius", positive=True))

    @property
    def symmetric(self) -> bool:
        return True

    @property
    def length_scale(self) -> float:
        return self.flat_half_width + self.radius

    def gap(self, x: ArrayLike) -> FloatArray:
        beyond = np.maximum(np.abs(np.asarray(x, dtype=float)) - self.flat_half_width, 0.0)
        return beyond * beyond / (2.0 * self.radius)

    @cached_property
    def _slope_pieces(self) -> _SlopePieces:
        w, k = self.flat_half_width, 1.0 / self.radius
        if w == 0.0:
            return _parabola_pieces(self.radius)
        return _SlopePieces(
            breaks=np.array([-w, w]),
            origins=np.array([-w, 0.0, w]),
            coeffs=np.array([[0.0, k, 0.0], [0.0, 0.0, 0.0], [0.0, k, 0.0]]),
        )


class TabulatedProfile(Profile):
    """Gap given by samples, interpolated by a cubic spline.

    The spline (scipy ``CubicSpline``, not-a-knot ends) makes h' continuous
    and piecewise quadratic, which the normal solver integrates exactly; it
    reproduces cubics exactly, so a sampled Hertz profile is exact. The
    interpolated h(0) is subtracted so that h(0) = 0. Outside the sampled
    span ``gap`` and ``slope`` extrapolate the end cubics, but a contact must
    lie inside the span (the solver raises ``ValueError`` otherwise).

    Parameters
    ----------
    x : array_like, shape (n,)
        Strictly increasing, finite sample positions [m], n >= 4,
        x[0] < 0 < x[-1].
    h : array_like, shape (n,)
        Gap at the samples [m], finite.

    Attributes
    ----------
    x, h : ndarray, shape (n,)
        The samples (read-only), h less the interpolated h(0).
    span : (float, float)
        (x[0], x[-1]).
    """

    def __init__(self, x: ArrayLike, h: ArrayLike) -> None:
        x = np.array(x, dtype=float)
        h = np.array(h, dtype=float)
        if x.ndim != 1 or h.shape != x.shape:
            raise ValueError(f"x and h must be 1-D of equal length, got shapes {x.shape} and {h.shape}")
        if x.size < 4:
            raise ValueError(f"x needs at least 4 samples, got {x.size}")
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(h))):
            raise ValueError("x and h must be finite")
        if np.any(np.diff(x) <= 0.0):
            raise ValueError("x must be strictly increasing")
        if not x[0] < 0.0 < x[-1]:
            raise ValueError(f"x must bracket 0, got the span [{x[0]!r}, {x[-1]!r}]")
        spline = CubicSpline(x, h)
        h0 = float(spline(0.0))
        spline.c[-1] -= h0
        self._spline = spline
        self.x = x
        self.h = h - h0
        self.x.flags.writeable = False
        self.h.flags.writeable = False
        self.span = (float(x[0]), float(x[-1]))
        mirrored = np.all(np.abs(x + x[::-1]) <= _SYMMETRY_RTOL * np.max(np.abs(x)))
        even = np.all(np.abs(self.h - self.h[::-1]) <= _SYMMETRY_RTOL * np.max(np.abs(self.h)))
        self._symmetric = bool(mirrored and even)
        self._pieces = _SlopePieces(
            breaks=x[1:-1].copy(), origins=x[:-1].copy(), coeffs=spline.derivative().c[::-1].T.copy()
        )

    def __repr__(self) -> str:
        return f"TabulatedProfile(<{self.x.size} samples on [{self.x[0]:g}, {self.x[-1]:g}]>)"

    @property
    def symmetric(self) -> bool:
        return self._symmetric

    @property
    def length_scale(self) -> float:
        return 0.5 * (self.span[1] - self.span[0])

    def gap(self, x: ArrayLike) -> FloatArray:
        return self._spline(np.asarray(x, dtype=float))

    @property
    def _slope_pieces(self) -> _SlopePieces:
        return self._pieces


def _span(profile: Profile) -> tuple[float, float]:
    """Where a contact may lie: the tabulated span, else the whole line."""
    return profile.span if isinstance(profile, TabulatedProfile) else (-math.inf, math.inf)


# ---------------------------------------------------------------------------
# Exact integrals over a contact [x0 - d, x0 + d]
# ---------------------------------------------------------------------------


_N_COS = 6  # cos(m theta), m = 0..5: enough for h' (degree 2) x cos(2 theta) and h'' x cos(3 theta)


def _product_to_sum(orders: int, degree: int) -> FloatArray:
    """W with cos(k t) cos(n t) = sum_m W[n, k * 6 + m] cos(m t), n < orders, k < degree."""
    W = np.zeros((orders, degree, _N_COS))
    for n in range(orders):
        for k in range(degree):
            W[n, k, n + k] += 0.5
            W[n, k, abs(n - k)] += 0.5
    return W.reshape(orders, degree * _N_COS)


_SLOPE_MOMENTS = _product_to_sum(3, 3)
_CURVATURE_MOMENTS = _product_to_sum(4, 2)
_SINE_ORDERS = np.arange(1, _N_COS, dtype=float)


def _half_angle_legs(xi: FloatArray, left: FloatArray, right: FloatArray) -> tuple[FloatArray, FloatArray]:
    """(sqrt(right - xi), sqrt(xi - left)): xi = x0 + d cos(theta) has theta / 2 = atan2 of these."""
    return np.sqrt(np.maximum(right - xi, 0.0)), np.sqrt(np.maximum(xi - left, 0.0))


class _PieceIntegrals(NamedTuple):
    """Per-piece data over a batch of contacts, shapes (B, J) or (B, J, 6)."""

    cos_integrals: FloatArray  # int cos(m theta) dtheta over the piece, m = 0..5
    value: FloatArray  # h'_j(x0), the piece's polynomial extended to x0
    curvature: FloatArray  # h''_j(x0)
    c2: FloatArray  # h'''_j / 2


def _piece_integrals(pieces: _SlopePieces, center: FloatArray, half_width: FloatArray) -> _PieceIntegrals:
    """Integrals of cos(m theta) over the pieces of h' met by contacts [x0 - d, x0 + d].

    ``center`` and ``half_width`` have shape (B,); the J pieces used are those
    met by any contact of the batch.
    """
    from ._geometry_kernels import _cos_integrals, _piece_polynomials

    left, right = center - half_width, center + half_width
    first = np.searchsorted(pieces.breaks, left.min(), side="right")
    last = np.searchsorted(pieces.breaks, right.max(), side="left") + 1
    cos_integrals = _cos_integrals(np.ascontiguousarray(left, dtype=float), np.ascontiguousarray(right, dtype=float),
                                   np.ascontiguousarray(pieces.lower[first:last]),
                                   np.ascontiguousarray(pieces.upper[first:last]))
    value, curvature, c2 = _piece_polynomials(np.ascontiguousarray(center, dtype=float),
                                              np.ascontiguousarray(pieces.origins[first:last]),
                                              np.ascontiguousarray(pieces.coeffs[first:last]))
    return _PieceIntegrals(cos_integrals, value, curvature, c2)


class _Moments(NamedTuple):
    """Angular moments over a batch of contacts (see ``_chebyshev_moments``)."""

    slope: FloatArray  # I_n, (B, 3)
    curvature: FloatArray  # K_n, (B, 4)
    slope_magnitude: FloatArray  # I_n with every term taken positive: its rounding scale, (B, 3)


def _moments_from(data: _PieceIntegrals, half_width: FloatArray) -> _Moments:
    from ._geometry_kernels import _moments_kernel

    slope, curvature, magnitude = _moments_kernel(
        data.cos_integrals, np.ascontiguousarray(data.value), np.ascontiguousarray(data.curvature),
        np.array(np.broadcast_to(data.c2, data.value.shape), dtype=float),  # (writable, as its compiled callers')
        np.ascontiguousarray(half_width, dtype=float).reshape(-1), _SLOPE_MOMENTS, _CURVATURE_MOMENTS)
    return _Moments(slope=slope, curvature=curvature, slope_magnitude=magnitude)


def _chebyshev_moments(pieces: _SlopePieces, center: FloatArray, half_width: FloatArray) -> _Moments:
    """Angular moments of h' and h'' over contacts [x0 - d, x0 + d], batched over (B,).

        I_n = int_0^pi h'(x0 + d cos t) cos(n t) dt,   n = 0, 1, 2
        K_n = int_0^pi h''(x0 + d cos t) cos(n t) dt,  n = 0, 1, 2, 3

    exact to rounding: on a piece h'(x0 + d cos t) = a0 + a1 cos t + a2 cos 2t,
    and cos(k t) cos(n t) = (cos((k + n) t) + cos((k - n) t)) / 2 integrates
    to sines at the piece's ends.
    """
    return _moments_from(_piece_integrals(pieces, center, half_width), half_width)


# ---------------------------------------------------------------------------
# Exact pressure on a given contact
# ---------------------------------------------------------------------------


def _log_kernel(x: FloatArray, knot: FloatArray, left: ArrayLike, right: ArrayLike, d: ArrayLike) -> FloatArray:
    """``_log_term`` broadcast over its arguments (infinite where x == knot, without a warning)."""
    from ._geometry_kernels import _log_ufunc

    with np.errstate(divide="ignore", invalid="ignore"):
        return _log_ufunc(x, knot, left, right, d)


@dataclass(frozen=True, eq=False)
class _ContactPressure:
    """The pressure bounded at both edges of a contact [x0 - d, x0 + d] (inversion of N1).

    p(x) = (1 / (pi A)) [ sum_k L(x, knot_k) jump_k(x) + sqrt(1 - s^2) (c0 + c1 s) ],
    s = (x - x0) / d, jump_k(x) = jumps[k] . (1, x - knot_k, (x - knot_k)^2) the
    change of the slope polynomial across the breakpoint knot_k inside the contact.
    """

    center: float
    half_width: float
    compliance: float
    knots: FloatArray  # (K,)
    jumps: FloatArray  # (K, 3)
    smooth: tuple[float, float]  # (c0, c1)

    @classmethod
    def from_integrals(
        cls, pieces: _SlopePieces, compliance: float, center: float, half_width: float, data: _PieceIntegrals
    ) -> _ContactPressure:
        """From ``data`` = ``_piece_integrals`` of this one contact.

        On piece j, h'(xi) - h'(x) = (xi - x) (h''_j(x0) + c2_j (xi + x - 2 x0)),
        and int t^m / sqrt(1 - t^2) dt over the piece is int cos^m(theta) dtheta.
        """
        D = data.cos_integrals[0]
        d = half_width
        c0 = d * float(np.sum(data.curvature[0] * D[:, 0] + data.c2[0] * d * D[:, 1]))
        c1 = d * d * float(np.sum(data.c2[0] * D[:, 0]))
        inside = (pieces.breaks > center - d) & (pieces.breaks < center + d)
        return cls(center, d, compliance, pieces.breaks[inside], pieces.jumps[inside], (c0, c1))

    @classmethod
    def build(cls, pieces: _SlopePieces, compliance: float, center: float, half_width: float) -> _ContactPressure:
        data = _piece_integrals(pieces, np.array([center]), np.array([half_width]))
        return cls.from_integrals(pieces, compliance, center, half_width, data)

    def edge_coefficients(self) -> tuple[float, float]:
        """(k_left, k_right) with p ~ k sqrt(distance to the edge) at each edge (found once per contact: a
        step's edge path asks at both ends, and the next sub-step's start is this one's end)."""
        return self._edge_coefficients

    @cached_property
    def _edge_coefficients(self) -> tuple[float, float]:
        """:meth:`edge_coefficients`.

        At the right edge sqrt(1 - s^2) -> sqrt(2 dist / d) and, for a knot
        inside, L(x, knot) -> sqrt(dist) sqrt(2 (knot - left) / (d (right - knot)))
        (mirrored at the left edge).
        """
        x0, d = self.center, self.half_width
        left, right = x0 - d, x0 + d
        c0, c1 = self.smooth
        root = math.sqrt(2.0 / d)
        k_left, k_right = (c0 - c1) * root, (c0 + c1) * root
        if self.knots.size:
            to_left, to_right = self.knots - left, right - self.knots
            j0, j1, j2 = self.jumps.T
            at_right = j0 + to_right * (j1 + to_right * j2)
            at_left = j0 - to_left * (j1 - to_left * j2)
            k_right += float(np.sum(at_right * np.sqrt(2.0 * to_left / (d * to_right))))
            k_left += float(np.sum(at_left * np.sqrt(2.0 * to_right / (d * to_left))))
        scale = 1.0 / (math.pi * self.compliance)
        return k_left * scale, k_right * scale

    def load_to(self, x: ArrayLike, magnitude: bool = False):
        """int p from the left edge to ``x`` [N/m], closed form (0 left of the contact, P right of it).

        With ``magnitude``, also the sum of the absolute values of the terms
        (same units): the result's rounding is about eps times it. The terms can
        be many times the load they add up to (a lightly loaded punch: 90x at
        1e-2 P0, 2e3x at 1e-4 P0, 4e8x at 1e-12 P0), and then the load of one
        cell, a difference of two such values, loses what a quadrature of p
        does not.

        With s, t the normalised x and knot and v = s - t, the smooth term
        integrates to c0 (theta - cos(theta) sin(theta)) / 2 - c1 sin^3(theta) / 3
        (s = -cos(theta)); a knot's term L(s, t) J(v), J(v) = a0 + a1 v + a2 v^2
        (a_m = jump_m d^m), by parts with the antiderivative V(v) = a0 v + a1 v^2
        / 2 + a2 v^3 / 3 (which vanishes on the knot, where L is infinite, as L
        vanishes at s = -1) and dL/ds = -sqrt(1 - t^2) / (v sqrt(1 - s^2)):

            int_-1^s L J ds = L(s, t) V(v) + sqrt(1 - t^2) int_-1^s (V(v) / v) / sqrt(1 - s^2) ds,

        V / v a quadratic in s, whose moments against 1 / sqrt(1 - s^2) are
        theta, -sin(theta) and (theta + cos(theta) sin(theta)) / 2. Exact where
        a quadrature of p meets the square roots at the edges and the x ln x
        kinks at the knots (the general solver's cell capacities, every cell
        boundary once).
        """
        from ._geometry_kernels import _load_to_terms

        x = np.asarray(x, dtype=float)
        total, size = _load_to_terms(np.ascontiguousarray(x.reshape(-1)), self.center, self.half_width,
                                     self.smooth[0], self.smooth[1], np.ascontiguousarray(self.knots, dtype=float),
                                     np.ascontiguousarray(self.jumps, dtype=float).reshape(-1, 3), magnitude)
        scale = self.half_width / (math.pi * self.compliance)
        total = total.reshape(x.shape) * scale
        return (total, size.reshape(x.shape) * scale) if magnitude else total

    def __call__(self, x: ArrayLike) -> FloatArray:
        x = np.asarray(x, dtype=float)
        from ._geometry_kernels import _pressure_at

        return _pressure_at(np.ascontiguousarray(x.reshape(-1)), *self.arguments()).reshape(x.shape)

    def arguments(self) -> tuple:
        """_geometry_kernels._pressure_at's arguments after the points (for compiled callers)."""
        return (self.center, self.half_width, self.smooth[0], self.smooth[1], self._knots, self._jumps,
                math.pi * self.compliance)

    @cached_property
    def _knots(self) -> FloatArray:
        return np.ascontiguousarray(self.knots, dtype=float)

    @cached_property
    def _jumps(self) -> FloatArray:
        return np.ascontiguousarray(self.jumps, dtype=float).reshape(-1, 3)


# ---------------------------------------------------------------------------
# The contact equations
# ---------------------------------------------------------------------------


class _ContactIteration(NamedTuple):
    """Outcome of ``_solve_contact_equations``."""

    converged: bool
    iterations: int
    residual: float
    center: float
    half_width: float


class _ContactEquations:
    """F1 = (d / A) I_1 - P and F2 = (d^2 / (2A)) I_2 + P x0 - M (N1, N2).

    F1 is scaled by P and F2 by |M| + P d_start.
    """

    def __init__(self, pieces: _SlopePieces, A: float, P: float, M: float, d_start: float) -> None:
        self.pieces, self.A, self.P, self.M = pieces, A, P, M
        self.scale = np.array([P, abs(M) + P * d_start])

    def __call__(self, x0: float, d: float) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Scaled residuals F (2,), their Jacobian in (x0, d) (2, 2) and rounding level (2,).

        The rounding level adds what rounding does to the terms of I_1 and
        I_2 and to the edge positions: near a kink of h'' the loads are so
        sensitive to an edge position that it can exceed any useful tolerance.
        (Compiled: _geometry_kernels._contact_equations, which the Newton
        iteration calls directly.)
        """
        from ._geometry_kernels import _contact_equations

        return _contact_equations(float(x0), float(d), *self.arguments())

    def arguments(self) -> tuple:
        """The compiled equations' arguments after (x0, d)."""
        pieces = self.pieces
        return (float(self.P), float(self.M), float(self.A), float(self.scale[0]), float(self.scale[1]),
                pieces.breaks, pieces.lower, pieces.upper, pieces.coeffs, pieces.origins, _SLOPE_MOMENTS,
                _CURVATURE_MOMENTS)


def _half_width_at(
    pieces: _SlopePieces,
    A: float,
    center: FloatArray,
    P: FloatArray,
    lower: FloatArray,
    upper: FloatArray,
    rtol: float,
    start: FloatArray | None = None,
) -> FloatArray:
    """Solve (d / A) I_1(x0, d) = P for d in [lower, upper], batched over (B,).

    Safeguarded Newton (bisection when a step leaves the bracket) from
    ``start`` (default ``upper``); needs load(lower) <= P <= load(upper). At
    a fixed centre the load increases with d for a convex profile; the
    bracket keeps the iteration safe for any profile. An entry stops when its
    step falls below rtol d, its bracket closes or its residual reaches the
    rounding level of the terms of I_1; only the entries still moving are
    evaluated.
    """
    lo = lower.copy()
    hi = upper.copy()
    d = upper.copy() if start is None else start.copy()
    active = np.arange(d.size)
    for _ in range(_MAX_BRACKET_ITER):
        da = d[active]
        moments = _chebyshev_moments(pieces, center[active], da)
        I1 = moments.slope[:, 1]
        K = moments.curvature
        residual = da * I1 / A - P[active]
        lo_a = np.where(residual < 0.0, da, lo[active])
        hi_a = np.where(residual >= 0.0, da, hi[active])
        lo[active], hi[active] = lo_a, hi_a
        derivative = I1 / A + da * (K[:, 0] + K[:, 2]) / (2.0 * A)
        with np.errstate(divide="ignore", invalid="ignore"):
            newton = da - residual / derivative
        step = np.where((newton >= lo_a) & (newton <= hi_a), newton, 0.5 * (lo_a + hi_a))
        converged = np.abs(residual) <= 4.0 * _EPS * (da * moments.slope_magnitude[:, 1] / A + P[active])
        d[active] = np.where(converged, da, step)
        active = active[~converged & (np.abs(step - da) > rtol * da) & (hi_a - lo_a > 4.0 * _EPS * da)]
        if active.size == 0:
            break
    return d


def _initial_half_width(pieces: _SlopePieces, A: float, P: float, x0: float, guess: float) -> float | None:
    """Half-width carrying P at centre x0 (to 1e-6 relative), searched from ``guess`` (> 0).

    Brackets by halving or doubling the guess, then refines; None when no
    bracket turns up.
    """

    def load(d: float) -> float:
        return d * float(_chebyshev_moments(pieces, np.array([x0]), np.array([d])).slope[0, 1]) / A

    lower = upper = guess
    if load(guess) >= P:
        for _ in range(_MAX_BRACKET_ITER):
            lower *= 0.5
            if load(lower) < P:
                break
        else:
            return None
    else:
        for _ in range(_MAX_BRACKET_ITER):
            upper *= 2.0
            if load(upper) >= P:
                break
        else:
            return None
    one = np.ones(1)
    return float(_half_width_at(pieces, A, x0 * one, P * one, lower * one, upper * one, 1e-6, guess * one)[0])


def _solve_contact_equations(
    profile: Profile,
    compliance: float,
    P: float,
    M: float,
    *,
    tol: float,
    half_width_guess: float | None = None,
    max_iter: int = _MAX_NEWTON_ITER,
    start: tuple[float, float] | None = None,
) -> _ContactIteration:
    """Contact centre and half-width for loads (P, M), any profile (N1, N2).

    Solves F1 = ``(d / A) I_1 - P`` = 0 and F2 = ``(d^2 / (2A)) I_2 + P x0 - M``
    = 0 by Newton's method on (x0, d) with the exact Jacobian, damped by the
    natural monotonicity test (Deuflhard): a step is accepted when the
    simplified Newton correction at the new point, J^-1 F(new), is smaller
    than the Newton correction. Unlike a test on |F|, this does not depend on
    how the two equations are scaled: with one edge just past a kink of h''
    (a rounded punch under a small load and a large moment) the loads are far
    more sensitive to that edge than to the other, and a residual test crawls.

    Parameters
    ----------
    profile : Profile
    compliance : float
        A [1/Pa].
    P, M : float
        Normal load (> 0) [N/m] and moment about x = 0 [N].
    tol : float
        Stop when |F1| / P and |F2| / (|M| + P d) are below tol, or below their
        rounding level where that is larger (see ``_ContactEquations``).
    half_width_guess : float, optional
        Where the search for the starting half-width begins (default: the
        Hertz half-width for a radius equal to the profile's length scale).
    max_iter : int
    start : (float, float), optional
        (x0, d) to start the iteration at (a warm start, see
        ``_warm_contact``), instead of the cold start below; ``half_width_guess``
        is then unused.

    Returns
    -------
    _ContactIteration
        ``converged`` is False when no start was bracketed or the iteration
        stalled; nothing is raised.

    Notes
    -----
    The start is x0 = M / P (the pressure centroid, clipped to a tabulated
    span) with d solving F1 = 0 at that centre. Started off that curve (at
    d = a(P), say) the iteration stalls under large moments.
    """
    pieces = profile._slope_pieces
    A = compliance
    if start is not None:
        x0, d = start
    else:
        lowest, highest = _span(profile)
        x0 = min(max(M / P, lowest), highest)
        if half_width_guess is None:
            half_width_guess = math.sqrt(2.0 * A * profile.length_scale * P / math.pi)
        d = _initial_half_width(pieces, A, P, x0, half_width_guess)
        if d is None:
            return _ContactIteration(False, 0, math.inf, x0, math.nan)
    from ._geometry_kernels import _contact_newton

    converged, iterations, norm, x0, d = _contact_newton(float(x0), float(d), float(tol), int(max_iter),
                                                         *_ContactEquations(pieces, A, P, M, d).arguments())
    return _ContactIteration(bool(converged), int(iterations), float(norm), float(x0), float(d))


def _warm_contact(near: NormalSolution, P: float, M: float) -> tuple[float, float]:
    """(x0, d) predicted to first order under (P, M) from the solution ``near`` (N3).

    The load increments (dP, dM) on the contact of ``near`` add the flat-punch
    pressure, c / sqrt(dist) at each edge with c = (dP +- 2 dM0 / d) /
    (pi sqrt(2 d)) and dM0 the moment increment about the contact centre; an
    edge where the pressure is k sqrt(dist) then moves outwards by 2 c / k.
    This is the exact linearisation of (N1, N2) at ``near``, from the pressure
    already built there (no moment evaluation). Where it is not finite or
    moves an edge by more than ``_WARM_REACH`` d, the contact of ``near`` itself.
    """
    x0, d = near.center, near.half_width
    try:
        with np.errstate(all="ignore"):
            d_left, d_right = near.edge_rates(P - near.P, M - near.M)
    except ZeroDivisionError:  # an edge without a square-root coefficient: no prediction
        return x0, d
    out_left, out_right = -d_left, d_right
    if math.isfinite(out_left) and math.isfinite(out_right) and max(abs(out_left), abs(out_right)) <= _WARM_REACH * d:
        return x0 + 0.5 * (out_right - out_left), d + 0.5 * (out_right + out_left)
    return x0, d


# ---------------------------------------------------------------------------
# Solutions
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class NormalSolution:
    """Contact under loads (P, M): edges, rigid rotation and pressure.

    Attributes
    ----------
    P, M : float
        Normal load [N/m] and moment about x = 0 [N].
    left, right : float
        Contact edges -a and c [m] (both 0.0 when separated).
    rotation : float
        Rigid rotation alpha of the pad in (N1) [rad].
    separated : bool
        True when P <= 0: no contact, zero pressure.
    iterations : int
        Newton iterations of the general solver (0 for the closed forms).
    residual : float
        Final scaled residual of the contact equations (0.0 for the closed forms).
    """

    P: float
    M: float
    left: float
    right: float
    rotation: float
    separated: bool
    iterations: int = 0
    residual: float = 0.0
    _pressure: _ContactPressure | None = field(default=None, repr=False, compare=False)

    @property
    def center(self) -> float:
        """Contact centre (left + right) / 2 [m]."""
        return 0.5 * (self.left + self.right)

    @property
    def half_width(self) -> float:
        """Contact half-width (right - left) / 2 [m]."""
        return 0.5 * (self.right - self.left)

    def pressure(self, x: ArrayLike) -> FloatArray:
        """Pressure p(x) [Pa]; ``x`` of any shape, result of the same shape, 0 outside (left, right)."""
        if self._pressure is None:
            return np.zeros(np.shape(x))[()]
        return self._pressure(x)[()]

    def pressure_arguments(self) -> tuple:
        """The arguments after the points of the compiled pressure (_geometry_kernels._pressure_at), for
        callers that evaluate it in compiled code; in contact only."""
        return self._pressure.arguments()

    def load_to(self, x: ArrayLike, magnitude: bool = False):
        """int p from the left edge to ``x`` [N/m] (0 left of the contact, P right of it), closed form;
        with ``magnitude`` also the size of the terms it sums (its rounding is about eps times that)."""
        if self._pressure is None:
            zero = np.zeros(np.shape(x))[()]
            return (zero, zero) if magnitude else zero
        out = self._pressure.load_to(x, magnitude)
        return (out[0][()], out[1][()]) if magnitude else out[()]

    def edge_rates(self, dP: float, dM: float) -> tuple[float, float]:
        """(dL, dR): how the contact edges move, to first order, under load increments (dP, dM) (N3).

        The increments add the flat-punch pressure c / sqrt(dist) at each edge,
        c = (dP -+ 2 dM0 / d) / (pi sqrt(2 d)) with dM0 the moment increment about
        the contact centre; an edge where the pressure is k sqrt(dist) moves
        outwards by 2 c / k (k exact, ``_ContactPressure.edge_coefficients``).
        """
        d = self.half_width
        k_left, k_right = self._pressure.edge_coefficients()
        dM0 = dM - dP * self.center
        base = math.pi * math.sqrt(2.0 * d)
        return -2.0 * (dP - 2.0 * dM0 / d) / (base * k_left), 2.0 * (dP + 2.0 * dM0 / d) / (base * k_right)


# ---------------------------------------------------------------------------
# Symmetric fast paths (M = 0)
# ---------------------------------------------------------------------------


class _SymmetricForms(abc.ABC):
    """a(P), P(a) and p(x, P) of a symmetric profile under M = 0, vectorised."""

    cheap_half_width = True  # then a(P) is a good start for the general solver

    @abc.abstractmethod
    def half_width(self, P: FloatArray) -> FloatArray: ...

    @abc.abstractmethod
    def load(self, a: FloatArray) -> FloatArray: ...

    @abc.abstractmethod
    def pressure(self, x: FloatArray, P: FloatArray) -> FloatArray:
        """p(x, P) for x and P of one (broadcast) shape."""

    def contact(self, P: float, M: float) -> tuple[float, float] | None:
        """(centre, half-width) in closed form, or None when the general solver is needed."""
        return (0.0, float(self.half_width(np.array(P)))) if M == 0.0 else None


class _HertzForms(_SymmetricForms):
    """a^2 = 2 A R P / pi, p = sqrt(a^2 - x^2) / (A R); a moment shifts the contact to x0 = M / P."""

    def __init__(self, radius: float, compliance: float) -> None:
        self.AR = compliance * radius

    def half_width(self, P: FloatArray) -> FloatArray:
        return np.sqrt(2.0 * self.AR * np.maximum(P, 0.0) / math.pi)

    def load(self, a: FloatArray) -> FloatArray:
        return np.where(a > 0.0, math.pi * a * a / (2.0 * self.AR), 0.0)

    def pressure(self, x: FloatArray, P: FloatArray) -> FloatArray:
        a = self.half_width(P)
        return np.sqrt(np.maximum((a - x) * (a + x), 0.0)) / self.AR

    def contact(self, P: float, M: float) -> tuple[float, float]:
        return M / P, float(self.half_width(np.array(P)))


_CYCLOID_SERIES = np.array([(-1.0) ** k / math.factorial(2 * k + 3) for k in range(9)])


def _cycloid(u: FloatArray) -> FloatArray:
    """u - sin(u) without cancellation: its Taylor series (9 terms, 1e-17 at u = 1) below u = 1."""
    small = u < 1.0
    us = np.where(small, u, 0.0)
    series = us**3 * np.polynomial.polynomial.polyval(us * us, _CYCLOID_SERIES)
    return np.where(small, series, u - np.sin(u))


class _PunchForms(_SymmetricForms):
    """Rounded punch under M = 0, a > w.

    P = a^2 (u - sin u) / (2 A R) with u = pi - 2 asin(w / a), and

        p(x) = (u sqrt(a^2 - x^2) + (x - w) L(x, w) - (x + w) L(x, -w)) / (pi A R),
        L(x, t) = ln| (a^2 - x t + sqrt(a^2 - x^2) sqrt(a^2 - t^2)) / (a (t - x)) |,

    the general piecewise formula for this profile. a(P) comes from Newton's
    method on ln P as a function of y = ln(a - w), close to linear both for
    a -> w (P ~ (a - w)^(3/2)) and for a >> w (P ~ a^2), started from the
    matching asymptote and kept below a - w = a_Hertz(P).
    """

    def __init__(self, flat_half_width: float, radius: float, compliance: float) -> None:
        self.w = flat_half_width
        self.AR = compliance * radius

    def _angle(self, excess: FloatArray) -> FloatArray:
        """u = 2 acos(w / a) from the excess a - w, accurate for a tiny excess."""
        return 2.0 * np.arctan2(np.sqrt(excess * (2.0 * self.w + excess)), self.w)

    def load(self, a: FloatArray) -> FloatArray:
        excess = np.maximum(a - self.w, 0.0)
        return (self.w + excess) ** 2 * _cycloid(self._angle(excess)) / (2.0 * self.AR)

    def half_width(self, P: FloatArray) -> FloatArray:
        positive = P > 0.0
        target = np.where(positive, P, 1.0)
        w = self.w
        kappa = 2.0 * self.AR * target / (w * w)
        small = np.cbrt(0.75 * np.minimum(kappa, 1.0))  # kappa ~ 4 delta^3 / 3, a = w / cos(delta)
        excess_small = w * 2.0 * np.sin(0.5 * small) ** 2 / np.cos(small)
        excess_large = (2.0 * w + np.sqrt(4.0 * w * w + 2.0 * math.pi * self.AR * target)) / math.pi - w
        hertz = np.sqrt(2.0 * self.AR * target / math.pi)
        y_max = np.log(hertz)
        y = np.minimum(np.log(np.where(kappa < 1.0, excess_small, excess_large)), y_max)
        log_target = np.log(target)
        for _ in range(_MAX_NEWTON_ITER):
            excess = np.exp(y)
            a = w + excess
            u = self._angle(excess)
            cycloid = _cycloid(u)
            log_load = np.log(a * a * cycloid / (2.0 * self.AR))
            # d ln P / dy = 2 (a - w) u / (a (u - sin u))
            step = (log_target - log_load) * a * cycloid / (2.0 * excess * u)
            y = np.minimum(y + step, y_max)
            if np.all(np.abs(step) <= 1e-12):
                break
        return np.where(positive, w + np.exp(y), 0.0)

    def pressure(self, x: FloatArray, P: FloatArray) -> FloatArray:
        a = self.half_width(P)
        inside = np.abs(x) < a
        x, a = x[inside], a[inside]
        total = self._angle(a - self.w) * np.sqrt((a - x) * (a + x))
        for knot in (-self.w, self.w):
            jump = math.copysign(1.0, knot) * (x - knot)
            with np.errstate(invalid="ignore"):  # 0 * inf on the knot, where the term is 0
                total = total + np.where(x == knot, 0.0, jump * _log_kernel(x, knot, -a, a, a))
        out = np.zeros(P.shape)
        out[inside] = total / (math.pi * self.AR)
        return out


_BATCH_ELEMENTS = 1 << 18  # half-width-piece pairs per batch of _NumericalForms: ~60 MB of temporaries


class _NumericalForms(_SymmetricForms):
    """A symmetric tabulated profile: P(a) = (a / A) I_1(0, a), a(P) by a bracketed Newton iteration.

    The loads at the half-widths a = x_k (the positive samples) are computed
    once; they bracket each root within one sample interval, where Newton's
    method started by linear interpolation converges in a few steps.
    """

    cheap_half_width = False

    def __init__(self, profile: TabulatedProfile, compliance: float) -> None:
        self.pieces = profile._slope_pieces
        self.A = compliance
        self.limit = profile.span[1]
        self.sizes = np.append(self.pieces.breaks[self.pieces.breaks > 0.0], self.limit)

    @cached_property
    def _size_loads(self) -> FloatArray:
        """P(x_k), made non-decreasing (a non-convex profile may lose load as a grows).

        A batch of B half-widths over J pieces takes about 240 B J bytes of
        temporaries; long tables are done in batches of at most
        _BATCH_ELEMENTS half-width-piece pairs (the same numbers, bounded memory).
        """
        sizes = self.sizes
        batch = max(1, _BATCH_ELEMENTS // max(1, self.pieces.breaks.size + 1))
        if sizes.size <= batch:
            loads = self.load(sizes)
        else:
            loads = np.concatenate([self.load(sizes[i:i + batch]) for i in range(0, sizes.size, batch)])
        return np.maximum.accumulate(loads)

    def load(self, a: FloatArray) -> FloatArray:
        if np.any(a > self.limit):
            raise ProfileSpanError(
                f"half-width {np.max(a):g} too large for the tabulated profile: "
                f"the contact would leave the tabulated span [{-self.limit:g}, {self.limit:g}]"
            )
        flat = np.maximum(a.ravel(), 0.0)
        I1 = _chebyshev_moments(self.pieces, np.zeros_like(flat), flat).slope[:, 1]
        return np.where(a > 0.0, (flat * I1 / self.A).reshape(a.shape), 0.0)

    def half_width(self, P: FloatArray) -> FloatArray:
        flat = P.ravel()
        positive = flat > 0.0
        out = np.zeros_like(flat)
        if np.any(positive):
            targets = flat[positive]
            loads = self._size_loads
            if np.max(targets) > loads[-1]:
                raise ProfileSpanError(
                    f"load {np.max(targets):g} too large for the tabulated profile: the contact would "
                    f"leave the tabulated span [{-self.limit:g}, {self.limit:g}] (beyond P = {loads[-1]:g})"
                )
            k = np.searchsorted(loads, targets)  # loads[k - 1] < P <= loads[k]
            upper = self.sizes[k]
            lower = np.where(k > 0, self.sizes[k - 1], 0.0)
            load_lower = np.where(k > 0, loads[k - 1], 0.0)
            start = lower + (upper - lower) * (targets - load_lower) / (loads[k] - load_lower)
            zeros = np.zeros_like(targets)
            out[positive] = _half_width_at(self.pieces, self.A, zeros, targets, lower, upper, 4.0 * _EPS, start)
        return out.reshape(P.shape)

    def pressure(self, x: FloatArray, P: FloatArray) -> FloatArray:
        out = np.zeros(P.shape)
        levels, which = np.unique(P, return_inverse=True)
        which = which.reshape(P.shape)
        for i, (level, a) in enumerate(zip(levels, self.half_width(levels))):
            if level > 0.0:
                mask = which == i
                out[mask] = _ContactPressure.build(self.pieces, self.A, 0.0, float(a))(x[mask])
        return out


# ---------------------------------------------------------------------------
# The normal problem
# ---------------------------------------------------------------------------


class NormalProblem:
    """Normal contact of a profile with an elastically similar half-plane (N1, N2).

    Parameters
    ----------
    profile : Profile
    compliance : float
        Composite compliance A [1/Pa] (``Material.compliance``).
    tol : float, optional
        Resolution knob of the general solver: it stops when the load and
        moment equations hold to ``tol`` relative (the moment relative to
        |M| + P d), or to rounding where that is coarser. The integrals and
        the pressure are exact for the piecewise-quadratic slopes used here,
        so this is the only knob: the edges come out to about ``tol``
        relative for the analytic profiles. For tabulated profiles the error
        is that of the spline through the samples.
    """

    def __init__(self, profile: Profile, compliance: float, *, tol: float = 1e-13) -> None:
        if not isinstance(profile, Profile):
            raise ValueError(f"profile must be a Profile, got {type(profile).__name__}")
        if not 0.0 < tol < 1.0:
            raise ValueError(f"tol must lie in (0, 1), got {tol!r}")
        self.profile = profile
        self.compliance = _require_positive("compliance", compliance)
        self.tol = float(tol)
        self._pieces = profile._slope_pieces
        self._forms = self._symmetric_forms()

    def _symmetric_forms(self) -> _SymmetricForms | None:
        profile, A = self.profile, self.compliance
        if isinstance(profile, Hertz):
            return _HertzForms(profile.radius, A)
        if isinstance(profile, RoundedPunch):
            if profile.flat_half_width == 0.0:
                return _HertzForms(profile.radius, A)
            return _PunchForms(profile.flat_half_width, profile.radius, A)
        if isinstance(profile, TabulatedProfile) and profile.symmetric:
            return _NumericalForms(profile, A)
        return None

    def __repr__(self) -> str:
        return f"NormalProblem({self.profile!r}, compliance={self.compliance!r}, tol={self.tol!r})"

    # -- any profile, any moment ----------------------------------------------

    def solve(self, P: float, M: float = 0.0, near: NormalSolution | None = None) -> NormalSolution:
        """Contact edges, rotation and pressure under loads (P, M) (N1, N2).

        Closed forms serve Hertz (any M) and the rounded punch under M = 0;
        the general solver serves everything else.

        Parameters
        ----------
        P : float
            Normal load [N/m]; P <= 0 gives a separated solution.
        M : float, optional
            Moment about x = 0 [N].
        near : NormalSolution, optional
            A solution of this problem at nearby loads (e.g. the previous
            sub-step's). The general solver then starts its Newton iteration
            at the first-order prediction from ``near`` instead of searching
            for a start; when that iteration does not converge in
            ``_MAX_WARM_ITER`` iterations it starts cold as without ``near``.
            The answer agrees with the cold one to the solver's tolerance
            (``iterations`` counts the warm iterations). Ignored by the closed
            forms and when ``near`` is separated.

        Raises
        ------
        ValueError
            If P or M is not finite, if no contact inside a tabulated
            profile's span carries (P, M), if the general solver does not
            converge, or if ``near`` is neither None nor a NormalSolution.
        """
        P, M = self._loads(P, M)
        if near is not None and not isinstance(near, NormalSolution):
            raise ValueError(f"near must be a NormalSolution or None, got {type(near).__name__}")
        if not P > 0.0:
            return self._separated(P, M)
        closed = self._forms.contact(P, M) if self._forms is not None else None
        if closed is not None:
            return self._solution(P, M, *closed)
        if near is not None:
            warm = self._solve_warm(P, M, near)
            if warm is not None:
                return warm
        # the cold start: its search begins at the symmetric half-width where that is cheap (not needed
        # when the warm start decides: a fifth of a warm solve's time on the rounded punch)
        guess = None
        if self._forms is not None and self._forms.cheap_half_width:
            guess = float(self._forms.half_width(np.array(P)))
        return self._solve_general(P, M, guess)

    @staticmethod
    def _loads(P: float, M: float) -> tuple[float, float]:
        P, M = float(P), float(M)
        if not (math.isfinite(P) and math.isfinite(M)):
            raise ValueError(f"P and M must be finite, got P={P!r}, M={M!r}")
        return P, M

    @staticmethod
    def _separated(P: float, M: float) -> NormalSolution:
        return NormalSolution(P=P, M=M, left=0.0, right=0.0, rotation=0.0, separated=True)

    def _solve_general(self, P: float, M: float, half_width_guess: float | None = None) -> NormalSolution:
        """The general solver started cold, for any profile (also those with closed forms, to test it on them;
        ``solve`` tries the warm start first)."""
        P, M = self._loads(P, M)
        if not P > 0.0:
            return self._separated(P, M)
        result = _solve_contact_equations(
            self.profile, self.compliance, P, M, tol=self.tol, half_width_guess=half_width_guess
        )
        lowest, highest = _span(self.profile)
        tabulated = math.isfinite(lowest)
        if not result.converged:
            why = (
                "the load or the moment is too large for the tabulated span, or the load so small that "
                "the samples' roughness (not convex, e.g. spline ringing at a kink) breaks the single contact"
                if tabulated
                else "the general solver did not converge"
            )
            raise ProfileSpanError(
                f"no contact found for P={P!r}, M={M!r} (residual {result.residual:.3g} after "
                f"{result.iterations} iterations): {why}"
            )
        left, right = result.center - result.half_width, result.center + result.half_width
        slack = 1e-12 * (highest - lowest) if tabulated else 0.0
        if left < lowest - slack or right > highest + slack:
            raise ProfileSpanError(
                f"load too large for the tabulated profile: the contact [{left:g}, {right:g}] under "
                f"P={P!r}, M={M!r} leaves the tabulated span [{lowest:g}, {highest:g}]"
            )
        return self._solution(P, M, result.center, result.half_width, result.iterations, result.residual)

    def _solve_warm(self, P: float, M: float, near: NormalSolution) -> NormalSolution | None:
        """The general solver started from ``near`` (``_warm_contact``); None where the cold start must decide.

        None when ``near`` is separated, when the iteration does not converge
        in ``_MAX_WARM_ITER`` iterations or leaves its trust checks, and when
        the contact found leaves a tabulated span (the cold start then gives
        the answer, or today's error).
        """
        if near.separated or near._pressure is None or not (near.half_width > 0.0 and near.P > 0.0):
            return None
        start = _warm_contact(near, P, M)
        if not (math.isfinite(start[0]) and math.isfinite(start[1]) and start[1] > 0.0):
            return None
        result = _solve_contact_equations(
            self.profile, self.compliance, P, M, tol=self.tol, max_iter=_MAX_WARM_ITER, start=start
        )
        if not result.converged:
            return None
        left, right = result.center - result.half_width, result.center + result.half_width
        lowest, highest = _span(self.profile)
        if not (lowest <= left and right <= highest):
            return None
        return self._solution(P, M, result.center, result.half_width, result.iterations, result.residual)

    def _solution(
        self, P: float, M: float, center: float, half_width: float, iterations: int = 0, residual: float = 0.0
    ) -> NormalSolution:
        from ._geometry_kernels import _contact_solution

        center, half_width = float(center), float(half_width)
        pieces = self._pieces
        slope, sum0, sum1, klo, khi = _contact_solution(center, half_width, pieces.breaks, pieces.lower,
                                                        pieces.upper, pieces.coeffs, pieces.origins,
                                                        _SLOPE_MOMENTS, _CURVATURE_MOMENTS)
        d = half_width
        smooth = (d * sum0, d * d * sum1)
        return NormalSolution(
            P=P,
            M=M,
            left=center - half_width,
            right=center + half_width,
            rotation=-float(slope) / math.pi,
            separated=False,
            iterations=iterations,
            residual=residual,
            _pressure=_ContactPressure(center, d, self.compliance, pieces.breaks[klo:khi], pieces.jumps[klo:khi],
                                       smooth),
        )

    # -- symmetric profiles, M = 0 ---------------------------------------------

    def _symmetric(self) -> _SymmetricForms:
        if self._forms is None:
            raise ValueError("half_width, load and pressure(x, P) need a symmetric profile; use solve(P, M)")
        return self._forms

    @property
    def cheap_half_width(self) -> bool:
        """Whether :meth:`half_width` and :meth:`load` are closed forms (Hertz, the rounded punch), not a
        root-finding over the profile's moments (a symmetric tabulated profile) or unavailable."""
        return self._forms is not None and self._forms.cheap_half_width

    def half_width(self, P: ArrayLike) -> FloatArray:
        """Half-width a(P) [m] of the symmetric contact [-a, a] under M = 0.

        Parameters
        ----------
        P : array_like, any shape
            Normal load [N/m].

        Returns
        -------
        ndarray, shape of ``P``
            0 where P <= 0; for the rounded punch a -> w as P -> 0+.
        """
        return self._symmetric().half_width(np.asarray(P, dtype=float))[()]

    def load(self, a: ArrayLike) -> FloatArray:
        """Load P(a) [N/m] that makes the symmetric contact [-a, a] under M = 0.

        Parameters
        ----------
        a : array_like, any shape
            Half-width [m].

        Returns
        -------
        ndarray, shape of ``a``
            0 where a <= 0 (rounded punch: a <= w).
        """
        return self._symmetric().load(np.asarray(a, dtype=float))[()]

    def pressure(self, x: ArrayLike, P: ArrayLike) -> FloatArray:
        """Pressure p(x, P) [Pa] of the symmetric contact under load P and M = 0.

        Parameters
        ----------
        x : array_like
            Positions [m].
        P : array_like
            Normal loads [N/m], broadcast against ``x``.

        Returns
        -------
        ndarray, the broadcast shape of ``x`` and ``P``
            0 outside |x| < a(P).
        """
        x, P = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(P, dtype=float))
        return self._symmetric().pressure(x, P)[()]
