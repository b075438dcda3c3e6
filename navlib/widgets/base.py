"""The base of every widget panel: controls, status line, error display, observe wiring and
the one render path.

Why one render path. JupyterLab 4.6 hands widget messages to kernel subshells by default
("kernel comms over subshells", ``perCommTarget``): a panel's update runs on one thread
while the end-of-cell hook of the inline backend (``flush_figures``) runs on another and
draws every figure pyplot holds. A panel figure open in pyplot at that moment is drawn by
both threads at once and reaches the page blank or partly drawn. So a panel never shows a
live figure:

* its figures are built inside :func:`navlib.plots.figure.detached`, so pyplot never holds
  them and no hook can find them;
* each figure is rasterised by Agg to PNG bytes shown in an :class:`ipywidgets.Image`
  (:func:`render_png`); a figure a panel keeps (:class:`KeptFigures`) is drawn in layers,
  its axes' frames kept between updates (:class:`~navlib.widgets.layers.LayeredFigure`),
  and a panel that knows which artists change blits them (:class:`Blitter`: the static
  background once, the changing artists on top);
* tables and notes are HTML widgets. No ``Output`` widget, no ``display`` of a figure.

A panel subclass names its controls and implements :meth:`Panel.refresh`, which gets the
names of the controls that changed (all of them on the first call), recomputes what they
touch and puts the results on show with :meth:`Panel.show`. A
:class:`~navlib.errors.NavlibInputError` raised there leaves the last good view in place
and shows its message in the status line; any other exception is shown there too (class
``navlib-panel-error``) and re-raised, so a bug is never silent.
"""

from __future__ import annotations

import contextlib
import functools
import gc
import html
import re
import time
from collections.abc import Iterable, Mapping

import ipywidgets as widgets
import pandas as pd
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from navlib.errors import NavlibInputError
from navlib.plots.figure import detached
from navlib.widgets.layers import LayeredFigure, agg_canvas, encode_png
from navlib.widgets.memory import keep_pages

__all__ = ["LOOK", "Blitter", "KeptFigures", "Panel", "collector_after", "error_html",
           "layout_key", "look", "render_png", "table_html"]

LOOK = {"style": {"description_width": "9em"}}
"""Common look of the controls (label width); panels add their own ``layout`` width."""


def look(width: str = "34em") -> dict:
    """Keyword arguments giving a control the common label width and ``width``."""
    return {**LOOK, "layout": widgets.Layout(width=width)}


def render_png(fig: Figure, dpi: float = 72.0) -> bytes:
    """Draw ``fig`` with Agg at ``dpi`` and return it as PNG bytes (fast, light compression).

    The figure should be detached (:func:`navlib.plots.figure.detached`): nothing else may
    draw it meanwhile.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        Detached figure.
    dpi : float, optional
        Resolution, dots per inch.

    Returns
    -------
    bytes
    """
    fig.set_dpi(dpi)
    canvas = agg_canvas(fig)
    canvas.draw()
    return encode_png(canvas.buffer_rgba())


