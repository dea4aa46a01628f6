"""The general tangential slip solver: any profile, P, Q, M and sigma all varying.

Formulation (docs/general_solver.md has the derivation and the error study).
The memory is the locked-in relative strain E(x) = Delta-eps (T1) of every
material point in contact, kept at the points of a fixed material lattice (plus
the two contact edges). A stuck point keeps its E; a slipping point takes the
current Delta-eps; a point leaving contact forgets; a point entering during a
step gets the strain it has at the instant its gap closes (physics.md, first
trap), from the memory rule (M1) in strain form (``_general_path``).

A step along the straight line from ``state.loads`` to ``loads1``:

1. normal problem at the end (skipped when P and M are unchanged);
2. arrival strains of the lattice points entering the contact;
3. the no-slip test (S1) at the start and the end contact, with the half-width
   d and the moment increment dM0 = dM - dP x0 about the contact centre:
   abs(dQ -+ (pi/4) d dsigma) < f (dP -+ 2 dM0 / d) at both edges. While it
   holds the whole contact sticks: q is the bounded solution of the stick
   equation over the contact (``_general_zones``), with the arrivals' strain
   closing equilibrium (the M1 increments, T2 sigma term included);
4. otherwise slip zones at one edge or both, of either sign, with the stick
   edges found from consistency and equilibrium, checked against Coulomb
   (abs(q) <= f p on the stick zone) and the slip direction (q . dslip >= 0);
5. E takes Delta-eps in the slip zones; slip, dissipation and rigid shift are
   updated.

Gross sliding (abs(Q) >= f P: q = sign(Q) f p) and separation (P <= 0: all
memory lost) are states the march passes through.

Rigid shift: relative tangential displacement of surface point x is
g(x) = delta + (A/pi) int q(xi) ln(abs(x - xi) / l) dxi + A sigma x / 4, with the
datum l = ``datum`` = profile length scale (as the exact method); delta follows
from a point stuck through the step. In gross sliding the point at the middle
of the contact keeps its g (delta is indeterminate under force control).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..geometry import NormalProblem, NormalSolution, RoundedPunch, TabulatedProfile
from ..state import ContactState, Loads, Regime, StepReport
from . import _general_sie as sie
from ._general_path import EdgePath, arrival_strains, outside_strain
from ._general_zones import Config, Shear, Solution, StepProblem

#: Default resolution: lattice points per contact width (between nodes and 2 nodes).
DEFAULT_NODES = 512
#: Accepted Coulomb excess on the stick zone, relative to f max p.
COULOMB_TOL = 1e-6
#: Accepted reversed slip in a slip zone, relative to the largest slip of the step.
DIRECTION_TOL = 1e-6
#: U-series terms for the log potential of q (the rigid shift).
FIT_TERMS = 256
#: Material points of the cluster laid on the slip side of each stick edge, at b +- h (k/K)^2.
CLUSTER_POINTS = 16
#: Virtual points for the square-root cell next to a stick edge.
VIRTUAL_POINTS = 8
#: Lattice spacings from a stick edge within which slip-zone strains use the closed form.
NEAR_SPACINGS = 4.0

# kinds of material point
LATTICE, EDGE, BREAK, CLUSTER, SINGULAR_LEFT, SINGULAR_RIGHT = range(6)


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
        Material points in contact, increasing: the two contact edges (first and
        last), lattice points, breakpoints of h', and clusters at stick edges.
    E : ndarray, shape (n,)
        Locked-in relative strain Delta-eps at X.
    G : ndarray, shape (n,)
        Slip accumulated at X since the point entered contact [m].
    kind : ndarray of int8, shape (n,)
        LATTICE, EDGE, BREAK, CLUSTER, or SINGULAR_LEFT/RIGHT: a stick edge at
        which a slip zone on that side ended; E rises like sqrt(distance) into
        the old slip zone, and the cell on that side is interpolated so.
    shear : Shear or None
        Representation of q(x).
    edge_ratio : tuple of float
        q / p at the left and right contact edges.
    q_fit : ndarray, shape (FIT_TERMS,), or None
        U-series of q on the contact (its log potential gives the shift).
    residual : float
        Consistency residual gamma_0 / (f p_max) of the last full-stick solve:
        the discretisation error estimate (0 after a slip solve, which zeroes it).
    """

    normal: NormalSolution | None
    origin: float
    spacing: float
    X: np.ndarray
    E: np.ndarray
    G: np.ndarray
    kind: np.ndarray
    shear: Shear | None
    edge_ratio: tuple
    q_fit: np.ndarray | None
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


