"""Mission files: a flight described before it flies, turned into an exact-IMU trajectory.

A mission is a TOML file (or the same content as a mapping) with units in the key suffixes,
like the sensor presets of ``data/sensors/``::

    name = "..."                 # label
    vehicle = "multicopter"      # rocket | multicopter | fixed-wing | ground
    rate_hz = 100.0              # IMU rate of the trajectory
    sensors = "pixhawk_mems"     # optional sensor preset (name or file) of the plan

    [site]                       # start site (launch pad, home point)
    lat_deg = ...
    lon_deg = ...
    alt_m = ...

    [gnss]                       # optional
    rate_hz = 5.0
    sigma_m = 2.0                # optional; else the preset's
    outages = [[40.0, 55.0]]     # [start_s, end_s] windows without GNSS

Rockets then give ``[rocket]`` (body: masses, drag area, spin) and ``[[phase]]`` tables of
kinds ``rail``, ``boost``, ``coast`` and optionally ``despin``, ``drogue``, ``main`` and
``landing`` (see :data:`ROCKET_PHASES`); they map one-to-one onto the keywords of
:func:`navlib.trajectory.sounding_rocket`, whose ODE and splines build the flight
(assumptions M1 and M7 of ``docs/assumptions.md``). Multicopters,
fixed-wing aircraft and ground vehicles give ``[limits]`` and ``[[waypoint]]`` tables
(position, leg speed, hover or hold times; see :data:`WAYPOINT_KEYS`), built by
:func:`waypoint_trajectory` (assumptions M2-M4).

Every mission trajectory goes through :func:`navlib.trajectory.base.build_trajectory`, so
its specific force and angular rate satisfy the ECEF kinematics exactly (the closure of
``tests/test_trajectory.py``) and are continuous: every change of velocity or heading is a
C^3 smoothstep blend whose length follows from the stated acceleration, turn-radius or bank
limits.
"""

from __future__ import annotations

import copy
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from navlib import earth
from navlib._validation import finite_scalar, latitude_deg, reject_unknown
from navlib.errors import NavlibInputError
from navlib.resources import data_dir
from navlib.segmentation import VEHICLES
from navlib.trajectory._attitude import smoothstep, unit_and_rate, zyx_attitude
from navlib.trajectory._flight import output_times, ramp_integral
from navlib.trajectory.base import Trajectory, build_trajectory
from navlib.trajectory.rocket import ROCKET_DEFAULTS, sounding_rocket
from navlib.units import DEG, G0

__all__ = ["MISSION_DIR", "Mission", "from_mission", "list_missions", "load_mission",
           "mission_path", "read_mission", "waypoint_trajectory", "with_values"]

MISSION_DIR = data_dir() / "missions"
"""Folder of the example missions (``data/missions/*.toml``, shipped in the wheel)."""


_TOP_KEYS = {"name", "description", "vehicle", "rate_hz", "sensors", "site", "gnss",
             "rocket", "phase", "limits", "waypoint"}
_SITE_KEYS = {"lat_deg", "lon_deg", "alt_m"}
_GNSS_KEYS = {"rate_hz", "sigma_m", "outages"}

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

WAYPOINT_KEYS = {
    "multicopter": {"hover_s"},
    "ground": {"hold_s"},
    "fixed-wing": set(),
}
"""Per vehicle class, the stop key of a waypoint (besides the position keys ``north_m,
east_m, up_m`` or ``lat_deg, lon_deg, alt_m``, and ``speed_m_s``, the speed of the leg
that arrives at the waypoint). A waypoint with a stop key is a stop (at rest for that many
seconds); the others are flown through, cutting the corner."""

