"""Flight-data quality: IMU saturation and GNSS faults, found, reported and excluded.

Two checks run on a flight's records before the fit (:func:`navlib.studies.assess.assess_flight`
calls :func:`check_records`); their thresholds are data, in ``data/quality.toml``
(:func:`load_thresholds`), with the reasoning in ``docs/assumptions.md``:

* **Saturation** (:func:`imu_saturation`, assumption Q1). A gyro or accelerometer sample at
  its sensor's range limit reads the limit, not the motion. The range comes from the
  reader (``imu.attrs["range"] = {"gyro_rad_s": ..., "accel_m_s2": ...}``), else from the
  sensor preset (``gyro_range_*`` / ``accel_range_*``, :class:`navlib.sensors.TriadSpec`);
  without either, a *flat top* (an extreme value repeated, far from the channel's bulk)
  counts too. Rule (Q1): a saturated sample is dropped from the IMU record, all six axes of
  it, so the fit bridges it as a hole from its neighbours and the GNSS (holes longer than
  the fit's ``max_bridge_s`` split the flight into spans); a flight with more than
  ``max_fraction`` of its samples saturated is refused. Where the board has a second,
  high-g accelerometer along body x (``imu.attrs["high_g"]``, an AltOS export's
  ``acceleration``), its calibrated reading stands in for the clipped ``f_x`` samples instead
  (:mod:`navlib.io.high_g`).
* **GNSS faults** (:func:`gnss_faults` of :mod:`navlib.io.gnss_faults`, assumptions
  Q2-Q4): frozen (stale) fixes that repeat a position while the vehicle moves, altitudes
  that disagree with the barometer (``imu.attrs["baro"]``, DataFrame ``t, alt_m``), and
  jumps the IMU cannot explain. Rule: the faulty fixes are dropped from the GNSS record
  before the fit (the epochs they leave are GNSS outages); a flight whose faulty fixes cover
  more than ``max_faulty_time_fraction`` of the GNSS record's *time* (:func:`faulty_time`,
  not its rows) is refused.

Every finding is a row of a tidy table (``check, channel, n, fraction, t_first, t_last,
spans, message``) whose ``message`` is a warning with times, e.g. ``gyro w_x at its +-2000
deg/s limit: 8 samples (0.05 %) at 147.9-148.1 s``.
"""


from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from navlib._validation import finite_scalar
from navlib.errors import NavlibInputError
from navlib.io.findings import (
    FINDING_COLUMNS,
    THRESHOLDS_FILE,
    check_record,
    finding,
    findings_frame,
    load_thresholds,
)
from navlib.io.gnss_faults import baro_lag, faulty_time, gnss_faults, shifted
from navlib.io.high_g import HighGStandIn, high_g_stand_in
from navlib.units import DEG

__all__ = ["FINDING_COLUMNS", "THRESHOLDS_FILE", "QualityCheck", "along_axis_stand_in",
           "check_records", "faulty_time", "gnss_faults", "imu_saturation", "load_thresholds"]

_GYRO = ("w_x", "w_y", "w_z")
_ACCEL = ("f_x", "f_y", "f_z")
_XYZ = ("x", "y", "z")


# --------------------------------------------------------------------------- saturation


def _ranges(imu: pd.DataFrame, spec) -> dict[str, tuple[float | None, str]]:
    """Range (SI) and its source for ``gyro`` and ``accel``: the reader's
    ``attrs["range"]``, else the preset's, else None."""
    given = imu.attrs.get("range") or {}
    if not isinstance(given, Mapping):
        raise NavlibInputError(f"imu.attrs['range']: expected a mapping with gyro_rad_s / "
                               f"accel_m_s2, got {given!r}")
    imu_spec = getattr(spec, "imu", None)
    out = {}
    for sensor, key in (("gyro", "gyro_rad_s"), ("accel", "accel_m_s2")):
        if given.get(key) is not None:
            out[sensor] = (finite_scalar(given[key], f"imu.attrs['range'][{key!r}]", 0.0,
                                         low_open=True), "the log")
        else:
            preset_range = getattr(getattr(imu_spec, sensor, None), "range", None)
            out[sensor] = (preset_range, f"preset {getattr(spec, 'name', '')!r}")
    return out


def _flat_top(x: np.ndarray, floor: float, p: dict) -> tuple[np.ndarray, list[float]] | None:
    """Samples of the channel ``x`` at a repeated extreme (module docstring) and the
    extremes, or None."""
    median = float(np.median(x))
    sigma = 1.4826 * float(np.median(np.abs(x - median)))
    hit = np.zeros(x.size, dtype=bool)
    values = []
    for extreme in (float(x.max()), float(x.min())):
        at = x == extreme
        if (np.count_nonzero(at) >= p["flat_top_min_samples"] and abs(extreme) >= floor
                and abs(extreme - median) >= p["flat_top_min_excursion_sigma"] * sigma):
            hit |= at
            values.append(extreme)
    return (hit, values) if values else None


