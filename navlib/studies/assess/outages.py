"""The GNSS record as the assessment's model sees it: which model epochs a kept fix aids,
and the outages of the record (docs/assumptions.md Q5).

The 21-state model is discretised to a regular grid of epochs (``gnss_rate_hz``); a fix
that is missing from the record (a gap), or was dropped by the quality checks (a frozen or
held position, a barometer disagreement, a jump: :func:`navlib.io.quality.check_records`),
aids no epoch. An epoch without a kept fix keeps its transition but has a zero
measurement matrix, as a planned outage does (assumption M6), so the covariance grows on
the IMU alone there and the sensability falls.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

__all__ = ["OUTAGE_COLUMNS", "gnss_outages", "measured_epochs", "outage_note"]

OUTAGE_COLUMNS = ("t_start", "t_end", "duration")
"""Columns of :func:`gnss_outages`: the last kept fix before the outage and the first after
it (or the span's start or end), s, and their difference, s."""


def measured_epochs(t_epochs, t_fixes) -> np.ndarray:
    """True at each model epoch that a kept fix aids.

    Each fix aids the epoch nearest it (the epochs' cells are split at the midpoints between
    consecutive epochs; the first and last cells reach half an interval outside), so one
    fix aids one epoch and an epoch whose cell holds no fix has no measurement.

    Parameters
    ----------
    t_epochs : array (N,)
        Model epoch times, s, increasing.
    t_fixes : array (M,)
        Times of the kept fixes, s.

    Returns
    -------
    ndarray of bool (N,)
    """
    t_epochs = np.asarray(t_epochs, dtype=float)
    t_fixes = np.asarray(t_fixes, dtype=float)
    measured = np.zeros(t_epochs.size, dtype=bool)
    if t_epochs.size == 0 or t_fixes.size == 0:
        return measured
    if t_epochs.size == 1:
        measured[0] = True
        return measured
    mid = 0.5 * (t_epochs[1:] + t_epochs[:-1])
    edges = np.concatenate([[t_epochs[0] - (mid[0] - t_epochs[0])], mid,
                            [t_epochs[-1] + (t_epochs[-1] - mid[-1])]])
    cell = np.searchsorted(edges, t_fixes, side="right") - 1
    measured[cell[(cell >= 0) & (cell < t_epochs.size)]] = True
    return measured


def gnss_outages(t_fixes, t_start: float, t_end: float, min_duration_s: float
                 ) -> pd.DataFrame:
    """Spans of ``[t_start, t_end]`` longer than ``min_duration_s`` without a kept fix.

    An outage runs from the last kept fix before it (or ``t_start``) to the first kept fix
    after it (or ``t_end``); ``duration`` is the time without a fix, s. The threshold is
    ``[gnss] outage_report_s`` of ``data/quality.toml`` in the assessment (assumption Q5).

    Parameters
    ----------
    t_fixes : array (K,)
        Times of the kept fixes, s.
    t_start, t_end : float
        The flight's first and last time, s.
    min_duration_s : float
        Shortest outage reported, s.

    Returns
    -------
    DataFrame
        :data:`OUTAGE_COLUMNS`, one row per outage in time order (empty when none).
    """
    t = np.asarray(t_fixes, dtype=float)
    t = np.sort(t[np.isfinite(t) & (t >= t_start) & (t <= t_end)])
    points = np.concatenate([[t_start], t, [t_end]])
    gap = np.diff(points)
    long = np.flatnonzero(gap > min_duration_s)
    return pd.DataFrame({"t_start": points[long], "t_end": points[long + 1],
                         "duration": gap[long]}, columns=list(OUTAGE_COLUMNS))


def outage_note(outages: pd.DataFrame, min_duration_s: float) -> str | None:
    """The outages in words for the assessment's notes (None when there are none)."""
    if outages.empty:
        return None
    spans = "; ".join(f"{r.t_start:.6g}..{r.t_end:.6g} s ({r.duration:.3g} s)"
                      for r in outages.itertuples(index=False))
    return (f"{len(outages)} GNSS outage(s) longer than {min_duration_s:g} s (no kept fix: a "
            f"gap in the record or fixes dropped by the quality checks): {spans}; the model "
            f"has no GNSS measurement at its epochs there, so the states it senses through "
            f"GNSS are sensed on the IMU alone inside them")
