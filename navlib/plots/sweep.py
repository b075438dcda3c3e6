"""Heat maps of sweep results (:mod:`navlib.sweep`; notebook 08).

Each builder takes the DataFrame :func:`navlib.sweep.sweep` returns and the columns to put on
the axes; the table behind each map is :func:`navlib.sweep.pivot` (points sharing a cell
combined with ``agg``). Every builder returns a new Figure (from :mod:`navlib.plots.figure`:
detached inside :func:`~navlib.plots.figure.detached`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from matplotlib.patches import Rectangle

from navlib.errors import NavlibInputError
from navlib.plots.figure import subplots
from navlib.sweep import pivot

__all__ = ["heatmap", "heatmaps_figure"]


def _label(value) -> str:
    if isinstance(value, float):
        return f"{value:g}"
    return str(value)


def heatmap(frame, x: str, y: str, value: str, *, fixed: Mapping | None = None,
            agg: str = "mean", threshold: float | None = None, ax=None, cmap: str = "viridis",
            vmin: float | None = None, vmax: float | None = None, title: str | None = None):
    """One heat map of ``value`` over ``x`` (columns) and ``y`` (rows), cells annotated.

    ``threshold`` outlines the cells at or above it (e.g. ``1/sqrt(2)`` for "sensible").
    Returns the Figure (a new one unless ``ax`` is given).

    Parameters
    ----------
    frame : pandas.DataFrame
        Sweep results.
    x, y : str
        Columns on the horizontal and vertical axes.
    value : str
        Column shown.
    fixed : Mapping or None, optional
        Values of the other factors to select.
    agg : str, optional
        Aggregation of repeated cells.
    threshold : float or None, optional
        Cells at or above it are outlined.
    ax : matplotlib.axes.Axes or None, optional
        Axes to draw on.
    cmap : str, optional
        Colour map.
    vmin, vmax : float or None, optional
        Colour range.
    title : str or None, optional
        Axes title.
    """
    table = pivot(frame, x, y, value, fixed, agg)
    if ax is None:
        fig, ax = subplots(figsize=(1.2 + 0.9 * table.shape[1], 1.2 + 0.55 * table.shape[0]),
                           layout="constrained")
    else:
        fig = ax.figure
    data = table.to_numpy(dtype=float)
    image = ax.imshow(data, cmap=cmap, aspect="auto", vmin=vmin, vmax=vmax, origin="lower")
    xlabels = [_label(v) for v in table.columns]
    long = max(len(t) for t in xlabels) > 5
    ax.set_xticks(range(table.shape[1]), xlabels, rotation=30 if long else 0,
                  ha="right" if long else "center")
    ax.set_yticks(range(table.shape[0]), [_label(v) for v in table.index])
    ax.set_xlabel(x)
    ax.set_ylabel(y)
    finite = data[np.isfinite(data)]
    mid = 0.5 * (finite.min() + finite.max()) if finite.size else 0.0
    for (i, j), v in np.ndenumerate(data):
        if np.isfinite(v):
            ax.text(j, i, f"{v:.3g}", ha="center", va="center", fontsize=8,
                    color="white" if v < mid else "black")
            if threshold is not None and v >= threshold:
                ax.add_patch(Rectangle((j - 0.5, i - 0.5), 1, 1, fill=False,
                                       edgecolor="red", linewidth=2))
    fig.colorbar(image, ax=ax, label=value)
    where = ", ".join(f"{k}={_label(v)}" for k, v in (fixed or {}).items())
    ax.set_title(title or f"{value}" + (f" ({where})" if where else "")
                 + f", {agg} of the other points", fontsize=9)
    return fig


def heatmaps_figure(frame, x: str, y: str, values: Sequence[str], *,
                    fixed: Mapping | None = None, agg: str = "mean",
                    thresholds: Mapping | None = None, titles: Mapping | None = None,
                    suptitle: str | None = None):
    """Side-by-side heat maps of several result columns over the same axes.

    Parameters
    ----------
    frame : pandas.DataFrame
        Sweep results.
    x, y : str
        Columns on the horizontal and vertical axes.
    values : sequence of str
        Columns shown, one map each.
    fixed : Mapping or None, optional
        Values of the other factors to select.
    agg : str, optional
        Aggregation of repeated cells.
    thresholds, titles : Mapping or None, optional
        Per column: outline threshold; axes title.
    suptitle : str or None, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    NavlibInputError
        If ``values`` is empty.
    """
    values = list(values)
    if not values:
        raise NavlibInputError("values: need at least one result column")
    thresholds = dict(thresholds or {})
    titles = dict(titles or {})
    n_x = frame[x].nunique() if x in frame.columns else 1
    n_y = frame[y].nunique() if y in frame.columns else 1
    fig, axes = subplots(1, len(values), figsize=(len(values) * (1.6 + 0.8 * n_x),
                                                  2.4 + 0.5 * n_y),
                         layout="constrained", squeeze=False)
    for ax, value in zip(axes[0], values, strict=True):
        heatmap(frame, x, y, value, fixed=fixed, agg=agg, threshold=thresholds.get(value),
                ax=ax, title=titles.get(value))
    if suptitle:
        fig.suptitle(suptitle)
    return fig
