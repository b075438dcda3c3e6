"""Interactive panels for notebooks 03 (excitability) and 04 (sensability).

Both panels call :mod:`navlib.studies.rocket` and the figure builders of
:mod:`navlib.plots.metrics`, and recompute only what a change touches
(:meth:`navlib.metrics.SegmentedAnalysis.with_settings`):

* the discretised 21-state model is cached per attitude-error frame
  (:func:`navlib.studies.rocket.rocket_chain`);
* a new eta reuses the segment SVDs, new segment limits or D0 redo only the three small
  SVDs, a new nu reuses the eigen-decompositions;
* the figure is kept and redrawn in place by Agg blitting (:class:`navlib.widgets.base.
  Blitter`), rendered once to PNG per update (the render path of
  :mod:`navlib.widgets.base`).

``last_timing`` holds the milliseconds of the last update: ``compute_ms``, ``render_ms``,
``table_ms`` (claims table) and ``total_ms``.
"""

from __future__ import annotations

import time

import ipywidgets as widgets
import numpy as np

from navlib import metrics
from navlib.errors import NavlibInputError
from navlib.models.ecef import ATTITUDE_ERRORS, STATE_NAMES
from navlib.plots.metrics import (
    excitability_dynamic_artists,
    excitability_figure,
    sensability_figure,
)
from navlib.studies import rocket
from navlib.widgets.base import Blitter, Panel, look
from navlib.widgets.static import TIMING_CLASS

__all__ = ["ExcitabilityPanel", "SensabilityPanel"]


def _timing(start: float, computed: float, rendered: float) -> dict:
    done = time.perf_counter()
    return {"compute_ms": 1e3 * (computed - start), "render_ms": 1e3 * (rendered - computed),
            "table_ms": 1e3 * (done - rendered), "total_ms": 1e3 * (done - start)}


def _timing_text(timing: dict) -> str:
    """The update's timing for the status line, in a ``navlib-timing`` span (a report page
    leaves it out: :func:`navlib.widgets.static.freeze_widgets`)."""
    return (f'<span class="{TIMING_CLASS}">update {timing["total_ms"]:.0f} ms (compute '
            f'{timing["compute_ms"]:.0f}, render {timing["render_ms"]:.0f}, table '
            f'{timing["table_ms"]:.0f})</span>')


def _claims_html(table) -> str:
    colour = {"reproduced": "#1a7f37", "partly": "#9a6700", "not reproduced": "#cf222e"}
    rows = "".join(
        f"<tr><td><b>{r.claim_id}</b></td><td style='color:{colour.get(r.verdict, '#000')}'>"
        f"{r.verdict}</td><td style='text-align:left'>{r.ours}</td></tr>"
        for r in table.itertuples())
    return (f"<table style='font-size:13px'><tr><th>claim</th><th>verdict</th>"
            f"<th>ours</th></tr>{rows}</table>")


class _ClaimsPanel(Panel):
    """A panel showing one figure (part ``figure``) beside a claims table (part ``claims``)."""

    @property
    def image(self) -> widgets.Image:
        return self.parts["figure"]

    @property
    def table(self) -> widgets.HTML:
        return self.parts["claims"]


