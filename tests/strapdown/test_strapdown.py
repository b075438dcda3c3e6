"""ECEF strapdown mechanisation: closure on exact IMU data, order of accuracy, exact cases."""

import numpy as np
import pandas as pd
import pytest
from scipy.spatial.transform import Rotation

import navlib.trajectory as trajectories
from navlib import NavlibInputError, earth, strapdown
from navlib.trajectory import build_trajectory


def spinning_ascent(duration_s=30.0, rate_hz=100.0, spin_hz=2.0, jitter=0.0, seed=0):
    """Analytic test flight: 2 Hz spin, pitch-over and yaw wobble, accelerating and turning.

    Position is a closed-form path in the launch site's (fixed) NED frame and the attitude
    a closed-form yaw/pitch/roll history, so velocity, acceleration and body rate are exact
    derivatives (no finite differences). ``jitter`` perturbs the sample times (fraction of
    the step) to exercise non-uniform sampling.
    """
    t = np.arange(0.0, duration_s + 0.5 / rate_hz, 1.0 / rate_hz)
    if jitter:
        t[1:-1] += jitter / rate_hz * np.random.default_rng(seed).uniform(-1, 1, t.size - 2)
    lat, lon = np.radians(-5.92), np.radians(-35.16)
    r0 = earth.geodetic_to_ecef(lat, lon, 10.0)
    C_n_e = earth.ned_to_ecef_matrix(lat, lon)
    p = np.stack([50 * t + 1.5 * t**2 + 200 * np.sin(0.15 * t),
                  20 * t + 300 * (1 - np.cos(0.1 * t)), -(12.5 * t**2 + 10 * t)], axis=1)
    v = np.stack([50 + 3 * t + 30 * np.cos(0.15 * t), 20 + 30 * np.sin(0.1 * t),
                  -(25 * t + 10)], axis=1)
    a = np.stack([3 - 4.5 * np.sin(0.15 * t), 3 * np.cos(0.1 * t), np.full_like(t, -25.0)],
                 axis=1)
    spin = 2 * np.pi * spin_hz
    roll, droll = spin * t + 0.5 * np.sin(0.3 * t), spin + 0.15 * np.cos(0.3 * t)
    pitch, dpitch = 1.3 - 0.02 * t + 0.05 * np.sin(0.5 * t), -0.02 + 0.025 * np.cos(0.5 * t)
    yaw, dyaw = 0.4 + 0.1 * np.sin(0.2 * t), 0.02 * np.cos(0.2 * t)
    C_b_n = Rotation.from_euler("ZYX", np.stack([yaw, pitch, roll], axis=1)).as_matrix()
    # Body rate of a Z-Y-X Euler sequence; NED is fixed in ECEF so w_eb_b = w_nb_b.
    w_eb_b = np.stack([
        droll - dyaw * np.sin(pitch),
        dpitch * np.cos(roll) + dyaw * np.cos(pitch) * np.sin(roll),
        -dpitch * np.sin(roll) + dyaw * np.cos(pitch) * np.cos(roll),
    ], axis=1)
    return build_trajectory(t, r0 + p @ C_n_e.T, v @ C_n_e.T, a @ C_n_e.T, C_n_e @ C_b_n,
                            w_eb_b, name="spinning ascent")


@pytest.fixture(scope="module")
def rocket():
    return trajectories.sounding_rocket()


def test_sounding_rocket_closure(rocket):
    """Issue 2: the 100 Hz exact IMU reproduces the flight, < 1 m and < 0.1 mrad at 86 s."""
    assert rocket.rate_hz == pytest.approx(100.0)
    assert rocket.t[-1] == pytest.approx(86.0)
    err = strapdown.closure_error(rocket)
    assert err.position_error[-1] < 1.0
    assert err.attitude_error[-1] < 1e-4
    # ... and along the whole flight, not just at the end.
    assert err.position_m < 1.0
    assert err.attitude_rad < 1e-4
    assert err.velocity_m_s < 0.05


def test_launcher_closure():
    launcher_ascent = getattr(trajectories, "launcher_ascent", None)
    if launcher_ascent is None:
        pytest.skip("navlib.trajectory.launcher_ascent not available yet")
    traj = launcher_ascent()
    assert traj.rate_hz == pytest.approx(200.0)
    err = strapdown.closure_error(traj)
    assert err.position_m < 0.1
    assert err.attitude_rad < 1e-5


