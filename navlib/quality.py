"""Flight-data quality: IMU saturation and GNSS faults, found, reported and excluded.

Two checks run on a flight's records before the fit (:func:`navlib.studies.assess.assess_flight`
calls :func:`check_records`); their thresholds are data, in ``data/quality.toml``
(:func:`load_thresholds`), with the reasoning in ``docs/assumptions.md``:

* **Saturation** (:func:`imu_saturation`, assumption Q1). A gyro or accelerometer sample at
  its sensor's range limit reads the limit, not the motion. The range comes from the
  reader (``imu.attrs["range"] = {"gyro_rad_s": ..., "accel_m_s2": ...}``), else from the
  sensor preset (``gyro_range_*`` / ``accel_range_*``, :class:`navlib.sensors.TriadSpec`);
  without either, a *flat top* (an extreme value repeated, far from the channel's bulk)
  counts too. Rule (Q1): a saturated sample is dropped from the IMU record, all six axes of
  it, so the fit bridges it as a hole from its neighbours and the GNSS (holes longer than
  the fit's ``max_bridge_s`` split the flight into spans); a flight with more than
  ``max_fraction`` of its samples saturated is refused.
* **GNSS faults** (:func:`gnss_faults`, assumptions Q2-Q4): frozen (stale) fixes that repeat
  a position while the vehicle moves, altitudes that disagree with the barometer
  (``imu.attrs["baro"]``, DataFrame ``t, alt_m``), and jumps the IMU cannot explain. Rule:
  the faulty fixes are dropped from the GNSS record before the fit; a flight with more than
  ``max_excluded_fraction`` of its fixes dropped is refused.

Every finding is a row of a tidy table (``check, channel, n, fraction, t_first, t_last,
spans, message``) whose ``message`` is a warning with times, e.g. ``gyro w_x at its +-2000
deg/s limit: 8 samples (0.05 %) at 147.9-148.1 s``.
"""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy.ndimage import maximum_filter1d

from navlib import earth
from navlib._validation import finite_array, finite_scalar, increasing_times, reject_unknown
from navlib.errors import NavlibInputError
from navlib.resources import data_dir
from navlib.units import DEG

__all__ = ["FINDING_COLUMNS", "QualityCheck", "check_records", "gnss_faults",
           "imu_saturation", "load_thresholds"]

THRESHOLDS_FILE = "quality.toml"
"""File of ``data/`` holding the thresholds (sections ``[saturation]`` and ``[gnss]``)."""
FINDING_COLUMNS = ("check", "channel", "n", "fraction", "t_first", "t_last", "spans",
                   "message")
_GYRO = ("w_x", "w_y", "w_z")
_ACCEL = ("f_x", "f_y", "f_z")
_XYZ = ("x", "y", "z")


def load_thresholds(overrides: Mapping | None = None) -> dict[str, dict[str, float]]:
    """The thresholds of ``data/quality.toml`` as ``{"saturation": {...}, "gnss": {...}}``.

    ``overrides`` (same two-level shape, e.g. ``{"gnss": {"jump_min_m": 20}}``) replaces
    single values; unknown sections or keys and non-positive values raise
    :class:`~navlib.errors.NavlibInputError`.
    """
    path = data_dir() / THRESHOLDS_FILE
    table = tomllib.loads(path.read_text(encoding="utf-8"))
    out = {section: {k: float(v) for k, v in values.items()} for section, values in
           table.items()}
    overrides = dict(overrides or {})
    reject_unknown(overrides, out, "quality thresholds")
    for section, values in overrides.items():
        if not isinstance(values, Mapping):
            raise NavlibInputError(f"quality thresholds [{section}]: expected a mapping of "
                                   f"threshold -> number, got {values!r}")
        reject_unknown(values, out[section], f"quality thresholds [{section}]")
        for key, value in values.items():
            out[section][key] = finite_scalar(value, f"quality thresholds [{section}] {key}",
                                              0.0, low_open=True)
    return out


# --------------------------------------------------------------------------- helpers


def _spans(t: np.ndarray, join_s: float) -> list[tuple[float, float]]:
    """Times ``t`` (sorted) grouped into spans whose members are closer than ``join_s``."""
    if t.size == 0:
        return []
    cut = np.flatnonzero(np.diff(t) > join_s)
    starts = np.r_[0, cut + 1]
    ends = np.r_[cut, t.size - 1]
    return [(float(t[a]), float(t[b])) for a, b in zip(starts, ends, strict=True)]


