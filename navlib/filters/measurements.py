"""Measurements of the EKF (docs/assumptions.md, launcher.md §6.3): GNSS position and velocity, the
attitude sensor and the reference-trajectory pseudo-measurement, each giving its innovation, ``H``
and ``R`` for the current nominal state; and the input parsing (IMU samples, epochs on the
IMU clock, attitude series).

A measurement is built with the error model (:class:`navlib.models.base.ErrorStateModel`),
whose ``measurements`` name the kinds it uses with their rows and sigma, and its data on the
IMU clock (``index``: IMU sample of each epoch). The filter calls
:meth:`Measurement.evaluate` at each epoch; a new measurement is one new subclass. A
:class:`FixedDesign` measurement (``H`` and ``R`` the same at every epoch: GNSS, attitude
sensor) also gives the innovations of many epochs at once (:meth:`FixedDesign.innovations`),
which the filter evaluates once per propagation window, where the nominal state is fixed.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import ClassVar

import numpy as np
import pandas as pd
from scipy.spatial.transform import Rotation

from navlib._validation import finite_array, increasing_times
from navlib.errors import NavlibInputError
from navlib.rotations import log_so3

__all__ = ["AttitudeSensor", "FixedDesign", "GnssPosition", "GnssVelocity", "Measurement",
           "ReferenceAttitude", "ekf_measurements", "epoch_index", "imu_arrays"]


class Measurement(ABC):
    """One kind of EKF measurement: its epochs, data and rows of the error model.

    Parameters
    ----------
    model : navlib.models.base.ErrorStateModel
    index : ndarray (K,) of int
        IMU sample of each epoch.
    values : ndarray (K, ...)
        The measured values.
    rows : navlib.models.base.MeasurementRows, optional
        Row names and per-axis sigma (``R = sigma^2 I``); default the model's
        ``measurements[kind]``.

    Attributes
    ----------
    kind : str
    names : tuple of str
    H : ndarray (m, n)
        The measurement matrix where it does not depend on the nominal state.
    R : ndarray (m, m)
    wants_posterior : bool
        The filter reports the posterior navigation attitude (3, 3) after each update to the
        measurement's ``observe`` method.
    """

    kind: ClassVar[str]
    wants_posterior: ClassVar[bool] = False

    def __init__(self, model, index, values, rows=None):
        if rows is None:
            if self.kind not in model.measurements:
                raise NavlibInputError(f"{self.kind}: the {model.name} model declares no rows "
                                       "for it; give rows=MeasurementRows(names, sigma)")
            rows = model.measurements[self.kind]
        self.index = np.asarray(index, dtype=int)
        self.values = values
        self.names = tuple(rows.names)
        self.R = rows.sigma**2 * np.eye(len(self.names))
        self.nav_sign = model.nav_sign
        self.H = np.zeros((len(self.names), len(model.state_names)))
        self._design(model.groups)

    @abstractmethod
    def _design(self, groups):
        """Fill the constant part of :attr:`H` from the model's state groups."""

    @abstractmethod
    def evaluate(self, i: int, nominal, j: int):
        """Innovation ``z`` (m,), ``H`` (m, n), ``R`` (m, m) of epoch ``i``, at sample ``j`` of
        ``nominal`` (:class:`navlib.models.base.Nominal`).

        Parameters
        ----------
        i : int
            Epoch index among this measurement's epochs.
        nominal : Nominal
            The nominal trajectory.
        j : int
            Its sample at the epoch.
        """


class FixedDesign(Measurement):
    """A measurement whose ``H`` and ``R`` (:attr:`H`, :attr:`R`) do not depend on the epoch
    or the nominal state; only the innovations do, given for many epochs at once."""

    @abstractmethod
    def innovations(self, i, nominal, j) -> np.ndarray:
        """Innovations ``z`` (K, m) of epochs ``i`` (K,) at samples ``j`` (K,) of ``nominal``
        (the same numbers as epoch by epoch).

        Parameters
        ----------
        i : numpy.ndarray
            Epoch indices, (K,).
        nominal : Nominal
            The nominal trajectory.
        j : numpy.ndarray
            Its samples at those epochs, (K,).
        """

    def evaluate(self, i, nominal, j):
        """Innovation, ``H`` and ``R`` of one epoch (:meth:`innovations` of that epoch alone).

        Parameters
        ----------
        i : int
            Epoch index.
        nominal : Nominal
            The nominal trajectory.
        j : int
            Its sample at the epoch.
        """
        return self.innovations(np.array([i]), nominal, np.array([j]))[0], self.H, self.R


