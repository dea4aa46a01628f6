"""The lattice's own response to a stick edge: where a stick edge lies within its cells.

    python benchmarks/calibrate_edge_rule.py            # fit, then check on other cases (~1 min)

The constants EDGE_RULE, EDGE_RULE_RHO, END_RULE_WITHIN and END_RULE_END of
halfslip.solvers.general come from here (and EDGE_RULE_REACH from its last table).

Inside the contact. Near a stick-slip boundary c the traction margin
f p - abs(q) vanishes like K sqrt(distance to c) on the stick side (J1 and J2
near their stick edges; any partial-slip state locally). The lattice carries a
constant shear per cell, and its discrete solution near c is not the cell
average of that square root: the outermost stick cell k slips once c is 0.17
of a cell inside its centre, and the ratio of its margin to its inner
neighbour's, rho = m_k / m_(k-1) (m = f cap - s q), runs from 0 to
EDGE_RULE_RHO ~ 0.70 while c crosses one cell. The map u(rho) = (c - x_k) / h
(outward, in cells) depends on nothing else to leading order: the kernel's
cell integrals are h times a fixed sequence plus a constant (absorbed by the
rigid shift), so the local discrete problem is the same at every scale. It is
measured on J1 (Hertz, closed form) at 2048 nodes with the stick edge far from
the contact edges and the centre, fitted by a quartic in rho.

At a contact edge E. A slip zone narrower than about two cells is placed by
the local Cattaneo form, (x - E) m^2 = x - c (m the margin relative to f cap),
extrapolated from the two outermost stick cells: within the end cell when it
sticks ("within"), or beyond the end cell when it alone slips ("end"). Its
discrete solution depends on the slip zone's width and on where E falls in the
lattice (the end cell's support is 0.5 to 1.5 cells): the error of that form
(up to 0.2 of a cell) is a smooth function of its own estimate w_est = E - c_est
and of the distance u_e from the end cell's centre to E, both in cells, fitted
by a polynomial of total degree END_DEGREE in (w_est, u_e), per branch, on J1
(Hertz, 1024 nodes, the lattice shifted against the contact through a cell).
"""
from __future__ import annotations

import argparse

import numpy as np
from scipy.optimize import brentq

from halfslip.geometry import Hertz, NormalProblem, RoundedPunch
from halfslip.solvers import general
from halfslip.solvers.general import GeneralSolver
from halfslip.state import Loads

A = 4 * (1 - 0.3**2) / 200e9
F = 0.6
P0 = 1.0e5
PROFILES = {"hertz": Hertz(radius=50e-3), "punch": RoundedPunch(flat_half_width=0.2e-3, radius=10e-3)}
#: Fit degree inside the contact (quartic: residual 1e-4 of a cell at 2048 nodes; cubic 7e-4, quadratic 7e-3).
DEGREE = 4
#: Total degree of the contact-edge fits (5: 95th percentile of the residual 0.02 of a cell, 4: 0.03; the largest
#: residual, 0.05 - 0.09, is where the margins barely change with the slip zone's width, before the branch changes).
END_DEGREE = 5
#: Cells the stick edge keeps from the contact edge and from the centre (the local form holds).
CLEAR = 8


def pairs(state, left, right, f=F):
    """(rho, u) at both stick edges of ``state`` whose exact positions are ``left``, ``right``."""
    m = state.memory
    x, h = m.x, m.spacing
    qmax = f * m.capacity
    stick = np.flatnonzero(m.status == 0)
    out = []
    for k, step, c in ((stick[-1], -1, right), (stick[0], 1, left)):
        nb, inner = k - step, k + step
        if not (0 <= nb < x.size and 0 <= inner < x.size) or m.status[nb] == 0 or m.status[inner] != 0:
            continue
        if min(nb, x.size - 1 - nb) < CLEAR or abs(x[k] - m.normal.center) < CLEAR * h:
            continue
        sgn = m.status[nb]
        margin = lambda j: qmax[j] - sgn * m.q[j]  # noqa: E731
        out.append((margin(k) / margin(inner), -step * (c - x[k]) / h))
    return out