class Blitter:
    """Render a kept figure to PNG, redrawing only its changing artists after the first time.

    The first render draws everything except ``dynamic`` (marked animated) and keeps that
    background; :meth:`png` restores it and draws the dynamic artists on top (Agg
    blitting), so an update costs a few milliseconds of drawing plus the PNG encoding
    instead of re-rasterising every tick label. The layout is frozen after the first draw.

    Parameters
    ----------
    fig : Figure
        A detached figure.
    dynamic : iterable of Artist
        The artists later updates change (lines, bars, titles, shading).
    dpi : float
    """

    def __init__(self, fig: Figure, dynamic: Iterable, dpi: float = 72.0):
        self.fig = fig
        self.dynamic: list = []
        self._layouts: dict = {}
        fig.set_dpi(dpi)
        self.canvas = agg_canvas(fig)
        self.set_dynamic(dynamic, redraw_background=False)
        self.canvas.draw()  # runs the layout once, then it is frozen
        if fig.get_layout_engine() is not None:
            fig.set_layout_engine("none")
        self.background = self.canvas.copy_from_bbox(fig.bbox)

    def set_dynamic(self, dynamic: Iterable, redraw_background: bool = True) -> None:
        """Replace the dynamic artists (e.g. new segment shading); with
        ``redraw_background`` the background is drawn again without them.

        Parameters
        ----------
        dynamic : iterable of matplotlib.artist.Artist
            The new dynamic artists.
        redraw_background : bool, optional
            Whether to draw the background again.
        """
        self.dynamic = list(dynamic)
        for artist in self.dynamic:
            artist.set_animated(True)
        if redraw_background:
            self.canvas.draw()
            self.background = self.canvas.copy_from_bbox(self.fig.bbox)

    def relayout(self, dynamic: Iterable, key=None) -> None:
        """Replace the dynamic artists and lay the figure out again before drawing its
        background (after labels or tick labels changed width), then freeze the layout.

        Parameters
        ----------
        dynamic : iterable of matplotlib.artist.Artist
            The new dynamic artists.
        key : hashable, optional
            What the layout depends on (e.g. the states shown): a layout computed under
            the same key is put back instead of computed again.
        """
        kept = self._layouts.get(key) if key is not None else None
        if kept is not None:
            for ax, position in zip(self.fig.axes, kept, strict=True):
                ax.set_position(position, which="both")
            self.set_dynamic(dynamic)
            return
        self.fig.set_layout_engine("constrained")
        self.set_dynamic(dynamic)
        self.fig.set_layout_engine("none")
        if key is not None:
            self._layouts[key] = [ax.get_position(original=True).frozen()
                                  for ax in self.fig.axes]

    def png(self) -> bytes:
        """The figure with the dynamic artists' current state, as PNG bytes."""
        self.canvas.restore_region(self.background)
        for artist in self.dynamic:
            if artist.figure is not None:  # removed artists are skipped
                self.fig.draw_artist(artist)
        return encode_png(self.canvas.buffer_rgba())


_SUPER_TEXTS = ("_suptitle", "_supxlabel", "_supylabel")


def _cell(ax):
    spec = ax.get_subplotspec()
    return None if spec is None else (spec.rowspan, spec.colspan)


def layout_key(fig: Figure) -> tuple:
    """What a figure's layout depends on beyond its data: size, the axes (grid cells,
    scales, axis labels) and the figure titles.

    Two figures of a builder with equal keys get equal layouts up to the width of their
    tick labels and figure titles, which :class:`KeptFigures` accepts when it reuses a layout
    (docs/assumptions.md, "Panel figures"): a figure title counts by its number of lines,
    the height constrained layout reserves for it, not by its words.
    """
    texts = tuple(None if getattr(fig, name, None) is None
                  else getattr(fig, name).get_text().count("\n") + 1 for name in _SUPER_TEXTS)
    return (tuple(fig.get_size_inches().round(4)), texts,
            tuple((type(ax).__name__, _cell(ax), ax.get_visible(), ax.get_xscale(),
                   ax.get_yscale(), ax.get_xlabel(), ax.get_ylabel()) for ax in fig.axes))


def _artists(fig: Figure) -> tuple:
    """Per axes: the number of lines, the patch, collection and text counts, the legend
    entries, and whether it holds an image or a collection other than polygons (which
    :func:`_transplant` does not copy)."""
    def legend(ax):
        found = ax.get_legend()
        return None if found is None else len(found.get_texts())

    return tuple((len(ax.lines), tuple(type(p).__name__ for p in ax.patches),
                  len(ax.collections), len(ax.texts), legend(ax),
                  bool(ax.images) or not all(isinstance(c, PolyCollection)
                                             for c in ax.collections)) for ax in fig.axes)


