"""What :class:`scipy.spatial.transform.Rotation` lacks: skew matrices, batched SO(3)
exp/log maps on plain arrays and Bortz helpers.

Attitude is carried as ``scipy.spatial.transform.Rotation`` objects (body -> ECEF). Small
rotation-vector error states use the skew-symmetric (cross-product) matrix ``S(v)``.
"""

from __future__ import annotations

import numpy as np

__all__ = ["bortz_coefficient", "bortz_rate", "cross", "exp_so3", "log_so3", "skew", "unskew"]


def skew(v):
    """Cross-product matrix S(v) with ``S(v) @ u == cross(v, u)``; ``v`` (..., 3) -> (..., 3, 3)."""
    v = np.asarray(v, dtype=float)
    out = np.zeros((*v.shape, 3))
    out[..., 0, 1] = -v[..., 2]
    out[..., 0, 2] = v[..., 1]
    out[..., 1, 0] = v[..., 2]
    out[..., 1, 2] = -v[..., 0]
    out[..., 2, 0] = -v[..., 1]
    out[..., 2, 1] = v[..., 0]
    return out


def unskew(m):
    """Inverse of :func:`skew`: the vector of a (..., 3, 3) skew-symmetric matrix."""
    m = np.asarray(m, dtype=float)
    return 0.5 * np.stack(
        [m[..., 2, 1] - m[..., 1, 2], m[..., 0, 2] - m[..., 2, 0], m[..., 1, 0] - m[..., 0, 1]],
        axis=-1,
    )


def cross(a, b):
    """Cross product of (..., 3) arrays (broadcasting), several times faster than
    ``np.cross`` on small inputs, which matters inside per-sample loops.

    Parameters
    ----------
    a, b : array_like, shape (..., 3)
        The two vectors; leading axes broadcast against each other.

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        ``a x b`` over the broadcast leading axes.
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    out = np.empty(a.shape if a.shape == b.shape else np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    out[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    out[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return out


def bortz_coefficient(angle):
    """Scalar ``(1 - a sin a / (2 (1 - cos a))) / a^2`` of the Bortz equation (docs/assumptions.md
    A2, A3).

    Evaluated as ``(1 - (a/2) cot(a/2)) / a^2``, which avoids the cancellation in
    ``1 - cos a``; below 0.2 rad the series ``1/12 + a^2/720 + a^4/30240 + a^6/1209600 +
    a^8/47900160`` is used (both forms agree to ~1e-15 at the switch). Tends to 1/12 as a -> 0;
    singular at 2 pi.
    """
    a = np.asarray(angle, dtype=float)
    small = np.abs(a) < 0.2
    a2 = a * a
    series = 1.0 / 12.0 + a2 * (
        1.0 / 720.0 + a2 * (1.0 / 30240.0 + a2 * (1.0 / 1209600.0 + a2 / 47900160.0))
    )
    if small.all():                # per-sample IMU increments: no closed form needed
        return np.asarray(series)
    a_safe = np.where(small, 1.0, a)
    half = 0.5 * a_safe
    exact = (1.0 - half / np.tan(half)) / a_safe**2
    return np.where(small, series, exact)


def bortz_rate(theta, w_b):
    """Rotation-vector derivative for ``C = exp(S(theta))`` driven by the body rate ``w_b``.

    ``dtheta/dt = w + 1/2 theta x w + c(|theta|) theta x (theta x w)``, the body-rate form
    that the docs/assumptions.md A2 verified numerically (España et al. 2019, Eq. 1 with the frame
    of omega corrected).

    Parameters
    ----------
    theta : array_like, shape (..., 3)
        Rotation vector of ``C = exp(S(theta))`` (rad).
    w_b : array_like, shape (..., 3)
        Body angular rate (rad/s), broadcast against ``theta``.

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        ``dtheta/dt`` (rad/s).
    """
    theta = np.asarray(theta, dtype=float)
    w_b = np.asarray(w_b, dtype=float)
    c = bortz_coefficient(np.linalg.norm(theta, axis=-1))[..., None]
    txw = cross(theta, w_b)
    return w_b + 0.5 * txw + c * cross(theta, txw)


def log_so3(C) -> np.ndarray:
    """Rotation vectors ``phi`` with ``C = exp(S(phi))`` of rotation matrices (..., 3, 3).

    The SO(3) log map: closed form ``theta / sin(theta) * unskew(C)``, with the scipy
    conversion near pi where the closed form loses accuracy. Inverse of :func:`exp_so3`.
    """
    C = np.asarray(C, dtype=float)
    cos = np.clip(0.5 * (np.trace(C, axis1=-2, axis2=-1) - 1.0), -1.0, 1.0)
    theta = np.arccos(cos)
    v = unskew(C)                                   # sin(theta) * axis
    small = theta < 1e-4
    factor = np.where(small, 1.0 + theta**2 / 6.0, theta / np.where(small, 1.0, np.sin(theta)))
    out = factor[..., None] * v
    near_pi = theta > 3.0
    if np.any(near_pi):
        # heavy: scipy.spatial.transform takes about 1 s to import, only angles near pi need it
        from scipy.spatial.transform import Rotation

        out[near_pi] = Rotation.from_matrix(C[near_pi]).as_rotvec()
    return out


def exp_so3(phi) -> np.ndarray:
    """Rotation matrices ``exp(S(phi))`` of rotation vectors (..., 3).

    The SO(3) exponential map by Rodrigues' formula (series below 1e-4 rad); the
    small-angle error-state convention ``C_true = exp(S(psi)) C_hat`` of the filters.
    """
    phi = np.asarray(phi, dtype=float)
    theta2 = np.sum(phi * phi, axis=-1)
    theta = np.sqrt(theta2)
    small = theta < 1e-4
    if small.all():                # feedback corrections: series only, nothing to mask
        a, b = 1.0 - theta2 / 6.0, 0.5 - theta2 / 24.0
    else:
        safe = np.where(small, 1.0, theta)
        a = np.where(small, 1.0 - theta2 / 6.0, np.sin(safe) / safe)
        b = np.where(small, 0.5 - theta2 / 24.0, (1.0 - np.cos(safe)) / safe**2)
    K = skew(phi)
    return np.eye(3) + a[..., None, None] * K + b[..., None, None] * (K @ K)
