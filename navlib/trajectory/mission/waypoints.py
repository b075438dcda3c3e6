"""Waypoint missions of multicopters, fixed-wing aircraft and ground vehicles.

``[limits]`` and ``[[waypoint]]`` tables (position, leg speed, hover or hold times; see
:data:`WAYPOINT_KEYS` and :data:`LIMIT_DEFAULTS`) become a trajectory through
:func:`waypoint_trajectory` (assumptions M2-M4 of ``docs/assumptions.md``): every change of
velocity or heading is a C^3 smoothstep blend whose length follows from the stated
acceleration, turn-radius or bank limits.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from navlib import earth
from navlib._validation import latitude_deg, reject_unknown
from navlib.errors import NavlibInputError
from navlib.trajectory._attitude import smoothstep, unit_and_rate, zyx_attitude
from navlib.trajectory._flight import output_times, ramp_integral
from navlib.trajectory.base import Trajectory, build_trajectory
from navlib.trajectory.mission.reading import Mission, checked_number, sub_table
from navlib.units import DEG, G0

__all__ = ["LIMIT_DEFAULTS", "WAYPOINT_KEYS", "waypoint_flight", "waypoint_plan"]

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
        lat = latitude_deg(checked_number(wp, "lat_deg", label), f"{label} lat_deg") * DEG
        lon = checked_number(wp, "lon_deg", label, -360.0, 360.0) * DEG
        alt = checked_number(wp, "alt_m", label, -500.0, 20_000.0)
        P = earth.geodetic_to_ecef(lat, lon, alt)
        P0, C_n_e = site
        return C_n_e.T @ (np.asarray(P) - P0)
    if not local:
        raise NavlibInputError(f"{label}: missing position (north_m, east_m, up_m or "
                               "lat_deg, lon_deg, alt_m)")
    return np.array([checked_number(wp, "north_m", label, default=0.0),
                     checked_number(wp, "east_m", label, default=0.0),
                     -checked_number(wp, "up_m", label, default=0.0)])


def _site(mission: Mission):
    site = mission.table["site"]
    lat, lon = float(site["lat_deg"]) * DEG, float(site["lon_deg"]) * DEG
    P0 = np.asarray(earth.geodetic_to_ecef(lat, lon, float(site.get("alt_m", 0.0))))
    return P0, np.asarray(earth.ned_to_ecef_matrix(lat, lon))


def waypoint_plan(mission: Mission) -> dict:
    """Checked waypoint plan: positions (NED, m, from the site), leg speeds, stops, limits."""
    where, table, vehicle = mission.where, mission.table, mission.vehicle
    if "phase" in table or "rocket" in table:
        raise NavlibInputError(f"{where}: a {vehicle} mission has [[waypoint]] tables, not "
                               "[[phase]] or [rocket]")
    limits = sub_table(table, "limits", where, required=False)
    reject_unknown(limits, LIMIT_DEFAULTS[vehicle], f"{where} [limits]")
    lim = {k: checked_number(limits, k, f"{where} [limits]", 0.0, low_open=True, default=d)
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
        speeds.append(checked_number(wp, "speed_m_s", label, 0.0, low_open=True,
                              default=lim["speed_m_s"]))
        hold = None
        if stop_key is not None and stop_key in wp:
            hold = checked_number(wp, stop_key, label, 0.0)
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


def waypoint_flight(mission: Mission) -> Trajectory:
    """The trajectory of a checked waypoint mission (motion and attitude as described by
    :func:`~navlib.trajectory.mission.waypoint_trajectory`)."""
    plan = waypoint_plan(mission)
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
