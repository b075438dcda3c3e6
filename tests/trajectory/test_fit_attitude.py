"""The flight fit's attitude on SO(3) and its start without a long rest.

Generated flights whose attitudes have no regular yaw/pitch/roll form in any fixed frame
(a vertical ascent followed by a tumble and a swinging, spinning parachute descent; two
loops) must be fitted with an exact IMU, and a rocket record must start from a 0.3 s
pre-launch window, from the logger's tilt or from the launch-rail angles the user gives.
"""

import re
import warnings

import numpy as np
import pandas as pd
import pytest
from scipy.interpolate import make_interp_spline
from scipy.spatial.transform import Rotation
from support.flights import exact_records

from navlib import NavlibInputError, earth, strapdown
from navlib.studies.assess import assess_flight
from navlib.trajectory import fit_flight_data, initial_attitude, position_spline
from navlib.trajectory._attitude import smoothstep, zyx_attitude
from navlib.trajectory._so3 import SO3Spline
from navlib.trajectory.base import build_trajectory

LAT, LON, ALT = np.radians(32.94), np.radians(-106.91), 1400.0
C_N_E = earth.ned_to_ecef_matrix(LAT, LON)


def _step(t, start, duration):
    return smoothstep((t - start) / duration)[0]


def _integral(t, y):
    """Cumulative trapezoid of samples ``y`` (M, ...) on ``t``, starting at 0."""
    inc = 0.5 * (y[1:] + y[:-1]) * np.diff(t).reshape(-1, *([1] * (y.ndim - 1)))
    return np.concatenate([np.zeros((1, *y.shape[1:])), np.cumsum(inc, axis=0)])


def _flight(t_end, velocity_ned, euler_rates, euler0, rate_hz=100.0, name="generated"):
    """Exact trajectory from NED velocity and yaw/pitch/roll rates (callables of t).

    Position and angles are integrated on a fine grid and interpolated by quintic splines;
    the IMU follows from the splines (:func:`build_trajectory`), so it is exact for them.
    The yaw/pitch/roll form only generates the truth: it is regular as a forward map even
    where pitch passes +-90 deg.
    """
    fine = np.linspace(0.0, t_end + 0.5, int((t_end + 0.5) * 1000) + 1)
    ned = _integral(fine, velocity_ned(fine))
    ang = np.asarray(euler0) + _integral(fine, euler_rates(fine))
    grid = fine[::20]
    pos, att = make_interp_spline(grid, ned[::20], k=5), make_interp_spline(grid, ang[::20], k=5)
    t = np.arange(round(t_end * rate_hz) + 1) / rate_hz
    P0 = earth.geodetic_to_ecef(LAT, LON, ALT)
    a, da = att(t), att(t, 1)
    C_b_e, w_eb_b = zyx_attitude(C_N_E, a[:, 0], a[:, 1], a[:, 2], da[:, 0], da[:, 1],
                                 da[:, 2])
    return build_trajectory(t, P0 + pos(t) @ C_N_E.T, pos(t, 1) @ C_N_E.T,
                            pos(t, 2) @ C_N_E.T, C_b_e, w_eb_b, name=name)


def rocket_with_parachute():
    """Vertical boost from the pad at 2 s (body x up, 1 rev/s spin), coast to apogee at
    ~12 s, a tumble through 150 deg of pitch, then a parachute descent at 8 m/s drifting
    with the wind, swinging +-20 deg at 0.5 Hz and spinning slowly about the vertical."""
    def velocity(t):
        up = 80.0 * _step(t, 2.0, 2.0) - 88.0 * _step(t, 4.0, 11.0)
        drift = _step(t, 12.0, 4.0)
        return np.column_stack([1.0 * drift, 3.0 * drift, -up])

    def rates(t):
        spin = 2.0 * np.pi * _step(t, 2.0, 2.0) * (1.0 - _step(t, 8.0, 3.0))
        flip = -150.0 * np.radians(1.0) / 3.0 * smoothstep((t - 12.0) / 3.0)[1]
        swing = np.radians(20.0) * np.pi * np.cos(np.pi * (t - 15.0)) * _step(t, 14.0, 2.0)
        yaw = 0.5 * _step(t, 14.0, 2.0)
        return np.column_stack([yaw, flip + swing, spin])

    return _flight(30.0, velocity, rates, [0.3, np.pi / 2, 0.0], name="rocket + parachute")


