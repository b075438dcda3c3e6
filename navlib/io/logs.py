"""A ``LOG`` argument of ``python -m navlib assess`` / ``plan --flight``: its kind and reader.

A ``LOG`` is one of (docs/sweeps.md):

* a PX4 ``.ulg`` file or an ArduPilot DataFlash ``.bin`` file (by suffix);
* one CSV file recognised by its header, whatever its name: an Altus Metrum AltOS export,
  a FIRM log (:mod:`navlib.io.firm`), or a CATS Vega ``imu.csv`` (:mod:`navlib.io.cats`,
  with ``baro.csv`` and ``gnssInfo.csv`` beside it);
* CSV files given together: ``imu.csv,gnss.csv``, ``imu.csv,baro.csv`` or
  ``imu.csv,gnss.csv,baro.csv`` (:func:`navlib.io.read_imu_csv`,
  :func:`navlib.io.read_gnss_csv`, :func:`navlib.io.baro.read_baro_csv`; the second of a pair
  is a barometer when its header has a pressure or altitude column and no position, and the
  last two of three may come in either order).

A barometer record goes in ``imu.attrs["baro"]`` (``t, alt_m``); a log without GNSS reads as
``gnss = None``. A CSV file that is none of these is refused with what it lacks.

Reader options (``read_log(spec, **read_options)``, ``python -m navlib assess --read KEY
VALUE``) are keywords of the reader of the log's kind (:func:`reader_keywords`): for CSV
files each goes to every file's reader that takes it (``time_unit`` to all three,
``gyro_unit`` to the IMU file, ``keep_held`` to the GNSS file); a keyword no reader of the
log takes is refused, naming those it takes.
"""

from __future__ import annotations

import inspect
from pathlib import Path

from navlib.errors import NavlibInputError
from navlib.io.altos import looks_like_altos, read_altos
from navlib.io.baro import BARO_COLUMNS, read_baro_csv
from navlib.io.cats import looks_like_cats, read_cats
from navlib.io.csv_files import GNSS_COLUMNS, IMU_COLUMNS, read_gnss_csv, read_imu_csv
from navlib.io.dataflash import read_dataflash
from navlib.io.firm import header_names, looks_like_firm, read_firm
from navlib.io.ulog import read_ulog

__all__ = ["LOG_KINDS", "parse_log", "read_log", "reader_keywords"]

LOG_KINDS = ("ulog", "dataflash", "altos", "firm", "cats", "csv")
"""The kinds :func:`parse_log` tells apart."""

_POSITION_KEYS = ("x", "y", "z", "lat", "lon", "lat_deg", "lon_deg")


def _has(names: set[str], columns: dict, keys) -> bool:
    return any(k in names or names & set(columns[k]) for k in keys)


def _is_baro(path: str) -> bool:
    """The header has a pressure or altitude column and no GNSS position column."""
    names = header_names(path)
    return (_has(names, BARO_COLUMNS, ("pressure_pa", "altitude_m"))
            and not _has(names, GNSS_COLUMNS, _POSITION_KEYS))


def _what_is_missing(spec: str, path: str) -> str:
    """Why one CSV file is no ``LOG``: what its header has and lacks."""
    names = header_names(path)
    if not names:
        return f"log {spec!r}: file not found or unreadable"
    imu = all(_has(names, IMU_COLUMNS, (k,)) for k in IMU_COLUMNS if k != "t")
    gnss = _has(names, GNSS_COLUMNS, _POSITION_KEYS)
    baro = _has(names, BARO_COLUMNS, ("pressure_pa", "altitude_m"))
    if imu:
        lacks = ("it has IMU columns" + (" and a barometer" if baro else "")
                 + (" and GNSS positions" if gnss else "")
                 + "; a single file is read only when it is an AltOS, FIRM or CATS export: "
                 "give the records as 'imu.csv,gnss.csv', 'imu.csv,baro.csv' or "
                 "'imu.csv,gnss.csv,baro.csv'")
    else:
        lacks = ("it has no IMU columns (specific force f_x/ax/acc_x... and angular rate "
                 "w_x/gx/gyro_x...), so it is not a flight log navlib reads alone"
                 + ("; it looks like a GNSS record: give 'imu.csv,gnss.csv'" if gnss else "")
                 + ("; it looks like a barometer record: give 'imu.csv,baro.csv'"
                    if baro and not gnss else ""))
    head = sorted(names)[:12]
    return (f"log {spec!r}: not a .ulg/.bin log nor a recognised CSV export (AltOS, FIRM, "
            f"CATS imu.csv): {lacks}; header names {head}")


