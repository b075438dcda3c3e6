"""The clock of an assessment: seconds since ignition for rockets, since the first sample else.

A log's own clock is whatever its logger counted (GPS seconds of the week, microseconds since
boot, AltOS's seconds from boost detection). The assessment states every time on one clock
whose zero is

* for a rocket, its ignition: the thrust onset the recorded specific force shows when the
  record starts on a pad (the fit's ``liftoff`` event,
  :func:`navlib.trajectory.liftoff.find_liftoff`) within ``IGNITION_MATCH_S`` of the first
  ``boost`` segment, else that segment's start (the flight computer's logged boost state
  when the log has states, :mod:`navlib.segmentation.logged`, else the detected powered
  run). The records decide: AltOS labels its 0.3 s pre-launch buffer ``boost``, and a
  powered run detected on the fit starts where the spline rounds the thrust step off. The
  boundary between a pad segment and the boost moves to the ignition
  (:func:`at_ignition`), so that boost starts at 0 s, also when a boost without GNSS fixes
  is joined to the coast after it (:func:`~navlib.studies.assess.automatic_segment_table`:
  ignition is an event of the flight, not of its measurements); a boost that starts the
  record keeps its start (the pre-launch rows before the ignition, at negative times);
* for a rocket without a boost in the record, and for every other vehicle, the first sample
  of the record (of the whole record when holes split it into spans assessed separately:
  the spans share its clock; a rocket's spans each take the ignition they hold).

The zero on the log's own clock (``t_zero``; ``t_ignition`` when it is an ignition) is stated
once, in the result's ``options`` and notes. Notes and warnings issued before the fit (data
quality, bridged holes) keep the log's clock.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from navlib.segmentation import segments_table
from navlib.segmentation.phases import clock_time, frame_on_clock

__all__ = ["IGNITION_MATCH_S", "at_ignition", "on_clock", "time_zero"]

_TIMES = ("t", "t_first", "t_last")
"""Time columns of the input summary, the residual frames and the logged channels."""


IGNITION_MATCH_S = 2.0
"""Largest distance between the records' thrust onset and the first boost segment's start
for the onset to be that boost's ignition, s."""


def time_zero(automatic, model, t_flight, vehicle: str | None,
              t_record: float | None = None, liftoff: float | None = None
              ) -> tuple[float, str]:
    """The zero of the assessment's clock on the log's clock (module docstring).

    Parameters
    ----------
    automatic : Segmentation
        The automatic segmentation of the span (its phases before any joining).
    model : DiscreteModel
        The span's model (unused by the rule; kept for the callers' one signature).
    t_flight : array (N,)
        The fitted flight's times on the log's clock.
    vehicle : str or None
        The vehicle class: a ``"rocket"`` counts from its first ``boost``.
    t_record : float, optional
        The first sample of the whole record, when ``t_flight`` is one of several spans
        (None: ``t_flight[0]``).
    liftoff : float, optional
        The thrust onset found from the recorded specific force, on the log's clock (the
        fit's ``events["liftoff"]``); None when the record does not start on a pad.

    Returns
    -------
    t_zero : float
        The zero on the log's clock, s.
    what : str
        ``"ignition"`` or ``"first sample"``.
    """
    if vehicle == "rocket":
        table = segments_table(automatic.segments, float(t_flight[0]), float(t_flight[-1]),
                               automatic)
        boost = table.loc[table["phase"] == "boost", "t_start"]
        if len(boost):
            start = float(boost.iloc[0])
            if liftoff is not None and abs(float(liftoff) - start) <= IGNITION_MATCH_S:
                return float(liftoff), "ignition"
            return start, "ignition"
    return float(t_flight[0] if t_record is None else t_record), "first sample"


def on_clock(t_zero: float, *, trajectory, model, automatic, inputs, gnss_residuals,
             imu_residuals, gnss_outages, logged: dict) -> dict:
    """Every time of an assessment's pieces minus ``t_zero``: the trajectory (``t`` and its
    ``events``), the model epochs, the segmentation, the input summary (``t_first``,
    ``t_last``), the residual frames, the GNSS outages (``t_start``, ``t_end``) and the
    logged channels beside the IMU (``t``; :func:`~navlib.segmentation.phases.clock_time`).

    Parameters
    ----------
    t_zero : float
        The zero (:func:`time_zero`), s on the log's clock.
    trajectory, model, automatic : Trajectory, DiscreteModel, Segmentation
        The fitted motion, its model and its segmentation.
    inputs, gnss_residuals, imu_residuals, gnss_outages : DataFrame or None
        The input summary, the fit's residual frames and the GNSS outages.
    logged : dict
        The logged channels (name -> DataFrame with ``t``).

    Returns
    -------
    dict
        The same pieces by their keyword names, every time minus ``t_zero``.
    """
    events = {k: float(clock_time(v, t_zero)) if isinstance(v, int | float) else v
              for k, v in trajectory.events.items()}
    return {"trajectory": replace(trajectory, t=clock_time(trajectory.t, t_zero),
                                  events=events),
            "model": replace(model, t=clock_time(model.t, t_zero)),
            "automatic": automatic.shifted(t_zero),
            "inputs": frame_on_clock(inputs, t_zero, _TIMES),
            "gnss_residuals": frame_on_clock(gnss_residuals, t_zero, _TIMES),
            "imu_residuals": frame_on_clock(imu_residuals, t_zero, _TIMES),
            "gnss_outages": frame_on_clock(gnss_outages, t_zero, ("t_start", "t_end")),
            "logged": {name: frame_on_clock(frame, t_zero, _TIMES)
                       for name, frame in logged.items()}}


def at_ignition(automatic):
    """For a zero at the records' thrust onset: the segmentation on the assessment's clock
    with the boundary between the segment before the first ``boost`` and the boost at 0 s,
    the ignition (module docstring), and the detected ignition of its events at 0 s (the
    thrust onset is what the records detect); the boundary is unchanged when the boost
    starts the record or lies more than ``IGNITION_MATCH_S`` away.

    Parameters
    ----------
    automatic : Segmentation
        On the assessment's clock (:func:`on_clock`).

    Returns
    -------
    Segmentation
    """
    events = automatic.events
    if events is not None and "ignition" in set(events["event"]):
        events = events.copy()
        first = events.index[events["event"] == "ignition"][0]
        events.loc[first, "t_detected"] = 0.0
        events.loc[first, "difference"] = 0.0 - events.loc[first, "t_logged"]
        automatic = replace(automatic, events=events)
    segments = automatic.segments
    boost = np.flatnonzero(segments["phase"].to_numpy() == "boost")
    if not boost.size or boost[0] == 0:
        return automatic
    i = int(boost[0])
    start = float(segments["t_start"].iloc[i])
    if (start == 0.0 or abs(start) > IGNITION_MATCH_S
            or float(segments["t_start"].iloc[i - 1]) >= 0.0
            or float(segments["t_end"].iloc[i]) <= 0.0):
        return automatic
    moved = segments.copy()
    moved.loc[moved.index[i], "t_start"] = 0.0
    moved.loc[moved.index[i - 1], "t_end"] = 0.0
    if "duration" in moved:
        moved["duration"] = moved["t_end"] - moved["t_start"]
    return replace(automatic, segments=moved)
