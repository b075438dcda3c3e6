"""Benchmarks of navlib.filters (issue 5 performance goals).

* ``filters.ekf_rocket``: the closed-loop EKF (21-state ECEF model, España et al.) over the
  86 s sounding-rocket flight — 8601 IMU samples at 100 Hz, GNSS position at 1 Hz — on
  simulated MotionPak-class data. Goal 1 s. Sensor simulation is outside the timing.
* ``filters.linear_mc_launcher``: 100 Monte-Carlo runs of the linear error-state filter on
  the launcher mission (150 s at 200 Hz, INS/GPS/att + RT with G, A, P Markov biases: 28
  states, 12 measurements at every sample), from building the error model to the last run:
  discretisation, the shared covariance recursion and gains, the 100 runs. Goal 30 s.
* ``filters.ekf_vs_pyins``: our EKF and the feedback filter of ``python-ins``
  (``pyins.filters.run_feedback_filter``, 9 NED states + gyro/accel biases and scale
  factors = 21 states, its default 0.1 s covariance step) on the **same** IMU/GNSS data of
  the rocket flight, timed back to back in one run. Columns give each filter's cost per IMU
  sample and their ratio. pyins is optional (``pip install python-ins``, needs numba); the
  case is skipped with a message when it is missing. Its numba kernels are compiled on a 1 s
  slice before timing. The goal column is our 1 s goal.

Data: ``navlib.sensors`` presets ``motionpak_tactical`` (rocket) and the launcher model's
own noise (linear mode).
"""

from __future__ import annotations

import sys
import time
from functools import cache

import numpy as np
import pandas as pd
from _harness import Case
from _harness import launcher_flight as _launcher
from _harness import rocket_flight as _rocket
from scipy.spatial.transform import Rotation

from navlib import earth, filters, sensors, strapdown
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


# --- python-ins comparison -------------------------------------------------------------------


def _pyins_inputs():
    """pyins increments, initial PVA, position measurements and sensor models for the rocket
    data (NED at the launch site: lat/lon in degrees, roll/pitch/heading of C_b_n in degrees
    as pyins's 'xyz' Euler convention)."""
    from pyins import inertial_sensor, measurements
    from pyins import strapdown as pyins_strapdown

    traj, imu, gnss = _rocket_data()
    frame = pd.DataFrame(np.hstack([imu.w_ib_b, imu.f_b]), index=imu.t,
                         columns=["gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z"])
    increments = pyins_strapdown.compute_increments_from_imu(frame, "rate")
    lat, lon, alt = earth.ecef_to_geodetic(traj.position[0])
    C_n_e = earth.ned_to_ecef_matrix(lat, lon)
    v_n = C_n_e.T @ traj.velocity[0]
    rph = Rotation.from_matrix(C_n_e.T @ traj.attitude[0].as_matrix()).as_euler("xyz",
                                                                                degrees=True)
    initial = pd.Series(np.r_[np.degrees(lat), np.degrees(lon), alt, v_n, rph],
                        index=["lat", "lon", "alt", "VN", "VE", "VD", "roll", "pitch",
                               "heading"], name=float(traj.t[0]))
    glat, glon, galt = earth.ecef_to_geodetic(gnss[["x", "y", "z"]].to_numpy())
    position = measurements.Position(
        pd.DataFrame({"lat": np.degrees(glat), "lon": np.degrees(glon), "alt": galt},
                     index=gnss.t.to_numpy()), float(gnss.sigma.iloc[0]))
    p = sensors.load_preset("motionpak_tactical").imu
    gyro = inertial_sensor.EstimationModel(
        bias_sd=p.gyro.bias, noise=p.gyro.noise_density, bias_walk=p.gyro.bias_random_walk,
        scale_misal_sd=np.diag([p.gyro.scale_factor] * 3))
    accel = inertial_sensor.EstimationModel(
        bias_sd=p.accel.bias, noise=p.accel.noise_density, bias_walk=p.accel.bias_random_walk,
        scale_misal_sd=np.diag([p.accel.scale_factor] * 3))
    return initial, increments, position, gyro, accel


@cache
def _pyins_ready():
    """Inputs, with pyins's numba kernels compiled on the first second (outside timing)."""
    from pyins import filters as pyins_filters

    initial, increments, position, gyro, accel = _pyins_inputs()
    pyins_filters.run_feedback_filter(initial, 30.0, 3.0, 1.0, 1.0, increments.iloc[:100],
                                      gyro, accel, measurements=[position], time_step=0.1)
    return initial, increments, position, gyro, accel


_LAST: dict = {}


def _ekf_vs_pyins():
    from pyins import filters as pyins_filters

    initial, increments, position, gyro, accel = _pyins_ready()
    start = time.perf_counter()
    ours = _ekf_rocket()
    t_ours = time.perf_counter() - start
    start = time.perf_counter()
    theirs = pyins_filters.run_feedback_filter(initial, 30.0, 3.0, 1.0, 1.0, increments, gyro,
                                               accel, measurements=[position], time_step=0.1)
    t_theirs = time.perf_counter() - start
    traj = _rocket()
    lat, lon, alt = (np.radians(theirs.trajectory.lat.iloc[-1]),
                     np.radians(theirs.trajectory.lon.iloc[-1]), theirs.trajectory.alt.iloc[-1])
    err_theirs = np.linalg.norm(earth.geodetic_to_ecef(lat, lon, alt) - traj.position[-1])
    err_ours = np.linalg.norm(ours.position[-1] - traj.position[-1])
    n = len(traj.t)
    _LAST.update(ours_us=1e6 * t_ours / n, pyins_us=1e6 * t_theirs / n,
                 ratio=t_theirs / t_ours, final_pos_err_ours_m=err_ours,
                 final_pos_err_pyins_m=err_theirs)
    return ours, theirs


def _comparison_columns(_best: float) -> dict:
    return {"ekf_us_per_step": _LAST["ours_us"], "pyins_us_per_step": _LAST["pyins_us"],
            "pyins_over_ours": _LAST["ratio"],
            "final_pos_err_m": f"{_LAST['final_pos_err_ours_m']:.2f} / "
                               f"{_LAST['final_pos_err_pyins_m']:.2f}"}


def cases() -> list[Case]:
    out = [
        Case("filters.ekf_rocket", "86 s @ 100 Hz, 21 states, 1 Hz GNSS", _ekf_rocket, 1.0),
        Case("filters.linear_mc_launcher", "100 runs x 30001 steps, 28 states", _linear_mc,
             30.0, repeat=1, warmup=False),
    ]
    try:
        import pyins  # noqa: F401
    except ImportError as exc:
        print(f"skipping filters.ekf_vs_pyins: python-ins is not installed or fails to import "
              f"({exc}); install it with `pip install python-ins` (needs numba)",
              file=sys.stderr)
        return out
    out.append(Case("filters.ekf_vs_pyins", "rocket 8601 samples, same data", _ekf_vs_pyins,
                    1.0, repeat=1, warmup=False, extra=_comparison_columns,
                    notes="time = ours + pyins back to back; final position error ours / pyins"))
    return out
