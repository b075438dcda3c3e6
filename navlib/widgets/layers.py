"""Kept panel figures drawn in layers: each axes' frame rasterised once, the data on top.

Moving a slider changes a panel figure's data, rarely its frames: the axes' background,
grid, ticks, tick labels, axis labels and titles cost 80-90 % of drawing a figure with Agg
(the SSAC sigma figure: 135 of 160 ms, of which its lines take 5), and they depend only on
the axes' limits, scales, tickers, texts and the artists drawn under the grid.
:class:`LayeredFigure` keeps the figure rasterised without its data artists (lines,
spines, texts, legends: everything from the lines' z-order up) and, per update, draws again
only the frames of axes whose :func:`frame_key` changed, then the data of every axes on
top, in the z-order a full draw uses: the image equals a full draw of the figure.

Before each update a kept figure's limits are snapped to its ticks and its "best" legends
placed (:mod:`navlib.widgets.panel_layout`).
"""

from __future__ import annotations

import hashlib
import io

import numpy as np
from matplotlib.axes._secondary_axes import SecondaryAxis
from matplotlib.axis import Axis
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import Collection
from matplotlib.figure import Figure
from matplotlib.font_manager import fontManager, get_font
from matplotlib.image import AxesImage
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.text import Text
from matplotlib.ticker import FixedFormatter, FixedLocator
from matplotlib.transforms import Bbox

from navlib.widgets.panel_layout import EDGE_ROOM_PT, freeze_decorations, place_legend, snap_limits

__all__ = ["FontHeights", "LayeredFigure", "agg_canvas", "data_artists", "encode_png", "frame_key"]


def encode_png(rgba) -> bytes:
    """PNG bytes of an Agg RGBA buffer: RGB only (figures are opaque) and light zlib
    compression, which halves the encoding time of the default settings.

    Parameters
    ----------
    rgba : array_like (height, width, 4)
        An Agg canvas' ``buffer_rgba()``.

    Returns
    -------
    bytes
    """
    from PIL import Image  # pillow ships with matplotlib

    buffer = io.BytesIO()
    rgb = np.ascontiguousarray(np.asarray(rgba)[..., :3])
    Image.fromarray(rgb).save(buffer, format="png", compress_level=1)
    return buffer.getvalue()


def agg_canvas(fig: Figure) -> FigureCanvasAgg:
    """The Agg canvas of ``fig`` (its own, or a new one attached to it).

    Parameters
    ----------
    fig : matplotlib.figure.Figure

    Returns
    -------
    matplotlib.backends.backend_agg.FigureCanvasAgg
    """
    return fig.canvas if isinstance(fig.canvas, FigureCanvasAgg) else FigureCanvasAgg(fig)


def _digest(*arrays) -> str:
    h = hashlib.blake2b(digest_size=12)
    for a in arrays:
        h.update(np.ascontiguousarray(np.asarray(a, dtype=float)).tobytes())
    return h.hexdigest()


def _artist_key(artist):
    """What a frame artist (drawn under the data) looks like, or a fresh object (never
    equal) for a kind this module does not read."""
    common = (type(artist).__name__, artist.get_visible(), artist.get_alpha(),
              artist.get_zorder())
    if isinstance(artist, Patch):
        return (*common, _digest(artist.get_path().vertices,
                                 artist.get_patch_transform().get_matrix(),
                                 artist.get_facecolor(), artist.get_edgecolor()))
    if isinstance(artist, Collection):
        paths = artist.get_paths()
        return (*common, len(paths),
                _digest(*(p.vertices for p in paths), artist.get_offsets(),
                        artist.get_facecolor(), artist.get_edgecolor(),
                        artist.get_linewidths()))
    if isinstance(artist, Line2D):
        return (*common, _digest(artist.get_xydata()), artist.get_color(),
                artist.get_linestyle(), artist.get_linewidth(), artist.get_marker())
    if isinstance(artist, Text):
        return (*common, artist.get_text(), artist.get_position(), artist.get_color())
    if isinstance(artist, AxesImage):
        return (*common, _digest(artist.get_array()), artist.get_extent())
    if isinstance(artist, SecondaryAxis):  # placed on its parent, its limits follow theirs
        tickers = (t for axis in (artist.xaxis, artist.yaxis)
                   for t in (axis.get_major_locator(), axis.get_major_formatter()))
        return (*common, artist.get_xlabel(), artist.get_ylabel(), *map(_ticker, tickers))
    return object()


