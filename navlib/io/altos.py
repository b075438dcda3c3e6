"""Altus Metrum AltOS CSV export (TeleMega and its kin): IMU, GPS fixes, the logger's own data.

AltOS, the ground software of the Altus Metrum flight computers, exports a flight as one CSV
row per logged record. Two header generations are in use:

* newer: the first header cell is ``#version``, then ``serial, flight, call, time, state,
  state_name, acceleration, pressure, altitude, ...``; cells are padded with blanks;
* older: the header starts ``time, acceleration, pressure, altitude, ...``, with no
  serial, flight or state columns.

Both name ``altitude`` twice: the first is the barometric altitude (m above mean sea level
from the standard atmosphere), the second, after ``latitude``/``longitude``, the GPS altitude
above mean sea level. :func:`read_altos` reads both generations (docs/assumptions.md IO1-IO4).

Axes and units (docs/assumptions.md IO1)
-------------------------------------------
``accel_x/y/z`` (m/s^2, specific force) and ``gyro_roll/pitch/yaw`` (deg/s) are on the
board's along / across / through axes. The navlib body frame is ``x`` = along (towards the
nose: on the pad the accelerometer reads about +9.9 m/s^2 on it), ``y`` = across, ``z`` =
through, with ``w_x`` = roll, ``w_y`` = pitch, ``w_z`` = yaw rates, positive by the right-hand
rule. All columns are taken with their logged signs; no axis is flipped.
"""

from __future__ import annotations

import re
import warnings

import numpy as np
import pandas as pd

from navlib import units
from navlib.earth import geodetic_to_ecef
from navlib.errors import FlightDataWarning, NavlibInputError
from navlib.io._table import (
    Column,
    Source,
    TextTable,
    check_finite,
    existing_file,
    parse_columns,
    read_text_table,
)
from navlib.io.checks import (
    MAX_OUTLIER_FRACTION,
    SAMPLE_ACCEL_MAX,
    apply_gap_policy,
    check_overlap,
    check_positions,
    check_sample_interval,
    check_times,
    reader_limits,
    validated_imu,
)
from navlib.io.sensor_health import check_imu_alive, dead_magnetometer

__all__ = ["ACCEL_COLUMNS", "FIX_COLUMNS", "GYRO_COLUMNS", "IMU_BLOCK", "MAG_LABELS",
           "MIN_SATELLITES", "TELEMEGA_RANGE", "looks_like_altos", "read_altos"]

ACCEL_COLUMNS = ("accel_x", "accel_y", "accel_z")
"""AltOS accelerometer columns (m/s^2) on the along, across, through axes."""
GYRO_COLUMNS = ("gyro_roll", "gyro_pitch", "gyro_yaw")
"""AltOS gyro columns (deg/s) about the along, across, through axes."""
FIX_COLUMNS = ("nsat", "hour", "minute", "second", "pdop", "hdop", "vdop")
"""Optional GPS columns that, with latitude, longitude and GPS altitude, mark a new fix."""
TELEMEGA_RANGE = {"gyro_rad_s": 2000.0 * units.DEG, "accel_m_s2": 16.0 * units.G0}
"""Full scale of the TeleMega IMU as AltOS configures it: +-2000 deg/s, +-16 g per axis."""
MIN_SATELLITES = 4
"""Fewest satellites (``nsat``) of a kept fix: fewer cannot give a 3-D position."""
IMU_BLOCK = ("gyro_roll", "gyro_pitch", "gyro_yaw", "mag_x", "mag_y", "mag_z", "tilt")
"""The IMU block of an AltOS export after ``accel_z``: gyro, magnetometer and tilt columns, in
order. Some exports name fewer of them in the header than every row holds (a header of 75
names over rows of 81 fields): :func:`read_altos` then reads the rows with the block's names
(assumption IO7)."""
_HEADER_PREFIX = "#version"
_OLD_HEAD = ("time", "acceleration", "pressure")
_SERIAL = re.compile(r"serial-(\d+)", re.IGNORECASE)


