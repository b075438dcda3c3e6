"""CSV writers of IMU and GNSS frames that :mod:`navlib.io.csv_files`' readers read back."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from navlib import units
from navlib._validation import finite_array
from navlib.earth import ecef_to_geodetic, ned_to_ecef_matrix
from navlib.errors import NavlibInputError
from navlib.io import _units
from navlib.io.csv_files import F_KEYS, IMU_KEYS, NED_KEYS, R_KEYS, V_KEYS, W_KEYS

__all__ = ["write_gnss_csv", "write_imu_csv"]


def _frame_values(frame, name: str, keys) -> dict[str, np.ndarray]:
    if not isinstance(frame, pd.DataFrame):
        raise NavlibInputError(f"{name}: expected a pandas DataFrame, got {type(frame).__name__}")
    missing = [k for k in keys if k not in frame.columns]
    if missing:
        raise NavlibInputError(f"{name}: missing column(s) {missing}; columns are "
                               f"{list(frame.columns)}")
    return {k: finite_array(frame[k].to_numpy(), f"{name}[{k!r}]", ndim=1) for k in keys}


def _write(columns: dict[str, np.ndarray], path, float_format: str | None) -> Path:
    p = Path(path)
    if not p.parent.is_dir():
        raise NavlibInputError(f"path: folder '{p.parent}' does not exist")
    pd.DataFrame(columns).to_csv(p, index=False, float_format=float_format)
    return p


def write_imu_csv(imu: pd.DataFrame, path, *, time_unit: str = "s", accel_unit: str = "m/s^2",
                  gyro_unit: str = "rad/s", float_format: str | None = None) -> Path:
    """Write an IMU DataFrame as CSV that :func:`~navlib.io.read_imu_csv` reads back unchanged.

    The header carries the units in brackets (``t [s], f_x [m/s^2], ..., w_z [rad/s]``),
    so reading needs no unit keywords. ``float_format`` None writes shortest round-trip
    decimals (lossless); e.g. ``"%.6g"`` makes smaller files. Returns the path written.

    Parameters
    ----------
    imu : pandas.DataFrame
        IMU record (``t``, s; ``f_x..f_z``, m/s^2; ``w_x..w_z``, rad/s).
    path : path-like
        Output file.
    time_unit, accel_unit, gyro_unit : str, optional
        Units written.
    float_format : str or None, optional
        Format of the numbers; None: shortest round-trip.

    Returns
    -------
    pathlib.Path
        The file written.
    """
    vals = _frame_values(imu, "imu", IMU_KEYS)
    f_t = _units.factor("time", time_unit, "time_unit")
    f_a = _units.factor("accel", accel_unit, "accel_unit")
    f_w = _units.factor("gyro", gyro_unit, "gyro_unit")
    out = {f"t [{time_unit}]": vals["t"] / f_t}
    out.update({f"{k} [{accel_unit}]": vals[k] / f_a for k in F_KEYS})
    out.update({f"{k} [{gyro_unit}]": vals[k] / f_w for k in W_KEYS})
    return _write(out, path, float_format)


def write_gnss_csv(gnss: pd.DataFrame, path, *, position: str = "ecef", velocity: str = "ecef",
                   time_unit: str = "s", float_format: str | None = None) -> Path:
    """Write a GNSS DataFrame as CSV that :func:`~navlib.io.read_gnss_csv` reads back.

    ``position="ecef"`` writes ``x [m], y [m], z [m]``; ``"geodetic"`` writes ``lat_deg,
    lon_deg, alt [m]`` (ellipsoidal height). Velocity columns, when the frame has them, go
    out as ECEF ``vx, vy, vz`` or, with ``velocity="ned"``, as ``vn, ve, vd`` (m/s);
    ``sigma [m]`` when present. Returns the path written.

    Parameters
    ----------
    gnss : pandas.DataFrame
        GNSS record (``t``, s; ``x, y, z``, ECEF, m; optional velocity and sigmas).
    path : path-like
        Output file.
    position : {"ecef", "geodetic"}, optional
        Position columns written.
    velocity : {"ecef", "ned"}, optional
        Velocity columns written.
    time_unit : str, optional
        Time unit written.
    float_format : str or None, optional
        Format of the numbers; None: shortest round-trip.

    Returns
    -------
    pathlib.Path
        The file written.
    """
    if position not in ("ecef", "geodetic"):
        raise NavlibInputError(f"position: expected 'ecef' or 'geodetic', got {position!r}")
    if velocity not in ("ecef", "ned"):
        raise NavlibInputError(f"velocity: expected 'ecef' or 'ned', got {velocity!r}")
    keys = ["t", *R_KEYS]
    if isinstance(gnss, pd.DataFrame):
        keys += [k for k in (*V_KEYS, "sigma") if k in gnss.columns]
    vals = _frame_values(gnss, "gnss", keys)
    f_t = _units.factor("time", time_unit, "time_unit")
    r_e = np.column_stack([vals[k] for k in R_KEYS])
    out = {f"t [{time_unit}]": vals["t"] / f_t}
    if position == "ecef":
        out.update({f"{k} [m]": r_e[:, i] for i, k in enumerate(R_KEYS)})
    else:
        lat, lon, alt = ecef_to_geodetic(r_e)
        out.update({"lat_deg": units.rad2deg(lat), "lon_deg": units.rad2deg(lon),
                    "alt [m]": alt})
    if "vx" in vals:
        v_e = np.column_stack([vals[k] for k in V_KEYS])
        if velocity == "ned":
            lat, lon, _ = ecef_to_geodetic(r_e)
            v = np.einsum("kji,kj->ki", ned_to_ecef_matrix(lat, lon), v_e)
            out.update({f"{k} [m/s]": v[:, i] for i, k in enumerate(NED_KEYS)})
        else:
            out.update({f"{k} [m/s]": v_e[:, i] for i, k in enumerate(V_KEYS)})
    if "sigma" in vals:
        out["sigma [m]"] = vals["sigma"]
    return _write(out, path, float_format)
