"""VS30-like sounding-rocket flight with an exact IMU (docs/assumptions.md, excitability.md §3-4).

The paper (España, Carrizo & Giribet 2019) gives only the event times and a few
magnitudes: pad until 18 s, boost 18-46 s with aerodynamic spin and a peak axial specific
force of about 110 m/s^2, a sign change of the axial specific force at 46 s, near free
flight (|f| < 0.5 m/s^2) above 40 km from 60 s, a de-spin at 73 s halving the axial rate,
end at 86 s, IMU at 100 Hz. Everything else is an assumption, exposed as a keyword of
:func:`sounding_rocket` with a documented default (docs/assumptions.md, excitability.md §4, "[Proto]
realisation").

Construction
------------
1. A point-mass ODE in ECEF (thrust along the body axis, drag of an exponential
   atmosphere along -V, normal gravity, Coriolis) is integrated finely with
   ``scipy.integrate.solve_ivp`` from the instant the thrust overcomes the weight
   component along the rail. On the rail the lateral motion is cancelled by the rail
   reaction, which fades smoothly over the last ``rail_fade_m`` metres (tip-off), and the
   thrust points along the rail; off the rail it points along the velocity (zero angle of
   attack, a gravity turn).
2. The ECEF displacement is represented by a quintic spline through the ODE samples
   (exactly zero before motion starts), so velocity and acceleration are its analytic
   derivatives.
3. The body x axis is the rail direction blended into the spline velocity direction by the
   same tip-off weight; yaw and pitch are taken in a fixed frame aligned with the rail (far
   from the Euler singularity) and the roll angle is the integral of a quintic spline of
   the spin rate, ``p = 2 pi spin_hz tanh((|V| / spin_speed_mps)^2)`` times a smooth
   de-spin step. The body rate follows from the Euler kinematics.
4. :func:`navlib.trajectory.base.build_trajectory` turns these into ``f^b`` and
   ``omega_ib^b`` exactly.
5. With ``drogue_rate_mps > 0`` the same ODE flies on through apogee and the descent under
   drogue and main to touchdown (:mod:`navlib.trajectory.recovery`, assumption M7).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

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
    ramp_integral,
    roll_spline,
    step,
)
from navlib.trajectory.base import Trajectory
from navlib.trajectory.recovery import (
    RECOVERY_DEFAULTS,
    Canopy,
    check_recovery,
    deployments,
    recovering,
    recovery_frame,
)
from navlib.units import DEG

__all__ = ["ROCKET_DEFAULTS", "sounding_rocket"]

ROCKET_DEFAULTS = {
    "lat_deg": -5.92,            # Barreira do Inferno launch centre (assumed site)
    "lon_deg": -35.16,
    "alt_m": 30.0,
    "rail_elevation_deg": 84.0,
    "rail_azimuth_deg": 100.0,
    "rail_length_m": 10.0,
    "rail_fade_m": 2.0,          # tip-off: rail reaction fades over the last metres
    "ignition_s": 18.0,
    "ignition_ramp_s": 0.3,
    "burnout_s": 46.0,           # end of thrust
    "tailoff_s": 1.0,
    "free_flight_s": 60.0,       # event marker (|f| < 0.5 m/s^2 expected from here)
    "despin_s": 73.0,            # centre of the de-spin step
    "despin_duration_s": 0.5,
    "despin_factor": 0.5,        # axial rate multiplied by this across the de-spin
    "end_s": 86.0,
    "rate_hz": 100.0,
    "mass_initial_kg": 1500.0,
    "mass_burnout_kg": 650.0,
    "thrust_n": 1.14 * 110.0 * 650.0,
    "drag_area_m2": 0.07,        # C_D * reference area
    "scale_height_m": 7200.0,
    "density_sea_level": RHO_SEA_LEVEL,
    "spin_hz": 2.0,              # aerodynamic spin reached at high speed
    "spin_speed_mps": 400.0,     # speed scale of the spin-up
    "roll0_deg": 0.0,
    "grid_step_s": 0.02,         # spline node spacing of the ODE samples
    **RECOVERY_DEFAULTS,         # no descent under canopy unless drogue_rate_mps > 0
}

_MARGIN_S = 2.0  # the splines extend past the end so their end conditions stay out of view


def _check(p):
    """Validate and normalise the rocket keywords (NavlibInputError names the argument)."""
    out = {k: finite_scalar(v, k) for k, v in p.items()}
    out["lat_deg"] = latitude_deg(p["lat_deg"], "lat_deg")
    finite_scalar(p["lon_deg"], "lon_deg", -360.0, 360.0)
    finite_scalar(p["alt_m"], "alt_m", -500.0, 10_000.0)
    finite_scalar(p["rail_elevation_deg"], "rail_elevation_deg", 0.0, 90.0, low_open=True)
    for key in ("rail_length_m", "rail_fade_m", "ignition_ramp_s", "tailoff_s",
                "despin_duration_s", "rate_hz", "mass_initial_kg", "mass_burnout_kg",
                "thrust_n", "scale_height_m", "spin_speed_mps", "grid_step_s"):
        finite_scalar(p[key], key, 0.0, low_open=True)
    for key in ("drag_area_m2", "density_sea_level", "spin_hz", "ignition_s"):
        finite_scalar(p[key], key, 0.0)
    finite_scalar(p["despin_factor"], "despin_factor", 0.0, 1.0)
    if out["rail_fade_m"] > out["rail_length_m"]:
        raise NavlibInputError(
            f"rail_fade_m: must not exceed rail_length_m ({out['rail_length_m']}), "
            f"got {out['rail_fade_m']}")
    if out["mass_burnout_kg"] >= out["mass_initial_kg"]:
        raise NavlibInputError(
            f"mass_burnout_kg: must be below mass_initial_kg ({out['mass_initial_kg']}), "
            f"got {out['mass_burnout_kg']}")
    if out["ignition_s"] + out["ignition_ramp_s"] > out["burnout_s"] - out["tailoff_s"]:
        raise NavlibInputError(
            "burnout_s: the burn must end after ignition_s + ignition_ramp_s + tailoff_s "
            f"({out['ignition_s'] + out['ignition_ramp_s'] + out['tailoff_s']} s), "
            f"got burnout_s={out['burnout_s']}")
    if not out["burnout_s"] <= out["free_flight_s"] <= out["end_s"]:
        raise NavlibInputError(
            f"free_flight_s: must lie between burnout_s ({out['burnout_s']}) and end_s "
            f"({out['end_s']}), got {out['free_flight_s']}")
    half = 0.5 * out["despin_duration_s"]
    if not out["burnout_s"] <= out["despin_s"] - half or out["despin_s"] + half > out["end_s"]:
        raise NavlibInputError(
            f"despin_s: the de-spin step [{out['despin_s'] - half}, {out['despin_s'] + half}] s "
            f"must lie between burnout_s ({out['burnout_s']}) and end_s ({out['end_s']})")
    check_recovery(out)
    if out["end_s"] * out["rate_hz"] < 2.0:
        raise NavlibInputError(f"rate_hz: gives fewer than 2 samples over end_s={out['end_s']}")
    return out


SPIN_KEYS = frozenset({"spin_hz", "spin_speed_mps", "roll0_deg", "despin_s",
                       "despin_duration_s", "despin_factor", "free_flight_s", "rate_hz"})
"""Keywords of :func:`sounding_rocket` that leave the flight path as it is: the roll about
the body x axis (the thrust and the drag act along it, so the spin does not steer), event
markers and the output rate. A panel moving them reuses the integrated path
(:func:`_flight_path`)."""


@dataclass(frozen=True, eq=False)
class _FlightPath:
    """The integrated translational motion of :func:`sounding_rocket` (no roll)."""

    P0: np.ndarray
    C_L_e: np.ndarray
    r_hat: np.ndarray
    canopy: Canopy
    grid: np.ndarray
    P_grid: np.ndarray
    V_grid: np.ndarray
    displacement: RestStartSpline
    t_lift: float
    m_lift: float
    v_exhaust: float
    t_final: float
    recovery_events: dict


@cache.memoized(maxsize=4)
def _flight_path(key: tuple) -> _FlightPath:
    """The path of the checked keywords ``key`` (sorted ``(name, value)`` pairs without
    :data:`SPIN_KEYS`): the rail, thrust, drag and gravity ODE integrated on the spline grid
    (and the recovery under canopy), kept in the process so that a new spin, de-spin or
    rate does not integrate it again."""
    p = dict(key)

    lat, lon = p["lat_deg"] * DEG, p["lon_deg"] * DEG
    P0 = earth.geodetic_to_ecef(lat, lon, p["alt_m"])
    C_L_e = launch_frame(lat, lon, p["rail_azimuth_deg"] * DEG, p["rail_elevation_deg"] * DEG)
    r_hat = C_L_e[:, 0]                       # rail direction, ECEF
    r_surface = np.linalg.norm(P0) - p["alt_m"]
    gamma0 = earth.normal_gravity_ecef(P0)

    t_ign, t_bo = p["ignition_s"], p["burnout_s"]
    tau_ign, tau_tail = p["ignition_ramp_s"], p["tailoff_s"]
    thrust_n, m0, m_bo = p["thrust_n"], p["mass_initial_kg"], p["mass_burnout_kg"]
    # total impulse = thrust x effective burn time (each ramp loses half its duration)
    burn_eff = (t_bo - t_ign) - 0.5 * (tau_ign + tau_tail)
    v_exhaust = thrust_n * burn_eff / (m0 - m_bo)

    def thrust(t):
        return thrust_n * step(t, t_ign, tau_ign) * (1.0 - step(t, t_bo - tau_tail, tau_tail))

    # lift-off: thrust beats the weight component along the rail (mass still ~ m0)
    def net_along_rail(t):
        return thrust(t) / m0 + gamma0 @ r_hat

    if net_along_rail(t_ign + tau_ign) <= 0.0:
        raise NavlibInputError(
            f"thrust_n: {thrust_n} N cannot lift {m0} kg along a rail at "
            f"{p['rail_elevation_deg']} deg (needs > {-m0 * (gamma0 @ r_hat):.0f} N)")
    t_lift = brentq(net_along_rail, t_ign, t_ign + tau_ign, xtol=1e-12)
    m_lift = m0 - (thrust_n / v_exhaust) * tau_ign * ramp_integral((t_lift - t_ign) / tau_ign)

    fade_start = p["rail_length_m"] - p["rail_fade_m"]
    fade_len = p["rail_fade_m"]
    cd_a, scale_h, rho0 = p["drag_area_m2"], p["scale_height_m"], p["density_sea_level"]

    w_e = earth.OMEGA_E
    canopy = Canopy(p, P0)

    def rhs(t, y):
        # scalar arithmetic where possible: this runs a few thousand times per flight
        P, V, m = y[:3], y[3:6], y[6]
        speed = math.sqrt(V[0] ** 2 + V[1] ** 2 + V[2] ** 2)
        rail = 1.0 - step((P - P0) @ r_hat, fade_start, fade_len)
        v_hat = V / speed if speed > 0.0 else r_hat
        u = rail * r_hat + (1.0 - rail) * v_hat
        u = u / math.sqrt(u @ u)
        T = thrust(t)
        h = math.sqrt(P @ P) - r_surface
        drag = 0.5 * rho0 * math.exp(-max(h, 0.0) / scale_h) * speed**2 * cd_a
        acc = (T * u - drag * v_hat) / m + earth.normal_gravity_ecef(P)
        acc[0] += 2.0 * w_e * V[1]     # - 2 Omega x V with Omega = [0, 0, w_e]
        acc[1] -= 2.0 * w_e * V[0]
        acc = canopy.blend(t, V, acc)
        acc = acc - rail * (acc - r_hat * (acc @ r_hat))   # rail reaction removes lateral part
        return np.array([V[0], V[1], V[2], acc[0], acc[1], acc[2], -T / v_exhaust])

    y0 = np.concatenate([P0, np.zeros(3), [m_lift]])
    cuts = [t_ign + tau_ign, t_bo - tau_tail, t_bo]
    t_final, recovery_events = p["end_s"], {}
    if recovering(p):
        recovery_events, t_final = deployments(rhs, canopy, t_lift, y0, p["end_s"], cuts)
    t_end = t_final + _MARGIN_S
    n_grid = int(np.ceil((t_end - t_lift) / p["grid_step_s"])) + 1
    grid = np.linspace(t_lift, t_end, n_grid)
    y_grid = integrate(rhs, grid, y0, cuts + canopy.breakpoints())
    P_grid, V_grid = y_grid[:, :3], y_grid[:, 3:6]
    acc_end = rhs(grid[-1], y_grid[-1])[3:6]
    displacement = RestStartSpline(grid, P_grid - P0, V_grid[-1], acc_end)
    return _FlightPath(P0, C_L_e, r_hat, canopy, grid, P_grid, V_grid, displacement,
                       float(t_lift), float(m_lift), float(v_exhaust), t_final,
                       recovery_events)


@cache.cached
def sounding_rocket(**overrides) -> Trajectory:
    """VS30-like sounding-rocket flight, 0..86 s, exact 100 Hz IMU (docs/assumptions.md,
    excitability.md §3-4).

    Parameters
    ----------
    **overrides
        Any of the assumed values below (defaults in ``ROCKET_DEFAULTS``); angles in
        degrees at this edge only.

        * site: ``lat_deg=-5.92``, ``lon_deg=-35.16``, ``alt_m=30`` (Barreira do Inferno);
        * rail: ``rail_elevation_deg=84``, ``rail_azimuth_deg=100``, ``rail_length_m=10``,
          ``rail_fade_m=2`` (tip-off distance over which the rail reaction fades);
        * timing, s: ``ignition_s=18`` (paper), ``ignition_ramp_s=0.3``, ``burnout_s=46``
          (paper: thrust ends), ``tailoff_s=1``, ``free_flight_s=60`` (paper, marker only),
          ``despin_s=73`` (paper, step centre), ``despin_duration_s=0.5``,
          ``despin_factor=0.5`` (paper: halves the axial rate), ``end_s=86`` (paper),
          ``rate_hz=100`` (paper);
        * vehicle: ``mass_initial_kg=1500``, ``mass_burnout_kg=650``,
          ``thrust_n=81510`` (= 1.14 x 110 m/s^2 x 650 kg so the axial specific force peaks
          near 110 m/s^2 at burnout), ``drag_area_m2=0.07`` (C_D A),
          ``scale_height_m=7200``, ``density_sea_level=1.225``; propellant flow is
          proportional to thrust;
        * spin: ``spin_hz=2`` (aerodynamic spin at high speed), ``spin_speed_mps=400``,
          ``roll0_deg=0``;
        * recovery (assumption M7 of ``docs/assumptions.md``; off by default):
          ``drogue_rate_mps=0`` (a positive descent rate adds apogee, drogue, optional main
          and touchdown; the flight then ends at touchdown or ``end_s``),
          ``drogue_delay_s=0`` (after apogee), ``drogue_tau_s=1`` (time constant of the
          approach to the descent rate), ``drogue_inflation_s=0.5``, ``main_height_m=0``
          (above the site), ``main_rate_mps=0`` (0: no main), ``main_tau_s=1``,
          ``main_inflation_s=1``, ``canopy_spin_hz=0`` (roll rate about the riser),
          ``canopy_swing_deg=0`` and ``canopy_swing_period_s=3`` (pendulum swing);
        * numerics: ``grid_step_s=0.02`` (spline nodes on the ODE solution).

    Returns
    -------
    Trajectory
        ``events``: ``ignition``, ``liftoff`` (thrust exceeds the weight along the rail),
        ``rail_exit``, ``burnout``, ``free_flight``, ``despin``, ``end``, and with a drogue
        ``apogee``, ``drogue``, ``main`` and ``landing`` (those reached before ``end_s``).
        ``parameters`` holds every keyword used plus derived values.

    Raises
    ------
    NavlibInputError
        Unknown keyword, non-finite or out-of-range value, impossible timing.

    Notes
    -----
    Before lift-off ``V = 0`` exactly, ``f^b = -C_e^b gamma`` and ``omega_ib^b = C_e^b
    Omega``. Position is C^4 after lift-off and C^2 across it; the attitude is C^3.
    """
    reject_unknown(overrides, ROCKET_DEFAULTS, "sounding_rocket")
    p = _check({**ROCKET_DEFAULTS, **overrides})
    path = _flight_path(tuple(sorted((k, v) for k, v in p.items() if k not in SPIN_KEYS)))
    lat, lon = p["lat_deg"] * DEG, p["lon_deg"] * DEG
    P0, C_L_e, r_hat, canopy = path.P0, path.C_L_e, path.r_hat, path.canopy
    grid, P_grid, V_grid = path.grid, path.P_grid, path.V_grid
    displacement, t_lift, t_final = path.displacement, path.t_lift, path.t_final
    fade_start, fade_len = p["rail_length_m"] - p["rail_fade_m"], p["rail_fade_m"]
    t_ign, t_bo = p["ignition_s"], p["burnout_s"]

    # spin: aerodynamic spin-up with speed, then a smooth de-spin step
    speed_grid = np.linalg.norm(V_grid, axis=1)
    despin = 1.0 - (1.0 - p["despin_factor"]) * smoothstep(
        (grid - p["despin_s"] + 0.5 * p["despin_duration_s"]) / p["despin_duration_s"])[0]
    spin = 2.0 * np.pi * p["spin_hz"] * np.tanh((speed_grid / p["spin_speed_mps"]) ** 2)
    spin = spin * despin
    if recovering(p):
        spin = canopy.spin(grid, spin)
    _, roll_angle = roll_spline(grid, spin)
    roll0 = p["roll0_deg"] * DEG

    def roll(t, nu):
        return roll_angle(t, nu) + (roll0 if nu == 0 else 0.0)

    def pointing(t, V, a):
        x = displacement(t) @ r_hat
        s, ds, _ = smoothstep((x - fade_start) / fade_len)
        rail = 1.0 - s
        speed = np.linalg.norm(V, axis=1)
        moving = speed > 0.0
        v_hat = np.where(moving[:, None], V / np.where(moving, speed, 1.0)[:, None], r_hat)
        dv_hat = np.where(
            moving[:, None],
            (a - v_hat * np.einsum("ni,ni->n", v_hat, a)[:, None])
            / np.where(moving, speed, 1.0)[:, None],
            0.0)
        drail = -ds / fade_len * (V @ r_hat)
        w = rail[:, None] * r_hat + (1.0 - rail)[:, None] * v_hat
        dw = drail[:, None] * (r_hat - v_hat) + (1.0 - rail)[:, None] * dv_hat
        return unit_and_rate(w, dw)

    t_out = output_times(t_final, p["rate_hz"])
    x_grid = (P_grid - P0) @ r_hat
    t_exit = float(np.interp(p["rail_length_m"], x_grid, grid))
    events = {
        "ignition": t_ign, "liftoff": float(t_lift), "rail_exit": t_exit, "burnout": t_bo,
        "free_flight": p["free_flight_s"], "despin": p["despin_s"], **path.recovery_events,
        "end": float(t_out[-1]) if recovering(p) else p["end_s"],
    }
    frame, turn = C_L_e, None
    if recovering(p):
        frame, turn = recovery_frame(lat, lon, p["rail_azimuth_deg"] * DEG), canopy.turn
    parameters = {**p, "exhaust_velocity_mps": path.v_exhaust,
                  "liftoff_mass_kg": path.m_lift}
    return assemble(t_out, P0, displacement, pointing, frame, roll, turn=turn, events=events,
                    name="sounding rocket (VS30-like)", parameters=parameters)
