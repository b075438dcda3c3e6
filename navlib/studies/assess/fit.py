"""The trajectory fit of a flight to assess (:func:`navlib.trajectory.fit_flight_data`), its
quality report, residuals and notes."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pandas as pd

from navlib._validation import finite_scalar
from navlib.errors import NavlibInputError
from navlib.io import FlightDataWarning
from navlib.models.ecef import imu_noise_densities
from navlib.studies.assess.agreement import (
    fit_bounds,
    fit_calibration,
    smoothed_residuals,
)
from navlib.studies.assess.inputs import GNSS_KEYS, IMU_KEYS, check_frame
from navlib.trajectory import fit_flight_data
from navlib.trajectory.liftoff import pad_fix_times
from navlib.trajectory.position_spline import coning_per_sample, resolved_samples

__all__ = ["fit_notes", "fit_records", "fit_report", "fit_residuals"]


def fit_report(trajectory, preset=None, gnss_sigma_m: float | None = None) -> pd.DataFrame:
    """The fit residuals of :func:`navlib.trajectory.fit_flight_data` as a tidy table.

    Columns ``quantity`` (GNSS position, GNSS velocity, specific force, angular rate),
    ``axis`` (x, y, z, 3d or max), ``rms`` (SI: m, m/s, m/s^2, rad/s; the ``max`` rows hold
    the largest norm) and ``unit``, and ``white_noise``: for the IMU rows the per-sample
    white-noise sigma of the sensor ``preset`` (``density / sqrt(dt)``), for the GNSS
    position rows ``gnss_sigma_m``; a floor the residual RMS sits near when the fit explains
    the data (biases and scale-factor errors add to it). NaN where not given.

    Parameters
    ----------
    trajectory : Trajectory
        Result of :func:`navlib.trajectory.fit_flight_data`.
    preset : str or None, optional
        Sensor preset of the white-noise floors.
    gnss_sigma_m : float or None, optional
        GNSS position sigma, m.
    """
    res = getattr(trajectory, "parameters", {}).get("fit_residuals")
    if res is None:
        raise NavlibInputError("trajectory: has no parameters['fit_residuals']; pass a "
                               "trajectory from navlib.trajectory.fit_flight_data")
    spec = {"gnss_position_rms_m": ("GNSS position", "m"),
            "gnss_velocity_rms_mps": ("GNSS velocity", "m/s"),
            "specific_force_rms_mps2": ("specific force", "m/s^2"),
            "angular_rate_rms_rad_s": ("angular rate", "rad/s")}
    extra = {"gnss_position_rms_3d_m": ("GNSS position", "3d"),
             "specific_force_max_mps2": ("specific force", "max"),
             "angular_rate_max_rad_s": ("angular rate", "max")}
    floor = _noise_floor(trajectory, preset) if preset is not None else {}
    if gnss_sigma_m is not None:
        floor["GNSS position"] = finite_scalar(gnss_sigma_m, "gnss_sigma_m", 0.0,
                                               low_open=True)
    rows = []
    for key, (quantity, unit) in spec.items():
        if key not in res:
            continue
        for axis, value in zip("xyz", np.atleast_1d(res[key]), strict=True):
            rows.append({"quantity": quantity, "axis": axis, "rms": float(value), "unit": unit,
                         "white_noise": floor.get(quantity, np.nan)})
    for key, (quantity, axis) in extra.items():
        if key in res:
            unit = next(u for q, u in spec.values() if q == quantity)
            rows.append({"quantity": quantity, "axis": axis, "rms": float(res[key]),
                         "unit": unit, "white_noise": np.nan})
    order = {q: i for i, (q, _) in enumerate(spec.values())}
    frame = pd.DataFrame(rows)
    frame = frame.sort_values("quantity", key=lambda s: s.map(order), kind="stable")
    return frame.reset_index(drop=True)


def fit_residuals(trajectory, imu: pd.DataFrame, gnss: pd.DataFrame, bounds: dict | None = None
                  ) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Residuals of the records against a fitted trajectory, over time.

    Parameters
    ----------
    trajectory : Trajectory
        Result of :func:`navlib.trajectory.fit_flight_data`.
    imu, gnss : pandas.DataFrame
        The records the trajectory was fitted to.
    bounds : dict, optional
        :func:`~navlib.studies.assess.agreement.fit_bounds` (None: ``data/quality.toml``).

    Returns
    -------
    gnss_residuals : DataFrame
        At the GNSS epochs inside the trajectory span (moved back by the lag the fit found,
        ``parameters["fit_residuals"]["gnss_lag_s"]``; a fix just before a record that
        starts on a pad at its first sample, :func:`~navlib.trajectory.liftoff.pad_fix_times`):
        ``t``, ``dx, dy, dz`` (recorded minus fitted ECEF position, m), ``d3`` (their norm)
        and, with GNSS velocity, ``dvx, dvy, dvz`` (m/s). The fit is interpolated linearly
        between its samples (error below ``|a| dt^2 / 8``: 1.4 mm at 110 m/s^2 and 100 Hz).
    imu_residuals : DataFrame
        At the trajectory samples (the IMU times of the fit): ``t``, ``df_x, df_y, df_z``
        (recorded minus the fit's exact specific force, m/s^2), ``dw_x, dw_y, dw_z``
        (angular rate, rad/s) and the norms ``df``, ``dw``; ``df_x_avg ... dw_z_avg``: the
        same after the fit's IMU calibration and a moving average
        (:func:`~navlib.studies.assess.agreement.smoothed_residuals`); ``turn_deg``: the
        recorded rotation since the previous sample, deg; ``coning_deg``: how far its axis
        moved against the previous sample's, deg
        (:func:`navlib.trajectory.position_spline.coning_per_sample`); ``resolved``: whether
        the fit took the sample's rotation as resolved
        (:func:`navlib.trajectory.position_spline.resolved_samples`).
    """
    check_frame(imu, "imu", IMU_KEYS)
    check_frame(gnss, "gnss", GNSS_KEYS)
    t = np.asarray(trajectory.t, dtype=float)
    lag = trajectory.parameters.get("fit_residuals", {}).get("gnss_lag_s", 0.0)
    # the fixes where the fit put them: moved back by the lag, those just before a pad at it
    t_g = pad_fix_times(gnss["t"].to_numpy(dtype=float) - lag, t[0],
                        "liftoff" in trajectory.events)
    keep = (t_g >= t[0]) & (t_g <= t[-1])
    out = {"t": t_g[keep]}
    for i, axis in enumerate("xyz"):
        out[f"d{axis}"] = gnss[axis].to_numpy(dtype=float)[keep] - np.interp(
            t_g[keep], t, trajectory.position[:, i])
    out["d3"] = np.sqrt(out["dx"] ** 2 + out["dy"] ** 2 + out["dz"] ** 2)
    if all(c in gnss.columns for c in ("vx", "vy", "vz")):
        for i, axis in enumerate("xyz"):
            out[f"dv{axis}"] = gnss[f"v{axis}"].to_numpy(dtype=float)[keep] - np.interp(
                t_g[keep], t, trajectory.velocity[:, i])
    t_i = imu["t"].to_numpy(dtype=float)
    k = np.searchsorted(t_i, t)
    k = np.clip(k, 0, t_i.size - 1)
    if not np.allclose(t_i[k], t, rtol=0.0, atol=1e-9):
        raise NavlibInputError("imu: the trajectory is not sampled at these IMU times; pass "
                               "the records the trajectory was fitted to")
    f_rec = imu[["f_x", "f_y", "f_z"]].to_numpy(dtype=float)[k]
    w_rec = imu[["w_x", "w_y", "w_z"]].to_numpy(dtype=float)[k]
    df = f_rec - trajectory.specific_force
    dw = w_rec - trajectory.angular_rate
    imu_out = {"t": t}
    for i, axis in enumerate("xyz"):
        imu_out[f"df_{axis}"] = df[:, i]
    for i, axis in enumerate("xyz"):
        imu_out[f"dw_{axis}"] = dw[:, i]
    imu_out["df"] = np.linalg.norm(df, axis=1)
    imu_out["dw"] = np.linalg.norm(dw, axis=1)
    bounds = fit_bounds() if bounds is None else bounds
    df_avg, dw_avg = smoothed_residuals(t, f_rec, trajectory.specific_force, w_rec,
                                        trajectory.angular_rate, fit_calibration(trajectory),
                                        bounds["moving_average_s"])
    for i, axis in enumerate("xyz"):
        imu_out[f"df_{axis}_avg"] = df_avg[:, i]
    for i, axis in enumerate("xyz"):
        imu_out[f"dw_{axis}_avg"] = dw_avg[:, i]
    step = np.diff(t, prepend=t[0] - (t[1] - t[0] if t.size > 1 else 0.0))
    imu_out["turn_deg"] = np.degrees(np.linalg.norm(w_rec, axis=1) * step)
    imu_out["coning_deg"] = np.degrees(coning_per_sample(t, w_rec))
    imu_out["resolved"] = resolved_samples(t, w_rec)
    return pd.DataFrame(out), pd.DataFrame(imu_out)


