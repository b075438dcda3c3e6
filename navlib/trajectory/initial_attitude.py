"""The initial attitude of a fitted flight: levelling, logged attitude, tilt, rail, heading.

Method step 1 of :mod:`navlib.trajectory.fit` (docs/assumptions.md, "fit — levelling from a
short pre-launch window"): :func:`start_attitude` levels in the quietest rest window
(:func:`quiet_window`, whose shortest length is :func:`min_level_s`), else takes the body-x
elevation from the logger's tilt or the launch rail; :func:`logged_attitude` reads the
autopilot's own attitude; :func:`coarse_heading` turns the IMU specific force about the
vertical onto the GNSS-derived one. The sensor preset's noise and turn-on biases set the
thresholds and priors (:func:`min_level_s`, :func:`gyro_drift_deg_s`,
:func:`accel_bias_sigma`).
"""

import numpy as np
import pandas as pd
from scipy.spatial.transform import Rotation, Slerp

from navlib import earth
from navlib.errors import NavlibInputError
from navlib.sensors import DEFAULT_IMU_PRESET, ImuSpec, load_preset
from navlib.units import DEG, G0

__all__ = ["MIN_LEVEL_SAMPLES", "REST_ACCEL_MPS2", "REST_RATE_DEG_S", "TURN_ON_FALLBACK",
           "VERTICAL_SIN2", "accel_bias_sigma", "accel_scale_sigma", "coarse_heading",
           "gyro_drift_deg_s", "heading_of", "level_attitude", "logged_attitude", "min_level_s",
           "quiet_window", "start_attitude"]

VERTICAL_SIN2 = np.sin(1.0 * DEG) ** 2   # body x within 1 deg of the vertical below this
_MIN_HORIZONTAL_F = 0.3     # m/s^2, RMS needed to estimate the heading
REST_ACCEL_MPS2 = 0.5
"""Largest GNSS-derived acceleration around a levelling window, m/s^2 (the segmentation's
rest acceleration: 0.5 m/s^2 tilts the levelled attitude by 3 deg)."""
MIN_LEVEL_SAMPLES = 10
"""Fewest samples of a levelling window: enough to judge the rest by the spread of the
specific force (its standard deviation from 10 samples is good to about 25 %)."""
REST_RATE_DEG_S = 3.0
"""Largest mean angular rate of a levelling window, deg/s (the segmentation's rest rate)."""


def level_attitude(f_b, gamma_e, C_n_e):
    """Body -> ECEF attitude from the mean specific force at rest, heading still free.

    TRIAD with the down direction exact: ``-f/|f|`` maps onto ``gamma/|gamma|``; the
    horizontal part of the body x axis (of the body y axis when x is within 1 deg of the
    vertical, as on a vertical launch rail) then points North of the geodetic NED frame
    ``C_n_e``. The caller turns the result about the vertical to the heading.

    Parameters
    ----------
    f_b : numpy.ndarray
        Mean specific force at rest, body axes, m/s^2, (3,).
    gamma_e : numpy.ndarray
        Gravity in ECEF, m/s^2, (3,).
    C_n_e : numpy.ndarray
        NED -> ECEF rotation matrix at the site, (3, 3).

    Returns
    -------
    scipy.spatial.transform.Rotation
        Body -> ECEF attitude.
    """
    d_b = -f_b / np.linalg.norm(f_b)
    z_e = gamma_e / np.linalg.norm(gamma_e)
    ref = np.eye(3)[0 if 1.0 - d_b[0] ** 2 >= VERTICAL_SIN2 else 1]
    t2_b = np.cross(d_b, ref)
    t2_b /= np.linalg.norm(t2_b)
    t2_e = np.cross(z_e, C_n_e[:, 0])
    t2_e /= np.linalg.norm(t2_e)
    T_b = np.column_stack([d_b, t2_b, np.cross(d_b, t2_b)])
    T_e = np.column_stack([z_e, t2_e, np.cross(z_e, t2_e)])
    return Rotation.from_matrix(T_e @ T_b.T)


