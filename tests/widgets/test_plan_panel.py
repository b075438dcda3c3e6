"""The plan panel's thresholds (navlib.widgets.plan): redrawn by blitting on the kept
timeline, the same picture as the timeline drawn in full."""

from io import BytesIO

import numpy as np
from PIL import Image

from navlib.plots.figure import detached
from navlib.plots.plan import timeline_figure
from navlib.studies.plan import plan_mission
from navlib.widgets.base import render_png
from navlib.widgets.plan import plan_panel


def _pixels(png: bytes) -> np.ndarray:
    return np.asarray(Image.open(BytesIO(png)).convert("RGB")).astype(int)


def test_threshold_redraw_equals_the_full_timeline():
    with detached():
        panel = plan_panel(plan_mission("sounding_rocket"))
        for name, value in (("e_threshold", 0.5), ("s_threshold", 0.3), ("nu", 0.99)):
            before = panel.parts["timeline"].value
            panel.controls[name].value = value
            assert "ok:" in panel.status.value
            kept = panel.figures.figure("timeline")
            full = timeline_figure(panel.plan)
            full.set_layout_engine("none")
            full.axes[0].set_position(kept.axes[0].get_position())
            full._suptitle.set_position(kept._suptitle.get_position())
            want = _pixels(render_png(full, panel.dpi))
            got = _pixels(panel.parts["timeline"].value)
            assert got.shape == want.shape
            # a few antialiased edge pixels (5e-5 of the image) where the redrawn bars meet
            # the kept background
            assert np.mean(np.any(got != want, axis=-1)) < 2e-4, name
            assert panel.parts["timeline"].value != before
        panel.controls["spin_hz"].value = panel.controls["spin_hz"].value + 0.25  # re-plan
        assert "ok:" in panel.status.value
        panel.controls["e_threshold"].value = 0.6
        assert "ok:" in panel.status.value
