"""What aided a recorded flight, and the reference rows of a flight without GNSS
(assumptions.md B1-B5).

:func:`aiding_records` turns the records a reader returned (``gnss`` None or a GNSS record
whose height came from the barometer, ``imu.attrs["baro"]``) into the position rows the
flight fit takes (:func:`navlib.trajectory.fit_flight_data`) and names the aiding
(:data:`navlib.models.baro.AIDINGS`). Without GNSS the rows are :func:`baro_reference_rows`:
height from the barometer, horizontal position dead-reckoned from the IMU levelled on the pad
(B5). They only seed the fit, whose IMU rows are exact; the model's measurements are the
barometer and the pad (:func:`navlib.models.baro.aided_model`), never these rows.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy.integrate import cumulative_trapezoid

from navlib import earth, strapdown, units
from navlib.covariance import kalman_covariance, sigma_in_frame
from navlib.errors import NavlibInputError
from navlib.io.baro import baro_height
from navlib.models.baro import BARO_SCALE, BARO_SIGMA_M, baro_sigma, static_pressure_error_m
from navlib.trajectory.fit import FIT_DEFAULTS
from navlib.trajectory.initial_attitude import level_attitude

__all__ = ["GAP_S", "LAUNCH_ACCEL_M_S2", "MIN_LEVEL_S", "ROW_RATE_HZ", "SITE_DEG",
           "aiding_of", "aiding_records", "baro_reference_rows", "baro_rows_weighted",
           "ned_sigmas", "reference_speed", "row_dynamic_error", "sigma_note"]

SITE_DEG = (45.0, 0.0)
"""Latitude and longitude assumed for a flight without GNSS, deg (B5): normal gravity
differs by at most 0.27 % between it and any site, and the Earth rate's components by the
cosine of the latitude difference."""
ROW_RATE_HZ = 10.0
"""Rate of the reference rows of a flight without GNSS, Hz (by construction: the position
spline's knots are 0.1 s apart)."""
LAUNCH_ACCEL_M_S2 = 3.0
"""Specific-force change from the pad's mean that ends the levelling window, m/s^2 (by
construction: above a rail's vibration, well below any motor's thrust)."""
MIN_LEVEL_S = 0.2
"""Shortest rest before launch to level the IMU on, s: an AltOS export keeps 0.3 s before
boost detection, of which 0.25-0.29 s precede the first 3 m/s^2 change. 20 samples at 100 Hz
level to 0.03 deg against 0.1 m/s^2 of noise, below the 0.6 deg a 0.1 m/s^2 bias gives
whatever the window (these rows only seed the fit, which levels again)."""
GAP_S = FIT_DEFAULTS["max_bridge_s"]
"""IMU holes longer than this (the fit's longest bridged hole, s) start a new piece whose
reference rows are built on their own: a pre-launch buffer logged long before the flight."""


def aiding_of(imu: pd.DataFrame, gnss: pd.DataFrame | None) -> str:
    """``gnss``, ``baro`` (no GNSS record) or ``gnss+baro`` (a GNSS record whose height is
    the barometer's, ``gnss.attrs["height_source"] == "baro"``).

    Parameters
    ----------
    imu : pandas.DataFrame
        IMU record (its barometer in ``attrs``).
    gnss : pandas.DataFrame or None
        GNSS record.

    Raises
    ------
    NavlibInputError
        Without GNSS and without a barometer.
    """
    if gnss is None:
        if _baro(imu) is None:
            raise NavlibInputError("gnss: no GNSS record and no barometer "
                                   "(imu.attrs['baro']): nothing aids the IMU; give a GNSS "
                                   "and/or a barometer record")
        return "baro"
    return "gnss+baro" if gnss.attrs.get("height_source") == "baro" else "gnss"


def _baro(imu) -> pd.DataFrame | None:
    baro = getattr(imu, "attrs", {}).get("baro")
    return baro if isinstance(baro, pd.DataFrame) and len(baro) >= 2 else None


def aiding_records(imu: pd.DataFrame, gnss: pd.DataFrame | None
                   ) -> tuple[pd.DataFrame, str, list[str]]:
    """The position rows for the fit, the aiding (:func:`aiding_of`) and notes in words.

    Parameters
    ----------
    imu : pandas.DataFrame
        IMU record.
    gnss : pandas.DataFrame or None
        GNSS record.

    Raises
    ------
    NavlibInputError
        Without GNSS, when no piece of the record yields barometer rows.
    """
    aiding = aiding_of(imu, gnss)
    if aiding == "gnss":
        return gnss, aiding, []
    if aiding == "gnss+baro":
        held = gnss.attrs.get("held_fixes_dropped", 0)
        return gnss, aiding, [
            "aiding gnss+baro: the GNSS record has no height, so its height is the "
            "barometric altitude (assumptions B1); the model measures GNSS north/east and "
            "the barometer (B2)" + (f"; {held} held fix(es) repeating the previous position "
                                    "were dropped" if held else "")]
    rows, notes = _rows_per_piece(imu, _baro(imu))
    return rows, aiding, notes


def _rows_per_piece(imu: pd.DataFrame, baro: pd.DataFrame) -> tuple[pd.DataFrame, list[str]]:
    """:func:`baro_reference_rows` of each IMU piece between holes longer than
    :data:`GAP_S` (a pre-launch buffer logged long before the flight is levelled on its own,
    or skipped with a note when it cannot be)."""
    t = imu["t"].to_numpy(dtype=float)
    after = np.flatnonzero(np.diff(t) > GAP_S) + 1
    bounds = list(zip(np.r_[0, after], np.r_[after, t.size], strict=True))
    rows, notes, errors = [], [], []
    for a, b in bounds:
        piece = imu.iloc[a:b]
        try:
            r, note = baro_reference_rows(piece, baro)
        except NavlibInputError as exc:
            errors.append(f"{t[a]:.6g}..{t[b - 1]:.6g} s: {exc}")
            continue
        rows.append(r)
        notes.append(note)
    if not rows:
        raise NavlibInputError("; ".join(errors))
    if errors:
        notes.append(f"the IMU record has holes longer than {GAP_S:g} s; no reference rows for "
                     f"the piece(s) {'; '.join(errors)}")
    out = pd.concat(rows, ignore_index=True)
    out.attrs = dict(rows[0].attrs)
    return out, notes


def baro_reference_rows(imu: pd.DataFrame, baro: pd.DataFrame,
                        site_deg=SITE_DEG) -> tuple[pd.DataFrame, str]:
    """Position rows (``t, x, y, z, sigma``, ECEF) of a flight without GNSS (B5).

    The IMU is levelled on the rest before launch (:data:`LAUNCH_ACCEL_M_S2`,
    :data:`MIN_LEVEL_S`; heading north by construction), its attitude integrated with the
    gyros and its specific force twice with the pad's gravity (no Coriolis: these rows only
    seed the fit); the horizontal part of that position, at ``site_deg``, gets the
    barometric height change above the pad. ``sigma`` is :func:`navlib.models.baro.baro_sigma`
    at rest: its static-pressure term needs the vehicle's speed, which neither the
    barometer's own climb rate (corrupted by the error it should weigh) nor this dead
    reckoning (it diverges in a tumbling descent) gives; :func:`baro_rows_weighted` adds it
    with the speed of a fit to these rows (B7).

    Parameters
    ----------
    imu : pandas.DataFrame
        IMU record (``t``, s; ``f_*``, m/s^2; ``w_*``, rad/s).
    baro : pandas.DataFrame
        Barometer record.
    site_deg : tuple of float, optional
        Latitude and longitude of the pad, deg.

    Raises
    ------
    NavlibInputError
        If the IMU and barometer overlap less than 2 s, or the rest before launch is shorter
        than :data:`MIN_LEVEL_S`.
    """
    t = imu["t"].to_numpy(dtype=float)
    f_b = imu[["f_x", "f_y", "f_z"]].to_numpy(dtype=float)
    w_b = imu[["w_x", "w_y", "w_z"]].to_numpy(dtype=float)
    t_b = baro["t"].to_numpy(dtype=float)
    t0, t1 = max(t[0], t_b[0]), min(t[-1], t_b[-1])
    if t1 - t0 < 2.0:
        raise NavlibInputError(f"imu, baro: the IMU ({t[0]:.6g}..{t[-1]:.6g} s) and the "
                               f"barometer ({t_b[0]:.6g}..{t_b[-1]:.6g} s) overlap for "
                               f"{max(t1 - t0, 0.0):.3g} s; need at least 2 s")
    keep = (t >= t0) & (t <= t1)
    t, f_b, w_b = t[keep], f_b[keep], w_b[keep]
    launch = _launch_index(t, f_b)
    if t[launch] - t[0] < MIN_LEVEL_S:
        raise NavlibInputError(
            f"imu: only {t[launch] - t[0]:.3g} s at rest before the specific force changes "
            f"by {LAUNCH_ACCEL_M_S2:g} m/s^2 (t = {t[launch]:.6g} s); a flight without GNSS "
            f"is levelled on at least {MIN_LEVEL_S:g} s on the pad")
    lat0, lon0 = (v * units.DEG for v in site_deg)
    h_b = baro_height(baro, t)
    pad = slice(0, launch)
    h_pad = float(np.median(h_b[pad]))
    P0 = earth.geodetic_to_ecef(lat0, lon0, h_pad)
    C_n_e = earth.ned_to_ecef_matrix(lat0, lon0)
    gamma = earth.normal_gravity_ecef(P0)
    att0 = level_attitude(f_b[pad].mean(axis=0), gamma, C_n_e)
    C_b_e = att0 * strapdown.body_attitude(t, w_b)
    a_e = C_b_e.apply(f_b) + gamma
    a_e[pad] = 0.0                                       # on the pad by construction
    v_e = cumulative_trapezoid(a_e, t, axis=0, initial=0.0)
    dP = cumulative_trapezoid(v_e, t, axis=0, initial=0.0)
    up = -C_n_e[:, 2]
    dP_h = dP - np.outer(dP @ up, up)
    grid = np.arange(t[0], t[-1], 1.0 / ROW_RATE_HZ)
    P_h = P0 + np.column_stack([np.interp(grid, t, dP_h[:, i]) for i in range(3)])
    lat, lon, _ = earth.ecef_to_geodetic(P_h)
    dh = baro_height(baro, grid) - h_pad
    r_e = earth.geodetic_to_ecef(lat, lon, h_pad + dh)
    rows = pd.DataFrame({"t": grid, "x": r_e[:, 0], "y": r_e[:, 1], "z": r_e[:, 2],
                         "sigma": baro_sigma(dh, BARO_SIGMA_M, BARO_SCALE)})
    rows.attrs.update(source="barometer + IMU dead reckoning", height_source="baro")
    note = (f"aiding baro: no GNSS; the reference motion is fitted to {len(rows)} rows at "
            f"{ROW_RATE_HZ:g} Hz whose height is the barometer's ({dh.max():.0f} m above the "
            f"pad at most) and whose horizontal position is dead-reckoned from the IMU "
            f"levelled on {t[launch] - t[0]:.1f} s of pad, heading north and site "
            f"{site_deg[0]:g} N {site_deg[1]:g} E assumed (assumptions B5): horizontal "
            f"position and velocity are not measured, only carried by the IMU")
    return rows, note


def row_dynamic_error(t, trajectory, aiding: str) -> np.ndarray:
    """The static-pressure altitude error expected of a barometric row at the times ``t``:
    :func:`navlib.models.baro.static_pressure_error_m` at the speed (:func:`reference_speed`)
    and height of ``trajectory`` there (B7), m; 0 outside the trajectory's span.

    Parameters
    ----------
    t : array_like
        Row times, s, on the trajectory's clock.
    trajectory : Trajectory
        The reference motion.
    aiding : str
        ``"baro"`` or ``"gnss+baro"``.

    Returns
    -------
    numpy.ndarray
    """
    inside, P, V = _reference_at(t, trajectory)
    lat, lon, h = earth.ecef_to_geodetic(P)
    return static_pressure_error_m(_airspeed(inside, lat, lon, V, aiding), h)


def reference_speed(t, trajectory, aiding: str) -> np.ndarray:
    """The airspeed a barometric row at the times ``t`` is read at (B7), m/s: the speed of
    ``trajectory`` (no wind) with GNSS (``aiding == "gnss+baro"``), its climb rate without
    (``"baro"``: its horizontal velocity is dead reckoning, B5, and a rocket's large speeds
    are mostly vertical); 0 outside its span.

    Parameters
    ----------
    t : array_like
        Times, s.
    trajectory : Trajectory
        The reference motion.
    aiding : str
        ``"baro"`` or ``"gnss+baro"``.

    Returns
    -------
    numpy.ndarray
    """
    inside, P, V = _reference_at(t, trajectory)
    lat, lon, _ = earth.ecef_to_geodetic(P)
    return _airspeed(inside, lat, lon, V, aiding)


def _reference_at(t, trajectory):
    """Whether the times ``t`` lie in ``trajectory``'s span, and its position and velocity
    there (ECEF, interpolated linearly)."""
    t = np.asarray(t, dtype=float)
    inside = (t >= trajectory.t[0]) & (t <= trajectory.t[-1])
    P, V = (np.column_stack([np.interp(t, trajectory.t, x[:, i]) for i in range(3)])
            for x in (trajectory.position, trajectory.velocity))
    return inside, P, V


def _airspeed(inside, lat, lon, V, aiding: str) -> np.ndarray:
    """:func:`reference_speed` of the reference velocity ``V`` at ``lat``, ``lon``."""
    if aiding == "gnss+baro":
        speed = np.linalg.norm(V, axis=1)
    else:
        up = -earth.ned_to_ecef_matrix(lat, lon)[..., 2]
        speed = np.abs(np.einsum("ki,ki->k", V, up.reshape(-1, 3)))
    return np.where(inside, speed, 0.0)


def baro_rows_weighted(rows: pd.DataFrame, trajectory) -> pd.DataFrame:
    """The barometer's reference rows (:func:`baro_reference_rows`) with a ``sigma`` taken at
    the speed of a fit to them (B7).

    A barometer's static-pressure error grows with the dynamic pressure and through the
    transonic range (:func:`navlib.models.baro.static_pressure_error_m`); it also corrupts
    the barometric climb rate, so the speed that weighs a row is the reference's climb rate
    (:func:`reference_speed`). ``sigma`` is :func:`navlib.models.baro.baro_sigma` of the
    row's height above the first row at that speed. Rows of a GNSS record whose height is
    the barometer's (``gnss+baro``) are not reweighted: the fit weighs each row's three axes
    alike, and a sigma that covers the barometer at high dynamic pressure would also take
    the weight of its horizontal GNSS (B7).

    Parameters
    ----------
    rows : pandas.DataFrame
        Rows of :func:`baro_reference_rows` (``t, x, y, z, sigma``, ECEF).
    trajectory : Trajectory
        A first fit to ``rows``.

    Returns
    -------
    pandas.DataFrame
        A copy of ``rows`` with the new ``sigma`` (``attrs`` kept).
    """
    speed = reference_speed(rows["t"], trajectory, "baro")
    _, _, h = earth.ecef_to_geodetic(rows[["x", "y", "z"]].to_numpy(dtype=float))
    out = rows.assign(sigma=baro_sigma(h - h[0], BARO_SIGMA_M, BARO_SCALE, speed,
                                       altitude_m=h))
    out.attrs = dict(rows.attrs)
    return out


def _launch_index(t, f_b) -> int:
    """First sample whose specific force differs from the mean of the samples before it by
    more than :data:`LAUNCH_ACCEL_M_S2` (after the first 0.1 s)."""
    mean = np.cumsum(f_b, axis=0) / np.arange(1, t.size + 1)[:, None]
    jump = np.linalg.norm(f_b[1:] - mean[:-1], axis=1) > LAUNCH_ACCEL_M_S2
    jump &= t[1:] - t[0] > 0.1
    hits = np.flatnonzero(jump)
    return int(hits[0]) + 1 if hits.size else t.size - 1


def ned_sigmas(model, trajectory) -> dict[str, np.ndarray]:
    """Standard deviations of position and velocity in north/east/down at every epoch.

    The Kalman covariance recursion of ``model``
    (:func:`navlib.covariance.kalman_covariance`, updated at every epoch), its ECEF position
    and velocity blocks turned into the local NED frame of the reference position. Returns
    ``t`` and ``position_m``, ``velocity_m_s`` (N, 3: north, east, down).

    Parameters
    ----------
    model : DiscreteModel
        The error-state model of the flight.
    trajectory : Trajectory
        Its reference trajectory.
    """
    result = kalman_covariance(model)
    t = np.asarray(trajectory.t, dtype=float)
    index = np.clip(np.searchsorted(t, model.t), 0, t.size - 1)
    lat, lon, _ = earth.ecef_to_geodetic(np.asarray(trajectory.position, dtype=float)[index])
    C_e_n = np.swapaxes(earth.ned_to_ecef_matrix(lat, lon), 1, 2)
    return {"t": np.asarray(model.t, dtype=float),
            "position_m": sigma_in_frame(result, (0, 1, 2), C_e_n),
            "velocity_m_s": sigma_in_frame(result, (3, 4, 5), C_e_n)}


def sigma_note(model, trajectory, aiding: str) -> str:
    """The end-of-flight position and velocity sigma in north/east/down, in words.

    Parameters
    ----------
    model : DiscreteModel
        The error-state model of the flight.
    trajectory : Trajectory
        Its reference trajectory.
    aiding : str
        ``"gnss"``, ``"baro"`` or ``"gnss+baro"``.
    """
    s = ned_sigmas(model, trajectory)
    p, v = s["position_m"], s["velocity_m_s"]
    text = (f"aiding {aiding}: at the end ({s['t'][-1]:.1f} s) the 21-state model's sigma is "
            f"north/east/down position {p[-1, 0]:.3g}/{p[-1, 1]:.3g}/{p[-1, 2]:.3g} m, "
            f"velocity {v[-1, 0]:.3g}/{v[-1, 1]:.3g}/{v[-1, 2]:.3g} m/s")
    if aiding == "baro":
        text += (f" (from {p[0, 0]:.3g}/{p[0, 1]:.3g}/{p[0, 2]:.3g} m at the start): only the "
                 "vertical is measured; horizontal position and velocity are unobservable "
                 "and their sigma grows with the IMU errors (the excitable/sensible lists "
                 "name ECEF axes, each holding part of the measured vertical: read north, "
                 "east and down from these sigmas)")
    return text
