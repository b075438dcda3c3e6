"""Mission files (navlib.trajectory.mission): the rocket mission reproduces the built-in
sounding rocket; waypoint missions satisfy the ECEF kinematics with smooth IMU signals and
keep their stated limits; bad files name the key, phase or waypoint."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from navlib import NavlibInputError, earth, strapdown
from navlib.trajectory import sounding_rocket
from navlib.trajectory.mission import (
    MISSION_DIR,
    from_mission,
    list_missions,
    load_mission,
    read_mission,
    with_values,
)
from navlib.units import DEG, G0

WAYPOINT_MISSIONS = ("multicopter_survey", "fixed_wing_survey", "ground_vehicle")


def test_examples_cover_every_vehicle_class():
    vehicles = {load_mission(name).vehicle for name in list_missions()}
    assert vehicles == {"rocket", "multicopter", "fixed-wing", "ground"}
    assert (MISSION_DIR / "sounding_rocket.toml").is_file()


def _compare(a, b):
    return {"position_m": np.abs(a.position - b.position).max(),
            "velocity_mps": np.abs(a.velocity - b.velocity).max(),
            "attitude_rad": (a.attitude.inv() * b.attitude).magnitude().max(),
            "specific_force_mps2": np.abs(a.specific_force - b.specific_force).max(),
            "angular_rate_rad_s": np.abs(a.angular_rate - b.angular_rate).max()}


# stated tolerances: the mission file writes the generator's defaults (thrust 81510 N is
# 1.14 * 110 * 650 up to the last bit), so both build the same flight to rounding
TOLERANCES = {"position_m": 1e-6, "velocity_mps": 1e-8, "attitude_rad": 1e-9,
              "specific_force_mps2": 1e-8, "angular_rate_rad_s": 1e-9}


def test_rocket_mission_reproduces_sounding_rocket():
    reference = sounding_rocket()
    planned = from_mission("sounding_rocket")
    np.testing.assert_array_equal(planned.t, reference.t)
    assert {k: planned.events[k] for k in reference.events} == pytest.approx(reference.events)
    errors = _compare(planned, reference)
    assert all(errors[k] <= TOLERANCES[k] for k in TOLERANCES), errors


def test_rocket_thrust_as_acceleration_gives_the_same_flight():
    table, _ = read_mission("sounding_rocket")
    boost = table["phase"][1]
    boost["acceleration_m_s2"] = boost.pop("thrust_n") / table["rocket"]["mass_burnout_kg"]
    errors = _compare(from_mission(table), sounding_rocket())
    assert errors["position_m"] < 1e-3 and errors["specific_force_mps2"] < 1e-6, errors


def test_rocket_mission_changes_reach_the_generator():
    slow = from_mission(with_values("sounding_rocket", {"rocket.spin_hz": 1.0}))
    spin = slow.angular_rate[(slow.t > 60) & (slow.t < 70), 0]
    reference = sounding_rocket(spin_hz=1.0).angular_rate[(slow.t > 60) & (slow.t < 70), 0]
    np.testing.assert_allclose(spin, reference, rtol=0, atol=1e-12)
    no_despin = dict(read_mission("sounding_rocket")[0])
    no_despin["phase"] = no_despin["phase"][:3]
    traj = from_mission(no_despin)
    w = traj.angular_rate[:, 0]
    before, after = w[(traj.t > 68) & (traj.t < 70)], w[(traj.t > 76) & (traj.t < 78)]
    assert abs(np.median(after) / np.median(before) - 1.0) < 0.02   # spin kept


@pytest.fixture(scope="module", params=WAYPOINT_MISSIONS)
def waypoint_traj(request):
    return request.param, from_mission(request.param)


def test_waypoint_velocity_matches_position_differences(waypoint_traj):
    _, traj = waypoint_traj
    t, P, V = traj.t, traj.position, traj.velocity
    fd = (P[2:] - P[:-2]) / (t[2:] - t[:-2])[:, None]
    assert np.abs(fd - V[1:-1]).max() < 1e-3


def test_waypoint_specific_force_matches_velocity_differences(waypoint_traj):
    _, traj = waypoint_traj
    t, P, V = traj.t, traj.position, traj.velocity
    dv = (V[2:] - V[:-2]) / (t[2:] - t[:-2])[:, None]
    f_e = dv + 2 * np.cross(earth.EARTH_RATE_ECEF, V[1:-1]) - earth.normal_gravity_ecef(P[1:-1])
    f_e_imu = traj.attitude[1:-1].apply(traj.specific_force[1:-1])
    assert np.linalg.norm(f_e - f_e_imu, axis=1).max() < 5e-3


def test_waypoint_attitude_increments_match_gyro(waypoint_traj):
    _, traj = waypoint_traj
    t, w, C = traj.t, traj.angular_rate, traj.attitude
    dt = np.diff(t)[:, None]
    body = Rotation.from_rotvec(0.5 * (w[:-1] + w[1:]) * dt
                                + np.cross(w[:-1], w[1:]) * dt**2 / 12.0)
    earth_step = Rotation.from_rotvec(-dt * earth.EARTH_RATE_ECEF)
    err = ((earth_step * C[:-1] * body).inv() * C[1:]).magnitude()
    assert err.max() < 1e-6


def test_waypoint_strapdown_closure(waypoint_traj):
    """The ECEF strapdown integrating the mission's own IMU at 50 Hz reproduces it (the
    closure of tests/strapdown/test_strapdown.py; measured 1.2 mm, 1.9 mm and 0.4 um)."""
    _, traj = waypoint_traj
    err = strapdown.closure_error(traj)
    assert err.position_m < 0.01
    assert err.velocity_m_s < 1e-3
    assert err.attitude_rad < 1e-5


def test_waypoint_imu_is_smooth(waypoint_traj):
    """No jumps: a sample-to-sample change stays far below the manoeuvre's own size."""
    _, traj = waypoint_traj
    df = np.abs(np.diff(traj.specific_force, axis=0)).max()
    dw = np.abs(np.diff(traj.angular_rate, axis=0)).max()
    assert df < 0.2          # m/s^2 per 20 ms step; turns and stops reach 2-6 m/s^2
    assert dw < 0.02         # rad/s per step; turns reach 0.4-0.9 rad/s


