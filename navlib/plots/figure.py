"""Where the builders of :mod:`navlib.plots` get their Figures: from pyplot, or detached.

Notebook cells get pyplot figures (shown by ``display`` or the inline backend as before).
Inside :func:`detached` the same builders make plain :class:`matplotlib.figure.Figure`
objects that pyplot's figure manager never holds: no ``plt.close`` needed, and no hook of
the inline backend (``flush_figures`` at the end of a cell, which under JupyterLab's
kernel subshells runs on another thread) can draw them while a widget panel renders
them. The switch is a :class:`contextvars.ContextVar`, so it holds for the thread (and
task) that set it only.
"""

from __future__ import annotations

import contextlib
import contextvars

import matplotlib.pyplot as plt
from matplotlib.figure import Figure

__all__ = ["detached", "figure", "is_detached", "show", "subplots"]

_DETACHED = contextvars.ContextVar("navlib_detached_figures", default=False)
_SUBPLOT_KEYWORDS = ("sharex", "sharey", "squeeze", "width_ratios", "height_ratios",
                     "subplot_kw", "gridspec_kw")


@contextlib.contextmanager
def detached():
    """Make the builders called in this block return figures outside pyplot."""
    token = _DETACHED.set(True)
    try:
        yield
    finally:
        _DETACHED.reset(token)


def is_detached() -> bool:
    """True inside :func:`detached` (on this thread)."""
    return _DETACHED.get()


def figure(**figure_kw) -> Figure:
    """``plt.figure(**figure_kw)``, or a detached ``Figure(**figure_kw)`` inside
    :func:`detached`."""
    return Figure(**figure_kw) if _DETACHED.get() else plt.figure(**figure_kw)


def show(fig: Figure) -> None:
    """Show ``fig`` as a notebook cell output and release it from pyplot.

    The one display helper of the notebooks: the figure is rendered once by ``display`` and
    closed, so the inline backend does not draw it a second time at the end of the cell and
    a long notebook does not keep every figure alive.
    """
    from IPython.display import display  # IPython loads only when a figure is shown

    display(fig)
    plt.close(fig)


def subplots(nrows: int = 1, ncols: int = 1, **keywords):
    """``plt.subplots`` with the same keywords, on a :func:`figure` (detached or not)."""
    subplot_kw = {k: keywords.pop(k) for k in _SUBPLOT_KEYWORDS if k in keywords}
    fig = figure(**keywords)
    return fig, fig.subplots(nrows, ncols, **subplot_kw)
