"""The 21-state ECEF error model of España, Carrizo & Giribet (2019), Eqs. (1)-(5), (23)-(24):
navigation errors and the 12 IMU parameters along a reference trajectory, discretised to
the GNSS epochs. The readings of the garbled kinematic block (docs/assumptions.md A4) and the
assumed IMU inverse model (A7): docs/models.md."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from itertools import pairwise

import numpy as np

from navlib import cache, earth, units
from navlib._validation import finite_scalar, reject_unknown
from navlib.discretize import chain, discretize_steps
from navlib.errors import NavlibInputError
from navlib.models._ecef21_kernel import ecef21_jacobians_kernel
from navlib.models.base import (
    HOLDS,
    DiscreteModel,
    ErrorState,
    LinearModel,
    MeasurementRows,
)
from navlib.resources import is_shipped_name
from navlib.rotations import skew
from navlib.sensors import DEFAULT_IMU_PRESET, load_preset
from navlib.sparse_discretize import discretize_window

__all__ = ["ATTITUDE_ERRORS", "DEFAULT_SENSORS", "NOISE_KEYS", "NOISE_NAMES", "P0_DEFAULTS",
           "PAPER_IDS", "STATE_GROUPS", "STATE_NAMES", "STREAM_SAMPLES", "Ecef21ErrorState",
           "ecef21", "ecef21_at_epochs", "ecef21_jacobians", "epoch_samples", "imu_noise_densities",
           "initial_covariance", "parameter_sigmas"]

STATE_NAMES = (
    "P_x", "P_y", "P_z", "V_x", "V_y", "V_z", "theta_x", "theta_y", "theta_z",
    "bg_x", "bg_y", "bg_z", "ba_x", "ba_y", "ba_z",
    "sg_x", "sg_y", "sg_z", "sa_x", "sa_y", "sa_z",
)
"""State names in the paper's order e1..e21 (Eq. 23)."""

PAPER_IDS = {name: f"e{i + 1}" for i, name in enumerate(STATE_NAMES)}
"""State name -> the paper's label (``"sg_x"`` -> ``"e16"``)."""

STATE_GROUPS = {
    "position": STATE_NAMES[0:3], "velocity": STATE_NAMES[3:6], "attitude": STATE_NAMES[6:9],
    "gyro_bias": STATE_NAMES[9:12], "acc_bias": STATE_NAMES[12:15],
    "gyro_scale": STATE_NAMES[15:18], "acc_scale": STATE_NAMES[18:21],
}
"""Physical groups of the 21 states."""

NOISE_NAMES = (
    "acc_wn_x", "acc_wn_y", "acc_wn_z", "gyro_wn_x", "gyro_wn_y", "gyro_wn_z",
    "bg_rw_x", "bg_rw_y", "bg_rw_z", "ba_rw_x", "ba_rw_y", "ba_rw_z",
    "sg_rw_x", "sg_rw_y", "sg_rw_z", "sa_rw_x", "sa_rw_y", "sa_rw_z",
)
"""The 18 noise channels ``[xi_mu (f, omega); xi_p (b_g, b_a, s_g, s_a)]`` (spec A6)."""

ATTITUDE_ERRORS = ("ecef", "body")

P0_DEFAULTS = {
    "sigma_p0_m": 30.0,
    "sigma_v0_m_s": 3.0,
    "sigma_theta0_deg": 1.0,
    "sigma_bg_deg_s": 0.05,
    "sigma_ba_m_s2": 0.02,
    "sigma_sg_ppm": 5000.0,
    "sigma_sa_ppm": 1000.0,
}
"""Initial standard deviations (spec excitability.md §5, all assumed [A])."""

NOISE_KEYS = ("arw_rad_sqrt_s", "vrw_m_s_sqrt_s", "bg_rw_rad_s_sqrt_s", "ba_rw_m_s2_sqrt_s",
              "sg_rw_per_sqrt_s", "sa_rw_per_sqrt_s")
"""Names of the noise densities (SI) the model takes from the sensor preset."""

DEFAULT_SENSORS = DEFAULT_IMU_PRESET


