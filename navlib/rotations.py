"""What :class:`scipy.spatial.transform.Rotation` lacks: skew matrices and Bortz helpers.

Attitude is carried as ``scipy.spatial.transform.Rotation`` objects (body -> ECEF). Small
rotation-vector error states use the skew-symmetric (cross-product) matrix ``S(v)``.
"""

from __future__ import annotations

import numpy as np


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
    ``np.cross`` on small inputs, which matters inside per-sample loops."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    out = np.empty(a.shape if a.shape == b.shape else np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    out[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    out[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return out


def bortz_coefficient(angle):
    """Scalar ``(1 - a sin a / (2 (1 - cos a))) / a^2`` of the Bortz equation (spec A2, A3).

    Evaluated as ``(1 - (a/2) cot(a/2)) / a^2``, which avoids the cancellation in
    ``1 - cos a``; below 0.2 rad the series ``1/12 + a^2/720 + a^4/30240 + a^6/1209600 +
    a^8/47900160`` is used (both forms agree to ~1e-15 at the switch). Tends to 1/12 as a -> 0;
    singular at 2 pi.
    """
    a = np.asarray(angle, dtype=float)
    small = np.abs(a) < 0.2
    a_safe = np.where(small, 1.0, a)
    half = 0.5 * a_safe
    exact = (1.0 - half / np.tan(half)) / a_safe**2
    a2 = a * a
    series = 1.0 / 12.0 + a2 * (
        1.0 / 720.0 + a2 * (1.0 / 30240.0 + a2 * (1.0 / 1209600.0 + a2 / 47900160.0))
    )
    return np.where(small, series, exact)


def bortz_rate(theta, w_b):
    """Rotation-vector derivative for ``C = exp(S(theta))`` driven by the body rate ``w_b``.

    ``dtheta/dt = w + 1/2 theta x w + c(|theta|) theta x (theta x w)``, the body-rate form
    that the spec note A2 verified numerically (España et al. 2019, Eq. 1 with the frame
    of omega corrected). ``theta`` and ``w_b`` are (..., 3).
    """
    theta = np.asarray(theta, dtype=float)
    w_b = np.asarray(w_b, dtype=float)
    c = bortz_coefficient(np.linalg.norm(theta, axis=-1))[..., None]
    txw = cross(theta, w_b)
    return w_b + 0.5 * txw + c * cross(theta, txw)
