"""Rows of a GNSS CSV file that are no new measurement (assumption Q7 of
docs/assumptions.md): held fixes (a row repeating the previous fix exactly, logged again
between a receiver's updates) and rows reporting an implausible number of satellites.
:func:`screen_fixes` finds them for :func:`navlib.io.read_gnss_csv`, which drops the held rows
and those with too few satellites for a 3-D fix, and keeps those reporting more satellites
than can be seen (a corrupt count; their positions are judged by the quality checks), each
kind with a :class:`~navlib.errors.FlightDataWarning` naming its count and lines."""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import replace

import numpy as np

from navlib.errors import FlightDataWarning
from navlib.io._table import Source

__all__ = ["MAX_SATELLITES", "MIN_SATELLITES", "SATELLITE_ALIASES", "screen_fixes"]

MAX_SATELLITES = 100
"""Most satellites a fix can plausibly use: about 130 GNSS satellites orbit in all (GPS,
GLONASS, Galileo, BeiDou) and at most about 60 are above one horizon (Q7)."""
MIN_SATELLITES = 4
"""Fewest satellites of a 3-D fix (three coordinates and the receiver clock)."""
SATELLITE_ALIASES = ("satellites", "sats", "nsat", "num_sats", "numsv", "satellites_used",
                     "sat_count", "n_sat")
"""Accepted header names of the optional satellite-count column (normalised)."""
_SHOWN = 5


def _lines(src: Source, rows: np.ndarray) -> str:
    shown = ", ".join(src.where(int(k)) for k in rows[:_SHOWN])
    return shown + (f" and {rows.size - _SHOWN} more" if rows.size > _SHOWN else "")


def _satellites(sats: np.ndarray, kept: np.ndarray, src: Source, column: str
                ) -> tuple[np.ndarray, int]:
    """Rows among ``kept`` with fewer than :data:`MIN_SATELLITES` (no 3-D fix: dropped), and
    how many report more than :data:`MAX_SATELLITES` (warned about but kept: the count is
    corrupt, not necessarily the position, which the quality checks judge)."""
    few = kept & (sats < MIN_SATELLITES)
    many = kept & (sats > MAX_SATELLITES)
    if many.any():
        rows = np.flatnonzero(many)
        warnings.warn(f"{src.label}, column {column}: {rows.size} of {sats.size} GNSS rows "
                      f"report more than {MAX_SATELLITES} satellites (up to "
                      f"{int(np.max(sats[many])):d}; about 60 can be above the horizon), at "
                      f"{_lines(src, rows)}: an implausible count; their positions are kept "
                      "and judged by the quality checks", FlightDataWarning, stacklevel=4)
    if few.any():
        rows = np.flatnonzero(few)
        warnings.warn(f"{src.label}, column {column}: {rows.size} of {sats.size} GNSS rows "
                      f"report fewer than {MIN_SATELLITES} satellites, at {_lines(src, rows)}: "
                      "no 3-D fix, dropped", FlightDataWarning, stacklevel=4)
    return few, int(np.count_nonzero(many))


def screen_fixes(values: Mapping[str, np.ndarray], fix_keys, src: Source,
                 satellites_label: str | None, keep_held: bool
                 ) -> tuple[dict[str, np.ndarray], Source, dict]:
    """The GNSS rows without, unless ``keep_held``, the held ones (every one of ``fix_keys``
    equal to the previous row's) and without the other rows whose ``satellites`` value is
    below :data:`MIN_SATELLITES` (rows above :data:`MAX_SATELLITES` are warned about and
    kept); each kind warned about with its count and first lines (assumption Q7).

    Parameters
    ----------
    values : mapping of str to ndarray
        The parsed columns by key (``t``, the ``fix_keys``, optional ``satellites``).
    fix_keys : sequence of str
        The columns a held row repeats: position, and velocity and sigma when the file has
        them.
    src : navlib.io._table.Source
        Where the rows come from, for the line numbers.
    satellites_label : str or None
        The satellite column as the file names it, for the message.
    keep_held : bool
        Keep the held rows.

    Returns
    -------
    values : dict
        The kept rows of each column.
    src : navlib.io._table.Source
        The source of the kept rows.
    attrs : dict
        ``implausible_rows`` (above the maximum), ``too_few_satellites``,
        ``held_fixes_dropped`` and ``held_runs`` (``(t_fix, t_last_repeat)`` per fix logged
        again, s, for :func:`navlib.io.gnss_faults.faulty_time`).
    """
    n = values["t"].size
    keep = np.ones(n, dtype=bool)
    attrs: dict = {"implausible_rows": 0, "too_few_satellites": 0, "held_fixes_dropped": 0,
                   "held_runs": []}
    if not keep_held:
        P = np.column_stack([values[k] for k in fix_keys])
        held = np.r_[False, np.all(P[1:] == P[:-1], axis=1)]
        if held.any():
            rows = np.flatnonzero(held)
            t = values["t"]
            fresh = np.flatnonzero(~held)
            last = np.r_[fresh[1:] - 1, n - 1]
            attrs["held_runs"] = [(float(t[a]), float(t[b]))
                                  for a, b in zip(fresh, last, strict=True) if b > a]
            attrs["held_fixes_dropped"] = int(rows.size)
            longest = max(b - a for a, b in attrs["held_runs"])
            warnings.warn(f"{src.label}: {rows.size} of {n} GNSS rows repeat the previous row's "
                          f"fix exactly (a fix held between the receiver's updates; the "
                          f"longest hold {longest:.3g} s), at {_lines(src, rows)}: not new "
                          "measurements, dropped; the time until the next fresh fix is a "
                          "GNSS outage (keep_held=True keeps them)", FlightDataWarning,
                          stacklevel=4)
            keep &= ~held
    if "satellites" in values:
        few, attrs["implausible_rows"] = _satellites(values["satellites"], keep, src,
                                                     satellites_label or "'satellites'")
        keep &= ~few
        attrs["too_few_satellites"] = int(np.count_nonzero(few))
    if keep.all():
        return dict(values), src, attrs
    out = {k: v[keep] for k, v in values.items()}
    src = replace(src, lines=None if src.lines is None else src.lines[keep],
                  raw=None if src.raw is None else [r for r, k in zip(src.raw, keep,
                                                                         strict=True) if k])
    return out, src, attrs
