"""Interactive panel for notebook 07: edit the segments and thresholds of a flight assessment.

The panel never refits or rediscretises: it calls
:meth:`navlib.studies.assess.FlightAssessment.with_settings` (excitability per segment, a
new ``nu`` on the stored information eigen-decompositions) and redraws the excitability
bars and spectrum and the sensability of a chosen state group (builders of
:mod:`navlib.plots.metrics`), the segments over the fitted IMU and the summary table.
Segment limits are typed as boundary times (``18, 46``: cuts inside the flight); "auto"
restores the automatic segmentation. Bad input shows its NavlibInputError in the panel.

Each figure is kept and redrawn by Agg blitting (:class:`navlib.widgets.base.Blitter`), only
when a control it depends on changed: eta redraws the excitability bars and spectrum in
place, nu the sensability curves, new boundaries the segment shading of the phases and
sensability figures (and the excitability figure, rebuilt when the number of segments
changes); the state group puts its states on the sensability figure in place and lays it out
again (:func:`navlib.plots.metrics.restate_sensability`).
"""

from __future__ import annotations

import ipywidgets as widgets

from navlib.errors import NavlibInputError
from navlib.metrics import nu_range
from navlib.models.ecef import STATE_GROUPS
from navlib.plots.assess import phases_figure, reshade_phases
from navlib.plots.metrics import (
    excitability_dynamic_artists,
    excitability_figure,
    reshade_segments,
    restate_sensability,
    sensability_figure,
)
from navlib.widgets.base import Blitter, Panel, look

__all__ = ["AssessPanel", "assess_panel", "boundaries_text", "parse_boundaries"]


def parse_boundaries(text: str):
    """``"18, 46.5"`` -> ``[18.0, 46.5]``; ``"auto"`` or blank -> ``"auto"``."""
    text = text.strip()
    if not text or text.lower() == "auto":
        return "auto"
    try:
        return [float(part) for part in text.replace(";", ",").split(",") if part.strip()]
    except ValueError as exc:
        raise NavlibInputError(f"segments: expected boundary times in s separated by commas, "
                               f"or 'auto'; got {text!r}") from exc


def boundaries_text(assessment) -> str:
    """The inner boundaries of an assessment's segments, as the panel's text shows them."""
    return ", ".join(f"{b:g}" for _, b in assessment.segments[:-1])


class AssessPanel(Panel):
    """Segment boundaries, eta, nu and a state group; ``update()`` re-evaluates and redraws.

    Attributes
    ----------
    controls : dict
        ``boundaries`` (text), ``eta`` (log slider), ``nu`` (slider inside the admissible
        range of docs/assumptions.md A11), ``group`` (dropdown of the 21-state groups).
    status : ipywidgets.HTML
    parts : dict
        ``phases``, ``excitability``, ``sensability`` (images) and ``summary`` (table).
    assessment : FlightAssessment
        The last successful re-evaluation.
    """

    error_prefix = "Not applied"

    def __init__(self, assessment, dpi: float = 72.0):
        self.base = assessment
        self.assessment = assessment
        low, _ = nu_range(len(assessment.state_names))
        th = assessment.thresholds
        controls = {
            "boundaries": widgets.Text(value=boundaries_text(assessment),
                                       description="boundaries [s]",
                                       continuous_update=False, **look()),
            "eta": widgets.FloatLogSlider(value=th["eta"], base=10, min=-8, max=-0.5, step=0.25,
                                          description="η (excitability)",
                                          continuous_update=False, readout_format=".1e",
                                          **look()),
            "nu": widgets.FloatSlider(value=th["nu"], min=round(low + 5e-4, 4), max=0.9995,
                                      step=0.0005, description="ν (sensability)",
                                      readout_format=".4f", continuous_update=False, **look()),
            "group": widgets.Dropdown(options=list(STATE_GROUPS), value="attitude",
                                      description="sensability of", **look()),
        }
        self._figures: dict = {}   # name -> Blitter
        self._sens_lines: list = []
        super().__init__(controls, dpi=dpi)

    def refresh(self, changed: set) -> None:
        """Re-evaluate with the current controls and redraw the figures ``changed`` touches."""
        c = self.controls
        segments = parse_boundaries(c["boundaries"].value) if "boundaries" in changed \
            else None
        if segments is None and not changed & {"eta", "nu"}:
            result = self.assessment
        else:
            source = self.base if segments is not None else self.assessment
            result = source.with_settings(segments, eta=c["eta"].value, nu=c["nu"].value)
        new_segments = result.segments != self.assessment.segments or not self._figures
        self.assessment = result
        self._draw_phases(result, new_segments)
        if new_segments or "eta" in changed:
            self._draw_excitability(result)
        if new_segments or changed & {"nu", "group"}:
            self._draw_sensability(result, "group" in changed, new_segments)
        summary = result.summary()
        self.show("summary", summary)
        self.status.value = (f"ok: {len(summary)} segment(s); excitable states per segment: "
                             f"{summary['n_excitable'].tolist()}, sensible: "
                             f"{summary['n_sensible'].tolist()}")

    def _draw_phases(self, result, new_segments: bool) -> None:
        blitter = self._figures.get("phases")
        if blitter is None:
            fig = phases_figure(result)
            blitter = Blitter(fig, reshade_phases(fig, result), self.dpi)
        elif new_segments:
            blitter.set_dynamic(reshade_phases(blitter.fig, result), redraw_background=False)
        else:
            return
        self._figures["phases"] = blitter
        self.show("phases", blitter)

    def _draw_excitability(self, result) -> None:
        blitter = self._figures.get("excitability")
        fig = excitability_figure(result, None if blitter is None else blitter.fig)
        if blitter is None or fig is not blitter.fig \
                or excitability_dynamic_artists(fig) != blitter.dynamic:
            blitter = Blitter(fig, excitability_dynamic_artists(fig), self.dpi)
        self._figures["excitability"] = blitter
        self.show("excitability", blitter)

    def _draw_sensability(self, result, new_group: bool, new_segments: bool) -> None:
        blitter = self._figures.get("sensability")
        states = list(STATE_GROUPS[self.controls["group"].value])
        if blitter is None:
            fig = sensability_figure(result, states,
                                     title="Sensability (ν on the slider) and ±2σ bands")
            self._sens_lines = [ln for ax in fig.axes for ln in ax.get_lines()
                                if ln.get_label() == "sensability"]
            blitter = Blitter(fig, [*reshade_segments(fig, result), *self._sens_lines],
                              self.dpi)
        elif new_group or new_segments:
            shading = reshade_segments(blitter.fig, result)
            if new_group:     # other labels and units: laid out again, not rebuilt
                self._sens_lines = restate_sensability(blitter.fig, result, states)
                blitter.relayout([*shading, *self._sens_lines],
                                 key=self.controls["group"].value)
            else:
                blitter.set_dynamic([*shading, *self._sens_lines], redraw_background=False)
        se = result.sensability
        for line, state in zip(self._sens_lines, states, strict=True):
            line.set_ydata(se.s[:, result.state_names.index(state)])
        self._figures["sensability"] = blitter
        self.show("sensability", blitter)


def assess_panel(assessment) -> AssessPanel:
    """Build the panel on a :class:`~navlib.studies.assess.FlightAssessment`."""
    return AssessPanel(assessment)
