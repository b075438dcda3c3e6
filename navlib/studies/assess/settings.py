"""The settings of one assessment, checked once at its entry and passed as one frozen object.

:func:`~navlib.studies.assess.assess_flight` validates its keywords (thresholds, preset,
option mappings, the vehicle class, the data-quality thresholds) and gathers them, with what
the records' checks decided (the aiding, the quality findings, the clock's first sample),
into an :class:`AssessmentSettings`; every span of a record split by long holes is assessed
with the same object (:func:`navlib.studies.assess.pipeline.assess_flight`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import pandas as pd

__all__ = ["AssessmentSettings"]


@dataclass(frozen=True)
class AssessmentSettings:
    """What every span of one assessment is assessed with.

    Attributes
    ----------
    spec : SensorSpec
        The sensor preset's errors (:func:`navlib.sensors.load_preset`).
    preset : str
        Its name.
    preset_reason : str
        Why it was chosen (given, or the log's autopilot).
    thresholds : Mapping
        ``eta``, ``nu``, ``e_threshold``, ``s_threshold``, ``min_fraction``, checked
        (:func:`navlib.metrics.check_thresholds`).
    segments : object or None
        Segment boundaries or table the user gave; None: automatic.
    gnss_rate_hz : float or None
        Model measurement rate, Hz; None: the span's median GNSS rate.
    gnss_sigma_m : float or None
        GNSS position sigma, m; None: from the record or the preset.
    heading_fallback_deg : float or None
        Initial heading assumed when the motion gives none, deg.
    fit_options, segment_options, model_options : Mapping
        Keywords of the fit, the segmentation and the model (checked).
    model_step_s : float or None
        Longest model step, s.
    vehicle : str or None
        The vehicle class (given or from the log); None: recognised from the fit.
    vehicle_reason : str
        Why that class.
    bounds : Mapping
        The fit-agreement bounds (:func:`~navlib.studies.assess.agreement.fit_bounds`).
    outage_report_s : float
        GNSS outages at least this long are named (``[gnss] outage_report_s``).
    aiding : str
        ``"gnss"``, ``"baro"`` or ``"gnss+baro"``.
    aiding_notes : sequence of str
        What the aiding choice assumed.
    findings : pandas.DataFrame
        The data-quality findings of the whole record (:func:`navlib.io.quality.check_records`).
    t_record : float
        The first IMU sample of the whole record on the log's clock, s.
    """

    spec: object
    preset: str
    preset_reason: str
    thresholds: Mapping
    segments: object
    gnss_rate_hz: float | None
    gnss_sigma_m: float | None
    heading_fallback_deg: float | None
    fit_options: Mapping
    segment_options: Mapping
    model_options: Mapping
    model_step_s: float | None
    vehicle: str | None
    vehicle_reason: str
    bounds: Mapping
    outage_report_s: float
    aiding: str
    aiding_notes: Sequence[str] = ()
    findings: pd.DataFrame = field(default_factory=pd.DataFrame)
    t_record: float = 0.0
