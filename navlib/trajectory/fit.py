"""A kinematically exact reference trajectory fitted to recorded flight data.

The idea of Giribet et al. (2007), as used by España et al. (2019, docs/assumptions.md,
excitability.md §4): find the smooth B-spline trajectory that best fits the recorded IMU and GNSS
data in a least-squares sense and whose IMU signals satisfy the kinematics (spec Eq. 1) exactly. Its
IMU is then re-derived from the splines with :func:`navlib.trajectory.base.exact_imu`, so a correct
strapdown integrating it reproduces the fitted position and attitude to the last digit of the
integrator.

How it works (initial attitude, attitude history, the position spline with its attitude
correction and IMU calibration, the attitude spline on SO(3), holes and rates, the residuals
it reports): docs/fit.md.
"""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
from scipy.spatial.transform import Rotation

from navlib import earth, strapdown
from navlib._validation import finite_array, finite_scalar, increasing_times, reject_unknown
from navlib.errors import NavlibInputError
from navlib.io import FlightDataWarning, check_overlap
from navlib.io.gnss_faults import shifted
from navlib.trajectory._so3 import SO3Spline
from navlib.trajectory.base import Trajectory, build_trajectory
from navlib.trajectory.gnss_lag import (
    LAG_MIN_GAIN,
    LAG_ROUNDS,
    LAG_STEP_S,
    MIN_GNSS_LAG_S,
    best_lag,
    lag_displacement,
    lag_profile,
)
from navlib.trajectory.initial_attitude import (
    VERTICAL_SIN2,
    accel_bias_sigma,
    accel_scale_sigma,
    coarse_heading,
    gyro_drift_deg_s,
    heading_of,
    logged_attitude,
    start_attitude,
)
from navlib.trajectory.liftoff import (
    LIFTOFF_KNOTS_S,
    liftoff_knots,
    pad_and_fixes,
    pad_start,
    thrust_change_knots,
)
from navlib.trajectory.position_spline import (
    ATTITUDE_SAMPLES_PER_KNOT,
    MAX_KNOT_SPACING_S,
    SAMPLES_PER_KNOT,
    SPLINE_DEGREE,
    AttitudeCorrection,
    PositionRows,
    place_knots,
    resolved_samples,
    thin,
)
from navlib.units import DEG

__all__ = ["FIT_DEFAULTS", "GNSS_COLUMNS", "GNSS_VELOCITY_COLUMNS", "HOLE_FACTOR", "IMU_COLUMNS",
           "MIN_IMU_RATE_HZ", "SCALE_CREDIBLE_SIGMAS", "fit_flight_data", "hole_bounds",
           "rate_and_holes"]

FIT_DEFAULTS = {
    "knot_spacing_s": 0.1,
    "attitude_knot_spacing_s": None,
    "sigma_position_m": 5.0,
    "sigma_velocity_mps": 0.5,
    "sigma_specific_force_mps2": 0.05,
    "heading_deg": None,
    "initial_attitude": None,
    "level_s": 1.0,
    "level_tilt_deg": 0.1,
    "initial_attitude_deg": None,
    "launch_elevation_deg": None,
    "launch_azimuth_deg": None,
    "level_tolerance": 0.05,
    "level_search_s": 60.0,
    "preset": None,
    "vibration_allowance_mps2": 2.0,
    "use_logged_attitude": True,
    "hold_pad": True,
    "estimate_gnss_lag": True,
    "max_bridge_s": 1.0,
    "sigma_accel_bias_mps2": None,
    "sigma_accel_scale": None,
    "attitude_prior_deg": 5.0,
    "attitude_drift_deg_s": None,
    "correction_knot_spacing_s": 10.0,
    "iterations": 3,
    "name": "fitted flight",
}