LIMIT_DEFAULTS = {
    "multicopter": {"max_acceleration_m_s2": 2.0, "speed_m_s": 5.0},
    "ground": {"max_acceleration_m_s2": 1.5, "turn_radius_m": 10.0, "speed_m_s": 5.0},
    "fixed-wing": {"max_acceleration_m_s2": 2.0, "bank_limit_deg": 30.0, "speed_m_s": 20.0},
}
"""``[limits]`` keys per vehicle class and their defaults (assumption M3): the largest
acceleration of a start, stop or speed change, the turn radius of a ground vehicle and the
bank limit of a fixed-wing aircraft; ``speed_m_s`` is the leg speed of waypoints that do
not give one."""

_PEAK_RATE = 2.1875
"""Largest slope of the C^3 smoothstep (``s'(1/2) = 35/16``): a blend of ``dv`` over ``T``
s peaks at ``35/16 |dv| / T`` m/s^2."""


@dataclass(frozen=True)
class Mission:
    """A checked mission (SI inside, the file's own values in ``table``).

    Attributes
    ----------
    name, vehicle : str
    rate_hz : float
        IMU rate of the trajectory, Hz.
    sensors : str or None
        The mission's sensor preset (name or file), if it names one.
    gnss_rate_hz : float or None
        GNSS rate of the plan, Hz (None: the preset's).
    gnss_sigma_m : float or None
        GNSS position sigma per axis, m (None: the preset's).
    outages : tuple of (float, float)
        GNSS outage windows ``(start_s, end_s)``.
    table : dict
        The mission as read (a deep copy), for :func:`with_values` and the reports.
    where : str
        The file name (or ``"mission"``) that error messages start with.
    """

    name: str
    vehicle: str
    rate_hz: float
    sensors: str | None
    gnss_rate_hz: float | None
    gnss_sigma_m: float | None
    outages: tuple
    table: dict = field(repr=False)
    where: str = "mission"


# --------------------------------------------------------------------------- reading


def list_missions() -> list[str]:
    """Names of the example missions shipped in ``data/missions/`` (sorted)."""
    return sorted(p.stem for p in MISSION_DIR.glob("*.toml"))


def mission_path(name_or_path) -> Path:
    """The file of an example mission name (``"multicopter_survey"``) or a path."""
    text = str(name_or_path)
    path = Path(text)
    if path.suffix == ".toml" or path.parent != Path("."):
        if not path.is_file():
            raise NavlibInputError(f"mission: file {text!r} not found")
        return path
    path = MISSION_DIR / f"{text}.toml"
    if not path.is_file():
        raise NavlibInputError(f"mission: unknown example mission {text!r}; available: "
                               f"{list_missions()}")
    return path


def read_mission(path_or_mapping) -> tuple[dict, str]:
    """The raw mission table and its label: a TOML file (path or example name) parsed, or a
    mapping deep-copied."""
    if isinstance(path_or_mapping, Mapping):
        return copy.deepcopy(dict(path_or_mapping)), "mission"
    if not isinstance(path_or_mapping, str | Path):
        raise NavlibInputError(f"mission: expected a TOML file, an example name or a mapping, "
                               f"got {type(path_or_mapping).__name__}")
    path = mission_path(path_or_mapping)
    try:
        table = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise NavlibInputError(f"{path.name}: not valid TOML ({exc})") from exc
    return table, path.name


def _number(table: Mapping, key: str, where: str, low=None, high=None, low_open=False,
            default=None) -> float:
    if key not in table:
        if default is None:
            raise NavlibInputError(f"{where}: missing key {key!r}")
        return float(default)
    value = table[key]
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise NavlibInputError(f"{where} {key}: expected a number, got {value!r}")
    return finite_scalar(value, f"{where} {key}", low, high, low_open)


def _table(parent: Mapping, key: str, where: str, required: bool = True) -> dict:
    if key not in parent:
        if required:
            raise NavlibInputError(f"{where}: missing table [{key}]")
        return {}
    value = parent[key]
    if not isinstance(value, Mapping):
        raise NavlibInputError(f"{where}: [{key}] must be a table, got {value!r}")
    return dict(value)


