"""Rocket missions: ``[rocket]`` and ``[[phase]]`` tables mapped onto :func:`sounding_rocket`.

The phase kinds ``rail``, ``boost``, ``coast`` and optionally ``despin``, ``drogue``,
``main`` and ``landing`` (:data:`ROCKET_PHASES`) map one-to-one onto the keywords of
:func:`navlib.trajectory.sounding_rocket`, whose ODE and splines build the flight
(assumptions M1 and M7 of ``docs/assumptions.md``).
"""

from __future__ import annotations

from collections.abc import Mapping

from navlib._validation import reject_unknown
from navlib.errors import NavlibInputError
from navlib.trajectory.base import Trajectory
from navlib.trajectory.mission.reading import Mission, checked_number, sub_table
from navlib.trajectory.rocket import ROCKET_DEFAULTS, sounding_rocket

__all__ = ["DESCENT_CAP_S", "ROCKET_BODY", "ROCKET_PHASES", "rocket_keywords", "rocket_trajectory"]

ROCKET_BODY = {"mass_initial_kg": "mass_initial_kg", "mass_burnout_kg": "mass_burnout_kg",
               "drag_area_m2": "drag_area_m2", "scale_height_m": "scale_height_m",
               "spin_hz": "spin_hz", "spin_speed_m_s": "spin_speed_mps",
               "roll0_deg": "roll0_deg"}
"""``[rocket]`` key -> :func:`sounding_rocket` keyword (all optional)."""

ROCKET_PHASES = {
    "rail": {"elevation_deg": "rail_elevation_deg", "azimuth_deg": "rail_azimuth_deg",
             "length_m": "rail_length_m", "fade_m": "rail_fade_m"},
    "boost": {"start_s": "ignition_s", "burn_time_s": None, "thrust_n": "thrust_n",
              "acceleration_m_s2": None, "ramp_s": "ignition_ramp_s",
              "tailoff_s": "tailoff_s"},
    "coast": {"end_s": "end_s", "free_flight_s": "free_flight_s"},
    "despin": {"at_s": "despin_s", "factor": "despin_factor",
               "duration_s": "despin_duration_s"},
    "drogue": {"rate_m_s": "drogue_rate_mps", "delay_s": "drogue_delay_s",
               "time_constant_s": "drogue_tau_s", "inflation_s": "drogue_inflation_s",
               "spin_hz": "canopy_spin_hz", "swing_deg": "canopy_swing_deg",
               "swing_period_s": "canopy_swing_period_s"},
    "main": {"height_m": "main_height_m", "rate_m_s": "main_rate_mps",
             "time_constant_s": "main_tau_s", "inflation_s": "main_inflation_s"},
    "landing": {"end_s": "end_s"},
}
"""Rocket phase kind -> its keys -> :func:`sounding_rocket` keyword (None: derived:
``burnout_s = start_s + burn_time_s``; ``thrust_n = acceleration_m_s2 * mass_burnout_kg``,
the thrust acceleration at burnout). ``boost`` needs ``start_s``, ``burn_time_s`` and one of
``thrust_n`` / ``acceleration_m_s2``; ``despin`` needs ``at_s``. Without a ``drogue`` the
flight ends at the coast's ``end_s`` (required). With one (assumption M7) the coast runs
through apogee, the drogue opens ``delay_s`` after it and brings the rocket to its descent
rate ``rate_m_s`` with the time constant ``time_constant_s``; an optional ``main`` opens at
``height_m`` above the site; the flight ends at touchdown, or at the ``landing`` phase's
``end_s`` (the end of the log) if that comes first. ``spin_hz`` of the drogue is the roll
rate about the riser under the canopies, ``swing_deg`` and ``swing_period_s`` a pendulum
swing of the body there."""

_POSITIVE_KEYS = {"rate_m_s", "time_constant_s", "inflation_s", "height_m", "swing_period_s"}
"""Phase keys that must be strictly positive."""

_REQUIRED_PHASE_KEYS = {"rail": (), "boost": ("start_s", "burn_time_s"), "coast": (),
                        "despin": ("at_s",), "drogue": ("rate_m_s",),
                        "main": ("height_m", "rate_m_s"), "landing": ()}

_PHASE_ORDER = ("rail", "boost", "coast", "drogue", "main", "landing")
"""Order of the rocket phases in the file (``despin`` may come anywhere after ``boost``)."""

DESCENT_CAP_S = 3600.0
"""End of a recovery flight that gives no ``[landing] end_s`` and has not touched down."""