def _ticker(ticker):
    """A tick locator or formatter by its kind, and its ticks or labels when they are
    fixed (a formatter's other state follows from the limits)."""
    if isinstance(ticker, FixedLocator):
        return ("FixedLocator", tuple(np.ravel(ticker.locs)))
    if isinstance(ticker, FixedFormatter):
        return ("FixedFormatter", tuple(ticker.seq))
    return (type(ticker).__name__,)


def _data_zorder(ax) -> float:
    """The z-order from which an axes' artists are data: above its x and y axes (ticks,
    grid, tick labels), which a full draw puts under the lines (``axes.axisbelow``). Even
    without a grid, an artist under the axes is frame: the tick marks start on the plot
    area's edge pixels."""
    return max(ax.xaxis.get_zorder(), ax.yaxis.get_zorder())


def _layered_children(ax) -> list:
    """The artists of ``ax`` that are frame or data: all but its patch, its x and y axes
    and its titles (always frame)."""
    titles = {ax.title, ax._left_title, ax._right_title}
    return [a for a in ax.get_children()
            if a is not ax.patch and not isinstance(a, Axis) and a not in titles]


def _is_data(ax, artist) -> bool:
    return artist.get_zorder() > _data_zorder(ax) or artist in ax.spines.values()


def _frame_artists(ax) -> list:
    return [a for a in _layered_children(ax) if not _is_data(ax, a)]


def data_artists(ax, framed=()) -> list:
    """The artists of ``ax`` drawn over its frame at every update: lines, spines, texts and
    the legend (z-order above the axes' ticks and grid), in drawing order.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    framed : collection of matplotlib.legend.Legend, optional
        Legends drawn with the frame instead (no data under them).

    Returns
    -------
    list of matplotlib.artist.Artist
    """
    found = [a for a in _layered_children(ax) if a not in framed and _is_data(ax, a)]
    return sorted(found, key=lambda a: a.get_zorder())


def frame_key(ax, framed=()) -> tuple:
    """What the frame of ``ax`` (patch, grid, ticks and their labels, axis labels, titles,
    the artists under the grid, a legend in ``framed``) depends on: equal keys draw equal
    frames. Its first entry holds the keys of the x axis, the y axis and the titles, and
    of what they all depend on (place, visibility).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    framed : collection of matplotlib.legend.Legend, optional
        Legends drawn with the frame.

    Returns
    -------
    tuple
    """
    legend = ax.get_legend()
    return (_side_keys(ax), tuple(_artist_key(a) for a in _frame_artists(ax)),
            None if legend not in framed else
            (str(legend._get_loc()), tuple(t.get_text() for t in legend.get_texts())))


SIDES = ("x", "y", "title")
"""The parts of a frame outside its plot area: the x and y axes' tick labels, offset texts
and labels, and the titles."""


def _axis_key(ax, axis) -> tuple:
    """What the tick labels, offset text and label of ``axis`` (of ``ax``) look like and
    where they are: equal keys, equal texts in equal places."""
    return (tuple(ax.get_position().bounds), tuple(axis.get_view_interval()),
            axis.get_scale(), axis.label.get_text(), axis.get_label_position(),
            axis.get_ticks_position(),
            *(_ticker(t) for t in (axis.get_major_locator(), axis.get_major_formatter(),
                                   axis.get_minor_locator(), axis.get_minor_formatter())))


def _side_keys(ax) -> dict:
    """The key of each of the :data:`SIDES` of the frame of ``ax``, and under ``"base"``
    what all of them depend on (place, visibility)."""
    return {"base": (tuple(ax.get_position().bounds), ax.get_visible(), ax.axison),
            "x": _axis_key(ax, ax.xaxis), "y": _axis_key(ax, ax.yaxis),
            "title": tuple(ax.get_title(loc) for loc in ("left", "center", "right"))}


def _side_texts(ax, side: str) -> list:
    """The texts one of the :data:`SIDES` of ``ax`` draws: the tick labels in view, the
    axis label and offset text, or the titles (visible, not empty)."""
    if side == "title":
        texts = [ax.title, ax._left_title, ax._right_title]
    elif not ax.axison:
        texts = []
    else:
        texts = _axis_texts(ax.xaxis if side == "x" else ax.yaxis)
    return [t for t in texts if t.get_visible() and t.get_text()]