TURN_ON_FALLBACK = {"gyro_bias_deg_s": 0.05, "accel_bias_m_s2": 0.02}
"""Turn-on bias sigmas for a preset that states none: the 21-state model's default P0
(``navlib.models.ecef.P0_DEFAULTS``, spec excitability.md §5)."""


def _imu_preset(preset) -> ImuSpec:
    """The IMU of the sensor preset named ``preset`` (None: :data:`DEFAULT_IMU_PRESET`)."""
    if preset is not None and not isinstance(preset, str):
        raise NavlibInputError(f"preset: expected a sensor preset name, got {preset!r}")
    imu = load_preset(preset or DEFAULT_IMU_PRESET).imu
    if imu is None:
        raise NavlibInputError(f"preset: {preset!r} has no IMU")
    return imu


def _white_sigmas(preset, rate):
    """Per-sample white-noise sigmas (specific force m/s^2, rate rad/s) of a preset."""
    imu = _imu_preset(preset)
    root = np.sqrt(rate)
    return float(imu.accel.noise_density) * root, float(imu.gyro.noise_density) * root


def _gnss_acceleration(tc, t_g, P_g, V_g, half_s, until=None):
    """Norm of the GNSS-derived acceleration around ``tc``: the slope of a straight line
    through the GNSS velocities within ``half_s`` (or the curvature of a parabola through
    the positions within ``5 half_s``: position noise needs the longer baseline); NaN when
    fewer than 3 epochs lie there. ``until``: only epochs up to that time count."""
    if until is not None:
        sel = t_g <= until
        t_g, P_g = t_g[sel], P_g[sel]
        V_g = None if V_g is None else V_g[sel]
    if V_g is not None:
        sel = np.abs(t_g - tc) <= half_s
        if sel.sum() < 3:
            return np.nan
        x = t_g[sel] - tc
        slope = np.polyfit(x, V_g[sel], 1)[0]
        return float(np.linalg.norm(slope))
    sel = np.abs(t_g - tc) <= 5.0 * half_s
    if sel.sum() < 3:
        return np.nan
    curv = np.polyfit(t_g[sel] - tc, P_g[sel], 2)[0]
    return float(np.linalg.norm(2.0 * curv))


def min_level_s(preset, rate_hz, tilt_deg):
    """Shortest rest window that levels to ``tilt_deg`` (1 sigma) at ``rate_hz``, s.

    Levelling takes the median specific force of the window; its tilt error from white
    accelerometer noise of ``sigma_f`` per sample (the ``preset``'s density times
    ``sqrt(rate_hz)``) is ``sqrt(pi / 2) sigma_f / (g sqrt(n))`` for ``n`` samples (the
    median's efficiency is 2/pi), so ``n >= (pi / 2) (sigma_f / (g tilt))^2``; at least
    ``MIN_LEVEL_SAMPLES`` samples are kept to judge the rest (docs/assumptions.md,
    "fit — levelling from a short pre-launch window"). For the ``pixhawk_mems`` preset at
    100 Hz and 0.1 deg this is the 10-sample floor, 0.1 s: the 0.3 s an AltOS log keeps
    before boost is enough. The accelerometer bias limits the tilt as well (0.1 m/s^2 is
    0.6 deg) whatever the window; the fit's attitude correction absorbs part of it.

    Parameters
    ----------
    preset : str or dict
        IMU noise preset.
    rate_hz : float
        IMU rate, Hz.
    tilt_deg : float
        Wanted tilt accuracy, deg (1 sigma).

    Returns
    -------
    float
        Window length, s.
    """
    sigma_f, _ = _white_sigmas(preset, rate_hz)
    n = np.pi / 2.0 * (sigma_f / (G0 * tilt_deg * DEG)) ** 2
    return max(int(np.ceil(n)), MIN_LEVEL_SAMPLES) / rate_hz