def _transplant(new: Figure, kept: Figure) -> None:
    """Give ``kept`` the data of ``new`` (same layout key and artists, no images and only
    polygon collections): line data and styles, rectangles, polygons (bars, bands), texts,
    titles, legends, tick locators and formatters, axis limits."""
    for name in _SUPER_TEXTS:
        if getattr(new, name, None) is not None:
            getattr(kept, name).set_text(getattr(new, name).get_text())
    for src, dst in zip(new.axes, kept.axes, strict=True):
        for a, b in zip(src.lines, dst.lines, strict=True):
            b.set_data(a.get_xdata(orig=True), a.get_ydata(orig=True))
            b.update({"label": a.get_label(), "visible": a.get_visible(),
                      "color": a.get_color(), "linestyle": a.get_linestyle(),
                      "linewidth": a.get_linewidth(), "alpha": a.get_alpha(),
                      "marker": a.get_marker()})
        for a, b in zip(src.patches, dst.patches, strict=True):
            if isinstance(a, Rectangle):
                b.set_bounds(*a.get_bbox().bounds)
            b.update({"facecolor": a.get_facecolor(), "edgecolor": a.get_edgecolor(),
                      "visible": a.get_visible()})
        for a, b in zip(src.collections, dst.collections, strict=True):
            paths = a.get_paths()
            b.set_verts_and_codes([p.vertices for p in paths], [p.codes for p in paths])
            b.update({"facecolor": a.get_facecolor(), "edgecolor": a.get_edgecolor(),
                      "visible": a.get_visible()})
        for a, b in zip(src.texts, dst.texts, strict=True):
            b.update({"text": a.get_text(), "position": a.get_position(),
                      "visible": a.get_visible()})
        for loc in ("left", "center", "right"):
            dst.set_title(src.get_title(loc), loc=loc)
        if src.get_legend() is not None:
            for a, b in zip(src.get_legend().get_texts(), dst.get_legend().get_texts(),
                            strict=True):
                b.set_text(a.get_text())
        for a, b in ((src.xaxis, dst.xaxis), (src.yaxis, dst.yaxis)):
            b.set_major_locator(a.get_major_locator())
            b.set_major_formatter(a.get_major_formatter())
            b.set_minor_locator(a.get_minor_locator())
            b.set_minor_formatter(a.get_minor_formatter())
        dst.dataLim.set(src.dataLim)  # what the kept figure's limits snap to
        dst.set_xlim(src.get_xlim(), auto=src.get_autoscalex_on())
        dst.set_ylim(src.get_ylim(), auto=src.get_autoscaley_on())


@contextlib.contextmanager
def collector_after():
    """Python's cyclic garbage collector held off while a panel updates, and on again after
    (unless it was off before): a collection that falls due in an update runs after the
    update's figures and status have gone to the page, not between the move and its image.

    In a notebook's kernel a full collection scans every object the notebook holds: in the
    browser tests' notebook 06 (about 340 000 objects) it fell inside the P0 move each
    time and took 150-170 of its 380-400 ms. The collection still runs, at the first
    allocation after the update.
    """
    collecting = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if collecting:
            gc.enable()


