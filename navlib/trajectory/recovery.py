"""Apogee and descent under drogue and main parachutes for the rocket generator (private).

:func:`navlib.trajectory.sounding_rocket` calls into this module when its
``drogue_rate_mps`` keyword is positive (assumption M7 of ``docs/assumptions.md``):

* after the coast the point-mass ODE flies the ballistic arc through apogee (the instant
  the geocentric radius stops growing, ``P . V = 0``);
* ``drogue_delay_s`` after apogee the drogue opens: over ``drogue_inflation_s`` a C^3
  smoothstep ``c(t)`` blends the ballistic acceleration into the canopy law
  ``dV/dt = (V_target - V) / tau``, ``V_target = -rate * up`` (up: the site's ellipsoid
  normal, no wind), so the velocity settles on the descent rate with the time constant
  ``tau``;
* when the height above the site (its tangent plane) falls to ``main_height_m`` the main
  opens: rate and time
  constant move to the main's over ``main_inflation_s`` with the same smoothstep;
* the flight ends at touchdown (height back to the site's tangent plane) or at ``end_s``,
  whichever comes first.

The body x axis turns from the flight direction to the riser (straight up, towards the
canopy): its yaw and pitch in :func:`recovery_frame` shrink to zero with a smoothstep over
the drogue's inflation plus time constant, and the roll rate blends into the canopy spin
with the same weight; a pendulum swing of the body about the vertical may be added.
Every change is a smoothstep of a smooth law, so specific force and body rate stay
continuous (C^1) and :func:`navlib.trajectory.base.build_trajectory` keeps the kinematics
exact.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from scipy.integrate import solve_ivp

from navlib import earth
from navlib._validation import finite_scalar
from navlib.errors import NavlibInputError
from navlib.trajectory._attitude import smoothstep
from navlib.trajectory._flight import step

__all__ = ["APOGEE_TURN_LIMIT", "RECOVERY_DEFAULTS", "Canopy", "check_recovery", "deployments",
           "recovering", "recovery_frame"]

RECOVERY_DEFAULTS = {
    "drogue_rate_mps": 0.0,       # 0: no recovery, the flight ends at end_s
    "drogue_delay_s": 0.0,        # after apogee
    "drogue_tau_s": 1.0,          # time constant of the approach to the descent rate
    "drogue_inflation_s": 0.5,    # length of the deployment smoothstep
    "main_height_m": 0.0,         # above the site
    "main_rate_mps": 0.0,         # 0: no main, the drogue lands the rocket
    "main_tau_s": 1.0,
    "main_inflation_s": 1.0,
    "canopy_spin_hz": 0.0,        # roll rate about the riser under the canopy
    "canopy_swing_deg": 0.0,      # amplitude of a pendulum swing of the body under the canopy
    "canopy_swing_period_s": 3.0,
}
"""Recovery keywords of :func:`navlib.trajectory.sounding_rocket` and their defaults."""
APOGEE_TURN_LIMIT = 10.0
"""Largest rate, rad/s, at which the flight direction may turn over apogee (gravity over the
speed there): a near-vertical flight that stops at apogee tumbles, which the pointing along
the velocity does not represent."""


def check_recovery(p: dict) -> None:
    """Validate the recovery keywords of a checked rocket keyword dict (names the keyword)."""
    for key in ("drogue_rate_mps", "drogue_delay_s", "main_height_m", "main_rate_mps"):
        finite_scalar(p[key], key, 0.0)
    for key in ("drogue_tau_s", "drogue_inflation_s", "main_tau_s", "main_inflation_s",
                "canopy_swing_period_s"):
        finite_scalar(p[key], key, 0.0, low_open=True)
    finite_scalar(p["canopy_swing_deg"], "canopy_swing_deg", 0.0, 45.0)
    if p["drogue_rate_mps"] == 0.0:
        for key in ("main_rate_mps", "canopy_spin_hz", "canopy_swing_deg"):
            if p[key] != 0.0:
                raise NavlibInputError(f"{key}: needs a drogue (drogue_rate_mps > 0), got "
                                       f"{p[key]} without one")
    if (p["main_rate_mps"] > 0.0) != (p["main_height_m"] > 0.0):
        raise NavlibInputError(
            "main_height_m: a main parachute needs both main_height_m and main_rate_mps "
            f"positive, got {p['main_height_m']} m and {p['main_rate_mps']} m/s")


def recovering(p: dict) -> bool:
    """Whether the keywords ask for a descent under canopy."""
    return p["drogue_rate_mps"] > 0.0


class Canopy:
    """The canopy law and its deployment times (set while the flight is integrated)."""

    def __init__(self, p: dict, P0):
        self.p = p
        self.P0 = np.asarray(P0, dtype=float)
        lat, lon = p["lat_deg"] * math.pi / 180.0, p["lon_deg"] * math.pi / 180.0
        self.up = -np.asarray(earth.ned_to_ecef_matrix(lat, lon))[:, 2]
        self.t_drogue = math.inf
        self.t_main = math.inf

    def height(self, P) -> float:
        """Height above the site's tangent plane, m (within a centimetre of the geodetic
        height for a drift of a few hundred metres)."""
        return float(self.up @ (P - self.P0))

    def blend(self, t, V, acc):
        """The ECEF acceleration ``acc`` of free flight blended into the canopy law.

        Parameters
        ----------
        t : float
            Time, s.
        V : numpy.ndarray
            ECEF velocity, m/s.
        acc : numpy.ndarray
            Free-flight ECEF acceleration, m/s^2.
        """
        c = step(t, self.t_drogue, self.p["drogue_inflation_s"])
        if c == 0.0:
            return acc
        m = step(t, self.t_main, self.p["main_inflation_s"])
        p = self.p
        rate = p["drogue_rate_mps"] + (p["main_rate_mps"] - p["drogue_rate_mps"]) * m
        tau = p["drogue_tau_s"] + (p["main_tau_s"] - p["drogue_tau_s"]) * m
        return (1.0 - c) * acc + c * (-rate * self.up - V) / tau

    def breakpoints(self) -> list:
        """Starts and ends of the deployment smoothsteps (finite ones)."""
        out = [self.t_drogue, self.t_drogue + self.p["drogue_inflation_s"],
               self.t_main, self.t_main + self.p["main_inflation_s"]]
        return [t for t in out if math.isfinite(t)]

    def hang(self, t):
        """Weight of the turn to hang under the drogue and its rate on an array of times: a
        smoothstep from the drogue's opening over its inflation plus time constant."""
        width = self.p["drogue_inflation_s"] + self.p["drogue_tau_s"]
        s, ds, _ = smoothstep((np.asarray(t, float) - self.t_drogue) / width)
        return s, ds / width

    def spin(self, t, ascent_spin):
        """Roll rate on the grid ``t``: the ascent spin blended into the canopy spin.

        Parameters
        ----------
        t : numpy.ndarray
            Times, s.
        ascent_spin : numpy.ndarray
            Ascent roll rate, rad/s.
        """
        c, _ = self.hang(t)
        return (1.0 - c) * ascent_spin + c * 2.0 * np.pi * self.p["canopy_spin_hz"]

    def turn(self, t, psi, theta, dpsi, dtheta):
        """Yaw and pitch of the flight direction in :func:`recovery_frame` (and rates) turned
        with the :meth:`hang` weight to the riser: body x straight up, tilted by the swing
        ``canopy_swing_deg sin(2 pi (t - t_drogue) / canopy_swing_period_s)`` in the
        vertical plane of the launch azimuth.

        Parameters
        ----------
        t : numpy.ndarray
            Times, s.
        psi, theta : numpy.ndarray
            Yaw and pitch, rad.
        dpsi, dtheta : numpy.ndarray
            Their rates, rad/s.
        """
        c, dc = self.hang(t)
        keep = 1.0 - c
        omega = 2.0 * np.pi / self.p["canopy_swing_period_s"]
        amplitude = self.p["canopy_swing_deg"] * np.pi / 180.0
        phase = omega * (np.asarray(t, float) - self.t_drogue)
        swing, dswing = amplitude * np.sin(phase), amplitude * omega * np.cos(phase)
        return (keep * psi + c * swing, keep * theta,
                keep * dpsi + dc * (swing - psi) + c * dswing, keep * dtheta - dc * theta)


