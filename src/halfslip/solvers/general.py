"""The general tangential slip solver: any profile, P, Q, M and sigma all varying.

Formulation (docs/general_solver.md has the derivation and the error study).
The memory is the locked-in relative strain E(x) = Delta-eps (T1) of every
material point in contact, kept at material points (``_general_points``): a
fixed lattice, the contact edges, the breakpoints of h', and clusters where E
has a square-root singularity. A stuck point keeps its E; a slipping point
takes the current Delta-eps; a point leaving contact forgets; a point entering
during a step gets the strain it has at the instant its gap closes (physics.md,
first trap), from the memory rule (M1) in strain form (``_general_path``).
The shear traction is never stored: on the stick zone it is the bounded
solution of the Cauchy singular integral equation whose right-hand side is E
(T1), and +-f p in the slip zones (``_general_zones``).

A step along the straight line from ``state.loads`` to ``loads1``:

1. normal problem at the end (skipped when P and M are unchanged);
2. arrival strains of the points entering the contact;
3. the no-slip test (S1) at the start and at the end contact, with the
   half-width d and the moment increment dM0 = dM - dP x0 about the contact
   centre: abs(dQ -+ (pi/4) d dsigma) < f (dP -+ 2 dM0 / d) at both edges.
   While it holds the whole contact sticks (no slip solve): the arrivals carry
   the fully stuck increments of M1 with the sigma term of T2, and q follows
   from E;
4. otherwise slip zones at one edge or both, of either sign, growing or
   receding: the stick edges satisfy consistency and equilibrium, and the
   configuration is checked against Coulomb (abs(q) <= f p on the stick zone)
   and the slip direction (q . dslip >= 0);
5. E takes Delta-eps in the slip zones; slip, dissipation and rigid shift are
   updated.

Gross sliding (abs(Q) >= f P: q = sign(Q) f p) and separation (P <= 0: all
memory lost) are states the march passes through.

Rigid shift: the relative tangential displacement of surface point x is
g(x) = delta + (A/pi) int q(xi) ln(abs(x - xi) / l) dxi + A sigma x / 4 with the
datum l = ``datum`` = profile length scale (as the exact method); delta follows
from a point stuck through the step. In gross sliding the middle of the
old/new contact overlap keeps its g (delta is indeterminate under force control).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..geometry import NormalProblem, NormalSolution, RoundedPunch, TabulatedProfile
from ..state import GROSS_SLIDING_MESSAGE, ContactState, Loads, Regime, StepReport
from ..state import frozen as _frozen
from .base import TangentialSolver
from . import _general_points as pts
from . import _general_sie as sie
from ._general_path import EdgePath, arrival_strains, outside_strain
from ._general_points import BREAK, CLUSTER, EDGE, LATTICE, SINGULAR_LEFT, SINGULAR_RIGHT
from ._general_zones import Config, Shear, Solution, StepProblem

#: Default resolution: lattice points per contact width (between nodes and 2 nodes).
DEFAULT_NODES = 512
#: Coulomb excess on the stick zone, relative to f max p, above which a step that passed the
#: no-slip test (S1) is re-solved with slip zones (S1 is exact for small steps; this catches
#: finite-step effects, not discretisation noise).
STICK_COULOMB_TOL = 1e-3
#: Where (S1) fails only at receding edges without a shear drive, full stick is accepted when
#: its consistency residual is below this fraction of f max p (rounding: q = 0 gives 0).
RECEDING_STICK_TOL = 1e-9
#: Accepted Coulomb excess of a slip-zone configuration, relative to f max p.
COULOMB_TOL = 1e-3
#: Accepted reversed slip in a slip zone, relative to the largest slip of the step.
DIRECTION_TOL = 0.05
#: Points at which a configuration is checked against Coulomb's law (with the square-root points
#: of E; sampling their square-root regions as well made the dovetail at 128 nodes 6x slower, by
#: rejecting configurations over excesses below 1e-2 that the stick-edge fix had already removed).
CHECK_POINTS = 64
#: A step whose slip solve finds no configuration that passes the checks is split in two
#: halves (the path stays straight), at most this many times over; so is a slipping step
#: over which a stuck edge advances by more than MAX_STRIP of the contact width (the strain
#: locked in by its arrivals depends on how the force was shared during the step, which
#: the gauge force F models to first order only).
MAX_SPLITS = 3
#: Halvings allowed to the step-size control (``edge_travel``): up to 2**CONTROL_SPLITS sub-steps.
CONTROL_SPLITS = 4
MAX_STRIP = 0.02
#: U-series terms of f chi p for its log potential (the rigid shift).
FIT_TERMS = 128
#: Lattice spacings from a stick edge within which slip-zone strains use the closed form.
NEAR_SPACINGS = 4.7  # not 4: cluster point 6 sits at exactly 4 h, and the choice flipped with rounding
#: A new stick edge within this many lattice spacings of an old singular point of its side is that
#: point: the edge moves onto it (far below the edge accuracy) and its exact stuck strain is kept. At
#: a load extreme of a cycle the reversed slip zone ends, exactly, at the stick edge of the previous
#: extreme; laid a rounding error eps beyond it, into the old slip zone, the new point took the
#: strain of that zone at eps (E' eps), which the linear interpolation to the next point (~0.1 h away)
#: spread over the stick zone, and the next extreme's edge moved by ~100 eps: a rounding error grew
#: by 1e2 per half cycle until the points no longer snapped (tension cycled alone, Hertz).
SNAP = 1e-6
#: Points next to a stick edge whose strain changes by less than this fraction of max abs(E) are
#: counted as stuck: they were locked at the slip limit with the same sign, and the equations
#: cannot place the edge within such a band (the exact method keeps them stuck). A tiny step
#: that continues a slip is trimmed whole by this and reported as stick (q stays right);
#: measuring against the step's own change instead fixed that but broke the periodicity of
#: in-phase cycles with tension and of the dovetail (stress tests): kept as it is.
TRIM_TOL = 1e-3
#: Two states are the same (a steady cycle is reached) when their contact and stick edges
#: agree to this fraction of the contact width and their locked-in strain E to this fraction
#: of max abs(E) in the mean: the discretisation's own stick-edge error at the default
#: resolution is 3e-5 .. 1e-4 of the width (docs/general_solver.md), so states closer than
#: this are equal within what the solver can resolve.
SAME_STATE_TOL = 1e-4
#: Gauss-Legendre points per interval of the dissipation quadrature (on [0, 1]).
DISSIPATION_GAUSS = 4
_LEGENDRE_NODES, _LEGENDRE_WEIGHTS = np.polynomial.legendre.leggauss(DISSIPATION_GAUSS)
_GAUSS = (0.5 * (_LEGENDRE_NODES + 1.0), 0.5 * _LEGENDRE_WEIGHTS)  # nodes and weights on [0, 1]


@dataclass(frozen=True)
class GeneralMemory:
    """Immutable memory of the general solver.

    Attributes
    ----------
    normal : NormalSolution or None
        Normal solution of the state (None when separated).
    origin, spacing : float
        The material lattice x_j = origin + j spacing (NaN before first contact).
    X : ndarray, shape (n,)
        Material points in contact, increasing; the contact edges first and last.
    kind : ndarray of int8, shape (n,)
        Kind of each point (``_general_points``).
    E : ndarray, shape (n,)
        Locked-in relative strain Delta-eps at X.
    kappa : ndarray, shape (n,)
        Square-root coefficient of E at singular points (0 elsewhere).
    G : ndarray, shape (n,)
        Slip accumulated at X since the point entered contact [m].
    shear : Shear or None
        Representation of q(x).
    chi_fit : ndarray, shape (FIT_TERMS,), or None
        U-series of f chi p on the contact (with shear.coef, the log potential of q).
    edge_ratio : tuple of float
        q / p at the left and right contact edges.
    residual : float
        Consistency residual gamma_0 / (f max p) of the last full-stick solve:
        the discretisation error estimate (slip solves zero it by moving the edges).
    """

    normal: NormalSolution | None
    origin: float
    spacing: float
    X: np.ndarray
    kind: np.ndarray
    E: np.ndarray
    kappa: np.ndarray
    G: np.ndarray
    shear: Shear | None
    chi_fit: np.ndarray | None
    edge_ratio: tuple
    residual: float = 0.0


@dataclass(frozen=True)
class _Edges:
    """Kinematics of the two edges for a step on a contact (x0, d): u, v of (S1)."""

    u: tuple
    v: tuple

    @classmethod
    def of(cls, sol: NormalSolution, loads0: Loads, loads1: Loads) -> "_Edges":
        d, x0 = sol.half_width, sol.center
        dP, dQ = loads1.P - loads0.P, loads1.Q - loads0.Q
        dM, dS = loads1.M - loads0.M, loads1.sigma - loads0.sigma
        dM0 = dM - dP * x0
        u = (dQ - 0.25 * math.pi * d * dS, dQ + 0.25 * math.pi * d * dS)
        v = (dP - 2.0 * dM0 / d, dP + 2.0 * dM0 / d)
        return cls(u, v)

    def sticks(self, friction: float) -> bool:
        return all(abs(u) < friction * v for u, v in zip(self.u, self.v))


@dataclass(frozen=True)
class _Data:
    """Material points of the new contact and what they carry into the step (shapes (n,))."""

    origin: float
    spacing: float
    X: np.ndarray
    kind: np.ndarray
    E: np.ndarray  # strain at the start (arrivals: on arrival, gauge force 0)
    kappa: np.ndarray  # its square-root coefficients
    gauge: np.ndarray  # d E / d F at arrivals
    kappa_gauge: np.ndarray  # and of the gauge
    side: np.ndarray  # int8: -1 / +1 arrived at the left / right edge, 0 was in contact
    G: np.ndarray  # slip so far
    first: float  # where contact formed (NaN unless the step starts separated)

    def stuck_arrivals(self, cfg: Config) -> np.ndarray:
        """Points that arrived at an edge that sticks in ``cfg`` (the gauge force acts on them)."""
        return ((self.side < 0) & (cfg.left == 0)) | ((self.side > 0) & (cfg.right == 0))

    def start(self, sol: Solution) -> tuple[np.ndarray, np.ndarray]:
        """Strain at the start of the step and its square-root coefficients, for a solution."""
        on = self.stuck_arrivals(sol.config)
        return self.E + sol.gauge * self.gauge * on, self.kappa + sol.gauge * self.kappa_gauge * on


class GeneralSolver(TangentialSolver):
    """Tangential solver for any profile and all four loads varying.

    Parameters
    ----------
    problem : NormalProblem
    friction : float
        Coulomb coefficient f.
    nodes : int
        Resolution: the material lattice keeps between ``nodes`` and
        2 ``nodes`` points across the contact, and the stick-zone solution
        is carried as a ``nodes``-term Chebyshev series where a series is used.
    stations : array_like, shape (n_stations,), optional
        Surface points whose accumulated slip :meth:`slip` returns.
    edge_travel : float, optional
        Step-size control: a slipping step over which a stick edge travels
        more than this fraction of the contact width is taken in halves (up to
        2**CONTROL_SPLITS sub-steps). Off by default.

    Attributes
    ----------
    datum : float
        Length l of the log-kernel datum of the rigid shift (profile length scale).
    counters : dict
        Work done: steps, stick steps, slip solves, configurations tried,
        residual evaluations, normal solves.
    """

    name = "general"

    def __init__(self, problem: NormalProblem, friction: float, nodes: int = DEFAULT_NODES, stations=None,
                 edge_travel: float | None = None):
        self.problem = problem
        self.edge_travel = None if edge_travel is None else float(edge_travel)
        if self.edge_travel is not None and not self.edge_travel > 0.0:
            raise ValueError(f"edge_travel must be positive, got {edge_travel!r}")
        self.f = float(friction)
        if not self.f > 0.0:
            raise ValueError(f"friction must be positive, got {friction!r}")
        self.nodes = int(nodes)
        if self.nodes < 8:
            raise ValueError(f"nodes must be at least 8, got {nodes!r}")
        self.A = problem.compliance
        self.datum = problem.profile.length_scale
        self.stations = None if stations is None else np.asarray(stations, dtype=float)
        self._slope = problem.profile.slope
        self._breaks = _slope_breaks(problem.profile)
        self.counters = dict.fromkeys(
            ("steps", "stick_steps", "slip_solves", "configurations", "evaluations", "normal_solves"), 0
        )

    # ------------------------------------------------------------------
    def initial_state(self, t0: float = 0.0) -> ContactState:
        """Separated, unloaded, no memory."""
        nan = math.nan
        mem = _empty_memory(nan, nan)
        return ContactState(float(t0), Loads(0.0, 0.0, 0.0, 0.0), nan, nan, nan, nan, 0.0, 0.0, mem)

    # ------------------------------------------------------------------
    def step(self, state: ContactState, t1: float, loads1: Loads) -> tuple[ContactState, StepReport]:
        """Advance ``state`` to time ``t1`` and ``loads1`` along the straight line in (P, Q, M, sigma).

        A step that no slip-zone configuration solves (typically a long step
        over which an edge first recedes and then advances, against the
        monotone zones assumed within a step), or in which a stuck edge
        advances more than MAX_STRIP of the width while the other slips, is
        split in halves along the same line, up to MAX_SPLITS times.

        Returns
        -------
        state : ContactState
            The new state (``state`` is not modified).
        report : StepReport
        """
        self.counters["steps"] += 1
        depth = MAX_SPLITS if self.edge_travel is None else CONTROL_SPLITS
        return self._step(state, float(t1), Loads(*(float(v) for v in loads1)), depth)

    def _step(self, state: ContactState, t1: float, loads1: Loads, splits: int) -> tuple[ContactState, StepReport]:
        """One step, split in halves while ``_single`` asks for it and ``splits`` remain."""
        new, report, split = self._single(state, t1, loads1)
        if not split or splits == 0:
            return new, report
        loads0 = state.loads
        mid = Loads(*(0.5 * (a + b) for a, b in zip(loads0, loads1)))
        half, first = self._step(state, 0.5 * (state.t + t1), mid, splits - 1)
        new, second = self._step(half, t1, loads1, splits - 1)
        message = "; ".join(m for m in (first.message, second.message) if m)
        return new, StepReport(second.regime, first.slipped or second.slipped,
                               first.normal_solved or second.normal_solved, message,
                               converged=first.converged and second.converged,
                               residual=max(first.residual, second.residual))

    def _single(self, state: ContactState, t1: float, loads1: Loads):
        """One straight step, without splitting.

        Returns
        -------
        state : ContactState
        report : StepReport
        split : bool
            Whether the step should rather be taken in two halves.
        """
        loads0 = state.loads
        mem = state.memory
        if loads1 == loads0:
            regime = Regime.SEPARATED if mem.normal is None else Regime.STICK
            new = ContactState(float(t1), loads0, state.contact_left, state.contact_right, state.contact_left,
                               state.contact_right, state.shift, state.dissipation, mem)
            return new, StepReport(regime, False, False, ""), False
        if not loads1.P > 0.0:
            return (*self._separate(state, t1, loads1), False)
        normal_changed = mem.normal is None or (loads1.P, loads1.M) != (loads0.P, loads0.M)
        if normal_changed:
            N1 = self.problem.solve(loads1.P, loads1.M)
            self.counters["normal_solves"] += 1
        else:
            N1 = mem.normal
        data = self._data(mem, N1, loads0, loads1)
        if abs(loads1.Q) >= self.f * loads1.P:
            return (*self._gross(state, t1, loads1, N1, data, normal_changed), False)
        f = self.f
        edges1 = _Edges.of(N1, loads0, loads1)
        sticks = edges1.sticks(f) and (mem.normal is None or _Edges.of(mem.normal, loads0, loads1).sticks(f))
        left, right = data.side < 0, data.side > 0
        Xa, (Ea, g_left, g_right) = pts.augment(data.X, data.kind, data.spacing, [
            (data.E, data.kappa), (data.gauge * left, data.kappa_gauge * left),
            (data.gauge * right, data.kappa_gauge * right)])
        # the previous fix-up is the persistent residual of the strain-based equilibrium,
        # except after opposite-sign zones, where it is mostly the sampling of their ramp
        bias = mem.shear.fixup if mem.shear is not None and not mem.shear.config.opposite else 0.0
        problem = StepProblem(N1, self._slope, self._breaks, Xa, Ea, (g_left, g_right), self.A, f, loads1.sigma,
                              loads1.Q, self.nodes, bias, data.X[data.kind >= SINGULAR_LEFT])
        chosen = None
        # (S1) asks each edge to advance; when it fails only because an edge recedes without a
        # shear drive there (a moment tilting the contact under Q = sigma = 0, say), the fully
        # stuck solution may well be bounded: try it before any slip solve (Coulomb decides)
        drive = 1e-12 * f * max(abs(loads0.P), abs(loads1.P))
        receding_only = not sticks and all((abs(u) <= drive) if v <= 0.0 else (abs(u) < f * v)
                                           for u, v in zip(edges1.u, edges1.v))
        if sticks or receding_only:
            sol = problem.solve(Config(0, 0))
            shear = problem.shear(sol)
            if self._coulomb(problem, shear) <= STICK_COULOMB_TOL:
                # where (S1) failed, the stuck solution must also meet the consistency (bounded q
                # with the edges held): its residual, relative to f max p, at rounding level
                if sticks or abs(problem.gammas(Config(0, 0), N1.left, N1.right, 0.0)[0]) <= \
                        RECEDING_STICK_TOL * problem.p_scale:
                    chosen = (sol, shear)
        slipped = chosen is None
        message, converged, residual = "", True, 0.0
        if slipped:
            self.counters["slip_solves"] += 1
            chosen, message, converged, residual = self._slip_solve(problem, data, mem, N1, edges1)
        sol, shear = chosen
        self.counters["evaluations"] += problem.evaluations
        split = not converged
        if slipped and mem.normal is not None:
            W = N1.right - N1.left
            strips = (mem.normal.left - N1.left, N1.right - mem.normal.right)
            split |= any(s == 0 and strip > MAX_STRIP * W for s, strip in zip((sol.config.left, sol.config.right),
                                                                                  strips))
        new, report = self._finish(state, t1, loads1, N1, data, problem, sol, shear, slipped, normal_changed,
                                   message, edges1, converged, residual)
        if self.edge_travel is not None and slipped and mem.normal is not None:
            # step-size control: a slipping step whose stick edges travel further than
            # edge_travel of the width is taken in halves (the dissipation and the arrival
            # strains are first order in the step)
            travel = max(_apart(new.stick_left, state.stick_left), _apart(new.stick_right, state.stick_right))
            split |= math.isfinite(travel) and travel > self.edge_travel * (N1.right - N1.left)
        return new, report, split

    # -- the material points of the new contact ----------------------------
    def _data(self, mem: GeneralMemory, N1: NormalSolution, loads0: Loads, loads1: Loads) -> _Data:
        """Points of the new contact with their start strain, gauge and slip (arrivals included)."""
        L1, R1 = N1.left, N1.right
        W = R1 - L1
        origin, h = mem.origin, mem.spacing
        if not math.isfinite(h):
            origin, h = 0.5 * (L1 + R1), W / self.nodes
        while W / h >= 2 * self.nodes:
            h *= 2.0
        while W / h < self.nodes:
            h *= 0.5
        j_lo = math.floor((L1 - origin) / h) + 1
        j_hi = math.ceil((R1 - origin) / h) - 1
        lattice = origin + h * np.arange(j_lo, j_hi + 1)
        breaks = self._breaks[(self._breaks > L1) & (self._breaks < R1)]
        carried = (mem.kind >= CLUSTER) & (mem.X > L1) & (mem.X < R1)
        parts = [([L1, R1], EDGE), (lattice, LATTICE), (breaks, BREAK)]
        N0 = mem.normal
        if N0 is not None:
            # an old edge the contact grew past: E may rise like a square root beyond it
            # (a strip narrower than two cluster points cannot fix kappa: the old edge is kept plain)
            offsets = pts.cluster_offsets(h)
            if L1 < N0.left:
                wide = N0.left - L1 > offsets[1]
                parts += [([N0.left], SINGULAR_LEFT if wide else CLUSTER),
                          (N0.left - offsets[N0.left - offsets > L1], CLUSTER)]
            if R1 > N0.right:
                wide = R1 - N0.right > offsets[1]
                parts += [([N0.right], SINGULAR_RIGHT if wide else CLUSTER),
                          (N0.right + offsets[N0.right + offsets < R1], CLUSTER)]
        new_kappa = np.zeros(sum(len(x) for x, _ in parts))
        X = np.concatenate([np.asarray(x, dtype=float) for x, _ in parts] + [mem.X[carried]])
        kind = np.concatenate([np.full(len(x), k) for x, k in parts] + [mem.kind[carried]]).astype(np.int8)
        kappa = np.concatenate([new_kappa, mem.kappa[carried]])
        X, kind, (kappa,) = pts.merge(X, kind, 1e-9 * h, kappa)
        n = X.size
        E = np.zeros(n)
        gauge = np.zeros(n)
        side_of = np.zeros(n, dtype=np.int8)
        G = np.zeros(n)
        if N0 is not None:
            old = (X >= N0.left) & (X <= N0.right)
            Xa0, (Ea0,) = pts.augment(mem.X, mem.kind, mem.spacing, [(mem.E, mem.kappa)])
            E[old] = np.interp(X[old], Xa0, Ea0)
            G[old] = np.interp(X[old], mem.X, mem.G)
        else:
            old = np.zeros(n, dtype=bool)
        arriving = ~old
        first = math.nan
        if np.any(arriving):
            path = EdgePath(self.problem, N0, N1, loads0, loads1)
            self.counters["normal_solves"] += path.solves
            if N0 is not None:
                E[arriving] = outside_strain(Xa0, Ea0, X[arriving], 2 * self.nodes)
                split = N0.center
            else:
                lam = path.lam_lo
                E[arriving] = 0.25 * self.A * (loads0.sigma + lam * (loads1.sigma - loads0.sigma))
                left, right = path.edges(np.array(lam))
                split = first = 0.5 * (float(left) + float(right))
            for side in (-1, 1):
                mask = arriving & ((X < split) if side < 0 else (X >= split))
                if np.any(mask):
                    inc, e = arrival_strains(path, X[mask], side, self.A)
                    E[mask] += inc
                    gauge[mask] = e
                    side_of[mask] = side
        fresh = np.flatnonzero((kind >= SINGULAR_LEFT) & (kappa == 0.0) & ~np.isin(X, mem.X[carried]))
        kappa_gauge = np.zeros(n)
        if fresh.size:
            kappa[fresh] = pts.fit_kappa(X, kind, h, E, fresh)
            kappa_gauge[fresh] = pts.fit_kappa(X, kind, h, gauge, fresh)
        return _Data(origin, h, X, kind, E, kappa, gauge, kappa_gauge, side_of, G, first)

    # -- slip -------------------------------------------------------------
    def _slip_solve(self, problem: StepProblem, data: _Data, mem: GeneralMemory, N1: NormalSolution,
                    edges1: _Edges):
        """Try slip configurations, most likely first.

        Returns
        -------
        chosen : (sol, shear)
        message : str
        converged : bool
            Whether a configuration met the Coulomb and slip-direction checks.
        residual : float
            The chosen configuration's violation of those checks relative to their
            tolerances (<= 1 when converged; inf when no configuration was found).
        """
        f = self.f
        N0 = mem.normal
        options = []
        for i, (u, v) in enumerate(zip(edges1.u, edges1.v)):
            advancing = N0 is None or (N1.left < N0.left if i == 0 else N1.right > N0.right)
            if advancing and v > 0.0:
                first = [0] if abs(u) < f * v else []
                s = 1 if u >= 0.0 else -1
                options.append(first + [s, -s] + ([0] if not first else []))
            else:
                drive = u - mem.edge_ratio[i] * v
                s = (1 if drive > 0.0 else -1) if drive != 0.0 else (1 if mem.edge_ratio[i] >= 0.0 else -1)
                options.append([s, -s])
        ranked = sorted(
            ((i + j, Config(a, b)) for i, a in enumerate(options[0]) for j, b in enumerate(options[1])),
            key=lambda item: item[0],
        )
        guess = None
        if mem.shear is not None and mem.shear.config != Config(0, 0) and mem.shear.radius > 0.0:
            guess = (max(mem.shear.stick_left, N1.left), min(mem.shear.stick_right, N1.right))
        best, best_violation = None, math.inf
        for _, cfg in ranked:
            if cfg == Config(0, 0):
                continue
            self.counters["configurations"] += 1
            for sol in problem.roots(cfg, guess, _limits(cfg, mem, N1)):
                shear = problem.shear(sol)
                violation = self._violation(problem, data, sol, shear)
                if violation <= 1.0:
                    return (sol, shear), "", True, violation
                if violation < best_violation:
                    best, best_violation = (sol, shear), violation
        if best is None:
            sol = problem.solve(Config(0, 0))
            shear = problem.shear(sol)
            return (sol, shear), ("slip solve: no slip-zone configuration converged; kept full stick "
                                  f"(Coulomb excess {self._coulomb(problem, shear):.2g} of f max p)"), False, math.inf
        return best, (
            "slip solve: no slip-zone configuration met the Coulomb and slip-direction checks; "
            f"kept the closest (violation {best_violation:.2g} x tolerance)"
        ), False, best_violation

    def _coulomb(self, problem: StepProblem, shear: Shear) -> float:
        """Largest excess of abs(q) over f p on the stick interval, relative to f max p.

        Checked at CHECK_POINTS Chebyshev points and at the square-root points of
        E, with the exact inversion of the stick data (the series converges too
        slowly next to square-root points).
        """
        t = sie.chebyshev_nodes(CHECK_POINTS)
        x = shear.center + shear.radius * t
        sing = problem.singular  # and where E has structure: its square-root points
        x = np.concatenate((x, sing[(sing > shear.stick_left) & (sing < shear.stick_right)]))
        p = problem.normal.pressure(x)
        q = shear.evaluate(x, p, self.f)
        return float(np.max(np.abs(q) - self.f * p)) / problem.p_scale

    def _violation(self, problem: StepProblem, data: _Data, sol: Solution, shear: Shear) -> float:
        """Coulomb excess and reversed slip, each relative to its tolerance (<= 1 passes)."""
        coulomb = self._coulomb(problem, shear)
        E_start, _ = data.start(sol)
        _, dg, (b1, b2) = self._slip_update(problem, shear, data.X, data.kind, E_start, data.spacing)
        reverse = 0.0
        for sign, zone in ((sol.config.left, data.X < b1), (sol.config.right, data.X > b2)):
            if sign != 0 and np.any(zone):
                reverse = max(reverse, float(np.max(-sign * dg[zone])))
        scale = float(np.max(np.abs(dg)))
        direction = reverse / scale if scale > 0.0 else 0.0
        return max(max(coulomb, 0.0) / COULOMB_TOL, direction / DIRECTION_TOL)

    def _slip_update(self, problem: StepProblem, shear: Shear, X: np.ndarray, kind: np.ndarray, E_start: np.ndarray,
                     h: float):
        """Strain at the end of the step, slip increment, and the stick edges, at points X.

        Stuck points keep E_start; points in a slip zone take the current
        Delta-eps, and their slip increment is the integral of the strain change
        from the stick edge outward (trapezoid over X; the stick edge does not
        slip). Points next to the stick edge whose strain does not change
        (TRIM_TOL) count as stuck, and the edge moves out to the first point
        that slips. An edge within SNAP h of a singular point of its side moves
        onto it first: that point is the old stick edge the new one meets, and
        it keeps its exact stuck strain (see SNAP).

        Returns
        -------
        E_end, dg : ndarray, shape (n,)
        edges : tuple of float
            The stick edges (b1, b2).
        """
        E_end = E_start.copy()
        dg = np.zeros_like(X)
        cfg = shear.config
        edges = [shear.stick_left, shear.stick_right]
        tol = TRIM_TOL * float(np.max(np.abs(E_start)))
        for k, (side, sign, sing) in enumerate(((-1, cfg.left, SINGULAR_LEFT), (1, cfg.right, SINGULAR_RIGHT))):
            b = edges[k]
            if sign != 0:
                met = np.flatnonzero((kind == sing) & (np.abs(X - b) <= SNAP * h))
                if met.size:
                    b = edges[k] = float(X[met[np.argmin(np.abs(X[met] - b))]])
            # (no point between the solved edge and the one it snapped to is taken into the zone:
            # the slip-zone strain is that of the stick interval solved for)
            zone = (X < min(b, shear.stick_left)) if side < 0 else (X > max(b, shear.stick_right))
            if sign == 0 or not np.any(zone):
                continue
            near = np.abs(X[zone] - b) <= NEAR_SPACINGS * h
            E_end[zone] = problem.strain(shear, X[zone], near)
            order = np.flatnonzero(zone)[::side]  # outward from b
            unchanged = np.abs(E_end[order] - E_start[order]) <= tol
            trim = int(np.argmin(unchanged)) if not np.all(unchanged) else order.size
            if trim:
                E_end[order[:trim]] = E_start[order[:trim]]
                b = X[order[trim - 1]]
                edges[k] = b
                order = order[trim:]
            xs = np.concatenate(([b], X[order]))
            diff = np.concatenate(([0.0], E_end[order] - E_start[order]))
            dg[order] = np.cumsum(0.5 * (diff[1:] + diff[:-1]) * np.diff(xs))
        return E_end, dg, tuple(edges)

    # -- finishing a step ---------------------------------------------------
    def _finish(self, state, t1, loads1, N1, data, problem, sol, shear, slipped, normal_changed, message, edges1,
                converged=True, violation=0.0):
        mem = state.memory
        f = self.f
        cfg = sol.config
        L1, R1 = N1.left, N1.right
        W = R1 - L1
        E_start, kappa = data.start(sol)
        X, kind, G0 = data.X, data.kind, data.G
        _, _, (b1, b2) = self._slip_update(problem, shear, X, kind, E_start, data.spacing)
        left_zone = cfg.left != 0 and b1 - L1 > 1e-9 * W
        right_zone = cfg.right != 0 and R1 - b2 > 1e-9 * W
        regime = Regime.PARTIAL_SLIP if (left_zone or right_zone) else Regime.STICK
        if regime == Regime.STICK:
            self.counters["stick_steps"] += 1
        if regime == Regime.PARTIAL_SLIP:
            X, kind, E_start, kappa, G0 = self._clusters(data, E_start, kappa, b1 if left_zone else None,
                                                             b2 if right_zone else None, N1)
        E_end, dg, _ = self._slip_update(problem, shear, X, kind, E_start, data.spacing)
        snap = SNAP * data.spacing
        fresh = np.flatnonzero((kind >= SINGULAR_LEFT) & ((np.abs(X - b1) <= snap) | (np.abs(X - b2) <= snap)))
        if fresh.size:
            kappa[fresh] = pts.fit_kappa(X, kind, data.spacing, E_end, fresh)
        dissipation = _dissipation(X, dg, mem.normal, N1, f)
        X, kind, E_end, kappa, G1 = pts.prune(X, kind, data.spacing, E_end, kappa, G0 + dg)
        ratio = list(mem.edge_ratio)
        for i, s in enumerate((cfg.left, cfg.right)):
            if s != 0:
                ratio[i] = s * f
            elif edges1.v[i] > 0.0:
                ratio[i] = edges1.u[i] / edges1.v[i]
        chi_fit = self._chi_fit(N1, shear)
        stuck = _stuck_point(mem.normal, b1, b2, data.first)
        shift = self._shift(state, N1, shear, chi_fit, stuck, loads1)
        residual = 0.0
        if cfg == Config(0, 0):
            residual = abs(problem.gammas(cfg, L1, R1, 0.0)[0]) / problem.p_scale
        new_mem = GeneralMemory(N1, data.origin, data.spacing, _frozen(X), _frozen(kind), _frozen(E_end),
                                _frozen(kappa), _frozen(G1), shear, chi_fit, tuple(ratio), residual)
        stick = (L1, R1) if regime == Regime.STICK else (b1, b2)
        new = ContactState(float(t1), loads1, L1, R1, stick[0], stick[1], shift, state.dissipation + dissipation,
                           new_mem)
        return new, StepReport(regime, slipped, normal_changed, message, converged=converged, residual=violation)

    def _clusters(self, data: _Data, E_start, kappa, b_left, b_right, N1):
        """Drop cluster points inside the slip zones and lay new ones at the stick edges.

        A stick edge b becomes a SINGULAR point (its E is the stuck value) with
        a cluster on its slip side; their strain at the end of the step is
        computed in closed form, and kappa fitted from it, by the caller.
        """
        X, kind = data.X, data.kind
        drop = np.zeros(X.size, dtype=bool)
        if b_left is not None:
            drop |= (X < b_left) & (kind >= CLUSTER)
        if b_right is not None:
            drop |= (X > b_right) & (kind >= CLUSTER)
        h = data.spacing
        offsets = pts.cluster_offsets(h)
        new_x, new_kind = [], []
        for b, side, sing in ((b_left, -1, SINGULAR_LEFT), (b_right, 1, SINGULAR_RIGHT)):
            if b is None:
                continue
            # an old singular point of this side at (or within rounding of) the new stick edge:
            # its square-root side is the new slip zone, overwritten -- the new point replaces it
            # (kept, it would win the merge with its stale kappa)
            drop |= (kind == sing) & (np.abs(X - b) <= SNAP * h)
            at = b + side * offsets
            at = at[(at > N1.left) & (at < N1.right)]
            new_x += [np.array([b]), at]
            new_kind += [np.array([sing]), np.full(at.size, CLUSTER)]
        keep = ~drop
        Xa, (Ea,) = pts.augment(X, kind, h, [(E_start, kappa)])
        add_x = np.concatenate(new_x)
        add_kind = np.concatenate(new_kind).astype(np.int8)
        X2 = np.concatenate((X[keep], add_x))
        kind2 = np.concatenate((kind[keep], add_kind))
        E2 = np.concatenate((E_start[keep], np.interp(add_x, Xa, Ea)))
        kappa2 = np.concatenate((kappa[keep], np.zeros(add_x.size)))
        G2 = np.concatenate((data.G[keep], np.interp(add_x, X, data.G)))
        X2, kind2, (E2, kappa2, G2) = pts.merge(X2, kind2, 1e-9 * h, E2, kappa2, G2)
        return X2, kind2, E2, kappa2, G2

    def _gross(self, state, t1, loads1, N1, data, normal_changed):
        """q = sign(Q) f p everywhere; g frozen at the middle of the old/new contact overlap."""
        mem = state.memory
        f = self.f
        s = 1 if loads1.Q > 0 else -1
        L1, R1 = N1.left, N1.right
        c = 0.5 * (L1 + R1)
        shear = Shear(L1, R1, c, c, Config(s, s), _frozen(np.zeros(self.nodes)), 0.0, 0.0)
        X = data.X
        E_end = s * f * (self._slope(X) + N1.rotation) + 0.25 * self.A * loads1.sigma
        stuck = _stuck_point(mem.normal, L1, R1, data.first)
        diff = E_end - data.E
        d0 = float(np.interp(stuck, X, diff))
        dg = np.zeros_like(X)
        for side in (-1, 1):
            idx = np.flatnonzero((X < stuck) if side < 0 else (X >= stuck))[::side]
            if idx.size:
                xs = np.concatenate(([stuck], X[idx]))
                ds = np.concatenate(([d0], diff[idx]))
                dg[idx] = np.cumsum(0.5 * (ds[1:] + ds[:-1]) * np.diff(xs))
        keep = data.kind < CLUSTER
        dissipation = _dissipation(X, dg, mem.normal, N1, f)
        chi_fit = self._chi_fit(N1, shear)
        shift = self._shift(state, N1, shear, chi_fit, stuck, loads1)
        new_mem = GeneralMemory(N1, data.origin, data.spacing, _frozen(X[keep]), _frozen(data.kind[keep]),
                                _frozen(E_end[keep]), _frozen(np.zeros(int(np.sum(keep)))),
                                _frozen((data.G + dg)[keep]), shear, chi_fit, (s * f, s * f), 0.0)
        message = ""
        if abs(loads1.Q) > f * loads1.P * (1.0 + 1e-12):
            message = GROSS_SLIDING_MESSAGE
        new = ContactState(float(t1), loads1, L1, R1, math.nan, math.nan, shift, state.dissipation + dissipation,
                           new_mem)
        return new, StepReport(Regime.GROSS_SLIDING, True, normal_changed, message)

    def _separate(self, state, t1, loads1):
        """All memory lost; the shift keeps g at the old contact centre."""
        mem = state.memory
        shift = state.shift
        if mem.normal is not None:
            shift += self._potential(mem.normal, mem.shear, mem.chi_fit, mem.normal.center)
        nan = math.nan
        message = f"separated (P <= 0): shear force Q = {loads1.Q:g} N/m not carried" if loads1.Q != 0.0 else ""
        new = ContactState(float(t1), loads1, nan, nan, nan, nan, shift, state.dissipation,
                           _empty_memory(mem.origin, mem.spacing))
        return new, StepReport(Regime.SEPARATED, False, mem.normal is not None, message)

    # -- rigid shift --------------------------------------------------------
    def _chi_fit(self, N: NormalSolution, shear: Shear) -> np.ndarray:
        """U-series coefficients of f chi p on the contact, shape (FIT_TERMS,)."""
        t = sie.u_nodes(FIT_TERMS)
        x = N.center + N.half_width * t
        return _frozen(sie.u_coefficients(self.f * shear.chi_p(x, N.pressure(x))))

    def _potential(self, N: NormalSolution, shear: Shear, chi_fit: np.ndarray, x: float) -> float:
        """(A/pi) int q ln(abs(x - xi) / l) dxi at x.

        q = f chi p (its U-series on the contact) + q* (the series of the stick
        interval) + the fix-up; each term's log potential is a series whose
        terms fall off like 1/k^2, so truncation and aliasing barely matter.
        """
        l = self.datum

        def series(a, centre, radius):
            t = (x - centre) / radius
            return self.A * radius * (0.5 * a[0] * math.log(radius / l) + sie.log_potential(a, t))

        total = series(chi_fit, N.center, N.half_width)
        if shear.radius > 0.0:
            total += series(shear.coef[1:], shear.center, shear.radius)
            if shear.fixup:
                total += series(np.array([2.0 * shear.fixup / (math.pi * shear.radius)]), shear.center, shear.radius)
        return total

    def _shift(self, state, N1, shear, chi_fit, stuck, loads1) -> float:
        """delta such that g(stuck) is unchanged (g = delta + potential + A sigma x / 4)."""
        mem = state.memory
        before = state.shift + 0.25 * self.A * state.loads.sigma * stuck
        if mem.normal is not None:
            before += self._potential(mem.normal, mem.shear, mem.chi_fit, stuck)
        return before - self._potential(N1, shear, chi_fit, stuck) - 0.25 * self.A * loads1.sigma * stuck

    # -- steady cycles ------------------------------------------------------
    def state_difference(self, a: ContactState, b: ContactState) -> float:
        """How far apart two states at the same loads are, relative to :data:`SAME_STATE_TOL`.

        The memory that decides the future is the contact (edges), the stick
        zone and the locked-in strain E. Measured:

        - contact and stick edges, relative to the contact width;
        - E, compared on the union of both point sets (square-root parts
          included) in the mean over the contact, relative to max abs(E): a
          mean, because a stick edge that moved by delta changes E pointwise by
          O(sqrt(delta)) in a strip of width O(delta) (the edge itself is
          compared directly).

        The accumulated slip G is not compared: it is output, not memory (no
        step reads it). Returns the largest of the measures divided by its
        tolerance (``inf`` when one state is separated and the other is not).
        """
        ma, mb = a.memory, b.memory
        if (ma.normal is None) != (mb.normal is None):
            return math.inf
        if ma.normal is None:
            return 0.0
        W = max(ma.normal.right - ma.normal.left, mb.normal.right - mb.normal.left)
        edges = max(_apart(u, v) for u, v in zip(
            (a.contact_left, a.contact_right, a.stick_left, a.stick_right),
            (b.contact_left, b.contact_right, b.stick_left, b.stick_right))) / W
        Xa, (Ea,) = pts.augment(ma.X, ma.kind, ma.spacing, [(ma.E, ma.kappa)])
        Xb, (Eb,) = pts.augment(mb.X, mb.kind, mb.spacing, [(mb.E, mb.kappa)])
        lo, hi = max(Xa[0], Xb[0]), min(Xa[-1], Xb[-1])
        grid = np.union1d(Xa, Xb)
        grid = grid[(grid >= lo) & (grid <= hi)]
        scale = max(float(np.max(np.abs(Ea))), float(np.max(np.abs(Eb))))
        strain = 0.0
        if grid.size > 1 and scale > 0.0:
            d = np.abs(np.interp(grid, Xa, Ea) - np.interp(grid, Xb, Eb))
            strain = float(np.sum(0.5 * (d[1:] + d[:-1]) * np.diff(grid))) / (W * scale)
        return max(edges, strain) / SAME_STATE_TOL

    def cycle_tolerance(self, state: ContactState) -> float:
        """How closely [m] the stick edges of a steady cycle repeat those of the cycle before.

        The cycle skipper asks for this step by step over the whole cycle, on
        top of :meth:`same_state` at the cycle's end.
        """
        return SAME_STATE_TOL * (state.contact_right - state.contact_left)

    def same_state(self, a: ContactState, b: ContactState) -> bool:
        """Whether two states agree to the solver's tolerance (:meth:`state_difference` <= 1)."""
        return self.state_difference(a, b) <= 1.0

    # -- output -----------------------------------------------------------
    def tractions(self, memory: GeneralMemory, x) -> tuple[np.ndarray, np.ndarray]:
        """Pressure p(x) and shear traction q(x) [Pa], each of the shape of ``x``."""
        x = np.asarray(x, dtype=float)
        if memory.normal is None:
            return np.zeros(x.shape), np.zeros(x.shape)
        p = memory.normal.pressure(x)
        return p, memory.shear.evaluate(x, p, self.f)

    def shear_force(self, memory: GeneralMemory) -> float:
        """The shear force the state carries, int q dx, from its representation [N/m]."""
        if memory.normal is None:
            return 0.0
        return memory.shear.force(memory.normal, self.f, self._breaks)

    def slip(self, memory: GeneralMemory) -> np.ndarray:
        """Slip accumulated at the stations since each entered contact [m]; NaN outside contact."""
        if self.stations is None:
            raise ValueError("slip is tracked only when the solver is built with stations")
        out = np.full(self.stations.shape, np.nan)
        if memory.normal is None:
            return out
        inside = (self.stations >= memory.X[0]) & (self.stations <= memory.X[-1])
        out[inside] = np.interp(self.stations[inside], memory.X, memory.G)
        return out


