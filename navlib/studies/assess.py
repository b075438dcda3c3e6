"""Assess a recorded flight: which navigation states could it estimate, segment by segment?

The excitability and sensability pipeline applied to a user's own IMU and GNSS records
(España, Carrizo & Giribet 2019, §4-6, with the 21-state ECEF model)::

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
epochs (the defaults of :mod:`navlib.metrics`). :class:`FlightAssessment` is a
:class:`navlib.metrics.SegmentedAnalysis`, so its ``with_settings`` re-evaluates new
segments or thresholds without refitting or rediscretising (the widgets use it).

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

from navlib import quality, sensors
from navlib._validation import finite_scalar, reject_unknown
from navlib.errors import NavlibInputError
from navlib.io import FlightDataWarning, check_overlap
from navlib.metrics import (
    E_THRESHOLD,
    MIN_FRACTION,
    S_THRESHOLD,
    SegmentedAnalysis,
    check_thresholds,
    in_segment,
)
from navlib.models.ecef import PAPER_IDS, STATE_GROUPS, ecef21_at_epochs
from navlib.segmentation import (
    SEGMENT_DEFAULTS,
    Segmentation,
    check_vehicle,
    recognise_vehicle,
    segment_flight,
    segments_table,
    vehicle_from_log,
)
from navlib.trajectory import fit_flight_data
from navlib.trajectory.fit import FIT_DEFAULTS

__all__ = ["FlightAssessment", "assess_flight", "choose_preset", "describe_inputs",
           "fit_report", "fit_residuals"]

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
    if len(frame) < 2:
        raise NavlibInputError(f"{name}: need at least 2 rows, got {len(frame)}")


def _median_rate(t: np.ndarray) -> float:
    return float(1.0 / np.median(np.diff(t))) if t.size > 1 else float("nan")


def describe_inputs(imu: pd.DataFrame, gnss: pd.DataFrame) -> pd.DataFrame:
    """One row per record (``imu``, ``gnss``, and their ``overlap``): samples, first and
    last time (s), duration (s), median rate (Hz), longest interval (s), gaps reported by
    the reader (``attrs["gaps"]``), samples the reader excluded as outliers
    (``attrs["outliers"]``, :func:`navlib.io.checks.flag_imu_outliers`) and the source
    file."""
    _check_frame(imu, "imu", _IMU_KEYS)
    _check_frame(gnss, "gnss", _GNSS_KEYS)
    rows = []
    for name, frame in (("imu", imu), ("gnss", gnss)):
        t = frame["t"].to_numpy(dtype=float)
        rows.append({"record": name, "samples": t.size, "t_first": t[0], "t_last": t[-1],
                     "duration_s": t[-1] - t[0], "rate_hz": _median_rate(t),
                     "longest_interval_s": float(np.max(np.diff(t))),
                     "gaps": len(frame.attrs.get("gaps", [])),
                     "outliers": len(frame.attrs.get("outliers", [])),
                     "source": str(frame.attrs.get("source", ""))})
    span = check_overlap(imu, gnss)
    t_i = imu["t"].to_numpy(dtype=float)
    inside = int(np.count_nonzero((t_i >= span.t_start) & (t_i <= span.t_end)))
    rows.append({"record": "overlap", "samples": inside, "t_first": span.t_start,
                 "t_last": span.t_end, "duration_s": span.duration, "rate_hz": np.nan,
                 "longest_interval_s": np.nan, "gaps": np.nan, "outliers": np.nan,
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
        given = any(fit_options.get(k) is not None for k in (
            "heading_deg", "initial_attitude", "initial_attitude_deg", "launch_azimuth_deg"))
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
class FlightAssessment(SegmentedAnalysis):
    """Everything :func:`assess_flight` computed, with tidy views.

    A :class:`navlib.metrics.SegmentedAnalysis` (``model``: the 21-state ECEF model
    discretised at the GNSS epochs; ``trajectory``: the fitted reference trajectory, exact
    IMU, ``parameters["fit_residuals"]``; ``segments``; ``excitability`` one per segment in
    the order of ``segment_table``; ``sensability`` over the whole flight, ``P0`` at the
    first epoch; ``settings`` and ``thresholds``: ``eta``, ``nu``, ``e_threshold``,
    ``s_threshold``, ``min_fraction``) whose segments carry the flight phases, with:

    Attributes
    ----------
    inputs : DataFrame
        :func:`describe_inputs` of the records.
    fit : DataFrame
        :func:`fit_report` of the residuals.
    automatic : Segmentation
        The automatic segmentation (features and phases), whatever segments were used.
    segment_table : DataFrame
        The segments assessed: ``segment`` (1-based), ``phase``, ``t_start``, ``t_end``,
        ``duration``, ``n_epochs`` (GNSS epochs of the model inside).
    options : dict
        Assumed values: ``preset``, ``gnss_rate_hz``, ``gnss_sigma_m``, fit and segmentation
        options, model options.
    gnss_residuals, imu_residuals : DataFrame
        Fit residuals over time (:func:`fit_residuals`).
    notes : tuple of str
        Assumptions and fallbacks taken (preset, initial attitude, levelling window, bridged
        holes, excluded samples, an assumed heading, a split record).
    spans : tuple of FlightAssessment
        When the record was split at long holes: every span's assessment in time order
        (this one among them); empty otherwise.
    quality : DataFrame or None
        The data-quality findings of the whole record (:func:`navlib.quality.check_records`:
        saturated IMU samples, frozen, disagreeing or jumping GNSS fixes, all dropped
        before the fit); each ``message`` was also issued as a
        :class:`~navlib.io.FlightDataWarning`.

    The long frames name each segment by ``segment`` (1-based) and ``phase``, and each state
    by ``state``, ``paper_id`` (e1..e21) and ``group``; the wide
    :meth:`~navlib.metrics.SegmentedAnalysis.excitability_table` labels its columns
    ``"<segment> <phase> <t_start>-<t_end> s"``; :meth:`to_frame` is the per-segment
    :meth:`~navlib.metrics.SegmentedAnalysis.summary`.
    """

    inputs: pd.DataFrame
    fit: pd.DataFrame
    automatic: Segmentation
    segment_table: pd.DataFrame
    options: dict = field(default_factory=dict)
    gnss_residuals: pd.DataFrame | None = None
    imu_residuals: pd.DataFrame | None = None
    notes: tuple[str, ...] = ()
    spans: tuple = ()
    quality: pd.DataFrame | None = None

    @property
    def vehicle(self) -> str:
        """The vehicle class whose words name the phases (``options["vehicle"]``)."""
        return self.options.get("vehicle", "")

    @property
    def labels(self) -> tuple[str, ...]:
        return tuple(_label(r) for r in self.segment_table.itertuples(index=False))

    def _segment_keys(self) -> dict:
        return {"segment": self.segment_table["segment"].to_numpy(),
                "phase": self.segment_table["phase"].to_numpy()}

    def _state_columns(self) -> dict:
        return {**super()._state_columns(),
                "paper_id": [PAPER_IDS[s] for s in self.state_names],
                "group": [_GROUP_OF[s] for s in self.state_names]}

    def to_frame(self) -> pd.DataFrame:
        """The per-segment :meth:`~navlib.metrics.SegmentedAnalysis.summary`."""
        return self.summary()

    def _segment_changes(self, segments) -> dict:
        """``segments`` as in :func:`assess_flight` (None keeps the current ones; ``"auto"``
        returns to the automatic segmentation)."""
        if segments is None:
            return {}
        if isinstance(segments, str) and segments == "auto":
            segments = self.automatic.segments
        table = _segment_table(segments, self.model, self.automatic, self.trajectory.t)
        return {"segment_table": table, "segments": _pairs(table)}


def _pairs(table: pd.DataFrame) -> tuple[tuple[float, float], ...]:
    return tuple((float(a), float(b)) for a, b in zip(table["t_start"], table["t_end"],
                                                      strict=True))


def _segment_table(segments, model, automatic: Segmentation, t_flight) -> pd.DataFrame:
    """Normalise ``segments`` (inside the fitted flight ``t_flight``) and count the model
    epochs each holds (at least 2 needed; the last epoch may precede the flight's end)."""
    table = segments_table(segments, float(t_flight[0]), float(t_flight[-1]), automatic)
    counts = _epoch_counts(table, model.t)
    for k, (count, row) in enumerate(zip(counts, table.itertuples(index=False), strict=True)):
        if count < 2:
            raise NavlibInputError(
                f"segments: segment {k + 1} ({row.phase}, {row.t_start:.6g}..{row.t_end:.6g} s)"
                f" holds {count} GNSS epoch(s) of the model; each segment needs at least 2 "
                f"(epochs every {np.median(np.diff(model.t)):.3g} s)")
    table.insert(0, "segment", np.arange(1, len(table) + 1))
    table["n_epochs"] = counts
    return table


def _epoch_counts(table: pd.DataFrame, t) -> list[int]:
    """Model epochs at ``t`` inside each segment."""
    return [int(np.count_nonzero(in_segment(t, a, b)))
            for a, b in zip(table["t_start"], table["t_end"], strict=True)]


def automatic_segment_table(segments, model, automatic: Segmentation, t_flight, *,
                            automatic_segments: bool) -> tuple[pd.DataFrame, list[str]]:
    """:func:`_segment_table` of ``segments``, with each automatic segment that holds fewer
    than two measured epochs of the model (a short phase between GNSS fixes, or one inside a
    GNSS outage: rows of ``model.H`` that are zero) joined to the segment before it (after
    it, for the first), with a note: excitability needs measurements (assumptions V1, M6).
    Segments the user gave (``automatic_segments=False``) are refused instead, naming the
    segment. Returns the table and the notes."""
    t = np.asarray(model.t)
    measured = np.any(np.asarray(model.H) != 0.0, axis=(1, 2))
    table = segments_table(segments, float(t_flight[0]), float(t_flight[-1]), automatic)
    entries = [[r.phase, float(r.t_start), float(r.t_end)]
               for r in table.itertuples(index=False)]
    notes = []
    k = 0
    while k < len(entries) and len(entries) > 1:
        phase, a, b = entries[k]
        count = int(np.count_nonzero(measured & in_segment(t, a, b)))
        if count >= 2:
            k += 1
            continue
        outage = count < np.count_nonzero(in_segment(t, a, b))
        why = ("lies inside a GNSS outage (no measurement, no excitability)" if outage else
               f"holds {count} GNSS epoch(s) of the model; each segment needs at least 2")
        if not automatic_segments:
            raise NavlibInputError(f"segments: segment {k + 1} ({phase}, {a:.6g}..{b:.6g} s) "
                                   f"{why}; join it to a neighbour")
        other = k - 1 if k > 0 else k + 1
        notes.append(f"segment {phase} {a:.6g}-{b:.6g} s {why}: joined to the "
                     f"{entries[other][0]} segment next to it")
        lo, hi = min(k, other), max(k, other)
        entries[lo] = [entries[other][0], entries[lo][1], entries[hi][2]]
        del entries[hi]
        k = lo
    return _segment_table([tuple(e) for e in entries], model, automatic, t_flight), notes



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


DEFAULT_PRESET = "motionpak_tactical"
"""Sensor preset of records that do not say what their hardware is (CSV files)."""
AUTOPILOT_PRESETS = {"px4": "pixhawk_mems", "ardupilot": "pixhawk_mems",
                     "altos": "altus_telemega"}
"""Preset chosen by default for logs whose reader found the autopilot or flight computer
(``attrs["autopilot"]``): the consumer MEMS class of the Pixhawk family
(``data/sensors/pixhawk_mems.toml``), the MPU-6000 class of the Altus Metrum TeleMega
(``data/sensors/altus_telemega.toml``)."""
MODEL_STEP_S = 0.02
"""Longest model step of the assessment (``ecef21_at_epochs(max_step_s=...)``), s: IMU steps
are grouped to 50 Hz, which keeps long flights fast while the 1 s transitions move by less
than 1e-3 relative on the sample flight (benchmarks/bench_assess.py)."""


def choose_preset(imu: pd.DataFrame, preset: str | None = None) -> tuple[str, str]:
    """The sensor preset to assess ``imu`` with and why: ``preset`` when given, else the
    :data:`AUTOPILOT_PRESETS` entry of the autopilot the reader found in the log, else
    :data:`DEFAULT_PRESET`."""
    if preset is not None:
        if not isinstance(preset, str):
            raise NavlibInputError(f"preset: expected a sensor preset name, got {preset!r}")
        return preset, "given"
    autopilot = str(getattr(imu, "attrs", {}).get("autopilot", "")).lower()
    if autopilot in AUTOPILOT_PRESETS:
        hardware = imu.attrs.get("hardware") or "hardware not named"
        return AUTOPILOT_PRESETS[autopilot], f"{autopilot} log ({hardware})"
    return DEFAULT_PRESET, "default (the records do not say what the IMU is)"


def _pieces(imu: pd.DataFrame, max_bridge_s: float) -> list[tuple[float, float]]:
    """IMU time spans separated by holes longer than ``max_bridge_s`` or by the reader's
    ``segment`` column (``on_gap="split"``)."""
    t = imu["t"].to_numpy(dtype=float)
    cut = np.diff(t) > max_bridge_s
    if "segment" in imu.columns:
        cut |= np.diff(imu["segment"].to_numpy()) != 0
    after = np.flatnonzero(cut) + 1
    starts, ends = np.r_[0, after], np.r_[after - 1, t.size - 1]
    return [(float(t[a]), float(t[b])) for a, b in zip(starts, ends, strict=True)]


def _piece(frame: pd.DataFrame, t0: float, t1: float) -> pd.DataFrame:
    t = frame["t"].to_numpy(dtype=float)
    out = frame[(t >= t0) & (t <= t1)].drop(columns="segment", errors="ignore")
    out = out.reset_index(drop=True)
    out.attrs = dict(frame.attrs)
    return out


def assess_flight(imu: pd.DataFrame, gnss: pd.DataFrame, preset: str | None = None,
                  segments=None, eta: float = 1e-3, nu: float = 0.985,
                  gnss_rate_hz: float | None = None, *, e_threshold: float = E_THRESHOLD,
                  s_threshold: float = S_THRESHOLD, min_fraction: float = MIN_FRACTION,
                  gnss_sigma_m: float | None = None, heading_fallback_deg: float | None = 0.0,
                  fit_options: Mapping | None = None, segment_options: Mapping | None = None,
                  model_options: Mapping | None = None,
                  model_step_s: float | None = MODEL_STEP_S, vehicle: str | None = None,
                  quality_thresholds: Mapping | None = None) -> FlightAssessment:
    """Fit, segment and assess a recorded flight with the 21-state ECEF model.

    Parameters
    ----------
    imu, gnss : DataFrame
        Records on a common time base, as from :func:`navlib.io.read_imu_csv`,
        :func:`navlib.io.read_gnss_csv`, :func:`navlib.io.read_ulog` or
        :func:`navlib.io.read_dataflash` (SI; ``gnss`` in ECEF, optional ``vx, vy, vz`` and
        ``sigma``). An IMU ``segment`` column (``on_gap="split"``) and IMU holes longer
        than the fit's ``max_bridge_s`` (default 1 s) split the flight into spans assessed
        separately; shorter holes are bridged by the fit, with a stated bound
        (``notes``); GNSS gaps (and a GNSS ``segment`` column) are bridged by the IMU. An
        autopilot attitude in ``imu.attrs["attitude"]`` (ULog, DataFlash) is the initial
        attitude unless ``fit_options`` say otherwise.
    preset : str, optional
        Sensor preset (``data/sensors/*.toml``) giving the IMU noise densities and the
        turn-on sigmas of ``P0`` (:func:`navlib.models.ecef.parameter_sigmas`). None:
        :func:`choose_preset` (the Pixhawk-class preset for PX4 and ArduPilot logs, else
        ``motionpak_tactical``); the choice and its reason are in ``options``.
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
        Measurement rate of the model; None: the median rate of the GNSS record (at most
        the IMU rate).
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
        Keywords of :func:`navlib.trajectory.fit_flight_data` (its ``preset`` defaults to
        ``preset``), :func:`navlib.segmentation.segment_flight` and
        :func:`navlib.models.ecef.ecef21_at_epochs` (``attitude_error``, P0 sigmas...).
    model_step_s : float or None
        Longest step of the model build (:data:`MODEL_STEP_S`); None: every IMU step.
    vehicle : str, optional
        One of :data:`navlib.segmentation.VEHICLES` (rocket, multicopter, fixed-wing,
        ground): the phases take its words. None: what the log says
        (:func:`navlib.segmentation.vehicle_from_log`), else recognised from the fitted
        kinematics (:func:`navlib.segmentation.recognise_vehicle`); the choice and its
        reason are in ``options``.
    quality_thresholds : mapping, optional
        Overrides of the data-quality thresholds of ``data/quality.toml``
        (:func:`navlib.quality.load_thresholds`, e.g. ``{"gnss": {"jump_min_m": 20}}``).
        Saturated IMU samples and faulty GNSS fixes are found, warned about with times and
        dropped before the fit (:func:`navlib.quality.check_records`, assumptions Q1-Q4).

    Returns
    -------
    FlightAssessment
        Of the longest span when the record was split; ``spans`` then holds every span's
        assessment in time order.

    Raises
    ------
    NavlibInputError
        Records that are not DataFrames or lack columns, records that do not overlap,
        overlap shorter than 2 s or holding fewer than 4 GNSS epochs (of every span), too
        much of the flight saturated or too many GNSS fixes faulty, IMU rates below the
        fit's minimum (:data:`navlib.trajectory.fit.MIN_IMU_RATE_HZ`), bad thresholds or
        segments (naming the segment), and the fit's own input errors.
    """
    thresholds = check_thresholds(eta, nu, e_threshold, s_threshold, min_fraction)
    _check_frame(imu, "imu", _IMU_KEYS)
    _check_frame(gnss, "gnss", _GNSS_KEYS)
    gnss = gnss.drop(columns="segment", errors="ignore")   # GNSS gaps: bridged by the IMU
    preset, preset_reason = choose_preset(imu, preset)
    spec = sensors.load_preset(preset)  # unknown names fail here, before the fit
    fit_options = {"preset": preset, **dict(fit_options or {})}
    segment_options = dict(segment_options or {})
    reject_unknown(segment_options, SEGMENT_DEFAULTS, "segment_options")
    model_options = dict(model_options or {})
    if "gnss_sigma_m" in model_options:
        raise NavlibInputError("model_options: pass gnss_sigma_m as its own keyword")
    if heading_fallback_deg is not None:
        heading_fallback_deg = finite_scalar(heading_fallback_deg, "heading_fallback_deg",
                                             -360.0, 360.0)
    if model_step_s is not None:
        model_step_s = finite_scalar(model_step_s, "model_step_s", 0.0, low_open=True)
    max_bridge_s = finite_scalar(fit_options.get("max_bridge_s", FIT_DEFAULTS["max_bridge_s"]),
                                 "max_bridge_s", 0.0, low_open=True)
    if vehicle is not None:
        vehicle, vehicle_reason = check_vehicle(vehicle), "given"
    else:
        vehicle, vehicle_reason = vehicle_from_log(imu.attrs)
    sigma = _gnss_sigma(gnss, spec) if gnss_sigma_m is None else gnss_sigma_m
    checked = quality.check_records(imu, gnss, spec,
                                    finite_scalar(sigma, "gnss_sigma_m", 0.0, low_open=True),
                                    quality_thresholds)
    for message in checked.warnings:
        warnings.warn(message, FlightDataWarning, stacklevel=2)
    imu, gnss = checked.imu, checked.gnss
    kwargs = {"spec": spec, "preset": preset, "preset_reason": preset_reason,
              "segments": segments, "thresholds": thresholds, "gnss_rate_hz": gnss_rate_hz,
              "gnss_sigma_m": gnss_sigma_m, "heading_fallback_deg": heading_fallback_deg,
              "fit_options": fit_options, "segment_options": segment_options,
              "model_options": model_options, "model_step_s": model_step_s,
              "vehicle": vehicle, "vehicle_reason": vehicle_reason,
              "findings": checked.findings}
    pieces = _pieces(imu, max_bridge_s)
    if len(pieces) == 1:
        return _assess_span(imu.drop(columns="segment", errors="ignore"), gnss, **kwargs)
    results, skipped = [], []
    for t0, t1 in pieces:
        try:
            results.append(_assess_span(_piece(imu, t0, t1), _piece(gnss, t0, t1), **kwargs))
        except NavlibInputError as exc:
            skipped.append(f"{t0:.6g}..{t1:.6g} s ({exc})")
    listing = ", ".join(f"{a:.6g}..{b:.6g} s" for a, b in pieces)
    if not results:
        raise NavlibInputError(
            f"imu: holes longer than max_bridge_s={max_bridge_s:g} s (or the reader's "
            f"'segment' column) split the record into {len(pieces)} spans ({listing}) and "
            f"none could be assessed: {'; '.join(skipped)}")
    main = max(results, key=lambda r: float(r.trajectory.t[-1] - r.trajectory.t[0]))
    index = next(i for i, r in enumerate(results) if r is main)
    note = (f"the IMU record has {len(pieces) - 1} hole(s) longer than max_bridge_s="
            f"{max_bridge_s:g} s, so it was split into {len(pieces)} spans ({listing}) assessed "
            f"separately; this result is the longest assessed span "
            f"{main.trajectory.t[0]:.6g}..{main.trajectory.t[-1]:.6g} s, all {len(results)} "
            f"are in .spans" + (f"; not assessed: {'; '.join(skipped)}" if skipped else ""))
    warnings.warn(note, FlightDataWarning, stacklevel=2)
    results[index] = replace(main, notes=(*main.notes, note))
    spans = tuple(results)
    return replace(results[index], spans=spans)


def _assess_span(imu, gnss, *, spec, preset, preset_reason, segments, thresholds,
                 gnss_rate_hz, gnss_sigma_m, heading_fallback_deg, fit_options,
                 segment_options, model_options, model_step_s, vehicle, vehicle_reason,
                 findings) -> FlightAssessment:
    """:func:`assess_flight` of one span without holes longer than ``max_bridge_s``."""
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
    gnss_rate_hz = min(gnss_rate_hz, trajectory.rate_hz)
    notes = [f"sensor preset {preset!r}: {preset_reason}", *notes, *_fit_notes(trajectory),
             *_outlier_notes(imu)]
    fit = fit_report(trajectory, preset, sigma)
    gnss_res, imu_res = fit_residuals(trajectory, imu, gnss)

    min_epochs_s = 2.0 / gnss_rate_hz
    seg_opts = dict(segment_options)
    seg_opts["min_duration_s"] = max(seg_opts.get("min_duration_s", 2.0), min_epochs_s)
    if vehicle is None:
        vehicle, vehicle_reason = recognise_vehicle(trajectory)
    notes.append(f"vehicle {vehicle!r}: {vehicle_reason}")
    automatic = segment_flight(trajectory, vehicle=vehicle, **seg_opts)

    model = ecef21_at_epochs(trajectory, gnss_rate_hz, sensors=preset, gnss_sigma_m=sigma,
                             max_step_s=model_step_s, **model_options)
    table, joined = automatic_segment_table(
        automatic.segments if segments is None else segments, model, automatic, trajectory.t,
        automatic_segments=segments is None)
    notes += joined
    residuals = trajectory.parameters.get("fit_residuals", {})
    options = {"preset": preset, "preset_reason": preset_reason, "gnss_rate_hz": gnss_rate_hz,
               "gnss_sigma_m": sigma, "heading_fallback_deg": heading_fallback_deg,
               "fit_options": fit_options, "segment_options": seg_opts,
               "model_options": model_options, "model_step_s": model_step_s,
               "imu_rate_hz": trajectory.rate_hz, "heading_deg": residuals.get("heading_deg"),
               "attitude_source": residuals.get("heading_source"), "vehicle": vehicle,
               "vehicle_reason": vehicle_reason}
    settings = {"attitude_error": model_options.get("attitude_error", "ecef"),
                "preset": preset, "gnss_sigma_m": sigma}
    return FlightAssessment.build(
        model, _pairs(table), trajectory=trajectory, **thresholds, settings=settings,
        inputs=inputs, fit=fit, automatic=automatic, segment_table=table, options=options,
        gnss_residuals=gnss_res, imu_residuals=imu_res, notes=tuple(notes), quality=findings)


def _fit_notes(trajectory) -> list[str]:
    """What the fit assumed or bridged, in words (initial attitude, levelling window,
    bridged holes with their bounds)."""
    res = trajectory.parameters.get("fit_residuals", {})
    out = []
    if res.get("initial_attitude_note"):
        out.append(f"initial attitude: {res['initial_attitude_note']} (heading "
                   f"{res.get('heading_deg', float('nan')):.1f} deg)")
    level = res.get("level") or {}
    if level:
        out.append(f"levelled over {level['t_start']:.6g}..{level['t_end']:.6g} s (the quietest"
                   f" rest window: spread {level['spread_mps2']:.3g} m/s^2, limit "
                   f"{level['spread_limit_mps2']:.3g}; mean rate "
                   f"{level['mean_rate_deg_s']:.3g} deg/s)")
    holes = res.get("imu_holes") or []
    if holes:
        worst = max(holes, key=lambda h: h["duration_s"])
        out.append(f"{len(holes)} IMU hole(s) bridged by the fit (longest {worst['duration_s']:.3g}"
                   f" s at t = {worst['t_start']:.6g} s: attitude within "
                   f"{worst['attitude_bound_deg']:.3g} deg, position within "
                   f"{worst['position_bound_m']:.3g} m if the motion varied monotonically "
                   "across it)")
    return out


def _outlier_notes(imu) -> list[str]:
    flagged = getattr(imu, "attrs", {}).get("outliers") or []
    if not flagged:
        return []
    shown = "; ".join(f"t = {o['t']:.6g} s {o['column']} = {o['value']:.4g}" for o in flagged[:5])
    more = f" and {len(flagged) - 5} more" if len(flagged) > 5 else ""
    return [f"{len(flagged)} IMU sample(s) excluded by the reader as non-physical ({shown}{more})"]