def _spans_text(spans: list[tuple[float, float]], shown: int = 3) -> str:
    parts = [f"{a:.1f} s" if b - a < 0.05 else f"{a:.1f}-{b:.1f} s" for a, b in spans[:shown]]
    text = ", ".join(parts)
    if len(spans) > shown:
        text += f" and {len(spans) - shown} more span(s)"
    return text


def _finding(check: str, channel: str, t_hit: np.ndarray, total: int, join_s: float,
             what: str, count_word: str, after: str = "") -> dict:
    spans = _spans(np.sort(t_hit), join_s)
    fraction = t_hit.size / total
    message = (f"{what}: {t_hit.size} {count_word} ({100.0 * fraction:.2g} %) at "
               f"{_spans_text(spans)}{after}")
    return {"check": check, "channel": channel, "n": int(t_hit.size), "fraction": fraction,
            "t_first": float(t_hit.min()), "t_last": float(t_hit.max()),
            "spans": spans, "message": message}


def _frame(rows: list[dict]) -> pd.DataFrame:
    return pd.DataFrame(rows, columns=list(FINDING_COLUMNS))


def _check_record(frame, name: str, columns) -> None:
    """A DataFrame with ``t`` and ``columns`` finite, at least 2 rows, times strictly
    increasing (as the navlib.io readers return); NavlibInputError naming what is not."""
    if not isinstance(frame, pd.DataFrame):
        raise NavlibInputError(f"{name}: expected a pandas DataFrame, got {type(frame).__name__}")
    missing = [c for c in ("t", *columns) if c not in frame.columns]
    if missing:
        raise NavlibInputError(f"{name}: missing column(s) {missing}; columns are "
                               f"{list(frame.columns)}")
    for column in columns:
        finite_array(frame[column].to_numpy(dtype=float, na_value=np.nan),
                     f"{name} column {column!r}", ndim=1)
    increasing_times(frame["t"].to_numpy(dtype=float, na_value=np.nan), f"{name} column 't'")


# --------------------------------------------------------------------------- saturation


def _ranges(imu: pd.DataFrame, spec) -> dict[str, tuple[float | None, str]]:
    """Range (SI) and its source for ``gyro`` and ``accel``: the reader's
    ``attrs["range"]``, else the preset's, else None."""
    given = imu.attrs.get("range") or {}
    if not isinstance(given, Mapping):
        raise NavlibInputError(f"imu.attrs['range']: expected a mapping with gyro_rad_s / "
                               f"accel_m_s2, got {given!r}")
    imu_spec = getattr(spec, "imu", None)
    out = {}
    for sensor, key in (("gyro", "gyro_rad_s"), ("accel", "accel_m_s2")):
        if given.get(key) is not None:
            out[sensor] = (finite_scalar(given[key], f"imu.attrs['range'][{key!r}]", 0.0,
                                         low_open=True), "the log")
        else:
            preset_range = getattr(getattr(imu_spec, sensor, None), "range", None)
            out[sensor] = (preset_range, f"preset {getattr(spec, 'name', '')!r}")
    return out


def _flat_top(x: np.ndarray, floor: float, p: dict) -> tuple[np.ndarray, list[float]] | None:
    """Samples of the channel ``x`` at a repeated extreme (module docstring) and the
    extremes, or None."""
    median = float(np.median(x))
    sigma = 1.4826 * float(np.median(np.abs(x - median)))
    hit = np.zeros(x.size, dtype=bool)
    values = []
    for extreme in (float(x.max()), float(x.min())):
        at = x == extreme
        if (np.count_nonzero(at) >= p["flat_top_min_samples"] and abs(extreme) >= floor
                and abs(extreme - median) >= p["flat_top_min_excursion_sigma"] * sigma):
            hit |= at
            values.append(extreme)
    return (hit, values) if values else None


