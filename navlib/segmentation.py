"""Automatic flight-phase segmentation from a trajectory's specific force and angular rate.

A recorded flight is cut into phases whose excitation differs (spec excitability.md §3, §6:
excitability is computed per segment; the paper's segments of the sounding rocket are the
pad [0, 19] s, the powered flight and spin [19, 60] s and the free fall [60, 86] s, where
``|f| < 0.5 m/s^2``). The phases are read from the kinematics of a (fitted)
:class:`~navlib.trajectory.Trajectory`, in ECEF, with ``f^e = C_b_e f^b``,
``omega_eb^e = C_b_e (omega_ib^b - C_e^b Omega)`` and the kinematic acceleration
``a^e = dV/dt = f^e + gamma(P) - 2 Omega x V``:

==========  ===============================================================================
phase       condition (checked in this order; the first that holds wins)
==========  ===============================================================================
rest        ``|V| < rest_speed_m_s``, ``|omega_eb| < rest_rate_deg_s`` and
            ``|a^e| < rest_accel_m_s2``: the vehicle stands (or hovers) still
powered     tangential specific force ``f_t = f^e . u > powered_accel_m_s2``: a thrust (or
            traction) pushes the vehicle forward along its path ``u``
turn        ``max(omega_perp, omega_path) > turn_rate_deg_s``: the body rotates about axes
            other than its *roll axis*, the body axis closest to the path (a rocket's spin
            or a car's roll is excluded; ``omega_perp`` drops that body-axis component of
            ``omega_eb^b``, so a spin axis a degree off the path does not count as a
            turn), or the velocity direction turns (``omega_path = |V x a| / |V|^2``, counted only
            above ``turn_speed_m_s``: at lower speed it is dominated by fit noise)
free_fall   ``|f| < free_fall_m_s2`` (and not powered): no force acts, ballistic flight
            above the atmosphere (the paper's "near free flight", ``|f| < 0.5 m/s^2``)
coast       lateral specific force ``|f^e - f_t u| < coast_lateral_m_s2`` (and not powered):
            nothing but drag along the path acts (a rocket after burnout in the air)
cruise      anything else: motion with the weight supported (level flight, driving)
==========  ===============================================================================

The path direction ``u`` is ``V/|V|`` above ``direction_speed_m_s``; below it ``u`` is the
direction of ``a^e`` when ``|a^e| > rest_accel_m_s2`` (a lift-off accelerates along its
rail from zero speed) and undefined otherwise (then ``f_t = 0``, the lateral force is
``|f|``, there is no roll axis and ``omega_perp = |omega_eb|``).

A vehicle descending at constant speed under a force opposite to its velocity (a drone
landing, a parachute) satisfies the coast condition: from ``f`` alone it cannot be told
from a body slowed by drag. Braking (``f_t < 0`` with the weight supported) shows as
cruise.

Against chatter the features are averaged over windows of ``resolution_s``, a phase is
kept until a phase earlier in the table holds or its own condition fails with every
threshold relaxed by the factor ``hysteresis``
(``rest``: limits times ``1 + h``; ``powered``, ``turn``: thresholds times ``1 - h``;
``free_fall``, ``coast``: limits times ``1 + h``), and runs shorter than ``min_duration_s`` are
merged into a neighbour (the longer one, or one of the same family: a short free fall next
to a coast joins it).

Vehicles (``docs/assumptions.md`` V1-V2). The table above is the *kinematic* labelling
(``vehicle=None``). Given a vehicle class of :data:`VEHICLES` (or one recognised by
:func:`recognise_vehicle`), the phases take that vehicle's words, :data:`VEHICLE_PHASES`:

* ``rocket``: the kinematic labels, then the flight's order. The launch is the start of the
  powered run that lifts the vehicle ``hover_height_m`` above its first position (or the
  moment it gets there, unpowered); every window before it is ``rest`` (a rocket on its pad
  stands, whatever the fit's noise suggests); from the launch to the apogee (the highest
  point) ``powered`` and ``free_fall`` stay and anything else is ``coast``; after the apogee
  every window is ``descent`` except kinematic ``rest`` (landed). A record that never rises
  that far is ``rest`` throughout, or ``descent`` outside kinematic rest when it ends
  ``hover_height_m`` lower than it starts (recorded from mid-descent).
* ``multicopter``, ``fixed-wing``, ``ground``: with ``v_up`` the vertical speed (up of the
  first position), ``v_h`` the horizontal speed and ``height`` the height above the
  flight's lowest point, in priority order ``rest`` (kinematic rest; a multicopter also
  below ``hover_height_m``), ``hover`` (multicopter only: ``height >= hover_height_m``,
  ``v_h < hover_speed_m_s``, ``|v_up| < climb_rate_m_s``), ``climb`` (``v_up >
  climb_rate_m_s``, or below ``hover_speed_m_s`` horizontally an upward acceleration over
  ``rest_accel_m_s2`` while rising: a vertical take-off), ``descent`` (the same downwards;
  neither for ``ground``),
  ``turn`` (the kinematic turn) and ``cruise``. No rocket word (powered, coast, free fall)
  is ever given to these vehicles.

The result is an editable table (:meth:`Segmentation.to_frame`: ``phase, t_start, t_end``);
:func:`segments_table` turns a user's edit (a DataFrame, a list of boundaries or of
``(t_start, t_end)`` / ``(phase, t_start, t_end)`` entries) back into that table.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from itertools import pairwise

import numpy as np
import pandas as pd

from navlib import earth
from navlib._validation import finite_scalar, reject_unknown
from navlib.errors import NavlibInputError
from navlib.units import DEG

__all__ = [
    "MAV_TYPES",
    "PHASES",
    "RECOGNITION_DEFAULTS",
    "SEGMENT_DEFAULTS",
    "VEHICLES",
    "VEHICLE_PHASES",
    "Segmentation",
    "check_vehicle",
    "flight_features",
    "recognise_vehicle",
    "segment_flight",
    "segments_table",
    "vehicle_from_log",
]

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

VEHICLES = ("rocket", "multicopter", "fixed-wing", "ground")
"""Vehicle classes whose phases :func:`segment_flight` names (module docstring)."""
VEHICLE_PHASES = {
    "rocket": ("rest", "powered", "coast", "free_fall", "descent"),
    "multicopter": ("rest", "hover", "climb", "descent", "turn", "cruise"),
    "fixed-wing": ("rest", "climb", "descent", "turn", "cruise"),
    "ground": ("rest", "turn", "cruise"),
}
"""The phase words of each vehicle class, in priority order (the last is the fallback)."""
RECOGNITION_DEFAULTS = {
    "rocket_accel_m_s2": 30.0,
    "rocket_speed_m_s": 20.0,
    "vertical_rate_m_s": 1.0,
    "vertical_max_speed_m_s": 2.0,
    "vertical_min_s": 1.0,
    "airborne_height_m": 20.0,
    "airborne_speed_m_s": 8.0,
    "road_grade_max": 0.15,
    "airborne_min_s": 1.0,
    "sideways_min_deg": 45.0,
    "sideways_min_s": 2.0,
}
"""Thresholds of :func:`recognise_vehicle` (``docs/assumptions.md`` V1; engineering choices)."""
MAV_TYPES = {1: "fixed-wing", 2: "multicopter", 3: "multicopter", 4: "multicopter",
             9: "rocket", 10: "ground", 11: "ground", 13: "multicopter", 14: "multicopter",
             15: "multicopter", 19: "multicopter", 20: "multicopter", 21: "multicopter",
             22: "multicopter", 23: "multicopter", 24: "fixed-wing", 29: "multicopter"}
"""MAVLink ``MAV_TYPE`` -> vehicle class (fixed wing; quad-, coaxial, helicopter, hexa-,
octo-, tricopter, dodecarotor; rocket; ground rover, surface boat; VTOLs, which take off as
rotorcraft; parafoil as fixed-wing)."""
_LOG_VEHICLES = (("arducopter", "multicopter"), ("copter", "multicopter"),
                 ("heli", "multicopter"), ("arduplane", "fixed-wing"), ("plane", "fixed-wing"),
                 ("rover", "ground"), ("ardurover", "ground"))

SEGMENT_COLUMNS = ("phase", "t_start", "t_end")
_FAMILY = {"free_fall": "unpowered", "coast": "unpowered"}
_FEATURES = ("speed", "accel", "f_norm", "gravity", "f_along", "f_lateral", "rate",
             "rate_across", "path_rate", "v_up", "v_h", "a_up", "height", "sideslip")
_TIME_TOL = 1e-6


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
    """

    segments: pd.DataFrame
    features: pd.DataFrame
    thresholds: dict = field(default_factory=dict)
    vehicle: str | None = None

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


