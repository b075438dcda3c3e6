"""PX4 ULog import through ``pyulog``: IMU from ``sensor_combined``, GNSS from the GPS topic.

Body frame
----------
PX4 logs ``sensor_combined.gyro_rad`` (rad/s) and ``accelerometer_m_s2`` (m/s^2, specific
force: about ``(0, 0, -9.8)`` when level at rest) in the vehicle's **FRD** body frame
(x forward, y right, z down), a right-handed frame. navlib's body frame ``b`` is any
right-handed frame fixed to the vehicle, the one whose orientation ``C_b_e`` a trajectory
carries, so by default it *is* FRD and the mapping is the identity: ``f_b = C_b_frd f_frd``
with ``C_b_frd = I``. ``body_frame="flu"`` (x forward, y left, z up) or any 3x3 proper
rotation matrix ``C_b_frd`` changes that choice; reflections are refused (they would make
the body frame left-handed and the kinematics wrong).

GPS topics and PX4 versions
---------------------------
Older logs have ``vehicle_gps_position`` with ``lat``/``lon`` (int, 1e-7 deg), ``alt``
(int mm, above mean sea level) and ``alt_ellipsoid`` (int mm); newer ones have
``vehicle_gps_position`` and/or ``sensor_gps`` with ``latitude_deg``, ``longitude_deg``,
``altitude_msl_m``, ``altitude_ellipsoid_m`` (float). Both are mapped. Velocities
``vel_n_m_s, vel_e_m_s, vel_d_m_s`` (when ``vel_ned_valid``) are rotated to ECEF, and
``eph``/``epv`` become ``sigma`` (:func:`navlib.io.csv_files.combine_sigma`). Fixes with
``fix_type`` below ``min_fix_type`` (default 3, a 3-D fix) are dropped: before a fix the
receiver reports placeholder positions.
"""

from __future__ import annotations

import contextlib
import io
import warnings

import numpy as np
import pandas as pd
from pyulog import ULog
from scipy.spatial.transform import Rotation

from navlib import units
from navlib._validation import finite_array
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
from navlib.io.csv_files import NED_KEYS, R_KEYS, V_KEYS, combine_sigma

__all__ = ["ATTITUDE_TOPIC", "BARO_TOPIC", "BODY_FRAMES", "GPS_TOPICS", "IMU_TOPIC", "READ_BUDGET",
           "body_rotation", "read_ulog"]

IMU_TOPIC = "sensor_combined"
ATTITUDE_TOPIC = "vehicle_attitude"
BARO_TOPIC = "vehicle_air_data"
GPS_TOPICS = ("vehicle_gps_position", "sensor_gps")
BODY_FRAMES = {"frd": np.eye(3), "flu": np.diag([1.0, -1.0, -1.0])}
"""Named body frames: ``C_b_frd`` taking PX4 FRD axes to the navlib body axes."""
_GYRO = tuple(f"gyro_rad[{i}]" for i in range(3))
_ACCEL = tuple(f"accelerometer_m_s2[{i}]" for i in range(3))
_VEL_NED = ("vel_n_m_s", "vel_e_m_s", "vel_d_m_s")


def body_rotation(body_frame) -> np.ndarray:
    """``C_b_frd`` for a named frame (``"frd"``, ``"flu"``) or a 3x3 proper rotation."""
    if isinstance(body_frame, str):
        key = body_frame.strip().lower()
        if key not in BODY_FRAMES:
            raise NavlibInputError(f"body_frame: expected one of {sorted(BODY_FRAMES)} or a "
                                   f"3x3 rotation matrix C_b_frd, got {body_frame!r}")
        return BODY_FRAMES[key]
    C = finite_array(body_frame, "body_frame", shape=(3, 3))
    if not np.allclose(C @ C.T, np.eye(3), atol=1e-6):
        raise NavlibInputError("body_frame: the matrix C_b_frd is not orthonormal")
    if np.linalg.det(C) < 0:
        raise NavlibInputError("body_frame: the matrix C_b_frd is a reflection (det -1); the "
                               "body frame would be left-handed")
    return C


READ_BUDGET = (16, 2 * 2**20)
"""pyulog may read at most ``16 * file size + 2 MiB`` bytes before the file is refused: on a
message damaged near the end of the file its corruption recovery seeks back and re-reads
forever (a clean log is read about once; recovery from a damaged stretch re-reads it)."""


class _ReadBudgetExceeded(Exception):
    """Not a ValueError: pyulog's recovery swallows those and would go on reading."""


