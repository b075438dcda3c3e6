"""Mission-plan figures: when each state becomes excitable and sensible."""

from __future__ import annotations

import numpy as np
from matplotlib.collections import PolyCollection
from matplotlib.patches import Patch

from navlib.plots.figure import subplots

__all__ = ["timeline_bars", "timeline_figure", "timeline_labels", "update_timeline"]


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


def update_timeline(fig, plan) -> None:
    """Redraw nothing, but give a :func:`timeline_figure` of the same mission and model the
    bars and legend entries of ``plan`` (other thresholds): what a threshold changes.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        A figure :func:`timeline_figure` drew.
    plan : navlib.studies.plan.MissionPlan
        The same plan with its new thresholds.
    """
    ax = fig.axes[0]
    for collection, verts in zip(ax.collections[:2], timeline_bars(plan), strict=True):
        collection.set_verts(verts)
    for text, label in zip(ax.get_legend().get_texts()[:2], timeline_labels(plan),
                           strict=True):
        text.set_text(label)


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
    for a, b in plan.outages:
        ax.axvspan(a, b, color="0.85", zorder=0)
    ax.axvspan(t[0], t[0] + transient_s, facecolor="none", edgecolor="0.6", hatch="//",
               linewidth=0, zorder=0)
    # one collection per kind (two artists, not two per state: a threshold redraws them)
    excitable, sensible = timeline_bars(plan)
    ax.add_collection(PolyCollection(excitable, color="tab:orange", alpha=0.35, linewidth=0))
    ax.add_collection(PolyCollection(sensible, color="tab:blue", linewidth=0))
    for r in plan.segment_table.itertuples(index=False):
        ax.axvline(r.t_start, color="0.5", linewidth=0.5, linestyle="--")
    ax.set_yticks(np.arange(len(names)), names, fontsize=7)
    ax.set_ylim(len(names) - 0.5, -0.5)
    ax.set_xlim(float(plan.trajectory.t[0]), float(plan.trajectory.t[-1]))
    ax.set_xlabel("t [s]")
    e_label, s_label = timeline_labels(plan)
    handles = [Patch(color="tab:orange", alpha=0.35, label=e_label),
               Patch(color="tab:blue", label=s_label)]
    if plan.outages:
        handles.append(Patch(color="0.85", label="GNSS outage"))
    handles.append(Patch(facecolor="none", edgecolor="0.6", hatch="//",
                         label="start-up transient"))
    ax.legend(handles=handles, fontsize=7, loc="lower center", bbox_to_anchor=(0.5, 1.0),
              ncol=4, frameon=False)
    fig.suptitle(f"{plan.mission.name}: when each state becomes excitable and sensible "
                 "(dashed: segment starts)", fontsize=10)
    return fig
