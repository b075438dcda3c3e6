"""The Trajectory type and the exact-IMU construction every generator shares.

IMU signals are consistent with the kinematics by construction (docs/assumptions.md, excitability.md
§4): given a smooth ECEF position ``P(t)`` with derivatives and a smooth attitude ``C_b_e(t)``
with its body rate ``omega_eb^b``,

* ``f^b = C_e^b (dV/dt + 2 Omega x V - gamma(P))``
* ``omega_ib^b = omega_eb^b + C_e^b Omega``

so a correct ECEF strapdown integrating ``f^b`` and ``omega_ib^b`` reproduces ``P``,
``V`` and ``C_b_e``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy.spatial.transform import Rotation

from navlib import earth
from navlib._validation import finite_array, increasing_times

__all__ = ["Trajectory", "build_trajectory", "exact_imu"]


@dataclass(frozen=True, eq=False)
class Trajectory:
    """A reference trajectory sampled at its IMU rate (contract: docs/library.md).

    Attributes
    ----------
    t : ndarray (N,)
        Time, s, strictly increasing.
    position, velocity : ndarray (N, 3)
        ECEF position (m) and velocity (m/s).
    attitude : scipy.spatial.transform.Rotation, length N
        Body -> ECEF rotation ``C_b_e``.
    specific_force : ndarray (N, 3)
        ``f^b`` in body axes, m/s^2: what an ideal accelerometer reads.
    angular_rate : ndarray (N, 3)
        ``omega_ib^b`` in body axes, rad/s: what an ideal gyro reads.
    events : dict
        Event name -> time in s (``ignition``, ``burnout``, ...).
    name : str
        Short label used in plots and reports.
    parameters : dict
        The keyword values the generator used (assumed values made visible).
    """

    t: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    attitude: Rotation
    specific_force: np.ndarray
    angular_rate: np.ndarray
    events: dict = field(default_factory=dict)
    name: str = ""
    parameters: dict = field(default_factory=dict)

    def __post_init__(self):
        n = len(self.t)
        for attr in ("position", "velocity", "specific_force", "angular_rate"):
            if getattr(self, attr).shape != (n, 3):
                raise ValueError(f"Trajectory.{attr} must have shape ({n}, 3)")
        if len(self.attitude) != n:
            raise ValueError(f"Trajectory.attitude must have length {n}")

    def __len__(self) -> int:
        return len(self.t)

    @property
    def rate_hz(self) -> float:
        """Nominal sampling rate (median of the step), Hz."""
        return float(1.0 / np.median(np.diff(self.t)))

    @property
    def geodetic(self):
        """``(lat, lon, alt)`` arrays (rad, rad, m) along the trajectory."""
        return earth.ecef_to_geodetic(self.position)

    def C_b_e(self) -> np.ndarray:
        """Body -> ECEF rotation matrices (N, 3, 3)."""
        return self.attitude.as_matrix()

    def at_rate(self, rate_hz: float) -> np.ndarray:
        """Indices of the samples nearest a regular grid at ``rate_hz`` (e.g. GNSS epochs)."""
        step = max(round(self.rate_hz / rate_hz), 1)
        return np.arange(0, len(self.t), step)

    def to_frame(self) -> pd.DataFrame:
        """Tidy DataFrame: one row per sample with ECEF, geodetic, attitude and IMU columns."""
        lat, lon, alt = self.geodetic
        quat = self.attitude.as_quat()  # scalar-last x, y, z, w
        cols = {
            "t": self.t,
            "x": self.position[:, 0], "y": self.position[:, 1], "z": self.position[:, 2],
            "vx": self.velocity[:, 0], "vy": self.velocity[:, 1], "vz": self.velocity[:, 2],
            "lat_deg": np.degrees(lat), "lon_deg": np.degrees(lon), "alt": alt,
            "speed": np.linalg.norm(self.velocity, axis=1),
            "qx": quat[:, 0], "qy": quat[:, 1], "qz": quat[:, 2], "qw": quat[:, 3],
            "f_x": self.specific_force[:, 0], "f_y": self.specific_force[:, 1],
            "f_z": self.specific_force[:, 2],
            "w_x": self.angular_rate[:, 0], "w_y": self.angular_rate[:, 1],
            "w_z": self.angular_rate[:, 2],
        }
        return pd.DataFrame(cols)


def exact_imu(position, velocity, acceleration, C_b_e, w_eb_b):
    """Ideal IMU signals from smooth kinematics (ECEF), vectorised over samples.

    Parameters
    ----------
    position, velocity, acceleration : ndarray (N, 3)
        ECEF ``P``, ``dP/dt`` and ``d^2P/dt^2`` from an analytic (spline) representation.
    C_b_e : ndarray (N, 3, 3)
        Body -> ECEF rotation matrices.
    w_eb_b : ndarray (N, 3)
        Body rate relative to ECEF, in body axes, from the attitude's analytic derivative.

    Returns
    -------
    f_b, w_ib_b : ndarray (N, 3)
        Specific force and inertial angular rate in body axes (docs/assumptions.md, excitability.md
        §4).
    """
    omega = earth.EARTH_RATE_ECEF
    f_e = acceleration + 2.0 * np.cross(omega, velocity) - earth.normal_gravity_ecef(position)
    C_e_b = np.swapaxes(C_b_e, -1, -2)
    f_b = np.einsum("nij,nj->ni", C_e_b, f_e)
    w_ib_b = w_eb_b + np.einsum("nij,j->ni", C_e_b, omega)
    return f_b, w_ib_b


def build_trajectory(t, position, velocity, acceleration, C_b_e, w_eb_b, *, events=None,
                     name="", parameters=None) -> Trajectory:
    """Assemble a :class:`Trajectory` whose IMU is exact for the given smooth kinematics.

    Parameters
    ----------
    t : numpy.ndarray
        Strictly increasing times, s, (N,).
    position, velocity, acceleration : numpy.ndarray
        ECEF kinematics, m, m/s, m/s^2, each (N, 3).
    C_b_e : numpy.ndarray
        Body -> ECEF attitude, (N, 3, 3).
    w_eb_b : numpy.ndarray
        Body rate relative to ECEF, body axes, rad/s, (N, 3).
    events : dict or None, optional
        Event name -> time, s.
    name : str, optional
        Trajectory name.
    parameters : dict or None, optional
        Settings recorded with it.

    Returns
    -------
    Trajectory

    Raises
    ------
    NavlibInputError
        If an array has the wrong shape, is not finite, or ``t`` is not increasing.
    """
    t = increasing_times(t, "t")
    n = t.size
    position = finite_array(position, "position", (n, 3))
    velocity = finite_array(velocity, "velocity", (n, 3))
    acceleration = finite_array(acceleration, "acceleration", (n, 3))
    C_b_e = finite_array(C_b_e, "C_b_e", (n, 3, 3))
    w_eb_b = finite_array(w_eb_b, "w_eb_b", (n, 3))
    f_b, w_ib_b = exact_imu(position, velocity, acceleration, C_b_e, w_eb_b)
    if C_b_e.strides[0] == 0:  # one matrix broadcast (a vehicle at rest): converted once
        attitude = Rotation.from_matrix(C_b_e[:1])[np.zeros(n, dtype=np.intp)]
    else:
        attitude = Rotation.from_matrix(C_b_e)
    return Trajectory(
        t=t, position=position, velocity=velocity, attitude=attitude,
        specific_force=f_b, angular_rate=w_ib_b, events=dict(events or {}), name=name,
        parameters=dict(parameters or {}),
    )