def imu_saturation(imu: pd.DataFrame, spec=None, thresholds: Mapping | None = None
                   ) -> tuple[np.ndarray, pd.DataFrame]:
    """IMU samples at their sensor's range limit, or at a flat top (assumption Q1).

    Parameters
    ----------
    imu : DataFrame
        ``t, f_x, f_y, f_z, w_x, w_y, w_z`` (SI); ``attrs["range"]`` (``gyro_rad_s``,
        ``accel_m_s2``) when the reader knows the board.
    spec : navlib.sensors.SensorSpec, optional
        The preset; its triads' ``range`` is used where the log gives none.
    thresholds : mapping, optional
        The ``[saturation]`` section of :func:`load_thresholds` (default: the file's).

    Returns
    -------
    saturated : ndarray of bool (N,)
        Rows with at least one axis saturated.
    findings : DataFrame
        One row per saturated channel (:data:`FINDING_COLUMNS`; ``check`` is
        ``saturation`` at a known limit, ``flat top`` otherwise).
    """
    _check_record(imu, "imu", (*_ACCEL, *_GYRO))
    p = dict(thresholds or load_thresholds()["saturation"])
    t = imu["t"].to_numpy(dtype=float)
    ranges = _ranges(imu, spec)
    saturated = np.zeros(t.size, dtype=bool)
    rows = []
    for sensor, channels, unit, factor, floor in (
            ("gyro", _GYRO, "deg/s", DEG, p["flat_top_min_gyro_deg_s"] * DEG),
            ("accel", _ACCEL, "m/s^2", 1.0, p["flat_top_min_accel_m_s2"])):
        limit, source = ranges[sensor]
        for channel in channels:
            x = imu[channel].to_numpy(dtype=float)
            if limit is not None:
                hit = np.abs(x) >= limit * (1.0 - p["limit_tolerance"])
                what = f"{sensor} {channel} at its +-{limit / factor:.4g} {unit} limit"
                after = f" (range from {source})"
                check = "saturation"
            else:
                flat = _flat_top(x, floor, p)
                if flat is None:
                    continue
                hit, values = flat
                at = " and ".join(f"{v / factor:.4g}" for v in values)
                what = f"{sensor} {channel} flat at {at} {unit}"
                after = " (a repeated extreme: the range is not known, taken as its limit)"
                check = "flat top"
            if hit.any():
                saturated |= hit
                rows.append(_finding(check, channel, t[hit], t.size, p["span_join_s"], what,
                                     "samples", after + "; dropped, the fit bridges them"))
    return saturated, _frame(rows)


# --------------------------------------------------------------------------- GNSS


def _moving_evidence(imu, gnss, a: int, b: int, t_next, p: dict) -> str | None:
    """Why the vehicle moved while the fixes ``a..b`` repeated one position, or None."""
    t_g = gnss["t"].to_numpy(dtype=float)
    t0, t1 = t_g[a], t_g[b] if t_next is None else t_next
    if all(c in gnss.columns for c in ("vx", "vy", "vz")):
        v = np.linalg.norm(gnss[["vx", "vy", "vz"]].to_numpy(dtype=float)[a:b + 1], axis=1)
        if np.nanmax(v) > p["moving_speed_m_s"]:
            return f"the GNSS velocity reads up to {np.nanmax(v):.3g} m/s"
    t_i = imu["t"].to_numpy(dtype=float)
    inside = (t_i >= t0) & (t_i <= t1)
    if np.count_nonzero(inside) >= 2:
        rate = np.linalg.norm(imu[list(_GYRO)].to_numpy(dtype=float)[inside], axis=1).mean()
        if rate > p["moving_rate_deg_s"] * DEG:
            return f"the gyros read {rate / DEG:.3g} deg/s on average"
        f_norm = np.linalg.norm(imu[list(_ACCEL)].to_numpy(dtype=float)[inside], axis=1)
        P = gnss[list(_XYZ)].to_numpy(dtype=float)[a]
        g = float(np.linalg.norm(earth.normal_gravity_ecef(P)))
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


