"""Validation of imported flight data: time stamps, gaps, plausible magnitudes, overlap.

Every check raises :class:`navlib.NavlibInputError` naming the source (file or log topic),
the column and the row. Two findings need not be fatal. Gaps: ``on_gap`` chooses whether
they are reported (``"warn"``), refused (``"raise"``) or split into segments (``"split"``:
an integer ``segment`` column, see :func:`split_at_gaps`). Non-physical IMU samples
(:func:`flag_imu_outliers`: beyond 35 rad/s or 100 g) are excluded and listed with time
and value while they are at most 1 % of the record, and refuse it beyond.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import pandas as pd

from navlib import units
from navlib._validation import finite_scalar
from navlib.earth import A
from navlib.errors import FlightDataWarning, NavlibInputError
from navlib.io._table import Source

ON_GAP = ("warn", "raise", "split")
"""Accepted values of the ``on_gap`` keyword."""
AUTO_GAP_FACTOR = 10.0
"""With ``max_gap_s=None`` a gap is an interval longer than this many median intervals."""
R_MIN_M = 6.3e6
"""Smallest plausible geocentric radius of a GNSS fix, m (below the poles' sea level)."""
R_MAX_M = 7.5e6
"""Largest plausible geocentric radius, m (about 1100 km altitude: high sounding rockets)."""
V_MAX_M_S = 12e3
"""Largest plausible ECEF speed, m/s (above Earth escape speed)."""
ACCEL_MAX = 30.0 * units.G0
"""Largest plausible median specific-force norm over a record, m/s^2."""
RATE_MAX_RAD_S = 35.0
"""Default largest plausible angular rate, rad/s (about 2000 deg/s, MEMS full scale)."""
SAMPLE_ACCEL_MAX = 100.0 * units.G0
"""Largest plausible specific-force norm of a single sample, m/s^2 (100 g: beyond the full
scale of autopilot and tactical accelerometers, 16-40 g)."""
MAX_OUTLIER_FRACTION = 0.01
"""Largest share of non-physical IMU samples a reader excludes before it refuses the record."""
IMU_DT_RANGE_S = (1e-5, 1.0)
"""Plausible median IMU sample interval, s (1 Hz .. 100 kHz)."""
GNSS_DT_RANGE_S = (1e-3, 100.0)
"""Plausible median GNSS epoch interval, s (0.01 Hz .. 1 kHz)."""


@dataclass(frozen=True)
class TimeOverlap:
    """Common time span of an IMU record and a GNSS record (s), see :func:`check_overlap`."""

    t_start: float
    t_end: float
    imu_span: tuple[float, float]
    gnss_span: tuple[float, float]
    n_gnss: int
    """GNSS epochs inside ``[t_start, t_end]``."""

    @property
    def duration(self) -> float:
        return self.t_end - self.t_start


def check_times(t: np.ndarray, source: Source, column: str) -> None:
    """At least two samples; strictly increasing; duplicates and backward steps named.

    Parameters
    ----------
    t : numpy.ndarray
        Time stamps, s, (N,).
    source : Source
        Where the rows come from (names the offending line in the message).
    column : str
        Name of the time column, for the message.

    Raises
    ------
    NavlibInputError
        With fewer than two samples, or at the first duplicate or backward time stamp.
    """
    if t.size < 2:
        raise source.error(column, None, f"need at least 2 samples, got {t.size}")
    dt = np.diff(t)
    bad = np.flatnonzero(dt <= 0.0)
    if bad.size:
        k = int(bad[0]) + 1
        prev = source.where(k - 1)
        if dt[k - 1] == 0.0:
            problem = f"duplicate time stamp {t[k]:.10g} (same as {prev})"
            dup = np.flatnonzero(dt == 0.0) + 1
            if dup.size > 1:
                shown = ", ".join(source.where(int(j)) for j in dup[:8])
                problem += (f"; {dup.size} duplicated time stamps in all, at {shown}"
                            + (" ..." if dup.size > 8 else ""))
        else:
            problem = (f"time stamp {t[k]:.10g} goes backwards from {t[k - 1]:.10g} at {prev}; "
                       f"time stamps must be strictly increasing")
        raise source.error(column, k, problem)


def _unit_hint(value: float, low: float, high: float, keyword: str, table) -> str:
    """Suggest the unit that would bring ``value`` (in SI under the declared unit) into range."""
    for name, f in table:
        if low <= value * f <= high:
            return f"; it looks like {name}: set {keyword}={name!r}"
    return ""


def check_sample_interval(t: np.ndarray, source: Source, column: str, kind: str,
                          time_factor: float) -> None:
    """The median interval must be plausible for an IMU or a GNSS receiver (unit mix-ups).

    Parameters
    ----------
    t : numpy.ndarray
        Time stamps, s, (N,).
    source : Source
        Where the rows come from.
    column : str
        Name of the time column, for the message.
    kind : {"imu", "gnss"}
        Which plausible range applies.
    time_factor : float
        Declared time unit in s, used to suggest the ``time_unit`` that fits.

    Raises
    ------
    NavlibInputError
        If the median interval is outside the plausible range.
    """
    low, high = IMU_DT_RANGE_S if kind == "imu" else GNSS_DT_RANGE_S
    dt = float(np.median(np.diff(t)))
    if low <= dt <= high:
        return
    raw = dt / time_factor
    hint = _unit_hint(raw, low, high, "time_unit",
                      [("s", 1.0), ("ms", units.MILLISECOND), ("us", units.MICROSECOND),
                       ("ns", units.NANOSECOND)])
    raise source.error(column, None,
                       f"median sample interval {dt:.6g} s is implausible for {kind.upper()} "
                       f"data (expected {low:g}..{high:g} s){hint}")


def check_imu_magnitudes(f_b: np.ndarray, source: Source, f_labels: str,
                         accel_declared_g: bool) -> None:
    """Catch unit mix-ups in IMU data from their magnitudes.

    * median |f| in [0.5, 2] m/s^2 although m/s^2 was declared: the data look like g;
    * median |f| in [50, 200] m/s^2 although g was declared: the data look like m/s^2;
    * median |f| above 30 g: implausible (mg, or a wrong scale).

    Angular rates in deg/s declared as rad/s, and single non-physical samples, are found by
    :func:`flag_imu_outliers`.

    The median over the record (not the maximum) keeps short shocks and burns from
    triggering; a record that legitimately violates these passes with ``check_magnitudes=False``.

    Parameters
    ----------
    f_b : numpy.ndarray
        Specific force, m/s^2, (N, 3).
    source : Source
        Where the rows come from.
    f_labels : str
        Names of the specific-force columns, for the message.
    accel_declared_g : bool
        Whether the reader was told the accelerometer is in g.

    Raises
    ------
    NavlibInputError
        On any of the three unit mix-ups above.
    """
    f_norm = np.linalg.norm(f_b, axis=1)
    med = float(np.median(f_norm))
    if not accel_declared_g and 0.5 <= med <= 2.0:
        raise source.error(f_labels, None,
                           f"median specific-force norm is {med:.3g} m/s^2: the data look "
                           f"like g, not m/s^2 (at rest it should read about 9.8); set "
                           f"accel_unit='g' (or check_magnitudes=False)")
    if accel_declared_g and 50.0 <= med <= 200.0:
        raise source.error(f_labels, None,
                           f"median specific-force norm is {med / units.G0:.3g} g: the data "
                           f"look like m/s^2, not g; set accel_unit='m/s^2'")
    if med > ACCEL_MAX:
        raise source.error(f_labels, None,
                           f"median specific-force norm {med:.3g} m/s^2 "
                           f"({med / units.G0:.3g} g) is implausible; mg or a wrong scale?")


def flag_imu_outliers(t: np.ndarray, f_b: np.ndarray, w_ib_b: np.ndarray, source: Source,
                      f_labels: str, w_labels: str, *, max_rate_rad_s: float = RATE_MAX_RAD_S,
                      max_accel_m_s2: float = SAMPLE_ACCEL_MAX,
                      max_fraction: float = MAX_OUTLIER_FRACTION,
                      rate_hint: str = "") -> tuple[np.ndarray, list[dict]]:
    """Non-physical IMU samples: flagged, listed, and excluded unless there are many.

    Rule: a sample whose angular-rate norm exceeds ``max_rate_rad_s`` (default 35 rad/s,
    about 2000 deg/s, the MEMS full scale) or whose specific-force norm exceeds
    ``max_accel_m_s2`` (default 100 g) cannot be a measurement of the vehicle's motion (a
    glitch, a bus error, a crash). When such samples make up at most ``max_fraction``
    (default 1 %) of the record they are excluded (the fit bridges the one-sample holes
    they leave) and returned in a list of ``{"t", "row", "where", "column", "value",
    "rule"}``; more of them refuse the record, naming the first, their count and share,
    and ``rate_hint`` (a keyword the reader has, such as a unit).

    Returns
    -------
    keep : ndarray of bool (N,)
        Samples to keep.
    outliers : list of dict

    Parameters
    ----------
    t, f_b, w_ib_b : numpy.ndarray
        Time stamps, s, (N,); specific force, m/s^2, and angular rate, rad/s, (N, 3).
    source : Source
        Where the rows come from.
    f_labels, w_labels : str
        Names of the specific-force and angular-rate columns, for the messages.
    max_rate_rad_s : float, optional
        Largest physical angular-rate norm, rad/s.
    max_accel_m_s2 : float, optional
        Largest physical specific-force norm, m/s^2.
    max_fraction : float, optional
        Largest share of flagged samples that is excluded rather than refused.
    rate_hint : str, optional
        Reader keyword named in the refusal message.

    Raises
    ------
    NavlibInputError
        If more than ``max_fraction`` of the samples are non-physical.
    """
    w_norm = np.linalg.norm(w_ib_b, axis=1)
    f_norm = np.linalg.norm(f_b, axis=1)
    bad_w, bad_f = w_norm > max_rate_rad_s, f_norm > max_accel_m_s2
    bad = bad_w | bad_f
    rows = np.flatnonzero(bad)
    if rows.size == 0:
        return ~bad, []
    share = rows.size / t.size
    if share > max_fraction:
        k = int(rows[0])
        if bad_w[k]:
            what, labels = (f"angular rate {w_norm[k]:.4g} rad/s exceeds max_rate_rad_s="
                            f"{max_rate_rad_s:g}"), w_labels
        else:
            what, labels = (f"specific force {f_norm[k]:.4g} m/s^2 exceeds max_accel_m_s2="
                            f"{max_accel_m_s2:g}"), f_labels
        raise source.error(labels, k,
                           f"{what}, and {rows.size} of {t.size} samples ({100 * share:.3g} %) "
                           f"are beyond these limits, more than max_outlier_fraction="
                           f"{max_fraction:g}{rate_hint}")
    out = []
    for k in rows:
        k = int(k)
        if bad_w[k]:
            out.append({"t": float(t[k]), "row": k, "where": source.where(k),
                        "column": w_labels, "value": float(w_norm[k]),
                        "rule": f"|w| > max_rate_rad_s={max_rate_rad_s:g}"})
        else:
            out.append({"t": float(t[k]), "row": k, "where": source.where(k),
                        "column": f_labels, "value": float(f_norm[k]),
                        "rule": f"|f| > max_accel_m_s2={max_accel_m_s2:g}"})
    first = out[0]
    warnings.warn(f"{source.label}: {len(out)} non-physical IMU sample(s) excluded, the first "
                  f"at {first['where']} (t = {first['t']:.6g} s, {first['column']} norm "
                  f"{first['value']:.4g}: {first['rule']})", FlightDataWarning, stacklevel=3)
    return ~bad, out


def validated_imu(t, f_b, w_ib_b, source: Source, time_label: str, f_labels: str,
                  w_labels: str, *, check_magnitudes: bool, limits: dict,
                  rate_hint: str) -> tuple[pd.DataFrame, Source]:
    """The checks every log reader applies to an IMU record, and its frame.

    Time stamps (:func:`check_times`, :func:`check_sample_interval`), then with
    ``check_magnitudes`` the unit checks (:func:`check_imu_magnitudes`, m/s^2 declared) and
    the non-physical samples (:func:`flag_imu_outliers` with ``limits``: ``max_rate_rad_s``,
    ``max_accel_m_s2``, ``max_fraction``), which are excluded and listed in
    ``attrs["outliers"]``. Returns the frame ``t, f_x..w_z`` and the source of its rows.

    Parameters
    ----------
    t, f_b, w_ib_b : numpy.ndarray
        Time stamps, s, (N,); specific force, m/s^2, and angular rate, rad/s, (N, 3).
    source : Source
        Where the rows come from.
    time_label, f_labels, w_labels : str
        Names of the time, specific-force and angular-rate columns, for the messages.
    check_magnitudes : bool
        Whether to run the unit and outlier checks.
    limits : dict
        Outlier limits from :func:`reader_limits`.
    rate_hint : str
        Reader keyword named when the record is refused.

    Raises
    ------
    NavlibInputError
        From any of the checks.
    """
    check_times(t, source, time_label)
    check_sample_interval(t, source, time_label, "imu", 1.0)
    outliers, keep = [], np.ones(t.size, dtype=bool)
    if check_magnitudes:
        check_imu_magnitudes(f_b, source, f_labels, False)
        keep, outliers = flag_imu_outliers(t, f_b, w_ib_b, source, f_labels, w_labels,
                                           **limits, rate_hint=rate_hint)
    frame = pd.DataFrame({"t": t[keep], "f_x": f_b[keep, 0], "f_y": f_b[keep, 1],
                          "f_z": f_b[keep, 2], "w_x": w_ib_b[keep, 0], "w_y": w_ib_b[keep, 1],
                          "w_z": w_ib_b[keep, 2]})
    frame.attrs["outliers"] = outliers
    if outliers and source.lines is not None:
        source = Source(source.label, source.lines[keep], row_word=source.row_word)
    return frame, source


def reader_limits(on_gap: str, imu_max_gap_s, gnss_max_gap_s, max_rate_rad_s,
                  max_accel_m_s2, max_outlier_fraction) -> dict:
    """The keywords every log reader shares, checked, and the outlier ``limits`` of
    :func:`validated_imu` they give.

    ``on_gap`` one of :data:`ON_GAP`; the gap thresholds None or positive; ``max_rate_rad_s``
    and ``max_accel_m_s2`` positive (``max_rate_rad_s`` may stay None for a reader that
    derives it from the sensor's range); ``max_outlier_fraction`` in [0, 1]. Returns
    ``{"max_rate_rad_s", "max_accel_m_s2", "max_fraction"}``.

    Parameters
    ----------
    on_gap : str
        Gap policy, one of :data:`ON_GAP`.
    imu_max_gap_s, gnss_max_gap_s : float or None
        Gap thresholds, s (None: automatic).
    max_rate_rad_s : float or None
        Largest physical angular-rate norm, rad/s.
    max_accel_m_s2 : float
        Largest physical specific-force norm, m/s^2.
    max_outlier_fraction : float
        Largest share of non-physical samples excluded rather than refused.

    Returns
    -------
    dict
        The outlier limits.

    Raises
    ------
    NavlibInputError
        If any keyword is out of its range.
    """
    if on_gap not in ON_GAP:
        raise NavlibInputError(f"on_gap: expected one of {list(ON_GAP)}, got {on_gap!r}")
    for name, value in (("imu_max_gap_s", imu_max_gap_s), ("gnss_max_gap_s", gnss_max_gap_s)):
        if value is not None:
            finite_scalar(value, name, 0.0, low_open=True)
    if max_rate_rad_s is not None:
        max_rate_rad_s = finite_scalar(max_rate_rad_s, "max_rate_rad_s", 0.0, low_open=True)
    return {"max_rate_rad_s": max_rate_rad_s,
            "max_accel_m_s2": finite_scalar(max_accel_m_s2, "max_accel_m_s2", 0.0,
                                            low_open=True),
            "max_fraction": finite_scalar(max_outlier_fraction, "max_outlier_fraction", 0.0,
                                          1.0)}


def check_positions(r_e: np.ndarray, source: Source, labels: str,
                    length_factor: float | None = None) -> None:
    """Every ECEF position must lie between 6300 km and 7500 km from the Earth's centre.

    ``length_factor`` (the declared length unit in m) enables a unit hint in the message.

    Parameters
    ----------
    r_e : numpy.ndarray
        ECEF positions, m, (N, 3).
    source : Source
        Where the rows come from.
    labels : str
        Names of the position columns, for the message.
    length_factor : float or None, optional
        Declared length unit in m.

    Raises
    ------
    NavlibInputError
        At the first position out of range.
    """
    r = np.linalg.norm(r_e, axis=1)
    bad = np.flatnonzero((r < R_MIN_M) | (r > R_MAX_M))
    if not bad.size:
        return
    k = int(bad[0])
    med = float(np.median(r))
    hint = "" if length_factor is None else _unit_hint(
        med / length_factor, R_MIN_M, R_MAX_M, "length_unit",
        [("m", 1.0), ("km", units.KILOMETRE), ("mm", units.MILLIMETRE)])
    raise source.error(labels, k,
                       f"position is {r[k]:.6g} m from the Earth's centre, {r[k] - A:.6g} m "
                       f"from the equatorial surface; expected {R_MIN_M:g}..{R_MAX_M:g} m "
                       f"(near the Earth's surface up to ~1100 km altitude){hint}")


def check_velocities(v_e: np.ndarray, source: Source, labels: str) -> None:
    """ECEF speeds must stay below 12 km/s.

    Parameters
    ----------
    v_e : numpy.ndarray
        ECEF velocities, m/s, (N, 3).
    source : Source
        Where the rows come from.
    labels : str
        Names of the velocity columns, for the message.

    Raises
    ------
    NavlibInputError
        At the first speed above the limit.
    """
    v = np.linalg.norm(v_e, axis=1)
    bad = np.flatnonzero(v > V_MAX_M_S)
    if bad.size:
        k = int(bad[0])
        raise source.error(labels, k, f"speed {v[k]:.6g} m/s exceeds {V_MAX_M_S:g} m/s; "
                                      f"wrong velocity unit?")


def check_positive(x: np.ndarray, source: Source, label: str) -> None:
    """Standard deviations must be strictly positive.

    Parameters
    ----------
    x : numpy.ndarray
        Standard deviations, (N,).
    source : Source
        Where the rows come from.
    label : str
        Name of the column, for the message.

    Raises
    ------
    NavlibInputError
        At the first value that is not strictly positive.
    """
    bad = np.flatnonzero(x <= 0.0)
    if bad.size:
        k = int(bad[0])
        raise source.error(label, k, f"standard deviation must be > 0, got {x[k]:.10g}")


def gap_threshold(t: np.ndarray, max_gap_s: float | None) -> float:
    """``max_gap_s``, or ``AUTO_GAP_FACTOR`` times the median interval when None.

    Parameters
    ----------
    t : numpy.ndarray
        Time stamps, s, (N,).
    max_gap_s : float or None
        Threshold, s; None for the automatic one.

    Returns
    -------
    float
        The threshold, s.

    Raises
    ------
    NavlibInputError
        If ``max_gap_s`` is not a positive number or None.
    """
    if max_gap_s is None:
        return AUTO_GAP_FACTOR * float(np.median(np.diff(t)))
    if not np.isfinite(max_gap_s) or max_gap_s <= 0:
        raise NavlibInputError(f"max_gap_s: must be a positive number or None, got {max_gap_s}")
    return float(max_gap_s)


def apply_gap_policy(frame: pd.DataFrame, source: Source, column: str,
                     max_gap_s: float | None, on_gap: str) -> pd.DataFrame:
    """Find intervals longer than the threshold in ``frame.t`` and act on them.

    The gaps are always listed in ``frame.attrs["gaps"]`` (dicts with ``t_start``, ``t_end``,
    ``duration_s``, ``row``: the first row after the gap, ``where``: its file line / sample).
    ``on_gap="warn"`` (default) also emits a :class:`FlightDataWarning`; ``"raise"`` raises
    :class:`NavlibInputError`; ``"split"`` adds an integer column ``segment`` (0, 1, ...)
    that increments after each gap.

    Parameters
    ----------
    frame : pandas.DataFrame
        Record with a time column ``t``, s.
    source : Source
        Where the rows come from.
    column : str
        Name of the time column, for the messages.
    max_gap_s : float or None
        Gap threshold, s (None: automatic, :func:`gap_threshold`).
    on_gap : {"warn", "raise", "split"}
        What to do on a gap.

    Returns
    -------
    pandas.DataFrame
        The frame, with ``attrs["gaps"]`` (and ``segment`` with ``"split"``).

    Raises
    ------
    NavlibInputError
        If ``on_gap`` is unknown, or ``"raise"`` and a gap is found.
    """
    if on_gap not in ON_GAP:
        raise NavlibInputError(f"on_gap: expected one of {list(ON_GAP)}, got {on_gap!r}")
    t = frame["t"].to_numpy()
    thr = gap_threshold(t, max_gap_s)
    dt = np.diff(t)
    # an interval equal to the threshold is no gap, whatever the rounding of times written
    # with a few decimals (AltOS logs 0.1 s steps under the parachutes, 10 x its 0.01 s median)
    rows = np.flatnonzero(dt > thr * (1.0 + 1e-6)) + 1
    gaps = [{"t_start": float(t[k - 1]), "t_end": float(t[k]), "duration_s": float(dt[k - 1]),
             "row": int(k), "where": source.where(int(k))} for k in rows]
    frame.attrs["gaps"] = gaps
    frame.attrs["max_gap_s"] = thr
    if gaps:
        longest = max(gaps, key=lambda g: g["duration_s"])
        text = (f"{len(gaps)} gap(s) longer than {thr:.4g} s; the first ends at "
                f"{gaps[0]['where']} (t = {gaps[0]['t_end']:.6g} s), the longest lasts "
                f"{longest['duration_s']:.4g} s")
        if on_gap == "raise":
            raise source.error(column, int(rows[0]),
                               text + "; pass on_gap='split' or 'warn', or a larger max_gap_s")
        if on_gap == "warn":
            warnings.warn(f"{source.label}: {text}", FlightDataWarning, stacklevel=3)
    if on_gap == "split":
        segment = np.zeros(t.size, dtype=np.int64)
        segment[rows] = 1
        frame["segment"] = np.cumsum(segment)
    return frame


def split_at_gaps(frame: pd.DataFrame) -> list[pd.DataFrame]:
    """The contiguous pieces of a record read with ``on_gap="split"``, without ``segment``.

    A frame without a ``segment`` column is returned whole, as a one-element list.
    """
    if not isinstance(frame, pd.DataFrame):
        raise NavlibInputError(f"frame: expected a pandas DataFrame, got {type(frame).__name__}")
    if "segment" not in frame.columns:
        return [frame]
    return [piece.drop(columns="segment").reset_index(drop=True)
            for _, piece in frame.groupby("segment", sort=True)]


def _span(frame, name: str) -> tuple[float, float, np.ndarray]:
    if not isinstance(frame, pd.DataFrame):
        raise NavlibInputError(f"{name}: expected a pandas DataFrame, got {type(frame).__name__}")
    if "t" not in frame.columns:
        raise NavlibInputError(f"{name}: missing column 't'; columns are {list(frame.columns)}")
    t = frame["t"].to_numpy(dtype=float)
    if t.size == 0 or not np.all(np.isfinite(t)):
        raise NavlibInputError(f"{name}: column 't' must be non-empty and finite")
    return float(t.min()), float(t.max()), t


def check_overlap(imu: pd.DataFrame, gnss: pd.DataFrame, *,
                  min_overlap_s: float = 0.0) -> TimeOverlap:
    """Check that the IMU and GNSS records share a time span; return that span.

    Parameters
    ----------
    imu, gnss : DataFrame
        Records with a time column ``t`` in s on a common time base (as returned by
        :func:`read_imu_csv`, :func:`read_gnss_csv`, :func:`read_ulog`).
    min_overlap_s : float
        Shortest acceptable common span, s. The default 0 only demands a positive overlap.

    Raises
    ------
    NavlibInputError
        When the spans do not overlap (or by less than ``min_overlap_s``); the message gives
        both spans, which usually reveals a time-base or time-unit mismatch.
    """
    i0, i1, _ = _span(imu, "imu")
    g0, g1, tg = _span(gnss, "gnss")
    start, end = max(i0, g0), min(i1, g1)
    spans = f"IMU spans {i0:.6g}..{i1:.6g} s, GNSS spans {g0:.6g}..{g1:.6g} s"
    if end <= start:
        raise NavlibInputError(
            f"imu, gnss: time spans do not overlap ({spans}); do both use the same time "
            f"origin and unit?"
        )
    if end - start < min_overlap_s:
        raise NavlibInputError(
            f"imu, gnss: time spans overlap by {end - start:.6g} s only, less than "
            f"min_overlap_s={min_overlap_s:g} ({spans})"
        )
    n = int(np.count_nonzero((tg >= start) & (tg <= end)))
    return TimeOverlap(start, end, (i0, i1), (g0, g1), n)
