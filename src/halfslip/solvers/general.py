"""The general tangential solver: each step is a strictly convex problem on a material lattice.

Formulation (docs/general_solver.md has the derivation and the measurements).
The surface is divided into cells of width h fixed in space, x_j = (j + 1/2) h
(both bodies are half-planes: material points do not move). A cell is in
contact when its centre is inside the contact [L, R]; it carries a constant
shear q_j and the relative tangential displacement of its centre (physics.md,
T1 integrated, the datum l of the log kernel):

    g_i = delta - sum_j t_(i-j) q_j + A sigma x_i / 4       (_toeplitz: T symmetric Toeplitz, SPD)

The memory is g_lock, the displacement each cell in contact had at the end of
the previous step (for a cell arriving during the step: at the instant its
centre entered the contact, below). Over a step to the loads (P, Q, M, sigma)
the new q minimises

    1/2 q^T T q + q^T (g_lock - A sigma x / 4)
    subject to  |q_j| <= f cap_j,  h sum q_j = Q,

cap_j = (1/h) int p over the cell (the end cells reach to the contact edges,
so that h sum cap = P exactly). The multiplier of the equality is the rigid
shift delta, and the multipliers of the bounds are the slip increments
s_j = g_j - g_lock,j: the Karush-Kuhn-Tucker conditions are exactly stick
(s = 0 where |q| < f cap), Coulomb and the slip direction (q s >= 0). T is
positive definite, so the solution is unique: any number of stick and slip
intervals, slip of either sign anywhere.

It is found by the primal-dual active set (the classic rule: a stick cell over
its bound slips in the direction of its q, a slip cell whose increment opposes
its direction sticks), warm-started from the previous step's pattern. Each
iteration solves T on the stick set: one contiguous run by the Gohberg-Semencul
formula (O(n log n)), several runs by conjugate gradients preconditioned with
the exact run solves. Should the pattern ever repeat, projected gradient
iterations (always convergent on a strictly convex problem) give the active set
a new start. Every step then checks its answer (Coulomb, direction,
equilibrium, stick) and reports it.

Arrivals (physics.md, first trap): a cell whose centre x enters the contact
at the left edge during the step locks the displacement it has at that
instant. Material between x and the old edge L0 arrived earlier and stuck, so

    g_lock(x) = g_0(x) - int_x^L0 inc(xi) dxi

with g_0 the displacement at the start of the step (the potential of the old
shear) and inc the strain the stuck increments (M1) add at xi up to its own
arrival (``_general_path.arrival_strains``); mirrored at the right edge.

Error estimate: the step is also taken on a shadow lattice of half the
resolution carried along in the state; the distance between the two solutions'
stick edges, relative to the contact width, estimates the fine solution's
edge error (the edges converge at first order in h).
"""
from __future__ import annotations

import functools
import math
import sys
from dataclasses import dataclass

import numba
import numpy as np

from .. import limits
from .._geometry_kernels import _load_to_terms, _pressure_at, pairwise_sum
from ..geometry import NormalProblem, NormalSolution
from ..state import EDGE_PATH_MESSAGE, EDGE_PATH_PATTERN, GROSS_SLIDING_MESSAGE, ContactState, Loads, Regime, StepReport
from ..state import frozen as _frozen
from ._general_path import EdgePath, arrival_strain_parts, hermite_integrals
from ._windows import EdgeWindows, same_windows, window_size
from . import _toeplitz
from ._toeplitz import ToeplitzLattice, _end_matvec, _G, _run_array, _run_bounds, kernel, stick_solve, table_products
from .base import BACKWARD_SLIP, FORWARD_SLIP, OUT_OF_CONTACT, STICK, TangentialSolver

# Compiled functions here call compiled functions of other files: _load_to_terms, _pressure_at and
# pairwise_sum (_geometry_kernels), hermite_integrals (_general_path), _run_bounds and table_products
# (_toeplitz). numba's cache checks only the file a function is defined in, so after changing one of those
# in a working copy, delete the caches (find src -name '*.nb[ic]' -delete): a caller here would keep the old
# one compiled into it (in 0.4.4's development, a recursive pairwise_sum so kept crashed the process). An
# installed upgrade rewrites every file, which resets them all.

#: Default resolution: cells across the reference contact width (the widest contact of the history).
DEFAULT_NODES = 1024
#: Largest contact-edge travel per slipping sub-step, relative to the contact width.
DEFAULT_TRAVEL = 0.01
#: Largest travel of a stick edge per slipping sub-step, relative to the contact width. 0.04 since 0.4.8
#: (0.02 before): against the random histories' reference refined in space and time (the IC baseline at N =
#: 16000, every step in four sub-steps), the stick edges are as close at 0.04 (vouched 95th percentile, with
#: windows: punch 6.2e-5 / 4.1e-5 at 512 / 1024 nodes against 6.6e-5 / 4.3e-5, Hertz 4.8e-5 / 3.6e-5 against
#: 4.9e-5 / 3.7e-5) and the final dissipation too (0.05-0.07 %), for 15-33 % less time a step; 0.08 loses the
#: punch's edges (1.1e-4 / 5.8e-5). What 0.04 costs: a long reversal step (the receding punch's last step,
#: tests/test_general.py) misses the exact method's dissipation by 0.84 % at 1024 nodes instead of 0.67 %
#: (0.97 % / 0.34 % at 256; Hertz within 0.07 % either way); the dovetail never has a stick edge travel 0.02 of
#: the width in a step (the same to the last bit). docs/general_solver.md, "0.4.7 -> 0.4.8".
DEFAULT_STICK_TRAVEL = 0.04
#: Most sub-steps one step is divided into.
MAX_SUBSTEPS = 64
#: The shadow lattice takes every SHADOW_EVERY-th sub-step of the fine one, and a step of at most that many
#: sub-steps in one take, the one that decided them (docs/general_solver.md, "The error estimate"). Its
#: sub-steps stay a fixed multiple of the fine ones, so the estimate converges with them. 2 keeps its
#: arrivals per sub-step in proportion to its cells; 4 takes 10-14 % less CPU time per step on the random
#: histories at 1024 nodes (A/B) with the same estimates there (95th percentile 7.0e-4 against 7.2e-4, the
#: same median and coverage), and at 4096 nodes the same median (2.8e-5) and a 95th percentile 1.26e-4
#: against 6.9e-5: the shadow's longer sub-steps add their time error, on the safe side. One take of the
#: whole step (no sub-steps for the shadow) would not converge: 4.2e-4 at 4096 nodes.
SHADOW_EVERY = 4
#: Cells a contact edge may advance in one sub-step while part of the contact slips (the arrivals' locked
#: displacements: the shape of M1's increments, their size from the lattice, _take; measured in
#: docs/general_solver.md).
ARRIVAL_CELLS = 8
#: How many cells beyond a growing edge the increments are matched to the lattice's own.
ARRIVAL_MATCH = 3
#: How near a whole number of cells (in cells) a point must be to count as a cell centre of the lattice, where
#: displacements are taken from the kernel's table (GeneralSolver._products): the centres are computed as
#: (j + 1/2) h, so they are within rounding of it; anything else is not a centre.
LATTICE_POINT = 1e-6
#: (dQ, dsigma) of the M1 increments whose shape the arrivals take: a unit shear force (the inverse
#: square root at a stuck edge; the actual (dQ, dsigma) is 0 when only P and M change, as when a moment
#: moves the contact, and the shape would be lost).
ARRIVAL_SHAPE = (1.0, 0.0)
#: A cell that leaves the contact while slipping carries, on average over its time in contact, this
#: fraction of its pressure at the step's start: near a contact edge p grows like the square root of the
#: distance to it, and the edge passes the cell at a steady rate over a (sub-)step, so p / p_0 = sqrt(1 - u)
#: over the fraction u of that time, whose mean is 2/3 (:meth:`GeneralSolver._leaving`).
LEAVING_PRESSURE = 2.0 / 3.0
#: Gauss-Legendre points (in theta, x = c - d cos theta) per piece of an end cell's support for its
#: pressure-weighted log integral (:class:`_EndCell`), mapped by the quintic smoothstep
#: 10 u^3 - 15 u^4 + 6 u^5 (points graded towards both ends of each piece: the log singularity at the cell's
#: own centre and the x ln x kinks of p at the ends of a punch flat). Against adaptive quadrature
#: (tests/test_solver_kernels.py): 7e-15 of t_0 at P0; a punch at 1e-12 P0, whose kink lies 4e-9 of the flat
#: beyond the contact edge (a near-singularity of the rule's piece), 1.7e-9 relative (24 points 8.7e-8,
#: the cubic smoothstep at 24 points 5.1e-7).
END_CELL_GAUSS = 32
_EC_T, _EC_W = np.polynomial.legendre.leggauss(END_CELL_GAUSS)
_EC_T, _EC_W = 0.5 * (_EC_T + 1.0), 0.5 * _EC_W
_EC_S, _EC_DS = _EC_T ** 3 * (10.0 - 15.0 * _EC_T + 6.0 * _EC_T ** 2), 30.0 * _EC_T ** 2 * (1.0 - _EC_T) ** 2 * _EC_W
#: Beyond this many cells from an end cell's centre its correction column comes from the multipole series of
#: the log kernel (END_CELL_TERMS terms; the support lies within a cell of the centre, so the series converges
#: like 1/END_CELL_NEAR^k: 8^-20 / 20 < 1e-19, below rounding) instead of the quadrature at every point.
END_CELL_NEAR = 8
END_CELL_TERMS = 20
#: End cells and cell-load tables kept, per contact (NormalSolution) and spacing. A step asks for those of its
#: fine and shadow lattices and the next step's start; a periodic history asks for the same
#: contacts again every cycle (the simulator keeps the normal solutions of its samples, simulator.contact_edges),
#: so that what depends on the contact alone is found once per phase rather than once per step (the dovetail:
#: 100 steps a cycle, 4 end cells and 2 tables a step, about 2 kB and 8 kB each at 1000 nodes).
END_CELLS_KEPT = 512
LOADS_KEPT = 256
#: States whose sum of shear GeneralSolver keeps (the next take of each asks).
SUMS_KEPT = 16
#: Active-set iterations before the projected-gradient restart.
MAX_ACTIVE_SET = 100
#: the stick-set solves' conjugate gradients (several runs far apart): relative residual, iterations
CG_TOL, CG_ITERATIONS = 1e-13, 200
#: The active set changes a cell only for a violation above this, relative to f max p (Coulomb) and to the
#: displacement scale A f max p h (slip direction): at a degenerate cell (at the bound and not slipping,
#: common where old slip zones are re-entered) rounding-level violations of either sign would otherwise
#: make the pattern chatter (measured on the motor example: excesses of 1e-13 .. 5e-11 f max p, 100
#: iterations without convergence). Far below CHECK_TOL, which the step's verification applies.
FLIP_TOL = 1e-10
#: A step's checks (Coulomb excess and equilibrium relative to f max p and f P; stick and direction
#: residuals relative to A f max p h) must hold to this: the solves
#: are exact to rounding (Gohberg-Semencul; CG to 1e-13), so anything larger is a failure.
CHECK_TOL = 1e-7
#: Relative rounding of the locked displacements, which carry the history's rigid slide: a slip
#: increment below ROUNDING max abs(g) cannot be told from zero (a punch at P = 2e-7 N/m after a
#: history at 1e5 N/m: A f max p h ~ 1e-19 m against g ~ 1e-10 m). ~500 machine epsilons: the FFT
#: solves lose a few hundred.
ROUNDING = 1e-13
#: Two states are the same (a steady cycle is reached) when their shear agrees to this fraction of
#: f max p and their locked displacements to this fraction of the largest slip increment of the
#: step, on the same cells: a repeating active-set pattern reproduces the state to rounding.
SAME_STATE_TOL = 1e-8
#: How the report of a separated step begins.
SEPARATED_PREFIX = "separated (P <= 0)"
#: The lattice's cell loads come from the closed-form load_to when its rounding is at most this fraction of
#: the mean load of a cell (and by quadrature otherwise): 1e-11, the accuracy the quadrature reaches
#: (tests/test_stress_general.py: test_capacity_is_the_mean_pressure_of_each_cell), 1e4 below the step
#: checks (CHECK_TOL).
LOAD_ROUNDING = 1e-11
EPS = float(np.finfo(float).eps)
#: How well a stick edge is placed within its cell, in cells: the floor of the edge error estimate of a
#: partially slipping step. J1 and J2 on both profiles at 128 .. 1024 nodes (248 steps, 19 loads and 12
#: unloadings per resolution): the edge error is 0.09 of a cell in the median, 0.13 at the 90th
#: percentile, while the distance to the shadow lattice's edges fell to 0.003 of a cell (error / that
#: distance up to 39); with this floor error / estimate is at most 1.7 there. Since 0.3.7 (EDGE_RULE) J1 and
#: J2 are placed to a few hundredths of a cell, and the floor is set by the random histories: edges inside the
#: contact 0.09 of a cell off at the 95th percentile at 1024 nodes.
EDGE_PLACEMENT = 0.1
#: How well a slip zone of at most about a cell is placed, in cells: the floor of the edge error estimate
#: where (S1) says a contact edge slips but its end cell sticks, or where the end cell alone slips (both
#: placed by the local Cattaneo form, which reports it, _run_edges; the shadow lattice places them the same
#: way, so the two lattices' distance says nothing there), unless the outermost stick cell is within
#: END_RATIO_ERROR of its bound (then half a cell). 0.3 since 0.4.9 (0.5 since 0.3.3, a whole cell before),
#: twice the largest error measured against the exact method on zones under 1.5 cells (J1 / J2, J3 with P
#: falling fast and slowly at dQ/dP = 0.25 .. 0.35 f from a proportional state at 0.3 f, the motor loop;
#: both profiles at 256 / 512 / 1024 nodes, the lattice and its windows' fine cells: 0.068 of a cell on the
#: lattice, 0.146 of a fine cell on the windows; J1 at Q = 0.001 .. 0.06 f P, 0.085 since END_RULE_*).
#: The dovetail's receding left edge (examples/dovetail.yaml, every step marched, windows at 1000 nodes
#: against the lattice at 16000) read 0.335 of a fine cell off where its end cell stood at 0.998 of its
#: bound, the zone about to take the whole cell, and 0.3 where 4000, 8000 and 16000 nodes disagree among
#: themselves by 0.66 of one (an ill-conditioned edge, docs/general_solver.md "Sub-cell zones").
SUBCELL_PLACEMENT = 0.3
#: How far from its bound an end cell's ratio q / (f cap) may be off: measured on proportional states (J3 with
#: k' = k, 256 nodes, 0.3.9) 0.5 - 5 % of it. An outermost stick cell nearer its bound than this may as well
#: slip, so a slip zone placed within it by the local form may reach its inner boundary: placed to half a cell
#: (_run_edges), as a bracketed edge.
END_RATIO_ERROR = 0.05
#: The lattice's own response to a square-root stick edge (benchmarks/calibrate_edge_rule.py): with rho =
#: m_k / m_(k-1) the traction margins f cap - s q of the outermost stick cell k and its inner neighbour,
#: the stick edge lies u(rho) = polyval(EDGE_RULE, rho) cells outward of x_k (from -0.17 at rho = 0, where
#: cell k is about to slip, to 0.82 at EDGE_RULE_RHO, where its outer neighbour is about to stick). The
#: local discrete problem is the same at every scale (the kernel's cell integrals are h times a fixed
#: sequence plus a constant that the rigid shift absorbs), so u depends on rho alone to leading order:
#: fitted on J1 (Hertz, 2048 nodes, residual 1.2e-4 of a cell), it places J1 and J2 on Hertz and on the
#: rounded punch at 256 - 1024 nodes to at most 0.024 of a cell (0.17 - 0.20 with the square of the
#: margin extrapolated linearly, 0.3.3 - 0.3.6).
EDGE_RULE = (0.181491, 0.103012, 0.448258, 0.997502, -0.174637)
EDGE_RULE_RHO = 0.7005
#: The largest rho a square-root margin gives on the lattice: slip zones of a few cells go a little beyond
#: EDGE_RULE_RHO (the next order of the local form; J1 and J2 on both profiles at 128 - 512 nodes: up to 0.79
#: on the punch at 128 nodes, 0.72 at 256, 0.70 at 512, their edges 0.70 - 0.82 of a cell outward). Up to
#: here an edge is put where EDGE_RULE ends (0.82; at most 0.12 of a cell off there); beyond it the margin
#: does not follow the square root (a margin an earlier slip left, a band of cells near their bound) and the
#: edge is bracketed by the two centres.
EDGE_RULE_REACH = 0.8
#: Slip zones at a contact edge E narrower than about two cells, placed by the local Cattaneo form
#: (x - E) m^2 = x - c from the two outermost stick cells (_run_edges), within the end cell where it sticks
#: (END_RULE_WITHIN) or beyond it where it alone slips (END_RULE_END): that form's estimate w_est of the slip
#: zone's width is off by up to 0.2 of a cell, by an amount that depends on w_est and on the distance u_e
#: from the end cell's centre to E (both in cells) alone. The lattice's response, w - w_est =
#: sum c[i][j] w_est^i u_e^j, fitted on J1 (Hertz, 1024 nodes, the contact edge at 41 places across a cell;
#: benchmarks/calibrate_edge_rule.py): J1 at 256 nodes on both profiles 95th percentile 0.03 / 0.02 of a
#: cell, largest 0.085 / 0.055 (the local form alone: 0.18 / 0.20), the largest where the margins barely
#: change with the width, before the branch changes.
END_RULE_WITHIN = (
    (9.059554e-02, -1.897481e+00, 1.169895e+01, -2.987890e+01, 3.350241e+01, -1.364702e+01),
    (2.797208e+00, -2.910195e+01, 9.741024e+01, -1.379325e+02, 6.885088e+01, 0.000000e+00),
    (1.298867e+01, -8.877401e+01, 1.967193e+02, -1.361102e+02, 0.000000e+00, 0.000000e+00),
    (3.056320e+01, -1.382052e+02, 1.459799e+02, 0.000000e+00, 0.000000e+00, 0.000000e+00),
    (3.692215e+01, -7.872075e+01, 0.000000e+00, 0.000000e+00, 0.000000e+00, 0.000000e+00),
    (1.688621e+01, 0.000000e+00, 0.000000e+00, 0.000000e+00, 0.000000e+00, 0.000000e+00),
)
END_RULE_END = (
    (1.996221e-01, -2.485424e-02, -4.923960e+00, -1.595531e+01, -1.930837e+01, -9.021456e+00),
    (-2.142632e-02, 1.000087e+01, 4.710284e+01, 7.807370e+01, 4.407653e+01, 0.000000e+00),
    (-4.984379e+00, -4.698341e+01, -1.168284e+02, -8.766971e+01, 0.000000e+00, 0.000000e+00),
    (1.562771e+01, 7.769391e+01, 8.739357e+01, 0.000000e+00, 0.000000e+00, 0.000000e+00),
    (-1.938142e+01, -4.359763e+01, 0.000000e+00, 0.000000e+00, 0.000000e+00, 0.000000e+00),
    (8.703506e+00, 0.000000e+00, 0.000000e+00, 0.000000e+00, 0.000000e+00, 0.000000e+00),
)
#: A stick run at a contact edge that (S1) says slips, this many cells wide or less, is an island that the
#: shadow lattice (cells twice as wide) cannot confirm: two of its cells. On the random histories at 1024
#: nodes such runs were 1-11 cells wide (Hertz) and 1 or >= 96 (punch); one of 3 cells at a receding
#: edge was gone at 2048 nodes, 0.2 of the width outside the next stick run (see _unresolved_reach).
UNCONFIRMED_ISLAND = 4
#: Levels of geometric grading (ratio 4) towards a kink of h' (punch flat ends) in the pressure integrals.
KINK_GRADING = 16
#: Gauss-Legendre points per cell for the pressure integrals and the arrival integrals.
CELL_GAUSS = 8
#: Points from edge to edge at which _Load checks the rounding of the closed-form loads (the size of their
#: terms varies smoothly along the contact).
LOAD_SAMPLES = 17
_GL_T, _GL_W = np.polynomial.legendre.leggauss(CELL_GAUSS)
_GL_T, _GL_W = 0.5 * (_GL_T + 1.0), 0.5 * _GL_W
#: Gauss-Legendre points of _Load's quadrature on the intervals at least FAR_SPANS of their own span (in
#: theta) from every knot of the pressure (its x ln x points), where p d sin(theta) is analytic in an ellipse
#: about the interval with semi-axes sum rho >= 2 FAR_SPANS = 60: the n-point rule's error is then below
#: 64 / 15 max|f| rho^(-2n) / (rho^2 - 1), 7e-18 max|f| for n = 4, far below the quadrature's 1e-14 of a
#: cell's load (tests/test_stress_general.py: test_the_load_quadratures_far_rule_is_the_eight_point_rule, and the
#: capacities against an independent quadrature, test_capacity_is_the_mean_pressure_of_each_cell). Most cells of a
#: rounded punch are that far from the flat's ends: the quadrature takes half the pressure evaluations.
FAR_GAUSS, FAR_SPANS = 4, 30.0
_FAR_T, _FAR_W = np.polynomial.legendre.leggauss(FAR_GAUSS)
_FAR_T, _FAR_W = 0.5 * (_FAR_T + 1.0), 0.5 * _FAR_W
#: Gauss-Legendre points on the intervals next to a kink of h' (x ln x in p).
KINK_GAUSS = 16
_KINK_T, _KINK_W = np.polynomial.legendre.leggauss(KINK_GAUSS)
_KINK_T, _KINK_W = 0.5 * (_KINK_T + 1.0), 0.5 * _KINK_W