def _per_axis(value, name: str) -> np.ndarray:
    arr = np.broadcast_to(np.asarray(value, dtype=float), (3,)).copy()
    if not np.all(np.isfinite(arr)) or np.any(arr < 0):
        raise NavlibInputError(f"{name}: expected a non-negative number or 3 of them, got {value}")
    return arr


def _imu_spec(sensors):
    """The ``navlib.sensors`` IMU spec behind ``sensors`` (None -> default preset), or the
    mapping itself."""
    if sensors is None:
        sensors = DEFAULT_SENSORS
    if isinstance(sensors, str):
        sensors = _shipped_preset(sensors) if is_shipped_name(sensors) else load_preset(sensors)
    if isinstance(sensors, Mapping):
        return sensors
    imu = getattr(sensors, "imu", sensors)
    if imu is None or not (hasattr(imu, "gyro") and hasattr(imu, "accel")):
        raise NavlibInputError(
            f"sensors: expected a preset name, a navlib.sensors SensorSpec/ImuSpec with an IMU, "
            f"or a mapping with {list(NOISE_KEYS)}; got {type(sensors).__name__}"
        )
    return imu


@cache.memoized(maxsize=16)
def _shipped_preset(name: str):
    """:func:`navlib.sensors.load_preset` of a shipped preset name, read once per process
    (the packaged files do not change while it runs; a design sweep asks for the preset's
    sigmas at every point). A file path is read at every call."""
    return load_preset(name)


def imu_noise_densities(sensors=None) -> dict:
    """Noise densities (SI, per axis) for the 18 channels from a sensor spec.

    Parameters
    ----------
    sensors : None, str, navlib.sensors.SensorSpec / ImuSpec, or mapping
        ``None`` takes the preset ``motionpak_tactical`` (docs/assumptions.md, excitability.md §5
        values); a string names a preset of :func:`navlib.sensors.load_preset`; a mapping gives the
        keys of :data:`NOISE_KEYS` directly (SI units).

    Returns
    -------
    dict
        :data:`NOISE_KEYS` -> ndarray (3,).

    Notes
    -----
    The model's parameters are Brownian (España Eq. 3). A preset's Gauss-Markov bias drift
    (sigma, tau) is folded into the random-walk density as ``sqrt(rw^2 + 2 sigma^2 / tau)``,
    the density of its driving noise (its decay over the 86 s flight is neglected).
    """
    spec = _imu_spec(sensors)
    if isinstance(spec, Mapping):
        reject_unknown(spec, NOISE_KEYS, "sensors")
        missing = [k for k in NOISE_KEYS if k not in spec]
        if missing:
            raise NavlibInputError(f"sensors: missing noise density key(s) {missing}")
        return {k: _per_axis(spec[k], f"sensors[{k!r}]") for k in NOISE_KEYS}
    gyro, acc = spec.gyro, spec.accel

    def bias_rw(triad):
        markov = (2.0 * triad.bias_markov_sigma**2 / triad.bias_markov_tau
                  if np.isfinite(triad.bias_markov_tau) else 0.0)
        return np.sqrt(triad.bias_random_walk**2 + markov)

    values = {
        "arw_rad_sqrt_s": gyro.noise_density, "vrw_m_s_sqrt_s": acc.noise_density,
        "bg_rw_rad_s_sqrt_s": bias_rw(gyro), "ba_rw_m_s2_sqrt_s": bias_rw(acc),
        "sg_rw_per_sqrt_s": gyro.scale_factor_random_walk,
        "sa_rw_per_sqrt_s": acc.scale_factor_random_walk,
    }
    return {k: _per_axis(v, f"sensors.{k}") for k, v in values.items()}


def parameter_sigmas(sensors=None) -> dict:
    """Initial sigmas of the 12 IMU parameters (edge units) from a sensor spec's turn-on
    values: ``sigma_bg_deg_s``, ``sigma_ba_m_s2``, ``sigma_sg_ppm``, ``sigma_sa_ppm``.

    A mapping of noise densities carries none: the :data:`P0_DEFAULTS` values are returned.
    A zero turn-on value in a preset falls back to the default too (P0 must be definite).
    """
    spec = _imu_spec(sensors)
    keys = ("sigma_bg_deg_s", "sigma_ba_m_s2", "sigma_sg_ppm", "sigma_sa_ppm")
    if isinstance(spec, Mapping):
        return {k: P0_DEFAULTS[k] for k in keys}
    values = (spec.gyro.bias / units.DEG, spec.accel.bias, spec.gyro.scale_factor / units.PPM,
              spec.accel.scale_factor / units.PPM)
    return {k: float(v) if v > 0 else P0_DEFAULTS[k] for k, v in zip(keys, values, strict=True)}


