"""The panel base (navlib.widgets.base), detached figures and the static export of widgets.

The browser tests (tests/browser, ``make test-browser``) drive the same panels in
JupyterLab; these run without a browser.
"""

import threading

import ipywidgets as widgets
import matplotlib.pyplot as plt
import nbformat
import numpy as np
import pytest
from matplotlib._pylab_helpers import Gcf
from matplotlib.layout_engine import ConstrainedLayoutEngine
from support.images import drawn_as_kept, pixels

from navlib.errors import NavlibInputError
from navlib.plots import figure as figure_mod
from navlib.plots.metrics import reshade_segments
from navlib.widgets import base, layers
from navlib.widgets.base import Blitter, Panel, render_png
from navlib.widgets.static import WIDGET_STATE, WIDGET_VIEW, freeze_widgets


class _LinePanel(Panel):
    """A small panel: the slope of a line, one kept (blitted) and one rebuilt figure."""

    def __init__(self, **kw):
        controls = {"slope": widgets.FloatSlider(value=1.0, min=-5, max=5,
                                         description="slope"),
                    "kind": widgets.Dropdown(options=["ok", "refuse", "crash"],
                                             description="kind")}
        self.blitter = None
        super().__init__(controls, **kw)

    def refresh(self, changed):
        kind = self.controls["kind"].value
        if kind == "refuse":
            raise NavlibInputError("kind: refused on purpose")
        if kind == "crash":
            raise ZeroDivisionError("a bug")
        slope = self.controls["slope"].value
        if self.blitter is None:
            fig, ax = figure_mod.subplots(figsize=(3, 2))
            (line,) = ax.plot([0, 1], [0, slope])
            ax.set_ylim(-5, 5)
            self.blitter = Blitter(fig, [line], self.dpi)
        self.blitter.dynamic[0].set_ydata([0, slope])
        self.show("kept", self.blitter)
        fig, ax = figure_mod.subplots(figsize=(3, 2))
        ax.bar([0], [slope])
        self.show("rebuilt", fig)
        self.show("table", f"<b>slope</b> {slope}")
        self.status.value = f"ok: slope {slope}"


def test_builders_are_detached_only_inside_the_block():
    plt.close("all")
    with figure_mod.detached():
        assert figure_mod.is_detached()
        fig, axes = figure_mod.subplots(2, 1, figsize=(3, 2), sharex=True,
                                        layout="constrained")
        assert plt.get_fignums() == [] and len(axes) == 2
    assert not figure_mod.is_detached()
    pyplot_fig, _ = figure_mod.subplots(figsize=(3, 2))
    assert plt.get_fignums() == [pyplot_fig.number]
    plt.close("all")
    assert render_png(fig)[:4] == b"\x89PNG"


def test_panel_shows_parts_counts_updates_and_keeps_last_view_on_refusal():
    panel = _LinePanel(dpi=40)
    assert list(panel.parts) == ["kept", "rebuilt", "table"]
    assert isinstance(panel.parts["kept"], widgets.Image)
    assert panel.parts["kept"].value[:4] == b"\x89PNG"
    assert panel.status.value.startswith("ok: slope 1.0")
    assert 'data-count="1"' in panel.status.value and panel.updates == 1
    assert f'data-ms="{panel.last_timing["total_ms"]:.1f}"' in panel.status.value
    first = panel.parts["kept"].value
    panel.controls["slope"].value = -2.0
    assert panel.parts["kept"].value != first and panel.updates == 2
    assert panel.status.value.count("navlib-update") == 1
    kept = panel.parts["kept"].value
    panel.controls["kind"].value = "refuse"
    assert "Invalid input:</b> kind: refused on purpose" in panel.status.value
    assert "data-ms" not in panel.status.value  # a refusal has no update time
    assert panel.parts["kept"].value == kept and panel.updates == 3
    with pytest.raises(ZeroDivisionError):
        panel.controls["kind"].value = "crash"
    assert "navlib-panel-error" in panel.status.value and "a bug" in panel.status.value
    assert "total_ms" in panel.last_timing
    panel.show("table", None)
    assert panel.parts["table"].layout.display == "none"
    panel.show("table", "back")
    assert panel.parts["table"].layout.display is None