def looping_flight():
    """An aircraft at 50 m/s flies two loops of 60 m radius: the pitch turns through 720
    deg, passing the vertical four times, with a small roll wobble."""
    def pitch_rate(t):
        return 50.0 / 60.0 * _step(t, 2.0, 1.0) * (1.0 - _step(t, 2.0 + 4 * np.pi * 1.2, 1.0))

    def velocity(t):
        alpha = _integral(t, pitch_rate(t))
        return 50.0 * np.column_stack([np.cos(alpha), np.zeros_like(t), -np.sin(alpha)])

    def rates(t):
        return np.column_stack([np.zeros_like(t), pitch_rate(t), 0.2 * np.cos(t)])

    return _flight(22.0, velocity, rates, [0.0, 0.0, 0.0], name="two loops")


def rail_rocket(rest_s, roll_deg=0.0, pitch_over_deg=0.0):
    """A rocket on a rail at 85 deg elevation, 120 deg azimuth, resting ``rest_s`` before a
    2 s boost at 60 m/s^2 (reached in 0.05 s) along the rail, then decelerating, with a
    spin-up to 2 rev/s; ``roll_deg`` about the body x axis on the rail (0: body y
    horizontal) and a pitch-over by ``pitch_over_deg`` between 3 and 8 s after launch."""
    elevation, azimuth = np.radians(85.0), np.radians(120.0)
    u = np.array([np.cos(elevation) * np.cos(azimuth), np.cos(elevation) * np.sin(azimuth),
                  -np.sin(elevation)])

    def velocity(t):
        thrust = 60.0 * _step(t, rest_s, 0.05) * (1.0 - _step(t, rest_s + 2.0, 0.2))
        return _integral(t, thrust - 12.0 * _step(t, rest_s + 2.0, 0.5))[:, None] * u

    def rates(t):
        spin = 4.0 * np.pi * _step(t, rest_s + 0.5, 2.0)
        pitch = -np.radians(pitch_over_deg) / 5.0 * smoothstep((t - rest_s - 3.0) / 5.0)[1]
        return np.column_stack([np.zeros_like(t), pitch, spin])

    return _flight(rest_s + 10.0, velocity, rates, [azimuth, elevation, np.radians(roll_deg)],
                   name="rail")


def _records(traj, **kw):
    return exact_records(traj, **{"gnss_hz": 5.0, "seed": 3, **kw})


def _euler_deg(traj, k=0):
    """Yaw, pitch, roll (deg) of the body against NED at sample ``k``."""
    C_b_n = C_N_E.T @ traj.attitude[k].as_matrix()
    with warnings.catch_warnings():     # pitch 90 deg: scipy warns, the angles stay exact
        warnings.simplefilter("ignore", UserWarning)
        return np.degrees(Rotation.from_matrix(C_b_n).as_euler("ZYX"))


def _compare(fit, truth):
    """Attitude, position, rate and specific-force errors against ``truth`` at the fit's
    samples (the fit spans the overlap of the IMU and GNSS records)."""
    k = np.searchsorted(truth.t, fit.t)
    assert np.array_equal(truth.t[k], fit.t)
    att = (fit.attitude.inv() * truth.attitude[k]).magnitude()
    d_p = np.linalg.norm(fit.position - truth.position[k], axis=1)
    d_w = np.linalg.norm(fit.angular_rate - truth.angular_rate[k], axis=1)
    d_f = np.linalg.norm(fit.specific_force - truth.specific_force[k], axis=1)
    return att, d_p, d_w, d_f


# --- the spline itself ---------------------------------------------------------------------

