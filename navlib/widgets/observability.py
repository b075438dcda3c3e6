"""Interactive panel for notebook 02: one launcher configuration's local observability.

Dropdowns for the solution, the bias set and the bias model rebuild the model
(:func:`navlib.models.launcher`) and recompute the 1 Hz rank / condition curve
(:func:`navlib.observability.local_observability`); the rank-tolerance slider re-ranks the
stored singular values (:meth:`LocalObservability.with_rtol`, no new SVDs) and re-analyses the
kept local matrix of the inspected step, giving the kept figures their new rank curve and
threshold in place while the ranks' axis range and the step's rank stay (drawn over their kept
frames, :meth:`~navlib.widgets.base.KeptFigures.redrawn`); the time slider analyses the local
matrix at that step
(:func:`navlib.observability.analyze`: singular values, unobservable groups, least observable
direction). Invalid combinations (a bias model without
biases, ...) show the NavlibInputError message instead of a figure. Figures go through the
render path of :mod:`navlib.widgets.base` (detached, PNG images).
"""

from __future__ import annotations

import html

import ipywidgets as widgets
import numpy as np

from navlib.errors import NavlibInputError
from navlib.models.launcher import (
    BIAS_MODELS,
    BIAS_SETS,
    SOLUTION_LABELS,
    SOLUTIONS,
    launcher_steps,
)
from navlib.observability import analyze, local_matrix, local_observability
from navlib.plots.observability import mission_figure, singular_values_figure
from navlib.studies.launcher import describe_direction
from navlib.widgets.base import Panel, look

__all__ = ["ObservabilityPanel", "observability_panel"]

_MODEL = ("solution", "biases", "bias_model", "variant")