def test_fourth_order_convergence():
    """Halving the step divides the closure error by ~16 on a spinning, turning flight."""
    errors = [strapdown.closure_error(spinning_ascent(rate_hz=rate)) for rate in (50, 100, 200)]
    pos = np.array([e.position_m for e in errors])
    att = np.array([e.attitude_rad for e in errors])
    assert np.all(pos[:-1] / pos[1:] > 12.0)
    assert np.all(att[:-1] / att[1:] > 12.0)
    # Absolute level at 100 Hz with 2 Hz spin and 35 m/s^2 on every axis.
    assert errors[1].position_m < 0.05
    assert errors[1].attitude_rad < 1e-5


def test_non_uniform_sampling():
    uniform = strapdown.closure_error(spinning_ascent(duration_s=20.0))
    jittered = strapdown.closure_error(spinning_ascent(duration_s=20.0, jitter=0.3))
    assert jittered.position_m < 3 * uniform.position_m + 1e-3
    assert jittered.attitude_rad < 3 * uniform.attitude_rad + 1e-7


def test_stationary_one_hour_is_exact():
    """At rest the increments are constant-axis rotations and gravity cancels f exactly:
    the Earth-rate factorisation keeps the attitude to round-off over an hour at 1 Hz."""
    traj = trajectories.stationary(duration_s=3600.0, rate_hz=1.0)
    err = strapdown.closure_error(traj)
    assert err.position_m < 1e-6
    assert err.velocity_m_s < 1e-9
    assert err.attitude_rad < 1e-12


def test_constant_body_rate_is_exact_at_any_step():
    """Fixed-axis rotation: C(t) = exp(-S(Omega) t) C0 exp(S(w t)), whatever the step."""
    t = np.arange(0.0, 20.0 + 1e-9, 1.0)  # 1 Hz, 3 rad/s: 3 rad per step
    w = np.array([1.0, -2.0, 2.0])
    n = t.size
    r0 = earth.geodetic_to_ecef(0.3, 1.0, 0.0)
    C0 = Rotation.from_rotvec([0.2, 0.1, -0.3])
    res = strapdown.integrate(t, np.zeros((n, 3)), np.tile(w, (n, 1)), r0, np.zeros(3), C0)
    expected = (Rotation.from_rotvec(np.outer(-t, earth.EARTH_RATE_ECEF)) * C0
                * Rotation.from_rotvec(np.outer(t, w)))
    assert np.max((expected.inv() * res.attitude).magnitude()) < 1e-13


def test_free_fall_in_inertial_space():
    """Zero specific force, released at rest in ECEF: an independent check of gravity and
    Coriolis by integrating the inertial-frame equations with scipy (gravitation only)."""
    from scipy.integrate import solve_ivp

    t = np.arange(0.0, 60.0 + 1e-9, 0.1)
    n = t.size
    r0 = earth.geodetic_to_ecef(np.radians(45.0), 0.2, 1.0e5)
    res = strapdown.integrate(t, np.zeros((n, 3)), np.zeros((n, 3)), r0, np.zeros(3),
                              Rotation.identity())
    omega = earth.EARTH_RATE_ECEF
    # Inertial frame coincident with ECEF at t = 0: v_i = v_e + Omega x r.
    y0 = np.concatenate([r0, np.cross(omega, r0)])
    sol = solve_ivp(lambda _, y: np.concatenate([y[3:], earth.gravitation_ecef(y[:3])]),
                    (0.0, t[-1]), y0, t_eval=t, method="DOP853", rtol=1e-13, atol=1e-9)
    r_i = sol.y[:3].T
    r_e = Rotation.from_rotvec(np.outer(-t, omega)).apply(r_i)
    assert np.max(np.linalg.norm(res.position - r_e, axis=1)) < 1e-5
    # The body (zero inertial rate) turns with -Omega relative to ECEF.
    assert res.attitude[-1].magnitude() == pytest.approx(earth.OMEGA_E * t[-1], rel=1e-12)