class ExcitabilityPanel(_ClaimsPanel):
    """eta (log slider), the three segment limits (range sliders), attitude-error frame and
    D0 dropdowns; redraws the Fig. 2 analogue, the energy spectrum and the X1-X7 table.

    Attributes
    ----------
    controls : dict
        ``eta``, ``tau1``, ``tau2``, ``tau3``, ``attitude_error``, ``d0``.
    analysis : RocketAnalysis
        The analysis shown.
    image, table : ipywidgets.Image, ipywidgets.HTML
        The figure and the claims table (parts ``figure`` and ``claims`` of the view).
    last_timing : dict
        ``compute_ms``, ``render_ms``, ``table_ms`` and ``total_ms`` of the last update.
    """

    def __init__(self, eta: float = 1e-3, segments=rocket.SEGMENTS, dpi: float = 72.0,
                 **analyze_options):
        end = float(rocket.rocket_trajectory(analyze_options.get("spin_hz", 2.0)).t[-1])
        slider = dict(continuous_update=False, **look())
        controls = {
            "eta": widgets.FloatLogSlider(value=eta, base=10, min=-8, max=-0.5, step=0.1,
                                          description="η", readout_format=".1e", **slider),
            **{f"tau{i + 1}": widgets.FloatRangeSlider(
                value=tuple(seg), min=0.0, max=end, step=1.0, description=f"τ{i + 1} [s]",
                readout_format=".0f", **slider) for i, seg in enumerate(segments)},
            "attitude_error": widgets.Dropdown(options=list(ATTITUDE_ERRORS),
                                               value=analyze_options.pop("attitude_error",
                                                                         "ecef"),
                                               description="attitude error", **look()),
            "d0": widgets.Dropdown(options=list(metrics.D0_CHOICES),
                                   value=analyze_options.pop("d0", "global"),
                                   description="D0 (A19)", **look()),
        }
        self.options = analyze_options
        self._bases: dict = {}
        self._segmented: dict = {}
        self._figure = None
        self._blitter = None
        self.analysis = None
        super().__init__(controls, dpi=dpi)

    def segments(self) -> tuple:
        return tuple(tuple(self.controls[f"tau{i + 1}"].value)
                     for i in range(sum(k.startswith("tau") for k in self.controls)))

    def _base(self, frame: str):
        if frame not in self._bases:  # model (cached chain) + sensability recursion
            self._bases[frame] = rocket.excitability_study(attitude_error=frame, **self.options)
        return self._bases[frame]

    def compute(self):
        """The analysis for the current controls (cached pieces reused)."""
        c = self.controls
        key = (c["attitude_error"].value, c["d0"].value, self.segments())
        if key not in self._segmented:  # the segment SVDs, re-thresholded for each eta
            if len(self._segmented) > 64:
                self._segmented.clear()
            self._segmented[key] = self._base(key[0]).with_settings(key[2], d0=key[1])
        return self._segmented[key].with_settings(eta=c["eta"].value)

    def refresh(self, changed: set) -> None:
        """Recompute what changed and redraw the kept figure in place."""
        start = time.perf_counter()
        analysis = self.compute()
        self.analysis = analysis
        computed = time.perf_counter()
        dynamic = None if self._figure is None else excitability_dynamic_artists(self._figure)
        figure = excitability_figure(analysis, self._figure)
        if figure is not self._figure or excitability_dynamic_artists(figure) != dynamic:
            self._figure = figure  # new figure or rebuilt axes: new background
            self._blitter = Blitter(figure, excitability_dynamic_artists(figure), self.dpi)
        self.show("figure", self._blitter)
        rendered = time.perf_counter()
        try:
            self.show("claims", _claims_html(rocket.claims_table(analysis, "excitability")))
        except NavlibInputError as exc:  # not three segments
            self.show("claims", f"<i>{exc}</i>")
        self.last_timing = _timing(start, computed, rendered)
        ne = ", ".join(f"τ{i + 1}: {e.ne}" for i, e in enumerate(analysis.excitability))
        self.status.value = f"ne {ne}; {_timing_text(self.last_timing)}"


class SensabilityPanel(_ClaimsPanel):
    """nu slider (admissible range shown) and a state selector; redraws the sensability of
    the chosen states with their 2-sigma bands and the S1-S8 table.

    Attributes
    ----------
    controls : dict
        ``nu`` slider and ``states`` multi-selector.
    analysis : RocketAnalysis
    image, table : ipywidgets.Image, ipywidgets.HTML
    last_timing : dict
    """

    def __init__(self, nu: float = 0.985, states=("P_x", "V_x"), dpi: float = 72.0,
                 **analyze_options):
        self.base = rocket.excitability_study(nu=nu, **analyze_options)
        low, high = metrics.nu_range(len(STATE_NAMES))
        controls = {
            "nu": widgets.FloatSlider(value=nu, min=round(low + 5e-4, 4), max=0.9995,
                                      step=0.0005, description="ν", readout_format=".4f",
                                      continuous_update=False, **look()),
            "states": widgets.SelectMultiple(options=list(STATE_NAMES), value=tuple(states),
                                             rows=7, description="states", **look()),
        }
        self.range_note = widgets.HTML(
            f"admissible ν ∈ (√(1 − 1/n), 1) = ({low:.4f}, {high:g}) for n = "
            f"{len(STATE_NAMES)} (spec A11); paper: 0.985")
        self._figure_states: tuple = ()
        self._lines: list = []
        self._blitter = None
        self.analysis = None
        super().__init__(controls, extras=[self.range_note], dpi=dpi)

    def refresh(self, changed: set) -> None:
        """Re-threshold at the new nu (no new eigen-decomposition) and redraw."""
        start = time.perf_counter()
        states = tuple(self.controls["states"].value)
        if not states:
            raise NavlibInputError("states: select at least one state")
        analysis = self.base.with_nu(self.controls["nu"].value)
        self.analysis = analysis
        computed = time.perf_counter()
        if states != self._figure_states:
            figure = sensability_figure(analysis, states,
                                        title="Sensability (ν on the slider) and ±2σ bands")
            self._figure_states = states
            self._lines = [ln for ax in figure.axes for ln in ax.get_lines()
                           if ln.get_label() == "sensability"]
            self._blitter = Blitter(figure, self._lines, self.dpi)
        se = analysis.sensability
        for line, state in zip(self._lines, states, strict=True):
            line.set_ydata(se.s[:, STATE_NAMES.index(state)])
        self.show("figure", self._blitter)
        rendered = time.perf_counter()
        self.show("claims", _claims_html(rocket.claims_table(analysis, "sensability")))
        self.last_timing = _timing(start, computed, rendered)
        nr = analysis.sensability.nr
        self.status.value = (f"ν = {analysis.sensability.nu:.4f}; sensible subspace dimension "
                             f"nr {nr.min()}-{nr.max()} (median {int(np.median(nr))}); "
                             f"{_timing_text(self.last_timing)}")