class _BoundedFile(io.BufferedReader):
    """A binary file that raises once more than ``budget`` bytes have been read from it."""

    def __init__(self, path, budget: int):
        super().__init__(io.FileIO(path, "rb"))
        self.budget = budget

    def read(self, size=-1):
        data = super().read(size)
        self.budget -= len(data)
        if self.budget < 0:
            raise _ReadBudgetExceeded("the parser keeps re-reading the same bytes (a damaged "
                                      "message near the end of the file?)")
        return data


def _load(path):
    p, label = existing_file(path)
    size = p.stat().st_size
    if size == 0:
        raise NavlibInputError(f"{label}: file is empty")
    try:
        # pyulog prints corruption notices; a library must not print, so catch them.
        with contextlib.redirect_stdout(io.StringIO()), \
                _BoundedFile(p, READ_BUDGET[0] * size + READ_BUDGET[1]) as handle:
            ulog = ULog(handle, message_name_filter_list=[IMU_TOPIC, ATTITUDE_TOPIC,
                                                          BARO_TOPIC, *GPS_TOPICS])
    except Exception as exc:  # pyulog raises several types on foreign or broken files
        raise NavlibInputError(f"{label}: not a readable PX4 ULog file ({exc})") from exc
    if ulog.file_corruption:
        warnings.warn(f"{label}: pyulog detected file corruption; data may be incomplete",
                      FlightDataWarning, stacklevel=3)
    for d in ulog.data_list:
        if "timestamp" not in d.data:
            raise NavlibInputError(f"{label}, topic '{d.name}': no 'timestamp' field (the "
                                   f"log's format definition of the topic is damaged); fields "
                                   f"are {sorted(d.data)}")
    return ulog, label


def _mav_type(ulog) -> int | None:
    """The log's ``MAV_TYPE`` parameter (the vehicle type, read by
    :func:`navlib.vehicles.vehicle_from_log`), or None when the log has none."""
    value = (getattr(ulog, "initial_parameters", None) or {}).get("MAV_TYPE")
    return None if value is None else int(value)


def _dataset(ulog, name: str, instance: int | None) -> list:
    return [d for d in ulog.data_list
            if d.name == name and (instance is None or d.multi_id == instance)]


def _fields(d, label: str, names) -> None:
    missing = [n for n in names if n not in d.data]
    if missing:
        raise NavlibInputError(f"{label}, topic '{d.name}': missing field(s) {missing}; "
                               f"fields are {sorted(d.data)}")


def _gps_timestamps(d, keep: np.ndarray) -> np.ndarray:
    """``timestamp_sample`` (time of the measurement) when logged, else ``timestamp``."""
    ts = d.data["timestamp"].astype(np.int64)
    if "timestamp_sample" in d.data:
        sample = d.data["timestamp_sample"].astype(np.int64)
        if np.all(sample[keep] > 0):
            return sample
    return ts


def _gps_candidate(d, min_fix_type: int):
    """Rows with a good enough fix and the resulting rate (Hz) of one GPS dataset."""
    n = len(d.data["timestamp"])
    keep = np.ones(n, dtype=bool)
    if "fix_type" in d.data:
        keep &= d.data["fix_type"] >= min_fix_type
    idx = np.flatnonzero(keep)
    if idx.size < 2:
        return idx, 0.0
    ts = _gps_timestamps(d, keep)[idx]
    span = (ts[-1] - ts[0]) * units.MICROSECOND
    return idx, (idx.size - 1) / span if span > 0 else 0.0


def _geodetic(d, label: str, idx: np.ndarray, altitude: str):
    """Latitude, longitude (rad), height (m) and the height reference, both field names."""
    data = d.data
    if "latitude_deg" in data:
        _fields(d, label, ("longitude_deg",))
        lat = units.deg2rad(data["latitude_deg"][idx])
        lon = units.deg2rad(data["longitude_deg"][idx])
        ell = data.get("altitude_ellipsoid_m")
        msl = data.get("altitude_msl_m")
        scale = 1.0
    elif "lat" in data:
        _fields(d, label, ("lon",))
        lat = data["lat"][idx].astype(float) * units.DEG_E7
        lon = data["lon"][idx].astype(float) * units.DEG_E7
        ell = data.get("alt_ellipsoid")
        msl = data.get("alt")
        scale = units.MILLIMETRE
    else:
        raise NavlibInputError(f"{label}, topic '{d.name}': no latitude field (expected "
                               f"'lat' or 'latitude_deg'); fields are {sorted(data)}")
    ell = None if ell is None or not np.any(ell[idx]) else ell[idx].astype(float) * scale
    msl = None if msl is None else msl[idx].astype(float) * scale
    if altitude == "ellipsoid" and ell is not None:
        return lat, lon, ell, "ellipsoid"
    if msl is None:
        raise NavlibInputError(f"{label}, topic '{d.name}': no altitude field")
    if altitude == "ellipsoid":
        warnings.warn(f"{label}, topic '{d.name}': no ellipsoidal height logged; using the "
                      f"height above mean sea level (off by the geoid undulation, up to "
                      f"~100 m)", FlightDataWarning, stacklevel=4)
    return lat, lon, msl, "msl"