def quiet_window(t, f_b, w_b, g, p, gnss=None):
    """The rest window to level in (:func:`_rest_window`), tried in this order: a window of
    ``level_s`` within the first ``level_search_s``; a window of the shortest length
    :func:`min_level_s` allows there (a short pre-launch record: the GNSS is looked at
    before the window only, and the window grows over the run of neighbouring windows at
    rest); a window of ``level_s`` later; a short one later (a later window's attitude is
    carried back by the gyros, through all the flight's rotation, so an early short
    window is preferred to it). Returns sample indices and a description.

    Parameters
    ----------
    t : numpy.ndarray
        IMU time stamps, s.
    f_b : numpy.ndarray
        Specific force, m/s^2, (N, 3).
    w_b : numpy.ndarray
        Angular rate, rad/s, (N, 3).
    g : float
        Local gravity magnitude, m/s^2.
    p : dict
        Fit settings (``preset``, ``level_s``, ``level_search_s``, ``level_tilt_deg`` ...).
    gnss : pandas.DataFrame or None, optional
        GNSS fixes, used to check that the vehicle is at rest.

    Raises
    ------
    NavlibInputError
        If no window is at rest.
    """
    rate = 1.0 / float(np.median(np.diff(t)))
    short_s = min_level_s(p["preset"], rate, p["level_tilt_deg"])
    tries = [(p["level_s"], False)] + ([(short_s, True)] if short_s < p["level_s"] else [])
    first = None
    for early in (True, False):
        for length, short in tries:
            try:
                return _rest_window(t, f_b, w_b, g, p, gnss, length, short, early)
            except NavlibInputError as exc:
                if first is None and not early:
                    first = exc
    tail = (f"; nor any window of {short_s:.3g} s, the shortest that levels to "
            f"level_tilt_deg={p['level_tilt_deg']:g} with this preset's noise"
            if len(tries) > 1 else "")
    raise NavlibInputError(f"{first}{tail}") from None


