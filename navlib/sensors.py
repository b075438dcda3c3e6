"""Sensor specifications (TOML presets in ``data/sensors/``) and IMU / GNSS error simulation.

Measurement model (spec excitability.md A1, A7), per triad, body axes::

    f_meas(t) = (I + diag(s_a(t)) + M_a) f(t) + b_a(t) + n_a(t)
    w_meas(t) = (I + diag(s_g(t)) + M_g) w(t) + b_g(t) + n_g(t)

* ``s`` scale factors: a turn-on value ``s0 ~ N(0, sigma_s^2)`` plus an optional random
  walk (spec Eq. 3 models parameters as Brownian motion).
* ``M`` misalignment / non-orthogonality: constant, zero diagonal, off-diagonal entries
  ``~ N(0, sigma_m^2)`` (small-angle).
* ``b(t) = b0 + b_markov(t) + b_rw(t)``: turn-on bias ``b0 ~ N(0, sigma_b^2)``, a
  first-order Gauss–Markov drift with steady-state sigma and time constant ``tau`` (started
  in its stationary distribution) and a random walk; any of them may be zero.
* ``n`` white noise of one-sided density ``N`` (ARW in rad/s/sqrt(Hz) = rad/sqrt(s), VRW in
  m/s^2/sqrt(Hz)); point samples at step ``dt`` have ``sigma = N / sqrt(dt)`` so that the
  integrated angle/velocity error grows as ``N sqrt(t)``.

The inverse model used by the error-state filters (spec A7),
``f = (I + diag s_a)^-1 (f_meas - b_a)``, is this one to first order. Discretisation is
exact: Gauss–Markov ``b_{k+1} = e^{-dt/tau} b_k + sigma sqrt(1 - e^{-2 dt/tau}) w_k``,
random walk ``b_{k+1} = b_k + q sqrt(dt) w_k``.

Preset files carry unit-suffixed keys (``gyro_bias_deg_h``, ``accel_vrw_ug_sqrt_hz``...);
:data:`_UNITS` lists every accepted spelling, all converted through :mod:`navlib.units`.
Each preset records its ``source`` and the keys whose values are ``assumed``.

Aiding sensors of the EKF simulations: :func:`simulate_attitude_sensor` (generic attitude
reference) and :class:`ReferenceTrajectory` (the launcher's reference-trajectory attitudes).
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field, fields
from pathlib import Path

import numpy as np
import pandas as pd

from navlib import units
from navlib._validation import finite_array, finite_scalar, reject_unknown
from navlib.allan import (  # noqa: F401 - re-exported: navlib.sensors.fit_allan (spec api.md)
    allan_deviation,
    fit_allan,
    write_allan_preset,
)
from navlib.errors import NavlibInputError
from navlib.outliers import as_outliers, channel_profile
from navlib.resources import data_dir
from navlib.rotations import exp_so3, log_so3

PRESET_DIR = data_dir() / "sensors"
"""Folder holding the ``*.toml`` sensor presets."""

# --- accepted keys and units ---------------------------------------------------------------

_GYRO_RATE = {"rad_s": 1.0, "deg_s": units.DEG, "deg_h": units.DEG_PER_HOUR}
_ACCEL = {"m_s2": 1.0, "mg": units.MG, "ug": units.UG}
_ANGLE = {"rad": 1.0, "deg": units.DEG}
_SCALE = {"ppm": units.PPM}
_TIME = {"s": 1.0}
_SCALE_RW = {"per_sqrt_s": 1.0, "ppm_sqrt_s": units.PPM}

_TRIAD_UNITS = {
    "gyro": {
        "bias": _GYRO_RATE,
        "scale_factor": _SCALE,
        "misalignment": _ANGLE,
        "arw": {"rad_sqrt_s": 1.0, "deg_sqrt_h": units.DEG_PER_SQRT_HOUR,
                "deg_sqrt_s": units.DEG, "deg_h_sqrt_hz": units.DEG_PER_HOUR_PER_SQRT_HZ},
        "bias_markov": _GYRO_RATE,
        "bias_markov_tau": _TIME,
        "bias_rw": {"rad_s_sqrt_s": 1.0},
        "scale_factor_rw": _SCALE_RW,
        "range": _GYRO_RATE,
    },
    "accel": {
        "bias": _ACCEL,
        "scale_factor": _SCALE,
        "misalignment": _ANGLE,
        "vrw": {"m_s2_sqrt_hz": 1.0, "m_s_sqrt_h": units.M_S_PER_SQRT_HOUR,
                "ug_sqrt_hz": units.UG_PER_SQRT_HZ, "mg_sqrt_hz": units.MG_PER_SQRT_HZ},
        "bias_markov": _ACCEL,
        "bias_markov_tau": _TIME,
        "bias_rw": {"m_s2_sqrt_s": 1.0},
        "scale_factor_rw": _SCALE_RW,
        "range": {**_ACCEL, "g": units.G0},
    },
}
_TRIAD_FIELD = {  # TOML field -> TriadSpec attribute
    "bias": "bias", "scale_factor": "scale_factor", "misalignment": "misalignment",
    "arw": "noise_density", "vrw": "noise_density", "bias_markov": "bias_markov_sigma",
    "bias_markov_tau": "bias_markov_tau", "bias_rw": "bias_random_walk",
    "scale_factor_rw": "scale_factor_random_walk", "range": "range",
}
_GNSS_UNITS = {
    "position_sigma": {"m": 1.0},
    "velocity_sigma": {"m_s": 1.0},
    "position_bias_markov": {"m": 1.0},
    "position_bias_tau": _TIME,
}
_ATTITUDE_UNITS = {"sigma": _ANGLE}


def _key_table(prefix_units: dict[str, dict[str, float]], prefix: str = "") -> dict:
    """Full TOML key -> (field, factor to SI)."""
    return {f"{prefix}{name}_{suffix}": (f"{prefix}{name}", factor)
            for name, suffixes in prefix_units.items() for suffix, factor in suffixes.items()}


_UNITS = {
    "imu": {**_key_table(_TRIAD_UNITS["gyro"], "gyro_"),
            **_key_table(_TRIAD_UNITS["accel"], "accel_"), "rate_hz": ("rate_hz", 1.0)},
    "gnss": {**_key_table(_GNSS_UNITS), "rate_hz": ("rate_hz", 1.0)},
    "attitude_sensor": _key_table(_ATTITUDE_UNITS),
}
"""Section -> accepted key -> (field, factor to SI). The one table of preset spellings."""

_TOP_LEVEL = {"name", "source", "notes", "assumed", "imu", "gnss", "attitude_sensor"}


# --- specifications ---------------------------------------------------------------------------


@dataclass(frozen=True)
class TriadSpec:
    """Error specification of one sensor triad (gyro or accelerometer), SI units.

    Attributes
    ----------
    bias : float
        1-sigma turn-on bias per axis, rad/s or m/s^2.
    scale_factor : float
        1-sigma turn-on scale-factor error, dimensionless.
    misalignment : float
        1-sigma of each off-diagonal entry of the misalignment matrix, rad.
    noise_density : float
        White-noise density (ARW rad/sqrt(s), VRW m/s^2/sqrt(Hz)).
    bias_markov_sigma, bias_markov_tau : float
        Steady-state sigma and time constant (s) of the Gauss–Markov bias drift.
    bias_random_walk : float
        Bias random-walk density, rad/s/sqrt(s) or m/s^2/sqrt(s).
    scale_factor_random_walk : float
        Scale-factor random-walk density, 1/sqrt(s).
    range : float or None
        Measurement range: the largest magnitude one axis reports, rad/s or m/s^2 (preset
        keys ``gyro_range_deg_s`` / ``_rad_s``, ``accel_range_g`` / ``_m_s2``); None when
        the preset does not say. Samples at it are saturated (:mod:`navlib.quality`).
    """

    bias: float = 0.0
    scale_factor: float = 0.0
    misalignment: float = 0.0
    noise_density: float = 0.0
    bias_markov_sigma: float = 0.0
    bias_markov_tau: float = np.inf
    bias_random_walk: float = 0.0
    scale_factor_random_walk: float = 0.0
    range: float | None = None

    def __post_init__(self):
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name == "range":
                if value is not None and not (np.isfinite(value) and value > 0):
                    raise NavlibInputError(f"range: must be a finite number > 0, got {value}")
            elif f.name == "bias_markov_tau":
                if not value > 0:
                    raise NavlibInputError(f"bias_markov_tau: must be > 0 s, got {value}")
            elif not (np.isfinite(value) and value >= 0):
                raise NavlibInputError(f"{f.name}: must be a finite number >= 0, got {value}")
        if self.bias_markov_sigma > 0 and not np.isfinite(self.bias_markov_tau):
            raise NavlibInputError("bias_markov_tau: needed (finite, s) when "
                                   "bias_markov_sigma > 0")


@dataclass(frozen=True)
class ImuSpec:
    """Gyro and accelerometer triads plus the nominal sampling rate (Hz, informative)."""

    gyro: TriadSpec = field(default_factory=TriadSpec)
    accel: TriadSpec = field(default_factory=TriadSpec)
    rate_hz: float | None = None


@dataclass(frozen=True)
class GnssSpec:
    """GNSS position/velocity errors: white noise per ECEF axis plus an optional
    Gauss–Markov position bias (steady-state sigma, time constant in s)."""

    position_sigma: float = 0.0
    velocity_sigma: float = 0.0
    position_bias_markov: float = 0.0
    position_bias_tau: float = np.inf
    rate_hz: float = 1.0

    def __post_init__(self):
        for name in ("position_sigma", "velocity_sigma", "position_bias_markov"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0):
                raise NavlibInputError(f"{name}: must be a finite number >= 0, got {value}")
        if not self.position_bias_tau > 0:
            raise NavlibInputError(f"position_bias_tau: must be > 0 s, got "
                                   f"{self.position_bias_tau}")
        if self.position_bias_markov > 0 and not np.isfinite(self.position_bias_tau):
            raise NavlibInputError("position_bias_tau: needed (finite, s) when "
                                   "position_bias_markov > 0")
        if not (np.isfinite(self.rate_hz) and self.rate_hz > 0):
            raise NavlibInputError(f"rate_hz: must be > 0, got {self.rate_hz}")


@dataclass(frozen=True)
class SensorSpec:
    """A sensor preset: IMU, GNSS and attitude-sensor errors with their provenance.

    Attributes
    ----------
    name, source, notes : str
        Identifier, bibliographic provenance and modelling notes.
    imu : ImuSpec or None
    gnss : GnssSpec or None
    attitude_sigma : float or None
        White noise of an attitude reference sensor, rad per axis.
    assumed : tuple of str
        ``section.key`` entries whose values are assumptions, not from the source.
    values : dict
        ``section.key`` -> value as written in the preset (edge units), for display.
    """

    name: str
    source: str
    imu: ImuSpec | None = None
    gnss: GnssSpec | None = None
    attitude_sigma: float | None = None
    assumed: tuple[str, ...] = ()
    notes: str = ""
    values: dict = field(default_factory=dict)

    def to_frame(self) -> pd.DataFrame:
        """One row per preset value: key, value as written, SI value, assumed flag."""
        rows = []
        for key, value in self.values.items():
            section, name = key.split(".", 1)
            _, factor = _UNITS[section][name]
            rows.append({"section": section, "key": name, "value": value,
                         "value_si": value * factor, "assumed": key in self.assumed})
        return pd.DataFrame(rows, columns=["section", "key", "value", "value_si", "assumed"])


# --- presets -------------------------------------------------------------------------------


def list_presets() -> list[str]:
    """Names of the presets shipped in ``data/sensors/`` (sorted)."""
    return sorted(p.stem for p in PRESET_DIR.glob("*.toml"))


def _preset_path(name_or_path) -> Path:
    text = str(name_or_path)
    path = Path(text)
    if path.suffix == ".toml" or path.parent != Path("."):
        if not path.is_file():
            raise NavlibInputError(f"name_or_path: sensor preset file {text!r} not found")
        return path
    path = PRESET_DIR / f"{text}.toml"
    if not path.is_file():
        raise NavlibInputError(
            f"name_or_path: unknown sensor preset {text!r}; available: {list_presets()}"
        )
    return path


def _parse_section(table, section: str, where: str) -> dict[str, float]:
    """Convert one preset section to ``{field: SI value}``, rejecting unknown keys."""
    if not isinstance(table, dict):
        raise NavlibInputError(f"{where}: [{section}] must be a table")
    accepted = _UNITS[section]
    reject_unknown(table, accepted, f"{where} [{section}]")
    out: dict[str, float] = {}
    for key, value in table.items():
        name, factor = accepted[key]
        if name in out:
            raise NavlibInputError(f"{where} [{section}]: {name} given twice (key {key!r})")
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise NavlibInputError(f"{where} [{section}] {key}: expected a number, got {value!r}")
        out[name] = float(finite_scalar(value, f"{where} [{section}] {key}", low=0.0) * factor)
    return out


def _triad(values: dict[str, float], prefix: str) -> TriadSpec:
    kwargs = {_TRIAD_FIELD[name[len(prefix):]]: v for name, v in values.items()
              if name.startswith(prefix)}
    return TriadSpec(**kwargs)


DEFAULT_IMU_PRESET = "motionpak_tactical"
"""The preset of the España sounding rocket's IMU (spec excitability.md §5): the default of
the 21-state model and of the flight fit."""


def load_preset(name_or_path) -> SensorSpec:
    """Load a sensor preset by name (see :func:`list_presets`) or from a TOML file path.

    Raises
    ------
    NavlibInputError
        Unknown preset or missing file, TOML syntax errors, unknown keys or sections
        (named with the file), negative or non-numeric values, an ``assumed`` entry that
        names no key of the file, or a missing ``source``.
    """
    path = _preset_path(name_or_path)
    where = path.name
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise NavlibInputError(f"{where}: not valid TOML ({exc})") from exc
    reject_unknown(data, _TOP_LEVEL, where)
    source = data.get("source")
    if not isinstance(source, str) or not source.strip():
        raise NavlibInputError(f"{where}: a non-empty 'source' (provenance) string is required")

    values: dict[str, float] = {}
    parsed: dict[str, dict[str, float]] = {}
    for section in ("imu", "gnss", "attitude_sensor"):
        if section in data:
            parsed[section] = _parse_section(data[section], section, where)
            values.update({f"{section}.{k}": v for k, v in data[section].items()})
    if not parsed:
        raise NavlibInputError(f"{where}: needs at least one of [imu], [gnss], "
                               "[attitude_sensor]")

    assumed = data.get("assumed", [])
    if not isinstance(assumed, list) or not all(isinstance(a, str) for a in assumed):
        raise NavlibInputError(f"{where}: 'assumed' must be a list of 'section.key' strings")
    missing = [a for a in assumed if a not in values]
    if missing:
        raise NavlibInputError(f"{where}: 'assumed' names keys not in the file: {missing}")

    try:
        imu = gnss = None
        if "imu" in parsed:
            v = parsed["imu"]
            imu = ImuSpec(gyro=_triad(v, "gyro_"), accel=_triad(v, "accel_"),
                          rate_hz=v.get("rate_hz"))
        if "gnss" in parsed:
            gnss = GnssSpec(**parsed["gnss"])
    except NavlibInputError as exc:
        raise NavlibInputError(f"{where}: {exc}") from exc
    attitude_sigma = parsed.get("attitude_sensor", {}).get("sigma")
    return SensorSpec(name=str(data.get("name", path.stem)), source=source.strip(), imu=imu,
                      gnss=gnss, attitude_sigma=attitude_sigma, assumed=tuple(assumed),
                      notes=str(data.get("notes", "")).strip(), values=values)


# --- simulation ----------------------------------------------------------------------------


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


def gauss_markov(t, sigma: float, tau: float, rng: np.random.Generator, n_axes: int = 3):
    """Stationary first-order Gauss–Markov samples at times ``t`` (exact discretisation).

    ``x_0 ~ N(0, sigma^2)``, ``x_{k+1} = a_k x_k + sigma sqrt(1 - a_k^2) w_k`` with
    ``a_k = exp(-(t_{k+1} - t_k) / tau)``. Returns (N, n_axes).
    """
    t = np.asarray(t, dtype=float)
    w = rng.standard_normal((t.size, n_axes))
    if sigma == 0.0:
        return np.zeros_like(w)
    a = np.exp(-np.diff(t) / tau)
    drive = w.copy()
    drive[1:] *= np.sqrt(1.0 - a * a)[:, None]
    if t.size > 1 and np.allclose(a, a[0], rtol=1e-9, atol=0.0):
        from scipy.signal import lfilter  # here: importing scipy.signal takes about 1 s

        x = lfilter([1.0], [1.0, -a[0]], drive, axis=0)
    else:
        x = np.empty_like(drive)
        x[0] = drive[0]
        for k in range(1, t.size):
            x[k] = a[k - 1] * x[k - 1] + drive[k]
    return sigma * x


def random_walk(t, density: float, rng: np.random.Generator, n_axes: int = 3):
    """Random walk from 0 at ``t[0]`` with density ``q``: increments ``q sqrt(dt) w``."""
    t = np.asarray(t, dtype=float)
    w = rng.standard_normal((t.size, n_axes))
    out = np.zeros_like(w)
    if density > 0.0:
        np.cumsum(density * np.sqrt(np.diff(t))[:, None] * w[1:], axis=0, out=out[1:])
    return out


def white_noise(t, density: float, rng: np.random.Generator, n_axes: int = 3):
    """Point samples of white noise of density ``N``: ``sigma_k = N / sqrt(dt_k)``.

    ``dt_k`` is the sample's step (the following one; the last sample reuses the last step).
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
    Model and discretisation in the module docstring (spec excitability.md A1, A7). Each
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


