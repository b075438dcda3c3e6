"""How a kept panel figure differs from the report's figure (docs/assumptions.md, "Panel
figures"), so that a small change of its data keeps its frames (:mod:`navlib.widgets.layers`).

* :func:`snap_limits` rounds an autoscaled axis outward to its ticks (matplotlib's
  ``round_numbers`` autolimit mode), so a small data change keeps the frame;
* :func:`place_legend` puts a legend where the fewest data points are, counting vertices
  (matplotlib's "best" also tests every segment), and says whether any data lies under it;
* :func:`freeze_decorations` keeps titles and x labels where the first layout put them.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.transforms import Bbox

__all__ = ["EDGE_ROOM_PT", "freeze_decorations", "place_legend", "snap_limits"]


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


def place_legend(legend, renderer) -> Bbox | None:
    """Put an axes legend at the standard location (``loc`` codes 1-10, as "best" tries
    them) that covers the fewest data points, the first one on a tie; its box there when no
    data lies under it (no vertex, no line crossing it, no patch or collection in its
    axes), else None.

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
    matplotlib.transforms.Bbox or None
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
        return None
    room = renderer.points_to_pixels(EDGE_ROOM_PT)
    around, inner = place.padded(room), ax.bbox.padded(-room)
    if not (inner.contains(around.x0, around.y0) and inner.contains(around.x1, around.y1)):
        return None  # it would meet the spines, drawn over the frame
    crossed = any(line.get_visible() and line.get_transform().transform_path(
        line.get_path()).intersects_bbox(around, filled=False) for line in ax.lines)
    return None if crossed else place


def freeze_decorations(fig: Figure) -> None:
    """Keep the titles and x-axis labels of a drawn figure where they are.

    matplotlib places them at every draw from the tick labels' extents (the x label under
    the tallest, the title over any top decoration): about a quarter of the time to draw
    the SSAC sigma figure (38 of 161 ms). In a kept figure (frozen layout, same fonts)
    their places do not change, unless an axes has x tick labels or its x label on top
    (then left to matplotlib). The y labels stay automatic: tick labels change width with
    the limits.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        A figure drawn at least once.
    """
    for ax in fig.axes:
        label = ax.xaxis.label
        ticks = [*ax.xaxis.majorTicks[:1], *ax.xaxis.minorTicks[:1]]
        if ax.xaxis.get_label_position() == "top" or any(t.label2.get_visible() for t in ticks):
            continue
        ax._autotitlepos = False
        where = label.get_transform().transform(label.get_position())
        ax.xaxis.set_label_coords(*ax.transAxes.inverted().transform(where))