def _outages(gnss: Mapping, where: str) -> tuple:
    raw = gnss.get("outages", [])
    if not isinstance(raw, list):
        raise NavlibInputError(f"{where} [gnss] outages: expected a list of [start_s, end_s] "
                               f"pairs, got {raw!r}")
    out = []
    for i, pair in enumerate(raw):
        label = f"{where} [gnss] outages[{i}]"
        if not isinstance(pair, list | tuple) or len(pair) != 2:
            raise NavlibInputError(f"{label}: expected [start_s, end_s], got {pair!r}")
        a = finite_scalar(pair[0], f"{label} start_s", 0.0)
        b = finite_scalar(pair[1], f"{label} end_s", a, low_open=True)
        out.append((a, b))
    return tuple(sorted(out))


def load_mission(path_or_mapping) -> Mission:
    """Read and check a mission (file, example name or mapping) without building it.

    Raises
    ------
    NavlibInputError
        Naming the file, the table, the phase or waypoint and the key: unknown keys or
        vehicle class, missing keys, values of the wrong type or out of range.
    """
    table, where = read_mission(path_or_mapping)
    reject_unknown(table, _TOP_KEYS, where)
    vehicle = table.get("vehicle")
    if vehicle not in VEHICLES:
        raise NavlibInputError(f"{where} vehicle: expected one of {list(VEHICLES)}, got "
                               f"{vehicle!r}")
    rate = _number(table, "rate_hz", where, 0.0, low_open=True,
                   default=100.0 if vehicle == "rocket" else 50.0)
    sensors = table.get("sensors")
    if sensors is not None and not isinstance(sensors, str):
        raise NavlibInputError(f"{where} sensors: expected a preset name or file, got "
                               f"{sensors!r}")
    site = _table(table, "site", where)
    reject_unknown(site, _SITE_KEYS, f"{where} [site]")
    latitude_deg(_number(site, "lat_deg", f"{where} [site]"), f"{where} [site] lat_deg")
    _number(site, "lon_deg", f"{where} [site]", -360.0, 360.0)
    _number(site, "alt_m", f"{where} [site]", -500.0, 10_000.0, default=0.0)
    gnss = _table(table, "gnss", where, required=False)
    reject_unknown(gnss, _GNSS_KEYS, f"{where} [gnss]")
    gnss_rate = (_number(gnss, "rate_hz", f"{where} [gnss]", 0.0, low_open=True)
                 if "rate_hz" in gnss else None)
    sigma = (_number(gnss, "sigma_m", f"{where} [gnss]", 0.0, low_open=True)
             if "sigma_m" in gnss else None)
    mission = Mission(name=str(table.get("name", where)), vehicle=vehicle, rate_hz=rate,
                      sensors=sensors, gnss_rate_hz=gnss_rate, gnss_sigma_m=sigma,
                      outages=_outages(gnss, where), table=table, where=where)
    if vehicle == "rocket":
        _rocket_keywords(mission)
    else:
        _waypoints(mission)
    return mission


def with_values(mission, changes: Mapping) -> dict:
    """A copy of the mission table with ``changes`` applied: ``{"rate_hz": 50}`` for a top
    key, ``{"rocket.spin_hz": 1.0}`` or ``{"gnss.outages": [[30, 40]]}`` for a key of a
    table, ``{"phase.2.burn_time_s": 20}`` / ``{"waypoint.3.speed_m_s": 8}`` for a key of
    the n-th (0-based) phase or waypoint. Returns the mapping (give it to
    :func:`from_mission` or :func:`load_mission`)."""
    table = mission.table if isinstance(mission, Mission) else read_mission(mission)[0]
    table = copy.deepcopy(table)
    for key, value in dict(changes).items():
        parts = str(key).split(".")
        target = table
        try:
            for part in parts[:-1]:
                target = target[int(part)] if isinstance(target, list) else \
                    target.setdefault(part, {})
        except (IndexError, ValueError, AttributeError) as exc:
            raise NavlibInputError(f"changes: {key!r} names no table of the mission "
                                   f"({exc})") from exc
        if not isinstance(target, dict):
            raise NavlibInputError(f"changes: {key!r} names no table of the mission")
        target[parts[-1]] = value
    return table