def parse_log(spec: str) -> tuple[str, tuple[Path, ...]]:
    """The kind (one of :data:`LOG_KINDS`) and file(s) of a ``LOG`` argument.

    One file is a ``.ulg`` or ``.bin`` by its suffix, an AltOS, FIRM or CATS export by its
    first line, whatever its name. Several CSV files are ``imu, gnss``, ``imu, baro`` or
    ``imu, gnss, baro`` (kind ``csv``, in the given order; the second of two is the
    barometer when its header says so, :func:`read_log`).
    """
    if not isinstance(spec, str) or not spec.strip():
        raise NavlibInputError(f"log: expected a file name, got {spec!r}")
    parts = [p.strip() for p in spec.split(",")]
    if len(parts) in (2, 3):
        if not all(p.lower().endswith(".csv") for p in parts):
            raise NavlibInputError(f"log {spec!r}: several files must be CSV files: "
                                   "'imu.csv,gnss.csv', 'imu.csv,baro.csv' or "
                                   "'imu.csv,gnss.csv,baro.csv'")
        return "csv", tuple(Path(p) for p in parts)
    if len(parts) != 1:
        raise NavlibInputError(f"log {spec!r}: expected one .ulg/.bin file, a .csv export "
                               "(AltOS, FIRM, CATS imu.csv) or 'imu.csv,gnss.csv[,baro.csv]'")
    suffix = Path(parts[0]).suffix.lower()
    if suffix == ".ulg":
        return "ulog", (Path(parts[0]),)
    if suffix == ".bin":
        return "dataflash", (Path(parts[0]),)
    for kind, looks in (("altos", looks_like_altos), ("firm", looks_like_firm),
                        ("cats", looks_like_cats)):
        if looks(parts[0]):
            return kind, (Path(parts[0]),)
    raise NavlibInputError(_what_is_missing(spec, parts[0]))


def _keywords(fn, *fixed: str) -> tuple[str, ...]:
    return tuple(p.name for p in inspect.signature(fn).parameters.values()
                 if p.kind is inspect.Parameter.KEYWORD_ONLY and p.name not in fixed)


_FIXED_BY_EXPORT = ("columns", "accel_unit", "gyro_unit", "sep")
"""Keywords of :func:`read_imu_csv` that the FIRM and CATS readers set themselves."""
_CSV_READERS = {"imu": _keywords(read_imu_csv), "gnss": _keywords(read_gnss_csv, "baro"),
                "baro": _keywords(read_baro_csv)}


def reader_keywords(kind: str) -> dict[str, tuple[str, ...]]:
    """The reader options a log of ``kind`` (:data:`LOG_KINDS`) accepts, by reader: one
    entry (the kind) for a single-file log, ``imu``, ``gnss`` and ``baro`` for CSV files."""
    if kind == "csv":
        return dict(_CSV_READERS)
    if kind in ("firm", "cats"):
        return {kind: _keywords(read_imu_csv, *_FIXED_BY_EXPORT)}
    reader = {"ulog": read_ulog, "dataflash": read_dataflash, "altos": read_altos}.get(kind)
    if reader is None:
        raise NavlibInputError(f"kind: expected one of {list(LOG_KINDS)}, got {kind!r}")
    return {kind: _keywords(reader)}


def _routed(spec: str, kind: str, options: dict) -> dict[str, dict]:
    """``options`` split by reader (:func:`reader_keywords`); unknown keywords refused."""
    accepted = reader_keywords(kind)
    taken = {k for names in accepted.values() for k in names}
    unknown = sorted(set(options) - taken)
    if unknown:
        raise NavlibInputError(
            f"read options {unknown}: not a keyword of the {kind} reader of log {spec!r}; it "
            f"takes {sorted(taken)}")
    return {reader: {k: v for k, v in options.items() if k in names}
            for reader, names in accepted.items()}


def read_log(spec: str, **read_options):
    """``imu, gnss`` of a ``LOG`` argument, read with the reader of its kind.

    Parameters
    ----------
    spec : str
        The ``LOG`` (:func:`parse_log`).
    **read_options
        Keywords of the reader of its kind (module docstring, :func:`reader_keywords`; e.g.
        ``max_rate_rad_s=60``, ``on_gap="split"``); the reader's defaults otherwise.

    Returns
    -------
    imu : DataFrame
        The IMU record; a barometer, when the log has one, is ``imu.attrs["baro"]``.
    gnss : DataFrame or None
        The GNSS record; None for a log without GNSS.

    Raises
    ------
    NavlibInputError
        A keyword no reader of the log takes (naming those it takes), and the reader's own
        errors.
    """
    kind, paths = parse_log(spec)
    options = _routed(spec, kind, read_options)
    if kind == "csv":
        if len(paths) == 2:
            paths = (paths[0], None, paths[1]) if _is_baro(str(paths[1])) else (*paths, None)
        elif _is_baro(str(paths[1])) and not _is_baro(str(paths[2])):
            paths = (paths[0], paths[2], paths[1])          # 'imu.csv,baro.csv,gnss.csv'
        return _read_csv_files(*paths, options)
    reader = {"ulog": read_ulog, "altos": read_altos, "firm": read_firm, "cats": read_cats,
              "dataflash": read_dataflash}[kind]
    return reader(paths[0], **options[kind])


def _read_csv_files(imu_path, gnss_path, baro_path, options):
    imu = read_imu_csv(imu_path, **options["imu"])
    baro = read_baro_csv(baro_path, **options["baro"]) if baro_path is not None else None
    gnss = (read_gnss_csv(gnss_path, baro=baro, **options["gnss"]) if gnss_path is not None
            else None)
    if baro is not None:
        imu.attrs["baro"] = baro
    return imu, gnss
