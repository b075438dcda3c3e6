"""Estimability read from a covariance run: mode shares, subspace drift, exchanges of
direction between sorted modes, settling times and the noise-free error of a filter.

Generic analyses of a :func:`navlib.covariance.normalized_eigen` result and of a
:class:`navlib.covariance.CovarianceResult` (Ham & Brown normalised eigen-analysis,
docs/assumptions.md, ssac.md §3.6; covariance analysis and estimability,
docs/assumptions.md, ssac.md §3.4); the SSAC study
(:mod:`navlib.studies.ssac`) reads the paper's pairs, X-shape and limits with them.

* :func:`subspace_shares` — share of each state in the span of some modes;
* :func:`split_modes` — the largest modes split by their weight on a set of states;
* :func:`projector_drift` — how far a subspace of modes moves after a time;
* :func:`dominant_changes` — epochs at which the dominant group of sorted modes changes;
* :func:`settling_time` — time of reaching a factor of the final sigma;
* :func:`noise_free_error` — the actual error of a noise-free run with the filter's gains
  (:func:`update_factors` and :func:`closed_loop_error`, its two steps, for several truths
  run through the same filter);
* :func:`sparse_basis` — a reduced row-echelon basis of a subspace (readable null vectors).
"""

from __future__ import annotations

import numpy as np

from navlib.kalman import kalman_gain

__all__ = ["closed_loop_error", "dominant_changes", "noise_free_error", "projector_drift",
           "settling_time", "sparse_basis", "split_modes", "subspace_shares", "update_factors"]


def subspace_shares(V: np.ndarray) -> np.ndarray:
    """Share of each state in the span of the orthonormal columns of ``V`` (n, k).

    ``sqrt(diag(V V'))``: 1 for a state lying entirely in the subspace, 0 for one orthogonal
    to it (docs/assumptions.md, ssac.md §3.6).
    """
    return np.sqrt(np.clip(np.diag(V @ V.T), 0.0, None))


def split_modes(V: np.ndarray, index, n_large: int) -> tuple[np.ndarray, np.ndarray]:
    """Split the ``n_large`` first (largest) modes of ``V`` (n, n) by their weight on the
    states ``index``.

    Parameters
    ----------
    V : ndarray (n, n)
        Eigenvectors as columns, largest mode first.
    index : sequence of int
        0-based states (e.g. the positions).
    n_large : int
        How many leading modes to split.

    Returns
    -------
    others, along : ndarray of int
        Sorted 0-based columns of the ``n_large - len(index)`` modes with the least weight
        on those states, and of the ``len(index)`` modes with the most (e.g. the position
        modes among the six largest, docs/assumptions.md, ssac.md §3.6).
    """
    index = list(index)
    head = V[:, :n_large]
    weight = np.sqrt(np.sum(head[index] ** 2, axis=0)) if index else np.zeros(n_large)
    order = np.argsort(weight)
    return np.sort(order[: n_large - len(index)]), np.sort(order[n_large - len(index):])


def projector_drift(eigenvectors: np.ndarray, columns, start: int) -> float:
    """Largest Frobenius distance, from epoch ``start`` on, of the projector onto the
    sorted modes ``columns`` from its value at the last epoch.

    Small when modes exchanging directions rotate inside a fixed subspace (the "vector sum"
    of the exchanging eigenvectors stays put, Silva et al. §3, Figs. 9–10).

    Parameters
    ----------
    eigenvectors : ndarray (N, n, n)
        Sorted eigenvectors per epoch (columns).
    columns : sequence of int
        0-based modes spanning the subspace.
    start : int
        First epoch compared.

    Returns
    -------
    float
    """
    V = eigenvectors[start:, :, columns]
    P = V @ np.swapaxes(V, 1, 2)
    return float(np.linalg.norm(P - P[-1], axis=(1, 2)).max())


def dominant_changes(eigenvectors: np.ndarray, groups, columns, start: int):
    """Epochs at which the dominant state group of some sorted modes changes.

    Parameters
    ----------
    eigenvectors : ndarray (N, n, n)
        Sorted eigenvectors as columns (:class:`navlib.covariance.NormalizedEigenResult`).
    groups : sequence of sequences of int
        State indices of each group (e.g. the paper's attitude-bias pairs).
    columns : sequence of int
        The sorted modes followed.
    start : int
        First epoch compared with its predecessor (at least 1).

    Returns
    -------
    list of (k, changed, before, after)
        Per epoch ``k`` with a change: the positions in ``columns`` that changed and the
        dominant group index of every followed mode at ``k - 1`` and ``k``.
    """
    weight = np.stack([np.sum(eigenvectors[:, list(idx)][:, :, columns] ** 2, axis=1)
                       for idx in groups], axis=1)  # (N, groups, columns)
    dominant = np.argmax(weight, axis=1)  # (N, columns)
    start = max(int(start), 1)
    changed = dominant[start:] != dominant[start - 1:-1]
    return [(int(k), np.flatnonzero(dominant[k] != dominant[k - 1]), dominant[k - 1],
             dominant[k]) for k in np.flatnonzero(changed.any(axis=1)) + start]