def ecef21_jacobians(position, C_b_e, f_b, w_ib_b, attitude_error: str = "ecef"):
    """Dynamics ``A`` (N, 21, 21) and noise input ``G`` (N, 21, 18) along reference samples.

    ``A = [[A_kin, B_kin B_pi], [0, 0]]`` (Eq. 24 as corrected in docs/assumptions.md A4, A5, A7)
    and ``G = blockdiag(B_kin, I_12)`` (docs/assumptions.md A6), vectorised over samples.

    Parameters
    ----------
    position : ndarray (N, 3)
        Reference ECEF position, m.
    C_b_e : ndarray (N, 3, 3)
        Reference body -> ECEF rotation.
    f_b, w_ib_b : ndarray (N, 3)
        Measured (reference) specific force, m/s^2, and inertial rate, rad/s, body axes.
    attitude_error : {"ecef", "body"}
        Attitude-error definition (docs/assumptions.md A4 (b) or (a)).
    """
    if attitude_error not in ATTITUDE_ERRORS:
        raise NavlibInputError(
            f"attitude_error: expected one of {ATTITUDE_ERRORS}, got {attitude_error!r}"
        )
    n_samples = len(position)
    A = np.zeros((n_samples, 21, 21))
    G = np.zeros((n_samples, 21, 18))
    eye = np.eye(3)
    omega = earth.EARTH_RATE_ECEF
    # position and velocity rows (Eq. 1 linearised)
    A[:, 0:3, 3:6] = eye
    A[:, 3:6, 0:3] = earth.gravity_jacobian_ecef(position)
    A[:, 3:6, 3:6] = -2.0 * skew(omega)
    # accelerometer errors through C_hat: df = -b_a - diag(f_hat) s_a (spec A7)
    A[:, 3:6, 12:15] = -C_b_e
    A[:, 3:6, 18:21] = -C_b_e * f_b[:, None, :]
    G[:, 3:6, 0:3] = C_b_e
    if attitude_error == "ecef":
        f_e = np.einsum("nij,nj->ni", C_b_e, f_b)
        A[:, 3:6, 6:9] = -skew(f_e)
        A[:, 6:9, 6:9] = -skew(omega)
        A[:, 6:9, 9:12] = -C_b_e
        A[:, 6:9, 15:18] = -C_b_e * w_ib_b[:, None, :]
        G[:, 6:9, 3:6] = C_b_e
    else:
        A[:, 3:6, 6:9] = -C_b_e @ skew(f_b)
        A[:, 6:9, 6:9] = -skew(w_ib_b)
        A[:, 6:9, 9:12] = -eye
        A[:, 6:9, 15:18] = -eye * w_ib_b[:, None, :]
        G[:, 6:9, 3:6] = eye
    G[:, 9:21, 6:18] = np.eye(12)
    return A, G