class KeptFigures:
    """The rebuilt figures of a panel, drawn without re-running their layout.

    A figure shown under a part name is kept once the layout engine (constrained layout)
    has placed it, and its layout is frozen. A later figure for the same part with the same
    :func:`layout_key`:

    * hands its data to the kept figure (:func:`_transplant`) when both hold the same
      artists without images or collections other than polygons: its axes and ticks
      already exist;
    * otherwise gets the kept figure's axes and title positions and is kept in its place.

    A panel may also give the kept figure new data itself (an ``update_*`` function of
    :mod:`navlib.plots`) and show :meth:`redrawn`. Every kept figure is drawn by a
    :class:`~navlib.widgets.layers.LayeredFigure`: only the axes' frames that changed are
    drawn again. The layout engine measures every tick label of every axis: without it a
    rebuilt figure draws in about half the time (docs/assumptions.md, "Panel figures").
    """

    def __init__(self):
        self._kept: dict = {}
        self._layers: dict = {}

    def figure(self, name: str) -> Figure | None:
        """The figure on show as part ``name`` (the kept one after a transplant), or None
        while no laid-out figure is kept for it."""
        kept = self._kept.get(name)
        return None if kept is None else kept[1]

    def render(self, name: str, fig: Figure, dpi: float) -> bytes:
        """PNG bytes of ``fig`` shown as part ``name``, reusing the kept figure's layout
        (and axes) when it fits, and its axes' frames where they did not change
        (:class:`~navlib.widgets.layers.LayeredFigure`).

        Parameters
        ----------
        name : str
            Part name.
        fig : matplotlib.figure.Figure
            Detached figure.
        dpi : float
            Resolution, dots per inch.

        Returns
        -------
        bytes
        """
        key = layout_key(fig)
        kept = self._kept.get(name)
        if kept is not None and kept[0] == key:
            old = kept[1]
            if _artists(fig) == _artists(old) and not any(a[-1] for a in _artists(fig)):
                _transplant(fig, old)
                return self._layers[name].png()
            fig.set_layout_engine("none")
            for ax, position in zip(fig.axes, old.axes, strict=True):
                ax.set_position(position.get_position())
            for text in _SUPER_TEXTS:
                if getattr(fig, text, None) is not None:
                    getattr(fig, text).set_position(getattr(old, text).get_position())
        elif fig.get_layout_engine() is None:
            return render_png(fig, dpi)
        self._kept[name] = (key, fig)
        self._layers[name] = LayeredFigure(fig, dpi)
        return self._layers[name].png()

    def redrawn(self, name: str) -> bytes:
        """PNG bytes of the kept figure of part ``name`` after a panel gave it new data in
        place (an ``update_*`` function of :mod:`navlib.plots`): its autoscaled axes
        rescaled to the data and snapped to their ticks, only the frames that changed
        drawn again.

        Parameters
        ----------
        name : str
            Part name; a figure must be kept for it (:meth:`figure`).

        Returns
        -------
        bytes
        """
        for ax in self._kept[name][1].axes:
            ax.relim()
            ax.autoscale_view()
        return self._layers[name].png()


def table_html(frame: pd.DataFrame, index: bool = False) -> str:
    """A DataFrame as a compact HTML table for a panel.

    Parameters
    ----------
    frame : pandas.DataFrame
        The table.
    index : bool, optional
        Whether to show the index.

    Returns
    -------
    str
    """
    return ("<div style='font-size:13px;overflow-x:auto'>"
            + frame.to_html(index=index, border=0, float_format=lambda v: f"{v:.4g}")
            + "</div>")


_MARK = re.compile(r'<span class="navlib-update"[^>]*></span>$')


def error_html(prefix: str, exc: BaseException) -> str:
    """The status line of a refused input: ``prefix`` in red, then the message.

    Parameters
    ----------
    prefix : str
        What was refused.
    exc : BaseException
        The error.

    Returns
    -------
    str
    """
    return f'<b style="color:#b00">{html.escape(prefix)}:</b> {html.escape(str(exc))}'


