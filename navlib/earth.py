"""WGS-84 Earth: geodetic <-> ECEF, the local NED frame, Earth rate, and normal gravity.

Normal gravity here is gravitation (central term plus J2) **plus the centrifugal term**
``-Omega x (Omega x r)``, because the ECEF navigation equation of España et al. (2019,
Eq. 1) has no separate centrifugal term (docs/assumptions.md A5). Its Jacobian with respect to the
ECEF position is given in closed form (:func:`gravity_jacobian_ecef`).

All angles in radians except where a name ends in ``_deg``. Arrays of points are stacked
on the first axis, ``(..., 3)``.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["E2", "EARTH_RATE_ECEF", "FLATTENING", "GM", "J2", "OMEGA_E", "A", "B",
           "ecef_to_geodetic", "geodetic_to_ecef", "gravitation_ecef", "gravity_jacobian_ecef",
           "gravity_magnitude", "ned_to_ecef_matrix", "normal_gravity_ecef", "normal_gravity_point",
           "radii_of_curvature"]

A = 6378137.0
"""WGS-84 semi-major axis, m."""
FLATTENING = 1.0 / 298.257223563
"""WGS-84 flattening."""
E2 = FLATTENING * (2.0 - FLATTENING)
"""First eccentricity squared."""
B = A * (1.0 - FLATTENING)
"""Semi-minor axis, m."""
GM = 3.986004418e14
"""Earth's gravitational constant (WGS-84), m^3/s^2."""
J2 = 1.082629821313e-3
"""Second zonal harmonic (WGS-84)."""
OMEGA_E = 7.292115e-5
"""Earth rotation rate (WGS-84), rad/s."""
EARTH_RATE_ECEF = np.array([0.0, 0.0, OMEGA_E])
"""Earth rate vector omega_ie^e, rad/s."""


def geodetic_to_ecef(lat, lon, alt):
    """Geodetic latitude, longitude and ellipsoidal height to ECEF position (WGS-84).

    Parameters
    ----------
    lat, lon : array_like
        Geodetic latitude and longitude (rad).
    alt : array_like
        Height above the ellipsoid (m); the three inputs broadcast.

    Returns
    -------
    numpy.ndarray, shape ``broadcast(lat, lon, alt).shape + (3,)``
        ECEF position (m).
    """
    lat, lon, alt = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (lat, lon, alt)))
    sin_lat = np.sin(lat)
    n = A / np.sqrt(1.0 - E2 * sin_lat**2)
    x = (n + alt) * np.cos(lat) * np.cos(lon)
    y = (n + alt) * np.cos(lat) * np.sin(lon)
    z = (n * (1.0 - E2) + alt) * sin_lat
    return np.stack([x, y, z], axis=-1)


def ecef_to_geodetic(r_e):
    """ECEF position (..., 3) in m to geodetic ``(lat, lon, alt)`` (rad, rad, m).

    Uses Bowring's initial guess and three fixed-point refinements, good to well below a
    millimetre from the Earth's centre region out to several Earth radii.
    """
    r_e = np.asarray(r_e, dtype=float)
    x, y, z = r_e[..., 0], r_e[..., 1], r_e[..., 2]
    p = np.hypot(x, y)
    lon = np.arctan2(y, x)
    ep2 = E2 / (1.0 - E2)
    theta = np.arctan2(z * A, p * B)
    lat = np.arctan2(z + ep2 * B * np.sin(theta) ** 3, p - E2 * A * np.cos(theta) ** 3)
    for _ in range(3):
        n = A / np.sqrt(1.0 - E2 * np.sin(lat) ** 2)
        alt = np.where(
            np.abs(np.cos(lat)) > 1e-9,
            p / np.maximum(np.abs(np.cos(lat)), 1e-300) - n,
            np.abs(z) - n * (1.0 - E2),
        )
        lat = np.arctan2(z, p * (1.0 - E2 * n / (n + alt)))
    n = A / np.sqrt(1.0 - E2 * np.sin(lat) ** 2)
    alt = p * np.cos(lat) + z * np.sin(lat) - n * (1.0 - E2 * np.sin(lat) ** 2)
    return lat, lon, alt


def ned_to_ecef_matrix(lat, lon):
    """Rotation matrix ``C_n_e`` whose columns are North, East, Down in ECEF.

    Parameters
    ----------
    lat, lon : array_like
        Geodetic latitude and longitude (rad); they broadcast.

    Returns
    -------
    numpy.ndarray, shape (..., 3, 3)
        ``C_n_e``: NED vectors to ECEF, ``v_e = C_n_e v_n``.
    """
    lat, lon = np.broadcast_arrays(np.asarray(lat, dtype=float), np.asarray(lon, dtype=float))
    sl, cl = np.sin(lat), np.cos(lat)
    so, co = np.sin(lon), np.cos(lon)
    north = np.stack([-sl * co, -sl * so, cl], axis=-1)
    east = np.stack([-so, co, np.zeros_like(lat)], axis=-1)
    down = np.stack([-cl * co, -cl * so, -sl], axis=-1)
    return np.stack([north, east, down], axis=-1)


