"""Satellite-launcher endo-atmospheric ascent from Churchill (docs/assumptions.md, launcher.md §4).

The paper's launcher simulator (DRDC) is not available; what the paper states is kept
and the rest is a documented surrogate:

* **paper**: launch from Churchill, Manitoba; target a 500 km circular sun-synchronous
  orbit; first engine for the first 109 s, the second for the remaining time; stage
  jettison causes brief rapid changes; fuel-optimal trajectory "mostly aimed in one
  direction" with near-zero lateral acceleration; everything at 200 Hz;
* **assumed** (keywords of :func:`launcher_ascent`): site coordinates, vehicle masses and
  thrusts, drag, the separation timing, the pitch programme and the lateral motion.

The pitch programme is the classic one for a gravity-turn ascent: vertical rise, a small
programmed pitch-over ("kick") towards the launch azimuth, then a smooth hand-over to
zero angle of attack (thrust along the velocity), after which gravity turns the
trajectory. The launch azimuth follows from the target inclination, ``sin(Az) = cos(i) / cos(lat)``
(non-rotating Earth), northerly branch.

The flight is integrated as a point-mass ODE in ECEF and represented by a quintic spline
(exact IMU by construction, as for :mod:`navlib.trajectory.rocket`). The attitude yaw
and pitch are taken in a fixed frame pitched 45 deg up along the launch azimuth, so a
vertical body axis (45 deg off that frame's x axis) is nowhere near the Euler
singularity; roll is held at ``roll_deg``.

**Lateral motion** (docs/assumptions.md, A-launcher-lateral). The paper's simulator
"considers, among other things, the launcher flexion, the wind, and the aerodynamic
coefficient", and its lateral acceleration is "almost null" but not zero: with exactly zero
lateral specific force a roll error reaches the velocity error only through the turning of
the body axes. Three declared sources, each a keyword:

* **wind gusts**: a train of discrete 1-cosine gusts of peak ``gust_mps`` (default 9 m/s,
  the discrete design gust of NASA's terrestrial-environment guidelines for launch
  vehicles, NASA/TM-2008-215633) and wavelength ``2 gust_gradient_m`` (gradient distance
  107 m, the longest of the 1-cosine gust of CS/FAR 25.341), met along the altitude, each
  from a direction turned by the golden angle from the previous one. A crosswind ``w``
  seen at airspeed ``V`` is an angle of attack ``w / V`` and a normal force
  ``q C_Nalpha S w / V`` (``normal_force_slope_m2`` = C_Nalpha S = 2 /rad x 2 m^2, the
  slender-body normal-force slope of a nose, Barrowman 1967, on a 1.6 m body): a lateral
  specific force ``0.5 rho V C_Nalpha S w / m`` perpendicular to the velocity;
* **attitude-control activity**: the control keeps the body axis on the programme and then
  on the velocity, so the body turns with every gust-driven turn of the velocity (body
  rates, and the gust's lateral force seen in body axes);
* **first bending mode**: the IMU oscillates laterally at ``bending_hz`` with an
  acceleration amplitude ``bending_mps2`` (default 0: no published level at hand; a
  keyword for experiments).
"""

from __future__ import annotations

import math

import numpy as np

from navlib import cache, earth
from navlib._validation import finite_scalar, latitude_deg, reject_unknown
from navlib.errors import NavlibInputError
from navlib.trajectory._attitude import launch_frame, smoothstep, unit_and_rate
from navlib.trajectory._flight import (
    RHO_SEA_LEVEL,
    RestStartSpline,
    assemble,
    integrate,
    output_times,
    step,
)
from navlib.trajectory.base import Trajectory
from navlib.units import DEG

__all__ = ["LATERAL_SOURCES", "LAUNCHER_DEFAULTS", "launch_azimuth", "launcher_ascent"]

