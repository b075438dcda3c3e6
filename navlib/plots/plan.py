"""Mission-plan figures: when each state becomes excitable and sensible."""

from __future__ import annotations

import numpy as np
from matplotlib.collections import LineCollection, PolyCollection
from matplotlib.patches import Patch

from navlib.plots.figure import subplots

__all__ = ["OUTAGE_GREY", "timeline_bars", "timeline_figure", "timeline_fits", "timeline_labels",
           "update_timeline"]

OUTAGE_GREY = "0.85"
"""Fill of the GNSS outage windows (and of their legend entry)."""


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Index runs ``(first, last)`` where ``mask`` holds."""
    edges = np.diff(np.r_[0, mask.astype(int), 0])
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1, strict=True))


def _bars(rows, half_height: float) -> list:
    """Rectangles (vertices) of the ``(start, width)`` spans of each row ``j`` of ``rows``,
    centred on ``y = j``: what ``broken_barh`` draws, for every row in one collection."""
    return [[(x, j - half_height), (x, j + half_height), (x + w, j + half_height),
             (x + w, j - half_height)] for j, spans in enumerate(rows) for x, w in spans]


def timeline_bars(plan) -> tuple[list, list]:
    """The bars of :func:`timeline_figure`: the vertices of the excitable spans (per segment)
    and of the sensible ones (per epoch, ``s >= s_threshold``), one row per state.

    Parameters
    ----------
    plan : navlib.studies.plan.MissionPlan
        The plan with its thresholds.

    Returns
    -------
    excitable, sensible : list
        Polygon vertices for a ``PolyCollection`` each.
    """
    names = list(plan.state_names)
    se = plan.sensability
    t = se.t
    ok = se.s >= plan.settings["s_threshold"]
    step = float(np.median(np.diff(t))) if t.size > 1 else 1.0
    table = plan.state_table()
    excitable = table[table["excitable"]]
    spans = {name: list(zip(rows["t_start"], rows["t_end"] - rows["t_start"], strict=True))
             for name, rows in excitable.groupby("state", sort=False)}
    return (_bars([spans.get(name, []) for name in names], 0.4),
            _bars([[(t[a], t[b] - t[a] + step) for a, b in _runs(ok[:, j])]
                   for j in range(len(names))], 0.2))


def timeline_labels(plan) -> tuple[str, str]:
    """The legend entries of the excitable and sensible bars, which name the thresholds."""
    return (f"excitable (e ≥ {plan.settings['e_threshold']:.3g}) in the segment",
            f"sensible (s ≥ {plan.settings['s_threshold']:.3g})")


def _outage_spans(plan) -> list:
    """Vertices of the outage windows, full height (x in data, y in axes coordinates)."""
    return [[(a, 0.0), (a, 1.0), (b, 1.0), (b, 0.0)] for a, b in plan.outages]


def _segment_starts(plan) -> list:
    """Full-height segments at the segment starts (x in data, y in axes coordinates)."""
    return [[(t, 0.0), (t, 1.0)] for t in plan.segment_table["t_start"]]


def _legend(ax, plan) -> None:
    e_label, s_label = timeline_labels(plan)
    handles = [Patch(color="tab:orange", alpha=0.35, label=e_label),
               Patch(color="tab:blue", label=s_label)]
    if plan.outages:
        handles.append(Patch(color=OUTAGE_GREY, label="GNSS outage"))
    handles.append(Patch(facecolor="none", edgecolor="0.6", hatch="//",
                         label="start-up transient"))
    ax.legend(handles=handles, fontsize=7, loc="lower center", bbox_to_anchor=(0.5, 1.0),
              ncol=4, frameon=False)


def timeline_fits(fig, plan) -> bool:
    """Whether ``fig`` (a :func:`timeline_figure`) shows the rows and time span of ``plan``,
    so that :func:`update_timeline` can give it the plan's data.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    plan : navlib.studies.plan.MissionPlan

    Returns
    -------
    bool
    """
    ax = fig.axes[0]
    rows = [label.get_text() for label in ax.get_yticklabels()]
    span = (float(plan.trajectory.t[0]), float(plan.trajectory.t[-1]))
    return rows == list(plan.state_names) and ax.get_xlim() == span


def update_timeline(fig, plan) -> None:
    """Give a :func:`timeline_figure` of the same rows and time span (:func:`timeline_fits`)
    the data of ``plan``: bars, outages, segment starts and legend, in place (a panel's kept
    figure after new thresholds or a re-plan).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        A figure :func:`timeline_figure` drew.
    plan : navlib.studies.plan.MissionPlan
        The new plan.
    """
    ax = fig.axes[0]
    outages, excitable, sensible, starts = ax.collections
    outages.set_verts(_outage_spans(plan))
    for collection, verts in zip((excitable, sensible), timeline_bars(plan), strict=True):
        collection.set_verts(verts)
    starts.set_segments(_segment_starts(plan))
    _legend(ax, plan)


def timeline_figure(plan, transient_s: float | None = None):
    """States (rows) over time: light bars where the state is excitable (per segment), dark
    bars where it is sensible (per epoch, ``s >= s_threshold``), grey the GNSS outages,
    hatched the start-up transient that :meth:`~navlib.studies.plan.MissionPlan.timeline`
    leaves out (``transient_s``; None: the plan's ``TRANSIENT_S``)."""
    if transient_s is None:
        transient_s = plan.TRANSIENT_S
    names = list(plan.state_names)
    t = plan.sensability.t
    fig, ax = subplots(1, 1, figsize=(11, 0.28 * len(names) + 1.6), layout="constrained")
    span = ax.get_xaxis_transform()  # x in data, y in axes coordinates
    # one collection per kind, every time (a panel gives them new data in place)
    # over the axes' ticks (z-order 1.5; there is no grid): data a panel redraws alone
    ax.add_collection(PolyCollection(_outage_spans(plan), color=OUTAGE_GREY, linewidth=0,
                                     zorder=1.6, transform=span))
    ax.axvspan(t[0], t[0] + transient_s, facecolor="none", edgecolor="0.6", hatch="//",
               linewidth=0, zorder=1.6)
    excitable, sensible = timeline_bars(plan)
    ax.add_collection(PolyCollection(excitable, color="tab:orange", alpha=0.35, linewidth=0,
                                     zorder=1.7))
    ax.add_collection(PolyCollection(sensible, color="tab:blue", linewidth=0, zorder=1.8))
    ax.add_collection(LineCollection(_segment_starts(plan), colors="0.5", linewidths=0.5,
                                     linestyles="--", zorder=2, transform=span))
    ax.set_yticks(np.arange(len(names)), names, fontsize=7)
    ax.set_ylim(len(names) - 0.5, -0.5)
    ax.set_xlim(float(plan.trajectory.t[0]), float(plan.trajectory.t[-1]))
    ax.set_xlabel("t [s]")
    _legend(ax, plan)
    fig.suptitle(f"{plan.mission.name}: when each state becomes excitable and sensible "
                 "(dashed: segment starts)", fontsize=10)
    return fig