# --------------------------------------------------------------------------- rockets


def _rocket_keywords(mission: Mission) -> tuple[dict, dict]:
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
    body = _table(table, "rocket", where, required=False)
    reject_unknown(body, ROCKET_BODY, f"{where} [rocket]")
    for key, keyword in ROCKET_BODY.items():
        if key in body:
            low = None if key == "roll0_deg" else 0.0
            kw[keyword] = _number(body, key, f"{where} [rocket]", low)
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
                value = _number(phase, key, label, low, low_open=key in _POSITIVE_KEYS)
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


def _rocket(mission: Mission) -> Trajectory:
    kw, origin = _rocket_keywords(mission)
    try:
        traj = sounding_rocket(**kw)
    except NavlibInputError as exc:
        keyword = str(exc).split(":", 1)[0]
        place = origin.get(keyword, "the defaults of navlib.trajectory.sounding_rocket")
        raise NavlibInputError(f"{mission.where} {place}: {exc}") from exc
    return traj


# --------------------------------------------------------------------------- waypoints


@dataclass(frozen=True)
class _Event:
    """One smoothstep blend of the velocity (and heading, pitch) over ``[c - T/2, c + T/2]``."""

    center: float
    duration: float
    dv: np.ndarray
    dpsi: float = 0.0
    dtheta: float = 0.0


def _position_keys(wp: Mapping, label: str, site) -> np.ndarray:
    local = {"north_m", "east_m", "up_m"} & set(wp)
    geo = {"lat_deg", "lon_deg", "alt_m"} & set(wp)
    if local and geo:
        raise NavlibInputError(f"{label}: give the position as north_m/east_m/up_m or as "
                               "lat_deg/lon_deg/alt_m, not both")
    if geo:
        lat = latitude_deg(_number(wp, "lat_deg", label), f"{label} lat_deg") * DEG
        lon = _number(wp, "lon_deg", label, -360.0, 360.0) * DEG
        alt = _number(wp, "alt_m", label, -500.0, 20_000.0)
        P = earth.geodetic_to_ecef(lat, lon, alt)
        P0, C_n_e = site
        return C_n_e.T @ (np.asarray(P) - P0)
    if not local:
        raise NavlibInputError(f"{label}: missing position (north_m, east_m, up_m or "
                               "lat_deg, lon_deg, alt_m)")
    return np.array([_number(wp, "north_m", label, default=0.0),
                     _number(wp, "east_m", label, default=0.0),
                     -_number(wp, "up_m", label, default=0.0)])


def _site(mission: Mission):
    site = mission.table["site"]
    lat, lon = float(site["lat_deg"]) * DEG, float(site["lon_deg"]) * DEG
    P0 = np.asarray(earth.geodetic_to_ecef(lat, lon, float(site.get("alt_m", 0.0))))
    return P0, np.asarray(earth.ned_to_ecef_matrix(lat, lon))