def ecef21(trajectory, sensors=None, *, attitude_error: str = "ecef", gnss_sigma_m: float = 5.0,
           sigma_p0_m: float = 30.0, sigma_v0_m_s: float = 3.0, sigma_theta0_deg: float = 1.0,
           sigma_bg_deg_s: float | None = None, sigma_ba_m_s2: float | None = None,
           sigma_sg_ppm: float | None = None, sigma_sa_ppm: float | None = None
           ) -> LinearModel:
    """The 21-state ECEF error model along ``trajectory`` at its IMU rate.

    Parameters
    ----------
    trajectory : navlib.trajectory.Trajectory
        Reference trajectory (``chi_r``; perfect instruments, so ``f_hat = f^b`` and
        ``omega_hat = omega_ib^b``).
    sensors : None, str, IMU spec or mapping
        Source of the noise densities (see :func:`imu_noise_densities`); default the
        ``motionpak_tactical`` preset (docs/assumptions.md, excitability.md §5, assumed values).
    attitude_error : {"ecef", "body"}
        Attitude-error frame (docs/assumptions.md A4): ECEF ``psi`` (default) or body ``dtheta``.
        The state names ``theta_x..z`` are then ECEF-axis or body-axis components.
    gnss_sigma_m : float
        GNSS position standard deviation per ECEF axis, ``R = sigma^2 I3`` (assumed 5 m).
    sigma_p0_m, sigma_v0_m_s, sigma_theta0_deg : float
        Initial standard deviations of position (30 m), velocity (3 m/s) and attitude
        (1 deg per axis), docs/assumptions.md, excitability.md §5 [A].
    sigma_bg_deg_s, sigma_ba_m_s2, sigma_sg_ppm, sigma_sa_ppm : float, optional
        Initial standard deviations of the IMU parameters; None takes the sensor spec's
        turn-on values (:func:`parameter_sigmas`; the default preset holds the §5 values
        0.05 deg/s, 0.02 m/s^2, 5000 ppm, 1000 ppm). ``P0`` is diagonal (the paper:
        "normally diagonal").

    Returns
    -------
    LinearModel
        ``A`` (N, 21, 21), ``G`` (N, 21, 18), ``Qc`` (18, 18), ``H`` (3, 21), ``R`` (3, 3),
        ``P0`` (21, 21), ``t`` the trajectory times, ``parameters`` every assumed value.
    """
    for attr in ("t", "position", "specific_force", "angular_rate", "attitude"):
        if not hasattr(trajectory, attr):
            raise NavlibInputError(f"trajectory: expected a navlib Trajectory (no {attr!r})")
    parts = _constant_parts(sensors, attitude_error, gnss_sigma_m, {
        "sigma_p0_m": sigma_p0_m, "sigma_v0_m_s": sigma_v0_m_s,
        "sigma_theta0_deg": sigma_theta0_deg, "sigma_bg_deg_s": sigma_bg_deg_s,
        "sigma_ba_m_s2": sigma_ba_m_s2, "sigma_sg_ppm": sigma_sg_ppm,
        "sigma_sa_ppm": sigma_sa_ppm})
    A, G = ecef21_jacobians(trajectory.position, trajectory.C_b_e(),
                            trajectory.specific_force, trajectory.angular_rate, attitude_error)
    parameters = {**parts["parameters"], "imu_rate_hz": float(trajectory.rate_hz)}
    return LinearModel(
        state_names=STATE_NAMES, A=A, G=G, Qc=parts["Qc"], H=parts["H"], R=parts["R"],
        t=np.asarray(trajectory.t, dtype=float), P0=parts["P0"],
        measurement_names=("gnss_x", "gnss_y", "gnss_z"),
        noise_names=NOISE_NAMES, name=f"ecef21 ({attitude_error} attitude error)",
        parameters=parameters,
    )


def _constant_parts(sensors, attitude_error: str, gnss_sigma_m, sigmas: Mapping) -> dict:
    """``Qc``, ``H``, ``R``, ``P0`` and the assumed values of :func:`ecef21` (no trajectory)."""
    if attitude_error not in ATTITUDE_ERRORS:
        raise NavlibInputError(
            f"attitude_error: expected one of {ATTITUDE_ERRORS}, got {attitude_error!r}"
        )
    P0, p0 = _initial_covariance({k: v for k, v in sigmas.items() if v is not None}, "ecef21",
                                 sensors)
    gnss_sigma_m = finite_scalar(gnss_sigma_m, "gnss_sigma_m", 0.0, low_open=True)
    noise = imu_noise_densities(sensors)
    psd = np.concatenate([noise[k] for k in ("vrw_m_s_sqrt_s", "arw_rad_sqrt_s",
                                             "bg_rw_rad_s_sqrt_s", "ba_rw_m_s2_sqrt_s",
                                             "sg_rw_per_sqrt_s", "sa_rw_per_sqrt_s")]) ** 2
    H = np.zeros((3, 21))
    H[:, 0:3] = np.eye(3)
    parameters = {
        "attitude_error": attitude_error,
        "gnss_sigma_m": gnss_sigma_m,
        **p0,
        **{k: v.tolist() for k, v in noise.items()},
        "sensors": sensors if isinstance(sensors, str) else
        (DEFAULT_SENSORS if sensors is None else "noise densities" if isinstance(sensors, Mapping)
         else getattr(sensors, "name", type(sensors).__name__)),
        "imu_inverse_model": "f = (I + diag s_a)^-1 (f_hat - b_a), likewise omega (spec A7)",
        "gravity": "normal gravity (J2 + centrifugal) and its Jacobian (spec A5)",
        "noise_channels": "18: acc/gyro white noise + random walks of b_g, b_a, s_g, s_a (A6)",
    }
    return {"Qc": np.diag(psd), "H": H, "R": gnss_sigma_m**2 * np.eye(3), "P0": P0,
            "parameters": parameters}


