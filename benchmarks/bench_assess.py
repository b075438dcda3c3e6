"""Long-flight assessment in bounded memory.

``assess.long_flight_<N>s``: :func:`navlib.studies.assess.assess_flight` of a generated
multicopter flight (``tests/support/flights.py``: pad, climb, figure-eight survey) of N seconds at
250 Hz with 5 Hz GNSS and the ``pixhawk_mems`` errors. The flight is generated and saved by
one subprocess; a fresh subprocess loads it and assesses it, and reports its wall time and
its peak resident memory (``resource.getrusage(RUSAGE_SELF).ru_maxrss``, measured, not
estimated; the loaded records are inside it). Goals: 30 minutes under 60 s and 2 GB.

``assess.rocket_10min``: the same for a generated 10-minute rocket flight at 100 Hz
(``data/missions/hpr_rocket.toml`` with a 6 s boost to about 5 km, a drogue at 30 m/s that
spins at 1 Hz and swings 40 deg, the main at 900 m at 1.9 m/s: boost, coast, apogee and a
tumbling descent to touchdown), 5 Hz GNSS and ``pixhawk_mems`` errors; the assessment
starts from the 2 s on the pad. Goals: under 20 s and 1 GB.

``assess.model_step_error``: what the 50 Hz model steps of the assessment
(``MODEL_STEP_S``) change in the discretised 21-state model of the sounding rocket at 1 Hz
(largest relative difference of ``F`` and of each epoch's ``Q`` against every-IMU-step).

``assess.altos_<flight>`` (issue 37, goal 3 s warm): each shared AltOS rocket flight
(``../shared/data/altos``, found as ``tests/support/locations.py`` finds it; no rows when absent)
assessed in this process after one warm-up, as the CLI does per flight
(:func:`navlib.reports.fleet.assess_log`: read, :func:`~navlib.studies.assess.assess_flight`,
the HTML page); ``time_s`` is the best of 3 of the whole, ``read_s``, ``assess_s`` and
``page_s`` the best of each part, ``cli_s`` the command line's wall time for the flight in a
new process (interpreter, imports, numba caches loaded; the second of two runs).

Run alone (``python benchmarks/bench_assess.py [seconds ...]``) for the table with memory,
``python benchmarks/bench_assess.py rocket`` for the rocket row,
``python benchmarks/bench_assess.py altos`` for the shared AltOS flights.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _harness import Case

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
GOAL_S = {1800: 60.0}
GOAL_MB = 2048.0
ROCKET_GOAL_S, ROCKET_GOAL_MB = 20.0, 1024.0
ALTOS_GOAL_S = 3.0
ROCKET_10MIN = {"phase.1.burn_time_s": 6.0, "phase.1.acceleration_m_s2": 90.0,
                "phase.3.rate_m_s": 30.0, "phase.3.spin_hz": 1.0, "phase.3.swing_deg": 40.0,
                "phase.3.swing_period_s": 4.0, "phase.4.height_m": 900.0,
                "phase.4.rate_m_s": 1.9}
"""Changes to the hpr_rocket mission for a 10-minute flight with a tumbling descent."""

_GENERATE = """
import sys, numpy as np
sys.path.insert(0, {tests!r})
from support.flights import multicopter, records
imu, gnss = records(multicopter({duration}, 250.0, pad_s=20.0), seed=1)
np.savez({path!r}, imu=imu.to_numpy(), gnss=gnss.to_numpy(),
         imu_cols=list(imu.columns), gnss_cols=list(gnss.columns))
"""

_GENERATE_ROCKET = """
import sys, numpy as np
sys.path.insert(0, {tests!r})
from support.flights import records
from navlib.trajectory.mission import from_mission, with_values
truth = from_mission(with_values("hpr_rocket", {changes!r}))
imu, gnss = records(truth, seed=1)
np.savez({path!r}, imu=imu.to_numpy(), gnss=gnss.to_numpy(),
         imu_cols=list(imu.columns), gnss_cols=list(gnss.columns))