def imu_saturation(imu: pd.DataFrame, spec=None, thresholds: Mapping | None = None,
                   stand_in: HighGStandIn | None = None) -> tuple[np.ndarray, pd.DataFrame]:
    """IMU samples at their sensor's range limit, or at a flat top (assumption Q1).

    Parameters
    ----------
    imu : DataFrame
        ``t, f_x, f_y, f_z, w_x, w_y, w_z`` (SI); ``attrs["range"]`` (``gyro_rad_s``,
        ``accel_m_s2``) when the reader knows the board.
    spec : navlib.sensors.SensorSpec, optional
        The preset; its triads' ``range`` is used where the log gives none.
    thresholds : mapping, optional
        The ``[saturation]`` section of :func:`load_thresholds` (default: the file's).
    stand_in : HighGStandIn, optional
        :func:`along_axis_stand_in`: its ``filled`` ``f_x`` samples are not judged against the
        range, and why the others were not filled is said in their finding.

    Returns
    -------
    saturated : ndarray of bool (N,)
        Rows with at least one axis saturated.
    findings : DataFrame
        One row per saturated channel (:data:`FINDING_COLUMNS`; ``check`` is
        ``saturation`` at a known limit, ``flat top`` otherwise).
    """
    check_record(imu, "imu", (*_ACCEL, *_GYRO))
    p = dict(thresholds or load_thresholds()["saturation"])
    t = imu["t"].to_numpy(dtype=float)
    ranges = _ranges(imu, spec)
    saturated = np.zeros(t.size, dtype=bool)
    rows = []
    for sensor, channels, unit, factor, floor in (
            ("gyro", _GYRO, "deg/s", DEG, p["flat_top_min_gyro_deg_s"] * DEG),
            ("accel", _ACCEL, "m/s^2", 1.0, p["flat_top_min_accel_m_s2"])):
        limit, source = ranges[sensor]
        for channel in channels:
            x = imu[channel].to_numpy(dtype=float)
            if limit is not None:
                hit = np.abs(x) >= limit * (1.0 - p["limit_tolerance"])
                what = f"{sensor} {channel} at its +-{limit / factor:.4g} {unit} limit"
                after = f" (range from {source})"
                check = "saturation"
                if stand_in is not None and channel == "f_x":
                    hit &= ~stand_in.filled
                    after += f"; {stand_in.refusal}" if stand_in.refusal else ""
            else:
                flat = _flat_top(x, floor, p)
                if flat is None:
                    continue
                hit, values = flat
                at = " and ".join(f"{v / factor:.4g}" for v in values)
                what = f"{sensor} {channel} flat at {at} {unit}"
                after = " (a repeated extreme: the range is not known, taken as its limit)"
                check = "flat top"
            if hit.any():
                saturated |= hit
                rows.append(finding(check, channel, t[hit], t.size, p["span_join_s"], what,
                                     "samples", after + "; dropped, the fit bridges them"))
    return saturated, findings_frame(rows)


def along_axis_stand_in(imu: pd.DataFrame, spec=None, thresholds: Mapping | None = None
                        ) -> HighGStandIn | None:
    """The high-g accelerometer's stand-in for the ``f_x`` samples at the accelerometer's
    range limit (:func:`navlib.io.high_g.high_g_stand_in`; assumption Q1).

    None when the record has no high-g reading (``imu.attrs["high_g"]``) or the range is
    not known (a flat top is not a limit the high-g reading can be checked against).
    """
    p = dict(thresholds or load_thresholds()["saturation"])
    limit = _ranges(imu, spec)["accel"][0]
    if limit is None or imu.attrs.get("high_g") is None:
        return None
    clipped = np.abs(imu["f_x"].to_numpy(dtype=float)) >= limit * (1.0 - p["limit_tolerance"])
    return high_g_stand_in(imu, clipped, limit, p)


# --------------------------------------------------------------------------- both


@dataclass(frozen=True, eq=False)
class QualityCheck:
    """Result of :func:`check_records`.

    Attributes
    ----------
    imu, gnss : DataFrame
        The records with the saturated samples and the faulty fixes dropped (``attrs``
        kept).
    findings : DataFrame
        Every finding (:data:`FINDING_COLUMNS`); ``message`` is the warning text.
    thresholds : dict
        The thresholds used.
    """

    imu: pd.DataFrame
    gnss: pd.DataFrame
    findings: pd.DataFrame
    thresholds: dict = field(default_factory=dict)

    @property
    def warnings(self) -> list[str]:
        """The findings' messages."""
        return list(self.findings["message"])


def _drop(frame: pd.DataFrame, bad: np.ndarray) -> pd.DataFrame:
    out = frame[~bad].reset_index(drop=True)
    out.attrs = dict(frame.attrs)
    return out