IMU_COLUMNS = ("t", "f_x", "f_y", "f_z", "w_x", "w_y", "w_z")
GNSS_COLUMNS = ("t", "x", "y", "z")
GNSS_VELOCITY_COLUMNS = ("vx", "vy", "vz")
_MIN_GNSS = 4
_MIN_IMU = 20
MIN_IMU_RATE_HZ = SAMPLES_PER_KNOT / MAX_KNOT_SPACING_S
"""Slowest median IMU rate the fit accepts, Hz (4 Hz): ``SAMPLES_PER_KNOT`` samples per
knot interval of at most ``MAX_KNOT_SPACING_S``. It is also twice the 1 Hz motion bandwidth
above (Nyquist), below which the gyro integration aliases the attitude."""
SCALE_CREDIBLE_SIGMAS = 3.0
"""An accelerometer scale error the fit estimates beyond this many prior sigmas (the
preset's scale-factor tolerance) is not a calibration but the fit shrinking a motion it
cannot follow (a tumble it does not resolve); the fit is then redone without a scale."""
HOLE_FACTOR = 10.0
"""An IMU interval longer than this many median intervals is a hole (as the readers'
``max_gap_s=None``, :data:`navlib.io.checks.AUTO_GAP_FACTOR`)."""

# --- input checking ----------------------------------------------------------------------


def _columns(frame, name, required, optional=()):
    if not isinstance(frame, pd.DataFrame):
        raise NavlibInputError(f"{name}: expected a pandas DataFrame, got {type(frame).__name__}")
    missing = [c for c in required if c not in frame.columns]
    if missing:
        raise NavlibInputError(
            f"{name}: missing column(s) {missing}; columns are {list(frame.columns)}")
    present = [c for c in optional if c in frame.columns]
    if present and len(present) != len(optional):
        absent = [c for c in optional if c not in frame.columns]
        raise NavlibInputError(
            f"{name}: velocity columns must come together; have {present}, missing {absent}")
    out = {}
    for col in (*required, *present):
        out[col] = finite_array(frame[col].to_numpy(dtype=float, na_value=np.nan),
                                f"{name} column {col!r}", ndim=1)
    increasing_times(out["t"], f"{name} column 't'")
    return out


def _options(options):
    reject_unknown(options, FIT_DEFAULTS, "fit_flight_data")
    p = {**FIT_DEFAULTS, **options}
    for key in ("knot_spacing_s", "sigma_position_m", "sigma_velocity_mps",
                "sigma_specific_force_mps2", "level_s", "level_tolerance", "attitude_prior_deg",
                "level_tilt_deg",
                "correction_knot_spacing_s", "level_search_s",
                "max_bridge_s"):
        p[key] = finite_scalar(p[key], key, 0.0, low_open=True)
    if p["attitude_drift_deg_s"] is None:
        p["attitude_drift_deg_s"] = gyro_drift_deg_s(p["preset"])
    p["attitude_drift_deg_s"] = finite_scalar(p["attitude_drift_deg_s"], "attitude_drift_deg_s",
                                              0.0, low_open=True)
    p["vibration_allowance_mps2"] = finite_scalar(p["vibration_allowance_mps2"],
                                                  "vibration_allowance_mps2", 0.0)
    if p["sigma_accel_scale"] is not None:
        p["sigma_accel_scale"] = finite_scalar(p["sigma_accel_scale"], "sigma_accel_scale",
                                               0.0, 0.5)
    if p["sigma_accel_bias_mps2"] is not None:
        p["sigma_accel_bias_mps2"] = finite_scalar(p["sigma_accel_bias_mps2"],
                                                   "sigma_accel_bias_mps2", 0.0)
    if p["knot_spacing_s"] > MAX_KNOT_SPACING_S:
        raise NavlibInputError(f"knot_spacing_s: {p['knot_spacing_s']:g} s exceeds "
                               f"{MAX_KNOT_SPACING_S:g} s (MAX_KNOT_SPACING_S)")
    for key in ("hold_pad", "estimate_gnss_lag"):
        if not isinstance(p[key], bool):
            raise NavlibInputError(f"{key}: expected True or False, got {p[key]!r}")
    if not isinstance(p["use_logged_attitude"], bool):
        raise NavlibInputError("use_logged_attitude: expected True or False, got "
                               f"{p['use_logged_attitude']!r}")
    if p["preset"] is not None and not isinstance(p["preset"], str):
        raise NavlibInputError(f"preset: expected a sensor preset name, got {p['preset']!r}")
    if p["attitude_knot_spacing_s"] is None:
        p["attitude_knot_spacing_s"] = p["knot_spacing_s"]
    p["attitude_knot_spacing_s"] = finite_scalar(p["attitude_knot_spacing_s"],
                                                 "attitude_knot_spacing_s", 0.0, low_open=True)
    if p["heading_deg"] is not None:
        p["heading_deg"] = finite_scalar(p["heading_deg"], "heading_deg", -360.0, 360.0)
    iterations = finite_scalar(p["iterations"], "iterations", 1.0, 20.0)
    if iterations != int(iterations):
        raise NavlibInputError(f"iterations: expected an integer, got {p['iterations']!r}")
    p["iterations"] = int(iterations)
    if p["launch_elevation_deg"] is not None:
        p["launch_elevation_deg"] = finite_scalar(p["launch_elevation_deg"],
                                                  "launch_elevation_deg", -90.0, 90.0)
    if p["launch_azimuth_deg"] is not None:
        p["launch_azimuth_deg"] = finite_scalar(p["launch_azimuth_deg"], "launch_azimuth_deg",
                                                -360.0, 360.0)
        if p["heading_deg"] is not None and p["heading_deg"] != p["launch_azimuth_deg"]:
            raise NavlibInputError(
                f"launch_azimuth_deg: {p['launch_azimuth_deg']:g} differs from heading_deg="
                f"{p['heading_deg']:g} (both are the body-x azimuth at the start); give one")
    if p["initial_attitude_deg"] is not None:
        if p["initial_attitude"] is not None:
            raise NavlibInputError("initial_attitude_deg: give it or initial_attitude, not both")
        p["initial_attitude_deg"] = finite_array(p["initial_attitude_deg"],
                                                 "initial_attitude_deg (yaw, pitch, roll)", (3,))
    q0 = p["initial_attitude"]
    if q0 is not None:
        if isinstance(q0, Rotation):
            if not q0.single:
                raise NavlibInputError("initial_attitude: expected one Rotation, got a stack")
        else:
            mat = finite_array(q0, "initial_attitude", (3, 3))
            if not np.allclose(mat.T @ mat, np.eye(3), atol=1e-6) or np.linalg.det(mat) < 0:
                raise NavlibInputError("initial_attitude: the 3x3 matrix is not a rotation")
            p["initial_attitude"] = Rotation.from_matrix(mat)
    return p


