"""Interactive panel for notebook 02: one launcher configuration's local observability.

Dropdowns for the solution, the bias set and the bias model rebuild the model
(:func:`navlib.models.launcher`) and recompute the 1 Hz rank / condition curve
(:func:`navlib.observability.local_observability`); the rank-tolerance slider re-ranks the
stored singular values (:meth:`LocalObservability.with_rtol`, no new SVDs); the time slider
analyses the local matrix at that step (:func:`navlib.observability.analyze`: singular values,
unobservable groups, least observable direction). Invalid combinations (a bias model without
biases, ...) show the NavlibInputError message instead of a figure.
"""

from __future__ import annotations

import ipywidgets as widgets
import matplotlib.pyplot as plt
import numpy as np
from IPython.display import display

from navlib.errors import NavlibInputError
from navlib.models.launcher import BIAS_MODELS, BIAS_SETS, SOLUTIONS, launcher
from navlib.observability import analyze, local_matrix, local_observability
from navlib.plots.observability import mission_figure, singular_values_figure
from navlib.studies.launcher import SOLUTION_LABELS, describe_direction


class ObservabilityPanel(widgets.VBox):
    """Controls + status line + two output areas (mission curve, inspected step).

    Attributes
    ----------
    controls : dict
        ``solution``, ``biases``, ``bias_model``, ``variant`` dropdowns; ``log10_rtol`` and
        ``t`` sliders.
    status : ipywidgets.HTML
    curve_output, step_output : ipywidgets.Output
    model : LinearModel or None
        The model of the current configuration.
    result : LocalObservability or None
        The curve at the current tolerance.
    """

    def __init__(self, trajectory, stride: int = 200):
        self.trajectory = trajectory
        self.stride = int(stride)
        look = dict(style={"description_width": "9em"}, layout=widgets.Layout(width="30em"))
        duration = float(trajectory.t[-1] - trajectory.t[0])
        self.controls = {
            "solution": widgets.Dropdown(options=[(SOLUTION_LABELS[s], s) for s in SOLUTIONS],
                                         value="ins_gps_att_rt", description="solution",
                                         **look),
            "biases": widgets.Dropdown(options=[(b or "none", b) for b in BIAS_SETS],
                                       value="GAP", description="biases", **look),
            "bias_model": widgets.Dropdown(options=list(BIAS_MODELS), value="random_walk",
                                           description="bias model", **look),
            "variant": widgets.Dropdown(options=["time_varying", "frozen"],
                                        description="eq. (6) reading", **look),
            "log10_rtol": widgets.FloatSlider(value=np.log10(28 * 12 * np.finfo(float).eps),
                                              min=-18.0, max=-2.0, step=0.25,
                                              description="log10 rank rtol",
                                              continuous_update=False, **look),
            "t": widgets.FloatSlider(value=round(duration / 2), min=0.0,
                                     max=max(duration - 1.0, 0.0), step=1.0,
                                     description="inspected time [s]",
                                     continuous_update=False, **look),
        }
        self.status = widgets.HTML()
        self.curve_output = widgets.Output()
        self.step_output = widgets.Output()
        self.model = None
        self._raw = None
        self.result = None
        for name in ("solution", "biases", "bias_model", "variant"):
            self.controls[name].observe(lambda _c: self.rebuild(), names="value")
        self.controls["log10_rtol"].observe(lambda _c: self.rerank(), names="value")
        self.controls["t"].observe(lambda _c: self.inspect(), names="value")
        super().__init__([widgets.VBox(list(self.controls.values())), self.status,
                          self.curve_output, self.step_output])
        self.rebuild()

    @property
    def rtol(self) -> float:
        return float(10.0 ** self.controls["log10_rtol"].value)

    def rebuild(self) -> None:
        """New configuration: build the model and the 1 Hz curve (errors go to ``status``)."""
        c = self.controls
        try:
            self.model = launcher(c["solution"].value, c["biases"].value,
                                  c["bias_model"].value, trajectory=self.trajectory)
            self._raw = local_observability(self.model, variant=c["variant"].value,
                                            stride=self.stride)
        except NavlibInputError as exc:
            self.model = self._raw = self.result = None
            self.status.value = f'<b style="color:#b00">Not a valid configuration:</b> {exc}'
            for out in (self.curve_output, self.step_output):
                out.clear_output()
            return
        self.rerank()

    def rerank(self) -> None:
        """Apply the rank tolerance to the stored singular values and redraw the curve."""
        if self._raw is None:
            return
        self.result = self._raw.with_rtol(self.rtol)
        r = self.result
        self.status.value = (
            f"{self.model.name}: n = {r.n}, rank {r.rank.min()}–{r.rank.max()} "
            f"({r.n_unobservable} unobservable), max log10 cond {r.log10_max_cond:.1f}, "
            f"{r.step.size} evaluations")
        with self.curve_output:
            self.curve_output.clear_output(wait=True)
            fig = mission_figure(r, self.trajectory.events, title=self.model.name)
            display(fig)
            plt.close(fig)
        self.inspect()

    def inspect(self) -> None:
        """Analyse O(k) at the inspected time: singular values, groups, weakest direction."""
        if self.model is None:
            return
        k = int(np.searchsorted(self.trajectory.t, self.controls["t"].value))
        k = min(k, int(self._raw.step[-1]))
        O = local_matrix(self.model, k, variant=self.controls["variant"].value)
        a = analyze(O, rtol=self.rtol, state_names=self.model.state_names,
                    coupling_threshold="auto")
        weakest = describe_direction(a.weakest_direction, self.model.state_names,
                                     self.trajectory.attitude[k].as_matrix())
        with self.step_output:
            self.step_output.clear_output(wait=True)
            fig = singular_values_figure(a, title=f"t = {self.trajectory.t[k]:.2f} s: rank "
                                         f"{a.rank}/{a.n}, cond {a.cond:.2e}")
            display(fig)
            plt.close(fig)
            groups = "; ".join("{" + ", ".join(g) + "}" for g in a.unobservable_groups)
            display(widgets.HTML(f"<b>unobservable groups:</b> {groups or 'none'}<br>"
                                 f"<b>least observable direction:</b> {weakest}"))


def observability_panel(trajectory, stride: int = 200) -> ObservabilityPanel:
    """Build the panel for a launcher trajectory; ``stride`` steps between evaluations
    (200 = 1 Hz on the 200 Hz ascent)."""
    return ObservabilityPanel(trajectory, stride=stride)
