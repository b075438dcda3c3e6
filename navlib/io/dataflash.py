"""ArduPilot DataFlash (``.bin``) import through ``pymavlink``: IMU, GPS and ATT messages.

A DataFlash log is a stream of self-describing binary records: ``FMT`` records declare each
message type (name, field formats, column names), data records follow.
:func:`read_dataflash` reads them with ``pymavlink.DFReader.DFReader_binary``.

Messages and layouts
--------------------
* ``IMU``: ``TimeUS`` (us since boot), ``GyrX/Y/Z`` (rad/s), ``AccX/Y/Z`` (m/s^2, specific
  force), body frame FRD (x forward, y right, z down). ArduPilot 4.x logs every IMU as
  ``IMU`` with an instance column ``I``; 3.x logs use ``IMU``, ``IMU2``, ``IMU3`` without
  one. Both are read; ``imu_instance`` picks one (default: the instance with most samples,
  the lowest on a tie).
* ``GPS``: ``Status`` (3: 3-D fix and better, kept from ``min_fix_type``), ``Lat``/``Lng``
  (deg), ``Alt`` (m above mean sea level: DataFlash logs no ellipsoidal height, so the
  positions are off by the geoid undulation, up to ~100 m; a constant offset the
  assessment does not depend on; docs/assumptions.md IO4), ``Spd`` (ground speed, m/s),
  ``GCrs`` (course over ground, deg), ``VZ`` (vertical speed, m/s, down positive), giving
  the NED velocity ``(Spd cos GCrs, Spd sin GCrs, VZ)``. Layouts: ``GPS`` with ``I`` (4.x)
  or ``GPS``/``GPS2``.
* ``ATT``: ``Roll``, ``Pitch``, ``Yaw`` (deg), the autopilot's attitude estimate, body (FRD)
  to NED as ``Rz(yaw) Ry(pitch) Rx(roll)``; attached as ``imu.attrs["attitude"]``, from
  which the flight fit takes its initial attitude.
* ``BARO`` ``Alt`` (m above the barometer's ground calibration), or in older logs ``CTUN``
  ``BarAlt``: attached as ``imu.attrs["baro"]`` (``t, alt_m``) so GNSS heights can be
  compared with it (docs/assumptions.md IO6).

Time stamps: logs from about 2015 on stamp every record with ``TimeUS`` (us since boot).
Older logs (ArduCopter/ArduPlane 3.1-3.3) use ``TimeMS`` (ms since boot), and their ``GPS``
carries its own clocks: ``T`` (ms since boot) beside ``TimeMS``/``Week`` (GPS time of week),
or ``TimeMS`` (boot) beside ``GMS``/``GWk``. Both generations are read on the boot clock
(:func:`_boot_time_us`, docs/assumptions.md IO5).

The body frame is FRD by default, as in :mod:`navlib.io.ulog` (``body_frame`` changes it).
"""

from __future__ import annotations

import contextlib
import io
import warnings

import numpy as np
import pandas as pd
from pymavlink import DFReader
from scipy.spatial.transform import Rotation

from navlib import units
from navlib.earth import geodetic_to_ecef, ned_to_ecef_matrix
from navlib.errors import NavlibInputError
from navlib.io._table import Column, Source, check_finite, existing_file
from navlib.io.checks import (
    MAX_OUTLIER_FRACTION,
    RATE_MAX_RAD_S,
    SAMPLE_ACCEL_MAX,
    FlightDataWarning,
    apply_gap_policy,
    check_overlap,
    check_positions,
    check_sample_interval,
    check_times,
    check_velocities,
    reader_limits,
    validated_imu,
)
from navlib.io.csv_files import R_KEYS, V_KEYS
from navlib.io.ulog import body_rotation

__all__ = ["read_dataflash"]

_IMU_FIELDS = ("GyrX", "GyrY", "GyrZ", "AccX", "AccY", "AccZ")
_GPS_FIELDS = ("Lat", "Lng", "Alt")
_TYPES = ("IMU", "IMU2", "IMU3", "GPS", "GPS2", "ATT", "BARO", "CTUN", "MSG")
_VEHICLES = ("ArduCopter", "ArduPlane", "ArduRover", "ArduSub", "Blimp", "AntennaTracker",
             "APM:")