class GeneralSolver:
    """Tangential solver for any profile and all four loads varying.

    Parameters
    ----------
    problem : NormalProblem
    friction : float
        Coulomb coefficient f.
    nodes : int
        Resolution: the material lattice keeps between ``nodes`` and
        2 ``nodes`` points across the contact, and q on the stick zone is a
        ``nodes``-term Chebyshev series (used inside the solver; output q is
        the exact inversion of the interpolated strain).
    stations : array_like, shape (n_stations,), optional
        Surface points whose accumulated slip :meth:`slip` returns.

    Attributes
    ----------
    datum : float
        Length l of the log-kernel datum of the rigid shift (profile length scale).
    counters : dict
        Work done: steps, stick steps, slip solves, configurations tried,
        residual evaluations, normal solves.
    """

    name = "general"

    def __init__(self, problem: NormalProblem, friction: float, nodes: int = DEFAULT_NODES, stations=None):
        self.problem = problem
        self.f = float(friction)
        if not self.f > 0.0:
            raise ValueError(f"friction must be positive, got {friction!r}")
        self.nodes = int(nodes)
        if self.nodes < 16:
            raise ValueError(f"nodes must be at least 16, got {nodes!r}")
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
        empty = _frozen(np.zeros(0))
        mem = GeneralMemory(None, nan, nan, empty, empty, empty, _frozen(np.zeros(0, np.int8)), None, (0.0, 0.0),
                            None)
        return ContactState(float(t0), Loads(0.0, 0.0, 0.0, 0.0), nan, nan, nan, nan, 0.0, 0.0, mem)

    # ------------------------------------------------------------------
    def step(self, state: ContactState, t1: float, loads1: Loads) -> tuple[ContactState, StepReport]:
        """Advance ``state`` to time ``t1`` and ``loads1`` along the straight line in (P, Q, M, sigma)."""
        loads1 = Loads(*(float(v) for v in loads1))
        loads0 = state.loads
        mem = state.memory
        self.counters["steps"] += 1
        if loads1 == loads0:
            regime = Regime.SEPARATED if mem.normal is None else Regime.STICK
            new = ContactState(float(t1), loads0, state.contact_left, state.contact_right, state.contact_left,
                               state.contact_right, state.shift, state.dissipation, mem)
            return new, StepReport(regime, False, False, "")
        if not loads1.P > 0.0:
            return self._separate(state, t1, loads1)
        normal_changed = mem.normal is None or (loads1.P, loads1.M) != (loads0.P, loads0.M)
        if normal_changed:
            N1 = self.problem.solve(loads1.P, loads1.M)
            self.counters["normal_solves"] += 1
        else:
            N1 = mem.normal
        data = self._data(mem, N1, loads0, loads1)
        if abs(loads1.Q) >= self.f * loads1.P:
            return self._gross(state, t1, loads1, N1, data, normal_changed)
        f = self.f
        edges1 = _Edges.of(N1, loads0, loads1)
        sticks = edges1.sticks(f) and (mem.normal is None or _Edges.of(mem.normal, loads0, loads1).sticks(f))
        Xa, Ea, ga = _augment(data.X, data.kind, data.E, data.gauge)
        problem = StepProblem(N1, self._slope, self._breaks, Xa, Ea, ga, self.A, f, loads1.sigma, loads1.Q,
                              self.nodes)
        chosen = None
        if sticks:
            sol = problem.solve(Config(0, 0))
            shear = problem.shear(sol)
            if self._coulomb(problem, shear) <= COULOMB_TOL:
                chosen = (sol, shear)
        slipped = chosen is None
        message = ""
        if slipped:
            self.counters["slip_solves"] += 1
            chosen, message = self._slip_solve(problem, data, mem, N1, edges1)
        sol, shear = chosen
        self.counters["evaluations"] += problem.evaluations
        return self._finish(state, t1, loads1, N1, data, problem, sol, shear, slipped, normal_changed, message,
                            edges1)

    # -- the material points of the new contact ----------------------------
    def _data(self, mem: GeneralMemory, N1: NormalSolution, loads0: Loads, loads1: Loads) -> "_Data":
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
        X = np.concatenate(([L1, R1], lattice, breaks, mem.X[carried]))
        kind = np.concatenate(([EDGE, EDGE], np.full(lattice.size, LATTICE), np.full(breaks.size, BREAK),
                               mem.kind[carried])).astype(np.int8)
        X, kind = _merge(X, kind, 1e-9 * h)
        n = X.size
        E = np.zeros(n)
        gauge = np.zeros(n)
        G = np.zeros(n)
        p0 = np.zeros(n)
        N0 = mem.normal
        if N0 is not None:
            old = (X >= N0.left) & (X <= N0.right)
            if np.array_equal(X, mem.X):
                E, G = mem.E.copy(), mem.G.copy()
            else:
                Xa0, Ea0 = _augment(mem.X, mem.kind, mem.E)
                E[old] = np.interp(X[old], Xa0, Ea0)
                G[old] = np.interp(X[old], mem.X, mem.G)
            p0 = N0.pressure(X)
        else:
            old = np.zeros(n, dtype=bool)
        arriving = ~old
        first = math.nan
        if np.any(arriving):
            path = EdgePath(self.problem, N0, N1, loads0, loads1)
            self.counters["normal_solves"] += path.solves
            if N0 is not None:
                Xa0, Ea0 = _augment(mem.X, mem.kind, mem.E)
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
        return _Data(origin, h, X, kind, E, gauge, G, p0, first)

    # -- slip -------------------------------------------------------------
    def _slip_solve(self, problem: StepProblem, data: "_Data", mem: GeneralMemory, N1: NormalSolution,
                    edges1: _Edges):
        """Try slip configurations, most likely first; return ((sol, shear), message)."""
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
            sol = problem.solve(cfg, guess)
            if not sol.converged:
                continue
            shear = problem.shear(sol)
            violation = self._violation(problem, data, sol, shear)
            if violation <= 1.0:
                return (sol, shear), ""
            if violation < best_violation:
                best, best_violation = (sol, shear), violation
        if best is None:
            sol = problem.solve(Config(0, 0))
            return (sol, problem.shear(sol)), "slip solve did not converge for any slip-zone configuration; " \
                                              "full stick kept"
        return best, (
            "slip solve: no slip-zone configuration met the Coulomb and slip-direction checks; "
            f"kept the closest (violation {best_violation:.2g} x tolerance)"
        )

    def _coulomb(self, problem: StepProblem, shear: Shear) -> float:
        """Largest excess of abs(q) over f p on the stick interval, relative to f max p."""
        t = sie.chebyshev_nodes(self.nodes)
        x = shear.center + shear.radius * t
        p = problem.normal.pressure(x)
        q = shear.evaluate(x, p, self.f)
        return float(np.max(np.abs(q) - self.f * p)) / problem.p_scale

    def _violation(self, problem, data, sol, shear) -> float:
        """Coulomb excess and reversed slip, each relative to its tolerance (<= 1 passes)."""
        coulomb = self._coulomb(problem, shear)
        E_start = data.E + sol.gauge * data.gauge
        _, dg = self._slip_update(problem, shear, data.X, data.kind, E_start, data.spacing)
        reverse = 0.0
        for sign, zone in ((sol.config.left, data.X < sol.stick_left), (sol.config.right, data.X > sol.stick_right)):
            if sign != 0 and np.any(zone):
                reverse = max(reverse, float(np.max(-sign * dg[zone])))
        scale = float(np.max(np.abs(dg)))
        direction = reverse / scale if scale > 0.0 else 0.0
        return max(coulomb / COULOMB_TOL, direction / DIRECTION_TOL)

    def _slip_update(self, problem, shear, X, kind, E_start, h):
        """Strain at the end of the step and slip increment at points X (shape (n,) each).

        Stuck points keep E_start; points in a slip zone take the current
        Delta-eps, and their slip increment is the integral of the strain change
        from the stick edge outward (trapezoid over X; the stick edge itself
        does not slip).
        """
        E_end = E_start.copy()
        dg = np.zeros_like(X)
        cfg = shear.config
        b1, b2 = shear.stick_left, shear.stick_right
        Xa, Ea = _augment(X, kind, E_start)
        for side, sign, zone in ((-1, cfg.left, X < b1), (1, cfg.right, X > b2)):
            if sign == 0 or not np.any(zone):
                continue
            b = b1 if side < 0 else b2
            near = np.abs(X[zone] - b) <= NEAR_SPACINGS * h
            E_end[zone] = problem.strain(shear, X[zone], near)
            order = np.flatnonzero(zone)[::-side]  # outward from b
            xs = np.concatenate(([b], X[order]))
            diff = np.concatenate(([0.0], E_end[order] - E_start[order]))
            dg[order] = np.cumsum(0.5 * (diff[1:] + diff[:-1]) * np.diff(xs))
        return E_end, dg

    # -- finishing a step ---------------------------------------------------
    def _finish(self, state, t1, loads1, N1, data, problem, sol, shear, slipped, normal_changed, message, edges1):
        mem = state.memory
        f = self.f
        cfg = sol.config
        L1, R1 = N1.left, N1.right
        W = R1 - L1
        b1, b2 = sol.stick_left, sol.stick_right
        left_zone = cfg.left != 0 and b1 - L1 > 1e-9 * W
        right_zone = cfg.right != 0 and R1 - b2 > 1e-9 * W
        regime = Regime.PARTIAL_SLIP if (left_zone or right_zone) else Regime.STICK
        if regime == Regime.STICK:
            self.counters["stick_steps"] += 1
        E_start = data.E + sol.gauge * data.gauge
        X, kind, E_start, G0, p0 = data.X, data.kind, E_start, data.G, data.p0
        if regime == Regime.PARTIAL_SLIP:
            X, kind, E_start, G0, p0 = self._clusters(data, E_start, b1 if left_zone else None,
                                                      b2 if right_zone else None, N1)
        E_end, dg = self._slip_update(problem, shear, X, kind, E_start, data.spacing)
        p1 = N1.pressure(X)
        dissipation = _dissipation(X, dg, p0, p1, f)
        ratio = list(mem.edge_ratio)
        for i, s in enumerate((cfg.left, cfg.right)):
            if s != 0:
                ratio[i] = s * f
            elif edges1.v[i] > 0.0:
                ratio[i] = edges1.u[i] / edges1.v[i]
        q_fit = self._fit(N1, shear)
        stuck = _stuck_point(mem.normal, b1, b2, data.first)
        shift = self._shift(state, mem, N1, q_fit, stuck, loads1)
        residual = 0.0
        if cfg == Config(0, 0):
            residual = abs(problem.gammas(cfg, L1, R1, sol.gauge)[0]) / problem.p_scale
        new_mem = GeneralMemory(N1, data.origin, data.spacing, _frozen(X), _frozen(E_end), _frozen(G0 + dg),
                                _frozen(kind), shear, tuple(ratio), q_fit, residual)
        stick = (L1, R1) if regime == Regime.STICK else (b1, b2)
        new = ContactState(float(t1), loads1, L1, R1, stick[0], stick[1], shift, state.dissipation + dissipation,
                           new_mem)
        return new, StepReport(regime, slipped, normal_changed, message)

    def _clusters(self, data, E_start, b_left, b_right, N1):
        """Drop cluster points inside the slip zones and lay new ones at the stick edges.

        A stick edge b becomes a SINGULAR point (E there is the stuck value) with
        CLUSTER_POINTS points at b -+ h (k/K)^2 on its slip side, so that the
        square-root rise of E into the slip zone survives when the zone stops.
        """
        X, kind = data.X, data.kind
        drop = np.zeros(X.size, dtype=bool)
        if b_left is not None:
            drop |= (X < b_left) & (kind >= CLUSTER)
        if b_right is not None:
            drop |= (X > b_right) & (kind >= CLUSTER)
        h = data.spacing
        offsets = h * (np.arange(1, CLUSTER_POINTS + 1) / CLUSTER_POINTS) ** 2
        new_x, new_kind = [], []
        for b, side, sing in ((b_left, -1, SINGULAR_LEFT), (b_right, 1, SINGULAR_RIGHT)):
            if b is None:
                continue
            pts = b + side * offsets
            pts = pts[(pts > N1.left) & (pts < N1.right)]
            new_x += [np.array([b]), pts]
            new_kind += [np.array([sing]), np.full(pts.size, CLUSTER)]
        keep = ~drop
        Xa, Ea = _augment(X, kind, E_start)
        add_x = np.concatenate(new_x)
        add_kind = np.concatenate(new_kind).astype(np.int8)
        X2 = np.concatenate((X[keep], add_x))
        kind2 = np.concatenate((kind[keep], add_kind))
        E2 = np.concatenate((E_start[keep], np.interp(add_x, Xa, Ea)))
        G2 = np.concatenate((data.G[keep], np.interp(add_x, X, data.G)))
        p2 = np.concatenate((data.p0[keep], np.interp(add_x, X, data.p0)))
        order = np.argsort(X2, kind="stable")
        X2, kind2, E2, G2, p2 = X2[order], kind2[order], E2[order], G2[order], p2[order]
        X2, kind2, (E2, G2, p2) = _merge(X2, kind2, 1e-9 * h, E2, G2, p2)
        return X2, kind2, E2, G2, p2

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
        p1 = N1.pressure(X)
        dissipation = _dissipation(X, dg, data.p0, p1, f)
        q_fit = self._fit(N1, shear)
        shift = self._shift(state, mem, N1, q_fit, stuck, loads1)
        new_mem = GeneralMemory(N1, data.origin, data.spacing, _frozen(X[keep]), _frozen(E_end[keep]),
                                _frozen((data.G + dg)[keep]), _frozen(data.kind[keep]), shear, (s * f, s * f),
                                q_fit, 0.0)
        message = ""
        if abs(loads1.Q) > f * loads1.P * (1.0 + 1e-12):
            message = "abs(Q) > f P: gross sliding, shear force carried limited to f P"
        new = ContactState(float(t1), loads1, L1, R1, math.nan, math.nan, shift, state.dissipation + dissipation,
                           new_mem)
        return new, StepReport(Regime.GROSS_SLIDING, True, normal_changed, message)

    def _separate(self, state, t1, loads1):
        mem = state.memory
        shift = state.shift
        if mem.normal is not None and mem.q_fit is not None:
            shift += self._potential(mem.normal, mem.q_fit, mem.normal.center)
        nan = math.nan
        empty = _frozen(np.zeros(0))
        new_mem = GeneralMemory(None, mem.origin, mem.spacing, empty, empty, empty, _frozen(np.zeros(0, np.int8)),
                                None, (0.0, 0.0), None)
        message = f"separated (P <= 0): shear force Q = {loads1.Q:g} N/m not carried" if loads1.Q != 0.0 else ""
        new = ContactState(float(t1), loads1, nan, nan, nan, nan, shift, state.dissipation, new_mem)
        return new, StepReport(Regime.SEPARATED, False, mem.normal is not None, message)

    # -- rigid shift --------------------------------------------------------
    def _fit(self, N: NormalSolution, shear: Shear) -> np.ndarray:
        """U-series coefficients of q on the contact, shape (FIT_TERMS,)."""
        t = sie.u_nodes(FIT_TERMS)
        x = N.center + N.half_width * t
        q = shear.evaluate(x, N.pressure(x), self.f)
        return _frozen(sie.u_coefficients(q))

    def _potential(self, N: NormalSolution, coef: np.ndarray, x: float) -> float:
        """(A/pi) int q ln(abs(x - xi) / l) dxi from the U-series of q."""
        r = N.half_width
        t = (x - N.center) / r
        return self.A * r * (0.5 * coef[0] * math.log(r / self.datum) + sie.log_potential(coef, t))

    def _shift(self, state, mem, N1, q_fit, stuck, loads1) -> float:
        """delta such that g(stuck) is unchanged (g = delta + potential + A sigma x / 4)."""
        before = state.shift + 0.25 * self.A * state.loads.sigma * stuck
        if mem.normal is not None:
            before += self._potential(mem.normal, mem.q_fit, stuck)
        return before - self._potential(N1, q_fit, stuck) - 0.25 * self.A * loads1.sigma * stuck

    # -- output -----------------------------------------------------------
    def tractions(self, memory: GeneralMemory, x) -> tuple[np.ndarray, np.ndarray]:
        """Pressure p(x) and shear traction q(x) [Pa], each of the shape of ``x``."""
        x = np.asarray(x, dtype=float)
        if memory.normal is None:
            return np.zeros(x.shape), np.zeros(x.shape)
        p = memory.normal.pressure(x)
        return p, memory.shear.evaluate(x, p, self.f, exact=True)

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