def test_so3_spline_holds_a_steady_spin_exactly_and_its_rates_are_derivatives():
    t = np.linspace(0.0, 4.0, 401)
    axis = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    start = Rotation.from_rotvec([0.4, 1.2, -0.3])
    spin = start * Rotation.from_rotvec(np.outer(7.0 * t, axis))     # 7 rad/s, 28 rad
    knots = position_spline.place_knots(t, 0.1)
    spline = SO3Spline.fit(t, spin, knots, 5)
    C, w = spline.evaluate(t)
    assert (Rotation.from_matrix(C).inv() * spin).magnitude().max() < 1e-9
    np.testing.assert_allclose(w, np.tile(7.0 * axis, (t.size, 1)), atol=1e-8)
    # a general motion: omega and alpha against central differences of C and omega
    wobble = spin * Rotation.from_rotvec(np.column_stack([np.sin(3 * t), np.cos(2 * t), t]))
    spline = SO3Spline.fit(t, wobble, knots, 5)
    tm, h = np.linspace(0.3, 3.7, 50), 1e-5
    C_m, w_m, a_m = spline.evaluate(tm, order=2)
    C_p, w_p = spline.evaluate(tm + h)
    C_q, w_q = spline.evaluate(tm - h)
    S = np.swapaxes(C_m, 1, 2) @ (C_p - C_q) / (2 * h)          # C^T dC/dt = S(omega)
    w_num = np.stack([S[:, 2, 1], S[:, 0, 2], S[:, 1, 0]], axis=1)
    np.testing.assert_allclose(w_m, w_num, atol=1e-6)
    np.testing.assert_allclose(a_m, (w_p - w_q) / (2 * h), atol=1e-4)


# --- attitudes with no regular yaw/pitch/roll form -------------------------------------------

@pytest.mark.parametrize("make", [rocket_with_parachute, looping_flight])
def test_fit_follows_vertical_tumbling_and_looping_attitudes(make):
    truth = make()
    imu, gnss = _records(truth)
    fit = fit_flight_data(imu, gnss, initial_attitude_deg=_euler_deg(truth),
                          sigma_position_m=0.01, knot_spacing_s=0.05)
    res = fit.parameters["fit_residuals"]
    assert res["initial_attitude_source"] == "user"
    att, d_p, d_w, d_f = _compare(fit, truth)
    assert att.max() < 1e-3 and np.median(att) < 1e-4
    assert d_p.max() < 0.05
    assert np.median(d_w) < 1e-4 and d_w.max() < 0.02
    assert np.median(d_f) < 0.01
    # the kinematics of the fitted trajectory close (the bounds of the rocket's closure in
    # test_strapdown and test_fit_flight_data)
    closure = strapdown.closure_error(fit)
    assert closure.position_m < 1.0 and closure.attitude_rad < 1e-4
    assert closure.velocity_m_s < 0.05


def test_vertical_rocket_is_levelled_and_its_heading_estimated():
    """Body x exactly vertical on the pad: levelling keeps the tilt exact and the heading
    (a turn about the vertical) comes from the parachute drift the GNSS sees."""
    truth = rocket_with_parachute()
    imu, gnss = _records(truth)
    fit = fit_flight_data(imu, gnss, sigma_position_m=0.01)
    res = fit.parameters["fit_residuals"]
    assert res["initial_attitude_source"] == "level" and res["heading_source"] == "estimated"
    att, d_p, _, _ = _compare(fit, truth)
    assert att.max() < 2e-4 and d_p.max() < 0.01


def test_noisy_tumbling_descent_residuals_at_noise_level():
    truth = rocket_with_parachute()
    sigma_f, sigma_w = 0.05, 2e-3
    imu, gnss = _records(truth, sigma_f=sigma_f, sigma_w=sigma_w)
    fit = fit_flight_data(imu, gnss, initial_attitude_deg=_euler_deg(truth),
                          sigma_position_m=0.5)
    res = fit.parameters["fit_residuals"]
    for value in res["angular_rate_rms_rad_s"]:
        assert 0.7 * sigma_w < value < 1.3 * sigma_w
    att, d_p, _, _ = _compare(fit, truth)
    assert np.median(att) < 0.01 and d_p.max() < 1.0


