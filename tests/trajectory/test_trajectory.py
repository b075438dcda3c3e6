"""Trajectory generators: paper event markers, pad statics, and construction-independent
consistency checks (finite differences of position, attitude increments vs gyro)."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from navlib import NavlibInputError, earth
from navlib.trajectory import launcher_ascent, sounding_rocket, stationary
from navlib.units import DEG


@pytest.fixture(scope="module")
def rocket():
    return sounding_rocket()


def _at(traj, t):
    return int(np.argmin(np.abs(traj.t - t)))


# --- attitude building blocks ----------------------------------------------------------

def test_zyx_body_rate_matches_matrix_derivative():
    """S(omega) = C^T dC/dt for C = Rz(psi) Ry(theta) Rx(phi), by central differences."""
    from navlib.rotations import unskew
    from navlib.trajectory._attitude import zyx_body_rate, zyx_matrix

    rng = np.random.default_rng(3)
    angles = rng.uniform(-1.4, 1.4, (50, 3))
    rates = rng.normal(size=(50, 3))
    h = 1e-6
    C_plus = zyx_matrix(*(angles + h * rates).T)
    C_minus = zyx_matrix(*(angles - h * rates).T)
    dC = (C_plus - C_minus) / (2 * h)
    C = zyx_matrix(*angles.T)
    w_fd = unskew(np.swapaxes(C, 1, 2) @ dC)
    w = zyx_body_rate(angles[:, 1], angles[:, 2], rates[:, 0], rates[:, 1], rates[:, 2])
    assert np.allclose(w, w_fd, atol=1e-8)
    ref = Rotation.from_euler("ZYX", angles).as_matrix()
    assert np.allclose(C, ref, atol=1e-14)


def test_smoothstep_is_c3_ramp():
    from navlib.trajectory._attitude import smoothstep

    x = np.linspace(-0.5, 1.5, 2001)
    s, ds, d2s = smoothstep(x)
    assert s[0] == 0.0 and s[-1] == 1.0 and np.all(np.diff(s) >= 0)
    assert np.allclose(np.gradient(s, x), ds, atol=2e-3)
    assert np.allclose(np.gradient(ds, x), d2s, atol=5e-2)
    assert smoothstep(0.5)[0] == pytest.approx(0.5)
    assert smoothstep(0.0)[2] == 0.0 and smoothstep(1.0)[2] == 0.0


# --- sounding rocket: paper magnitudes (spec excitability.md §3) -------------------------

def test_rocket_sampling_and_events(rocket):
    assert rocket.t[0] == 0.0 and rocket.t[-1] == pytest.approx(86.0)
    assert rocket.rate_hz == pytest.approx(100.0)
    assert np.allclose(np.diff(rocket.t), 0.01)
    ev = rocket.events
    for name, value in [("ignition", 18.0), ("burnout", 46.0), ("free_flight", 60.0),
                        ("despin", 73.0), ("end", 86.0)]:
        assert ev[name] == value
    assert 18.0 < ev["liftoff"] < ev["rail_exit"] < 20.0


def test_rocket_peak_axial_specific_force_near_burnout(rocket):
    f_x = rocket.specific_force[:, 0]
    k = int(np.argmax(f_x))
    assert f_x[k] == pytest.approx(110.0, rel=0.03)
    assert 44.0 <= rocket.t[k] <= 46.0


def test_rocket_axial_force_changes_sign_at_burnout(rocket):
    f_x = rocket.specific_force[:, 0]
    boost = (rocket.t > 19.0) & (rocket.t < 45.0)
    assert np.all(f_x[boost] > 40.0)
    crossing = rocket.t[np.flatnonzero((f_x[:-1] > 0) & (f_x[1:] <= 0))]
    crossing = crossing[crossing > 19.0]
    assert crossing.size == 1 and 45.0 < crossing[0] <= 46.0
    coast = (rocket.t >= 46.0) & (rocket.t < 55.0)
    assert np.all(f_x[coast] < 0.0)
    assert -15.0 < f_x[_at(rocket, 46.0)] < -5.0


def test_rocket_free_flight_above_40_km(rocket):
    free = rocket.t >= 60.0
    assert np.linalg.norm(rocket.specific_force[free], axis=1).max() < 0.5
    _, _, alt = rocket.geodetic
    assert alt[_at(rocket, 60.0)] > 40e3
    assert np.all(np.diff(alt[rocket.t > 18.5]) > 0)  # still climbing at 86 s


def test_rocket_despin_halves_axial_rate(rocket):
    w_x = rocket.angular_rate[:, 0]
    before, after = w_x[_at(rocket, 72.0)], w_x[_at(rocket, 74.0)]
    assert after / before == pytest.approx(0.5, rel=1e-3)
    assert before == pytest.approx(2 * np.pi * 2.0, rel=1e-3)
    # the step is smooth: its steepest slope is that of the C^3 ramp (35/16 x step / 0.5 s)
    window = (rocket.t[1:] > 72.0) & (rocket.t[1:] < 74.0)
    max_slope = 35.0 / 16.0 * (before - after) / 0.5
    assert np.abs(np.diff(w_x) / 0.01)[window].max() < 1.02 * max_slope


def test_rocket_spin_ramps_with_speed(rocket):
    w_x = rocket.angular_rate[:, 0]
    speed = np.linalg.norm(rocket.velocity, axis=1)
    boost = (rocket.t > 18.5) & (rocket.t < 30.0)
    assert np.all(np.diff(w_x[boost]) > -1e-6)
    assert np.all(np.diff(speed[boost]) > 0)
    assert w_x[_at(rocket, 19.0)] < 0.2 * w_x[_at(rocket, 40.0)]


def test_rocket_spin_does_not_steer_the_flight_path(monkeypatch):
    """The spin, de-spin and output rate leave the integrated path as it is (SPIN_KEYS):
    a new spin reuses it, and gives the same trajectory as a path integrated afresh,
    bit for bit; a keyword outside SPIN_KEYS (the site) integrates a new one."""
    from navlib.trajectory import rocket as rocket_module

    monkeypatch.setenv("NAVLIB_NO_CACHE", "1")  # every call builds (no disk cache)
    path = rocket_module._flight_path
    sounding_rocket()
    before = path.cache_info()
    spun = sounding_rocket(spin_hz=3.1, despin_s=74.0, rate_hz=50.0)
    after = path.cache_info()
    assert (after.hits, after.misses) == (before.hits + 1, before.misses)
    path.cache_clear()
    fresh = sounding_rocket(spin_hz=3.1, despin_s=74.0, rate_hz=50.0)
    sounding_rocket(alt_m=629.0)
    assert path.cache_info().misses == 2
    for name in ("t", "position", "velocity", "specific_force", "angular_rate"):
        assert np.array_equal(getattr(spun, name), getattr(fresh, name)), name
    assert np.array_equal(spun.attitude.as_quat(), fresh.attitude.as_quat())
    assert spun.events == fresh.events


def test_rocket_lateral_specific_force_small_in_flight(rocket):
    flight = rocket.t > rocket.events["rail_exit"] + 1.0
    assert np.abs(rocket.specific_force[flight, 1:]).max() < 0.05


def test_rocket_pad_statics(rocket):
    pad = rocket.t < rocket.events["ignition"]
    assert np.all(rocket.velocity[pad] == 0.0)
    assert np.all(rocket.position[pad] == rocket.position[0])
    gamma = earth.normal_gravity_ecef(rocket.position[pad])
    f_expect = rocket.attitude[pad].inv().apply(-gamma)
    assert np.allclose(rocket.specific_force[pad], f_expect, atol=1e-12)
    assert np.allclose(np.linalg.norm(rocket.angular_rate[pad], axis=1), earth.OMEGA_E,
                       rtol=1e-12)
    # body x along the rail: 84 deg elevation, 100 deg azimuth
    lat, lon, _ = earth.ecef_to_geodetic(rocket.position[0])
    x_n = earth.ned_to_ecef_matrix(lat, lon).T @ rocket.attitude[0].apply([1.0, 0.0, 0.0])
    assert np.degrees(np.arcsin(-x_n[2])) == pytest.approx(84.0, abs=1e-9)
    assert np.degrees(np.arctan2(x_n[1], x_n[0])) == pytest.approx(100.0, abs=1e-9)


def test_rocket_site_default(rocket):
    lat, lon, alt = rocket.geodetic
    assert alt[0] == pytest.approx(30.0, abs=1e-6)
    assert np.degrees(lat[0]) == pytest.approx(-5.92, abs=1e-9)
    assert np.degrees(lon[0]) == pytest.approx(-35.16, abs=1e-9)


# --- construction-independent consistency -----------------------------------------------

def test_rocket_velocity_matches_position_differences(rocket):
    t, P, V = rocket.t, rocket.position, rocket.velocity
    fd = (P[2:] - P[:-2]) / (t[2:] - t[:-2])[:, None]
    # central-difference error ~ h^2/6 |jerk|: jerk peaks near 270 m/s^3 in the 1 s tail-off
    err = np.abs(fd - V[1:-1]).max(axis=1)
    assert err.max() < 1e-2
    steady = (t[1:-1] > 20.0) & (t[1:-1] < 44.0)
    assert err[steady].max() < 1e-4


def test_rocket_specific_force_matches_velocity_differences(rocket):
    t, P, V, C = rocket.t, rocket.position, rocket.velocity, rocket.attitude
    dv = (V[2:] - V[:-2]) / (t[2:] - t[:-2])[:, None]
    f_e = dv + 2 * np.cross(earth.EARTH_RATE_ECEF, V[1:-1]) - earth.normal_gravity_ecef(P[1:-1])
    f_e_imu = C[1:-1].apply(rocket.specific_force[1:-1])
    err = np.linalg.norm(f_e - f_e_imu, axis=1)
    tc, lift = t[1:-1], rocket.events["liftoff"]
    # the jerk jumps at lift-off (acceleration is only C^0 there): central differences of V
    # are off by ~h |jump| / 4 right at it, so the check skips half a second after it
    assert err[(tc < lift - 0.015) | (tc > lift + 0.5)].max() < 0.05
    steady = ((tc > 19.5) & (tc < 44.0)) | (tc > 47.0)
    assert err[steady].max() < 1e-4


def test_rocket_attitude_increments_match_gyro():
    traj = sounding_rocket(rate_hz=400.0)
    t, w, C = traj.t, traj.angular_rate, traj.attitude
    dt = np.diff(t)[:, None]
    # body increment: trapezoid + coning term; Earth rotation applied on the ECEF side
    body = Rotation.from_rotvec(0.5 * (w[:-1] + w[1:]) * dt
                                + np.cross(w[:-1], w[1:]) * dt**2 / 12.0)
    earth_step = Rotation.from_rotvec(-dt * earth.EARTH_RATE_ECEF)
    predicted = earth_step * C[:-1] * body
    err = (predicted.inv() * C[1:]).magnitude()
    assert err.max() < 1e-6
    # and integrating the gyro over the whole flight keeps the attitude within 0.1 mrad
    att = C[0]
    for k in range(len(t) - 1):
        att = earth_step[k] * att * body[k]
    assert (att.inv() * C[-1]).magnitude() < 1e-4


def test_rocket_keyword_overrides_change_flight():
    slow = sounding_rocket(spin_hz=1.0, rate_hz=50.0, end_s=70.0, despin_s=65.0)
    assert slow.t[-1] == pytest.approx(70.0) and slow.rate_hz == pytest.approx(50.0)
    assert slow.angular_rate[_at(slow, 60.0), 0] == pytest.approx(2 * np.pi, rel=1e-3)
    assert slow.parameters["spin_hz"] == 1.0
    again = sounding_rocket()
    assert again.angular_rate[_at(again, 60.0), 0] == pytest.approx(4 * np.pi, rel=1e-3)


@pytest.mark.parametrize("kwargs, name", [
    ({"burnout_s": 10.0}, "burnout_s"),
    ({"despin_s": 90.0}, "despin_s"),
    ({"free_flight_s": 40.0}, "free_flight_s"),
    ({"lat_deg": 95.0}, "lat_deg"),
    ({"spin_hz": float("nan")}, "spin_hz"),
    ({"mass_burnout_kg": 2000.0}, "mass_burnout_kg"),
    ({"thrust_n": 1000.0}, "thrust_n"),
    ({"rail_elevation_deg": 0.0}, "rail_elevation_deg"),
    ({"rate_hz": -1.0}, "rate_hz"),
    ({"spinn_hz": 1.0}, "spinn_hz"),
])
def test_rocket_bad_input(kwargs, name):
    with pytest.raises(NavlibInputError, match=name):
        sounding_rocket(**kwargs)


# --- launcher (spec launcher.md §4) ------------------------------------------------------

@pytest.fixture(scope="module")
def launcher():
    return launcher_ascent()


def test_launcher_sampling_and_events(launcher):
    assert launcher.rate_hz == pytest.approx(200.0)
    assert launcher.t[-1] == pytest.approx(150.0) and len(launcher) == 30001
    ev = launcher.events
    assert ev["liftoff"] == 0.0 and ev["stage1_burnout"] == 109.0
    assert ev["stage1_burnout"] <= ev["separation"] < ev["stage2_ignition"] < ev["end"]


def test_launcher_liftoff_vertical_thrust_over_mass(launcher):
    p = launcher.parameters
    assert np.abs(launcher.velocity[0]).max() < 1e-12
    f0 = launcher.specific_force[0]
    assert f0[0] == pytest.approx(p["stage1_thrust_n"] / p["mass_liftoff_kg"], rel=1e-9)
    assert np.abs(f0[1:]).max() < 1e-9
    lat, lon, _ = earth.ecef_to_geodetic(launcher.position[0])
    x_n = earth.ned_to_ecef_matrix(lat, lon).T @ launcher.attitude[0].apply([1.0, 0, 0])
    assert x_n[2] == pytest.approx(-1.0, abs=1e-12)   # body x straight up: no gimbal lock
    assert np.degrees(lat) == pytest.approx(58.73) and np.degrees(lon) == pytest.approx(-93.82)


def test_launcher_lateral_specific_force_small_but_not_zero(launcher):
    """Gusts (A-launcher-lateral): the paper's "almost null" lateral acceleration, not zero."""
    f = launcher.specific_force
    lateral = np.hypot(f[:, 1], f[:, 2])
    assert 0.01 < np.sqrt(np.mean(lateral**2)) < 0.2
    assert lateral.max() < 0.5
    assert np.all(np.abs(f[:, 0]) > 0.0)
    calm = launcher_ascent(gust_mps=0.0).specific_force
    assert np.abs(calm[:, 1:]).max() < 0.05                 # programme and spline only
    assert np.sqrt(np.mean(calm[launcher.t > 30.0, 1:] ** 2)) < 1e-4


