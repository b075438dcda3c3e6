"""Kinematic features of a trajectory that the segmentation reads (ECEF, docs/assumptions.md,
excitability.md §3).

:func:`flight_features` gives them per sample: speed, kinematic acceleration
``a^e = f^e + gamma(P) - 2 Omega x V``, specific force along and across the path, the body
rate off its roll axis, the turn rate of the path, vertical and horizontal speed, height;
:func:`window_means` averages them over windows of the segmentation's resolution.
"""


import numpy as np
import pandas as pd

from navlib import earth
from navlib.errors import NavlibInputError
from navlib.units import DEG

__all__ = ["FEATURES", "flight_features", "trajectory_arrays", "window_means"]

FEATURES = ("speed", "accel", "f_norm", "gravity", "f_along", "f_lateral", "rate",
             "rate_across", "path_rate", "v_up", "v_h", "a_up", "height", "sideslip")


def trajectory_arrays(trajectory):
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

    Parameters
    ----------
    trajectory : Trajectory
        The (fitted) trajectory.
    direction_speed_m_s : float, optional
        Speed above which the path direction is ``V/|V|``, m/s.
    rest_accel_m_s2 : float, optional
        Acceleration below which the direction is undefined at low speed, m/s^2.
    turn_speed_m_s : float, optional
        Speed above which the path rate counts, m/s.
    """
    t, P, V, f_b, w_ib_b, C_b_e = trajectory_arrays(trajectory)
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


def window_means(features: pd.DataFrame, resolution_s: float) -> pd.DataFrame:
    """Average the per-sample features over consecutive windows of ``resolution_s``.

    Parameters
    ----------
    features : pandas.DataFrame
        Result of :func:`flight_features`.
    resolution_s : float
        Window length, s.

    Returns
    -------
    pandas.DataFrame
    """
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
    for name in FEATURES:
        sums = np.bincount(k, weights=features[name].to_numpy(), minlength=n_bins)
        out[name] = sums[used] / counts[used]
    frame = pd.DataFrame(out)
    return frame[["t", "t_start", "t_end", *FEATURES]]
