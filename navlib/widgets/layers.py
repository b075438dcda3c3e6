"""Kept panel figures drawn in layers: each axes' frame rasterised once, the data on top.

Moving a slider changes a panel figure's data, rarely its frames: the axes' background,
grid, ticks, tick labels, axis labels and titles cost 80-90 % of drawing a figure with Agg
(the SSAC sigma figure: 135 of 160 ms, of which its lines take 5), and they depend only on
the axes' limits, scales, tickers, texts and the artists drawn under the grid.
:class:`LayeredFigure` keeps the figure rasterised without its data artists (lines,
spines, texts, legends: everything from the lines' z-order up) and, per update, draws again
only the frames of axes whose :func:`frame_key` changed, then the data of every axes on
top, in the z-order a full draw uses: the image equals a full draw of the figure.

:func:`snap_limits` rounds an autoscaled axis outward to its ticks (matplotlib's
``round_numbers`` autolimit mode) in kept panel figures, so a small data change keeps the
frame (docs/assumptions.md, "Panel figures").
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
from matplotlib.image import AxesImage
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.text import Text
from matplotlib.ticker import FixedFormatter, FixedLocator
from matplotlib.transforms import Bbox

__all__ = ["LayeredFigure", "agg_canvas", "data_artists", "encode_png", "frame_key",
           "freeze_decorations", "place_legend", "snap_limits"]


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


EDGE_ROOM_PT = 1.2
"""Room for a drawn edge's width and antialiasing, in points: around a legend's box, where
no line may pass and no spine lie for the legend to be drawn with the frame, and around a
plot area, which no other axes' frame may enter for the figure to be drawn in layers."""


def snap_limits(fig: Figure) -> None:
    """Set each autoscaled axis of ``fig`` to its data's span rounded outward to the
    nearest ticks of its locator (no margins).

    Axes whose limits were set by their builder (``set_xlim`` turns autoscaling off) keep
    them. Data spanning 0.0200-0.0287 with ticks every 0.002 get 0.020-0.030; a log axis
    snaps to its (decade) ticks. Call it before the figure's data move into a kept one:
    it reads the data limits of the figure's own artists.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    """
    for ax in fig.axes:
        for axis, auto, set_lim in ((ax.xaxis, ax.get_autoscalex_on(), ax.set_xlim),
                                    (ax.yaxis, ax.get_autoscaley_on(), ax.set_ylim)):
            if not auto:
                continue
            low, high = sorted(axis.get_data_interval())
            if not (np.isfinite(low) and np.isfinite(high) and high > low):
                continue
            if axis.get_scale() == "log" and low <= 0:
                low = axis.get_minpos()
            ticks = np.asarray(axis.get_major_locator().tick_values(low, high), float)
            below, above = ticks[ticks <= low], ticks[ticks >= high]
            if below.size and above.size and below.max() < above.min():
                lo, hi = below.max(), above.min()
                if axis.get_scale() != "log" or lo > 0:
                    set_lim(*((hi, lo) if axis.get_inverted() else (lo, hi)), auto=True)


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
    frames.

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
    return (tuple(ax.get_position().bounds), ax.get_visible(), ax.axison,
            ax.get_xlim(), ax.get_ylim(), ax.get_xscale(), ax.get_yscale(),
            ax.get_xlabel(), ax.get_ylabel(),
            tuple(ax.get_title(loc) for loc in ("left", "center", "right")),
            tuple(_ticker(t) for axis in (ax.xaxis, ax.yaxis)
                  for t in (axis.get_major_locator(), axis.get_major_formatter(),
                            axis.get_minor_locator(), axis.get_minor_formatter())),
            tuple(_artist_key(a) for a in _frame_artists(ax)),
            None if legend not in framed else
            (str(legend._get_loc()), tuple(t.get_text() for t in legend.get_texts())))


def _y_key(ax) -> tuple:
    """What the place of the y label of ``ax`` depends on (matplotlib puts it beside the
    extents of the y tick labels and the spine): equal keys, equal places. A frame redrawn
    because only its x axis changed then keeps its y label where it was instead of measuring
    the y tick labels again (about 6 ms an axes)."""
    axis = ax.yaxis
    return (tuple(ax.get_position().bounds), ax.get_ylim(), ax.get_yscale(), ax.get_ylabel(),
            axis.get_label_position(), axis.get_ticks_position(),
            *(_ticker(t) for t in (axis.get_major_locator(), axis.get_major_formatter(),
                                   axis.get_minor_locator(), axis.get_minor_formatter())))