def rate_and_holes(t, max_bridge_s):
    """Median IMU rate (Hz) and the holes (index of the sample after each) to bridge.

    Refuses rates below :data:`MIN_IMU_RATE_HZ` and holes longer than ``max_bridge_s``.

    Parameters
    ----------
    t : numpy.ndarray
        IMU times, s.
    max_bridge_s : float
        Longest hole bridged, s.

    Raises
    ------
    NavlibInputError
        If the rate is too low or a hole too long.
    """
    dt = np.diff(t)
    rate = float(1.0 / np.median(dt))
    if rate < MIN_IMU_RATE_HZ:
        raise NavlibInputError(
            f"imu: median rate {rate:.3g} Hz is below the minimum {MIN_IMU_RATE_HZ:g} Hz of "
            f"the fit: it needs {SAMPLES_PER_KNOT} samples per spline knot interval of at most "
            f"{MAX_KNOT_SPACING_S:g} s to follow ~1 Hz manoeuvres (and twice that motion "
            "bandwidth to integrate the gyros without aliasing)")
    after = np.flatnonzero(dt > HOLE_FACTOR / rate) + 1
    longest = int(after[np.argmax(dt[after - 1])]) if after.size else None
    if longest is not None and dt[longest - 1] > max_bridge_s:
        raise NavlibInputError(
            f"imu: hole of {dt[longest - 1]:.3g} s between t = {t[longest - 1]:.6g} s and "
            f"{t[longest]:.6g} s is longer than max_bridge_s={max_bridge_s:g} s; assess the "
            "pieces on either side separately (navlib.studies.assess.assess_flight splits "
            "there itself) or raise max_bridge_s")
    return rate, after


