"""FIRM flight-computer CSV logs (one file: IMU, barometer and on-board estimates, no GNSS).

A FIRM log is recognised by its header (:func:`looks_like_firm`): ``timestamp_seconds``,
``pressure_pascals``, ``raw_acceleration_{x,y,z}_gs`` and ``raw_angular_rate_{x,y,z}_deg_per_s``
(the NCSU AirbrakesV2 export of FIRM v1.0; other columns, the board's own estimates, are
ignored). Units: s, Pa, g, deg/s; axes are the board's, whatever its mounting (the flight fit
finds the attitude at rest). The accelerometer reads specific force (+1 g up at rest), the
navlib convention.
"""

from __future__ import annotations

import pandas as pd

from navlib.io._table import existing_file, split_header_name
from navlib.io.baro import read_baro_csv
from navlib.io.csv_files import read_imu_csv

__all__ = ["FIRM_BARO_COLUMNS", "FIRM_COLUMNS", "header_names", "looks_like_firm", "read_firm"]

FIRM_COLUMNS = {
    "t": "timestamp_seconds",
    "f_x": "raw_acceleration_x_gs", "f_y": "raw_acceleration_y_gs",
    "f_z": "raw_acceleration_z_gs",
    "w_x": "raw_angular_rate_x_deg_per_s", "w_y": "raw_angular_rate_y_deg_per_s",
    "w_z": "raw_angular_rate_z_deg_per_s",
}
"""IMU columns of a FIRM log, by navlib name."""
FIRM_BARO_COLUMNS = {"t": "timestamp_seconds", "pressure_pa": "pressure_pascals",
                     "temperature_c": "temperature_celsius"}
"""Barometer columns of a FIRM log, by navlib name."""


def header_names(path) -> set[str]:
    """Normalised names of the first line of ``path`` (empty when unreadable)."""
    try:
        p, _ = existing_file(path)
        with p.open("r", encoding="utf-8-sig", errors="replace") as fh:
            first = fh.readline()
    except (OSError, ValueError):
        return set()
    return {split_header_name(h)[0] for h in first.replace(";", ",").split(",")}


def looks_like_firm(path) -> bool:
    """Whether the first line of ``path`` is a FIRM header (module docstring)."""
    return {*FIRM_COLUMNS.values(), "pressure_pascals"} <= header_names(path)


def read_firm(path, **imu_options) -> tuple[pd.DataFrame, None]:
    """``imu, None`` of a FIRM log; the barometer is ``imu.attrs["baro"]``.

    Parameters
    ----------
    path : str or Path
    **imu_options
        Keywords of :func:`navlib.io.read_imu_csv` (``max_gap_s``, ``on_gap``,
        ``max_rate_rad_s``...); the columns and units are FIRM's.

    Returns
    -------
    imu : DataFrame
        As :func:`navlib.io.read_imu_csv`; ``attrs``: ``flight_computer = "FIRM"``,
        ``vehicle = "rocket"``, ``baro`` (:func:`navlib.io.baro.read_baro_csv`: ``t, alt_m,
        pressure_pa, temperature_c``).
    gnss : None
        FIRM has no GNSS receiver.
    """
    imu = read_imu_csv(path, columns=FIRM_COLUMNS, accel_unit="g", gyro_unit="deg/s",
                       **imu_options)
    baro = read_baro_csv(path, columns=FIRM_BARO_COLUMNS)
    imu.attrs.update(autopilot="firm", hardware="FIRM v1.0", flight_computer="FIRM",
                     vehicle="rocket", baro=baro)
    return imu, None
