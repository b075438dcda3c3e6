"""Notebook 02's panel (navlib.widgets.observability): each control recomputes only what it
touches, and the rank-tolerance slider's blitted redraw shows the new tolerance."""

import numpy as np
import pytest

from navlib.plots.figure import detached
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