class ObservabilityPanel(Panel):
    """Controls + status line + the mission curve and the inspected step.

    A change of ``solution``, ``biases``, ``bias_model`` or ``variant`` rebuilds the model
    and the curve, ``log10_rtol`` re-ranks the stored singular values, ``t`` only
    re-inspects.

    Attributes
    ----------
    controls : dict
        ``solution``, ``biases``, ``bias_model``, ``variant`` dropdowns; ``log10_rtol`` and
        ``t`` sliders.
    status : ipywidgets.HTML
    parts : dict
        ``curve`` and ``step`` images, ``step_notes`` (unobservable groups, weakest
        direction).
    model : LinearModel or None
        The model of the current configuration (None after a refused one).
    result : LocalObservability or None
        The curve at the current tolerance.
    """

    error_prefix = "Not a valid configuration"

    def __init__(self, trajectory, stride: int = 200, dpi: float = 72.0):
        self.trajectory = trajectory
        self.stride = int(stride)
        duration = float(trajectory.t[-1] - trajectory.t[0])
        controls = {
            "solution": widgets.Dropdown(options=[(SOLUTION_LABELS[s], s) for s in SOLUTIONS],
                                         value="ins_gps_att_rt", description="solution",
                                         **look("30em")),
            "biases": widgets.Dropdown(options=[(b or "none", b) for b in BIAS_SETS],
                                       value="GAP", description="biases", **look("30em")),
            "bias_model": widgets.Dropdown(options=list(BIAS_MODELS), value="random_walk",
                                           description="bias model", **look("30em")),
            "variant": widgets.Dropdown(options=["time_varying", "frozen"],
                                        description="eq. (6) reading", **look("30em")),
            "log10_rtol": widgets.FloatSlider(value=np.log10(28 * 12 * np.finfo(float).eps),
                                              min=-18.0, max=-2.0, step=0.25,
                                              description="log10 rank rtol",
                                              continuous_update=False, **look("30em")),
            "t": widgets.FloatSlider(value=round(duration / 2), min=0.0,
                                     max=max(duration - 1.0, 0.0), step=1.0,
                                     description="inspected time [s]",
                                     continuous_update=False, **look("30em")),
        }
        self.model = None
        self._raw = None
        self.result = None
        self._kept_curve = False  # whether the kept curve figure is this model's
        self._step = None     # (step, O(k), analysis) of the kept spectrum
        super().__init__(controls, dpi=dpi)

    @property
    def rtol(self) -> float:
        return float(10.0 ** self.controls["log10_rtol"].value)

    def refresh(self, changed: set) -> None:
        """Rebuild, re-rank and/or re-inspect, as the changed controls require."""
        if changed & set(_MODEL):
            self.rebuild(rebuild_model=bool(changed & set(_MODEL[:3])))
        if self.model is None:
            return  # a refused configuration stays on show until a model control changes
        if changed & set(_MODEL):  # another model or reading: another curve and O(k)
            self._kept_curve, self._step = False, None
        if changed & {*_MODEL, "log10_rtol"}:
            self.rerank()
        self.inspect()

    def rebuild(self, rebuild_model: bool = True) -> None:
        """New configuration: build the model (unless only the eq. (6) reading changed
        and a model is kept) and the 1 Hz curve (a refused one clears the figures and raises
        its NavlibInputError)."""
        c = self.controls
        try:
            if rebuild_model or self.model is None:
                # Euler steps computed for the evaluated windows only (as Table 2)
                self.model = launcher_steps(c["solution"].value, c["biases"].value,
                                            c["bias_model"].value, trajectory=self.trajectory)
            self._raw = local_observability(self.model, variant=c["variant"].value,
                                            stride=self.stride)
        except NavlibInputError:
            self.model = self._raw = self.result = None
            for name in ("curve", "step", "step_notes"):
                self.show(name, None)
            raise

    def rerank(self) -> None:
        """Apply the rank tolerance to the stored singular values and redraw the curve."""
        self.result = self._raw.with_rtol(self.rtol)
        r = self.result
        self.status.value = (
            f"{self.model.name}: n = {r.n}, rank {r.rank.min()}–{r.rank.max()} "
            f"({r.n_unobservable} unobservable), max log10 cond {r.log10_max_cond:.1f}, "
            f"{r.step.size} evaluations")
        kept = self.figures.figure("curve") if self._kept_curve else None
        if kept is not None and kept.axes[0].get_ylim() == (min(r.rank.min(), r.n) - 1.5,
                                                             r.n + 1.5):
            kept.axes[0].lines[0].set_ydata(r.rank)
            self.show("curve", self.figures.redrawn("curve"))
            return
        self.show("curve", mission_figure(
            r, self.trajectory.events,
            title=f"{self.model.name}; eq. (6) {self.controls['variant'].value}"))
        self._kept_curve = True

    def inspect(self) -> None:
        """Analyse O(k) at the inspected time: singular values, groups, weakest direction."""
        k = int(np.searchsorted(self.trajectory.t, self.controls["t"].value))
        k = min(k, int(self._raw.step[-1]))
        kept = self._step if self._step is not None and self._step[0] == k else None
        O = local_matrix(self.model, k, variant=self.controls["variant"].value) \
            if kept is None else kept[1]
        a = analyze(O, rtol=self.rtol, state_names=self.model.state_names,
                    coupling_threshold="auto")
        weakest = describe_direction(a.weakest_direction, self.model.state_names,
                                     self.trajectory.attitude[k].as_matrix())
        fig = self.figures.figure("step")
        if kept is not None and fig is not None and kept[2].rank == a.rank \
                and _threshold_in_view(fig, a):
            _move_threshold(fig, a)
            self.show("step", self.figures.redrawn("step"))
        else:
            self.show("step", singular_values_figure(
                a, title=f"t = {self.trajectory.t[k]:.2f} s "
                         f"({self.controls['variant'].value}): rank {a.rank}/{a.n}, "
                         f"cond {a.cond:.2e}"))
            self._step = (k, O, a)
        groups = "; ".join("{" + ", ".join(g) + "}" for g in a.unobservable_groups)
        self.show("step_notes", f"<b>unobservable groups:</b> {html.escape(groups or 'none')}"
                                f"<br><b>least observable direction:</b> "
                                f"{html.escape(weakest)}")


def _threshold_in_view(fig, analysis) -> bool:
    """Whether the rank threshold ``log10(rtol sigma_1)`` lies inside the kept spectrum's
    y range (else the figure is rebuilt and rescaled)."""
    low, high = fig.axes[0].get_ylim()
    return bool(low < np.log10(analysis.rtol * analysis.singular_values[0]) < high)


def _move_threshold(fig, analysis) -> None:
    """Put the kept spectrum's threshold line and its legend label at the new rtol (the
    rank, hence bars and title, unchanged), as :func:`singular_values_figure` draws them."""
    ax = fig.axes[0]
    line, legend = ax.lines[0], ax.get_legend()
    line.set_ydata([np.log10(analysis.rtol * analysis.singular_values[0])] * 2)
    label = f"rtol × σ1 (rtol {analysis.rtol:.1e})"
    for text in legend.get_texts():
        if text.get_text() == line.get_label():
            text.set_text(label)
    line.set_label(label)


def observability_panel(trajectory, stride: int = 200) -> ObservabilityPanel:
    """Build the panel for a launcher trajectory; ``stride`` steps between evaluations
    (200 = 1 Hz on the 200 Hz ascent)."""
    return ObservabilityPanel(trajectory, stride=stride)