def hole_bounds(t, f_b, w_b, after):
    """Stated uncertainty of each bridged IMU hole (module docstring, "Holes").

    Across a hole of length ``L`` the gyro history and the position spline interpolate
    between the samples on either side. If the signals vary monotonically inside, the
    attitude error stays below ``theta = |w_b - w_a| L / 2`` and the position error below
    ``(|f_b - f_a| / 2 + |f| theta) L^2 / 8`` (the deflection of a string of length ``L``
    pinned at both ends under that acceleration error).

    Parameters
    ----------
    t : numpy.ndarray
        IMU times, s.
    f_b, w_b : numpy.ndarray
        Specific force, m/s^2, and angular rate, rad/s, (N, 3).
    after : numpy.ndarray
        Index of the sample after each hole.
    """
    out = []
    for k in after:
        L = float(t[k] - t[k - 1])
        theta = 0.5 * L * float(np.linalg.norm(w_b[k] - w_b[k - 1]))
        f_mag = 0.5 * float(np.linalg.norm(f_b[k]) + np.linalg.norm(f_b[k - 1]))
        acc = 0.5 * float(np.linalg.norm(f_b[k] - f_b[k - 1])) + f_mag * theta
        out.append({"t_start": float(t[k - 1]), "t_end": float(t[k]), "duration_s": L,
                    "attitude_bound_deg": float(np.degrees(theta)),
                    "position_bound_m": acc * L**2 / 8.0})
    return out


# --- the fit -----------------------------------------------------------------------------


def fit_flight_data(imu, gnss, **options) -> Trajectory:
    """Least-squares B-spline reference trajectory with an exact IMU (Giribet et al. 2007).

    Parameters
    ----------
    imu : DataFrame
        Columns ``t, f_x, f_y, f_z, w_x, w_y, w_z`` (s, m/s^2, rad/s; body axes; point
        samples), as from :func:`navlib.io.read_imu_csv`.
    gnss : DataFrame
        Columns ``t, x, y, z`` (ECEF, m) and optionally ``vx, vy, vz`` (m/s) and ``sigma``
        (per-epoch position standard deviation, m), on the IMU's time base.
    **options
        ``knot_spacing_s=0.1`` (position spline), ``attitude_knot_spacing_s=None`` (same),
        ``sigma_position_m=5`` (when no ``sigma`` column), ``sigma_velocity_mps=0.5``,
        ``sigma_specific_force_mps2=0.05`` (weights of the three kinds of rows),
        ``heading_deg=None`` (azimuth of the body x axis at the start; None: estimated),
        ``attitude_prior_deg=5``, ``attitude_drift_deg_s=None`` (the named ``preset``'s
        turn-on gyro bias, at least 0.01; 0.01 without a preset),
        ``correction_knot_spacing_s=10`` (the attitude correction, method step 3),
        ``initial_attitude=None`` (a scipy Rotation or 3x3 body -> ECEF matrix at the first
        IMU sample of the overlap; replaces levelling and heading),
        ``use_logged_attitude=True`` (start from ``imu.attrs["attitude"]`` when present),
        ``hold_pad=True`` (zero velocity and the lift-off attitude from the first sample
        until the lift-off :func:`~navlib.trajectory.liftoff.find_liftoff` reads from the
        recorded specific force; levelling only on that pad; docs/assumptions.md FIT4),
        ``estimate_gnss_lag=True`` (fixes that trail the fitted motion by a significant lag
        are moved back by it and the fit redone; ``fit_residuals["gnss_lag_s"]``; FIT6),
        ``initial_attitude_deg=None`` (yaw, pitch, roll of the body against the local NED
        frame at the first sample, deg; replaces levelling and heading),
        ``launch_elevation_deg=None``, ``launch_azimuth_deg=None`` (launch-rail angles of
        the body x axis, deg: the azimuth sets the heading of any source that leaves it
        free, the elevation is used when neither levelling nor a logged tilt is possible),
        ``level_s=1`` (length of the rest window used for levelling),
        ``level_tilt_deg=0.1`` (tilt accuracy that sets the shortest levelling window
        tried when no ``level_s`` window is at rest,
        :func:`~navlib.trajectory.initial_attitude.min_level_s`),
        ``level_tolerance=0.05`` (accepted relative difference between its median |f| and
        normal gravity: consumer MEMS scale factors reach a few percent),
        ``level_search_s=60`` (windows starting this long after the start are preferred),
        ``preset=None`` (sensor preset whose white noise sets the rest thresholds; None:
        ``motionpak_tactical``), ``vibration_allowance_mps2=2`` (accelerometer spread of
        motor vibration accepted at rest), ``max_bridge_s=1`` (longest IMU hole bridged),
        ``sigma_accel_bias_mps2=None`` (prior sigma of the constant accelerometer bias the
        fit estimates; None: the named ``preset``'s turn-on bias, no bias without a preset),
        ``sigma_accel_scale=None`` (prior sigma of its per-axis scale-factor error; None:
        the ``preset``'s scale factor, none without a preset),
        ``iterations=3`` (gravity/Coriolis/heading relinearisations), ``name``.

    Returns
    -------
    Trajectory
        Sampled at the IMU times inside the common span; its IMU is exact for the fitted
        splines. ``parameters["fit_residuals"]`` reports the residuals (module docstring);
        ``parameters`` also holds the options used. ``events``: ``start``, ``end``.

    Raises
    ------
    NavlibInputError
        Missing or non-finite columns, non-increasing times, too few samples,
        non-overlapping spans, an IMU rate below ``MIN_IMU_RATE_HZ``, a hole longer than
        ``max_bridge_s``, no rest window to level in (without ``initial_attitude``, a
        logged attitude or tilt, or ``launch_elevation_deg``), a heading that cannot be
        estimated, unknown options.
    """
    p = _options(options)
    traj = _fit(imu, gnss, p)
    lag = 0.0
    if p["estimate_gnss_lag"]:
        # each fit follows part of the lag its fixes carry, so the scan of a refit with the
        # lag found sees the rest; kept only when the refits lower the GNSS residual enough
        base = traj
        profile = base.parameters["fit_residuals"]["gnss_lag_profile"]
        for k in range(LAG_ROUNDS):
            found = traj.parameters["fit_residuals"]["gnss_lag_profile"]
            step = best_lag(found["lag_s"], found["rms_m"],
                            MIN_GNSS_LAG_S if k == 0 else 0.25 * LAG_STEP_S)
            if not step:
                break
            lag += step
            traj = _fit(imu, shifted(gnss, lag), p)
        rms = [x.parameters["fit_residuals"]["gnss_position_rms_3d_m"] for x in (base, traj)]
        sigma = float(np.median(gnss["sigma"])) if "sigma" in gnss else p["sigma_position_m"]
        if (abs(lag) < MIN_GNSS_LAG_S or rms[1] > (1.0 - LAG_MIN_GAIN) * rms[0]
                or lag_displacement(base, gnss["t"].to_numpy(dtype=float), lag) < sigma):
            traj, lag = base, 0.0
        traj.parameters["fit_residuals"]["gnss_lag_profile"] = profile
    traj.parameters["fit_residuals"]["gnss_lag_s"] = lag
    return traj


