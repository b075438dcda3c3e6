"""One colour per flight phase, shared by every figure of a page.

The phase shading of the assessment figures, the bars and spectra of the excitability
figure and the segment shading of the sensability figures all take their colours from
:func:`phase_colour`, so a phase has the same colour in every figure that shows it (a
report page used to colour the flight-phase strip by phase and the excitability bars by
segment number: one phase, two colours). A phase word not in :data:`PHASE_COLOURS` (a
user-named segment) gets a colour of :data:`OTHER_COLOURS` chosen from its name alone, so
it too keeps its colour from figure to figure.
"""

from __future__ import annotations

import zlib

__all__ = ["OTHER_COLOURS", "PHASE_COLOURS", "phase_colour", "segment_phases"]

PHASE_COLOURS = {
    # the automatic phases of every vehicle class (navlib.segmentation.VEHICLE_PHASES)
    "rest": "0.55", "powered": "tab:red", "turn": "tab:purple", "free_fall": "tab:cyan",
    "coast": "tab:blue", "cruise": "tab:green", "climb": "tab:orange", "hover": "tab:olive",
    "descent": "tab:brown",
    # the flight computer's rocketry phases (AltOS, CATS)
    "pad": "0.55", "boost": "tab:red", "fast": "tab:orange", "apogee": "k",
    "drogue": "tab:brown", "main": "tab:pink", "landed": "0.35",
}
"""Colour of each phase word (matplotlib colour specs). Words for the same kind of motion
share a colour (``rest`` / ``pad``, ``powered`` / ``boost``)."""

OTHER_COLOURS = ("gold", "navy", "darkslategray", "tab:gray", "teal", "indigo")
"""Colours of phase words not in :data:`PHASE_COLOURS`, picked by a checksum of the word."""


def phase_colour(phase: str) -> str:
    """The colour of ``phase`` in every figure (:data:`PHASE_COLOURS`, else a fixed pick of
    :data:`OTHER_COLOURS` by the word's CRC-32, independent of the figure and of the order
    the phases come in)."""
    word = str(phase)
    if word in PHASE_COLOURS:
        return PHASE_COLOURS[word]
    base = word.replace("+", " ").split()[0] if word.strip() else word
    # "boost 2" is a boost, and so is "boost+coast" (a boost joined to the coast after it)
    if base in PHASE_COLOURS:
        return PHASE_COLOURS[base]
    return OTHER_COLOURS[zlib.crc32(word.encode("utf-8")) % len(OTHER_COLOURS)]


def segment_phases(analysis) -> list[str] | None:
    """The phase of each segment of ``analysis`` when it has a segment table with a
    ``phase`` column of one row per segment (a flight assessment or a mission plan), else
    None (the paper's analyses: segments without phases)."""
    table = getattr(analysis, "segment_table", None)
    segments = getattr(analysis, "segments", None)
    if table is None or segments is None or "phase" not in getattr(table, "columns", ()):
        return None
    phases = [str(p) for p in table["phase"]]
    return phases if len(phases) == len(segments) else None
