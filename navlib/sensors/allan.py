"""IMU noise terms from a static log: overlapping Allan deviation and the noise-term fit.

:func:`allan_deviation` computes the overlapping Allan deviation of each IMU axis with the
maintained implementation of PyPI ``allantools`` (``oadev`` on rate data, NIST SP 1065
eq. 11). :func:`fit_allan` fits the three classic noise terms to it (IEEE Std 952-1997
Annex C; assumption M5 of ``docs/assumptions.md``)::

    AVAR(tau) = N^2 / tau + (2 ln 2 / pi) B^2 + K^2 tau / 3

``N`` the white-noise density (angle random walk, rad/sqrt(s); velocity random walk,
m/s/sqrt(s)), ``B`` the bias instability (rad/s, m/s^2; the flicker floor of the deviation
is ``0.664 B``) and ``K`` the rate random walk (rad/s/sqrt(s), m/s^2/sqrt(s)). The fit is a
non-negative least squares on the relative error of the Allan variance, each averaging time
weighted by the square root of the number of independent clusters it holds (long averaging
times are noisy). A term is *resolved* when it carries at least half of the fitted variance
at some averaging time of the data; otherwise its value is NaN and ``reason`` says why.
:func:`write_allan_preset` writes the fit as a sensor preset (``data/sensors`` format).
"""

from __future__ import annotations

import json
import math
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.optimize import nnls

from navlib._validation import finite_scalar
from navlib.errors import NavlibInputError
from navlib.resources import data_dir
from navlib.units import DEG, G0, HOUR

__all__ = ["AXES", "BI_FACTOR", "allan_deviation", "allan_model", "datasheet_units",
           "fit_allan", "write_allan_preset"]

AXES = ("w_x", "w_y", "w_z", "f_x", "f_y", "f_z")
"""IMU columns, gyros first (rad/s), then accelerometers (m/s^2)."""
BI_FACTOR = math.sqrt(2.0 * math.log(2.0) / math.pi)
"""Allan-deviation floor of a flicker bias of instability ``B``: ``0.664 B``."""
TERMS = ("random_walk", "bias_instability", "rate_random_walk")
RESOLVED_SHARE = 0.5
"""Share of the fitted Allan variance a term must carry at some tau to count as resolved."""
MAX_GAP_STEPS = 10.0
"""Longest interval of a record the Allan deviation accepts, in sample steps: real logs drop
a sample now and then; the samples are then taken as evenly spaced (assumption M5)."""
MAX_IRREGULAR = 1e-3
"""Largest share of intervals longer than 1.5 sample steps the Allan deviation accepts."""
MIN_CLUSTERS = 3
"""Fewest independent clusters (``duration / tau``) an averaging time needs to be fitted."""
REWEIGHT = 4
"""Passes of the fit: the first weighs by the measured variance, the others by the fit."""
_UNITS = {"w": ("rad/s/√Hz (rad/√s)", "rad/s", "rad/s/√s"),
          "f": ("m/s²/√Hz (m/s/√s)", "m/s²", "m/s²/√s")}