def _fit(imu, gnss, p) -> Trajectory:
    """:func:`fit_flight_data` with checked options ``p`` and the fixes at their times."""
    imu_cols = _columns(imu, "imu", IMU_COLUMNS)
    gnss_cols = _columns(gnss, "gnss", GNSS_COLUMNS, GNSS_VELOCITY_COLUMNS)
    if "sigma" in gnss.columns:
        sigma = finite_array(gnss["sigma"].to_numpy(dtype=float, na_value=np.nan),
                             "gnss column 'sigma'", ndim=1)
        if np.any(sigma <= 0):
            raise NavlibInputError("gnss column 'sigma': values must be positive")
    else:
        sigma = np.full(gnss_cols["t"].size, p["sigma_position_m"])
    span = check_overlap(imu, gnss, min_overlap_s=2.0 * p["knot_spacing_s"])

    t_all = imu_cols["t"]
    t_start = span.t_start
    if p["hold_pad"]:
        t_start = pad_start(t_all, np.column_stack([imu_cols[c] for c in IMU_COLUMNS[1:]]),
                            np.array([gnss_cols[c][0] for c in GNSS_COLUMNS[1:]]), t_start,
                            p["level_tolerance"])
    keep = (t_all >= t_start) & (t_all <= span.t_end)
    if keep.sum() < _MIN_IMU:
        raise NavlibInputError(
            f"imu: need at least {_MIN_IMU} samples inside the common span, got {keep.sum()}")
    t = t_all[keep]
    f_b = np.column_stack([imu_cols[c][keep] for c in ("f_x", "f_y", "f_z")])
    w_b = np.column_stack([imu_cols[c][keep] for c in ("w_x", "w_y", "w_z")])
    rate, holes = rate_and_holes(t, p["max_bridge_s"])
    pad, t_fix, g_keep = pad_and_fixes(
        t, f_b, w_b, gnss_cols["t"], np.column_stack([gnss_cols[c] for c in GNSS_COLUMNS[1:]]),
        p["level_tolerance"], p["hold_pad"])
    if g_keep.sum() < _MIN_GNSS:
        raise NavlibInputError(
            f"gnss: need at least {_MIN_GNSS} epochs inside the IMU span, got {g_keep.sum()}")
    t_g, t_stamp = t_fix[g_keep], gnss_cols["t"][g_keep]
    P_g = np.column_stack([gnss_cols[c][g_keep] for c in GNSS_COLUMNS[1:]])
    V_g = (np.column_stack([gnss_cols[c][g_keep] for c in GNSS_VELOCITY_COLUMNS])
           if "vx" in gnss_cols else None)
    sigma = sigma[g_keep]
    if np.any(np.linalg.norm(P_g, axis=1) < 1e6):
        raise NavlibInputError("gnss: positions must be ECEF in metres (|r| < 1000 km found)")

    # 1-2: initial attitude and gyro-integrated attitude history -------------------------
    lat0, lon0, _ = earth.ecef_to_geodetic(P_g[0])
    C_n_e = earth.ned_to_ecef_matrix(lat0, lon0)
    gamma0 = earth.normal_gravity_ecef(P_g[0])
    P_start = P_g[0]
    # Earth rotation since t[0] (ECEF mechanisation: C(t) = E(t) C0 B(t), E = exp(-S(Omega) t))
    earth_turn = Rotation.from_rotvec(np.outer(-(t - t[0]), earth.EARTH_RATE_ECEF))
    relative = earth_turn * strapdown.body_attitude(t, w_b)   # E(t) B(t): the start taken as I
    pad_end = None if pad is None else pad[1]
    user = p["initial_attitude"] is not None or p["initial_attitude_deg"] is not None
    logged = logged_attitude(imu, t[0], C_n_e) if (
        not user and p["use_logged_attitude"]) else None
    level_info = {}
    azimuth_deg = p["heading_deg"] if p["heading_deg"] is not None else p["launch_azimuth_deg"]
    if user:
        att0, source, kind = p["initial_attitude"], "initial_attitude", "user"
        if att0 is None:
            att0 = Rotation.from_matrix(C_n_e) * Rotation.from_euler(
                "ZYX", p["initial_attitude_deg"] * DEG)
        note = "user (initial_attitude" + ("_deg" if p["initial_attitude"] is None else "") + ")"
    elif logged is not None:
        att0, source, kind = logged, "log", "log"
        note = "logger attitude (the autopilot's own attitude estimate logged at the start)"
    else:
        att0, kind, note, level_info = start_attitude(
            imu, t, f_b, w_b, p, gamma0, C_n_e, (t_g, P_g, V_g), earth_turn, relative,
            pad_end)
        if azimuth_deg is not None:
            x_down = att0.apply([1.0, 0.0, 0.0]) @ (gamma0 / np.linalg.norm(gamma0))
            if 1.0 - x_down**2 < VERTICAL_SIN2:
                raise NavlibInputError(
                    "heading_deg: the body x axis is within 1 deg of the vertical at the "
                    "start, so its azimuth (heading_deg, launch_azimuth_deg) is undefined; "
                    "pass initial_attitude_deg instead")
            down = gamma0 / np.linalg.norm(gamma0)
            turn = azimuth_deg * DEG - heading_of(att0, C_n_e)
            att0 = Rotation.from_rotvec(down * turn) * att0
        source = "keyword"
    attitude = earth_turn * att0 * earth_turn.inv() * relative
    # the vertical about which a heading change turns, carried along with the Earth
    axis_e = earth_turn.apply(gamma0 / np.linalg.norm(gamma0))
    if source == "keyword" and azimuth_deg is None:
        delta = coarse_heading(t, attitude.apply(f_b), axis_e, t_g, P_g, V_g)
        attitude = Rotation.from_rotvec(axis_e * delta) * attitude
        source = "estimated"
    if kind in ("tilt", "rail"):
        # the roll about the start's body x axis: the same closed form about that axis
        x_e = earth_turn.apply(attitude[0].apply([1.0, 0.0, 0.0]))
        try:
            delta = coarse_heading(t, attitude.apply(f_b), x_e, t_g, P_g, V_g)
            attitude = Rotation.from_rotvec(x_e * delta) * attitude
            roll = f"roll about body x estimated from GNSS ({np.degrees(delta):.1f} deg)"
        except NavlibInputError:
            roll = "roll about body x 0 (the specific force never leaves that axis)"
        note += (", azimuth " + ("estimated from GNSS" if azimuth_deg is None else
                                 f"{azimuth_deg:g} deg given") + ", " + roll)
    if p["launch_elevation_deg"] is not None and kind != "rail":
        unused = _unused_elevation(p["launch_elevation_deg"], attitude[0], C_n_e, note)
        warnings.warn(unused, FlightDataWarning, stacklevel=2)
        note += f"; {unused}"

    attitude = _hold_pad(attitude, pad_end)

    # 3: position spline and attitude correction --------------------------------------
    knots = place_knots(t, p["knot_spacing_s"])
    keep_out = None
    if pad is not None:
        knots = liftoff_knots(knots, t, pad_end)
        keep_out = (float(t[pad_end]), float(t[pad_end]) + LIFTOFF_KNOTS_S)
    resolved = resolved_samples(t, w_b)
    knots = thrust_change_knots(knots, t, f_b, resolved, keep_out)
    sigma_sa, scale_note = np.full(3, accel_scale_sigma(p)), ""
    while True:
        rows = PositionRows(knots, t, t_g, P_g, V_g, sigma, p, P_start, pad_end, resolved)
        correction, corrected, coef = _correct(rows, attitude, f_b, t, p, sigma_sa)
        beyond = np.abs(correction.scale) > SCALE_CREDIBLE_SIGMAS * sigma_sa
        if not (beyond & (sigma_sa > 0)).any():
            break
        scale_note += "".join(
            f"accelerometer {axis} scale error {correction.scale[i]:.3g} found, beyond "
            f"{SCALE_CREDIBLE_SIGMAS:g} x its prior {sigma_sa[i]:.3g}: taken as the fit "
            "absorbing a motion it does not follow, refitted without that scale; "
            for i, axis in enumerate("xyz") if beyond[i] and sigma_sa[i] > 0)
        sigma_sa = np.where(beyond, 0.0, sigma_sa)
    scale_note = scale_note.rstrip("; ")
    attitude = corrected

    # 4: smooth attitude on SO(3) --------------------------------------------------------
    attitude = _hold_pad(attitude, pad_end)    # the correction's slow drift, undone there
    rate_norm = np.linalg.norm(w_b, axis=1)
    turn = np.r_[0.0, np.cumsum(0.5 * (rate_norm[1:] + rate_norm[:-1]) * np.diff(t))]
    att_knots = place_knots(t, p["attitude_knot_spacing_s"], turn)
    used = thin(t, att_knots, ATTITUDE_SAMPLES_PER_KNOT)
    C_b_e, w_eb_b = SO3Spline.fit(t[used], attitude[used], att_knots, SPLINE_DEGREE).evaluate(t)

    # 5: final position fit with the smooth attitude, exact IMU, residuals ----------------
    f_e = np.einsum("nij,nj->ni", C_b_e, correction.corrected(f_b))
    for _ in range(p["iterations"]):
        coef, _ = rows.solve(f_e, coef)
    P, V, a = rows.evaluate(coef)
    attitude_fit = Rotation.from_matrix(C_b_e)
    events = {"start": float(t[0]), "end": float(t[-1])}
    if pad is not None:
        events["liftoff"] = pad[0]
    traj = build_trajectory(t, P, V, a, C_b_e, w_eb_b, events=events, name=str(p["name"]))
    residuals = _residuals(traj, f_b, w_b, rows, coef, t_g, P_g, V_g)
    if p["estimate_gnss_lag"]:
        lags, rms = lag_profile(rows, f_e, coef, t_stamp, P_g, V_g, sigma)
        residuals["gnss_lag_profile"] = {"lag_s": lags.tolist(), "rms_m": rms.tolist()}
    residuals.update({
        "heading_deg": float(np.degrees(heading_of(attitude_fit[0], C_n_e))),
        "heading_source": source, "initial_attitude_source": kind,
        "initial_attitude_note": note, "n_imu": int(t.size), "n_gnss": int(t_g.size),
        "n_knots": int(knots.size - 2 * SPLINE_DEGREE), "imu_rate_hz": rate,
        "imu_holes": hole_bounds(t, f_b, w_b, holes), "level": level_info,
        "sigma_specific_force_used_mps2": float(np.median(rows.sigma_f)),
        "accel_bias_mps2": [float(b) for b in correction.bias],
        "accel_scale": [float(1.0 + s) for s in correction.scale],
        "accel_scale_note": scale_note,
        "unresolved_fraction": float(1.0 - resolved.mean()),
        "liftoff_s": None if pad is None else pad[0],
    })
    params = {k: v for k, v in p.items() if k not in ("initial_attitude", "initial_attitude_deg")}
    params["fit_residuals"] = residuals
    return Trajectory(t=traj.t, position=traj.position, velocity=traj.velocity,
                      attitude=traj.attitude, specific_force=traj.specific_force,
                      angular_rate=traj.angular_rate, events=traj.events, name=traj.name,
                      parameters=params)


