"""Figures for the outlier-sensitivity study (Beaudoin et al. 2018 Figs. 4, 7-13 analogues).

Builders take the result objects of :mod:`navlib.studies.outliers` and return new matplotlib
Figures; they only convert units (rad -> deg or urad) and lay out axes.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from navlib.errors import NavlibInputError
from navlib.models.launcher import SOLUTION_LABELS
from navlib.plots.figure import subplots
from navlib.units import DEG

__all__ = ["consistency_figure", "correlation_figure", "ekf_crosscheck_figure", "ekf_sigma_figure",
           "induced_figure", "monte_carlo_figure", "response_figure", "roll_sigma_figure"]

_UNITS = {  # watch -> (label, factor applied to SI values)
    "roll": ("urad", 1e6), "pitch": ("urad", 1e6), "yaw": ("urad", 1e6),
    "ref_roll": ("urad", 1e6), "bp": ("m", 1.0),
}


def _unit(watch: str):
    return _UNITS.get(watch, ("", 1.0))


def response_figure(responses: Sequence, title: str | None = None, before: float = 5.0,
                    component: int = 0):
    """Truth and estimate of the watched error state around an outlier, one panel per
    solution, with the filter's +-3 sigma around the truth (Figs. 4, 8, 9, 12 analogues).

    Parameters
    ----------
    responses : sequence of OutlierResponse
    before : float
        Seconds shown before the outlier.
    component : int
        Component of a vector quantity (``bp``: 0 = ECEF x).
    """
    responses = list(responses)
    if not responses:
        raise NavlibInputError("responses: need at least one OutlierResponse")
    fig, axes = subplots(1, len(responses), figsize=(5.2 * len(responses), 3.4),
                         squeeze=False, constrained_layout=True, sharey=False)
    for ax, r in zip(axes[0], responses, strict=True):
        label, f = _unit(r.watch)
        t_o = r.outlier.time
        sel = r.t >= t_o - before
        t = r.t[sel]
        truth = r.truth[sel, component] * f
        est = r.estimate[sel, component] * f
        sig = r.sigma[sel, component] * f
        ax.fill_between(t, truth - 3 * sig, truth + 3 * sig, color="0.85",
                        label="truth +- 3 sigma")
        ax.plot(t, truth, color="k", lw=1.2, label="true error")
        ax.plot(t, est, color="C3", lw=1.2, label="estimate")
        ax.axvline(t_o, color="0.5", ls=":", lw=1)
        s = r.score
        ax.set_title(f"{SOLUTION_LABELS.get(r.solution, r.solution)}: {s.verdict}\n"
                     f"retained {s.retained:.2f}, tau {s.time_constant:.3g} s", fontsize=9)
        ax.set_xlabel("t [s]")
        ax.set_ylabel(f"{r.watch} error [{label}]")
        ax.grid(True, alpha=0.3)
        # keep the response visible: the 3-sigma band may be far larger
        span = np.nanmax(np.abs(np.concatenate([truth, est])))
        if span > 0:
            ax.set_ylim(-2.5 * span, 2.5 * span)
    axes[0, 0].legend(fontsize=8, loc="best")
    fig.suptitle(title or responses[0].outlier.label())
    return fig


def induced_figure(responses: Sequence, title: str | None = None, log: bool = True):
    """Outlier-induced error ``|d(t)|`` of several solutions on one axis, with the recovery
    window's end marked (the quantity the verdict scores).

    Parameters
    ----------
    responses : sequence
        Outlier responses of :mod:`navlib.studies.outliers`, one per solution.
    title : str or None, optional
        Axes title.
    log : bool, optional
        Logarithmic y axis.

    Returns
    -------
    matplotlib.figure.Figure
    """
    responses = list(responses)
    fig, ax = subplots(figsize=(7.5, 3.6), constrained_layout=True)
    for i, r in enumerate(responses):
        f = _unit(r.watch)[1]
        d = np.linalg.norm(r.induced, axis=1) * f
        sel = r.t >= r.outlier.time - 1.0
        ax.plot(r.t[sel], d[sel], color=f"C{i}",
                label=f"{SOLUTION_LABELS.get(r.solution, r.solution)} ({r.score.verdict})")
        ax.axhline(r.score.peak * f * np.exp(-1), color=f"C{i}", ls=":", lw=0.8)
    ax.axvline(responses[0].outlier.time + responses[0].score.window, color="0.4", ls="--",
               lw=1, label="end of window")
    if log:
        ax.set_yscale("log")
    ax.set_xlabel("t [s]")
    ax.set_ylabel(f"|induced error| [{_unit(responses[0].watch)[0]}]")
    ax.grid(True, alpha=0.3, which="both")
    ax.legend(fontsize=8)
    ax.set_title(title or "outlier-induced error (dotted: 1/e of the peak)")
    return fig


def correlation_figure(frame, title: str | None = None):
    """Correlation coefficients of ``T_E^B psi`` and ``psi_ref`` per axis (Fig. 10).

    Parameters
    ----------
    frame : pandas.DataFrame
        Correlations with columns ``t``, ``axis`` and ``rho``.
    title : str or None, optional
        Axes title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = subplots(figsize=(6.5, 3.4), constrained_layout=True)
    for axis, sel in frame.groupby("axis", sort=False):
        ax.plot(sel.t, sel.rho, label=axis)
    ax.axhline(-0.9, color="0.5", ls=":", lw=1, label="|rho| = 0.9")
    ax.set_ylim(-1.05, 0.2)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("rho")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(title or "attitude error vs launcher divergence (Fig. 10 analogue)")
    return fig


