"""Dead IMU channels: an accelerometer that never reads gravity, an axis stuck at one value.

A logger can write IMU columns for a sensor that is unpowered, disconnected or failed: the
cells are numbers, so the unit and magnitude checks pass, and the flight fit later fails on
something else. :func:`check_imu_alive` refuses such a record first, naming the sensor and
what it read.
"""

from __future__ import annotations

import numpy as np

from navlib import units
from navlib.io._table import Source

__all__ = ["ALIVE_ACCEL_M_S2", "MIN_SAMPLES", "MOVING_RATE_RAD_S", "check_imu_alive",
           "dead_magnetometer"]

MIN_SAMPLES = 100
"""Records shorter than this are not judged (a short rest may legitimately read constant)."""
ALIVE_ACCEL_M_S2 = 0.5 * units.G0
"""Smallest largest-specific-force of a live accelerometer, m/s^2: gravity alone gives 1 g at
rest, so a record that never reaches half of it has no working accelerometer."""
MOVING_RATE_RAD_S = 0.5
"""Angular rate above which the record moves, rad/s: then a channel that never changes while
the five others do is stuck, not quiet (a vehicle at rest may read one quantised value)."""


def check_imu_alive(f_b: np.ndarray, w_ib_b: np.ndarray, source: Source, f_labels: str,
                    w_labels: str, also: str = "") -> None:
    """Raise naming the dead sensor: no gravity on the accelerometer, or one accelerometer or
    gyro axis that reads one value over the whole record while the five other channels change
    and show motion (another gyro axis beyond :data:`MOVING_RATE_RAD_S`, or another
    accelerometer axis changing by more than half a g).

    ``f_b`` (m/s^2) and ``w_ib_b`` (rad/s) are (N, 3); ``f_labels`` / ``w_labels`` the
    columns as ``'a'/'b'/'c'``, for the message; ``also`` is appended to it (what the
    log's other sensors of the IMU read, :func:`dead_magnetometer`).
    """
    n = f_b.shape[0]
    if n < MIN_SAMPLES:
        return
    largest = float(np.max(np.linalg.norm(f_b, axis=1)))
    if largest < ALIVE_ACCEL_M_S2:
        raise source.error(f_labels, None,
                           f"dead accelerometer: the specific force never exceeds "
                           f"{largest:.3g} m/s^2 over {n} samples, while gravity alone reads "
                           f"9.8 m/s^2 at rest (unpowered, disconnected or not logged){also}")
    channels = np.column_stack([f_b, w_ib_b])
    constant = np.ptp(channels, axis=0) == 0.0
    if constant.sum() != 1:
        return          # none, or a simulated motion that leaves several axes exactly zero
    k = int(np.flatnonzero(constant)[0])
    others = np.delete(channels, k, axis=1)
    gyro = others[:, 2:] if k < 3 else others[:, 3:]
    accel = others[:, :3] if k >= 3 else others[:, :2]
    if (np.max(np.linalg.norm(gyro, axis=1)) <= MOVING_RATE_RAD_S
            and np.max(np.ptp(accel, axis=0)) <= ALIVE_ACCEL_M_S2):
        return          # the other channels show no motion: a quiet axis, not a dead one
    labels = (f_labels if k < 3 else w_labels).split("/")
    what = "accelerometer" if k < 3 else "gyro"
    raise source.error(labels[k % 3] if len(labels) == 3 else labels[0], None,
                       f"stuck {what} axis: all {n} samples read {channels[0, k]:.6g} while "
                       f"the other five IMU channels change and the vehicle moves; the "
                       f"sensor (or this channel) is dead{also}")


def dead_magnetometer(mag: np.ndarray | None, labels: str) -> str:
    """A clause naming a magnetometer that reads exactly zero on every axis in every sample,
    for the dead-IMU message: ``""`` when it reads anything else.

    Parameters
    ----------
    mag : ndarray (N, 3) or None
        The magnetometer samples, any unit (NaN where empty); None: the log has none.
    labels : str
        Its columns as ``'a'/'b'/'c'``, for the message.

    Returns
    -------
    str
    """
    if mag is None or mag.size == 0 or np.any(np.nan_to_num(mag, nan=0.0) != 0.0):
        return ""
    return (f"; the magnetometer {labels} reads 0 on every axis in all {mag.shape[0]} rows "
            "too: the IMU looks unpowered")
