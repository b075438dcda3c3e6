"""The assessment pipeline: the sensor preset, the pieces of a log with gaps, and
:func:`assess_flight`."""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import replace

import numpy as np
import pandas as pd

from navlib import sensors
from navlib._validation import finite_scalar, reject_unknown
from navlib.errors import NavlibInputError
from navlib.io import FlightDataWarning, quality
from navlib.metrics import (
    E_THRESHOLD,
    MIN_FRACTION,
    S_THRESHOLD,
    check_thresholds,
)
from navlib.models.baro import aided_model, without_gnss
from navlib.models.ecef import ecef21_at_epochs, epoch_samples
from navlib.segmentation import (
    SEGMENT_DEFAULTS,
    check_vehicle,
    recognise_vehicle,
    segment_flight,
    vehicle_from_log,
)
from navlib.studies.assess import clock
from navlib.studies.assess.agreement import fit_bounds
from navlib.studies.assess.aiding import (
    aiding_records,
    baro_rows_weighted,
    row_dynamic_error,
    sigma_note,
)
from navlib.studies.assess.fit import fit_notes, fit_records, fit_report, fit_residuals
from navlib.studies.assess.inputs import (
    GNSS_KEYS,
    IMU_KEYS,
    check_frame,
    check_gnss_record,
    check_imu_record,
    describe_inputs,
    median_rate,
    validate_records,
)
from navlib.studies.assess.outages import gnss_outages, measured_epochs, outage_note
from navlib.studies.assess.result import (
    FlightAssessment,
    automatic_segment_table,
    segment_pairs,
    with_agreement,
)
from navlib.studies.assess.settings import AssessmentSettings
from navlib.trajectory.fit import FIT_DEFAULTS

__all__ = ["AUTOPILOT_PRESETS", "DEFAULT_PRESET", "LOGGED_CHANNELS", "MODEL_STEP_S",
           "assess_flight", "choose_preset"]


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
                     "altos": "altus_telemega", "firm": "pixhawk_mems", "cats": "pixhawk_mems"}
"""Preset chosen by default for logs whose reader found the autopilot or flight computer
(``attrs["autopilot"]``): the consumer MEMS class of the Pixhawk family
(``data/sensors/pixhawk_mems.toml``, also for the FIRM and CATS flight computers' MEMS
IMUs), the MPU-6000 class of the Altus Metrum TeleMega (``data/sensors/altus_telemega.toml``)."""
MODEL_STEP_S = 0.02
"""Longest model step of the assessment (``ecef21_at_epochs(max_step_s=...)``), s: IMU steps
are grouped to 50 Hz, which keeps long flights fast while the 1 s transitions move by less
than 1e-3 relative on the sample flight (benchmarks/bench_assess.py)."""


def choose_preset(imu: pd.DataFrame, preset: str | None = None) -> tuple[str, str]:
    """The sensor preset to assess ``imu`` with and why: ``preset`` when given, else the
    :data:`AUTOPILOT_PRESETS` entry of the autopilot the reader found in the log, else
    :data:`DEFAULT_PRESET`.

    Parameters
    ----------
    imu : pandas.DataFrame
        IMU record (its ``attrs["autopilot"]`` and ``attrs["hardware"]``).
    preset : str or None, optional
        A preset name to use as given.

    Returns
    -------
    tuple of (str, str)
        The preset name and the reason.

    Raises
    ------
    NavlibInputError
        If ``preset`` is not a string.
    """
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


