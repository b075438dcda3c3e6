"""Unit names accepted by the flight-data readers and writers, mapped to SI factors.

The factors themselves come from :mod:`navlib.units` (the one place that converts units);
this module only spells out which names a CSV header or a keyword may use.
"""

from __future__ import annotations

from navlib import units
from navlib.errors import NavlibInputError

TIME = {"s": 1.0, "sec": 1.0, "ms": units.MILLISECOND, "us": units.MICROSECOND,
        "µs": units.MICROSECOND, "usec": units.MICROSECOND, "ns": units.NANOSECOND}
ACCEL = {"m/s^2": 1.0, "m/s2": 1.0, "m/s²": 1.0, "m/s/s": 1.0, "g": units.G0, "mg": units.MG}
GYRO = {"rad/s": 1.0, "deg/s": units.DEG, "dps": units.DEG, "°/s": units.DEG}
LENGTH = {"m": 1.0, "mm": units.MILLIMETRE, "km": units.KILOMETRE}
VELOCITY = {"m/s": 1.0, "mm/s": units.MILLIMETRE, "km/s": units.KILOMETRE}
ANGLE = {"rad": 1.0, "deg": units.DEG, "°": units.DEG}
DEGREES = {"deg": units.DEG, "°": units.DEG}
PRESSURE = {"pa": 1.0, "hpa": units.HECTOPASCAL, "mbar": units.HECTOPASCAL,
            "kpa": units.KILOPASCAL}

KINDS = {"time": TIME, "accel": ACCEL, "gyro": GYRO, "length": LENGTH, "velocity": VELOCITY,
         "angle": ANGLE, "degrees": DEGREES, "pressure": PRESSURE}
"""Unit tables by quantity kind (the kind of each CSV column)."""

VELOCITY_OF_LENGTH = {"m": "m/s", "mm": "mm/s", "km": "km/s"}
"""The velocity unit implied by a ``length_unit`` keyword."""


def normalise(name: str) -> str:
    """Canonical spelling of a unit name: lower case, no blanks, ``**`` as ``^``."""
    return name.strip().lower().replace(" ", "").replace("**", "^")


def factor(kind: str, name: str, where: str) -> float:
    """SI factor of unit ``name`` of quantity ``kind``; ``where`` names the keyword or column."""
    table = KINDS[kind]
    key = normalise(str(name))
    if key not in table:
        raise NavlibInputError(
            f"{where}: unit {name!r} not understood for a {kind} quantity; "
            f"accepted: {sorted(table)}"
        )
    return table[key]
