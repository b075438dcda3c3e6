"""A small Altus Metrum AltOS CSV export writer for tests: both header generations, and the
layouts of boards without a gyro (TeleMetrum) or without GPS (EasyMega).

:func:`rocket_rows` makes a stated, arbitrary record (not a simulation): 0.3 s on the pad,
100 Hz rows to ``t_drogue``, 10 Hz rows after it with "held" rows in between (the IMU values
of the row before at a new time, as AltOS exports them under drogue), a few exact duplicate
rows, and GPS columns that repeat the last fix on every row, a new fix every second.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

NEW_HEAD = ("serial,flight,call,time,state,state_name,acceleration,pressure,altitude,height,"
            "speed,temperature,accel_x,accel_y,accel_z,gyro_roll,gyro_pitch,gyro_yaw,mag_x,"
            "mag_y,mag_z,tilt,pyro,connected,locked,nsat,latitude,longitude,altitude,year,"
            "month,day,hour,minute,second,pdop,hdop,vdop").split(",")
OLD_HEAD = ("time,acceleration,pressure,altitude,height,speed,temperature,accel_x,accel_y,"
            "accel_z,gyro_roll,gyro_pitch,gyro_yaw,mag_x,mag_y,mag_z,tilt,latitude,longitude,"
            "altitude").split(",")
STATES = {"boost": 3, "coast": 5, "drogue": 6, "main": 7, "landed": 8}
IMU = ("accel_x", "accel_y", "accel_z", "gyro_roll", "gyro_pitch", "gyro_yaw")
GPS = ("nsat", "latitude", "longitude", "altitude", "hour", "minute", "second", "pdop",
       "hdop", "vdop")
LAT0, LON0, ALT0 = 39.0159236, -105.7107031, 2682.0


def rocket_rows(t_drogue=6.0, t_end=12.0, *, duplicates=(0.5, 2.0), low_sat_second=None,
                pad_s=0.3):
    """Rows (DataFrame, one per export row, ``gps_altitude`` and ``baro_altitude`` named
    apart) of a short record, ``pad_s`` on the pad before boost; ``low_sat_second``: the fix
    of that second has 3 satellites."""
    fast = np.round(np.arange(-pad_s, t_drogue, 0.01), 2)
    slow = np.round(np.arange(t_drogue, t_end + 1e-9, 0.1), 2)
    t = np.concatenate([fast, slow])
    burn = (t >= 0.0) & (t < 2.0)
    rows = pd.DataFrame({
        "time": t,
        "state_name": np.where(t < 2.0, "boost", np.where(t < t_drogue, "coast", "drogue")),
        "accel_x": np.round(np.where(t < 0.0, 9.87, np.where(burn, 80.0 + 5 * t, -3.0)), 2),
        "accel_y": np.round(0.3 + 0.1 * np.sin(7 * t), 2),
        "accel_z": np.round(-0.2 + 0.1 * np.cos(5 * t), 2),
        "gyro_roll": np.round(np.where(t < 0.0, 0.1, 300.0 * np.sin(0.3 * t)), 2),
        "gyro_pitch": np.round(20.0 * np.sin(t), 2),
        "gyro_yaw": np.round(-15.0 * np.cos(2 * t), 2),
        "tilt": np.round(3.0 + 2.0 * np.maximum(t, 0.0), 2),
        "baro_altitude": np.round(ALT0 - 20.0 + 30.0 * np.maximum(t, 0.0) ** 1.5, 2),
    })
    rows.loc[rows.state_name.eq("drogue") & (rows.time >= t_end - 0.05), "state_name"] = "landed"
    second = np.floor(t + 0.3).astype(int)          # a new fix at -0.3, 0.7, 1.7, ... s
    rows["nsat"] = np.where(second == low_sat_second, 3, 9)
    rows["latitude"] = np.round(LAT0 + 2e-5 * second, 7)
    rows["longitude"] = np.round(LON0 - 1e-5 * second, 7)
    rows["gps_altitude"] = np.round(ALT0 + 40.0 * second, 1)
    rows["gps_second"] = second
    # held rows under drogue: the row before, at a time between two 10 Hz rows
    held = rows[rows.time > t_drogue + 0.05].iloc[::3].copy()
    held_prev = rows.loc[held.index - 1]
    copied = [*IMU, "tilt", "baro_altitude"]
    held[copied] = held_prev[copied].to_numpy()
    held["time"] = np.round(held_prev["time"].to_numpy() + 0.04, 2)
    dup = rows[np.isin(rows.time, duplicates)]
    out = pd.concat([rows, held, dup]).sort_values("time", kind="stable")
    return out.reset_index(drop=True)


def _new_row(r) -> list[str]:
    second = int(r.gps_second)
    return ["1257", " 18", "KB0G", f"{r.time:9.2f}", f"{STATES[r.state_name]:2d}",
            f"{r.state_name:>8s}", f"{_high_g(r):8.2f}", "73957.00", f"{r.baro_altitude:8.2f}",
            f"{r.baro_altitude - ALT0:8.2f}", "0.00", "27.0", f"{r.accel_x:7.2f}",
            f"{r.accel_y:7.2f}", f"{r.accel_z:7.2f}", f"{r.gyro_roll:8.2f}",
            f"{r.gyro_pitch:8.2f}", f"{r.gyro_yaw:8.2f}", *_mag(r, (" -0.08", " -0.22", " -0.20")),
            f"{r.tilt:7.2f}", "4.36", "1", "1", f"{int(r.nsat):3d}", f"{r.latitude:12.7f}",
            f"{r.longitude:12.7f}", f"{r.gps_altitude:8.1f}", "2019", " 5", "26", "16",
            f"{33 + (11 + second) // 60:3d}", f"{(11 + second) % 60:3d}", "1.6", "0.8", "1.4"]


def _high_g(r) -> float:
    """The ``acceleration`` cell: the rows' ``high_g`` when given, else ``accel_x``."""
    return getattr(r, "high_g", r.accel_x)


