"""Figures for assessing a recorded flight (notebook 07) that :mod:`navlib.plots.metrics`
does not draw: the phases over the fitted specific force and angular rate, the fit
residuals over time, and the per-segment "which states" map.

The excitability bars, energy spectrum and sensability curves come from
:mod:`navlib.plots.metrics` unchanged: a :class:`navlib.studies.assess.FlightAssessment`
offers the same ``segments``, ``excitability``, ``sensability``, ``settings`` and
``state_names`` as the rocket analysis those builders were written for. Every builder here
takes a ``FlightAssessment`` and returns a new Figure; nothing is computed beyond unit
conversion and thinning long records for display.
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.patches import Patch

from navlib.plots.figure import subplots
from navlib.plots.phases import phase_colour
from navlib.units import DEG

_MAX_POINTS = 20_000
_LABEL_SHARE = 0.09
"""Segments narrower than this share of the flight are labelled with their number only."""
_HEATMAP_MAX_WIDTH_IN = 12.0
"""Widest estimable-states figure: about a page's width, so its 9 pt labels stay readable."""


def _thin(n: int) -> slice:
    return slice(None, None, max(1, int(np.ceil(n / _MAX_POINTS))))


def shade_phases(ax, segment_table, label: bool = True, alpha: float = 0.12,
                 gid: str | None = None) -> list:
    """Shade each segment of ``segment_table`` (``phase, t_start, t_end``) in its phase
    colour; with ``label`` write ``"<segment> <phase>"`` along the top of the axes.

    Returns the artists added (their ``gid`` set to ``gid``), for :func:`reshade_phases`.
    """
    artists = []
    span = float(segment_table["t_end"].max() - segment_table["t_start"].min()) or 1.0
    narrow = 0
    for k, row in enumerate(segment_table.itertuples(index=False)):
        colour = phase_colour(row.phase)
        artists.append(ax.axvspan(row.t_start, row.t_end, color=colour, alpha=alpha,
                                  linewidth=0, gid=gid))
        if label:
            number = getattr(row, "segment", k + 1)
            # a segment too narrow for "<n> <phase>" gets its number only, raised every
            # other time, so neighbouring labels do not overlap (the legend names phases)
            wide = (row.t_end - row.t_start) / span >= _LABEL_SHARE
            narrow = 0 if wide else narrow + 1
            artists.append(ax.annotate(f"{number} {row.phase}" if wide else f"{number}",
                                       ((row.t_start + row.t_end) / 2, 1.0),
                                       xytext=(0, 7 * (narrow % 2)), textcoords="offset points",
                                       xycoords=("data", "axes fraction"), ha="center",
                                       va="bottom", fontsize=7, color="0.25", gid=gid))
    return artists


def reshade_phases(fig, assessment) -> list:
    """Replace the assessed-segment shading of a :func:`phases_figure` by that of
    ``assessment`` (same flight, other segments) in place; returns the new artists."""
    for ax in fig.axes[:2]:
        for artist in [*ax.patches, *ax.texts]:
            if artist.get_gid() == "assessed":
                artist.remove()
    return [artist for ax in fig.axes[:2] for artist in
            shade_phases(ax, assessment.segment_table, label=ax is fig.axes[0],
                         gid="assessed")]


def phases_figure(assessment):
    """The fitted specific force and angular rate (body axes) with the assessed segments
    shaded by phase, and a strip of the automatic segmentation underneath."""
    traj = assessment.trajectory
    sl = _thin(len(traj.t))
    t = traj.t[sl]
    f_b = traj.specific_force[sl]
    w_b = traj.angular_rate[sl] / DEG
    fig, axes = subplots(3, 1, figsize=(11, 6.2), sharex=True, layout="constrained",
                         gridspec_kw={"height_ratios": [3, 3, 0.6]})
    for ax, data, name, unit in ((axes[0], f_b, "f", "m/s²"), (axes[1], w_b, "ω_ib", "deg/s")):
        for i, axis in enumerate("xyz"):
            ax.plot(t, data[:, i], linewidth=0.9, label=f"{name}_{axis}")
        ax.plot(t, np.linalg.norm(data, axis=1), color="k", linewidth=0.8, label=f"|{name}|")
        ax.set_ylabel(f"{name} [{unit}]")
        ax.legend(fontsize=7, ncol=4, loc="upper right")
        shade_phases(ax, assessment.segment_table, label=ax is axes[0], gid="assessed")
    auto = assessment.automatic.segments
    shade_phases(axes[2], auto, label=False, alpha=1.0)
    axes[2].set_yticks([])
    axes[2].set_ylabel("auto", fontsize=8)
    present = list(dict.fromkeys(auto["phase"]))  # in order of appearance
    axes[2].legend(handles=[Patch(color=phase_colour(p), label=p) for p in present],
                   fontsize=7, loc="center left", bbox_to_anchor=(1.005, 0.5),
                   frameon=False)
    axes[2].set_xlabel("t [s]")
    fig.suptitle(f"Fitted specific force and angular rate, body axes "
                 f"({traj.name or 'flight'}); shading: assessed segments", fontsize=10)
    return fig


