"""Findings of the flight-data quality checks (:mod:`navlib.io.quality`,
:mod:`navlib.io.gnss_faults`): their thresholds (``data/quality.toml``), their table
(:data:`FINDING_COLUMNS`) and the helpers that word them with times and spans."""

from __future__ import annotations

import tomllib
import warnings
from collections.abc import Mapping

import numpy as np
import pandas as pd

from navlib._validation import finite_array, finite_scalar, increasing_times, reject_unknown
from navlib.errors import NavlibInputError
from navlib.resources import data_dir

__all__ = ["FINDING_COLUMNS", "RENAMED", "THRESHOLDS_FILE", "check_record", "finding",
           "findings_frame", "load_thresholds", "spans", "spans_text"]

THRESHOLDS_FILE = "quality.toml"
"""File of ``data/`` holding the thresholds (sections ``[saturation]`` and ``[gnss]``)."""
FINDING_COLUMNS = ("check", "channel", "n", "fraction", "t_first", "t_last", "spans",
                   "message")


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
    overrides = _renamed(dict(overrides or {}))
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



RENAMED = {("gnss", "max_excluded_fraction"): "max_faulty_time_fraction"}
"""Threshold keys renamed, old -> new, accepted for one release with a DeprecationWarning
(``[gnss] max_excluded_fraction`` counted faulty rows; its successor counts their time)."""


def _renamed(overrides: dict) -> dict:
    """``overrides`` with the :data:`RENAMED` keys under their new names, each warned about."""
    for (section, old), new in RENAMED.items():
        values = overrides.get(section)
        if isinstance(values, Mapping) and old in values:
            warnings.warn(f"quality thresholds [{section}] {old} is now {new} (the share of the "
                          f"record's time, not of its rows); the old name goes in the next "
                          "release", DeprecationWarning, stacklevel=4)
            values = dict(values)
            values.setdefault(new, values[old])
            del values[old]
            overrides[section] = values
    return overrides


def spans(t: np.ndarray, join_s: float) -> list[tuple[float, float]]:
    """Times grouped into spans whose members are closer than ``join_s``.

    Parameters
    ----------
    t : ndarray
        Sorted times, s.
    join_s : float
        Largest interval inside a span, s.

    Returns
    -------
    list of (float, float)
        First and last time of each span.
    """
    if t.size == 0:
        return []
    cut = np.flatnonzero(np.diff(t) > join_s)
    starts = np.r_[0, cut + 1]
    ends = np.r_[cut, t.size - 1]
    return [(float(t[a]), float(t[b])) for a, b in zip(starts, ends, strict=True)]


def spans_text(spans: list[tuple[float, float]], shown: int = 3) -> str:
    """The first ``shown`` spans as ``"12.0 s, 14.2-15.0 s and 2 more span(s)"``.

    Parameters
    ----------
    spans : list of (float, float)
        As :func:`spans` returns them.
    shown : int
        How many are written out.

    Returns
    -------
    str
    """
    parts = [f"{a:.1f} s" if b - a < 0.05 else f"{a:.1f}-{b:.1f} s" for a, b in spans[:shown]]
    text = ", ".join(parts)
    if len(spans) > shown:
        text += f" and {len(spans) - shown} more span(s)"
    return text


def finding(check: str, channel: str, t_hit: np.ndarray, total: int, join_s: float,
            what: str, count_word: str, after: str = "") -> dict:
    """One finding (a :data:`FINDING_COLUMNS` row) of the samples at times ``t_hit``.

    Parameters
    ----------
    check, channel : str
        The finding's ``check`` and ``channel`` columns.
    t_hit : ndarray
        Times of the samples found, s.
    total : int
        Samples of the record (the ``fraction``'s denominator).
    join_s : float
        Samples closer than this form one span, s.
    what, count_word, after : str
        The message reads ``"<what>: <n> <count_word> (<share> %) at <spans><after>"``.

    Returns
    -------
    dict
    """
    grouped = spans(np.sort(t_hit), join_s)
    fraction = t_hit.size / total
    message = (f"{what}: {t_hit.size} {count_word} ({100.0 * fraction:.2g} %) at "
               f"{spans_text(grouped)}{after}")
    return {"check": check, "channel": channel, "n": int(t_hit.size), "fraction": fraction,
            "t_first": float(t_hit.min()), "t_last": float(t_hit.max()),
            "spans": grouped, "message": message}


def findings_frame(rows: list[dict]) -> pd.DataFrame:
    """The findings ``rows`` as a table of :data:`FINDING_COLUMNS` (empty when none)."""
    return pd.DataFrame(rows, columns=list(FINDING_COLUMNS))


def check_record(frame, name: str, columns) -> None:
    """Check a record is a DataFrame with ``t`` and ``columns`` finite, at least 2 rows and
    times strictly increasing (as the navlib.io readers return).

    Parameters
    ----------
    frame : DataFrame
        The record.
    name : str
        Its name in the messages (``imu``, ``gnss``).
    columns : sequence of str
        The columns besides ``t`` it must have.

    Raises
    ------
    NavlibInputError
        Naming what is not so.
    """
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