def _piece(frame: pd.DataFrame, t0_s: float, t1_s: float) -> pd.DataFrame:
    t = frame["t"].to_numpy(dtype=float)
    out = frame[(t >= t0_s) & (t <= t1_s)].drop(columns="segment", errors="ignore")
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
        attitude unless ``fit_options`` say otherwise. ``gnss`` None (a flight without
        GNSS) or a record whose height is barometric (``attrs["height_source"]``) is aided
        by the barometer ``imu.attrs["baro"]`` and the pad
        (:func:`navlib.studies.assess.aiding.aiding_records`,
        :func:`navlib.models.baro.aided_model`); ``options["aiding"]`` names it.
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
        Excitability energy threshold (docs/assumptions.md A14).
    nu : float in (0, 1)
        Sensability threshold (docs/assumptions.md A11; 0.985 is the paper's value for 21 states).
    gnss_rate_hz : float, optional
        Measurement rate of the model; None: the median rate of the GNSS record (at most
        the IMU rate). The epochs are a regular grid in time at this rate
        (:func:`navlib.models.ecef.epoch_samples`); each kept fix aids the epoch nearest it
        and an epoch no kept fix aids (a gap, a frozen or excluded fix) has no measurement
        (assumption Q5). Spans without a kept fix longer than ``[gnss] outage_report_s`` are
        named in ``notes`` and listed in ``gnss_outages``.
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
        (:func:`navlib.io.quality.load_thresholds`, e.g. ``{"gnss": {"jump_min_m": 20}}``).
        Saturated IMU samples and faulty GNSS fixes are found, warned about with times and
        dropped before the fit (:func:`navlib.io.quality.check_records`, assumptions Q1-Q4).

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
    check_frame(imu, "imu", IMU_KEYS)
    gnss, aiding, aiding_notes = aiding_records(imu, gnss)
    check_frame(gnss, "gnss", GNSS_KEYS)
    gnss = gnss.drop(columns="segment", errors="ignore")   # GNSS gaps: bridged by the IMU
    preset, preset_reason = choose_preset(imu, preset)
    spec = sensors.load_preset(preset)  # unknown names fail here, before the fit
    # rows of the barometer alone: it is taken as on time, no lag scanned (FIT6, B7)
    no_lag = {"estimate_gnss_lag": False} if aiding == "baro" else {}
    fit_options = {"preset": preset, **no_lag, **dict(fit_options or {})}
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
    check_imu_record(imu)   # before the quality checks, which judge the GNSS by the IMU
    check_gnss_record(gnss)
    sigma = _gnss_sigma(gnss, spec) if gnss_sigma_m is None else gnss_sigma_m
    checked = quality.check_records(imu, gnss, spec,
                                    finite_scalar(sigma, "gnss_sigma_m", 0.0, low_open=True),
                                    quality_thresholds)
    for message in checked.warnings:
        warnings.warn(message, FlightDataWarning, stacklevel=2)
    imu, gnss = checked.imu, checked.gnss
    settings = AssessmentSettings(
        spec=spec, preset=preset, preset_reason=preset_reason, thresholds=thresholds,
        segments=segments, gnss_rate_hz=gnss_rate_hz, gnss_sigma_m=gnss_sigma_m,
        heading_fallback_deg=heading_fallback_deg, fit_options=fit_options,
        segment_options=segment_options, model_options=model_options,
        model_step_s=model_step_s, vehicle=vehicle, vehicle_reason=vehicle_reason,
        bounds=fit_bounds(quality_thresholds),
        outage_report_s=checked.thresholds["gnss"]["outage_report_s"], aiding=aiding,
        aiding_notes=tuple(aiding_notes), findings=checked.findings,
        t_record=float(imu["t"].iloc[0]))
    pieces = _pieces(imu, max_bridge_s)
    if len(pieces) == 1:
        return _assess_span(imu.drop(columns="segment", errors="ignore"), gnss, settings)
    results, skipped = [], []
    for t0, t1 in pieces:
        try:
            results.append(_assess_span(_piece(imu, t0, t1), _piece(gnss, t0, t1), settings))
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


def _assess_span(imu, gnss, settings: AssessmentSettings) -> FlightAssessment:
    """:func:`assess_flight` of one span without holes longer than ``max_bridge_s``."""
    s = settings
    gnss_rate_hz, vehicle, vehicle_reason = s.gnss_rate_hz, s.vehicle, s.vehicle_reason
    span = validate_records(imu, gnss)
    inputs = describe_inputs(imu, gnss)
    t_g = gnss["t"].to_numpy(dtype=float)
    t_g = t_g[(t_g >= span.t_start) & (t_g <= span.t_end)]
    if gnss_rate_hz is None:
        gnss_rate_hz = median_rate(t_g)
    gnss_rate_hz = finite_scalar(gnss_rate_hz, "gnss_rate_hz", 0.0, low_open=True)
    sigma = _gnss_sigma(gnss, s.spec) if s.gnss_sigma_m is None else s.gnss_sigma_m
    sigma = finite_scalar(sigma, "gnss_sigma_m", 0.0, low_open=True)

    if s.aiding != "baro":
        trajectory, notes = fit_records(imu, gnss, s.fit_options, s.heading_fallback_deg)
    else:
        # the barometer's rows weighed at the climb rate of a first fit, the fit redone (B7)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", FlightDataWarning)
            first, _ = fit_records(imu, gnss, s.fit_options, s.heading_fallback_deg)
        gnss = baro_rows_weighted(gnss, first)
        trajectory, notes = fit_records(imu, gnss, s.fit_options, s.heading_fallback_deg)
    gnss_rate_hz = min(gnss_rate_hz, trajectory.rate_hz)
    notes = [f"sensor preset {s.preset!r}: {s.preset_reason}", *s.aiding_notes, *notes,
             *fit_notes(trajectory), *_outlier_notes(imu)]
    fit = fit_report(trajectory, s.preset, sigma)
    gnss_res, imu_res = fit_residuals(trajectory, imu, gnss, s.bounds)
    if s.aiding != "gnss":
        gnss_res["baro_dynamic_m"] = row_dynamic_error(gnss_res["t"], trajectory,
                                                       s.aiding)

    min_epochs_s = 2.0 / gnss_rate_hz
    seg_opts = dict(s.segment_options)
    seg_opts["min_duration_s"] = max(seg_opts.get("min_duration_s", 2.0), min_epochs_s)
    if vehicle is None:
        vehicle, vehicle_reason = recognise_vehicle(trajectory)
    notes.append(f"vehicle {vehicle!r}: {vehicle_reason}")
    logged = imu.attrs.get("flight_states") if vehicle == "rocket" else None
    automatic = segment_flight(trajectory, vehicle=vehicle, flight_states=logged, **seg_opts)

    model = ecef21_at_epochs(trajectory, gnss_rate_hz, sensors=s.preset, gnss_sigma_m=sigma,
                             max_step_s=s.model_step_s,
                             epochs=epoch_samples(trajectory.t, gnss_rate_hz), **s.model_options)
    model = aided_model(model, trajectory, s.aiding, gnss_sigma_m=sigma)
    model, outages = _as_recorded(model, None if s.aiding == "baro" else gnss, trajectory.t,
                                  s.outage_report_s)
    if s.aiding != "gnss":                     # the model as recorded: its outages included
        notes.append(sigma_note(model, trajectory, s.aiding))
    liftoff = trajectory.events.get("liftoff")
    t_zero, zero = clock.time_zero(automatic, model, trajectory.t, vehicle, s.t_record, liftoff)
    moved = clock.on_clock(t_zero, trajectory=trajectory, model=model, automatic=automatic,
                           inputs=inputs, gnss_residuals=gnss_res, imu_residuals=imu_res,
                           gnss_outages=outages, logged=_logged(imu, trajectory.t))
    trajectory, model = moved["trajectory"], moved["model"]
    automatic = moved["automatic"]
    if zero == "ignition" and liftoff is not None and t_zero == liftoff:   # from the records
        automatic = clock.at_ignition(automatic)
    inputs, gnss_res, imu_res = moved["inputs"], moved["gnss_residuals"], moved["imu_residuals"]
    outages, logged_channels = moved["gnss_outages"], moved["logged"]
    notes.append(f"times are seconds since the {zero}, at {t_zero:.6g} s on the log's clock"
                 + (" (phases from the flight computer's logged states; detected beside them "
                    "in .automatic.events)" if automatic.source == "logged" else ""))
    notes += [n for n in (outage_note(outages, s.outage_report_s),) if n]
    table, joined = automatic_segment_table(
        automatic.segments if s.segments is None else s.segments, model, automatic, trajectory.t,
        automatic_segments=s.segments is None)
    notes += joined
    table, unrepresented = with_agreement(table, trajectory, imu_res, gnss_res, s.bounds)
    for message in unrepresented:
        warnings.warn(message, FlightDataWarning, stacklevel=3)
    notes += unrepresented
    residuals = trajectory.parameters.get("fit_residuals", {})
    options = {"preset": s.preset, "preset_reason": s.preset_reason, "gnss_rate_hz": gnss_rate_hz,
               "gnss_sigma_m": sigma, "heading_fallback_deg": s.heading_fallback_deg,
               "fit_options": s.fit_options, "segment_options": seg_opts,
               "model_options": s.model_options, "model_step_s": s.model_step_s,
               "imu_rate_hz": trajectory.rate_hz, "heading_deg": residuals.get("heading_deg"),
               "attitude_source": residuals.get("heading_source"), "vehicle": vehicle,
               "vehicle_reason": vehicle_reason, "t_zero": t_zero, "time_zero": zero,
               "phase_source": automatic.source, "fit_bounds": s.bounds, "aiding": s.aiding}
    model_settings = {"attitude_error": s.model_options.get("attitude_error", "ecef"),
                      "preset": s.preset, "gnss_sigma_m": sigma}
    return FlightAssessment.build(
        model, segment_pairs(table), trajectory=trajectory, **s.thresholds,
        settings=model_settings,
        inputs=inputs, fit=fit, automatic=automatic, segment_table=table, options=options,
        gnss_residuals=gnss_res, imu_residuals=imu_res, notes=tuple(notes), quality=s.findings,
        gnss_outages=outages, logged=logged_channels)


def _as_recorded(model, gnss: pd.DataFrame | None, t_flight, outage_report_s: float):
    """The model with zero GNSS measurement rows at the epochs no kept fix aids
    (:func:`~navlib.studies.assess.outages.measured_epochs`, assumption Q5; every row for a
    GNSS-only model, the ``gnss_*`` rows beside a barometer, assumptions B1-B3) and the GNSS
    outages longer than ``outage_report_s`` over the flight ``t_flight``. ``gnss`` None (a
    flight aided by its barometer alone): the model as it is and no outages."""
    if gnss is None:
        return model, gnss_outages(np.empty(0), 0.0, 0.0, outage_report_s)
    xyz = gnss[["x", "y", "z"]].to_numpy(dtype=float)
    t_fix = gnss["t"].to_numpy(dtype=float)[np.all(np.isfinite(xyz), axis=1)]
    model = without_gnss(model, ~measured_epochs(model.t, t_fix))
    outages = gnss_outages(t_fix, float(t_flight[0]), float(t_flight[-1]), outage_report_s)
    return model, outages


LOGGED_CHANNELS = {"baro": ("t", "alt_m"), "tilt": ("t", "tilt"),
                   "attitude": ("t", "qw", "qx", "qy", "qz")}
"""What a reader attaches to ``imu.attrs`` beside the IMU that the flight figure compares
the reference with (:attr:`FlightAssessment.logged`)."""


def _logged(imu: pd.DataFrame, t_flight) -> dict:
    """The :data:`LOGGED_CHANNELS` the reader attached, inside the flight ``t_flight``."""
    out = {}
    for name, columns in LOGGED_CHANNELS.items():
        frame = getattr(imu, "attrs", {}).get(name)
        if not isinstance(frame, pd.DataFrame) or not set(columns) <= set(frame.columns):
            continue
        t = frame["t"].to_numpy(dtype=float)
        inside = (t >= t_flight[0]) & (t <= t_flight[-1])
        if inside.any():
            out[name] = frame.loc[inside, list(columns)].reset_index(drop=True)
    return out



def _outlier_notes(imu) -> list[str]:
    flagged = getattr(imu, "attrs", {}).get("outliers") or []
    if not flagged:
        return []
    shown = "; ".join(f"t = {o['t']:.6g} s {o['column']} = {o['value']:.4g}" for o in flagged[:5])
    more = f" and {len(flagged) - 5} more" if len(flagged) > 5 else ""
    return [f"{len(flagged)} IMU sample(s) excluded by the reader as non-physical ({shown}{more})"]