class ReferenceTrajectory:
    """Reference-trajectory attitudes for the RT pseudo-measurement in EKF simulations.

    The launcher flies the true trajectory ``C(t)``; the on-board reference attitude
    differs from it by the divergence ``d`` (body axes): ``C_ref = C exp(S(d))``, so that
    ``rotvec(C_hat' C_ref) = T_E^B psi + d`` is Beaudoin's eq. (8). ``d`` is the
    ``psi_ref`` block of the closed-loop attitude dynamics of the RT augmentation
    (spec launcher.md §3.4), ``x_a' = M x_a + a1_sign [T_E^B psi; 0] + [0; omega_wind]``
    with ``M`` = ``dynamics`` (10 x 10, :func:`navlib.models.launcher.rt_dynamics_matrix`),
    integrated with the
    paper's Euler steps. It is driven by white wind rates of ``sigma_wind`` rad/s per
    sample and by the **actual** navigation attitude error ``psi`` of the filter that calls
    it (``C = (I + S(psi)) C_nav``: the control steers with the navigation attitude), so
    truth and filter model agree. Outliers on the ``rt`` channels are added to the emitted
    ``d`` only (the stored reference is wrong, the vehicle is not).

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
    1 deg per axis); ``att`` outliers (:mod:`navlib.outliers`) are added to ``n``.

    Returns
    -------
    t : ndarray (K,)
    C_att : ndarray (K, 3, 3)
        Measured body -> ECEF attitudes.
    """
    sigma = finite_scalar(sigma, "sigma", 0.0)
    rng = rng if rng is not None else np.random.default_rng(seed)
    idx = (np.arange(len(trajectory.t)) if rate_hz is None
           else trajectory.at_rate(finite_scalar(rate_hz, "rate_hz", 0.0, low_open=True)))
    t = np.asarray(trajectory.t, dtype=float)[idx]
    noise = sigma * rng.standard_normal((idx.size, 3))
    from navlib.outliers import inject

    noise = inject(noise, t, as_outliers(outliers), "att")
    return t, exp_so3(noise) @ trajectory.attitude[idx].as_matrix()