def rocket_keywords(mission: Mission) -> tuple[dict, dict]:
    """:func:`sounding_rocket` keywords of a rocket mission, and keyword -> where it was set.
    """
    where, table = mission.where, mission.table
    if "waypoint" in table or "limits" in table:
        raise NavlibInputError(f"{where}: a rocket mission has [[phase]] tables, not "
                               "[[waypoint]] or [limits]")
    site = table["site"]
    kw = {"lat_deg": float(site["lat_deg"]), "lon_deg": float(site["lon_deg"]),
          "alt_m": float(site.get("alt_m", 0.0)), "rate_hz": mission.rate_hz}
    origin = {k: f"[site] {k}" for k in ("lat_deg", "lon_deg", "alt_m")}
    origin["rate_hz"] = "rate_hz"
    body = sub_table(table, "rocket", where, required=False)
    reject_unknown(body, ROCKET_BODY, f"{where} [rocket]")
    for key, keyword in ROCKET_BODY.items():
        if key in body:
            low = None if key == "roll0_deg" else 0.0
            kw[keyword] = checked_number(body, key, f"{where} [rocket]", low)
            origin[keyword] = f"[rocket] {key}"
    phases = table.get("phase")
    if not isinstance(phases, list) or not phases:
        raise NavlibInputError(f"{where}: a rocket mission needs [[phase]] tables (kinds "
                               f"{list(ROCKET_PHASES)})")
    seen = {}
    for i, phase in enumerate(phases):
        label = f"{where} phase {i}"
        if not isinstance(phase, Mapping):
            raise NavlibInputError(f"{label}: expected a table, got {phase!r}")
        kind = phase.get("kind")
        if kind == "apogee":
            raise NavlibInputError(
                f"{label}: 'apogee' is not a phase but the event that ends the climb; the "
                "'drogue' phase's delay_s counts from it")
        if kind not in ROCKET_PHASES:
            raise NavlibInputError(
                f"{label}: kind {kind!r} is not a rocket phase this planner builds; expected "
                f"one of {list(ROCKET_PHASES)}")
        if kind in seen:
            raise NavlibInputError(f"{label}: a second '{kind}' phase (first: phase "
                                   f"{seen[kind]})")
        seen[kind] = i
        label = f"{label} ({kind})"
        reject_unknown({k: v for k, v in phase.items() if k != "kind"}, ROCKET_PHASES[kind],
                       label)
        for key in _REQUIRED_PHASE_KEYS[kind]:
            if key not in phase:
                raise NavlibInputError(f"{label}: missing key {key!r}")
        for key, keyword in ROCKET_PHASES[kind].items():
            if key in phase:
                low = None if key in ("azimuth_deg", "spin_hz") else 0.0
                value = checked_number(phase, key, label, low, low_open=key in _POSITIVE_KEYS)
                if keyword is not None:
                    kw[keyword] = value
                    origin[keyword] = f"phase {i} ({kind}) {key}"
        if kind == "boost":
            if ("thrust_n" in phase) == ("acceleration_m_s2" in phase):
                raise NavlibInputError(f"{label}: give exactly one of 'thrust_n' and "
                                       "'acceleration_m_s2'")
            kw["burnout_s"] = float(phase["start_s"]) + float(phase["burn_time_s"])
            origin["burnout_s"] = f"phase {i} (boost) start_s + burn_time_s"
            if "acceleration_m_s2" in phase:
                mass = kw.get("mass_burnout_kg", ROCKET_DEFAULTS["mass_burnout_kg"])
                kw["thrust_n"] = float(phase["acceleration_m_s2"]) * mass
                origin["thrust_n"] = f"phase {i} (boost) acceleration_m_s2"
    for kind in ("rail", "boost", "coast"):
        if kind not in seen:
            raise NavlibInputError(f"{where}: no '{kind}' phase; a rocket mission needs rail, "
                                   "boost and coast (despin, drogue, main, landing optional)")
    present = [k for k in _PHASE_ORDER if k in seen]
    order = [seen[k] for k in present]
    if order != sorted(order):
        raise NavlibInputError(f"{where}: phases must come in the order "
                               f"{', '.join(present)} (got them at positions {order})")
    coast = phases[seen["coast"]]
    if "drogue" in seen:
        if "end_s" in coast:
            raise NavlibInputError(
                f"{where} phase {seen['coast']} (coast): no end_s with a drogue phase: the "
                "coast ends at apogee and the flight at touchdown (give the end of the log as "
                "the landing phase's end_s)")
        kw.setdefault("end_s", DESCENT_CAP_S)
    else:
        for kind in ("main", "landing"):
            if kind in seen:
                raise NavlibInputError(f"{where} phase {seen[kind]} ({kind}): needs a "
                                       "'drogue' phase before it")
        if "end_s" not in coast:
            raise NavlibInputError(f"{where} phase {seen['coast']} (coast): missing key "
                                   "'end_s' (the end of the flight without a drogue)")
    if "free_flight_s" not in kw:   # an event marker only: inside the coast
        kw["free_flight_s"] = kw["burnout_s"] if "drogue" in seen else min(
            max(ROCKET_DEFAULTS["free_flight_s"], kw["burnout_s"]), kw["end_s"])
    if "despin" not in seen:        # no de-spin: a unit factor inside the coast
        kw["despin_factor"] = 1.0
        kw["despin_duration_s"] = min(ROCKET_DEFAULTS["despin_duration_s"],
                                      kw["end_s"] - kw["burnout_s"])
        kw["despin_s"] = (kw["burnout_s"] + 0.5 * kw["despin_duration_s"] if "drogue" in seen
                          else 0.5 * (kw["burnout_s"] + kw["end_s"]))
    return kw, origin


def rocket_trajectory(mission: Mission) -> Trajectory:
    kw, origin = rocket_keywords(mission)
    try:
        traj = sounding_rocket(**kw)
    except NavlibInputError as exc:
        keyword = str(exc).split(":", 1)[0]
        place = origin.get(keyword, "the defaults of navlib.trajectory.sounding_rocket")
        raise NavlibInputError(f"{mission.where} {place}: {exc}") from exc
    return traj
