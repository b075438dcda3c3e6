"""Benchmarks of navlib.filters (issue 5 performance goals).

* ``filters.ekf_rocket``: the closed-loop EKF (21-state ECEF model, España et al.) over the
  86 s sounding-rocket flight — 8601 IMU samples at 100 Hz, GNSS position at 1 Hz — on
  simulated MotionPak-class data. Goal 1 s. Sensor simulation is outside the timing.
* ``filters.linear_mc_launcher``: 100 Monte-Carlo runs of the linear error-state filter on
  the launcher mission (150 s at 200 Hz, INS/GPS/att + RT with G, A, P Markov biases: 28
  states, 12 measurements at every sample), from building the error model to the last run:
  discretisation, the shared covariance recursion and gains, the 100 runs. Goal 30 s.

The comparison with ``python-ins`` (accuracy, NEES and cost over 20 seeds) is
``filters.ekf_vs_pyins`` in ``bench_pyins.py``.

Data: ``navlib.sensors`` presets ``motionpak_tactical`` (rocket) and the launcher model's
own noise (linear mode).
"""

from __future__ import annotations

from functools import cache

from _harness import Case
from _harness import launcher_flight as _launcher
from _harness import rocket_flight as _rocket

from navlib import filters, sensors, strapdown
from navlib.models import launcher


@cache
def _rocket_data(seed: int = 1):
    traj = _rocket()
    spec = sensors.load_preset("motionpak_tactical")
    imu = sensors.simulate_imu(traj, spec, seed=seed)
    gnss = sensors.simulate_gnss(traj, spec, seed=seed + 1)
    return traj, imu, gnss


def _ekf_rocket():
    traj, imu, gnss = _rocket_data()
    return filters.ekf(imu, gnss, initial=strapdown.StrapdownState.from_trajectory(traj),
                       model="ecef21", model_options={"sensors": "motionpak_tactical"})


def _linear_mc():
    model = launcher("ins_gps_att_rt", "GAP", "markov", _launcher())
    return filters.simulate_linear(model, runs=100, seed=0)


def cases() -> list[Case]:
    out = [
        Case("filters.ekf_rocket", "86 s @ 100 Hz, 21 states, 1 Hz GNSS", _ekf_rocket, 1.0),
        Case("filters.linear_mc_launcher", "100 runs x 30001 steps, 28 states", _linear_mc,
             30.0, repeat=1, warmup=False),
    ]
    return out
