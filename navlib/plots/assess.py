"""Figures for assessing a recorded flight (notebook 07) that :mod:`navlib.plots.metrics`
does not draw: the flight itself (the reference against the records), the phases over the
fitted specific force and angular rate, the fit residuals over time, and the per-segment
"which states" map.

The excitability bars, energy spectrum and sensability curves come from
:mod:`navlib.plots.metrics` unchanged: a :class:`navlib.studies.assess.FlightAssessment`
offers the same ``segments``, ``excitability``, ``sensability``, ``settings`` and
``state_names`` as the rocket analysis those builders were written for. Every builder here
takes a ``FlightAssessment`` and returns a new Figure; nothing is computed beyond unit
conversion, frame changes and thinning long records for display (and, in
:func:`flight_figure`, the barometer's offset to the reference, named on the figure; its IMU
residuals are the averaged ones the segment verdicts read).
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.patches import Patch
from scipy.spatial.transform import Rotation

from navlib import earth
from navlib.plots.figure import subplots
from navlib.plots.phases import phase_colour
from navlib.units import DEG

__all__ = ["estimable_figure", "fit_residuals_figure", "flight_figure", "phases_figure",
           "reshade_phases", "shade_phases"]

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

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes to shade.
    segment_table : pandas.DataFrame
        Segments (``phase, t_start, t_end``), s.
    label : bool, optional
        Write the segment names.
    alpha : float, optional
        Opacity.
    gid : str or None, optional
        Group id of the artists.
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
    ``assessment`` (same flight, other segments) in place; returns the new artists.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        A :func:`phases_figure`.
    assessment : FlightAssessment
        The assessment whose segments are shaded.
    """
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


def _wrapped(angle_deg: np.ndarray) -> np.ndarray:
    """``angle_deg`` with NaN where it wraps by more than 180 deg (no vertical lines)."""
    out = np.asarray(angle_deg, dtype=float).copy()
    if out.size > 1:
        jump = np.flatnonzero(np.abs(np.diff(out)) > 180.0)
        out = np.insert(out, jump + 1, np.nan)
    return out


def _wrapped_t(t: np.ndarray, angle_deg: np.ndarray) -> np.ndarray:
    t = np.asarray(t, dtype=float)
    jump = np.flatnonzero(np.abs(np.diff(angle_deg)) > 180.0)
    return np.insert(t, jump + 1, np.nan)


def _tilt_deg(C_b_n: np.ndarray) -> np.ndarray:
    """Angle of body x from the local upward vertical, deg."""
    return np.degrees(np.arccos(np.clip(-C_b_n[:, 2, 0], -1.0, 1.0)))


def _mark_spans(axes, assessment) -> list:
    """Hatch the GNSS outages and the segments the fit does not represent on every axes;
    returns legend handles for what was drawn."""
    handles = []
    outages = getattr(assessment, "gnss_outages", None)
    if outages is not None and len(outages):
        for ax in axes:
            for row in outages.itertuples(index=False):
                ax.axvspan(row.t_start, row.t_end, facecolor="none", edgecolor="0.45",
                           hatch="xx", linewidth=0.0, zorder=0)
        handles.append(Patch(facecolor="none", edgecolor="0.45", hatch="xx",
                             label="GNSS outage (no kept fix)"))
    table = assessment.segment_table
    if "represented" in table:
        bad = table[~table["represented"].astype(bool)]
        for ax in axes:
            for row in bad.itertuples(index=False):
                ax.axvspan(row.t_start, row.t_end, facecolor="none", edgecolor="tab:red",
                           hatch="////", linewidth=0.0, zorder=0)
        for row in bad.itertuples(index=False):   # the reasons: the segment table, warnings
            axes[0].annotate("not represented", ((row.t_start + row.t_end) / 2, 0.02),
                             xycoords=("data", "axes fraction"), ha="center", va="bottom",
                             fontsize=6, color="tab:red",
                             bbox={"facecolor": "white", "alpha": 0.85, "edgecolor": "none",
                                   "pad": 1.0})
        if len(bad):
            handles.append(Patch(facecolor="none", edgecolor="tab:red", hatch="////",
                                 label="segment the fit does not represent"))
    return handles