@dataclass(frozen=True)
class GeneralMemory:
    """Immutable memory of the lattice solver.

    Attributes
    ----------
    normal : NormalSolution or None
        Normal solution of the state (None when separated).
    spacing : float
        Cell width h [m] (NaN before the first contact).
    first : int
        Lattice index of the first cell in contact.
    status : ndarray of int8, shape (n,)
        What each cell did in the step that ended here: 0 stuck, +1 / -1 slipped
        forward / backward (q = +- f cap).
    q : ndarray, shape (n,)
        Shear traction of each cell [Pa].
    g : ndarray, shape (n,)
        Relative tangential displacement of each cell's centre [m] (consistent with ``shift``).
    G : ndarray, shape (n,)
        Slip accumulated since each cell entered contact [m].
    capacity : ndarray, shape (n,)
        Mean pressure over each cell (h sum = P) [Pa].
    shift : float
        Rigid shift delta of this lattice's solution (datum of the solver) [m].
    error : float
        Error estimate of the stick edges, relative to the contact width (NaN without the shadow).
    coarse : GeneralMemory or None
        The shadow lattice's memory (half the resolution) for the error estimate.
    windows : tuple of EdgeWindow
        The fine windows at the contact edges after the take that ended here (``edge_windows``;
        :mod:`halfslip.solvers._windows`): their own shear and slip, the history of the next take's windows.
    """

    normal: NormalSolution | None
    spacing: float
    first: int
    status: np.ndarray
    q: np.ndarray
    g: np.ndarray
    G: np.ndarray
    capacity: np.ndarray
    shift: float = 0.0
    error: float = math.nan
    coarse: "GeneralMemory | None" = None
    windows: tuple = ()

    @property
    def x(self) -> np.ndarray:
        """Cell centres [m]."""
        return (self.first + 0.5 + np.arange(self.q.size)) * self.spacing


@dataclass(frozen=True)
class _Context:
    """What both lattices of one step share: the end's normal solution, the fine cell, the edge path
    (None unless the contact grows), the pressure integrals, whether the normal problem was solved."""

    N1: NormalSolution
    h: float
    path: EdgePath | None
    load: "_Load"
    normal_changed: bool


@dataclass(frozen=True)
class _Outcome:
    """One lattice's step: the new memory and what the step did."""

    memory: GeneralMemory
    shift: float
    dissipation: float
    stick: tuple
    widest: tuple
    regime: Regime
    slipped: bool
    iterations: int
    residual: float
    message: str = ""
    slipping: tuple = (False, False)  # whether (S1) says the left / right contact edge slips in the step
    placement: float = 0.0  # how far, in cells, the placement rule puts the outermost / widest edges at most (_run_edges)
    slip: np.ndarray | None = None  # each cell's slip in the take and its load at the take's start (the fine take's,
    cap0: np.ndarray | None = None  # with edge_windows: the windows take the dissipation of the cells they cover)
    undecided: tuple = (0.0, 0.0)  # with edge_windows: _undecided_reach at the outermost left / right stick edge
    placed: tuple = (0.0, 0.0)  # with edge_windows: _run_edges' placement of the outermost left / right stick edge
    drives: tuple | None = None  # (S1)'s (u / f, v) at each contact edge where one slips, as _run_edges takes them