def _rest_window(t, f_b, w_b, g, p, gnss, length, short, early_only):
    """The quietest window of ``length`` s in which the vehicle stands still (or hovers).

    Windows of ``length`` start every ``length / 2``. A window qualifies when its median
    specific force has a norm within ``level_tolerance`` of gravity ``g``, its spread (the
    RMS over the axes of the standard deviation of ``f``) is below ``3 sigma_f +
    vibration_allowance_mps2`` (``sigma_f`` the preset's per-sample white noise: motor
    vibration of an armed multicopter is 1-1.6 m/s^2 and averages out over the window) and
    its mean angular rate is below ``REST_RATE_DEG_S`` (plus three sigmas of the gyro
    white noise averaged over the window) and the GNSS sees no acceleration above
    ``REST_ACCEL_MPS2`` around it (:func:`_gnss_acceleration`; a turning or accelerating
    vehicle would tilt the levelled attitude; ``short``: only the epochs up to the window's
    end, since a launch follows a short pre-launch window at once). Of the qualifying
    windows within the first ``level_search_s`` the one with the smallest spread is taken,
    else (unless ``early_only``) the quietest later one (the gyros carry its attitude back
    to the start); with ``short`` it grows over the neighbouring qualifying windows.
    Returns sample indices
    ``k0, k1`` and a description.
    """
    rate = 1.0 / float(np.median(np.diff(t)))
    sigma_f, sigma_w = _white_sigmas(p["preset"], rate)
    starts = np.arange(t[0], max(t[-1] - length, t[0]) + 1e-12, 0.5 * length)
    k0 = np.searchsorted(t, starts, side="left")
    k1 = np.searchsorted(t, starts + length, side="right")
    ok = k1 - k0 >= 3
    k0, k1, starts = k0[ok], k1[ok], starts[ok]
    if k0.size == 0:
        raise NavlibInputError(f"imu: fewer than 3 samples in every level_s={length:g} s "
                               "window; raise level_s or pass initial_attitude")
    c1 = np.r_[np.zeros((1, 3)), np.cumsum(f_b, axis=0)]
    c2 = np.r_[np.zeros((1, 3)), np.cumsum(f_b**2, axis=0)]
    cw = np.r_[np.zeros((1, 3)), np.cumsum(w_b, axis=0)]
    n = (k1 - k0)[:, None]
    mean = (c1[k1] - c1[k0]) / n
    spread = np.sqrt(np.maximum((c2[k1] - c2[k0]) / n - mean**2, 0.0).sum(axis=1))
    mean_rate = np.linalg.norm((cw[k1] - cw[k0]) / n, axis=1)
    spread_max = 3.0 * sigma_f + p["vibration_allowance_mps2"]
    rate_max = REST_RATE_DEG_S * DEG + 3.0 * sigma_w / np.sqrt(n[:, 0])
    gravity_ok = np.abs(np.linalg.norm(mean, axis=1) - g) <= p["level_tolerance"] * g
    good = gravity_ok & (spread <= spread_max) & (mean_rate <= rate_max)
    accel = np.full(starts.size, np.nan)
    if gnss is not None:
        half = max(length, 2.0)
        for i in np.flatnonzero(good):
            accel[i] = _gnss_acceleration(starts[i] + 0.5 * length, *gnss, half,
                                          until=starts[i] + length if short else None)
        good &= ~(accel > REST_ACCEL_MPS2)
    early = good & (starts <= t[0] + p["level_search_s"])
    pool = early if early.any() or early_only else good
    if not pool.any():
        best = int(np.argmin(np.abs(np.linalg.norm(mean, axis=1) - g) / g
                             + spread / max(spread_max, 1e-12)))
        raise NavlibInputError(
            f"imu: no window of level_s={length:g} s where the vehicle is at rest, so "
            f"the initial attitude cannot be levelled; the closest, at t = {starts[best]:.6g} "
            f"s, has mean |f| = {np.linalg.norm(mean[best]):.3f} m/s^2 (gravity {g:.3f}, "
            f"level_tolerance={p['level_tolerance']:g}), spread {spread[best]:.3f} m/s^2 "
            f"(limit {spread_max:.3f}: 3 x {sigma_f:.3g} white noise of preset "
            f"{p['preset'] or 'motionpak_tactical'!r} + vibration_allowance_mps2="
            f"{p['vibration_allowance_mps2']:g}) and mean rate "
            f"{np.degrees(mean_rate[best]):.3g} deg/s (limit {np.degrees(rate_max[best]):.3g}),"
            f" and no window passing these has a GNSS acceleration below {REST_ACCEL_MPS2:g} "
            "m/s^2; pass initial_attitude, or a log with the autopilot's attitude")
    i = j = int(np.flatnonzero(pool)[np.argmin(spread[pool])])
    if short:                      # the whole run of overlapping windows at rest
        while i > 0 and good[i - 1]:
            i -= 1
        while j + 1 < good.size and good[j + 1]:
            j += 1
    seen = accel[i:j + 1][np.isfinite(accel[i:j + 1])]
    info = {"t_start": float(t[k0[i]]), "t_end": float(t[k1[j] - 1]),
            "spread_mps2": float(spread[i:j + 1].max()), "spread_limit_mps2": float(spread_max),
            "mean_rate_deg_s": float(np.degrees(mean_rate[i:j + 1].max())),
            "gnss_accel_mps2": float(seen.max()) if seen.size else float("nan"),
            "window_s": float(t[k1[j] - 1] - t[k0[i]]), "short": short}
    return int(k0[i]), int(k1[j]), info


def _attached_near(imu, key, columns, t0_s, valid=None):
    """The table a reader attached as ``imu.attrs[key]`` (columns ``t`` and ``columns``):
    its finite rows (and those ``valid`` accepts) as ``t, values`` and the index of the row
    nearest ``t0_s``; None when there is no such row within 1 s."""
    table = imu.attrs.get(key) if hasattr(imu, "attrs") else None
    if not isinstance(table, pd.DataFrame) or len(table) == 0 or not {
            "t", *columns} <= set(table.columns):
        return None
    t = table["t"].to_numpy(dtype=float)
    values = table[list(columns)].to_numpy(dtype=float)
    ok = np.all(np.isfinite(values), axis=1) & np.isfinite(t)
    if valid is not None:
        ok &= valid(values)
    if not ok.any():
        return None
    t, values = t[ok], values[ok]
    k = int(np.argmin(np.abs(t - t0_s)))
    if abs(t[k] - t0_s) > 1.0:
        return None
    return t, values, k


