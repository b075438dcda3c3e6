"""A minimal ArduPilot DataFlash (.bin) writer for tests: FMT records, then data records.

Each record is ``0xA3 0x95 <type id>`` followed by the fields packed little-endian as the
record's FMT declares (format characters as ArduPilot's ``LogStructure.h``: ``Q`` uint64,
``B`` uint8, ``f`` float, ``L`` int32 degrees * 1e7, ``e`` int32 * 100, ``n`` char[4],
``N`` char[16], ``Z`` char[64], ``i`` int32, ``I`` uint32, ``h`` int16, ``H`` uint16).
"""

from __future__ import annotations

import struct

HEAD = b"\xa3\x95"
FMT_ID = 0x80
_STRUCT = {"Q": "Q", "B": "B", "f": "f", "L": "i", "e": "i", "n": "4s", "N": "16s",
           "Z": "64s", "i": "i", "I": "I", "h": "h", "H": "H", "d": "d", "b": "b"}
_SCALE = {"L": 1e7, "e": 100.0}

LAYOUTS = {
    # ArduPilot 4.x: one message per kind with an instance column I
    "4.x": {
        "IMU": ("QBffffff", "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ"),
        "GPS": ("QBBLLeffff", "TimeUS,I,Status,Lat,Lng,Alt,Spd,GCrs,VZ,HDop"),
        "ATT": ("Qffffff", "TimeUS,DesRoll,Roll,DesPitch,Pitch,DesYaw,Yaw"),
        "BARO": ("QBf", "TimeUS,I,Alt"),
        "MSG": ("QZ", "TimeUS,Message"),
    },
    # ArduPilot 3.x: IMU, IMU2, GPS without an instance column
    "3.x": {
        "IMU": ("Qffffff", "TimeUS,GyrX,GyrY,GyrZ,AccX,AccY,AccZ"),
        "IMU2": ("Qffffff", "TimeUS,GyrX,GyrY,GyrZ,AccX,AccY,AccZ"),
        "GPS": ("QBLLeffff", "TimeUS,Status,Lat,Lng,Alt,Spd,GCrs,VZ,HDop"),
        "ATT": ("Qffffff", "TimeUS,DesRoll,Roll,DesPitch,Pitch,DesYaw,Yaw"),
        "BARO": ("Qf", "TimeUS,Alt"),
        "MSG": ("QZ", "TimeUS,Message"),
    },
    # before about 2015 (ArduCopter 3.1-3.3): TimeMS (ms since boot); GPS TimeMS is the GPS
    # time of week beside Week, its boot time is T; the barometer in CTUN BarAlt
    "TimeMS": {
        "IMU": ("Iffffff", "TimeMS,GyrX,GyrY,GyrZ,AccX,AccY,AccZ"),
        "IMU2": ("Iffffff", "TimeMS,GyrX,GyrY,GyrZ,AccX,AccY,AccZ"),
        "GPS": ("BIHBfLLeefffI", "Status,TimeMS,Week,NSats,HDop,Lat,Lng,RelAlt,Alt,Spd,GCrs,VZ,T"),
        "ATT": ("Iffffff", "TimeMS,DesRoll,Roll,DesPitch,Pitch,DesYaw,Yaw"),
        "CTUN": ("Iff", "TimeMS,Alt,BarAlt"),
        "MSG": ("Z", "Message"),
    },
}
GPS_WEEK_START_MS = 345_600_000
"""GPS time of week (ms) written at boot in the TimeMS layout (GPS TimeMS = this + boot ms)."""


def _pack_format(fmt: str) -> struct.Struct:
    return struct.Struct("<" + "".join(_STRUCT[c] for c in fmt))


