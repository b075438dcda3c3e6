"""Small covariance algebra of :mod:`navlib.kalman`: the symmetric part, the PSD square
root and the definiteness switch of the innovation covariance."""

from __future__ import annotations

import numpy as np

__all__ = ["definite_noise", "psd_sqrt", "symmetrize"]


def symmetrize(P):
    """The symmetric part ``(P + P') / 2`` of one matrix or a stack (..., n, n)."""
    P = np.asarray(P)
    return 0.5 * (P + P.swapaxes(-1, -2))



def psd_sqrt(M) -> np.ndarray:
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
