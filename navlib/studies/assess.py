"""Assess a recorded flight: which navigation states could it estimate, segment by segment?

The pipeline of issue 6, applied to a user's own IMU and GNSS records (España, Carrizo &
Giribet 2019, §4-6, with the 21-state ECEF model)::

    import (navlib.io)  ->  fit (navlib.trajectory.fit_flight_data)  ->  segment
    (navlib.segmentation)  ->  model (navlib.models.ecef.ecef21_at_epochs)  ->  metrics
    (navlib.metrics: excitability per segment, sensability over time)

:func:`assess_flight` returns a :class:`FlightAssessment` holding every intermediate result
and tidy tables: the input summary, the fit residuals, the segments, the excitability of
the 21 states per segment, the sensability over time and a summary of the states each
segment could estimate. The summary states facts of the metrics at stated thresholds,
nothing more: a state is *excitable* in a segment when ``e >= e_threshold`` (default
``1/sqrt(2)``: more than half of the state's unit vector lies in the excited subspace) and
*sensible* when ``s >= s_threshold`` at no less than ``min_fraction`` of the segment's
epochs. :meth:`FlightAssessment.with_settings` re-evaluates new segments or thresholds
without refitting or rediscretising (the widgets use it).

Assumptions that matter (all visible in ``FlightAssessment.options``): the sensor preset
(noise densities and the turn-on sigmas of ``P0``), the GNSS sigma (the records' median
``sigma`` column when present, else the preset's), the GNSS rate of the model (the
records' median rate unless given), and, for flights whose heading cannot be estimated
from the motion (quasi-static drones), a fallback initial heading.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from navlib import sensors
from navlib._validation import finite_scalar, reject_unknown
from navlib.errors import NavlibInputError
from navlib.io import FlightDataWarning, check_overlap
from navlib.metrics import excitability_segment, sensability_model
from navlib.models.ecef import PAPER_IDS, STATE_GROUPS, ecef21_at_epochs
from navlib.segmentation import (
    SEGMENT_DEFAULTS,
    Segmentation,
    segment_flight,
    segments_table,
)
from navlib.trajectory import fit_flight_data

__all__ = ["FlightAssessment", "assess_flight", "describe_inputs", "fit_report",
           "fit_residuals"]

E_THRESHOLD = 1.0 / math.sqrt(2.0)
"""Default excitability threshold: ``e^2 > 1/2``, the state lies mostly in the excited
subspace."""
S_THRESHOLD = 1.0 / math.sqrt(2.0)
"""Default sensability threshold (same reading for the sensible subspace)."""
MIN_FRACTION = 0.5
"""Default share of a segment's epochs at which ``s >= s_threshold`` must hold."""
MIN_DURATION_S = 2.0
"""Shortest common IMU/GNSS span accepted, s."""
MIN_GNSS_EPOCHS = 4
"""Fewest GNSS epochs accepted inside the common span (the fit needs four)."""

_IMU_KEYS = ("t", "f_x", "f_y", "f_z", "w_x", "w_y", "w_z")
_GNSS_KEYS = ("t", "x", "y", "z")
_GROUP_OF = {name: group for group, names in STATE_GROUPS.items() for name in names}


# --------------------------------------------------------------------------- inputs


def _check_frame(frame, name: str, keys) -> None:
    if not isinstance(frame, pd.DataFrame):
        raise NavlibInputError(f"{name}: expected a pandas DataFrame (navlib.io readers), got "
                               f"{type(frame).__name__}")
    missing = [k for k in keys if k not in frame.columns]
    if missing:
        raise NavlibInputError(f"{name}: missing column(s) {missing}; columns are "
                               f"{list(frame.columns)}")
    if "segment" in frame.columns and frame["segment"].nunique() > 1:
        raise NavlibInputError(
            f"{name}: the record has {frame['segment'].nunique()} pieces split at gaps "
            "(column 'segment'); assess each piece of navlib.io.split_at_gaps separately")
    if len(frame) < 2:
        raise NavlibInputError(f"{name}: need at least 2 rows, got {len(frame)}")


