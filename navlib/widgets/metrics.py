"""Interactive panels for notebooks 03 (excitability) and 04 (sensability).

Both panels call :mod:`navlib.studies.rocket` and the figure builders of
:mod:`navlib.plots.metrics`, and recompute only what a change touches:

* the discretised 21-state model is cached per attitude-error frame
  (:func:`navlib.studies.rocket.rocket_chain`);
* a new eta reuses the segment SVDs (``with_eta``), new segment limits or D0 redo only the
  three small SVDs, a new nu reuses the eigen-decompositions (``with_nu``);
* the figure is kept and redrawn in place, rendered once to PNG per update.

``last_timing`` holds the milliseconds spent computing and rendering in the last update.
"""

from __future__ import annotations

import io
import time
from dataclasses import replace

import ipywidgets as widgets
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg

from navlib import metrics
from navlib.errors import NavlibInputError
from navlib.models.ecef import ATTITUDE_ERRORS, STATE_NAMES
from navlib.plots.metrics import excitability_figure, sensability_figure
from navlib.studies import rocket

_LOOK = dict(style={"description_width": "9em"}, layout=widgets.Layout(width="34em"))


def _png(fig, dpi: float) -> bytes:
    """One Agg draw of ``fig`` at ``dpi``, encoded to PNG (savefig would draw twice)."""
    from PIL import Image

    if fig.dpi != dpi:
        fig.set_dpi(dpi)
    canvas = FigureCanvasAgg(fig) if not isinstance(fig.canvas, FigureCanvasAgg) \
        else fig.canvas
    canvas.draw()
    buffer = io.BytesIO()
    Image.fromarray(np.asarray(canvas.buffer_rgba())).save(buffer, format="png",
                                                           compress_level=1)
    return buffer.getvalue()


def _freeze_layout(fig) -> None:
    """After the first render keep the axes where the constrained layout put them."""
    if fig.get_layout_engine() is not None:
        fig.set_layout_engine("none")


def _claims_html(table) -> str:
    colour = {"reproduced": "#1a7f37", "partly": "#9a6700", "not reproduced": "#cf222e"}
    rows = "".join(
        f"<tr><td><b>{r.claim_id}</b></td><td style='color:{colour.get(r.verdict, '#000')}'>"
        f"{r.verdict}</td><td style='text-align:left'>{r.ours}</td></tr>"
        for r in table.itertuples())
    return (f"<table style='font-size:11px'><tr><th>claim</th><th>verdict</th>"
            f"<th>ours</th></tr>{rows}</table>")


class ExcitabilityPanel(widgets.VBox):
    """eta (log slider), the three segment limits (range sliders), attitude-error frame and
    D0 dropdowns; redraws the Fig. 2 analogue, the energy spectrum and the X1-X7 table.

    Attributes
    ----------
    controls : dict
        ``eta``, ``tau1``, ``tau2``, ``tau3``, ``attitude_error``, ``d0``.
    analysis : RocketAnalysis
        The analysis shown.
    last_timing : dict
        ``compute_ms`` and ``render_ms`` of the last update.
    """

    def __init__(self, eta: float = 1e-3, segments=rocket.SEGMENTS, dpi: float = 72.0,
                 **analyze_options):
        end = float(rocket.rocket_trajectory(analyze_options.get("spin_hz", 2.0)).t[-1])
        slider = dict(continuous_update=False, **_LOOK)
        self.controls = {
            "eta": widgets.FloatLogSlider(value=eta, base=10, min=-8, max=-0.5, step=0.1,
                                          description="η", readout_format=".1e", **slider),
            **{f"tau{i + 1}": widgets.FloatRangeSlider(
                value=tuple(seg), min=0.0, max=end, step=1.0, description=f"τ{i + 1} [s]",
                readout_format=".0f", **slider) for i, seg in enumerate(segments)},
            "attitude_error": widgets.Dropdown(options=list(ATTITUDE_ERRORS),
                                               value=analyze_options.pop("attitude_error",
                                                                         "ecef"),
                                               description="attitude error", **_LOOK),
            "d0": widgets.Dropdown(options=list(metrics.D0_CHOICES),
                                   value=analyze_options.pop("d0", "global"),
                                   description="D0 (A19)", **_LOOK),
        }
        self.options = analyze_options
        self.dpi = float(dpi)
        self.status = widgets.HTML()
        self.image = widgets.Image(format="png")
        self.table = widgets.HTML()
        self.last_timing: dict = {}
        self._bases: dict = {}
        self._excitations: dict = {}
        self._figure = None
        self.analysis = None
        for control in self.controls.values():
            control.observe(lambda _change: self.update(), names="value")
        super().__init__([widgets.VBox(list(self.controls.values())), self.status,
                          self.image, self.table])
        self.update()

    def segments(self) -> tuple:
        return tuple(tuple(self.controls[f"tau{i + 1}"].value)
                     for i in range(sum(k.startswith("tau") for k in self.controls)))

    def _base(self, frame: str):
        if frame not in self._bases:  # model (cached chain) + sensability recursion
            self._bases[frame] = rocket.analyze(attitude_error=frame, **self.options)
        return self._bases[frame]

    def compute(self):
        """The analysis for the current controls (cached pieces reused)."""
        c = self.controls
        base = self._base(c["attitude_error"].value)
        key = (c["attitude_error"].value, c["d0"].value, self.segments())
        if key not in self._excitations:
            if len(self._excitations) > 64:
                self._excitations.clear()
            self._excitations[key] = rocket.excitability_segments(
                base.model, self.segments(), base.settings["eta"], c["d0"].value,
                base.sensability)
        excitation = tuple(e.with_eta(c["eta"].value) for e in self._excitations[key])
        return replace(base, excitability=excitation, segments=self.segments(),
                       settings={**base.settings, "eta": excitation[0].eta,
                                 "d0": c["d0"].value})

    def update(self) -> None:
        """Recompute what changed and redraw (errors go to ``status``)."""
        start = time.perf_counter()
        try:
            analysis = self.compute()
        except NavlibInputError as exc:
            self.status.value = f'<b style="color:#b00">Invalid input:</b> {exc}'
            return
        self.analysis = analysis
        computed = time.perf_counter()
        first = self._figure is None
        self._figure = excitability_figure(analysis, self._figure)
        self.image.value = _png(self._figure, self.dpi)
        if first:
            _freeze_layout(self._figure)
            plt.close(self._figure)
        rendered = time.perf_counter()
        try:
            self.table.value = _claims_html(rocket.claims_table(analysis, "excitability"))
        except NavlibInputError as exc:  # not three segments
            self.table.value = f"<i>{exc}</i>"
        self.last_timing = {"compute_ms": 1e3 * (computed - start),
                            "render_ms": 1e3 * (rendered - computed)}
        ne = ", ".join(f"τ{i + 1}: {e.ne}" for i, e in enumerate(analysis.excitability))
        self.status.value = (f"ne {ne}; compute {self.last_timing['compute_ms']:.0f} ms, "
                             f"render {self.last_timing['render_ms']:.0f} ms")