class Panel(widgets.VBox):
    """Controls, a status line and a view of named parts (PNG images and HTML).

    Parameters
    ----------
    controls : mapping of str to ipywidgets.ValueWidget
        Observed on ``value``; a change calls :meth:`update` with its name.
    extras : sequence of Widget
        Shown under the controls (notes, buttons) and not observed.
    dpi : float
        Resolution the figures are rendered at (72: the inline backend's).
    update_now : bool
        Run the first :meth:`update` (all controls) at the end of construction.

    Attributes
    ----------
    controls : dict
    status : ipywidgets.HTML
        Summary of the last update, or the message of the refused input; it ends with a
        hidden ``<span class="navlib-update" data-count="N" data-ms="T">``, N counting the
        updates handled (applied or refused), which tells a page (and the browser tests)
        that an update is complete, and T the milliseconds the kernel spent on an applied
        one (``last_timing["total_ms"]``; absent after a refusal).
    view : ipywidgets.VBox
        The parts, in the order they were first shown.
    parts : dict
        Name -> the Image or HTML widget of that part.
    last_timing : dict
        ``total_ms`` of the last applied update (subclasses may add their own keys).
    figures : KeptFigures
        The rebuilt figures shown, kept to reuse their layout (and axes) while their
        layout key is unchanged.
    error_prefix : str
        Class attribute: the status prefix of a refused input.

    Notes
    -----
    The first panel of a process calls :func:`navlib.widgets.memory.keep_pages`: numpy and
    glibc then keep a move's large arrays on pages the process already has.
    """

    error_prefix = "Invalid input"

    def __init__(self, controls: Mapping, *, extras: Iterable = (), dpi: float = 72.0,
                 update_now: bool = True):
        keep_pages()  # numpy and glibc keep a move's arrays on the process' pages
        self.controls = dict(controls)
        self.dpi = float(dpi)
        self.status = widgets.HTML()
        self.view = widgets.VBox()
        self.parts: dict = {}
        self.last_timing: dict = {}
        self.figures = KeptFigures()
        self.updates = 0
        for name, control in self.controls.items():
            control.observe(functools.partial(self._changed, name), names="value")
        header = widgets.VBox([*self.controls.values(), *extras])
        header.add_class("navlib-controls")
        self.status.add_class("navlib-status")
        self.view.add_class("navlib-view")
        super().__init__([header, self.status, self.view])
        self.add_class("navlib-panel")
        if update_now:
            self.update()

    def _changed(self, name: str, _change) -> None:
        self.update((name,))

    def update(self, changed: Iterable[str] | None = None) -> bool:
        """Recompute and redraw for the controls named in ``changed`` (None: all).

        Returns True when applied; a NavlibInputError is shown in ``status`` (False
        returned, the last good view kept). Python's cyclic garbage collector waits until
        the figures and the status are sent (:func:`collector_after`).
        """
        names = set(self.controls) if changed is None else set(changed)
        start = time.perf_counter()
        with collector_after():
            try:
                with detached():
                    self.refresh(names)
            except NavlibInputError as exc:
                self._done(error_html(self.error_prefix, exc))
                return False
            except Exception as exc:
                self._done(f'<b class="navlib-panel-error" style="color:#b00">'
                           f'{html.escape(type(exc).__name__)}:</b> {html.escape(str(exc))}')
                raise
            self.last_timing["total_ms"] = 1e3 * (time.perf_counter() - start)
            self._done(self.status.value, self.last_timing["total_ms"])
            return True

    def _done(self, status: str, total_ms: float | None = None) -> None:
        self.updates += 1
        ms = "" if total_ms is None else f' data-ms="{total_ms:.1f}"'
        self.status.value = (_MARK.sub("", status) + f'<span class="navlib-update" '
                             f'data-count="{self.updates}"{ms} hidden></span>')

    def refresh(self, changed: set) -> None:
        """Recompute what the controls in ``changed`` touch and :meth:`show` it."""
        raise NotImplementedError

    def show(self, name: str, content) -> None:
        """Put ``content`` on show as part ``name``.

        ``content``: a detached Figure (rendered to PNG at ``dpi``), a :class:`Blitter`
        (its current PNG), PNG bytes, a DataFrame (HTML table), an HTML string, or None
        (the part is hidden).

        Parameters
        ----------
        name : str
            Part name.
        content : Figure, Blitter, bytes, pandas.DataFrame, str or None
            What to show.
        """
        if content is None:
            if name in self.parts:
                self.parts[name].layout.display = "none"
            return
        if isinstance(content, Figure):
            content = self.figures.render(name, content, self.dpi)
        elif isinstance(content, Blitter):
            content = content.png()
        elif isinstance(content, pd.DataFrame):
            content = table_html(content)
        kind = widgets.Image if isinstance(content, bytes) else widgets.HTML
        part = self.parts.get(name)
        if part is None or not isinstance(part, kind):
            part = kind(format="png") if kind is widgets.Image else kind()
            part.add_class(f"navlib-part-{name}")
            self.parts[name] = part
            self.view.children = tuple(self.parts.values())
        part.value = content
        part.layout.display = None