def _trajectory_arrays(trajectory):
    for attr in ("t", "position", "velocity", "specific_force", "angular_rate", "attitude"):
        if not hasattr(trajectory, attr):
            raise NavlibInputError(f"trajectory: expected a navlib Trajectory (no {attr!r})")
    t = np.asarray(trajectory.t, dtype=float)
    if t.size < 2:
        raise NavlibInputError(f"trajectory: need at least 2 samples, got {t.size}")
    return (t, np.asarray(trajectory.position, dtype=float),
            np.asarray(trajectory.velocity, dtype=float),
            np.asarray(trajectory.specific_force, dtype=float),
            np.asarray(trajectory.angular_rate, dtype=float), trajectory.attitude.as_matrix())


def flight_features(trajectory, direction_speed_m_s: float = 1.0,
                    rest_accel_m_s2: float = 0.5,
                    turn_speed_m_s: float = 3.0) -> pd.DataFrame:
    """Per-sample kinematic features the segmentation reads (module docstring).

    Returns
    -------
    DataFrame
        ``t``; ``speed`` ``|V|`` (m/s); ``accel`` ``|a^e|``, ``f_norm`` ``|f|`` and
        ``gravity`` ``|gamma(P)|`` (m/s^2); ``f_along`` ``f^e . u`` and ``f_lateral``
        ``|f^e - f_along u|`` (m/s^2);
        ``rate`` ``|omega_eb|``, ``rate_across`` its part off the roll axis (the body axis
        closest to ``u``) and ``path_rate`` ``|V x a| / |V|^2`` (rad/s; 0 below
        ``turn_speed_m_s``); ``v_up`` and ``v_h`` the vertical and horizontal speed (m/s,
        up of the first position's ellipsoid normal), ``a_up`` the vertical acceleration
        (m/s^2), ``height`` the height above the
        flight's lowest point (m) and ``sideslip`` the horizontal angle between the body
        x axis and the velocity (rad, in [0, pi]; 0 below ``turn_speed_m_s`` or with the
        body x axis within 5 deg of vertical).
    """
    t, P, V, f_b, w_ib_b, C_b_e = _trajectory_arrays(trajectory)
    omega = earth.EARTH_RATE_ECEF
    gamma = earth.normal_gravity_ecef(P)
    f_e = np.einsum("nij,nj->ni", C_b_e, f_b)
    w_eb_b = w_ib_b - np.einsum("nji,j->ni", C_b_e, omega)
    a_e = f_e + gamma - 2.0 * np.cross(omega, V)
    speed = np.linalg.norm(V, axis=1)
    a_norm = np.linalg.norm(a_e, axis=1)
    moving = speed >= direction_speed_m_s
    pushed = ~moving & (a_norm > rest_accel_m_s2)
    u = np.zeros_like(V)
    u[moving] = V[moving] / speed[moving, None]
    u[pushed] = a_e[pushed] / a_norm[pushed, None]
    f_along = np.einsum("ni,ni->n", f_e, u)
    # roll axis: the body axis closest to the path; its rate component is not a turn
    u_b = np.einsum("nji,nj->ni", C_b_e, u)
    roll = np.take_along_axis(w_eb_b, np.argmax(np.abs(u_b), axis=1)[:, None], axis=1)[:, 0]
    roll[~(moving | pushed)] = 0.0
    rate = np.linalg.norm(w_eb_b, axis=1)
    path_rate = np.zeros_like(speed)
    fast = speed >= max(turn_speed_m_s, direction_speed_m_s)
    path_rate[fast] = np.linalg.norm(np.cross(V[fast], a_e[fast]), axis=1) / speed[fast] ** 2
    lat, lon, _ = earth.ecef_to_geodetic(P[0])
    up = -earth.ned_to_ecef_matrix(lat, lon)[:, 2]
    v_up = V @ up
    height = (P - P[0]) @ up
    x_h = C_b_e[:, :, 0] - np.outer(C_b_e[:, :, 0] @ up, up)
    v_hv = V - np.outer(v_up, up)
    norms = np.linalg.norm(x_h, axis=1) * np.linalg.norm(v_hv, axis=1)
    level = (np.linalg.norm(x_h, axis=1) > np.sin(5.0 * DEG)) & \
        (np.linalg.norm(v_hv, axis=1) >= turn_speed_m_s)
    sideslip = np.zeros_like(speed)
    sideslip[level] = np.arccos(np.clip(np.einsum("ni,ni->n", x_h[level], v_hv[level])
                                        / norms[level], -1.0, 1.0))
    return pd.DataFrame({
        "t": t,
        "speed": speed,
        "accel": a_norm,
        "f_norm": np.linalg.norm(f_e, axis=1),
        "gravity": np.linalg.norm(gamma, axis=1),
        "f_along": f_along,
        "f_lateral": np.linalg.norm(f_e - f_along[:, None] * u, axis=1),
        "rate": rate,
        "rate_across": np.sqrt(np.maximum(rate**2 - roll**2, 0.0)),
        "path_rate": path_rate,
        "v_up": v_up,
        "v_h": np.sqrt(np.maximum(speed**2 - v_up**2, 0.0)),
        "a_up": a_e @ up,
        "height": height - height.min(),
        "sideslip": sideslip,
    })