def check_records(imu: pd.DataFrame, gnss: pd.DataFrame, spec=None, sigma_m: float = 5.0,
                  thresholds: Mapping | None = None) -> QualityCheck:
    """Find saturated IMU samples and faulty GNSS fixes, drop them, and refuse a flight
    with too many (module docstring; assumptions Q1-Q4). Fixes that trail the barometer
    are first moved back by their lag (:func:`~navlib.io.gnss_faults.baro_lag`, FIT6;
    ``gnss.attrs["lag_s"]`` and a ``gnss lag`` finding).

    Parameters
    ----------
    imu, gnss : DataFrame
        The records (:func:`imu_saturation`, :func:`gnss_faults`).
    spec : navlib.sensors.SensorSpec, optional
        Sensor preset (IMU ranges).
    sigma_m : float
        GNSS position sigma where the record has none, m.
    thresholds : mapping, optional
        Overrides of ``data/quality.toml`` (:func:`load_thresholds`).

    Raises
    ------
    NavlibInputError
        Records that are not DataFrames, lack columns, hold fewer than 2 rows, non-finite
        values or times that do not increase; more than ``[saturation] max_fraction`` of the
        IMU samples saturated, or faulty fixes covering more than ``[gnss]
        max_faulty_time_fraction`` of the GNSS record's time (:func:`faulty_time`; naming
        the findings and how to change the threshold).
    """
    check_record(imu, "imu", (*_ACCEL, *_GYRO))
    check_record(gnss, "gnss", _XYZ)
    p = load_thresholds(thresholds)
    stand_in = along_axis_stand_in(imu, spec, p["saturation"])
    high_g, checked_attrs = [], imu.attrs
    if stand_in is not None and stand_in.filled.any():
        t = imu["t"].to_numpy(dtype=float)
        limit = _ranges(imu, spec)["accel"][0]
        high_g = [finding("high-g", "f_x", t[stand_in.filled], t.size,
                          p["saturation"]["span_join_s"],
                          f"accel f_x beyond its +-{limit:.4g} m/s^2 limit", "samples",
                          f"; {stand_in.note}")]
        imu = imu.assign(f_x=stand_in.f_x)
        imu.attrs = dict(checked_attrs)
    saturated, sat = imu_saturation(imu, spec, p["saturation"], stand_in)
    sat = pd.concat([findings_frame(high_g), sat], ignore_index=True) if high_g else sat
    _refuse_share(saturated, "imu: {} % of the samples are saturated",
                  p["saturation"], "saturation", "max_fraction", sat["message"])
    clean_imu = _drop(imu, saturated)
    lag, lag_rows = baro_lag(clean_imu, gnss, p["gnss"], sigma_m)
    if lag:
        gnss = shifted(gnss, lag)
        gnss.attrs["lag_s"] = lag
    bad, faults = gnss_faults(clean_imu, gnss, sigma_m, p["gnss"])
    faults = pd.concat([findings_frame(lag_rows), faults], ignore_index=True) if lag_rows \
        else faults
    _refuse_faulty_time(gnss, bad, clean_imu, p["gnss"], faults["message"])
    findings = pd.concat([f for f in (sat, faults) if len(f)] or [findings_frame([])],
                         ignore_index=True)
    return QualityCheck(imu=clean_imu, gnss=_drop(gnss, bad), findings=findings,
                        thresholds=p)


def _refuse_share(flags, what: str, table: dict, section: str, key: str, messages) -> None:
    """NavlibInputError when the share of ``flags`` exceeds ``table[key]`` (the
    ``[section] key`` of data/quality.toml), naming the findings ``messages``."""
    fraction = np.count_nonzero(flags) / flags.size
    if fraction > table[key]:
        share = f"{100 * fraction:.3g}"
        raise NavlibInputError(
            f"{what.format(share)}, more than the "
            f"{100 * table[key]:.3g} % an assessment accepts "
            f"(data/quality.toml [{section}] {key}): {'; '.join(messages)}")



def _refuse_faulty_time(gnss: pd.DataFrame, bad: np.ndarray, imu: pd.DataFrame, table: dict,
                        messages) -> None:
    """NavlibInputError when the faulty fixes (and long held ones) cover more than ``[gnss]
    max_faulty_time_fraction`` of the GNSS record's time (:func:`faulty_time`), saying what
    covers it, what is left and how to change the threshold."""
    faulty, span, parts = faulty_time(gnss, bad, imu, table)
    limit = table["max_faulty_time_fraction"]
    if span <= 0 or faulty <= limit * span:
        return
    accept = min(0.95, float(np.ceil(20.0 * faulty / span)) / 20.0 + 0.05)
    found = f": {'; '.join(messages)}" if len(messages) else ""
    raise NavlibInputError(
        f"gnss: faulty fixes cover {faulty:.3g} s of the GNSS record's {span:.3g} s "
        f"({100 * faulty / span:.3g} %: {', '.join(parts)}), leaving {span - faulty:.3g} s "
        f"usable; an assessment needs at least {100 * (1 - limit):.3g} % of the time usable "
        f"(data/quality.toml [gnss] max_faulty_time_fraction = {limit:g}; to accept this "
        f"record, e.g. python -m navlib assess LOG -p quality_thresholds "
        f"'{{\"gnss\": {{\"max_faulty_time_fraction\": {accept:.2g}}}}}', or "
        f"assess_flight(..., quality_thresholds=...)){found}")