def test_launcher_lateral_defaults_pinned_to_their_sources():
    from navlib.trajectory.launcher import LATERAL_SOURCES, LAUNCHER_DEFAULTS
    assert LAUNCHER_DEFAULTS["gust_mps"] == 9.0                # NASA/TM-2008-215633
    assert LAUNCHER_DEFAULTS["gust_gradient_m"] == 107.0       # CS/FAR 25.341: 350 ft
    assert LAUNCHER_DEFAULTS["normal_force_slope_m2"] == 2.0 * 2.0  # Barrowman: 2 /rad
    assert LAUNCHER_DEFAULTS["bending_mps2"] == 0.0            # no published level at hand
    assert set(LATERAL_SOURCES) == {"gust_mps", "gust_gradient_m", "normal_force_slope_m2"}


def test_launcher_bending_mode_oscillates_laterally_from_rest():
    traj = launcher_ascent(duration_s=20.0, gust_mps=0.0, bending_mps2=0.2, bending_hz=6.0)
    calm = launcher_ascent(duration_s=20.0, gust_mps=0.0)
    assert np.abs(traj.velocity[0]).max() < 1e-12
    extra = traj.attitude.inv().apply(traj.attitude.apply(traj.specific_force)
                                      - calm.attitude.apply(calm.specific_force))
    late = traj.t > 2.0
    assert np.abs(extra[late]).max() == pytest.approx(0.2, rel=0.02)
    assert np.abs(extra[late, 0]).max() < 0.01                 # lateral to the body


