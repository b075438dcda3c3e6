"""Unit conversions: the one place where degrees, deg/h, mg, ppm and friends meet SI.

Inside navlib everything is SI with angles in radians. Names at the edges carry a suffix
(``lat_deg``, ``sigma_bg_deg_h``); convert them here and nowhere else.
"""

import numpy as np

__all__ = ["DEG", "DEG_E7", "DEG_PER_HOUR", "DEG_PER_HOUR_PER_SQRT_HZ", "DEG_PER_SQRT_HOUR", "G0",
           "HOUR", "KILOMETRE", "MG", "MG_PER_SQRT_HZ", "MICROSECOND", "MILLIMETRE", "MILLIRADIAN",
           "MILLISECOND", "MINUTE", "M_S_PER_SQRT_HOUR", "NANOSECOND", "PPM", "UG",
           "UG_PER_SQRT_HZ", "deg2rad", "rad2deg"]

G0 = 9.80665
"""Standard gravity, m/s^2 (used only to convert g, mg and ug)."""

DEG = np.pi / 180.0
"""One degree in radians."""
MILLIRADIAN = 1e-3
"""One milliradian in radians."""
MINUTE = 60.0
"""One minute in seconds."""
HOUR = 3600.0
"""One hour in seconds."""

DEG_PER_HOUR = DEG / HOUR
"""One deg/h in rad/s."""
DEG_PER_SQRT_HOUR = DEG / np.sqrt(HOUR)
"""One deg/sqrt(h) (angle random walk) in rad/sqrt(s)."""
DEG_PER_HOUR_PER_SQRT_HZ = DEG_PER_HOUR
"""One deg/h/sqrt(Hz) in rad/s/sqrt(Hz) = rad/sqrt(s)."""
MG = 1e-3 * G0
"""One milli-g in m/s^2."""
UG = 1e-6 * G0
"""One micro-g in m/s^2."""
UG_PER_SQRT_HZ = UG
"""One ug/sqrt(Hz) in m/s^2/sqrt(Hz) = m/s/sqrt(s)."""
MG_PER_SQRT_HZ = MG
"""One mg/sqrt(Hz) in m/s/sqrt(s)."""
M_S_PER_SQRT_HOUR = 1.0 / np.sqrt(HOUR)
"""One m/s/sqrt(h) (velocity random walk) in m/s/sqrt(s)."""
PPM = 1e-6
"""One part per million, dimensionless."""


def deg2rad(x):
    """Degrees to radians (arrays welcome)."""
    return np.asarray(x, dtype=float) * DEG


def rad2deg(x):
    """Radians to degrees (arrays welcome)."""
    return np.asarray(x, dtype=float) / DEG


# Added for flight-data import (navlib.io): time stamps, lengths and PX4 integer angles.
MILLISECOND = 1e-3
"""One millisecond in seconds."""
MICROSECOND = 1e-6
"""One microsecond in seconds (PX4 ULog time stamps)."""
NANOSECOND = 1e-9
"""One nanosecond in seconds."""
MILLIMETRE = 1e-3
"""One millimetre in metres (PX4 ``alt`` fields)."""
KILOMETRE = 1e3
"""One kilometre in metres."""
HECTOPASCAL = 100.0
"""One hectopascal (= one millibar) in pascals (barometer CSV files)."""
KILOPASCAL = 1e3
"""One kilopascal in pascals."""
DEG_E7 = 1e-7 * DEG
"""One step of the integer 1e-7-degree angle encoding (PX4 ``lat``/``lon``, MAVLink), in rad."""
