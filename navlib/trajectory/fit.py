"""A kinematically exact reference trajectory fitted to recorded flight data.

The idea of Giribet et al. (2007), as used by España et al. (2019, spec excitability.md
§4): find the smooth B-spline trajectory that best fits the recorded IMU and GNSS data in
a least-squares sense and whose IMU signals satisfy the kinematics (spec Eq. 1) exactly.
Its IMU is then re-derived from the splines with
:func:`navlib.trajectory.base.exact_imu`, so a correct strapdown integrating it reproduces
the fitted position and attitude to the last digit of the integrator.

Method (:func:`fit_flight_data`)
--------------------------------
1. **Initial attitude** (docs/assumptions.md, "fit — levelling from a short pre-launch
   window"), the first source that applies: the user's (``initial_attitude``, a body ->
   ECEF rotation, or ``initial_attitude_deg=(yaw, pitch, roll)`` of the body against the
   local NED frame); the autopilot's own attitude when the reader attached it
   (``imu.attrs["attitude"]``: PX4 ``vehicle_attitude``, ArduPilot ``ATT``;
   ``use_logged_attitude=True``), interpolated to the first sample (it carries a heading,
   which levelling cannot); accelerometer levelling on the median specific force of the
   quietest rest window of ``level_s`` (:func:`_quiet_window`: thresholds from the
   ``preset``'s white noise plus ``vibration_allowance_mps2``; the first
   ``level_search_s`` seconds are preferred, and the gyros carry a later window's attitude
   back to the start, so a record may start in the air), or failing that of the shortest
   window that levels to ``level_tilt_deg`` with the preset's noise (:func:`min_level_s`:
   0.1 s at 100 Hz for a MEMS IMU, so the 0.3 s an AltOS log keeps before boost will do);
   the body-x elevation from the logger's tilt (``imu.attrs["tilt"]``, AltOS); the
   launch-rail elevation ``launch_elevation_deg``. Levelling, tilt and rail leave the
   heading free: ``heading_deg`` or ``launch_azimuth_deg`` (azimuth of the body x axis) if
   given, else a coarse closed-form estimate that turns the IMU specific force about the
   vertical onto the GNSS-derived one (velocity differences when GNSS velocity is given,
   else second differences of the positions, against IMU averages over the same
   windows); tilt and rail then turn the attitude about the start's body x axis by the
   same closed form (roll 0, body y horizontal, when the specific force never leaves
   that axis). The source is
   recorded in the residuals (``initial_attitude_source``, ``initial_attitude_note``).
2. **Attitude history.** The gyros are integrated with
   :func:`navlib.strapdown.body_attitude` (the fourth-order attitude chain of
   :func:`navlib.strapdown.integrate`, with Earth rate), giving ``C_b_e`` at every sample.
3. **Position spline and attitude correction.** ``P(t)`` is a quintic B-spline with knots
   every ``knot_spacing_s`` (default 0.1 s: ten 100 Hz samples per knot interval, short
   enough for thrust ramps of a few tenths of a second and the 0.5 s de-spin of the
   sounding rocket; longer spacing smooths noise more but rounds off such transients).
   Its coefficients solve one weighted linear least-squares problem with rows
   ``P(t_j) = P_j`` (weight ``1/sigma``, from the ``sigma`` column or
   ``sigma_position_m``), ``P'(t_j) = V_j`` when GNSS velocity is present
   (``sigma_velocity_mps``) and, at every IMU sample,
   ``P'' = (I + S(eps(t))) C_b_e f^b + gamma(P) - 2 Omega x P'``
   (``sigma_specific_force_mps2``). ``eps(t)`` is a slowly varying attitude correction
   (cubic B-spline, knots every ``correction_knot_spacing_s``, at most
   ``MAX_CORRECTION_INTERVALS`` intervals; prior ``attitude_prior_deg`` on its value and
   ``attitude_drift_deg_s`` on its change) that absorbs levelling/heading errors and gyro
   drift, and a constant accelerometer bias (body axes; prior ``sigma_accel_bias_mps2``,
   by default the ``preset``'s turn-on bias; without a preset none is estimated), which
   the fit would otherwise take for motion; all solved jointly through a Schur complement.
   Gravity, Coriolis and ``eps`` are relinearised ``iterations`` times; specific-force
   rows whose residual exceeds 4 sigma are down-weighted (Huber; on the first pass
   ``sigma_specific_force_mps2`` is raised to the robust scale of the residuals, so
   vibration weighs as noise), so a transient the spline cannot follow does not bend the
   attitude. The normal equations of
   the spline are banded (one Cholesky factorisation serves the three axes).
4. **Attitude spline.** The corrected attitude samples are fitted by a cumulative quintic
   B-spline on SO(3) (:class:`navlib.trajectory._so3.SO3Spline`; docs/assumptions.md,
   "fit — attitude spline on SO(3)"): no yaw/pitch/roll, so no attitude is singular and a
   vertical ascent, a loop, a tumble or a parachute descent are all fitted alike. Knots
   every ``attitude_knot_spacing_s`` (default: ``knot_spacing_s``), closer where the body
   turns by more than ``MAX_TURN_PER_KNOT_RAD`` in one interval; the control rotations
   minimise the squared rotation angle between spline and samples (Gauss-Newton). The
   body rate is the spline's analytic one.
5. The position is refitted with the smooth attitude, and the exact IMU is derived.

Holes and rates
---------------
An IMU interval longer than ``HOLE_FACTOR`` (10) median intervals is a hole. Holes up to
``max_bridge_s`` (default 1 s) are bridged: knots inside them are dropped
(:func:`_knots`: every knot interval keeps ``SAMPLES_PER_KNOT`` samples), so one polynomial
piece and the gyro chain interpolate across, and ``fit_residuals["imu_holes"]`` states a
bound for each (:func:`_hole_bounds`). Longer holes are refused (``assess_flight`` splits
the record there). The same knot rule lets low rates through (at 10 Hz the knot intervals
become 0.2 s); below ``MIN_IMU_RATE_HZ`` (4 Hz: 2 samples per interval of at most
``MAX_KNOT_SPACING_S`` = 0.5 s, the longest that still follows 1 Hz manoeuvres) the fit
refuses the record, naming the rate and the minimum.

Observability caveat: accelerometers and GNSS see the attitude only through the direction
of the specific force, so a rotation about that direction (on the pad: the heading; for a
near-vertical rocket also in flight) is determined only by how that direction changes over
the record. Give ``heading_deg`` (or ``launch_azimuth_deg``), ``initial_attitude`` or
``initial_attitude_deg`` when they are known.

Residuals (``trajectory.parameters["fit_residuals"]``)
-----------------------------------------------------
* ``gnss_position_rms_m`` (x, y, z) and ``gnss_position_rms_3d_m``: GNSS minus fit;
* ``gnss_velocity_rms_mps`` (x, y, z) when GNSS velocity was given;
* ``specific_force_rms_mps2`` and ``angular_rate_rms_rad_s`` (x, y, z body axes): recorded
  IMU minus the fitted trajectory's exact IMU, with their maxima
  ``specific_force_max_mps2`` and ``angular_rate_max_rad_s`` (norms);
* ``heading_deg`` (body-x azimuth at the start) and ``heading_source``
  (``keyword``, ``initial_attitude``, ``log`` or ``estimated``);
  ``initial_attitude_source`` (``user``, ``log``, ``level``, ``tilt`` or ``rail``) and
  ``initial_attitude_note`` (the same in words, for reports); ``n_imu``, ``n_gnss``,
  ``n_knots``, ``imu_rate_hz``;
* ``imu_holes`` (bridged holes: ``t_start``, ``t_end``, ``duration_s``,
  ``attitude_bound_deg``, ``position_bound_m``), ``level`` (the levelling window and its
  statistics, empty when not levelled), ``sigma_specific_force_used_mps2`` and
  ``accel_bias_mps2`` (the estimated accelerometer bias, body axes).

With noiseless data of a trajectory the splines can represent, all residuals are near
zero; with noisy data they sit at the noise level (the fit's degrees of freedom absorb a
small fraction, about ``n_coefficients / n_rows``).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import scipy.sparse as sp
from scipy.interpolate import BSpline
from scipy.linalg import solveh_banded
from scipy.spatial.transform import Rotation, Slerp

from navlib import earth, strapdown
from navlib._validation import finite_array, finite_scalar, increasing_times, reject_unknown
from navlib.errors import NavlibInputError
from navlib.io import check_overlap
from navlib.sensors import DEFAULT_IMU_PRESET, ImuSpec, load_preset
from navlib.trajectory._so3 import SO3Spline, basis
from navlib.trajectory.base import Trajectory, build_trajectory
from navlib.units import DEG, G0

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
    "max_bridge_s": 1.0,
    "sigma_accel_bias_mps2": None,
    "attitude_prior_deg": 5.0,
    "attitude_drift_deg_s": None,
    "correction_knot_spacing_s": 10.0,
    "iterations": 3,
    "name": "fitted flight",
}

IMU_COLUMNS = ("t", "f_x", "f_y", "f_z", "w_x", "w_y", "w_z")
GNSS_COLUMNS = ("t", "x", "y", "z")
GNSS_VELOCITY_COLUMNS = ("vx", "vy", "vz")
_K = 5                      # quintic splines: C^4 position, C^2 specific force
_MIN_GNSS = 4
_MIN_IMU = 20
_VERTICAL_SIN2 = np.sin(1.0 * DEG) ** 2   # body x within 1 deg of the vertical below this
_MIN_HORIZONTAL_F = 0.3     # m/s^2, RMS needed to estimate the heading
_HUBER = 4.0                # specific-force rows beyond this many sigma are down-weighted
SAMPLES_PER_KNOT = 2
"""Fewest IMU samples in each knot interval of the splines (knots are merged until so)."""
MAX_KNOT_SPACING_S = 0.5
"""Longest knot interval the fit accepts: a quintic B-spline follows features about two knot
intervals long, so 0.5 s intervals still resolve the ~1 Hz manoeuvres of aircraft and
multicopters (and the 0.5 s de-spin of the sounding rocket)."""
MAX_TURN_PER_KNOT_RAD = 1.5
"""Largest rotation of the body within one knot interval of the attitude spline, rad: its
control rotations then differ by well under pi (the cumulative spline's increments are
principal logarithms) and a tumble or fast spin gets denser knots."""
ATTITUDE_SAMPLES_PER_KNOT = 6
"""About this many attitude samples per knot interval enter the attitude spline's fit (every
n-th of a denser interval): the samples are integrated gyro readings, smooth at that scale,
and the Gauss-Newton cost grows with their number (a 250 Hz record has 25 per 0.1 s)."""
MIN_IMU_RATE_HZ = SAMPLES_PER_KNOT / MAX_KNOT_SPACING_S
"""Slowest median IMU rate the fit accepts, Hz (4 Hz): ``SAMPLES_PER_KNOT`` samples per
knot interval of at most ``MAX_KNOT_SPACING_S``. It is also twice the 1 Hz motion bandwidth
above (Nyquist), below which the gyro integration aliases the attitude."""
MAX_CORRECTION_INTERVALS = 60
"""Most knot intervals of the attitude correction: flights longer than 60
``correction_knot_spacing_s`` get wider intervals (10 min at the default 10 s), which keeps
its dense Schur complement small; a cubic spline still holds the linear drift of a gyro
bias exactly."""
HOLE_FACTOR = 10.0
"""An IMU interval longer than this many median intervals is a hole (as the readers'
``max_gap_s=None``, :data:`navlib.io.checks.AUTO_GAP_FACTOR`)."""
REST_ACCEL_MPS2 = 0.5
"""Largest GNSS-derived acceleration around a levelling window, m/s^2 (the segmentation's
rest acceleration: 0.5 m/s^2 tilts the levelled attitude by 3 deg)."""
MIN_LEVEL_SAMPLES = 10
"""Fewest samples of a levelling window: enough to judge the rest by the spread of the
specific force (its standard deviation from 10 samples is good to about 25 %)."""
REST_RATE_DEG_S = 3.0
"""Largest mean angular rate of a levelling window, deg/s (the segmentation's rest rate)."""


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
        p["attitude_drift_deg_s"] = _gyro_drift_deg_s(p["preset"])
    p["attitude_drift_deg_s"] = finite_scalar(p["attitude_drift_deg_s"], "attitude_drift_deg_s",
                                              0.0, low_open=True)
    p["vibration_allowance_mps2"] = finite_scalar(p["vibration_allowance_mps2"],
                                                  "vibration_allowance_mps2", 0.0)
    if p["sigma_accel_bias_mps2"] is not None:
        p["sigma_accel_bias_mps2"] = finite_scalar(p["sigma_accel_bias_mps2"],
                                                   "sigma_accel_bias_mps2", 0.0)
    if p["knot_spacing_s"] > MAX_KNOT_SPACING_S:
        raise NavlibInputError(f"knot_spacing_s: {p['knot_spacing_s']:g} s exceeds "
                               f"{MAX_KNOT_SPACING_S:g} s (MAX_KNOT_SPACING_S)")
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


# --- B-spline machinery ------------------------------------------------------------------

def _knots(t, spacing, turn=None):
    """Clamped quintic knot vector on ``[t[0], t[-1]]``, interior knots about ``spacing`` apart.

    Knots come from a uniform grid; a knot is dropped when fewer than ``SAMPLES_PER_KNOT``
    samples ``t`` would lie between it and the previous knot kept (or after it), so holes
    in the record and low rates merge knot intervals instead of leaving coefficients
    without data (the normal equations stay definite). With ``turn`` (the cumulative
    rotation angle of the body at ``t``, rad) the grid is uniform in
    ``(t - t[0]) / spacing + turn / MAX_TURN_PER_KNOT_RAD`` instead, so no knot interval
    turns the body by more than ``MAX_TURN_PER_KNOT_RAD`` (the attitude spline).
    """
    t0, t1 = float(t[0]), float(t[-1])
    if turn is None:
        n_int = max(int(np.ceil((t1 - t0) / spacing - 1e-9)), 1)
        grid = np.linspace(t0, t1, n_int + 1)[1:-1]
    else:
        u = (t - t0) / spacing + (turn - turn[0]) / MAX_TURN_PER_KNOT_RAD
        n_int = max(int(np.ceil(u[-1] - 1e-9)), 1)
        grid = np.interp(np.linspace(0.0, u[-1], n_int + 1)[1:-1], u, t)
    below = np.searchsorted(t, grid, side="left")     # samples before each candidate knot
    keep, last = [], 0
    for knot, count in zip(grid, below, strict=True):
        if count - last >= SAMPLES_PER_KNOT and t.size - count >= SAMPLES_PER_KNOT:
            keep.append(knot)
            last = count
    return np.r_[np.full(_K + 1, t0), keep, np.full(_K + 1, t1)]


def _thin(t, knots, per_interval):
    """Indices of the samples kept for a fit on ``knots``: in each knot interval with ``c``
    samples, every ``max(1, c // per_interval)``-th one (the first and last sample always)."""
    inner = knots[_K + 1:-_K - 1]
    interval = np.searchsorted(inner, t, side="right")
    first = np.searchsorted(interval, np.arange(inner.size + 1), side="left")
    count = np.diff(np.r_[first, t.size])
    stride = np.maximum(count // per_interval, 1)
    pos = np.arange(t.size) - first[interval]
    keep = pos % stride[interval] == 0
    keep[[0, -1]] = True
    return np.flatnonzero(keep)


def _basis(x, knots, nu):
    """Sparse (N, m) matrix of the ``nu``-th derivatives of the quintic B-spline basis."""
    return basis(x, knots, _K, nu)


def _banded(N):
    """Upper banded storage of a symmetric sparse matrix with bandwidth ``_K``."""
    m = N.shape[0]
    ab = np.zeros((_K + 1, m))
    for d in range(_K + 1):
        ab[_K - d, d:] = N.diagonal(d)
    return ab


# --- attitude ----------------------------------------------------------------------------

def _level(f_b, gamma_e, C_n_e):
    """Body -> ECEF attitude from the mean specific force at rest, heading still free.

    TRIAD with the down direction exact: ``-f/|f|`` maps onto ``gamma/|gamma|``; the
    horizontal part of the body x axis (of the body y axis when x is within 1 deg of the
    vertical, as on a vertical launch rail) then points North of the geodetic NED frame
    ``C_n_e``. The caller turns the result about the vertical to the heading.
    """
    d_b = -f_b / np.linalg.norm(f_b)
    z_e = gamma_e / np.linalg.norm(gamma_e)
    ref = np.eye(3)[0 if 1.0 - d_b[0] ** 2 >= _VERTICAL_SIN2 else 1]
    t2_b = np.cross(d_b, ref)
    t2_b /= np.linalg.norm(t2_b)
    t2_e = np.cross(z_e, C_n_e[:, 0])
    t2_e /= np.linalg.norm(t2_e)
    T_b = np.column_stack([d_b, t2_b, np.cross(d_b, t2_b)])
    T_e = np.column_stack([z_e, t2_e, np.cross(z_e, t2_e)])
    return Rotation.from_matrix(T_e @ T_b.T)


def _rate_and_holes(t, max_bridge_s):
    """Median IMU rate (Hz) and the holes (index of the sample after each) to bridge.

    Refuses rates below :data:`MIN_IMU_RATE_HZ` and holes longer than ``max_bridge_s``.
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


def _hole_bounds(t, f_b, w_b, after):
    """Stated uncertainty of each bridged IMU hole (module docstring, "Holes").

    Across a hole of length ``L`` the gyro history and the position spline interpolate
    between the samples on either side. If the signals vary monotonically inside, the
    attitude error stays below ``theta = |w_b - w_a| L / 2`` and the position error below
    ``(|f_b - f_a| / 2 + |f| theta) L^2 / 8`` (the deflection of a string of length ``L``
    pinned at both ends under that acceleration error).
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
    """
    sigma_f, _ = _white_sigmas(preset, rate_hz)
    n = np.pi / 2.0 * (sigma_f / (G0 * tilt_deg * DEG)) ** 2
    return max(int(np.ceil(n)), MIN_LEVEL_SAMPLES) / rate_hz


def _quiet_window(t, f_b, w_b, g, p, gnss=None):
    """The rest window to level in (:func:`_rest_window`), tried in this order: a window of
    ``level_s`` within the first ``level_search_s``; a window of the shortest length
    :func:`min_level_s` allows there (a short pre-launch record: the GNSS is looked at
    before the window only, and the window grows over the run of neighbouring windows at
    rest); a window of ``level_s`` later; a short one later (a later window's attitude is
    carried back by the gyros, through all the flight's rotation, so an early short
    window is preferred to it). Returns sample indices and a description."""
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


def _logged_attitude(imu, t0, C_n_e):
    """Body -> ECEF attitude at ``t0`` from the autopilot attitude a reader attached
    (``imu.attrs["attitude"]``: ``t, qw, qx, qy, qz``, body -> NED), or None."""
    att = imu.attrs.get("attitude") if hasattr(imu, "attrs") else None
    if not isinstance(att, pd.DataFrame) or len(att) == 0 or not {
            "t", "qw", "qx", "qy", "qz"} <= set(att.columns):
        return None
    t = att["t"].to_numpy(dtype=float)
    q = att[["qx", "qy", "qz", "qw"]].to_numpy(dtype=float)
    ok = np.all(np.isfinite(q), axis=1) & np.isfinite(t) & (np.linalg.norm(q, axis=1) > 0.5)
    if not ok.any():
        return None
    t, q = t[ok], q[ok]
    k = int(np.argmin(np.abs(t - t0)))
    if abs(t[k] - t0) > 1.0:
        return None
    if k + 1 < t.size and t[k] < t0 < t[k + 1]:
        C_b_n = Slerp(t[k:k + 2], Rotation.from_quat(q[k:k + 2]))([t0])[0]
    else:
        C_b_n = Rotation.from_quat(q[k])
    return Rotation.from_matrix(C_n_e) * C_b_n


def _heading_of(C_b_e0, C_n_e):
    """Azimuth (rad) of the body x axis at the start."""
    x_n = C_n_e.T @ C_b_e0.apply([1.0, 0.0, 0.0])
    return float(np.arctan2(x_n[1], x_n[0]))


def _coarse_heading(t, f_e, axis_e, t_g, P_g, V_g=None):
    """Heading correction (rad) rotating IMU specific force onto the GNSS-derived one.

    ``f_e`` is the IMU specific force in ECEF with the provisional attitude and ``axis_e``
    the (Earth-fixed, rotating) vertical about which the heading turns. With GNSS velocity
    the GNSS side is the velocity difference between consecutive epochs (the acceleration
    averaged over the interval, against the IMU average over the same interval); without,
    the second difference of positions (the acceleration averaged with a triangle weight,
    against the same weighting of the IMU). Velocity differences are far less noisy: at
    5 Hz, 2 m of position noise make second differences of ~100 m/s^2.
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


def _start_attitude(imu, t, f_b, w_b, p, gamma0, C_n_e, gnss, earth_turn, relative):
    """Initial attitude (body -> ECEF at ``t[0]``, heading still free) without a user's or
    logger's full attitude: levelled in a rest window (:func:`_quiet_window`), else the
    body-x elevation from the logger's tilt (``imu.attrs["tilt"]``), else from
    ``launch_elevation_deg``; for the last two the body y axis is horizontal (roll 0) and
    the caller sets the azimuth and estimates the roll. Returns the attitude, the source (``level``,
    ``tilt`` or ``rail``), its description and the levelling window (empty unless level).
    """
    try:
        k0, k1, info = _quiet_window(t, f_b, w_b, np.linalg.norm(gamma0), p, gnss)
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
    att_q = _level(np.median(f_b[k0:k1], axis=0), gamma0, C_n_e)
    # attitude at the window start, carried back to t[0] through the gyro history
    E_q, R_q = earth_turn[k0], relative[k0]
    att0 = E_q.inv() * att_q * R_q.inv() * E_q
    where = "pre-launch" if info["short"] else "rest"
    note = (f"levelled from {info['window_s']:.2f} s {where} window "
            f"({info['t_start']:.6g}..{info['t_end']:.6g} s)")
    return att0, "level", note, info


def _logged_tilt(imu, t0):
    """Body-x angle from the vertical (rad) at ``t0`` from the tilt a reader attached
    (``imu.attrs["tilt"]``: ``t, tilt`` in rad), or None (no tilt within 1 s)."""
    tilt = imu.attrs.get("tilt") if hasattr(imu, "attrs") else None
    if not isinstance(tilt, pd.DataFrame) or not {"t", "tilt"} <= set(tilt.columns):
        return None
    t = tilt["t"].to_numpy(dtype=float)
    a = tilt["tilt"].to_numpy(dtype=float)
    ok = np.isfinite(t) & np.isfinite(a)
    if not ok.any():
        return None
    t, a = t[ok], a[ok]
    k = int(np.argmin(np.abs(t - t0)))
    if abs(t[k] - t0) > 1.0:
        return None
    return float(np.clip(a[k], 0.0, np.pi))


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
        ``initial_attitude_deg=None`` (yaw, pitch, roll of the body against the local NED
        frame at the first sample, deg; replaces levelling and heading),
        ``launch_elevation_deg=None``, ``launch_azimuth_deg=None`` (launch-rail angles of
        the body x axis, deg: the azimuth sets the heading of any source that leaves it
        free, the elevation is used when neither levelling nor a logged tilt is possible),
        ``level_s=1`` (length of the rest window used for levelling),
        ``level_tilt_deg=0.1`` (tilt accuracy that sets the shortest levelling window
        tried when no ``level_s`` window is at rest, :func:`min_level_s`),
        ``level_tolerance=0.05`` (accepted relative difference between its median |f| and
        normal gravity: consumer MEMS scale factors reach a few percent),
        ``level_search_s=60`` (windows starting this long after the start are preferred),
        ``preset=None`` (sensor preset whose white noise sets the rest thresholds; None:
        ``motionpak_tactical``), ``vibration_allowance_mps2=2`` (accelerometer spread of
        motor vibration accepted at rest), ``max_bridge_s=1`` (longest IMU hole bridged),
        ``sigma_accel_bias_mps2=None`` (prior sigma of the constant accelerometer bias the
        fit estimates; None: the named ``preset``'s turn-on bias, no bias without a preset),
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
    keep = (t_all >= span.t_start) & (t_all <= span.t_end)
    if keep.sum() < _MIN_IMU:
        raise NavlibInputError(
            f"imu: need at least {_MIN_IMU} samples inside the common span, got {keep.sum()}")
    t = t_all[keep]
    f_b = np.column_stack([imu_cols[c][keep] for c in ("f_x", "f_y", "f_z")])
    w_b = np.column_stack([imu_cols[c][keep] for c in ("w_x", "w_y", "w_z")])
    rate, holes = _rate_and_holes(t, p["max_bridge_s"])
    g_keep = (gnss_cols["t"] >= t[0]) & (gnss_cols["t"] <= t[-1])
    if g_keep.sum() < _MIN_GNSS:
        raise NavlibInputError(
            f"gnss: need at least {_MIN_GNSS} epochs inside the IMU span, got {g_keep.sum()}")
    t_g = gnss_cols["t"][g_keep]
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
    user = p["initial_attitude"] is not None or p["initial_attitude_deg"] is not None
    logged = _logged_attitude(imu, t[0], C_n_e) if (
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
        att0, kind, note, level_info = _start_attitude(
            imu, t, f_b, w_b, p, gamma0, C_n_e, (t_g, P_g, V_g), earth_turn, relative)
        if azimuth_deg is not None:
            x_down = att0.apply([1.0, 0.0, 0.0]) @ (gamma0 / np.linalg.norm(gamma0))
            if 1.0 - x_down**2 < _VERTICAL_SIN2:
                raise NavlibInputError(
                    "heading_deg: the body x axis is within 1 deg of the vertical at the "
                    "start, so its azimuth (heading_deg, launch_azimuth_deg) is undefined; "
                    "pass initial_attitude_deg instead")
            down = gamma0 / np.linalg.norm(gamma0)
            turn = azimuth_deg * DEG - _heading_of(att0, C_n_e)
            att0 = Rotation.from_rotvec(down * turn) * att0
        source = "keyword"
    attitude = earth_turn * att0 * earth_turn.inv() * relative
    # the vertical about which a heading change turns, carried along with the Earth
    axis_e = earth_turn.apply(gamma0 / np.linalg.norm(gamma0))
    if source == "keyword" and azimuth_deg is None:
        delta = _coarse_heading(t, attitude.apply(f_b), axis_e, t_g, P_g, V_g)
        attitude = Rotation.from_rotvec(axis_e * delta) * attitude
        source = "estimated"
    if kind in ("tilt", "rail"):
        # the roll about the start's body x axis: the same closed form about that axis
        x_e = earth_turn.apply(attitude[0].apply([1.0, 0.0, 0.0]))
        try:
            delta = _coarse_heading(t, attitude.apply(f_b), x_e, t_g, P_g, V_g)
            attitude = Rotation.from_rotvec(x_e * delta) * attitude
            roll = f"roll about body x estimated from GNSS ({np.degrees(delta):.1f} deg)"
        except NavlibInputError:
            roll = "roll about body x 0 (the specific force never leaves that axis)"
        note += (", azimuth " + ("estimated from GNSS" if azimuth_deg is None else
                                 f"{azimuth_deg:g} deg given") + ", " + roll)

    # 3: position spline and attitude correction --------------------------------------
    knots = _knots(t, p["knot_spacing_s"])
    rows = _Rows(knots, t, t_g, P_g, V_g, sigma, p, P_start)
    correction = _Correction(t, p, _accel_bias_sigma(p))
    coef = None
    for _ in range(p["iterations"]):
        C = attitude.as_matrix()
        f_e = np.einsum("nij,nj->ni", C, f_b - correction.bias)
        coef, eps = rows.solve(f_e, coef, correction, C)
        rows.robust_weights(coef, f_e, eps)
        attitude = Rotation.from_rotvec(eps) * attitude

    # 4: smooth attitude on SO(3) --------------------------------------------------------
    rate_norm = np.linalg.norm(w_b, axis=1)
    turn = np.r_[0.0, np.cumsum(0.5 * (rate_norm[1:] + rate_norm[:-1]) * np.diff(t))]
    att_knots = _knots(t, p["attitude_knot_spacing_s"], turn)
    used = _thin(t, att_knots, ATTITUDE_SAMPLES_PER_KNOT)
    C_b_e, w_eb_b = SO3Spline.fit(t[used], attitude[used], att_knots, _K).evaluate(t)

    # 5: final position fit with the smooth attitude, exact IMU, residuals ----------------
    f_e = np.einsum("nij,nj->ni", C_b_e, f_b - correction.bias)
    for _ in range(p["iterations"]):
        coef, _ = rows.solve(f_e, coef)
    P, V, a = rows.evaluate(coef)
    attitude_fit = Rotation.from_matrix(C_b_e)
    traj = build_trajectory(t, P, V, a, C_b_e, w_eb_b, events={"start": float(t[0]),
                            "end": float(t[-1])}, name=str(p["name"]))
    residuals = _residuals(traj, f_b, w_b, rows, coef, t_g, P_g, V_g)
    residuals.update({
        "heading_deg": float(np.degrees(_heading_of(attitude_fit[0], C_n_e))),
        "heading_source": source, "initial_attitude_source": kind,
        "initial_attitude_note": note, "n_imu": int(t.size), "n_gnss": int(t_g.size),
        "n_knots": int(knots.size - 2 * _K), "imu_rate_hz": rate,
        "imu_holes": _hole_bounds(t, f_b, w_b, holes), "level": level_info,
        "sigma_specific_force_used_mps2": float(rows.sigma_f),
        "accel_bias_mps2": [float(b) for b in correction.bias],
    })
    params = {k: v for k, v in p.items() if k not in ("initial_attitude", "initial_attitude_deg")}
    params["fit_residuals"] = residuals
    return Trajectory(t=traj.t, position=traj.position, velocity=traj.velocity,
                      attitude=traj.attitude, specific_force=traj.specific_force,
                      angular_rate=traj.angular_rate, events=traj.events, name=traj.name,
                      parameters=params)


class _Rows:
    """The weighted least-squares rows of the position spline (method step 3).

    Unknowns are the spline coefficients of ``P - P_ref`` for x, y, z (same basis) and,
    optionally, the attitude correction. The three axes share the banded normal matrix.
    """

    def __init__(self, knots, t, t_g, P_g, V_g, sigma, p, P_ref):
        self.P_ref = P_ref
        self.B0, self.B1, self.B2 = (_basis(t, knots, nu) for nu in range(3))
        self.G0, self.G1 = _basis(t_g, knots, 0), _basis(t_g, knots, 1)
        self.sigma_f = p["sigma_specific_force_mps2"]
        self.scaled = False
        w_g2 = 1.0 / sigma**2
        self.N_gnss = self.G0.T @ (self.G0 * w_g2[:, None])
        rhs_gnss = self.G0.T @ (w_g2[:, None] * (P_g - P_ref))
        if V_g is not None:
            w_v2 = 1.0 / p["sigma_velocity_mps"] ** 2
            self.N_gnss = self.N_gnss + w_v2 * (self.G1.T @ self.G1)
            rhs_gnss = rhs_gnss + w_v2 * (self.G1.T @ V_g)
        self.rhs_gnss = rhs_gnss
        self.set_weights(np.ones(t.size))
        # first linearisation point: GNSS positions interpolated to the IMU times
        self.P0 = np.column_stack([np.interp(t, t_g, P_g[:, i]) for i in range(3)])
        self.V0 = np.column_stack([np.interp(t, t_g, np.gradient(P_g[:, i], t_g))
                                   for i in range(3)])

    def set_weights(self, factor):
        """IMU row weights ``factor / sigma_f^2`` and the banded normal matrix."""
        self.w_f2 = factor / self.sigma_f**2
        self.N = sp.csr_array(self.B2.T @ (self.B2 * self.w_f2[:, None]) + self.N_gnss)
        self.ab = _banded(self.N)

    def robust_weights(self, coef, f_e, eps):
        """Huber factors from the specific-force residual norms (threshold ``_HUBER`` sigma).

        The first call also raises ``sigma_f`` to the robust scale of the residuals
        (1.4826 x their median absolute value) when that is larger: vibration then weighs
        as the noise it is against the GNSS rows.
        """
        P, V, a = self.evaluate(coef)
        r = (f_e + np.cross(eps, f_e) + earth.normal_gravity_ecef(P)
             - 2.0 * np.cross(earth.EARTH_RATE_ECEF, V))
        if not self.scaled:
            self.sigma_f = max(self.sigma_f, 1.4826 * float(np.median(np.abs(a - r))))
            self.scaled = True
        size = np.linalg.norm(a - r, axis=1) / (_HUBER * self.sigma_f)
        self.set_weights(1.0 / np.maximum(size, 1.0))

    def _solve(self, rhs):
        x = solveh_banded(self.ab, rhs)
        return x + solveh_banded(self.ab, rhs - self.N @ x)   # one refinement step

    def evaluate(self, coef):
        return self.P_ref + self.B0 @ coef, self.B1 @ coef, self.B2 @ coef

    def solve(self, f_e, coef, correction=None, C=None):
        """Coefficients (m, 3) and the attitude correction rotation vectors (N, 3).

        With a :class:`_Correction`, the specific force rows read
        ``P'' = (I + S(eps(t))) C f + gamma - 2 Omega x V``; ``eps`` is eliminated through
        its Schur complement (a small dense system) so the banded solve stays banded.
        """
        if coef is None:
            P, V = self.P0, self.V0
        else:
            P, V, _ = self.evaluate(coef)
        r = f_e + earth.normal_gravity_ecef(P) - 2.0 * np.cross(earth.EARTH_RATE_ECEF, V)
        w = self.w_f2[:, None]
        rhs = self.B2.T @ (w * r) + self.rhs_gnss
        if correction is None:
            return self._solve(rhs), np.zeros_like(f_e)
        G = correction.columns(f_e, C)                    # 3 x sparse (N, n_u)
        Q = [sp.csr_array(self.B2.T @ (G[a] * w)) for a in range(3)]
        n_u = G[0].shape[1]
        sol = self._solve(np.hstack([rhs, *(q.toarray() for q in Q)]))
        c0 = sol[:, :3]
        S = [sol[:, 3 + a * n_u: 3 + (a + 1) * n_u] for a in range(3)]
        lhs = correction.prior.copy()
        b = -correction.prior @ correction.total      # the prior holds the accumulated sum
        for a in range(3):
            lhs += (G[a].T @ (G[a] * w)).toarray() - Q[a].T @ S[a]
            b += Q[a].T @ c0[:, a] - G[a].T @ (w[:, 0] * r[:, a])
        e = np.linalg.solve(lhs, b)
        correction.total = correction.total + e
        coef = c0 + np.column_stack([S[a] @ e for a in range(3)])
        return coef, correction.evaluate(e)


class _Correction:
    """Slowly varying attitude correction ``eps(t)`` (ECEF rotation vector, cubic B-spline)
    and a constant accelerometer bias ``b_a`` (body axes).

    ``C <- exp(S(eps)) C`` absorbs the initial tilt/heading error and the gyro drift that
    the recorded specific force and GNSS reveal; ``f <- f - b_a`` the accelerometer bias,
    which would otherwise be taken for motion (a parked vehicle drifting at a few m/s).
    Prior: each ``eps`` coefficient ~ N(0, ``attitude_prior_deg``^2) and neighbouring
    coefficients differ by ~ N(0, (``attitude_drift_deg_s`` x knot spacing)^2), so
    stretches without attitude information (free fall) keep the gyro attitude; each bias
    component ~ N(0, ``sigma_ba``^2), the preset's turn-on accelerometer bias.
    """

    def __init__(self, t, p, sigma_ba):
        k = 3
        n_int = max(int(np.ceil((t[-1] - t[0]) / p["correction_knot_spacing_s"] - 1e-9)), 1)
        n_int = min(n_int, MAX_CORRECTION_INTERVALS)
        inner = np.linspace(t[0], t[-1], n_int + 1)
        knots = np.r_[np.full(k, t[0]), inner, np.full(k, t[-1])]
        x = np.minimum(t, np.nextafter(t[-1], -np.inf))
        self.beta = sp.csr_array(BSpline.design_matrix(x, knots, k))   # (N, n_c), sparse
        n_c = self.beta.shape[1]
        step = (t[-1] - t[0]) / n_int
        D = np.diff(np.eye(n_c), axis=0)
        per_axis = (np.eye(n_c) / (p["attitude_prior_deg"] * DEG) ** 2
                    + D.T @ D / (p["attitude_drift_deg_s"] * DEG * step) ** 2)
        # unknowns ordered (axis j, coef i) for eps, then the three bias components
        n_b = 3 if sigma_ba > 0 else 0                  # no bias unknowns without a prior
        self.prior = np.zeros((3 * n_c + n_b, 3 * n_c + n_b))
        self.prior[:3 * n_c, :3 * n_c] = np.kron(np.eye(3), per_axis)
        if n_b:
            self.prior[3 * n_c:, 3 * n_c:] = np.eye(3) / sigma_ba**2
        self.n_c = n_c
        self.total = np.zeros(3 * n_c + n_b)             # sum of the increments applied

    @property
    def bias(self):
        """Accumulated accelerometer bias estimate (body axes, m/s^2)."""
        return self.total[3 * self.n_c:] if self.total.size > 3 * self.n_c else np.zeros(3)

    def columns(self, f_e, C):
        """Sparse ``G[a]`` (N, n_u) for the axes a: ``beta_i(t_k) (e_j x f_e(t_k))_a`` for
        ``eps`` and ``-C_b_e[k, a, j]`` for the bias."""
        out = []
        for a in range(3):
            blocks = []
            for j in range(3):
                e_j = np.zeros(3)
                e_j[j] = 1.0
                cross = np.cross(e_j, f_e)[:, a]          # (N,)
                blocks.append(sp.diags_array(cross) @ self.beta)
            if self.total.size > 3 * self.n_c:
                blocks.append(sp.csr_array(-C[:, a, :]))
            out.append(sp.csr_array(sp.hstack(blocks)))
        return out

    def evaluate(self, e):
        return np.column_stack([self.beta @ e[j * self.n_c:(j + 1) * self.n_c]
                                for j in range(3)])


def _gyro_drift_deg_s(preset):
    """Default ``attitude_drift_deg_s``: how fast an uncorrected gyro bias turns the
    attitude, the preset's turn-on gyro bias (at least 0.01 deg/s); 0.01 without a preset."""
    if preset is None:
        return 0.01
    bias = _imu_preset(preset).gyro.bias
    return max(0.01, bias / DEG if bias > 0 else TURN_ON_FALLBACK["gyro_bias_deg_s"])


def _accel_bias_sigma(p):
    """Prior sigma of the fit's accelerometer bias, m/s^2: ``sigma_accel_bias_mps2``, else
    the turn-on value of the named ``preset``, else 0 (no bias estimated)."""
    if p["sigma_accel_bias_mps2"] is not None:
        return p["sigma_accel_bias_mps2"]
    if p["preset"] is None:
        return 0.0
    bias = _imu_preset(p["preset"]).accel.bias
    return float(bias) if bias > 0 else TURN_ON_FALLBACK["accel_bias_m_s2"]


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