def logged_attitude(imu, t0_s, C_n_e):
    """Body -> ECEF attitude at ``t0_s`` from the autopilot attitude a reader attached
    (``imu.attrs["attitude"]``: ``t, qw, qx, qy, qz``, body -> NED), or None.

    Parameters
    ----------
    imu : pandas.DataFrame
        IMU record.
    t0_s : float
        Time, s.
    C_n_e : numpy.ndarray
        NED -> ECEF rotation matrix, (3, 3).

    Returns
    -------
    scipy.spatial.transform.Rotation or None
    """
    found = _attached_near(imu, "attitude", ("qx", "qy", "qz", "qw"), t0_s,
                           valid=lambda q: np.linalg.norm(q, axis=1) > 0.5)
    if found is None:
        return None
    t, q, k = found
    if k + 1 < t.size and t[k] < t0_s < t[k + 1]:
        C_b_n = Slerp(t[k:k + 2], Rotation.from_quat(q[k:k + 2]))([t0_s])[0]
    else:
        C_b_n = Rotation.from_quat(q[k])
    return Rotation.from_matrix(C_n_e) * C_b_n


def heading_of(C_b_e0, C_n_e):
    """Azimuth (rad) of the body x axis at the start.

    Parameters
    ----------
    C_b_e0 : scipy.spatial.transform.Rotation
        Body -> ECEF attitude.
    C_n_e : numpy.ndarray
        NED -> ECEF rotation matrix, (3, 3).

    Returns
    -------
    float
        Heading, rad.
    """
    x_n = C_n_e.T @ C_b_e0.apply([1.0, 0.0, 0.0])
    return float(np.arctan2(x_n[1], x_n[0]))


def coarse_heading(t, f_e, axis_e, t_g, P_g, V_g=None):
    """Heading correction (rad) rotating IMU specific force onto the GNSS-derived one.

    ``f_e`` is the IMU specific force in ECEF with the provisional attitude and ``axis_e``
    the (Earth-fixed, rotating) vertical about which the heading turns. With GNSS velocity
    the GNSS side is the velocity difference between consecutive epochs (the acceleration
    averaged over the interval, against the IMU average over the same interval); without,
    the second difference of positions (the acceleration averaged with a triangle weight,
    against the same weighting of the IMU). Velocity differences are far less noisy: at
    5 Hz, 2 m of position noise make second differences of ~100 m/s^2.

    Parameters
    ----------
    t : numpy.ndarray
        IMU time stamps, s.
    f_e : numpy.ndarray
        IMU specific force in ECEF, m/s^2, (N, 3).
    axis_e : numpy.ndarray
        Vertical, ECEF unit vector.
    t_g : numpy.ndarray
        GNSS time stamps, s.
    P_g : numpy.ndarray
        GNSS positions, ECEF, m.
    V_g : numpy.ndarray or None, optional
        GNSS velocities, ECEF, m/s.

    Returns
    -------
    float
        Heading correction, rad.
    """
    c_f = np.r_[np.zeros((1, 3)), np.cumsum(f_e, axis=0)]
    c_1 = np.arange(t.size + 1, dtype=float)
    if V_g is not None:
        h = np.diff(t_g)[:, None]
        vel = 0.5 * (V_g[1:] + V_g[:-1])
        gnss_f = (np.diff(V_g, axis=0) / h + 2.0 * np.cross(earth.EARTH_RATE_ECEF, vel)
                  - earth.normal_gravity_ecef(0.5 * (P_g[1:] + P_g[:-1])))
        i0 = np.searchsorted(t, t_g[:-1], side="left")
        i1 = np.searchsorted(t, t_g[1:], side="right")
        n = c_1[i1] - c_1[i0]
        imu_f = np.where((n > 0)[:, None], (c_f[i1] - c_f[i0]) / np.maximum(n, 1)[:, None],
                         np.nan)
    else:
        gnss_f, imu_f = _triangle_pairs(t, f_e, t_g, P_g, c_f, c_1)
    ok = np.all(np.isfinite(imu_f), axis=1)
    z = axis_e[0]
    u = imu_f[ok] - np.outer(imu_f[ok] @ z, z)
    w = gnss_f[ok] - np.outer(gnss_f[ok] @ z, z)
    if not ok.any() or np.sqrt(np.mean(np.sum(u**2, 1))) < _MIN_HORIZONTAL_F:
        raise NavlibInputError(
            "heading_deg: the horizontal specific force is too small to derive the heading "
            f"(needs an RMS above {_MIN_HORIZONTAL_F} m/s^2); pass heading_deg or "
            "initial_attitude")
    return float(np.arctan2(np.sum(np.cross(u, w) @ z), np.sum(u * w)))


