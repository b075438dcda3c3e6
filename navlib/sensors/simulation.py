"""IMU and GNSS errors simulated along a trajectory (docs/assumptions.md A1, A7).

The measurement model is that of :mod:`navlib.sensors`; discretisation is exact:
Gauss–Markov ``b_{k+1} = e^{-dt/tau} b_k + sigma sqrt(1 - e^{-2 dt/tau}) w_k``, random
walk ``b_{k+1} = b_k + q sqrt(dt) w_k``, white noise of density ``N`` sampled with
``sigma = N / sqrt(dt)``. Every error source draws from its own child generator.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
import pandas as pd

from navlib._validation import finite_array, finite_scalar, reject_unknown
from navlib.errors import NavlibInputError
from navlib.sensors.presets import GnssSpec, ImuSpec, SensorSpec, TriadSpec

__all__ = ["ImuSimulation", "TriadErrors", "first_order_recursion", "gauss_markov", "random_walk",
           "simulate_gnss", "simulate_imu", "white_noise"]


def _generators(seed, rng, n: int) -> list[np.random.Generator]:
    """``n`` independent child generators from ``seed`` or ``rng`` (one per error source,
    so changing one source's size or level leaves the others' realisations unchanged)."""
    if rng is not None and seed is not None:
        raise NavlibInputError("seed, rng: give one or the other, not both")
    if rng is None:
        rng = np.random.default_rng(seed)
    elif not isinstance(rng, np.random.Generator):
        raise NavlibInputError(f"rng: expected a numpy.random.Generator, got {type(rng).__name__}")
    return rng.spawn(n)


def _trajectory_arrays(trajectory):
    try:
        t = np.asarray(trajectory.t, dtype=float)
        f_b = np.asarray(trajectory.specific_force, dtype=float)
        w_ib_b = np.asarray(trajectory.angular_rate, dtype=float)
    except AttributeError as exc:
        raise NavlibInputError(
            f"trajectory: expected a navlib Trajectory, got {type(trajectory).__name__}"
        ) from exc
    return t, f_b, w_ib_b


@numba.njit(cache=True, nogil=True)
def first_order_recursion(a, drive, out):
    """``out[0] = drive[0]``, ``out[k] = a[k - 1] out[k - 1] + drive[k]`` per column of
    ``drive`` (N, n): the Gauss-Markov recursion, bitwise what ``scipy.signal.lfilter([1],
    [1, -a])`` gives for a constant ``a`` (tests/sensors), without importing scipy.signal
    (about 1.2 CPU-s, with the scipy.stats it loads) or a Python loop per sample.

    Parameters
    ----------
    a : numpy.ndarray, shape (N - 1,)
        Step factors ``a[k] = exp(-dt_k / tau)``.
    drive : numpy.ndarray, shape (N, n)
        Driving terms, one column per axis.
    out : numpy.ndarray, shape (N, n)
        Filled in place (may be ``drive`` itself).
    """
    for j in range(drive.shape[1]):
        out[0, j] = drive[0, j]
    for k in range(1, drive.shape[0]):
        for j in range(drive.shape[1]):
            out[k, j] = a[k - 1] * out[k - 1, j] + drive[k, j]


def gauss_markov(t, sigma: float, tau_s: float, rng: np.random.Generator, n_axes: int = 3):
    """Stationary first-order Gauss–Markov samples at times ``t`` (exact discretisation).

    ``x_0 ~ N(0, sigma^2)``, ``x_{k+1} = a_k x_k + sigma sqrt(1 - a_k^2) w_k`` with
    ``a_k = exp(-(t_{k+1} - t_k) / tau_s)``.

    Parameters
    ----------
    t : array_like, shape (N,)
        Sample times (s), increasing.
    sigma : float
        Steady-state standard deviation (units of the result).
    tau_s : float
        Correlation time (s).
    rng : numpy.random.Generator
        Source of the normal draws.
    n_axes : int, optional
        Independent columns (default 3).

    Returns
    -------
    numpy.ndarray, shape (N, n_axes)
        The process at ``t``.
    """
    t = np.asarray(t, dtype=float)
    w = rng.standard_normal((t.size, n_axes))
    if sigma == 0.0:
        return np.zeros_like(w)
    a = np.exp(-np.diff(t) / tau_s)
    drive = w.copy()
    drive[1:] *= np.sqrt(1.0 - a * a)[:, None]
    if t.size > 1 and np.allclose(a, a[0], rtol=1e-9, atol=0.0):
        a = np.full(a.size, a[0])  # a uniform step: one factor, as a fixed-step filter
    x = np.empty_like(drive)
    first_order_recursion(a, drive, x)
    return sigma * x


def random_walk(t, density: float, rng: np.random.Generator, n_axes: int = 3):
    """Random walk from 0 at ``t[0]`` with density ``q``: increments ``q sqrt(dt) w``.

    Parameters
    ----------
    t : array_like, shape (N,)
        Sample times (s), increasing.
    density : float
        ``q``, units of the result per sqrt(s); 0 gives zeros.
    rng : numpy.random.Generator
        Source of the normal draws.
    n_axes : int, optional
        Independent columns (default 3).

    Returns
    -------
    numpy.ndarray, shape (N, n_axes)
        The walk, 0 in the first row.
    """
    t = np.asarray(t, dtype=float)
    w = rng.standard_normal((t.size, n_axes))
    out = np.zeros_like(w)
    if density > 0.0:
        np.cumsum(density * np.sqrt(np.diff(t))[:, None] * w[1:], axis=0, out=out[1:])
    return out


def white_noise(t, density: float, rng: np.random.Generator, n_axes: int = 3):
    """Point samples of white noise of density ``N``: ``sigma_k = N / sqrt(dt_k)``.

    ``dt_k`` is the sample's step (the following one; the last sample reuses the last step).

    Parameters
    ----------
    t : array_like, shape (N,)
        Sample times (s), increasing.
    density : float
        One-sided density ``N``, units of the result times sqrt(s).
    rng : numpy.random.Generator
        Source of the normal draws.
    n_axes : int, optional
        Independent columns (default 3).

    Returns
    -------
    numpy.ndarray, shape (N, n_axes)
        The noise samples.
    """
    t = np.asarray(t, dtype=float)
    w = rng.standard_normal((t.size, n_axes))
    dt = np.diff(t)
    dt = np.append(dt, dt[-1]) if dt.size else np.ones(1)
    return density / np.sqrt(dt)[:, None] * w


@dataclass(frozen=True, eq=False)
class TriadErrors:
    """Realised errors of one triad: ``meas = (I + diag(scale_factor) + misalignment) truth
    + bias + noise``; ``bias`` and ``scale_factor`` are (N, 3), ``misalignment`` (3, 3)."""

    bias: np.ndarray
    scale_factor: np.ndarray
    misalignment: np.ndarray
    noise: np.ndarray

    def apply(self, truth: np.ndarray) -> np.ndarray:
        """The measured signal for true signal ``truth`` (N, 3)."""
        return (truth + self.scale_factor * truth + truth @ self.misalignment.T + self.bias
                + self.noise)


def _simulate_triad(t, spec: TriadSpec, rngs, fixed_bias=None, fixed_scale=None) -> TriadErrors:
    n = t.size
    g_bias, g_scale, g_mis, g_noise, g_markov, g_rw, g_scale_rw = rngs
    b0 = spec.bias * g_bias.standard_normal(3) if fixed_bias is None else fixed_bias
    s0 = spec.scale_factor * g_scale.standard_normal(3) if fixed_scale is None else fixed_scale
    mis = spec.misalignment * g_mis.standard_normal((3, 3))
    np.fill_diagonal(mis, 0.0)
    bias = (b0 + gauss_markov(t, spec.bias_markov_sigma, spec.bias_markov_tau, g_markov)
            + random_walk(t, spec.bias_random_walk, g_rw))
    scale = s0 + random_walk(t, spec.scale_factor_random_walk, g_scale_rw)
    noise = white_noise(t, spec.noise_density, g_noise)
    return TriadErrors(bias=bias, scale_factor=np.broadcast_to(scale, (n, 3)).copy(),
                       misalignment=mis, noise=noise)


@dataclass(frozen=True, eq=False)
class ImuSimulation:
    """Simulated IMU output and the error realisation that produced it.

    Attributes
    ----------
    t : ndarray (N,)
    f_b, w_ib_b : ndarray (N, 3)
        Measured specific force (m/s^2) and angular rate (rad/s), body axes.
    accel, gyro : TriadErrors
        True errors (bias and scale factor over time, misalignment, white noise).
    """

    t: np.ndarray
    f_b: np.ndarray
    w_ib_b: np.ndarray
    accel: TriadErrors
    gyro: TriadErrors

    def to_frame(self, errors: bool = False) -> pd.DataFrame:
        """IMU columns ``t, f_x, f_y, f_z, w_x, w_y, w_z`` (the ``navlib.io`` layout); with
        ``errors=True`` also the true biases ``b_ax.. b_gz`` and scale factors
        ``s_ax.. s_gz``."""
        cols = {"t": self.t}
        for i, axis in enumerate("xyz"):
            cols[f"f_{axis}"] = self.f_b[:, i]
        for i, axis in enumerate("xyz"):
            cols[f"w_{axis}"] = self.w_ib_b[:, i]
        if errors:
            for sym, triad in (("a", self.accel), ("g", self.gyro)):
                for i, axis in enumerate("xyz"):
                    cols[f"b_{sym}{axis}"] = triad.bias[:, i]
                for i, axis in enumerate("xyz"):
                    cols[f"s_{sym}{axis}"] = triad.scale_factor[:, i]
        return pd.DataFrame(cols)


def _imu_spec(spec) -> ImuSpec:
    if isinstance(spec, ImuSpec):
        return spec
    if isinstance(spec, SensorSpec):
        if spec.imu is None:
            raise NavlibInputError(f"spec: preset {spec.name!r} has no [imu] section")
        return spec.imu
    raise NavlibInputError(f"spec: expected a SensorSpec or ImuSpec, got {type(spec).__name__}")


def simulate_imu(trajectory, spec, seed=None, *, rng=None, **overrides) -> ImuSimulation:
    """Corrupt a trajectory's exact IMU signals with the errors of ``spec``.

    Parameters
    ----------
    trajectory : navlib.trajectory.Trajectory
        Supplies ``t``, ``specific_force`` and ``angular_rate`` (the IMU sampling times).
    spec : SensorSpec or ImuSpec
        E.g. ``load_preset("launcher_table1")``.
    seed : int, optional
        Seed for a fresh generator; or pass ``rng`` (not both).
    rng : numpy.random.Generator, optional
    **overrides
        ``gyro_bias``, ``accel_bias``, ``gyro_scale_factor``, ``accel_scale_factor``: (3,)
        SI values to use as the turn-on errors instead of random draws (e.g. the constant
        0.5 deg/h biases of the SSAC simulation).

    Returns
    -------
    ImuSimulation
        Measured ``f_b``, ``w_ib_b`` and the true error realisation.

    Notes
    -----
    Model and discretisation in the module docstring (docs/assumptions.md A1, A7). Each
    error source draws from its own child generator, so a run is reproducible by seed and
    changing one level (say the ARW) leaves the other realisations unchanged.
    """
    reject_unknown(overrides, ("gyro_bias", "accel_bias", "gyro_scale_factor",
                               "accel_scale_factor"), "simulate_imu")
    imu = _imu_spec(spec)
    t, f_b, w_ib_b = _trajectory_arrays(trajectory)
    fixed = {k: finite_array(v, k, (3,)) for k, v in overrides.items()}
    rngs = _generators(seed, rng, 14)
    gyro = _simulate_triad(t, imu.gyro, rngs[:7], fixed.get("gyro_bias"),
                           fixed.get("gyro_scale_factor"))
    accel = _simulate_triad(t, imu.accel, rngs[7:], fixed.get("accel_bias"),
                            fixed.get("accel_scale_factor"))
    return ImuSimulation(t=t, f_b=accel.apply(f_b), w_ib_b=gyro.apply(w_ib_b), accel=accel,
                         gyro=gyro)


def simulate_gnss(trajectory, spec, rate_hz: float | None = None, seed=None, *, rng=None,
                  with_errors: bool = False) -> pd.DataFrame:
    """GNSS ECEF position and velocity fixes with white noise and a Markov position bias.

    Parameters
    ----------
    trajectory : navlib.trajectory.Trajectory
    spec : SensorSpec or GnssSpec
    rate_hz : float, optional
        Fix rate; default the spec's ``rate_hz``. Epochs are the trajectory samples nearest
        a regular grid (``Trajectory.at_rate``).
    seed, rng
        As in :func:`simulate_imu`.
    with_errors : bool
        Also return the true position bias ``bias_x, bias_y, bias_z`` (m).

    Returns
    -------
    DataFrame
        ``t, x, y, z, vx, vy, vz, sigma`` (ECEF m, m/s; ``sigma`` the per-axis position
        white-noise sigma, m) — the ``navlib.io`` GNSS layout.
    """
    if isinstance(spec, SensorSpec):
        if spec.gnss is None:
            raise NavlibInputError(f"spec: preset {spec.name!r} has no [gnss] section")
        spec = spec.gnss
    if not isinstance(spec, GnssSpec):
        raise NavlibInputError(f"spec: expected a SensorSpec or GnssSpec, got "
                               f"{type(spec).__name__}")
    rate = spec.rate_hz if rate_hz is None else finite_scalar(rate_hz, "rate_hz", 0.0,
                                                               low_open=True)
    t_all, _, _ = _trajectory_arrays(trajectory)
    idx = trajectory.at_rate(rate)
    t = t_all[idx]
    g_pos, g_vel, g_bias = _generators(seed, rng, 3)
    bias = gauss_markov(t, spec.position_bias_markov, spec.position_bias_tau, g_bias)
    pos = (np.asarray(trajectory.position)[idx] + bias
           + spec.position_sigma * g_pos.standard_normal((t.size, 3)))
    vel = (np.asarray(trajectory.velocity)[idx]
           + spec.velocity_sigma * g_vel.standard_normal((t.size, 3)))
    cols = {"t": t, "x": pos[:, 0], "y": pos[:, 1], "z": pos[:, 2], "vx": vel[:, 0],
            "vy": vel[:, 1], "vz": vel[:, 2], "sigma": np.full(t.size, spec.position_sigma)}
    if with_errors:
        cols.update({"bias_x": bias[:, 0], "bias_y": bias[:, 1], "bias_z": bias[:, 2]})
    return pd.DataFrame(cols)