_TIME = "_t_us"
"""Key of the boot time stamp (us) every record gets from its generation's time field."""


_TIME_FIELD = "_t_field"
"""Key of the name of the field the boot time came from (for messages)."""


def _boot_time_us(kind: str, data: dict) -> tuple[str, np.ndarray | None] | None:
    """Boot time (us) of one message type's records and the field it comes from.

    ``TimeUS`` (us; logs from about 2015 on). Older logs: ``TimeMS`` (ms since boot), except
    in ``GPS``, where ``T`` (ms since boot) is the boot time when logged, and a ``TimeMS``
    beside ``Week`` is the GPS time of week, not a boot time (``GMS``/``GWk`` logs keep
    ``TimeMS`` as boot time). None when no boot time is logged; ``(field, None)`` when the
    field does not hold finite numbers (a damaged format).
    """
    if "TimeUS" in data:
        name, scale = "TimeUS", 1
    elif kind == "GPS" and "T" in data:
        name, scale = "T", 1000
    elif "TimeMS" in data and not (kind == "GPS" and "Week" in data):
        name, scale = "TimeMS", 1000
    else:
        return None
    raw = data[name]
    if raw.dtype.kind not in "iuf" or not np.all(np.isfinite(raw)):
        return name, None
    return name, raw.astype(np.int64) * scale


def _numbers(values: list) -> np.ndarray:
    """The values of one field as a numeric array when they all are numbers, else as given."""
    arr = np.array(values)
    if arr.dtype.kind in "iufb":
        return arr
    try:
        return arr.astype(float)
    except (TypeError, ValueError):
        return arr


def _numeric(data: dict, fields) -> bool:
    return all(data[f].dtype.kind in "iufb" for f in fields)


class _NoProgress(Exception):
    """pymavlink's parser returned a message without moving past it."""


class _GuardedReader(DFReader.DFReader_binary):
    """``DFReader_binary`` that refuses to return a message without advancing (a damaged FMT
    declaring a record length of 0 makes pymavlink parse the same bytes forever) and indexes
    the log in Python: pymavlink's compiled indexer prints a line per damaged byte straight
    to the process's stderr, past any redirection (thousands of ``bad header`` lines on the
    terminal for one damaged block); the Python indexer prints through ``sys.stderr``,
    which :func:`_load` catches (measured: both public ArduPilot logs read in 9.4 s instead
    of 7.6 s)."""

    def init_arrays_fast(self, progress_callback=None):
        self.init_arrays(progress_callback=progress_callback)

    def _parse_next(self):
        start = self.offset
        message = super()._parse_next()
        if message is not None and self.offset <= start:
            raise _NoProgress(f"the record at byte {start} has a length that does not "
                              f"move the parser forward (a damaged FMT record?)")
        return message


def _load(path) -> dict[str, dict]:
    """Columns of the messages of interest: ``{(type, instance): {field: ndarray}}``."""

    p, label = existing_file(path)
    if p.stat().st_size == 0:
        raise NavlibInputError(f"{label}: file is empty")
    rows: dict = {}
    messages = []
    sink = io.StringIO()
    log = None
    try:
        # pymavlink prints notices on odd bytes; a library must not print, so catch them
        with contextlib.redirect_stdout(sink), contextlib.redirect_stderr(sink):
            log = _GuardedReader(str(p))
            while True:
                m = log.recv_match(type=list(_TYPES))
                if m is None:
                    break
                kind = m.get_type()
                data = m.to_dict()
                if kind == "MSG":
                    messages.append(str(data.get("Message", "")))
                    continue
                base = kind.rstrip("23")
                inst = int(data["I"]) if "I" in data else (int(kind[-1]) - 1 if kind[-1] in "23"
                                                            else 0)
                rows.setdefault((base, inst), []).append(data)
    except Exception as exc:  # pymavlink raises several types on foreign or broken files
        raise NavlibInputError(f"{label}: not a readable ArduPilot DataFlash log ({exc})"
                               ) from exc
    finally:
        if log is not None:
            log.close()
    notices = sink.getvalue()
    if "Skipped" in notices or "bad header" in notices:
        bad = notices.count("bad header")
        where = f" ({bad} byte(s) without a record header)" if bad else ""
        warnings.warn(f"{label}: pymavlink skipped bad bytes{where}; data may be incomplete",
                      FlightDataWarning, stacklevel=3)
    columns = {key: {f: _numbers([r.get(f, np.nan) for r in rs]) for f in rs[0]}
               for key, rs in rows.items()}
    for (kind, _), data in columns.items():
        stamp = _boot_time_us(kind, data)
        if stamp is not None:
            data[_TIME_FIELD] = stamp[0]
            if stamp[1] is not None:
                data[_TIME] = stamp[1]
    return columns, messages, label


