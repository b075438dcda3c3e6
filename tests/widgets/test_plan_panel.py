"""The plan panel (navlib.widgets.plan): thresholds and re-plans give the kept timeline
new data in place, the same picture as the timeline drawn in full."""

import numpy as np
from support.images import drawn_as_kept, pixels

from navlib.plots.figure import detached
from navlib.plots.plan import timeline_figure
from navlib.studies.plan import plan_mission
from navlib.widgets.plan import plan_panel


def test_every_move_shows_the_timeline_drawn_in_full():
    with detached():
        panel = plan_panel(plan_mission("sounding_rocket"))
        kept = panel.figures.figure("timeline")
        moves = [("e_threshold", 0.5), ("s_threshold", 0.3), ("nu", 0.99),
                 ("spin_hz", panel.controls["spin_hz"].value + 0.25), ("outage_length", 20.0),
                 ("outage_start", 30.0), ("preset", "pixhawk_mems"), ("outage_length", 0.0)]
        for name, value in moves:
            before = panel.parts["timeline"].value
            panel.controls[name].value = value
            assert "ok:" in panel.status.value, name
            assert panel.figures.figure("timeline") is kept  # new data, same figure
            want = drawn_as_kept(timeline_figure(panel.plan), kept, panel.dpi)
            assert np.array_equal(pixels(panel.parts["timeline"].value), want), name
            assert panel.parts["timeline"].value != before, name
        assert "GNSS outage" not in [t.get_text() for t in kept.axes[0].get_legend().get_texts()]
