"""Cost of the closed-loop EKF per IMU sample (issues 26, 37: goal < 10 us at equal accuracy).

* ``ekf.rocket_per_sample``: the 86 s sounding-rocket flight (8601 IMU samples at 100 Hz,
  21-state ECEF model of España et al., GNSS position at 1 Hz), as ``filters.ekf_rocket``
  in ``bench_filters.py``; ``us_per_sample`` is the time over the samples.
* ``ekf.launcher_per_sample``: the launcher error-state EKF with an update at every sample
  (40 s of the ascent at 200 Hz, INS/GPS/att, GAP Markov biases, 0.1 s feedback windows,
  one BLAS thread), as the noisy run of notebook 05.

* the table after the rocket row: CPU time of the first rocket EKF in a fresh process with
  an empty numba cache (``NUMBA_CACHE_DIR``), i.e. the compile of every kernel it runs
  (strapdown, Kalman update and propagation, the sparse discretisation). The cold report
  budget of issue 37 must not grow, so its goal is the time measured before the sparse
  kernels (17.3 and 20.6 CPU-s in two runs on 2026-12-04 at load 7-8 on 2 cores). The
  rocket's run is one compiled loop since (:mod:`navlib.filters.ekf_loop`), whose compile
  (with its callees) adds about 14 CPU-s here (16.1 -> 30.4 CPU-s, load 1); no notebook of
  the report runs a 21-state EKF, so the report does not compile it.

Sensor simulation is outside the timing of the rocket row (the launcher row includes it, as
:func:`navlib.filters.simulate_ekf` does). Times are the best of 3 in wall time
(``us_per_sample``) and in this process's CPU time (``cpu_us_per_sample``,
:func:`time.process_time`), which other processes on the shared cores change less; read
``uptime`` beside them.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from functools import cache
from pathlib import Path

import pandas as pd
from _harness import Case
from _harness import rocket_flight as _rocket
from threadpoolctl import threadpool_limits

from navlib import filters, sensors, strapdown
from navlib.trajectory import launcher_ascent

GOAL_S_PER_SAMPLE = 10e-6
ROCKET_SAMPLES = 8601
LAUNCHER_SAMPLES = 8001
COMPILE_BEFORE_CPU_S = 17.3
_CPU: dict[str, float] = {}


@cache
def _rocket_data(seed: int = 1):
    traj = _rocket()
    spec = sensors.load_preset("motionpak_tactical")
    return (traj, sensors.simulate_imu(traj, spec, seed=seed),
            sensors.simulate_gnss(traj, spec, seed=seed + 1))


def _ekf_rocket():
    traj, imu, gnss = _rocket_data()
    return filters.ekf(imu, gnss, initial=strapdown.StrapdownState.from_trajectory(traj),
                       model="ecef21", model_options={"sensors": "motionpak_tactical"})


@cache
def _ascent():
    return launcher_ascent(duration_s=40.0)


def _ekf_launcher():
    short = _ascent()
    with threadpool_limits(1):
        return filters.simulate_ekf(short, solution="ins_gps_att", biases="GAP",
                                    bias_model="markov", model_options={"a1_sign": 1.0},
                                    seed=0, gnss_rate_hz=short.rate_hz, window_s=0.1)


def _cpu_timed(name: str, func):
    """``func`` recording the least CPU time of its calls under ``name``."""
    def timed():
        start = time.process_time()
        out = func()
        _CPU[name] = min(_CPU.get(name, float("inf")), time.process_time() - start)
        return out
    return timed


def _per_sample(name: str, samples: int):
    return lambda best: {"us_per_sample": best / samples * 1e6,
                         "cpu_us_per_sample": _CPU[name] / samples * 1e6,
                         "goal_us": GOAL_S_PER_SAMPLE * 1e6}


_FIRST_RUN = """
import sys, time
sys.path.insert(0, sys.argv[1])
import bench_ekf
bench_ekf._rocket_data()
start = time.process_time()
bench_ekf._ekf_rocket()
print(time.process_time() - start)
"""


def _first_compile() -> pd.DataFrame:
    """CPU time of the first rocket EKF in a new process with an empty numba cache."""
    with tempfile.TemporaryDirectory() as empty:
        run = subprocess.run([sys.executable, "-c", _FIRST_RUN, str(Path(__file__).parent)],
                             env={**os.environ, "NUMBA_CACHE_DIR": empty}, check=True,
                             capture_output=True, text=True)
    cpu = float(run.stdout.split()[-1])
    return pd.DataFrame([{"what": "first rocket EKF, empty numba cache", "cpu_s": cpu,
                          "goal_cpu_s": COMPILE_BEFORE_CPU_S,
                          "ratio": cpu / COMPILE_BEFORE_CPU_S}])


def cases() -> list[Case]:
    rocket, launcher = "ekf.rocket_per_sample", "ekf.launcher_per_sample"
    return [
        Case(rocket, "86 s @ 100 Hz, 21 states, 1 Hz GNSS", _cpu_timed(rocket, _ekf_rocket),
             ROCKET_SAMPLES * GOAL_S_PER_SAMPLE, extra=_per_sample(rocket, ROCKET_SAMPLES),
             table=_first_compile),
        Case(launcher, "40 s @ 200 Hz, 18 states, update every sample",
             _cpu_timed(launcher, _ekf_launcher), LAUNCHER_SAMPLES * GOAL_S_PER_SAMPLE,
             extra=_per_sample(launcher, LAUNCHER_SAMPLES)),
    ]
