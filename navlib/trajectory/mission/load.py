"""A mission checked as a whole (:func:`load_mission`) and built (:func:`from_mission`).

The top-level, ``[site]`` and ``[gnss]`` keys are checked here; the rocket phases and the
waypoints by their builders (:mod:`~navlib.trajectory.mission.rockets`,
:mod:`~navlib.trajectory.mission.waypoints`), so that a mission that loads also builds.
"""

from __future__ import annotations

from navlib._validation import latitude_deg, reject_unknown
from navlib.errors import NavlibInputError
from navlib.trajectory.base import Trajectory
from navlib.trajectory.mission.reading import (
    Mission,
    checked_number,
    checked_outages,
    read_mission,
    sub_table,
)
from navlib.trajectory.mission.rockets import rocket_keywords, rocket_trajectory
from navlib.trajectory.mission.waypoints import waypoint_flight, waypoint_plan
from navlib.vehicles import VEHICLES

__all__ = ["from_mission", "load_mission", "waypoint_trajectory"]

_TOP_KEYS = {"name", "description", "vehicle", "rate_hz", "sensors", "site", "gnss",
             "rocket", "phase", "limits", "waypoint"}
_SITE_KEYS = {"lat_deg", "lon_deg", "alt_m"}
_GNSS_KEYS = {"rate_hz", "sigma_m", "outages", "aiding"}


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
    rate = checked_number(table, "rate_hz", where, 0.0, low_open=True,
                   default=100.0 if vehicle == "rocket" else 50.0)
    sensors = table.get("sensors")
    if sensors is not None and not isinstance(sensors, str):
        raise NavlibInputError(f"{where} sensors: expected a preset name or file, got "
                               f"{sensors!r}")
    site = sub_table(table, "site", where)
    reject_unknown(site, _SITE_KEYS, f"{where} [site]")
    latitude_deg(checked_number(site, "lat_deg", f"{where} [site]"), f"{where} [site] lat_deg")
    checked_number(site, "lon_deg", f"{where} [site]", -360.0, 360.0)
    checked_number(site, "alt_m", f"{where} [site]", -500.0, 10_000.0, default=0.0)
    gnss = sub_table(table, "gnss", where, required=False)
    reject_unknown(gnss, _GNSS_KEYS, f"{where} [gnss]")
    gnss_rate = (checked_number(gnss, "rate_hz", f"{where} [gnss]", 0.0, low_open=True)
                 if "rate_hz" in gnss else None)
    sigma = (checked_number(gnss, "sigma_m", f"{where} [gnss]", 0.0, low_open=True)
             if "sigma_m" in gnss else None)
    mission = Mission(name=str(table.get("name", where)), vehicle=vehicle, rate_hz=rate,
                      sensors=sensors, gnss_rate_hz=gnss_rate, gnss_sigma_m=sigma,
                      outages=checked_outages(gnss, where), table=table, where=where)
    if vehicle == "rocket":
        rocket_keywords(mission)
    else:
        waypoint_plan(mission)
    return mission


def from_mission(path_or_mapping) -> Trajectory:
    """The trajectory a mission file describes, with an exact IMU (docs/plan.md).

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
        traj = rocket_trajectory(mission)
        return Trajectory(t=traj.t, position=traj.position, velocity=traj.velocity,
                          attitude=traj.attitude, specific_force=traj.specific_force,
                          angular_rate=traj.angular_rate, events=dict(traj.events),
                          name=mission.name,
                          parameters={**traj.parameters, "mission": mission.name,
                                      "vehicle": "rocket", "outages": mission.outages})
    return waypoint_trajectory(mission)


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
    return waypoint_flight(mission)
