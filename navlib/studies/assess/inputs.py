"""The records of a flight to assess: their summary and the checks the pipeline runs first
(columns, a common IMU/GNSS span long enough for the fit)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from navlib.errors import NavlibInputError
from navlib.io import check_overlap

MIN_DURATION_S = 2.0
"""Shortest common IMU/GNSS span accepted, s."""
MIN_GNSS_EPOCHS = 4
"""Fewest GNSS epochs accepted inside the common span (the fit needs four)."""

IMU_KEYS = ("t", "f_x", "f_y", "f_z", "w_x", "w_y", "w_z")
GNSS_KEYS = ("t", "x", "y", "z")


def check_frame(frame, name: str, keys) -> None:
    if not isinstance(frame, pd.DataFrame):
        raise NavlibInputError(f"{name}: expected a pandas DataFrame (navlib.io readers), got "
                               f"{type(frame).__name__}")
    missing = [k for k in keys if k not in frame.columns]
    if missing:
        raise NavlibInputError(f"{name}: missing column(s) {missing}; columns are "
                               f"{list(frame.columns)}")
    if len(frame) < 2:
        raise NavlibInputError(f"{name}: need at least 2 rows, got {len(frame)}")


def median_rate(t: np.ndarray) -> float:
    return float(1.0 / np.median(np.diff(t))) if t.size > 1 else float("nan")


def describe_inputs(imu: pd.DataFrame, gnss: pd.DataFrame) -> pd.DataFrame:
    """One row per record (``imu``, ``gnss``, and their ``overlap``): samples, first and
    last time (s), duration (s), median rate (Hz), longest interval (s), gaps reported by
    the reader (``attrs["gaps"]``), samples the reader excluded as outliers
    (``attrs["outliers"]``, :func:`navlib.io.checks.flag_imu_outliers`) and the source
    file."""
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
    check_frame(imu, "imu", IMU_KEYS)
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

