"""The SSAC panel (notebook 06) updates its kept figures in place: the image equals the
figures built anew for the same study and drawn in full in the panel's form."""

import numpy as np
import pytest
from support.images import pixels

from navlib.plots.figure import detached
from navlib.plots.ssac import ssac_eigenvalues_figure, ssac_sigma_figure
from navlib.studies.ssac import closed_form_limits
from navlib.widgets.base import render_png
from navlib.widgets.layers import snap_limits
from navlib.widgets.ssac import ssac_panel


def _as_kept(fig, kept, dpi: float) -> np.ndarray:
    """``fig`` in the layout of ``kept``, limits snapped, legends where ``kept`` has them."""
    fig.set_layout_engine("none")
    for ax, old in zip(fig.axes, kept.axes, strict=True):
        ax.set_position(old.get_position())
        ax.title.set_position(old.title.get_position())
        ax.xaxis.label.set_transform(old.xaxis.label.get_transform())
        ax.xaxis.label.set_position(old.xaxis.label.get_position())
        ax.xaxis._autolabelpos, ax._autotitlepos = False, False
        if ax.get_legend() is not None:
            ax.get_legend().set_loc(old.get_legend()._get_loc())
    if fig._suptitle is not None:
        fig._suptitle.set_position(kept._suptitle.get_position())
    snap_limits(fig)  # with the ticks of the kept layout
    return pixels(render_png(fig, dpi))


@pytest.mark.parametrize(("control", "value"), [("lat_deg", 40.0), ("duration_min", 7.0),
                                                ("attitude_scale", 10.0), ("P0", "generic")])
def test_moved_control_shows_the_new_study_as_new_figures_would(control, value):
    with detached():
        panel = ssac_panel(duration_min=5.0)
        kept = panel.figures.figure("sigma"), panel.figures.figure("eigenvalues")
        panel.controls[control].value = value
        assert "ok:" in panel.status.value
        assert (panel.figures.figure("sigma"), panel.figures.figure("eigenvalues")) == kept
        study = panel.study
        want = {"sigma": _as_kept(ssac_sigma_figure(study, closed_form_limits(study)),
                                  kept[0], panel.dpi),
                "eigenvalues": _as_kept(ssac_eigenvalues_figure(study), kept[1], panel.dpi)}
    for part, drawn in want.items():
        assert np.array_equal(pixels(panel.parts[part].value), drawn), part