class SensabilityPanel(widgets.VBox):
    """nu slider (admissible range shown) and a state selector; redraws the sensability of
    the chosen states with their 2-sigma bands and the S1-S8 table.

    Attributes
    ----------
    controls : dict
        ``nu`` slider and ``states`` multi-selector.
    analysis : RocketAnalysis
    last_timing : dict
    """

    def __init__(self, nu: float = 0.985, states=("P_x", "V_x"), dpi: float = 72.0,
                 **analyze_options):
        self.base = rocket.analyze(nu=nu, **analyze_options)
        low, high = metrics.nu_range(len(STATE_NAMES))
        slider = dict(continuous_update=False, **_LOOK)
        self.controls = {
            "nu": widgets.FloatSlider(value=nu, min=round(low + 5e-4, 4), max=0.9995,
                                      step=0.0005, description="ν", readout_format=".4f",
                                      **slider),
            "states": widgets.SelectMultiple(options=list(STATE_NAMES), value=tuple(states),
                                             rows=7, description="states", **_LOOK),
        }
        self.range_note = widgets.HTML(
            f"admissible ν ∈ (√(1 − 1/n), 1) = ({low:.4f}, {high:g}) for n = "
            f"{len(STATE_NAMES)} (spec A11); paper: 0.985")
        self.dpi = float(dpi)
        self.status = widgets.HTML()
        self.image = widgets.Image(format="png")
        self.table = widgets.HTML()
        self.last_timing: dict = {}
        self._figure = None
        self._figure_states: tuple = ()
        self.analysis = None
        for control in self.controls.values():
            control.observe(lambda _change: self.update(), names="value")
        super().__init__([widgets.VBox([*self.controls.values(), self.range_note]),
                          self.status, self.image, self.table])
        self.update()

    def update(self) -> None:
        """Re-threshold at the new nu (no new eigen-decomposition) and redraw."""
        start = time.perf_counter()
        states = tuple(self.controls["states"].value)
        if not states:
            self.status.value = "<i>select at least one state</i>"
            return
        try:
            analysis = self.base.with_nu(self.controls["nu"].value)
        except NavlibInputError as exc:
            self.status.value = f'<b style="color:#b00">Invalid input:</b> {exc}'
            return
        self.analysis = analysis
        computed = time.perf_counter()
        if states != self._figure_states:
            if self._figure is not None:
                plt.close(self._figure)
            self._figure = sensability_figure(analysis, states)
            self._figure_states = states
            self.image.value = _png(self._figure, self.dpi)
            _freeze_layout(self._figure)
            plt.close(self._figure)
        else:
            se = analysis.sensability
            lines = [ln for ax in self._figure.axes for ln in ax.get_lines()
                     if ln.get_label() == "sensability"]
            for line, state in zip(lines, states, strict=True):
                line.set_ydata(se.s[:, STATE_NAMES.index(state)])
            self._figure.suptitle(f"Sensability (ν = {se.nu:.4f}) and 2σ bands", fontsize=10)
            self.image.value = _png(self._figure, self.dpi)
        rendered = time.perf_counter()
        self.table.value = _claims_html(rocket.claims_table(analysis, "sensability"))
        self.last_timing = {"compute_ms": 1e3 * (computed - start),
                            "render_ms": 1e3 * (rendered - computed)}
        nr = analysis.sensability.nr
        self.status.value = (f"sensible subspace dimension nr: {nr.min()}-{nr.max()} "
                             f"(median {int(sorted(nr)[len(nr) // 2])}); compute "
                             f"{self.last_timing['compute_ms']:.0f} ms, render "
                             f"{self.last_timing['render_ms']:.0f} ms")