def _figure_key(fig: Figure) -> tuple:
    texts = [getattr(fig, n, None) for n in ("_suptitle", "_supxlabel", "_supylabel")]
    return (tuple(fig.get_size_inches()), fig.dpi, len(fig.axes),
            tuple(None if t is None else (t.get_text(), t.get_position()) for t in texts),
            tuple(_artist_key(a) for a in (*fig.texts, *fig.lines, *fig.patches,
                                           *fig.images, *fig.legends)))


def _data_points(ax) -> np.ndarray:
    """Display coordinates of the vertices of the lines, patches and collections of
    ``ax`` (what ``loc="best"`` keeps a legend off)."""
    points = [np.empty((0, 2))]
    for artist in (*ax.lines, *ax.patches, *ax.collections):
        if not artist.get_visible():
            continue
        if isinstance(artist, Line2D):
            points.append(artist.get_transform().transform(artist.get_xydata()))
        elif isinstance(artist, Patch):
            points.append(artist.get_transform().transform_path(artist.get_path()).vertices)
        else:
            transform = artist.get_transform()
            points += [transform.transform_path(path).vertices for path in artist.get_paths()]
            if len(artist.get_offsets()):
                points.append(artist.get_offset_transform().transform(artist.get_offsets()))
    found = np.concatenate(points)
    return found[np.isfinite(found).all(axis=1)]


def place_legend(legend, renderer) -> bool:
    """Put an axes legend at the standard location (``loc`` codes 1-10, as "best" tries
    them) that covers the fewest data points, the first one on a tie; True when no data
    lies under it there (no vertex, no line crossing it, no patch or collection in its
    axes).

    matplotlib's "best" also tests each line's segments against each candidate, which
    takes 45 of 112 ms of the SSAC eigenvalue figure (15 lines of 3601 points); counting
    the vertices costs a few milliseconds, and only the chosen place is tested for
    crossing lines.

    Parameters
    ----------
    legend : matplotlib.legend.Legend
        A legend of an axes.
    renderer : matplotlib.backend_bases.RendererBase

    Returns
    -------
    bool
    """
    ax = legend.axes
    points = _data_points(ax)
    box = legend.get_window_extent(renderer)
    size = Bbox.from_bounds(0, 0, box.width, box.height)
    anchor = legend.get_bbox_to_anchor()
    best = None
    for code in range(1, len(legend.codes)):
        left, bottom = legend._get_anchored_bbox(code, size, anchor, renderer)
        inside = int(np.count_nonzero((points[:, 0] >= left) & (points[:, 0] <= left + box.width)
                                      & (points[:, 1] >= bottom)
                                      & (points[:, 1] <= bottom + box.height)))
        if best is None or inside < best[0]:
            best = (inside, code, Bbox.from_bounds(left, bottom, box.width, box.height))
        if inside == 0:
            break
    inside, code, place = best
    legend.set_loc(code)
    if inside or ax.patches or ax.collections:
        return False
    room = renderer.points_to_pixels(EDGE_ROOM_PT)
    place, inner = place.padded(room), ax.bbox.padded(-room)
    if not (inner.contains(place.x0, place.y0) and inner.contains(place.x1, place.y1)):
        return False  # it would meet the spines, drawn over the frame
    return not any(line.get_visible() and line.get_transform().transform_path(
        line.get_path()).intersects_bbox(place, filled=False) for line in ax.lines)


def _axis_boxes(axis, renderer) -> list:
    """Extents of the tick labels an axis drew last, its label and offset text (what
    ``Axis.get_tightbbox`` measures, without placing the ticks again)."""
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
    return [t.get_window_extent(renderer) for t in texts if t.get_visible() and t.get_text()]