def _median_rate(t: np.ndarray) -> float:
    return float(1.0 / np.median(np.diff(t))) if t.size > 1 else float("nan")


def describe_inputs(imu: pd.DataFrame, gnss: pd.DataFrame) -> pd.DataFrame:
    """One row per record (``imu``, ``gnss``, and their ``overlap``): samples, first and
    last time (s), duration (s), median rate (Hz), longest interval (s), gaps reported by
    the reader (``attrs["gaps"]``) and the source file."""
    _check_frame(imu, "imu", _IMU_KEYS)
    _check_frame(gnss, "gnss", _GNSS_KEYS)
    rows = []
    for name, frame in (("imu", imu), ("gnss", gnss)):
        t = frame["t"].to_numpy(dtype=float)
        rows.append({"record": name, "samples": t.size, "t_first": t[0], "t_last": t[-1],
                     "duration_s": t[-1] - t[0], "rate_hz": _median_rate(t),
                     "longest_interval_s": float(np.max(np.diff(t))),
                     "gaps": len(frame.attrs.get("gaps", [])),
                     "source": str(frame.attrs.get("source", ""))})
    span = check_overlap(imu, gnss)
    t_i = imu["t"].to_numpy(dtype=float)
    inside = int(np.count_nonzero((t_i >= span.t_start) & (t_i <= span.t_end)))
    rows.append({"record": "overlap", "samples": inside, "t_first": span.t_start,
                 "t_last": span.t_end, "duration_s": span.duration, "rate_hz": np.nan,
                 "longest_interval_s": np.nan, "gaps": np.nan,
                 "source": f"{span.n_gnss} GNSS epochs inside"})
    return pd.DataFrame(rows)


def _validate(imu, gnss):
    _check_frame(imu, "imu", _IMU_KEYS)
    _check_frame(gnss, "gnss", _GNSS_KEYS)
    span = check_overlap(imu, gnss)
    if span.duration < MIN_DURATION_S:
        raise NavlibInputError(
            f"imu, gnss: the records overlap for {span.duration:.3g} s only; an assessment "
            f"needs at least {MIN_DURATION_S:g} s of common IMU and GNSS data")
    if span.n_gnss < MIN_GNSS_EPOCHS:
        raise NavlibInputError(
            f"gnss: {span.n_gnss} epoch(s) inside the IMU span "
            f"{span.t_start:.6g}..{span.t_end:.6g} s; need at least {MIN_GNSS_EPOCHS}")
    return span


# --------------------------------------------------------------------------- fit


