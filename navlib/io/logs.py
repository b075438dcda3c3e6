"""A ``LOG`` argument of ``python -m navlib assess`` / ``plan --flight``: its kind and reader.

A ``LOG`` is a PX4 ``.ulg`` file, an ArduPilot DataFlash ``.bin`` file, an Altus Metrum AltOS
CSV export (recognised by its header, whatever its name) or an ``imu.csv,gnss.csv`` pair
(spec api.md "Scale").
"""

from __future__ import annotations

from pathlib import Path

from navlib.errors import NavlibInputError
from navlib.io.altos import looks_like_altos, read_altos
from navlib.io.csv_files import read_gnss_csv, read_imu_csv
from navlib.io.dataflash import read_dataflash
from navlib.io.ulog import read_ulog

LOG_KINDS = ("ulog", "dataflash", "altos", "csv")
"""The kinds :func:`parse_log` tells apart."""


def parse_log(spec: str) -> tuple[str, tuple[Path, ...]]:
    """The kind (one of :data:`LOG_KINDS`) and file(s) of a ``LOG`` argument.

    One file is a ``.ulg`` or ``.bin`` by its suffix, an AltOS export by its first line
    (:func:`navlib.io.altos.looks_like_altos`), whatever its name.
    """
    if not isinstance(spec, str) or not spec.strip():
        raise NavlibInputError(f"log: expected a file name, got {spec!r}")
    parts = [p.strip() for p in spec.split(",")]
    if len(parts) == 2:
        if not all(p.lower().endswith(".csv") for p in parts):
            raise NavlibInputError(f"log {spec!r}: a pair must be 'imu.csv,gnss.csv'")
        return "csv", (Path(parts[0]), Path(parts[1]))
    if len(parts) != 1:
        raise NavlibInputError(f"log {spec!r}: expected one .ulg/.bin file, an AltOS .csv "
                               "export or an 'imu.csv,gnss.csv' pair")
    suffix = Path(parts[0]).suffix.lower()
    if suffix == ".ulg":
        return "ulog", (Path(parts[0]),)
    if suffix == ".bin":
        return "dataflash", (Path(parts[0]),)
    if looks_like_altos(parts[0]):
        return "altos", (Path(parts[0]),)
    raise NavlibInputError(f"log {spec!r}: unknown kind; expected .ulg, .bin, an AltOS .csv "
                           "export (header '#version,...' or 'time,acceleration,...') or "
                           "'imu.csv,gnss.csv'")


def read_log(spec: str):
    """``imu, gnss`` of a ``LOG`` argument (:func:`parse_log`), read with the reader of its
    kind and that reader's defaults."""
    kind, paths = parse_log(spec)
    if kind == "ulog":
        return read_ulog(paths[0])
    if kind == "csv":
        return read_imu_csv(paths[0]), read_gnss_csv(paths[1])
    if kind == "altos":
        return read_altos(paths[0])
    return read_dataflash(paths[0])