def _check_imu(imu) -> tuple[pd.DataFrame, float, list[str]]:
    if not isinstance(imu, pd.DataFrame):
        raise NavlibInputError(f"imu: expected a pandas DataFrame (navlib.io readers), got "
                               f"{type(imu).__name__}")
    axes = [a for a in AXES if a in imu.columns]
    if "t" not in imu.columns or not axes:
        raise NavlibInputError(f"imu: needs a 't' column and at least one of {list(AXES)}; "
                               f"columns are {list(imu.columns)}")
    t = imu["t"].to_numpy(dtype=float)
    if t.size < 100:
        raise NavlibInputError(f"imu: {t.size} rows; an Allan deviation needs a static log "
                               "of at least 100 samples (hours for the rate random walk)")
    dt = np.diff(t)
    if not np.all(np.isfinite(t)) or np.any(dt <= 0):
        raise NavlibInputError("imu: column 't' must be finite and strictly increasing")
    step = float(np.median(dt))
    long = np.flatnonzero(dt > 1.5 * step)
    worst = int(np.argmax(dt))
    if dt[worst] > MAX_GAP_STEPS * step or long.size > MAX_IRREGULAR * dt.size:
        raise NavlibInputError(
            f"imu: row {worst + 1} (t = {t[worst + 1]:.6g} s) follows a gap of "
            f"{dt[worst]:.3g} s (sample step {step:.3g} s; {long.size} interval(s) longer "
            f"than 1.5 steps); the Allan deviation needs an evenly sampled record (gaps of at "
            f"most {MAX_GAP_STEPS:g} steps in at most {100 * MAX_IRREGULAR:g}% of the "
            "intervals): fit a span without gaps")
    for a in axes:
        if not np.all(np.isfinite(imu[a].to_numpy(dtype=float))):
            raise NavlibInputError(f"imu: column {a!r} contains NaN or infinite values")
    return imu, 1.0 / step, axes, int(long.size)