def _initial_covariance(sigmas: Mapping, where: str, sensors=None):
    reject_unknown(sigmas, P0_DEFAULTS, where)
    defaults = {**P0_DEFAULTS, **parameter_sigmas(sensors)}
    p0 = {k: finite_scalar(sigmas.get(k, v), k, 0.0, low_open=True)
          for k, v in defaults.items()}
    sigma0 = np.repeat([
        p0["sigma_p0_m"], p0["sigma_v0_m_s"], p0["sigma_theta0_deg"] * units.DEG,
        p0["sigma_bg_deg_s"] * units.DEG, p0["sigma_ba_m_s2"],
        p0["sigma_sg_ppm"] * units.PPM, p0["sigma_sa_ppm"] * units.PPM,
    ], 3)
    return np.diag(sigma0**2), p0


def initial_covariance(sensors=None, **sigmas) -> np.ndarray:
    """Diagonal ``P0`` (21, 21) in SI from edge-unit sigmas (keys of :data:`P0_DEFAULTS`).

    The same ``P0`` :func:`ecef21` builds: IMU-parameter sigmas default to the sensor spec's
    turn-on values (:func:`parameter_sigmas`), the others to :data:`P0_DEFAULTS`. Use it to
    change ``P0`` of a discretised model without rebuilding it
    (``dataclasses.replace(discrete, P0=initial_covariance(...))``).

    Parameters
    ----------
    sensors : None, str, IMU spec or mapping, optional
        Source of the IMU-parameter sigmas (as :func:`ecef21`).
    **sigmas
        Sigmas in edge units, keys of :data:`P0_DEFAULTS`.

    Returns
    -------
    numpy.ndarray
        ``P0``, (21, 21).
    """
    return _initial_covariance(sigmas, "initial_covariance", sensors)[0]


def ecef21_at_epochs(trajectory, gnss_rate_hz: float = 1.0, method: str = "series",
                     hold: str = "mean", sensors=None, max_step_s: float | None = None,
                     epochs=None, **model_options) -> DiscreteModel:
    """The 21-state model discretised to the GNSS epochs of ``trajectory`` (cached).

    Builds the model of :func:`ecef21` along the trajectory and chains the steps to epochs
    ``gnss_rate_hz`` apart (docs/assumptions.md A8: 100 IMU steps per 1 Hz epoch). The build streams
    over blocks of epochs (at most :data:`STREAM_SAMPLES` trajectory samples at a time), so its
    memory does not grow with the flight's length: only the per-epoch ``F``, ``Q`` are kept.
    Results are cached in memory on the trajectory object's identity and the options, so that
    widgets changing only the metric settings (eta, nu, segments) never rebuild the model,
    and on disk on the trajectory's content (:mod:`navlib.cache`), so that other notebooks
    and later runs do not either.

    Parameters
    ----------
    trajectory : Trajectory
    gnss_rate_hz : float
        GNSS rate; epochs are the samples nearest a regular grid (``trajectory.at_rate``).
    method, hold
        See :meth:`navlib.models.LinearModel.discretize`; the defaults (series Van Loan,
        two-sample mean hold) are fast and second order in the IMU step.
    sensors : None, str or mapping
        Sensor preset name or noise densities (see :func:`imu_noise_densities`).
    max_step_s : float, optional
        Longest model step (decimation). None: every IMU step, as above. Otherwise the IMU
        steps are grouped ``k = floor(max_step_s / dt)`` at a time (never across an epoch)
        and the model is evaluated at the group ends only: each group is one step whose
        ``A`` and ``W = G Qc G'`` are the means of the two ends (trapezoidal rule, second
        order in the group length; the fitted trajectories are smooth at that scale). On
        the sounding rocket at 1 Hz epochs, 0.02 s steps change ``F`` by 3e-4 and ``Q`` by
        4e-3 relative (``benchmarks/bench_assess.py`` prints both).
    epochs : sequence of int, optional
        Indices of the trajectory samples that are the epochs (increasing, at least 2),
        e.g. :func:`epoch_samples` on a log whose IMU rate changes during the flight, where
        a grid in samples is not one in time. None: ``trajectory.at_rate(gnss_rate_hz)``.
    **model_options
        Passed to :func:`ecef21` (``attitude_error``, ``gnss_sigma_m``, P0 sigmas).
    """
    gnss_rate_hz = finite_scalar(gnss_rate_hz, "gnss_rate_hz", 0.0, low_open=True)
    if max_step_s is not None:
        max_step_s = finite_scalar(max_step_s, "max_step_s", 0.0, low_open=True)
    if isinstance(sensors, Mapping):  # frozen to a hashable key for the cache
        sensors = tuple(sorted((k, tuple(_per_axis(v, f"sensors[{k!r}]")))
                               for k, v in sensors.items()))
    elif sensors is not None and not isinstance(sensors, str):
        raise NavlibInputError("sensors: ecef21_at_epochs caches on a preset name or a "
                               "mapping of noise densities; got "
                               f"{type(sensors).__name__}")
    key = tuple(sorted(model_options.items()))
    try:
        hash(key)
    except TypeError as exc:
        raise NavlibInputError("model options must be plain numbers or strings") from exc
    if epochs is not None:
        epochs = _checked_epochs(epochs, len(trajectory.t))
    return _cached_chain(trajectory, gnss_rate_hz, method, hold, sensors, key, max_step_s,
                         epochs)


