"""Run the examples and write the numbers docs/user_guide.md quotes to docs/guide_numbers.json.

    python docs/make_guide_numbers.py            # all examples (the dovetail marches in a few seconds)
    python docs/make_guide_numbers.py hertz_pad  # some of them

Each example gives the lines ``halfslip run`` prints (``summary``, without
the first line's timing and the output path) and named numbers, each
formatted as the guide writes it (``quoted``). The guide must contain every
one of them verbatim; tests/test_guide_numbers.py checks that, and that a
fresh run of the cheap examples gives the same strings.
"""
from __future__ import annotations

import json
import re
import sys
from pathlib import Path

import numpy as np

import halfslip as hs
from halfslip import post
from halfslip.cli import summarize
from halfslip.si import quantity

DOCS = Path(__file__).resolve().parent
EXAMPLES = DOCS.parent / "examples"
NUMBERS = DOCS / "guide_numbers.json"
CHEAP = ("hertz_pad", "motor")
"""Examples a test runs afresh (the exact method, well under a second each)."""


def summary_lines(ds) -> list[str]:
    """The run summary as the guide shows it: the first line without its timing, no output path."""
    lines = summarize(ds, "OUT.h5")[:-1]
    lines[0] = re.sub(r", [0-9.e+-]+ s \([0-9,]+ steps/s\)$", "", lines[0])
    return lines


def _cycle_numbers(ds) -> dict[str, str]:
    energy = post.dissipation_per_cycle(ds)["dissipation"].values
    zone = post.permanent_stick(ds)
    last = ds.isel(t=-1)
    return {
        "contact_half_width": quantity(float(last.contact_right - last.contact_left) / 2, "m"),
        "permanent_stick_half_width": quantity(float(zone["right"] - zone["left"]) / 2, "m"),
        "dissipation_per_cycle": quantity(float(energy[-1]), "J/m"),
        "dissipation_first_cycle": quantity(float(energy[0]), "J/m"),
        "skipped_cycles": str(int(ds.attrs["skipped_cycles"])),
        "steps_marched": str(int(ds.attrs["count_steps"])),
    }


def hertz_pad() -> dict:
    ds = hs.simulate(hs.load_scene(EXAMPLES / "hertz_pad.yaml"))
    numbers = _cycle_numbers(ds)
    loops = post.hysteresis_loops(ds)
    energy = post.dissipation_per_cycle(ds)
    work, solver = float(loops["work"].values[-1]), float(energy["dissipation"].values[-1])
    density = energy["dissipation_density"].isel(cycle=-1)
    stress = post.stress_range(ds)
    range_name = next(name for name in stress.data_vars if "range" in name)
    sxx = post.surface_stress(ds)
    top = post.peak(sxx)
    numbers.update({
        "loop_work": quantity(work, "J/m"),
        "loop_work_error": f"{100 * (work / solver - 1):+.2f} %".replace("-", "−"),
        "stress_range_peak": quantity(float(stress[range_name].max()), "Pa", 3),
        "peak_slip_amplitude": quantity(float(post.slip_amplitude(ds).max()), "m", 3),
        "dissipation_density_integral": quantity(float(np.trapezoid(np.nan_to_num(density.values), ds.x.values)),
                                                 "J/m"),
        "surface_stress_peak": quantity(float(top["value"]), "Pa", 3),
        "surface_stress_peak_t": f"{float(top['t']):g} s",
        "ruiz_peak_x": quantity(abs(float(post.ruiz(ds)["x_peak"])), "m", 3),
        "tangent_point_P": quantity(post.loop_tangent_point(ds)[0], "N/m", 3),
    })
    return {"summary": summary_lines(ds), "quoted": numbers}


def motor() -> dict:
    scene = hs.load_scene(EXAMPLES / "motor.yaml")
    ds = hs.simulate(scene)
    numbers = _cycle_numbers(ds)
    density = post.dissipation_per_cycle(ds)["dissipation_density"].isel(cycle=-1)
    numbers.update({
        "max_shear_ratio": f"{scene.history.max_shear_ratio(scene.friction):.2f}",
        "dissipation_density_integral": quantity(float(np.trapezoid(np.nan_to_num(density.values), ds.x.values)),
                                                 "J/m"),
    })
    return {"summary": summary_lines(ds), "quoted": numbers}


def dovetail() -> dict:
    scene = hs.load_scene(EXAMPLES / "dovetail.yaml")
    ds = hs.simulate(scene)
    numbers = _cycle_numbers(ds)
    steady = hs.steady_state(scene)
    numbers.update({
        "steady_stick_left": quantity(float(steady.permanent_stick_left), "m", 5),
        "steady_stick_right": quantity(float(steady.permanent_stick_right), "m", 5),
        "steady_dissipation_per_cycle": quantity(float(steady.dissipation_per_cycle), "J/m"),
    })
    zone = post.permanent_stick(ds)
    values = {"permanent_stick_left": float(zone["left"]), "permanent_stick_right": float(zone["right"]),
              "wall_time": float(ds.attrs["wall_time"])}
    return {"summary": summary_lines(ds), "quoted": numbers, "values": values}


def tabulated() -> dict:
    ds = hs.simulate(hs.load_scene(EXAMPLES / "tabulated.yaml"))
    wall = float(ds.attrs["wall_time"])
    return {"summary": summary_lines(ds)[:1],
            "quoted": {"steps": f"{int(ds.attrs['count_steps'])} steps", "wall_time": f"about {wall:.0f} s"},
            "values": {"wall_time": wall}}


EXAMPLE_NUMBERS = {"hertz_pad": hertz_pad, "motor": motor, "dovetail": dovetail, "tabulated": tabulated}


def main(names: list[str]) -> None:
    stored = json.loads(NUMBERS.read_text()) if NUMBERS.exists() else {}
    for name in names or list(EXAMPLE_NUMBERS):
        print(f"running {name} ...", file=sys.stderr)
        stored[name] = EXAMPLE_NUMBERS[name]()
    stored["halfslip_version"] = hs.__version__
    NUMBERS.write_text(json.dumps(stored, indent=2, ensure_ascii=False, sort_keys=True) + "\n")
    print(f"written to {NUMBERS}", file=sys.stderr)


if __name__ == "__main__":
    main(sys.argv[1:])