def allan_deviation(imu: pd.DataFrame, rate_hz: float | None = None,
                    points_per_decade: int = 10) -> pd.DataFrame:
    """Overlapping Allan deviation of every IMU axis of a static record.

    Parameters
    ----------
    imu : DataFrame
        ``t`` (s, evenly sampled) and any of ``w_x, w_y, w_z`` (rad/s), ``f_x, f_y, f_z``
        (m/s^2): what the :mod:`navlib.io` readers return.
    rate_hz : float, optional
        Sampling rate; None: from the median step of ``t``.
    points_per_decade : int
        Averaging times ``tau`` log-spaced from one sample to a third of the record.

    Returns
    -------
    DataFrame
        ``tau_s`` and one column per axis (rad/s, m/s^2); ``attrs``: ``rate_hz``,
        ``duration_s``, ``n_samples`` and ``irregular_intervals`` (intervals longer than 1.5
        sample steps, taken as one step: at most :data:`MAX_IRREGULAR` of them, none longer
        than :data:`MAX_GAP_STEPS` steps, else NavlibInputError naming the row).
    """
    # allantools pulls in scipy.stats at import (about 1 s): imported where it is used
    import allantools

    imu, rate_auto, axes, irregular = _check_imu(imu)
    rate = rate_auto if rate_hz is None else finite_scalar(rate_hz, "rate_hz", 0.0,
                                                           low_open=True)
    if not isinstance(points_per_decade, int | np.integer) or not 1 <= points_per_decade <= 100:
        raise NavlibInputError(f"points_per_decade: expected an integer in 1..100, got "
                               f"{points_per_decade!r}")
    n = len(imu)
    m_max = max(n // 3, 1)
    m = np.unique(np.round(np.logspace(0.0, math.log10(m_max),
                                       int(points_per_decade * math.log10(m_max)) + 1)))
    taus = m / rate
    out = {}
    for a in axes:
        tau, dev, _, _ = allantools.oadev(imu[a].to_numpy(dtype=float), rate=rate,
                                          data_type="freq", taus=taus)
        out[a] = pd.Series(dev, index=np.round(tau * rate).astype(int))
    frame = pd.DataFrame(out).sort_index()
    frame.insert(0, "tau_s", frame.index.to_numpy() / rate)
    frame = frame.reset_index(drop=True)
    frame.attrs.update(rate_hz=rate, duration_s=n / rate, n_samples=n,
                       irregular_intervals=irregular)
    return frame


def allan_model(tau_s, random_walk=0.0, bias_instability=0.0, rate_random_walk=0.0):
    """Allan deviation of the three noise terms at ``tau_s`` (NaN terms count as zero):
    ``sqrt(N^2 / tau + (0.664 B)^2 + K^2 tau / 3)``.

    Parameters
    ----------
    tau_s : array_like
        Averaging times (s).
    random_walk : float
        ``N``, angle or velocity random walk (per sqrt(s)).
    bias_instability : float
        ``B``, the bias instability.
    rate_random_walk : float
        ``K``, the rate random walk (per s^1.5).

    Returns
    -------
    ndarray, shaped like ``tau_s``
    """
    tau_s = np.asarray(tau_s, dtype=float)
    n, b, k = (0.0 if not np.isfinite(x) else float(x)
               for x in (random_walk, bias_instability, rate_random_walk))
    return np.sqrt(n**2 / tau_s + (BI_FACTOR * b) ** 2 + k**2 * tau_s / 3.0)


def _fit_axis(tau, dev, duration):
    clusters = np.floor(duration / tau)
    use = (clusters >= MIN_CLUSTERS) & np.isfinite(dev) & (dev > 0)
    tau, dev, clusters = tau[use], dev[use], clusters[use]
    if tau.size < 3:
        nan = (np.nan,) * 3
        return nan, {"rms_log_error": np.nan, "tau_min_s": np.nan, "tau_max_s": np.nan,
                     "n_taus": int(tau.size), "tau_floor_s": np.nan,
                     "reason": "fewer than 3 averaging times with 3 clusters: record too "
                               "short"}
    basis = np.stack([1.0 / tau, np.ones_like(tau), tau], axis=1)
    dof = np.sqrt(clusters - 1.0)
    scale = dev**2                 # relative errors; then scaled by the fitted model, so
    for _ in range(REWEIGHT):      # that low measured points do not pull the fit down
        weight = dof / scale
        coef, _ = nnls(basis * weight[:, None], dev**2 * weight)
        fitted = basis @ coef
        scale = np.where(fitted > 0, fitted, dev**2)
    parts = basis * coef
    model = parts.sum(axis=1)
    share = parts / np.where(model > 0, model, 1.0)[:, None]
    values = (math.sqrt(coef[0]), math.sqrt(coef[1]) / BI_FACTOR, math.sqrt(3.0 * coef[2]))
    reasons = []
    resolved = []
    for j, name in enumerate(TERMS):
        top = float(share[:, j].max())
        if coef[j] == 0.0:
            reasons.append(f"{name}: fitted zero (no tau range shows it)")
            resolved.append(np.nan)
        elif top < RESOLVED_SHARE:
            reasons.append(f"{name}: carries at most {100 * top:.0f}% of the Allan variance "
                           f"over tau {tau[0]:.3g}-{tau[-1]:.3g} s (needs "
                           f"{100 * RESOLVED_SHARE:.0f}%)")
            resolved.append(np.nan)
        else:
            resolved.append(values[j])
    log_err = np.log10(np.sqrt(np.where(model > 0, model, np.nan)) / dev)
    ok = np.isfinite(log_err)
    quality = {"rms_log_error": float(np.sqrt(np.average(log_err[ok] ** 2,
                                                         weights=clusters[ok] - 1.0))),
               "tau_min_s": float(tau[0]), "tau_max_s": float(tau[-1]),
               "n_taus": int(tau.size), "tau_floor_s": float(tau[np.argmin(dev)]),
               "reason": "; ".join(reasons)}
    return tuple(resolved), quality


def fit_allan(imu, rate_hz: float | None = None) -> pd.DataFrame:
    """Angle/velocity random walk, bias instability and rate random walk per axis.

    Parameters
    ----------
    imu : DataFrame
        A static IMU record (as :func:`allan_deviation` takes), or the frame
        :func:`allan_deviation` returned (recognised by its ``tau_s`` column; its
        ``attrs["duration_s"]`` bounds the usable averaging times).
    rate_hz : float, optional
        Sampling rate of a record (None: from ``t``).

    Returns
    -------
    DataFrame
        Indexed by axis (``w_x`` ... ``f_z``, those present): ``random_walk`` (rad/√s,
        m/s/√s), ``bias_instability`` (rad/s, m/s²), ``rate_random_walk`` (rad/s/√s,
        m/s²/√s), their units (``unit_random_walk``, ...), and the fit quality:
        ``rms_log_error`` (RMS of log10 fitted/measured deviation, each averaging time
        weighted by its independent clusters less one, as in the fit), ``tau_min_s``,
        ``tau_max_s``, ``n_taus`` (averaging times used: at least 3 clusters each),
        ``tau_floor_s`` (tau of the lowest measured deviation) and ``reason`` (why a term
        is NaN; empty when all three are resolved). ``attrs`` keeps ``rate_hz``,
        ``duration_s`` and the deviation frame (``attrs["adev"]``).
    """
    if isinstance(imu, pd.DataFrame) and "tau_s" in imu.columns:
        adev = imu
        if "duration_s" not in adev.attrs:
            raise NavlibInputError("imu: an Allan-deviation frame needs attrs['duration_s'] "
                                   "(pass the frame allan_deviation returned)")
    else:
        adev = allan_deviation(imu, rate_hz)
    axes = [a for a in AXES if a in adev.columns]
    if not axes:
        raise NavlibInputError(f"imu: no IMU axis among the columns {list(adev.columns)}")
    tau = adev["tau_s"].to_numpy(dtype=float)
    rows = []
    for a in axes:
        values, quality = _fit_axis(tau, adev[a].to_numpy(dtype=float),
                                    float(adev.attrs["duration_s"]))
        units = _UNITS[a[0]]
        rows.append({"axis": a, **dict(zip(TERMS, values, strict=True)),
                     **{f"unit_{k}": u for k, u in zip(TERMS, units, strict=True)}, **quality})
    fit = pd.DataFrame(rows).set_index("axis")
    fit.attrs.update(rate_hz=adev.attrs.get("rate_hz"), duration_s=adev.attrs["duration_s"],
                     adev=adev)
    return fit


def datasheet_units(fit: pd.DataFrame) -> pd.DataFrame:
    """The fitted terms in datasheet units: gyros ARW deg/√h, bias instability deg/h, RRW
    deg/h/√h; accelerometers VRW m/s/√h, bias instability µg, RRW m/s²/√h (assumption M5:
    µg with g = 9.80665 m/s²)."""
    rows = []
    for axis, r in fit.iterrows():
        if axis.startswith("w"):
            rows.append({"axis": axis, "random_walk": r.random_walk / DEG * math.sqrt(HOUR),
                         "unit_random_walk": "deg/√h",
                         "bias_instability": r.bias_instability / DEG * HOUR,
                         "unit_bias_instability": "deg/h",
                         "rate_random_walk": r.rate_random_walk / DEG * HOUR * math.sqrt(HOUR),
                         "unit_rate_random_walk": "deg/h/√h"})
        else:
            rows.append({"axis": axis, "random_walk": r.random_walk * math.sqrt(HOUR),
                         "unit_random_walk": "m/s/√h",
                         "bias_instability": r.bias_instability / G0 * 1e6,
                         "unit_bias_instability": "µg",
                         "rate_random_walk": r.rate_random_walk * math.sqrt(HOUR),
                         "unit_rate_random_walk": "m/s²/√h"})
    return pd.DataFrame(rows).set_index("axis")


_NOISE_PREFIXES = ("gyro_arw_", "gyro_bias_markov_", "gyro_bias_rw_", "accel_vrw_",
                   "accel_bias_markov_", "accel_bias_rw_")


def _toml_value(value) -> str:
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, bool):
        return "true" if value else "false"
    return repr(float(value))