def fit_residuals_figure(assessment):
    """Recorded minus fitted: GNSS position per ECEF axis (with the model's ±sigma) and the
    IMU specific force and angular rate per body axis, over time."""
    gnss = assessment.gnss_residuals
    imu = assessment.imu_residuals
    sl = _thin(len(imu))
    sigma = assessment.options.get("gnss_sigma_m")
    fig, axes = subplots(3, 1, figsize=(11, 6.4), sharex=True, layout="constrained")
    for axis in "xyz":
        axes[0].plot(gnss["t"], gnss[f"d{axis}"], "o-", markersize=2.5, linewidth=0.7,
                     label=f"Δ{axis}")
    if sigma:
        axes[0].axhspan(-sigma, sigma, color="0.85", zorder=0, label=f"±σ = {sigma:.3g} m")
    axes[0].set_ylabel("GNSS − fit [m]")
    for axis in "xyz":
        axes[1].plot(imu["t"].iloc[sl], imu[f"df_{axis}"].iloc[sl], linewidth=0.5,
                     label=f"Δf_{axis}")
        axes[2].plot(imu["t"].iloc[sl], imu[f"dw_{axis}"].iloc[sl] / DEG, linewidth=0.5,
                     label=f"Δω_{axis}")
    axes[1].set_ylabel("IMU − fit, f [m/s²]")
    axes[2].set_ylabel("IMU − fit, ω [deg/s]")
    axes[2].set_xlabel("t [s]")
    for ax in axes:
        ax.legend(fontsize=7, ncol=4, loc="upper right")
        shade_phases(ax, assessment.segment_table, label=ax is axes[0], alpha=0.08)
    fig.suptitle("Fit residuals (white noise, biases and scale-factor errors of the records "
                 "stay in them)", fontsize=10)
    return fig


def estimable_figure(assessment):
    """Per segment (columns) and state (rows): excitability ``e`` and the share of epochs
    with ``s >= s_threshold``; cells at or above their threshold are outlined."""
    table = assessment.state_table()
    names = list(assessment.state_names)
    segs = assessment.segment_table
    e = table.pivot(index="state", columns="segment", values="e").loc[names]
    frac = table.pivot(index="state", columns="segment", values="s_fraction").loc[names]
    th = assessment.thresholds
    labels = [f"{r.segment} {r.phase}\n{r.t_start:.4g}–{r.t_end:.4g} s"
              for r in segs.itertuples(index=False)]
    width = min(3.2 + 1.3 * len(segs), _HEATMAP_MAX_WIDTH_IN / 2)
    fig, axes = subplots(1, 2, figsize=(2 * width, 7.2), layout="constrained")
    many = len(segs) > 4  # column labels turned upright when they would run into each other
    panels = ((axes[0], e.to_numpy(), th["e_threshold"], "excitability e"),
              (axes[1], frac.to_numpy(), th["min_fraction"],
               f"share of epochs with s ≥ {th['s_threshold']:.3g}"))
    for ax, values, threshold, title in panels:
        image = ax.imshow(values, cmap="Blues", vmin=0.0, vmax=1.0, aspect="auto")
        for (j, k), v in np.ndenumerate(values):
            good = v >= threshold
            ax.text(k, j, f"{v:.2f}", ha="center", va="center", fontsize=8 if many else 9,
                    color="white" if v > 0.6 else "0.2", fontweight="bold" if good else None)
            if good:
                ax.add_patch(plt.Rectangle((k - 0.5, j - 0.5), 1, 1, fill=False,
                                           edgecolor="tab:red", linewidth=1.2))
        ax.set_xticks(np.arange(len(labels)), labels, fontsize=9, rotation=90 if many else 0)
        ax.set_yticks(np.arange(len(names)), names, fontsize=9)
        ax.set_title(f"{title} (outlined: ≥ {threshold:.3g})", fontsize=10)
        fig.colorbar(image, ax=ax, shrink=0.6)
    fig.suptitle(f"Which states this flight could estimate, segment by segment "
                 f"(η = {th['eta']:.0e}, ν = {th['nu']:.3f}, preset "
                 f"{assessment.options.get('preset')})", fontsize=10)
    return fig
