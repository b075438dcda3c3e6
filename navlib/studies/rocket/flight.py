"""The rocket flight of España et al. (2019) §5: trajectory, coning variant and the 21-state
model at the GNSS epochs, with the paper's segments and operational thresholds."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.spatial.transform import Rotation

from navlib import earth, metrics
from navlib._validation import finite_scalar
from navlib.cache import memoized
from navlib.errors import NavlibInputError
from navlib.models.ecef import (
    P0_DEFAULTS,
    STATE_GROUPS,
    STATE_NAMES,
    ecef21_at_epochs,
    initial_covariance,
)
from navlib.trajectory import build_trajectory, sounding_rocket
from navlib.trajectory._attitude import smoothstep

__all__ = ["ATTITUDE", "BASELINE", "BRIEF_S", "CONING_KEYS", "EXCITABILITY_DEPENDS", "FUTILE",
           "GYRO_NOISE_KEYS", "IN_SO", "LOW", "NOT_IMPROVED", "ONLY_AFTER", "PARAMETERS",
           "QUIET_GYRO_SCALE", "SEGMENTS", "SEGMENT_LABELS", "SENSABILITY_DEPENDS", "SENSIBLE",
           "TRANSIENT_S", "add_coning", "rocket_chain", "rocket_trajectory"]

SEGMENTS = ((0.0, 19.0), (19.0, 60.0), (60.0, 86.0))
"""The paper's segments tau1 (pad), tau2 (powered flight and spin), tau3 (free fall), s."""
SEGMENT_LABELS = ("tau1", "tau2", "tau3")

IN_SO = metrics.E_THRESHOLD
"""Excitability above which a state "lies (mostly) in S_O" (spec §3, X4 note): 1/sqrt(2)."""
SENSIBLE = metrics.S_THRESHOLD
"""Sensability above which a state counts as sensible at an epoch: 1/sqrt(2)."""
LOW = metrics.LOW
"""Excitability (or sensability) below which a state is "very low" / "barely" excited."""
BRIEF_S = 10.0
"""Longest total time (s) that still counts as "briefly" sensible (S7)."""
TRANSIENT_S = 5.0
"""Start-up epochs (s after t0) left out of the "weakly sensible" counts (S7, S8)."""
NOT_IMPROVED = 0.9
"""sigma_end / sigma_0 above which an a-priori bound is "not improved" (S7)."""
FUTILE = 0.5
"""sigma_end / sigma_0 above which in-flight calibration of a parameter is futile (S8)."""
ONLY_AFTER = 0.5
"""S4's "q_x, q_y grow only after lift-off": the rise of their sensability over the pad
(after :data:`TRANSIENT_S`) must stay below this share of the gain in the 10 s after
lift-off (docs/assumptions.md, A-S4-only-after)."""
QUIET_GYRO_SCALE = 1e-4
"""Factor on the gyro ARW, bias random walk and initial bias sigma of S5's counterfactual
run: the claim names the gyro errors as the cause, so removing them must make the heading
sensible (docs/assumptions.md, A-S5-cause)."""
GYRO_NOISE_KEYS = ("arw_rad_sqrt_s", "bg_rw_rad_s_sqrt_s")
"""The gyro noise densities S5's counterfactual scales (:data:`QUIET_GYRO_SCALE`)."""
EXCITABILITY_DEPENDS = ("eta", "p0", "sigma_sg_ppm", "spin_hz")
"""The assumptions X1-X7's numbers depend on (the keys of :data:`ROBUSTNESS_GRID`)."""
SENSABILITY_DEPENDS = ("nu", "p0", "sigma_sg_ppm", "spin_hz")
"""The assumptions S1-S8's numbers depend on."""

BASELINE = {"spin_hz": 2.0, "attitude_error": "ecef", "eta": 1e-3, "nu": 0.985,
            "d0": "global", "gnss_sigma_m": 5.0, **P0_DEFAULTS}
"""Baseline settings: all assumed, the paper gives none (docs/assumptions.md, "excitability.md
§5 — parameter values")."""

PARAMETERS = STATE_NAMES[9:]
"""The 12 IMU parameter states (e10-e21)."""
ATTITUDE = STATE_GROUPS["attitude"]


def _frozen(options: dict | None) -> tuple:
    options = dict(options or {})
    try:
        key = tuple(sorted(options.items()))
        hash(key)
    except TypeError as exc:
        raise NavlibInputError("trajectory_options: expected plain numbers") from exc
    return key