def _triangle_pairs(t, f_e, t_g, P_g, c_f, c_1):
    """GNSS second differences and the triangle-weighted IMU averages over their windows
    (the second difference is the acceleration averaged with a triangle, B-spline, weight)."""
    h_prev, h_next = np.diff(t_g)[:-1], np.diff(t_g)[1:]
    P0, P1, P2 = P_g[:-2], P_g[1:-1], P_g[2:]
    acc = 2.0 * ((P2 - P1) / h_next[:, None] - (P1 - P0) / h_prev[:, None]) / (
        h_prev + h_next)[:, None]
    vel = (P2 - P0) / (h_prev + h_next)[:, None]
    gnss_f = acc + 2.0 * np.cross(earth.EARTH_RATE_ECEF, vel) - earth.normal_gravity_ecef(P1)
    lo, mid, hi = t_g[:-2], t_g[1:-1], t_g[2:]
    i_lo = np.searchsorted(t, lo, side="left")
    i_mid = np.searchsorted(t, mid, side="right")
    i_hi = np.searchsorted(t, hi, side="right")
    c_tf = np.r_[np.zeros((1, 3)), np.cumsum(t[:, None] * f_e, axis=0)]
    c_t = np.r_[0.0, np.cumsum(t)]

    def part(i0, i1):
        return c_f[i1] - c_f[i0], c_tf[i1] - c_tf[i0], c_1[i1] - c_1[i0], c_t[i1] - c_t[i0]

    f1, tf1, n1, s1 = part(i_lo, i_mid)              # rising side: (t - lo) / (mid - lo)
    f2, tf2, n2, s2 = part(i_mid, i_hi)              # falling side: (hi - t) / (hi - mid)
    d1, d2 = (mid - lo)[:, None], (hi - mid)[:, None]
    num = (tf1 - lo[:, None] * f1) / d1 + (hi[:, None] * f2 - tf2) / d2
    den = (s1 - lo * n1) / d1[:, 0] + (hi * n2 - s2) / d2[:, 0]
    imu_f = np.where((n1 + n2 > 0)[:, None], num / np.maximum(den, 1e-300)[:, None], np.nan)
    return gnss_f, imu_f