def _keeps_clear_of_its_sides(ax) -> bool:
    """Whether every frame artist of ``ax`` is clipped to its plot area, so that redrawing
    the plot area and some of its sides touches nothing outside them."""
    return not ax.child_axes and all(
        a.get_clip_on() and (a.get_clip_box() is not None or a.get_clip_path() is not None)
        for a in _frame_artists(ax))


def _meet(rects, others) -> bool:
    """Whether any of the pixel rectangles ``(x0, top, x1, bottom)`` in ``rects`` shares a
    pixel with any in ``others``."""
    return any(a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]
               for a in rects for b in others)


def _figure_key(fig: Figure) -> tuple:
    texts = [getattr(fig, n, None) for n in ("_suptitle", "_supxlabel", "_supylabel")]
    return (tuple(fig.get_size_inches()), fig.dpi, len(fig.axes),
            tuple(None if t is None else (t.get_text(), t.get_position()) for t in texts),
            tuple(_artist_key(a) for a in (*fig.texts, *fig.lines, *fig.patches,
                                           *fig.images, *fig.legends)))


def _axis_texts(axis) -> list:
    """The tick labels in view of an axis as it drew them last, its label and offset text
    (what ``Axis.get_tightbbox`` measures, without placing the ticks again)."""
    if not axis.get_visible():
        return []
    scale = axis.get_transform()
    low, high = sorted(scale.transform(axis.get_view_interval()))
    room = 1e-9 * (high - low)
    texts = [axis.label, axis.offsetText]
    for ticks, locs in ((axis.majorTicks, axis.get_majorticklocs()),
                        (axis.minorTicks, axis.get_minorticklocs())):
        for tick, loc in zip(ticks, locs, strict=False):
            if low - room <= scale.transform(loc) <= high + room:
                texts += [tick.label1, tick.label2]
    return texts


class FontHeights:
    """A font's line metrics (ascent, descent, line gap in pixels), as matplotlib 3.11's
    ``Text._get_layout`` computes them from the font's OS/2 or hhea table, once per font
    and size.

    ``Text._get_layout`` reads them again for every text it lays out (a font lookup and
    two table reads: a fifth of the SSAC sigma frame's text layout) unless the renderer
    offers ``_get_font_height_metrics``, as matplotlib's PDF and PS renderers do.
    :class:`LayeredFigure` gives its Agg renderer an instance. Earlier versions of
    matplotlib do not ask for it, and the images are the same either way (test).

    Parameters
    ----------
    dpi : float
        The renderer's (and figure's) resolution.
    """

    def __init__(self, dpi: float):
        self.dpi = dpi
        self.known: dict = {}

    def __call__(self, prop) -> tuple:
        """(ascent, descent, line gap) of the font of ``prop``, or Nones when it has neither
        table (matplotlib then measures a sample text)."""
        found = self.known.get(hash(prop))
        if found is not None and found[0] == prop:
            return found[1]
        font = get_font(fontManager._find_fonts_by_props(prop))
        metrics = (None, None, None)
        for name, gap, ascent, descent in (("OS/2", "sTypoLineGap", "sTypoAscender",
                                            "sTypoDescender"),
                                           ("hhea", "lineGap", "ascent", "descent")):
            table = font.get_sfnt_table(name)
            if table is not None:  # the same operations, in the same order, as matplotlib
                scale = 1 / font.get_sfnt_table("head")["unitsPerEm"] \
                    * prop.get_size_in_points() * self.dpi / 72
                metrics = (table[ascent] * scale, -table[descent] * scale, table[gap] * scale)
                break
        self.known[hash(prop)] = (prop.copy(), metrics)
        return metrics