def test_the_collector_waits_until_an_update_has_been_sent(monkeypatch):
    """Python's garbage collector is off while a panel computes, draws and sends (the
    status is set last), on again after an update, a refusal and a crash; a collector the
    user turned off stays off."""
    import gc

    seen = []
    panel = _LinePanel(dpi=40)
    monkeypatch.setattr(panel, "_done", lambda *a: seen.append(gc.isenabled()))
    assert gc.isenabled()
    panel.controls["slope"].value = 2.0
    assert gc.isenabled()
    panel.controls["kind"].value = "refuse"
    assert gc.isenabled()
    with pytest.raises(ZeroDivisionError):
        panel.controls["kind"].value = "crash"
    assert gc.isenabled() and seen == [False, False, False]
    gc.disable()
    try:
        panel.controls["kind"].value = "ok"
        assert not gc.isenabled() and len(seen) == 4
    finally:
        gc.enable()


def test_blitted_png_matches_a_fresh_render_of_the_same_state():
    panel = _LinePanel(dpi=40)
    panel.controls["slope"].value = 3.0
    with figure_mod.detached():
        fig, ax = figure_mod.subplots(figsize=(3, 2))
    (line,) = ax.plot([0, 1], [0, 3.0])
    ax.set_ylim(-5, 5)
    fresh = Blitter(fig, [line], 40).png()
    assert panel.parts["kept"].value == fresh


def test_panel_updates_never_open_a_pyplot_figure_even_from_another_thread(monkeypatch):
    """The render path of issue 13: while panels update on a worker thread (as under
    JupyterLab's kernel subshells), pyplot never holds a figure a hook could redraw."""
    plt.close("all")
    seen = []
    encode = layers.encode_png
    for module in (base, layers):  # figures and their layers are encoded in both
        monkeypatch.setattr(module, "encode_png", lambda rgba: (seen.append(len(Gcf.figs)),
                                                                encode(rgba))[1])
    panel = _LinePanel(dpi=30)
    stop = threading.Event()
    open_figures = []

    def watch():
        while not stop.is_set():
            open_figures.append(len(plt.get_fignums()))

    watcher = threading.Thread(target=watch)
    watcher.start()
    try:
        worker = threading.Thread(target=lambda: [
            setattr(panel.controls["slope"], "value", float(v)) for v in range(-4, 5)])
        worker.start()
        worker.join()
    finally:
        stop.set()
        watcher.join()
    assert seen and set(seen) == {0}
    assert open_figures and set(open_figures) == {0}
    assert panel.controls["slope"].value == 4.0 and panel.updates == 10


def test_reshade_segments_replaces_the_shading_in_place():
    from navlib.plots.metrics import _shade_segments

    with figure_mod.detached():
        fig, axes = figure_mod.subplots(2, 1)
    for ax in axes:
        ax.plot([0, 10], [0, 1])
        _shade_segments(ax, [(0, 4), (4, 10)])
    new = reshade_segments(fig, [(0, 2), (2, 6), (6, 10)])
    assert len(new) == 2 * 2 * 3
    for ax in axes:
        spans = [p for p in ax.patches if p.get_gid() == "segment"]
        assert len(spans) == 3 and len(ax.get_lines()) == 1


def _notebook_with(panel) -> nbformat.NotebookNode:
    state = widgets.Widget.get_manager_state(drop_defaults=False)
    nb = nbformat.v4.new_notebook()
    cell = nbformat.v4.new_code_cell("panel")
    cell.outputs = [nbformat.v4.new_output(
        "display_data", data={WIDGET_VIEW: {"model_id": panel.model_id, "version_major": 2,
                                            "version_minor": 0},
                              "text/plain": "VBox(...)"})]
    nb.cells = [cell]
    nb.metadata["widgets"] = {WIDGET_STATE: state}
    return nb


def test_freeze_widgets_shows_the_final_figures_and_settings_without_scripts():
    panel = _LinePanel(dpi=30)
    panel.controls["slope"].value = 2.5
    panel.show("table", None)  # hidden parts stay hidden
    nb = _notebook_with(panel)
    assert freeze_widgets(nb) == 1
    data = nb.cells[0].outputs[0]["data"]
    assert WIDGET_VIEW not in data and "widgets" not in nb.metadata
    page = data["text/html"]
    assert page.count('src="data:image/png;base64,') == 2
    assert "slope</b> 2.5" in page and "<b>kind</b> ok" in page
    assert "ok: slope 2.5" in page and "navlib-part-table" not in page