def sweep(kind, nodes, lo, hi, num, unload=None):
    """J1 from (P0, 0) to Q = r f P0, r in [lo, hi] (or, with ``unload`` = Q_max / f P0, J2 back from it):
    (rho, u) at the stick edges away from the contact edges."""
    problem = NormalProblem(PROFILES[kind], A)
    solver = GeneralSolver(problem, F, nodes, estimate=False)
    loaded, _ = solver.step(solver.initial_state(), 1.0, Loads(P0, 0.0, 0.0, 0.0))
    if unload is not None:
        loaded, _ = solver.step(loaded, 2.0, Loads(P0, unload * F * P0, 0.0, 0.0))
    out = []
    for r in np.linspace(lo, hi, num):
        state, _ = solver.step(loaded, 3.0, Loads(P0, r * F * P0, 0.0, 0.0))
        if unload is None:
            c = float(problem.half_width(P0 - r * P0))
        else:
            c = float(problem.half_width(P0 - (unload - r) * P0 / 2))
        out += pairs(state, -c, c)
    return np.array(out).reshape(-1, 2)


def end_sweep(kind, nodes, shifts, widths):
    """J1 with slip zones of ``widths`` cells at the contact edges, the lattice's width set so that the edge
    falls at ``shifts`` places within its cells: rows (w, w_est, u_e, branch) at the right edge (cells;
    branch 0 within the end cell, 1 the end cell alone slipping, 2 other). w_est is the local form's own
    estimate: the solver's END_RULE_* corrections are switched off here (they are what is fitted)."""
    saved = dict(general._END_RULES)
    general._END_RULES.update({key: np.zeros_like(value) for key, value in saved.items()})
    try:
        return _end_rows(kind, nodes, shifts, widths)
    finally:
        general._END_RULES.update(saved)


def _end_rows(kind, nodes, shifts, widths):
    problem = NormalProblem(PROFILES[kind], A)
    a = float(problem.half_width(P0))
    rows = []
    for shift in np.linspace(1.0, 1.0 + 4.0 / nodes, shifts):
        solver = GeneralSolver(problem, F, nodes, width=2 * a * shift, estimate=False)
        loaded, _ = solver.step(solver.initial_state(), 1.0, Loads(P0, 0.0, 0.0, 0.0))
        mem = loaded.memory
        h, E = mem.spacing, loaded.contact_right
        u_e = (E - mem.x[-1]) / h
        for w in np.linspace(0.002, 2.3, widths):
            c = E - w * h
            r = brentq(lambda r: float(problem.half_width(P0 * (1 - r))) - c, 1e-14, 0.5, xtol=1e-15)
            state, _ = solver.step(loaded, 2.0, Loads(P0, r * F * P0, 0.0, 0.0))
            k = np.flatnonzero(state.memory.status == 0)[-1]
            n = state.memory.q.size
            rows.append((w, (E - state.stick_right) / h, u_e, 0 if k == n - 1 else 1 if k == n - 2 else 2))
    return np.array(rows)


def _design(w, u, degree):
    return np.array([w**i * u**j for i in range(degree + 1) for j in range(degree + 1 - i)]).T


