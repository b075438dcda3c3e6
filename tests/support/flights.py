"""Generated multicopter flights for the flight-assessment tests and the long-flight benchmark.

A quadcopter-like vehicle stands on its pads for ``pad_s``, climbs ``climb_m`` and flies a
figure of eight (``radius_m``, one loop every ``period_s``) with its yaw swinging; roll and
pitch are whatever tilts the thrust onto the needed acceleration (multicopter kinematics).
Kinematics are quintic interpolating splines of smooth functions, so the IMU of
:func:`navlib.trajectory.base.build_trajectory` is exact for them. Not a navlib generator:
a test fixture with stated, arbitrary numbers.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy.interpolate import make_interp_spline
from scipy.spatial.transform import Rotation

from navlib import earth, sensors
from navlib.trajectory._attitude import smoothstep, zyx_attitude
from navlib.trajectory.base import build_trajectory

G = 9.80665


def multicopter(duration_s=120.0, rate_hz=250.0, *, pad_s=10.0, climb_m=20.0,
                radius_m=60.0, period_s=60.0, lat_deg=47.397, lon_deg=8.545, alt_m=488.0,
                t_start=0.0):
    """Exact multicopter trajectory on ``[t_start, duration_s]`` at ``rate_hz``."""
    grid = np.arange(0.0, duration_s + 1.0, 0.05)
    s, _, _ = smoothstep((grid - pad_s) / 8.0)              # lift-off ramp
    w = 2.0 * np.pi / period_s
    tau = np.maximum(grid - pad_s, 0.0)
    north = s * radius_m * np.sin(w * tau)
    east = s * 0.5 * radius_m * np.sin(2.0 * w * tau)
    down = -s * climb_m
    ned = np.column_stack([north, east, down])
    yaw = 0.3 + s * 0.8 * np.sin(0.5 * w * tau)
    spl = make_interp_spline(grid, ned, k=5)
    yaw_spl = make_interp_spline(grid, yaw, k=5)
    n = round((duration_s - t_start) * rate_hz) + 1
    t = t_start + np.arange(n) / rate_hz
    p_n, v_n, a_n = spl(t), spl(t, 1), spl(t, 2)
    psi, dpsi = yaw_spl(t), yaw_spl(t, 1)
    # thrust direction: body z along -(a - g) in NED, yaw given
    f_n = a_n - np.array([0.0, 0.0, G])
    df_n = spl(t, 3)
    cps, sps = np.cos(psi), np.sin(psi)
    # rotate into the yawed frame, then pitch/roll of the thrust axis
    fx = cps * f_n[:, 0] + sps * f_n[:, 1]
    fy = -sps * f_n[:, 0] + cps * f_n[:, 1]
    fz = f_n[:, 2]
    dfx = cps * df_n[:, 0] + sps * df_n[:, 1] + dpsi * fy
    dfy = -sps * df_n[:, 0] + cps * df_n[:, 1] - dpsi * fx
    dfz = df_n[:, 2]
    theta = np.arctan2(fx, -fz)                               # pitch
    h = np.hypot(fx, fz)
    phi = np.arctan2(-fy, h)                                  # roll
    dtheta = (-fz * dfx + fx * dfz) / (fx**2 + fz**2)
    dh = (fx * dfx + fz * dfz) / h
    dphi = (-h * dfy + fy * dh) / (h**2 + fy**2)
    lat, lon = np.radians(lat_deg), np.radians(lon_deg)
    C_n_e = earth.ned_to_ecef_matrix(lat, lon)
    P0 = earth.geodetic_to_ecef(lat, lon, alt_m)
    P = P0 + p_n @ C_n_e.T
    V = v_n @ C_n_e.T
    A = a_n @ C_n_e.T
    C_b_e, w_eb_b = zyx_attitude(C_n_e, psi, theta, phi, dpsi, dtheta, dphi)
    return build_trajectory(t, P, V, A, C_b_e, w_eb_b,
                            events={"liftoff": pad_s, "end": float(t[-1])}, name="multicopter")


def records(truth, *, preset="pixhawk_mems", seed=1, vibration_mps2=0.0, gnss_rate_hz=5.0):
    """Simulated IMU and GNSS frames of ``truth`` with the preset's errors (and an optional
    white vibration of ``vibration_mps2`` per axis on the accelerometers)."""
    spec = sensors.load_preset(preset)
    imu = sensors.simulate_imu(truth, spec, seed=seed).to_frame()
    if vibration_mps2:
        rng = np.random.default_rng(seed + 100)
        imu[["f_x", "f_y", "f_z"]] += vibration_mps2 * rng.standard_normal((len(imu), 3))
    gnss = sensors.simulate_gnss(truth, spec, rate_hz=gnss_rate_hz, seed=seed + 1)
    return imu, gnss


def logged_attitude(truth, lat_deg=47.397, lon_deg=8.545, every=10):
    """The autopilot attitude a log would carry: body -> NED quaternion (w, x, y, z)."""
    C_n_e = earth.ned_to_ecef_matrix(np.radians(lat_deg), np.radians(lon_deg))
    idx = np.arange(0, len(truth.t), every)
    C_b_n = C_n_e.T @ truth.C_b_e()[idx]
    from scipy.spatial.transform import Rotation

    q = Rotation.from_matrix(C_b_n).as_quat()              # x, y, z, w
    return pd.DataFrame({"t": truth.t[idx], "qw": q[:, 3], "qx": q[:, 0], "qy": q[:, 1],
                         "qz": q[:, 2]})


def exact_records(traj, *, sigma_f=0.0, sigma_w=0.0, sigma_p=0.0, gnss_hz=1.0,
                  velocity=False, seed=0):
    """IMU and GNSS frames of ``traj``'s exact signals plus white noise of ``sigma_f``
    (m/s^2), ``sigma_w`` (rad/s) and ``sigma_p`` (m), GNSS at ``gnss_hz`` (with its velocity
    columns when ``velocity``)."""
    rng = np.random.default_rng(seed)
    n = len(traj)
    f = traj.specific_force + sigma_f * rng.standard_normal((n, 3))
    w = traj.angular_rate + sigma_w * rng.standard_normal((n, 3))
    imu = pd.DataFrame({"t": traj.t, "f_x": f[:, 0], "f_y": f[:, 1], "f_z": f[:, 2],
                        "w_x": w[:, 0], "w_y": w[:, 1], "w_z": w[:, 2]})
    g = traj.at_rate(gnss_hz)
    P = traj.position[g] + sigma_p * rng.standard_normal((g.size, 3))
    gnss = pd.DataFrame({"t": traj.t[g], "x": P[:, 0], "y": P[:, 1], "z": P[:, 2]})
    if velocity:
        gnss["vx"], gnss["vy"], gnss["vz"] = traj.velocity[g].T
    return imu, gnss


def dataflash_flight():
    """The multicopter flight the DataFlash tests write (tests/support/dataflash_writer.py): its
    truth, IMU and GNSS records, the GNSS as geodetic fixes with NED velocity (``geo``) and
    the attitude as the autopilot logs it (``att``, yaw/pitch/roll in degrees)."""
    truth = multicopter(24.0, 50.0, pad_s=6.0)
    imu, gnss = records(truth, seed=5)
    lat, lon, alt = truth.geodetic
    g = truth.at_rate(5.0)
    v_n = np.einsum("kji,kj->ki", earth.ned_to_ecef_matrix(lat[g], lon[g]), truth.velocity[g])
    geo = pd.DataFrame({"t": truth.t[g], "lat_deg": np.degrees(lat[g]),
                        "lon_deg": np.degrees(lon[g]), "alt_m": alt[g], "vn": v_n[:, 0],
                        "ve": v_n[:, 1], "vd": v_n[:, 2]})
    C_n_e = earth.ned_to_ecef_matrix(lat[0], lon[0])
    ypr = Rotation.from_matrix(C_n_e.T @ truth.C_b_e()[::5]).as_euler("ZYX", degrees=True)
    att = pd.DataFrame({"t": truth.t[::5], "yaw_deg": ypr[:, 0], "pitch_deg": ypr[:, 1],
                        "roll_deg": ypr[:, 2]})
    return truth, imu, gnss, geo, att

