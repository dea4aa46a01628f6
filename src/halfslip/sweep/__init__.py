"""Batch parameter sweeps: one scene, many cases, one result dataset.

A sweep file (docs/interface.md, "Sweep file"; docs/sweeps.md) names a base
scene and the fields to change::

    scene: dovetail.yaml
    vary:                                       # a grid: the product of the lists
      loads[1].cycles.Q.amplitude: {linspace: [1.0e4, 6.0e4, 11]}
      loads[1].cycles.sigma.amplitude: [0.0, 1.0e7, 2.0e7, 4.0e7]
    # or instead of vary:  cases: [{friction: 0.5}, {friction: 0.7, geometry.radius: 0.02}]
    # optional:            set: {solver.nodes: 256}    (applied to every case)
    #                      per_cycle: false            (skip the per-cycle marching)

Each case is the base scene's parsed YAML data with the case's values put in
at their paths, dumped and read again with :func:`~halfslip.scene.parse_scene`,
so a case is validated exactly like a scene file. A case whose scene has a
cycles segment with a direct steady-state construction is solved with
:func:`~halfslip.steady.steady_state`; any other case is marched with
:func:`~halfslip.simulator.simulate` and summarised over its last cycle.

The result is one :class:`xarray.Dataset`: for a grid one dimension per varied
path (named by the path, the values as coordinate), for explicit cases a
``case`` dimension with each varied path as a coordinate on it. Its variables
are the per-case summaries (``SUMMARIES``) plus ``done``, a mask of the cases
that have run. While a sweep runs, the whole dataset is rewritten atomically
every few seconds, so an interrupted sweep rerun with the same output file
runs only the cases not yet done; ``sweep_hash`` in the attributes makes sure
it is the same sweep.

Cases run in-process (one worker), in local worker processes
(:class:`concurrent.futures.ProcessPoolExecutor`, the default) or on an
existing ``dask.distributed`` cluster (``scheduler=``). Every case is a
deterministic function of its scene, so all three give identical numbers.
"""
from __future__ import annotations

from .run import CHECKPOINT_SECONDS, CaseResult, _ProgressLine, run_case, sweep
from .spec import CASE_BYTES, Sweep, load_sweep, parse_sweep
from .table import (
    NOT_RUN,
    REGIME_NO_RESULT,
    SUMMARIES,
    is_sweep_result,
    march_case,
    plot_sweep,
    solve_case,
)

__all__ = [
    "SUMMARIES",
    "Sweep",
    "is_sweep_result",
    "load_sweep",
    "parse_sweep",
    "plot_sweep",
    "sweep",
]