def _checked_epochs(epochs, n_samples: int) -> tuple:
    """``epochs`` as a tuple of sample indices (hashable, for the cache), or an error."""
    arr = np.asarray(epochs)
    if (arr.ndim != 1 or arr.size < 2 or not np.issubdtype(arr.dtype, np.integer)
            or arr[0] < 0 or arr[-1] >= n_samples or np.any(np.diff(arr) <= 0)):
        raise NavlibInputError(f"epochs: expected at least 2 increasing sample indices in "
                               f"[0, {n_samples}), got {epochs!r:.80}")
    return tuple(int(k) for k in arr)


def epoch_samples(t, rate_hz: float) -> np.ndarray:
    """Indices of the samples of ``t`` nearest the times ``t[0] + k / rate_hz`` (each once).

    The epochs of a regular grid in time. On a log sampled at a constant rate that is a
    multiple of ``rate_hz`` they are those of ``Trajectory.at_rate``; on a log whose rate
    changes (an AltOS export: 100 Hz in boost, 10 Hz in descent) they stay ``1 / rate_hz``
    apart where ``at_rate``, every so many samples, would drift to 10 times that.

    Parameters
    ----------
    t : numpy.ndarray
        Sample times, s.
    rate_hz : float
        Epoch rate, Hz.
    """
    t = np.asarray(t, dtype=float)
    rate_hz = finite_scalar(rate_hz, "rate_hz", 0.0, low_open=True)
    grid = t[0] + np.arange(int(np.floor((t[-1] - t[0]) * rate_hz + 1e-9)) + 1) / rate_hz
    k = np.clip(np.searchsorted(t, grid), 1, t.size - 1)
    k -= (grid - t[k - 1]) <= (t[k] - grid)
    return np.unique(k)


STREAM_SAMPLES = 1_000
"""Samples per block of :func:`ecef21_at_epochs` (docs/performance.md, "Model blocks")."""


@cache.memoized(maxsize=32)
def _cached_chain(trajectory, gnss_rate_hz, method, hold, sensors, key, max_step_s,
                  epochs=None):
    """:func:`_chain` kept per trajectory object in memory (and on disk by its content)."""
    discrete = _chain(trajectory, gnss_rate_hz, method, hold, sensors, key, max_step_s,
                      epochs)
    for arr in (discrete.F, discrete.Q, discrete.H, discrete.R, discrete.P0, discrete.t):
        arr.flags.writeable = False  # shared by every caller of the cache
    return discrete