def flight_figure(assessment):
    """The flight: altitude, speed and attitude of the reference trajectory against the
    records, with residual-over-time panels beneath.

    Top to bottom: geodetic height of the reference, the kept GNSS fixes and the barometer
    (``assessment.logged["baro"]``, shifted by its median offset to the reference, which
    the legend gives); speed of the reference and of the GNSS (its velocity when recorded,
    else differenced consecutive fixes); attitude: the angle of body x from the vertical
    for rockets and logs with a tilt column (``logged["tilt"]``, AltOS), else roll, pitch
    and yaw against the local NED frame (with the logger's own estimate,
    ``logged["attitude"]``, dashed); GNSS minus reference in north, east, down (for a flight
    without GNSS, ``options["aiding"] == "baro"``, the barometric rows its fit was seeded
    with take the GNSS's place, named so); IMU minus
    reference specific force and angular rate per body axis after the fit's calibration and
    a moving average (``imu_residuals["df_x_avg"]`` ...: the residuals ``fit_f_rms`` and
    ``fit_w_rms`` are read from, :func:`navlib.studies.assess.agreement.smoothed_residuals`).
    Assessed segments are shaded by phase, GNSS outages (``assessment.gnss_outages``)
    cross-hatched in grey and segments the fit does not represent
    (``segment_table["represented"]``, when present) hatched in red.
    """
    traj = assessment.trajectory
    sl = _thin(len(traj.t))
    t = traj.t[sl]
    lat, lon, alt = earth.ecef_to_geodetic(traj.position[sl])
    C_n_e = earth.ned_to_ecef_matrix(lat, lon)
    C_b_n = np.swapaxes(C_n_e, 1, 2) @ traj.attitude[sl].as_matrix()
    logged = getattr(assessment, "logged", None) or {}
    # the position rows the reference was fitted to: GNSS fixes, or for a flight without
    # GNSS the barometric-height rows that seed its fit (docs/assumptions.md B5)
    rows = "baro rows" if assessment.options.get("aiding") == "baro" else "GNSS"
    fig, axes = subplots(6, 1, figsize=(11, 12.5), sharex=True, layout="constrained",
                         gridspec_kw={"height_ratios": [3, 2.2, 2.2, 1.8, 1.8, 1.8]})

    # altitude
    ax = axes[0]
    ax.plot(t, alt, color="k", linewidth=1.0, label="reference")
    gnss = assessment.gnss_residuals
    if gnss is not None and len(gnss):
        t_g = gnss["t"].to_numpy(dtype=float)
        d = gnss[["dx", "dy", "dz"]].to_numpy(dtype=float)
        p_g = np.column_stack([np.interp(t_g, traj.t, traj.position[:, i]) for i in range(3)])
        _, _, alt_g = earth.ecef_to_geodetic(p_g + d)
        ax.plot(t_g, alt_g, ".", color="tab:green", markersize=3, label=f"{rows} (kept fixes)")
    baro = logged.get("baro")
    if baro is not None and len(baro):
        t_b = baro["t"].to_numpy(dtype=float)
        h_b = baro["alt_m"].to_numpy(dtype=float)
        offset = float(np.nanmedian(np.interp(t_b, t, alt) - h_b))
        ax.plot(t_b[_thin(t_b.size)], (h_b + offset)[_thin(t_b.size)], color="tab:orange",
                linewidth=0.8, label=f"barometer {offset:+.1f} m (median offset)")
    ax.set_ylabel("height [m]")

    # speed
    ax = axes[1]
    ax.plot(t, np.linalg.norm(traj.velocity[sl], axis=1), color="k", linewidth=1.0,
            label="reference")
    if gnss is not None and len(gnss) > 1:
        if {"dvx", "dvy", "dvz"} <= set(gnss.columns):
            v_g = np.column_stack([np.interp(t_g, traj.t, traj.velocity[:, i])
                                   + gnss[f"dv{a}"].to_numpy(dtype=float)
                                   for i, a in enumerate("xyz")])
            ax.plot(t_g, np.linalg.norm(v_g, axis=1), ".", color="tab:green", markersize=3,
                    label="GNSS velocity")
        else:
            dt = np.diff(t_g)
            near = dt <= 1.5 * np.median(dt)
            speed = np.linalg.norm(np.diff(p_g + d, axis=0), axis=1)[near] / dt[near]
            ax.plot(0.5 * (t_g[1:] + t_g[:-1])[near], speed, ".", color="tab:green",
                    markersize=3, label=f"{rows} (differenced fixes)")
    ax.set_ylabel("speed [m/s]")

    # attitude
    ax = axes[2]
    tilt = logged.get("tilt")
    if tilt is not None or assessment.options.get("vehicle") == "rocket":
        ax.plot(t, _tilt_deg(C_b_n), color="k", linewidth=1.0, label="reference")
        if tilt is not None:
            ax.plot(tilt["t"].iloc[_thin(len(tilt))], tilt["tilt"].iloc[_thin(len(tilt))] / DEG,
                    color="tab:purple", linewidth=0.8, label="logger tilt")
        ax.set_ylabel("body x from\nvertical [deg]")
    else:
        ypr = np.degrees(Rotation.from_matrix(C_b_n).as_euler("ZYX"))
        att = logged.get("attitude")
        if att is not None:
            q = att[["qx", "qy", "qz", "qw"]].to_numpy(dtype=float)
            ok = np.linalg.norm(q, axis=1) > 0.5
            t_a = att["t"].to_numpy(dtype=float)[ok]
            ypr_a = np.degrees(Rotation.from_quat(q[ok]).as_euler("ZYX"))
        colours = ("tab:blue", "tab:orange", "tab:green")
        for k, (name, colour) in enumerate(zip(("yaw", "pitch", "roll"), colours,
                                               strict=True)):
            ax.plot(_wrapped_t(t, ypr[:, k]), _wrapped(ypr[:, k]), color=colour,
                    linewidth=1.0, label=f"{name} reference")
            if att is not None and t_a.size:
                ax.plot(_wrapped_t(t_a, ypr_a[:, k]), _wrapped(ypr_a[:, k]), "--",
                        color=colour, linewidth=0.8, label=f"{name} logger")
        ax.set_ylabel("attitude vs NED [deg]")

    # residuals
    ax = axes[3]
    if gnss is not None and len(gnss):
        lat_g, lon_g, _ = earth.ecef_to_geodetic(p_g)
        d_n = np.einsum("nji,nj->ni", earth.ned_to_ecef_matrix(lat_g, lon_g), d)
        for i, name in enumerate(("north", "east", "down")):
            ax.plot(t_g, d_n[:, i], ".", markersize=2.5, label=f"Δ{name}")
    sigma = assessment.options.get("gnss_sigma_m")
    if sigma:
        ax.axhspan(-sigma, sigma, color="0.88", zorder=0, label=f"±σ = {sigma:.3g} m")
    ax.set_ylabel(f"{rows} − ref [m]")
    imu = assessment.imu_residuals
    if imu is not None and len(imu) > 1:
        t_i = imu["t"].to_numpy(dtype=float)
        sl_i = _thin(t_i.size)
        window = assessment.options["fit_bounds"]["moving_average_s"]
        for ax, prefix, scale, unit in ((axes[4], "df", 1.0, "m/s²"),
                                        (axes[5], "dw", DEG, "deg/s")):
            for axis in "xyz":
                smooth = imu[f"{prefix}_{axis}_avg"].to_numpy(dtype=float) / scale
                ax.plot(t_i[sl_i], smooth[sl_i], linewidth=0.8, label=f"{prefix[1]}_{axis}")
            ax.axhline(0.0, color="0.6", linewidth=0.5)
            ax.set_ylabel(f"IMU − ref [{unit}]\n{window:g} s mean, calibrated")
    axes[-1].set_xlabel("t [s]")
    for k, ax in enumerate(axes):
        shade_phases(ax, assessment.segment_table, label=k == 0, alpha=0.1)
    marks = _mark_spans(axes, assessment)
    for k, ax in enumerate(axes):
        handles, _ = ax.get_legend_handles_labels()
        if k == 0:
            handles = handles + marks
        if handles:
            ax.legend(handles=handles, fontsize=7, ncol=4, loc="upper right")
    fig.suptitle(f"The flight: reference trajectory against the records "
                 f"({traj.name or 'flight'}); shading: assessed segments", fontsize=10)
    return fig
