"""The exact memory method for symmetric contacts with M = sigma = 0.

physics.md, end of "Varying P" (the Barber-Davies-Hills construction): the
whole tangential state is one function w(P') on the load levels 0 <= P' <= P,
abs(w) <= f, and

    q(x) = int w(P') dp(x, P')/dP' dP' = sum_k w_k [p(x, P_{k+1}) - p(x, P_k)],
    Q    = W(P) = int_0^P w dP'.

We carry the cumulative W(P') as a piecewise-linear function (knots P_k, W_k).
For a straight step (P0, Q0) -> (P1, Q1) the update is, exactly:

1. rising P: extend W on [P0, P1] with slope clip(dQ/dP, -f, f)  (memory rule M1);
   falling P: truncate W at P1 (the levels above leave the contact);
2. if W(P1) != Q1 the outermost levels slip with w = s f, s = sign(Q1 - W(P1)):
   W <- max(W, Q1 - f (P1 - P'))  (s = +1)   or   min(W, Q1 + f (P1 - P'))  (s = -1).

The knots below the crossing P_Y are untouched; the stick zone is
[-a(P_Y), a(P_Y)]. Incremental application along the segment gives the same W
as one step (the slip lines move monotonically), so the answer at a segment's
end does not depend on how finely the segment is sampled. Work per step is
proportional to the number of knots removed, plus one.

Derived quantities (all exact for straight steps):

* relative slip of a point x that entered contact at level P_x = P(a = |x|):
  Phi(x) = (A/pi) int_0^{P_x} w(P') arccosh(|x|/a(P')) dP', slip = change of Phi
  since arrival (the contact centre sticks unless the contact slides);
* rigid shift, datum of the log kernel at distance l = profile length scale:
  delta = v0 - (A/pi) [int w ln a dP' - W(P) ln(2 l)], v0 fixed while the centre sticks;
* dissipation: while the slip front (the crossing P_Y) sweeps level y, the rate is
  (A/pi) f (f - s w_old(y)) K(y; P) |dy|, K(y; P) = int_y^P ln(a(P')/a(y)) dP',
  integrated in closed form over each linear piece of the old W with the
  primitives of ``levels.py``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..geometry import NormalProblem
from ..state import GROSS_SLIDING_MESSAGE, ContactState, Loads, Regime, StepReport
from ..state import frozen as _frozen
from .base import TangentialSolver
from .levels import HertzLevels, LevelIntegrals, level_integrals

_EPS = np.finfo(float).eps


@dataclass(frozen=True)
class LevelMemory:
    """Piecewise-linear W(P') with its running integrals at the knots.

    Attributes
    ----------
    P : tuple of float, shape (n,)
        Knot load levels, P[0] = 0, increasing; P[-1] is the current load.
    W : tuple of float, shape (n,)
        W at the knots; W[-1] is the shear force carried.
    L : tuple of float, shape (n,)
        Lambda(P_k) = int_0^{P_k} ln a.
    C : tuple of float, shape (n,)
        int_0^{P_k} w ln a dP'.
    v0 : float
        Relative displacement of the stuck centre (changes only in gross sliding,
        where it is indeterminate under force control; we keep it).
    phi_ref : ndarray, shape (n_stations,), or None
        Phi of each tracked surface station when it last entered contact (NaN
        while out of contact); slip = Phi - phi_ref. None when slip is not tracked.
    """

    P: tuple
    W: tuple
    L: tuple
    C: tuple
    v0: float = 0.0
    phi_ref: np.ndarray | None = None

    @classmethod
    def empty(cls, phi_ref: np.ndarray | None = None) -> "LevelMemory":
        return cls((0.0,), (0.0,), (0.0,), (0.0,), 0.0, phi_ref)

    def slopes(self) -> np.ndarray:
        P = np.asarray(self.P)
        W = np.asarray(self.W)
        return np.diff(W) / np.diff(P) if len(P) > 1 else np.zeros(0)


@dataclass(frozen=True)
class _Trial:
    """W after extension/truncation, before slip."""

    P: list
    W: list
    L: list
    C: list


class ExactMemory(TangentialSolver):
    """Tangential solver: exact memory of load levels (symmetric, M = sigma = 0).

    Parameters
    ----------
    problem : NormalProblem
        Normal problem of a symmetric profile.
    friction : float
        Coulomb coefficient f.
    P_max : float
        Largest normal load of the history (sizes the level tables).
    stations : array_like, shape (n_stations,), optional
        Surface points whose accumulated slip is tracked (only when slip is stored).
    """

    name = "exact"

    def __init__(self, problem: NormalProblem, friction: float, P_max: float, stations=None):
        if not problem.profile.symmetric:
            raise ValueError("the exact method needs a symmetric profile")
        self.problem = problem
        self.f = float(friction)
        self.A = problem.compliance
        self.levels: LevelIntegrals = level_integrals(problem, max(P_max, 0.0))
        self.datum = problem.profile.length_scale
        self._ln2l = math.log(2.0 * self.datum)
        self.stations = None if stations is None else np.asarray(stations, float)
        self._a_min = float(problem.half_width(1e-300 * max(P_max, 1.0)))  # a(0+): w for a punch

    # ------------------------------------------------------------------
    def initial_state(self, t0: float = 0.0) -> ContactState:
        nan = float("nan")
        ref = None if self.stations is None else _frozen(np.full(self.stations.shape, np.nan))
        return ContactState(t0, Loads(0.0, 0.0, 0.0, 0.0), nan, nan, nan, nan, 0.0, 0.0, LevelMemory.empty(ref))

    # ------------------------------------------------------------------
    def _trial(self, mem: LevelMemory, P1: float, Q1: float) -> _Trial:
        """Extend (slope clip(dQ/dP)) or truncate W to [0, P1], no slip."""
        P, W, L, Cc = list(mem.P), list(mem.W), list(mem.L), list(mem.C)
        P0, Q0 = P[-1], W[-1]
        lv = self.levels
        if P1 > P0:
            k = (Q1 - Q0) / (P1 - P0)
            w = min(max(k, -self.f), self.f)
            L1 = lv.lam(P1)
            W1 = Q0 + w * (P1 - P0)
            through = W[-2] + (W1 - W[-2]) * (P0 - P[-2]) / (P1 - P[-2]) if len(P) > 1 else math.inf
            if abs(through - Q0) <= 64 * _EPS * (self.f * P1 + abs(W1) + abs(Q0)):
                # the old top knot lies on the line to the new one, to rounding:
                # move the top piece's end instead of adding a knot
                P[-1], W[-1], L[-1] = P1, W1, L1
                Cc[-1] = Cc[-2] + (W1 - W[-2]) / (P1 - P[-2]) * (L1 - L[-2])
            else:
                P.append(P1)
                W.append(W1)
                Cc.append(Cc[-1] + w * (L1 - L[-1]))
                L.append(L1)
        elif P1 < P0:
            while len(P) > 1 and P[-2] >= P1:
                P.pop(), W.pop(), L.pop(), Cc.pop()
            if len(P) == 1:  # P1 <= 0 reached the origin
                pass
            else:
                Pa, Pb = P[-2], P[-1]
                w = (W[-1] - W[-2]) / (Pb - Pa)
                L1 = lv.lam(P1)
                W[-1] = W[-2] + w * (P1 - Pa)
                Cc[-1] = Cc[-2] + w * (L1 - L[-2])
                L[-1] = L1
                P[-1] = P1
        return _Trial(P, W, L, Cc)

    def _slip(self, tr: _Trial, P1: float, Q1: float, s: int) -> tuple[float, bool]:
        """Apply the slip line of sign s through (P1, Q1) in place.

        Returns the stick level P_Y and whether the contact slides grossly.
        """
        f = self.f
        if s * Q1 >= f * P1:  # gross sliding: every level at w = s f
            lv = self.levels
            L1 = lv.lam(P1) if P1 > 0 else 0.0
            tr.P[:] = [0.0, P1] if P1 > 0 else [0.0]
            tr.W[:] = [0.0, s * f * P1] if P1 > 0 else [0.0]
            tr.L[:] = [0.0, L1] if P1 > 0 else [0.0]
            tr.C[:] = [0.0, s * f * L1] if P1 > 0 else [0.0]
            return 0.0, True
        c1 = s * Q1 - f * P1
        P, W, L, Cc = tr.P, tr.W, tr.L, tr.C
        # Pop knots strictly inside the slip band, H(P_j) < c1. Knots on the slip
        # line (within rounding) are kept: their levels already carry w = s f and
        # do not change, so the points they govern do not slip and the stick level
        # is the highest level still on or above the line.
        tol = 64 * _EPS * (f * P1 + abs(Q1))
        while len(P) > 1 and s * W[-2] - f * P[-2] < c1 - tol:
            P.pop(), W.pop(), L.pop(), Cc.pop()
        # crossing inside the piece (P[-2], P[-1]) -- or the top knot is the old top
        j = len(P) - 2
        Pa, Wa = P[j], W[j]
        Pb, Wb = P[-1], W[-1]
        w = (Wb - Wa) / (Pb - Pa) if Pb > Pa else s * f
        Ha = s * Wa - f * Pa
        denom = f - s * w
        y = Pa + (Ha - c1) / denom if denom > 0 else Pa
        y = min(max(y, Pa), P1)
        lv = self.levels
        del P[j + 1 :], W[j + 1 :], L[j + 1 :], Cc[j + 1 :]
        if y > Pa * (1 + 4 * _EPS) and y > 0:
            Ly = lv.lam(y)
            P.append(y)
            W.append(Wa + w * (y - Pa))
            Cc.append(Cc[-1] + w * (Ly - L[-1]))
            L.append(Ly)
        L1 = lv.lam(P1)
        P.append(P1)
        W.append(Q1)
        Cc.append(Cc[-1] + s * f * (L1 - L[-1]))
        L.append(L1)
        return y, False

    def _dissipation(self, mem: LevelMemory, P1: float, Q1: float, s: int) -> float:
        """Energy dissipated during the straight step, exact (see module doc)."""
        f = self.f
        P, W = mem.P, mem.W
        P0, Q0 = P[-1], W[-1]
        dP = P1 - P0
        c0 = s * Q0 - f * P0
        c1 = s * Q1 - f * P1
        dc = c1 - c0
        if dc <= 0.0:
            return 0.0
        c_end = min(c1, 0.0)  # beyond H(0) = 0 the contact slides grossly
        lv = self.levels
        total = 0.0
        for j in range(len(P) - 2, -1, -1):  # from the top down, as the front travels
            Pa, Pb = P[j], P[j + 1]
            if s * W[j + 1] - f * Pb >= c_end:
                break  # H at this piece's top is above the front's final level: done
            if Pb <= Pa:
                continue
            w = (W[j + 1] - W[j]) / (Pb - Pa)
            slope = f - s * w  # -dH/dy on this piece
            if slope <= 1e-12 * f:
                continue  # levels already slipping this way: no new slip from here
            Ha = s * W[j] - f * Pa
            lo = max(Pa, Pa + (Ha - c_end) / slope)
            hi = min(Pb, Pa + (Ha - c0) / slope)
            if lo >= hi:
                continue
            # P at the instant the front is at y: alpha + beta y
            beta = -dP * slope / dc
            alpha = P0 + dP * (Ha + slope * Pa - c0) / dc
            if dP < 0.0:  # front must lie inside the (shrinking) contact: y < alpha + beta y
                if beta < 1.0:
                    hi = min(hi, alpha / (1.0 - beta))
                elif beta > 1.0:
                    lo = max(lo, alpha / (1.0 - beta))
                elif alpha <= 0.0:
                    continue
                if lo >= hi:
                    continue
            # K >= 0; a negative value is cancellation for a sliver of front travel
            total += f * slope * max(self._kernel_integral(alpha, beta, lo, hi), 0.0)
        return self.A / math.pi * total

    def _kernel_integral(self, alpha, beta, lo, hi) -> float:
        """int_lo^hi K(y; alpha + beta y) dy, K(y; P) = Lambda(P) - Lambda(y) - (P - y) ln a(y)."""
        lv = self.levels
        width = hi - lo
        if abs(beta) * width > 1e-7 * max(abs(alpha), hi):
            t1 = (lv.psi(alpha + beta * hi) - lv.psi(alpha + beta * lo)) / beta
        else:  # P nearly constant over the piece: midpoint of Lambda(P(y)), error O(beta^2 width^3)
            t1 = lv.lam(alpha + beta * 0.5 * (lo + hi)) * width
        return (
            t1
            - (lv.psi(hi) - lv.psi(lo))
            - alpha * (lv.lam(hi) - lv.lam(lo))
            - (beta - 1.0) * (lv.xi(hi) - lv.xi(lo))
        )

    # ------------------------------------------------------------------
    def advance_memory(self, mem: LevelMemory, P1: float, Q1: float):
        """One straight step of the level memory.

        Returns
        -------
        new : LevelMemory
        regime : Regime
        stick_level : float
            P_Y; the stick zone is [-a(P_Y), a(P_Y)] (P1 when all sticks, 0 when
            sliding or separated).
        dissipated : float
            Energy dissipated during the step [J/m].
        """
        P1 = max(float(P1), 0.0)
        Q1 = float(Q1)
        P0, Q0 = mem.P[-1], mem.W[-1]
        tr = self._trial(mem, P1, Q1)
        scale = self.f * max(P0, P1) + abs(Q1) + abs(Q0)
        mismatch = Q1 - tr.W[-1]
        if abs(mismatch) <= 16 * _EPS * scale:
            tr.W[-1] = Q1 if len(tr.P) > 1 else 0.0
            regime = Regime.STICK if P1 > 0 else Regime.SEPARATED
            stick_level, dissipated = P1, 0.0
        else:
            s = 1 if mismatch > 0 else -1
            dissipated = self._dissipation(mem, P1, Q1, s)
            stick_level, gross = self._slip(tr, P1, Q1, s)
            regime = Regime.GROSS_SLIDING if gross else Regime.PARTIAL_SLIP
        if P1 <= 0.0:
            return LevelMemory((0.0,), (0.0,), (0.0,), (0.0,), mem.v0, mem.phi_ref), Regime.SEPARATED, 0.0, dissipated
        new = LevelMemory(tuple(tr.P), tuple(tr.W), tuple(tr.L), tuple(tr.C), mem.v0, mem.phi_ref)
        return new, regime, stick_level, dissipated

    def _track_arrivals(self, state: ContactState, new: LevelMemory, loads1: Loads) -> LevelMemory:
        """Update phi_ref: stations leaving contact forget, arriving ones stick at arrival.

        A station entering during the step sticks from the instant its gap closes
        (physics.md, first trap): its reference is Phi at the intermediate load
        where a(P) = |x|, found by advancing the memory along the same straight step.
        """
        if self.stations is None:
            return new
        X = np.abs(self.stations)
        P0, Q0 = state.loads.P, state.loads.Q
        P1, Q1 = max(loads1.P, 0.0), loads1.Q
        a0 = float(self.problem.half_width(P0)) if P0 > 0 else 0.0
        a1 = float(self.problem.half_width(P1)) if P1 > 0 else 0.0
        ref = np.array(new.phi_ref if new.phi_ref is not None else np.full(X.shape, np.nan))
        ref[X >= a1] = np.nan
        if P1 > 0 and P0 <= 0:
            a0 = -1.0  # every station inside the new contact arrives during this step
        for i in np.flatnonzero((X >= a0) & (X < a1)):
            P_x = self._entry_level(X[i:i + 1])[0]
            lam = (P_x - max(P0, 0.0)) / (P1 - max(P0, 0.0))
            mem_x = self.advance_memory(state.memory, P_x, Q0 + lam * (Q1 - Q0))[0]
            ref[i] = self.phi(mem_x, X[i:i + 1], inclusive=True)[0] if P_x > 0 else 0.0
        return LevelMemory(new.P, new.W, new.L, new.C, new.v0, _frozen(ref))

    def _entry_level(self, X: np.ndarray) -> np.ndarray:
        """Load level at which |x| = a(P) enters contact (0 inside a(0+))."""
        X = np.asarray(X, float)
        out = np.zeros_like(X)
        beyond = X > self._a_min
        if beyond.any():
            out[beyond] = self.problem.load(X[beyond])
        return out

    # ------------------------------------------------------------------
    def step(self, state: ContactState, t1: float, loads1: Loads) -> tuple[ContactState, StepReport]:
        """Advance ``state`` to time ``t1`` and loads ``loads1`` along a straight line."""
        mem, regime, stick_level, dD = self.advance_memory(state.memory, loads1.P, loads1.Q)
        mem = self._track_arrivals(state, mem, loads1)
        P_changed = loads1.P != state.loads.P
        if regime == Regime.SEPARATED:
            a = float("nan")
        elif P_changed or math.isnan(state.contact_right):
            a = float(self.problem.half_width(mem.P[-1]))  # the normal problem, M = 0: a(P)
        else:
            a = state.contact_right  # P unchanged: reuse the normal solution
        if regime in (Regime.STICK, Regime.PARTIAL_SLIP):
            b = a if regime == Regime.STICK else float(self.problem.half_width(stick_level))
            stick = (-b, b)
        else:
            stick = (float("nan"), float("nan"))
        message = ""
        if regime == Regime.GROSS_SLIDING and abs(loads1.Q) > self.f * loads1.P * (1 + 1e-12):
            message = GROSS_SLIDING_MESSAGE
        new_state = ContactState(
            t=float(t1),
            loads=loads1,
            contact_left=-a,
            contact_right=a,
            stick_left=stick[0],
            stick_right=stick[1],
            shift=self.shift(mem),
            dissipation=state.dissipation + dD,
            memory=mem,
        )
        report = StepReport(regime, regime in (Regime.PARTIAL_SLIP, Regime.GROSS_SLIDING), P_changed, message,
                            error_estimate=0.0, shear_error_estimate=0.0)
        return new_state, report

    @property
    def can_march(self) -> bool:
        """Whether :meth:`march` (compiled, Hertz, extents only) serves this instance."""
        from ._exact_kernel import march_hertz

        return march_hertz is not None and isinstance(self.levels, HertzLevels) and self.stations is None

    def march(self, state: ContactState, t: np.ndarray, P: np.ndarray, Q: np.ndarray):
        """Many straight steps at once, compiled (see ``_exact_kernel``); extents only.

        Parameters
        ----------
        state : ContactState
        t, P, Q : ndarray, shape (k,)
            Times and loads of the next k sampled points.

        Returns
        -------
        state : ContactState
            The state after the last point.
        steps : dict of ndarray, shape (k,)
            Per step: ``regime``, ``contact_left/right``, ``stick_left/right``,
            ``shift``, ``dissipation`` (cumulative), ``normal_solved``.
        """
        from ._exact_kernel import march_hertz

        mem = state.memory
        k = len(P)
        n = len(mem.P)
        cap = n + 2 * k + 2
        arrays = [np.zeros(cap) for _ in range(4)]
        for a, src in zip(arrays, (mem.P, mem.W, mem.L, mem.C)):
            a[:n] = src
        level, regime, D = np.empty(k), np.empty(k, np.int8), np.empty(k)
        top_W, top_C = np.empty(k), np.empty(k)
        P = np.asarray(P, float)
        n = march_hertz(*arrays, n, P, np.asarray(Q, float), self.f, self.A, self.levels.ln_alpha,
                        state.dissipation, level, regime, D, top_W, top_C)
        a = np.where(regime > 0, self.problem.half_width(np.maximum(P, 0.0)), np.nan)
        b = np.where(regime == Regime.STICK, a, np.where(regime == Regime.PARTIAL_SLIP,
                                                       self.problem.half_width(level), np.nan))
        shift = mem.v0 - self.A / math.pi * (top_C - top_W * self._ln2l)
        previous_P = np.concatenate([[state.loads.P], P[:-1]])
        new_mem = LevelMemory(*(tuple(x[:n].tolist()) for x in arrays), mem.v0, mem.phi_ref)
        last = ContactState(float(t[-1]), Loads(float(P[-1]), float(Q[-1]), 0.0, 0.0), float(-a[-1]), float(a[-1]),
                            float(-b[-1]), float(b[-1]), float(shift[-1]), float(D[-1]), new_mem)
        steps = {"regime": regime, "contact_left": -a, "contact_right": a, "stick_left": -b, "stick_right": b,
                 "shift": shift, "dissipation": D, "normal_solved": P != previous_P}
        return last, steps

    def same_state(self, a: ContactState, b: ContactState) -> bool:
        """Whether two states have the same memory, to rounding (1e-12 of f P_max).

        Used to detect a steady cycle: the knots of W and the slip references
        must agree; the dissipation and the time may differ.
        """
        ma, mb = a.memory, b.memory
        if len(ma.P) != len(mb.P):
            return False
        scale = max(ma.P[-1], mb.P[-1], 1e-300)
        if not (np.allclose(ma.P, mb.P, rtol=0, atol=1e-12 * scale)
                and np.allclose(ma.W, mb.W, rtol=0, atol=1e-12 * self.f * scale)):
            return False
        if ma.phi_ref is None:
            return True
        slip_scale = self.A * self.f * scale
        return bool(np.allclose(ma.phi_ref, mb.phi_ref, rtol=0, atol=1e-12 * slip_scale, equal_nan=True))

    # -- reconstruction ---------------------------------------------------
    def shift(self, mem: LevelMemory) -> float:
        """Rigid shift delta, datum of the log kernel at distance l = profile length scale."""
        return mem.v0 - self.A / math.pi * (mem.C[-1] - mem.W[-1] * self._ln2l)

    def tractions(self, mem: LevelMemory, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Pressure p(x) and shear traction q(x), shape (nx,) each."""
        x = np.asarray(x, float)
        P = np.asarray(mem.P)
        if len(P) == 1:
            z = np.zeros_like(x)
            return z, z.copy()
        p_levels = self.problem.pressure(x[:, None], P[None, :])  # (nx, n)
        q = np.diff(p_levels, axis=1) @ mem.slopes()
        return p_levels[:, -1], q

    def phi(self, mem: LevelMemory, x: np.ndarray, inclusive: bool = False) -> np.ndarray:
        """Phi(x) = (A/pi) int_{a(P') < |x|} w arccosh(|x|/a) dP' for points in contact.

        NaN outside the contact (``inclusive`` admits the edge itself).
        """
        X = np.abs(np.asarray(x, float))
        P = np.asarray(mem.P)
        out = np.full(X.shape, np.nan)
        if len(P) == 1:
            return out
        a_top = float(self.problem.half_width(P[-1]))
        # inclusive: a station arriving at the edge, where a(load(|x|)) may round an ulp below |x|
        inside = X <= a_top * (1 + 16 * _EPS) if inclusive else X < a_top
        Xi = X[inside]
        P_X = np.minimum(self._entry_level(Xi), P[-1])
        w = mem.slopes()
        lo = np.minimum(P[None, :-1], P_X[:, None])
        hi = np.minimum(P[None, 1:], P_X[:, None])
        J = self.levels.arccosh_integral(Xi[:, None], P_X[:, None], lo, hi)
        out[inside] = self.A / math.pi * (J @ w)
        return out

    def slip(self, mem: LevelMemory) -> np.ndarray:
        """Accumulated slip of each tracked station since it entered contact (NaN outside)."""
        if self.stations is None or mem.phi_ref is None:
            raise ValueError("slip is tracked only when the method is built with stations")
        return self.phi(mem, self.stations) - mem.phi_ref