def _unused_elevation(given_deg, C_b_e0, C_n_e, source):
    """The words for a ``launch_elevation_deg`` that another source outranked: which, and
    how far the body-x elevation it gave lies from the flag (docs/assumptions.md FIT5)."""
    x_n = C_n_e.T @ C_b_e0.apply([1.0, 0.0, 0.0])
    elevation = float(np.degrees(np.arcsin(np.clip(-x_n[2], -1.0, 1.0))))
    return (f"launch_elevation_deg={given_deg:g} not used: the initial attitude came from "
            f"{source.split(',')[0]}, whose body-x elevation is {elevation:.1f} deg "
            f"({elevation - given_deg:+.1f} deg from the flag)")


def _correct(rows, attitude, f_b, t, p, sigma_sa):
    """Method step 3: the position spline, the attitude correction, the accelerometer bias
    and scale error, relinearised ``iterations`` times. Returns the correction, the
    corrected attitude samples and the spline coefficients."""
    correction = AttitudeCorrection(t, p, accel_bias_sigma(p), sigma_sa)
    coef = None
    for _ in range(p["iterations"]):
        C = attitude.as_matrix()
        f_e = np.einsum("nij,nj->ni", C, correction.corrected(f_b))
        coef, eps = rows.solve(f_e, coef, correction, C, f_b)
        rows.robust_weights(coef, f_e, eps)
        attitude = Rotation.from_rotvec(eps) * attitude
    return correction, attitude, coef