def test_launcher_staging(launcher):
    t, f_x = launcher.t, launcher.specific_force[:, 0]
    p = launcher.parameters
    before = f_x[(t > 100.0) & (t < 107.0)]
    assert np.all(before > 30.0)                        # stage 1 near burnout, light vehicle
    coast = (t > 109.0) & (t < 111.0)
    assert np.all(np.abs(f_x[coast]) < 2.0)             # drag only between the stages
    k = int(np.argmin(np.abs(t - 112.0)))
    upper = p["mass_liftoff_kg"] - p["stage1_propellant_kg"] - p["stage1_dry_kg"]
    assert f_x[k] == pytest.approx(p["stage2_thrust_n"] / upper, rel=0.05)


def test_launcher_climbs_towards_sun_synchronous_azimuth(launcher):
    az = launcher.parameters["azimuth_deg"]
    assert az == pytest.approx(np.degrees(np.arcsin(np.cos(97.4 * DEG) / np.cos(58.73 * DEG))))
    assert -20.0 < az < -10.0                            # north-north-west
    lat, lon, alt = launcher.geodetic
    v_n = earth.ned_to_ecef_matrix(lat[-1], lon[-1]).T @ launcher.velocity[-1]
    assert np.degrees(np.arctan2(v_n[1], v_n[0])) == pytest.approx(az, abs=2.0)
    elevation = np.degrees(np.arctan2(-v_n[2], np.hypot(v_n[0], v_n[1])))
    assert 10.0 < elevation < 60.0                      # gravity turn well under way
    assert 40e3 < alt[-1] < 150e3                        # still endo-atmospheric-ish