def _waypoints(mission: Mission) -> dict:
    """Checked waypoint plan: positions (NED, m, from the site), leg speeds, stops, limits."""
    where, table, vehicle = mission.where, mission.table, mission.vehicle
    if "phase" in table or "rocket" in table:
        raise NavlibInputError(f"{where}: a {vehicle} mission has [[waypoint]] tables, not "
                               "[[phase]] or [rocket]")
    limits = _table(table, "limits", where, required=False)
    reject_unknown(limits, LIMIT_DEFAULTS[vehicle], f"{where} [limits]")
    lim = {k: _number(limits, k, f"{where} [limits]", 0.0, low_open=True, default=d)
           for k, d in LIMIT_DEFAULTS[vehicle].items()}
    if vehicle == "fixed-wing" and lim["bank_limit_deg"] >= 80.0:
        raise NavlibInputError(f"{where} [limits] bank_limit_deg: expected below 80 deg, got "
                               f"{lim['bank_limit_deg']}")
    wps = table.get("waypoint")
    if not isinstance(wps, list) or len(wps) < 2:
        raise NavlibInputError(f"{where}: a {vehicle} mission needs at least 2 [[waypoint]] "
                               "tables")
    site = _site(mission)
    stop_key = next(iter(WAYPOINT_KEYS[vehicle]), None)
    allowed = {"north_m", "east_m", "up_m", "lat_deg", "lon_deg", "alt_m", "speed_m_s",
               *WAYPOINT_KEYS[vehicle]}
    points, speeds, stops = [], [], []
    for i, wp in enumerate(wps):
        label = f"{where} waypoint {i}"
        if not isinstance(wp, Mapping):
            raise NavlibInputError(f"{label}: expected a table, got {wp!r}")
        reject_unknown(wp, allowed, label)
        points.append(_position_keys(wp, label, site))
        if i == 0 and "speed_m_s" in wp:
            raise NavlibInputError(f"{label}: speed_m_s is the speed of the leg arriving at a "
                                   "waypoint; the first waypoint has none")
        speeds.append(_number(wp, "speed_m_s", label, 0.0, low_open=True,
                              default=lim["speed_m_s"]))
        hold = None
        if stop_key is not None and stop_key in wp:
            hold = _number(wp, stop_key, label, 0.0)
        elif stop_key is not None and i in (0, len(wps) - 1):
            hold = 0.0                           # ground vehicles start and end at rest
        stops.append(hold)
        if i and np.linalg.norm(points[i] - points[i - 1]) < 1e-3:
            raise NavlibInputError(f"{label}: at the position of waypoint {i - 1}; legs need "
                                   "a length")
    points = np.array(points)
    if vehicle in ("ground", "fixed-wing"):
        for i in range(1, len(points)):
            d = points[i] - points[i - 1]
            if np.hypot(d[0], d[1]) < 0.5 * abs(d[2]):
                raise NavlibInputError(f"{where} waypoint {i}: the leg from waypoint {i - 1} "
                                       f"climbs or sinks steeper than 1:2 ({d[2]:+.1f} m down "
                                       f"over {np.hypot(d[0], d[1]):.1f} m); a {vehicle} "
                                       "cannot fly it")
    return {"points": points, "speeds": np.array(speeds[1:]), "stops": stops, "limits": lim,
            "site": site}


def _wrap(angle: float) -> float:
    return float((angle + np.pi) % (2.0 * np.pi) - np.pi)