def _is_header(fields: list[str]) -> bool:
    """``#version, ..., time, ...`` (newer) or ``time, acceleration, pressure, ...`` (older)."""
    names = [f.strip().strip("\"'").lower() for f in fields]
    return ((names[0].lstrip("#") == "version" and "time" in names)
            or tuple(names[:3]) == _OLD_HEAD)


def looks_like_altos(path) -> bool:
    """Whether ``path`` starts with an AltOS CSV export header (either generation).

    Only the first non-blank line is read: ``#version,serial,...,time,...`` or
    ``time,acceleration,pressure,...``. A missing or unreadable file is not an export.
    """
    try:
        with open(path, "rb") as fh:
            head = fh.read(8192)
    except OSError:
        return False
    text = head.decode("utf-8-sig", errors="replace")
    line = next((ln for ln in text.splitlines() if ln.strip()), "")
    return _is_header(line.split(","))


def _layout(table: TextTable, label: str) -> dict[str, int]:
    """Field index of each column read, by name; the two ``altitude`` columns told apart."""
    names = [h.strip().lower() for h in table.header]
    if not _is_header(names):
        raise NavlibInputError(f"{label}: not an AltOS CSV export; expected a header starting "
                               f"'#version,serial,...' or 'time,acceleration,pressure,...', "
                               f"got {table.header[:4]}")
    index: dict[str, int] = {}
    for i, name in enumerate(names):
        if name == "altitude":
            continue
        if name in index:
            raise table.source.error(repr(table.header[i]), None,
                                     f"duplicate column: fields {index[name] + 1} and {i + 1} "
                                     f"of the header")
        index[name] = i
    altitudes = [i for i, name in enumerate(names) if name == "altitude"]
    lat = index.get("latitude")
    baro = [i for i in altitudes if lat is None or i < lat]
    gps = [i for i in altitudes if lat is not None and i > lat]
    if baro:
        index["baro_altitude"] = baro[0]
    if gps:
        index["gps_altitude"] = gps[0]
    missing_imu = [c for c in ("time", *ACCEL_COLUMNS, *GYRO_COLUMNS) if c not in index]
    if missing_imu:
        board = ("no gyro: a TeleMetrum or TeleMini export"
                 if any(c in missing_imu for c in GYRO_COLUMNS) else "an incomplete export")
        raise table.source.error(None, None,
                                 f"missing IMU column(s) {missing_imu} ({board}); read_altos "
                                 f"needs time, a 3-axis accelerometer (accel_x/y/z) and a "
                                 f"3-axis gyro (gyro_roll/pitch/yaw), as TeleMega logs them")
    missing_gps = [c for c in ("latitude", "longitude", "gps_altitude") if c not in index]
    if missing_gps and "baro_altitude" not in index:
        names_gps = [c if c != "gps_altitude" else "altitude (GPS, after longitude)"
                     for c in missing_gps]
        raise table.source.error(None, None,
                                 f"missing GPS column(s) {names_gps} and no barometric "
                                 f"'altitude' (no GPS receiver: an EasyMega or EasyMini "
                                 f"export); read_altos needs GPS fixes or the barometer")
    return index


def _repair_header(header: list[str], fields: int, label: str) -> list[str]:
    """The header of an export whose every row has ``fields`` fields: with the names of
    :data:`IMU_BLOCK` it lacks put back after ``accel_z`` when they are exactly the extra
    fields (a FlightDataWarning says so); NavlibInputError with that diagnosis otherwise."""
    names = [h.strip().lower() for h in header]
    extra = fields - len(header)
    missing = [c for c in IMU_BLOCK if c not in names]
    present = [c for c in IMU_BLOCK if c in names]
    where = names.index("accel_z") + 1 if "accel_z" in names else None
    contiguous = where is not None and names[where:where + len(present)] == present
    if extra <= 0 or len(missing) != extra or not contiguous:
        lacks = (f"it lacks {missing} of that block" if missing else
                 "it names the whole block")
        raise NavlibInputError(
            f"{label}: the header names {len(header)} columns but every row has {fields} "
            f"fields; the {abs(extra)} {'extra' if extra > 0 else 'missing'} field(s) are not "
            f"the AltOS gyro/magnetometer/tilt block {list(IMU_BLOCK)} after accel_z ({lacks}"
            f"{'' if contiguous or where is None else ', not in its place after accel_z'}"
            f"{'' if where is not None else '; no accel_z column'}), so which field is which "
            "cannot be told; export the flight again with AltOS")
    warnings.warn(f"{label}: the header names {len(header)} columns but every row has {fields} "
                  f"fields; the {extra} extra fields are read as the AltOS IMU block the header "
                  f"lacks ({', '.join(missing)}, after accel_z)", FlightDataWarning,
                  stacklevel=4)
    return [*header[:where], *IMU_BLOCK, *header[where + len(present):]]