def _hold_pad(attitude, pad_end):
    """The attitude samples with the pad (up to ``pad_end``) at the attitude of lift-off
    (docs/assumptions.md FIT4); unchanged without a pad."""
    if pad_end is None:
        return attitude
    n = len(attitude)
    return attitude[np.r_[np.full(pad_end + 1, pad_end), np.arange(pad_end + 1, n)]]


def _rms(x):
    return [float(v) for v in np.sqrt(np.mean(np.asarray(x) ** 2, axis=0))]


def _residuals(traj, f_b, w_b, rows, coef, t_g, P_g, V_g):
    P_fit_g = rows.P_ref + rows.G0 @ coef
    d_p = P_g - P_fit_g
    d_f = f_b - traj.specific_force
    d_w = w_b - traj.angular_rate
    out = {
        "gnss_position_rms_m": _rms(d_p),
        "gnss_position_rms_3d_m": float(np.sqrt(np.mean(np.sum(d_p**2, axis=1)))),
        "specific_force_rms_mps2": _rms(d_f),
        "specific_force_max_mps2": float(np.linalg.norm(d_f, axis=1).max()),
        "angular_rate_rms_rad_s": _rms(d_w),
        "angular_rate_max_rad_s": float(np.linalg.norm(d_w, axis=1).max()),
    }
    if V_g is not None:
        out["gnss_velocity_rms_mps"] = _rms(V_g - rows.G1 @ coef)
    return out
