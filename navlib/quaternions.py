"""Quaternion arithmetic on ``(..., 4)`` scalar-last arrays (``(x, y, z, w)``, the order of
:mod:`scipy.spatial.transform`), vectorised over leading axes, for the strapdown
mechanisation (:mod:`navlib.strapdown`, docs/assumptions.md A2) and the SO(3) spline fit
(:mod:`navlib.trajectory`). ``q`` rotates body vectors into ECEF when it is an attitude.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from scipy.spatial.transform import Rotation

from navlib import earth
from navlib.rotations import cross

__all__ = ["earth_quat", "prefix_products", "quat_from_matrix", "quat_from_rotvec", "quat_mul",
           "quat_rotate"]


def quat_mul(p, q):
    """Hamilton product ``p ⊗ q`` (matrix order: ``C(p ⊗ q) = C(p) C(q)``).

    Parameters
    ----------
    p, q : numpy.ndarray, shape (..., 4)
        Quaternions, scalar last ``(x, y, z, w)``; leading axes broadcast.

    Returns
    -------
    numpy.ndarray, shape (..., 4)
        The product, scalar last.
    """
    px, py, pz, pw = p[..., 0], p[..., 1], p[..., 2], p[..., 3]
    qx, qy, qz, qw = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    out = np.empty(p.shape if p.shape == q.shape else np.broadcast_shapes(p.shape, q.shape))
    out[..., 0] = pw * qx + px * qw + py * qz - pz * qy
    out[..., 1] = pw * qy - px * qz + py * qw + pz * qx
    out[..., 2] = pw * qz + px * qy - py * qx + pz * qw
    out[..., 3] = pw * qw - px * qx - py * qy - pz * qz
    return out


def quat_from_rotvec(phi):
    """Unit quaternion of ``exp(S(phi))`` with a series for small angles."""
    angle = np.linalg.norm(phi, axis=-1)
    half = 0.5 * angle
    small = angle < 1e-4
    safe = np.where(small, 1.0, angle)
    # sin(a/2)/a, with its Taylor series 1/2 - a^2/48 below 1e-4 rad.
    k = np.where(small, 0.5 - angle**2 / 48.0, np.sin(half) / safe)
    return np.concatenate([k[..., None] * phi, np.cos(half)[..., None]], axis=-1)


def quat_rotate(q, v):
    """Rotate vectors by unit quaternions: ``C(q) v``.

    Parameters
    ----------
    q : numpy.ndarray, shape (..., 4)
        Unit quaternions, scalar last ``(x, y, z, w)``.
    v : numpy.ndarray, shape (..., 3)
        Vectors, broadcast against ``q``'s leading axes.

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        The rotated vectors.
    """
    u = q[..., :3]
    w = q[..., 3:]
    uv = cross(u, v)
    return v + 2.0 * (w * uv + cross(u, uv))


def earth_quat(tau_s):
    """Quaternion of ``exp(-S(Omega) tau)``, ``tau = tau_s`` (s): rotation by ``-Omega tau``
    about ECEF z."""
    half = -0.5 * earth.OMEGA_E * np.asarray(tau_s, dtype=float)
    zero = np.zeros_like(half)
    return np.stack([zero, zero, np.sin(half), np.cos(half)], axis=-1)


def prefix_products(q):
    """Running products ``q_0 ⊗ q_1 ⊗ ... ⊗ q_k`` of (N, 4) quaternions (Hillis–Steele scan).

    Log-depth and vectorised: ``ceil(log2 N)`` batched products instead of N scalar ones.
    """
    out = np.array(q, dtype=float, copy=True)
    shift = 1
    while shift < len(out):
        out[shift:] = quat_mul(out[:-shift], out[shift:])
        shift *= 2
    return out / np.linalg.norm(out, axis=-1, keepdims=True)


def quat_from_matrix(C) -> np.ndarray:
    """``Rotation.from_matrix(C).as_quat()`` of one attitude matrix: compiled
    (:func:`_matrix_quat_kernel`, scipy's formulas in scipy's order, the same quaternion to
    the bit) when ``C`` is a rotation to 1e-13 (far inside scipy's own tolerance, so scipy
    would not project it either), else scipy with its projection."""
    C = np.require(C, float, "CW")  # one kernel type: a read-only view would compile again
    quat = np.empty(4)
    if _matrix_quat_kernel(C, quat):
        return quat
    return Rotation.from_matrix(C).as_quat()


@numba.njit(cache=True)
def _matrix_quat_kernel(C, quat):
    """The quaternion of a rotation matrix ``C`` into ``quat`` by scipy's
    ``Rotation.from_matrix`` formulas for an orthogonal matrix (the largest of the diagonal
    and the trace chooses the formula, then normalised); False, ``quat`` unset, when ``C``
    is not a proper rotation to 1e-13 (``|C C' - I|`` and the sign of the determinant)."""
    for i in range(3):
        for j in range(3):
            gram = C[i, 0] * C[j, 0] + C[i, 1] * C[j, 1] + C[i, 2] * C[j, 2]
            if not abs(gram - (1.0 if i == j else 0.0)) < 1e-13:
                return False
    det = (C[0, 0] * (C[1, 1] * C[2, 2] - C[1, 2] * C[2, 1])
           - C[0, 1] * (C[1, 0] * C[2, 2] - C[1, 2] * C[2, 0])
           + C[0, 2] * (C[1, 0] * C[2, 1] - C[1, 1] * C[2, 0]))
    if not det > 0:
        return False
    trace = C[0, 0] + C[1, 1] + C[2, 2]
    choice, best = 0, C[0, 0]
    for i in range(1, 3):
        if C[i, i] > best:
            choice, best = i, C[i, i]
    if trace > best:
        quat[0] = C[2, 1] - C[1, 2]
        quat[1] = C[0, 2] - C[2, 0]
        quat[2] = C[1, 0] - C[0, 1]
        quat[3] = 1.0 + trace
    else:
        i = choice
        j = (i + 1) % 3
        k = (j + 1) % 3
        quat[i] = 1.0 - trace + 2.0 * C[i, i]
        quat[j] = C[j, i] + C[i, j]
        quat[k] = C[k, i] + C[i, k]
        quat[3] = C[k, j] - C[j, k]
    norm = math.sqrt(quat[0] * quat[0] + quat[1] * quat[1] + quat[2] * quat[2]
                     + quat[3] * quat[3])
    for i in range(4):
        quat[i] /= norm
    return True