def _noise_floor(trajectory, preset) -> dict:
    dt = 1.0 / trajectory.rate_hz
    noise = imu_noise_densities(preset)
    return {"specific force": float(np.mean(noise["vrw_m_s_sqrt_s"])) / math.sqrt(dt),
            "angular rate": float(np.mean(noise["arw_rad_sqrt_s"])) / math.sqrt(dt)}


def fit_records(imu, gnss, fit_options: dict, heading_fallback_deg):
    """:func:`fit_flight_data`, retried with a fallback heading when the motion cannot
    give one (the fit names ``heading_deg`` in that error).

    Parameters
    ----------
    imu, gnss : pandas.DataFrame
        The records.
    fit_options : dict
        Keywords of :func:`fit_flight_data`.
    heading_fallback_deg : float or None
        Heading assumed when the motion gives none, deg; None: no retry.

    Returns
    -------
    tuple of (Trajectory, list of str)
        The fit and the notes (the assumed heading).

    Raises
    ------
    NavlibInputError
        From the fit, when no fallback applies.
    """
    notes = []
    try:
        return fit_flight_data(imu, gnss, **fit_options), notes
    except NavlibInputError as exc:
        given = any(fit_options.get(k) is not None for k in (
            "heading_deg", "initial_attitude", "initial_attitude_deg", "launch_azimuth_deg"))
        if given or heading_fallback_deg is None or not str(exc).startswith("heading_deg:"):
            raise
        notes.append(f"initial heading not observable from the motion ({exc}); assumed "
                     f"heading_deg={heading_fallback_deg:g} (body-x azimuth at the start)")
        warnings.warn(notes[-1], FlightDataWarning, stacklevel=3)
        options = {**fit_options, "heading_deg": heading_fallback_deg}
        return fit_flight_data(imu, gnss, **options), notes



