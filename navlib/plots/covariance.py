"""Generic figures for covariance histories and the normalised eigen-analysis.

Builders take :class:`navlib.covariance.CovarianceResult` /
:class:`navlib.covariance.NormalizedEigenResult` objects and return new matplotlib Figures;
they only convert units and lay out axes.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import matplotlib.pyplot as plt
import numpy as np

from navlib.errors import NavlibInputError
from navlib.plots.figure import subplots

__all__ = ["TIME_UNITS", "eigenvalues_figure", "eigenvectors_figure", "ratio_figure", "sigma_axes",
           "sigma_figure", "update_eigenvalues_figure", "update_sigma_figure"]

TIME_UNITS = {"s": 1.0, "min": 60.0, "h": 3600.0}


def _time(t, unit: str):
    if unit not in TIME_UNITS:
        raise NavlibInputError(f"time_unit: expected one of {list(TIME_UNITS)}, got {unit!r}")
    return np.asarray(t) / TIME_UNITS[unit]


def _sigma_curves(result, states, units, time_unit: str, prior: bool = False):
    """Times and sigma(t) of each state in its display unit."""
    sigma = result.sigma_prior if prior else result.sigma
    idx = result.index(list(states))
    return _time(result.t, time_unit), [sigma[:, i] * (units or {}).get(name, ("", 1.0))[1]
                                        for name, i in zip(states, idx, strict=True)]


def sigma_axes(ax, result, states: Sequence[str], units: Mapping | None = None,
               time_unit: str = "min", log: bool = False, prior: bool = False) -> None:
    """Draw sigma(t) of ``states`` on ``ax``; ``units`` maps state -> (label, factor).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes to draw on.
    result : CovarianceResult
        Covariance history.
    states : sequence of str
        States drawn.
    units : Mapping or None, optional
        State -> (unit label, factor from SI).
    time_unit : {"s", "min", "h"}, optional
        Unit of the time axis.
    log : bool, optional
        Logarithmic y axis.
    prior : bool, optional
        Draw the prior instead of the posterior sigma.
    """
    t, curves = _sigma_curves(result, states, units, time_unit, prior)
    labels = {(units or {}).get(name, ("", 1.0))[0] for name in states}
    for name, curve in zip(states, curves, strict=True):
        ax.plot(t, curve, label=name)
    if log:
        ax.set_yscale("log")
    ax.set_xlabel(f"t [{time_unit}]")
    ax.set_ylabel("sigma" + (f" [{', '.join(sorted(labels))}]" if any(labels) else ""))
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)


def sigma_figure(result, groups: Mapping[str, Sequence[str]], units: Mapping | None = None,
                 log_groups: Sequence[str] = (), time_unit: str = "min", ncols: int = 3,
                 title: str | None = None):
    """One panel per group of states: sigma(t) in display units.

    Parameters
    ----------
    result : CovarianceResult
    groups : mapping title -> state names
    units : mapping state -> (unit label, factor), optional
    log_groups : titles of groups drawn with a logarithmic y axis
    """
    n = len(groups)
    nrows = int(np.ceil(n / ncols))
    fig, axes = subplots(nrows, ncols, figsize=(4.2 * ncols, 3.0 * nrows), squeeze=False,
                         constrained_layout=True)
    for k, (ax, (name, states)) in enumerate(zip(axes.flat, groups.items(), strict=False)):
        sigma_axes(ax, result, states, units, time_unit, log=name in log_groups)
        ax.set_title(name)
        if k + ncols < n:  # the panel below it shows the common time axis
            ax.tick_params(labelbottom=False)
            ax.set_xlabel("")
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    if title:
        fig.suptitle(title)
    return fig


def update_sigma_figure(fig, result, groups: Mapping[str, Sequence[str]],
                        units: Mapping | None = None, time_unit: str = "min") -> None:
    """Give a :func:`sigma_figure` of the same groups the sigma(t) of ``result``, in place
    (lines only: a panel's kept figure; the caller rescales the axes).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        A figure :func:`sigma_figure` built with ``groups``.
    result : CovarianceResult
        The new covariance history.
    groups, units, time_unit
        As given to :func:`sigma_figure`.
    """
    for ax, states in zip(fig.axes, groups.values(), strict=False):
        t, curves = _sigma_curves(result, states, units, time_unit)
        for line, curve in zip(ax.lines, curves, strict=False):
            line.set_data(t, curve)


def _eigenvalue_curves(eig, modes, time_unit: str, tracked: bool):
    values = eig.tracked_values if tracked else eig.eigenvalues
    modes = list(range(1, eig.n + 1)) if modes is None else list(modes)
    return modes, _time(eig.t, time_unit), [np.clip(values[:, m - 1], 1e-12, None)
                                            for m in modes]


def update_eigenvalues_figure(fig, eig, modes: Sequence[int] | None = None,
                              time_unit: str = "min", tracked: bool = False) -> None:
    """Give an :func:`eigenvalues_figure` of the same modes the eigenvalues of ``eig``, in
    place (lines only: a panel's kept figure; the caller rescales the axes).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        A figure :func:`eigenvalues_figure` built with ``modes``.
    eig : NormalizedEigenResult
        The new eigen-analysis.
    modes, time_unit, tracked
        As given to :func:`eigenvalues_figure`.
    """
    _, t, curves = _eigenvalue_curves(eig, modes, time_unit, tracked)
    for line, curve in zip(fig.axes[0].lines, curves, strict=True):
        line.set_data(t, curve)


def eigenvalues_figure(eig, modes: Sequence[int] | None = None, time_unit: str = "min",
                       log: bool = True, tracked: bool = False, title: str | None = None):
    """Normalised eigenvalues over time (Silva et al. Fig. 7 analogue), modes 1-based.

    Parameters
    ----------
    eig : NormalizedEigenResult
        Eigen-decomposition of the normalised covariance over time.
    modes : sequence of int or None, optional
        Modes drawn, 1-based; None: all.
    time_unit : {"s", "min", "h"}, optional
        Unit of the time axis.
    log : bool, optional
        Logarithmic y axis.
    tracked : bool, optional
        Draw the tracked instead of the sorted eigenvalues.
    title : str or None, optional
        Axes title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    modes, t, curves = _eigenvalue_curves(eig, modes, time_unit, tracked)
    fig, ax = subplots(figsize=(8, 4), constrained_layout=True)
    for m, curve in zip(modes, curves, strict=True):
        ax.plot(t, curve, label=f"λ{m}", linewidth=1.6 if m <= 6 else 0.9)
    if log:
        ax.set_yscale("log")
    ax.set_xlabel(f"t [{time_unit}]")
    ax.set_ylabel(f"normalised eigenvalue (sum = {eig.order:g})")
    ax.grid(True, alpha=0.3)
    ax.legend(ncol=5, fontsize=7)
    ax.set_title(title or ("tracked" if tracked else "sorted") + " eigenvalues of P_n(t)")
    return fig


def eigenvectors_figure(eig, modes: Sequence[int] = (1, 2, 3, 4, 5, 6), min_component: float
                        = 0.1, time_unit: str = "min", tracked: bool = False, ncols: int = 3,
                        t_from_s: float = 0.0, title: str | None = None):
    """Eigenvector components over time, one panel per mode (Figs. 8–13 analogues).

    Only states whose component exceeds ``min_component`` in magnitude at some epoch after
    ``t_from_s`` (s) are drawn. With ``tracked=False`` (sorted order) crossings of nearly equal
    eigenvalues show as the paper's X-shape; ``tracked=True`` follows the branches.

    Parameters
    ----------
    eig : NormalizedEigenResult
        Eigen-decomposition of the normalised covariance over time.
    modes : sequence of int, optional
        Modes drawn, 1-based, one panel each.
    min_component : float, optional
        Smallest component magnitude of a state drawn.
    time_unit : {"s", "min", "h"}, optional
        Unit of the time axis.
    tracked : bool, optional
        Draw the tracked instead of the sorted eigenvectors.
    ncols : int, optional
        Panels per row.
    t_from_s : float, optional
        Time from which components are considered, s.
    title : str or None, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    vectors = eig.tracked_vectors if tracked else eig.eigenvectors
    modes = list(modes)
    nrows = int(np.ceil(len(modes) / ncols))
    fig, axes = subplots(nrows, ncols, figsize=(4.2 * ncols, 2.8 * nrows), squeeze=False,
                         sharex=True, constrained_layout=True)
    t = _time(eig.t, time_unit)
    start = int(np.searchsorted(eig.t, t_from_s))
    colors = plt.get_cmap("tab20").colors  # one colour per state, stable across panels
    for ax, m in zip(axes.flat, modes, strict=False):
        comp = vectors[start:, :, m - 1]
        shown = np.flatnonzero(np.abs(comp).max(axis=0) > min_component)
        for line, j in enumerate(shown):  # dashes keep overlapping +-0.707 pairs visible
            ax.plot(t[start:], comp[:, j], label=eig.state_names[j],
                    color=colors[j % len(colors)], linestyle=("-", "--", ":", "-.")[line % 4])
        ax.set_ylim(-1.05, 1.05)
        ax.set_title(f"mode {m}" + (" (tracked)" if tracked else ""))
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="best")
    for ax in axes.flat[len(modes):]:
        ax.set_visible(False)
    for ax in axes[-1]:
        ax.set_xlabel(f"t [{time_unit}]")
    if title:
        fig.suptitle(title)
    return fig


def ratio_figure(t, ratio, state_names: Sequence[str], states: Sequence[str] | None = None,
                 time_unit: str = "min", title: str | None = None):
    """Covariance ratio sigma_i(t0)/sigma_i(t) over time (log y), e.g. from
    :func:`navlib.covariance.covariance_ratio`.

    Parameters
    ----------
    t : numpy.ndarray
        Times, s.
    ratio : numpy.ndarray
        Covariance ratios, (N, n).
    state_names : sequence of str
        Names of the ``n`` columns.
    states : sequence of str or None, optional
        States drawn; None: all.
    time_unit : {"s", "min", "h"}, optional
        Unit of the time axis.
    title : str or None, optional
        Axes title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    names = list(state_names)
    states = names if states is None else list(states)
    fig, ax = subplots(figsize=(8, 4), constrained_layout=True)
    tt = _time(t, time_unit)
    for s in states:
        ax.plot(tt, ratio[:, names.index(s)], label=s)
    ax.set_yscale("log")
    ax.set_xlabel(f"t [{time_unit}]")
    ax.set_ylabel("sigma(t0) / sigma(t)")
    ax.grid(True, alpha=0.3)
    ax.legend(ncol=5, fontsize=7)
    if title:
        ax.set_title(title)
    return fig
