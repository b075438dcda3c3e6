"""Kalman-filter algebra shared by the linear simulator, the EKF and
:func:`navlib.covariance.kalman_covariance`: gains with the pseudo-inverse rule, the
Joseph-form update, NEES/NIS consistency statistics (spec launcher.md §6.2-6.4; issue 5).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from scipy import stats

from navlib._validation import finite_scalar
from navlib.covariance import symmetrize
from navlib.errors import NavlibInputError

_PINV_RTOL = 1e-12
"""Relative cut-off of the innovation-covariance pseudo-inverse; the value
:func:`navlib.covariance.kalman_covariance` uses by default, so that the gains here
reproduce its posterior covariances."""


def _psd_sqrt(M) -> np.ndarray:
    """Batched symmetric square root ``L`` with ``L L' = M`` for PSD ``M`` (..., n, n)."""
    w, V = np.linalg.eigh(symmetrize(M))
    return V * np.sqrt(np.clip(w, 0.0, None))[..., None, :]

def definite_noise(R) -> np.ndarray:
    """Whether each measurement-noise covariance ``R`` (..., m, m) is positive definite
    (smallest eigenvalue above ``1e-12`` of its largest entry): the switch between the
    inverse and the pseudo-inverse of the innovation covariance in :func:`kalman_gain`."""
    R = np.asarray(R, dtype=float)
    if R.shape[-1] == 0:
        return np.zeros(R.shape[:-2], dtype=bool)
    r_min = np.linalg.eigvalsh(R).min(axis=-1)
    return r_min > 1e-12 * np.maximum(np.abs(R).max(axis=(-1, -2)), 1e-300)


@dataclass(frozen=True, eq=False)
class Gains:
    """Kalman gains and innovation-covariance pseudo-inverses (one epoch or a batch)."""

    K: np.ndarray          # (..., n, m)
    S_pinv: np.ndarray     # (..., m, m)
    dof: np.ndarray        # (...,) rank of S used (0 at epochs without update)


def kalman_gain(P_prior, H, R, *, pinv_rtol: float = _PINV_RTOL, definite=None) -> Gains:
    """Gain ``K = P- H' S^+`` with ``S = H P- H' + R``, for one epoch or a batch.

    ``S^+`` is the inverse when ``R`` is positive definite (:func:`definite_noise`) and the
    eigen-decomposition pseudo-inverse otherwise (eigenvalues below ``pinv_rtol * max``
    dropped), which gives the optimal update in the measured subspace and no update in the
    directions with ``S = 0`` (ideal measurements, ``R = 0``). The one implementation of
    this rule: :func:`joseph_update`, :func:`kalman_gains`, the EKF
    (:func:`navlib.filters.ekf`) and :func:`navlib.covariance.kalman_covariance` use it.

    Parameters
    ----------
    P_prior : ndarray (..., n, n)
    H : ndarray (..., m, n)
    R : ndarray (..., m, m)
    pinv_rtol : float
    definite : bool or ndarray (...,) of bool, optional
        :func:`definite_noise` of ``R`` when already known (computed otherwise).
    """
    P_prior = np.asarray(P_prior, dtype=float)
    H = np.asarray(H, dtype=float)
    PHt = P_prior @ H.swapaxes(-1, -2)
    S = symmetrize(H @ PHt + R)
    batch, m = S.shape[:-2], S.shape[-1]
    if m == 0:
        return Gains(PHt, S, np.zeros(batch, dtype=int))
    definite = np.asarray(definite_noise(R) if definite is None else definite, dtype=bool)
    if bool(definite) if definite.ndim == 0 else definite.all():
        S_pinv, dof = np.linalg.inv(S), np.full(batch, m) if batch else np.int64(m)
    elif definite.ndim == 0 or not definite.any():
        S_pinv, dof = _eigen_pinv(S, pinv_rtol)
    else:
        definite = np.broadcast_to(definite, batch)
        S_pinv, dof = np.empty_like(S), np.full(batch, m)
        S_pinv[definite] = np.linalg.inv(S[definite])
        S_pinv[~definite], dof[~definite] = _eigen_pinv(S[~definite], pinv_rtol)
    return Gains(PHt @ S_pinv, S_pinv, dof)


def _eigen_pinv(S, rtol: float):
    """Eigen-decomposition pseudo-inverse of symmetric ``S`` (..., m, m) and its kept rank."""
    w, V = np.linalg.eigh(S)
    keep = w > rtol * np.maximum(w[..., -1:], 0.0)
    inv_w = np.where(keep, 1.0 / np.where(keep, w, 1.0), 0.0)
    return (V * inv_w[..., None, :]) @ V.swapaxes(-1, -2), keep.sum(axis=-1)


@functools.cache
def _identity(n: int) -> np.ndarray:
    """The (read-only) n x n identity of :func:`joseph_update`, made once per size."""
    eye = np.eye(n)
    eye.flags.writeable = False
    return eye


def joseph_update(P_prior, H, R, *, pinv_rtol: float = _PINV_RTOL, definite=None):
    """Joseph-form measurement update ``P+ = (I - K H) P- (I - K H)' + K R K'`` with the
    gain of :func:`kalman_gain` (one epoch or a batch); returns ``(P_post, Gains)``.

    The Joseph form holds for any gain, so ``P+`` stays symmetric positive semi-definite
    with a singular or zero ``R`` (spec launcher.md §6.2).
    """
    P_prior = np.asarray(P_prior, dtype=float)
    gains = kalman_gain(P_prior, H, R, pinv_rtol=pinv_rtol, definite=definite)
    K = gains.K
    IKH = _identity(P_prior.shape[-1]) - K @ H
    P_post = IKH @ P_prior @ IKH.swapaxes(-1, -2) + K @ R @ K.swapaxes(-1, -2)
    return symmetrize(P_post), gains


def kalman_gains(P_prior, H, R, measured, pinv_rtol: float = _PINV_RTOL) -> Gains:
    """Batched gains of :func:`kalman_gain` at all epochs at once (P_prior (N, n, n)).

    The rule of :func:`navlib.covariance.kalman_covariance`, so the Joseph update with these
    gains reproduces its posteriors. Epochs with ``measured`` False get zero gain and dof.
    """
    gains = kalman_gain(P_prior, H, R, pinv_rtol=pinv_rtol)
    measured = np.asarray(measured, dtype=bool)
    gains.K[~measured] = 0.0
    return Gains(gains.K, gains.S_pinv, np.where(measured, gains.dof, 0))


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
    w, V = np.linalg.eigh(symmetrize(C))
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