def freeze_decorations(fig: Figure) -> None:
    """Keep the titles and x-axis labels of a drawn figure where they are.

    matplotlib places them at every draw from the tick labels' extents (the x label under
    the tallest, the title over any top decoration): about a quarter of the time to draw
    the SSAC sigma figure (38 of 161 ms). In a kept figure (frozen layout, same fonts)
    their places do not change, unless an axes has its x ticks or label on top (then left
    to matplotlib). The y labels stay automatic: tick labels change width with the limits.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        A figure drawn at least once.
    """
    for ax in fig.axes:
        label = ax.xaxis.label
        if ax.xaxis.get_label_position() == "top" or \
                ax.xaxis.get_ticks_position() in ("top", "unknown"):
            continue
        ax._autotitlepos = False
        where = label.get_transform().transform(label.get_position())
        ax.xaxis.set_label_coords(*ax.transAxes.inverted().transform(where))


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
        self.y_keys: list = []
        self.figure_key = None
        self.regions: list = []
        self.full_draws = 0
        self.frame_draws = 0
        self.best_legends = [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None
                             and ax.get_legend()._get_loc() == 0]  # 0: "best"
        self.framed: set = set()

    def _hide_data(self, hidden: bool) -> None:
        for ax in self.fig.axes:
            for artist in data_artists(ax, self.framed):
                artist.set_animated(hidden)

    def _region(self, ax, renderer) -> Bbox:
        ticks = [t for axis in (ax.xaxis, ax.yaxis) for t in (*axis.majorTicks[:1],
                                                              *axis.minorTicks[:1])]
        outside = max((t.get_tick_padding() for t in ticks), default=0.0)  # outward marks
        boxes = [ax.bbox.padded(renderer.points_to_pixels(outside))]
        if ax.axison:
            boxes += [box for axis in (ax.xaxis, ax.yaxis) for box in _axis_boxes(axis, renderer)]
        for child in ax.child_axes:  # a secondary axis' ticks and labels (part of the frame)
            if child.get_visible() and child.axison:
                boxes += [box for axis in (child.xaxis, child.yaxis)
                          for box in _axis_boxes(axis, renderer)]
        boxes += [t.get_window_extent(renderer) for t in (ax.title, ax._left_title,
                                                          ax._right_title) if t.get_text()]
        if ax.get_legend() in self.framed:
            boxes.append(ax.get_legend().get_window_extent(renderer))
        # the spines' half width and the antialiasing of edges and glyphs
        return Bbox.union([b for b in boxes if b is not None and b.width > 0]).padded(
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
        self.regions = [self._region(ax, renderer) for ax in self.fig.axes]
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

    def _draw_changed_frames(self, changed: list) -> bool:
        """Clear and draw again the frames of the axes in ``changed`` (and of those whose
        regions meet theirs) on the kept background; False when a frame grew into another
        one or a figure text (the caller then draws everything)."""
        axes = self.fig.axes
        group = set(changed)
        grown = True
        while grown:  # the axes whose regions meet a redrawn one are redrawn with it
            grown = False
            for i in range(len(axes)):
                if i not in group and any(self.regions[i].overlaps(self.regions[j])
                                          for j in group):
                    group.add(i)
                    grown = True
        renderer = self.canvas.get_renderer()
        self.canvas.restore_region(self.background)
        for i in group:
            x0, top, x1, bottom = self._pixels(self.regions[i])
            # xy is Agg's offset of the copy, not its place
            self.canvas.restore_region(self.blank, bbox=(x0, top, x1, bottom), xy=(0, 0))
        self._hide_data(True)
        kept = [axes[i].yaxis for i in group if axes[i].yaxis._autolabelpos
                and self.y_keys[i] == _y_key(axes[i])]
        for axis in kept:  # the y label where the last draw put it (same tick labels)
            axis._autolabelpos = False
        try:
            for i in sorted(group, key=lambda i: axes[i].get_zorder()):
                axes[i].draw(renderer)
        finally:
            self._hide_data(False)
            for axis in kept:
                axis._autolabelpos = True
        others = [self.regions[i] for i in range(len(axes)) if i not in group]
        others += self._figure_boxes(renderer)
        for i in group:
            region = self._region(axes[i], renderer)
            if any(region.overlaps(b) for b in others):
                return False
            self.regions[i] = region
        self.background = self.canvas.copy_from_bbox(self.fig.bbox)
        self.frame_draws += len(group)
        return True

    def png(self) -> bytes:
        """The figure as PNG bytes, its frames drawn again only where their keys changed."""
        renderer = self.canvas.get_renderer()
        engine = self.fig.get_layout_engine()
        if engine is not None:  # the first time: lay out, then keep the layout
            engine.execute(self.fig)
            self.fig.set_layout_engine("none")
        snap_limits(self.fig)  # with the ticks of the laid-out axes
        self.framed = {legend for legend in self.best_legends if place_legend(legend, renderer)}
        keys = [frame_key(ax, self.framed) for ax in self.fig.axes]
        figure_key = _figure_key(self.fig)
        if (self.background is None or figure_key != self.figure_key
                or len(keys) != len(self.keys)):
            self._draw_all_frames()
        else:
            changed = [i for i, (a, b) in enumerate(zip(keys, self.keys, strict=True)) if a != b]
            if changed and not self._draw_changed_frames(changed):
                self._draw_all_frames()
        self.keys, self.figure_key = keys, figure_key
        self.y_keys = [_y_key(ax) for ax in self.fig.axes]
        if not self._layered():  # a full draw interleaves the axes' frames and data
            self.canvas.draw()
            return encode_png(self.canvas.buffer_rgba())
        self.canvas.restore_region(self.background)
        for ax in self.fig.axes:
            if ax.get_visible():
                for artist in data_artists(ax, self.framed):
                    artist.draw(renderer)
        return encode_png(self.canvas.buffer_rgba())