def _pick(columns, kind: str, instance, label: str, fields, found_types,
          optional=()) -> tuple[int, dict]:
    """One instance of a message type with its time and ``fields`` (and the ``optional``
    fields it has) numeric; NavlibInputError naming what is missing or not a number."""
    candidates = {inst: c for (k, inst), c in columns.items() if k == kind}
    if not candidates:
        raise NavlibInputError(f"{label}: no '{kind}' messages in the log; message types of "
                               f"interest found: {found_types}")
    if instance is None:
        instance = max(sorted(candidates), key=lambda i: candidates[i]["mavpackettype"].size)
    elif instance not in candidates:
        raise NavlibInputError(f"{label}: no '{kind}' instance {instance}; instances are "
                               f"{sorted(candidates)}")
    data = candidates[instance]
    logged = sorted(f for f in data if not f.startswith(("_", "mavpackettype")))
    where = f"{label}, message '{kind}' instance {instance}"
    if _TIME_FIELD not in data:
        raise NavlibInputError(f"{where}: no time field (TimeUS, or TimeMS in logs before "
                               f"2015, or T in their GPS); fields are {logged}")
    if _TIME not in data:
        raise NavlibInputError(f"{where}: time field '{data[_TIME_FIELD]}' does not hold "
                               f"finite numbers (a damaged format definition?)")
    missing = [f for f in fields if f not in data]
    if missing:
        raise NavlibInputError(f"{where}: missing field(s) {missing}; fields are {logged}")
    odd = [f for f in (*fields, *optional) if f in data and not _numeric(data, (f,))]
    if odd:
        raise NavlibInputError(f"{where}: field(s) {odd} do not hold numbers (a damaged "
                               f"format definition?)")
    return instance, data


def _hardware(messages) -> str:
    for text in messages:
        if text.startswith(_VEHICLES):
            return text
    return ""


def read_dataflash(path, *, body_frame="frd", imu_instance: int | None = None,
                   gps_instance: int | None = None, min_fix_type: int = 3,
                   imu_max_gap_s: float | None = None, gnss_max_gap_s: float | None = None,
                   on_gap: str = "warn", check_magnitudes: bool = True,
                   max_rate_rad_s: float = RATE_MAX_RAD_S,
                   max_accel_m_s2: float = SAMPLE_ACCEL_MAX,
                   max_outlier_fraction: float = MAX_OUTLIER_FRACTION,
                   require_overlap: bool = True) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Read the IMU and GNSS records of an ArduPilot DataFlash log (via ``pymavlink``).

    Parameters
    ----------
    path : str or Path
        The ``.bin`` file.
    body_frame : {"frd", "flu"} or (3, 3) array
        The navlib body frame relative to ArduPilot's FRD axes, as ``C_b_frd``
        (:func:`navlib.io.ulog.body_rotation`).
    imu_instance, gps_instance : int, optional
        IMU / GPS instance (0-based: ``I`` column, or ``IMU2`` = 1). None: the instance with
        most messages.
    min_fix_type : int
        Smallest accepted GPS ``Status`` (3: 3-D fix); other fixes are dropped.
    imu_max_gap_s, gnss_max_gap_s, on_gap, check_magnitudes, max_rate_rad_s, \