def _empty_memory(origin: float, spacing: float) -> GeneralMemory:
    empty = _frozen(np.zeros(0))
    return GeneralMemory(None, origin, spacing, empty, _frozen(np.zeros(0, np.int8)), empty, empty, empty, None,
                         None, (0.0, 0.0))


def _dissipation(X, dg, N0: NormalSolution | None, N1: NormalSolution, f) -> float:
    """int f (p0 + p1)/2 abs(dg) dx: dg linear between the points, the pressures exact.

    Gauss-Legendre (DISSIPATION_GAUSS points) on each interval where anything
    slipped. The pressure falls like a square root at a contact edge, next to
    which the slip is largest, so a trapezoid on the products p dg at the
    points would underestimate the energy at first order in the spacing (7 %
    on the dovetail example at 512 nodes, where the slip zone spans about 1 %
    of the contact); with the pressure taken exactly the sum converges with
    the slip itself.
    """
    moving = np.flatnonzero((dg[1:] != 0.0) | (dg[:-1] != 0.0))
    if moving.size == 0:
        return 0.0
    t, w = _GAUSS
    lo, hi = X[moving], X[moving + 1]
    x = lo[:, None] + (hi - lo)[:, None] * t[None, :]
    slip = np.abs(dg[moving][:, None] + (dg[moving + 1] - dg[moving])[:, None] * t[None, :])
    p0 = N0.pressure(x) if N0 is not None else 0.0  # a step from separation starts unloaded
    p = 0.5 * (p0 + N1.pressure(x))
    return float(f * np.sum((p * slip) @ w * (hi - lo)))


