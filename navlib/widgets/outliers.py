"""Interactive panels for notebook 05: outlier injection and a Monte-Carlo run.

:class:`OutlierPanel` — dropdowns/sliders for the channel, time, magnitude, shape (and pulse
duration), solution and watched quantity call :func:`navlib.studies.outliers.outlier_response`
and redraw the response, the induced error and the recovery score.

:class:`MonteCarloPanel` — runs :func:`navlib.studies.outliers.monte_carlo_outlier` for the
panel's current outlier with a progress bar (``ipywidgets.IntProgress``) and draws the error
band and the NEES/NIS consistency.

Both share one :class:`navlib.studies.outliers.FilterCache`, so only a change of solution
recomputes the covariance. Figures go through the render path of :mod:`navlib.widgets.base`
(detached, PNG images).
"""

from __future__ import annotations

import ipywidgets as widgets
import pandas as pd

from navlib.filters.recovery import scores_frame
from navlib.models.launcher import SOLUTIONS
from navlib.plots.outliers import induced_figure, monte_carlo_figure, response_figure
from navlib.sensors.faults import CHANNELS, KINDS, Outlier
from navlib.studies.outliers import (
    WATCHES,
    FilterCache,
    default_trajectory,
    monte_carlo_outlier,
    outlier_response,
    record_stride,
)
from navlib.widgets.base import Panel, look

__all__ = ["MonteCarloPanel", "OutlierPanel"]


class OutlierPanel(Panel):
    """Controls + status + figures; ``update()`` reruns the outlier response and redraws.

    Attributes
    ----------
    controls : dict
        ``solution``, ``channel``, ``watch``, ``time``, ``magnitude``, ``shape``,
        ``duration``, ``window`` widgets (``duration`` enabled for a pulse only).
    parts : dict
        ``response`` and ``induced`` images (the latter hidden when the channel is absent
        from the solution) and the ``scores`` table.
    response : OutlierResponse or None
        The last response computed.
    cache : FilterCache
    """

    def __init__(self, trajectory=None, *, cache: FilterCache | None = None,
                 biases: str = "GAP", bias_model: str = "markov", dpi: float = 72.0,
                 **model_options):
        self.cache = cache or FilterCache(trajectory if trajectory is not None
                                          else default_trajectory(), size=1, **model_options)
        traj = self.cache.trajectory
        t0, t1 = float(traj.t[0]), float(traj.t[-1])
        slider = dict(continuous_update=False, **look("28em"))
        controls = {
            "solution": widgets.Dropdown(options=list(SOLUTIONS), value="ins_gps_rt",
                                         description="solution", **look("28em")),
            "channel": widgets.Dropdown(options=list(KINDS) + list(CHANNELS), value="gyro_x",
                                        description="channel", **look("28em")),
            "watch": widgets.Dropdown(options=list(WATCHES), value="roll",
                                      description="watched", **look("28em")),
            "time": widgets.FloatSlider(value=min(50.0, 0.5 * (t0 + t1)), min=t0 + 1.0,
                                        max=t1 - 2.0, step=0.5, description="time [s]",
                                        **slider),
            "magnitude": widgets.FloatText(value=0.002, description="magnitude [SI]",
                                           **look("28em")),
            "shape": widgets.Dropdown(options=["spike", "step", "pulse"], value="spike",
                                      description="shape", **look("28em")),
            "duration": widgets.FloatSlider(value=1.0, min=0.05, max=20.0, step=0.05,
                                            description="pulse [s]", **slider),
            "window": widgets.FloatSlider(value=min(100.0, t1 - 51.0), min=1.0,
                                          max=max(2.0, t1 - t0), step=1.0,
                                          description="window [s]", **slider),
        }
        self.settings = {"biases": biases, "bias_model": bias_model}
        self.response = None
        super().__init__(controls, dpi=dpi)

    def outlier(self) -> Outlier:
        """The outlier described by the controls."""
        c = self.controls
        shape = c["shape"].value
        return Outlier(c["channel"].value, c["time"].value, c["magnitude"].value, shape,
                       c["duration"].value if shape == "pulse" else None)

    def refresh(self, changed: set) -> None:
        """Recompute the response for the current controls and redraw."""
        c = self.controls
        c["duration"].disabled = c["shape"].value != "pulse"
        outlier = self.outlier()
        resp = outlier_response(c["solution"].value, outlier, c["watch"].value,
                                window=c["window"].value, cache=self.cache,
                                record_every=record_stride(self.cache.trajectory),
                                **self.settings)
        self.response = resp
        s = resp.score
        applied = "" if resp.applied else " (channel absent in this solution: no effect)"
        self.status.value = (f"{outlier.label()}: <b>{s.verdict}</b>{applied}; retained "
                             f"{s.retained:.3g}, tau {s.time_constant:.3g} s")
        self.show("response", response_figure([resp]))
        self.show("induced", induced_figure([resp]) if resp.applied else None)
        self.show("scores", scores_frame({resp.solution: s}))


class MonteCarloPanel(Panel):
    """Runs slider, seed, a Run button and a progress bar for :func:`monte_carlo_outlier`.

    The outlier, solution and watched quantity come from an :class:`OutlierPanel`; nothing
    runs until the button is pressed (the runs slider and seed are read then).

    Attributes
    ----------
    parts : dict
        ``band`` image and ``consistency`` table of the last run.
    result : MonteCarloResult or None
    """

    def __init__(self, outlier_panel: OutlierPanel, runs: int = 50, dpi: float = 72.0):
        self.source = outlier_panel
        self.runs = widgets.IntSlider(value=runs, min=2, max=500, step=2, description="runs",
                                      continuous_update=False, **look("28em"))
        self.seed = widgets.IntText(value=0, description="seed", **look("28em"))
        self.button = widgets.Button(description="Run Monte Carlo")
        self.progress = widgets.IntProgress(value=0, min=0, max=100, description="progress")
        self.result = None
        self.button.on_click(lambda _b: self.update(("run",)))
        super().__init__({}, extras=[self.runs, self.seed, self.button, self.progress],
                         dpi=dpi, update_now=False)
        self.add_class("navlib-panel-manual")

    def _progress(self, done: int, total: int) -> None:
        self.progress.value = int(100 * done / max(total, 1))

    def run(self) -> bool:
        """Run the Monte Carlo for the outlier panel's current settings and redraw
        (what pressing the button does); True when it ran."""
        return self.update(("run",))

    def refresh(self, changed: set) -> None:
        """Run the Monte Carlo and redraw."""
        src = self.source
        c = src.controls
        outlier = src.outlier()
        self.progress.value = 0
        self.status.value = "running ..."
        mc = monte_carlo_outlier(c["solution"].value, outlier, c["watch"].value,
                                 runs=self.runs.value, seed=self.seed.value,
                                 window=c["window"].value, cache=src.cache,
                                 progress=self._progress, **src.settings)
        self.result = mc
        self.progress.value = 100
        self.status.value = (f"{self.runs.value} runs: {mc.score.verdict}; NEES/NIS inside "
                             f"95 % bounds (nominal runs) {mc.nominal_consistency['nees']:.0%}"
                             f" / {mc.nominal_consistency['nis']:.0%}")
        self.show("band", monte_carlo_figure(mc, c["watch"].value))
        self.show("consistency", pd.DataFrame([{"case": "with outlier", **mc.consistency},
                                               {"case": "nominal",
                                                **mc.nominal_consistency}]))