class LayeredFigure:
    """A detached figure rendered to PNG with its axes' frames kept between updates.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        A detached figure; a layout engine, if any, runs in the first :meth:`png` and is
        then switched off (the layout is frozen, as for every kept panel figure).
    dpi : float

    Notes
    -----
    Axes whose frames' regions (plot area, ticks, tick and axis labels, titles) overlap
    are one group and redrawn together; a figure whose plot areas overlap (twin or inset
    axes), whose figure texts change, or whose redrawn frame grows into a neighbour is
    drawn in full.
    """

    def __init__(self, fig: Figure, dpi: float = 72.0):
        self.fig = fig
        fig.set_dpi(dpi)
        self.canvas = agg_canvas(fig)
        self.background = None
        self.blank = None
        self.keys: list = []
        self.boxes: list = []
        self.figure_key = None
        self.regions: list = []
        self.full_draws = 0
        self.frame_draws = 0
        self.partial_draws = 0
        self.best_legends = [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None
                             and ax.get_legend()._get_loc() == 0]  # 0: "best"
        self.framed: dict = {}

    def _hide_data(self, hidden: bool) -> None:
        for ax in self.fig.axes:
            for artist in data_artists(ax, self.framed):
                artist.set_animated(hidden)

    @staticmethod
    def _plot_box(ax, renderer) -> Bbox:
        """The plot area of ``ax`` with its outward tick marks, on the edges they are on."""
        out = dict.fromkeys(("left", "bottom", "right", "top"), 0.0)
        for axis, edges in ((ax.xaxis, ("bottom", "top")), (ax.yaxis, ("left", "right"))):
            for tick in (*axis.majorTicks[:1], *axis.minorTicks[:1]):
                for line, edge in zip((tick.tick1line, tick.tick2line), edges, strict=True):
                    if line.get_visible():
                        out[edge] = max(out[edge], tick.get_tick_padding())
        px = {edge: renderer.points_to_pixels(v) for edge, v in out.items()}
        box = ax.bbox
        return Bbox.from_extents(box.x0 - px["left"], box.y0 - px["bottom"],
                                 box.x1 + px["right"], box.y1 + px["top"])

    def _boxes(self, ax, renderer, sides=SIDES) -> dict:
        """The extent of each text of ``sides`` of ``ax`` as its last draw put it
        (side -> {text: Bbox}), and under ``"other"`` those of a framed legend and of a
        secondary axis' ticks and labels (a list)."""
        boxes = {side: {t: t.get_window_extent(renderer) for t in _side_texts(ax, side)}
                 for side in sides}
        texts = [t for child in ax.child_axes if child.get_visible() and child.axison
                 for axis in (child.xaxis, child.yaxis) for t in _axis_texts(axis)
                 if t.get_visible() and t.get_text()]
        boxes["other"] = [t.get_window_extent(renderer) for t in texts]
        if ax.get_legend() in self.framed:
            boxes["other"].append(self.framed[ax.get_legend()])
        return boxes

    def _region(self, ax, boxes: dict, renderer) -> Bbox:
        """Everything the frame of ``ax`` draws: its plot area, ticks and ``boxes``, with
        room for the spines' half width and the antialiasing of edges and glyphs."""
        found = [self._plot_box(ax, renderer), *boxes["other"],
                 *(b for side in SIDES for b in boxes[side].values())]
        return Bbox.union([b for b in found if b is not None and b.width > 0]).padded(
            renderer.points_to_pixels(EDGE_ROOM_PT))

    def _layered(self) -> bool:
        """Whether each axes' plot area and spines keep clear of the other axes' frames
        (no twin or inset axes, no tick label against a neighbour's spine), so that
        drawing every frame before every axes' data gives the image of a full draw."""
        renderer = self.canvas.get_renderer()
        room = renderer.points_to_pixels(EDGE_ROOM_PT)
        axes = self.fig.axes
        return not any(i != j and axes[i].get_visible() and axes[j].get_visible()
                       and axes[i].bbox.padded(room).overlaps(self.regions[j])
                       for i in range(len(axes)) for j in range(len(axes)))

    def _draw_all_frames(self) -> None:
        renderer = self.canvas.get_renderer()
        renderer.clear()
        self.fig.patch.draw(renderer)
        self.blank = self.canvas.copy_from_bbox(self.fig.bbox)
        self._hide_data(True)
        try:
            self.canvas.draw()
        finally:
            self._hide_data(False)
        if self.background is None:
            freeze_decorations(self.fig)
        self.background = self.canvas.copy_from_bbox(self.fig.bbox)
        self.boxes = [self._boxes(ax, renderer) for ax in self.fig.axes]
        self.regions = [self._region(ax, b, renderer) for ax, b in zip(self.fig.axes, self.boxes,
                                                                        strict=True)]
        self.full_draws += 1

    def _figure_boxes(self, renderer) -> list:
        texts = [getattr(self.fig, n, None) for n in ("_suptitle", "_supxlabel", "_supylabel")]
        return [t.get_window_extent(renderer) for t in (*texts, *self.fig.texts)
                if t is not None and t.get_visible() and t.get_text()]

    def _pixels(self, box: Bbox) -> tuple:
        height = self.fig.bbox.height
        x0, x1 = int(np.floor(box.x0)), int(np.ceil(box.x1))
        top, bottom = int(np.floor(height - box.y1)), int(np.ceil(height - box.y0))
        return x0, top, x1, bottom

    def _group(self, changed: list) -> set:
        """``changed`` and the axes whose regions meet theirs, until none is added."""
        group = set(changed)
        grown = True
        while grown:
            grown = False
            for i in range(len(self.fig.axes)):
                if i not in group and any(self.regions[i].overlaps(self.regions[j])
                                          for j in group):
                    group.add(i)
                    grown = True
        return group

    def _kept_sides(self, group: set, sides: dict) -> dict:
        """Per axes of ``group``, the :data:`SIDES` whose keys did not change, when the
        rest of its frame can be redrawn without their texts; titles only where they stay
        put (:func:`~navlib.widgets.panel_layout.freeze_decorations`: matplotlib places
        the others at each draw, from decorations of the other sides)."""
        axes, old = self.fig.axes, [key[0] for key in self.keys]
        return {i: tuple(side for side in SIDES if sides[i][side] == old[i][side]
                         and (side != "title" or axes[i]._autotitlepos is False))
                if sides[i]["base"] == old[i]["base"]
                and _keeps_clear_of_its_sides(axes[i]) else () for i in group}

    def _ink(self, box: Bbox) -> tuple:
        """The pixels a text whose box is ``box`` may colour: its box rounded out to whole
        pixels and one more on each side (a descender or a superscript of DejaVu reaches one
        pixel past its layout box)."""
        x0, top, x1, bottom = self._pixels(box)
        return x0 - 1, top - 1, x1 + 1, bottom + 1

    def _bands(self, i: int, sides) -> list:
        """Pixel rectangles that the new texts of the x and y axes among ``sides`` of axes
        ``i`` are expected in: the rows (x) or columns (y) of the old ones, across the axes'
        region. New limits move tick labels along their axis, not across it; the check
        after the draw catches a text outside."""
        x0, top, x1, bottom = self._pixels(self.regions[i])
        bands = []
        for side in sides:
            rects = [self._ink(b) for b in self.boxes[i][side].values()]
            if rects and side == "x":
                bands.append((x0, min(r[1] for r in rects), x1, max(r[3] for r in rects)))
            elif rects:
                bands.append((min(r[0] for r in rects), top, max(r[2] for r in rects), bottom))
        return bands

    def _plan(self, group: set, sides: dict, renderer) -> tuple:
        """(pixel rectangles to clear, {kept text: its pixels}) of the axes in ``group``,
        whose sides' keys are now ``sides``.

        An axes whose side keys all changed, or which cannot be redrawn in parts, clears
        its whole region. The others clear their plot area (with room for antialiased
        edges), the old places of their changed sides' texts and the bands of the new ones
        (:meth:`_bands`), and keep the texts of their unchanged sides, but for those that
        meet a cleared place: these are cleared and drawn again too."""
        room = renderer.points_to_pixels(EDGE_ROOM_PT)
        kept = self._kept_sides(group, sides)
        zones, keep = [], {}
        for i in group:
            ax, boxes = self.fig.axes[i], self.boxes[i]
            zones += self._bands(i, [s for s in ("x", "y") if sides[i][s] != self.keys[i][0][s]])
            if not kept[i]:
                zones.append(self._pixels(self.regions[i]))
                continue
            zones.append(self._pixels(self._plot_box(ax, renderer).padded(room)))
            zones += [self._ink(b) for b in boxes["other"]]
            for side in SIDES:
                rects = {t: self._ink(b) for t, b in boxes[side].items()}
                if side in kept[i]:
                    keep.update(rects)
                else:
                    zones += rects.values()
        crowded = True
        while crowded:
            crowded = [t for t, rect in keep.items() if _meet(zones, [rect])]
            zones += [keep.pop(t) for t in crowded]
        return zones, keep

    def _draw_changed_frames(self, changed: list, keys: list) -> bool:
        """Clear and draw again the frames of the axes in ``changed`` (and of those whose
        regions meet theirs), whose frame keys are now ``keys``, on the kept background;
        False when a frame grew into another one, a kept text or a figure text (the caller
        then draws everything).

        The texts of a frame's unchanged sides (x axis, y axis, titles) are kept where no
        cleared place meets them (:meth:`_plan`): about half of a frame's drawing when new
        x limits leave the y tick labels as they were."""
        axes = self.fig.axes
        group = self._group(changed)
        renderer = self.canvas.get_renderer()
        sides = {i: keys[i][0] for i in group}
        zones, keep = self._plan(group, sides, renderer)
        self.canvas.restore_region(self.background)
        for rect in zones:  # xy is Agg's offset of the copy, not its place
            self.canvas.restore_region(self.blank, bbox=rect, xy=(0, 0))
        # an axis label stays where the last draw put it when its tick labels are the same
        fixed = [axis for i in group for side, axis in (("x", axes[i].xaxis),
                                                        ("y", axes[i].yaxis))
                 if axis._autolabelpos and sides[i][side] == self.keys[i][0][side]]
        self._hide_data(True)
        for text in keep:
            text.set_visible(False)
        for axis in fixed:
            axis._autolabelpos = False
        try:
            for i in sorted(group, key=lambda i: axes[i].get_zorder()):
                axes[i].draw(renderer)
        finally:
            self._hide_data(False)
            for text in keep:
                text.set_visible(True)
            for axis in fixed:
                axis._autolabelpos = True
        others = [self.regions[i] for i in range(len(axes)) if i not in group]
        others += self._figure_boxes(renderer)
        room = renderer.points_to_pixels(EDGE_ROOM_PT)
        for i in group:
            boxes = self._boxes(axes[i], renderer, [s for s in SIDES if not any(
                t in keep for t in self.boxes[i][s])])
            boxes = {**{s: self.boxes[i][s] for s in SIDES}, **boxes}
            region = self._region(axes[i], boxes, renderer)
            drawn = [self._ink(b) for side in SIDES for t, b in boxes[side].items()
                     if t not in keep] + [self._ink(b) for b in boxes["other"]]
            drawn.append(self._pixels(self._plot_box(axes[i], renderer).padded(room)))
            if any(region.overlaps(b) for b in others) or _meet(drawn, keep.values()):
                return False
            self.boxes[i], self.regions[i] = boxes, region
        self.background = self.canvas.copy_from_bbox(self.fig.bbox)
        self.frame_draws += len(group)
        self.partial_draws += sum(any(t in keep for s in SIDES for t in self.boxes[i][s])
                                  for i in group)
        return True

    def png(self) -> bytes:
        """The figure as PNG bytes, its frames drawn again only where their keys changed."""
        renderer = self.canvas.get_renderer()
        if not hasattr(renderer, "_get_font_height_metrics"):
            renderer._get_font_height_metrics = FontHeights(renderer.dpi)
        engine = self.fig.get_layout_engine()
        if engine is not None:  # the first time: lay out, then keep the layout
            engine.execute(self.fig)
            self.fig.set_layout_engine("none")
        snap_limits(self.fig)  # with the ticks of the laid-out axes
        places = {legend: place_legend(legend, renderer) for legend in self.best_legends}
        self.framed = {legend: place for legend, place in places.items() if place is not None}
        keys = [frame_key(ax, self.framed) for ax in self.fig.axes]
        figure_key = _figure_key(self.fig)
        if (self.background is None or figure_key != self.figure_key
                or len(keys) != len(self.keys)):
            self._draw_all_frames()
        else:
            changed = [i for i, (a, b) in enumerate(zip(keys, self.keys, strict=True)) if a != b]
            if changed and not self._draw_changed_frames(changed, keys):
                self._draw_all_frames()
        self.keys, self.figure_key = keys, figure_key
        if not self._layered():  # a full draw interleaves the axes' frames and data
            self.canvas.draw()
            return encode_png(self.canvas.buffer_rgba())
        self.canvas.restore_region(self.background)
        for ax in self.fig.axes:
            if ax.get_visible():
                for artist in data_artists(ax, self.framed):
                    artist.draw(renderer)
        return encode_png(self.canvas.buffer_rgba())