def _events(plan: dict, vehicle: str, where: str) -> tuple[list, np.ndarray, float, dict]:
    """The velocity blends of a waypoint plan, the initial velocity, the end time and the
    waypoint passage times."""
    p, speeds, stops, lim = plan["points"], plan["speeds"], plan["stops"], plan["limits"]
    n = len(p)
    legs = np.diff(p, axis=0)
    lengths = np.linalg.norm(legs, axis=1)
    v = legs / lengths[:, None] * speeds[:, None]
    horizontal = np.hypot(legs[:, 0], legs[:, 1]) > 1e-6 * lengths
    heading = np.zeros(n - 1)
    last = next((np.arctan2(legs[k, 1], legs[k, 0]) for k in range(n - 1) if horizontal[k]),
                0.0)
    for k in range(n - 1):
        last = np.arctan2(legs[k, 1], legs[k, 0]) if horizontal[k] else last
        heading[k] = last
    pitch = np.arctan2(-legs[:, 2], np.hypot(legs[:, 0], legs[:, 1]))
    a_max = lim["max_acceleration_m_s2"]

    def turn_duration(va, vb, k):
        dv = np.linalg.norm(vb - va)
        a = a_max
        if vehicle != "multicopter":    # turns within the turn radius or bank limit,
            if vehicle == "ground":      # speed changes within max_acceleration; the
                # tightest radius is mid-blend, where the speed is |va + vb| / 2
                a = (0.5 * np.linalg.norm(va + vb)) ** 2 / lim["turn_radius_m"]
            else:
                a = G0 * np.tan(lim["bank_limit_deg"] * DEG)
            dv = max(dv, abs(np.linalg.norm(vb) - np.linalg.norm(va)) * a / a_max)
            ha, hb = va[:2], vb[:2]
            cos = ha @ hb / (np.linalg.norm(ha) * np.linalg.norm(hb))
            if cos < np.cos(150.0 * DEG):
                raise NavlibInputError(
                    f"{where} waypoint {k}: the course turns by "
                    f"{np.degrees(np.arccos(np.clip(cos, -1, 1))):.0f} deg; a fixed-wing "
                    "mission turns by less than 150 deg at a waypoint (add a waypoint)")
        return _PEAK_RATE * dv / a

    events: list[_Event] = []
    zero = np.zeros(3)
    if vehicle == "fixed-wing":       # starts in flight along the first leg
        v_init, center, window_out = v[0], 0.0, 0.0
    else:
        v_init = zero
        T = _PEAK_RATE * speeds[0] / a_max
        center = stops[0] + 0.5 * T
        events.append(_Event(center, T, v[0]))
        window_out = 0.5 * T
    times = {"waypoint 0": center}
    for k in range(1, n):
        t_arrive = center + lengths[k - 1] / speeds[k - 1]
        times[f"waypoint {k}"] = t_arrive
        if k == n - 1:
            if stops[k] is not None:
                T = _PEAK_RATE * speeds[k - 1] / a_max
                new = [_Event(t_arrive, T, -v[k - 1])]
                end = t_arrive + 0.5 * T + stops[k]
                window_in = 0.5 * T
            else:
                new, end, window_in = [], t_arrive, 0.0
        elif stops[k] is not None:
            T_stop = _PEAK_RATE * speeds[k - 1] / a_max
            T_go = _PEAK_RATE * speeds[k] / a_max
            center_next = t_arrive + 0.5 * T_stop + stops[k] + 0.5 * T_go
            new = [_Event(t_arrive, T_stop, -v[k - 1]),
                   _Event(center_next, T_go, v[k], _wrap(heading[k] - heading[k - 1]),
                          pitch[k] - pitch[k - 1])]
            window_in = 0.5 * T_stop
        else:
            T = turn_duration(v[k - 1], v[k], k)
            center_next = t_arrive
            new = [_Event(t_arrive, T, v[k] - v[k - 1], _wrap(heading[k] - heading[k - 1]),
                          pitch[k] - pitch[k - 1])] if T > 0 else []
            window_in = 0.5 * T
        if lengths[k - 1] / speeds[k - 1] < window_out + window_in - 1e-9:
            need = (window_out + window_in) * speeds[k - 1]
            raise NavlibInputError(
                f"{where} waypoint {k}: the leg from waypoint {k - 1} is {lengths[k - 1]:.1f} m "
                f"long, too short for the manoeuvres at its ends at {speeds[k - 1]:g} m/s "
                f"within the [limits] (needs {need:.1f} m); lower the speed, move the "
                "waypoint or raise the limits")
        events.extend(new)
        if k < n - 1:
            center = center_next if stops[k] is not None else t_arrive
            window_out = 0.5 * new[-1].duration if new else 0.0
    return events, np.asarray(v_init, float), float(end), {
        "times": times, "heading0": float(heading[0]), "pitch0": float(pitch[0])}


def _blend(events, t, which, width: int = 3):
    """Sum over events of ``amount * S``: ``which`` picks (amount, order) with order 0: the
    integral of the smoothstep (position), 1: the smoothstep, 2: its rate, 3: its second
    derivative (scaled by the window lengths)."""
    out = np.zeros((t.size, width))
    for ev in events:
        amount, order = which(ev)
        if np.all(amount == 0.0):
            continue
        x = (t - (ev.center - 0.5 * ev.duration)) / ev.duration
        if order == 0:
            shape = np.where(x >= 1.0, 0.5 + (x - 1.0), ramp_integral(x)) * ev.duration
        else:
            s, ds, d2s = smoothstep(x)
            shape = (s, ds / ev.duration, d2s / ev.duration**2)[order - 1]
        out = out + np.multiply.outer(shape, amount)
    return out


