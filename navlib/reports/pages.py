"""Self-contained HTML pages of ``python -m navlib assess`` and ``plan``: one page per flight
or mission, tables as HTML and figures as embedded PNG.

Plotting is heavy (matplotlib and the figure builders): it is imported only when a page is
written, after the Agg backend is chosen, so a Dask worker that never writes a page never
loads it.
"""

from __future__ import annotations

import base64
import html
import io
from collections.abc import Sequence
from pathlib import PurePath

import pandas as pd

from navlib.studies.assess.states import EXCITABLE_MARK, SENSIBLE_MARK, how_well
from navlib.studies.plan import plan_beside_flight

__all__ = ["figure_png", "flight_page", "log_title", "plan_page"]

_STYLE = ("body{font-family:sans-serif;font-size:16px;line-height:1.4;max-width:1200px;"
          "margin:auto;padding:0 1em} "
          "table{border-collapse:collapse;font-size:14px} "
          "td,th{border:1px solid #ccc;padding:2px 6px;vertical-align:top} "
          "img{max-width:100%;height:auto} .path{color:#555;font-size:14px} "
          "h1,h2,.path{overflow-wrap:anywhere}")
"""Page style: 16 px text, 14 px tables, figures never wider than the page and always at
their own aspect ratio (``height: auto``)."""
_DPI = 110
"""Resolution of the embedded figures: an 11-inch figure is 1210 px, about the page's
width, so matplotlib's 7-8 pt labels show at 11-12 px at 100 % zoom."""


def log_title(log: str) -> str:
    """The file name(s) of a ``LOG`` argument, without folders: ``flight.ulg``, or
    ``imu.csv + gnss.csv`` for a CSV pair (page titles and headings; the full path is
    stated once on the page)."""
    names = [PurePath(part.strip()).name or part.strip() for part in str(log).split(",")]
    return " + ".join(names)


def _plots():
    """The figure builders, after choosing the Agg backend (module docstring)."""
    import matplotlib  # heavy: loaded only when a page is written

    matplotlib.use("Agg", force=False)
    from navlib.plots import assess as aplots  # imports pyplot: after the backend choice
    from navlib.plots.metrics import excitability_figure  # same reason
    from navlib.plots.plan import timeline_figure  # same reason

    return aplots, excitability_figure, timeline_figure


def figure_png(fig) -> str:
    """The figure as a base64 PNG (:data:`_DPI`); the figure is closed."""
    import matplotlib.pyplot as plt  # heavy; _plots chose the Agg backend first

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=_DPI)
    plt.close(fig)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _page(title: str, parts: Sequence[str], notes: Sequence[str], notes_heading: str,
          figures: Sequence[tuple[str, object]], tail: Sequence[str] = ()) -> str:
    body = list(parts)
    if notes:
        body.append(f"<h2>{notes_heading}</h2><ul>"
                    + "".join(f"<li>{html.escape(str(n))}</li>" for n in notes) + "</ul>")
    for heading, fig in figures:
        body.append(f"<h2>{html.escape(heading)}</h2>"
                    f'<img alt="{html.escape(heading)}" src="data:image/png;base64,'
                    f'{figure_png(fig)}">')
    body.extend(tail)
    return ("<!DOCTYPE html><html><head><meta charset='utf-8'><title>"
            f"{html.escape(title)}</title><style>{_STYLE}</style></head><body>"
            + "\n".join(body) + "</body></html>")