class GeneralSolver(TangentialSolver):
    """Tangential solver for any profile and all four loads varying.

    Parameters
    ----------
    problem : NormalProblem
    friction : float
        Coulomb coefficient f.
    nodes : int
        Cells across the reference width ``width`` (the lattice spacing is
        width / nodes for the whole run).
    stations : array_like, optional
        Surface points whose accumulated slip :meth:`slip` returns.
    width : float, optional
        Reference contact width [m]; by default the width of the first contact.
    estimate : bool
        Carry the half-resolution shadow for the per-step error estimate. Its take
        of the whole step also decides the sub-steps (:meth:`_pieces`); without it
        the fine lattice takes that trial.
    travel : float, optional
        Largest travel of a contact edge, as a fraction of the contact width,
        over a slipping (sub-)step (0: never subdivide). Default DEFAULT_TRAVEL.
    stick_travel : float, optional
        Largest travel of a stick edge over a slipping (sub-)step, as a
        fraction of the contact width (0: never). Default DEFAULT_STICK_TRAVEL.
    arrivals : bool
        Sub-step a partially slipping step whose contact grows so that no edge
        advances more than one cell per sub-step (:meth:`_pieces`).
    normals : dict, optional
        Normal solutions of this problem keyed by (P, M) (the simulator's
        start-up solved each distinct sample of the history,
        ``simulator.contact_edges``): a (sub-)step ending on one of them
        takes it instead of solving again (the dovetail: 591 -> 141 normal
        solves, 132 of them at start-up). They agree with the step's own
        warm-started solve to the normal solver's tolerance.
    edge_windows : bool
        After every fine take, solve the contact's first and last cells again
        on fine windows (:mod:`halfslip.solvers._windows`): the outermost
        stick points, the shear, slip and station states on their cells and
        the dissipation there are theirs; the state carries their shear and
        slip as their history (none from 8000 nodes: the lattice is as fine).

    Attributes
    ----------
    datum : float
        Length l of the log-kernel datum of the rigid shift (profile length scale).
    counters : dict
        Work done: steps, sub-steps, takes (the fine and the shadow lattice's solves of a step or
        sub-step), active-set iterations, CG iterations, restarts, normal solves.
    """

    name = "general"

    def __init__(self, problem: NormalProblem, friction: float, nodes: int = DEFAULT_NODES, stations=None,
                 width: float | None = None, estimate: bool = True, travel: float | None = None,
                 stick_travel: float | None = None, arrivals: bool = True, normals: dict | None = None,
                 edge_windows: bool = False):
        self.problem = problem
        self._normals = {} if normals is None else normals
        self.f = float(friction)
        if not self.f > 0.0:
            raise ValueError(f"friction must be positive, got {friction!r}")
        self.nodes = int(nodes)
        if self.nodes < 8:
            raise ValueError(f"nodes must be at least 8, got {nodes!r}")
        self.width = None if width is None else float(width)
        if self.width is not None and not (math.isfinite(self.width) and self.width > 0.0):
            raise ValueError(f"width must be positive, got {width!r}")
        self.A = problem.compliance
        self.datum = problem.profile.length_scale
        self.stations = None if stations is None else np.asarray(stations, dtype=float)
        self.estimate = bool(estimate)
        self.arrivals = bool(arrivals)
        self.travel = DEFAULT_TRAVEL if travel is None else float(travel)
        self.stick_travel = DEFAULT_STICK_TRAVEL if stick_travel is None else float(stick_travel)
        if not (math.isfinite(self.stick_travel) and self.stick_travel >= 0.0):
            raise ValueError(f"stick_travel must be >= 0, got {stick_travel!r}")
        if not (math.isfinite(self.travel) and self.travel >= 0.0):
            raise ValueError(f"travel must be >= 0, got {travel!r}")
        self._lattices: dict[float, ToeplitzLattice] = {}
        self.windows = None
        if edge_windows and window_size(self.nodes)[1] >= 2:  # (from 8000 nodes the lattice is as fine)
            self.windows = EdgeWindows(self, sys.modules[__name__])
        self._kinks, self._graded_kinks = _slope_kinks(problem.profile)
        self._end_cells = _Kept(END_CELLS_KEPT)
        self._loads = _Kept(LOADS_KEPT)
        self._columns = _Kept(LOADS_KEPT)
        self._end_args = _Kept(LOADS_KEPT)  # _end_arguments' answers
        self._paths = _Kept(LOADS_KEPT)
        #: the edge path of the step being cut into sub-steps and the fraction of it at each sub-step's loads:
        #: their paths are parts of it (_on_line)
        self._line: tuple[EdgePath | None, dict[Loads, float]] | None = None
        self._sums = _Kept(SUMS_KEPT)  # sum q of the recent takes' states, by their q (the next take's datum term)
        self.counters = dict.fromkeys(("steps", "substeps", "takes", "shadow_takes", "iterations", "cg_iterations",
                                       "restarts", "normal_solves", "path_solves"), 0)

    # ------------------------------------------------------------------
    def initial_state(self, t0: float = 0.0) -> ContactState:
        """Separated, unloaded, no memory."""
        nan = math.nan
        return ContactState(float(t0), Loads(0.0, 0.0, 0.0, 0.0), nan, nan, nan, nan, 0.0, 0.0,
                            _empty(nan, None, 0.0))

    def step(self, state: ContactState, t1: float, loads1: Loads) -> tuple[ContactState, StepReport]:
        """Advance ``state`` to ``t1`` and ``loads1`` along the straight line in (P, Q, M, sigma).

        A step that slipped is taken again in equal sub-steps along the same
        line when its answer depends on the path within it (:meth:`_pieces`
        says when and how many); :meth:`_finish` says what its error estimate is.
        """
        self.counters["steps"] += 1
        loads1 = Loads(*(float(v) for v in loads1))
        t1 = float(t1)
        if loads1 == state.loads or not loads1.P > 0.0:
            return self._single(state, t1, loads1, None)[:2]
        ctx = self._context(state, loads1)
        rough = end = None
        if self.estimate:
            # the shadow lattice (twice the cell) takes the whole step: its answer decides the sub-steps, the
            # fine takes start from its pattern, and the error estimate compares it with the fine end state
            rough = self._rough(state, loads1, ctx)
            pieces = self._pieces(state, ctx, rough)
            end = _refined(rough.memory)
            if pieces <= 1:
                fine = self._take(state.memory, ctx.h, state.loads, loads1, ctx.N1, ctx.path, ctx.load, end)
                # unless the fine lattice slips where the shadow did not (a slip within the shadow's cells) and
                # that asks for sub-steps, this is the step
                if not fine.slipped or rough.slipped or (pieces := self._pieces(state, ctx, fine)) <= 1:
                    return self._finish(state, t1, loads1, ctx, fine, rough)[:2]
                # (a writable copy, as _refined's pattern: _toward_kernel is compiled once)
                end = (fine.memory.first, fine.memory.status.copy())
        else:
            fine = self._take(state.memory, ctx.h, state.loads, loads1, ctx.N1, ctx.path, ctx.load)
            pieces = self._pieces(state, ctx, fine)
            if pieces <= 1:
                return self._finish(state, t1, loads1, ctx, fine, None)[:2]
            end = (fine.memory.first, fine.memory.status.copy())
        self.counters["substeps"] += pieces
        # a step from separation: the sub-steps share the part of the step in contact
        loads0 = state.loads
        lo = 0.0 if state.memory.normal is not None or loads0.P >= 0.0 else loads0.P / (loads0.P - loads1.P)
        reports = []
        self._line = (ctx.path, {loads0: lo})  # the sub-steps' edge paths are parts of the step's (_on_line)
        try:
            sub, spread = self._sub_steps(state, t1, loads1, ctx, rough, end, pieces, lo, reports)
        finally:
            self._line = None
        last = reports[-1]
        # the gross-sliding and separation messages speak of the step's end loads (a sub-step may slide or be
        # separated while the end is not); the edge path's of locks the step keeps (none where it ends sliding)
        message = "; ".join(dict.fromkeys(r.message for r in reports if r.message and (
            r is last or not (r.message == GROSS_SLIDING_MESSAGE or r.message.startswith(SEPARATED_PREFIX)))))
        if last.regime == Regime.GROSS_SLIDING:
            # (a step ending in gross sliding drops its sub-steps' edge path notes)
            message = "; ".join(m for m in EDGE_PATH_PATTERN.sub("", message).split("; ") if m)
        return sub, StepReport(last.regime, any(r.slipped for r in reports), any(r.normal_solved for r in reports),
                               message,
                               converged=all(r.converged for r in reports),
                               residual=max(r.residual for r in reports),
                               iterations=sum(r.iterations for r in reports),
                               error_estimate=_at_least(last.error_estimate, spread),
                               shear_error_estimate=last.shear_error_estimate)

    def _sub_steps(self, state: ContactState, t1: float, loads1: Loads, ctx: "_Context", rough, end,
                   pieces: int, lo: float, reports: list) -> tuple[ContactState, float]:
        """:meth:`step`'s ``pieces`` equal sub-steps along its line from the fraction ``lo`` (their reports
        appended to ``reports``); returns the last state and the spread of the widest stick intervals."""
        loads0, t0 = state.loads, state.t
        spread = 0.0
        sub = shadow_from = state
        for k in range(1, pieces + 1):
            lam = lo + (1.0 - lo) * k / pieces
            at = Loads(*(a + lam * (b - a) for a, b in zip(loads0, loads1))) if k < pieces else loads1
            self._line[1][at] = lam if k < pieces else 1.0
            # the active set starts from the sub-step's start pattern moved towards the whole step's end
            # pattern (the stick-slip boundaries travel steadily through a step)
            hint = _toward(sub.memory, end, 1.0 / (pieces - k + 1))
            # the shadow lattice (twice the cell) takes every SHADOW_EVERY-th sub-step (its trial of the whole
            # step is that when there are no more sub-steps than that)
            last = k == pieces
            shadow = None
            if rough is not None and (last or k % SHADOW_EVERY == 0):
                shadow = rough if pieces <= SHADOW_EVERY else shadow_from.loads
            # the last sub-step ends where the whole step does: its normal solution is the step's
            sub, rep, apart = self._single(sub, t0 + lam * (t1 - t0) if not last else t1, at, shadow, hint,
                                           ctx.N1 if last else None)
            if shadow is not None:
                shadow_from = sub
            spread = max(spread, apart)  # (0 from a sub-step the shadow waits in, unless the windows set it)
            reports.append(rep)
        return sub, spread

    def _pieces(self, state: ContactState, ctx: "_Context", trial: "_Outcome") -> int:
        """Sub-steps for a step whose single solve is ``trial`` (the shadow's, or the fine lattice's where
        there is no shadow or it did not slip and the fine one did; 1: no sub-steps).

        * Arrivals while part of the contact slips: the arrivals' locked
          displacements come from the stuck increments (M1) of a fully stuck
          contact, which a partial slip does not have; sub-steps in which every
          contact edge advances at most one cell make that error first order in
          the cell, as the lattice's (as the IC reference, which splits its steps
          at every arrival). Measured on the random histories at 1024 nodes
          (docs/general_solver.md): stick edges 95th percentile 1.6e-3 -> 3e-4 of
          the width (Hertz), 7.5e-4 -> 3.3e-4 (punch).
        * A contact edge travelling more than ``travel`` of the width in a
          slipping step, or a stick edge more than ``stick_travel``: the
          answer depends on the path within the step (the dissipation error is
          second order in the step, measured against the exact method), at most
          MAX_SUBSTEPS.
        * A contact forming in a step that slips: its arrivals' stuck
          increments miss any slip on the way (a punch step from zero had a
          7 % interior slip zone that four sub-steps and the IC reference do not).
        """
        if not trial.slipped:
            return 1
        N0, N1 = state.memory.normal, ctx.N1
        W = N1.right - N1.left
        moved = 1.0 if N0 is None else max(abs(N1.left - N0.left), abs(N1.right - N0.right)) / W
        pieces = math.ceil(moved / self.travel) if self.travel > 0.0 else 1
        if self.stick_travel > 0.0 and trial.regime == Regime.PARTIAL_SLIP and np.isfinite(state.stick_left):
            # from the lattice's own edges (not the windows', which leave the lattice as it is)
            old = [state.stick_left, state.stick_right]
            for w in state.memory.windows:
                old[(w.side + 1) // 2] = w.lattice_edge
            travelled = max(abs(trial.stick[0] - old[0]), abs(trial.stick[1] - old[1])) / W
            pieces = max(pieces, math.ceil(travelled / self.stick_travel))
        pieces = min(MAX_SUBSTEPS, pieces)
        if self.arrivals and trial.regime == Regime.PARTIAL_SLIP and N0 is not None:
            grew = max(N0.left - N1.left, N1.right - N0.right, 0.0) / ctx.h
            pieces = max(pieces, math.ceil(grew / ARRIVAL_CELLS))
        return pieces

    def _single(self, state: ContactState, t1: float, loads1: Loads, shadow, hint=None,
                normal=None) -> tuple[ContactState, StepReport, float]:
        """One step, not subdivided; ``shadow`` the shadow lattice's take to ``loads1`` (an _Outcome) or the
        loads its memory is at, from which it then takes it (None: the shadow waits); ``normal`` the normal
        solution at ``loads1`` where the caller has it. Returns the state, the report and how far apart the
        two lattices' widest stick intervals are (/ W; the windows' own estimate where they give it, _finish)."""
        loads0 = state.loads
        mem = state.memory
        if loads1 == loads0:
            regime = Regime.SEPARATED if mem.normal is None else Regime.STICK
            new = ContactState(float(t1), loads0, state.contact_left, state.contact_right, state.contact_left,
                               state.contact_right, state.shift, state.dissipation, mem)
            return new, StepReport(regime, False, False, ""), 0.0
        if not loads1.P > 0.0:
            return *self._separate(state, t1, loads1), 0.0
        ctx, fine = self._fine(state, loads1, hint, normal)
        if isinstance(shadow, Loads):
            # its active set starts from the fine lattice's answer, coarsened (its own memory is sub-steps older)
            shadow = self._rough(state, loads1, ctx, shadow, _coarsened(fine.memory))
        return self._finish(state, t1, loads1, ctx, fine, shadow)

    def _fine(self, state: ContactState, loads1: Loads, hint=None, normal=None) -> tuple["_Context", "_Outcome"]:
        """The step's context (:meth:`_context`) and its take on the fine lattice (P1 > 0)."""
        ctx = self._context(state, loads1, normal)
        return ctx, self._take(state.memory, ctx.h, state.loads, loads1, ctx.N1, ctx.path, ctx.load, hint)

    def _context(self, state: ContactState, loads1: Loads, normal=None) -> "_Context":
        """What both lattices of a step to ``loads1`` share (P1 > 0): the normal solution there (``normal`` where
        the caller has it: the trial take's, for the last sub-step; it keeps the cell loads and end cells
        found for it), the fine cell, the edge path and the cell loads."""
        loads0 = state.loads
        mem = state.memory
        normal_changed = mem.normal is None or (loads1.P, loads1.M) != (loads0.P, loads0.M)
        if normal_changed:
            N1 = normal if normal is not None else self._normals.get((loads1.P, loads1.M))
            if N1 is None:
                # warm-started from the step's start (the loads of consecutive (sub-)steps are close)
                N1 = self.problem.solve(loads1.P, loads1.M, near=mem.normal)
                self.counters["normal_solves"] += 1
        else:
            N1 = mem.normal
        h = mem.spacing
        if not math.isfinite(h):
            h = (self.width if self.width is not None else N1.right - N1.left) / self.nodes
        path = self._path(mem.normal, N1, loads0, loads1)
        load = self._loads.get(h, (N1,))
        if load is None:
            load = self._loads.put(h, (N1,), _Load(N1, h, self._kinks, graded=self._graded_kinks))
        return _Context(N1, h, path, load, normal_changed)

    def _path(self, N0: NormalSolution | None, N1: NormalSolution, loads0: Loads, loads1: Loads):
        """The edge path of a step whose contact grows beyond ``N0`` (None otherwise)."""
        if (loads1.P, loads1.M) == (loads0.P, loads0.M) and N0 is not None:
            return None
        if N0 is not None and N1.left >= N0.left and N1.right <= N0.right:
            return None
        path = self._paths.get((loads0, loads1), (N0, N1))
        if path is None:
            parent = _on_line(self._line, loads0, loads1) if N0 is not None else None
            width = N1.right - N1.left
            cell = (self.width if self.width is not None else width) / self.nodes / width
            path = self._paths.put((loads0, loads1), (N0, N1), EdgePath(self.problem, N0, N1, loads0, loads1, parent,
                                                                        cell, lazy=True, tally=self.counters))
        return path

    def _finish(self, state: ContactState, t1: float, loads1: Loads, ctx: "_Context", fine: "_Outcome",
                rough: "_Outcome | None") -> tuple[ContactState, StepReport, float]:
        """The error estimate against the shadow lattice's take ``rough`` to the same end (None: no estimate,
        the shadow memory stays), the new state and report, and the distance of the two lattices' widest stick
        intervals (/ W; 0 without the shadow; with windows that give both outermost stick points of the lattice's
        widest interval, their own estimate, with or without the shadow).

        The estimate of the state is the distance of the two lattices' outermost
        stick points. A sub-stepped step reports the larger of it and the
        largest distance of the widest intervals over the sub-steps the shadow
        took (:meth:`step`): the edges sweep through their cells, and where
        they fall in a cell sets their error (0.1-0.25 of a cell), so the two
        lattices can agree by chance at the end (J1 at 256 nodes: error
        3.9e-4 of W, end estimate 5.7e-5); the widest intervals, not the
        outermost points, because stick islands of a cell or two at an
        advancing edge come and go between sub-steps (the outermost distance
        reached 0.24 of W in sub-steps whose end states agree to 1e-4).
        """
        mem = state.memory
        N1, h = ctx.N1, ctx.h
        W = N1.right - N1.left
        error = shear = math.nan
        spread = 0.0
        coarse = mem.coarse
        if rough is not None:
            coarse = rough.memory
            error = max(_apart(a, b) for a, b in zip(fine.stick, rough.stick)) / W
            if fine.regime == Regime.PARTIAL_SLIP:
                # the lattices can agree by chance to far less than either is placed
                error = max(error, EDGE_PLACEMENT * h / W)
            spread = max(_apart(a, b) for a, b in zip(fine.widest, rough.widest)) / W
            shear = _shear_apart(fine.memory, coarse) / (self.f * loads1.P)
        elif not self.estimate:
            coarse = None
        unresolved = 0.0
        if fine.regime != Regime.GROSS_SLIDING:
            # edges placed by a local form or only bracketed (_run_edges), and islands (S1) doubts
            unresolved = _unresolved_reach(fine.slipping, fine.memory.status, h)
            reach = max(fine.placement * h, unresolved)
            if reach > 0.0:
                error = max(error if math.isfinite(error) else 0.0, reach / W)
        windows, edges, regime = (), fine.stick, fine.regime
        if self.windows is not None and fine.regime in (Regime.PARTIAL_SLIP, Regime.STICK):
            # (the checks serve the estimate against the shadow: where it waits, there is none)
            windows, edges, own, checks = self.windows.solve(state, loads1, ctx, fine,
                                                             check=self.estimate and rough is not None)
            regime = _windowed_regime(fine, windows, edges, N1)
            if self.estimate and None not in own:
                # both outermost stick points are the windows': the estimate is theirs (each at least its
                # distance from the lattice's edge, EdgeWindows._own_error) and (S1)'s doubts, and so is the spread
                # over sub-steps (step), in place of the lattices' (their cells' placement is what the windows
                # refine); also where the stick zone is split inside (until 0.4.11 the lattice's there)
                error = spread = max(max(own), unresolved) / W
            elif (self.estimate and rough is not None and any(c is not None for c in checks)
                  and all(o is not None or c is not None for o, c in zip(own, checks))):
                # each outermost stick point is a window's or the lattice's checked by a window around it
                # (EdgeWindows._check): there, its distance from the check's edge and the check's own placement
                # together in place of the lattice's placement floor, at least the two lattices' distance on that
                # side (the check inherits the lattice's history, which that distance measures); split stick
                # zones too
                sides = [o if o is not None else max(abs(c[0] - e) + c[1], _apart(e, r))
                         for o, c, e, r in zip(own, checks, fine.stick, rough.stick)]
                error = spread = max(max(sides), unresolved) / W
            else:
                # a window's edge far from the lattice's must not look right: the estimate covers their distance
                apart = max((abs(u - v) for u, v in zip(edges, fine.stick) if math.isfinite(u - v)),
                            default=0.0) / W
                if apart > 0.0:
                    error = max(error if math.isfinite(error) else 0.0, apart)
        m = fine.memory  # (dataclasses.replace, which took 10 us of a take)
        memory = GeneralMemory(m.normal, m.spacing, m.first, m.status, m.q, m.g, m.G, m.capacity, m.shift, error,
                               coarse, windows)
        spent = fine.dissipation + sum(w.dissipation for w in windows)  # (the windows': in place of their cells')
        new = ContactState(float(t1), loads1, N1.left, N1.right, edges[0], edges[1], fine.shift,
                           state.dissipation + spent, memory)
        converged = fine.residual <= 1.0
        message = fine.message
        if not converged:
            message = "; ".join(m for m in (message, f"active set not converged (check residual {fine.residual:.3g} "
                                                      f"x tolerance)") if m)
        # the path's own outcome (the lattice's is above), where the locks take anything from it (a load change
        # of Q or sigma) and keep it (not in gross sliding: every cell's slip resets its lock)
        if (ctx.path is not None and ctx.path.dominant and regime != Regime.GROSS_SLIDING
                and (loads1.Q, loads1.sigma) != (state.loads.Q, state.loads.sigma)):
            message = "; ".join(m for m in (message, EDGE_PATH_MESSAGE.format(error=ctx.path.error)) if m)
        return new, StepReport(regime, fine.slipped, ctx.normal_changed, message, converged=converged,
                               residual=fine.residual, iterations=fine.iterations, error_estimate=error,
                               shear_error_estimate=shear), spread

    def _rough(self, state: ContactState, loads1: Loads, ctx: "_Context", shadow_from: Loads | None = None,
               hint=None) -> "_Outcome":
        """The shadow lattice's take to ``loads1`` (the end of ``ctx``) from the shadow memory ``state`` carries,
        which is at ``shadow_from`` (None: ``state``'s loads; a sub-step's shadow is taken every SHADOW_EVERY
        sub-steps), its active set starting from ``hint`` (None: its own pattern)."""
        cmem = state.memory.coarse
        if cmem is None or not math.isfinite(cmem.spacing):
            cmem = _empty(2.0 * ctx.h, None, state.shift)
        start = state.loads if shadow_from is None else shadow_from
        path = ctx.path if start == state.loads else self._path(cmem.normal, ctx.N1, start, loads1)
        return self._take(cmem, cmem.spacing, start, loads1, ctx.N1, path, ctx.load, hint, shadow=True)

    # -- one lattice ----------------------------------------------------------
    def _lattice(self, h: float, n: int) -> ToeplitzLattice:
        """The Toeplitz data of the lattice of spacing ``h`` for at least ``n`` cells.

        Sized for the reference width (``width`` / h cells) with half as much
        again for contacts wider than it, grown by half when a contact needs
        more: its Levinson table takes 4 size^2 bytes (limits.GENERAL_BYTES_PER_NODE_PAIR).
        """
        lat = self._lattices.get(h)
        if lat is None or lat.size < n:
            expected = n if self.width is None else math.ceil(self.width / h)
            size = max(n, 64, (3 * expected) // 2 if lat is None else (3 * lat.size) // 2)
            lat = self._lattices[h] = ToeplitzLattice(h, size, self.A)
        return lat

    def _take(self, mem: GeneralMemory, h: float, loads0: Loads, loads1: Loads,
              N1: NormalSolution, path: EdgePath | None, load: _Load, hint=None, shadow: bool = False) -> _Outcome:
        """The step on the lattice of spacing ``h`` whose memory is ``mem``; ``hint`` = (first, status),
        where known, the pattern the active set starts from (the memory's otherwise: the solution is
        unique, the start sets only how many iterations it takes). The ``shadow`` lattice's take leaves out
        the dissipation of the cells that leave (its dissipation is not used)."""
        A, f = self.A, self.f
        self.counters["shadow_takes" if shadow else "takes"] += 1
        first, n = _cells(N1.left, N1.right, h)
        # the cells' centres, what each carries into the step and the pattern the active set starts from
        old = mem.normal is not None
        x, status, glock, G, cap0, known, start, arrived = _carried(
            first, n, h, mem.first, *((mem.status, mem.g, mem.G, mem.capacity) if old else _NOTHING_CARRIED),
            *(hint if hint is not None else (0, _NO_HINT)))
        cap = load.capacity(first, n, h)
        lat = self._lattice(h, n)
        # the end cells carry their shear like the pressure over their supports, which reach to the contact's
        # edges (as their loads cap do)
        ends = _end_supports(N1, first, n, h)
        lat = _EndCellLattice(lat, ends, self._take_columns(N1, first, n, h, ends, x), N1)
        g0 = before = fit_of = None
        if arrived:
            found = self._arrived(mem, N1, path, x, known, h, first, lat, glock) if old else None
            if found is not None:
                g0, before, fit_of = found
            else:
                glock[~known], g0, before = self._arrivals(mem, loads0, loads1, N1, path, x, known, h)
        # the bulk term, r (stick: (T q)_i - delta = -r_i), the bounds, and r's mid-range and largest size
        sigma_term, r, qmax, r0, qmax_max, r_max = _take_inputs(glock, x, 0.25 * A * loads1.sigma, f, cap)
        gross = abs(loads1.Q) >= f * loads1.P
        if gross:
            sgn = 1 if loads1.Q > 0.0 else -1
            status = np.full(n, sgn, np.int8)
            q = sgn * qmax
            Tq = lat.matvec(q)
            # the rigid slide is indeterminate under force control: the smallest one that lets every
            # cell slip in the direction of its shear (the last cell to move has no increment, as at
            # the onset of gross sliding from partial slip); dissipation is then the least possible
            moved = Tq + r  # s = delta - moved
            delta_int = float(np.max(moved)) if sgn > 0 else float(np.min(moved))
            iterations, restarts = 0, 0
            message = GROSS_SLIDING_MESSAGE if abs(loads1.Q) > f * loads1.P * (1.0 + 1e-12) else ""
        else:
            # a constant in r only shifts delta: the common offset r0 (_take_inputs') is taken out (the locked
            # displacements carry the history's rigid slide, which may dwarf what the step changes)
            gscale = A * qmax_max * h
            floor = ROUNDING * r_max
            tolerances = _decision_tolerances(qmax_max, gscale, floor)
            fit = None
            if fit_of is not None:  # _arrived's, given r0
                fit = fit_of(r0)
            elif self.arrivals and old and g0 is not None and path is not None:
                fit = self._arrival_fit(mem, lat, h, loads1, path, x, known, g0, before, glock, r0)
            q, delta_int, status, Tq, iterations, restarts, sizes = self._active_set(
                lat, n, r - r0, qmax, loads1.Q / h, start, *tolerances, fit)
            delta_int += r0
            message = ""
            if sizes is not None:
                # the fitted sides' locks: their increments sized to the lattice (_arrival_fit)
                _, now, shape, *_ = fit
                glock = glock.copy()
                for j, size in sizes:
                    glock += size * shape[j] - now[j]
        self.counters["iterations"] += iterations
        self.counters["restarts"] += restarts
        g, s, G, runs, slipped, total, spent, cap_max, coulomb, direction, stuck, locked = _settled(
            delta_int, Tq, sigma_term, glock, status, q, qmax, cap0, cap, f, G)
        if gross:
            residual = 0.0
        else:
            residual = _verdict(coulomb, direction, stuck, h * total, loads1.Q, f * loads1.P, f * cap_max,
                                A * f * cap_max * h, ROUNDING * locked)
        dissipation = spent * h
        shift = self._shift(delta_int, total, h, lat)
        q = _frozen(q)  # (the state's, below; read-only before _leaving's compiled passes take it, as a state's q)
        if old and not shadow:
            # cells that leave the contact during the step while slipping dissipate until they leave
            dissipation += self._leaving(mem, N1, first, n, shift, x, q, h, loads1.sigma, total)
        memory = GeneralMemory(N1, h, first, _frozen(status), q, _frozen(g), _frozen(G), _frozen(cap),
                               shift)
        self._sums.put(None, (memory.q,), total)
        drives = _edge_drives(N1, loads0, loads1) if mem.normal is not None else None
        slipping = _slipping_edges(drives, loads0, loads1, f) if drives is not None else (False, False)
        drives = tuple((u / f, v) for u, v in drives) if any(slipping) else None
        placement = 0.0
        undecided = placed = (0.0, 0.0)
        if slipped == 0:
            regime, edges = Regime.STICK, (N1.left, N1.right)
            if any(slipping):
                # (S1): an edge slips, over less than its end cell (which sticks)
                *edges, placed = _run_edges_each(x, q, qmax, status, N1, h, 0, n - 1, slipping, drives)
                edges, placement = tuple(edges), float(placed.max())
                if edges != (N1.left, N1.right):
                    regime = Regime.PARTIAL_SLIP
            widest = edges
        elif slipped == n:
            regime, edges = Regime.GROSS_SLIDING, (math.nan, math.nan)
            widest = edges
        else:
            runs = list(map(tuple, runs.tolist()))
            regime = Regime.PARTIAL_SLIP
            *edges, placed = _run_edges_each(x, q, qmax, status, N1, h, runs[0][0], runs[-1][1] - 1, slipping,
                                             drives)
            edges, placement = tuple(edges), float(placed.max())
            # cells beside the edges that are as much stuck as slipping (at the bound, not slipping); each side's
            # for the windows (whose edge does not replace an undecided one: EdgeWindows._window)
            by_side = self.windows is not None and not shadow
            reaches = [_undecided_reach(x, q, qmax, s, status, N1, h, runs[0][0], runs[-1][1] - 1, slipping, drives,
                                        edges, *tolerances, sides=k) for k in (((0,), (1,)) if by_side else ((0, 1),))]
            placement = max(placement, *reaches)
            if by_side:
                undecided = tuple(reaches)
            a, b = max(runs, key=lambda r: r[1] - r[0])
            if len(runs) == 1:
                widest = edges
            else:  # the estimate covers the widest interval too (its spread over sub-steps, _finish)
                *widest, inner = _run_edges(x, q, qmax, status, N1, h, a, b - 1, slipping, drives)
                widest, placement = tuple(widest), max(placement, inner)
        kept = ((s, cap0, undecided, (float(placed[0]), float(placed[1]))) if self.windows is not None and not shadow
                else (None, None, (0.0, 0.0), (0.0, 0.0)))
        return _Outcome(memory, shift, dissipation, edges, widest, regime, slipped > 0, iterations, residual,
                        message, slipping, placement, *kept, drives)

    def _active_set(self, lat: "_EndCellLattice", n: int, r: np.ndarray, qmax: np.ndarray, total: float,
                    status: np.ndarray, qtol: float, stol: float, fit=None):
        """Primal-dual active set for min 1/2 q^T T' q + q^T r, |q| <= qmax, sum q = total (compiled:
        _toeplitz.active_set), restarted from the projected gradient's pattern when a pattern repeats;
        with ``fit`` (:meth:`_arrival_fit`), the arrivals' sizes found in the same iterations.

        Returns q, the internal shift delta (the equality's multiplier), the
        final pattern, T' q, the iterations, the restarts and [(side index, size)] of the fitted sides
        (None: none fitted).
        """
        m, spec = lat.lat._circulant(n)
        r = np.ascontiguousarray(r, dtype=float)
        side_of, now, phi, K, e, m1 = fit if fit is not None else _no_fit(n)
        iterations = restarts = 0
        while True:
            q, delta, status, Tq, it, cg, code, sizes, fitted = _toeplitz.active_set(
                lat.lat.tables, spec, m, lat.idx, lat.C, r, qmax, float(total), status, qtol, stol,
                MAX_ACTIVE_SET * (restarts + 1) - iterations, CG_TOL, CG_ITERATIONS, side_of, now, phi, K, e, m1)
            iterations += it
            self.counters["cg_iterations"] += cg
            if code == _toeplitz.CONVERGED or restarts == 3:
                found = [(j, float(sizes[j])) for j in range(m1.size) if fitted[j]]
                return (q, delta, status, Tq, iterations, restarts + (code != _toeplitz.CONVERGED),
                        found or None)
            restarts += 1
            status = _projected_gradient(lat, n, r, qmax, total, q)

    # -- arrivals ---------------------------------------------------------------
    def _arrived(self, mem, N1, path, x, known, h, first, lat, glock):
        """:meth:`_arrivals` and :meth:`_arrival_fit` in one compiled pass (:func:`_arrival_terms`, the same
        numbers) where the old contact exists and the edge path is a hermite one: sets the arrived cells'
        locks in ``glock`` and returns their start displacements, the match points' ({side: value}) and the
        fit as a function of r0 (None: nothing fitted); None where the general path must take it."""
        if path is None or path.kind not in ("hermite", "table"):
            return None
        N0, n = mem.normal, x.size
        olds, news = self._end_arguments(N0, mem.first, mem.q.size, h), self._end_arguments(N1, first, n, h)
        if olds is None or news is None:
            return None
        tab = lat.lat
        # the kernel table reaches from the old cells to the match points and over the take's cells
        span = max(first + n - 1 + ARRIVAL_MATCH - mem.first, mem.first + mem.q.size - 1 - first + ARRIVAL_MATCH)
        t = tab._kernel_to(max(span + 1, n + ARRIVAL_MATCH + 1))
        l0, l1 = path.loads0, path.loads1
        ok, locks, g0, before, has, side_of, now, phi, K, cx, bef, m1, fitted = _arrival_terms(
            x, known, first, h, self.A, N0.center, N0.left, N0.right, t, mem.shift, mem.q, mem.first,
            self._datum_factor(h, tab) * self._sum(mem.q), 0.25 * self.A * l0.sigma, *olds, END_CELL_NEAR,
            LATTICE_POINT, path.hermite_arguments(-1), path.hermite_arguments(1), _GL_T, _GL_W, l1.Q - l0.Q,
            l1.sigma - l0.sigma, self.arrivals, *news, ARRIVAL_MATCH, *ARRIVAL_SHAPE, 0.25 * self.A * l1.sigma)
        if not ok:
            return None
        glock[~known] = locks
        before = {side: float(before[s]) for s, side in enumerate((-1, 1)) if has[s]}
        if not fitted:
            return g0, before, lambda r0: None
        k = fitted
        return g0, before, lambda r0: (side_of, now[:k], phi[:k], K[:k], r0 + cx[:k] - bef[:k], m1[:k])

    def _arrivals(self, mem: GeneralMemory, loads0: Loads, loads1: Loads, N1: NormalSolution,
                  path: EdgePath | None, x: np.ndarray, known: np.ndarray, h: float):
        """Locked displacement of the cells centred at ``x`` that enter the contact during the step (those not
        ``known``; M1's: a fully stuck contact's increments, :meth:`_arrival_fit` sizes them where part of
        the contact slips), the displacement they had at its start, and that at the match point of each
        growing side ({side: value}; both None for a contact that forms in the step). The integrals run on
        to the match point (:func:`_match_points`), where the fit asks for them again."""
        A = self.A
        if path is None:
            path = EdgePath(self.problem, mem.normal, N1, loads0, loads1)
        xs = x[~known]
        out = np.empty(xs.size)
        if mem.normal is not None:
            N0 = mem.normal
            # x ascending: the cells left of the old contact's centre arrive at its left edge
            split = int(np.searchsorted(xs, N0.center))
            match = [(side, xe) for side, xe in _match_points(x, h).items()
                     if (split if side < 0 else xs.size - split)]
            # the displacement at the start of the step, from the old shear, there and at the match points
            at = np.empty(xs.size + len(match))
            at[:xs.size] = xs
            at[xs.size:] = [xe for _, xe in match]
            start = self._displacement(mem.shift, mem.x, mem.q, mem.spacing, loads0.sigma, at, mem.normal)
            g0 = start[:xs.size]
            for side, xe in match:
                edge = N0.left if side < 0 else N0.right
                part = slice(0, split) if side < 0 else slice(split, xs.size)
                out[part] = g0[part] + side * _integrate(path, np.append(xs[part], xe), edge, side, A, None)[:-1]
            return out, g0, {side: float(v) for (side, _), v in zip(match, start[xs.size:])}
        lam0 = path.lam_lo
        left, right = path.edges(np.array(lam0))
        xf = 0.5 * (float(left) + float(right))
        sig0 = loads0.sigma + lam0 * (loads1.sigma - loads0.sigma)
        gf = mem.shift + 0.25 * A * sig0 * xf
        for side in (-1, 1):
            mask = (xs < xf) if side < 0 else (xs >= xf)
            if np.any(mask):
                out[mask] = gf + side * _integrate(path, xs[mask], xf, side, A, (loads0, loads1))
        return out, None, None

    def _arrival_fit(self, mem, lat, h, loads1, path, x, known, g0, before, glock, r0):
        """What the active set needs to size the arrivals' increments to the lattice (_toeplitz.active_set),
        or None where no edge grows.

        M1's increments are those of a fully stuck contact. At a growing edge
        where part of the contact slips and some arrived cells stick, the
        locked increments become size x ARRIVAL_SHAPE's, the size such that
        the lattice's displacement ARRIVAL_MATCH cells beyond the new edge
        changes over the step by size x the shape's change there. For a given
        pattern the solution is affine in the sizes: the active set solves for
        them beside delta in each iteration, with the shape as one more column
        of its stick-set solve.

        ``g0`` and ``before`` are the arrived cells' and the match points' displacements at the step's
        start (:meth:`_arrivals`). Returns (side_of, now, phi, K, e, m1): per cell, the index of the fitted side it arrived at (-1:
        none); per side, M1's increments on its arrived cells (now) and the shape's (phi), T' at the match
        point (K: the kernel of each cell there, the end cells' shear over their supports; the lattice's
        datum, whose terms cancel against delta's), the match point's constants (e: its bulk-tension
        displacement and r0 less its displacement at the step's start) and the shape's change there (m1).
        """
        A = self.A
        n = x.size
        N0 = mem.normal
        side_of = np.full(n, -1, np.int64)
        now, phi, K, e, m1 = [], [], [], [], []
        t = lat.lat._kernel_to(n + ARRIVAL_MATCH + 1)
        first = round(x[0] / h - 0.5)
        ends = _end_supports(lat.normal, first, n, h)
        new = ~known
        # x ascending: the cells left of the old contact's centre arrive at its left edge
        split = int(np.searchsorted(x, N0.center))
        match = [(side, xe) for side, xe in _match_points(x, h).items()
                 if np.any(new[:split] if side < 0 else new[split:])]
        if not match:
            return None
        # T' at the match points: the end cells' columns at both in one pass
        columns = self._end_columns(lat.normal, first, h, ends, np.array([xe for _, xe in match]))
        at_ends = [k for k, _, _ in ends]
        start = np.zeros(n)
        start[new] = g0
        for j, (side, xe) in enumerate(match):
            arrived = new.copy()  # this side's
            if side < 0:
                arrived[split:] = False
            else:
                arrived[:split] = False
            edge = N0.left if side < 0 else N0.right
            # the shape's increments at the arrived cells and the match point (the quadrature of _arrivals)
            shaped = side * _integrate(path, np.append(x[arrived], xe), edge, side, A, None, ARRIVAL_SHAPE)
            unit = float(shaped[-1])
            if not (unit != 0.0 and math.isfinite(unit)):
                continue
            shape = np.zeros(n)
            shape[arrived] = shaped[:-1]
            cur = np.zeros(n)
            cur[arrived] = glock[arrived] - start[arrived]
            # the kernel from each cell to the match point ARRIVAL_MATCH cells beyond the first or last cell
            row = (t[ARRIVAL_MATCH:n + ARRIVAL_MATCH] if side < 0 else t[ARRIVAL_MATCH:n + ARRIVAL_MATCH][::-1]).copy()
            row[at_ends] += columns[j]
            side_of[arrived] = len(m1)
            now.append(cur)
            phi.append(shape)
            K.append(row)
            e.append(r0 + 0.25 * A * loads1.sigma * xe - before[side])
            m1.append(unit)
        if not m1:
            return None
        return side_of, np.array(now), np.array(phi), np.array(K), np.array(e), np.array(m1)

    def _leaving(self, mem, N1, first, n, shift, x, q, h, sigma1, total) -> float:
        """Dissipation of the cells that leave the contact during the step while slipping: the end state does
        not hold them, and until 0.3.5 their slip until they left was lost (tests/test_general.py,
        test_a_receding_contact_keeps_the_dissipation_of_the_cells_that_leave: against the exact method,
        0.56 % / 3.3 % of the history's dissipation missing at 256 nodes, Hertz / punch, with the default
        sub-steps, and 9.4 % / 10.5 % of it in the receding step taken whole; now 0.02 % / 0.04 %).

        Each slipped lam (g1 - g_start) until its centre left (lam the fraction of the step at which the
        receding edge passed it, linear in the edge's travel; g1 the displacement at its centre at the end,
        from the end's shear; its slip rate taken as steady), under LEAVING_PRESSURE times its capacity at
        the start; none where that slip would oppose its shear. ``total`` is sum q (the take's, numpy's).
        """
        lo, hi = mem.first, mem.first + mem.q.size
        if lo >= first and hi <= first + n:  # every old cell is still in contact
            return 0.0
        # the old cells on the take's lattice (the memory a take starts from is its own lattice's)
        lat = self._lattice(h, n)
        N0 = mem.normal
        edges = (N0.left, N0.right, N0.center, N1.left, N1.right)
        bound = self.f * LEAVING_PRESSURE
        done, xs, at, terms = _leaving_terms(
            mem.first, mem.status, mem.g, mem.capacity, first, n, h, *edges, bound,
            lat._kernel_to(max(hi - first, first + n - lo)), shift, q, self._datum_factor(h, lat) * total,
            0.25 * self.A * sigma1, self.A, *self._end_arguments(N1, first, n, h), END_CELL_NEAR, LATTICE_POINT)
        if not done:  # a point inside an end cell's support: the general displacement
            g1 = self._displacement(shift, x, q, h, sigma1, xs, N1)
            terms = _leaving_slip(xs, at, g1, mem.status, mem.g, mem.capacity, *edges, bound)
        return float(np.sum(terms)) * mem.spacing

    def _sum(self, q: np.ndarray) -> float:
        """float(np.sum(q)) of a state's shear, kept from the take that found it (its _settled's)."""
        total = self._sums.get(None, (q,))
        return float(np.sum(q)) if total is None else total

    def _shift(self, delta_int: float, total: float, h: float, lat: ToeplitzLattice) -> float:
        """The rigid shift in the package's datum of the lattice's internal one, ``total`` the sum of the
        cells' shear (Q = h total): delta_l = delta_int + (A/pi) Q ln(l / l_int)."""
        return delta_int + (self.A / math.pi) * h * total * math.log(self.datum / lat.datum)

    def _displacement(self, shift, xc, q, spacing, sigma, xs, normal) -> np.ndarray:
        """Relative tangential displacement at ``xs`` of the shear ``q`` on the cells centred at ``xc``
        (package datum, ``shift`` the rigid shift) under the bulk tension ``sigma``: T1. ``normal`` is the
        contact of the state whose cells ``xc`` are (all of them): its end cells carry their shear like
        the pressure over their supports (:func:`_end_supports`). ``q`` of shape (n,) or (n, k). At points of
        the state's lattice (every use in a step: arrived, leaving and match points) one compiled pass,
        :func:`_displaced`; elsewhere the kernel's products and the end cells' columns."""
        xs = np.ascontiguousarray(xs, dtype=float)
        first = int(round(xc[0] / spacing - 0.5)) if xc.size else 0
        ends = _end_supports(normal, first, xc.size, spacing)
        lat = self._lattices.get(spacing)
        if np.ndim(q) == 1 and lat is not None and ends:
            # the usual case (the cells of a state, points on its lattice) in one compiled pass
            span, ri, ci = _lattice_indices(xs, np.ascontiguousarray(xc, dtype=float), spacing, LATTICE_POINT)
            if span:
                out, done = _displaced(shift, lat._kernel_to(span), ri, ci, np.ascontiguousarray(q, dtype=float),
                                       self._datum_factor(spacing, lat) * float(np.sum(q)), 0.25 * self.A * sigma,
                                       xs, -(self.A / math.pi), *self._end_arguments(normal, first, xc.size, spacing),
                                       END_CELL_NEAR, LATTICE_POINT)
                if done:
                    return out
        bulk = 0.25 * self.A * sigma * xs
        out = shift - self._products(xs, xc, spacing, q) + (bulk[:, None] if np.ndim(q) == 2 else bulk)
        if ends:
            C = self._end_columns(normal, first, spacing, ends, xs)
            out = out - C @ q[[k for k, _, _ in ends]]
        return out

    def _datum_factor(self, h: float, lat: ToeplitzLattice) -> float:
        """(A/pi) h ln(l / l_int): what a unit of the cells' summed shear adds to the displacement in the
        package's datum l over the lattice's internal one (its kernel table's)."""
        return (self.A / math.pi) * h * math.log(self.datum / lat.datum)

    def _end_cell(self, normal, first: int, k: int, a: float, b: float, h: float) -> "_EndCell":
        """The end cell k (of a state whose cells start at lattice index ``first``) with support [a, b], kept."""
        cell = self._end_cells.get((a, b, first + k, h), (normal,))
        if cell is None:
            cell = self._end_cells.put((a, b, first + k, h), (normal,),
                                       _EndCell(normal, a, b, (first + k) * h, h, self._kinks))
        return cell

    def _end_arguments(self, normal, first: int, n: int, h: float):
        """What the compiled passes (:func:`_displaced` and those that call it) take of the end cells of a state
        of n cells from lattice index ``first``: their indices among its cells and the first and last cell's
        :meth:`_EndCell.kernel_arguments` (the same cell for a contact of one cell); None out of contact."""
        got = self._end_args.get((first, n, h), (normal,))
        if got is None:  # a take's are asked again by its arrivals and leaving cells, and by the next take
            ends = _end_supports(normal, first, n, h)
            if not ends:
                return None
            cells = [self._end_cell(normal, first, k, a, b, h) for k, a, b in ends]
            got = self._end_args.put((first, n, h), (normal,), (np.array([k for k, _, _ in ends], np.int64),
                                                                cells[0].kernel_arguments(),
                                                                cells[-1].kernel_arguments()))
        return got

    def _end_columns(self, normal, first, h, ends, xs) -> np.ndarray:
        """(T' - T) at the points ``xs`` for the end cells ``ends`` [(k, a, b)] of a state whose cells start
        at lattice index ``first``: minus the displacement of a unit shear (force h) spread like the
        pressure of ``normal`` over [a, b], less that of the same force spread over the cell (:class:`_EndCell`,
        kept for the recent states). Shape (xs.size, len(ends)); the datum cancels. Two new end cells
        (a take's, at a new contact) are set up and evaluated in one compiled call (:func:`_end_pair`)."""
        if len(ends) == 2 and all(self._end_cells.get((a, b, first + k, h), (normal,)) is None for k, a, b in ends):
            cells = [_EndCell(normal, a, b, (first + k) * h, h, self._kinks, build=False) for k, a, b in ends]
            one, two = cells
            parts, out, rests = _end_pair(one.cuts, one.x0, one.inside, one.lo, one.a, one.b, two.cuts, two.x0,
                                          two.inside, two.lo, two.a, two.b, normal.center, normal.half_width, _EC_S,
                                          _EC_DS, normal.pressure_arguments(), h, END_CELL_TERMS,
                                          np.ascontiguousarray(xs, dtype=float), END_CELL_NEAR, LATTICE_POINT,
                                          -(self.A / math.pi))
            for c, ((k, a, b), cell) in enumerate(zip(ends, cells)):
                cell.built(parts[c])
                self._end_cells.put((a, b, first + k, h), (normal,), cell)
                if rests[c].size:  # points inside its support other than its centre
                    out[rests[c], c] = -(self.A / math.pi) * cell._inside(xs[rests[c]])
            return out
        out = np.empty((xs.size, len(ends)))
        for c, (k, a, b) in enumerate(ends):
            out[:, c] = -(self.A / math.pi) * self._end_cell(normal, first, k, a, b, h).potential(xs)
        return out

    def _take_columns(self, normal, first, n, h, ends, x) -> np.ndarray:
        """:meth:`_end_columns` at a take's own cell centres ``x`` (read only), kept per contact and cells
        (LOADS_KEPT): the fine and shadow takes of a periodic history's phase recur every cycle."""
        columns = self._columns.get((first, n, h), (normal,))
        if columns is None:
            columns = self._end_columns(normal, first, h, ends, x)
            columns.flags.writeable = False
            self._columns.put((first, n, h), (normal,), columns)
        return columns

    def _products(self, xs, xc, spacing, q) -> np.ndarray:
        """sum_j t(xs_i - xc_j) q_j in the package datum, ``q`` of shape (n,) or (n, k).

        Where ``xs`` and ``xc`` are cell centres of a lattice already built (every use: arrived and
        leaving cells, the arrivals' match points a whole number of cells beyond the contact), the kernel
        comes from its table (no logarithms; 0.3.5 formed the rows of T by :func:`kernel`, 9 % of a
        random history's time at 1024 nodes, 16 % at 4096); elsewhere from :func:`kernel`.
        """
        lat = self._lattices.get(spacing)
        span, ri, ci = (0, None, None) if lat is None else _lattice_indices(
            np.ascontiguousarray(xs, dtype=float), np.ascontiguousarray(xc, dtype=float), spacing, LATTICE_POINT)
        if span == 0:
            return kernel(xs[:, None] - xc[None, :], spacing, self.datum, self.A) @ q
        q2 = np.asarray(q, dtype=float)
        q2 = q2[:, None] if q2.ndim == 1 else np.ascontiguousarray(q2)
        out = table_products(lat._kernel_to(span), ri, ci, q2)
        # the table's datum is the lattice's: t_l = t_int + (A/pi) h ln(l / l_int)
        out += self._datum_factor(spacing, lat) * q2.sum(axis=0)[None, :]
        return out[:, 0] if np.ndim(q) == 1 else out

    def _separate(self, state, t1, loads1):
        """All memory lost; the shift keeps g at the old contact centre."""
        mem = state.memory
        shift = state.shift
        if mem.normal is not None:
            c = mem.normal.center
            shift = float(np.interp(c, mem.x, mem.g)) - 0.25 * self.A * state.loads.sigma * c
        nan = math.nan
        message = f"{SEPARATED_PREFIX}: shear force Q = {loads1.Q:g} N/m not carried" if loads1.Q != 0.0 else ""
        coarse = None if mem.coarse is None else _empty(mem.coarse.spacing, None, shift)
        new = ContactState(float(t1), loads1, nan, nan, nan, nan, shift, state.dissipation,
                           _empty(mem.spacing, coarse, shift))
        return new, StepReport(Regime.SEPARATED, False, mem.normal is not None, message)

    # -- the step contract's queries ------------------------------------------------
    def stick_intervals(self, state: ContactState) -> int:
        """Number of stick intervals (runs of stuck cells)."""
        mem = state.memory
        if mem.normal is None:
            return 0
        return len(_runs(mem.status == 0))

    def stick_zones(self, state: ContactState) -> list[tuple[float, float]]:
        """The stick intervals of the state, left to right, as (left, right) [m] within their cells; an
        interval that reaches an end cell ends at the state's stick edge there (the contact edge, or a
        slip zone narrower than the end cell placed inside it where the step's (S1) says the edge slips)."""
        mem = state.memory
        if mem.normal is None:
            return []
        runs = _runs(mem.status == 0)
        if not runs:
            return []
        qmax = self.f * mem.capacity
        zones = [_run_edges(mem.x, mem.q, qmax, mem.status, mem.normal, mem.spacing, a, b - 1)[:2] for a, b in runs]
        if runs[0][0] == 0:
            zones[0] = (state.stick_left, zones[0][1])
        if runs[-1][1] == mem.q.size:
            zones[-1] = (zones[-1][0], state.stick_right)
        return zones

    def station_states(self, state: ContactState, x: np.ndarray, q: np.ndarray) -> np.ndarray:
        """Out of contact / stick / forward / backward slip at surface points, from the cells (the windows'
        fine cells where the state has them)."""
        mem = state.memory
        x = np.asarray(x, dtype=float)
        codes = np.full(x.shape, OUT_OF_CONTACT, np.int8)
        if mem.normal is None:
            return codes
        inside = (x >= mem.normal.left) & (x <= mem.normal.right)
        j = np.clip(np.floor(x / mem.spacing).astype(np.int64) - mem.first, 0, mem.q.size - 1)
        st = mem.status[j]
        for w in mem.windows:  # the fine windows' own, on their cells
            on, k = w.at(x)
            st = np.where(on, w.status[k], st)
        codes[inside & (st == 0)] = STICK
        codes[inside & (st > 0)] = FORWARD_SLIP
        codes[inside & (st < 0)] = BACKWARD_SLIP
        return codes

    def state_difference(self, a: ContactState, b: ContactState) -> float:
        """How far apart two states are, relative to :data:`SAME_STATE_TOL` (inf: different cells)."""
        ma, mb = a.memory, b.memory
        if (ma.normal is None) != (mb.normal is None):
            return math.inf
        if ma.normal is None:
            return 0.0
        if ma.first != mb.first or ma.q.size != mb.q.size or ma.spacing != mb.spacing:
            return math.inf
        qs = self.f * max(float(ma.capacity.max()), float(mb.capacity.max()))
        dq = float(np.max(np.abs(ma.q - mb.q))) / qs
        if ma.windows or mb.windows:
            # the windows on the same cells; not their shear: they are the lattice's output (one-way coupled),
            # a steady lattice drives them to a steady state only slowly (the dovetail: their shear creeps by
            # 4e-6 of f max p a cycle, their edges by 8e-6 of a cell), and the cycle check (cycles.py) holds
            # their edges, which the windows are for, to 1e-3 of a cell at every step of the cycle
            if not same_windows(ma.windows, mb.windows):
                return math.inf
        # displacement scale: what f max p over the contact width moves a surface point by
        gs = self.A * qs * (ma.normal.right - ma.normal.left)
        dg = float(np.max(np.abs((ma.g - mb.g) - (a.shift - b.shift)))) / gs
        return max(dq, dg) / SAME_STATE_TOL

    def same_state(self, a: ContactState, b: ContactState) -> bool:
        """Whether the two states agree to :data:`SAME_STATE_TOL` on the same cells."""
        return self.state_difference(a, b) <= 1.0

    def cycle_tolerance(self, state: ContactState) -> float:
        """Stick edges of a steady cycle repeat to rounding: a thousandth of a cell [m]."""
        return 1e-3 * state.memory.spacing

    # -- output -------------------------------------------------------------------
    def tractions(self, memory: GeneralMemory, x) -> tuple[np.ndarray, np.ndarray]:
        """Pressure p(x) and shear q(x) [Pa]: q = (q_j / cap_j) p within cell j (so |q| <= f p), within the fine
        cells of the state's windows (``edge_windows``) where it has them."""
        x = np.asarray(x, dtype=float)
        if memory.normal is None:
            return np.zeros(x.shape), np.zeros(x.shape)
        p = memory.normal.pressure(x)
        j = np.clip(np.floor(x / memory.spacing).astype(np.int64) - memory.first, 0, memory.q.size - 1)
        with np.errstate(divide="ignore", invalid="ignore"):
            chi = np.where(memory.capacity > 0.0, memory.q / memory.capacity, 0.0)[j]
            for w in memory.windows:  # the fine windows' own shear on their cells (the force they carry is the
                on, k = w.at(x)       # lattice's there)
                chi = np.where(on, np.where(w.capacity > 0.0, w.q / w.capacity, 0.0)[k], chi)
        return p, chi * p

    def shear_force(self, memory: GeneralMemory) -> float:
        """int q dx of the state [N/m]."""
        if memory.normal is None:
            return 0.0
        return memory.spacing * float(np.sum(memory.q))

    def slip(self, memory: GeneralMemory) -> np.ndarray:
        """Slip accumulated at the stations since each entered contact [m]; NaN outside contact."""
        if self.stations is None:
            raise ValueError("slip is tracked only when the solver is built with stations")
        out = np.full(self.stations.shape, np.nan)
        if memory.normal is None:
            return out
        inside = (self.stations >= memory.normal.left) & (self.stations <= memory.normal.right)
        x, G = memory.x, memory.G
        if memory.windows:  # the windows' fine cells in place of the lattice's they cover
            keep = np.ones(x.size, bool)
            for w in memory.windows:
                keep[w.lo:w.hi] = False
            parts = [(x[keep], G[keep])] + [((w.first + 0.5 + np.arange(w.q.size)) * w.spacing, w.G)
                                            for w in memory.windows]
            x = np.concatenate([p[0] for p in parts])
            order = np.argsort(x, kind="stable")
            x, G = x[order], np.concatenate([p[1] for p in parts])[order]
        out[inside] = np.interp(self.stations[inside], x, G)
        return out


# ---------------------------------------------------------------------------
def _empty(spacing: float, coarse, shift: float) -> GeneralMemory:
    e = _frozen(np.zeros(0))
    return GeneralMemory(None, spacing, 0, _frozen(np.zeros(0, np.int8)), e, e, e, e, shift, math.nan, coarse)


def _cells(L: float, R: float, h: float) -> tuple[int, int]:
    """First lattice index and number of cells whose centres lie inside (L, R) (at least one)."""
    j0 = math.floor(L / h - 0.5) + 1
    j1 = math.ceil(R / h - 0.5) - 1
    if j1 < j0:
        j0 = j1 = math.floor(0.5 * (L + R) / h)
    return j0, j1 - j0 + 1


class _Load:
    """The load int_L^b p of the contact of ``N`` at every boundary b = k h of the lattice (and its ends).

    In closed form (``NormalSolution.load_to``, one evaluation per boundary)
    when its rounding, eps times the size of the terms it sums, is at most
    LOAD_ROUNDING of the mean load of a cell; otherwise (a lightly loaded punch,
    whose pressure is a small difference of large terms: at 1e-2 P0 and 1024
    cells) by quadrature, which loses only what p itself does.

    Quadrature: in x = c - d cos(theta) the integrand p d sin(theta) is smooth up to the
    edges (p vanishes like a square root there): Gauss-Legendre in theta on
    each interval. Where h' has a kink inside the contact (the ends of a punch
    flat: p has an x ln x kink there) the intervals are also cut at the kink and
    graded towards it (KINK_GRADING levels of ratio 4): uncut, the cell holding
    a flat end had its capacity off by 8e-5 .. 6e-2 of h max p at P0 .. 1e-4 P0
    (punch, 128 nodes), which showed as int q - Q up to 1e-4 f P. The shadow
    lattice (spacing 2h) reads its boundaries from the same table.
    """

    def __init__(self, N: NormalSolution, h: float, kinks: np.ndarray = np.zeros(0), graded: bool = True):
        self.N, self.h = N, h
        self.k0 = math.ceil(N.left / h)
        # the lattice points inside the contact, the closed form there and the size of its terms, which varies
        # smoothly along the contact: LOAD_SAMPLES samples find its largest
        limit = LOAD_ROUNDING * N.P * h / (N.right - N.left)  # the rounding the closed form may have
        inner, cum, size = _closed_form_loads(N.left, N.right, h, self.k0, math.floor(N.right / h), N.P,
                                              *N.pressure_arguments(), limit)
        self.k0 = round(inner[0] / h) if inner.size else self.k0
        self.inner = inner.size
        self.closed_form = cum.size > 0  # (_closed_form_loads leaves the loads out where EPS size > limit)
        if self.closed_form:
            self.cum = cum
            return
        self.cum = _quadrature_loads(N, N.left, N.right, inner, kinks, graded, h)

    def capacity(self, first: int, n: int, spacing: float) -> np.ndarray:
        """(1/spacing) int p over each of the n cells from ``first``, the end cells extended to the edges
        (normalised so that spacing sum = P: the quadrature's own ~1e-10 would show in gross sliding)."""
        return _cell_loads(self.cum, self.k0, self.inner, first, n, round(spacing / self.h), spacing, self.N.P)


def _quadrature_loads(N: NormalSolution, xa: float, xb: float, inner: np.ndarray, kinks: np.ndarray, graded: bool,
                      h: float) -> np.ndarray:
    """int p from ``xa`` to each of ``xa`` (0), ``inner`` (increasing, strictly between) and ``xb``, by _Load's
    quadrature (its notes): Gauss-Legendre in theta on the intervals between these points and the kinks of h'
    inside the contact, graded towards the kinks (and, where ``graded``, towards the contact edges) on the scale
    of min(``h``, d), KINK_GAUSS points beside them. _Load takes it over the contact at its lattice points, the
    edge windows (solvers._windows) over theirs."""
    L, R, c, d = N.left, N.right, N.center, N.half_width
    kinks = kinks[(kinks > L) & (kinks < R)]
    extra = [kinks]
    if graded and kinks.size:
        # graded towards the kinks and towards the contact edges, where p changes on the scale of the
        # distance between edge and kink (a - w of a lightly loaded punch) rather than of the cell
        step = min(h, d) * 0.25 ** np.arange(1, KINK_GRADING + 1)
        extra += [kinks[:, None] - step[None, :], kinks[:, None] + step[None, :], L + step, R - step]
    extra = np.concatenate([e.ravel() for e in extra])
    extra = extra[(extra > xa) & (extra < xb)]
    pts = np.unique(np.concatenate((inner, extra)))
    bounds = np.concatenate(([xa], pts, [xb]))
    th = np.arccos(np.clip((c - bounds) / d, -1.0, 1.0))
    near = np.zeros(bounds.size - 1, bool)
    if extra.size:
        # the intervals next to a kink (and its grading): p is x ln x there, KINK_GAUSS points
        at = np.searchsorted(bounds, extra)  # extra's places among the bounds (all of them are there)
        near[at - 1] = near[np.minimum(at, bounds.size - 2)] = True
        if xa == L:
            near[:2] = True
        if xb == R:
            near[-2:] = True
    part = _interval_loads(th[:-1], np.diff(th), near, c, d, _GL_T, _GL_W, _KINK_T, _KINK_W, _FAR_T, _FAR_W,
                           FAR_SPANS, N.pressure_arguments())
    cum = np.concatenate(([0.0], np.cumsum(part)))  # at bounds
    return cum[np.concatenate(([0], np.searchsorted(pts, inner) + 1, [bounds.size - 1]))]


@numba.njit(cache=True)
def _interval_loads(lo, span, near, c, d, t, w, tk, wk, tf, wf, far, pressure):  # pragma: no cover - compiled
    """int p over each interval [theta_i, theta_i + span_i] of x = c - d cos(theta) (_Load's quadrature): p d
    sin(theta) at the Gauss-Legendre points ``t`` (weights ``w``) of the interval, those ``near`` a kink at
    ``tk`` (``wk``), those at least ``far`` spans from every knot of the pressure (its x ln x points: p d
    sin(theta) is analytic elsewhere, the square roots at the edges taken out by theta) at ``tf`` (``wf``);
    ``pressure`` is _geometry_kernels._pressure_at's arguments. The pressure in one call over every point
    (until 607df68 numpy's arrays of every interval at both rules: 0.9 ms a contact of 2048 cells, a quarter
    of the rounded punch's step on the random histories there; 0.4 ms with this and the far rule)."""
    m = lo.size
    x0, half, knots = pressure[0], pressure[1], pressure[4]
    marks = np.empty(knots.size)  # the knots inside the contact, in theta
    nk = 0
    for k in range(knots.size):
        if x0 - half < knots[k] < x0 + half:
            marks[nk] = math.acos(min(max((c - knots[k]) / d, -1.0), 1.0))
            nk += 1
    rule = np.empty(m, np.int64)  # 0: t, 1: tk, 2: tf
    count = 0
    for i in range(m):
        if near[i]:
            rule[i] = 1
        else:
            rule[i] = 2
            for k in range(nk):
                if max(marks[k] - (lo[i] + span[i]), lo[i] - marks[k], 0.0) < far * span[i]:
                    rule[i] = 0
                    break
        count += (t.size, tk.size, tf.size)[rule[i]]
    xs = np.empty(count)
    ds = np.empty(count)
    k = 0
    for i in range(m):
        nodes = (t, tk, tf)[rule[i]]
        for j in range(nodes.size):
            th = lo[i] + span[i] * nodes[j]
            xs[k] = c - d * math.cos(th)
            ds[k] = d * math.sin(th)
            k += 1
    p = _pressure_at(xs, *pressure)
    out = np.empty(m)
    k = 0
    for i in range(m):
        weights = (w, wk, wf)[rule[i]]
        total = 0.0
        for j in range(weights.size):
            total += p[k] * ds[k] * weights[j]
            k += 1
        out[i] = total * span[i]
    return out


@numba.njit(cache=True)
def _lattice_indices(xs, xc, spacing, tol):  # pragma: no cover - compiled
    """The lattice indices of the points ``xs`` and ``xc`` (centres x = (i + 1/2) spacing, each within ``tol``
    of a cell of one) and the span of all of them in cells; span 0 where one is not a lattice point or either
    is empty (GeneralSolver._products then forms its kernel)."""
    ri = np.empty(xs.size, np.int64)
    ci = np.empty(xc.size, np.int64)
    if xs.size == 0 or xc.size == 0:
        return 0, ri, ci
    lo = hi = 0
    for k in range(xs.size + xc.size):
        v = (xs[k] if k < xs.size else xc[k - xs.size]) / spacing - 0.5
        r = np.rint(v)
        if not abs(v - r) <= tol:
            return 0, ri, ci
        i = int(r)
        if k < xs.size:
            ri[k] = i
        else:
            ci[k - xs.size] = i
        if k == 0 or i < lo:
            lo = i
        if k == 0 or i > hi:
            hi = i
    return hi - lo + 1, ri, ci


@numba.njit(cache=True)
def _closed_form_loads(left, right, h, k0, k1, P, x0, d, c0, c1, knots, jumps, piA, limit):  # pragma: no cover
    """_Load's closed form in one call: the lattice points k h (k0 <= k <= k1) strictly inside the contact
    [left, right], int p from its left edge to the left edge, each of them and the right edge (0, ..., P:
    NormalSolution.load_to; ``x0`` .. ``piA`` the compiled pressure's arguments) and the largest size of
    that sum's terms at LOAD_SAMPLES points from edge to edge (np.linspace's); the loads are left out (an
    empty array) where EPS times that size, the closed form's rounding, exceeds ``limit``: the caller then
    takes the quadrature (_Load, the same test)."""
    samples = np.empty(LOAD_SAMPLES)
    step = (right - left) / (LOAD_SAMPLES - 1)
    for i in range(LOAD_SAMPLES - 1):
        samples[i] = i * step + left
    samples[LOAD_SAMPLES - 1] = right
    count = 0
    for k in range(k0, k1 + 1):
        if left < h * k < right:
            count += 1
    inner = np.empty(count)
    c = 0
    for k in range(k0, k1 + 1):
        v = h * k
        if left < v < right:
            inner[c] = v
            c += 1
    scale = d / piA
    _, size = _load_to_terms(samples, x0, d, c0, c1, knots, jumps, True)
    largest = -np.inf
    for i in range(size.size):
        largest = max(largest, size[i] * scale)
    if not EPS * largest <= limit:
        return inner, np.empty(0), largest
    total, _ = _load_to_terms(inner, x0, d, c0, c1, knots, jumps, False)
    cum = np.empty(total.size + 2)
    cum[0] = 0.0
    for i in range(total.size):
        cum[i + 1] = total[i] * scale
    cum[total.size + 1] = P
    return inner, cum, largest


@numba.njit(cache=True)
def _fine_cell_loads(left, right, h, j0, j1, P, x0, d, c0, c1, knots, jumps, piA, limit, at_left,
                     at_right):  # pragma: no cover - compiled
    """(1/h) int p over the cells j0 .. j1 of spacing h (boundaries k h), the first reaching to the left contact
    edge where ``at_left`` and the last to the right one where ``at_right`` (_windows.EdgeWindows._loads): the
    differences of :func:`_closed_form_loads`' loads at their boundaries; empty where it rounds beyond
    ``limit`` (the caller's quadrature then)."""
    _, cum, _ = _closed_form_loads(left, right, h, j0, j1 + 1, P, x0, d, c0, c1, knots, jumps, piA, limit)
    if cum.size == 0:
        return cum
    n = j1 - j0 + 2
    F = np.full(n, np.nan)
    c = 1
    for t in range(n):
        v = h * (j0 + t)  # (the closed form's own test of which points are inside)
        if left < v < right:
            F[t] = cum[c]
            c += 1
    if at_left:
        F[0] = 0.0
    if at_right:
        F[n - 1] = P
    out = np.empty(n - 1)
    for t in range(n - 1):
        out[t] = (F[t + 1] - F[t]) / h
    return out


# read-only as a state's arrays are: numba compiles _carried once for both (a read-only array is a type of its own)
_NOTHING_CARRIED = tuple(_frozen(a) for a in (np.zeros(0, np.int8), np.zeros(0), np.zeros(0), np.zeros(0)))
_NO_HINT = np.zeros(0, np.int8)


@numba.njit(cache=True)
def _carried(first, n, h, first0, status0, g0, G0, cap0, hint_first, hint):  # pragma: no cover - compiled
    """What the n cells from lattice index ``first`` (spacing ``h``) carry into a take from the memory whose
    cells start at ``first0`` (its status, locked displacements, accumulated slip and capacities; empty: out
    of contact): their centres (GeneralMemory.x's), status, locks (not set where not carried), slip,
    capacity at the start, which cells are carried, the start pattern (the status, overwritten by ``hint``
    from ``hint_first`` where it has cells) and whether any cell arrives."""
    x = np.empty(n)
    for i in range(n):
        x[i] = (first + 0.5 + i) * h
    status = np.zeros(n, np.int8)
    glock = np.empty(n)
    G = np.zeros(n)
    cap = np.zeros(n)
    known = np.zeros(n, np.bool_)
    lo, hi = max(first, first0), min(first + n, first0 + status0.size)
    for j in range(lo, hi):
        i, k = j - first, j - first0
        status[i] = status0[k]
        glock[i] = g0[k]
        G[i] = G0[k]
        cap[i] = cap0[k]
        known[i] = True
    start = status.copy()
    for j in range(max(first, hint_first), min(first + n, hint_first + hint.size)):
        start[j - first] = hint[j - hint_first]
    return x, status, glock, G, cap, known, start, hi - lo < n


@numba.njit(cache=True)
def _cell_loads(cum, k0, inner, first, n, m, spacing, P):  # pragma: no cover - compiled
    """_Load.capacity: (1/spacing) int p over each of the n cells from ``first`` (cells of m table cells), from
    the table's cumulative loads ``cum`` (at the contact's left edge, its ``inner`` lattice points from k0 and
    its right edge; the end cells reach to the edges), scaled so that spacing times their (numpy) sum is
    ``P``."""
    cap = np.empty(n)
    last = cum.size - 1
    lo = 0.0
    for j in range(n):
        if j < n - 1:
            i = (first + 1 + j) * m - k0 + 1  # the cell's right boundary among the table's points
            hi = cum[min(max(i, 0), inner + 1)]
        else:
            hi = cum[last]
        cap[j] = (hi - lo) / spacing
        lo = hi
    total = pairwise_sum(cap, 0, n) * spacing
    if total > 0.0:
        scale = P / total
        for j in range(n):
            cap[j] *= scale
    return cap


def _integrate(path: EdgePath, xs: np.ndarray, edge: float, side: int, A: float, formation,
               change=None) -> np.ndarray:
    """int between ``edge`` and each of ``xs`` (outward on ``side``) of the arrival strain of the load change
    ``change`` (dQ, dsigma; the path's own by default).

    Without ``formation``: the stuck increments only (their strain at the
    start is in g_0). With ``formation`` = (loads0, loads1): the whole strain
    on arrival, A sigma / 4 where the contact forms (fraction ``path.lam_lo``)
    plus the increments (which carry the rest of the bulk term, A sigma' / 4 in
    d(Delta-eps)/dlam: adding A sigma(lam_x) / 4 counted it twice).

    The integrals per unit Q' and sigma' (linear in the two) are kept on ``path``: M1's increments and the
    arrivals' shape (a unit shear force) at the same points come from one quadrature (GeneralSolver._arrivals
    and _arrival_fit ask for the same points).
    """
    key = (xs.tobytes(), edge, side, A)
    parts = path.integrals.get(key)
    if parts is None:
        order = np.argsort(side * xs)
        xsorted = xs[order]
        parts = np.empty((xs.size, 3))
        if path.kind in ("hermite", "table") and xs.size:
            parts[order] = hermite_integrals(np.ascontiguousarray(xsorted), edge, side, A,
                                             *path.hermite_arguments(side), _GL_T, _GL_W)
        else:
            ends = np.concatenate(([edge], xsorted))
            a, b = ends[:-1], ends[1:]
            pts = a[:, None] + (b - a)[:, None] * _GL_T[None, :]
            inc = arrival_strain_parts(path, pts.ravel(), side, A)
            seg = np.einsum("ijc,j->ic", inc.reshape(pts.shape + (2,)), _GL_W) * np.abs(b - a)[:, None]
            parts[order, :2] = np.cumsum(seg, axis=0)
            parts[order, 2] = np.cumsum(np.abs(b - a))  # the distance from the edge, for a constant strain
        parts.flags.writeable = False
        path.integrals[key] = parts
    l0, l1 = path.loads0, path.loads1
    dQ, dS = (l1.Q - l0.Q, l1.sigma - l0.sigma) if change is None else change
    out = dQ * parts[:, 0] + dS * parts[:, 1]
    if formation is not None:
        l0, l1 = formation
        out = out + 0.25 * A * (l0.sigma + path.lam_lo * (l1.sigma - l0.sigma)) * parts[:, 2]
    return out


def _on_line(line: tuple[EdgePath | None, dict[Loads, float]] | None, loads0: Loads,
             loads1: Loads) -> tuple[EdgePath, float, float] | None:
    """(path, a, b) where the straight step from ``loads0`` to ``loads1`` is the part [a, b] of the step whose
    edge path is ``path``: ``line`` = (path, the fraction of the step at each of its sub-steps' loads, as
    GeneralSolver._sub_steps made them), else None."""
    # (_kind, not kind: a lazy path is verified when its edges are used)
    if line is None or line[0] is None or line[0]._kind not in ("hermite", "table"):
        return None
    path, fractions = line
    a, b = fractions.get(loads0), fractions.get(loads1)
    return (path, a, b) if a is not None and b is not None and a < b else None


def _toward(now: GeneralMemory, end, fraction: float):
    """(first, status) over the cells of ``end`` = (first, status) on ``now``'s lattice: on the cells ``now``
    holds too, its pattern with ``fraction`` of the way to ``end``'s taken; on the cells that arrive,
    ``end``'s (None when ``end`` is None or the two share no cell). Each run of cells whose status differs
    lies between a boundary of ``now`` and its place in ``end``; it flips from the side where ``now``
    already has the run's end status, the nearest cells first (no side: it is left as it is)."""
    if now.normal is None or end is None:
        return None
    first, e = end
    lo, hi = max(now.first, first), min(now.first + now.q.size, first + e.size)
    if hi <= lo:
        return None
    return first, _toward_kernel(now.first, now.status, first, e, fraction, lo, hi)


@numba.njit(cache=True)
def _toward_kernel(first0, status0, first, e, fraction, lo, hi):  # pragma: no cover - compiled
    """:func:`_toward`'s pattern: ``e`` (cells from ``first``) with the cells lo..hi - 1 both hold taken from
    ``status0`` (cells from ``first0``), then each run that differs from ``e`` moved ``fraction`` of the way
    (rounded half to even, as Python's round)."""
    s = e.copy()  # cells that arrive: as at the end
    for j in range(lo, hi):
        s[j - first] = status0[j - first0]
    runs = _run_bounds(s != e)
    for r in range(runs.shape[0]):
        a, b = runs[r, 0], runs[r, 1]
        count = int(np.rint(fraction * (b - a)))
        if count == 0:
            continue
        if a > 0 and s[a - 1] == e[a]:
            for j in range(a, a + count):
                s[j] = e[j]
        elif b < s.size and s[b] == e[b - 1]:
            for j in range(b - count, b):
                s[j] = e[j]
    return s


def _refined(coarse: GeneralMemory):
    """(first, status) of the shadow's pattern ``coarse`` on the fine lattice (half its cell): fine cells 2c
    and 2c + 1 take coarse cell c's status; None out of contact."""
    if coarse.normal is None:
        return None
    return 2 * coarse.first, np.repeat(coarse.status, 2)


def _coarsened(fine: GeneralMemory):
    """(first, status) of ``fine``'s pattern on the lattice of twice its cell (the shadow's): coarse cell c
    covers fine cells 2c and 2c + 1 and takes the status of the one of them in ``fine``'s range, the
    second where both are."""
    first = fine.first // 2
    count = (fine.first + fine.q.size + 1) // 2 - first
    idx = np.clip(2 * (first + np.arange(count)) + 1 - fine.first, 0, fine.q.size - 1)
    return first, fine.status[idx].copy()


def _decision_tolerances(qmax_max: float, gscale: float, floor: float) -> tuple[float, float]:
    """(shear, slip): how far past its bound a stuck cell's shear, and against its direction a slipping cell's
    increment, may go before the active set changes the cell (FLIP_TOL of f max p, ``qmax_max``, and of A f
    max p h, the slip never below ``floor``, the rounding of the locked displacements)."""
    return FLIP_TOL * qmax_max, max(FLIP_TOL * gscale, floor)


@numba.njit(cache=True)
def _take_inputs(glock, x, c1, f, cap):  # pragma: no cover - compiled
    """A take's bulk term c1 x (c1 = A sigma1 / 4), r = glock - c1 x, the bounds f cap, and r's mid-range,
    the largest bound and r's largest size, in one pass (the numbers of numpy's array steps)."""
    n = x.size
    sigma_term = np.empty(n)
    r = np.empty(n)
    qmax = np.empty(n)
    lo, hi, size, top = np.inf, -np.inf, 0.0, -np.inf
    for i in range(n):
        sigma_term[i] = c1 * x[i]
        r[i] = glock[i] - sigma_term[i]
        qmax[i] = f * cap[i]
        lo, hi = min(lo, r[i]), max(hi, r[i])
        size, top = max(size, abs(r[i])), max(top, qmax[i])
    return sigma_term, r, qmax, 0.5 * (lo + hi), top, size


def _match_points(x: np.ndarray, h: float) -> dict:
    """{side: x}: the points ARRIVAL_MATCH cells beyond a take's first and last cell centres ``x``, where the
    arrivals' increments are matched to the lattice (GeneralSolver._arrival_fit)."""
    return {-1: float(x[0]) - ARRIVAL_MATCH * h, 1: float(x[-1]) + ARRIVAL_MATCH * h}


@functools.lru_cache(maxsize=64)
def _no_fit(n: int):
    """The active set's arrival arguments when nothing is fitted (GeneralSolver._arrival_fit's form), kept per
    n: the compiled active set only reads them (left writable: a read-only array is another type to numba,
    and the active set would be compiled twice)."""
    none = np.zeros((0, n))
    return np.full(n, -1, np.int64), none, none, none, np.zeros(0), np.zeros(0)


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Half-open (start, stop) of the runs of True in ``mask``."""
    return list(map(tuple, _run_bounds(np.ascontiguousarray(mask, dtype=np.bool_)).tolist()))


def _projected_gradient(lat: ToeplitzLattice, n: int, r: np.ndarray, qmax: np.ndarray, total: float,
                        q0: np.ndarray, iterations: int = 2000) -> np.ndarray:
    """Accelerated projected gradient (FISTA) for the step problem; returns its active pattern.

    Always convergent on a strictly convex problem; used only to restart the
    active set when its pattern repeats.
    """
    L = float(np.sum(np.abs(lat.t[:n]))) * 2.0  # bound on the largest eigenvalue (Gershgorin)
    q = _project(np.clip(q0, -qmax, qmax), qmax, total)
    y, tk = q.copy(), 1.0
    for _ in range(iterations):
        grad = lat.matvec(y) + r
        q_new = _project(y - grad / L, qmax, total)
        t_new = 0.5 * (1.0 + math.sqrt(1.0 + 4.0 * tk * tk))
        y = q_new + ((tk - 1.0) / t_new) * (q_new - q)
        q, tk = q_new, t_new
    status = np.zeros(n, np.int8)
    tight = 1e-9 * float(qmax.max())
    status[q >= qmax - tight] = 1
    status[q <= -qmax + tight] = -1
    return status


def _project(v: np.ndarray, qmax: np.ndarray, total: float) -> np.ndarray:
    """Projection onto {|q| <= qmax, sum q = total}: clip(v - mu) with mu by bisection."""
    lo, hi = float(np.min(v - qmax)) - 1.0, float(np.max(v + qmax)) + 1.0
    for _ in range(200):
        mu = 0.5 * (lo + hi)
        if np.sum(np.clip(v - mu, -qmax, qmax)) > total:
            lo = mu
        else:
            hi = mu
    return np.clip(v - 0.5 * (lo + hi), -qmax, qmax)


def _verdict(coulomb, direction, stuck, force, Q, fP, qscale, gscale, floor=0.0) -> float:
    """The step's own verification, relative to CHECK_TOL, from the largest Coulomb excess, slip against
    the shear and slip of a stuck cell (:func:`_settled`): Coulomb relative to f max p, slip direction
    and stick relative to A f max p h, the displacement a cell's bound shear makes, but never below
    ``floor``, the rounding of the stored displacements; equilibrium relative to f P."""
    scale_s = max(gscale, floor / CHECK_TOL)
    equilibrium = abs(force - Q) / fP
    return max(coulomb / qscale, direction / scale_s, stuck / scale_s, equilibrium) / CHECK_TOL


@numba.njit(cache=True)
def _settled(delta, Tq, sigma_term, glock, status, q, qmax, cap0, cap, f, G0):  # pragma: no cover - compiled
    """A take's end from its active set's answer: g (the locked displacement where a cell sticks, the relative
    displacement delta - T' q + A sigma x / 4 where it slips), the slip s = g - the lock (0 where stuck), the
    accumulated slip G0 + s, the runs of stuck cells (half-open, (k, 2)), how many cells slip, sum q and the sum of
    each slipping cell's dissipation f (cap0 + cap) / 2 |s| (numpy's sums: pairwise_sum; the caller scales
    it), max cap, and what :func:`_verdict` checks: the largest Coulomb excess abs(q) - qmax (at least 0),
    slip against the shear and slip where stuck, and max abs(lock)."""
    n = q.size
    g = np.empty(n)
    s = np.empty(n)
    parts = np.empty(n)
    count = 0
    coulomb = direction = stuck = locked = 0.0
    for i in range(n):
        coulomb = max(coulomb, abs(q[i]) - qmax[i])
        locked = max(locked, abs(glock[i]))
        gi = delta - Tq[i] + sigma_term[i]
        si = gi - glock[i]
        if status[i] == 0:
            stuck = max(stuck, abs(si))
            g[i] = glock[i]
            s[i] = 0.0
        else:
            direction = max(direction, -(status[i] * si))
            g[i] = gi
            s[i] = si
            parts[count] = f * 0.5 * (cap0[i] + cap[i]) * abs(si)
            count += 1
    G = np.empty(n)
    top = -np.inf
    for i in range(n):
        G[i] = G0[i] + s[i]
        top = max(top, cap[i])
    return (g, s, G, _run_bounds(status == 0), count, pairwise_sum(q, 0, n), pairwise_sum(parts, 0, count), top,
            coulomb, direction, stuck, locked)


def _run_edges(x, q, qmax, status, N: NormalSolution, h: float, i: int, k: int,
               slipping=(False, False), drives=None, side: int | None = None) -> tuple[float, float, float]:
    """Edges of the stick run of cells i..k (the outermost stick points for the first and last stuck
    cells), within the cell, and how far either may be from where it is put, in cells, where that is
    more than EDGE_PLACEMENT (SUBCELL_PLACEMENT at a contact edge, half a cell there where the outermost stick
    cell is within END_RATIO_ERROR of its bound, half a cell for a bracketed edge,
    below; 0 otherwise); ``side`` 0 or 1: how far the left or the right one may be (None: either).

    Inside the contact the traction margin f cap - s q vanishes like the square root of the distance to
    the edge, and where the lattice puts the edge for that is its own response, EDGE_RULE (since 0.3.7):
    u(rho) cells outward of the outermost stick cell's centre, rho the ratio of its margin to its inner
    neighbour's, from 0.17 of a cell inside that centre to 0.82 outside it. Until 0.3.7 the margin's
    square was extrapolated linearly to its zero, which is the continuous form and not the lattice's:
    0.17 - 0.20 of a cell off on J1 and J2 (now at most 0.024), 2.0e-4 / 2.6e-4 of the width at the 95th
    percentile of the random histories at 1024 nodes (Hertz / punch; now 1.1e-4 / 2.1e-4 with this rule).
    Where rho exceeds what a square-root margin gives on the lattice (EDGE_RULE_REACH), the margin does
    not grow inwards like the square root (a band of cells within a small fraction of their bound, as
    before a load maximum, or a margin an earlier slip left): the edge is then bracketed by the two
    centres and put midway, at most half a cell from either (since 0.3.3; until then at the neighbour's
    centre: the dovetail at 1000 nodes, against 16000, 95th percentile of the edge error 0.67 -> 0.38 of
    a cell, largest 0.84 -> 0.47). Where the rule applies but the third cell in has less margin than the
    second (within the run's near half), the square root it read does not go on: the edge stays where the
    rule puts it, placed to half a cell (since 0.3.8; the dovetail early in each loading half, 0.28 of a
    cell off against the 0.1-cell floor).

    A stick run reaching the end cell ends at the contact edge, unless (S1) says that edge slips
    (``slipping``, left and right): then the slip zone is narrower than the end cell, and its edge c is
    where (x - E) m^2 (m = 1 - s q / (f cap), E the contact edge) extrapolates to zero, as it does for
    the local Cattaneo solution. s is the way the edge slips: that of the stuck increment's singular term
    there, u - chi v with ``drives`` = (u / f, v) of (S1) at each edge and chi = q / (f cap) of the end
    cell (since 0.3.8; until then the sign of q there, which a receding edge need not slip with: J3, the
    punch at 512 nodes 0.35 of a cell off, now 0.031). So too when the end cell is the only slipping cell between the run and
    its contact edge (since 0.3.3; the traction margin's square stopped at the end cell's centre there).
    That form's estimate is corrected by the lattice's response to it, END_RULE_WITHIN and END_RULE_END
    (since 0.3.7: J1 at 256 nodes with the contact edge anywhere in its cell, largest error 0.085 / 0.055
    of a cell against 0.20 before; the random Hertz histories at 1024 nodes 95th percentile 1.1e-4 ->
    7.3e-5 of the width, the punch's 2.1e-4 -> 1.9e-4)."""
    left, right, placements = _run_edges_each(x, q, qmax, status, N, h, i, k, slipping, drives)
    return left, right, float(placements.max() if side is None else placements[side])


def _run_edges_each(x, q, qmax, status, N: NormalSolution, h: float, i: int, k: int, slipping=(False, False),
                    drives=None) -> tuple[float, float, np.ndarray]:
    """:func:`_run_edges` with each side's placement (left, right), in cells."""
    return _run_edges_kernel(x, q, qmax, status, float(N.left), float(N.right), h, i, k, bool(slipping[0]),
                             bool(slipping[1]), drives is not None,
                             _NO_DRIVES if drives is None else np.array(drives, dtype=float), _END_RULES[True],
                             _END_RULES[False])


@numba.njit(cache=True)
def _run_edges_kernel(x, q, qmax, status, left, right, h, i, k, open_left, open_right, driven, drives,
                      within_rule, end_rule):  # pragma: no cover - compiled
    """_run_edges, compiled (since 0.4.4; the same operations): the contact's edges, (S1)'s ``open_left`` and
    ``open_right`` and, where ``driven``, its ``drives`` ((2, 2): (u / f, v) at each edge); the end rules
    END_RULE_WITHIN and END_RULE_END as arrays (benchmarks/calibrate_edge_rule.py sets them to zero). The
    placement is each side's (since 0.4.6)."""
    out = np.empty(2)
    placement = np.zeros(2)  # (each side's)
    for side in range(2):
        end, step, edge, open_ = (i, 1, left, open_left) if side == 0 else (k, -1, right, open_right)
        nb = end - step
        within = nb < 0 or nb >= x.size  # the run reaches the end cell
        if within:
            if not open_:
                out[side] = edge
                continue
            if driven:
                # the slip at the edge goes the way of the stuck increment's singular term there, u - chi f v
                # with chi = q / (f p) at the edge (the end cell's): at an advancing edge that slips (abs(u) >=
                # f v) the sign of u, at a receding one not necessarily that of q (unloading from a
                # proportional state q = chi f p with dQ / dP above chi f slips backwards)
                u, v = drives[side, 0], drives[side, 1]
                sgn = 1 if u - (q[end] / qmax[end] if qmax[end] > 0.0 else 0.0) * v >= 0.0 else -1
            else:
                sgn = 1 if q[end] >= 0.0 else -1
        else:
            sgn = int(status[nb])
        m0 = 1.0 - sgn * q[end] / qmax[end] if qmax[end] > 0 else 0.0
        near = m0 < END_RATIO_ERROR  # (the outermost stick cell may as well slip)
        inner = end + step
        if 0 <= inner < x.size and status[inner] == 0 and qmax[inner] > 0:
            m1 = 1.0 - sgn * q[inner] / qmax[inner]
        else:
            m1 = m0
        m0, m1 = max(m0, 0.0) ** 2, max(m1, 0.0) ** 2
        if within or nb == 0 or nb == x.size - 1:
            # a slip zone within the end cell, or of about a cell (the end cell nb alone slips): near a
            # contact edge E, (x - E) m^2 = x - c for the local Cattaneo solution (m^2 = (x - c) / (x - E));
            # its zero from the two outermost stick cells, between the first of them and the contact edge
            # (within) or the slipping end cell's centre
            u0 = abs(x[end] - edge)
            lower = 0.0 if within else u0 - h
            m0, m1 = m0 * u0, m1 * (u0 + h)
            w = u0 - m0 * h / (m1 - m0) if m1 > m0 else lower
            w = min(max(w, lower), u0)
            # and the lattice's response to that form (END_RULE_*), at most EDGE_INSIDE inward of the cell's centre
            w_est, u_e = w / h, u0 / h - (0.0 if within else 1.0)
            w += h * _polyval2d(w_est, u_e, within_rule if within else end_rule)
            out[side] = edge + step * min(max(w, lower), u0 + EDGE_INSIDE * h)
            # (an outermost stick cell about to slip: the zone may reach its inner boundary, half a cell)
            placement[side] = max(placement[side], 0.5 if near else SUBCELL_PLACEMENT)
            continue
        # the traction margin f cap - |q| vanishes like the square root of the distance to the stick edge,
        # and the lattice's response to that is EDGE_RULE
        m0 *= qmax[end] ** 2
        m1 *= (qmax[inner] if 0 <= inner < x.size else qmax[end]) ** 2
        rho = math.sqrt(m0 / m1) if m1 > 0.0 else math.inf
        if rho <= EDGE_RULE_REACH:
            frac = _edge_rule(min(rho, EDGE_RULE_RHO))
            # the rule reads a square root off two cells; the next cell in must continue it. A margin that
            # falls again there was left by an earlier slip (the dovetail early in each loading half: the
            # slip zone grows into cells the last half-cycle left near their other bound), and the rule's
            # place is then as uncertain as a bracketed one
            far = inner + step
            if 2 * abs(far - end) <= k - i and status[far] == 0 and qmax[far] > 0:  # (the run's near half)
                if (max(1.0 - sgn * q[far] / qmax[far], 0.0) * qmax[far]) ** 2 < m1:
                    placement[side] = max(placement[side], 0.5)
        else:
            # the margin does not grow inwards as the square root would (an ill-conditioned band of cells
            # near their bound, or a margin left by an earlier slip): the edge lies between the two
            # centres, and their midpoint is at most half a cell from it
            frac = 0.5
            placement[side] = max(placement[side], 0.5)
        out[side] = x[end] - step * frac * h
    return out[0], out[1], placement


@numba.njit(cache=True)
def _polyval2d(x, y, c):  # pragma: no cover - compiled
    """sum c[i, j] x^i y^j as numpy.polynomial.polynomial.polyval2d takes it for scalars (Horner in x for
    every power of y, then in y; the same operations)."""
    v = np.empty(c.shape[1])
    for j in range(c.shape[1]):
        v[j] = c[c.shape[0] - 1, j] + x * 0.0
    for i in range(c.shape[0] - 2, -1, -1):
        for j in range(c.shape[1]):
            v[j] = c[i, j] + v[j] * x
    out = v[v.size - 1] + y * 0.0
    for j in range(v.size - 2, -1, -1):
        out = v[j] + out * y
    return out


#: How far inside its outermost stick cell's centre a stick edge may lie, in cells: where EDGE_RULE puts it
#: when that cell is about to slip (rho = 0).
EDGE_INSIDE = -EDGE_RULE[-1]
_END_RULES = {True: np.array(END_RULE_WITHIN), False: np.array(END_RULE_END)}
_NO_DRIVES = np.zeros((2, 2))


@numba.njit(cache=True)
def _edge_rule(rho):  # pragma: no cover - compiled
    """Where a stick edge lies outward of its outermost stick cell's centre, in cells (EDGE_RULE)."""
    u = 0.0
    for c in EDGE_RULE:
        u = u * rho + c
    return u


def _slope_kinks(profile) -> tuple[np.ndarray, bool]:
    """Points where h' is not smooth, and whether to grade the pressure integrals towards them.

    The ends of a punch flat (graded: p has an x ln x kink); the samples of a
    tabulated profile (cut, not graded: there can be thousands).
    """
    from ..geometry import RoundedPunch, TabulatedProfile

    if isinstance(profile, RoundedPunch) and profile.flat_half_width > 0.0:
        w = profile.flat_half_width
        return np.array([-w, w]), True
    if isinstance(profile, TabulatedProfile):
        return np.asarray(profile.x, dtype=float), False
    return np.zeros(0), False


def _undecided_band(q, qmax, s, status, end: int, step: int, qtol: float, stol: float) -> tuple[int, int]:
    """The cells the active set left undecided at the stick edge beside the stuck cell ``end``, ``step`` the
    way out of the stick run there (-1 at a left edge, +1 at a right one): (stuck, slipping), how many stuck
    cells from ``end`` inward carry their bound (within ``qtol``) and how many slipping cells beyond it do
    not slip (within ``stol``). Each of them is as much a stick cell as a slip cell at the tolerances the
    active set decides by (:func:`_decision_tolerances`)."""
    n = q.size
    stuck = 0
    j = end
    while 0 <= j < n and status[j] == 0 and abs(q[j]) >= qmax[j] - qtol:
        stuck += 1
        j -= step
    slipping = 0
    j = end + step
    while 0 <= j < n and status[j] != 0 and abs(s[j]) <= stol:
        slipping += 1
        j += step
    return stuck, slipping


def _undecided_reach(x, q, qmax, s, status, N, h, i, k, slipping, drives, edges, qtol, stol,
                     sides=(0, 1)) -> float:
    """How far, in cells, the outermost stick edges (``edges``, of the stick cells i..k) may be from where
    they are put because the active set left cells beside them undecided (:func:`_undecided_band`): the
    edge lies anywhere between where the pattern with those cells slipping puts it and where the pattern
    with them stuck does (_run_edges on each), and the reach is the farther one's distance plus the
    placement floor EDGE_PLACEMENT of that edge (the span of the stick cells where every one of them is
    undecided). 0 where there are none. ``sides``: the edges to look at (0 the left one, 1 the right)."""
    reach = 0.0
    for side, (end, step) in enumerate(((i, -1), (k, 1))):
        if side not in sides:
            continue
        stuck, free = _undecided_band(q, qmax, s, status, end, step, qtol, stol)
        for count, now in ((stuck, 0), (free, 1)):
            if count == 0:
                continue
            alt = status.copy()
            if now == 0:  # the undecided stuck cells slip, the way of their shear
                cells = end - step * np.arange(count)
                alt[cells] = np.where(q[cells] >= 0.0, 1, -1)
                left = np.flatnonzero(alt[i:k + 1] == 0)  # the stick cells that remain
                if left.size == 0:  # every stick cell is undecided: the edge may be anywhere in them
                    reach = max(reach, float(k - i + 1))
                    continue
                a, b = i + int(left[0]), i + int(left[-1])
            else:  # the slipping cells that do not slip stick
                alt[end + step * (1 + np.arange(count))] = 0
                a, b = (i - count, k) if side == 0 else (i, k + count)
            other = _run_edges(x, q, qmax, _frozen(alt), N, h, a, b, slipping, drives)[side]
            # (that edge is placed to EDGE_PLACEMENT as any other)
            reach = max(reach, abs(other - edges[side]) / h + EDGE_PLACEMENT)
    return reach


def _unresolved_reach(slipping: tuple, status: np.ndarray, h: float) -> float:
    """How far a stick edge may be from where the lattice puts it at a contact edge whose stick run
    may be an island (``slipping``, left and right, :func:`_slipping_edges`) [m] (0 where there is
    none).

    physics.md (S1): an edge of the contact (half-width d) sticks through a
    small step only if abs(u) < f v, u = dQ -+ (pi/4) d dsigma, v = dP -+ 2 dM0 / d
    (v > 0: the edge advances). A stationary or receding edge (v <= 0) with a
    shear drive (u != 0) slips. When that fails and the end cell still sticks,
    either the slip zone there is narrower than a cell (_run_edges places it
    within the end cell and says how well), or the stick run at the edge, if
    at most UNCONFIRMED_ISLAND cells wide, is an island that the continuous
    solution does not have (seen on the random histories: a 3-cell island
    left at a receding, slipping edge at 1024 nodes, gone at 2048, 0.2 of the
    width outside the stick run that follows it; the shadow lattice had it
    too): then the stick edge may be as far in as the next stick run, and
    that distance is the reach.
    """
    reach = 0.0
    for side, slips in zip((-1, 1), slipping):
        cells = status if side < 0 else status[::-1]
        if not (slips and cells[0] == 0):
            continue
        gap = np.flatnonzero(cells != 0)
        if gap.size:
            beyond = np.flatnonzero(cells[gap[0]:] == 0)
            if beyond.size and gap[0] <= UNCONFIRMED_ISLAND:  # an island, another stick run after its gap
                reach = max(reach, (gap[0] + beyond[0] + 0.5) * h)
    return reach


def _edge_drives(N1: NormalSolution, loads0: Loads, loads1: Loads) -> tuple[tuple[float, float], ...]:
    """(u, v) of (S1) at the left and right contact edges over the step: the tangential and normal increments
    that drive each edge, u = dQ -+ (pi/4) d dsigma and v = dP -+ 2 dM0 / d (v > 0: the edge advances)."""
    d, x0 = N1.half_width, N1.center
    dP, dQ = loads1.P - loads0.P, loads1.Q - loads0.Q
    dM0 = (loads1.M - loads0.M) - dP * x0
    dS = loads1.sigma - loads0.sigma
    return tuple((dQ + side * 0.25 * math.pi * d * dS, dP + side * 2.0 * dM0 / d) for side in (-1, 1))


def _slipping_edges(drives: tuple, loads0: Loads, loads1: Loads, f: float) -> tuple[bool, bool]:
    """Whether (S1) says the left / right contact edge slips over the step, from its ``drives``
    (:func:`_edge_drives`; see :func:`_unresolved_reach`)."""
    drive = 1e-12 * f * max(abs(loads0.P), abs(loads1.P))
    out = [bool(abs(u) >= f * v if v > 0.0 else abs(u) > drive) for u, v in drives]
    return out[0], out[1]


def _shear_apart(fine: GeneralMemory, coarse: GeneralMemory) -> float:
    """int abs(q_fine - q_coarse) dx of two lattices' solutions [N/m], q = (q_j / cap_j) p within each cell.

    Both shears are the cell's ratio chi_j = q_j / cap_j times the pressure, so
    the integral is sum_j h cap_j abs(chi_j - chi_J) over the fine cells j, J
    the shadow's cell holding j's centre (cells without load count nothing).
    Compiled (:func:`_shear_apart_kernel`; the numbers of numpy's steps).
    """
    return _shear_apart_kernel(fine.first, fine.spacing, fine.q, fine.capacity, coarse.first, coarse.spacing,
                               coarse.q, coarse.capacity)


@numba.njit(cache=True)
def _shear_apart_kernel(first, h, q, cap, first_c, h_c, q_c, cap_c):  # pragma: no cover - compiled
    """:func:`_shear_apart` of the fine cells from lattice index ``first`` (spacing ``h``, shear ``q``, loads
    ``cap``) against the shadow's (``first_c``, ``h_c``, ``q_c``, ``cap_c``): h times numpy's sum
    (:func:`pairwise_sum`) of cap_j abs(chi_j - chi_J)."""
    n = q.size
    terms = np.empty(n)
    for j in range(n):
        J = min(max(int(math.floor((first + 0.5 + j) * h / h_c)) - first_c, 0), q_c.size - 1)
        chi = q[j] / cap[j] if cap[j] > 0.0 else 0.0
        chi_c = q_c[J] / cap_c[J] if cap_c[J] > 0.0 else 0.0
        terms[j] = cap[j] * abs(chi - chi_c)
    return h * pairwise_sum(terms, 0, n)


def _windowed_regime(fine: "_Outcome", windows: tuple, edges, N: NormalSolution) -> Regime:
    """The regime of a take whose edge windows ``windows`` report the outermost stick points ``edges``: partial slip
    where a lattice cell outside the windows slips, a window's fine cell slips or a stick point lies inside the
    contact (a slip zone placed inside an end cell), full stick otherwise (since 0.4.6: the lattice's regime
    with the windows' edges could say full stick beside a window's slip zone, or partial slip with the stick
    zone the whole contact)."""
    covered = np.zeros(fine.memory.status.size, bool)
    for w in windows:
        covered[w.lo:w.hi] = True
        if np.any(w.status):
            return Regime.PARTIAL_SLIP
    if np.any(fine.memory.status[~covered]) or tuple(edges) != (N.left, N.right):
        return Regime.PARTIAL_SLIP
    return Regime.STICK


def _at_least(estimate: float, spread: float) -> float:
    """``estimate`` raised to ``spread`` (NaN stays NaN: no shadow)."""
    return estimate if math.isnan(estimate) else max(estimate, spread)


def _apart(u: float, v: float) -> float:
    if math.isnan(u) or math.isnan(v):
        return 0.0 if math.isnan(u) and math.isnan(v) else math.inf
    return abs(u - v)


# -- the end cells ------------------------------------------------------------------------------------------
def _end_supports(normal, first: int, n: int, h: float) -> list:
    """[(k, a, b)]: the cells (0 .. n-1 of a state's) whose shear acts over [a, b] instead of their cell: the
    first over [L, (first + 1) h], the last over [(first + n - 1) h, R] (one cell: [L, R]); none when out
    of contact."""
    if normal is None or n == 0:
        return []
    L, R = normal.left, normal.right
    if n == 1:
        return [(0, L, R)]
    return [(0, L, (first + 1) * h), (n - 1, (first + n - 1) * h, R)]


class _EndCell:
    """A force h spread like the pressure of ``normal`` over [a, b], against the same force over the cell
    [lo, lo + h]: int ln|x - xi| w(xi) dxi over [a, b] (w = h p / int_a^b p) less int ln|x - xi| dxi over
    the cell, at any points (:meth:`potential`).

    In theta (xi = c - d cos theta) p d sin(theta) is smooth up to the contact edges (a square root or an
    inverse square root there); [a, b] is cut at the profile's slope ``kinks`` (the ends of a punch flat:
    p has an x ln x kink there, which a punch at 1e-12 P0 has 4e-9 of the flat inside its end cells) and,
    for an x inside it, at x, whose log singularity is taken out (p(x) times the closed form of
    int ln|x - xi|, plus the continuous rest). Each piece: Gauss-Legendre in theta mapped by the quintic
    smoothstep, which grades the points towards both of its ends. Beyond END_CELL_NEAR cells of the cell's
    centre x0 both integrals are the multipole series ln|x - xi| = ln|x - x0| - sum_k ((xi - x0) / (x -
    x0))^k / k, whose ln cancels between the two (the same force) and whose k-th term is the difference of
    the k-th moments. What depends on the cell only (the rule, the moments, the value at the cell's own
    centre) is found once: a state's end cells are asked again at every take of the step and by the next.
    Compiled (:func:`_end_cell_build`): since 0.4.2 but for the pressure, 47 -> 19 us a cell, 7-9 % of a step
    on the random histories at 1024 nodes; with the pressure since 0.4.3.
    """

    def __init__(self, normal, a: float, b: float, lo: float, h: float, kinks: np.ndarray, build: bool = True):
        self.normal, self.a, self.b, self.lo, self.h = normal, a, b, lo, h
        self.x0 = lo + 0.5 * h
        # the pieces: cut at the kinks and at the cell's centre (inside the support: it is in the contact)
        self.cuts = (np.concatenate(([a], kinks[(kinks > a) & (kinks < b)], [b])) if kinks.size
                     else np.array([a, b]))
        self.inside = a < self.x0 < b
        if build:  # (or :func:`_end_pair` with another, then :meth:`built`)
            self.built(_end_cell_build(self.cuts, self.x0, self.inside, normal.center, normal.half_width, _EC_S,
                                       _EC_DS, normal.pressure_arguments(), h, a, b, END_CELL_TERMS))

    def built(self, parts: tuple) -> None:
        """Take :func:`_end_cell_build`'s answer: the rule's points; the weights of the force h, the moments of
        the pressure-shaped force less those of the uniform one (odd ones of the cell vanish), in cells (the
        k-th moment over h^(k + 1)), and the shaped potential at the cell's own centre, from the same points
        (the rule is cut there)."""
        self.xi, self.w, self.scale, self.series, at_own = parts
        self.own = at_own if self.inside else None

    def kernel_arguments(self) -> tuple:
        """:func:`_end_cell_kernel`'s arguments between the points and ``near``."""
        return (self.x0, self.h, self.lo, self.a, self.b, self.series, self.xi, self.w,
                math.nan if self.own is None else self.own)

    def potential(self, xs: np.ndarray) -> np.ndarray:
        """The difference of the two log potentials at ``xs``."""
        xs = np.ascontiguousarray(xs, dtype=float)
        out, rest = _end_cell_kernel(xs, *self.kernel_arguments(), END_CELL_NEAR, LATTICE_POINT)
        if rest.size:
            out[rest] = self._inside(xs[rest])
        return out

    def _inside(self, xn: np.ndarray) -> np.ndarray:
        """The potentials at points inside the support other than the cell's centre (rare: the lattice's
        points inside an end cell's support are its own centre): the rule cut at each of them."""
        part = np.empty(xn.size)
        cuts, N = self.cuts, self.normal
        for i, x in enumerate(xn.tolist()):
            xj, pj, dj = _cut_rule(cuts, x, True, N.center, N.half_width, _EC_S, _EC_DS, N.pressure_arguments())
            part[i] = _shaped_at(x, xj, pj, dj, self.scale, self.a, self.b)
        return part - (_G(xn - self.lo) - _G(xn - self.lo - self.h))


@numba.njit(cache=True)
def _displaced(shift, t, ri, ci, q, datum, bulk, xs, scale, ends, one, two, near, tol):  # pragma: no cover
    """GeneralSolver._displacement in one pass for a state's shear ``q`` on its cells ``ci`` at the lattice
    points ``ri`` (``t`` the kernel's table, ``datum`` its datum's term, ``bulk`` A sigma / 4): shift - T q +
    bulk x, less the end cells' corrections, ``scale`` = -A/pi times each end cell's potential (``one`` and
    ``two``: :meth:`_EndCell.kernel_arguments` of the cells ``ends``, one of them for a contact of one cell)
    times its shear; False where a point lies inside an end cell's support (the caller's general path)."""
    n = xs.size
    out = table_products(t, ri, ci, q.reshape((q.size, 1)))[:, 0]
    for i in range(n):
        out[i] = (shift - (out[i] + datum)) + bulk * xs[i]
    corr = np.zeros(n)  # the end cells' columns times their shear, summed over the cells
    for c in range(ends.size):
        pot, rest = _end_potential(xs, c, one, two, near, tol)
        if rest.size:
            return out, False
        qc = q[ends[c]]
        for i in range(n):
            corr[i] += (scale * pot[i]) * qc
    for i in range(n):
        out[i] -= corr[i]
    return out, True


@numba.njit(cache=True)
def _arrival_terms(x, known, first, h, A, centre, edge_l, edge_r, t, shift0, q0, first0, datum0, bulk0, ends0,
                   one0, two0, near, tol, args_l, args_r, gauss_t, gauss_w, dQ, dS, fit, ends1, one1, two1,
                   match, shape_q, shape_s, c1):  # pragma: no cover - compiled
    """GeneralSolver._arrivals and _arrival_fit in one pass where both contacts exist and the edge path is a
    hermite one (every take of a growing contact but the step it forms in; :meth:`GeneralSolver._arrived`
    gives the arguments). The arrived cells (not ``known``) left of the old contact's ``centre`` arrive at
    its left edge, the others at its right; the match points lie ``match`` cells beyond the first and last
    cell. The start displacement from the old shear ``q0`` (cells from lattice index ``first0``; ``datum0``,
    ``bulk0``, ``ends0``, ``one0``, ``two0`` as :func:`_displaced`'s) at the arrived cells and the match points;
    the arrival integrals of each side (:func:`hermite_integrals`, ``args_l`` / ``args_r`` the path's
    hermite_arguments) give M1's locks (the load change ``dQ``, ``dS``) and, with ``fit``, the arrivals'
    shape (``shape_q``, ``shape_s``) and T' at the match points (``t`` the lattice's kernel table, the take's
    end cells ``ends1`` with their kernel arguments ``one1``, ``two1``), ``c1`` = A sigma1 / 4.

    Returns ok (False: a point met an end cell's support; the caller's general path), the arrived cells'
    locks and start displacements, the match points' start displacements and which sides have arrivals
    ((2,) each), and the fit's per-cell side index, now, phi, K, the match points' c1 x and start
    displacements and the shapes' units (one row per fitted side; the caller forms e with r0)."""
    n = x.size
    count = 0
    for i in range(n):
        if not known[i]:
            count += 1
    cells = np.empty(count, np.int64)
    k = 0
    for i in range(n):
        if not known[i]:
            cells[k] = i
            k += 1
    split = 0  # x ascending: the arrived cells left of the old centre come first
    while split < count and x[cells[split]] < centre:
        split += 1
    has = np.zeros(2, np.bool_)
    has[0], has[1] = split > 0, split < count
    xe = np.array([x[0] - match * h, x[n - 1] + match * h])
    # the start displacement at the arrived cells and the match points (lattice points of the same lattice)
    m = count + int(has[0]) + int(has[1])
    at = np.empty(m)
    ri = np.empty(m, np.int64)
    for c in range(count):
        at[c] = x[cells[c]]
        ri[c] = first + cells[c]
    c = count
    for s in range(2):
        if has[s]:
            at[c] = xe[s]
            ri[c] = first - match if s == 0 else first + n - 1 + match
            c += 1
    ci = np.empty(q0.size, np.int64)
    for j in range(q0.size):
        ci[j] = first0 + j
    start, done = _displaced(shift0, t, ri, ci, q0, datum0, bulk0, at, -(A / math.pi), ends0, one0, two0, near, tol)
    glock = np.empty(count)
    before = np.zeros(2)
    side_of = np.full(n, -1, np.int64)
    now = np.zeros((2, n))
    phi = np.zeros((2, n))
    K = np.zeros((2, n))
    cx = np.zeros(2)
    bef = np.zeros(2)
    m1 = np.zeros(2)
    fitted = 0
    if not done:
        return False, glock, start[:count], before, has, side_of, now, phi, K, cx, bef, m1, fitted
    c = count
    for s in range(2):
        if has[s]:
            before[s] = start[c]
            c += 1
    for s in range(2):
        if not has[s]:
            continue
        side = -1 if s == 0 else 1
        lo, hi = (0, split) if s == 0 else (split, count)
        kk = hi - lo
        pts = np.empty(kk + 1)  # outward from the edge: the arrived cells, then the match point
        order = np.empty(kk, np.int64)  # the arrived index of each
        for i in range(kk):
            order[i] = hi - 1 - i if s == 0 else lo + i
            pts[i] = at[order[i]]
        pts[kk] = xe[s]
        if s == 0:
            parts = hermite_integrals(pts, edge_l, -1, A, *args_l, gauss_t, gauss_w)
        else:
            parts = hermite_integrals(pts, edge_r, 1, A, *args_r, gauss_t, gauss_w)
        for i in range(kk):
            a = order[i]
            glock[a] = start[a] + side * (dQ * parts[i, 0] + dS * parts[i, 1])
        if not fit:
            continue
        unit = side * (shape_q * parts[kk, 0] + shape_s * parts[kk, 1])
        if not (unit != 0.0 and math.isfinite(unit)):
            continue
        for i in range(kk):
            a = order[i]
            cell = cells[a]
            phi[fitted, cell] = side * (shape_q * parts[i, 0] + shape_s * parts[i, 1])
            now[fitted, cell] = glock[a] - start[a]
            side_of[cell] = fitted
        # T' at the match point: the kernel from each cell, the end cells' shear over their supports
        for i in range(n):
            K[fitted, i] = t[match + i] if s == 0 else t[n - 1 + match - i]
        point = xe[s:s + 1]
        for e in range(ends1.size):
            pot, rest = _end_potential(point, e, one1, two1, near, tol)
            if rest.size:
                return False, glock, start[:count], before, has, side_of, now, phi, K, cx, bef, m1, fitted
            K[fitted, ends1[e]] += -(A / math.pi) * pot[0]
        cx[fitted] = c1 * xe[s]
        bef[fitted] = before[s]
        m1[fitted] = unit
        fitted += 1
    return True, glock, start[:count], before, has, side_of, now, phi, K, cx, bef, m1, fitted


@numba.njit(cache=True)
def _leaving_terms(first0, status0, g0, cap0, first, n, h, left0, right0, centre0, left1, right1, bound, t, shift, q,
                   datum, bulk, A, ends, one, two, near, tol):  # pragma: no cover - compiled
    """GeneralSolver._leaving's terms in one pass: the cells of the old state (from lattice index ``first0``: its
    status, locks and capacities) outside the take's n cells from ``first`` that slipped, their slip until
    they left (:func:`_leaving_slip`) from the end's displacement there (:func:`_displaced` of the take's
    shear ``q`` with its arguments, ``A`` the compliance). Returns done (False where a point met an end
    cell's support: the caller finds the displacement by the general path), the cells' centres, their
    indices in the old state and the terms (the caller sums them)."""
    count = 0
    for j in range(status0.size):
        if status0[j] != 0 and not (first <= first0 + j < first + n):
            count += 1
    xs = np.empty(count)
    ri = np.empty(count, np.int64)
    at = np.empty(count, np.int64)
    k = 0
    for j in range(status0.size):
        if status0[j] != 0 and not (first <= first0 + j < first + n):
            xs[k] = (first0 + 0.5 + j) * h  # GeneralMemory.x's
            ri[k] = first0 + j
            at[k] = j
            k += 1
    if count == 0:
        return True, xs, at, np.zeros(0)
    ci = np.empty(n, np.int64)
    for i in range(n):
        ci[i] = first + i
    g1, done = _displaced(shift, t, ri, ci, q, datum, bulk, xs, -(A / math.pi), ends, one, two, near, tol)
    if not done:
        return False, xs, at, np.zeros(0)
    return True, xs, at, _leaving_slip(xs, at, g1, status0, g0, cap0, left0, right0, centre0, left1, right1, bound)


@numba.njit(cache=True)
def _leaving_slip(xs, at, g1, status0, g0, cap0, left0, right0, centre0, left1, right1, bound):  # pragma: no cover
    """Each leaving cell's ``bound`` (f LEAVING_PRESSURE) times its capacity times |lam (g1 - g0)| (none where
    that slip would oppose its shear): lam the fraction of the step at which the receding edge (from
    ``left0`` / ``right0`` to ``left1`` / ``right1``) passed its centre ``xs``, g1 the end's displacement
    there, ``at`` its index in the old state (GeneralSolver._leaving)."""
    terms = np.empty(xs.size)
    for k in range(xs.size):
        x = xs[k]
        if x < centre0:
            lam = (x - left0) / (left1 - left0) if left1 != left0 else 1.0
        else:
            lam = (x - right0) / (right1 - right0) if right1 != right0 else 1.0
        lam = min(max(lam, 0.0), 1.0)
        slip = lam * (g1[k] - g0[at[k]])
        if not status0[at[k]] * slip > 0.0:
            slip = 0.0
        terms[k] = bound * cap0[at[k]] * abs(slip)
    return terms

@numba.njit(cache=True)
def _end_pair(cuts0, x00, inside0, lo0, a0, b0, cuts1, x01, inside1, lo1, a1, b1, c, d, S, DS, pressure, h, terms,
              xs, near, tol, scale):  # pragma: no cover - compiled
    """Two end cells of a contact (centre c, half-width d, its pressure's arguments) set up (:func:`_end_cell_build`
    each: their cuts, centres, whether the centre lies inside the support, supports [a, b] and cells from lo)
    and their columns at ``xs``: ``scale`` (-A / pi) times each one's potential (:func:`_end_cell_kernel`).
    Returns both set-ups, the columns (xs.size, 2) and, per cell, the points inside its support other than
    its centre (their column is not set: GeneralSolver._end_columns)."""
    one = _end_cell_build(cuts0, x00, inside0, c, d, S, DS, pressure, h, a0, b0, terms)
    two = _end_cell_build(cuts1, x01, inside1, c, d, S, DS, pressure, h, a1, b1, terms)
    out = np.empty((xs.size, 2))
    pot, rest0 = _end_cell_kernel(xs, x00, h, lo0, a0, b0, one[3], one[0], one[1], one[4] if inside0 else math.nan,
                                  near, tol)
    for i in range(xs.size):
        out[i, 0] = scale * pot[i]
    pot, rest1 = _end_cell_kernel(xs, x01, h, lo1, a1, b1, two[3], two[0], two[1], two[4] if inside1 else math.nan,
                                  near, tol)
    for i in range(xs.size):
        out[i, 1] = scale * pot[i]
    return (one, two), out, (rest0, rest1)

@numba.njit(cache=True)
def _end_potential(xs, e, one, two, near, tol):  # pragma: no cover - compiled
    """:func:`_end_cell_kernel` of a state's end cell e (0: the first, ``one``; else the last, ``two``: their
    :meth:`_EndCell.kernel_arguments`) at ``xs``."""
    if e == 0:
        return _end_cell_kernel(xs, *one, near, tol)
    return _end_cell_kernel(xs, *two, near, tol)


@numba.njit(cache=True)
def _end_cell_rule(breaks, c, d, S, DS):  # pragma: no cover - compiled
    """_EndCell's rule over the pieces between ``breaks``: in theta (x = c - d cos theta), on each piece the
    Gauss-Legendre points S mapped by the quintic smoothstep (weights DS); the points and their weights in x."""
    g = S.size
    xi = np.empty((breaks.size - 1) * g)
    dxi = np.empty(xi.size)
    for j in range(breaks.size - 1):
        t0 = math.acos(min(max((c - breaks[j]) / d, -1.0), 1.0))
        t1 = math.acos(min(max((c - breaks[j + 1]) / d, -1.0), 1.0))
        for i in range(g):
            t = t0 + (t1 - t0) * S[i]
            xi[j * g + i] = c - d * math.cos(t)
            dxi[j * g + i] = d * math.sin(t) * ((t1 - t0) * DS[i])
    return xi, dxi


@numba.njit(cache=True)
def _end_cell_build(cuts, x0, own, c, d, S, DS, pressure, h, a, b, terms):  # pragma: no cover - compiled
    """_EndCell's set-up in one call: its rule over the pieces between ``cuts`` (and x0 where ``own``, the
    cell's centre inside the support: the rule is cut there too), the pressure at its points (``pressure``:
    _geometry_kernels._pressure_at's arguments) and :func:`_end_cell_setup`. Returns the points, the weights
    of the force h, their scale, the multipole coefficients and the shaped potential at x0 (NaN unless
    ``own``)."""
    xi, p, dxi = _cut_rule(cuts, x0, own, c, d, S, DS, pressure)
    w, scale, series, shaped = _end_cell_setup(xi, p, dxi, x0, h, a, b, own, terms)
    return xi, w, scale, series, shaped


@numba.njit(cache=True)
def _cut_rule(cuts, at, cut, c, d, S, DS, pressure):  # pragma: no cover - compiled
    """_EndCell's rule (:func:`_end_cell_rule`) over the pieces between ``cuts``, also cut at ``at`` where
    ``cut`` (a point inside the support: the cell's centre, or a point :meth:`_EndCell._inside` asks for), and
    the pressure at its points (``pressure``: _geometry_kernels._pressure_at's arguments), at ``at`` last where
    ``cut``: the points, the pressure and the weights."""
    if cut:
        breaks = np.empty(cuts.size + 1)  # at among the cuts, after any equal to it (as sorted() puts it)
        k = 0
        placed = False
        for i in range(cuts.size):
            if not placed and cuts[i] > at:
                breaks[k] = at
                k += 1
                placed = True
            breaks[k] = cuts[i]
            k += 1
        if not placed:
            breaks[k] = at
    else:
        breaks = cuts
    xi, dxi = _end_cell_rule(breaks, c, d, S, DS)
    points = np.empty(xi.size + 1 if cut else xi.size)
    points[:xi.size] = xi
    if cut:
        points[xi.size] = at
    return xi, _pressure_at(points, *pressure), dxi


@numba.njit(cache=True)
def _end_cell_setup(xi, p, dxi, x0, h, a, b, own, terms):  # pragma: no cover - compiled
    """_EndCell's weights of the force h at ``xi`` (pressure ``p``, and at x0 last where ``own``), their scale,
    multipole coefficients (_end_cell_series) and, where ``own``, the shaped potential at x0 (_shaped_at)."""
    n = xi.size
    total = 0.0
    for j in range(n):
        total += p[j] * dxi[j]
    scale = h / total
    w = np.empty(n)
    for j in range(n):
        w[j] = p[j] * dxi[j] * scale
    at = _shaped_at(x0, xi, p, dxi, scale, a, b) if own else math.nan
    return w, scale, _end_cell_series(xi, w, x0, h, terms), at


@numba.njit(cache=True)
def _shaped_at(x, xi, p, dxi, scale, a, b):  # pragma: no cover - compiled
    """int ln|x - xi| w(xi) dxi at a point x inside the support [a, b], from a rule cut at x (points ``xi``,
    pressure ``p`` with the pressure at x last, weights ``dxi``, w = scale p): w(x) int ln|x - xi| in closed
    form, plus the rest, (w(xi) - w(x)) ln|x - xi|, which vanishes at x like (xi - x) ln|xi - x| (a point of
    the rule at x to rounding, a piece of the cut rule shorter than rounding: the term's limit, 0)."""
    px = p[xi.size] * scale
    rest = 0.0
    for j in range(xi.size):
        d = abs(x - xi[j])
        if d > 0.0:
            rest += math.log(d) * (p[j] * scale - px) * dxi[j]
    return px * (_g(x - a) - _g(x - b)) + rest


@numba.njit(cache=True)
def _end_cell_series(xi, w, x0, h, terms):  # pragma: no cover - compiled
    """The multipole series' coefficients of _EndCell: (k-th moment of the force ``w`` at ``xi`` less that of
    the same force spread over the cell of centre x0) / k, in cells (moments over h^(k + 1))."""
    out = np.zeros(terms)
    for j in range(xi.size):
        s = (xi[j] - x0) / h
        v = w[j] / h
        for k in range(terms):
            v *= s
            out[k] += v
    for k in range(terms):
        if (k + 1) % 2 == 0:
            out[k] -= 2.0 * 0.5 ** (k + 2) / (k + 2)
        out[k] /= k + 1
    return out


@numba.njit(cache=True)
def _end_cell_kernel(xs, x0, h, lo, a, b, series, xi, w, own, near, tol):  # pragma: no cover - compiled
    """_EndCell.potential at ``xs``: the multipole series beyond ``near`` cells of x0, the rule's sum
    nearer, ``own`` at the cell's centre; the indices of the other points inside (a, b), left for the
    caller (their out is not set)."""
    out = np.empty(xs.size)
    rest = np.empty(xs.size, np.int64)
    count = 0
    for i in range(xs.size):
        x = xs[i]
        if abs(x - x0) >= near * h:
            u = h / (x - x0)
            acc = 0.0
            for m in range(series.size, 0, -1):
                acc = (acc + series[m - 1]) * u
            out[i] = -h * acc
            continue
        if a < x < b:
            if own == own and abs(x - x0) <= tol * h:
                shaped = own
            else:
                rest[count] = i
                count += 1
                continue
        else:
            shaped = 0.0
            for j in range(xi.size):
                shaped += w[j] * math.log(abs(x - xi[j]))
        out[i] = shaped - (_g(x - lo) - _g(x - lo - h))
    return out, rest[:count]


@numba.njit(cache=True)
def _g(v):  # pragma: no cover - compiled
    """v ln|v| - v (0 at 0): _toeplitz._G of one number."""
    return v * math.log(abs(v)) - v if v != 0.0 else 0.0


class _Kept:
    """What is found again for the same contacts: values per key and ``owners`` (the NormalSolutions they were
    found for, checked by identity, so that an id reused by a later object finds nothing), the oldest going
    first once their sizes add up to more than ``budget`` (None: no bound; a size is 1 an item unless given,
    bytes for the Woodbury columns). The solver's per-contact tables, end cells, edge paths and Woodbury
    columns all live in one each."""

    def __init__(self, budget: int | None):
        self.budget, self.size = budget, 0
        self._items: dict[tuple, tuple] = {}

    def get(self, key, owners: tuple):
        if len(owners) == 1:  # the common case, without the generators
            owner = owners[0]
            got = self._items.get((key, id(owner)))
            return got[1] if got is not None and got[0][0] is owner else None
        got = self._items.get((key, *map(id, owners)))
        return got[1] if got is not None and all(a is b for a, b in zip(got[0], owners)) else None

    def put(self, key, owners: tuple, value, size: int = 1):
        """Keep ``value`` (and return it)."""
        full = (key, id(owners[0])) if len(owners) == 1 else (key, *map(id, owners))
        old = self._items.pop(full, None)
        if old is not None:
            self.size -= old[2]
        self._items[full] = (owners, value, size)
        self.size += size
        while self.budget is not None and self.size > self.budget and self._items:
            self.size -= self._items.pop(next(iter(self._items)))[2]
        return value


class _EndCellLattice:
    """T' = T + the end cells' correction columns C on one take's n cells (their shear spread like the
    pressure over their supports, :func:`_end_supports`; collocation stays at the cell centres, so T' is not
    symmetric): products, and solves on a stick set by Woodbury where an end cell sticks, with the
    correction columns as more right-hand sides of the lattice's own solve. Used as the ToeplitzLattice of
    the take by the active set (which takes its tables, idx and C into the compiled iterations), the
    gross-sliding branch and the arrivals' fit (the match points' columns)."""

    def __init__(self, lat: ToeplitzLattice, ends: list, columns: np.ndarray, normal):
        self.lat = lat
        # as the ToeplitzLattice it stands in for: t (the projected gradient's bound), datum (the shift's), h
        self.t, self.datum, self.h = lat.t, lat.datum, lat.h
        self.idx = np.array([k for k, _, _ in ends], np.int64)
        self.C = np.ascontiguousarray(columns, dtype=float).reshape(-1, self.idx.size)
        self.normal = normal  # the take's contact, whose end cells these are (the arrivals' fit asks)

    def matvec(self, v: np.ndarray) -> np.ndarray:
        """T' v for v of shape (n,) (compiled: _toeplitz._end_matvec)."""
        m, spec = self.lat._circulant(v.size)
        return _end_matvec(spec, m, self.idx, self.C, np.ascontiguousarray(v, dtype=float))

    def solve_runs(self, runs, n, rhs, ones: bool = False):
        """T'_SS^-1 rhs (with ``ones``: T'_SS^-1 [1, rhs]) on the stick set of ``runs``, by Woodbury where an
        end cell sticks (compiled: _toeplitz.stick_solve); the CG iterations."""
        m, spec = self.lat._circulant(n)
        y, cg = stick_solve(self.lat.tables, spec, m, _run_array(runs), n, self.idx, self.C,
                           np.ascontiguousarray(rhs, dtype=float), CG_TOL, CG_ITERATIONS)
        return (y if ones else y[:, 1:]), cg