def waypoint_trajectory(mission) -> Trajectory:
    """Exact-IMU trajectory of a multicopter, fixed-wing or ground mission (assumptions
    M2-M4 of ``docs/assumptions.md``).

    The motion is written in the local NED frame of the site (a tangent plane: ``up_m`` is
    height above it) as the polyline through the waypoints with every change of velocity a
    C^3 smoothstep blend centred on the waypoint: flown-through waypoints are passed at the
    corner's inner side (the path cuts the corner symmetrically), stops end exactly on the
    waypoint. Blend lengths come from the ``[limits]``: ``35/16 |dv| / a`` with ``a`` the
    largest acceleration (and, in turns, ``v^2 / turn_radius`` or ``g tan(bank_limit)``).

    Attitude: a multicopter points its thrust axis (body -z) along the specific force of the
    designed motion with the heading of the current leg; a ground vehicle keeps the heading
    and slope of the leg with zero roll; a fixed-wing aircraft flies along its velocity
    (no sideslip, no angle of attack) banked for a coordinated turn,
    ``tan(phi) = v_h dpsi/dt / g``. Headings and slopes change with the same blends, so
    angular rates are continuous. IMU signals then follow exactly
    (:func:`navlib.trajectory.base.build_trajectory`).
    """
    mission = mission if isinstance(mission, Mission) else load_mission(mission)
    if mission.vehicle == "rocket":
        raise NavlibInputError(f"{mission.where}: a rocket mission is built from phases "
                               "(use from_mission)")
    plan = _waypoints(mission)
    events, v_init, end, info = _events(plan, mission.vehicle, mission.where)
    t = output_times(end, mission.rate_hz)
    if t.size < 2:
        raise NavlibInputError(f"{mission.where} rate_hz: gives fewer than 2 samples over "
                               f"the {end:.3g} s mission")
    r = plan["points"][0] + np.outer(t, v_init) + _blend(events, t, lambda e: (e.dv, 0))
    v = v_init + _blend(events, t, lambda e: (e.dv, 1))
    a = _blend(events, t, lambda e: (e.dv, 2))
    jerk = _blend(events, t, lambda e: (e.dv, 3))
    psi = info["heading0"] + _blend(events, t, lambda e: (np.array([e.dpsi]), 1), 1)[:, 0]
    dpsi = _blend(events, t, lambda e: (np.array([e.dpsi]), 2), 1)[:, 0]
    vehicle = mission.vehicle
    if vehicle == "multicopter":
        theta, phi, dtheta, dphi = _thrust_tilt(a, jerk, psi, dpsi)
    elif vehicle == "ground":
        theta = info["pitch0"] + _blend(events, t, lambda e: (np.array([e.dtheta]), 1), 1)[:, 0]
        dtheta = _blend(events, t, lambda e: (np.array([e.dtheta]), 2), 1)[:, 0]
        phi = dphi = np.zeros_like(t)
    else:
        psi, theta, phi, dpsi, dtheta, dphi = _coordinated(v, a, jerk)
    P0, C_n_e = plan["site"]
    C_b_e, w_eb_b = zyx_attitude(C_n_e, psi, theta, phi, dpsi, dtheta, dphi)
    events_out = {**info["times"], "end": float(t[-1])}
    parameters = {"mission": mission.name, "vehicle": vehicle, "limits": plan["limits"],
                  "outages": mission.outages}
    return build_trajectory(t, P0 + r @ C_n_e.T, v @ C_n_e.T, a @ C_n_e.T, C_b_e, w_eb_b,
                            events=events_out, name=mission.name, parameters=parameters)