def _windows(features: pd.DataFrame, resolution_s: float) -> pd.DataFrame:
    """Average the per-sample features over consecutive windows of ``resolution_s``."""
    t = features["t"].to_numpy()
    t0, t1 = float(t[0]), float(t[-1])
    n_bins = max(int(np.ceil((t1 - t0) / resolution_s - 1e-9)), 1)
    k = np.minimum(((t - t0) / resolution_s).astype(int), n_bins - 1)
    counts = np.bincount(k, minlength=n_bins)
    used = counts > 0
    # window edges rounded to the nanosecond so that 18.000000000000004 reads 18
    out = {"t_start": np.round(t0 + resolution_s * np.arange(n_bins)[used], 9)}
    out["t_end"] = np.minimum(np.round(out["t_start"] + resolution_s, 9), t1)
    out["t"] = 0.5 * (out["t_start"] + out["t_end"])
    for name in _FEATURES:
        sums = np.bincount(k, weights=features[name].to_numpy(), minlength=n_bins)
        out[name] = sums[used] / counts[used]
    frame = pd.DataFrame(out)
    return frame[["t", "t_start", "t_end", *_FEATURES]]


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


def _rocket_sequence(labels: np.ndarray, height: np.ndarray, rise_m: float) -> np.ndarray:
    """Rocket words from the kinematic labels and the flight's order (module docstring)."""
    out = labels.copy()
    rise = np.flatnonzero(height - height[0] >= rise_m)
    if rise.size == 0:   # never rose: on the pad throughout, or recorded from mid-descent
        falling = height[0] - height[-1] > rise_m
        out[labels != "rest"] = "descent" if falling else "rest"
        return out
    launch = int(rise[0])
    while launch > 0 and labels[launch - 1] == "powered":
        launch -= 1
    out[:launch] = "rest"
    apogee = launch + int(np.argmax(height[launch:]))
    ascent = out[launch:apogee + 1]
    ascent[~np.isin(ascent, ("powered", "free_fall"))] = "coast"
    after = out[apogee + 1:]
    after[after != "rest"] = "descent"
    return out


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
        if duration(runs[k]) >= min_duration - _TIME_TOL:
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