class GnssPosition(FixedDesign):
    """ECEF GNSS position (m): ``z = nav_sign (r_gnss - r_hat)``, minus the nominal GNSS bias
    estimate when the model has one (``bp``: ``H = [I, I]``, Beaudoin et al. 2018 eq. 2)."""

    kind = "gnss_pos"

    def _design(self, groups):
        self.H[:, groups["position"]] = np.eye(3)
        if "bp" in groups:
            self.H[:, groups["bp"]] = np.eye(3)

    def innovations(self, i, nominal, j):
        """GNSS position innovations ``nav_sign (r_gnss - r_nominal) (- b_p)`` (K, 3), m.

        Parameters
        ----------
        i : numpy.ndarray
            Epoch indices, (K,).
        nominal : Nominal
            The nominal trajectory.
        j : numpy.ndarray
            Its samples at those epochs, (K,).
        """
        z = self.nav_sign * (self.values[i] - nominal.position[j])
        if "bp" in nominal.parameters:
            z = z - nominal.parameters["bp"][j]
        return z


class GnssVelocity(FixedDesign):
    """ECEF GNSS velocity (m/s): ``z = nav_sign (v_gnss - v_hat)``, ``H = I`` on velocity."""

    kind = "gnss_vel"

    def _design(self, groups):
        self.H[:, groups["velocity"]] = np.eye(3)

    def innovations(self, i, nominal, j):
        """GNSS velocity innovations ``nav_sign (v_gnss - v_nominal)`` (K, 3), m/s.

        Parameters
        ----------
        i : numpy.ndarray
            Epoch indices, (K,).
        nominal : Nominal
            The nominal trajectory.
        j : numpy.ndarray
            Its samples at those epochs, (K,).
        """
        return self.nav_sign * (self.values[i] - nominal.velocity[j])


def _ecef_attitude_error(model, kind):
    if model.attitude_frame != "ecef":
        raise NavlibInputError(f"{kind}: measured with the ECEF attitude error psi; the "
                               f"{model.name} model uses {model.attitude_frame!r}")


class AttitudeSensor(FixedDesign):
    """Body -> ECEF attitude sensor (Beaudoin et al. 2018 eq. 3): ``z = rotvec(C_att C_hat')``,
    ECEF axes, ``H = I`` on the attitude error ``psi``."""

    kind = "att"

    def __init__(self, model, index, values, rows=None):
        _ecef_attitude_error(model, "attitude")
        super().__init__(model, index, values, rows)

    def _design(self, groups):
        self.H[:, groups["attitude"]] = np.eye(3)

    def innovations(self, i, nominal, j):
        """Attitude-sensor innovations ``log(C_meas C_nominal')`` (K, 3), rad.

        Parameters
        ----------
        i : numpy.ndarray
            Epoch indices, (K,).
        nominal : Nominal
            The nominal trajectory.
        j : numpy.ndarray
            Its samples at those epochs, (K,).
        """
        return log_so3(self.values[i] @ np.swapaxes(nominal.C_b_e[j], -1, -2))


