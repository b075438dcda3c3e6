"""Interactive heat map of a sweep result (notebook 08): pick the axes, the value, the rest.

Dropdowns choose the x and y parameters, the result column and how the points sharing a
cell are combined; one dropdown per other parameter fixes it to a value or leaves it
combined ("all"); the dropdown of a parameter on an axis is disabled. Every redraw is
:func:`navlib.plots.sweep.heatmap` on the stored result (nothing is recomputed), shown by
the render path of :mod:`navlib.widgets.base` (a detached figure as a PNG image).
"""

from __future__ import annotations

from collections.abc import Sequence

import ipywidgets as widgets
import pandas as pd

from navlib.errors import NavlibInputError
from navlib.plots.sweep import heatmap
from navlib.sweep import AGGREGATES, parameter_columns
from navlib.widgets.base import Panel, look

__all__ = ["ALL", "SweepPanel", "sweep_panel"]

ALL = "all"
"""Choice of a parameter dropdown that leaves the parameter combined over its values."""


class SweepPanel(Panel):
    """Controls + status line + heat map; ``update()`` redraws it from the stored result.

    Attributes
    ----------
    frame : DataFrame
        The sweep result.
    parameters, values : list of str
        Parameter columns and numeric result columns.
    controls : dict
        ``x``, ``y``, ``value``, ``agg`` and one dropdown per parameter (``fix:<name>``).
    status : ipywidgets.HTML
    parts : dict
        ``heatmap``: the image of the current map.
    """

    error_prefix = "Invalid choice"

    def __init__(self, frame: pd.DataFrame, parameters: Sequence[str] | None = None,
                 x: str | None = None, y: str | None = None, value: str | None = None,
                 threshold: float | None = None, dpi: float = 72.0):
        if not isinstance(frame, pd.DataFrame) or frame.empty:
            raise NavlibInputError("frame: expected a non-empty sweep result DataFrame")
        self.frame = frame
        self.parameters = list(parameters) if parameters is not None else \
            parameter_columns(frame)
        unknown = [p for p in self.parameters if p not in frame.columns]
        if unknown or len(self.parameters) < 2:
            raise NavlibInputError(f"parameters: need two or more columns of the frame, got "
                                   f"{self.parameters}")
        self.values = [c for c in frame.columns if c not in self.parameters and
                       (pd.api.types.is_numeric_dtype(frame[c]) or frame[c].dtype == bool)]
        if not self.values:
            raise NavlibInputError("frame: no numeric result column to map")
        self.threshold = threshold
        controls = {
            "x": widgets.Dropdown(options=self.parameters, value=x or self.parameters[0],
                                  description="x axis", **look("26em")),
            "y": widgets.Dropdown(options=self.parameters, value=y or self.parameters[1],
                                  description="y axis", **look("26em")),
            "value": widgets.Dropdown(options=self.values, value=value or self.values[0],
                                      description="value", **look("26em")),
            "agg": widgets.Dropdown(options=AGGREGATES, value="mean",
                                    description="combine", **look("26em")),
        }
        for name in self.parameters:
            options = [ALL, *[str(v) for v in pd.unique(frame[name])]]
            controls[f"fix:{name}"] = widgets.Dropdown(options=options, value=ALL,
                                                       description=name, **look("26em"))
        super().__init__(controls, dpi=dpi, update_now=False)
        self.children[0].layout = widgets.Layout(display="grid",
                                                 grid_template_columns="repeat(2, 27em)")
        self.update()

    def fixed(self) -> dict:
        """``{parameter: value}`` fixed by the dropdowns (not the axes), original types."""
        out = {}
        axes = (self.controls["x"].value, self.controls["y"].value)
        for name in self.parameters:
            choice = self.controls[f"fix:{name}"].value
            if name in axes or choice == ALL:
                continue
            out[name] = next(v.item() if hasattr(v, "item") else v
                             for v in pd.unique(self.frame[name]) if str(v) == choice)
        return out

    def figure(self):
        """The heat map of the current choices (a new Figure; detached inside
        :func:`navlib.plots.figure.detached`)."""
        c = self.controls
        return heatmap(self.frame, c["x"].value, c["y"].value, c["value"].value,
                       fixed=self.fixed(), agg=c["agg"].value, threshold=self.threshold)

    def refresh(self, changed: set) -> None:
        """Redraw with the current choices; the dropdowns of the axis parameters are
        disabled (fixing them would change nothing)."""
        axes = (self.controls["x"].value, self.controls["y"].value)
        for name in self.parameters:
            self.controls[f"fix:{name}"].disabled = name in axes
        fig = self.figure()
        self.status.value = f"{len(self.frame)} points; fixed: {self.fixed() or 'none'}"
        self.show("heatmap", fig)


def sweep_panel(frame: pd.DataFrame, parameters: Sequence[str] | None = None, **choices
                ) -> SweepPanel:
    """Build the heat-map panel of a sweep result; ``choices``: ``x``, ``y``, ``value``,
    ``threshold``."""
    return SweepPanel(frame, parameters, **choices)