def _limits(cfg: Config, mem: GeneralMemory, N1: NormalSolution) -> tuple[float, float]:
    """Bounds (lo, hi) of the stick edges of a slip configuration.

    A slip zone at an edge that advanced must cover the points that arrived
    there (their locked-in strain assumes they stuck): b stays inside the old
    contact. A slip zone that continues with the sign it had cannot give
    points back to the stick zone within a step (E there already equals the
    slipping strain, so the equations do not see such a b): b stays at or
    beyond the old stick edge.
    """
    lo, hi = N1.left, N1.right
    N0, old = mem.normal, mem.shear
    if N0 is None:
        return lo, hi
    if cfg.left:
        lo = max(lo, N0.left)
        if old is not None and old.config.left == cfg.left and old.radius > 0.0:
            lo = max(lo, old.stick_left)
    if cfg.right:
        hi = min(hi, N0.right)
        if old is not None and old.config.right == cfg.right and old.radius > 0.0:
            hi = min(hi, old.stick_right)
    return lo, hi


def _stuck_point(N0: NormalSolution | None, b1: float, b2: float, first: float) -> float:
    """A point stuck through the step: middle of the stick interval within the old contact."""
    if N0 is None:
        return first
    lo, hi = max(b1, N0.left), min(b2, N0.right)
    return 0.5 * (lo + hi) if hi > lo else 0.5 * (b1 + b2)


def _slope_breaks(profile) -> np.ndarray:
    """Points where h' is not smooth (its piecewise-linear interpolation is exact between them)."""
    if isinstance(profile, RoundedPunch) and profile.flat_half_width > 0.0:
        w = profile.flat_half_width
        return np.array([-w, w])
    if isinstance(profile, TabulatedProfile):
        return np.asarray(profile.x, dtype=float)
    return np.zeros(0)


def _apart(u: float, v: float) -> float:
    """abs(u - v), with NaN equal to NaN (no stick zone in either) and infinitely far from a number."""
    if math.isnan(u) or math.isnan(v):
        return 0.0 if math.isnan(u) and math.isnan(v) else math.inf
    return abs(u - v)