def flight_page(log: str, result, warning_texts: Sequence[str]) -> str:
    """The page of one assessed flight (a :class:`~navlib.studies.assess.FlightAssessment`)."""
    aplots, excitability_figure, _ = _plots()
    figures = [("The flight: reference against the records", aplots.flight_figure(result)),
               ("Flight phases", aplots.phases_figure(result)),
               ("Excitability per segment", excitability_figure(result)),
               ("Which states each segment could estimate", aplots.estimable_figure(result)),
               ("Fit residuals", aplots.fit_residuals_figure(result))]
    assumed = pd.DataFrame([{k: result.options.get(k) for k in (
        "vehicle", "preset", "gnss_rate_hz", "gnss_sigma_m", "heading_deg")}])
    parts = [f"<h1>Flight assessment: {html.escape(log_title(log))}</h1>",
             f'<p class="path">Log: <code>{html.escape(log)}</code></p>',
             "<h2>What this flight can estimate, and how well</h2>",
             "<p>1-sigma of each state in navigation axes at the flight's start and at the "
             f"end of each segment; {SENSIBLE_MARK} sensible (the measurements pin it down), "
             f"{EXCITABLE_MARK} excitable only (the motion makes it observable); a segment "
             "marked not represented has no verdicts, its reference motion departs from the "
             "records (see the warnings). Times are seconds since ignition (rockets) or the "
             "first sample.</p>",
             how_well(result.states_table()).to_html(index=False),
             "<h2>Segments and estimable states</h2>",
             "<p>Per segment, the states the flight's motion makes observable "
             "(excitable) and the ones the measurements pin down (sensible).</p>",
             result.summary().to_html(index=False),
             "<p>Generated by <code>python -m navlib assess</code> "
             "(navlib.studies.assess.assess_flight, 21-state ECEF model). The statements are "
             "about the linearised model along the fitted trajectory under the stated preset "
             "and thresholds.</p>",
             "<h2>Assumed</h2>", assumed.to_html(index=False),
             "<h2>Inputs</h2>", result.inputs.to_html(index=False)]
    if result.gnss_outages is not None and len(result.gnss_outages):
        parts += ["<h2>GNSS outages</h2><p>No kept fix (the model has no GNSS measurement "
                  "there, so sensability falls inside them):</p>",
                  result.gnss_outages.to_html(index=False, float_format="%.6g")]
    return _page(log_title(log), parts, [*warning_texts, *result.notes], "Warnings and notes",
                 figures, ["<h2>Fit residuals (table)</h2>" + result.fit.to_html(index=False)])


def plan_page(label: str, plan, warning_texts: Sequence[str] = (),
              flight: tuple[str, object] | None = None) -> str:
    """The page of one mission plan (a :class:`~navlib.studies.plan.MissionPlan`); with
    ``flight = (log, assessment)`` of a recorded flight of the same vehicle, also the
    planned-beside-flown table (:func:`~navlib.studies.plan.plan_beside_flight`) and the
    flight's estimable states."""
    aplots, excitability_figure, timeline_figure = _plots()
    figures = [("Planned specific force and angular rate, with the phases",
                aplots.phases_figure(plan)),
               ("When each state becomes excitable and sensible", timeline_figure(plan)),
               ("Excitability per segment", excitability_figure(plan)),
               ("Which states each segment could estimate", aplots.estimable_figure(plan))]
    assumed = pd.DataFrame([{"vehicle": plan.mission.vehicle, **{
        k: plan.options.get(k) for k in ("preset", "gnss_rate_hz", "gnss_sigma_m")},
        "outages": "; ".join(f"{a:g}-{b:g} s" for a, b in plan.outages) or "none"}])
    parts = [f"<h1>Mission plan: {html.escape(plan.mission.name)}</h1>",
             f"<p>{html.escape(str(plan.mission.table.get('description', '')))}</p>",
             "<h2>Segments and estimable states</h2>", plan.summary().to_html(index=False),
             "<h2>Timeline</h2>", plan.timeline().to_html(index=False, float_format="%.4g"),
             f"<p>Generated by <code>python -m navlib plan</code> from "
             f"<code>{html.escape(label)}</code> (navlib.studies.plan.plan_mission, 21-state "
             "ECEF model along the planned trajectory). The statements are about the "
             "linearised model under the stated preset, GNSS and thresholds.</p>",
             "<h2>Assumed</h2>", assumed.to_html(index=False),
             "<h2>Planned records</h2>", plan.inputs.to_html(index=False)]
    if flight is not None:
        log, flown = flight
        parts += [f"<h2>Planned beside flown: {html.escape(log_title(log))}</h2>",
                  f'<p class="path">Log: <code>{html.escape(log)}</code></p>',
                  "<p>States excitable or sensible in at least one segment of each phase, "
                  "as the plan expected them and as the recorded flight delivered them "
                  f"(flight assessed with preset {html.escape(str(flown.options['preset']))})."
                  "</p>", plan_beside_flight(plan, flown).to_html(index=False)]
        figures.append((f"Flown: which states each segment could estimate "
                        f"({log_title(log)})",
                        aplots.estimable_figure(flown)))
    return _page(plan.mission.name, parts, [*warning_texts, *plan.notes], "Notes", figures)