def test_freeze_widgets_without_state_keeps_the_text_fallback():
    nb = nbformat.v4.new_notebook()
    cell = nbformat.v4.new_code_cell("w")
    cell.outputs = [nbformat.v4.new_output(
        "display_data", data={WIDGET_VIEW: {"model_id": "gone"}, "text/plain": "IntSlider"})]
    nb.cells = [cell]
    assert freeze_widgets(nb) == 0
    assert cell.outputs[0]["data"] == {"text/plain": "IntSlider"}


def test_ink_of_blank_figure_is_lower_than_drawn():
    """Guards the browser suite's blank-figure criterion on the real render path."""
    with figure_mod.detached():
        drawn, ax = figure_mod.subplots(figsize=(3, 2))
        ax.plot([0, 1], [0, 1])
        ax.set_title("title")
        blank, _ = figure_mod.subplots(figsize=(3, 2))

    def ink(fig):
        rgb = pixels(render_png(fig, 40))
        grey = (rgb.max(axis=2) - rgb.min(axis=2) < 24) & (rgb.sum(axis=2) < 420)
        return grey.mean()

    blank.axes[0].set_axis_off()
    assert ink(blank) == 0.0 < ink(drawn)


def _two_axes_figure(scale: float, label: str = "y", band: bool = False,
                     dots: bool = False):
    """A constrained-layout figure of lines, bars, a legend and titles, data times ``scale``."""
    fig, (top, bottom) = figure_mod.subplots(2, 1, figsize=(4, 3), layout="constrained")
    top.plot([0, 1, 2], [0, scale, 4 * scale], label=f"line {scale:g}")
    top.axhline(2 * scale, color="k", linestyle="--")
    top.legend()
    top.set_ylabel(label)
    top.set_title(f"scale {scale:g}")
    bottom.bar([0, 1, 2], [1, -scale, 3 * scale], color=["C0", "C1", "C2"])
    if band:
        bottom.fill_between([0, 2], 0, scale, alpha=0.2)
        bottom.broken_barh([(0.5 * scale, 1.0)], (0.5, 1.0), color="C3")
    if dots:
        bottom.scatter([0, 1], [scale, 2 * scale])
    fig.suptitle("kept")
    return fig


def test_kept_figure_redrawn_with_new_data_equals_a_new_figure_in_its_layout():
    kept = base.KeptFigures()
    with figure_mod.detached():
        kept.render("part", _two_axes_figure(1.0, band=True), 50)
        kept_fig = kept._kept["part"][1]
        assert not isinstance(kept_fig.get_layout_engine(), ConstrainedLayoutEngine)
        png = kept.render("part", _two_axes_figure(7.5, band=True), 50)
        assert kept._kept["part"][1] is kept_fig  # the data moved into the kept figure
        reference = drawn_as_kept(_two_axes_figure(7.5, band=True), kept_fig, 50)
    assert np.array_equal(pixels(png), reference)
    assert kept_fig.axes[0].get_title() == "scale 7.5"
    assert kept_fig.axes[0].get_legend().get_texts()[0].get_text() == "line 7.5"


def test_kept_figure_with_markers_lends_its_layout_and_a_new_label_relayouts():
    kept = base.KeptFigures()
    with figure_mod.detached():
        kept.render("part", _two_axes_figure(1.0, dots=True), 50)
        first = kept._kept["part"][1]
        second = _two_axes_figure(3.0, dots=True)
        kept.render("part", second, 50)  # markers (not polygons): drawn in the kept layout
        assert kept._kept["part"][1] is second
        assert not isinstance(second.get_layout_engine(), ConstrainedLayoutEngine)
        for ax, old in zip(second.axes, first.axes, strict=True):
            assert np.allclose(ax.get_position().bounds, old.get_position().bounds)
        relabelled = _two_axes_figure(3.0, label="a much longer label\nover two lines",
                                      dots=True)
        kept.render("part", relabelled, 50)  # new key: constrained layout runs again
    assert kept._kept["part"][1] is relabelled
    assert not np.allclose(relabelled.axes[0].get_position().bounds,
                           first.axes[0].get_position().bounds)


def test_a_panel_keeps_large_arrays_on_the_process_pages():
    """Building a panel turns numpy's huge-page advice off and, with glibc, raises its mmap
    and trim thresholds (navlib.widgets.memory), once."""
    import sys

    from navlib.widgets import memory

    panel = Panel({"x": widgets.FloatSlider(value=1.0)}, update_now=False)
    assert panel.updates == 0
    advise = np._core.multiarray._set_madvise_hugepage
    assert advise(False) is False  # it was off already
    if sys.platform.startswith("linux"):
        assert memory.keep_pages() is True
