"""Aiding sensors of the EKF simulations: attitude references with noise and outliers.

:func:`simulate_attitude_sensor` is a generic attitude reference; :class:`ReferenceTrajectory`
the launcher's reference-trajectory attitudes (the RT pseudo-measurement). Outliers come
from :mod:`navlib.sensors.faults` (channels ``att`` and ``rt_*``).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from navlib._validation import finite_array, finite_scalar
from navlib.errors import NavlibInputError
from navlib.rotations import exp_so3, log_so3
from navlib.sensors.faults import as_outliers, channel_profile, inject

__all__ = ["ReferenceTrajectory", "simulate_attitude_sensor"]


class ReferenceTrajectory:
    """Reference-trajectory attitudes for the RT pseudo-measurement in EKF simulations.

    The launcher flies the true trajectory ``C(t)``; the on-board reference attitude
    differs from it by the divergence ``d`` (body axes): ``C_ref = C exp(S(d))``, so that
    ``rotvec(C_hat' C_ref) = T_E^B psi + d`` is Beaudoin's eq. (8). ``d`` is the
    ``psi_ref`` block of the closed-loop attitude dynamics of the RT augmentation
    (docs/assumptions.md, launcher.md §3.4), ``x_a' = M x_a + a1_sign [T_E^B psi; 0] + [0;
    omega_wind]`` with ``M`` = ``dynamics`` (10 x 10,
    :func:`navlib.models.launcher.rt_dynamics_matrix`), integrated with the paper's Euler steps. It
    is driven by white wind rates of ``sigma_wind`` rad/s per sample and by the **actual**
    navigation attitude error ``psi`` of the filter that calls it (``C = (I + S(psi)) C_nav``: the
    control steers with the navigation attitude), so truth and filter model agree. Outliers on the
    ``rt`` channels are added to the emitted ``d`` only (the stored reference is wrong, the vehicle
    is not).

    Call it as ``reference(k, t_k, C_nav_prev)`` at increasing IMU samples, with the
    navigation attitude the control used since the previous call (the posterior after that
    call's update; None at the first call) — what :func:`ekf` does. ``history()`` returns
    the true divergence at the calls.
    """

    def __init__(self, trajectory, dynamics, *, sigma_wind: float = 0.01,
                 a1_sign: float = 1.0, seed=None, rng=None, outliers=None, noise: bool = True):
        self._C = trajectory.attitude.as_matrix()
        self._t = np.asarray(trajectory.t, dtype=float)
        self._M = finite_array(dynamics, "dynamics", shape=(10, 10))
        self._sigma = finite_scalar(sigma_wind, "sigma_wind", 0.0)
        if a1_sign not in (1, -1, 1.0, -1.0):
            raise NavlibInputError(f"a1_sign: expected +1 or -1, got {a1_sign}")
        self._a1 = float(a1_sign)
        self._rng = rng if rng is not None else np.random.default_rng(seed)
        self._noise = bool(noise)
        outliers = as_outliers(outliers)
        self._add = np.stack([channel_profile(outliers, f"rt_{a}", self._t)
                              for a in ("x", "y", "z")], axis=1)
        self._x = np.zeros(10)
        self._last = None        # sample index of the previous call
        self._hist_t, self._hist_d = [], []

    def __call__(self, k, t_k, C_nav_prev):
        k = int(k)
        if self._last is not None:
            k_prev = self._last
            if k <= k_prev:
                raise NavlibInputError("reference: calls must come at increasing samples")
            dt = self._t[k] - self._t[k_prev]
            drive = np.zeros(10)
            if C_nav_prev is not None:
                C_prev = self._C[k_prev]
                psi = log_so3(C_prev @ np.asarray(C_nav_prev).T)
                drive[:3] = self._a1 * (C_prev.T @ psi)
            if self._noise and self._sigma > 0:
                drive[7:] = self._sigma * self._rng.standard_normal(3)
            self._x = self._x + dt * (self._M @ self._x + drive)
        self._last = k
        d = self._x[7:].copy()
        self._hist_t.append(self._t[k])
        self._hist_d.append(d)
        return self._C[k] @ exp_so3(d + self._add[k])

    def history(self) -> pd.DataFrame:
        """True divergence ``d`` (body axes, rad) at the calls: ``t, ref_x, ref_y, ref_z``."""
        d = np.array(self._hist_d).reshape(-1, 3)
        return pd.DataFrame({"t": np.array(self._hist_t), "ref_x": d[:, 0], "ref_y": d[:, 1],
                             "ref_z": d[:, 2]})


def simulate_attitude_sensor(trajectory, sigma: float, rate_hz: float | None = None,
                             seed=None, *, rng=None, outliers=None):
    """Attitude-sensor fixes ``C_att = exp(S(n)) C`` with white ECEF-axis noise ``n``.

    Generic attitude reference sensor of Beaudoin et al. §2.2 (white noise only, Table 1:
    1 deg per axis); ``att`` outliers (:mod:`navlib.sensors.faults`) are added to ``n``.

    Parameters
    ----------
    trajectory : navlib.trajectory.Trajectory
        The true motion; its attitudes are measured.
    sigma : float
        Noise standard deviation per ECEF axis (rad), >= 0.
    rate_hz : float, optional
        Fix rate (Hz); None measures at every trajectory sample.
    seed : int, optional
        Seed of a new generator, when ``rng`` is not given.
    rng : numpy.random.Generator, optional
        Source of the noise (overrides ``seed``).
    outliers : optional
        Outlier specification read by :func:`navlib.sensors.faults.as_outliers` (channel ``att``).

    Returns
    -------
    t : ndarray (K,)
    C_att : ndarray (K, 3, 3)
        Measured body -> ECEF attitudes.

    Raises
    ------
    NavlibInputError
        When ``sigma`` is negative or not finite, or ``rate_hz`` is not positive.
    """
    sigma = finite_scalar(sigma, "sigma", 0.0)
    rng = rng if rng is not None else np.random.default_rng(seed)
    idx = (np.arange(len(trajectory.t)) if rate_hz is None
           else trajectory.at_rate(finite_scalar(rate_hz, "rate_hz", 0.0, low_open=True)))
    t = np.asarray(trajectory.t, dtype=float)[idx]
    noise = sigma * rng.standard_normal((idx.size, 3))

    noise = inject(noise, t, as_outliers(outliers), "att")
    return t, exp_so3(noise) @ trajectory.attitude[idx].as_matrix()
