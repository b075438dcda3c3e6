"""One colour per phase across the figures of a page (issue 34): the phase shading of the
assessment figures, the excitability bars and spectra and the sensability shading take the
same colour for the same phase; analyses without phases keep one colour per segment."""

from types import SimpleNamespace

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest
from matplotlib.colors import to_rgba

from navlib.plots.assess import shade_phases
from navlib.plots.metrics import SEGMENT_COLOURS, excitability_figure, reshade_segments
from navlib.plots.phases import OTHER_COLOURS, PHASE_COLOURS, phase_colour, segment_phases

PHASES = ["rest", "powered", "coast", "powered", "parachute"]


def _analysis(phases):
    """A stand-in segmented analysis: 4 states, one segment per phase (or without phases)."""
    n = 4
    segments = tuple((10.0 * i, 10.0 * (i + 1)) for i in range(len(phases or [0, 0])))
    ex = [SimpleNamespace(e=np.linspace(0.1, 0.9, n) * (i + 1) / 6, S=np.logspace(0, -3, n),
                          ne=2) for i in range(len(segments))]
    fields = dict(segments=segments, excitability=ex, state_names=[f"s{i}" for i in range(n)],
                  settings={"e_threshold": 0.7, "eta": 1e-3, "d0": "global"})
    if phases:
        fields["segment_table"] = pd.DataFrame({
            "phase": phases, "t_start": [a for a, _ in segments],
            "t_end": [b for _, b in segments]})
    return SimpleNamespace(**fields)


def _rgba(colour):
    return tuple(np.round(to_rgba(colour)[:3], 6))


def test_phase_colour_is_one_per_word_and_independent_of_order():
    assert phase_colour("coast") == PHASE_COLOURS["coast"]
    assert phase_colour("boost 2") == PHASE_COLOURS["boost"]  # a second motor burn
    assert phase_colour("parachute") in OTHER_COLOURS
    assert phase_colour("parachute") == phase_colour("parachute")
    assert segment_phases(_analysis(PHASES)) == PHASES
    assert segment_phases(_analysis(None)) is None


def test_figures_of_a_flight_colour_each_phase_alike():
    analysis = _analysis(PHASES)
    wanted = [_rgba(phase_colour(p)) for p in PHASES]
    fig = excitability_figure(analysis)
    bars, spectrum = fig.axes[:2]
    assert [_rgba(c.patches[0].get_facecolor()) for c in bars.containers] == wanted
    assert [c.get_label() for c in bars.containers] == [
        "τ1 rest", "τ2 powered", "τ3 coast", "τ4 powered", "τ5 parachute"]
    lines = {ln.get_gid(): ln for ln in spectrum.get_lines()}
    assert [_rgba(lines[f"spectrum{i}"].get_color()) for i in range(len(PHASES))] == wanted
    plt.close(fig)

    fig, ax = plt.subplots()
    shaded = [a for a in shade_phases(ax, analysis.segment_table) if hasattr(a, "get_xy")]
    assert [_rgba(a.get_facecolor()) for a in shaded] == wanted
    ax.axvspan(0, 1, gid="segment")  # a sensability axis: its segment shading
    shading = [a for a in reshade_segments(fig, analysis) if hasattr(a, "get_xy")]
    assert [_rgba(a.get_facecolor()) for a in shading] == wanted
    plt.close(fig)


@pytest.mark.parametrize("segments", ["analysis", "list"])
def test_segments_without_phases_keep_a_colour_each(segments):
    analysis = _analysis(None)
    fig = excitability_figure(analysis)
    wanted = [_rgba(c) for c in SEGMENT_COLOURS[:2]]
    assert [_rgba(c.patches[0].get_facecolor()) for c in fig.axes[0].containers] == wanted
    plt.close(fig)
    fig, ax = plt.subplots()
    ax.axvspan(0, 1, gid="segment")
    given = analysis if segments == "analysis" else list(analysis.segments)
    shading = [a for a in reshade_segments(fig, given) if hasattr(a, "get_xy")]
    assert [_rgba(a.get_facecolor()) for a in shading] == wanted
    plt.close(fig)