def roll_sigma_figure(frame, pairs=(("ins_gps", "ins_gps_rt"), ("ins_gps_att", "ins_gps_att_rt")),
                      axis: str = "roll"):
    """Roll-error sigma with and without the reference trajectory (Figs. 7, 11), deg, log.

    Parameters
    ----------
    frame : pandas.DataFrame
        Covariance evolution with a ``solution`` column and sigma columns, rad.
    pairs : sequence of tuple of str, optional
        ``(without RT, with RT)`` solution pairs, one panel each.
    axis : str, optional
        Attitude axis plotted.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, axes = subplots(1, len(pairs), figsize=(5.4 * len(pairs), 3.4), squeeze=False,
                         constrained_layout=True)
    for ax, pair in zip(axes[0], pairs, strict=True):
        for sol in pair:
            sel = frame[(frame.solution == sol) & (frame.axis == axis)]
            ax.plot(sel.t, sel.sigma / DEG, label=SOLUTION_LABELS.get(sol, sol))
        ax.set_yscale("log")
        ax.set_xlabel("t [s]")
        ax.set_ylabel(f"{axis} sigma [deg]")
        ax.grid(True, alpha=0.3, which="both")
        ax.legend(fontsize=8)
    axes[0, 0].set_title("Fig. 7 analogue")
    if len(pairs) > 1:
        axes[0, 1].set_title("Fig. 11 analogue")
    return fig


def monte_carlo_figure(mc, watch: str = "roll", title: str | None = None):
    """Monte-Carlo errors with the outlier: RMS with and without it, the induced part and the
    filter's sigma (the noise band a static error hides in).

    Parameters
    ----------
    mc : object
        Monte-Carlo outlier result of :mod:`navlib.studies.outliers` (frame and score).
    watch : str, optional
        State plotted.
    title : str or None, optional
        Axes title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    label, f = _unit(watch)
    fr = mc.to_frame()
    fig, ax = subplots(figsize=(7.5, 3.6), constrained_layout=True)
    runs = mc.error.shape[1]
    for r in range(min(runs, 20)):
        ax.plot(mc.t, mc.error[:, r, 0] * f, color="0.8", lw=0.5)
    ax.plot(fr.t, fr.rms * f, color="C3", label=f"RMS error ({runs} runs, with outlier)")
    ax.plot(fr.t, fr.rms_nominal * f, color="C0", ls="--", label="RMS error without")
    ax.plot(fr.t, fr.sigma * f, color="k", lw=1, label="filter sigma")
    ax.plot(fr.t, fr.induced * f, color="C2", lw=1.5, label="outlier-induced part")
    ax.set_xlabel("t [s]")
    ax.set_ylabel(f"{watch} estimation error [{label}]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    s = mc.score
    ax.set_title(title or f"{s.verdict}: residual {s.residual * f:.3g} {label} = "
                 f"{s.residual_vs_pre:.2g} x pre-outlier RMS, {s.residual_vs_3sigma:.2g} x 3 sigma",
                 fontsize=9)
    return fig


def consistency_figure(sim, title: str | None = None):
    """Run-averaged NEES and NIS of a :class:`navlib.filters.LinearSimulation` with their
    95 % chi-square bounds.

    Parameters
    ----------
    sim : navlib.filters.LinearSimulation
        The simulation.
    title : str or None, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, axes = subplots(1, 2, figsize=(11, 3.4), constrained_layout=True)
    for ax, frame, key in ((axes[0], sim.nees_frame(), "nees"), (axes[1], sim.nis_frame(), "nis")):
        ax.plot(frame.t, frame[key], lw=0.8, label=f"mean {key.upper()}")
        ax.plot(frame.t, frame.lower, color="k", ls="--", lw=0.8, label="95 % bounds")
        ax.plot(frame.t, frame.upper, color="k", ls="--", lw=0.8)
        ax.set_xlabel("t [s]")
        ax.set_ylabel(key.upper())
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    c = sim.consistency()
    fig.suptitle(title or f"{sim.runs} runs: NEES inside bounds {c['nees']:.0%}, NIS "
                 f"{c['nis']:.0%}")
    return fig


def ekf_crosscheck_figure(check, title: str | None = None):
    """Outlier-induced roll error through the closed-loop EKF and the linear filter.

    Parameters
    ----------
    check : object
        EKF cross-check of :mod:`navlib.studies.outliers.crosscheck`.
    title : str or None, optional
        Axes title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fr = check.to_frame()
    fig, ax = subplots(figsize=(7.5, 3.4), constrained_layout=True)
    ax.plot(fr.t, fr.ekf * 1e6, label=f"EKF ({check.score_ekf.verdict})")
    ax.plot(fr.t, fr.linear * 1e6, ls="--", label=f"linear KF ({check.linear.score.verdict})")
    ax.set_xlim(check.linear.outlier.time - 2.0, fr.t.iloc[-1])
    ax.set_xlabel("t [s]")
    ax.set_ylabel("induced roll error [urad]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(title or f"{SOLUTION_LABELS.get(check.linear.solution)}: "
                 f"{check.linear.outlier.label()}", fontsize=9)
    return fig


def ekf_sigma_figure(frame, axes_names=("roll", "pitch", "yaw", "pos_x")):
    """EKF sigma against the covariance analysis, with the EKF's actual error
    (:func:`navlib.studies.outliers.ekf_vs_covariance`); attitude in deg, position in m.

    Parameters
    ----------
    frame : pandas.DataFrame
        Result of :func:`navlib.studies.outliers.ekf_vs_covariance`.
    axes_names : sequence of str, optional
        States plotted, one panel each.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, axes = subplots(1, len(axes_names), figsize=(4.2 * len(axes_names), 3.2),
                         squeeze=False, constrained_layout=True)
    for ax, name in zip(axes[0], axes_names, strict=True):
        sel = frame[frame.axis == name]
        f, unit = (1.0, "m") if name.startswith("pos") else (1.0 / DEG, "deg")
        ax.plot(sel.t, sel.error * f, color="0.6", lw=0.7, label="EKF error")
        ax.plot(sel.t, 3 * sel.sigma_ekf * f, color="C3", label="EKF 3 sigma")
        ax.plot(sel.t, -3 * sel.sigma_ekf * f, color="C3")
        ax.plot(sel.t, 3 * sel.sigma_cov * f, color="k", ls="--", lw=1,
                label="covariance analysis")
        ax.plot(sel.t, -3 * sel.sigma_cov * f, color="k", ls="--", lw=1)
        ax.set_title(name)
        ax.set_xlabel("t [s]")
        ax.set_ylabel(f"[{unit}]")
        ax.grid(True, alpha=0.3)
    axes[0, 0].legend(fontsize=8)
    return fig
