"""Simulated EKF scenarios: sensors along a trajectory, outliers injected, one
:func:`~navlib.filters.ekf.ekf` run (docs/assumptions.md, launcher.md §6.2-6.4), as the outlier
study's closed-loop cross-checks use it.

:func:`simulate_ekf` builds the IMU, GNSS, attitude sensor and reference trajectory of
:mod:`navlib.sensors`, injects the outliers of :mod:`navlib.sensors.faults` and perturbs the
initial state; :class:`EKFRun` is what it returns.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from navlib import sensors as sensor_lib
from navlib import strapdown
from navlib.errors import NavlibInputError
from navlib.filters.ekf import EKFResult, EKFSnapshot, ekf, error_model
from navlib.filters.measurements import epoch_index
from navlib.kalman import psd_sqrt
from navlib.models.base import Nominal
from navlib.models.launcher import rt_dynamics_matrix
from navlib.quaternions import quat_from_matrix
from navlib.sensors import ReferenceTrajectory, simulate_attitude_sensor
from navlib.sensors.faults import as_outliers, inject

__all__ = ["EKFRun", "simulate_ekf"]

_AXES = ("x", "y", "z")


@dataclass(frozen=True, eq=False)
class EKFRun:
    """One simulated EKF run: the result and what it was fed.

    Attributes
    ----------
    result : EKFResult
    errors : DataFrame
        ``result.errors(trajectory)``.
    truth_parameters : dict
        True parameter histories at the result epochs in the model's convention (``bg``,
        ``ba`` body-axis biases; ``bp`` minus the GPS position bias).
    reference : DataFrame or None
        True launcher divergence (RT solutions).
    initial_error : ndarray (n_nav,)
        The drawn initial navigation error (position, velocity, attitude).
    """

    result: EKFResult
    errors: pd.DataFrame
    truth_parameters: dict
    reference: pd.DataFrame | None
    initial_error: np.ndarray


def simulate_ekf(trajectory, *, sensors="launcher_table1", model: str = "launcher",
                 solution: str = "ins_gps", biases: str = "GA", bias_model: str = "markov",
                 model_options: dict | None = None, gnss_rate_hz: float | None = None,
                 outliers=None, seed=None, initial_error: bool = True, noise: bool = True,
                 window_s: float = 0.1, keep_covariance: bool = False,
                 gnss_velocity_sigma: float | None = None, snapshot_before: float | None = None,
                 resume: EKFRun | None = None) -> EKFRun:
    """Simulate sensors along ``trajectory``, inject outliers and run :func:`ekf`.

    The IMU and GNSS come from :func:`navlib.sensors.simulate_imu` /
    :func:`~navlib.sensors.simulate_gnss` with the preset ``sensors``; the attitude sensor
    from :func:`simulate_attitude_sensor` (the preset's sigma), the reference trajectory from
    :class:`ReferenceTrajectory`. ``outliers`` are added to those data (EKF-mode injection of
    :mod:`navlib.sensors.faults`). The initial nominal state is the truth perturbed by a draw from
    the model's ``P0`` navigation block (``initial_error``). With ``noise=False`` the
    sensors are error-free (a deterministic run, e.g. to isolate an outlier response).

    Seeds: one ``numpy.random.SeedSequence(seed)`` spawns independent streams for the IMU,
    GNSS, attitude sensor, reference trajectory and initial error, so a run with an
    outlier and one without share every noise realisation.

    Parameters
    ----------
    trajectory : Trajectory
        Truth; the IMU samples are its samples.
    sensors : str or navlib.sensors.SensorSpec
        Sensor preset of the simulated data (default ``launcher_table1``). The GNSS
        position bias is simulated only when the filter estimates it (launcher ``P``), so
        truth and filter model agree; for ``ecef21`` the model's noise densities default to
        the same preset.
    model, solution, biases, bias_model, model_options
        As in :func:`ekf`.
    window_s, keep_covariance, gnss_velocity_sigma
        As in :func:`ekf`.
    gnss_rate_hz : float, optional
        GNSS fix rate (default the preset's; the paper's launcher uses every sample).
    outliers : Outlier or sequence of Outlier, optional
    seed : int, optional
    initial_error, noise : bool
    snapshot_before : float, optional
        As in :func:`ekf` (``run.result.snapshot``).
    resume : EKFRun, optional
        A run of the same call without ``outliers`` and with a snapshot taken before the
        earliest outlier (a sample spacing before its time): this run starts there, which
        gives the same result as running it from the start (the simulated sensors are the
        same until the outliers, whose injection changes nothing before them).

    Returns
    -------
    EKFRun
    """
    outliers = as_outliers(outliers)
    spec = sensor_lib.load_preset(sensors) if isinstance(sensors, str) else sensors
    es = error_model(model, np.asarray(trajectory.t, dtype=float), solution, biases,
                      bias_model, model_options, gnss_velocity_sigma, sensors=sensors)
    seq = np.random.SeedSequence(seed)
    g_imu, g_gnss, g_att, g_ref, g_init = (np.random.default_rng(s) for s in seq.spawn(5))
    if "bp" not in es.parameters:
        # truth matches the filter model: no GNSS position bias unless it is estimated
        spec = replace(spec, gnss=replace(spec.gnss, position_bias_markov=0.0))
    if noise:
        imu = sensor_lib.simulate_imu(trajectory, spec, rng=g_imu)
        gnss = sensor_lib.simulate_gnss(trajectory, spec, rate_hz=gnss_rate_hz, rng=g_gnss,
                                        with_errors=True)
    else:
        quiet = sensor_lib.SensorSpec(name="noise-free", source="",
                                      imu=sensor_lib.ImuSpec(),
                                      gnss=sensor_lib.GnssSpec(rate_hz=spec.gnss.rate_hz))
        imu = sensor_lib.simulate_imu(trajectory, quiet, rng=g_imu)
        gnss = sensor_lib.simulate_gnss(trajectory, quiet, rate_hz=gnss_rate_hz, rng=g_gnss,
                                        with_errors=True)
    t = imu.t
    imu_df = pd.DataFrame({"t": t})
    f_b = inject(imu.f_b, t, outliers, "accel")
    w_b = inject(imu.w_ib_b, t, outliers, "gyro")
    for i, a in enumerate(_AXES):
        imu_df[f"f_{a}"] = f_b[:, i]
    for i, a in enumerate(_AXES):
        imu_df[f"w_{a}"] = w_b[:, i]
    tg = gnss["t"].to_numpy(float)
    snapshot = _snapshot_to_resume(resume, outliers, (t, tg))
    gnss = gnss.copy()
    gnss[["x", "y", "z"]] = inject(gnss[["x", "y", "z"]].to_numpy(), tg, outliers, "gnss_pos")
    gnss[["vx", "vy", "vz"]] = inject(gnss[["vx", "vy", "vz"]].to_numpy(), tg, outliers,
                                      "gnss_vel")

    attitude = reference = None
    if "att" in es.measurements:
        sigma_att = (model_options or {}).get("sigma_att", spec.attitude_sigma or 0.0)
        attitude = simulate_attitude_sensor(trajectory, sigma_att if noise else 0.0, rng=g_att,
                                            outliers=outliers)
    if "rt" in es.measurements:
        reference = ReferenceTrajectory(
            trajectory, rt_dynamics_matrix(), sigma_wind=es.settings["sigma_wind"],
            a1_sign=es.settings["a1_sign"], rng=g_ref, outliers=outliers, noise=noise)

    # initial error: a draw from the model's P0 navigation block, fed back with minus sign
    truth0 = strapdown.StrapdownState.from_trajectory(trajectory, 0)
    nav = np.concatenate([es.groups[g] for g in ("position", "velocity", "attitude")])
    P_nav = es.P0[np.ix_(nav, nav)]
    dx0 = (g_init.standard_normal(9) @ psd_sqrt(P_nav).T) if initial_error else np.zeros(9)
    dx = np.zeros((1, len(es.state_names)))
    dx[0, nav] = -dx0
    hat0 = es.correct(Nominal(t[:1], truth0.position[None], truth0.velocity[None],
                              trajectory.attitude[:1].as_matrix(), f_b[:1], w_b[:1], {}), dx)
    initial = strapdown.StrapdownState(t=truth0.t, position=hat0.position[0],
                                       velocity=hat0.velocity[0],
                                       q_b_e=quat_from_matrix(hat0.C_b_e[0]))
    result = ekf(imu_df, gnss, initial=initial, model=es, attitude=attitude,
                 reference=reference, window_s=window_s, keep_covariance=keep_covariance,
                 snapshot_before=snapshot_before, resume=snapshot)
    k = epoch_index(t, result.t, "result")
    truth_par = {g: bias[k] for g, bias in (("bg", imu.gyro.bias), ("ba", imu.accel.bias))
                 if g in es.parameters}
    if "bp" in es.parameters:
        kg = np.clip(np.searchsorted(tg, result.t), 0, tg.size - 1)
        truth_par["bp"] = -gnss[["bias_x", "bias_y", "bias_z"]].to_numpy()[kg]
    return EKFRun(result, result.errors(trajectory), truth_par,
                  reference.history() if reference is not None else None, dx0)


def _snapshot_to_resume(resume, outliers, clocks) -> EKFSnapshot | None:
    """The snapshot of ``resume`` (:func:`simulate_ekf`), checked to lie before the
    outliers' first sample (the largest sample spacing of the IMU and GNSS ``clocks``
    before the earliest outlier time)."""
    if resume is None:
        return None
    snapshot = getattr(getattr(resume, "result", None), "snapshot", None)
    if snapshot is None:
        raise NavlibInputError("resume: expected an EKFRun made with snapshot_before=")
    spacing = max(float(np.max(np.diff(c))) for c in clocks if c.size > 1)
    if outliers and snapshot.t >= min(o.time for o in outliers) - spacing:
        raise NavlibInputError(f"resume: the snapshot at {snapshot.t:g} s is not before the "
                               "outliers")
    return snapshot
