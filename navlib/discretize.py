"""Continuous -> discrete error models: matrix exponential, Van Loan, Euler, chaining.

For ``dx/dt = A x + G w`` with white ``w`` of power spectral density ``Qc``:

* ``F = expm(A dt)`` and, by Van Loan (1978), ``Q = int_0^dt expm(A s) G Qc G' expm(A s)' ds``
  from one exponential of the block matrix ``[[-A, G Qc G'], [0, A']] dt``
  (spec excitability.md A8);
* the papers' Euler form ``F = I + A dt``, ``Q = G Qc G' dt`` (Beaudoin et al. 2018 eq. 1,
  ``A_lc = I + s_t F``), selectable with ``method="euler"``;
* :func:`chain` multiplies per-step transitions between measurement epochs and accumulates
  ``Q <- Phi Q Phi' + Q_j`` (spec A8: 100 IMU steps per 1 Hz GNSS epoch).

Everything is batched over the leading (time) axis.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import expm

from navlib.errors import NavlibInputError

METHODS = ("expm", "euler")


def _as_steps(matrix, n_steps: int, name: str) -> np.ndarray:
    matrix = np.asarray(matrix, dtype=float)
    if matrix.ndim == 2:
        return np.broadcast_to(matrix, (n_steps, *matrix.shape))
    if matrix.ndim == 3 and matrix.shape[0] == n_steps:
        return matrix
    raise NavlibInputError(
        f"{name}: expected one matrix or a stack of {n_steps} matrices, got shape {matrix.shape}"
    )


def discretize_steps(A, G, Qc, dt, method: str = "expm"):
    """Per-step transition and process-noise matrices.

    Parameters
    ----------
    A : ndarray (n, n) or (K, n, n)
        Continuous dynamics, held constant over each step.
    G : ndarray (n, q) or (K, n, q)
        Noise input matrix.
    Qc : ndarray (q, q)
        Power spectral density of the white noise ``w``.
    dt : float or ndarray (K,)
        Step lengths, s.
    method : {"expm", "euler"}
        Matrix exponential with Van Loan noise, or ``I + A dt`` with ``G Qc G' dt``.

    Returns
    -------
    F, Q : ndarray (K, n, n)
    """
    if method not in METHODS:
        raise NavlibInputError(f"method: expected one of {METHODS}, got {method!r}")
    A = np.asarray(A, dtype=float)
    dt = np.atleast_1d(np.asarray(dt, dtype=float))
    n_steps = A.shape[0] if A.ndim == 3 else dt.size
    if dt.size == 1:
        dt = np.full(n_steps, dt[0])
    if dt.size != n_steps or np.any(~np.isfinite(dt)) or np.any(dt <= 0):
        raise NavlibInputError(f"dt: expected {n_steps} positive finite step(s)")
    A = _as_steps(A, n_steps, "A")
    G = _as_steps(G, n_steps, "G")
    Qc = np.asarray(Qc, dtype=float)
    n = A.shape[-1]
    W = np.einsum("kiq,qr,kjr->kij", G, Qc, G)
    step = dt[:, None, None]
    if method == "euler":
        return np.eye(n) + A * step, W * step
    block = np.zeros((n_steps, 2 * n, 2 * n))
    block[:, :n, :n] = -A * step
    block[:, :n, n:] = W * step
    block[:, n:, n:] = np.swapaxes(A, 1, 2) * step
    E = expm(block)
    F = np.swapaxes(E[:, n:, n:], 1, 2)
    Q = F @ E[:, :n, n:]
    return F, 0.5 * (Q + np.swapaxes(Q, 1, 2))


def chain(F_steps, Q_steps, epochs):
    """Combine per-step ``F``, ``Q`` into transitions between measurement epochs.

    Parameters
    ----------
    F_steps, Q_steps : ndarray (K, n, n)
        Step ``j`` maps sample ``j`` to ``j + 1``.
    epochs : ndarray of int (M,)
        Increasing sample indices of the measurement epochs (``epochs[-1] <= K``).

    Returns
    -------
    F, Q : ndarray (M-1, n, n)
        ``F[i]`` maps epoch ``i`` to ``i + 1``; ``Q[i]`` is the accumulated process noise.
        Intervals of equal length are chained together in one batched loop.
    """
    epochs = np.asarray(epochs)
    if epochs.ndim != 1 or epochs.size < 2 or np.any(np.diff(epochs) <= 0):
        raise NavlibInputError("epochs: expected at least 2 strictly increasing sample indices")
    if epochs[0] < 0 or epochs[-1] > len(F_steps):
        raise NavlibInputError(f"epochs: indices must lie in [0, {len(F_steps)}]")
    n = F_steps.shape[-1]
    starts, lengths = epochs[:-1], np.diff(epochs)
    F = np.empty((starts.size, n, n))
    Q = np.empty((starts.size, n, n))
    for length in np.unique(lengths):
        sel = np.flatnonzero(lengths == length)
        Fi = F_steps[starts[sel]].copy()
        Qi = Q_steps[starts[sel]].copy()
        for j in range(1, int(length)):
            Phi = F_steps[starts[sel] + j]
            Fi = Phi @ Fi
            Qi = Phi @ Qi @ np.swapaxes(Phi, 1, 2) + Q_steps[starts[sel] + j]
        F[sel], Q[sel] = Fi, Qi
    return F, 0.5 * (Q + np.swapaxes(Q, 1, 2))
