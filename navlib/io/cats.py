"""CATS Vega flight-computer exports: ``imu.csv`` with ``baro.csv`` and ``gnssInfo.csv``
beside it.

An export is recognised by the header of its ``imu.csv`` (:func:`looks_like_cats`):
``ts, id, Ax, Ay, Az, Gx, Gy, Gz`` (s, sensor id, m/s^2, deg/s; board axes). In the same
folder, ``baro.csv`` (``ts, id, T, P``: s, id, deg C, Pa) is the barometer and
``gnssInfo.csv`` (``ts, latitude, longitude, satellites``), when present, the GNSS fixes,
**without height**: their height is the barometric altitude (assumptions.md B1). A fix
repeating the previous one exactly (a receiver's position held between its updates, logged
again) is not a new measurement, and a row reporting an impossible satellite count (the
first rows of the shared Hedy flight report 193) is not trusted: :func:`read_gnss_csv` drops
both with a warning naming their count and lines (assumption Q7).
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from navlib.errors import NavlibInputError
from navlib.io.baro import read_baro_csv
from navlib.io.csv_files import read_gnss_csv, read_imu_csv
from navlib.io.firm import header_names

__all__ = ["BARO_FILE", "CATS_IMU_HEADER", "GNSS_FILE", "looks_like_cats", "read_cats"]

CATS_IMU_HEADER = ("ts", "id", "ax", "ay", "az", "gx", "gy", "gz")
"""Normalised header of a CATS ``imu.csv``."""
BARO_FILE = "baro.csv"
GNSS_FILE = "gnssInfo.csv"


def looks_like_cats(path) -> bool:
    """Whether the first line of ``path`` is a CATS ``imu.csv`` header (module docstring)."""
    return set(CATS_IMU_HEADER) <= header_names(path)


def _single_sensor(path, ids) -> None:
    if ids is not None and len(set(ids)) > 1:
        raise NavlibInputError(f"file '{path}': column 'id' names {len(set(ids))} sensors "
                               f"({', '.join(sorted(set(ids)))}); split the file by sensor")


def read_cats(path, **imu_options) -> tuple[pd.DataFrame, pd.DataFrame | None]:
    """``imu, gnss`` of a CATS Vega export given by its ``imu.csv``.

    Parameters
    ----------
    path : str or Path
        The export's ``imu.csv``; ``baro.csv`` must be in the same folder, ``gnssInfo.csv``
        may be.
    **imu_options
        Keywords of :func:`navlib.io.read_imu_csv`.

    Returns
    -------
    imu : DataFrame
        As :func:`navlib.io.read_imu_csv`; ``attrs``: ``flight_computer = "CATS"``,
        ``vehicle = "rocket"``, ``baro`` (``t, alt_m, pressure_pa, temperature_c``).
    gnss : DataFrame or None
        As :func:`navlib.io.read_gnss_csv` with the barometric height
        (``attrs["height_source"] = "baro"``, ``attrs["held_fixes_dropped"]``); None
        without ``gnssInfo.csv``.

    Raises
    ------
    NavlibInputError
        No ``baro.csv`` beside the file, several sensor ids in one file, and the readers'
        own errors.
    """
    path = Path(path)
    baro_path = path.parent / BARO_FILE
    if not baro_path.is_file():
        raise NavlibInputError(f"file '{path}': a CATS export's barometer '{BARO_FILE}' is "
                               f"not beside it (looked for '{baro_path}')")
    imu = read_imu_csv(path, columns={"t": "ts"}, gyro_unit="deg/s", **imu_options)
    _single_sensor(path, pd.read_csv(path, usecols=["id"])["id"].astype(str))
    baro = read_baro_csv(baro_path, columns={"t": "ts", "pressure_pa": "P",
                                             "temperature_c": "T"})
    imu.attrs.update(autopilot="cats", hardware="CATS Vega", flight_computer="CATS",
                     vehicle="rocket", baro=baro)
    gnss_path = path.parent / GNSS_FILE
    if not gnss_path.is_file():
        return imu, None
    gnss = read_gnss_csv(gnss_path, columns={"t": "ts"}, baro=baro, position="geodetic")
    return imu, gnss
