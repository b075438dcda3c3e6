"""Figures of the SSAC study (Silva et al. 2017; notebook 06).

Thin wrappers over :mod:`navlib.plots.covariance` with the paper's groupings and display
units, plus the P0-sensitivity bar chart. Every builder returns a new Figure; the
``update_*`` functions give a panel's kept figure new data in place.
"""

from __future__ import annotations

import numpy as np

from navlib.plots.covariance import (
    eigenvalues_figure,
    eigenvectors_figure,
    sigma_figure,
    update_eigenvalues_figure,
    update_sigma_figure,
)
from navlib.plots.figure import subplots
from navlib.studies.ssac import STATE_GROUPS, SSACStudy

__all__ = ["SIGMA_PANELS", "p0_sensitivity_figure", "ssac_eigenvalues_figure",
           "ssac_eigenvectors_figure", "ssac_sigma_figure", "update_ssac_eigenvalues_figure",
           "update_ssac_sigma_figure"]

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
    panels = _sigma_panels(study)
    fig = sigma_figure(study.covariance, panels, study.model.parameters["display_units"],
                       log_groups=("velocity", "gyro bias (Fig. 5)",
                                   "accelerometer bias (Fig. 6)"),
                       title=f"SSAC {study.model.n}-state filter: standard deviations")
    for ax, value in _eq44_limits(panels, limits, fig.axes):
        ax.axhline(value, color="k", linestyle="--", linewidth=0.8, label=_eq44_label(value))
        ax.legend(fontsize=8)
    return fig


def update_ssac_sigma_figure(fig, study: SSACStudy, limits=None) -> None:
    """Give a :func:`ssac_sigma_figure` of a study of the same states the sigma(t) and
    eq. (44) limits of ``study``, in place (a panel's kept figure).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        A figure :func:`ssac_sigma_figure` built, with limits when ``limits`` is given.
    study : SSACStudy
        The new covariance run.
    limits : pandas.DataFrame or None, optional
        Closed-form limits (:func:`navlib.studies.ssac.closed_form_limits`).
    """
    panels = _sigma_panels(study)
    update_sigma_figure(fig, study.covariance, panels,
                        study.model.parameters["display_units"])
    for ax, value in _eq44_limits(panels, limits, fig.axes):
        ax.lines[-1].set_ydata([value, value])
        ax.get_legend().get_texts()[-1].set_text(_eq44_label(value))


def _sigma_panels(study: SSACStudy) -> dict:
    names = set(study.state_names)
    panels = {k: tuple(s for s in v if s in names) for k, v in SIGMA_PANELS.items()}
    return {k: v for k, v in panels.items() if v}


def _eq44_limits(panels: dict, limits, axes) -> list:
    """(axes, eq. (44) limit) of the tilt and azimuth panels; none without limits."""
    if limits is None:
        return []
    lim = limits.set_index("state")
    return [(ax, lim.loc[states[0], "eq44"])
            for ax, key, states in zip(axes, panels, panels.values(), strict=False)
            if key.startswith(("tilt", "azimuth"))]


def _eq44_label(value: float) -> str:
    return f"eq. (44) {value:.4g}"


def ssac_eigenvalues_figure(study: SSACStudy):
    """Normalised eigenvalues over time (Fig. 7 analogue), sorted, log scale (of
    :attr:`~navlib.studies.ssac.SSACStudy.spectrum`)."""
    return eigenvalues_figure(study.spectrum, title="Ham–Brown normalised eigenvalues "
                              "(sorted, descending)")


def update_ssac_eigenvalues_figure(fig, study: SSACStudy) -> None:
    """Give a :func:`ssac_eigenvalues_figure` the eigenvalues of ``study``, in place.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        A figure :func:`ssac_eigenvalues_figure` built for a study of as many states.
    study : SSACStudy
        The new covariance run.
    """
    update_eigenvalues_figure(fig, study.spectrum)


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