def _baro(imu, gnss, keep: np.ndarray, p: dict) -> tuple[np.ndarray, list[dict]]:
    baro = imu.attrs.get("baro")
    t = gnss["t"].to_numpy(dtype=float)
    bad = np.zeros(t.size, dtype=bool)
    if baro is None:
        return bad, []
    if not isinstance(baro, pd.DataFrame) or not {"t", "alt_m"} <= set(baro.columns):
        raise NavlibInputError("imu.attrs['baro']: expected a DataFrame with columns t, alt_m")
    t_b = baro["t"].to_numpy(dtype=float)
    h_b = baro["alt_m"].to_numpy(dtype=float)
    ok = np.isfinite(t_b) & np.isfinite(h_b)
    t_b, h_b = t_b[ok], h_b[ok]
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
    row = _finding("gnss altitude", "altitude", t[idx], t.size, p["span_join_s"],
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
    finding = _finding("gnss jump", "position", t[hit], t_all.size, window,
                       f"GNSS position jumps the IMU cannot explain (up to "
                       f"{residual[hit].max():.3g} m off the path through the neighbouring "
                       "fixes)", "fixes", "; excluded")
    return bad, [finding]


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
    _check_record(imu, "imu", (*_ACCEL, *_GYRO))
    _check_record(gnss, "gnss", _XYZ)
    p = dict(thresholds or load_thresholds()["gnss"])
    sigma_m = finite_scalar(sigma_m, "sigma_m", 0.0, low_open=True)
    frozen, rows = _frozen(imu, gnss, p)
    baro, baro_rows = _baro(imu, gnss, ~frozen, p)
    jumps, jump_rows = _jumps(imu, gnss, ~(frozen | baro), sigma_m, p)
    return frozen | baro | jumps, _frame(rows + baro_rows + jump_rows)


# --------------------------------------------------------------------------- both


@dataclass(frozen=True, eq=False)
class QualityCheck:
    """Result of :func:`check_records`.

    Attributes
    ----------
    imu, gnss : DataFrame
        The records with the saturated samples and the faulty fixes dropped (``attrs``
        kept).
    findings : DataFrame
        Every finding (:data:`FINDING_COLUMNS`); ``message`` is the warning text.
    thresholds : dict
        The thresholds used.
    """

    imu: pd.DataFrame
    gnss: pd.DataFrame
    findings: pd.DataFrame
    thresholds: dict = field(default_factory=dict)

    @property
    def warnings(self) -> list[str]:
        """The findings' messages."""
        return list(self.findings["message"])


def _drop(frame: pd.DataFrame, bad: np.ndarray) -> pd.DataFrame:
    out = frame[~bad].reset_index(drop=True)
    out.attrs = dict(frame.attrs)
    return out


def check_records(imu: pd.DataFrame, gnss: pd.DataFrame, spec=None, sigma_m: float = 5.0,
                  thresholds: Mapping | None = None) -> QualityCheck:
    """Find saturated IMU samples and faulty GNSS fixes, drop them, and refuse a flight
    with too many (module docstring; assumptions Q1-Q4).

    Parameters
    ----------
    imu, gnss : DataFrame
        The records (:func:`imu_saturation`, :func:`gnss_faults`).
    spec : navlib.sensors.SensorSpec, optional
        Sensor preset (IMU ranges).
    sigma_m : float
        GNSS position sigma where the record has none, m.
    thresholds : mapping, optional
        Overrides of ``data/quality.toml`` (:func:`load_thresholds`).

    Raises
    ------
    NavlibInputError
        Records that are not DataFrames, lack columns, hold fewer than 2 rows, non-finite
        values or times that do not increase; more than ``[saturation] max_fraction`` of the
        IMU samples saturated, or more than ``[gnss] max_excluded_fraction`` of the fixes
        faulty (naming the findings).
    """
    _check_record(imu, "imu", (*_ACCEL, *_GYRO))
    _check_record(gnss, "gnss", _XYZ)
    p = load_thresholds(thresholds)
    saturated, sat = imu_saturation(imu, spec, p["saturation"])
    _refuse_share(saturated, "imu: {} % of the samples are saturated",
                  p["saturation"], "saturation", "max_fraction", sat["message"])
    clean_imu = _drop(imu, saturated)
    bad, faults = gnss_faults(clean_imu, gnss, sigma_m, p["gnss"])
    _refuse_share(bad, "gnss: {} % of the fixes are faulty",
                  p["gnss"], "gnss", "max_excluded_fraction", faults["message"])
    findings = pd.concat([f for f in (sat, faults) if len(f)] or [_frame([])],
                         ignore_index=True)
    return QualityCheck(imu=clean_imu, gnss=_drop(gnss, bad), findings=findings,
                        thresholds=p)


def _refuse_share(flags, what: str, table: dict, section: str, key: str, messages) -> None:
    """NavlibInputError when the share of ``flags`` exceeds ``table[key]`` (the
    ``[section] key`` of data/quality.toml), naming the findings ``messages``."""
    fraction = np.count_nonzero(flags) / flags.size
    if fraction > table[key]:
        share = f"{100 * fraction:.3g}"
        raise NavlibInputError(
            f"{what.format(share)}, more than the "
            f"{100 * table[key]:.3g} % an assessment accepts "
            f"(data/quality.toml [{section}] {key}): {'; '.join(messages)}")

