"""Covariance histories read in other frames and as correlations and ratios (docs/assumptions.md,
launcher.md §6.2 item 6, §6.3; docs/assumptions.md, ssac.md §8 item 7): :func:`block_in_frame`,
:func:`sigma_in_frame`, :func:`correlation`, :func:`group_correlation`, :func:`covariance_ratio`,
:func:`convergence_time`.
"""

from __future__ import annotations

import numpy as np

from navlib._validation import finite_array, finite_scalar
from navlib.covariance.recursion import CovarianceResult, stack_steps
from navlib.errors import NavlibInputError
from navlib.kalman import symmetrize

__all__ = ["as_covariances", "block_in_frame", "convergence_time", "correlation",
           "covariance_ratio", "group_correlation", "sigma_in_frame"]


def as_covariances(P) -> np.ndarray:
    if isinstance(P, CovarianceResult):
        return P.P_post
    P = finite_array(P, "P")
    if P.ndim == 2:
        P = P[None]
    if P.ndim != 3 or P.shape[1] != P.shape[2]:
        raise NavlibInputError(f"P: expected (N, n, n) covariances, got shape {P.shape}")
    return P


def _state_index(P, idx, name: str) -> np.ndarray:
    n = P.shape[-1]
    if isinstance(idx, str):
        idx = [idx]
    idx = list(idx)
    if idx and isinstance(idx[0], str):
        raise NavlibInputError(f"{name}: state names need a CovarianceResult; got arrays")
    idx = np.asarray(idx, dtype=int)
    if idx.ndim != 1 or idx.size == 0 or idx.min() < -n or idx.max() >= n:
        raise NavlibInputError(f"{name}: expected state indices in [0, {n}), got {idx}")
    return idx


def _resolve(P, idx, name: str) -> np.ndarray:
    """State indices from names (needs a CovarianceResult) or integers."""
    if isinstance(P, CovarianceResult):
        labels = [idx] if isinstance(idx, str) else list(idx)
        if labels and isinstance(labels[0], str):
            return P.index(labels)
    return _state_index(as_covariances(P), idx, name)


def _rotations(C, count: int, size: int, name: str) -> np.ndarray | None:
    if C is None:
        return None
    if hasattr(C, "as_matrix"):
        C = C.as_matrix()
    C = finite_array(C, name)
    return stack_steps(C, count, (size, size), name)


def block_in_frame(P, states, C=None) -> np.ndarray:
    """Covariance of a group of states expressed in another frame, per epoch.

    ``P_b = C P_block C'`` with ``C`` the rotation from the states' frame to the wanted
    one, e.g. ``C = T_E^B`` turns the ECEF attitude-error block into body axes
    (docs/assumptions.md, launcher.md §6.2 item 6: ``P_body = T_E^B P_psipsi T_B^E``).

    Parameters
    ----------
    P : CovarianceResult or ndarray (N, n, n)
        Covariance history (the posterior of a result).
    states : sequence of str or int
        The group (names need a CovarianceResult), e.g. the three attitude errors.
    C : ndarray (k, k) or (N, k, k) or scipy Rotation, optional
        Rotation to apply; None keeps the frame.

    Returns
    -------
    ndarray (N, k, k)
    """
    idx = _resolve(P, states, "states")
    P = as_covariances(P)
    block = P[:, idx[:, None], idx]
    C = _rotations(C, P.shape[0], idx.size, "C")
    return block if C is None else symmetrize(C @ block @ np.swapaxes(C, 1, 2))


def sigma_in_frame(P, states, C=None) -> np.ndarray:
    """Standard deviations of a rotated group, (N, k): ``sqrt(diag(C P_block C'))``.

    E.g. roll/pitch/yaw error sigma in body axes from an ECEF attitude-error block with
    ``C = T_E^B`` per epoch (docs/assumptions.md, launcher.md §6.2 item 6).

    Parameters
    ----------
    P : CovarianceResult or ndarray (N, n, n)
        Covariance history (the posterior of a result).
    states : sequence of str or int
        The group of k states (names need a CovarianceResult).
    C : ndarray (k, k) or (N, k, k) or scipy Rotation, optional
        Rotation to the wanted frame; None keeps the frame.

    Returns
    -------
    ndarray (N, k)
        Standard deviations in the units of the states.
    """
    block = block_in_frame(P, states, C)
    return np.sqrt(np.clip(np.diagonal(block, axis1=1, axis2=2), 0.0, None))