def add_coning(traj, coning_deg: float = 3.0, coning_hz: float = 0.5,
               start_s: float | None = None, ramp_s: float = 2.0):
    """The same flight path with the body coning about its nominal attitude.

    ``C_b_e = C_nom Rx(phi) Ry(alpha) Rx(-phi)``: the body x axis tilts by ``alpha`` (ramped
    in with a smoothstep from ``start_s``, default lift-off) about a lateral axis turning at
    ``coning_hz``. Position, velocity and ``f^e`` are unchanged, so the accelerometers see a
    lateral specific force ``|f| sin(alpha)``; the IMU stays exact (analytic body rate,
    :func:`navlib.trajectory.build_trajectory`). Used to test whether lateral *body* motion
    resolves the X3/S6 tension (it does not: the ECEF attitude error couples through ``f^e``).

    Parameters
    ----------
    traj : Trajectory
        The flight.
    coning_deg : float, optional
        Cone half-angle, deg.
    coning_hz : float, optional
        Coning frequency, Hz.
    start_s : float or None, optional
        Start of the ramp, s; None: lift-off.
    ramp_s : float, optional
        Ramp length, s.

    Returns
    -------
    Trajectory
    """
    coning_deg = finite_scalar(coning_deg, "coning_deg", 0.0, 30.0)
    coning_hz = finite_scalar(coning_hz, "coning_hz", 0.0)
    ramp_s = finite_scalar(ramp_s, "ramp_s", 0.0, low_open=True)
    if start_s is None:
        start_s = traj.events.get("liftoff", traj.t[0])
    start_s = finite_scalar(start_s, "start_s")
    t = traj.t
    step, dstep, _ = smoothstep((t - start_s) / ramp_s)
    alpha = np.radians(coning_deg) * step
    dalpha = np.radians(coning_deg) * dstep / ramp_s
    dphi = 2.0 * np.pi * coning_hz
    e_x, e_y = np.eye(3)[0], np.eye(3)[1]
    R1 = Rotation.from_rotvec(np.outer(dphi * t, e_x))
    R2 = Rotation.from_rotvec(np.outer(alpha, e_y))
    R3 = R1.inv()
    R = R1 * R2 * R3
    w_R = ((R3.inv() * R2.inv()).apply(np.outer(np.full_like(t, dphi), e_x))
           + R3.inv().apply(np.outer(dalpha, e_y)) - dphi * e_x)
    omega = earth.EARTH_RATE_ECEF
    C_nom = traj.C_b_e()
    w_nom = traj.angular_rate - np.einsum("nji,j->ni", C_nom, omega)
    f_e = np.einsum("nij,nj->ni", C_nom, traj.specific_force)
    acc = f_e - 2.0 * np.cross(omega, traj.velocity) + earth.normal_gravity_ecef(traj.position)
    return build_trajectory(t, traj.position, traj.velocity, acc, C_nom @ R.as_matrix(),
                            R.inv().apply(w_nom) + w_R, events=traj.events,
                            name=f"{traj.name} + coning",
                            parameters={**traj.parameters, "coning_deg": coning_deg,
                                        "coning_hz": coning_hz})


CONING_KEYS = ("coning_deg", "coning_hz")


@memoized(maxsize=16)
def _trajectory(spin_hz: float, key: tuple):
    options = dict(key)
    coning = {k: options.pop(k) for k in CONING_KEYS if k in options}
    traj = sounding_rocket(spin_hz=spin_hz, **options)
    return add_coning(traj, **coning) if coning else traj


def rocket_trajectory(spin_hz: float = 2.0, **overrides):
    """The VS30-like flight (:func:`navlib.trajectory.sounding_rocket`), cached per settings.

    ``overrides`` are ``sounding_rocket`` keywords plus ``coning_deg``/``coning_hz``
    (:func:`add_coning`). The same object comes back for the same settings, so the
    discretised model cached on it (:func:`navlib.models.ecef.ecef21_at_epochs`) is reused
    by widgets and sweeps.

    Parameters
    ----------
    spin_hz : float, optional
        Roll rate, Hz.
    **overrides
        Keywords of :func:`navlib.trajectory.sounding_rocket` and of :func:`add_coning`.

    Returns
    -------
    Trajectory
    """
    spin_hz = finite_scalar(spin_hz, "spin_hz", 0.0)
    if "spin_hz" in overrides:
        raise NavlibInputError("spin_hz: pass it once, as the first argument")
    return _trajectory(spin_hz, _frozen(overrides))


def rocket_chain(spin_hz: float = 2.0, attitude_error: str = "ecef", sensors=None,
                 gnss_sigma_m: float = 5.0, gnss_rate_hz: float = 1.0,
                 trajectory_options: dict | None = None, **sigmas):
    """The 21-state model of the rocket flight at the GNSS epochs (cached).

    The discretised ``F``, ``Q`` depend only on the trajectory (spin), the attitude-error
    frame and the sensor noise; they are cached. ``P0`` (from ``sigmas``, see
    :data:`navlib.models.ecef.P0_DEFAULTS`) and ``R = gnss_sigma_m^2 I`` are attached
    afterwards at no cost.

    Returns
    -------
    DiscreteModel
        ``t`` (87,) at 1 Hz for the 0-86 s flight, ``F``, ``Q`` (86, 21, 21), ``H``, ``R``,
        ``P0``.

    Parameters
    ----------
    spin_hz : float, optional
        Roll rate, Hz.
    attitude_error : {"ecef", "body"}, optional
        Attitude-error frame.
    sensors : optional
        Sensor preset (as :func:`navlib.models.ecef21`).
    gnss_sigma_m : float, optional
        GNSS position sigma, m.
    gnss_rate_hz : float, optional
        GNSS rate, Hz.
    trajectory_options : dict or None, optional
        Keywords of :func:`rocket_trajectory`.
    **sigmas
        Initial sigmas, keywords of :func:`navlib.models.ecef21`.
    """
    traj = rocket_trajectory(spin_hz, **dict(_frozen(trajectory_options)))
    base = ecef21_at_epochs(traj, gnss_rate_hz, sensors=sensors, attitude_error=attitude_error)
    gnss_sigma_m = finite_scalar(gnss_sigma_m, "gnss_sigma_m", 0.0, low_open=True)
    R = np.broadcast_to(gnss_sigma_m**2 * np.eye(3), base.R.shape)
    return replace(base, P0=initial_covariance(sensors, **sigmas), R=R)
