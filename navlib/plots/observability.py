"""Figures for the observability-matrix study (notebook 02, Beaudoin et al. 2018 §4.1).

Each builder takes library results (:class:`navlib.observability.LocalObservability`,
:class:`navlib.observability.ObservabilityResult`, :class:`navlib.studies.launcher.Table2Result`
or the :func:`navlib.studies.launcher.fig1_data` frame) and returns a new Figure.
"""

from __future__ import annotations

import numpy as np
from matplotlib.ticker import MaxNLocator

from navlib.models.launcher import SOLUTION_LABELS
from navlib.plots.figure import subplots
from navlib.plots.trajectory import LAUNCHER_MARKERS, mark_events
from navlib.studies.launcher import SINGULAR_LOG10

__all__ = ["UNACCEPTABLE_LOG10", "fig1_figure", "mission_figure", "singular_values_figure",
           "table2_figure"]

UNACCEPTABLE_LOG10 = 10.0
"""cond > 1e10 is unacceptable in double precision (Beaudoin et al., after Judd [37])."""


def fig1_figure(data, s_t: float = 0.005):
    """Fig. 1 analogue: cond of the simplified model's O against ``c_p`` (log-log).

    Parameters
    ----------
    data : pandas.DataFrame
        From :func:`navlib.studies.launcher.fig1_data` (``c_p``, ``cond``, ``rank``).
    s_t : float
        Sampling time used, s (for the ``1.171 c_p / s_t`` guide line).
    """
    finite = data[np.isfinite(data.c_p)]
    fig, ax = subplots(figsize=(7, 4.5), layout="constrained")
    ax.loglog(finite.c_p, finite.cond, "o-", color="C0", label="cond(O), rank 6")
    guide = np.logspace(np.log10(finite.c_p.min()), np.log10(finite.c_p.max()), 50)
    ax.loglog(guide, 1.171 * guide / s_t, "--", color="0.5",
              label=r"$1.171\,c_p/s_t$ (spec §10a)")
    infinite = data[~np.isfinite(data.c_p)]
    if len(infinite):
        row = infinite.iloc[0]
        ax.axhline(row.cond, color="C3", linestyle=":",
                   label=f"$c_p=\\infty$ (random walk): rank {int(row['rank'])}, "
                         f"cond {row.cond:.1e}")
    ax.set_xlabel("GPS-bias Markov time constant $c_p$ [s]")
    ax.set_ylabel("condition number of O")
    ax.set_title(f"Simplified position / GPS-bias model (eq. 7), $s_t$ = {s_t * 1e3:g} ms")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return fig


def mission_figure(res, events: dict | None = None, title: str = ""):
    """Rank and log10 condition number of the local O(k) over the mission.

    Parameters
    ----------
    res : LocalObservability
    events : dict, optional
        Trajectory events (name -> s) to mark, e.g. ``traj.events``.
    """
    frame = res.to_frame()
    fig, (ax_r, ax_c) = subplots(2, 1, sharex=True, figsize=(8, 5.5), layout="constrained")
    ax_r.step(frame.t, frame["rank"], where="post", color="C0", label="rank O(k)")
    ax_r.axhline(res.n, color="0.5", linestyle="--", linewidth=1, label=f"n = {res.n}")
    ax_r.set_ylabel("rank")
    ax_r.set_ylim(min(frame["rank"].min(), res.n) - 1.5, res.n + 1.5)
    ax_r.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax_r.legend(fontsize=8, loc="lower right")
    ax_c.plot(frame.t, frame.log10_cond, color="C1")
    ax_c.axhline(UNACCEPTABLE_LOG10, color="C3", linestyle=":", linewidth=1,
                 label="1e10: unacceptable (double precision)")
    ax_c.set_ylabel("log10 cond O(k)")
    ax_c.set_xlabel("time [s]")
    ax_c.legend(fontsize=8, loc="best")
    for ax in (ax_r, ax_c):
        ax.grid(True, alpha=0.3)
        if events:
            mark_events(ax, events, LAUNCHER_MARKERS, label=ax is ax_r)
    fig.suptitle(title or f"Local observability over the mission ({res.variant}, "
                 f"window {res.window} steps, rtol {res.rtol:.1e})")
    return fig


def table2_figure(result):
    """Our log10 max cond against the paper's, one point per configuration of Table 2.

    Filled markers: unobservable count matches the paper; open markers: it does not. The
    grey band is the match tolerance; the shaded corner is "numerically singular" (>= 1e16).
    """
    frame = result.frame
    fig, ax = subplots(figsize=(7, 6), layout="constrained")
    lo, hi = -0.5, max(21.0, frame.log10_cond.max() + 0.5)
    diag = np.array([lo, hi])
    ax.fill_between(diag, diag - result.cond_tol, diag + result.cond_tol, color="0.9",
                    label=f"match: ±{result.cond_tol:g} order")
    ax.fill_between([SINGULAR_LOG10, hi], SINGULAR_LOG10, hi, color="C3", alpha=0.08,
                    label="both numerically singular (match)")
    ax.plot(diag, diag, color="0.5", linewidth=0.8)
    markers = {"none": "s", "markov": "o", "random_walk": "^"}
    for i, (solution, label) in enumerate(SOLUTION_LABELS.items()):
        for model, marker in markers.items():
            sel = frame[(frame.solution == solution) & (frame.bias_model == model)]
            if not len(sel):
                continue
            jitter = 0.08 * (i - 1.5)
            ok = sel.match_unobservable
            ax.scatter(sel.paper_log10_cond[ok] + jitter, sel.log10_cond[ok], marker=marker,
                       color=f"C{i}", label=f"{label}, {model}")
            ax.scatter(sel.paper_log10_cond[~ok] + jitter, sel.log10_cond[~ok], marker=marker,
                       facecolors="none", edgecolors=f"C{i}")
    ax.set_xlim(lo, hi)
    ax.set_ylim(lo, hi)
    ax.set_xlabel("paper: log10 cond (Table 2)")
    ax.set_ylabel("ours: log10 max cond over the mission")
    n_match = int(frame.match.sum())
    ax.set_title(f"Table 2: {n_match}/{len(frame)} configurations match "
                 f"({result.variant}, {result.duration_s:g} s mission)")
    ax.legend(fontsize=6, ncol=2, loc="upper left")
    ax.grid(True, alpha=0.3)
    return fig


def singular_values_figure(analysis, title: str = ""):
    """Singular values of one local O(k) with the rank threshold ``rtol * sigma_1``."""
    s = analysis.singular_values
    fig, ax = subplots(figsize=(7, 3.5), layout="constrained")
    keep = np.arange(s.size) < analysis.rank
    with np.errstate(divide="ignore"):
        log_s = np.log10(np.where(s > 0, s, np.nan))
    ax.bar(np.arange(1, s.size + 1)[keep], log_s[keep], color="C0", label="counted in rank")
    ax.bar(np.arange(1, s.size + 1)[~keep], log_s[~keep], color="C3", label="below threshold")
    ax.axhline(np.log10(analysis.rtol * s[0]), color="0.3", linestyle="--", linewidth=1,
               label=f"rtol × σ1 (rtol {analysis.rtol:.1e})")
    ax.set_xlabel("index i")
    ax.set_ylabel("log10 σ_i")
    ax.set_title(title or f"rank {analysis.rank}/{analysis.n}, cond {analysis.cond:.2e}")
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    return fig
