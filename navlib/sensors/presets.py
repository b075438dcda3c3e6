"""Sensor specifications and the TOML presets of ``data/sensors/`` that carry them.

Preset files carry unit-suffixed keys (``gyro_bias_deg_h``, ``accel_vrw_ug_sqrt_hz``...);
:data:`_UNITS` lists every accepted spelling, all converted through :mod:`navlib.units`.
Each preset records its ``source`` and the keys whose values are ``assumed``. The error
terms are those of the measurement model of :mod:`navlib.sensors` (docs/assumptions.md A1, A7).
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field, fields
from pathlib import Path

import numpy as np
import pandas as pd

from navlib import units
from navlib._validation import finite_scalar, reject_unknown
from navlib.errors import NavlibInputError
from navlib.resources import data_dir, toml_names, toml_path

__all__ = ["DEFAULT_IMU_PRESET", "PRESET_DIR", "GnssSpec", "ImuSpec", "SensorSpec", "TriadSpec",
           "list_presets", "load_preset"]

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
        the preset does not say. Samples at it are saturated (:mod:`navlib.io.quality`).
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
    return toml_names(PRESET_DIR)


def _preset_path(name_or_path) -> Path:
    return toml_path(PRESET_DIR, name_or_path, "name_or_path", "sensor preset file",
                     "sensor preset")


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
"""The preset of the España sounding rocket's IMU (docs/assumptions.md, excitability.md §5): the
default of the 21-state model and of the flight fit."""


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