LAUNCHER_DEFAULTS = {
    "lat_deg": 58.73,              # Churchill Rocket Research Range (assumed coordinates)
    "lon_deg": -93.82,
    "alt_m": 10.0,
    "inclination_deg": 97.4,       # sun-synchronous at 500 km
    "azimuth_deg": None,           # None: from the inclination (northerly branch)
    "duration_s": 150.0,
    "rate_hz": 200.0,
    "stage1_burnout_s": 109.0,     # paper
    "stage1_tailoff_s": 1.0,
    "separation_s": 110.0,         # stage-1 dry mass leaves (smooth over separation_duration_s)
    "separation_duration_s": 0.2,
    "stage2_ignition_s": 111.0,
    "stage2_ramp_s": 0.5,
    "mass_liftoff_kg": 30000.0,
    "stage1_propellant_kg": 20000.0,
    "stage1_dry_kg": 2500.0,
    "stage1_thrust_n": 420e3,
    "stage2_propellant_kg": 5000.0,
    "stage2_thrust_n": 110e3,
    "stage2_exhaust_velocity_mps": 2900.0,
    "drag_area_m2": 1.5,           # C_D * reference area
    "scale_height_m": 7200.0,
    "density_sea_level": RHO_SEA_LEVEL,
    "pitchover_s": 6.0,            # end of the vertical rise
    "kick_deg": 2.5,               # programmed pitch-over angle
    "kick_duration_s": 8.0,
    "turn_blend_s": 10.0,          # hand-over from the programme to zero angle of attack
    "roll_deg": 0.0,
    "gust_mps": 9.0,               # NASA/TM-2008-215633 discrete design gust (A-launcher-lateral)
    "gust_gradient_m": 107.0,      # CS/FAR 25.341 1-cosine gust, longest gradient distance
    "normal_force_slope_m2": 4.0,  # C_Nalpha S: 2 /rad (slender body, Barrowman) x 2 m^2
    "bending_mps2": 0.0,           # first bending mode, lateral IMU acceleration amplitude
    "bending_hz": 6.0,
    "grid_step_s": 0.05,
}

LATERAL_SOURCES = {
    "gust_mps": "NASA/TM-2008-215633 (Johnson 2008): 9 m/s discrete design gust",
    "gust_gradient_m": "CS/FAR 25.341(a): 1-cosine gust, gradient distance 9-107 m",
    "normal_force_slope_m2": "Barrowman (1967): nose normal-force slope 2 /rad, on 2 m^2",
}
"""The published source of each default of the lateral motion (docs/assumptions.md,
A-launcher-lateral; a test pins the defaults to these values)."""

_GOLDEN_ANGLE = math.pi * (3.0 - math.sqrt(5.0))

_MARGIN_S = 2.0
_FRAME_ELEVATION = 45.0 * DEG


def launch_azimuth(lat, inclination):
    """Northerly launch azimuth (rad) reaching ``inclination`` from latitude ``lat`` (rad).

    Parameters
    ----------
    lat, inclination : float
        Launch latitude and orbit inclination, rad.

    Raises
    ------
    NavlibInputError
        If the inclination cannot be reached by a direct ascent.
    """
    ratio = math.cos(inclination) / math.cos(lat)
    if abs(ratio) > 1.0:
        raise NavlibInputError(
            f"inclination_deg: {math.degrees(inclination):.2f} deg cannot be reached from "
            f"latitude {math.degrees(lat):.2f} deg by a direct ascent")
    return math.asin(ratio)


