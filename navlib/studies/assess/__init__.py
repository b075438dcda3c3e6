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

How well each state is known, in navigation axes and units (position and velocity north,
east, down; roll, pitch, yaw; IMU errors per body axis in deg/h, mg, ppm), per segment:
:meth:`FlightAssessment.states_table` (:mod:`.states`), the ``states.csv`` of
``python -m navlib assess``. Times are seconds since a rocket's ignition (the start of its
first boost) and since the first sample for other vehicles; the zero on the log's own clock
is ``FlightAssessment.t_ignition`` / ``options["t_zero"]`` (:mod:`.clock`).

Modules: :mod:`.inputs` (summary and checks of the records), :mod:`.fit` (the trajectory fit,
its report and residuals), :mod:`.result` (:class:`FlightAssessment`, the segment table),
:mod:`.states` (sigma in navigation axes and units), :mod:`.clock` (the time zero) and
:mod:`.pipeline` (:func:`assess_flight`).
"""

from navlib.metrics import E_THRESHOLD, MIN_FRACTION, S_THRESHOLD
from navlib.studies.assess.fit import fit_report, fit_residuals
from navlib.studies.assess.inputs import MIN_DURATION_S, MIN_GNSS_EPOCHS, describe_inputs
from navlib.studies.assess.pipeline import (
    AUTOPILOT_PRESETS,
    DEFAULT_PRESET,
    MODEL_STEP_S,
    assess_flight,
    choose_preset,
)
from navlib.studies.assess.result import (
    FlightAssessment,
    automatic_segment_table,
    segment_pairs,
)
from navlib.studies.assess.settings import AssessmentSettings

__all__ = ["AUTOPILOT_PRESETS", "DEFAULT_PRESET", "E_THRESHOLD", "MIN_DURATION_S",
           "MIN_FRACTION", "MIN_GNSS_EPOCHS", "MODEL_STEP_S", "S_THRESHOLD", "AssessmentSettings",
           "FlightAssessment",
           "assess_flight", "automatic_segment_table", "choose_preset", "describe_inputs",
           "fit_report", "fit_residuals", "segment_pairs"]