MAG_LABELS = "'mag_x'/'mag_y'/'mag_z'"


def _magnetometer(table: TextTable, index: dict, rows: np.ndarray) -> np.ndarray | None:
    """The ``mag_x/y/z`` cells of ``rows`` (NaN where empty), or None without them."""
    if not all(c in index for c in ("mag_x", "mag_y", "mag_z")):
        return None
    cols = {c: Column(c, table.header[index[c]], index[c]) for c in ("mag_x", "mag_y", "mag_z")}
    data = parse_columns(table, cols)
    return np.column_stack([data[c][rows] for c in cols])


def _cells(table: TextTable, field: int) -> list[str]:
    return [ln.split(",")[field].strip() for ln in table.source.raw]


def _hardware(table: TextTable, index: dict, path) -> str:
    """Board and serial: a board with gyro and GPS is a TeleMega (the one AltOS board with
    both); the serial from the ``serial`` column, else from AltOS's file name."""
    serial = None
    if "serial" in index:
        serial = _cells(table, index["serial"])[0] or None
    if serial is None:
        m = _SERIAL.search(str(path))
        serial = m.group(1) if m else None
    return "TeleMega" + (f" serial {serial}" if serial else "")


def _repeats(values: np.ndarray) -> np.ndarray:
    """Rows equal in every column to the row before them."""
    same = np.zeros(values.shape[0], dtype=bool)
    same[1:] = np.all(values[1:] == values[:-1], axis=1)
    return same


def _fixes(data: dict, index: dict) -> tuple[np.ndarray, int]:
    """Rows where a new GPS fix appears, and how many new fixes were dropped as unusable.

    A fix is a change of any GPS column (position, altitude and, when exported, ``nsat``,
    the GPS clock and the DOPs) from the row before; the first row counts as one. Kept are
    fixes with a non-zero position, ``locked`` (when exported) and ``nsat >= 4`` (when
    exported). docs/assumptions.md IO3.
    """
    cols = ["latitude", "longitude", "gps_altitude", *[c for c in FIX_COLUMNS if c in index]]
    values = np.column_stack([data[c] for c in cols])
    new = ~_repeats(values)
    usable = (data["latitude"] != 0.0) | (data["longitude"] != 0.0)
    if "locked" in data:
        usable &= data["locked"] > 0
    if "nsat" in data:
        usable &= data["nsat"] >= MIN_SATELLITES
    rows = np.flatnonzero(new & usable)
    return rows, int(np.count_nonzero(new & ~usable))


def _transitions(t: np.ndarray, names: list[str]) -> pd.DataFrame:
    """``t, state`` at the first row of each run of one flight state."""
    start = [0] + [k for k in range(1, len(names)) if names[k] != names[k - 1]]
    return pd.DataFrame({"t": t[start], "state": [names[k] for k in start]})


