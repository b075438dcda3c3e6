"""A vehicle at rest on the ground, body axes aligned with the local NED frame.

Default site: the SSAC experiment at LINCS/IAE, São José dos Campos (docs/assumptions.md, ssac.md
§4.1: -23°12'47", -45°51'38", 629 m, 60 min, IMU at 100 Hz).
"""

from __future__ import annotations

import numpy as np

from navlib import earth
from navlib._validation import finite_scalar, latitude_deg
from navlib.errors import NavlibInputError
from navlib.trajectory._flight import output_times
from navlib.trajectory.base import Trajectory, build_trajectory
from navlib.units import DEG

__all__ = ["stationary"]


def stationary(lat_deg=-23.213056, lon_deg=-45.860556, alt_m=629.0, duration_s=3600.0,
               rate_hz=100.0) -> Trajectory:
    """Stationary vehicle with body = NED (docs/assumptions.md, ssac.md §4.1 defaults).

    Parameters
    ----------
    lat_deg, lon_deg : float
        Geodetic latitude in [-90, 90] and longitude, degrees.
    alt_m : float
        Ellipsoidal height, m.
    duration_s : float
        Length of the record, s (> 0).
    rate_hz : float
        IMU rate, Hz (> 0).

    Returns
    -------
    Trajectory
        ``C_b_e = C_n_e``, ``V = 0``, ``f^b = -C_e^b gamma``, ``omega_ib^b = C_e^b Omega``
        (i.e. ``Omega [cos L, 0, -sin L]`` in NED). Events: ``start``, ``end``.
    """
    lat = latitude_deg(lat_deg, "lat_deg") * DEG
    lon = finite_scalar(lon_deg, "lon_deg", -360.0, 360.0) * DEG
    alt = finite_scalar(alt_m, "alt_m", -11_000.0, 1.0e6)
    duration = finite_scalar(duration_s, "duration_s", 0.0, low_open=True)
    rate = finite_scalar(rate_hz, "rate_hz", 0.0, low_open=True)
    if duration * rate < 1.0:
        raise NavlibInputError(
            f"duration_s: {duration} s at rate_hz={rate} gives fewer than 2 samples")
    t = output_times(duration, rate)
    n = t.size
    P = np.broadcast_to(earth.geodetic_to_ecef(lat, lon, alt), (n, 3))
    zeros = np.zeros((n, 3))
    C_b_e = np.broadcast_to(earth.ned_to_ecef_matrix(lat, lon), (n, 3, 3))
    return build_trajectory(
        t, P, zeros, zeros, C_b_e, zeros, events={"start": 0.0, "end": float(t[-1])},
        name="stationary",
        parameters={"lat_deg": float(lat_deg), "lon_deg": float(lon_deg), "alt_m": alt,
                    "duration_s": duration, "rate_hz": rate},
    )
