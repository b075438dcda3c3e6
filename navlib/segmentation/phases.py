"""Flight phases from the kinematic features: the labelling, its hysteresis and short-run merging.

:func:`segment_flight` applies the table of :mod:`navlib.segmentation` (rest, powered, turn,
free fall, coast, cruise) window by window, relaxes the thresholds by ``hysteresis`` while a
phase lasts, merges runs shorter than ``min_duration_s`` and, for a vehicle class, renames
the phases with that vehicle's words (``docs/assumptions.md`` V1-V2).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from navlib._validation import finite_scalar, reject_unknown
from navlib.segmentation.features import flight_features, window_means
from navlib.segmentation.logged import flight_events, logged_segments
from navlib.units import DEG
from navlib.vehicles import VEHICLE_PHASES, check_vehicle

__all__ = ["PHASES", "SEGMENT_COLUMNS", "SEGMENT_DEFAULTS", "TIME_TOL_S", "Segmentation",
           "clock_time", "frame_on_clock", "segment_flight"]

PHASES = ("rest", "powered", "turn", "free_fall", "coast", "cruise")
"""Phase labels in priority order (module docstring)."""

SEGMENT_DEFAULTS = {
    "rest_speed_m_s": 1.0,
    "rest_rate_deg_s": 3.0,
    "rest_accel_m_s2": 0.5,
    "powered_accel_m_s2": 2.0,
    "turn_rate_deg_s": 5.0,
    "free_fall_m_s2": 0.5,
    "coast_lateral_m_s2": 2.0,
    "direction_speed_m_s": 1.0,
    "turn_speed_m_s": 3.0,
    "resolution_s": 0.1,
    "hysteresis": 0.25,
    "min_duration_s": 2.0,
    "climb_rate_m_s": 1.0,
    "hover_height_m": 2.0,
    "hover_speed_m_s": 1.0,
}
"""Default thresholds of :func:`segment_flight` (engineering choices, not from a paper)."""

SEGMENT_COLUMNS = ("phase", "t_start", "t_end")
_FAMILY = {"free_fall": "unpowered", "coast": "unpowered"}
TIME_TOL_S = 1e-6


def clock_time(t, t_zero: float) -> np.ndarray:
    """``t - t_zero`` rounded to the nanosecond: times on a clock moved to a new zero read as
    typed (``59.3 - 18.1`` is ``41.2``, not ``41.199999999999996``), so boundaries written
    out and typed back match the segments; no log resolves a nanosecond."""
    return np.round(np.asarray(t, dtype=float) - float(t_zero), 9)


def frame_on_clock(frame: pd.DataFrame | None, t_zero: float, columns) -> pd.DataFrame | None:
    """A copy of ``frame`` with each of its ``columns`` of times moved to the clock whose zero
    is ``t_zero`` (:func:`clock_time`; columns it lacks are skipped, None stays None).

    Parameters
    ----------
    frame : DataFrame or None
        A table with time columns (s).
    t_zero : float
        The new zero on the frame's clock, s.
    columns : sequence of str
        The time columns to move.
    """
    if frame is None:
        return None
    frame = frame.copy()
    for column in columns:
        if column in frame.columns:
            frame[column] = clock_time(frame[column].to_numpy(dtype=float), t_zero)
    return frame


@dataclass(frozen=True, eq=False)
class Segmentation:
    """Phases of a flight found by :func:`segment_flight`.

    Attributes
    ----------
    segments : DataFrame
        ``phase, t_start, t_end, duration`` (s), contiguous, covering the flight.
    features : DataFrame
        One row per window of ``resolution_s``: ``t`` (window centre), ``t_start``,
        ``t_end``, the features ``speed`` (m/s), ``accel``, ``f_norm``, ``gravity``,
        ``f_along``, ``f_lateral`` (m/s^2), ``rate``, ``rate_across``, ``path_rate``
        (rad/s), the label of the strict thresholds ``raw`` and the final ``phase``.
    thresholds : dict
        The thresholds used (:data:`SEGMENT_DEFAULTS` with the caller's changes).
    vehicle : str or None
        The vehicle class whose words name the phases (None: kinematic labels).
    source : str
        ``"detected"`` (the kinematics) or ``"logged"`` (a rocket's flight-computer states,
        :func:`~navlib.segmentation.logged.logged_segments`).
    detected : DataFrame or None
        The detected segments when ``segments`` are the logged ones (else None).
    events : DataFrame or None
        A rocket's events, logged and detected side by side
        (:func:`~navlib.segmentation.logged.flight_events`); None for other vehicles.
    """

    segments: pd.DataFrame
    features: pd.DataFrame
    thresholds: dict = field(default_factory=dict)
    vehicle: str | None = None
    source: str = "detected"
    detected: pd.DataFrame | None = None
    events: pd.DataFrame | None = None

    def shifted(self, t_zero: float) -> Segmentation:
        """The same segmentation on a clock whose zero is ``t_zero`` of this one (every
        time minus ``t_zero``, :func:`clock_time`)."""
        times = ("t", "t_start", "t_end", "t_logged", "t_detected")
        return replace(self, segments=frame_on_clock(self.segments, t_zero, times),
                       features=frame_on_clock(self.features, t_zero, times),
                       detected=frame_on_clock(self.detected, t_zero, times),
                       events=frame_on_clock(self.events, t_zero, times))

    def to_frame(self) -> pd.DataFrame:
        """The editable segment table (a copy): ``phase, t_start, t_end, duration``."""
        return self.segments.copy()

    def phase_at(self, t) -> np.ndarray:
        """Automatic phase label at times ``t`` (s), from the windows of ``features``."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        edges = self.features["t_start"].to_numpy()
        k = np.clip(np.searchsorted(edges, t, side="right") - 1, 0, edges.size - 1)
        return self.features["phase"].to_numpy()[k]


def _options(options: Mapping) -> dict:
    reject_unknown(options, SEGMENT_DEFAULTS, "segment_flight")
    p = {k: finite_scalar(options.get(k, v), k, 0.0, low_open=True)
         for k, v in SEGMENT_DEFAULTS.items() if k != "hysteresis"}
    p["hysteresis"] = finite_scalar(options.get("hysteresis", SEGMENT_DEFAULTS["hysteresis"]),
                                    "hysteresis", 0.0, 0.9)
    return p


def _conditions(w: pd.DataFrame, p: dict, relax: float,
                vehicle: str | None = None) -> dict[str, np.ndarray]:
    """Boolean condition of each phase per window, thresholds relaxed by ``relax``, in
    priority order (the fallback phase, ``cruise``, holds where none does)."""
    wider, narrower = 1.0 + relax, 1.0 - relax
    rest = ((w["speed"] < p["rest_speed_m_s"] * wider)
            & (w["rate"] < p["rest_rate_deg_s"] * DEG * wider)
            & (w["accel"] < p["rest_accel_m_s2"] * wider))
    powered = w["f_along"] > p["powered_accel_m_s2"] * narrower
    turn = np.maximum(w["rate_across"], w["path_rate"]) > p["turn_rate_deg_s"] * DEG * narrower
    if vehicle in (None, "rocket"):
        unpowered = w["f_along"] <= p["powered_accel_m_s2"] * wider
        free_fall = (w["f_norm"] < p["free_fall_m_s2"] * wider) & unpowered
        coast = (w["f_lateral"] < p["coast_lateral_m_s2"] * wider) & unpowered
        return {"rest": rest.to_numpy(), "powered": powered.to_numpy(), "turn": turn.to_numpy(),
                "free_fall": free_fall.to_numpy(), "coast": coast.to_numpy()}
    # a vertical take-off or landing starts with an acceleration before it has the speed
    slow = w["v_h"] < p["hover_speed_m_s"] * wider
    pushed = w["a_up"].abs() > p["rest_accel_m_s2"] * narrower
    climb = (w["v_up"] > p["climb_rate_m_s"] * narrower) | (
        slow & pushed & (w["a_up"] > 0) & (w["v_up"] > 0))
    descent = (w["v_up"] < -p["climb_rate_m_s"] * narrower) | (
        slow & pushed & (w["a_up"] < 0) & (w["v_up"] < 0))
    low = w["height"] < p["hover_height_m"] * wider
    hover = ((w["height"] >= p["hover_height_m"] * narrower)
             & (w["v_h"] < p["hover_speed_m_s"] * wider)
             & (w["v_up"].abs() < p["climb_rate_m_s"] * wider))
    out = {"rest": (rest & low if vehicle == "multicopter" else rest).to_numpy(),
           "hover": hover.to_numpy(), "climb": climb.to_numpy(), "descent": descent.to_numpy(),
           "turn": turn.to_numpy()}
    return {phase: out[phase] for phase in VEHICLE_PHASES[vehicle][:-1]}


def _classify(conditions: dict[str, np.ndarray], n: int) -> np.ndarray:
    label = np.full(n, "cruise", dtype=object)
    for phase in reversed(list(conditions)):  # the first phase in priority order wins
        label[conditions[phase]] = phase
    return label


def _with_hysteresis(strict: np.ndarray, relaxed: dict[str, np.ndarray]) -> np.ndarray:
    """Keep the current phase while its relaxed condition holds and no phase of higher
    priority holds strictly; otherwise take the strict label. ``relaxed`` is in priority
    order and holds the fallback phase last."""
    rank = {phase: i for i, phase in enumerate(relaxed)}
    out = strict.copy()
    current = strict[0]
    for k in range(strict.size):
        if rank[strict[k]] < rank[current] or not relaxed[current][k]:
            current = strict[k]
        out[k] = current
    return out


def _rocket_sequence(labels: np.ndarray, height: np.ndarray,
                     rise_m: float) -> tuple[np.ndarray, int | None]:
    """Rocket words from the kinematic labels and the flight's order (module docstring), and
    the window of the apogee (None when the record never rises ``rise_m``)."""
    out = np.full(labels.size, "pad", dtype=object)
    rise = np.flatnonzero(height - height[0] >= rise_m)
    if rise.size == 0:   # never rose: on the pad throughout, or recorded from mid-descent
        if height[0] - height[-1] > rise_m:
            out[:] = np.where(labels == "rest", "landed", "descent")
        return out, None
    launch = int(rise[0])
    while launch > 0 and labels[launch - 1] == "powered":
        launch -= 1
    apogee = launch + int(np.argmax(height[launch:]))
    ascent = labels[launch:apogee + 1]
    out[launch:apogee + 1] = np.where(ascent == "powered", "boost",
                                      np.where(ascent == "free_fall", "free_fall", "coast"))
    out[apogee + 1:] = np.where(labels[apogee + 1:] == "rest", "landed", "descent")
    return out, apogee


def _runs(labels: np.ndarray) -> list[list]:
    """Runs of equal labels as ``[label, first, last]`` index triples."""
    change = np.flatnonzero(labels[1:] != labels[:-1]) + 1
    starts = np.concatenate([[0], change])
    ends = np.concatenate([change - 1, [labels.size - 1]])
    return [[labels[s], int(s), int(e)] for s, e in zip(starts, ends, strict=True)]


def _merge_short(runs: list[list], t_start: np.ndarray, t_end: np.ndarray,
                 min_duration: float) -> list[list]:
    """Merge the shortest run below ``min_duration`` into a neighbour, repeatedly: one of the
    same family (free fall and coast are both unpowered flight) if there is one, else the
    longer."""
    def duration(run):
        return t_end[run[2]] - t_start[run[1]]

    while len(runs) > 1:
        k = min(range(len(runs)), key=lambda i: duration(runs[i]))
        if duration(runs[k]) >= min_duration - TIME_TOL_S:
            break
        neighbours = [i for i in (k - 1, k + 1) if 0 <= i < len(runs)]
        family = _FAMILY.get(runs[k][0])
        kin = [i for i in neighbours
               if family is not None and _FAMILY.get(runs[i][0]) == family]
        j = max(kin or neighbours, key=lambda i: duration(runs[i]))
        lo, hi = min(j, k), max(j, k)
        merged = [runs[j][0], runs[lo][1], runs[hi][2]]
        runs[lo:hi + 1] = [merged]
        # neighbours that now carry the same label become one run
        i = 0
        while i < len(runs) - 1:
            if runs[i][0] == runs[i + 1][0]:
                runs[i:i + 2] = [[runs[i][0], runs[i][1], runs[i + 1][2]]]
            else:
                i += 1
    return runs


def segment_flight(trajectory, vehicle: str | None = None, flight_states=None,
                   **thresholds) -> Segmentation:
    """Cut a flight into phases (rest, powered, turn, free fall, coast, cruise) from its
    kinematics, named in a vehicle's words when ``vehicle`` is given.

    Parameters
    ----------
    trajectory : navlib.trajectory.Trajectory
        A reference trajectory, typically :func:`navlib.trajectory.fit_flight_data` of a
        recorded flight (its IMU is smooth and exact).
    vehicle : str, optional
        One of :data:`VEHICLES`: the phases take its words (:data:`VEHICLE_PHASES`, module
        docstring); None: the kinematic labels.
    flight_states : DataFrame or sequence, optional
        A rocket flight computer's own states (``t, state`` at each change, as
        :func:`navlib.io.read_altos` keeps them in ``attrs["flight_states"]``, or
        ``(state, t)`` pairs): with ``vehicle="rocket"`` the segments are the logged phases
        (:func:`~navlib.segmentation.logged.logged_segments`) and the detected ones are kept
        beside them (``detected``, ``events``). Ignored for other vehicles.
    **thresholds
        Any of :data:`SEGMENT_DEFAULTS`: ``rest_speed_m_s`` (1), ``rest_rate_deg_s`` (3),
        ``rest_accel_m_s2`` (0.5), ``powered_accel_m_s2`` (2), ``turn_rate_deg_s`` (5),
        ``free_fall_m_s2`` (0.5), ``coast_lateral_m_s2`` (2), ``direction_speed_m_s`` (1),
        ``turn_speed_m_s`` (3), ``resolution_s`` (0.1), ``hysteresis`` (0.25, in [0, 0.9]),
        ``min_duration_s`` (2), and for the vehicle words ``climb_rate_m_s`` (1),
        ``hover_height_m`` (2), ``hover_speed_m_s`` (1). Conditions in the module docstring.

    Returns
    -------
    Segmentation
        ``segments`` (``phase, t_start, t_end, duration``, contiguous from the first to
        the last sample), the per-window ``features`` and, for a rocket, its ``events``.
    """
    vehicle = None if vehicle is None else check_vehicle(vehicle)
    p = _options(thresholds)
    features = flight_features(trajectory, p["direction_speed_m_s"], p["rest_accel_m_s2"],
                               p["turn_speed_m_s"])
    w = window_means(features, p["resolution_s"])
    n = len(w)
    strict = _classify(_conditions(w, p, 0.0, vehicle), n)
    relaxed = _conditions(w, p, p["hysteresis"], vehicle)
    relaxed["cruise"] = strict == "cruise"
    labels = _with_hysteresis(strict, relaxed)
    apogee = None
    if vehicle == "rocket":
        labels, apogee = _rocket_sequence(labels, w["height"].to_numpy(), p["hover_height_m"])
    t_start, t_end = w["t_start"].to_numpy(), w["t_end"].to_numpy()
    runs = _merge_short(_runs(labels), t_start, t_end, p["min_duration_s"])
    final = labels.copy()
    for label, first, last in runs:
        final[first:last + 1] = label
    w["raw"] = strict
    w["phase"] = final
    segments = pd.DataFrame({
        "phase": [r[0] for r in runs],
        "t_start": [float(t_start[r[1]]) for r in runs],
        "t_end": [float(t_end[r[2]]) for r in runs],
    })
    segments["duration"] = segments["t_end"] - segments["t_start"]
    if vehicle != "rocket":
        return Segmentation(segments=segments, features=w, thresholds=p, vehicle=vehicle)
    t_apogee = None if apogee is None else float(w["t"].iloc[apogee])
    logged = None if flight_states is None else logged_segments(
        flight_states, float(t_start[0]), float(t_end[-1]))
    events = flight_events(segments, t_apogee, logged)
    if logged is None:
        return Segmentation(segments=segments, features=w, thresholds=p, vehicle=vehicle,
                            events=events)
    w["detected"] = final
    edges = logged["t_start"].to_numpy()
    k = np.clip(np.searchsorted(edges, w["t"].to_numpy(), side="right") - 1, 0, edges.size - 1)
    w["phase"] = logged["phase"].to_numpy()[k]
    return Segmentation(segments=logged, features=w, thresholds=p, vehicle=vehicle,
                        source="logged", detected=segments, events=events)