def test_launcher_consistency_and_override():
    traj = launcher_ascent(duration_s=30.0, rate_hz=100.0)
    assert traj.t[-1] == pytest.approx(30.0)
    assert "stage1_burnout" not in traj.events
    t, P, V = traj.t, traj.position, traj.velocity
    fd = (P[2:] - P[:-2]) / (t[2:] - t[:-2])[:, None]
    assert np.abs(fd - V[1:-1]).max() < 1e-4
    dv = (V[2:] - V[:-2]) / (t[2:] - t[:-2])[:, None]
    f_e = dv + 2 * np.cross(earth.EARTH_RATE_ECEF, V[1:-1]) - earth.normal_gravity_ecef(P[1:-1])
    assert np.abs(f_e - traj.attitude[1:-1].apply(traj.specific_force[1:-1])).max() < 1e-3


@pytest.mark.parametrize("kwargs, name", [
    ({"stage1_burnout_s": 20.0}, "pitchover_s"),
    ({"stage2_ignition_s": 105.0}, "stage2_ignition_s"),
    ({"duration_s": 1000.0}, "duration_s"),
    ({"inclination_deg": 20.0}, "inclination_deg"),
    ({"lat_deg": float("nan")}, "lat_deg"),
    ({"stage1_thrust_n": 1e5}, "stage1_thrust_n"),
    ({"azimuth_deg": "north"}, "azimuth_deg"),
    ({"spin_hz": 1.0}, "spin_hz"),
    ({"gust_mps": -1.0}, "gust_mps"),
    ({"bending_hz": 0.0}, "bending_hz"),
])
def test_launcher_bad_input(kwargs, name):
    with pytest.raises(NavlibInputError, match=name):
        launcher_ascent(**kwargs)


