"""The per-case table of a sweep: summaries of a case (reusing :mod:`halfslip.post`), the result dataset."""
from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Mapping
from typing import Any

import numpy as np
import xarray as xr

from ..errors import HalfslipInputError
from ..state import Regime
from ..variables import SUMMARY
from .spec import Sweep, _get_path, _text, _tokens

SUMMARIES: dict[str, tuple[str, str]] = {name: SUMMARY[name] for name in (
    "permanent_stick_left", "permanent_stick_right", "peak_slip_amplitude", "dissipation_per_cycle", "regime",
    "status", "run_time", "method", "done")}
"""Per-case variables of a sweep result: name -> (units, long_name)."""

REGIME_NO_RESULT = -1
"""``regime`` of a case that has not run or failed."""

_REGIME_FLAGS = np.concatenate([[REGIME_NO_RESULT], Regime.flag_values()]).astype(np.int8)
_REGIME_MEANINGS = "no_result " + Regime.flag_meanings()  # a run's names, and one for no result

NOT_RUN = "not run"
"""``status`` of a case that has not run yet."""



@dataclasses.dataclass(frozen=True)
class CaseResult:
    """What one case produced (returned by a worker to the driver)."""

    index: int
    summaries: dict[str, float]
    status: str
    method: str
    run_time: float
    full: xr.Dataset | None = None


class _CaseInterrupted(Exception):
    """A marching run inside a case was interrupted (its result is partial)."""


def _empty_summaries() -> dict[str, float]:
    return {
        "permanent_stick_left": math.nan,
        "permanent_stick_right": math.nan,
        "peak_slip_amplitude": math.nan,
        "dissipation_per_cycle": math.nan,
        "regime": REGIME_NO_RESULT,
    }


def solve_case(scene, *, per_cycle: bool = True) -> tuple[dict[str, float], str, xr.Dataset]:
    """Summaries of one scene: directly when possible, else by marching.

    Returns
    -------
    summaries : dict
        ``permanent_stick_left``, ``permanent_stick_right``, ``peak_slip_amplitude``,
        ``dissipation_per_cycle``, ``regime``.
    method : str
        ``'steady: <construction>'`` or ``'march: <method>'``.
    full : xarray.Dataset
        The steady-state or the simulation dataset.
    """
    from ..steady import steady_state

    if any(segment.kind == "cycles" for segment in scene.history.segments):
        try:
            ds = steady_state(scene, per_cycle=per_cycle)
        except HalfslipInputError:  # no direct construction for these loads: march
            pass
        else:
            summaries = _empty_summaries()
            for name in summaries:
                if name in ds:
                    summaries[name] = float(ds[name]) if name != "regime" else int(ds[name])
            return summaries, f"steady: {ds.attrs['method']}", ds
    return march_case(scene)


def march_case(scene) -> tuple[dict[str, float], str, xr.Dataset]:
    """March `scene` with :func:`~halfslip.simulator.simulate` and summarise its last cycle.

    The last cycle is the last fully stored cycle of the last ``cycles``
    segment (with ``skip_steady_cycles`` the last marched one, which the
    skipped ones repeat), found by :func:`halfslip.post.cycles` from the
    result's segment table. Every step is stored (``output.every = 1``) and
    ``slip`` is added to the stored fields. The permanent stick zone is the
    intersection of the stick zones of that cycle's steps
    (:func:`halfslip.post.permanent_stick`); the regime is gross sliding if
    any step slides, full stick if every step sticks, else partial slip
    (:func:`halfslip.cycles.window_regime`). Without a cycles segment the
    window is the last segment of the history and the per-cycle quantities
    are NaN.
    """
    from .. import post
    from ..cycles import read_segments, stick_intersection, window_regime
    from ..simulator import simulate

    fields = tuple(dict.fromkeys((*scene.output.fields, "slip")))
    scene = dataclasses.replace(scene, output=dataclasses.replace(scene.output, fields=fields, every=1))
    ds = simulate(scene)
    if not ds.attrs.get("complete", 1):
        raise _CaseInterrupted
    segments = read_segments(ds)
    cyclic = segments.cycles()
    summaries = _empty_summaries()
    if cyclic:
        table = post.cycles(ds)
        table = table.isel(cycle=np.flatnonzero(table["segment"].values == cyclic[-1]))
        if not table.sizes["cycle"]:
            raise RuntimeError("the marched result holds no complete cycle of the last cycles segment")
        part = ds.isel(t=slice(int(table["i_start"][-1]), int(table["i_stop"][-1]) + 1))
        summaries["dissipation_per_cycle"] = float(part["dissipation"][-1] - part["dissipation"][0])
        summaries["peak_slip_amplitude"] = float(post.slip_amplitude(part, cycle=None).max())
    else:  # no cycles: the last segment of the history
        steps = ds["step"].values
        part = ds.isel(t=np.flatnonzero((steps >= segments.first_step[-1]) & (steps <= segments.last_step[-1])))
    left, right = stick_intersection(part["stick_left"].values, part["stick_right"].values)
    summaries["permanent_stick_left"], summaries["permanent_stick_right"] = left, right
    summaries["regime"] = window_regime(part["regime"].values)
    return summaries, f"march: {ds.attrs['method']}", ds


# -- the result dataset ------------------------------------------------------


