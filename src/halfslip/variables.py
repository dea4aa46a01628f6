"""Units and long names of every variable halfslip stores: one table.

A result of :func:`halfslip.simulate` (``RUN``: per stored step, per-point
fields, the segment table, the final scalars) and the per-case or steady
summaries of :func:`halfslip.sweep` and :func:`halfslip.steady_state`
(``SUMMARY``) take their ``units`` and ``long_name`` attributes from here
(:func:`attrs`). Derived quantities of :mod:`halfslip.post` name their own,
next to the formula that computes them.
"""
from __future__ import annotations

SUMMARY: dict[str, tuple[str, str]] = {
    "permanent_stick_left": ("m", "left edge of the permanent stick zone"),
    "permanent_stick_right": ("m", "right edge of the permanent stick zone"),
    "peak_slip_amplitude": ("m", "peak slip amplitude in the steady cycle"),
    "slip_amplitude": ("m", "slip amplitude in the steady cycle"),
    "dissipation_per_cycle": ("J/m", "energy dissipated per steady cycle"),
    "regime": ("1", "steady-cycle regime"),
    "status": ("1", "'ok', 'not run', or the one-line error of the case"),
    "run_time": ("s", "wall-clock time of the case"),
    "method": ("1", "how the case was solved: 'steady: <construction>' or 'march: <method>'"),
    "done": ("1", "the case has run (successfully or not)"),
}
"""Scalars of a steady state, and per-case variables of a sweep: name -> (units, long_name)."""

SEGMENT: dict[str, tuple[str, str]] = {
    "segment_kind": ("1", "kind of the load segment (flag_meanings)"),
    "segment_first_step": ("1", "index of the load history step where the segment begins"),
    "segment_last_step": ("1", "index of the load history step where the segment ends"),
    "segment_t_start": ("s", "time where the segment begins"),
    "segment_t_stop": ("s", "time where the segment ends"),
    "segment_period": ("s", "cycle period (NaN unless cycles)"),
    "segment_cycle_count": ("1", "number of cycles (0 unless cycles)"),
    "segment_steps_per_cycle": ("1", "load history steps per cycle (0 unless cycles)"),
    "segment_cycles_skipped": ("1", "cycles not marched: repeats of the last marched cycle"),
    "segment_skip_t_start": ("s", "end of the last marched cycle, where the skipped cycles start (NaN if none)"),
    "segment_skip_dissipation": ("J/m", "energy dissipated by the skipped cycles (0 if none)"),
}
"""The segment table of a run (dimension ``segment``, :mod:`halfslip.cycles`)."""

RUN: dict[str, tuple[str, str]] = {
    "t": ("s", "time"),
    "step": ("1", "index of the step in the load history"),
    "x": ("m", "surface coordinate"),
    "P": ("N/m", "normal load"),
    "Q": ("N/m", "shear force"),
    "M": ("N", "moment about the pad axis"),
    "sigma": ("Pa", "differential bulk tension sigma_A - sigma_B"),
    "contact_left": ("m", "left contact edge"),
    "contact_right": ("m", "right contact edge"),
    "stick_left": ("m", "left stick-zone edge"),
    "stick_right": ("m", "right stick-zone edge"),
    "regime": ("1", "contact regime"),
    "rigid_shift": ("m", "rigid tangential displacement of pad relative to substrate"),
    "dissipation": ("J/m", "frictional energy dissipated since the start"),
    "p": ("Pa", "contact pressure"),
    "q": ("Pa", "shear traction exerted by the pad on the substrate"),
    "slip": ("m", "accumulated slip since the point entered contact"),
    "converged": ("1", "whether the step met the method's own tolerance (1) or not (0)"),
    "residual": ("1", "violation of the step's checks relative to their tolerance (<= 1 when converged)"),
    "error_estimate": ("1", "estimated error of the stick edges relative to the contact width (general solver: "
                            "distance to the half-resolution solution; 0 for the exact method)"),
    "shear_error_estimate": ("1", "estimated error of the shear traction, int abs(q - q_exact) dx relative to f P "
                                  "(general solver: distance to the half-resolution solution; 0 for the exact method)"),
    "stick_intervals": ("1", "number of stick intervals (0 when nothing sticks)"),
    "state": ("1", "what the surface point did in the step"),
    "final_t": ("s", "time of the run's last state (after skipped cycles: the end they stand for)"),
    "final_dissipation": ("J/m", "frictional energy dissipated up to the run's last state, skipped cycles included"),
    "permanent_stick_left": SUMMARY["permanent_stick_left"],
    "permanent_stick_right": SUMMARY["permanent_stick_right"],
    **SEGMENT,
}
"""Every variable of a run result: name -> (units, long_name)."""


def attrs(name: str, table: dict[str, tuple[str, str]] = RUN, **extra) -> dict:
    """``{"units": ..., "long_name": ..., **extra}`` of variable `name` in `table`."""
    units, long_name = table[name]
    return {"units": units, "long_name": long_name, **extra}