def write_allan_preset(fit: pd.DataFrame, path, *, name: str, source: str,
                       base: str | None = None) -> Path:
    """Write an Allan fit as a sensor preset file (the ``data/sensors`` TOML format).

    The noise keys come from the fit, averaged over the resolved axes of each triad:
    ``*_arw_rad_sqrt_s`` / ``accel_vrw_m_s2_sqrt_hz`` (random walk), ``*_bias_rw_*`` (rate
    random walk) and the bias instability as a Gauss-Markov drift of that sigma with the
    time constant of the deviation's floor (assumption M5). Unresolved terms are left out.
    ``base`` (a preset name or file) supplies every other key (turn-on biases, scale
    factors, GNSS); its own noise keys are replaced.

    Parameters
    ----------
    fit : pandas.DataFrame
        The table :func:`fit_allan` returned.
    path : str or Path
        TOML file to write.
    name : str
        Preset name written in the file.
    source : str
        Where the recording came from (the preset's ``source``).
    base : str, optional
        Preset name or file supplying the other keys.

    Returns
    -------
    Path
        The file written; load it with :func:`navlib.sensors.load_preset`.

    Raises
    ------
    NavlibInputError
        For a ``fit`` not from :func:`fit_allan`, an empty ``name`` or ``source``, or an
        unknown ``base``.
    """
    if not isinstance(fit, pd.DataFrame) or not set(TERMS) <= set(fit.columns):
        raise NavlibInputError("fit: expected the DataFrame fit_allan returned")
    for label, text in (("name", name), ("source", source)):
        if not isinstance(text, str) or not text.strip():
            raise NavlibInputError(f"{label}: expected a non-empty string, got {text!r}")
    imu, gnss, assumed = {}, {}, []
    if base is not None:
        base_path = Path(base) if str(base).endswith(".toml") else \
            data_dir() / "sensors" / f"{base}.toml"
        if not base_path.is_file():
            raise NavlibInputError(f"base: sensor preset {base!r} not found")
        table = tomllib.loads(base_path.read_text(encoding="utf-8"))
        imu = {k: v for k, v in table.get("imu", {}).items()
               if not k.startswith(_NOISE_PREFIXES)}
        gnss = dict(table.get("gnss", {}))
        assumed = [a for a in table.get("assumed", [])
                   if a.split(".", 1)[-1] in imu or a.startswith("gnss.")]
    if fit.attrs.get("rate_hz"):
        imu["rate_hz"] = float(fit.attrs["rate_hz"])
    adev = fit.attrs.get("adev")
    for triad, prefix, rw_key, rrw_key, bi_key in (
            ("w", "gyro", "arw_rad_sqrt_s", "bias_rw_rad_s_sqrt_s", "bias_markov_rad_s"),
            ("f", "accel", "vrw_m_s2_sqrt_hz", "bias_rw_m_s2_sqrt_s", "bias_markov_m_s2")):
        rows = fit[[str(a).startswith(triad) for a in fit.index]]
        for term, key in (("random_walk", rw_key), ("rate_random_walk", rrw_key),
                          ("bias_instability", bi_key)):
            values = rows[term].to_numpy(dtype=float)
            values = values[np.isfinite(values)]
            if values.size:
                imu[f"{prefix}_{key}"] = float(values.mean())
                if term == "bias_instability":
                    floor = rows["tau_floor_s"].to_numpy(dtype=float)
                    imu[f"{prefix}_bias_markov_tau_s"] = float(np.nanmean(floor))
                    assumed.append(f"imu.{prefix}_bias_markov_tau_s")
    lines = [f"name = {_toml_value(name)}", f"source = {_toml_value(source)}",
             "notes = " + _toml_value(
                 "Noise terms fitted by navlib.sensors.fit_allan (mean of the resolved axes; "
                 "bias instability as a Gauss-Markov drift with the tau of the Allan floor)"
                 + (f"; other keys from preset {base!r}" if base else "")),
             f"assumed = {_toml_value(sorted(set(assumed)))}", "", "[imu]"]
    lines += [f"{k} = {_toml_value(v)}" for k, v in imu.items()]
    if gnss:
        lines += ["", "[gnss]", *[f"{k} = {_toml_value(v)}" for k, v in gnss.items()]]
    if adev is not None:
        lines.insert(3, f"# Allan record: {adev.attrs.get('duration_s', float('nan')):.6g} s "
                        f"at {adev.attrs.get('rate_hz', float('nan')):.6g} Hz")
    path = Path(path)
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path
