"""Rocket descent under drogue and main (navlib.trajectory.recovery, assumption M7): the
kinematics close exactly through apogee and both deployments, the stated descent rates are
reached, the body hangs (and, if asked, swings) under the canopy, bad descent keys are
refused with their place, and the hpr_rocket example plans with a descent segment."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from navlib import NavlibInputError, earth, strapdown
from navlib.studies.plan import plan_mission
from navlib.trajectory import sounding_rocket
from navlib.trajectory.mission import from_mission, read_mission, with_values
from navlib.units import DEG

SITE = (40.88 * DEG, -119.08 * DEG)
UP = -earth.ned_to_ecef_matrix(*SITE)[:, 2]


@pytest.fixture(scope="module")
def hpr():
    return from_mission("hpr_rocket")


def _window(traj, event, before=2.0, after=3.0):
    t = traj.t
    return (t >= traj.events[event] - before) & (t <= traj.events[event] + after)


def _height(traj):
    return (traj.position - traj.position[0]) @ UP


def test_events_come_in_flight_order_at_the_stated_heights(hpr):
    ev = hpr.events
    order = ["ignition", "liftoff", "burnout", "apogee", "drogue", "main", "landing"]
    assert [ev[k] for k in order] == sorted(ev[k] for k in order)
    assert ev["drogue"] == pytest.approx(ev["apogee"] + 1.0, abs=1e-12)   # delay_s = 1
    h, t = _height(hpr), hpr.t
    v_up = hpr.velocity @ UP
    k = np.searchsorted(t, ev["apogee"])
    assert v_up[k - 1] > 0.0 >= v_up[k + 1] and h[k] == pytest.approx(h.max(), abs=0.01)
    assert np.interp(ev["main"], t, h) == pytest.approx(300.0, abs=0.01)
    assert ev["end"] == t[-1] and ev["landing"] - t[-1] < 0.01      # touchdown ends the log
    assert 0.0 < h[-1] < 6.0 * 0.01 + 1e-6                           # the last 10 ms


def test_descent_rates_are_reached_with_their_time_constants(hpr):
    ev, t = hpr.events, hpr.t
    v_up = hpr.velocity @ UP
    horizontal = np.linalg.norm(hpr.velocity - np.outer(v_up, UP), axis=1)
    steady_drogue = (t > ev["drogue"] + 12.0) & (t < ev["main"])
    np.testing.assert_allclose(v_up[steady_drogue], -25.0, atol=1e-3)
    assert horizontal[steady_drogue].max() < 1e-3
    steady_main = t > ev["main"] + 20.0
    np.testing.assert_allclose(v_up[steady_main], -6.0, atol=1e-3)
    # the main's first-order approach: 1 - 1/e of the way within about one time constant
    # (1.5 s) after its 1 s inflation half-way point
    k = np.searchsorted(t, ev["main"] + 0.5 + 1.5)
    share = (v_up[k] + 25.0) / (-6.0 + 25.0)
    assert 0.5 < share < 0.8, share


def _derivative(x, t, i):
    """Five-point central difference of samples ``x`` at indices ``i`` (regular ``t``)."""
    dt = t[1] - t[0]
    return (x[i - 2] - 8 * x[i - 1] + 8 * x[i + 1] - x[i + 2]) / (12 * dt)


def test_kinematics_close_through_apogee_and_both_deployments(hpr):
    """Velocity, specific force and gyro against differences of position, velocity and
    attitude (measured at most 1.7e-6 m/s, 1.1e-4 m/s^2 and 4.1e-6 rad per step, at the
    drogue's opening: the limits of the difference formulas, not of the IMU)."""
    t, P, V, C, w = (hpr.t, hpr.position, hpr.velocity, hpr.attitude,
                     hpr.angular_rate)
    for event in ("apogee", "drogue", "main"):
        i = np.flatnonzero(_window(hpr, event))
        fd = _derivative(P, t, i)
        assert np.abs(fd - V[i]).max() < 1e-5, event
        f_e = (_derivative(V, t, i) + 2 * np.cross(earth.EARTH_RATE_ECEF, V[i])
               - earth.normal_gravity_ecef(P[i]))
        assert np.linalg.norm(f_e - C[i].apply(hpr.specific_force[i]), axis=1).max() < 1e-3
        dt = (t[i + 1] - t[i])[:, None]
        body = Rotation.from_rotvec(0.5 * (w[i] + w[i + 1]) * dt
                                    + np.cross(w[i], w[i + 1]) * dt**2 / 12.0)
        earth_step = Rotation.from_rotvec(-dt * earth.EARTH_RATE_ECEF)
        err = ((earth_step * C[i] * body).inv() * C[i + 1]).magnitude()
        assert err.max() < 2e-5, event


def test_strapdown_closure_over_the_whole_flight(hpr):
    """The ECEF strapdown on the flight's own 100 Hz IMU, pad to touchdown (measured 4.6 cm,
    3.7 mm/s, 2.4e-5 rad over 87 s, the velocity peak a transient of the 0.1 s ignition ramp
    at lift-off; the VS30-like flight gives 7.1 cm, 1.1 mm/s over 86 s). From apogee to
    touchdown, through both deployments, the errors grow by 4.4 cm and 0.9 mm/s, and the
    attitude error stays below 1.4e-6 rad."""
    err = strapdown.closure_error(hpr)
    assert err.position_m < 0.1
    assert err.velocity_m_s < 5e-3
    assert err.attitude_rad < 1e-4
    k = np.searchsorted(hpr.t, hpr.events["apogee"])
    assert err.position_error[-1] - err.position_error[k] < 0.08
    assert abs(err.velocity_error[-1] - err.velocity_error[k]) < 2e-3
    assert err.attitude_error[k:].max() < 1e-5


def test_imu_is_smooth_after_the_boost(hpr):
    """Deployments are fast but smooth: measured 0.38 m/s^2 and 0.095 rad/s per 10 ms step
    at most, body rate 3.5 rad/s at most (the turn to hang under the drogue)."""
    after = hpr.t[1:] > hpr.events["burnout"] + 0.5
    df = np.abs(np.diff(hpr.specific_force, axis=0))[after].max()
    dw = np.abs(np.diff(hpr.angular_rate, axis=0))[after].max()
    assert df < 0.6 and dw < 0.2
    assert np.abs(hpr.angular_rate[hpr.t > hpr.events["burnout"]]).max() < 5.0


def test_body_hangs_up_the_riser_and_spins_as_stated(hpr):
    hanging = hpr.t > hpr.events["drogue"] + 0.5 + 1.0          # inflation + time constant
    x_body = hpr.attitude[hanging].apply([1.0, 0.0, 0.0])
    assert np.abs(x_body - UP).max() < 1e-9
    omega_ie_b = hpr.attitude[hanging].inv().apply(earth.EARTH_RATE_ECEF)
    spin = hpr.angular_rate[hanging] - omega_ie_b
    np.testing.assert_allclose(spin[:, 0], 2 * np.pi * 0.2, atol=1e-9)
    assert np.abs(spin[:, 1:]).max() < 1e-9
    # under the steady canopy the accelerometer reads one g up the body axis
    steady = hpr.t > hpr.events["main"] + 15.0
    g = np.linalg.norm(earth.normal_gravity_ecef(hpr.position[steady]), axis=1)
    np.testing.assert_allclose(hpr.specific_force[steady, 0], g, rtol=1e-4)


def test_swing_tilts_the_body_in_the_azimuth_plane(hpr):
    swing = from_mission(with_values("hpr_rocket", {"phase.3.swing_deg": 10.0,
                                                    "phase.3.swing_period_s": 3.0}))
    np.testing.assert_array_equal(swing.position, hpr.position)     # attitude only
    C_n_e = earth.ned_to_ecef_matrix(*SITE)
    along = C_n_e @ [np.cos(30 * DEG), np.sin(30 * DEG), 0.0]        # launch azimuth 30 deg
    across = np.cross(UP, along)
    hanging = swing.t > swing.events["drogue"] + 1.5
    x_body = swing.attitude[hanging].apply([1.0, 0.0, 0.0])
    tilt = np.arcsin(x_body @ along)
    assert np.abs(x_body @ across).max() < 1e-9
    assert np.abs(tilt).max() == pytest.approx(10 * DEG, abs=1e-4)
    phase = 2 * np.pi * (swing.t[hanging] - swing.events["drogue"]) / 3.0
    np.testing.assert_allclose(tilt, 10 * DEG * np.sin(phase), atol=1e-9)
    t, w, C = swing.t, swing.angular_rate, swing.attitude
    i = np.flatnonzero(_window(swing, "drogue"))
    dt = (t[i + 1] - t[i])[:, None]
    body = Rotation.from_rotvec(0.5 * (w[i] + w[i + 1]) * dt
                                + np.cross(w[i], w[i + 1]) * dt**2 / 12.0)
    earth_step = Rotation.from_rotvec(-dt * earth.EARTH_RATE_ECEF)
    assert ((earth_step * C[i] * body).inv() * C[i + 1]).magnitude().max() < 2e-5
    assert strapdown.closure_error(swing).attitude_rad < 1e-4


def test_landing_end_s_cuts_the_log_and_drogue_alone_lands():
    cut = from_mission(with_values("hpr_rocket", {"phase.5.end_s": 30.0}))
    assert cut.t[-1] == pytest.approx(30.0) and cut.events["end"] == cut.t[-1]
    assert "drogue" in cut.events and "main" not in cut.events
    assert "landing" not in cut.events
    table, _ = read_mission("hpr_rocket")
    table["phase"] = [p for p in table["phase"] if p["kind"] != "main"]
    drogue_only = from_mission(table)
    v_up = drogue_only.velocity @ UP
    assert "main" not in drogue_only.events and "landing" in drogue_only.events
    np.testing.assert_allclose(v_up[-100:], -25.0, atol=1e-3)


def test_without_a_drogue_nothing_changes():
    """The recovery keywords default to off: the built-in flight keeps its 86 s end and the
    sounding_rocket.toml mission still reproduces it (tests/trajectory/test_mission.py)."""
    traj = sounding_rocket()
    assert traj.t[-1] == 86.0 and "apogee" not in traj.events


def _without(*kinds):
    table, _ = read_mission("hpr_rocket")
    table["phase"] = [p for p in table["phase"] if p["kind"] not in kinds]
    return table


def _drop_key(phase, key, mission="hpr_rocket"):
    table, _ = read_mission(mission)
    del table["phase"][phase][key]
    return table


def _swap(a, b):
    table, _ = read_mission("hpr_rocket")
    table["phase"][a], table["phase"][b] = table["phase"][b], table["phase"][a]
    return table


@pytest.mark.parametrize(("mission", "words"), [
    (with_values("hpr_rocket", {"phase.3.rate_m_s": 0.0}), "phase 3 (drogue) rate_m_s"),
    (with_values("hpr_rocket", {"phase.3.rate_m_s": "slow"}),
     "phase 3 (drogue) rate_m_s: expected a number"),
    (with_values("hpr_rocket", {"phase.3.time_constant_s": -1.0}),
     "phase 3 (drogue) time_constant_s"),
    (with_values("hpr_rocket", {"phase.3.delay_s": -2.0}), "phase 3 (drogue) delay_s"),
    (with_values("hpr_rocket", {"phase.3.chute": "red"}),
     "phase 3 (drogue): unknown keyword(s) ['chute']"),
    (with_values("hpr_rocket", {"phase.4.height_m": 2000.0}),
     "phase 4 (main) height_m: main_height_m: the drogue opens at"),
    (with_values("hpr_rocket", {"phase.4.inflation_s": 0.0}), "phase 4 (main) inflation_s"),
    (with_values("hpr_rocket", {"phase.3.swing_period_s": 0.0}),
     "phase 3 (drogue) swing_period_s"),
    (with_values("hpr_rocket", {"phase.3.delay_s": 40.0}),
     "phase 3 (drogue) delay_s: drogue_delay_s: the rocket is on the ground before"),
    (with_values(_without("main"), {"phase.3.delay_s": 40.0}),
     "phase 3 (drogue) delay_s: drogue_delay_s: the rocket lands at"),
    (with_values("hpr_rocket", {"phase.0.elevation_deg": 90.0}),
     "phase 0 (rail) elevation_deg: rail_elevation_deg: the flight reaches apogee at"),
    (with_values("hpr_rocket", {"phase.2.end_s": 30.0}), "no end_s with a drogue phase"),
    (with_values("hpr_rocket", {"phase.5.end_s": -3.0}), "phase 5 (landing) end_s"),
    (with_values("hpr_rocket", {"phase.3.kind": "apogee"}), "'apogee' is not a phase"),
    (_without("drogue"), "phase 3 (main): needs a 'drogue' phase before it"),
    (_drop_key(3, "rate_m_s"), "phase 3 (drogue): missing key 'rate_m_s'"),
    (_drop_key(4, "height_m"), "phase 4 (main): missing key 'height_m'"),
    (_swap(3, 4), "phases must come in the order rail, boost, coast, drogue, main"),
    (_without("drogue", "main"), "phase 3 (landing): needs a 'drogue' phase before it"),
    (_drop_key(2, "end_s", "sounding_rocket"), "phase 2 (coast): missing key 'end_s'"),
])
def test_bad_descent_keys_name_the_place(mission, words):
    with pytest.raises(NavlibInputError) as info:
        from_mission(mission)
    assert words in str(info.value), str(info.value)


@pytest.mark.parametrize(("kwargs", "words"), [
    ({"main_rate_mps": 5.0}, "main_rate_mps: needs a drogue"),
    ({"drogue_rate_mps": 20.0, "main_height_m": 300.0}, "main_height_m: a main parachute"),
    ({"drogue_rate_mps": 20.0, "drogue_tau_s": 0.0}, "drogue_tau_s"),
    ({"drogue_rate_mps": 20.0, "canopy_swing_deg": 50.0}, "canopy_swing_deg"),
    ({"canopy_swing_deg": 5.0}, "canopy_swing_deg: needs a drogue"),
])
def test_bad_recovery_keywords_of_the_generator(kwargs, words):
    with pytest.raises(NavlibInputError, match=words):
        sounding_rocket(**kwargs)


def test_hpr_rocket_plans_with_a_descent_segment():
    plan = plan_mission("hpr_rocket")
    summary = plan.summary()
    phases = list(summary["phase"])
    assert phases[0] == "pad" and "boost" in phases and phases[-1] == "descent"
    descent = summary[summary["phase"] == "descent"].iloc[0]
    apogee = plan.trajectory.events["apogee"]
    assert abs(descent["t_start"] - apogee) < 1.0
    assert descent["t_end"] > plan.trajectory.events["main"]