class ReferenceAttitude(Measurement):
    """Reference-trajectory pseudo-measurement (Beaudoin et al. 2018 eq. 8), noise-free:
    ``z = rotvec(C_hat' C_ref)`` in body axes, ``H = [C_hat', I]`` on ``psi`` and the
    reference-trajectory attitude ``psi_ref``.

    ``values`` are reference attitudes (K, 3, 3), or a callable
    ``reference(k, t_k, C_nav_prev) -> (3, 3)`` (a :class:`navlib.sensors.ReferenceTrajectory`)
    called at each epoch with the posterior navigation attitude of the previous epoch.
    """

    kind = "rt"

    def __init__(self, model, index, values, rows=None):
        _ecef_attitude_error(model, "reference")
        super().__init__(model, index, values, rows)
        self.wants_posterior = callable(values)
        self._attitude = model.groups["attitude"]
        self._posterior = None

    def _design(self, groups):
        self.H[:, groups["reference"]] = np.eye(3)

    def evaluate(self, i, nominal, j):
        """Innovation ``log(C_hat' C_ref)`` (rad), ``H`` with ``C_hat'`` on the attitude columns,
        and ``R`` of epoch ``i``.

        Parameters
        ----------
        i : int
            Epoch index.
        nominal : Nominal
            The nominal trajectory.
        j : int
            Its sample at the epoch.
        """
        C_hat = nominal.C_b_e[j]
        if callable(self.values):
            C_ref = np.asarray(self.values(int(self.index[i]), nominal.t[j], self._posterior),
                               dtype=float)
        else:
            C_ref = self.values[i]
        H = self.H.copy()
        H[:, self._attitude] = C_hat.T
        return log_so3(C_hat.T @ C_ref), H, self.R

    def observe(self, C_b_e):
        """Posterior navigation attitude after the update (for the next callable call)."""
        self._posterior = C_b_e


def ekf_measurements(model, t, gnss=None, attitude=None, reference=None) -> list:
    """The measurements of ``model`` from the EKF's data, in update order (GNSS position,
    GNSS velocity, attitude sensor, reference trajectory).

    GNSS velocity is used when the model has its rows and ``gnss`` has ``vx, vy, vz``; the
    attitude sensor and the reference trajectory are required when the model uses them.

    Parameters
    ----------
    model : Model
        The error-state model (its ``measurements`` say which are used).
    t : numpy.ndarray
        IMU time stamps, s.
    gnss : pandas.DataFrame or None, optional
        GNSS fixes with ``t, x, y, z`` (ECEF, m) and optionally ``vx, vy, vz`` (m/s).
    attitude : optional
        Attitude-sensor data, when the model uses it.
    reference : optional
        Reference trajectory, when the model uses it.

    Returns
    -------
    list
        The measurements.

    Raises
    ------
    NavlibInputError
        If the data are malformed, a measurement epoch is not on an IMU sample, or a
        measurement the model uses is missing.
    """
    kinds = model.measurements
    out = []
    if gnss is not None:
        if not isinstance(gnss, pd.DataFrame) or not {"t", "x", "y", "z"} <= set(gnss.columns):
            raise NavlibInputError("gnss: expected a DataFrame with columns t, x, y, z")
        kg = epoch_index(t, gnss["t"].to_numpy(float), "gnss")
        out.append(GnssPosition(model, kg, gnss[["x", "y", "z"]].to_numpy(float)))
        if "gnss_vel" in kinds and {"vx", "vy", "vz"} <= set(gnss.columns):
            out.append(GnssVelocity(model, kg, gnss[["vx", "vy", "vz"]].to_numpy(float)))
    if "att" in kinds:
        if attitude is None:
            raise NavlibInputError(f"attitude: the {model.name} model uses attitude-sensor "
                                   "updates; give attitude data")
        ta, Ca = _rotations(attitude, "attitude")
        out.append(AttitudeSensor(model, epoch_index(t, ta, "attitude"), Ca))
    if "rt" in kinds:
        if reference is None:
            raise NavlibInputError(f"reference: the {model.name} model needs reference-"
                                   "trajectory attitudes or a ReferenceTrajectory")
        if callable(reference):
            out.append(ReferenceAttitude(model, np.arange(t.size), reference))
        else:
            tr, Cr = _rotations(reference, "reference")
            out.append(ReferenceAttitude(model, epoch_index(t, tr, "reference"), Cr))
    return out


def imu_arrays(imu):
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
    t = increasing_times(t, "imu.t")
    return t, finite_array(f, "imu.f_b", (t.size, 3)), finite_array(w, "imu.w_ib_b", (t.size, 3))


def epoch_index(t_imu, t_meas, name: str) -> np.ndarray:
    """Nearest IMU sample of each measurement time (within half a sample).

    Parameters
    ----------
    t_imu : numpy.ndarray
        IMU time stamps, s.
    t_meas : numpy.ndarray
        Measurement time stamps, s.
    name : str
        Name of the measurement, for the message.

    Returns
    -------
    numpy.ndarray
        Index of the IMU sample of each measurement.

    Raises
    ------
    NavlibInputError
        If a measurement time is not within half a sample of an IMU sample.
    """
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
