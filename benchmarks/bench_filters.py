"""Benchmarks of navlib.filters (issue 5 performance goals).

* ``filters.ekf_rocket``: the closed-loop EKF (21-state ECEF model, España et al.) over the
  86 s sounding-rocket flight — 8601 IMU samples at 100 Hz, GNSS position at 1 Hz — on
  simulated MotionPak-class data. Goal 1 s. Sensor simulation is outside the timing.
* ``filters.linear_mc_launcher``: 100 Monte-Carlo runs of the linear error-state filter on
  the launcher mission (150 s at 200 Hz, INS/GPS/att + RT with G, A, P Markov biases: 28
  states, 12 measurements at every sample), from building the error model to the last run:
  discretisation, the shared covariance recursion and gains, the 100 runs. Goal 30 s.
* ``filters.linear_runs_prepared`` and ``filters.linear_unit_responses``: the simulation
  alone, on a filter already prepared (notebook 05, issue 14): the ``nominal`` cell's 100
  runs of INS/GPS/att (GAP Markov biases, 18 states, 9 measurements at every 200 Hz
  sample, 30001 epochs, ``a1_sign=+1``) and the noise-free unit responses of that filter to
  the paper's outliers (T2-T4 spike and step, from 50 s). Goals 0.93 s and 0.16 s: half the
  1.85 s and 0.31 s of the step-by-step loop before issue 14 (2 cores, load 0.5).

* ``filters.ekf_outlier_study``: the closed-loop EKF runs of notebook 05 (issue 14): the
  launcher error-state EKF at every 200 Hz sample with 0.1 s feedback windows, GAP Markov
  biases, ``a1_sign=+1`` — the noise-free cross-checks of T2 (INS/GPS) and T4 (INS/GPS/att)
  over the 150 s ascent, each a nominal run with a snapshot before 50 s and the run with
  the outlier resumed from it (108k updates in all with the next run), and the noisy 40 s
  INS/GPS/att run kept with its covariances. Goal 11.7 s: half the 23.3 s these runs took
  before issue 14 (2 cores, load 0.7).

The comparison with ``python-ins`` (accuracy, NEES and cost over 20 seeds) is
``filters.ekf_vs_pyins`` in ``bench_pyins.py``.

Data: ``navlib.sensors`` presets ``motionpak_tactical`` (rocket) and the launcher model's
own noise (linear mode).
"""

from __future__ import annotations

from functools import cache

import numpy as np
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


def _ekf_outlier_study():
    """As ``ostudy.ekf_vs_covariance`` and ``ostudy.ekf_crosscheck`` run them (one BLAS
    thread), without their linear-filter parts."""
    from threadpoolctl import threadpool_limits

    from navlib.studies.outliers.paper import PAPER_TESTS
    from navlib.trajectory import launcher_ascent

    traj = _launcher()
    short = launcher_ascent(duration_s=40.0)
    options = {"a1_sign": 1.0}
    with threadpool_limits(1):
        filters.simulate_ekf(short, solution="ins_gps_att", biases="GAP", bias_model="markov",
                             model_options=options, seed=0, gnss_rate_hz=short.rate_hz,
                             window_s=0.1, keep_covariance=True)
        for solution, test in (("ins_gps", "T2"), ("ins_gps_att", "T4")):
            outlier = PAPER_TESTS[test].outlier(time=50.0)
            kw = dict(solution=solution, biases="GAP", bias_model="markov",
                      model_options=options, gnss_rate_hz=traj.rate_hz, noise=False,
                      initial_error=False, window_s=0.1)
            before = outlier.time - float(np.max(np.diff(traj.t)))
            nominal = filters.simulate_ekf(traj, snapshot_before=before, **kw)
            filters.simulate_ekf(traj, outliers=outlier, resume=nominal, **kw)


def _linear_mc():
    model = launcher("ins_gps_att_rt", "GAP", "markov", _launcher())
    return filters.simulate_linear(model, runs=100, seed=0)


@cache
def _outlier_filter():
    from navlib.studies import outliers as ostudy

    cache = ostudy.FilterCache(_launcher(), size=1, a1_sign=1.0)
    return cache.get("ins_gps_att", "GAP", "markov")


def _linear_runs_prepared():
    return filters.simulate_linear(_outlier_filter(), runs=100, seed=0)


def _linear_unit_responses():
    from navlib.filters.linear import unit_responses
    from navlib.studies.outliers.paper import PAPER_TESTS

    units = [test.outlier(shape) for test in PAPER_TESTS.values()
             for shape in ("spike", "step") if "ins_gps_att" in test.solutions]
    return unit_responses(_outlier_filter(), units)


def cases() -> list[Case]:
    out = [
        Case("filters.ekf_rocket", "86 s @ 100 Hz, 21 states, 1 Hz GNSS", _ekf_rocket, 1.0),
        Case("filters.ekf_outlier_study", "5 runs, 108k updates, 18 states",
             _ekf_outlier_study, 11.7, repeat=1, warmup=False),
        Case("filters.linear_mc_launcher", "100 runs x 30001 steps, 28 states", _linear_mc,
             30.0, repeat=1, warmup=False),
        Case("filters.linear_runs_prepared", "100 runs x 30001 steps, 18 states",
             _linear_runs_prepared, 0.93),
        Case("filters.linear_unit_responses", "4 responses x 20001 steps, 18 states",
             _linear_unit_responses, 0.16),
    ]
    return out