# --- starting without a long rest -------------------------------------------------------------

def test_minimum_levelling_window_follows_the_preset_noise():
    # a MEMS IMU at 100 Hz reaches 0.1 deg with the 10-sample floor: 0.1 s
    assert initial_attitude.min_level_s("pixhawk_mems", 100.0, 0.1) == pytest.approx(0.1)
    # a ten times tighter tilt needs a hundred times more samples once above the floor
    long_ = initial_attitude.min_level_s("pixhawk_mems", 100.0, 0.001)
    longer = initial_attitude.min_level_s("pixhawk_mems", 100.0, 0.0001)
    assert long_ > 0.1 and longer / long_ == pytest.approx(100.0, rel=0.01)


def test_short_pre_launch_window_levels_the_start():
    truth = rail_rocket(rest_s=0.3)
    imu, gnss = _records(truth, sigma_f=0.02, sigma_w=2e-4)
    with pytest.raises(NavlibInputError, match="level_s=1"):
        fit_flight_data(imu, gnss, preset="pixhawk_mems", launch_azimuth_deg=120.0, level_s=1.0,
                        level_tilt_deg=1e-3)
    fit = fit_flight_data(imu, gnss, preset="pixhawk_mems", launch_azimuth_deg=120.0)
    res = fit.parameters["fit_residuals"]
    assert res["initial_attitude_source"] == "level"
    assert res["level"]["short"] and 0.25 <= res["level"]["window_s"] <= 0.3
    assert re.match(r"levelled from 0\.(2[5-9]|30) s pre-launch window",
                    res["initial_attitude_note"])
    assert res["heading_deg"] == pytest.approx(120.0, abs=0.5)
    att, d_p, _, _ = _compare(fit, truth)
    # within what the accelerometer-bias prior of the preset (0.1 m/s^2: 0.6 deg) leaves
    assert att[0] < np.radians(0.6) and np.median(att) < np.radians(0.6)
    assert d_p.max() < 0.5


def test_logger_tilt_starts_a_record_in_flight():
    truth = rail_rocket(rest_s=0.3)
    imu, gnss = _records(truth)
    imu = imu[imu.t >= 1.0].reset_index(drop=True)       # in the boost: no rest at all
    gnss = gnss[gnss.t >= 1.0]
    with pytest.raises(NavlibInputError, match="launch_elevation_deg"):
        fit_flight_data(imu, gnss, launch_azimuth_deg=120.0)
    imu.attrs["tilt"] = pd.DataFrame({"t": truth.t[::10], "tilt": np.radians(5.0)})
    fit = fit_flight_data(imu, gnss, launch_azimuth_deg=120.0, sigma_position_m=0.01)
    res = fit.parameters["fit_residuals"]
    assert res["initial_attitude_source"] == "tilt"
    note = re.fullmatch(r"logger tilt \(5\.0 deg from vertical\), azimuth 120 deg given, "
                        r"roll about body x estimated from GNSS \((-?[\d.]+) deg\)",
                        res["initial_attitude_note"])
    assert abs(float(note.group(1))) < 1.0                  # the truth has body y horizontal
    att, d_p, _, _ = _compare(fit, truth)
    assert att.max() < 1e-3 and d_p.max() < 0.05


def test_launch_rail_angles_start_a_record_in_flight():
    truth = rail_rocket(rest_s=0.3)
    imu, gnss = _records(truth)
    imu, gnss = imu[imu.t >= 1.0], gnss[gnss.t >= 1.0]
    fit = fit_flight_data(imu, gnss, launch_elevation_deg=85.0, launch_azimuth_deg=120.0,
                          sigma_position_m=0.01)
    res = fit.parameters["fit_residuals"]
    assert res["initial_attitude_source"] == "rail"
    assert res["initial_attitude_note"].startswith("launch rail 85 deg elevation, azimuth 120")
    att, d_p, _, _ = _compare(fit, truth)
    assert att.max() < 1e-3 and d_p.max() < 0.05


