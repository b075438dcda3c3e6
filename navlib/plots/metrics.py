"""Figures for excitability and sensability (notebooks 03, 04 and 07).

Builders take a :class:`navlib.metrics.SegmentedAnalysis` (the rocket study's
:class:`~navlib.studies.rocket.RocketAnalysis`, a flight's
:class:`~navlib.studies.assess.FlightAssessment`) or tables made from one, draw the
analysis's own thresholds, and return a new matplotlib Figure; nothing is computed here
beyond unit conversion:

* :func:`excitability_bars` / :func:`energy_spectrum` / :func:`excitability_figure`:
  the Fig. 2 analogue (bars of ``e_tau^i``, 21 components x segments) and the log plot of
  ``S_tau(u^i)`` with the eta line and ``ne``;
* :func:`sensability_figure`: the Figs. 3-5 analogues (sensability beside the physical
  2-sigma band of each chosen state);
* :func:`measures_figure`: sensability beside the PSINS covariance ratio;
* :func:`tension_figure`, :func:`sweep_figure`: the X3 / S6-S7 trade and the pass/fail
  matrix of the sensitivity sweep.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from navlib.covariance import covariance_ratio
from navlib.metrics import E_THRESHOLD, LOW
from navlib.models.ecef import PAPER_IDS
from navlib.plots.figure import figure, subplots
from navlib.plots.phases import phase_colour, segment_phases
from navlib.units import DEG, PPM

__all__ = ["SEGMENT_COLOURS", "SPECTRUM_FLOOR", "display_unit", "energy_spectrum",
           "excitability_bars", "excitability_dynamic_artists", "excitability_figure",
           "measures_figure", "reshade_segments", "restate_sensability", "segment_colours",
           "segment_legend", "sensability_figure", "short_name", "sweep_figure", "tension_figure"]

SEGMENT_COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple")
"""Colours of the segments of an analysis without phases (the papers' τ1, τ2, ...); the
segments of a flight or a plan take their phase's colour (:mod:`navlib.plots.phases`)."""
SPECTRUM_FLOOR = 1e-45
"""Smallest S drawn on the log axis (exact zeros of rank-deficient segments)."""
_DISPLAY = {"P": (1.0, "m"), "V": (1.0, "m/s"), "theta": (DEG, "deg"), "bg": (DEG, "deg/s"),
            "ba": (1.0, "m/s²"), "sg": (PPM, "ppm"), "sa": (PPM, "ppm")}


def display_unit(state: str) -> tuple[float, str]:
    """(SI value of one display unit, unit label) for a 21-state name, e.g. theta -> deg."""
    return _DISPLAY.get(state.rsplit("_", 1)[0], (1.0, ""))


def short_name(state: str) -> str:
    """Compact axis label of a state name: ``theta_x`` -> ``θx``, ``bg_y`` -> ``bgy``."""
    return state.replace("theta", "θ").replace("_", "")


def _segment_label(i: int, segment) -> str:
    return f"τ{i + 1} [{segment[0]:g}, {segment[1]:g}] s"


def segment_colours(analysis) -> list:
    """One colour per segment of ``analysis`` (or of a plain list of ``(start, end)``
    segments): its phase's colour when the segments have phases
    (:func:`navlib.plots.phases.segment_phases`), else :data:`SEGMENT_COLOURS` in turn."""
    phases = segment_phases(analysis)
    if phases is not None:
        return [phase_colour(p) for p in phases]
    segments = getattr(analysis, "segments", analysis)
    return [SEGMENT_COLOURS[i % len(SEGMENT_COLOURS)] for i in range(len(segments))]


def segment_legend(analysis) -> list[str]:
    """Legend text of each segment: ``τ1`` or, with phases, ``τ1 coast``."""
    phases = segment_phases(analysis) or [""] * len(analysis.segments)
    return [f"τ{i + 1} {p}".rstrip() for i, p in enumerate(phases)]


def excitability_bars(analysis, ax=None):
    """Fig. 2 analogue: bars of ``e_tau^i`` for each state (the 21 components, labelled with
    the paper's e1-e21 when they are the 21-state model's), one colour per segment.

    Dashed line at the analysis's ``e_threshold`` ("lies in S_O", 1/sqrt(2) by default),
    dotted at the "very low" share :data:`navlib.metrics.LOW`.

    Parameters
    ----------
    analysis : Analysis
        Result of :func:`navlib.metrics.analyze_trajectory`.
    ax : matplotlib.axes.Axes or None, optional
        Axes to draw on; None makes a new figure.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = (subplots(figsize=(11, 3.6)) if ax is None else (ax.figure, ax))
    names = analysis.state_names
    k = len(analysis.segments)
    width = 0.8 / k
    x = np.arange(len(names))
    colours, labels = segment_colours(analysis), segment_legend(analysis)
    for i, ex in enumerate(analysis.excitability):
        ax.bar(x - 0.4 + width * (i + 0.5), ex.e, width, color=colours[i], label=labels[i])
    ax.axhline(analysis.settings["e_threshold"], color="0.3", linestyle="--", linewidth=0.8,
               gid="e_threshold")
    ax.axhline(LOW, color="0.6", linestyle=":", linewidth=0.8)
    ax.set_xticks(x, [f"{PAPER_IDS[n]}\n{short_name(n)}" if n in PAPER_IDS else short_name(n)
                      for n in names], fontsize=7)
    ax.set_ylim(0, 1.05)
    ax.set_ylabel("excitability e")
    ax.set_title(_bars_title(analysis), fontsize=10)
    ax.legend(fontsize=7, ncol=k, loc="upper right")
    return fig


def _bars_title(analysis) -> str:
    s = analysis.settings
    segments = ", ".join(_segment_label(i, seg) for i, seg in enumerate(analysis.segments))
    frame = f", {s['attitude_error']} attitude error" if "attitude_error" in s else ""
    return f"Excitability per segment: {segments}\nη = {s['eta']:.0e}, D0 {s['d0']}{frame}"


def energy_spectrum(analysis, ax=None):
    """``S_tau(u^i)`` (Eq. 19) on a log axis per segment, the eta line and each ``ne``.

    Parameters
    ----------
    analysis : Analysis
        Result of :func:`navlib.metrics.analyze_trajectory`.
    ax : matplotlib.axes.Axes or None, optional
        Axes to draw on; None makes a new figure.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = (subplots(figsize=(6, 3.6)) if ax is None else (ax.figure, ax))
    n = len(analysis.state_names)
    i_dir = np.arange(1, n + 1)
    colours, labels = segment_colours(analysis), segment_legend(analysis)
    for i, ex in enumerate(analysis.excitability):
        colour = colours[i]
        ax.semilogy(i_dir, np.maximum(ex.S, SPECTRUM_FLOOR), "o-", color=colour,
                    markersize=3, label=labels[i], gid=f"spectrum{i}")
        ax.axvline(min(ex.ne, n), color=colour, linestyle=":", linewidth=1.0,
                   visible=ex.ne <= n, gid=f"ne{i}")
    eta = analysis.settings["eta"]
    ax.axhline(eta, color="k", linestyle="--", linewidth=1.0, label="η",
               gid="eta")
    ax.set_ylim(SPECTRUM_FLOOR / 10.0, 10.0 * n)  # fixed, so redraws keep their axes
    ax.set_xlabel("direction i (u^i)")
    ax.set_ylabel("S_τ(u^i)")
    ax.set_xticks(i_dir[::2])
    ax.set_title(_spectrum_title(analysis), fontsize=10)
    ax.legend(fontsize=7)
    return fig


def _spectrum_title(analysis) -> str:
    ne = " / ".join(str(ex.ne) for ex in analysis.excitability)
    return (f"Energy spectrum of the normalised O_τ\n"
            f"η = {analysis.settings['eta']:.0e}: ne = {ne}")


def excitability_figure(analysis, fig=None):
    """Bars (Fig. 2 analogue) and energy spectrum side by side in one Figure.

    ``fig``: a Figure made by this function to redraw in place (its two axes are cleared and
    redrawn, their positions kept), which widgets use to avoid a new layout per update.

    Parameters
    ----------
    analysis : Analysis
        Result of :func:`navlib.metrics.analyze_trajectory`.
    fig : matplotlib.figure.Figure or None, optional
        Figure to redraw in place.

    Returns
    -------
    matplotlib.figure.Figure
    """
    if fig is not None and _update_in_place(fig, analysis):
        return fig
    if fig is None:
        fig = figure(figsize=(14, 3.8), layout="constrained")
        grid = fig.add_gridspec(1, 3)
        bars, spectrum = fig.add_subplot(grid[0, :2]), fig.add_subplot(grid[0, 2])
    else:
        bars, spectrum = fig.axes[:2]
        bars.cla()
        spectrum.cla()
    excitability_bars(analysis, bars)
    energy_spectrum(analysis, spectrum)
    return fig


def _update_in_place(fig, analysis) -> bool:
    """Set new heights, spectra, ne and eta on the artists of an excitability figure with
    the same number of segments, states and ``e_threshold`` (no new artists, ticks or
    layout)."""
    bars, spectrum = fig.axes[:2]
    containers = bars.containers
    lines = {ln.get_gid(): ln for ln in spectrum.get_lines()}
    k, n = len(analysis.excitability), len(analysis.state_names)
    threshold = [ln.get_ydata()[0] for ln in bars.get_lines() if ln.get_gid() == "e_threshold"]
    if len(containers) != k or any(f"spectrum{i}" not in lines for i in range(k)) \
            or len(containers[0].patches) != n \
            or threshold != [analysis.settings["e_threshold"]] \
            or [c.get_label() for c in containers] != segment_legend(analysis):
        return False  # other segments, states, threshold or phases (colours, legend)
    for i, ex in enumerate(analysis.excitability):
        for patch, height in zip(containers[i].patches, ex.e, strict=True):
            patch.set_height(height)
        lines[f"spectrum{i}"].set_ydata(np.maximum(ex.S, SPECTRUM_FLOOR))
        lines[f"ne{i}"].set_xdata([min(ex.ne, n)] * 2)
        lines[f"ne{i}"].set_visible(ex.ne <= n)
    lines["eta"].set_ydata([analysis.settings["eta"]] * 2)
    bars.title.set_text(_bars_title(analysis))
    spectrum.title.set_text(_spectrum_title(analysis))
    return True


def excitability_dynamic_artists(fig) -> list:
    """The artists :func:`excitability_figure` changes on an in-place update (bars, spectra,
    ne and eta lines, titles), for blitting renderers."""
    bars, spectrum = fig.axes[:2]
    return [*bars.patches, bars.title, *spectrum.get_lines(), spectrum.title]


def _shade_segments(ax, analysis) -> list:
    artists = []
    colours = segment_colours(analysis)
    for i, (a, b) in enumerate(getattr(analysis, "segments", analysis)):
        artists.append(ax.axvspan(a, b, color=colours[i], alpha=0.06 if colours[i] in
                                  SEGMENT_COLOURS else 0.12, linewidth=0, gid="segment"))
        artists.append(ax.annotate(f"τ{i + 1}", ((a + b) / 2, 1.0),
                                   xycoords=("data", "axes fraction"), ha="center",
                                   va="bottom", fontsize=7, color="0.35", gid="segment"))
    return artists


def reshade_segments(fig, analysis) -> list:
    """Replace the segment shading of a :func:`sensability_figure` by that of the segments
    of ``analysis`` (coloured by phase when they have phases; or a plain list of
    ``(start, end)`` segments) in place; returns the new artists (for blitting
    renderers).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        A :func:`sensability_figure`.
    analysis : Analysis or list of tuple
        The analysis whose segments are shaded, or ``(start, end)`` pairs, s.

    Returns
    -------
    list
        The new artists.
    """
    axes = [ax for ax in fig.axes if any(a.get_gid() == "segment" for a in ax.patches)]
    for ax in axes:
        for artist in [*ax.patches, *ax.texts]:
            if artist.get_gid() == "segment":
                artist.remove()
    return [artist for ax in axes for artist in _shade_segments(ax, analysis)]


def sensability_figure(analysis, states: Sequence[str], k: float = 2.0, title: str = ""):
    """Figs. 3-5 analogues: sensability of each state (left axis) and its physical
    ``±k sigma`` band (right axis, display units), segments shaded, the analysis's
    ``s_threshold`` dotted.

    Parameters
    ----------
    analysis : navlib.metrics.SegmentedAnalysis
    states : sequence of str
        e.g. ``["P_x", "V_x"]`` (Fig. 3), ``["theta_x", "theta_y", "theta_z"]`` (Fig. 4),
        ``["bg_x", "bg_y", "bg_z"]`` (Fig. 5).
    k : float
        Band half-width in sigmas (paper: 2).
    """
    states = list(states)
    fig, axes = subplots(len(states), 1, figsize=(9, 2.1 * len(states) + 0.4),
                         sharex=True, squeeze=False, layout="constrained")
    for row, ax in enumerate(axes[:, 0]):
        ax.plot([], [], color="tab:blue", linewidth=1.5, label="sensability",
                gid=f"sensability:{row}")
        ax.axhline(analysis.settings["s_threshold"], color="tab:blue", linestyle=":",
                   linewidth=0.8)
        ax.set_ylim(-0.03, 1.05)
        _shade_segments(ax, analysis)
        twin = ax.twinx()
        twin.set_gid(f"band:{row}")
        twin.fill_between([], [], [], color="tab:red", alpha=0.15, linewidth=0)
        twin.plot([], [], color="tab:red", linewidth=0.8)
        twin.plot([], [], color="tab:red", linewidth=0.8)
    restate_sensability(fig, analysis, states, k)
    axes[-1, 0].set_xlabel("t [s]")
    s = analysis.settings
    fig.suptitle(title or f"Sensability (ν = {s['nu']:.3f}) and {k:g}σ bands", fontsize=10)
    return fig


def restate_sensability(fig, analysis, states: Sequence[str], k: float = 2.0) -> list:
    """Put ``states`` (as many as the figure's rows) on a :func:`sensability_figure` in
    place: the sensability curves, the bands with their limits, the axis labels. A panel
    changes the state group this way without building and laying out a new figure.

    Returns
    -------
    list of Line2D
        The sensability curves, one per row.
    """
    se = analysis.sensability
    rows = {a.get_gid(): a for a in fig.axes if a.get_gid()}
    lines = {ln.get_gid(): ln for ax in fig.axes for ln in ax.get_lines() if ln.get_gid()}
    if len(lines) != len(states):
        raise ValueError(f"the figure has {len(lines)} rows, not {len(states)} states")
    out = []
    for row, state in enumerate(states):
        j = analysis.state_names.index(state)
        line = lines[f"sensability:{row}"]
        line.set_data(se.t, se.s[:, j])
        line.axes.set_ylabel(f"s({state})", color="tab:blue")
        line.axes.relim()
        line.axes.autoscale_view(scaley=False)
        scale, unit = display_unit(state)
        band = k * se.sigma[:, j] / scale
        twin = rows[f"band:{row}"]
        twin.collections[0].set_data(se.t, -band, band)
        upper, lower = twin.get_lines()
        upper.set_data(se.t, band)
        lower.set_data(se.t, -band)
        twin.relim()
        twin.autoscale_view()
        twin.set_ylabel(f"±{k:g}σ [{unit}]", color="tab:red")
        out.append(line)
    return out


def measures_figure(analysis, states: Sequence[str]):
    """Sensability beside the PSINS covariance ratio ``sigma_i(t0)/sigma_i(t)`` (log).

    Parameters
    ----------
    analysis : Analysis
        Result of :func:`navlib.metrics.analyze_trajectory`.
    states : sequence of str
        States to plot.

    Returns
    -------
    matplotlib.figure.Figure
    """
    states = list(states)
    se = analysis.sensability
    ratio = covariance_ratio(se.sigma)
    fig, (ax_s, ax_r) = subplots(1, 2, figsize=(12, 3.4), layout="constrained")
    for state in states:
        j = analysis.state_names.index(state)
        line, = ax_s.plot(se.t, se.s[:, j], label=state)
        ax_r.semilogy(se.t, ratio[:, j], color=line.get_color(), label=state)
    for ax in (ax_s, ax_r):
        _shade_segments(ax, analysis)
        ax.set_xlabel("t [s]")
    ax_s.axhline(analysis.settings["s_threshold"], color="0.4", linestyle=":")
    ax_s.set_ylabel("sensability s")
    ax_r.axhline(1.0, color="0.4", linestyle=":")
    ax_r.set_ylabel("σ(t0)/σ(t)  (PSINS ratio)")
    ax_s.legend(fontsize=7, ncol=2)
    fig.suptitle("Sensability versus the covariance-ratio 'observability degree'", fontsize=10)
    return fig


_VERDICT_MARKERS = {"reproduced": "o", "partly": "s", "not reproduced": "x"}


def tension_figure(table):
    """X3 versus S6/S7: ``e16`` in tau2 against the attitude band growth, per variant."""
    fig, ax = subplots(figsize=(8, 4), layout="constrained")
    for r in table.itertuples():
        ax.scatter(r.max_theta_growth, r.e16_tau2, marker=_VERDICT_MARKERS.get(r.X3, "o"),
                   s=50, color="tab:green" if r.all_three else "tab:red")
        ax.annotate(r.variant, (r.max_theta_growth, r.e16_tau2), fontsize=7,
                    xytext=(4, 2), textcoords="offset points")
    ax.axhline(E_THRESHOLD, color="0.4", linestyle="--", linewidth=0.8)
    ax.axvline(1.0, color="0.4", linestyle=":", linewidth=0.8)
    ax.set_xscale("log")
    ax.set_xlabel("max σθ(t)/σθ(0) in τ2 (S6 wants < 1)")
    ax.set_ylabel("e16 (sg_x) in τ2 (X3 wants ≥ 1/√2)")
    ax.set_title("The X3 / S6-S7 tension (marker: X3 verdict; green: X3 with S6, S7)",
                 fontsize=10)
    return fig


def sweep_figure(sweep, claim_ids: Sequence[str] | None = None):
    """Pass/fail matrix of a sensitivity sweep (rows: settings; columns: claims).

    ``sweep`` as from :func:`navlib.studies.rocket.sensitivity_sweep`: a ``factor`` column,
    the factor columns, one boolean column per claim (default: all of them, in order).

    Parameters
    ----------
    sweep : pandas.DataFrame
        The sweep table.
    claim_ids : sequence of str or None, optional
        Claims shown as columns; None shows all.

    Returns
    -------
    matplotlib.figure.Figure
    """
    passed = [c for c in sweep.columns if sweep[c].dtype == bool]
    claim_ids = passed if claim_ids is None else list(claim_ids)
    factors = [c for c in sweep.columns if c not in ("factor", "n_reproduced", *passed)]
    matrix = sweep[claim_ids].to_numpy(dtype=float)
    labels = []
    for r in sweep.itertuples():
        if r.factor in ("baseline", "grid"):
            labels.append(r.factor if r.factor == "baseline" else
                          ", ".join(f"{k}={getattr(r, k)}" for k in factors))
        else:
            labels.append(f"{r.factor} = {getattr(r, r.factor)}")
    height = 0.28 * len(labels) + 1.2
    fig, ax = subplots(figsize=(9, height), layout="constrained")
    ax.imshow(matrix, cmap="RdYlGn", vmin=0, vmax=1, aspect="auto")
    ax.set_xticks(np.arange(len(claim_ids)), claim_ids, fontsize=8)
    ax.set_yticks(np.arange(len(labels)), labels, fontsize=7)
    ax.set_title("Claims reproduced (green) per setting", fontsize=10)
    return fig