class DataFlashWriter:
    """Collects records and writes a .bin file (FMT records of every type first)."""

    def __init__(self, layout: str = "4.x"):
        self.types = {}
        self.records = []
        for i, (name, (fmt, cols)) in enumerate(LAYOUTS[layout].items()):
            self.types[name] = (0x81 + i, fmt, cols.split(","), _pack_format(fmt))

    def add(self, name: str, **values) -> None:
        type_id, fmt, cols, packer = self.types[name]
        out = []
        for c, col in zip(fmt, cols, strict=True):
            v = values.get(col, 0)
            if c in _SCALE:
                v = round(v * _SCALE[c])
            elif c in "nNZ":
                v = str(v).encode()
            elif c in "QBiIhHb":
                v = int(v)
            out.append(v)
        self.records.append(HEAD + bytes([type_id]) + packer.pack(*out))

    def write(self, path) -> None:
        fmt_packer = _pack_format("BBnNZ")
        head = [HEAD + bytes([FMT_ID]) + fmt_packer.pack(
            FMT_ID, 89, b"FMT", b"BBnNZ", b"Type,Length,Name,Format,Columns")]
        for name, (type_id, fmt, cols, packer) in self.types.items():
            head.append(HEAD + bytes([FMT_ID]) + fmt_packer.pack(
                type_id, 3 + packer.size, name.encode(), fmt.encode(), ",".join(cols).encode()))
        with open(path, "wb") as fh:
            fh.write(b"".join(head + self.records))


def write_flight(path, imu, gnss_geodetic, attitude=None, *, layout="4.x", t0_us=50_000_000,
                 imu_instances=(0,), gps_status=6, message="ArduCopter V4.5.0 (test)",
                 baro=None):
    """Write IMU frames and GNSS fixes as a DataFlash log.

    ``imu``: DataFrame ``t, f_x..w_z`` (FRD body); ``gnss_geodetic``: DataFrame ``t, lat_deg,
    lon_deg, alt_m, vn, ve, vd``; ``attitude``: DataFrame ``t, roll_deg, pitch_deg, yaw_deg``;
    ``baro``: DataFrame ``t, alt_m`` (``BARO`` Alt, or ``CTUN`` BarAlt in the ``"TimeMS"``
    layout). Records are written in time order; a second IMU instance
    (``imu_instances=(0, 1)``) is a copy with a small offset in the gyros. The ``"TimeMS"``
    layout stamps records in ms (``t0_us`` rounded to ms).
    """
    import math

    w = DataFlashWriter(layout)
    events = [(0.0, "MSG", {"Message": message})]
    for row in imu.itertuples(index=False):
        for inst in imu_instances:
            vals = {"GyrX": row.w_x + 1e-3 * inst, "GyrY": row.w_y, "GyrZ": row.w_z,
                    "AccX": row.f_x, "AccY": row.f_y, "AccZ": row.f_z}
            if layout == "4.x":
                events.append((row.t, "IMU", {**vals, "I": inst}))
            else:
                events.append((row.t, "IMU" if inst == 0 else f"IMU{inst + 1}", vals))
    for row in gnss_geodetic.itertuples(index=False):
        spd = math.hypot(row.vn, row.ve)
        crs = math.degrees(math.atan2(row.ve, row.vn)) % 360.0
        vals = {"Status": gps_status, "Lat": row.lat_deg, "Lng": row.lon_deg, "Alt": row.alt_m,
                "Spd": spd, "GCrs": crs, "VZ": row.vd, "HDop": 0.8}
        if layout == "4.x":
            vals["I"] = 0
        events.append((row.t, "GPS", vals))
    if attitude is not None:
        for row in attitude.itertuples(index=False):
            events.append((row.t, "ATT", {"Roll": row.roll_deg, "Pitch": row.pitch_deg,
                                          "Yaw": row.yaw_deg}))
    if baro is not None:
        kind, field = ("CTUN", "BarAlt") if layout == "TimeMS" else ("BARO", "Alt")
        for row in baro.itertuples(index=False):
            events.append((row.t, kind, {field: row.alt_m}))
    events.sort(key=lambda e: e[0])
    for t, name, vals in events:
        boot_us = t0_us + round(t * 1e6)
        boot_ms = round(boot_us / 1000)
        if layout != "TimeMS":
            w.add(name, TimeUS=boot_us, **vals)
        elif name == "GPS":
            w.add(name, TimeMS=GPS_WEEK_START_MS + boot_ms, Week=2000, NSats=10, T=boot_ms,
                  **vals)
        else:
            w.add(name, TimeMS=boot_ms, **vals)
    w.write(path)