def test_a_launch_elevation_outranked_by_levelling_is_named_not_ignored():
    truth = rail_rocket(rest_s=2.0)
    imu, gnss = _records(truth, sigma_f=0.02, sigma_w=2e-4)
    with pytest.warns(Warning, match=r"launch_elevation_deg=80 not used: the initial attitude "
                                     r"came from levelled .* body-x elevation is 85\.\d deg "
                                     r"\(\+5\.\d deg from the flag\)"):
        fit = fit_flight_data(imu, gnss, preset="pixhawk_mems", launch_elevation_deg=80.0,
                              launch_azimuth_deg=120.0)
    res = fit.parameters["fit_residuals"]
    assert res["initial_attitude_source"] == "level"
    assert "launch_elevation_deg=80 not used" in res["initial_attitude_note"]
    # the flag is used when nothing outranks it: no warning then
    late = imu[imu.t >= 3.0].reset_index(drop=True)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fit = fit_flight_data(late, gnss[gnss.t >= 3.0], preset="pixhawk_mems",
                              launch_elevation_deg=85.0, launch_azimuth_deg=120.0)
    assert fit.parameters["fit_residuals"]["initial_attitude_source"] == "rail"


def test_roll_on_the_rail_is_estimated_once_the_rocket_pitches_over():
    """The rail gives the body x axis; the roll about it shows once that axis turns away
    from the specific force (a 20 deg pitch-over), and the GNSS fixes it."""
    truth = rail_rocket(rest_s=0.3, roll_deg=30.0, pitch_over_deg=20.0)
    imu, gnss = _records(truth)
    imu, gnss = imu[imu.t >= 1.0], gnss[gnss.t >= 1.0]
    fit = fit_flight_data(imu, gnss, launch_elevation_deg=85.0, launch_azimuth_deg=120.0,
                          sigma_position_m=0.01)
    note = fit.parameters["fit_residuals"]["initial_attitude_note"]
    roll = float(re.search(r"roll about body x estimated from GNSS \((-?[\d.]+) deg\)",
                           note).group(1))
    assert roll == pytest.approx(30.0, abs=2.0)
    att, d_p, _, _ = _compare(fit, truth)
    assert np.degrees(att.max()) < 0.5 and d_p.max() < 0.05


@pytest.mark.parametrize("options, match", [
    ({"launch_elevation_deg": 95.0}, "launch_elevation_deg"),
    ({"launch_azimuth_deg": 10.0, "heading_deg": 20.0}, "launch_azimuth_deg"),
    ({"initial_attitude_deg": (1.0, 2.0)}, "initial_attitude_deg"),
    ({"initial_attitude_deg": (1.0, 2.0, 3.0), "initial_attitude": np.eye(3)},
     "initial_attitude_deg"),
    ({"level_tilt_deg": 0.0}, "level_tilt_deg"),
])
def test_bad_start_options(options, match):
    imu, gnss = _records(rail_rocket(rest_s=0.3))
    with pytest.raises(NavlibInputError, match=match):
        fit_flight_data(imu, gnss, **options)


def test_assessment_notes_name_the_initial_attitude_source():
    truth = rail_rocket(rest_s=0.3)
    imu, gnss = _records(truth, sigma_f=0.02, sigma_w=2e-4)
    result = assess_flight(imu, gnss, preset="pixhawk_mems",
                           fit_options={"launch_azimuth_deg": 120.0})
    assert any(re.match(r"initial attitude: levelled from 0\.(2[5-9]|30) s pre-launch window", n)
               for n in result.notes)
    imu, gnss = imu[imu.t >= 1.0], gnss[gnss.t >= 1.0]
    result = assess_flight(imu, gnss, preset="pixhawk_mems", fit_options={
        "launch_elevation_deg": 85.0, "launch_azimuth_deg": 120.0})
    assert any(n.startswith("initial attitude: launch rail 85 deg elevation, azimuth 120 deg "
                            "given") for n in result.notes)
