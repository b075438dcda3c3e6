"""Cost of the closed-loop EKF per IMU sample (issue 26: goal < 10 us at equal accuracy).

* ``ekf.rocket_per_sample``: the 86 s sounding-rocket flight (8601 IMU samples at 100 Hz,
  21-state ECEF model of España et al., GNSS position at 1 Hz), as ``filters.ekf_rocket``
  in ``bench_filters.py``; ``us_per_sample`` is the time over the samples.
* ``ekf.launcher_per_sample``: the launcher error-state EKF with an update at every sample
  (40 s of the ascent at 200 Hz, INS/GPS/att, GAP Markov biases, 0.1 s feedback windows,
  one BLAS thread), as the noisy run of notebook 05.

Sensor simulation is outside the timing of the rocket row (the launcher row includes it, as
:func:`navlib.filters.simulate_ekf` does). Times are the best of 3; the machine is shared,
so read ``uptime`` beside them.
"""

from __future__ import annotations

from functools import cache

from _harness import Case
from _harness import rocket_flight as _rocket
from threadpoolctl import threadpool_limits

from navlib import filters, sensors, strapdown
from navlib.trajectory import launcher_ascent

GOAL_S_PER_SAMPLE = 10e-6
ROCKET_SAMPLES = 8601
LAUNCHER_SAMPLES = 8001


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


def _per_sample(samples: int):
    return lambda best: {"us_per_sample": best / samples * 1e6}


def cases() -> list[Case]:
    return [
        Case("ekf.rocket_per_sample", "86 s @ 100 Hz, 21 states, 1 Hz GNSS", _ekf_rocket,
             ROCKET_SAMPLES * GOAL_S_PER_SAMPLE, extra=_per_sample(ROCKET_SAMPLES)),
        Case("ekf.launcher_per_sample", "40 s @ 200 Hz, 18 states, update every sample",
             _ekf_launcher, LAUNCHER_SAMPLES * GOAL_S_PER_SAMPLE,
             extra=_per_sample(LAUNCHER_SAMPLES)),
    ]
