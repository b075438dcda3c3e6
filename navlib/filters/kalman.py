"""Kalman-filter algebra shared by the linear simulator, the EKF and
:func:`navlib.covariance.kalman_covariance`: gains with the pseudo-inverse rule, the
Joseph-form update, NEES/NIS consistency statistics (spec launcher.md §6.2-6.4; issue 5).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import stats

from navlib._validation import finite_scalar
from navlib.errors import NavlibInputError

_PINV_RTOL = 1e-12
"""Relative cut-off of the innovation-covariance pseudo-inverse; the value
:func:`navlib.covariance.kalman_covariance` uses by default, so that the gains here
reproduce its posterior covariances."""


def _sym(P):
    return 0.5 * (P + np.swapaxes(P, -1, -2))


def _psd_sqrt(M) -> np.ndarray:
    """Batched symmetric square root ``L`` with ``L L' = M`` for PSD ``M`` (..., n, n)."""
    w, V = np.linalg.eigh(_sym(M))
    return V * np.sqrt(np.clip(w, 0.0, None))[..., None, :]

@dataclass(frozen=True, eq=False)
class Gains:
    """Kalman gains and innovation-covariance pseudo-inverses at every epoch."""

    K: np.ndarray          # (N, n, m)
    S_pinv: np.ndarray     # (N, m, m)
    dof: np.ndarray        # (N,) rank of S used (0 at epochs without update)


def kalman_gains(P_prior, H, R, measured, pinv_rtol: float = _PINV_RTOL) -> Gains:
    """Batched gains ``K = P- H' S^+`` with ``S = H P- H' + R`` (all epochs at once).

    ``S^+`` is the inverse when ``R`` is positive definite and the eigen-decomposition
    pseudo-inverse (eigenvalues below ``pinv_rtol * max`` dropped) otherwise — the rule of
    :func:`navlib.covariance.kalman_covariance`, so the Joseph update with these gains
    reproduces its posteriors. Epochs with ``measured`` False get zero gain.
    """
    P_prior = np.asarray(P_prior)
    N = P_prior.shape[0]
    m = H.shape[-2]
    PHt = P_prior @ np.swapaxes(H, 1, 2)
    S = _sym(H @ PHt + R)
    w, V = np.linalg.eigh(S)
    keep = w > pinv_rtol * np.maximum(w[:, -1:], 0.0)
    inv_w = np.where(keep, 1.0 / np.where(keep, w, 1.0), 0.0)
    S_pinv = (V * inv_w[:, None, :]) @ np.swapaxes(V, 1, 2)
    r_min = np.linalg.eigvalsh(R).min(axis=-1)
    definite = r_min > 1e-12 * np.maximum(np.abs(R).max(axis=(-1, -2)), 1e-300)
    if definite.any():
        S_pinv[definite] = np.linalg.inv(S[definite])
        keep[definite] = True
    K = PHt @ S_pinv
    measured = np.asarray(measured, dtype=bool)
    K[~measured] = 0.0
    dof = np.where(measured, keep.sum(axis=1), 0)
    if m == 0:
        dof = np.zeros(N, dtype=int)
    return Gains(K, S_pinv, dof)


def chi2_bounds(dof, runs: int = 1, alpha: float = 0.05):
    """Two-sided ``1 - alpha`` bounds of a Monte-Carlo averaged NEES or NIS.

    The average over ``runs`` independent runs of a chi-square statistic with ``dof``
    degrees of freedom is ``chi2(runs dof) / runs`` (Bar-Shalom, Li & Kirubarajan 2001,
    §5.4); returns ``(lower, upper)`` (arrays when ``dof`` is one).
    """
    dof = np.asarray(dof, dtype=float)
    runs = int(runs)
    if runs < 1:
        raise NavlibInputError(f"runs: expected >= 1, got {runs}")
    alpha = finite_scalar(alpha, "alpha", 0.0, 1.0, low_open=True)
    total = runs * dof
    lo = np.where(total > 0, stats.chi2.ppf(alpha / 2, np.maximum(total, 1)) / runs, 0.0)
    hi = np.where(total > 0, stats.chi2.ppf(1 - alpha / 2, np.maximum(total, 1)) / runs, 0.0)
    return lo, hi


def nees_basis(P, rtol: float = 1e-10):
    """The data-independent part of :func:`nees_values` for covariances (K, n, n).

    Returns ``(scale, active, V, inv_w, dof)``: the standard deviations used to scale ``P``
    to a correlation matrix, the states with non-zero variance, the eigenvectors of that
    matrix, the inverse of its kept eigenvalues (0 for dropped directions) and the kept
    rank. Computed once per covariance history and reused for every error history
    (:func:`simulate_linear` caches it on the :class:`LinearFilter`).
    """
    d = np.sqrt(np.clip(np.diagonal(P, axis1=1, axis2=2), 0.0, None))
    active = d > 0
    safe = np.where(active, d, 1.0)
    C = P / safe[:, :, None] / safe[:, None, :]
    C = np.where(active[:, :, None] & active[:, None, :], C, 0.0)
    w, V = np.linalg.eigh(_sym(C))
    keep = w > rtol * np.maximum(w[:, -1:], 0.0)
    inv_w = np.where(keep, 1.0 / np.where(keep, w, 1.0), 0.0)
    return safe, active, V, inv_w, keep.sum(axis=1)


def nees_values(err, P, rtol: float = 1e-10, basis=None):
    """NEES ``e' P^+ e`` of errors (K, R, n) against covariances (K, n, n); returns the
    NEES (K, R) and its degrees of freedom (K,).

    Scaled to a correlation matrix first (states of very different units); directions with
    (relative) zero variance are left out, and the degrees of freedom are the kept rank.
    ``basis``: :func:`nees_basis` of ``P`` when already computed (``P`` and ``rtol`` are
    then not used).
    """
    safe, active, V, inv_w, dof = basis if basis is not None else nees_basis(P, rtol)
    en = np.where(active[:, None, :], err / safe[:, None, :], 0.0)
    proj = en @ V
    return (proj**2 @ inv_w[:, :, None])[..., 0], dof


def _joseph_update(P, H, R, innov):
    """Joseph-form update with the pseudo-inverse rule of kalman_covariance; returns
    ``(P_post, K, S_pinv, dof)``."""
    PHt = P @ H.T
    S = _sym(H @ PHt + R)
    r_min = np.linalg.eigvalsh(R).min() if R.size else 0.0
    if R.size and r_min > 1e-12 * max(np.abs(R).max(), 1e-300):
        S_pinv = np.linalg.inv(S)
        dof = S.shape[0]
    else:
        w, V = np.linalg.eigh(S)
        keep = w > _PINV_RTOL * max(w[-1], 0.0)
        S_pinv = (V[:, keep] / w[keep]) @ V[:, keep].T
        dof = int(keep.sum())
    K = PHt @ S_pinv
    IKH = np.eye(P.shape[0]) - K @ H
    return _sym(IKH @ P @ IKH.T + K @ R @ K.T), K, S_pinv, dof