def recovery_frame(lat, lon, azimuth):
    """Fixed frame with x up, y horizontal along ``azimuth`` and z across: the body axis of a
    recovery flight (up the rail, over apogee along the azimuth, down, back up the riser)
    stays in its x-y plane, far from the yaw-pitch-roll singularity.

    Parameters
    ----------
    lat, lon : float
        Pad latitude and longitude, rad.
    azimuth : float
        Launch azimuth, rad.

    Returns
    -------
    numpy.ndarray
        Frame -> ECEF rotation matrix, (3, 3).
    """
    C_n_e = np.asarray(earth.ned_to_ecef_matrix(lat, lon))
    up = np.array([0.0, 0.0, -1.0])
    along = np.array([math.cos(azimuth), math.sin(azimuth), 0.0])
    return C_n_e @ np.column_stack([up, along, np.cross(up, along)])


def _first_crossing(rhs, t0, y0, t_stop, cuts, event, rtol, atol):
    """First downward zero of ``event(t, y)`` in ``(t0, t_stop]``: ``(time, state)``, or
    ``(None, state at t_stop)``. The span is split at ``cuts`` like
    :func:`navlib.trajectory._flight.integrate`."""
    def ev(t, y):
        return event(y)

    ev.terminal, ev.direction = True, -1.0
    edges = np.unique(np.r_[t0, [c for c in cuts if t0 < c < t_stop], t_stop])
    y = np.asarray(y0, dtype=float)
    for lo, hi in itertools.pairwise(edges):
        sol = solve_ivp(rhs, (lo, hi), y, method="DOP853", rtol=rtol, atol=atol, events=ev)
        if not sol.success:  # pragma: no cover - smooth right-hand sides do not fail
            raise NavlibInputError(f"flight integration failed: {sol.message}")
        if sol.status == 1:
            return float(sol.t_events[0][0]), sol.y_events[0][0]
        y = sol.y[:, -1]
    return None, y