def start_attitude(imu, t, f_b, w_b, p, gamma0, C_n_e, gnss, earth_turn, relative,
                   pad_end=None):
    """Initial attitude (body -> ECEF at ``t[0]``, heading still free) without a user's or
    logger's full attitude: levelled in a rest window (:func:`quiet_window`), else the
    body-x elevation from the logger's tilt (``imu.attrs["tilt"]``), else from
    ``launch_elevation_deg``; for the last two the body y axis is horizontal (roll 0) and
    the caller sets the azimuth and estimates the roll. Returns the attitude, the source
    (``level``, ``tilt`` or ``rail``), its description and the levelling window (empty
    unless level). ``pad_end``: index of the lift-off sample
    (:func:`navlib.trajectory.liftoff.find_liftoff`); the levelling window then lies on the
    pad, never after lift-off (docs/assumptions.md FIT4).

    Parameters
    ----------
    imu : pandas.DataFrame
        IMU record (its ``attrs`` may carry a logged tilt).
    t : numpy.ndarray
        IMU time stamps, s.
    f_b : numpy.ndarray
        Specific force, m/s^2, (N, 3).
    w_b : numpy.ndarray
        Angular rate, rad/s, (N, 3).
    p : dict
        Fit settings.
    gamma0 : numpy.ndarray
        Gravity at the start, ECEF, m/s^2.
    C_n_e : numpy.ndarray
        NED -> ECEF rotation matrix, (3, 3).
    gnss : pandas.DataFrame or None
        GNSS fixes.
    earth_turn, relative : scipy.spatial.transform.Rotation
        Earth rotation and gyro-integrated body rotation since ``t[0]``, per sample.
    pad_end : int or None, optional
        Index of the lift-off sample.

    Raises
    ------
    NavlibInputError
        If no rest window, logged tilt or launch elevation is available.
    """
    pad = slice(None) if pad_end is None else slice(0, pad_end + 1)
    try:
        k0, k1, info = quiet_window(t[pad], f_b[pad], w_b[pad], np.linalg.norm(gamma0), p,
                                    gnss)
    except NavlibInputError as exc:
        tilt = _logged_tilt(imu, t[0])
        if tilt is not None:
            elevation, kind = 0.5 * np.pi - tilt, "tilt"
            note = f"logger tilt ({np.degrees(tilt):.1f} deg from vertical)"
        elif p["launch_elevation_deg"] is not None:
            elevation, kind = p["launch_elevation_deg"] * DEG, "rail"
            note = f"launch rail {p['launch_elevation_deg']:g} deg elevation"
        else:
            raise NavlibInputError(f"{exc}; the log has no tilt either: give "
                                   "launch_elevation_deg (and launch_azimuth_deg) or "
                                   "initial_attitude_deg") from None
        att0 = Rotation.from_matrix(C_n_e) * Rotation.from_euler("ZYX", [0.0, elevation, 0.0])
        return att0, kind, note, {}
    att_q = level_attitude(np.median(f_b[k0:k1], axis=0), gamma0, C_n_e)
    # attitude at the window start, carried back to t[0] through the gyro history
    E_q, R_q = earth_turn[k0], relative[k0]
    att0 = E_q.inv() * att_q * R_q.inv() * E_q
    where = "pre-launch" if info["short"] else "rest"
    note = (f"levelled from {info['window_s']:.2f} s {where} window "
            f"({info['t_start']:.6g}..{info['t_end']:.6g} s)")
    return att0, "level", note, info


def _logged_tilt(imu, t0_s):
    """Body-x angle from the vertical (rad) at ``t0_s`` from the tilt a reader attached
    (``imu.attrs["tilt"]``: ``t, tilt`` in rad), or None (no tilt within 1 s)."""
    found = _attached_near(imu, "tilt", ("tilt",), t0_s)
    if found is None:
        return None
    _, a, k = found
    return float(np.clip(a[k, 0], 0.0, np.pi))


def gyro_drift_deg_s(preset):
    """Default ``attitude_drift_deg_s``: how fast an uncorrected gyro bias turns the
    attitude, the preset's turn-on gyro bias (at least 0.01 deg/s); 0.01 without a preset."""
    if preset is None:
        return 0.01
    bias = _imu_preset(preset).gyro.bias
    return max(0.01, bias / DEG if bias > 0 else TURN_ON_FALLBACK["gyro_bias_deg_s"])


def accel_bias_sigma(p):
    """Prior sigma of the fit's accelerometer bias, m/s^2: ``sigma_accel_bias_mps2``, else
    the turn-on value of the named ``preset``, else 0 (no bias estimated)."""
    if p["sigma_accel_bias_mps2"] is not None:
        return p["sigma_accel_bias_mps2"]
    if p["preset"] is None:
        return 0.0
    bias = _imu_preset(p["preset"]).accel.bias
    return float(bias) if bias > 0 else TURN_ON_FALLBACK["accel_bias_m_s2"]


def accel_scale_sigma(p):
    """Prior sigma of the fit's accelerometer scale-factor error (dimensionless):
    ``sigma_accel_scale``, else the named ``preset``'s scale factor, else 0 (none
    estimated)."""
    if p["sigma_accel_scale"] is not None:
        return p["sigma_accel_scale"]
    if p["preset"] is None:
        return 0.0
    return float(_imu_preset(p["preset"]).accel.scale_factor)