def test_step_matches_integrate():
    traj = spinning_ascent(duration_s=5.0)
    full = strapdown.integrate(traj.t, traj.specific_force, traj.angular_rate,
                               traj.position[0], traj.velocity[0], traj.attitude[0])
    f_mid = strapdown._interpolate(traj.t, traj.specific_force, 0.5)
    w_mid = strapdown._interpolate(traj.t, traj.angular_rate, 0.5)
    state = strapdown.StrapdownState.from_trajectory(traj)
    linear = state
    for k in range(len(traj.t) - 1):
        sl = slice(k, k + 2)
        dt = traj.t[k + 1] - traj.t[k]
        state = strapdown.step(state, traj.specific_force[sl], traj.angular_rate[sl], dt,
                               f_mid=f_mid[k], w_mid=w_mid[k])
        linear = strapdown.step(linear, traj.specific_force[sl], traj.angular_rate[sl], dt)
    assert state.t == pytest.approx(traj.t[-1])
    np.testing.assert_allclose(state.position, full.position[-1], rtol=0, atol=1e-5)
    np.testing.assert_allclose(state.velocity, full.velocity[-1], rtol=0, atol=1e-6)
    assert (state.attitude.inv() * full.attitude[-1]).magnitude() < 1e-12
    # Linear mid-points are only second order: clearly worse than the cubic reconstruction.
    lin_err = np.linalg.norm(linear.position - traj.position[-1])
    cubic_err = np.linalg.norm(state.position - traj.position[-1])
    assert lin_err > 10 * cubic_err


def test_block_propagation_matches_single_run():
    """Restarting integrate() every second from its own end state (how a filter with 1 Hz
    updates propagates) costs no accuracy: one-sided cubic ends are still fourth order."""
    traj = spinning_ascent(duration_s=10.0)
    full = strapdown.integrate(traj.t, traj.specific_force, traj.angular_rate,
                               traj.position[0], traj.velocity[0], traj.attitude[0])
    state = strapdown.StrapdownState.from_trajectory(traj)
    for k0 in range(0, len(traj.t) - 1, 100):
        sl = slice(k0, k0 + 101)
        state = strapdown.integrate(traj.t[sl], traj.specific_force[sl], traj.angular_rate[sl],
                                    state.position, state.velocity, state.q_b_e).state(-1)
    assert state.t == traj.t[-1]
    np.testing.assert_allclose(state.position, full.position[-1], rtol=0, atol=2e-3)
    assert (state.attitude.inv() * full.attitude[-1]).magnitude() < 1e-7


def test_result_frame_and_state(rocket):
    res = strapdown.integrate(rocket.t[:50], rocket.specific_force[:50],
                              rocket.angular_rate[:50], rocket.position[0],
                              rocket.velocity[0], rocket.attitude[0].as_matrix())
    frame = res.to_frame()
    assert isinstance(frame, pd.DataFrame)
    assert list(frame.columns) == ["t", "x", "y", "z", "vx", "vy", "vz", "qx", "qy", "qz", "qw"]
    assert len(frame) == 50
    s = res.state(10)
    assert s.t == rocket.t[10]
    np.testing.assert_array_equal(s.position, res.position[10])
    err = strapdown.closure_error(rocket, duration_s=1.0)
    assert len(err.t) == 101
    assert list(err.to_frame().columns) == ["t", "position_error_m", "velocity_error_m_s",
                                            "attitude_error_rad"]


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"t": [0.0, 0.02, 0.01]}, "t"),
        ({"f_b": np.zeros((3, 2))}, "f_b"),
        ({"w_ib_b": np.full((3, 3), np.nan)}, "w_ib_b"),
        ({"position0": [1.0, 2.0, 3.0]}, "position0"),
        ({"velocity0": [1.0, 2.0]}, "velocity0"),
        ({"attitude0": np.ones((3, 3))}, "attitude0"),
        ({"attitude0": [0.0, 0.0, 0.0, 2.0]}, "attitude0"),
        ({"attitude0": Rotation.identity(2)}, "attitude0"),
    ],
)
def test_bad_input_names_the_argument(kwargs, name):
    args = {"t": [0.0, 0.01, 0.02], "f_b": np.zeros((3, 3)), "w_ib_b": np.zeros((3, 3)),
            "position0": [earth.A, 0.0, 0.0], "velocity0": np.zeros(3),
            "attitude0": Rotation.identity()}
    args.update(kwargs)
    with pytest.raises(NavlibInputError, match=name):
        strapdown.integrate(**args)


def test_step_bad_input():
    state = strapdown.StrapdownState(0.0, np.array([earth.A, 0, 0]), np.zeros(3),
                                     np.array([0, 0, 0, 1.0]))
    with pytest.raises(NavlibInputError, match="f_b"):
        strapdown.step(state, np.zeros(3), np.zeros((2, 3)), 0.01)
    with pytest.raises(NavlibInputError, match="dt"):
        strapdown.step(state, np.zeros((2, 3)), np.zeros((2, 3)), 0.0)
    with pytest.raises(NavlibInputError, match="duration_s"):
        strapdown.closure_error(spinning_ascent(duration_s=1.0), duration_s=0.001)
