"""A user's edit of the segments turned back into the segment table.

:func:`segments_table` accepts a DataFrame (an edited
:meth:`~navlib.segmentation.Segmentation.to_frame`), a list of boundaries or of
``(t_start, t_end)`` / ``(phase, t_start, t_end)`` entries; phases left out take the
automatic segmentation's majority label over the segment.
"""

from collections.abc import Mapping, Sequence
from itertools import pairwise

import numpy as np
import pandas as pd

from navlib._validation import finite_scalar
from navlib.errors import NavlibInputError
from navlib.segmentation.phases import SEGMENT_COLUMNS, TIME_TOL_S, Segmentation

__all__ = ["segments_table"]


def _entry(item, k: int) -> tuple[str | None, float, float]:
    """One segment entry: a mapping, ``(t_start, t_end)`` or ``(phase, t_start, t_end)``."""
    where = f"segments[{k}]"
    if isinstance(item, Mapping):
        missing = [c for c in ("t_start", "t_end") if c not in item]
        if missing:
            raise NavlibInputError(f"{where}: missing key(s) {missing}")
        phase = item.get("phase")
        start, end = item["t_start"], item["t_end"]
    elif isinstance(item, Sequence) and not isinstance(item, str) and len(item) in (2, 3):
        phase = item[0] if len(item) == 3 else None
        start, end = item[-2], item[-1]
    else:
        raise NavlibInputError(f"{where}: expected (t_start, t_end), (phase, t_start, t_end) "
                               f"or a mapping, got {item!r}")
    if phase is not None and (not isinstance(phase, str) or not phase.strip()):
        raise NavlibInputError(f"{where}: phase must be a non-empty string, got {phase!r}")
    return (None if phase is None else phase.strip(), finite_scalar(start, f"{where} t_start"),
            finite_scalar(end, f"{where} t_end"))


def _from_boundaries(values: np.ndarray, t0: float, t1: float) -> list:
    if np.any(np.diff(values) <= 0):
        raise NavlibInputError(f"segments: boundaries must be strictly increasing, got "
                               f"{values.tolist()}")
    cuts = values[(values > t0 + TIME_TOL_S) & (values < t1 - TIME_TOL_S)]
    outside = values[(values < t0 - TIME_TOL_S) | (values > t1 + TIME_TOL_S)]
    if outside.size:
        raise NavlibInputError(f"segments: boundaries {outside.tolist()} lie outside the flight "
                               f"span {t0:.6g}..{t1:.6g} s")
    edges = np.concatenate([[t0], cuts, [t1]])
    return [(None, float(a), float(b)) for a, b in pairwise(edges)]


def segments_table(segments, t_start: float, t_end: float,
                   automatic: Segmentation | None = None) -> pd.DataFrame:
    """Normalise a user's segment choice to the table ``phase, t_start, t_end, duration``.

    Parameters
    ----------
    segments : DataFrame, sequence of numbers, or sequence of entries
        * a DataFrame with ``t_start``, ``t_end`` and optionally ``phase`` columns (e.g.
          an edited :meth:`Segmentation.to_frame`);
        * a list of boundary times, e.g. ``[18, 46]`` or ``[0, 18, 46, 86]``: contiguous
          segments between them, the flight's ends added when missing;
        * a list of ``(t_start, t_end)`` or ``(phase, t_start, t_end)`` tuples or mappings:
          these windows only (gaps allowed, overlaps not).
    t_start, t_end : float
        The flight span, s; every segment must lie inside it.
    automatic : Segmentation, optional
        Labels segments given without a phase by the automatic phase covering most of the
        segment; without it they are labelled ``segment 1``, ``segment 2``, ...

    Raises
    ------
    NavlibInputError
        Unreadable entries, boundaries not increasing or outside the span, empty or
        overlapping segments (naming the entry).
    """
    t0 = finite_scalar(t_start, "t_start")
    t1 = finite_scalar(t_end, "t_end")
    if t1 <= t0:
        raise NavlibInputError(f"t_end: must be after t_start = {t0}, got {t1}")
    if isinstance(segments, Segmentation):
        segments = segments.segments
    if isinstance(segments, pd.DataFrame):
        missing = [c for c in ("t_start", "t_end") if c not in segments.columns]
        if missing:
            raise NavlibInputError(f"segments: missing column(s) {missing}; columns are "
                                   f"{list(segments.columns)}")
        cols = [c for c in SEGMENT_COLUMNS if c in segments.columns]
        entries = [_entry(dict(zip(cols, row, strict=True)), k)
                   for k, row in enumerate(segments[cols].itertuples(index=False))]
    elif isinstance(segments, np.ndarray) or (
            isinstance(segments, Sequence) and not isinstance(segments, str)):
        items = list(segments)
        if not items:
            raise NavlibInputError("segments: empty; give boundaries or segment entries")
        if all(isinstance(x, int | float | np.integer | np.floating)
               and not isinstance(x, bool) for x in items):
            values = np.array([finite_scalar(x, f"segments[{k}]")
                               for k, x in enumerate(items)])
            entries = _from_boundaries(values, t0, t1)
        else:
            entries = [_entry(item, k) for k, item in enumerate(items)]
    else:
        raise NavlibInputError(f"segments: expected a DataFrame, a list of boundaries or of "
                               f"(t_start, t_end) entries, got {type(segments).__name__}")
    if not entries:
        raise NavlibInputError("segments: no segment given")
    rows = sorted(entries, key=lambda e: e[1])
    for k, (_, a, b) in enumerate(rows):
        if b <= a:
            raise NavlibInputError(f"segments: segment {k + 1} ({a:.6g}..{b:.6g} s) is empty; "
                                   f"t_end must be after t_start")
        if a < t0 - TIME_TOL_S or b > t1 + TIME_TOL_S:
            raise NavlibInputError(f"segments: segment {k + 1} ({a:.6g}..{b:.6g} s) leaves the "
                                   f"flight span {t0:.6g}..{t1:.6g} s")
        if k and a < rows[k - 1][2] - TIME_TOL_S:
            raise NavlibInputError(f"segments: segment {k + 1} ({a:.6g}..{b:.6g} s) overlaps "
                                   f"segment {k} (ends {rows[k - 1][2]:.6g} s)")
    phases = [phase if phase is not None else _majority(automatic, a, b, k)
              for k, (phase, a, b) in enumerate(rows)]
    table = pd.DataFrame({"phase": phases, "t_start": [max(r[1], t0) for r in rows],
                          "t_end": [min(r[2], t1) for r in rows]})
    table["duration"] = table["t_end"] - table["t_start"]
    return table


def _majority(automatic: Segmentation | None, a: float, b: float, k: int) -> str:
    """The automatic phase covering most of ``[a, b]`` (``segment k+1`` without one)."""
    if automatic is None:
        return f"segment {k + 1}"
    seg = automatic.segments
    overlap = (np.minimum(seg["t_end"], b) - np.maximum(seg["t_start"], a)).clip(lower=0.0)
    totals = overlap.groupby(seg["phase"]).sum()
    return str(totals.idxmax()) if totals.max() > 0 else f"segment {k + 1}"