# --- stationary --------------------------------------------------------------------------

def test_stationary_statics():
    traj = stationary(duration_s=10.0)
    assert len(traj) == 1001 and traj.rate_hz == pytest.approx(100.0)
    lat, lon = -23.213056 * DEG, -45.860556 * DEG
    C_n_e = earth.ned_to_ecef_matrix(lat, lon)
    assert np.allclose(traj.C_b_e(), C_n_e, atol=1e-15)
    assert np.all(traj.velocity == 0.0)
    w_n = earth.OMEGA_E * np.array([np.cos(lat), 0.0, -np.sin(lat)])
    assert np.allclose(traj.angular_rate, w_n, atol=1e-18)
    gamma_n = C_n_e.T @ earth.normal_gravity_ecef(traj.position[0])
    assert np.allclose(traj.specific_force, -gamma_n, atol=1e-12)
    assert traj.specific_force[0, 2] == pytest.approx(-9.787, abs=5e-3)
    _, _, alt = traj.geodetic
    assert np.allclose(alt, 629.0, atol=1e-6)


@pytest.mark.parametrize("kwargs, name", [
    ({"lat_deg": -91.0}, "lat_deg"),
    ({"duration_s": 0.0}, "duration_s"),
    ({"rate_hz": float("inf")}, "rate_hz"),
    ({"alt_m": "high"}, "alt_m"),
])
def test_stationary_bad_input(kwargs, name):
    with pytest.raises(NavlibInputError, match=name):
        stationary(**kwargs)
