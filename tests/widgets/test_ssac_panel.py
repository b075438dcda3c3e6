"""The SSAC panel (notebook 06) updates its kept figures in place: the image equals the
figures built anew for the same study and drawn in full in the panel's form."""

import numpy as np
import pytest
from support.images import drawn_as_kept, pixels

from navlib.plots.figure import detached
from navlib.plots.ssac import ssac_eigenvalues_figure, ssac_sigma_figure
from navlib.studies.ssac import closed_form_limits
from navlib.widgets.ssac import ssac_panel


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
        want = {"sigma": drawn_as_kept(ssac_sigma_figure(study, closed_form_limits(study)),
                                  kept[0], panel.dpi),
                "eigenvalues": drawn_as_kept(ssac_eigenvalues_figure(study), kept[1], panel.dpi)}
    for part, drawn in want.items():
        assert np.array_equal(pixels(panel.parts[part].value), drawn), part
