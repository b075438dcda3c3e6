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
``landing`` (see :data:`~navlib.trajectory.mission.rockets.ROCKET_PHASES`); they map
one-to-one onto the keywords of :func:`navlib.trajectory.sounding_rocket`, whose ODE and
splines build the flight (assumptions M1 and M7 of ``docs/assumptions.md``). Multicopters,
fixed-wing aircraft and ground vehicles give ``[limits]`` and ``[[waypoint]]`` tables
(position, leg speed, hover or hold times; see
:data:`~navlib.trajectory.mission.waypoints.WAYPOINT_KEYS`), built by
:func:`waypoint_trajectory` (assumptions M2-M4).

Every mission trajectory goes through :func:`navlib.trajectory.base.build_trajectory`, so
its specific force and angular rate satisfy the ECEF kinematics exactly (the closure of
``tests/trajectory/test_trajectory.py``) and are continuous: every change of velocity or
heading is a C^3 smoothstep blend whose length follows from the stated acceleration,
turn-radius or bank limits.

Modules: :mod:`~navlib.trajectory.mission.reading` (the file and its tables),
:mod:`~navlib.trajectory.mission.rockets`, :mod:`~navlib.trajectory.mission.waypoints`
(the two kinds of flight) and :mod:`~navlib.trajectory.mission.load` (the whole mission
checked and built); the public names are re-exported here.
"""

from navlib.trajectory.mission.load import from_mission, load_mission, waypoint_trajectory
from navlib.trajectory.mission.reading import (
    MISSION_DIR,
    Mission,
    list_missions,
    mission_path,
    read_mission,
    with_values,
)
from navlib.trajectory.mission.rockets import DESCENT_CAP_S, ROCKET_BODY, ROCKET_PHASES
from navlib.trajectory.mission.waypoints import LIMIT_DEFAULTS, WAYPOINT_KEYS

__all__ = ["DESCENT_CAP_S", "LIMIT_DEFAULTS", "MISSION_DIR", "ROCKET_BODY", "ROCKET_PHASES",
           "WAYPOINT_KEYS", "Mission", "from_mission", "list_missions", "load_mission",
           "mission_path", "read_mission", "waypoint_trajectory", "with_values"]
