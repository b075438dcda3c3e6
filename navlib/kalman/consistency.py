"""Filter consistency statistics of :mod:`navlib.kalman`: the Monte-Carlo NEES/NIS bounds and
the normalised estimation errors (docs/assumptions.md, launcher.md §6.2-6.4)."""

from __future__ import annotations

import numpy as np
from scipy.special import gammaincinv

from navlib._validation import finite_scalar
from navlib.errors import NavlibInputError
from navlib.kalman.algebra import symmetrize

__all__ = ["chi2_bounds", "nees_basis", "nees_values"]


def chi2_bounds(dof, runs: int = 1, alpha: float = 0.05):
    """Two-sided ``1 - alpha`` bounds of a Monte-Carlo averaged NEES or NIS.

    The average over ``runs`` independent runs of a chi-square statistic with ``dof``
    degrees of freedom is ``chi2(runs dof) / runs`` (Bar-Shalom, Li & Kirubarajan 2001,
    §5.4).

    The chi-square quantile is ``2 gammaincinv(k / 2, q)``, what ``scipy.stats.chi2.ppf``
    evaluates (the same numbers), without importing ``scipy.stats`` (about 0.3-0.7 s in a
    process that needs nothing else of it), and once per distinct ``dof`` (a NEES history
    has one per epoch but a few distinct values; each quantile is an iterative inversion).

    Parameters
    ----------
    dof : int or array_like of int
        Degrees of freedom of one run.
    runs : int
        Independent runs averaged.
    alpha : float
        Two-sided significance level.

    Returns
    -------
    lower, upper : float or ndarray
        Shaped like ``dof``.
    """
    dof = np.asarray(dof, dtype=float)
    runs = int(runs)
    if runs < 1:
        raise NavlibInputError(f"runs: expected >= 1, got {runs}")
    alpha = finite_scalar(alpha, "alpha", 0.0, 1.0, low_open=True)
    total = runs * dof
    k, where = np.unique(np.maximum(total, 1), return_inverse=True)
    where = where.reshape(total.shape)

    def bound(q: float) -> np.ndarray:
        return np.where(total > 0, (2 * gammaincinv(k / 2, q) / runs)[where], 0.0)

    return bound(alpha / 2), bound(1 - alpha / 2)


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
    """NEES ``e' P^+ e``, scaled to a correlation matrix first (states of very different
    units); directions with (relative) zero variance are left out, and the degrees of
    freedom are the kept rank. Intermediates are formed in place where they can be.

    Parameters
    ----------
    err : ndarray (K, R, n)
        Errors of R runs at K epochs.
    P, rtol
        Covariances (K, n, n) and cut-off as in :func:`nees_basis` (unused with ``basis``).
    basis : tuple, optional
        :func:`nees_basis` of ``P`` when already computed.

    Returns
    -------
    nees : ndarray (K, R)
    dof : ndarray (K,)
    """
    safe, active, V, inv_w, dof = basis if basis is not None else nees_basis(P, rtol)
    en = np.divide(err, safe[:, None, :])
    np.copyto(en, 0.0, where=~active[:, None, :])
    proj = en @ V
    np.square(proj, out=proj)
    return (proj @ inv_w[:, :, None])[..., 0], dof