@cache.cached
def _chain(trajectory, gnss_rate_hz, method, hold, sensors, key, max_step_s, epochs=None):
    """The streamed build of :func:`ecef21_at_epochs` (arguments validated and frozen)."""
    if isinstance(sensors, tuple):
        sensors = dict(sensors)
    options = dict(key)
    reject_unknown(options, ("attitude_error", "gnss_sigma_m", *P0_DEFAULTS), "ecef21")
    attitude_error = options.pop("attitude_error", "ecef")
    parts = _constant_parts(sensors, attitude_error, options.pop("gnss_sigma_m", 5.0),
                            options)
    if hold not in HOLDS:
        raise NavlibInputError(f"hold: expected one of {HOLDS}, got {hold!r}")
    t = np.asarray(trajectory.t, dtype=float)
    epochs = trajectory.at_rate(gnss_rate_hz) if epochs is None else np.asarray(epochs)
    if epochs.size < 2:
        raise NavlibInputError(f"gnss_rate_hz: {gnss_rate_hz:g} Hz gives fewer than 2 epochs "
                               f"over the {t[-1] - t[0]:.3g} s trajectory")
    stride = 1 if max_step_s is None else max(int(max_step_s * trajectory.rate_hz + 1e-9), 1)
    # step boundaries: every ``stride`` samples inside each epoch interval, and the epochs
    bounds = [np.arange(a, b, stride) for a, b in pairwise(epochs)]
    bounds = np.concatenate([*bounds, epochs[-1:]])
    at_epoch = np.searchsorted(bounds, epochs)
    C_b_e = trajectory.attitude
    F, Q = [], []
    e0 = 0
    while e0 < epochs.size - 1:                     # blocks of whole epoch intervals
        e1 = e0 + 1
        while e1 < epochs.size - 1 and epochs[e1 + 1] - epochs[e0] <= STREAM_SAMPLES:
            e1 += 1
        b = bounds[at_epoch[e0]:at_epoch[e1] + 1]
        # the model is needed at the step boundaries only (every sample when stride is 1)
        A, G = ecef21_jacobians(trajectory.position[b], C_b_e[b].as_matrix(),
                                trajectory.specific_force[b], trajectory.angular_rate[b],
                                attitude_error)
        # "series": the compiled sparse steps (navlib.sparse_discretize; 58 of 441 entries
        # of A non-zero on the rocket), equal to discretize_steps' series to rounding
        steps = discretize_window if method == "series" else discretize_steps
        F_steps, Q_steps = steps(*_held(A, G, parts["Qc"], hold, stride > 1), np.diff(t[b]),
                                 method)
        del A, G
        Fi, Qi = chain(F_steps, Q_steps, at_epoch[e0:e1 + 1] - at_epoch[e0])
        F.append(Fi)
        Q.append(Qi)
        e0 = e1
    n_ep = epochs.size
    return DiscreteModel(t[epochs], np.concatenate(F), np.concatenate(Q),
                         np.broadcast_to(parts["H"], (n_ep, 3, 21)),
                         np.broadcast_to(parts["R"], (n_ep, 3, 3)), STATE_NAMES,
                         ("gnss_x", "gnss_y", "gnss_z"), parts["P0"])


def _held(A, G, Qc, hold, decimated):
    """``A``, ``G``, ``Qc`` held over each step (``W = G Qc G'``): the left end, or the mean
    of the two ends (trapezoidal first Magnus term). Over one IMU step ``G`` is averaged (as
    :meth:`LinearModel.discretize`); over a decimated step ``W`` is, by ``G = [G_0, G_1]``
    with ``Qc / 2`` on both diagonal blocks (a mean ``G`` rotating within the step shrinks)."""
    if hold == "left":
        return A[:-1], G[:-1], Qc
    A_bar = 0.5 * (A[:-1] + A[1:])
    if not decimated:
        return A_bar, 0.5 * (G[:-1] + G[1:]), Qc
    q = Qc.shape[0]
    both = np.zeros((2 * q, 2 * q))
    both[:q, :q] = both[q:, q:] = 0.5 * Qc
    return A_bar, np.concatenate([G[:-1], G[1:]], axis=2), both