def fit_report(trajectory, preset=None, gnss_sigma_m: float | None = None) -> pd.DataFrame:
    """The fit residuals of :func:`navlib.trajectory.fit_flight_data` as a tidy table.

    Columns ``quantity`` (GNSS position, GNSS velocity, specific force, angular rate),
    ``axis`` (x, y, z, 3d or max), ``rms`` (SI: m, m/s, m/s^2, rad/s; the ``max`` rows hold
    the largest norm) and ``unit``, and ``white_noise``: for the IMU rows the per-sample
    white-noise sigma of the sensor ``preset`` (``density / sqrt(dt)``), for the GNSS
    position rows ``gnss_sigma_m``; a floor the residual RMS sits near when the fit explains
    the data (biases and scale-factor errors add to it). NaN where not given.
    """
    res = getattr(trajectory, "parameters", {}).get("fit_residuals")
    if res is None:
        raise NavlibInputError("trajectory: has no parameters['fit_residuals']; pass a "
                               "trajectory from navlib.trajectory.fit_flight_data")
    spec = {"gnss_position_rms_m": ("GNSS position", "m"),
            "gnss_velocity_rms_mps": ("GNSS velocity", "m/s"),
            "specific_force_rms_mps2": ("specific force", "m/s^2"),
            "angular_rate_rms_rad_s": ("angular rate", "rad/s")}
    extra = {"gnss_position_rms_3d_m": ("GNSS position", "3d"),
             "specific_force_max_mps2": ("specific force", "max"),
             "angular_rate_max_rad_s": ("angular rate", "max")}
    floor = _noise_floor(trajectory, preset) if preset is not None else {}
    if gnss_sigma_m is not None:
        floor["GNSS position"] = finite_scalar(gnss_sigma_m, "gnss_sigma_m", 0.0,
                                               low_open=True)
    rows = []
    for key, (quantity, unit) in spec.items():
        if key not in res:
            continue
        for axis, value in zip("xyz", np.atleast_1d(res[key]), strict=True):
            rows.append({"quantity": quantity, "axis": axis, "rms": float(value), "unit": unit,
                         "white_noise": floor.get(quantity, np.nan)})
    for key, (quantity, axis) in extra.items():
        if key in res:
            unit = next(u for q, u in spec.values() if q == quantity)
            rows.append({"quantity": quantity, "axis": axis, "rms": float(res[key]),
                         "unit": unit, "white_noise": np.nan})
    order = {q: i for i, (q, _) in enumerate(spec.values())}
    frame = pd.DataFrame(rows)
    frame = frame.sort_values("quantity", key=lambda s: s.map(order), kind="stable")
    return frame.reset_index(drop=True)