def segment_flight(trajectory, vehicle: str | None = None, **thresholds) -> Segmentation:
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
        the last sample) and the per-window ``features``.
    """
    vehicle = None if vehicle is None else check_vehicle(vehicle)
    p = _options(thresholds)
    features = flight_features(trajectory, p["direction_speed_m_s"], p["rest_accel_m_s2"],
                               p["turn_speed_m_s"])
    w = _windows(features, p["resolution_s"])
    n = len(w)
    strict = _classify(_conditions(w, p, 0.0, vehicle), n)
    relaxed = _conditions(w, p, p["hysteresis"], vehicle)
    relaxed["cruise"] = strict == "cruise"
    labels = _with_hysteresis(strict, relaxed)
    if vehicle == "rocket":
        labels = _rocket_sequence(labels, w["height"].to_numpy(), p["hover_height_m"])
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
    return Segmentation(segments=segments, features=w, thresholds=p, vehicle=vehicle)


# --------------------------------------------------------------------------- vehicles


def check_vehicle(vehicle) -> str:
    """``vehicle`` if it is one of :data:`VEHICLES` (case and ``_``/``-`` forgiven)."""
    text = str(vehicle).strip().lower().replace("_", "-") if isinstance(vehicle, str) else None
    if text == "fixedwing":
        text = "fixed-wing"
    if text not in VEHICLES:
        raise NavlibInputError(f"vehicle: expected one of {list(VEHICLES)}, got {vehicle!r}")
    return text


def vehicle_from_log(attrs: Mapping) -> tuple[str | None, str]:
    """The vehicle class a log says it is, from a reader's ``attrs``, and why.

    ``attrs["vehicle"]`` when a reader sets one of :data:`VEHICLES`; ``rocket`` for an
    Altus Metrum AltOS export (``attrs["flight_states"]``: only rocket flight computers
    write one); the ArduPilot firmware banner (``attrs["hardware"]``, e.g. ``ArduCopter
    V4.5.0`` -> multicopter, ``ArduPlane`` -> fixed-wing, ``Rover`` -> ground). ``(None,
    "")`` when the log does not say (then :func:`recognise_vehicle` reads the kinematics).
    """
    attrs = attrs if isinstance(attrs, Mapping) else {}
    given = attrs.get("vehicle")
    if isinstance(given, str) and given.strip().lower() in VEHICLES:
        return given.strip().lower(), "the log names it"
    if attrs.get("flight_states") is not None:
        return "rocket", "an Altus Metrum AltOS flight-computer log"
    mav_type = attrs.get("mav_type")
    if isinstance(mav_type, int | np.integer) and int(mav_type) in MAV_TYPES:
        return MAV_TYPES[int(mav_type)], f"the log's MAV_TYPE {int(mav_type)}"
    banner = str(attrs.get("hardware") or "").lower()
    if str(attrs.get("autopilot", "")).lower() == "ardupilot" and banner:
        for word, vehicle in _LOG_VEHICLES:
            if word in banner:
                return vehicle, f"the ArduPilot firmware banner {attrs['hardware']!r}"
    return None, ""


def recognise_vehicle(trajectory, **thresholds) -> tuple[str, str]:
    """The vehicle class of a (fitted) flight from its kinematics, and why
    (``docs/assumptions.md`` V1).

    In order: ``rocket`` when the specific force exceeds ``rocket_accel_m_s2`` (30, about
    3 g, over 0.1 s) and the vertical speed ``rocket_speed_m_s`` (20); ``multicopter`` when
    the vehicle moves vertically (``|v_up| > vertical_rate_m_s``, 1) with little horizontal
    speed (``v_h < vertical_max_speed_m_s``, 2) for ``vertical_min_s`` (1 s) in all (only
    rotorcraft and rockets take off or land vertically), or flies sideways (a sideslip
    between ``sideways_min_deg`` (45) and 180 minus it, above ``hover_height_m`` of
    :data:`SEGMENT_DEFAULTS` and 3 m/s) for ``sideways_min_s`` (2 s): an aeroplane or a car
    goes where its nose points (or backwards), a multicopter in any direction;
    ``fixed-wing`` when it rises
    ``airborne_height_m`` (20) above its lowest point and climbs or descends faster than a
    road allows (``|v_up| > road_grade_max v_h``, 0.15) at ``v_h > airborne_speed_m_s`` (8)
    for ``airborne_min_s`` (1 s) in all;
    else ``ground``. A stationary record is ``ground``.

    Parameters
    ----------
    trajectory : navlib.trajectory.Trajectory
    **thresholds
        Any of :data:`RECOGNITION_DEFAULTS`.
    """
    reject_unknown(thresholds, RECOGNITION_DEFAULTS, "recognise_vehicle")
    p = {k: finite_scalar(thresholds.get(k, v), k, 0.0, low_open=True)
         for k, v in RECOGNITION_DEFAULTS.items()}
    w = _windows(flight_features(trajectory), 0.1)
    dt = (w["t_end"] - w["t_start"]).to_numpy()
    f_peak, up_peak = float(w["f_norm"].max()), float(w["v_up"].max())
    if f_peak > p["rocket_accel_m_s2"] and up_peak > p["rocket_speed_m_s"]:
        return "rocket", (f"kinematics: specific force up to {f_peak:.3g} m/s^2 and vertical "
                          f"speed up to {up_peak:.3g} m/s")
    vertical = ((w["v_up"].abs() > p["vertical_rate_m_s"])
                & (w["v_h"] < p["vertical_max_speed_m_s"])).to_numpy()
    if dt[vertical].sum() >= p["vertical_min_s"]:
        return "multicopter", (f"kinematics: {dt[vertical].sum():.3g} s of vertical motion "
                               f"(|v_up| > {p['vertical_rate_m_s']:g} m/s at horizontal speed "
                               f"below {p['vertical_max_speed_m_s']:g} m/s)")
    slip = w["sideslip"].to_numpy()
    sideways = ((slip > p["sideways_min_deg"] * DEG) & (slip < np.pi - p["sideways_min_deg"] * DEG)
                & (w["height"] >= SEGMENT_DEFAULTS["hover_height_m"]).to_numpy())
    if dt[sideways].sum() >= p["sideways_min_s"]:
        return "multicopter", (f"kinematics: {dt[sideways].sum():.3g} s of flight sideways "
                               f"(body x axis over {p['sideways_min_deg']:g} deg off the "
                               "velocity)")
    steep = ((w["v_h"] > p["airborne_speed_m_s"])
             & (w["v_up"].abs() > p["road_grade_max"] * w["v_h"])).to_numpy()
    height = float(w["height"].max())
    if height > p["airborne_height_m"] and dt[steep].sum() >= p["airborne_min_s"]:
        return "fixed-wing", (f"kinematics: {height:.3g} m of height range and "
                              f"{dt[steep].sum():.3g} s of climb or descent steeper than a road "
                              f"at over {p['airborne_speed_m_s']:g} m/s")
    return "ground", ("kinematics: no boost, no vertical take-off or landing, no airborne "
                      "climb")


# --------------------------------------------------------------------------- user edits


def _entry(item, k: int) -> tuple[str | None, float, float]:
    """One segment entry: a mapping, ``(t_start, t_end)`` or ``(phase, t_start, t_end)``."""
    where = f"segments[{k}]"
    if isinstance(item, Mapping):
        missing = [c for c in ("t_start", "t_end") if c not in item]
        if missing:
            raise NavlibInputError(f"{where}: missing key(s) {missing}")
        phase = item.get("phase")
        start, end = item["t_start"], item["t_end"]
    elif isinstance(item, Sequence) and not isinstance(item, str) and len(item) in (2, 3):
        phase = item[0] if len(item) == 3 else None
        start, end = item[-2], item[-1]
    else:
        raise NavlibInputError(f"{where}: expected (t_start, t_end), (phase, t_start, t_end) "
                               f"or a mapping, got {item!r}")
    if phase is not None and (not isinstance(phase, str) or not phase.strip()):
        raise NavlibInputError(f"{where}: phase must be a non-empty string, got {phase!r}")
    return (None if phase is None else phase.strip(), finite_scalar(start, f"{where} t_start"),
            finite_scalar(end, f"{where} t_end"))


def _from_boundaries(values: np.ndarray, t0: float, t1: float) -> list:
    if np.any(np.diff(values) <= 0):
        raise NavlibInputError(f"segments: boundaries must be strictly increasing, got "
                               f"{values.tolist()}")
    cuts = values[(values > t0 + _TIME_TOL) & (values < t1 - _TIME_TOL)]
    outside = values[(values < t0 - _TIME_TOL) | (values > t1 + _TIME_TOL)]
    if outside.size:
        raise NavlibInputError(f"segments: boundaries {outside.tolist()} lie outside the flight "
                               f"span {t0:.6g}..{t1:.6g} s")
    edges = np.concatenate([[t0], cuts, [t1]])
    return [(None, float(a), float(b)) for a, b in pairwise(edges)]


def segments_table(segments, t_start: float, t_end: float,
                   automatic: Segmentation | None = None) -> pd.DataFrame:
    """Normalise a user's segment choice to the table ``phase, t_start, t_end, duration``.

    Parameters
    ----------
    segments : DataFrame, sequence of numbers, or sequence of entries
        * a DataFrame with ``t_start``, ``t_end`` and optionally ``phase`` columns (e.g.
          an edited :meth:`Segmentation.to_frame`);
        * a list of boundary times, e.g. ``[18, 46]`` or ``[0, 18, 46, 86]``: contiguous
          segments between them, the flight's ends added when missing;
        * a list of ``(t_start, t_end)`` or ``(phase, t_start, t_end)`` tuples or mappings:
          these windows only (gaps allowed, overlaps not).
    t_start, t_end : float
        The flight span, s; every segment must lie inside it.
    automatic : Segmentation, optional
        Labels segments given without a phase by the automatic phase covering most of the
        segment; without it they are labelled ``segment 1``, ``segment 2``, ...

    Raises
    ------
    NavlibInputError
        Unreadable entries, boundaries not increasing or outside the span, empty or
        overlapping segments (naming the entry).
    """
    t0 = finite_scalar(t_start, "t_start")
    t1 = finite_scalar(t_end, "t_end")
    if t1 <= t0:
        raise NavlibInputError(f"t_end: must be after t_start = {t0}, got {t1}")
    if isinstance(segments, Segmentation):
        segments = segments.segments
    if isinstance(segments, pd.DataFrame):
        missing = [c for c in ("t_start", "t_end") if c not in segments.columns]
        if missing:
            raise NavlibInputError(f"segments: missing column(s) {missing}; columns are "
                                   f"{list(segments.columns)}")
        cols = [c for c in SEGMENT_COLUMNS if c in segments.columns]
        entries = [_entry(dict(zip(cols, row, strict=True)), k)
                   for k, row in enumerate(segments[cols].itertuples(index=False))]
    elif isinstance(segments, np.ndarray) or (
            isinstance(segments, Sequence) and not isinstance(segments, str)):
        items = list(segments)
        if not items:
            raise NavlibInputError("segments: empty; give boundaries or segment entries")
        if all(isinstance(x, int | float | np.integer | np.floating)
               and not isinstance(x, bool) for x in items):
            values = np.array([finite_scalar(x, f"segments[{k}]")
                               for k, x in enumerate(items)])
            entries = _from_boundaries(values, t0, t1)
        else:
            entries = [_entry(item, k) for k, item in enumerate(items)]
    else:
        raise NavlibInputError(f"segments: expected a DataFrame, a list of boundaries or of "
                               f"(t_start, t_end) entries, got {type(segments).__name__}")
    if not entries:
        raise NavlibInputError("segments: no segment given")
    rows = sorted(entries, key=lambda e: e[1])
    for k, (_, a, b) in enumerate(rows):
        if b <= a:
            raise NavlibInputError(f"segments: segment {k + 1} ({a:.6g}..{b:.6g} s) is empty; "
                                   f"t_end must be after t_start")
        if a < t0 - _TIME_TOL or b > t1 + _TIME_TOL:
            raise NavlibInputError(f"segments: segment {k + 1} ({a:.6g}..{b:.6g} s) leaves the "
                                   f"flight span {t0:.6g}..{t1:.6g} s")
        if k and a < rows[k - 1][2] - _TIME_TOL:
            raise NavlibInputError(f"segments: segment {k + 1} ({a:.6g}..{b:.6g} s) overlaps "
                                   f"segment {k} (ends {rows[k - 1][2]:.6g} s)")
    phases = [phase if phase is not None else _majority(automatic, a, b, k)
              for k, (phase, a, b) in enumerate(rows)]
    table = pd.DataFrame({"phase": phases, "t_start": [max(r[1], t0) for r in rows],
                          "t_end": [min(r[2], t1) for r in rows]})
    table["duration"] = table["t_end"] - table["t_start"]
    return table


def _majority(automatic: Segmentation | None, a: float, b: float, k: int) -> str:
    """The automatic phase covering most of ``[a, b]`` (``segment k+1`` without one)."""
    if automatic is None:
        return f"segment {k + 1}"
    seg = automatic.segments
    overlap = (np.minimum(seg["t_end"], b) - np.maximum(seg["t_start"], a)).clip(lower=0.0)
    totals = overlap.groupby(seg["phase"]).sum()
    return str(totals.idxmax()) if totals.max() > 0 else f"segment {k + 1}"
