"""GNSS faults (assumptions Q2-Q4 of docs/assumptions.md): frozen fixes that repeat a
position while the vehicle moves, altitudes that disagree with the barometer
(``imu.attrs["baro"]``, DataFrame ``t, alt_m``) and jumps the IMU cannot explain, found by
:func:`gnss_faults` with the ``[gnss]`` thresholds of ``data/quality.toml``; and the time
they cover (:func:`faulty_time`), by which :func:`navlib.io.quality.check_records` judges a
record (a frozen stretch is an outage, not a reason to refuse a flight whose other fixes are
good)."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pandas as pd
from scipy.ndimage import maximum_filter1d

from navlib import earth
from navlib._validation import finite_scalar
from navlib.errors import NavlibInputError
from navlib.io.findings import (
    check_record,
    finding,
    findings_frame,
    load_thresholds,
)
from navlib.units import DEG

__all__ = ["baro_lag", "faulty_time", "gnss_faults", "grid_minimum", "shifted"]

_GYRO = ("w_x", "w_y", "w_z")
_ACCEL = ("f_x", "f_y", "f_z")
_XYZ = ("x", "y", "z")


def _moving_evidence(imu, gnss, a: int, b: int, t_next, p: dict) -> str | None:
    """Why the vehicle moved while the fixes ``a..b`` repeated one position, or None."""
    t_g = gnss["t"].to_numpy(dtype=float)
    t0, t1 = t_g[a], t_g[b] if t_next is None else t_next
    if all(c in gnss.columns for c in ("vx", "vy", "vz")):
        v = np.linalg.norm(gnss[["vx", "vy", "vz"]].to_numpy(dtype=float)[a:b + 1], axis=1)
        if np.nanmax(v) > p["moving_speed_m_s"]:
            return f"the GNSS velocity reads up to {np.nanmax(v):.3g} m/s"
    return _imu_motion(imu, t0, t1, gnss[list(_XYZ)].to_numpy(dtype=float)[a], p)


def _imu_motion(imu, t0: float, t1: float, position: np.ndarray, p: dict) -> str | None:
    """Why the IMU says the vehicle moved over ``t0..t1`` (a mean angular rate above
    ``moving_rate_deg_s``, a mean specific force off the normal gravity at ``position``,
    ECEF m, by more than ``moving_accel_m_s2``), or None."""
    t_i = imu["t"].to_numpy(dtype=float)
    inside = (t_i >= t0) & (t_i <= t1)
    if np.count_nonzero(inside) >= 2:
        rate = np.linalg.norm(imu[list(_GYRO)].to_numpy(dtype=float)[inside], axis=1).mean()
        if rate > p["moving_rate_deg_s"] * DEG:
            return f"the gyros read {rate / DEG:.3g} deg/s on average"
        f_norm = np.linalg.norm(imu[list(_ACCEL)].to_numpy(dtype=float)[inside], axis=1)
        g = float(np.linalg.norm(earth.normal_gravity_ecef(position)))
        off = abs(float(f_norm.mean()) - g)
        if off > p["moving_accel_m_s2"]:
            return f"the mean specific force is {off:.3g} m/s^2 off gravity"
    return None


def _frozen(imu, gnss, p: dict) -> tuple[np.ndarray, list[dict]]:
    t = gnss["t"].to_numpy(dtype=float)
    P = gnss[list(_XYZ)].to_numpy(dtype=float)
    bad = np.zeros(t.size, dtype=bool)
    rows = []
    a = 0
    while a < t.size - 1:
        b = a
        while b + 1 < t.size and np.linalg.norm(P[b + 1] - P[a]) <= p["frozen_tolerance_m"]:
            b += 1
        if b > a and t[b] - t[a] >= p["frozen_min_duration_s"]:
            t_next = t[b + 1] if b + 1 < t.size else None
            why = _moving_evidence(imu, gnss, a, b, t_next, p)
            if why is None and t_next is not None:
                step = float(np.linalg.norm(P[b + 1] - P[a]))
                if step > p["frozen_exit_distance_m"]:
                    why = f"the next fresh fix lies {step:.3g} m away"
            if why is not None:
                bad[a + 1:b + 1] = True
                rows.append({
                    "check": "gnss frozen", "channel": "position", "n": b - a,
                    "fraction": (b - a) / t.size, "t_first": float(t[a]),
                    "t_last": float(t[b]), "spans": [(float(t[a]), float(t[b]))],
                    "message": (f"GNSS position frozen for {t[b] - t[a]:.3g} s at "
                                f"{t[a]:.1f}-{t[b]:.1f} s ({b - a + 1} fixes repeat one "
                                f"position) while {why}: the {b - a} repeated fix(es) "
                                "excluded")})
        a = b + 1
    return bad, rows


def _baro_coverage(t: np.ndarray, t_b: np.ndarray, h_g_all: np.ndarray, h_b: np.ndarray,
                   p: dict) -> list[dict]:
    """A finding when the barometer covers less than ``baro_min_coverage`` of the GNSS span:
    the altitudes are compared only where both exist, and the spans of the two records
    must not be read as a disagreement."""
    span = t[-1] - t[0]
    covered = max(0.0, min(t[-1], t_b[-1]) - max(t[0], t_b[0])) if t_b.size else 0.0
    if span <= 0 or covered >= p["baro_min_coverage"] * span:
        return []
    outside = (t < t_b[0]) | (t > t_b[-1]) if t_b.size else np.ones(t.size, dtype=bool)
    where = f"{t_b[0]:.1f}-{t_b[-1]:.1f} s" if t_b.size else "no time"
    return [{
        "check": "gnss altitude", "channel": "barometer coverage",
        "n": int(np.count_nonzero(outside)), "fraction": float(np.mean(outside)),
        "t_first": float(t[0]), "t_last": float(t[-1]), "spans": [(float(t[0]), float(t[-1]))],
        "message": (f"the barometer record covers only {where} of the GNSS span "
                    f"{t[0]:.1f}-{t[-1]:.1f} s ({100 * covered / span:.2g} %): the GNSS altitude "
                    f"(spanning {np.ptp(h_g_all):.3g} m over the flight) is checked against it "
                    f"there only (barometer spanning {np.ptp(h_b) if h_b.size else 0:.3g} m); "
                    "their whole spans are not comparable")}]


def _baro_offset(d: np.ndarray, height: np.ndarray, max_scale: float) -> np.ndarray:
    """The expected GNSS-minus-barometer altitude ``a + b height`` (Q2): an offset (geoid,
    datum, pressure reference) and a scale error of the barometric model (a non-standard
    atmosphere: about 3 % per 10 K), fitted by Siegel's repeated medians (robust to half the
    fixes being wrong), the scale clipped to ``max_scale``."""
    if np.ptp(height) <= 0:
        return np.full_like(d, np.median(d))
    from scipy.stats import siegelslopes  # here: scipy.stats costs 0.7 s in every process

    b = float(np.clip(siegelslopes(d, height).slope, -max_scale, max_scale))
    return np.median(d - b * height) + b * height


def _baro_record(imu) -> tuple[np.ndarray, np.ndarray] | None:
    """``(t, alt_m)`` of ``imu.attrs["baro"]`` (finite rows), None without a barometer."""
    baro = imu.attrs.get("baro")
    if baro is None:
        return None
    if not isinstance(baro, pd.DataFrame) or not {"t", "alt_m"} <= set(baro.columns):
        raise NavlibInputError("imu.attrs['baro']: expected a DataFrame with columns t, alt_m")
    t_b = baro["t"].to_numpy(dtype=float)
    h_b = baro["alt_m"].to_numpy(dtype=float)
    ok = np.isfinite(t_b) & np.isfinite(h_b)
    return t_b[ok], h_b[ok]


def _line_misfit(h_g: np.ndarray, h_b: np.ndarray) -> float:
    """RMS of the GNSS-minus-barometer altitude about its line ``a + b h_b`` (the offset
    and scale of the barometric model, Q2)."""
    A = np.column_stack([np.ones_like(h_b), h_b - h_b.mean()])
    d = h_g - h_b
    r = d - A @ np.linalg.lstsq(A, d, rcond=None)[0]
    return float(np.sqrt(np.mean(r**2)))


def grid_minimum(x: np.ndarray, y: np.ndarray) -> float:
    """Where ``y``, sampled on the regular grid ``x``, is smallest: the grid point of its
    minimum, moved to the vertex of the parabola through it and its neighbours when the
    minimum is inside the grid and the parabola opens upwards.

    Parameters
    ----------
    x : numpy.ndarray
        Regular grid, increasing.
    y : numpy.ndarray
        Values on the grid, finite.

    Returns
    -------
    float
    """
    i = int(np.argmin(y))
    at = float(x[i])
    if 0 < i < x.size - 1:
        curvature = y[i - 1] - 2.0 * y[i] + y[i + 1]
        if curvature > 0:
            at += 0.5 * (y[i - 1] - y[i + 1]) / curvature * float(x[1] - x[0])
    return at


def shifted(gnss, lag):
    """A copy of the GNSS record with its fix times moved back by ``lag``, s.

    Parameters
    ----------
    gnss : pandas.DataFrame
        The record (``t`` and the fix columns).
    lag : float
        The lag, s.

    Returns
    -------
    pandas.DataFrame
    """
    out = gnss.copy()
    out["t"] = gnss["t"].to_numpy(dtype=float) - lag
    return out


def baro_lag(imu: pd.DataFrame, gnss: pd.DataFrame, thresholds: Mapping | None = None,
             sigma_m: float = 0.0) -> tuple[float, list[dict]]:
    """The lag of the GNSS fixes behind the barometer (docs/assumptions.md FIT6, Q2).

    A receiver whose fix trails the motion, or a logger that stamps a fix when it arrives,
    records the altitude of ``lag`` seconds before; under a boost at 250 m/s a 1 s lag puts
    the fixes 250 m low, and the altitude check would exclude them as disagreeing with the
    barometer while the fit bent the motion to meet the rest. The lag is the shift of the
    fix times, scanned over +-``lag_max_s`` in steps of ``lag_step_s`` (the minimum refined
    by a parabola), that minimises the misfit of the GNSS altitude against the barometric
    altitude at the shifted times (:func:`_line_misfit`). It counts when it is at least
    ``lag_min_s``, lowers the misfit of no lag by ``lag_min_gain`` and moves the fixes'
    altitude by more than ``sigma_m`` (``|lag|`` times the RMS barometric climb rate over a
    second about the fixes: a hovering vehicle's sub-metre misfit can fall with a lag that is
    not there); the
    barometer is taken as on time.

    Parameters
    ----------
    imu : DataFrame
        The IMU record, with ``attrs["baro"]`` (``t, alt_m``) when the log has a barometer.
    gnss : DataFrame
        ``t, x, y, z`` (ECEF, m).
    thresholds : mapping, optional
        The ``[gnss]`` section of :func:`load_thresholds`.
    sigma_m : float, optional
        GNSS position sigma, m: the least altitude change the lag must make.

    Returns
    -------
    lag : float
        Seconds the fixes trail the barometer (0 without a barometer, vertical motion or a
        significant lag).
    findings : list of dict
        One finding naming the lag and the misfit with and without it, when one was found.
    """
    p = dict(thresholds or load_thresholds()["gnss"])
    record = _baro_record(imu)
    t = gnss["t"].to_numpy(dtype=float)
    if record is None or record[0].size < 2:
        return 0.0, []
    t_b, h_b = record
    n = round(p["lag_max_s"] / p["lag_step_s"])
    lags = p["lag_step_s"] * np.arange(-n, n + 1)
    inside = (t - lags.max() >= t_b[0]) & (t - lags.min() <= t_b[-1])
    if np.count_nonzero(inside) < 4:
        return 0.0, []
    _, _, h_g = earth.ecef_to_geodetic(gnss[list(_XYZ)].to_numpy(dtype=float)[inside])
    misfit = np.array([_line_misfit(h_g, np.interp(t[inside] - lag, t_b, h_b))
                       for lag in lags])
    lag = grid_minimum(lags, misfit)
    no_lag, least = float(misfit[n]), float(misfit.min())
    # the barometric climb rate over a second about each fix (its noise differentiated at
    # the barometer's own rate would pass for motion)
    climb = np.interp(t[inside] + 0.5, t_b, h_b) - np.interp(t[inside] - 0.5, t_b, h_b)
    moved = abs(lag) * float(np.sqrt(np.mean(climb**2)))
    if (abs(lag) < p["lag_min_s"] or least > (1.0 - p["lag_min_gain"]) * no_lag
            or moved <= sigma_m):
        return 0.0, []
    row = finding("gnss lag", "time", t, t.size, p["span_join_s"],
                  f"GNSS fixes trail the barometer by {lag:.2f} s (altitude misfit "
                  f"{no_lag:.3g} m at their stamps, {least:.3g} m moved back by the lag)",
                  "fixes", "; moved back by the lag")
    return lag, [row]


def _baro(imu, gnss, keep: np.ndarray, p: dict) -> tuple[np.ndarray, list[dict]]:
    record = _baro_record(imu)
    t = gnss["t"].to_numpy(dtype=float)
    bad = np.zeros(t.size, dtype=bool)
    if record is None:
        return bad, []
    t_b, h_b = record
    _, _, h_g_all = earth.ecef_to_geodetic(gnss[list(_XYZ)].to_numpy(dtype=float))
    rows = _baro_coverage(t, t_b, h_g_all, h_b, p)
    inside = keep & (t >= t_b[0]) & (t <= t_b[-1]) if t_b.size >= 2 else np.zeros_like(keep)
    if np.count_nonzero(inside) < 3:
        return bad, rows
    h_g = h_g_all[inside]
    h_bi = np.interp(t[inside], t_b, h_b)
    height = h_bi - h_b[0]
    d = h_g - h_bi
    d = d - _baro_offset(d, height, p["baro_max_scale"])
    limit = (p["baro_tolerance_m"] + p["baro_tolerance_fraction"] * np.abs(height)
             + p["baro_tolerance_span_fraction"] * np.ptp(height))
    off = np.abs(d) > limit
    if not off.any():
        return bad, rows
    idx = np.flatnonzero(inside)[off]
    n_in = int(np.count_nonzero(inside))
    excluded = off.sum() <= p["baro_max_excluded_fraction"] * n_in
    if excluded:
        bad[idx] = True
    action = ("excluded" if excluded else
              f"kept: more than {100 * p['baro_max_excluded_fraction']:.3g} % of the fixes "
              "disagree, so which sensor is wrong cannot be told")
    row = finding("gnss altitude", "altitude", t[idx], t.size, p["span_join_s"],
                   f"GNSS altitude disagrees with the barometer by up to "
                   f"{np.abs(d).max():.3g} m after removing their offset and scale (GNSS "
                   f"altitude spans {np.ptp(h_g):.3g} m, barometer {np.ptp(h_bi):.3g} m where "
                   f"both exist; tolerance {p['baro_tolerance_m']:g} m + "
                   f"{p['baro_tolerance_fraction']:g} x height + "
                   f"{p['baro_tolerance_span_fraction']:g} x height span)", "fixes",
                   f"; {action}")
    return bad, [*rows, row]


def _jerk_bound(imu, p: dict) -> tuple[np.ndarray, np.ndarray]:
    """IMU times and the bound ``|df/dt| + |w| |f|`` of the kinematic jerk (m/s^3),
    ``f`` smoothed by a moving average over ``jerk_smoothing_s``."""
    t = imu["t"].to_numpy(dtype=float)
    f = imu[list(_ACCEL)].to_numpy(dtype=float)
    w = imu[list(_GYRO)].to_numpy(dtype=float)
    dt = float(np.median(np.diff(t)))
    n = min(max(round(p["jerk_smoothing_s"] / dt), 1), t.size)  # "same" keeps t.size rows
    kernel = np.ones(n) / n
    f_s = np.column_stack([np.convolve(f[:, i], kernel, mode="same") for i in range(3)])
    df = np.gradient(f_s, t, axis=0)
    bound = np.linalg.norm(df, axis=1) + np.linalg.norm(w, axis=1) * np.linalg.norm(f_s, axis=1)
    return t, bound


def _leave_one_out(t: np.ndarray, P: np.ndarray, window: float):
    """Residual of each fix from the least-squares quadratic in time through the other fixes
    within ``+-window`` (NaN without one on each side and four in all), the half-width ``h``
    used, and the neighbour offsets with their validity (for the local-maximum test)."""
    n = t.size
    dt = float(np.median(np.diff(t))) if n > 1 else window
    m = max(int(np.ceil(window / max(dt, 1e-9))), 1)
    m = min(m, max(n - 1, 1))
    offsets = np.r_[-m:0, 1:m + 1]
    j = np.arange(n)[:, None] + offsets[None, :]
    inside = (j >= 0) & (j < n)
    j = np.clip(j, 0, n - 1)
    tau = t[j] - t[:, None]
    valid = inside & (np.abs(tau) <= window)
    before = np.count_nonzero(valid & (offsets < 0), axis=1)
    after = np.count_nonzero(valid & (offsets > 0), axis=1)
    ok = (before >= 1) & (after >= 1) & (before + after >= 4)
    wv = valid.astype(float)
    powers = np.stack([np.ones_like(tau), tau, tau**2], axis=-1) * wv[..., None]
    AtA = np.einsum("nki,nkj->nij", powers, powers)
    dP = P[j] - P[:, None, :]
    Aty = np.einsum("nki,nkc->nic", powers, dP)
    residual = np.full(n, np.nan)
    if ok.any():
        coef = np.linalg.solve(AtA[ok], Aty[ok])
        residual[ok] = np.linalg.norm(coef[:, 0, :], axis=1)
    h = np.max(np.abs(tau) * wv, axis=1)
    return residual, h, j, valid


def _jumps(imu, gnss, keep: np.ndarray, sigma: float, p: dict) -> tuple[np.ndarray, list]:
    t_all = gnss["t"].to_numpy(dtype=float)
    idx = np.flatnonzero(keep)
    bad = np.zeros(t_all.size, dtype=bool)
    if idx.size < 5:
        return bad, []
    t = t_all[idx]
    P = gnss[list(_XYZ)].to_numpy(dtype=float)[idx]
    if "sigma" in gnss.columns:
        s = gnss["sigma"].to_numpy(dtype=float)[idx]
        s = np.where(np.isfinite(s) & (s > 0), s, sigma)
    else:
        s = np.full(t.size, sigma)
    window = p["jump_window_s"]
    residual, h, j, valid = _leave_one_out(t, P, window)
    # the IMU's jerk bound, its largest value within +-window of each fix
    t_i, jerk = _jerk_bound(imu, p)
    rate = 1.0 / float(np.median(np.diff(t_i)))
    widest = maximum_filter1d(jerk, size=2 * int(np.ceil(window * rate)) + 1, mode="nearest")
    k_i = np.clip(np.searchsorted(t_i, t), 0, t_i.size - 1)
    bound = np.maximum(p["jump_min_m"], p["jump_sigmas"] * s) + widest[k_i] * h**3 / 6.0
    filled = np.nan_to_num(residual, nan=-np.inf)
    neighbour_max = np.max(np.where(valid, filled[j], -np.inf), axis=1)
    # a jump is the largest residual of its window (its neighbours' predictions it spoils)
    hit = np.isfinite(residual) & (residual > bound) & (filled >= neighbour_max)
    if not hit.any():
        return bad, []
    bad[idx[hit]] = True
    jump = finding("gnss jump", "position", t[hit], t_all.size, window,
                       f"GNSS position jumps the IMU cannot explain (up to "
                       f"{residual[hit].max():.3g} m off the path through the neighbouring "
                       "fixes)", "fixes", "; excluded")
    return bad, [jump]


def gnss_faults(imu: pd.DataFrame, gnss: pd.DataFrame, sigma_m: float,
                thresholds: Mapping | None = None) -> tuple[np.ndarray, pd.DataFrame]:
    """GNSS fixes that are frozen, disagree with the barometer, or jump (Q2-Q4).

    Parameters
    ----------
    imu : DataFrame
        The IMU record (SI), with ``attrs["baro"]`` (``t, alt_m``) when the log has a
        barometer.
    gnss : DataFrame
        ``t, x, y, z`` (ECEF, m), optional ``vx, vy, vz`` and ``sigma``.
    sigma_m : float
        GNSS position sigma, m, where the record has no ``sigma`` column.
    thresholds : mapping, optional
        The ``[gnss]`` section of :func:`load_thresholds`.

    Returns
    -------
    bad : ndarray of bool (len(gnss),)
        Fixes to exclude (frozen repeats, barometer disagreements when few, jumps).
    findings : DataFrame
        One row per kind of fault found (:data:`FINDING_COLUMNS`).
    """
    check_record(imu, "imu", (*_ACCEL, *_GYRO))
    check_record(gnss, "gnss", _XYZ)
    p = dict(thresholds or load_thresholds()["gnss"])
    sigma_m = finite_scalar(sigma_m, "sigma_m", 0.0, low_open=True)
    frozen, rows = _frozen(imu, gnss, p)
    baro, baro_rows = _baro(imu, gnss, ~frozen, p)
    jumps, jump_rows = _jumps(imu, gnss, ~(frozen | baro), sigma_m, p)
    return frozen | baro | jumps, findings_frame(rows + baro_rows + jump_rows)


def faulty_time(gnss: pd.DataFrame, bad: np.ndarray, imu: pd.DataFrame, p: dict
                ) -> tuple[float, float, list[str]]:
    """The time of the GNSS record its faulty fixes cover, its span, and what covers it.

    Each fix stands for the time half-way to its neighbours (the first and last for the
    half-interval on their inner side); the faulty time is the sum over the fixes ``bad``
    flags, plus the fixes a reader dropped as held (``attrs["held_runs"]``, ``(t_fix,
    t_last_repeat)`` per fix logged again unchanged) over every run lasting at least
    ``frozen_min_duration_s`` while the vehicle moved (the IMU says so, or the next fresh
    fix lies more than ``frozen_exit_distance_m`` away: the signs of a frozen fix, Q2): a
    receiver that repeats one fix that long in motion delivers no measurement,
    whereas shorter repeats are its update interval and repeats at rest may be the truth.
    A fault is counted by the time it covers, not by its rows: a receiver logged at 20 Hz
    while frozen fills many rows with little time (assumptions Q4, Q7).

    Parameters
    ----------
    gnss : DataFrame
        The GNSS record as read (``t, x, y, z``; ``attrs["held_runs"]`` when a reader
        dropped held rows).
    bad : ndarray of bool (len(gnss),)
        The fixes found faulty (:func:`gnss_faults`).
    imu : DataFrame
        The IMU record, for the motion during each hold.
    p : dict
        The ``[gnss]`` thresholds of :func:`~navlib.io.findings.load_thresholds`.

    Returns
    -------
    faulty_s, span_s : float
        Faulty time and the record's span, s.
    parts : list of str
        The faulty time by cause, for a message.
    """
    t = gnss["t"].to_numpy(dtype=float)
    span = float(t[-1] - t[0]) if t.size > 1 else 0.0
    if t.size < 2:
        return 0.0, span, []
    edges = np.r_[t[0], 0.5 * (t[1:] + t[:-1]), t[-1]]
    share = np.diff(edges)
    excluded = float(share[bad].sum())
    parts = [f"{excluded:.3g} s of excluded fixes"] if bad.any() else []
    P = gnss[list(_XYZ)].to_numpy(dtype=float)

    def moved(a: float, b: float) -> bool:
        k = min(int(np.searchsorted(t, a)), t.size - 1)         # the fix that was held
        step = float(np.linalg.norm(P[k + 1] - P[k])) if k + 1 < t.size else 0.0
        return (step > p["frozen_exit_distance_m"]
                or _imu_motion(imu, a, b, P[k], p) is not None)

    runs = [(a, b) for a, b in gnss.attrs.get("held_runs", ())
            if b - a >= p["frozen_min_duration_s"] and moved(a, b)]
    held = float(sum(b - a for a, b in runs))
    if runs:
        longest = max(runs, key=lambda r: r[1] - r[0])
        parts.append(f"{held:.3g} s of {len(runs)} fix(es) held at least "
                     f"{p['frozen_min_duration_s']:g} s while the vehicle moved (the longest "
                     f"{longest[1] - longest[0]:.3g} s from {longest[0]:.1f} s)")
    return min(excluded + held, span), span, parts