def fit_notes(trajectory) -> list[str]:
    """What the fit assumed or bridged, in words (initial attitude, levelling window,
    bridged holes with their bounds)."""
    res = trajectory.parameters.get("fit_residuals", {})
    out = []
    if res.get("initial_attitude_note"):
        out.append(f"initial attitude: {res['initial_attitude_note']} (heading "
                   f"{res.get('heading_deg', float('nan')):.1f} deg)")
    level = res.get("level") or {}
    if level:
        out.append(f"levelled over {level['t_start']:.6g}..{level['t_end']:.6g} s (the quietest"
                   f" rest window: spread {level['spread_mps2']:.3g} m/s^2, limit "
                   f"{level['spread_limit_mps2']:.3g}; mean rate "
                   f"{level['mean_rate_deg_s']:.3g} deg/s)")
    holes = res.get("imu_holes") or []
    if holes:
        worst = max(holes, key=lambda h: h["duration_s"])
        out.append(f"{len(holes)} IMU hole(s) bridged by the fit (longest {worst['duration_s']:.3g}"
                   f" s at t = {worst['t_start']:.6g} s: attitude within "
                   f"{worst['attitude_bound_deg']:.3g} deg, position within "
                   f"{worst['position_bound_m']:.3g} m if the motion varied monotonically "
                   "across it)")
    return out

