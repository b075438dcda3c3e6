"""Measurement data of the EKF: IMU samples, epochs on the IMU clock, attitude series,
and the measurement rows of each error-model family (issue 5)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from navlib._validation import finite_array
from navlib.errors import NavlibInputError

_MEAS_KINDS = {
    "launcher": {"att": "psi_m_", "gnss_vel": "dv_m_", "gnss_pos": "dr_m_", "rt": "psi_ref_m_"},
    "ecef21": {"gnss_pos": "gnss_", "gnss_vel": "gnss_v"},
}


def _imu_arrays(imu):
    if isinstance(imu, pd.DataFrame):
        cols = ["t", "f_x", "f_y", "f_z", "w_x", "w_y", "w_z"]
        missing = [c for c in cols if c not in imu.columns]
        if missing:
            raise NavlibInputError(f"imu: missing column(s) {missing}")
        t = imu["t"].to_numpy(float)
        f = imu[cols[1:4]].to_numpy(float)
        w = imu[cols[4:7]].to_numpy(float)
    else:
        try:
            t, f, w = imu.t, imu.f_b, imu.w_ib_b
        except AttributeError as exc:
            raise NavlibInputError(
                "imu: expected a navlib.sensors.ImuSimulation or a DataFrame with t, f_x.. w_z"
            ) from exc
    from navlib._validation import increasing_times

    t = increasing_times(t, "imu.t")
    return t, finite_array(f, "imu.f_b", (t.size, 3)), finite_array(w, "imu.w_ib_b", (t.size, 3))


def _epoch_index(t_imu, t_meas, name: str) -> np.ndarray:
    """Nearest IMU sample of each measurement time (within half a sample)."""
    t_meas = finite_array(t_meas, f"{name}.t", ndim=1)
    k = np.clip(np.searchsorted(t_imu, t_meas), 1, t_imu.size - 1)
    k = np.where(np.abs(t_imu[k - 1] - t_meas) <= np.abs(t_imu[k] - t_meas), k - 1, k)
    half = 0.5 * np.median(np.diff(t_imu))
    bad = np.flatnonzero(np.abs(t_imu[k] - t_meas) > half + 1e-9)
    if bad.size:
        raise NavlibInputError(
            f"{name}: epoch at t = {t_meas[bad[0]]:g} s is not on an IMU sample "
            f"(IMU spans {t_imu[0]:g}..{t_imu[-1]:g} s)"
        )
    return k


def _rotations(data, name: str):
    """(t, (K, 3, 3)) from ``(t, Rotation)`` or a DataFrame ``t, qx, qy, qz, qw``."""
    from scipy.spatial.transform import Rotation

    if isinstance(data, pd.DataFrame):
        cols = ["qx", "qy", "qz", "qw"]
        missing = [c for c in ["t", *cols] if c not in data.columns]
        if missing:
            raise NavlibInputError(f"{name}: missing column(s) {missing}")
        return data["t"].to_numpy(float), Rotation.from_quat(data[cols].to_numpy()).as_matrix()
    try:
        t, rot = data
    except (TypeError, ValueError) as exc:
        raise NavlibInputError(f"{name}: expected (t, Rotation) or a DataFrame t, qx..qw") from exc
    mats = rot.as_matrix() if hasattr(rot, "as_matrix") else finite_array(rot, name)
    return np.asarray(t, dtype=float), np.asarray(mats).reshape(-1, 3, 3)
