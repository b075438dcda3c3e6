"""Comparing rendered figures pixel by pixel."""

from io import BytesIO

import numpy as np
from PIL import Image

from navlib.widgets.base import render_png
from navlib.widgets.panel_layout import snap_limits


def pixels(png: bytes) -> np.ndarray:
    """The RGB pixels of PNG bytes, as integers (differences do not wrap)."""
    return np.asarray(Image.open(BytesIO(png)).convert("RGB")).astype(int)


def drawn_as_kept(fig, kept, dpi: float) -> np.ndarray:
    """The pixels of ``fig`` drawn in full as a panel shows its kept figure ``kept``: in
    its layout (axes, titles, x labels and figure title where ``kept`` has them), the
    autoscaled limits snapped to their ticks, the legends at the kept ones' places."""
    fig.set_layout_engine("none")
    for ax, old in zip(fig.axes, kept.axes, strict=True):
        ax.set_position(old.get_position())
        ax.title.set_position(old.title.get_position())
        ax.xaxis.label.set_transform(old.xaxis.label.get_transform())
        ax.xaxis.label.set_position(old.xaxis.label.get_position())
        ax.xaxis._autolabelpos, ax._autotitlepos = False, False
        if ax.get_legend() is not None:
            ax.get_legend().set_loc(old.get_legend()._get_loc())
    if fig._suptitle is not None:
        fig._suptitle.set_position(kept._suptitle.get_position())
    snap_limits(fig)  # with the ticks of the kept layout
    return pixels(render_png(fig, dpi))
