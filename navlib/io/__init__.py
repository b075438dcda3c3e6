"""Flight-data import and validation: IMU/GNSS CSV files, PX4 ULog, ArduPilot DataFlash logs
and Altus Metrum AltOS CSV exports.

Public contract (docs/assess.md)::

    imu = navlib.io.read_imu_csv(path, **units)    # t, f_x, f_y, f_z, w_x, w_y, w_z (SI)
    gnss = navlib.io.read_gnss_csv(path, **units)  # t, x, y, z (ECEF m) [+ vx, vy, vz, sigma]
    imu, gnss = navlib.io.read_ulog(path)          # PX4 ULog via pyulog, same columns
    imu, gnss = navlib.io.read_dataflash(path)     # ArduPilot .bin via pymavlink, same columns
    imu, gnss = navlib.io.read_altos(path)         # Altus Metrum AltOS CSV export, same columns
    baro = navlib.io.read_baro_csv(path, **units)  # t, alt_m [+ pressure_pa, temperature_c]
    imu, gnss = navlib.io.read_firm(path)          # FIRM log: gnss None, imu.attrs["baro"]
    imu, gnss = navlib.io.read_cats(path)          # CATS Vega imu.csv (+ baro.csv, gnssInfo.csv)

plus :func:`check_overlap` (IMU and GNSS spans), :func:`split_at_gaps` (records read with
``on_gap="split"``) and the inverse writers :func:`write_imu_csv`, :func:`write_gnss_csv`.
Column names, aliases and unit keywords: :mod:`navlib.io.csv_files`; PX4 body frame and
field mapping: :mod:`navlib.io.ulog`; DataFlash messages: :mod:`navlib.io.dataflash`; AltOS
columns and axes: :mod:`navlib.io.altos`; barometer CSV files: :mod:`navlib.io.baro`; FIRM and
CATS exports: :mod:`navlib.io.firm`, :mod:`navlib.io.cats`; dead IMU channels:
:mod:`navlib.io.sensor_health`; held and implausible GNSS rows: :mod:`navlib.io.gnss_rows`;
the kind of a ``LOG`` argument, its reader and reader options: :mod:`navlib.io.logs`; the
data-quality checks run before an assessment (saturation, GNSS faults judged by time):
:mod:`navlib.io.quality`. A barometer record rides on ``imu.attrs["baro"]``; a log without
GNSS reads as ``gnss = None``. Every
problem raises :class:`navlib.NavlibInputError` naming file, column and line (or topic,
field and message).
"""

from navlib.io.altos import read_altos
from navlib.io.baro import read_baro_csv
from navlib.io.cats import read_cats
from navlib.io.checks import FlightDataWarning, TimeOverlap, check_overlap, split_at_gaps
from navlib.io.csv_files import (
    GNSS_COLUMNS,
    IMU_COLUMNS,
    combine_sigma,
    read_gnss_csv,
    read_imu_csv,
)
from navlib.io.csv_writers import write_gnss_csv, write_imu_csv
from navlib.io.dataflash import read_dataflash
from navlib.io.firm import read_firm
from navlib.io.logs import LOG_KINDS, parse_log, read_log
from navlib.io.ulog import read_ulog

__all__ = [
    "GNSS_COLUMNS",
    "IMU_COLUMNS",
    "LOG_KINDS",
    "FlightDataWarning",
    "TimeOverlap",
    "check_overlap",
    "combine_sigma",
    "parse_log",
    "read_altos",
    "read_baro_csv",
    "read_cats",
    "read_dataflash",
    "read_firm",
    "read_gnss_csv",
    "read_imu_csv",
    "read_log",
    "read_ulog",
    "split_at_gaps",
    "write_gnss_csv",
    "write_imu_csv",
]