def radii_of_curvature(lat):
    """Meridian and prime-vertical radii ``(R_M, R_N)`` in m at geodetic latitude ``lat``."""
    s2 = np.sin(np.asarray(lat, dtype=float)) ** 2
    r_n = A / np.sqrt(1.0 - E2 * s2)
    r_m = A * (1.0 - E2) / (1.0 - E2 * s2) ** 1.5
    return r_m, r_n


def _j2_terms(r_e):
    r_e = np.asarray(r_e, dtype=float)
    r2 = np.sum(r_e**2, axis=-1)
    r = np.sqrt(r2)
    s = r_e[..., 2] ** 2 / r2
    return r_e, r, s


def gravitation_ecef(r_e):
    """Gravitational acceleration (central + J2) at ECEF positions (..., 3), m/s^2."""
    r_e, r, s = _j2_terms(r_e)
    k = 1.5 * J2 * GM * A**2
    a_coef = np.array([1.0, 1.0, 3.0])
    central = -GM * r_e / r[..., None] ** 3
    j2 = -k * r_e * (a_coef - 5.0 * s[..., None]) / r[..., None] ** 5
    return central + j2


def normal_gravity_ecef(r_e):
    """Normal gravity gamma^e = gravitation + centrifugal, at ECEF positions (..., 3), m/s^2.

    This is what a stationary accelerometer senses the negative of (docs/assumptions.md A5).
    """
    r_e = np.asarray(r_e, dtype=float)
    centrifugal = OMEGA_E**2 * r_e * np.array([1.0, 1.0, 0.0])
    return gravitation_ecef(r_e) + centrifugal


def normal_gravity_point(x: float, y: float, z: float) -> tuple[float, float, float]:
    """:func:`normal_gravity_ecef` at one ECEF position ``(x, y, z)`` (m), in scalar
    arithmetic: the same operations in the same order, so bitwise the same three components
    (tests/test_earth.py), without the array calls (an ODE right-hand side calls it ~50 000
    times per trajectory: about 4 instead of 20 us a call).

    Parameters
    ----------
    x, y, z : float
        ECEF position, m.

    Returns
    -------
    tuple of float
        Normal gravity (x, y, z), m/s^2.
    """
    r2 = (x * x + y * y) + z * z       # the order of np.sum over three entries
    r = np.array([math.sqrt(r2)])
    r3, r5 = float((r**3)[0]), float((r**5)[0])    # NumPy's power (not libm's pow)
    j2 = -1.5 * J2 * GM * A**2
    s5 = 5.0 * (z * z / r2)
    w2 = OMEGA_E**2
    return ((-GM * x / r3 + j2 * x * (1.0 - s5) / r5) + w2 * x * 1.0,
            (-GM * y / r3 + j2 * y * (1.0 - s5) / r5) + w2 * y * 1.0,
            (-GM * z / r3 + j2 * z * (3.0 - s5) / r5) + w2 * z * 0.0)


def gravity_jacobian_ecef(r_e):
    """Jacobian d(gamma^e)/d(r^e) (..., 3, 3) of :func:`normal_gravity_ecef`.

    Central term ``-GM/r^3 (I - 3 r r^T / r^2)``, the J2 term differentiated in closed form,
    and the centrifugal term ``-S(Omega)^2 = Omega^2 diag(1, 1, 0)`` (docs/assumptions.md A5).
    """
    r_e, r, s = _j2_terms(r_e)
    eye = np.eye(3)
    rr = r_e[..., :, None] * r_e[..., None, :]
    r_ = r[..., None, None]
    central = -GM * (eye / r_**3 - 3.0 * rr / r_**5)

    k = 1.5 * J2 * GM * A**2
    a_coef = np.array([1.0, 1.0, 3.0])
    h = (a_coef - 5.0 * s[..., None]) / r[..., None] ** 5  # (..., 3), per component i
    z = r_e[..., 2]
    ds = -2.0 * s[..., None] * r_e / r[..., None] ** 2  # d s / d r_j
    ds[..., 2] += 2.0 * z / r**2
    dh = (a_coef - 5.0 * s[..., None])[..., :, None] * (-5.0 * r_e[..., None, :] / r_**7) + (
        -5.0 * ds[..., None, :] / r_**5
    )
    j2 = -k * (eye * h[..., :, None] + r_e[..., :, None] * dh)
    centrifugal = OMEGA_E**2 * np.diag([1.0, 1.0, 0.0])
    return central + j2 + centrifugal


def gravity_magnitude(lat, alt):
    """Magnitude of normal gravity at a geodetic latitude and height.

    Parameters
    ----------
    lat : array_like
        Geodetic latitude (rad).
    alt : array_like
        Height above the ellipsoid (m), broadcast against ``lat``.

    Returns
    -------
    numpy.ndarray
        ``|g|`` (m/s^2) of :func:`normal_gravity_ecef` at those points.
    """
    r_e = geodetic_to_ecef(lat, np.zeros_like(np.asarray(lat, dtype=float)), alt)
    return np.linalg.norm(normal_gravity_ecef(r_e), axis=-1)
