"""The records of a flight to assess: their summary and the checks the pipeline runs first
(columns, enough IMU samples, an accelerometer that feels gravity, a common IMU/GNSS span
long enough for the fit)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from navlib import units
from navlib._validation import increasing_times
from navlib.errors import NavlibInputError
from navlib.io import check_overlap
from navlib.io.checks import R_MAX_M, R_MIN_M
from navlib.io.sensor_health import ALIVE_ACCEL_M_S2
from navlib.trajectory.fit import MIN_IMU_RATE_HZ

__all__ = ["GNSS_KEYS", "IMU_KEYS", "MIN_DURATION_S", "MIN_GNSS_EPOCHS", "MIN_IMU_SAMPLES",
           "MIN_PEAK_ACCEL_G", "check_frame", "check_gnss_record", "check_imu_record",
           "describe_inputs", "median_rate", "validate_records"]

MIN_DURATION_S = 2.0
"""Shortest common IMU/GNSS span accepted, s."""
MIN_GNSS_EPOCHS = 4
"""Fewest GNSS epochs accepted inside the common span (the fit needs four)."""

MIN_IMU_SAMPLES = int(np.ceil(MIN_DURATION_S * MIN_IMU_RATE_HZ)) + 1
"""Fewest IMU samples accepted: :data:`MIN_DURATION_S` of data at the fit's lowest IMU rate
(:data:`navlib.trajectory.fit.MIN_IMU_RATE_HZ`), by construction."""
MIN_PEAK_ACCEL_G = ALIVE_ACCEL_M_S2 / units.G0
"""Specific-force norm, g, an IMU record must reach at least once (assumption Q6 of
docs/assumptions.md; the readers' live-accelerometer bound,
:data:`navlib.io.sensor_health.ALIVE_ACCEL_M_S2`, here for records handed over as
DataFrames): an accelerometer reads about 1 g whenever something holds gravity off (the
ground at rest, thrust or rotors, lift, drag under a parachute); a record that never reads
half of it fell freely from its first sample to its last, which cannot be told from a dead
accelerometer."""

IMU_KEYS = ("t", "f_x", "f_y", "f_z", "w_x", "w_y", "w_z")
GNSS_KEYS = ("t", "x", "y", "z")


def check_frame(frame, name: str, keys) -> None:
    """A record must be a DataFrame with the columns ``keys`` and at least two rows.

    Parameters
    ----------
    frame : pandas.DataFrame
        The record.
    name : str
        Its name, for the message.
    keys : iterable of str
        Required columns.

    Raises
    ------
    NavlibInputError
        Naming what is wrong.
    """
    if not isinstance(frame, pd.DataFrame):
        raise NavlibInputError(f"{name}: expected a pandas DataFrame (navlib.io readers), got "
                               f"{type(frame).__name__}")
    missing = [k for k in keys if k not in frame.columns]
    if missing:
        raise NavlibInputError(f"{name}: missing column(s) {missing}; columns are "
                               f"{list(frame.columns)}")
    if len(frame) < 2:
        raise NavlibInputError(f"{name}: need at least 2 rows, got {len(frame)}")


def _channel_text(name: str, x: np.ndarray) -> str:
    if x.size and np.all(x == x[0]):
        return f"{name} reads {x[0]:.4g} in every sample"
    return f"{name} median {np.median(x):.4g} ({np.min(x):.4g}..{np.max(x):.4g})"


def _finite_columns(frame: pd.DataFrame, name: str, keys) -> None:
    """``keys`` of ``frame`` finite numbers, ``t`` strictly increasing."""
    for key in keys:
        x = frame[key].to_numpy(dtype=float, na_value=np.nan)
        bad = np.flatnonzero(~np.isfinite(x))
        if bad.size:
            raise NavlibInputError(f"{name}: column {key!r} is not finite at row {int(bad[0])} "
                                   f"({x[bad[0]]}; {bad.size} row(s) in all)")
    increasing_times(frame["t"].to_numpy(dtype=float), f"{name} column 't'")


def check_imu_record(imu: pd.DataFrame) -> None:
    """The IMU checks every assessment runs before the data-quality checks that rely on the
    IMU (:func:`navlib.io.quality.check_records`: the GNSS faults are judged against it).

    * at least :data:`MIN_IMU_SAMPLES` samples;
    * finite samples, strictly increasing times;
    * a specific-force norm reaching :data:`MIN_PEAK_ACCEL_G` (assumption Q6): an
      accelerometer reading zeros (dead, unplugged, zeroed columns) or values in g is
      refused, naming what each axis read.
    """
    n = len(imu)
    if n < MIN_IMU_SAMPLES:
        raise NavlibInputError(
            f"imu: {n} sample(s); an assessment needs at least {MIN_IMU_SAMPLES} IMU samples "
            f"({MIN_DURATION_S:g} s of data at the fit's lowest rate of {MIN_IMU_RATE_HZ:g} "
            f"Hz)")
    _finite_columns(imu, "imu", IMU_KEYS)
    f_b = imu[list(IMU_KEYS[1:4])].to_numpy(dtype=float)
    peak = float(np.max(np.linalg.norm(f_b, axis=1)))
    if peak < MIN_PEAK_ACCEL_G * units.G0:
        axes = "; ".join(_channel_text(k, f_b[:, i]) for i, k in enumerate(IMU_KEYS[1:4]))
        raise NavlibInputError(
            f"imu f_x, f_y, f_z: the accelerometer never reads {MIN_PEAK_ACCEL_G:g} g: its "
            f"specific-force norm is at most {peak:.4g} m/s^2 ({peak / units.G0:.3g} g) over "
            f"{n} samples ({axes}); at rest it reads gravity, about {units.G0:.3g} m/s^2, and "
            "a vehicle is held against gravity some time of any record (the ground, thrust, "
            "lift, drag): a dead or unplugged accelerometer, zeroed columns, or data in g "
            "(the CSV reader's accel_unit='g')?")


def check_gnss_record(gnss: pd.DataFrame) -> None:
    """The GNSS checks every assessment runs before the data-quality checks: finite fixes at
    strictly increasing times, every position between :data:`navlib.io.checks.R_MIN_M` and
    :data:`~navlib.io.checks.R_MAX_M` from the Earth's centre (ECEF, m), as the readers
    demand (a record of zeros was refused as frozen fixes)."""
    _finite_columns(gnss, "gnss", GNSS_KEYS)
    r = np.linalg.norm(gnss[list(GNSS_KEYS[1:])].to_numpy(dtype=float), axis=1)
    bad = np.flatnonzero((r < R_MIN_M) | (r > R_MAX_M))
    if bad.size:
        k = int(bad[0])
        raise NavlibInputError(
            f"gnss: the position of row {k} (t = {gnss['t'].iloc[k]:.6g} s) is {r[k]:.6g} m "
            f"from the Earth's centre, and {bad.size} of {r.size} fixes lie outside "
            f"{R_MIN_M:g}..{R_MAX_M:g} m; expected ECEF x, y, z in m (navlib.io readers)")


def median_rate(t: np.ndarray) -> float:
    return float(1.0 / np.median(np.diff(t))) if t.size > 1 else float("nan")


def describe_inputs(imu: pd.DataFrame, gnss: pd.DataFrame) -> pd.DataFrame:
    """One row per record (``imu``, ``gnss``, and their ``overlap``): samples, first and
    last time (s), duration (s), median rate (Hz), longest interval (s), gaps reported by
    the reader (``attrs["gaps"]``), samples the reader excluded as outliers
    (``attrs["outliers"]``, :func:`navlib.io.checks.flag_imu_outliers`) and the source
    file.

    Parameters
    ----------
    imu, gnss : pandas.DataFrame
        The records.

    Returns
    -------
    pandas.DataFrame
    """
    check_frame(imu, "imu", IMU_KEYS)
    check_frame(gnss, "gnss", GNSS_KEYS)
    rows = []
    for name, frame in (("imu", imu), ("gnss", gnss)):
        t = frame["t"].to_numpy(dtype=float)
        rows.append({"record": name, "samples": t.size, "t_first": t[0], "t_last": t[-1],
                     "duration_s": t[-1] - t[0], "rate_hz": median_rate(t),
                     "longest_interval_s": float(np.max(np.diff(t))),
                     "gaps": len(frame.attrs.get("gaps", [])),
                     "outliers": len(frame.attrs.get("outliers", [])),
                     "source": str(frame.attrs.get("source", ""))})
    span = check_overlap(imu, gnss)
    t_i = imu["t"].to_numpy(dtype=float)
    inside = int(np.count_nonzero((t_i >= span.t_start) & (t_i <= span.t_end)))
    rows.append({"record": "overlap", "samples": inside, "t_first": span.t_start,
                 "t_last": span.t_end, "duration_s": span.duration, "rate_hz": np.nan,
                 "longest_interval_s": np.nan, "gaps": np.nan, "outliers": np.nan,
                 "source": f"{span.n_gnss} GNSS epochs inside"})
    return pd.DataFrame(rows)


def validate_records(imu, gnss):
    """The records checked for an assessment: frames with the required columns that overlap
    for long enough with enough position epochs.

    Parameters
    ----------
    imu, gnss : pandas.DataFrame
        The records (``gnss`` may be the barometer's reference rows of a flight without GNSS).

    Returns
    -------
    TimeOverlap
        Their common span (:func:`navlib.io.checks.check_overlap`), at least
        :data:`MIN_DURATION_S` long with :data:`MIN_GNSS_EPOCHS` epochs.

    Raises
    ------
    NavlibInputError
        Naming the record at fault and what is short (a span without barometer rows, such
        as a pre-launch buffer the barometer aiding could not level, is named as such).
    """
    check_frame(imu, "imu", IMU_KEYS)
    if (isinstance(gnss, pd.DataFrame) and len(gnss) < 2
            and str(gnss.attrs.get("source", "")).startswith("barometer")):
        raise NavlibInputError(
            f"no barometer reference rows in this span ({len(gnss)}): a piece of the record "
            "the barometer aiding could not level (too short, or not at rest; the notes say "
            "why), such as a pre-launch buffer")
    check_frame(gnss, "gnss", GNSS_KEYS)
    span = check_overlap(imu, gnss)
    if span.duration < MIN_DURATION_S:
        raise NavlibInputError(
            f"imu, gnss: the records overlap for {span.duration:.3g} s only; an assessment "
            f"needs at least {MIN_DURATION_S:g} s of common IMU and GNSS data")
    if span.n_gnss < MIN_GNSS_EPOCHS:
        raise NavlibInputError(
            f"gnss: {span.n_gnss} epoch(s) inside the IMU span "
            f"{span.t_start:.6g}..{span.t_end:.6g} s; need at least {MIN_GNSS_EPOCHS}")
    return span

