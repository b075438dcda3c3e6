"""Notebook 02's panel (navlib.widgets.observability): each control recomputes only what it
touches, and the rank-tolerance slider gives the kept figures the new tolerance in place,
the same picture as the figures drawn in full."""

import numpy as np
import pytest
from support.images import drawn_as_kept, pixels

from navlib.observability import analyze
from navlib.plots.figure import detached
from navlib.plots.observability import mission_figure, singular_values_figure
from navlib.trajectory import launcher_ascent
from navlib.widgets.observability import observability_panel


@pytest.fixture(scope="module")
def panel():
    with detached():
        return observability_panel(launcher_ascent(duration_s=30.0), stride=400)


def _ok(panel):
    assert "Not a valid configuration" not in panel.status.value
    assert "navlib-panel-error" not in panel.status.value


def _threshold(panel):
    line = panel.figures.figure("step").axes[0].lines[0]
    return float(line.get_ydata()[0])


def test_rank_tolerance_moves_the_threshold_and_reranks(panel):
    rtol = panel.controls["log10_rtol"]
    before = panel.parts["step"].value
    rtol.value = rtol.value + 0.5
    _ok(panel)
    s = panel._raw.singular_values
    np.testing.assert_array_equal(panel.result.rank,
                                  np.sum(s > panel.rtol * s[:, :1], axis=1))
    sigma_1 = np.linalg.svd(panel._step[1], compute_uv=False)[0]
    assert _threshold(panel) == pytest.approx(np.log10(panel.rtol * sigma_1))
    assert panel.parts["step"].value != before
    rtol.value = rtol.value - 0.5
    _ok(panel)


def test_a_rank_tolerance_move_shows_the_figures_drawn_in_full(panel):
    """The kept curve and spectrum get the new ranks and threshold in place: each image is
    the figure of the new tolerance drawn in full in the kept layout."""
    rtol = panel.controls["log10_rtol"]
    start = rtol.value
    with detached():
        for value in (start + 0.25, start + 0.75, start):
            kept = panel.figures.figure("curve"), panel.figures.figure("step")
            rtol.value = value
            _ok(panel)
            assert (panel.figures.figure("curve"), panel.figures.figure("step")) == kept
            title = f"{panel.model.name}; eq. (6) {panel.controls['variant'].value}"
            want = drawn_as_kept(mission_figure(panel.result, panel.trajectory.events,
                                                title=title), kept[0], panel.dpi)
            assert np.array_equal(pixels(panel.parts["curve"].value), want), value
            O = panel._step[1]
            a = analyze(O, rtol=panel.rtol, state_names=panel.model.state_names,
                        coupling_threshold="auto")
            step_title = kept[1].axes[0].get_title() or kept[1]._suptitle.get_text()
            full = singular_values_figure(a, title=step_title)
            want = drawn_as_kept(full, kept[1], panel.dpi)
            assert np.array_equal(pixels(panel.parts["step"].value), want), value


@pytest.mark.parametrize("control, other", [("solution", "ins_gps"), ("variant", "frozen"),
                                            ("biases", "GA")])
def test_a_model_change_at_the_same_time_then_a_rank_tolerance(panel, control, other):
    """The kept O(k) and figures of the previous model are not reused for the next one."""
    start = panel.controls[control].value
    panel.controls[control].value = other
    _ok(panel)
    assert panel._step[1].shape[1] == panel.model.n
    panel.controls["log10_rtol"].value += 0.25
    _ok(panel)
    panel.controls["log10_rtol"].value -= 0.25
    panel.controls[control].value = start
    _ok(panel)
    assert panel.model.n == 28