def settling_time(t: np.ndarray, sigma: np.ndarray, factor: float = 1.05) -> np.ndarray:
    """Time after which each state's sigma stays within ``factor`` of its final value.

    The reading ``t_1.05_final`` of "reaches steady state" (docs/assumptions.md
    A-SSAC-convergence).

    Parameters
    ----------
    t : ndarray (N,)
        Epoch times (s).
    sigma : ndarray (N, n)
        Standard deviations per state.
    factor : float, optional
        Band above the final value (default 1.05).

    Returns
    -------
    ndarray (n,)
        Times (s); NaN for states without net reduction.
    """
    above = sigma > factor * sigma[-1]
    last = np.where(above.any(axis=0), t.size - 1 - np.argmax(above[::-1], axis=0), -1)
    settled = t[np.minimum(last + 1, t.size - 1)].astype(float)
    settled[sigma[-1] >= sigma[0]] = np.nan
    return settled


def noise_free_error(F: np.ndarray, H: np.ndarray, R: np.ndarray, P_prior: np.ndarray,
                     x0: np.ndarray) -> np.ndarray:
    """Actual error of a noise-free run of a Kalman filter updated at every epoch.

    The truth starts at ``x0``, the estimate at zero, and each epoch applies the filter's
    gains ``K_k`` (:func:`navlib.kalman.kalman_gain` of ``P_prior``):
    ``e_0 = (I - K_0 H) x0``, ``e_{k+1} = (I - K_{k+1} H) F_k e_k``
    (docs/assumptions.md, ssac.md §3.4, the
    actual error of Silva et al. Part I, Fig. 3).

    Parameters
    ----------
    F : ndarray (N-1, n, n) or (n, n)
    H : ndarray (m, n)
    R : ndarray (m, m)
    P_prior : ndarray (N, n, n)
    x0 : ndarray (n,)

    Returns
    -------
    ndarray (N, n)
        Error (truth - estimate) at every epoch.
    """
    return closed_loop_error(F, update_factors(H, R, P_prior), x0)


def update_factors(H: np.ndarray, R: np.ndarray, P_prior: np.ndarray) -> np.ndarray:
    """``I - K_k H`` of a Kalman filter updated at every epoch, with the gains
    :func:`navlib.kalman.kalman_gain` of ``P_prior``: what :func:`noise_free_error` applies
    at each update.

    Parameters
    ----------
    H : ndarray (m, n) or (N, m, n)
        Measurement matrices.
    R : ndarray (m, m) or (N, m, m)
        Measurement-noise covariances.
    P_prior : ndarray (N, n, n)
        Prior covariances.

    Returns
    -------
    ndarray (N, n, n)
    """
    n = P_prior.shape[-1]
    return np.eye(n) - kalman_gain(P_prior, H, R).K @ H


def closed_loop_error(F: np.ndarray, I_KH: np.ndarray, x0: np.ndarray) -> np.ndarray:
    """:func:`noise_free_error` from the filter's :func:`update_factors`:
    ``e_0 = I_KH[0] x0``, ``e_{k+1} = I_KH[k+1] F_k e_k``.

    Parameters
    ----------
    F : ndarray (N-1, n, n)
        Transition matrices.
    I_KH : ndarray (N, n, n)
        Update factors ``I - K_k H``.
    x0 : ndarray (n,)
        Initial error.

    Returns
    -------
    ndarray (N, n)
        Posterior error per epoch.
    """
    N, n = I_KH.shape[0], I_KH.shape[-1]
    F = np.broadcast_to(F, (N - 1, n, n))
    e = np.empty((N, n))
    e[0] = I_KH[0] @ x0
    for k in range(N - 1):
        e[k + 1] = I_KH[k + 1] @ (F[k] @ e[k])
    return e


def sparse_basis(V: np.ndarray) -> np.ndarray:
    """Reduced row-echelon basis of span(V) (n, k), scaled so the pivot entries are 1.

    Readable null vectors: each basis vector has a 1 on its own pivot state and zeros on the
    others' (the reduced-model analytic vectors of docs/assumptions.md, ssac.md §3.3).
    """
    Q, _ = np.linalg.qr(V)
    B = Q.T.copy()  # rows span the subspace
    rows, cols = B.shape
    pivot_row = 0
    for col in range(cols):
        if pivot_row == rows:
            break
        pivot = pivot_row + int(np.argmax(np.abs(B[pivot_row:, col])))
        if abs(B[pivot, col]) < 1e-9 * np.abs(B).max():
            continue
        B[[pivot_row, pivot]] = B[[pivot, pivot_row]]
        B[pivot_row] /= B[pivot_row, col]
        for r in range(rows):
            if r != pivot_row:
                B[r] -= B[r, col] * B[pivot_row]
        pivot_row += 1
    B[np.abs(B) < 1e-14 * np.abs(B).max()] = 0.0
    return B[:pivot_row].T