class _Table:
    """Per-case arrays of a sweep, filled as results arrive."""

    def __init__(self, spec: Sweep):
        n = spec.n_cases
        self.spec = spec
        self.values = {name: np.full(n, math.nan) for name in
                       ("permanent_stick_left", "permanent_stick_right", "peak_slip_amplitude",
                        "dissipation_per_cycle", "run_time")}
        self.regime = np.full(n, REGIME_NO_RESULT, dtype=np.int8)
        self.status = np.full(n, NOT_RUN, dtype=object)
        self.method = np.full(n, "", dtype=object)
        self.done = np.zeros(n, dtype=bool)

    def record(self, result: CaseResult) -> None:
        i = result.index
        for name, value in result.summaries.items():
            if name == "regime":
                self.regime[i] = value
            else:
                self.values[name][i] = value
        self.values["run_time"][i] = result.run_time
        self.status[i] = result.status
        self.method[i] = result.method
        self.done[i] = True

    def restore(self, ds: xr.Dataset) -> None:
        """Take over the finished cases of an earlier, interrupted run of the same sweep."""
        done = ds["done"].values.reshape(-1).astype(bool)
        for name, array in self.values.items():
            array[done] = ds[name].values.reshape(-1)[done]
        self.regime[done] = ds["regime"].values.reshape(-1)[done]
        self.status[done] = ds["status"].values.reshape(-1)[done].astype(object)
        self.method[done] = ds["method"].values.reshape(-1)[done].astype(object)
        self.done |= done

    @property
    def failed(self) -> int:
        return int(np.sum(self.done & (self.status != "ok")))

    def dataset(self, attrs: Mapping[str, Any]) -> xr.Dataset:
        spec = self.spec
        shape, dims = spec.shape, spec.dims

        def var(name, array):
            units, long_name = SUMMARIES[name]
            return (dims, array.reshape(shape), {"units": units, "long_name": long_name})

        data = {name: var(name, array) for name, array in self.values.items()}
        data["regime"] = var("regime", self.regime)
        data["regime"][2].update(flag_values=_REGIME_FLAGS, flag_meanings=_REGIME_MEANINGS)
        data["status"] = var("status", self.status)
        data["method"] = var("method", self.method)
        data["done"] = var("done", self.done)
        order = ["permanent_stick_left", "permanent_stick_right", "peak_slip_amplitude", "dissipation_per_cycle",
                 "regime", "status", "run_time", "method", "done"]
        ds = xr.Dataset({name: data[name] for name in order}, coords=_coordinates(spec))
        ds.attrs.update(attrs)
        return ds


def _coordinates(spec: Sweep) -> dict[str, Any]:
    attrs = {"long_name": "varied scene field"}
    if spec.kind == "grid":
        return {
            name: (name, _coordinate_values(list(values)), {**attrs, "path": path, "units": _units_of(path)})
            for name, path, values in zip(spec.names, spec.paths, spec.axes)
        }
    coords: dict[str, Any] = {"case": ("case", np.arange(spec.n_cases), {"long_name": "case number", "units": "1"})}
    for name, path in zip(spec.names, spec.paths):
        present, base = _get_path(spec.scene_data, path)
        values = [case[path] if path in case else (base if present else None) for case in spec.cases]
        coords[name] = ("case", _coordinate_values(values), {**attrs, "path": path, "units": _units_of(path)})
    return coords


def _coordinate_values(values: list[Any]) -> np.ndarray:
    """Numbers -> float64 (int64 for integers; NaN for absent); booleans -> bool; else text."""
    present = [v for v in values if v is not None]
    if present and all(isinstance(v, bool) for v in present) and len(present) == len(values):
        return np.array(values, dtype=bool)
    if present and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in present):
        if all(isinstance(v, int) for v in present) and len(present) == len(values):
            return np.array(values, dtype=np.int64)
        return np.array([math.nan if v is None else float(v) for v in values], dtype=float)
    return np.array(["" if v is None else _text(v) for v in values], dtype=object)


_UNIT_OF_FIELD = {
    "friction": "1", "E": "Pa", "nu": "1", "radius": "m", "flat_half_width": "m", "P": "N/m", "Q": "N/m",
    "M": "N", "sigma": "Pa", "duration": "s", "period": "s", "phase": "degree", "count": "1",
    "steps": "1", "steps_per_cycle": "1", "nodes": "1", "every": "1", "points": "1",
}
_LOAD_NAMES = ("P", "Q", "M", "sigma")


def _units_of(path: str) -> str:
    """Units of a scene field, from its path (docs/interface.md); '1' when unknown or dimensionless."""
    keys = [token for token in _tokens(path) if isinstance(token, str)]
    last = keys[-1]
    if last in ("amplitude", "mean") and len(keys) >= 2 and keys[-2] in _LOAD_NAMES:
        return _UNIT_OF_FIELD[keys[-2]]
    return _UNIT_OF_FIELD.get(last, "1")


def is_sweep_result(ds: xr.Dataset) -> bool:
    """True for a dataset written by :func:`sweep` (so ``halfslip plot`` can dispatch)."""
    return "sweep_hash" in ds.attrs and "done" in ds


# -- pictures -----------------------------------------------------------------


def plot_sweep(ds: xr.Dataset, path: str | os.PathLike | None = None):
    """Pictures of a sweep result: :func:`halfslip.plot.sweep_map`, saved to `path` if given.

    Kept here for scripts written against halfslip 0.1; the drawing lives in
    :mod:`halfslip.plot` (``halfslip plot MAP.h5`` draws it too).

    Parameters
    ----------
    ds : xarray.Dataset
        A result of :func:`sweep` (or read back from its file).
    path : path, optional
        Also save the figure there (format from the suffix).

    Returns
    -------
    matplotlib.figure.Figure
        Made without pyplot (no global state, Agg canvas).
    """
    from ..plot import DPI, sweep_map

    fig = sweep_map(ds)
    if path is not None:
        fig.savefig(path, dpi=DPI)
    return fig
