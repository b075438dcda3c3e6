"""Mission-plan panel: sensor preset, GNSS outage, spin rate and thresholds; redraws the
timeline of when each state becomes excitable and sensible."""

from __future__ import annotations

import ipywidgets as widgets

from navlib.metrics import nu_range
from navlib.plots.plan import timeline_figure, timeline_fits, update_timeline
from navlib.sensors import list_presets
from navlib.studies.plan import plan_mission
from navlib.widgets.base import Panel, look

__all__ = ["PlanPanel", "plan_panel"]


class PlanPanel(Panel):
    """Controls of a mission plan; ``update()`` re-plans only for what changed and gives the
    kept timeline the new bars, outages, segment starts and legend in place, its frame kept
    (:meth:`~navlib.widgets.base.KeptFigures.redrawn`).

    Attributes
    ----------
    controls : dict
        ``preset`` (dropdown of the shipped sensor presets and the plan's own, which may be
        a file), ``outage_start`` and
        ``outage_length`` (s; length 0: no outage, and the start is disabled), ``spin_hz``
        (rockets only; disabled otherwise), ``e_threshold``, ``s_threshold`` and ``nu``.
    parts : dict
        ``timeline`` (image) and ``summary`` (table).
    plan : MissionPlan
        The last successful plan.
    """

    error_prefix = "Not applied"

    def __init__(self, plan, dpi: float = 72.0):
        self.plan = plan
        mission = plan.mission
        end = float(plan.trajectory.t[-1])
        start, length = plan.outages[0] if plan.outages else (0.0, 0.0)
        if plan.outages:
            length = length - start
        rocket = mission.vehicle == "rocket"
        spin = float(mission.table.get("rocket", {}).get("spin_hz", 2.0)) if rocket else 0.0
        low, _ = nu_range(len(plan.state_names))
        th = plan.thresholds
        presets = list(dict.fromkeys([*list_presets(), plan.options["preset"]]))
        controls = {
            "preset": widgets.Dropdown(options=presets, value=plan.options["preset"],
                                       description="sensor grade", **look()),
            "outage_start": widgets.FloatSlider(value=start, min=0.0, max=end, step=1.0,
                                                description="outage start [s]",
                                                continuous_update=False, **look()),
            "outage_length": widgets.FloatSlider(value=length, min=0.0, max=end, step=1.0,
                                                 description="outage length [s]",
                                                 continuous_update=False, **look()),
            "spin_hz": widgets.FloatSlider(value=spin, min=0.0, max=5.0, step=0.25,
                                           description="spin rate [Hz]", disabled=not rocket,
                                           continuous_update=False, **look()),
            "e_threshold": widgets.FloatSlider(value=th["e_threshold"], min=0.05, max=0.99,
                                               step=0.01, description="excitable if e ≥",
                                               continuous_update=False, **look()),
            "s_threshold": widgets.FloatSlider(value=th["s_threshold"], min=0.05, max=0.99,
                                               step=0.01, description="sensible if s ≥",
                                               continuous_update=False, **look()),
            "nu": widgets.FloatSlider(value=th["nu"], min=round(low + 5e-4, 4), max=0.9995,
                                      step=0.0005, description="ν (sensability)",
                                      readout_format=".4f", continuous_update=False, **look()),
        }
        super().__init__(controls, dpi=dpi)

    def refresh(self, changed: set) -> None:
        """Re-plan (new trajectory or model) for the preset, outage and spin; re-read the
        thresholds only for the others."""
        c = {name: control.value for name, control in self.controls.items()}
        self.controls["outage_start"].disabled = c["outage_length"] <= 0
        if changed == {"outage_start"} and c["outage_length"] <= 0:
            return  # the start of no outage: nothing to re-plan or redraw
        plan = self.plan
        replanned = bool(changed & {"preset", "outage_start", "outage_length", "spin_hz"})
        if replanned:
            outages = [(c["outage_start"], c["outage_start"] + c["outage_length"])] \
                if c["outage_length"] > 0 else []
            changes = {"rocket.spin_hz": c["spin_hz"]} \
                if plan.mission.vehicle == "rocket" else None
            plan = plan_mission(plan.mission, c["preset"], changes=changes, outages=outages,
                                gnss_rate_hz=plan.options["gnss_rate_hz"],
                                gnss_sigma_m=plan.options["gnss_sigma_m"])
        plan = plan.with_settings(e_threshold=c["e_threshold"], s_threshold=c["s_threshold"],
                                  nu=c["nu"])
        self.plan = plan
        kept = self.figures.figure("timeline")
        if kept is not None and timeline_fits(kept, plan):
            update_timeline(kept, plan)
            self.show("timeline", self.figures.redrawn("timeline"))
        else:
            self.show("timeline", timeline_figure(plan))
        summary = plan.summary()
        self.show("summary", summary[["segment", "phase", "t_start", "t_end", "n_excitable",
                                      "n_sensible", "sensible"]])
        self.status.value = (f"ok: {plan.mission.name}, preset {plan.options['preset']}, "
                             f"outages {list(plan.outages) or 'none'}; sensible states per "
                             f"segment: {summary['n_sensible'].tolist()}")


def plan_panel(plan) -> PlanPanel:
    """Build the panel on a :class:`~navlib.studies.plan.MissionPlan`."""
    return PlanPanel(plan)
