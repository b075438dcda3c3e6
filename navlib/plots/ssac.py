"""Figures of the SSAC study (Silva et al. 2017; notebook 06).

Thin wrappers over :mod:`navlib.plots.covariance` with the paper's groupings and display
units, plus the P0-sensitivity bar chart. Every builder returns a new Figure.
"""

from __future__ import annotations

import numpy as np

from navlib.plots.covariance import eigenvalues_figure, eigenvectors_figure, sigma_figure
from navlib.plots.figure import subplots
from navlib.studies.ssac import STATE_GROUPS, SSACStudy

__all__ = ["SIGMA_PANELS", "p0_sensitivity_figure", "ssac_eigenvalues_figure",
           "ssac_eigenvectors_figure", "ssac_sigma_figure"]

SIGMA_PANELS = {
    "tilt (Fig. 1)": ("psiN", "psiE"),
    "azimuth (Fig. 2)": ("psiD",),
    "velocity": STATE_GROUPS["velocity"],
    "position (Figs. 3-4)": STATE_GROUPS["position"],
    "gyro bias (Fig. 5)": STATE_GROUPS["gyro bias"],
    "accelerometer bias (Fig. 6)": STATE_GROUPS["accelerometer bias"],
}
"""Panels of :func:`ssac_sigma_figure` (Figs. 1–6 analogues; figure identities inferred,
ssac.md §5.2)."""


def ssac_sigma_figure(study: SSACStudy, limits=None):
    """sigma(t) of all 15 states in six panels (deg, m/s, m, deg/h, mg; bias panels log).

    ``limits`` (a :func:`navlib.studies.ssac.closed_form_limits` frame) adds dashed lines at
    the eq. (44) limits of psiN/psiE and psiD.

    Parameters
    ----------
    study : SSACStudy
        The covariance run.
    limits : pandas.DataFrame or None, optional
        Closed-form limits drawn as dashed lines.

    Returns
    -------
    matplotlib.figure.Figure
    """
    names = set(study.state_names)
    panels = {k: tuple(s for s in v if s in names) for k, v in SIGMA_PANELS.items()}
    panels = {k: v for k, v in panels.items() if v}
    fig = sigma_figure(study.covariance, panels, study.model.parameters["display_units"],
                       log_groups=("velocity", "gyro bias (Fig. 5)",
                                   "accelerometer bias (Fig. 6)"),
                       title=f"SSAC {study.model.n}-state filter: standard deviations")
    if limits is not None:
        lim = limits.set_index("state")
        for ax, key, states in zip(fig.axes, panels, panels.values(), strict=False):
            if key.startswith(("tilt", "azimuth")):
                value = lim.loc[states[0], "eq44"]
                ax.axhline(value, color="k", linestyle="--", linewidth=0.8,
                           label=f"eq. (44) {value:.4g}")
                ax.legend(fontsize=8)
    return fig


def ssac_eigenvalues_figure(study: SSACStudy):
    """Normalised eigenvalues over time (Fig. 7 analogue), sorted, log scale."""
    return eigenvalues_figure(study.eigen, title="Ham–Brown normalised eigenvalues "
                              "(sorted, descending)")


def ssac_eigenvectors_figure(study: SSACStudy, tracked: bool = False):
    """Components of the six largest modes over time (Figs. 8–13 analogues).

    Sorted order (default) shows the X-shape exchanges; ``tracked=True`` follows each
    branch backwards from its 60 min direction.

    Parameters
    ----------
    study : SSACStudy
        The covariance run.
    tracked : bool, optional
        Follow each branch instead of the sorted order.

    Returns
    -------
    matplotlib.figure.Figure
    """
    return eigenvectors_figure(study.eigen, modes=range(1, 7), tracked=tracked, t_from_s=60.0,
                               title="eigenvectors of the six largest normalised eigenvalues"
                               + (" (tracked)" if tracked else " (sorted)"))


def p0_sensitivity_figure(table):
    """Bias share of each pair mode, matched vs modified P0 (Figs. 23–25 analogue).

    ``table`` is :func:`navlib.studies.ssac.p0_sensitivity`.
    """
    variants = list(dict.fromkeys(table["P0"]))
    pairs = list(dict.fromkeys(table["pair"]))
    fig, ax = subplots(figsize=(7, 3.5), constrained_layout=True)
    width = 0.8 / len(variants)
    x = np.arange(len(pairs))
    for i, variant in enumerate(variants):
        rows = table[table["P0"] == variant].set_index("pair").loc[pairs]
        ax.bar(x + i * width, rows["bias_share"], width, label=variant)
    ax.axhline(1 / np.sqrt(2), color="k", linestyle=":", linewidth=0.8, label="45° (1/√2)")
    ax.set_xticks(x + width * (len(variants) - 1) / 2, pairs)
    ax.set_ylim(0, 1.05)
    ax.set_ylabel("bias component of the pair mode")
    ax.set_title("P0 sensitivity: bias share at the end of the run")
    ax.legend(fontsize=8)
    return fig
