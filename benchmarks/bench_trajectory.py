"""Benchmarks of trajectory synthesis, IMU simulation and strapdown integration.

* ``trajectory.sounding_rocket`` / ``trajectory.launcher_ascent``: build the reference
  flights with exact IMU (8601 samples at 100 Hz; 150 s at 200 Hz). Goal 1 s each.
* ``trajectory.strapdown_rocket`` / ``trajectory.strapdown_launcher``: integrate the exact
  IMU of those flights with :func:`navlib.strapdown.integrate` (closure check). Goal 1 s.
* ``trajectory.strapdown_step_loop``: 100 calls of :func:`navlib.strapdown.step` (one
  second of rocket data), the per-sample path a filter would use. Goal 25 ms
  (250 us per sample, i.e. 2 s for the whole flight).
* ``trajectory.strapdown_blocks_1hz``: the whole rocket flight as 86 calls of
  :func:`navlib.strapdown.integrate`, each over one second of samples and started from the
  previous call's end state — how a filter with 1 Hz GNSS updates propagates cheaply.
  Goal 0.5 s.
* ``trajectory.simulate_imu_rocket``: corrupt the rocket IMU with the MotionPak-class
  preset (all error sources active). Goal 0.1 s.
* ``trajectory.fit_rocket``: :func:`navlib.trajectory.fit_flight_data` on the rocket's exact
  IMU (8601 samples, 2 Hz spin) and 1 Hz GNSS positions with GNSS velocity, heading given:
  levelling, gyro chain, position spline with attitude correction, attitude spline on SO(3),
  exact IMU. Goal 3 s.

The trajectories are built once outside the strapdown and simulation timings.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from _harness import Case
from _harness import launcher_flight as _launcher
from _harness import rocket_flight as _rocket

import navlib.trajectory as trajectories
from navlib import sensors, strapdown


def _integrate(traj):
    return strapdown.integrate(traj.t, traj.specific_force, traj.angular_rate,
                               traj.position[0], traj.velocity[0], traj.attitude[0])


def _step_loop(n_steps: int = 100):
    traj = _rocket()
    k0 = 3000  # inside the boost: spin, thrust, pitch-over
    state = strapdown.StrapdownState.from_trajectory(traj, k0)
    f_b, w_ib_b, t = traj.specific_force, traj.angular_rate, traj.t
    for k in range(k0, k0 + n_steps):
        state = strapdown.step(state, f_b[k:k + 2], w_ib_b[k:k + 2], t[k + 1] - t[k])
    return state


def _blocks_1hz():
    traj = _rocket()
    state = strapdown.StrapdownState.from_trajectory(traj)
    for k0 in range(0, len(traj.t) - 1, 100):
        sl = slice(k0, k0 + 101)
        res = strapdown.integrate(traj.t[sl], traj.specific_force[sl], traj.angular_rate[sl],
                                  state.position, state.velocity, state.q_b_e)
        state = res.state(-1)
    return state


def _fit_rocket():
    traj = _rocket()
    g = traj.at_rate(1.0)
    imu = pd.DataFrame(np.column_stack([traj.t, traj.specific_force, traj.angular_rate]),
                       columns=["t", "f_x", "f_y", "f_z", "w_x", "w_y", "w_z"])
    gnss = pd.DataFrame(np.column_stack([traj.t[g], traj.position[g], traj.velocity[g]]),
                        columns=["t", "x", "y", "z", "vx", "vy", "vz"])
    return trajectories.fit_flight_data(imu, gnss, heading_deg=100.0)


def cases() -> list[Case]:
    motionpak = sensors.load_preset("motionpak_tactical")
    return [
        Case("trajectory.sounding_rocket", "86 s @ 100 Hz", trajectories.sounding_rocket, 1.0),
        Case("trajectory.launcher_ascent", "150 s @ 200 Hz", trajectories.launcher_ascent, 1.0),
        Case("trajectory.strapdown_rocket", "8601 samples", lambda: _integrate(_rocket()), 1.0),
        Case("trajectory.strapdown_launcher", "30001 samples", lambda: _integrate(_launcher()),
             1.0),
        Case("trajectory.strapdown_step_loop", "100 steps", _step_loop, 0.025),
        Case("trajectory.strapdown_blocks_1hz", "86 x 101 samples", _blocks_1hz, 0.5),
        Case("trajectory.simulate_imu_rocket", "8601 samples",
             lambda: sensors.simulate_imu(_rocket(), motionpak, seed=0), 0.1),
        Case("trajectory.fit_rocket", "8601 samples, 1 Hz GNSS", _fit_rocket, 3.0, repeat=2),
    ]