"""

_ASSESS = """
import json, resource, time, warnings
import numpy as np, pandas as pd
from navlib.studies.assess import assess_flight
d = np.load({path!r})
imu = pd.DataFrame(d["imu"], columns=[str(c) for c in d["imu_cols"]])
gnss = pd.DataFrame(d["gnss"], columns=[str(c) for c in d["gnss_cols"]])
start = time.perf_counter()
with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    result = assess_flight(imu, gnss, preset="pixhawk_mems")
elapsed = time.perf_counter() - start
peak_kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(json.dumps({{"time_s": elapsed, "peak_mb": peak_kb / 1024.0, "samples": len(imu),
                  "segments": len(result.segment_table), "epochs": int(result.model.t.size),
                  "phases": " ".join(result.segment_table.phase)}}))
"""


def _generate_and_assess(generate: str, **keywords) -> dict:
    """Run the script ``generate`` (formatted with ``keywords`` and the ``path`` it writes),
    then assess the flight in a fresh process; wall time and peak memory of the latter."""
    with tempfile.TemporaryDirectory() as tmp:
        path = str(Path(tmp) / "flight.npz")
        subprocess.run([sys.executable, "-c", generate.format(
            tests=str(ROOT / "tests"), path=path, **keywords)], check=True, timeout=1800)
        out = subprocess.run([sys.executable, "-c", _ASSESS.format(path=path)], check=True,
                             capture_output=True, text=True, timeout=1800)
    return json.loads(out.stdout.strip().splitlines()[-1])


def measure(duration_s: float) -> dict:
    """The generated multicopter flight of ``duration_s``, assessed."""
    row = _generate_and_assess(_GENERATE, duration=float(duration_s))
    row["duration_s"] = duration_s
    row["mb_per_flight_s"] = row["peak_mb"] / duration_s
    return row


def measure_rocket() -> dict:
    """The generated 10-minute rocket flight with a tumbling descent, assessed."""
    return _generate_and_assess(_GENERATE_ROCKET, changes=ROCKET_10MIN)


def model_step_error() -> dict:
    """Relative change of F and Q (1 Hz epochs, sounding rocket) with 50 Hz model steps."""
    import numpy as np

    from navlib.models.ecef import ecef21_at_epochs
    from navlib.studies.assess import MODEL_STEP_S
    from navlib.trajectory import sounding_rocket

    traj = sounding_rocket()
    full = ecef21_at_epochs(traj, 1.0)
    coarse = ecef21_at_epochs(traj, 1.0, max_step_s=MODEL_STEP_S)
    dF = np.abs(coarse.F - full.F).max() / np.abs(full.F).max()
    dQ = (np.abs(coarse.Q - full.Q).max(axis=(1, 2)) / np.abs(full.Q).max(axis=(1, 2))).max()
    return {"F_rel": float(dF), "Q_rel": float(dQ)}


def _long_case(duration_s: int) -> Case:
    seen = {}

    def run():
        seen.update(measure(duration_s))

    def extra(_elapsed):
        return {"assess_s": seen["time_s"], "peak_mb": seen["peak_mb"],
                "mem_ratio": seen["peak_mb"] / GOAL_MB}

    return Case(f"assess.long_flight_{duration_s}s", f"{duration_s} s at 250 Hz", run,
                GOAL_S.get(duration_s, duration_s / 30.0), repeat=1, warmup=False,
                extra=extra, notes="time_s includes generating the flight")


def _rocket_case() -> Case:
    seen = {}

    def run():
        seen.update(measure_rocket())

    def extra(_elapsed):
        return {"assess_s": seen["time_s"], "peak_mb": seen["peak_mb"],
                "mem_ratio": seen["peak_mb"] / ROCKET_GOAL_MB, "phases": seen["phases"]}

    return Case("assess.rocket_10min", "10 min at 100 Hz, tumbling descent", run,
                ROCKET_GOAL_S, repeat=1, warmup=False, extra=extra,
                notes="time_s includes generating the flight")


def altos_logs() -> list[Path]:
    """The shared AltOS flight logs (none when the shared folder is absent)."""
    sys.path.insert(0, str(ROOT / "tests"))
    from support.locations import SHARED_DATA

    return sorted((SHARED_DATA / "altos").glob("*.csv"))


def _cli_seconds(log: Path) -> float:
    """Wall time of ``python -m navlib assess LOG`` (one process, synchronous scheduler: a
    fresh interpreter, its imports and the page written), the second of two runs."""
    with tempfile.TemporaryDirectory() as out:
        command = [sys.executable, "-m", "navlib", "assess", str(log), "--output", out,
                   "--scheduler", "synchronous"]
        for _ in range(2):
            start = time.perf_counter()
            subprocess.run(command, check=True, capture_output=True, timeout=600)
            elapsed = time.perf_counter() - start
    return elapsed


def _altos_case(log: Path) -> Case:
    import warnings

    from navlib.io import read_log
    from navlib.reports.pages import flight_page
    from navlib.studies.assess import assess_flight

    parts: dict[str, float] = {}

    def timed(name, func, *args):
        start = time.perf_counter()
        out = func(*args)
        parts[name] = min(parts.get(name, float("inf")), time.perf_counter() - start)
        return out

    def run():
        # the steps of navlib.reports.fleet.assess_log (its summary row aside), each timed
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            imu, gnss = timed("read_s", read_log, str(log))
            result = timed("assess_s", assess_flight, imu, gnss)
            timed("page_s", flight_page, str(log), result, [])

    def extra(_elapsed):
        return {**parts, "cli_s": _cli_seconds(log)}

    name = log.stem.split("-serial-")[-1]
    return Case(f"assess.altos_{name}", f"AltOS {log.stem[:10]}, read + assess + page", run,
                ALTOS_GOAL_S, extra=extra)


def cases():
    return [_long_case(1800), _rocket_case(),
            Case("assess.model_step_error", "rocket, 1 Hz epochs", model_step_error, 5.0,
                 repeat=1, warmup=False, extra=lambda _e: model_step_error()),
            *(_altos_case(log) for log in altos_logs())]


def _altos_table() -> int:
    import pandas as pd
    from _harness import time_case

    rows = [time_case(_altos_case(log)) for log in altos_logs()]
    if not rows:
        print("no shared AltOS flights (../shared/data/altos or $NAVLIB_SHARED_DIR/data/altos)",
              file=sys.stderr)
        return 1
    with pd.option_context("display.width", 200, "display.max_columns", 20,
                           "display.float_format", "{:.3g}".format):
        print(pd.DataFrame(rows).to_string(index=False))
    return 0


def main(argv: list[str]) -> int:
    import pandas as pd

    if argv == ["altos"]:
        return _altos_table()
    if argv == ["rocket"]:
        row = measure_rocket()
        print(f"10-minute rocket flight ({row['samples']} samples): assessed in "
              f"{row['time_s']:.1f} s (goal {ROCKET_GOAL_S:g} s), peak {row['peak_mb']:.0f} MB "
              f"(goal {ROCKET_GOAL_MB:g} MB); phases {row['phases']}")
        return 0
    durations = [float(a) for a in argv] or [60.0, 600.0, 1800.0]
    rows = []
    for d in durations:
        t0 = time.perf_counter()
        row = measure(d)
        row["total_s"] = time.perf_counter() - t0
        row["goal_s"] = GOAL_S.get(int(d), float("nan"))
        row["goal_mb"] = GOAL_MB
        rows.append(row)
        print(f"{d:.0f} s flight: assessed in {row['time_s']:.1f} s, peak "
              f"{row['peak_mb']:.0f} MB", file=sys.stderr, flush=True)
    table = pd.DataFrame(rows)[["duration_s", "samples", "epochs", "segments", "time_s",
                                "goal_s", "peak_mb", "goal_mb", "mb_per_flight_s",
                                "total_s"]]
    with pd.option_context("display.width", 200, "display.float_format", "{:.4g}".format):
        print(table.to_string(index=False))
        print("model steps of", model_step_error())
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(HERE))
    raise SystemExit(main(sys.argv[1:]))
