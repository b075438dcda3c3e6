"""Generated vehicles for the vehicle-class and phase tests: a car, a hovering multicopter and
a small rocket under a parachute.

Each moves in a local North-East-Down frame fixed at the start (flat-Earth kinematics over
a few hundred metres, then mapped to ECEF); the body stays level with a given yaw, or points
its x axis up (the rocket). Motion is a monotone cubic (PCHIP) or a smoothstep profile, so
:func:`navlib.trajectory.base.build_trajectory` gives an exact IMU for it. Test fixtures
with stated, arbitrary numbers, not navlib generators.
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import PchipInterpolator, make_interp_spline
from scipy.spatial.transform import Rotation

from navlib import earth
from navlib.trajectory.base import build_trajectory

LAT_DEG, LON_DEG, ALT_M = 47.397, 8.545, 488.0


def _step(x):
    """Quintic smoothstep on [0, 1] and its derivative."""
    x = np.clip(x, 0.0, 1.0)
    return x**3 * (10.0 - 15.0 * x + 6.0 * x**2), 30.0 * x**2 * (1.0 - x) ** 2


def _build(t, p_n, v_n, a_n, C_b_n, w_eb_b, name):
    lat, lon = np.radians(LAT_DEG), np.radians(LON_DEG)
    C_n_e = earth.ned_to_ecef_matrix(lat, lon)
    P0 = earth.geodetic_to_ecef(lat, lon, ALT_M)
    return build_trajectory(t, P0 + p_n @ C_n_e.T, v_n @ C_n_e.T, a_n @ C_n_e.T,
                            C_n_e @ C_b_n, w_eb_b, name=name)


def car(duration_s=80.0, rate_hz=100.0, speed_m_s=15.0):
    """Stands 10 s, speeds up to ``speed_m_s`` over 10 s, turns 90 deg left over 35-45 s,
    brakes over 60-70 s and stands again; level body, nose along the road."""
    grid = np.arange(0.0, duration_s + 0.5, 0.01)
    speed = speed_m_s * (_step((grid - 10.0) / 10.0)[0] - _step((grid - 60.0) / 10.0)[0])
    heading = -0.5 * np.pi * _step((grid - 35.0) / 10.0)[0]
    v = np.column_stack([speed * np.cos(heading), speed * np.sin(heading), 0.0 * grid])
    p = np.concatenate([[np.zeros(3)], np.cumsum(0.5 * (v[1:] + v[:-1]) * 0.01, axis=0)])
    spl = make_interp_spline(grid[::5], p[::5], k=5)
    t = np.arange(round(duration_s * rate_hz) + 1) / rate_hz
    psi = -0.5 * np.pi * _step((t - 35.0) / 10.0)[0]
    dpsi = -0.5 * np.pi * _step((t - 35.0) / 10.0)[1] / 10.0
    w = np.zeros((t.size, 3))
    w[:, 2] = dpsi
    C_b_n = Rotation.from_euler("z", psi[:, None]).as_matrix()
    return _build(t, spl(t), spl(t, 1), spl(t, 2), C_b_n, w, "car")


def hover(duration_s=60.0, rate_hz=100.0, climb_m=10.0):
    """Stands 10 s, climbs ``climb_m`` straight up over 10-16 s, hovers until 40 s, comes
    straight down over 40-46 s and stands; level body, yaw 0.4 rad."""
    t = np.arange(round(duration_s * rate_hz) + 1) / rate_hz
    up, dup = _step((t - 10.0) / 6.0)
    down, ddown = _step((t - 40.0) / 6.0)
    # second derivative of the smoothstep: 60 x (1 - x) (1 - 2x)
    x1, x2 = np.clip((t - 10.0) / 6.0, 0, 1), np.clip((t - 40.0) / 6.0, 0, 1)
    d2 = 60.0 * x1 * (1 - x1) * (1 - 2 * x1) - 60.0 * x2 * (1 - x2) * (1 - 2 * x2)
    zeros = np.zeros_like(t)
    p = np.column_stack([zeros, zeros, -climb_m * (up - down)])
    v = np.column_stack([zeros, zeros, -climb_m * (dup - ddown) / 6.0])
    a = np.column_stack([zeros, zeros, -climb_m * d2 / 36.0])
    C_b_n = np.repeat(Rotation.from_euler("z", 0.4).as_matrix()[None], t.size, axis=0)
    return _build(t, p, v, a, C_b_n, np.zeros((t.size, 3)), "hover")


def parachute_rocket(duration_s=60.0, rate_hz=100.0):
    """Vertical rocket: on its pad 5 s, boost to 90 m/s over 5-8 s, coast decelerating at
    12 m/s^2 (gravity and drag) to its apogee at 15.5 s, then down under a parachute at
    8 m/s; body x axis up throughout."""
    knots = np.array([0.0, 4.0, 5.0, 8.0, 15.5, 17.5, 25.0, duration_s + 1.0])
    v_up = np.array([0.0, 0.0, 0.0, 90.0, 0.0, -8.0, -8.0, -8.0])
    v = PchipInterpolator(knots, v_up)
    h = v.antiderivative()
    t = np.arange(round(duration_s * rate_hz) + 1) / rate_hz
    zeros = np.zeros_like(t)
    p = np.column_stack([zeros, zeros, -h(t)])
    vel = np.column_stack([zeros, zeros, -v(t)])
    acc = np.column_stack([zeros, zeros, -v.derivative()(t)])
    C_b_n = np.repeat(Rotation.from_euler("y", 90.0, degrees=True).as_matrix()[None], t.size,
                      axis=0)
    return _build(t, p, vel, acc, C_b_n, np.zeros((t.size, 3)), "parachute rocket")


def plane(duration_s=120.0, rate_hz=50.0, speed_m_s=20.0):
    """Stands 10 s, rolls and takes off reaching ``speed_m_s`` by 20 s, climbs 52 m at a
    20 % grade (20-35 s), flies level, turns 180 deg left over 50-65 s, descends 52 m at
    the same grade (80-95 s) and flies on; level body, nose along the track."""
    grid = np.arange(0.0, duration_s + 0.5, 0.01)
    speed = speed_m_s * _step((grid - 10.0) / 10.0)[0]
    climb = 0.2 * speed_m_s * (_step((grid - 20.0) / 2.0)[0] - _step((grid - 33.0) / 2.0)[0]
                               - _step((grid - 80.0) / 2.0)[0] + _step((grid - 93.0) / 2.0)[0])
    heading = -np.pi * _step((grid - 50.0) / 15.0)[0]
    horizontal = np.sqrt(np.maximum(speed**2 - climb**2, 0.0))
    v = np.column_stack([horizontal * np.cos(heading), horizontal * np.sin(heading), -climb])
    p = np.concatenate([[np.zeros(3)], np.cumsum(0.5 * (v[1:] + v[:-1]) * 0.01, axis=0)])
    spl = make_interp_spline(grid[::5], p[::5], k=5)
    t = np.arange(round(duration_s * rate_hz) + 1) / rate_hz
    s, ds = _step((t - 50.0) / 15.0)
    w = np.zeros((t.size, 3))
    w[:, 2] = -np.pi * ds / 15.0
    C_b_n = Rotation.from_euler("z", (-np.pi * s)[:, None]).as_matrix()
    return _build(t, spl(t), spl(t, 1), spl(t, 2), C_b_n, w, "plane")