_GROUP_NAMES = ("position", "velocity", "attitude", "bg", "ba", "sg", "sa")


@dataclass(frozen=True, eq=False)
class Ecef21ErrorState(ErrorState):
    """The 21-state ECEF model as the error-state model of :func:`navlib.filters.ekf`.

    Errors are ``truth - estimate`` (``nav_sign = +1``, España et al. 2019), the attitude
    error ECEF or body (docs/assumptions.md A4); the 12 IMU parameters (``bg, ba, sg, sa``) are
    random walks (no decay) and every state is reset after feedback. Measurements: GNSS position,
    and GNSS velocity when its sigma is given. Jacobians: :func:`ecef21_jacobians`, discretised
    by the batched matrix exponential by default. Build with :meth:`build`.
    """

    @classmethod
    def build(cls, sensors=None, *, attitude_error: str = "ecef", gnss_sigma_m: float = 5.0,
              gnss_velocity_sigma: float | None = None, **sigmas) -> Ecef21ErrorState:
        """The model of :func:`ecef21` (same keywords), plus GNSS velocity updates with
        sigma ``gnss_velocity_sigma`` (m/s) when given.

        Parameters
        ----------
        sensors : None, str, IMU spec or mapping, optional
            As :func:`ecef21`.
        attitude_error : {"ecef", "body"}, optional
            Attitude-error frame.
        gnss_sigma_m : float, optional
            GNSS position sigma per ECEF axis, m.
        gnss_velocity_sigma : float or None, optional
            GNSS velocity sigma per axis, m/s; None: no velocity updates.
        **sigmas
            Initial sigmas, keywords of :func:`ecef21`.
        """
        parts = _constant_parts(sensors, attitude_error, gnss_sigma_m, sigmas)
        rows = {"gnss_pos": MeasurementRows(("gnss_x", "gnss_y", "gnss_z"),
                                            parts["parameters"]["gnss_sigma_m"])}
        if gnss_velocity_sigma is not None:
            rows["gnss_vel"] = MeasurementRows(
                ("gnss_vx", "gnss_vy", "gnss_vz"),
                finite_scalar(gnss_velocity_sigma, "gnss_velocity_sigma", 0.0, low_open=True))
        groups = {g: np.arange(3 * i, 3 * i + 3) for i, g in enumerate(_GROUP_NAMES)}
        return cls(name="ecef21", state_names=STATE_NAMES, Qc=parts["Qc"], P0=parts["P0"],
                   groups=groups, parameters=_GROUP_NAMES[3:], reset=np.ones(21, dtype=bool),
                   decay={g: np.zeros(3) for g in _GROUP_NAMES[3:]}, nav_sign=1.0,
                   attitude_frame=attitude_error, measurements=rows, default_method="expm",
                   settings=parts["parameters"])

    @classmethod
    def from_options(cls, options: dict, *, gnss_velocity_sigma: float | None = None,
                     sensors=None, **_) -> Ecef21ErrorState:
        """:meth:`build` from the EKF's keywords: ``options`` are :func:`ecef21`'s, whose
        ``sensors`` default to the simulated ``sensors`` preset when known (the launcher's
        solution, biases and bias model do not apply).

        Parameters
        ----------
        options : dict
            Keywords of :func:`ecef21`.
        gnss_velocity_sigma : float or None, optional
            GNSS velocity sigma per axis, m/s.
        sensors : optional
            The simulated sensors preset, the default of ``options["sensors"]``.
        **_
            The EKF's other keywords, ignored.
        """
        options = dict(options)
        if isinstance(sensors, str):
            options.setdefault("sensors", sensors)
        return cls.build(gnss_velocity_sigma=gnss_velocity_sigma, **options)

    def jacobians(self, nominal):
        """:func:`ecef21_jacobians` along the nominal trajectory and compensated IMU, by the
        compiled :func:`ecef21_jacobians_kernel` (the same entries to
        rounding)."""
        k = nominal.t.size
        A, G = np.empty((k, 21, 21)), np.empty((k, 21, 18))
        ecef21_jacobians_kernel(*(np.require(a, float, "CW") for a in (
            nominal.position, nominal.C_b_e, nominal.f_b, nominal.w_ib_b)),
            self.attitude_frame == "body", A, G)
        return A, G