def deployments(rhs, canopy: Canopy, t_start, y_start, t_cap, cuts, rtol=1e-10, atol=1e-6):
    """Find apogee, the deployments and touchdown along the flight, setting the canopy's
    times. ``y_start`` is the state at ``t_start`` (after burnout). Returns the events and
    the end time of the flight (touchdown or ``t_cap``).

    Parameters
    ----------
    rhs : callable
        Right-hand side of the flight ODE, ``rhs(t, y)``.
    canopy : Canopy
        The canopy, whose times are set.
    t_start : float
        Start time, s.
    y_start : numpy.ndarray
        State at ``t_start``.
    t_cap : float
        Latest end time, s.
    cuts : sequence of float
        Times where the integration is split, s.
    rtol, atol : float, optional
        Tolerances of the ODE solver.

    Raises
    ------
    NavlibInputError
        If the flight turns too far at apogee.
    """
    p = canopy.p
    events = {}
    t_apo, y = _first_crossing(rhs, t_start, y_start, t_cap, cuts,
                               lambda y: y[:3] @ y[3:6], rtol, atol)
    if t_apo is None:
        return events, t_cap
    speed = float(np.linalg.norm(y[3:6]))
    turn = float(np.linalg.norm(earth.normal_gravity_ecef(y[:3]))) / max(speed, 1e-9)
    if turn > APOGEE_TURN_LIMIT:
        raise NavlibInputError(
            f"rail_elevation_deg: the flight reaches apogee at {speed:.2g} m/s, so its "
            f"direction turns over at {turn:.3g} rad/s (above {APOGEE_TURN_LIMIT:g}: a tumble "
            "the pointing along the velocity does not represent); tilt the rail further from "
            "the vertical")
    events["apogee"] = t_apo
    canopy.t_drogue = t_apo + p["drogue_delay_s"]
    t = t_apo
    if canopy.t_drogue >= t_cap:
        return events, t_cap
    events["drogue"] = canopy.t_drogue
    if p["main_rate_mps"] > 0.0:
        sol = solve_ivp(rhs, (t, canopy.t_drogue), y, method="DOP853", rtol=rtol, atol=atol)
        y, t = sol.y[:, -1], canopy.t_drogue
        if canopy.height(y[:3]) <= 0.0:
            raise NavlibInputError(
                f"drogue_delay_s: the rocket is on the ground before the drogue opens at "
                f"{canopy.t_drogue:.2f} s")
        if canopy.height(y[:3]) <= p["main_height_m"]:
            raise NavlibInputError(
                f"main_height_m: the drogue opens at {canopy.height(y[:3]):.0f} m, not above "
                f"the main's deployment height {p['main_height_m']} m")
        t_main, y = _first_crossing(rhs, t, y, t_cap, canopy.breakpoints(),
                                    lambda y: canopy.height(y[:3]) - p["main_height_m"],
                                    rtol, atol)
        if t_main is None:
            return events, t_cap
        events["main"] = canopy.t_main = t_main
        t = t_main
    t_land, _ = _first_crossing(rhs, t, y, t_cap, canopy.breakpoints(),
                                lambda y: canopy.height(y[:3]), rtol, atol)
    if t_land is None:
        return events, t_cap
    if t_land <= canopy.t_drogue + p["drogue_inflation_s"]:
        raise NavlibInputError(
            f"drogue_delay_s: the rocket lands at {t_land:.2f} s, before the drogue opening "
            f"at {canopy.t_drogue:.2f} s has ended")
    events["landing"] = t_land
    return events, t_land
