"""Panel update latency in-process (issue 26, item 4): each control of each panel moved.

Builds the panels of notebooks 01, 02, 03, 04, 06, 07 and 09 as their quick mode does and
moves every control one step and back (slider: one step, dropdown: the next option, text:
its last number times 0.9), ``--repeats`` times, timing the whole update the move triggers
(``Panel.update`` through the control's observer: compute, figure, PNG encoding, tables),
without the browser. Prints the median and max per panel and control beside the goal of the
issue (thresholds eta, nu, e, s: 100 ms; segments, trajectory, latitude, duration: 300 ms)
and the load average. ``benchmarks/bench_browser.py`` measures the same moves in the page.

Usage: ``python benchmarks/bench_panels.py [--repeats N] [panel ...]`` (panel names: 01,
02, ...). Not a timed case of ``benchmarks/run.py``: :func:`cases` is empty.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import ipywidgets as widgets
import numpy as np

REPO = Path(__file__).resolve().parents[1]
THRESHOLDS = ("eta", "nu", "e_threshold", "s_threshold", "log10_rtol")
"""Controls that only re-threshold stored results (goal 100 ms); the others 300 ms."""


def cases() -> list:
    """No case for ``benchmarks/run.py``: run this benchmark alone."""
    return []


def _rocket():
    from navlib.widgets.trajectory import rocket_panel

    return rocket_panel(rate_hz=20.0)


def _observability():
    from navlib.trajectory import launcher_ascent
    from navlib.widgets.observability import observability_panel

    return observability_panel(launcher_ascent(duration_s=30.0), stride=400)


def _excitability():
    from navlib.studies import rocket
    from navlib.widgets.metrics import ExcitabilityPanel

    return ExcitabilityPanel(eta=1e-3, segments=rocket.SEGMENTS, spin_hz=2.0,
                             attitude_error="ecef", d0="global", gnss_sigma_m=5.0)


def _sensability():
    from navlib.widgets.metrics import SensabilityPanel

    return SensabilityPanel(nu=0.985, spin_hz=2.0, attitude_error="ecef", prior_update=False,
                            gnss_sigma_m=5.0, sigma_sg_ppm=5000.0)


def _ssac():
    from navlib.widgets.ssac import ssac_panel

    return ssac_panel(duration_min=10.0)


def _assess():
    from navlib import io
    from navlib.studies.assess import assess_flight
    from navlib.widgets.assess import assess_panel

    sample = REPO / "data" / "sample_flight"
    result = assess_flight(io.read_imu_csv(sample / "imu.csv"),
                           io.read_gnss_csv(sample / "gnss.csv"), model_step_s=0.02)
    return assess_panel(result)


def _plan():
    from navlib.studies.plan import plan_mission
    from navlib.widgets.plan import plan_panel

    return plan_panel(plan_mission("sounding_rocket"))


PANELS = {"01": _rocket, "02": _observability, "03": _excitability, "04": _sensability,
          "06": _ssac, "07": _assess, "09": _plan}


def _moved(control):
    """The value one step away from the control's current one (None: cannot move)."""
    if control.disabled:
        return None
    value = control.value
    if isinstance(control, widgets.FloatLogSlider):
        up = value * control.base ** control.step
        return up if np.log(up) / np.log(control.base) <= control.max + 1e-9 else \
            value / control.base ** control.step
    if isinstance(control, widgets.FloatRangeSlider):
        low, high = value
        return (low, high + control.step) if high + control.step <= control.max else \
            (low, high - control.step)
    if isinstance(control, widgets.FloatSlider):
        return value + control.step if value + control.step <= control.max else \
            value - control.step
    if isinstance(control, widgets.SelectMultiple):
        options = [o[1] if isinstance(o, tuple) else o for o in control.options]
        extra = next(o for o in options if o not in value)
        return (*value, extra)
    if isinstance(control, widgets.Dropdown):
        options = [o[1] if isinstance(o, tuple) else o for o in control.options]
        return options[(options.index(value) + 1) % len(options)]
    if isinstance(control, widgets.Text):
        parts = [p.strip() for p in value.split(",")]
        try:
            parts[-1] = f"{0.9 * float(parts[-1]):.6g}"
        except ValueError:
            return None
        return ", ".join(parts)
    return None


def measure(panel, repeats: int) -> list[dict]:
    """Move every control of ``panel`` forth and back ``repeats`` times; one row per
    control: median and max milliseconds of the update a move triggers."""
    rows = []
    for name, control in panel.controls.items():
        start_value = control.value
        target = _moved(control)
        if target is None:
            continue
        times, refused = [], 0
        for k in range(repeats):
            tic = time.perf_counter()
            control.value = target if k % 2 == 0 else start_value
            times.append(1e3 * (time.perf_counter() - tic))
            refused += f"{panel.error_prefix}:" in panel.status.value
        control.value = start_value
        goal = 100.0 if name in THRESHOLDS else 300.0
        rows.append({"control": name, "n": repeats, "median_ms": float(np.median(times)),
                     "max_ms": float(np.max(times)), "goal_ms": goal, "refused": refused})
    return rows


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=6)
    parser.add_argument("panels", nargs="*", default=list(PANELS))
    args = parser.parse_args(argv)
    import pandas as pd

    from navlib.plots.figure import detached

    frames = []
    for key in args.panels:
        tic = time.perf_counter()
        with detached():
            panel = PANELS[key]()
        built = time.perf_counter() - tic
        print(f"{key}: built in {built:.1f} s", file=sys.stderr, flush=True)
        rows = measure(panel, args.repeats)
        frames.append(pd.DataFrame(rows).assign(panel=key))
    table = pd.concat(frames)[["panel", "control", "n", "median_ms", "max_ms", "goal_ms",
                               "refused"]]
    load = os.getloadavg()
    print(f"load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f} on {os.cpu_count()} cores")
    print(table.to_string(index=False, float_format="{:.0f}".format))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