def read_ulog(path, *, body_frame="frd", gps_topic: str | None = None,
              gps_instance: int | None = None, min_fix_type: int = 3,
              altitude: str = "ellipsoid", imu_max_gap_s: float | None = None,
              gnss_max_gap_s: float | None = None, on_gap: str = "warn",
              check_magnitudes: bool = True, max_rate_rad_s: float = RATE_MAX_RAD_S,
              max_accel_m_s2: float = SAMPLE_ACCEL_MAX,
              max_outlier_fraction: float = MAX_OUTLIER_FRACTION,
              require_overlap: bool = True) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Read the IMU and GNSS records of a PX4 ULog file (via ``pyulog``).

    Parameters
    ----------
    path : str or Path
        The ``.ulg`` file.
    body_frame : {"frd", "flu"} or (3, 3) array
        The navlib body frame relative to PX4's FRD axes, as ``C_b_frd`` (module docstring).
        Default ``"frd"``: identity, navlib's body frame is PX4's.
    gps_topic : {"vehicle_gps_position", "sensor_gps"}, optional
        Force a GPS topic. None: of all instances of both topics holding at least two fixes,
        the one with the highest fix rate.
    gps_instance : int, optional
        Force a topic instance (``multi_id``).
    min_fix_type : int
        Smallest accepted ``fix_type`` (3: 3-D fix); rows below are dropped.
    altitude : {"ellipsoid", "msl"}
        Height used for ECEF positions. ``"ellipsoid"`` falls back to MSL, with a
        :class:`~navlib.io.FlightDataWarning`, when the log has no ellipsoidal height.
    imu_max_gap_s, gnss_max_gap_s : float, optional
        Longest accepted interval in each record, s; None: 10 median intervals.
    on_gap, check_magnitudes, max_rate_rad_s, max_accel_m_s2, max_outlier_fraction
        As in :func:`~navlib.io.read_imu_csv` (gaps: both records; non-physical samples are
        excluded from the IMU and listed in ``attrs["outliers"]``).
    require_overlap : bool
        Raise when the IMU and GNSS time spans do not overlap (:func:`check_overlap`).

    Returns
    -------
    imu, gnss : DataFrame
        The columns of :func:`~navlib.io.read_imu_csv` and :func:`~navlib.io.read_gnss_csv`
        (``gnss`` has ``vx, vy, vz`` and ``sigma`` when logged). Both ``t`` are in s from a
        common origin, the earlier of the first IMU and first kept GNSS time stamps; that
        origin, in PX4 boot-time microseconds, is ``attrs["t0_us"]``. Other ``attrs``:
        ``source``, ``topic``, ``body_frame`` / ``altitude_reference``, ``dropped_no_fix``,
        ``gaps``, ``outliers``, ``autopilot`` (``"px4"``), ``hardware`` (the log's
        ``ver_hw``), ``attitude`` (the autopilot's ``vehicle_attitude`` as ``t, qw, qx, qy,
        qz``, navlib body -> NED, or None; the flight fit starts from it), ``baro``
        (``vehicle_air_data.baro_alt_meter`` as ``t, alt_m``, the barometric altitude above
        mean sea level from the standard atmosphere, or None; docs/assumptions.md IO6), and
        ``clipping``
        (samples flagged by PX4's ``accelerometer_clipping`` /
        ``gyro_clipping``; any flag also warns) and ``mav_type`` (the ``MAV_TYPE``
        parameter, the vehicle type, or None). The IMU sample time is
        ``sensor_combined.timestamp`` (PX4 integrates the accelerometer over the gyro
        interval; ``accelerometer_timestamp_relative`` is not applied).

    Raises
    ------
    NavlibInputError
        Missing, empty or non-ULog file (also a damaged one on which pyulog would re-read
        without end: :data:`READ_BUDGET`); missing topic or field; no GPS fix; NaN/inf values,
        duplicate or decreasing time stamps, gaps with ``on_gap="raise"``, implausible
        magnitudes, non-overlapping IMU and GNSS spans (all naming topic, field, message).
    """
    limits = reader_limits(on_gap, imu_max_gap_s, gnss_max_gap_s, max_rate_rad_s,
                           max_accel_m_s2, max_outlier_fraction)
    if altitude not in ("ellipsoid", "msl"):
        raise NavlibInputError(f"altitude: expected 'ellipsoid' or 'msl', got {altitude!r}")
    if gps_topic is not None and gps_topic not in GPS_TOPICS:
        raise NavlibInputError(f"gps_topic: expected one of {list(GPS_TOPICS)} or None, got "
                               f"{gps_topic!r}")
    C_b_frd = body_rotation(body_frame)
    ulog, label = _load(path)
    topics = sorted({d.name for d in ulog.data_list})

    imu_sets = _dataset(ulog, IMU_TOPIC, None)
    if not imu_sets:
        raise NavlibInputError(f"{label}: no '{IMU_TOPIC}' topic (IMU) in the log; logged "
                               f"topics of interest: {topics}")
    d_imu = max(imu_sets, key=lambda d: len(d.data["timestamp"]))
    _fields(d_imu, label, (*_GYRO, *_ACCEL))

    candidates = []
    for name in (gps_topic,) if gps_topic else GPS_TOPICS:
        for d in _dataset(ulog, name, gps_instance):
            idx, rate = _gps_candidate(d, min_fix_type)
            candidates.append((rate, -GPS_TOPICS.index(d.name), d, idx))
    usable = [c for c in candidates if c[3].size >= 2]
    if not usable:
        found = ", ".join(f"{d.name}[{d.multi_id}]: {len(d.data['timestamp'])} messages, "
                          f"{idx.size} with fix_type >= {min_fix_type}"
                          for _, _, d, idx in candidates) or "no GPS topic"
        raise NavlibInputError(f"{label}: no usable GPS data ({found}); need at least 2 fixes "
                               f"in {list(GPS_TOPICS) if gps_topic is None else [gps_topic]}")
    _, _, d_gps, idx = max(usable, key=lambda c: (c[0], c[1]))

    ts_imu = d_imu.data["timestamp"].astype(np.int64)
    ts_gps = _gps_timestamps(d_gps, idx)[idx]
    t0 = int(min(ts_imu[0], ts_gps[0]))

    imu, src_imu = _imu_frame(d_imu, label, ts_imu, t0, C_b_frd, check_magnitudes, limits)
    info = getattr(ulog, "msg_info_dict", {}) or {}
    imu.attrs.update(source=str(path), topic=IMU_TOPIC, t0_us=t0,
                     body_frame=body_frame if isinstance(body_frame, str) else "custom",
                     autopilot="px4", hardware=str(info.get("ver_hw", "")),
                     mav_type=_mav_type(ulog),
                     attitude=_attitude(ulog, t0, C_b_frd), baro=_baro(ulog, t0))
    imu = apply_gap_policy(imu, src_imu, "'timestamp'", imu_max_gap_s, on_gap)

    gnss, src_gps = _gnss_frame(d_gps, label, idx, ts_gps, t0, altitude, check_magnitudes)
    gnss.attrs.update(source=str(path), t0_us=t0,
                      dropped_no_fix=int(len(d_gps.data["timestamp"]) - idx.size))
    gnss = apply_gap_policy(gnss, src_gps, "'timestamp'", gnss_max_gap_s, on_gap)
    if require_overlap:
        check_overlap(imu, gnss)
    return imu, gnss


def _attitude(ulog, t0: int, C_b_frd: np.ndarray) -> pd.DataFrame | None:
    """The autopilot's attitude estimate (``vehicle_attitude.q``, FRD -> NED, scalar first)
    as ``t, qw, qx, qy, qz`` of the navlib body frame -> NED, or None when not logged."""
    sets = [d for d in _dataset(ulog, ATTITUDE_TOPIC, None)
            if all(f"q[{i}]" in d.data for i in range(4))]
    if not sets:
        return None
    d = max(sets, key=lambda d: len(d.data["timestamp"]))
    q = np.column_stack([d.data[f"q[{i}]"].astype(float) for i in (1, 2, 3, 0)])
    ok = np.all(np.isfinite(q), axis=1) & (np.linalg.norm(q, axis=1) > 0.5)
    if not ok.any():
        return None
    C_b_n = Rotation.from_quat(q[ok]) * Rotation.from_matrix(C_b_frd.T)
    x, y, z, w = C_b_n.as_quat().T
    t = (d.data["timestamp"].astype(np.int64)[ok] - t0) * units.MICROSECOND
    return pd.DataFrame({"t": t, "qw": w, "qx": x, "qy": y, "qz": z})


def _baro(ulog, t0: int) -> pd.DataFrame | None:
    """``vehicle_air_data.baro_alt_meter`` as ``t, alt_m`` (finite rows), or None."""
    sets = [d for d in _dataset(ulog, BARO_TOPIC, None) if "baro_alt_meter" in d.data]
    if not sets:
        return None
    d = max(sets, key=lambda d: len(d.data["timestamp"]))
    alt = d.data["baro_alt_meter"].astype(float)
    ok = np.isfinite(alt)
    if not ok.any():
        return None
    t = (d.data["timestamp"].astype(np.int64)[ok] - t0) * units.MICROSECOND
    return pd.DataFrame({"t": t, "alt_m": alt[ok]})


def _imu_frame(d, label, ts, t0, C_b_frd, check_magnitudes, limits) -> pd.DataFrame:
    src = Source(f"{label}, topic '{d.name}'", np.arange(ts.size), row_word="message")
    raw = {k: d.data[k].astype(float) for k in (*_GYRO, *_ACCEL)}
    check_finite(raw, {k: Column(k, k, None) for k in raw}, src)
    t = (ts - t0) * units.MICROSECOND
    f_b = np.column_stack([raw[k] for k in _ACCEL]) @ C_b_frd.T
    w_ib_b = np.column_stack([raw[k] for k in _GYRO]) @ C_b_frd.T
    frame, kept = validated_imu(
        t, f_b, w_ib_b, src, "'timestamp'", "'accelerometer_m_s2'", "'gyro_rad'",
        check_magnitudes=check_magnitudes, limits=limits,
        rate_hint="; PX4 logs gyro_rad in rad/s, so a vehicle this fast needs a larger "
                  "max_rate_rad_s (or check_magnitudes=False)")
    clipped = {}
    for field in ("accelerometer_clipping", "gyro_clipping"):
        if field in d.data:
            rows = np.flatnonzero(d.data[field])
            clipped[field] = int(rows.size)
            if rows.size:
                warnings.warn(f"{src.label}: '{field}' flags {rows.size} sample(s), the first "
                              f"at {src.where(int(rows[0]))}: the sensor saturated there",
                              FlightDataWarning, stacklevel=3)
    frame.attrs["clipping"] = clipped
    return frame, kept


def _gnss_frame(d, label, idx, ts, t0, altitude, check_magnitudes):
    src = Source(f"{label}, topic '{d.name}'", idx, row_word="message")
    lat, lon, alt, ref = _geodetic(d, label, idx, altitude)
    check_finite({"lat": lat, "lon": lon, "alt": alt},
                 {k: Column(k, k, None) for k in ("lat", "lon", "alt")}, src)
    t = (ts - t0) * units.MICROSECOND
    check_times(t, src, "'timestamp'")
    check_sample_interval(t, src, "'timestamp'", "gnss", 1.0)
    r_e = geodetic_to_ecef(lat, lon, alt)
    if check_magnitudes:
        check_positions(r_e, src, "'lat/lon/alt'")
    out = {"t": t, **dict(zip(R_KEYS, r_e.T, strict=True))}
    data = d.data
    velocity = None
    if all(k in data for k in _VEL_NED) and (
            "vel_ned_valid" not in data or np.all(data["vel_ned_valid"][idx])):
        v_n = np.column_stack([data[k][idx].astype(float) for k in _VEL_NED])
        check_finite(dict(zip(NED_KEYS, v_n.T, strict=True)),
                     {k: Column(k, f, None) for k, f in zip(NED_KEYS, _VEL_NED, strict=True)},
                     src)
        v_e = np.einsum("kij,kj->ki", ned_to_ecef_matrix(lat, lon), v_n)
        if check_magnitudes:
            check_velocities(v_e, src, "'vel_n_m_s/vel_e_m_s/vel_d_m_s'")
        out.update(zip(V_KEYS, v_e.T, strict=True))
        velocity = "ned"
    if "eph" in data and "epv" in data:
        eph, epv = data["eph"][idx].astype(float), data["epv"][idx].astype(float)
        if np.all(np.isfinite(eph) & np.isfinite(epv) & (eph > 0) & (epv > 0)):
            out["sigma"] = combine_sigma(eph, epv)
        else:
            warnings.warn(f"{src.label}: eph/epv not positive and finite at every fix; no "
                          f"sigma column", FlightDataWarning, stacklevel=3)
    frame = pd.DataFrame(out)
    frame.attrs.update(topic=d.name, instance=int(d.multi_id), altitude_reference=ref,
                       velocity_input=velocity)
    return frame, src