def _mag(r, default) -> tuple[str, ...]:
    """The magnetometer cells: the rows' ``mag_x/y/z`` when given, else ``default``."""
    if not hasattr(r, "mag_x"):
        return default
    return tuple(f"{getattr(r, c):6.2f}" for c in ("mag_x", "mag_y", "mag_z"))


def _old_row(r) -> list[str]:
    return [f"{r.time:g}", f"{_high_g(r):g}", "96945", f"{r.baro_altitude:g}",
            f"{r.baro_altitude - ALT0:g}", "0", "20.4", f"{r.accel_x:g}", f"{r.accel_y:g}",
            f"{r.accel_z:g}", f"{r.gyro_roll:g}", f"{r.gyro_pitch:g}", f"{r.gyro_yaw:g}",
            "-0.62", "-0.06", "-0.17", f"{r.tilt:g}", f"{r.latitude:.7f}", f"{r.longitude:.7f}",
            f"{r.gps_altitude:g}"]


def write_altos(path, rows, *, generation="version", board="telemega") -> None:
    """Write ``rows`` (from :func:`rocket_rows`) as an AltOS export.

    ``generation``: ``"version"`` (``#version`` header, padded cells) or ``"legacy"`` (header
    from ``time``). ``board``: ``"telemega"`` (all columns), ``"telemetrum"`` (no 3-axis IMU
    columns: it has one accelerometer axis and no gyro) or ``"easymega"`` (no GPS columns).
    """
    if generation == "version":
        head, cells = ["#version", *NEW_HEAD], [["6", *_new_row(r)] for r in
                                                rows.itertuples(index=False)]
    else:
        head, cells = list(OLD_HEAD), [_old_row(r) for r in rows.itertuples(index=False)]
    drop = set()
    if board == "telemetrum":
        drop = {i for i, h in enumerate(head) if h.startswith(("accel_", "gyro_", "mag_"))
                or h == "tilt"}
    elif board == "easymega":
        lat = head.index("latitude")
        drop = {i for i, h in enumerate(head) if h in GPS and (h != "altitude" or i > lat)}
        drop |= {i for i, h in enumerate(head) if h in ("year", "month", "day", "locked")}
    keep = [i for i in range(len(head)) if i not in drop]
    lines = [",".join(head[i] for i in keep)]
    lines += [",".join(c[i] for i in keep) for c in cells]
    with open(path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write("\n".join(lines) + "\n")