def read_altos(path, *, imu_max_gap_s: float | None = None,
               gnss_max_gap_s: float | None = None, on_gap: str = "warn",
               check_magnitudes: bool = True, max_rate_rad_s: float | None = None,
               max_accel_m_s2: float = SAMPLE_ACCEL_MAX,
               max_outlier_fraction: float = MAX_OUTLIER_FRACTION,
               require_overlap: bool = True) -> tuple[pd.DataFrame, pd.DataFrame | None]:
    """Read the IMU and GPS records of an Altus Metrum AltOS CSV export.

    Parameters
    ----------
    path : str or Path
        The ``.csv`` export, either header generation (module docstring).
    imu_max_gap_s, gnss_max_gap_s, on_gap, check_magnitudes, max_accel_m_s2, \
max_outlier_fraction, require_overlap
        As in :func:`~navlib.io.read_ulog`. Rows are sparser under drogue and main; their
        times are kept as logged and the gap policy reports the holes.
    max_rate_rad_s : float, optional
        Largest plausible angular-rate norm, rad/s. None: sqrt(3) times the TeleMega gyro
        range (no reading of three axes within range can exceed it).

    Returns
    -------
    imu, gnss : DataFrame
        ``imu``: ``t, f_x, f_y, f_z, w_x, w_y, w_z`` (s, m/s^2, rad/s; body x along, y across,
        z through, docs/assumptions.md IO1); ``t`` is the export's ``time``, s from boost
        detection (negative on the pad). Rows that repeat the previous row's IMU values are
        not new samples and are dropped (IO2). ``gnss``: ``t, x, y, z`` (ECEF, m), one row per
        fix (IO3), height above mean sea level (IO4). ``imu.attrs``: ``source``, ``format``
        (``"altos-version"`` or ``"altos-legacy"``), ``hardware`` (e.g. ``"TeleMega serial
        1257"``), ``range`` (``gyro_rad_s``, ``accel_m_s2`` per axis), ``autopilot``
        (``"altos"``), ``body_frame`` (``"along-across-through"``), ``attitude`` (None),
        ``flight_states`` (``t, state`` at each change of the logger's state, or None in the
        older export), ``tilt`` (``t, tilt``: angle of body x from vertical, rad), ``baro``
        (``t, alt_m``: barometric altitude, m above mean sea level), ``high_g`` (``t, f_x``:
        the high-g accelerometer along body x, the export's ``acceleration``, m/s^2 with its
        pad reading removed; it stands in for clipped ``f_x`` samples, assumption Q1),
        ``repeated_rows``,
        ``gaps``, ``outliers``. ``gnss.attrs``: ``source``, ``altitude_reference``
        (``"msl"``), ``dropped_no_fix``, ``gaps``. ``gnss`` is None for an export without
        GPS columns but with the barometric ``altitude`` (EasyMega): the barometer aids it.

    Raises
    ------
    NavlibInputError
        Missing, empty, binary or foreign file; a header of neither generation; no gyro
        (TeleMetrum) columns; neither GPS nor barometer columns; rows with a wrong number of
        fields (a header shorter than every row is read when its missing names are the
        :data:`IMU_BLOCK`, and refused with that diagnosis otherwise), non-numeric or
        non-finite cells, repeated or decreasing times with different values, fewer than
        two fixes, implausible magnitudes or positions, non-overlapping spans (naming column
        and line).
    """
    limits = reader_limits(on_gap, imu_max_gap_s, gnss_max_gap_s, max_rate_rad_s,
                           max_accel_m_s2, max_outlier_fraction)
    _, label = existing_file(path)
    table = read_text_table(path, ",", header_prefix=_HEADER_PREFIX,
                            repair_header=_repair_header)
    index = _layout(table, label)
    src = table.source
    has_gps = all(c in index for c in ("latitude", "longitude", "gps_altitude"))
    wanted = ["time", *ACCEL_COLUMNS, *GYRO_COLUMNS,
              *[c for c in ("latitude", "longitude", "gps_altitude", *FIX_COLUMNS, "locked",
                            "tilt", "baro_altitude", "acceleration") if c in index]]
    cols = {c: Column(c, table.header[index[c]], index[c]) for c in wanted}
    data = parse_columns(table, cols)
    for optional in ("tilt", "baro_altitude", "acceleration"):  # all empty: ignored
        if optional in data and not np.isfinite(data[optional]).any():
            del data[optional], cols[optional]
    check_finite(data, cols, src)

    t_all = data["time"]
    imu_values = np.column_stack([data[c] for c in (*ACCEL_COLUMNS, *GYRO_COLUMNS)])
    keep = ~_repeats(imu_values)
    rows = np.flatnonzero(keep)
    imu_src = Source(src.label, src.lines[rows], [src.raw[k] for k in rows], src.sep)
    t = t_all[rows]
    f_b = imu_values[rows, :3]
    w_ib_b = imu_values[rows, 3:] * units.DEG
    mag_note = dead_magnetometer(_magnetometer(table, index, rows), MAG_LABELS)
    check_imu_alive(f_b, w_ib_b, imu_src, "'accel_x'/'accel_y'/'accel_z'",
                    "'gyro_roll'/'gyro_pitch'/'gyro_yaw'", also=mag_note)
    if mag_note:
        warnings.warn(f"{label}: {mag_note[2:].replace(': the IMU looks unpowered', '')}: a "
                      "dead magnetometer (navlib does not use it)", FlightDataWarning,
                      stacklevel=2)

    hardware = _hardware(table, index, path)
    sensor_range = dict(TELEMEGA_RANGE)  # _layout accepts gyro + GPS boards only: TeleMega
    if limits["max_rate_rad_s"] is None:
        limits["max_rate_rad_s"] = float(np.sqrt(3.0) * sensor_range["gyro_rad_s"])
    imu, imu_src = validated_imu(
        t, f_b, w_ib_b, imu_src, "'time'", "'accel_x/accel_y/accel_z'",
        "'gyro_roll/gyro_pitch/gyro_yaw'", check_magnitudes=check_magnitudes, limits=limits,
        rate_hint="; AltOS logs gyro_roll/pitch/yaw in deg/s (converted here)")
    kept_rows = rows[np.isin(t, imu["t"].to_numpy())]
    states = None
    if "state_name" in index:
        states = _transitions(t_all, _cells(table, index["state_name"]))
    extras = {"tilt": None, "baro": None, "high_g": None}
    if "tilt" in data:
        extras["tilt"] = pd.DataFrame({"t": t_all[kept_rows],
                                       "tilt": data["tilt"][kept_rows] * units.DEG})
    if "baro_altitude" in data:
        extras["baro"] = pd.DataFrame({"t": t_all[kept_rows],
                                       "alt_m": data["baro_altitude"][kept_rows]})
    if "acceleration" in data:
        extras["high_g"] = pd.DataFrame({"t": t_all[kept_rows],
                                         "f_x": data["acceleration"][kept_rows]})
    imu.attrs.update(source=str(path),
                     format="altos-version" if "version" in index else "altos-legacy",
                     hardware=hardware, range=sensor_range, autopilot="altos",
                     body_frame="along-across-through", attitude=None, flight_states=states,
                     repeated_rows=int(t_all.size - rows.size), **extras)
    imu = apply_gap_policy(imu, imu_src, "'time'", imu_max_gap_s, on_gap)
    if not has_gps:                 # EasyMega: aided by its barometer (assumptions B1-B5)
        return imu, None

    fix_rows, dropped = _fixes(data, index)
    gps_src = Source(f"{label} (GPS fixes)", src.lines[fix_rows], [src.raw[k] for k in fix_rows],
                     src.sep)
    if fix_rows.size < 2:
        raise gps_src.error("'latitude/longitude/altitude'", None,
                            f"need at least 2 GPS fixes, found {fix_rows.size} ({dropped} "
                            f"more without a position, lock or {MIN_SATELLITES} satellites)")
    t_gps = t_all[fix_rows]
    check_times(t_gps, gps_src, "'time'")
    check_sample_interval(t_gps, gps_src, "'time'", "gnss", 1.0)
    lat = units.deg2rad(data["latitude"][fix_rows])
    lon = units.deg2rad(data["longitude"][fix_rows])
    r_e = geodetic_to_ecef(lat, lon, data["gps_altitude"][fix_rows])
    if check_magnitudes:
        check_positions(r_e, gps_src, "'latitude/longitude/altitude'")
    gnss = pd.DataFrame({"t": t_gps, "x": r_e[:, 0], "y": r_e[:, 1], "z": r_e[:, 2]})
    gnss.attrs.update(source=str(path), altitude_reference="msl", dropped_no_fix=dropped)
    gnss = apply_gap_policy(gnss, gps_src, "'time'", gnss_max_gap_s, on_gap)
    if require_overlap:
        check_overlap(imu, gnss)
    return imu, gnss