def _check(p):
    out = {}
    for key, value in p.items():
        out[key] = None if (key == "azimuth_deg" and value is None) else finite_scalar(value, key)
    latitude_deg(out["lat_deg"], "lat_deg")
    finite_scalar(out["lon_deg"], "lon_deg", -360.0, 360.0)
    finite_scalar(out["alt_m"], "alt_m", -500.0, 10_000.0)
    finite_scalar(out["inclination_deg"], "inclination_deg", 0.0, 180.0)
    finite_scalar(out["kick_deg"], "kick_deg", 0.0, 30.0, low_open=True)
    for key in ("gust_mps", "normal_force_slope_m2", "bending_mps2"):
        finite_scalar(out[key], key, 0.0)
    for key in ("gust_gradient_m", "bending_hz"):
        finite_scalar(out[key], key, 0.0, low_open=True)
    for key in ("duration_s", "rate_hz", "stage1_burnout_s", "stage1_tailoff_s",
                "separation_duration_s", "stage2_ramp_s", "mass_liftoff_kg",
                "stage1_propellant_kg", "stage1_dry_kg", "stage1_thrust_n",
                "stage2_propellant_kg", "stage2_thrust_n", "stage2_exhaust_velocity_mps",
                "scale_height_m", "kick_duration_s", "turn_blend_s", "grid_step_s"):
        finite_scalar(out[key], key, 0.0, low_open=True)
    for key in ("drag_area_m2", "density_sea_level", "pitchover_s"):
        finite_scalar(out[key], key, 0.0)
    upper = out["mass_liftoff_kg"] - out["stage1_propellant_kg"] - out["stage1_dry_kg"]
    if upper <= out["stage2_propellant_kg"]:
        raise NavlibInputError(
            "stage2_propellant_kg: the upper stage (mass_liftoff_kg - stage1_propellant_kg - "
            f"stage1_dry_kg = {upper} kg) must weigh more than its propellant "
            f"({out['stage2_propellant_kg']} kg)")
    if out["stage1_burnout_s"] <= out["stage1_tailoff_s"]:
        raise NavlibInputError(
            f"stage1_burnout_s: must exceed stage1_tailoff_s ({out['stage1_tailoff_s']}), "
            f"got {out['stage1_burnout_s']}")
    if out["separation_s"] < out["stage1_burnout_s"]:
        raise NavlibInputError(
            f"separation_s: must not precede stage1_burnout_s ({out['stage1_burnout_s']}), "
            f"got {out['separation_s']}")
    if out["stage2_ignition_s"] < out["separation_s"] + out["separation_duration_s"]:
        raise NavlibInputError(
            "stage2_ignition_s: must follow the separation (separation_s + "
            f"separation_duration_s = {out['separation_s'] + out['separation_duration_s']}), "
            f"got {out['stage2_ignition_s']}")
    if out["pitchover_s"] + out["kick_duration_s"] + out["turn_blend_s"] >= out[
            "stage1_burnout_s"]:
        raise NavlibInputError(
            "pitchover_s: the pitch programme (pitchover_s + kick_duration_s + turn_blend_s) "
            f"must end before stage1_burnout_s ({out['stage1_burnout_s']})")
    stage2_burn = out["stage2_propellant_kg"] * out["stage2_exhaust_velocity_mps"] / out[
        "stage2_thrust_n"]
    stage2_end = out["stage2_ignition_s"] + 0.5 * out["stage2_ramp_s"] + stage2_burn
    if out["duration_s"] > stage2_end:
        raise NavlibInputError(
            f"duration_s: the second stage runs out of propellant at {stage2_end:.1f} s; "
            f"got duration_s={out['duration_s']}")
    if out["duration_s"] * out["rate_hz"] < 2.0:
        raise NavlibInputError(
            f"rate_hz: gives fewer than 2 samples over duration_s={out['duration_s']}")
    return out


def _gust_field(peak, gradient, downrange, crossrange):
    """Horizontal wind (ECEF, m/s) of the gust train as a function of altitude ``h`` (m):
    consecutive 1-cosine gusts ``peak (1 - cos(2 pi h / L)) / 2`` of wavelength
    ``L = 2 gradient``, gust ``k`` blowing from ``k`` golden angles off downrange (every
    direction visited, none repeated). None when ``peak`` is 0. Each gust starts and ends
    with zero speed and slope, so the field is continuous with a continuous derivative."""
    if peak == 0.0:
        return None
    wavelength = 2.0 * gradient

    def wind(h):
        x = max(h, 0.0) / wavelength
        k = math.floor(x)
        speed = 0.5 * peak * (1.0 - math.cos(2.0 * math.pi * (x - k)))
        angle = k * _GOLDEN_ANGLE
        return speed * (math.cos(angle) * downrange + math.sin(angle) * crossrange)

    return wind