def fit_residuals(trajectory, imu: pd.DataFrame, gnss: pd.DataFrame
                  ) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Residuals of the records against a fitted trajectory, over time.

    Returns
    -------
    gnss_residuals : DataFrame
        At the GNSS epochs inside the trajectory span: ``t``, ``dx, dy, dz`` (recorded minus
        fitted ECEF position, m), ``d3`` (their norm) and, with GNSS velocity, ``dvx, dvy,
        dvz`` (m/s). The fit is interpolated linearly between its samples (error below
        ``|a| dt^2 / 8``: 1.4 mm at 110 m/s^2 and 100 Hz).
    imu_residuals : DataFrame
        At the trajectory samples (the IMU times of the fit): ``t``, ``df_x, df_y, df_z``
        (recorded minus the fit's exact specific force, m/s^2), ``dw_x, dw_y, dw_z``
        (angular rate, rad/s) and the norms ``df``, ``dw``.
    """
    _check_frame(imu, "imu", _IMU_KEYS)
    _check_frame(gnss, "gnss", _GNSS_KEYS)
    t = np.asarray(trajectory.t, dtype=float)
    t_g = gnss["t"].to_numpy(dtype=float)
    keep = (t_g >= t[0]) & (t_g <= t[-1])
    out = {"t": t_g[keep]}
    for i, axis in enumerate("xyz"):
        out[f"d{axis}"] = gnss[axis].to_numpy(dtype=float)[keep] - np.interp(
            t_g[keep], t, trajectory.position[:, i])
    out["d3"] = np.sqrt(out["dx"] ** 2 + out["dy"] ** 2 + out["dz"] ** 2)
    if all(c in gnss.columns for c in ("vx", "vy", "vz")):
        for i, axis in enumerate("xyz"):
            out[f"dv{axis}"] = gnss[f"v{axis}"].to_numpy(dtype=float)[keep] - np.interp(
                t_g[keep], t, trajectory.velocity[:, i])
    t_i = imu["t"].to_numpy(dtype=float)
    k = np.searchsorted(t_i, t)
    k = np.clip(k, 0, t_i.size - 1)
    if not np.allclose(t_i[k], t, rtol=0.0, atol=1e-9):
        raise NavlibInputError("imu: the trajectory is not sampled at these IMU times; pass "
                               "the records the trajectory was fitted to")
    f_rec = imu[["f_x", "f_y", "f_z"]].to_numpy(dtype=float)[k]
    w_rec = imu[["w_x", "w_y", "w_z"]].to_numpy(dtype=float)[k]
    df = f_rec - trajectory.specific_force
    dw = w_rec - trajectory.angular_rate
    imu_out = {"t": t}
    for i, axis in enumerate("xyz"):
        imu_out[f"df_{axis}"] = df[:, i]
    for i, axis in enumerate("xyz"):
        imu_out[f"dw_{axis}"] = dw[:, i]
    imu_out["df"] = np.linalg.norm(df, axis=1)
    imu_out["dw"] = np.linalg.norm(dw, axis=1)
    return pd.DataFrame(out), pd.DataFrame(imu_out)


def _noise_floor(trajectory, preset) -> dict:
    from navlib.models.ecef import imu_noise_densities

    dt = 1.0 / trajectory.rate_hz
    noise = imu_noise_densities(preset)
    return {"specific force": float(np.mean(noise["vrw_m_s_sqrt_s"])) / math.sqrt(dt),
            "angular rate": float(np.mean(noise["arw_rad_sqrt_s"])) / math.sqrt(dt)}


def _fit(imu, gnss, fit_options: dict, heading_fallback_deg):
    """:func:`fit_flight_data`, retried with a fallback heading when the motion cannot
    give one (the fit names ``heading_deg`` in that error)."""
    notes = []
    try:
        return fit_flight_data(imu, gnss, **fit_options), notes
    except NavlibInputError as exc:
        given = fit_options.get("heading_deg") is not None or \
            fit_options.get("initial_attitude") is not None
        if given or heading_fallback_deg is None or not str(exc).startswith("heading_deg:"):
            raise
        notes.append(f"initial heading not observable from the motion ({exc}); assumed "
                     f"heading_deg={heading_fallback_deg:g} (body-x azimuth at the start)")
        warnings.warn(notes[-1], FlightDataWarning, stacklevel=3)
        options = {**fit_options, "heading_deg": heading_fallback_deg}
        return fit_flight_data(imu, gnss, **options), notes


# --------------------------------------------------------------------------- result


def _label(row) -> str:
    return f"{int(row.segment)} {row.phase} {row.t_start:.4g}-{row.t_end:.4g} s"


@dataclass(frozen=True, eq=False)
class FlightAssessment:
    """Everything :func:`assess_flight` computed, with tidy views.

    Attributes
    ----------
    trajectory : Trajectory
        The fitted reference trajectory (exact IMU; ``parameters["fit_residuals"]``).
    inputs : DataFrame
        :func:`describe_inputs` of the records.
    fit : DataFrame
        :func:`fit_report` of the residuals.
    automatic : Segmentation
        The automatic segmentation (features and phases), whatever segments were used.
    segment_table : DataFrame
        The segments assessed: ``segment`` (1-based), ``phase``, ``t_start``, ``t_end``,
        ``duration``, ``n_epochs`` (GNSS epochs of the model inside).
    model : DiscreteModel
        The 21-state ECEF model discretised at the GNSS epochs.
    excitability : tuple of ExcitabilityResult
        One per segment, in the order of ``segment_table``.
    sensability : SensabilityResult
        Over the whole flight, ``P0`` at the first epoch.
    thresholds : dict
        ``eta``, ``nu``, ``e_threshold``, ``s_threshold``, ``min_fraction``.
    options : dict
        Assumed values: ``preset``, ``gnss_rate_hz``, ``gnss_sigma_m``, fit and segmentation
        options, model options.
    gnss_residuals, imu_residuals : DataFrame
        Fit residuals over time (:func:`fit_residuals`).
    notes : tuple of str
        Fallbacks taken (e.g. an assumed heading).

    ``segments`` (tuple of ``(t_start, t_end)``), ``settings`` and ``state_names`` give the
    view the figure builders of :mod:`navlib.plots.metrics` read (as from a
    :class:`navlib.studies.rocket.RocketAnalysis`).
    """

    trajectory: object
    inputs: pd.DataFrame
    fit: pd.DataFrame
    automatic: Segmentation
    segment_table: pd.DataFrame
    model: object
    excitability: tuple
    sensability: object
    thresholds: dict
    options: dict = field(default_factory=dict)
    gnss_residuals: pd.DataFrame | None = None
    imu_residuals: pd.DataFrame | None = None
    notes: tuple[str, ...] = ()

    @property
    def state_names(self) -> tuple[str, ...]:
        return tuple(self.model.state_names)

    @property
    def segments(self) -> tuple[tuple[float, float], ...]:
        """``(t_start, t_end)`` of each assessed segment, s."""
        return tuple((float(a), float(b)) for a, b in
                     zip(self.segment_table["t_start"], self.segment_table["t_end"],
                         strict=True))

    @property
    def settings(self) -> dict:
        """Thresholds and model choices, as the metric figure builders label them."""
        return {**self.thresholds, "d0": "global",
                "attitude_error": self.options.get("model_options", {}).get("attitude_error",
                                                                            "ecef"),
                "preset": self.options.get("preset"),
                "gnss_sigma_m": self.options.get("gnss_sigma_m")}

    def excitability_frame(self) -> pd.DataFrame:
        """Long table: one row per (segment, state): ``segment``, ``phase``, ``t_start``,
        ``t_end``, ``state``, ``paper_id`` (e1..e21), ``group``, ``e``, ``excitable``
        (``e >= e_threshold``), ``ne``."""
        frames = []
        for row, ex in zip(self.segment_table.itertuples(index=False), self.excitability,
                           strict=True):
            frames.append(pd.DataFrame({
                "segment": row.segment, "phase": row.phase, "t_start": row.t_start,
                "t_end": row.t_end, "state": list(self.state_names),
                "paper_id": [PAPER_IDS[s] for s in self.state_names],
                "group": [_GROUP_OF[s] for s in self.state_names],
                "e": ex.e, "excitable": ex.e >= self.thresholds["e_threshold"], "ne": ex.ne,
            }))
        return pd.concat(frames, ignore_index=True)

    def excitability_table(self) -> pd.DataFrame:
        """Wide table: the 21 states (rows, model order) by segments (columns), values ``e``."""
        long = self.excitability_frame()
        long["label"] = [_label(r) for r in long.itertuples(index=False)]
        wide = long.pivot(index="state", columns="label", values="e")
        labels = [_label(r) for r in self.segment_table.itertuples(index=False)]
        return wide.loc[list(self.state_names), labels]

    def sensability_frame(self) -> pd.DataFrame:
        """Long table over time: ``t``, ``state``, ``s``, ``sigma`` (physical 1-sigma), ``nr``,
        plus the ``segment`` and ``phase`` holding each epoch (NaN/"" outside segments)."""
        frame = self.sensability.to_frame()
        seg = _segment_of(self.sensability.t, self.segment_table)
        index = np.repeat(seg, len(self.state_names))
        table = self.segment_table
        frame["segment"] = np.where(index >= 0, table["segment"].to_numpy()[index], np.nan)
        frame["phase"] = np.where(index >= 0, table["phase"].to_numpy()[index], "")
        return frame

    def state_table(self) -> pd.DataFrame:
        """One row per (segment, state): ``e``, ``excitable``, ``s_fraction`` (share of the
        segment's epochs with ``s >= s_threshold``), ``sensible`` (``s_fraction >=
        min_fraction``), ``sigma_start``, ``sigma_end`` (physical posterior 1-sigma at the
        segment's first and last epoch, SI) and their ``sigma_ratio``."""
        long = self.excitability_frame()
        se = self.sensability
        t = se.t
        s_ok = se.s >= self.thresholds["s_threshold"]
        fraction, start, end = [], [], []
        for row in self.segment_table.itertuples(index=False):
            sel = np.flatnonzero((t >= row.t_start - 1e-9) & (t <= row.t_end + 1e-9))
            fraction.append(s_ok[sel].mean(axis=0))
            start.append(se.sigma[sel[0]])
            end.append(se.sigma[sel[-1]])
        long["s_fraction"] = np.concatenate(fraction)
        long["sensible"] = long["s_fraction"] >= self.thresholds["min_fraction"]
        long["sigma_start"] = np.concatenate(start)
        long["sigma_end"] = np.concatenate(end)
        long["sigma_ratio"] = long["sigma_end"] / long["sigma_start"]
        return long

    def summary(self) -> pd.DataFrame:
        """One row per segment: limits, ``n_epochs``, ``ne``, and the states that segment
        could estimate by each metric: ``excitable`` and ``sensible`` (comma-separated state
        names at the thresholds of ``thresholds``), with their counts."""
        table = self.state_table()
        rows = []
        for seg in self.segment_table.itertuples(index=False):
            part = table[table["segment"] == seg.segment]
            excitable = part.loc[part["excitable"], "state"].tolist()
            sensible = part.loc[part["sensible"], "state"].tolist()
            rows.append({"segment": seg.segment, "phase": seg.phase, "t_start": seg.t_start,
                         "t_end": seg.t_end, "n_epochs": seg.n_epochs,
                         "ne": int(part["ne"].iloc[0]), "n_excitable": len(excitable),
                         "excitable": ", ".join(excitable) or "-",
                         "n_sensible": len(sensible), "sensible": ", ".join(sensible) or "-"})
        return pd.DataFrame(rows)

    def to_frame(self) -> pd.DataFrame:
        """The per-segment :meth:`summary`."""
        return self.summary()

    def with_settings(self, segments=None, *, eta: float | None = None,
                      nu: float | None = None, e_threshold: float | None = None,
                      s_threshold: float | None = None,
                      min_fraction: float | None = None) -> FlightAssessment:
        """The same flight with other segments or thresholds (no refit, same model).

        ``segments`` as in :func:`assess_flight` (None keeps the current ones; ``"auto"``
        returns to the automatic segmentation).
        """
        th = _thresholds({**self.thresholds, **{k: v for k, v in (
            ("eta", eta), ("nu", nu), ("e_threshold", e_threshold),
            ("s_threshold", s_threshold), ("min_fraction", min_fraction)) if v is not None}})
        if segments is None:
            table = self.segment_table.drop(columns=["segment", "n_epochs"])
        elif isinstance(segments, str) and segments == "auto":
            table = self.automatic.segments
        else:
            table = segments
        table = _segment_table(table, self.model, self.automatic, self.trajectory.t)
        excit = _excitability(self.model, table, th["eta"])
        sens = self.sensability if th["nu"] == self.sensability.nu else \
            self.sensability.with_nu(th["nu"])
        return replace(self, segment_table=table, excitability=excit, sensability=sens,
                       thresholds=th)


def _segment_of(t: np.ndarray, segments: pd.DataFrame) -> np.ndarray:
    """Index (0-based row of ``segments``) holding each time, -1 outside; a boundary epoch
    belongs to the later segment."""
    out = np.full(t.size, -1)
    for i, row in enumerate(segments.itertuples(index=False)):
        out[(t >= row.t_start - 1e-9) & (t <= row.t_end + 1e-9)] = i
    return out


def _thresholds(values: Mapping) -> dict:
    return {
        "eta": finite_scalar(values["eta"], "eta", 0.0, 1.0, low_open=True),
        "nu": finite_scalar(values["nu"], "nu", 0.0, 1.0, low_open=True),
        "e_threshold": finite_scalar(values["e_threshold"], "e_threshold", 0.0, 1.0),
        "s_threshold": finite_scalar(values["s_threshold"], "s_threshold", 0.0, 1.0),
        "min_fraction": finite_scalar(values["min_fraction"], "min_fraction", 0.0, 1.0),
    }


def _segment_table(segments, model, automatic: Segmentation, t_flight) -> pd.DataFrame:
    """Normalise ``segments`` (inside the fitted flight ``t_flight``) and count the model
    epochs each holds (at least 2 needed; the last epoch may precede the flight's end)."""
    table = segments_table(segments, float(t_flight[0]), float(t_flight[-1]), automatic)
    t = model.t
    counts = [int(np.count_nonzero((t >= a - 1e-9) & (t <= b + 1e-9)))
              for a, b in zip(table["t_start"], table["t_end"], strict=True)]
    for k, (count, row) in enumerate(zip(counts, table.itertuples(index=False), strict=True)):
        if count < 2:
            raise NavlibInputError(
                f"segments: segment {k + 1} ({row.phase}, {row.t_start:.6g}..{row.t_end:.6g} s)"
                f" holds {count} GNSS epoch(s) of the model; each segment needs at least 2 "
                f"(epochs every {np.median(np.diff(t)):.3g} s)")
    table.insert(0, "segment", np.arange(1, len(table) + 1))
    table["n_epochs"] = counts
    return table


def _excitability(model, table: pd.DataFrame, eta: float) -> tuple:
    return tuple(excitability_segment(model, row.t_start, row.t_end, eta=eta)
                 for row in table.itertuples(index=False))


# --------------------------------------------------------------------------- pipeline


def _gnss_sigma(gnss: pd.DataFrame, spec) -> float:
    if "sigma" in gnss.columns:
        sigma = gnss["sigma"].to_numpy(dtype=float)
        sigma = sigma[np.isfinite(sigma) & (sigma > 0)]
        if sigma.size:
            return float(np.median(sigma))
    gnss_spec = getattr(spec, "gnss", None)
    if gnss_spec is not None and gnss_spec.position_sigma > 0:
        return float(gnss_spec.position_sigma)
    return 5.0


def assess_flight(imu: pd.DataFrame, gnss: pd.DataFrame, preset: str = "motionpak_tactical",
                  segments=None, eta: float = 1e-3, nu: float = 0.985,
                  gnss_rate_hz: float | None = None, *, e_threshold: float = E_THRESHOLD,
                  s_threshold: float = S_THRESHOLD, min_fraction: float = MIN_FRACTION,
                  gnss_sigma_m: float | None = None, heading_fallback_deg: float | None = 0.0,
                  fit_options: Mapping | None = None, segment_options: Mapping | None = None,
                  model_options: Mapping | None = None) -> FlightAssessment:
    """Fit, segment and assess a recorded flight with the 21-state ECEF model.

    Parameters
    ----------
    imu, gnss : DataFrame
        Records on a common time base, as from :func:`navlib.io.read_imu_csv`,
        :func:`navlib.io.read_gnss_csv` or :func:`navlib.io.read_ulog` (SI; ``gnss`` in
        ECEF, optional ``vx, vy, vz`` and ``sigma``).
    preset : str
        Sensor preset (``data/sensors/*.toml``) giving the IMU noise densities and the
        turn-on sigmas of ``P0`` (:func:`navlib.models.ecef.parameter_sigmas`).
    segments : None, DataFrame or list
        None: the automatic segmentation (:func:`navlib.segmentation.segment_flight`).
        Otherwise anything :func:`navlib.segmentation.segments_table` accepts: an edited
        segment table, a list of boundaries (``[18, 46]``) or of ``(t_start, t_end)`` /
        ``(phase, t_start, t_end)`` entries. Each segment needs 2 GNSS epochs.
    eta : float in (0, 1)
        Excitability energy threshold (spec A14).
    nu : float in (0, 1)
        Sensability threshold (spec A11; 0.985 is the paper's value for 21 states).
    gnss_rate_hz : float, optional
        Measurement rate of the model; None: the median rate of the GNSS record.
    e_threshold, s_threshold, min_fraction : float in [0, 1]
        Summary thresholds (module docstring).
    gnss_sigma_m : float, optional
        GNSS position sigma of the model; None: the median ``sigma`` of the record, else the
        preset's GNSS sigma, else 5 m.
    heading_fallback_deg : float or None
        Initial heading assumed when the fit cannot estimate it from the motion (hover,
        rest); recorded in ``notes`` with a :class:`~navlib.io.FlightDataWarning`. None
        lets the fit's error through.
    fit_options, segment_options, model_options : mapping, optional
        Keywords of :func:`navlib.trajectory.fit_flight_data`,
        :func:`navlib.segmentation.segment_flight` and
        :func:`navlib.models.ecef.ecef21_at_epochs` (``attitude_error``, P0 sigmas...).

    Returns
    -------
    FlightAssessment

    Raises
    ------
    NavlibInputError
        Records that are not DataFrames or lack columns, records split at gaps, records
        that do not overlap, overlap shorter than 2 s or holding fewer than 4 GNSS epochs,
        bad thresholds or segments (naming the segment), and the fit's own input errors.
    """
    thresholds = _thresholds({"eta": eta, "nu": nu, "e_threshold": e_threshold,
                              "s_threshold": s_threshold, "min_fraction": min_fraction})
    if not isinstance(preset, str):
        raise NavlibInputError(f"preset: expected a sensor preset name, got {preset!r}")
    spec = sensors.load_preset(preset)  # unknown names fail here, before the fit
    fit_options = dict(fit_options or {})
    segment_options = dict(segment_options or {})
    reject_unknown(segment_options, SEGMENT_DEFAULTS, "segment_options")
    model_options = dict(model_options or {})
    if "gnss_sigma_m" in model_options:
        raise NavlibInputError("model_options: pass gnss_sigma_m as its own keyword")
    if heading_fallback_deg is not None:
        heading_fallback_deg = finite_scalar(heading_fallback_deg, "heading_fallback_deg",
                                             -360.0, 360.0)
    span = _validate(imu, gnss)
    inputs = describe_inputs(imu, gnss)
    t_g = gnss["t"].to_numpy(dtype=float)
    t_g = t_g[(t_g >= span.t_start) & (t_g <= span.t_end)]
    if gnss_rate_hz is None:
        gnss_rate_hz = _median_rate(t_g)
    gnss_rate_hz = finite_scalar(gnss_rate_hz, "gnss_rate_hz", 0.0, low_open=True)
    sigma = _gnss_sigma(gnss, spec) if gnss_sigma_m is None else gnss_sigma_m
    sigma = finite_scalar(sigma, "gnss_sigma_m", 0.0, low_open=True)

    trajectory, notes = _fit(imu, gnss, fit_options, heading_fallback_deg)
    fit = fit_report(trajectory, preset, sigma)
    gnss_res, imu_res = fit_residuals(trajectory, imu, gnss)

    min_epochs_s = 2.0 / gnss_rate_hz
    seg_opts = dict(segment_options)
    seg_opts["min_duration_s"] = max(seg_opts.get("min_duration_s", 2.0), min_epochs_s)
    automatic = segment_flight(trajectory, **seg_opts)

    model = ecef21_at_epochs(trajectory, gnss_rate_hz, sensors=preset, gnss_sigma_m=sigma,
                             **model_options)
    table = _segment_table(automatic.segments if segments is None else segments, model,
                           automatic, trajectory.t)
    excit = _excitability(model, table, thresholds["eta"])
    sens = sensability_model(model, nu=thresholds["nu"])
    options = {"preset": preset, "gnss_rate_hz": gnss_rate_hz, "gnss_sigma_m": sigma,
               "heading_fallback_deg": heading_fallback_deg, "fit_options": fit_options,
               "segment_options": seg_opts, "model_options": model_options,
               "imu_rate_hz": trajectory.rate_hz,
               "heading_deg": trajectory.parameters.get("fit_residuals", {}).get("heading_deg")}
    return FlightAssessment(trajectory=trajectory, inputs=inputs, fit=fit, automatic=automatic,
                            segment_table=table, model=model, excitability=excit,
                            sensability=sens, thresholds=thresholds, options=options,
                            gnss_residuals=gnss_res, imu_residuals=imu_res,
                            notes=tuple(notes))
