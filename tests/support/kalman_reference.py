"""NumPy reference of the compiled Kalman kernels (issue 26): the step-by-step NumPy code the
kernels of :mod:`navlib.kalman` and :mod:`navlib.filters.ekf` replaced, kept here
(not in the library) to compare against (tests/kalman/test_kalman.py) and to time against
(benchmarks/bench_kernels.py).
"""

from __future__ import annotations

import numpy as np


def symmetrize(P):
    return 0.5 * (P + P.swapaxes(-1, -2))


def gain(P, H, R, definite: bool, pinv_rtol: float = 1e-12):
    """``(K, S_pinv, dof)`` of one epoch: inverse of ``S`` when ``definite``, else the
    eigen-decomposition pseudo-inverse (eigenvalues above ``pinv_rtol * max`` kept)."""
    PHt = P @ H.T
    S = symmetrize(H @ PHt + R)
    m = S.shape[-1]
    if m == 0:
        return PHt, S, 0
    if definite:
        S_pinv, dof = np.linalg.inv(S), m
    else:
        w, V = np.linalg.eigh(S)
        keep = w > pinv_rtol * max(w[-1], 0.0)
        inv_w = np.where(keep, 1.0 / np.where(keep, w, 1.0), 0.0)
        S_pinv, dof = (V * inv_w) @ V.T, int(keep.sum())
    return PHt @ S_pinv, S_pinv, dof


def joseph(P, H, R, definite: bool, pinv_rtol: float = 1e-12):
    """``(P_post, K, S_pinv, dof)``: the Joseph-form update with :func:`gain`."""
    K, S_pinv, dof = gain(P, H, R, definite, pinv_rtol)
    IKH = np.eye(P.shape[-1]) - K @ H
    return symmetrize(IKH @ P @ IKH.T + K @ R @ K.T), K, S_pinv, dof


def predict(P, F, Q):
    return symmetrize(F @ P @ F.T + Q)


def recursion(F, Q, H, R, P0, measured, definite, pinv_rtol: float = 1e-12):
    """Priors, posteriors (N, n, n) and gains of the Kalman covariance recursion from the
    prior ``P0`` at epoch 0 (updated where ``measured``)."""
    count, n = measured.size, P0.shape[-1]
    m = H.shape[-2]
    priors, posts = np.empty((count, n, n)), np.empty((count, n, n))
    K, S_pinv, dof = np.zeros((count, n, m)), np.zeros((count, m, m)), np.zeros(count, int)
    P = P0
    for k in range(count):
        if k:
            P = predict(P, F[k - 1], Q[k - 1])
        priors[k] = P
        if measured[k]:
            P, K[k], S_pinv[k], dof[k] = joseph(P, H[k], R[k], definite[k], pinv_rtol)
        posts[k] = P
    return priors, posts, K, S_pinv, dof


def propagate(x, P, F, Q, kept):
    """The EKF's propagation between updates, sample by sample (``kept``: the RT states
    driven by the kept columns only)."""
    for Fj, Qj in zip(F, Q, strict=True):
        x_next = Fj @ x
        if kept.size:
            x_next[kept] = Fj[np.ix_(kept, kept)] @ x[kept]
        x = x_next
        P = predict(P, Fj, Qj)
    return x, P


def _update(x, P, z, H, R, definite, pinv_rtol, P_post, K, S_pinv):
    innov = z - H @ x
    P_post[:], K[:], S_pinv[:], dof = joseph(P, H, R, definite, pinv_rtol)
    return x + K @ innov, innov, innov @ S_pinv @ innov, dof


def fixed_updates(x, P, F, Q, kept, j0, samples, z, H, R, definite, pinv_rtol, xs, Ps,
                  innovations, nis, dofs, j_end):
    """:func:`navlib.kalman.fixed_updates_kernel` written with the NumPy steps above (same
    arguments and outputs), to run the EKF with them."""
    K, S_pinv = np.empty((H.shape[1], H.shape[0])), np.empty((H.shape[0], H.shape[0]))
    for u, j in enumerate(samples):
        x, P = propagate(x, P, F[j0:j], Q[j0:j], kept)
        j0 = j
        x, innovations[u], nis[u], dofs[u] = _update(x, P, z[u], H, R, definite, pinv_rtol,
                                                     Ps[u], K, S_pinv)
        xs[u], P = x, Ps[u]
    return propagate(x, P, F[j0:j_end], Q[j0:j_end], kept)