max_accel_m_s2, max_outlier_fraction, require_overlap
        As in :func:`~navlib.io.read_ulog`.

    Returns
    -------
    imu, gnss : DataFrame
        The columns of :func:`~navlib.io.read_ulog` (``gnss``: ``t, x, y, z, vx, vy, vz``;
        ``t`` in s from the earlier of the first IMU and first kept GPS ``TimeUS``, which is
        ``attrs["t0_us"]``). ``imu.attrs``: ``source``, ``message``, ``instance``,
        ``body_frame``, ``gaps``, ``outliers``, ``autopilot`` (``"ardupilot"``),
        ``hardware`` (the firmware banner, e.g. ``ArduCopter V4.5.0`` or ``APM:Copter
        V3.3``), ``attitude`` (``ATT`` as ``t, qw, qx, qy, qz``, navlib body -> NED, or
        None), ``baro`` (``t, alt_m``, or None), ``time_field`` (``"TimeUS"`` or
        ``"TimeMS"``: the log's generation). ``gnss.attrs``: ``source``,
        ``instance``, ``altitude_reference`` (``"msl"``), ``dropped_no_fix``, ``gaps``.

    Raises
    ------
    NavlibInputError
        Missing, empty or foreign file (also a damaged one on which pymavlink would stop
        advancing); no IMU or GPS messages, a missing or non-numeric field; no fix;
        NaN/inf values, duplicate or decreasing time stamps, gaps with ``on_gap="raise"``,
        implausible magnitudes, non-overlapping IMU and GNSS spans (naming message, field
        and message index).
    """
    limits = reader_limits(on_gap, imu_max_gap_s, gnss_max_gap_s, max_rate_rad_s,
                           max_accel_m_s2, max_outlier_fraction)
    C_b_frd = body_rotation(body_frame)
    columns, messages, label = _load(path)
    found = sorted({k for k, _ in columns})
    i_imu, d_imu = _pick(columns, "IMU", imu_instance, label, _IMU_FIELDS, found)
    i_gps, d_gps = _pick(columns, "GPS", gps_instance, label, _GPS_FIELDS, found,
                         optional=("Status", "Spd", "GCrs", "VZ"))

    status = d_gps.get("Status", np.full(d_gps[_TIME].size, 3))
    idx = np.flatnonzero(status >= min_fix_type)
    if idx.size < 2:
        raise NavlibInputError(f"{label}: no usable GPS data (message 'GPS' instance {i_gps}: "
                               f"{status.size} messages, {idx.size} with Status >= "
                               f"{min_fix_type}); need at least 2 fixes")
    ts_imu = d_imu[_TIME]
    ts_gps = d_gps[_TIME][idx]
    t0 = int(min(ts_imu[0], ts_gps[0]))

    imu_label = f"{label}, message 'IMU' instance {i_imu}"
    imu_time = repr(d_imu[_TIME_FIELD])
    src = Source(imu_label, np.arange(ts_imu.size), row_word="message")
    raw = {k: d_imu[k].astype(float) for k in _IMU_FIELDS}
    check_finite(raw, {k: Column(k, k, None) for k in raw}, src)
    f_b = np.column_stack([raw[k] for k in _IMU_FIELDS[3:]]) @ C_b_frd.T
    w_ib_b = np.column_stack([raw[k] for k in _IMU_FIELDS[:3]]) @ C_b_frd.T
    imu, src = validated_imu(
        (ts_imu - t0) * units.MICROSECOND, f_b, w_ib_b, src, imu_time, "'AccX/AccY/AccZ'",
        "'GyrX/GyrY/GyrZ'", check_magnitudes=check_magnitudes, limits=limits,
        rate_hint="; ArduPilot logs GyrX/Y/Z in rad/s, so a vehicle this fast needs a larger "
                  "max_rate_rad_s (or check_magnitudes=False)")
    imu.attrs.update(source=str(path), message="IMU", instance=i_imu, t0_us=t0,
                     body_frame=body_frame if isinstance(body_frame, str) else "custom",
                     autopilot="ardupilot", hardware=_hardware(messages),
                     attitude=_attitude(columns, t0, C_b_frd), baro=_baro(columns, t0),
                     time_field=d_imu[_TIME_FIELD])
    imu = apply_gap_policy(imu, src, imu_time, imu_max_gap_s, on_gap)

    gps_time = repr(d_gps[_TIME_FIELD])
    gnss, src_gps = _gnss_frame(d_gps, f"{label}, message 'GPS' instance {i_gps}", idx,
                                (ts_gps - t0) * units.MICROSECOND, check_magnitudes, gps_time)
    gnss.attrs.update(source=str(path), instance=i_gps, t0_us=t0, altitude_reference="msl",
                      dropped_no_fix=int(status.size - idx.size))
    gnss = apply_gap_policy(gnss, src_gps, gps_time, gnss_max_gap_s, on_gap)
    if require_overlap:
        check_overlap(imu, gnss)
    return imu, gnss


def _gnss_frame(d, label, idx, t, check_magnitudes, time_label):
    src = Source(label, idx, row_word="message")
    lat, lon, alt = (d[k][idx].astype(float) for k in _GPS_FIELDS)
    check_finite({"Lat": lat, "Lng": lon, "Alt": alt},
                 {k: Column(k, k, None) for k in _GPS_FIELDS}, src)
    check_times(t, src, time_label)
    check_sample_interval(t, src, time_label, "gnss", 1.0)
    lat, lon = units.deg2rad(lat), units.deg2rad(lon)
    r_e = geodetic_to_ecef(lat, lon, alt)
    if check_magnitudes:
        check_positions(r_e, src, "'Lat/Lng/Alt'")
    out = {"t": t, **dict(zip(R_KEYS, r_e.T, strict=True))}
    if all(k in d for k in ("Spd", "GCrs", "VZ")):
        spd, crs, vz = (d[k][idx].astype(float) for k in ("Spd", "GCrs", "VZ"))
        check_finite({"Spd": spd, "GCrs": crs, "VZ": vz},
                     {k: Column(k, k, None) for k in ("Spd", "GCrs", "VZ")}, src)
        crs = units.deg2rad(crs)
        v_n = np.column_stack([spd * np.cos(crs), spd * np.sin(crs), vz])
        v_e = np.einsum("kij,kj->ki", ned_to_ecef_matrix(lat, lon), v_n)
        if check_magnitudes:
            check_velocities(v_e, src, "'Spd/GCrs/VZ'")
        out.update(zip(V_KEYS, v_e.T, strict=True))
    return pd.DataFrame(out), src


def _attitude(columns, t0: int, C_b_frd: np.ndarray) -> pd.DataFrame | None:
    """``ATT`` Roll/Pitch/Yaw (deg, FRD -> NED) as navlib body -> NED quaternions."""
    data = columns.get(("ATT", 0))
    fields = ("Roll", "Pitch", "Yaw")
    if data is None or not all(k in data for k in (_TIME, *fields)) or not _numeric(data,
                                                                                    fields):
        return None
    angles = np.column_stack([data[k].astype(float) for k in ("Yaw", "Pitch", "Roll")])
    ok = np.all(np.isfinite(angles), axis=1)
    if not ok.any():
        return None
    C_b_n = (Rotation.from_euler("ZYX", angles[ok], degrees=True)
             * Rotation.from_matrix(C_b_frd.T))
    x, y, z, w = C_b_n.as_quat().T
    t = (data[_TIME][ok] - t0) * units.MICROSECOND
    return pd.DataFrame({"t": t, "qw": w, "qx": x, "qy": y, "qz": z})


def _baro(columns, t0: int) -> pd.DataFrame | None:
    """Barometric altitude as ``t, alt_m``: ``BARO`` ``Alt`` (instance 0), else ``CTUN``
    ``BarAlt`` (older logs); m above the barometer's ground calibration, so only its changes
    compare with GNSS heights. None when neither is logged with finite values."""
    for kind, field in (("BARO", "Alt"), ("CTUN", "BarAlt")):
        data = columns.get((kind, 0))
        if (data is None or _TIME not in data or field not in data
                or not _numeric(data, (field,))):
            continue
        alt = data[field].astype(float)
        ok = np.isfinite(alt)
        if ok.any():
            return pd.DataFrame({"t": (data[_TIME][ok] - t0) * units.MICROSECOND,
                                 "alt_m": alt[ok]})
    return None