@dataclass(frozen=True)
class _Data:
    """Material points of the new contact and what they carry into the step (shapes (n,))."""

    origin: float
    spacing: float
    X: np.ndarray
    kind: np.ndarray
    E: np.ndarray  # strain at the start (arrivals: on arrival, gauge force 0)
    gauge: np.ndarray  # d E / d F
    G: np.ndarray  # slip so far
    p0: np.ndarray  # pressure at the start
    first: float  # where contact formed (NaN unless the step starts separated)


def _augment(X: np.ndarray, kind: np.ndarray, E: np.ndarray, *others: np.ndarray):
    """Insert virtual points in the cell on the slip side of each SINGULAR point.

    In that cell E = E(b) + (E(x1) - E(b)) sqrt((x - b) / (x1 - b)); the
    virtual points b + (x1 - b)(j/V)^2 carry it to the piecewise-linear
    machinery. ``others`` are interpolated linearly.

    Returns
    -------
    Xa, Ea, *others_a : ndarray, shape (m,) each
    """
    sing = np.flatnonzero(kind >= SINGULAR_LEFT)
    if sing.size == 0:
        return (X, E, *others)
    frac = np.arange(1, VIRTUAL_POINTS) / VIRTUAL_POINTS
    xs, es = [X], [E]
    for i in sing:
        j = i - 1 if kind[i] == SINGULAR_LEFT else i + 1
        if j < 0 or j >= X.size:
            continue
        xs.append(X[i] + (X[j] - X[i]) * frac**2)
        es.append(E[i] + (E[j] - E[i]) * frac)
    Xa = np.concatenate(xs)
    Ea = np.concatenate(es)
    order = np.argsort(Xa, kind="stable")
    Xa, Ea = Xa[order], Ea[order]
    return (Xa, Ea, *(np.interp(Xa, X, o) for o in others))


def _merge(X, kind, tol, *values):
    """Sort points and drop near-duplicates, keeping edges and then the highest kind."""
    priority = np.where(kind == EDGE, 10, kind)
    order = np.lexsort((-priority, X))
    X, kind = X[order], kind[order]
    values = [v[order] for v in values]
    keep = np.ones(X.size, dtype=bool)
    last = 0
    for i in range(1, X.size):
        if X[i] - X[last] <= tol:
            # keep the higher priority of the two
            if priority[order][i] > priority[order][last]:
                keep[last] = False
                last = i
            else:
                keep[i] = False
        else:
            last = i
    # no point may sit beyond or on an edge except the edges themselves
    edges = kind == EDGE
    lo, hi = X[edges].min(), X[edges].max()
    keep &= edges | ((X > lo + tol) & (X < hi - tol))
    out = (X[keep], kind[keep])
    if values:
        return (*out, tuple(v[keep] for v in values))
    return out


def _dissipation(X, dg, p0, p1, f) -> float:
    """int f (p0 + p1)/2 abs(dg) dx over the points, trapezoid."""
    y = f * 0.5 * (p0 + p1) * np.abs(dg)
    return float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(X)))


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


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.asarray(a)
    a.flags.writeable = False
    return a