def correlation(P, i=None, j=None) -> np.ndarray:
    """Correlation coefficients ``rho_ij = P_ij / sqrt(P_ii P_jj)`` over time (docs/assumptions.md,
    launcher.md §6.3).

    Parameters
    ----------
    P : CovarianceResult or ndarray (N, n, n)
    i, j : str or int, optional
        Two states; when omitted the full correlation matrices are returned.

    Returns
    -------
    ndarray (N,) for a pair, (N, n, n) otherwise. Entries with a zero variance are NaN.
    """
    if (i is None) != (j is None):
        raise NavlibInputError("i, j: give both states or neither")
    if i is not None:
        a = _resolve(P, [i], "i")[0]
        b = _resolve(P, [j], "j")[0]
        P = as_covariances(P)
        den = np.sqrt(P[:, a, a] * P[:, b, b])
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(den > 0, P[:, a, b] / np.where(den > 0, den, 1.0), np.nan)
    P = as_covariances(P)
    d = np.sqrt(np.clip(np.diagonal(P, axis1=1, axis2=2), 0.0, None))
    den = d[:, :, None] * d[:, None, :]
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(den > 0, P / np.where(den > 0, den, 1.0), np.nan)


def group_correlation(P, states_a, states_b, C_a=None, C_b=None) -> np.ndarray:
    """Per-axis correlation of two rotated 3-vectors of states (docs/assumptions.md, launcher.md
    §6.3 item 2).

    With ``a = C_a x_a`` and ``b = C_b x_b`` (e.g. ``C_a = T_E^B`` for an ECEF attitude
    error and ``C_b = I`` for a body-axis one), returns
    ``rho_k = cov(a_k, b_k) / sqrt(var a_k var b_k)`` for each axis k.

    Parameters
    ----------
    P : CovarianceResult or ndarray (N, n, n)
        Covariance history (the posterior of a result).
    states_a, states_b : sequence of str or int
        The two groups of k states (names need a CovarianceResult).
    C_a, C_b : ndarray (k, k) or (N, k, k) or scipy Rotation, optional
        Rotations applied to each group; None keeps its frame.

    Returns
    -------
    ndarray (N, k)
        Correlation coefficients in [-1, 1].
    """
    ia = _resolve(P, states_a, "states_a")
    ib = _resolve(P, states_b, "states_b")
    if ia.size != ib.size:
        raise NavlibInputError(f"states_a, states_b: groups differ in size ({ia.size}, {ib.size})")
    P = as_covariances(P)
    count = P.shape[0]
    eye = np.eye(ia.size)
    C_a = _rotations(C_a, count, ia.size, "C_a")
    C_b = _rotations(C_b, count, ib.size, "C_b")
    C_a = np.broadcast_to(eye, (count, *eye.shape)) if C_a is None else C_a
    C_b = np.broadcast_to(eye, (count, *eye.shape)) if C_b is None else C_b
    Paa = C_a @ P[:, ia[:, None], ia] @ np.swapaxes(C_a, 1, 2)
    Pbb = C_b @ P[:, ib[:, None], ib] @ np.swapaxes(C_b, 1, 2)
    Pab = C_a @ P[:, ia[:, None], ib] @ np.swapaxes(C_b, 1, 2)
    den = np.sqrt(np.clip(np.diagonal(Paa, axis1=1, axis2=2) * np.diagonal(Pbb, axis1=1,
                                                                             axis2=2), 0, None))
    cross = np.diagonal(Pab, axis1=1, axis2=2)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(den > 0, cross / np.where(den > 0, den, 1.0), np.nan)


def covariance_ratio(sigma) -> np.ndarray:
    """PSINS-style observability degree ``sigma_i(t0) / sigma_i(t)``, (N, n).

    1 means no information gained on state i since t0; large values mean the state was
    estimated. A zero ``sigma_i(t)`` gives inf (a zero initial sigma gives NaN).

    Parameters
    ----------
    sigma : CovarianceResult or ndarray (N, n)
    """
    if isinstance(sigma, CovarianceResult):
        sigma = sigma.sigma
    sigma = finite_array(sigma, "sigma", ndim=2)
    if np.any(sigma < 0):
        raise NavlibInputError("sigma: standard deviations must be non-negative")
    with np.errstate(divide="ignore", invalid="ignore"):
        return sigma[:1] / sigma


def convergence_time(t, sigma, fraction: float = 0.95) -> np.ndarray:
    """Time at which each state has made ``fraction`` of its total sigma reduction.

    ``t_c = min { t : sigma(s) <= sigma_0 - fraction (sigma_0 - sigma_end) for all s >= t }``
    (docs/assumptions.md, ssac.md §8 item 7). States with no net reduction get NaN.

    Parameters
    ----------
    t : ndarray (N,)
    sigma : ndarray (N, n)
    fraction : float in (0, 1]

    Returns
    -------
    ndarray (n,)
    """
    t = finite_array(t, "t", ndim=1)
    sigma = finite_array(sigma, "sigma", shape=(t.size, None))
    fraction = finite_scalar(fraction, "fraction", 0.0, 1.0, low_open=True)
    level = sigma[0] - fraction * (sigma[0] - sigma[-1])
    above = sigma > level * (1.0 + 1e-12)
    # last epoch still above the level; convergence is the next one
    last_above = np.where(above.any(axis=0), t.size - 1 - np.argmax(above[::-1], axis=0), -1)
    out = t[np.minimum(last_above + 1, t.size - 1)].astype(float)
    out[sigma[-1] >= sigma[0]] = np.nan
    return out
