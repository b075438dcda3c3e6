"""Interactive panel for notebook 07: edit the segments and thresholds of a flight assessment.

The panel never refits or rediscretises: it calls
:meth:`navlib.studies.assess.FlightAssessment.with_settings` (excitability per segment, a
new ``nu`` on the stored information eigen-decompositions) and redraws the excitability
bars and spectrum and the sensability of a chosen state group (builders of
:mod:`navlib.plots.metrics`), the segments over the fitted IMU and the summary table.
Segment limits are typed as boundary times (``18, 46``: cuts inside the flight); "auto"
restores the automatic segmentation. Bad input shows its NavlibInputError in the panel.
"""

from __future__ import annotations

import ipywidgets as widgets
import matplotlib.pyplot as plt
from IPython.display import display

from navlib.errors import NavlibInputError
from navlib.metrics import nu_range
from navlib.models.ecef import STATE_GROUPS
from navlib.plots.assess import phases_figure
from navlib.plots.metrics import excitability_figure, sensability_figure


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


class AssessPanel(widgets.VBox):
    """Segment boundaries, eta, nu and a state group; ``update()`` re-evaluates and redraws.

    Attributes
    ----------
    controls : dict
        ``boundaries`` (text), ``eta`` (log slider), ``nu`` (slider inside the admissible
        range of spec A11), ``group`` (dropdown of the 21-state groups).
    status : ipywidgets.HTML
    output : ipywidgets.Output
    assessment : FlightAssessment
        The last successful re-evaluation.
    """

    def __init__(self, assessment):
        self.base = assessment
        self.assessment = assessment
        look = dict(style={"description_width": "9em"}, layout=widgets.Layout(width="34em"))
        low, _ = nu_range(len(assessment.state_names))
        th = assessment.thresholds
        self.controls = {
            "boundaries": widgets.Text(value=boundaries_text(assessment),
                                       description="boundaries [s]",
                                       continuous_update=False, **look),
            "eta": widgets.FloatLogSlider(value=th["eta"], base=10, min=-8, max=-0.5, step=0.25,
                                          description="η (excitability)",
                                          continuous_update=False, readout_format=".1e",
                                          **look),
            "nu": widgets.FloatSlider(value=th["nu"], min=round(low + 5e-4, 4), max=0.9995,
                                      step=0.0005, description="ν (sensability)",
                                      readout_format=".4f", continuous_update=False, **look),
            "group": widgets.Dropdown(options=list(STATE_GROUPS), value="attitude",
                                      description="sensability of", **look),
        }
        self.status = widgets.HTML()
        self.output = widgets.Output()
        for control in self.controls.values():
            control.observe(lambda _change: self.update(), names="value")
        super().__init__([widgets.VBox(list(self.controls.values())), self.status,
                          self.output])
        self.update()

    def update(self) -> None:
        """Re-evaluate with the current controls and redraw (errors go to ``status``)."""
        c = self.controls
        try:
            segments = parse_boundaries(c["boundaries"].value)
            result = self.base.with_settings(segments, eta=c["eta"].value, nu=c["nu"].value)
        except NavlibInputError as exc:
            self.status.value = f'<b style="color:#b00">Not applied:</b> {exc}'
            return
        self.assessment = result
        summary = result.summary()
        self.status.value = (f"ok: {len(summary)} segment(s); excitable states per segment: "
                             f"{summary['n_excitable'].tolist()}, sensible: "
                             f"{summary['n_sensible'].tolist()}")
        states = list(STATE_GROUPS[c["group"].value])
        with self.output:
            self.output.clear_output(wait=True)
            for fig in (phases_figure(result), excitability_figure(result),
                        sensability_figure(result, states)):
                display(fig)
                plt.close(fig)
            display(summary)


def assess_panel(assessment) -> AssessPanel:
    """Build the panel on a :class:`~navlib.studies.assess.FlightAssessment`."""
    return AssessPanel(assessment)