def _matrix(coef, degree):
    """The fit's coefficients as c[i, j] of w^i u^j (numpy.polynomial.polynomial.polyval2d)."""
    c = np.zeros((degree + 1, degree + 1))
    k = 0
    for i in range(degree + 1):
        for j in range(degree + 1 - i):
            c[i, j] = coef[k]
            k += 1
    return c


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--nodes", type=int, default=2048)
    args = ap.parse_args(argv)
    np.set_printoptions(precision=6, suppress=False, linewidth=120)
    # inside: two slip-zone sizes, each edge swept through several cells
    data = np.vstack([sweep("hertz", args.nodes, 0.30, 0.3015, 161), sweep("hertz", args.nodes, 0.60, 0.6015, 161)])
    coef = np.polyfit(data[:, 0], data[:, 1], DEGREE)
    rho_max = float(data[:, 0].max())
    fit = np.abs(np.polyval(coef, data[:, 0]) - data[:, 1]).max()
    print(f"inside: J1 Hertz, {args.nodes} nodes, {len(data)} edges: u in [{data[:, 1].min():.4f}, "
          f"{data[:, 1].max():.4f}] cells, rho in [{data[:, 0].min():.4f}, {rho_max:.4f}]; largest residual of the "
          f"fit {fit:.1e} cells")
    print("EDGE_RULE = (" + ", ".join(f"{c:.6f}" for c in coef) + ")  # highest power first")
    print(f"EDGE_RULE_RHO = {rho_max:.4f}")
    # at the contact edges
    ends = end_sweep("hertz", 1024, 41, 80)
    fits = {}
    for branch, name in ((0, "END_RULE_WITHIN"), (1, "END_RULE_END")):
        s = ends[ends[:, 3] == branch]
        X = _design(s[:, 1], s[:, 2], END_DEGREE)
        c, *_ = np.linalg.lstsq(X, s[:, 0] - s[:, 1], rcond=None)
        r = np.abs(s[:, 0] - s[:, 1] - X @ c)
        raw = np.abs(s[:, 0] - s[:, 1])
        fits[branch] = _matrix(c, END_DEGREE)
        print(f"\ncontact edge, {name}: J1 Hertz, 1024 nodes, {len(s)} edges, w_est in [{s[:, 1].min():.3f}, "
              f"{s[:, 1].max():.3f}]: the local form's error 95th percentile {np.percentile(raw, 95):.3f}, largest "
              f"{raw.max():.3f} cells; the fit's residual {np.percentile(r, 95):.3f}, {r.max():.3f}")
        print(f"{name} = (  # c[i][j] of w_est^i u_e^j")
        for row in fits[branch]:
            print("    (" + ", ".join(f"{v:.6e}" for v in row) + "),")
        print(")")
    print("\nthe same fits on other cases (distance of the rule's edge from the exact one, cells):")
    print("| case | edges | this rule: max | median | the rule of 0.3.3-0.3.6: max | median | largest rho |\n"
          "|---|---:|---:|---:|---:|---:|---:|")
    old = lambda rho: rho**2 / (1 - rho**2)  # noqa: E731  (the rule of 0.3.3 - 0.3.6)
    for name, d in (
        ("J1 Hertz 256 nodes", sweep("hertz", 256, 0.30, 0.36, 121)),
        ("J1 Hertz 1024 nodes", sweep("hertz", 1024, 0.50, 0.505, 121)),
        ("J1 punch 256 nodes", sweep("punch", 256, 0.50, 0.56, 121)),
        ("J1 punch 1024 nodes", sweep("punch", 1024, 0.90, 0.903, 121)),
        ("J2 Hertz 256 nodes (Q_max 0.8 f P)", sweep("hertz", 256, 0.30, 0.36, 121, unload=0.8)),
        ("J2 punch 512 nodes (Q_max 0.8 f P)", sweep("punch", 512, 0.30, 0.33, 121, unload=0.8)),
        ("J1 Hertz 128 nodes, Q = 0.1 .. 0.95 f P", sweep("hertz", 128, 0.1, 0.95, 300)),
        ("J1 punch 128 nodes, Q = 0.1 .. 0.95 f P", sweep("punch", 128, 0.1, 0.95, 300)),
        ("J1 punch 256 nodes, Q = 0.1 .. 0.95 f P", sweep("punch", 256, 0.1, 0.95, 300)),
    ):
        e = np.abs(np.polyval(coef, np.minimum(d[:, 0], rho_max)) - d[:, 1])
        e0 = np.abs(old(d[:, 0]) - d[:, 1])
        print(f"| {name} | {len(d)} | {e.max():.3f} | {np.median(e):.3f} | {e0.max():.3f} | {np.median(e0):.3f} | "
              f"{d[:, 0].max():.3f} |")
    print("\n| contact-edge case | branch | edges | this rule: 95th pct | max | the local form alone: 95th pct | max |\n"
          "|---|---|---:|---:|---:|---:|---:|")
    for name, d in (("J1 Hertz 256 nodes", end_sweep("hertz", 256, 21, 40)),
                    ("J1 punch 256 nodes", end_sweep("punch", 256, 21, 40))):
        for branch, label in ((0, "within"), (1, "end")):
            s = d[d[:, 3] == branch]
            w = s[:, 1] + np.polynomial.polynomial.polyval2d(s[:, 1], s[:, 2], fits[branch])
            e, e0 = np.abs(w - s[:, 0]), np.abs(s[:, 1] - s[:, 0])
            print(f"| {name} | {label} | {len(s)} | {np.percentile(e, 95):.3f} | {e.max():.3f} | "
                  f"{np.percentile(e0, 95):.3f} | {e0.max():.3f} |")


if __name__ == "__main__":
    main()