def _thrust_tilt(a, jerk, psi, dpsi):
    """Pitch and roll (and rates) that put body -z along the designed specific force
    ``a - g`` (NED, constant design gravity ``G0``) under the heading ``psi``."""
    g = np.array([0.0, 0.0, G0])
    u, du = unit_and_rate(g - a, -jerk)          # body z axis (down when hovering)
    c, s = np.cos(psi), np.sin(psi)
    h = np.stack([c * u[:, 0] + s * u[:, 1], -s * u[:, 0] + c * u[:, 1], u[:, 2]], axis=1)
    dh = np.stack([c * du[:, 0] + s * du[:, 1] + dpsi * (-s * u[:, 0] + c * u[:, 1]),
                   -s * du[:, 0] + c * du[:, 1] + dpsi * (-c * u[:, 0] - s * u[:, 1]),
                   du[:, 2]], axis=1)
    hxz = h[:, 0] ** 2 + h[:, 2] ** 2
    theta = np.arctan2(h[:, 0], h[:, 2])
    phi = np.arctan2(-h[:, 1], np.sqrt(hxz))
    dtheta = (h[:, 2] * dh[:, 0] - h[:, 0] * dh[:, 2]) / hxz
    dphi = -dh[:, 1] / np.sqrt(hxz)
    return theta, phi, dtheta, dphi


def _coordinated(v, a, jerk):
    """Heading and pitch of the velocity and the bank of a coordinated turn, with rates."""
    vn, ve, vd = v[:, 0], v[:, 1], v[:, 2]
    an, ae, ad = a[:, 0], a[:, 1], a[:, 2]
    jn, je = jerk[:, 0], jerk[:, 1]
    vh2 = vn**2 + ve**2
    vh = np.sqrt(vh2)
    dvh = (vn * an + ve * ae) / vh
    psi = np.arctan2(ve, vn)
    dpsi = (vn * ae - ve * an) / vh2
    theta = np.arctan2(-vd, vh)
    dtheta = (vh * (-ad) + vd * dvh) / (vh2 + vd**2)
    w = (vn * ae - ve * an) / (vh * G0)
    dw = ((vn * je - ve * jn) * vh - (vn * ae - ve * an) * dvh) / (vh2 * G0)
    return psi, theta, np.arctan(w), dpsi, dtheta, dw / (1.0 + w**2)


# --------------------------------------------------------------------------- entry point


def from_mission(path_or_mapping) -> Trajectory:
    """The trajectory a mission file describes, with an exact IMU (spec api.md "Planning").

    Parameters
    ----------
    path_or_mapping : str, Path, mapping or Mission
        A TOML mission file, the name of an example mission (:func:`list_missions`), the
        same content as a mapping (module docstring) or a :func:`load_mission` result.

    Returns
    -------
    Trajectory
        Rockets: :func:`navlib.trajectory.sounding_rocket` with the phases' keywords (its
        events: ``ignition``, ``liftoff``, ``rail_exit``, ``burnout``, ..., with a drogue
        ``apogee``, ``drogue``, ``main``, ``landing``). Other vehicles:
        :func:`waypoint_trajectory` (events ``waypoint k`` at the nominal passage of each
        waypoint and ``end``). ``parameters["mission"]`` names the mission.

    Raises
    ------
    NavlibInputError
        Naming the file, the table, phase or waypoint and the key, and what was expected.
    """
    mission = path_or_mapping if isinstance(path_or_mapping, Mission) else \
        load_mission(path_or_mapping)
    if mission.vehicle == "rocket":
        traj = _rocket(mission)
        return Trajectory(t=traj.t, position=traj.position, velocity=traj.velocity,
                          attitude=traj.attitude, specific_force=traj.specific_force,
                          angular_rate=traj.angular_rate, events=dict(traj.events),
                          name=mission.name,
                          parameters={**traj.parameters, "mission": mission.name,
                                      "vehicle": "rocket", "outages": mission.outages})
    return waypoint_trajectory(mission)