def test_multicopter_stops_and_hovers_on_its_waypoints():
    traj = from_mission("multicopter_survey")
    mission = load_mission("multicopter_survey")
    speed = np.linalg.norm(traj.velocity, axis=1)
    assert np.all(speed[traj.t < 5.0] == 0.0)              # 5 s on the ground first
    C_n_e = earth.ned_to_ecef_matrix(47.397742 * DEG, 8.545594 * DEG)
    local = (traj.position - traj.position[0]) @ C_n_e
    # the stop blend ends 3.28 s after the nominal passage (6 m/s at 2 m/s^2), then 5 s hover
    hover = (traj.t > traj.events["waypoint 3"] + 3.5) & (traj.t < traj.events["waypoint 3"]
                                                            + 8.0)
    np.testing.assert_allclose(local[hover], [[120.0, 60.0, -30.0]] * hover.sum(), atol=1e-6)
    assert mission.outages == ((48.0, 63.0),)


def test_fixed_wing_bank_and_ground_turn_radius_stay_within_limits():
    fw = from_mission("fixed_wing_survey")
    lat, lon, _ = fw.geodetic
    C_n_e = earth.ned_to_ecef_matrix(lat[0], lon[0])
    roll = Rotation.from_matrix(C_n_e.T @ fw.C_b_e()).as_euler("ZYX")[:, 2]
    assert 20 * DEG < np.abs(roll).max() <= 30 * DEG + 1e-6
    ground = from_mission("ground_vehicle")
    v = np.linalg.norm(ground.velocity, axis=1)
    a_lat = np.linalg.norm(np.cross(ground.velocity, np.gradient(ground.velocity, ground.t,
                                                                 axis=0)), axis=1)
    moving = v > 1.0
    radius = v[moving] ** 2 / np.maximum(a_lat[moving] / v[moving], 1e-12)
    assert radius.min() > 10.0 * 0.99
    assert np.abs(fw.specific_force[:, 2]).max() < G0 / np.cos(30 * DEG) + 2.5


@pytest.mark.parametrize(("mission", "changes", "words"), [
    ("sounding_rocket", {"vehicle": "boat"}, "vehicle: expected one of"),
    ("sounding_rocket", {"phase.1.burn_time_s": -1.0}, "phase 1 (boost) burn_time_s"),
    ("sounding_rocket", {"phase.1.acceleration_m_s2": 100.0}, "exactly one of"),
    ("sounding_rocket", {"phase.2.kind": "parafoil"}, "phase 2: kind 'parafoil'"),
    ("sounding_rocket", {"phase.3.at_s": 90.0}, "phase 3 (despin) at_s"),
    ("sounding_rocket", {"rocket.mass_kg": 3.0}, "[rocket]: unknown keyword(s) ['mass_kg']"),
    ("sounding_rocket", {"gnss.outages": [[10.0, 5.0]]}, "outages[0] end_s"),
    ("multicopter_survey", {"waypoint.2.speed_m_s": "fast"}, "waypoint 2 speed_m_s"),
    ("multicopter_survey", {"waypoint.1.hold_s": 3.0}, "waypoint 1: unknown keyword(s)"),
    ("multicopter_survey", {"waypoint.0.speed_m_s": 3.0}, "waypoint 0: speed_m_s"),
    ("ground_vehicle", {"waypoint.2.east_m": 5.0}, "waypoint 2: the leg from waypoint 1"),
    ("fixed_wing_survey", {"limits.bank_limit_deg": 5.0}, "too short for the manoeuvres"),
    ("fixed_wing_survey", {"waypoint.2.north_m": -200.0, "waypoint.2.east_m": 1.0},
     "turns by"),
    ("ground_vehicle", {"site.lat_deg": 95.0}, "[site] lat_deg"),
])
def test_bad_missions_name_the_place(mission, changes, words):
    with pytest.raises(NavlibInputError) as info:
        from_mission(with_values(mission, changes))
    assert words in str(info.value), str(info.value)


def test_bad_mission_file_names_the_file(tmp_path):
    bad = tmp_path / "broken.toml"
    bad.write_text("vehicle = 'ground'\n[site\n", encoding="utf-8")
    with pytest.raises(NavlibInputError, match=r"broken\.toml: not valid TOML"):
        from_mission(bad)
    with pytest.raises(NavlibInputError, match="unknown example mission"):
        from_mission("no_such_mission")