class _Bending:
    """A displacement plus the first bending mode at the IMU: a lateral oscillation along
    ``direction`` of acceleration amplitude ``amplitude`` (m/s^2) at ``hz``, faded in over the
    first second (C^3 smoothstep) so the vehicle still starts from rest."""

    _FADE_S = 1.0

    def __init__(self, rigid, amplitude, hz, direction):
        self.rigid, self.direction = rigid, np.asarray(direction, dtype=float)
        self.omega = 2.0 * math.pi * hz
        self.scale = amplitude / self.omega**2

    def __call__(self, t, nu=0):
        t = np.asarray(t, dtype=float)
        e, de, d2e = smoothstep(t / self._FADE_S)
        de, d2e = de / self._FADE_S, d2e / self._FADE_S**2
        w = self.omega
        s, ds, d2s = np.sin(w * t), w * np.cos(w * t), -w * w * np.sin(w * t)
        value = [e * s, de * s + e * ds, d2e * s + 2.0 * de * ds + e * d2s][nu]
        return self.rigid(t, nu) + (self.scale * value)[:, None] * self.direction


@cache.cached
def launcher_ascent(**overrides) -> Trajectory:
    """Churchill launcher, endo-atmospheric ascent, exact 200 Hz IMU (docs/assumptions.md,
    launcher.md §4).

    Parameters
    ----------
    **overrides
        Assumed values (defaults in ``LAUNCHER_DEFAULTS``):

        * site: ``lat_deg=58.73``, ``lon_deg=-93.82``, ``alt_m=10`` (Churchill);
        * direction: ``inclination_deg=97.4`` (500 km sun-synchronous),
          ``azimuth_deg=None`` (derived, about -14.4 deg = NNW; give a number to override);
        * timing, s: ``duration_s=150``, ``rate_hz=200`` (paper), ``stage1_burnout_s=109``
          (paper, thrust ends), ``stage1_tailoff_s=1``, ``separation_s=110``,
          ``separation_duration_s=0.2``, ``stage2_ignition_s=111``, ``stage2_ramp_s=0.5``;
        * vehicle: ``mass_liftoff_kg=30000``, ``stage1_propellant_kg=20000``,
          ``stage1_dry_kg=2500``, ``stage1_thrust_n=420e3`` (lift-off thrust/weight 1.43;
          propellant flow proportional to thrust), ``stage2_propellant_kg=5000``,
          ``stage2_thrust_n=110e3``, ``stage2_exhaust_velocity_mps=2900``,
          ``drag_area_m2=1.5``, ``scale_height_m=7200``, ``density_sea_level=1.225``;
        * pitch programme: ``pitchover_s=6``, ``kick_deg=2.5``, ``kick_duration_s=8``,
          ``turn_blend_s=10``; ``roll_deg=0``;
        * lateral motion (module docstring, :data:`LATERAL_SOURCES`): ``gust_mps=9``
          (0 = no wind: zero lateral specific force after the pitch programme),
          ``gust_gradient_m=107``, ``normal_force_slope_m2=4``, ``bending_mps2=0``,
          ``bending_hz=6``;
        * numerics: ``grid_step_s=0.05``.

    Returns
    -------
    Trajectory
        Starts at lift-off (hold-down release at full thrust, ``V = 0``, ``f^b = T/m``
        along the body axis). ``events``: ``liftoff``, ``pitchover``, ``gravity_turn``,
        ``stage1_burnout``, ``separation``, ``stage2_ignition``, ``end``.

    Raises
    ------
    NavlibInputError
        Unknown keyword, non-finite or out-of-range value, impossible timing or masses.
    """
    reject_unknown(overrides, LAUNCHER_DEFAULTS, "launcher_ascent")
    p = _check({**LAUNCHER_DEFAULTS, **overrides})

    lat, lon = p["lat_deg"] * DEG, p["lon_deg"] * DEG
    if p["azimuth_deg"] is None:
        azimuth = launch_azimuth(lat, p["inclination_deg"] * DEG)
    else:
        azimuth = p["azimuth_deg"] * DEG
    P0 = earth.geodetic_to_ecef(lat, lon, p["alt_m"])
    C_n_e = earth.ned_to_ecef_matrix(lat, lon)
    up = -C_n_e[:, 2]
    downrange = C_n_e @ np.array([math.cos(azimuth), math.sin(azimuth), 0.0])
    C_L_e = launch_frame(lat, lon, azimuth, _FRAME_ELEVATION)
    r_surface = np.linalg.norm(P0) - p["alt_m"]
    w_e = earth.OMEGA_E

    # --- propulsion: thrust profiles and mass flow --------------------------------------
    t_bo1, tau1 = p["stage1_burnout_s"], p["stage1_tailoff_s"]
    t_ig2, tau2 = p["stage2_ignition_s"], p["stage2_ramp_s"]
    T1, T2 = p["stage1_thrust_n"], p["stage2_thrust_n"]
    ve1 = T1 * (t_bo1 - 0.5 * tau1) / p["stage1_propellant_kg"]
    ve2 = p["stage2_exhaust_velocity_mps"]
    t_sep, tau_sep, m_dry1 = p["separation_s"], p["separation_duration_s"], p["stage1_dry_kg"]

    def thrusts(t):
        return (T1 * (1.0 - step(t, t_bo1 - tau1, tau1)), T2 * step(t, t_ig2, tau2))

    # --- pitch programme: vertical, kick towards the azimuth, hand-over to V ------------
    t_po, tau_kick, kick = p["pitchover_s"], p["kick_duration_s"], p["kick_deg"] * DEG
    t_blend, tau_blend = t_po + tau_kick, p["turn_blend_s"]

    def programme(t):
        """Programmed direction k(t) (ECEF unit) and its derivative, vectorised."""
        s, ds, _ = smoothstep((t - t_po) / tau_kick)
        delta, ddelta = kick * s, kick * ds / tau_kick
        k = np.cos(delta)[:, None] * up + np.sin(delta)[:, None] * downrange
        dk = ddelta[:, None] * (-np.sin(delta)[:, None] * up + np.cos(delta)[:, None] * downrange)
        return k, dk

    up_x, up_y, up_z = (float(c) for c in up)
    dn_x, dn_y, dn_z = (float(c) for c in downrange)

    def thrust_direction(t, V, speed):
        """Unit thrust direction (x, y, z) at ``t`` for the velocity ``V`` of norm ``speed``
        (scalar arithmetic: the operations of the 3-vector expressions, entry by entry)."""
        b = step(t, t_blend, tau_blend)
        x = (t - t_po) / tau_kick
        delta = kick * (1.0 if x >= 1.0 else step(t, t_po, tau_kick))
        c, s = math.cos(delta), math.sin(delta)
        k = (c * up_x + s * dn_x, c * up_y + s * dn_y, c * up_z + s * dn_z)
        if b == 0.0:
            return k
        u = np.array([(1.0 - b) * k[i] + b * V[i] / speed for i in range(3)])
        norm = math.sqrt(u @ u)
        return u[0] / norm, u[1] / norm, u[2] / norm

    cd_a, scale_h, rho0 = p["drag_area_m2"], p["scale_height_m"], p["density_sea_level"]
    crossrange = np.cross(up, downrange)
    gust = _gust_field(p["gust_mps"], p["gust_gradient_m"], downrange, crossrange)
    cn_a = p["normal_force_slope_m2"]

    def forces(t, P, V, m):
        """``(a_x, a_y, a_z, mdot)``: acceleration (ECEF, m/s^2) and mass flow (kg/s)."""
        thrust1, thrust2 = thrusts(t)
        speed = math.sqrt(V @ V)
        h = math.sqrt(P @ P) - r_surface
        half_rho = 0.5 * rho0 * math.exp(-max(h, 0.0) / scale_h)
        thrust, drag = thrust1 + thrust2, half_rho * speed * cd_a
        direction = thrust_direction(t, V, speed)
        acc = [(thrust * direction[i] - drag * V[i]) / m for i in range(3)]
        if speed > 0.0 and gust is not None:
            w = gust(h)
            along = (V @ w) / (speed * speed)
            lift = half_rho * speed * cn_a / m                    # q C_Na S (w / V) / m
            acc = [acc[i] + lift * (w[i] - V[i] * along) for i in range(3)]
        g = earth.normal_gravity_point(P[0], P[1], P[2])
        acc = [acc[i] + g[i] for i in range(3)]
        acc[0] += 2.0 * w_e * V[1]     # - 2 Omega x V, Omega = [0, 0, w_e]
        acc[1] -= 2.0 * w_e * V[0]
        mdot = -thrust1 / ve1 - thrust2 / ve2
        x = (t - t_sep) / tau_sep
        if 0.0 < x < 1.0:
            mdot -= m_dry1 * 140.0 * x**3 * (1.0 - x) ** 3 / tau_sep
        return acc[0], acc[1], acc[2], mdot

    def accel(t, P, V, m):
        *acc, mdot = forces(t, P, V, m)
        return np.array(acc), mdot

    def rhs(t, y):
        return np.array([y[3], y[4], y[5], *forces(t, y[:3], y[3:6], y[6])])

    t_end = p["duration_s"] + _MARGIN_S
    grid = np.linspace(0.0, t_end, int(np.ceil(t_end / p["grid_step_s"])) + 1)
    y0 = np.concatenate([P0, np.zeros(3), [p["mass_liftoff_kg"]]])
    breaks = [t_po, t_blend, t_blend + tau_blend, t_bo1 - tau1, t_bo1, t_sep, t_sep + tau_sep,
              t_ig2, t_ig2 + tau2]
    y_grid = integrate(rhs, grid, y0, breaks)
    P_grid, V_grid = y_grid[:, :3], y_grid[:, 3:6]
    acc0 = accel(0.0, P0, np.zeros(3), p["mass_liftoff_kg"])[0]
    if acc0 @ up <= 0.0:
        raise NavlibInputError(
            f"stage1_thrust_n: {T1} N does not lift {p['mass_liftoff_kg']} kg off the pad")
    acc_end = accel(grid[-1], P_grid[-1], V_grid[-1], y_grid[-1, 6])[0]
    displacement = RestStartSpline(grid, P_grid - P0, V_grid[-1], acc_end, d2y_start=acc0)
    if p["bending_mps2"] > 0.0:
        displacement = _Bending(displacement, p["bending_mps2"], p["bending_hz"], crossrange)

    def pointing(t, V, a):
        k, dk = programme(t)
        b, db, _ = smoothstep((t - t_blend) / tau_blend)
        db = db / tau_blend
        speed = np.linalg.norm(V, axis=1)
        moving = speed > 0.0
        safe = np.where(moving, speed, 1.0)[:, None]
        v_hat = np.where(moving[:, None], V / safe, k)
        dv_hat = np.where(moving[:, None],
                          (a - v_hat * np.einsum("ni,ni->n", v_hat, a)[:, None]) / safe, 0.0)
        w = (1.0 - b)[:, None] * k + b[:, None] * v_hat
        dw = db[:, None] * (v_hat - k) + (1.0 - b)[:, None] * dk + b[:, None] * dv_hat
        return unit_and_rate(w, dw)

    roll0 = p["roll_deg"] * DEG

    def roll(t, nu):
        return np.full(t.shape, roll0 if nu == 0 else 0.0)

    t_out = output_times(p["duration_s"], p["rate_hz"])
    events = {
        "liftoff": 0.0, "pitchover": t_po, "gravity_turn": t_blend + tau_blend,
        "stage1_burnout": t_bo1, "separation": t_sep, "stage2_ignition": t_ig2,
        "end": float(t_out[-1]),
    }
    events = {k: v for k, v in events.items() if v <= t_out[-1]}
    parameters = {**p, "azimuth_deg": math.degrees(azimuth), "stage1_exhaust_velocity_mps": ve1}
    return assemble(t_out, P0, displacement, pointing, C_L_e, roll, events=events,
                    name="launcher ascent (Churchill)", parameters=parameters)
