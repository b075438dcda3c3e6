"""Generated TeleMega flights written as AltOS CSV exports, for checks of the whole
assessment (reader, fit, segmentation, agreement) on flights of known truth.

:func:`telemega_export` flies a rocket mission (:func:`navlib.trajectory.mission.from_mission`)
and writes what a TeleMega would have exported of it (the newer header generation of
:mod:`support.altos_writer`): the log clock starts at boost detection (specific force
along the body beyond 3 g) with 0.3 s of pad before it; 100 Hz rows to the drogue and 10 Hz
rows after; the IMU with the ``altus_telemega`` preset's errors (turn-on biases, +-3 %
scale factors, noise), rounded to the export's 0.01 and clipped to its ranges; the high-g
accelerometer along the body (``acceleration``: its own scale error, 0.3 m/s^2 noise, steps
of 0.53 m/s^2, its pad reading removed, not clipped); 1 Hz fixes
taken at whole receiver seconds with white noise, a slow Markov offset and integer-metre
altitude, each appearing on the first row after it arrived ``latency_s`` (plus jitter)
later; a barometric altitude off by a temperature scale; the flight states from the
mission's events. The numbers are stated, arbitrary choices (not fitted to any log); the
truth is returned beside the file.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from navlib import earth, sensors
from navlib.trajectory.mission import from_mission, with_values
from support.altos_writer import write_altos

BOOST_DETECT_MPS2 = 3.0 * 9.80665
"""Specific force along the body at which the log clock starts (AltOS boost detection)."""
ACCEL_RANGE_MPS2 = 16.0 * 9.80665
GYRO_RANGE_DEG_S = 2000.0
"""The MPU-6000 ranges the export clips to (``data/sensors/altus_telemega.toml``)."""
HIGH_G_STEP_MPS2 = 0.53
"""Step of the export's ``acceleration`` column (the shared TeleMega flights' high-g reading
changes by multiples of it)."""


def _states(t_truth, events):
    """AltOS flight state names at the truth times."""
    names = np.full(t_truth.size, "boost", dtype=object)
    for key, name in (("burnout", "coast"), ("drogue", "drogue"), ("main", "main"),
                      ("landing", "landed")):
        if key in events:
            names[t_truth >= events[key]] = name
    return names


def _fix_positions(truth, t_fix, rng, sigma_h_m, sigma_v_m, offset_m, tau_s):
    """Fixes at ``t_fix`` (truth times): truth plus white noise and a first-order Markov
    offset, in geodetic coordinates (deg, deg, m)."""
    P = np.column_stack([np.interp(t_fix, truth.t, truth.position[:, i]) for i in range(3)])
    lat, lon, _ = earth.ecef_to_geodetic(P)
    C = earth.ned_to_ecef_matrix(float(lat[0]), float(lon[0]))
    offset = np.zeros((t_fix.size, 3))
    a = np.exp(-1.0 / tau_s)
    offset[0] = offset_m * rng.standard_normal(3)
    for k in range(1, t_fix.size):
        offset[k] = a * offset[k - 1] + offset_m * np.sqrt(1.0 - a * a) * rng.standard_normal(3)
    noise = rng.standard_normal((t_fix.size, 3)) * np.array([sigma_h_m, sigma_h_m, sigma_v_m])
    P = P + (offset + noise) @ C.T
    return earth.ecef_to_geodetic(P)


def telemega_export(path, changes=None, *, seed=0, latency_s=0.5, baro_scale=0.97,
                    sigma_h_m=2.0, sigma_v_m=3.0, offset_m=2.0, tau_s=60.0,
                    mission="hpr_rocket", generation="version", gnss_gap=None,
                    high_g_scale=-0.025, board="telemega", **imu_overrides):
    """Fly ``mission`` with ``changes`` (:func:`with_values`) and write its TeleMega export
    (``generation`` of :func:`write_altos`; ``gnss_gap``: ``(start, end)`` on the export's
    clock with no new fix, a receiver that lost lock; ``high_g_scale``: the high-g
    accelerometer's scale error, the shared flights' reads 2.5-2.9 % below the IMU's in
    boost; ``board``: ``"easymega"`` writes no GPS columns).

    Returns
    -------
    truth : Trajectory
        The flown motion, on the mission's clock.
    t_detect : float
        Boost detection on the mission's clock (the export's time zero).
    """
    rng = np.random.default_rng(seed)
    truth = from_mission(with_values(mission, changes or {}))
    t = truth.t
    f_along = truth.specific_force[:, 0]
    t_detect = float(t[np.argmax(f_along > BOOST_DETECT_MPS2)])
    t_fast_end = truth.events.get("drogue", t[-1])
    keep = t >= t_detect - 0.3 - 1e-9
    keep &= (t <= t_fast_end) | (np.rint((t - t_fast_end) * 100.0) % 10 == 0)
    spec = sensors.load_preset("altus_telemega")
    imu = sensors.simulate_imu(truth, spec, seed=seed, **imu_overrides).to_frame()
    f = np.clip(imu[["f_x", "f_y", "f_z"]].to_numpy(), -ACCEL_RANGE_MPS2, ACCEL_RANGE_MPS2)
    w = np.clip(np.degrees(imu[["w_x", "w_y", "w_z"]].to_numpy()), -GYRO_RANGE_DEG_S,
                GYRO_RANGE_DEG_S)

    noise = np.random.default_rng([seed, 1]).standard_normal(t.size)   # rng's draws kept
    high_g = (1.0 + high_g_scale) * f_along + 0.3 * noise
    high_g = HIGH_G_STEP_MPS2 * np.round((high_g - high_g[0]) / HIGH_G_STEP_MPS2)

    lat0, lon0, h0 = earth.ecef_to_geodetic(truth.position[0])
    _, _, h = earth.ecef_to_geodetic(truth.position)
    up = earth.ned_to_ecef_matrix(float(lat0), float(lon0))[:, 2] * -1.0
    along = truth.C_b_e()[:, :, 0]
    tilt = np.degrees(np.arccos(np.clip(along @ up, -1.0, 1.0)))
    baro = h0 + baro_scale * (h - h0) + 0.3 * rng.standard_normal(t.size)

    # fixes at whole receiver seconds (a random phase against the log clock)
    phase = rng.uniform(0.0, 1.0)
    t_fix = np.arange(t[0] + phase, t[-1] - latency_s - 0.1, 1.0)
    lat, lon, alt = _fix_positions(truth, t_fix, rng, sigma_h_m, sigma_v_m, offset_m, tau_s)
    arrival = t_fix + latency_s + rng.uniform(-0.03, 0.03, t_fix.size)
    if gnss_gap is not None:
        lost = (t_fix - t_detect >= gnss_gap[0]) & (t_fix - t_detect <= gnss_gap[1])
        t_fix, lat, lon, alt, arrival = (x[~lost] for x in (t_fix, lat, lon, alt, arrival))
    t_log = t[keep]
    fix_of_row = np.searchsorted(arrival, t_log, side="right") - 1
    if np.any(fix_of_row < 0):
        raise ValueError("the export would start before the first fix arrived")
    rows = pd.DataFrame({
        "time": np.round(t_log - t_detect, 2),
        "state_name": _states(t_log, truth.events),
        "accel_x": np.round(f[keep, 0], 2), "accel_y": np.round(f[keep, 1], 2),
        "accel_z": np.round(f[keep, 2], 2), "high_g": np.round(high_g[keep], 2),
        "gyro_roll": np.round(w[keep, 0], 2), "gyro_pitch": np.round(w[keep, 1], 2),
        "gyro_yaw": np.round(w[keep, 2], 2),
        "tilt": np.round(tilt[keep], 2),
        "baro_altitude": np.round(baro[keep], 2),
        "nsat": rng.integers(9, 13, t_fix.size)[fix_of_row],
        "latitude": np.round(np.degrees(lat), 7)[fix_of_row],
        "longitude": np.round(np.degrees(lon), 7)[fix_of_row],
        "gps_altitude": np.round(alt)[fix_of_row],
        "gps_second": fix_of_row,
    })
    write_altos(path, rows, generation=generation, board=board)
    return truth, t_detect
