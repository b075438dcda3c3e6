"""Sensor presets (TOML) and IMU / GNSS error simulation: values, statistics, errors."""

import numpy as np
import pandas as pd
import pytest

import navlib.trajectory as trajectories
from navlib import NavlibInputError, sensors, units
from navlib.sensors import GnssSpec, ImuSpec, TriadSpec


@pytest.fixture(scope="module")
def still():
    return trajectories.stationary(duration_s=600.0, rate_hz=100.0)


@pytest.fixture(scope="module")
def rocket():
    return trajectories.sounding_rocket()


# --- presets --------------------------------------------------------------------------------


def test_presets_listed_and_loaded():
    names = sensors.list_presets()
    assert {"launcher_table1", "motionpak_tactical", "ssac_tactical"} <= set(names)
    for name in names:
        spec = sensors.load_preset(name)
        assert spec.name == name
        assert len(spec.source) > 40
        frame = spec.to_frame()
        assert set(frame.columns) == {"section", "key", "value", "value_si", "assumed"}
        assert frame["assumed"].sum() == len(spec.assumed)


def test_launcher_table1_values():
    """Beaudoin 2018 Table 1 converted to SI, checked against spec launcher.md §5."""
    spec = sensors.load_preset("launcher_table1")
    gyro, accel = spec.imu.gyro, spec.imu.accel
    assert gyro.noise_density == pytest.approx(3.4907e-6, rel=1e-4)
    assert gyro.bias_markov_sigma == pytest.approx(2.4241e-7, rel=1e-4)
    assert accel.noise_density == pytest.approx(1.1474e-3, rel=1e-4)
    assert accel.bias_markov_sigma == pytest.approx(0.073550, rel=1e-4)
    assert gyro.bias_markov_tau == accel.bias_markov_tau == 100.0
    assert gyro.bias == accel.bias == 0.0
    assert spec.imu.rate_hz == 200.0
    assert spec.attitude_sigma == pytest.approx(np.radians(1.0))
    # Per-sample sigma at 200 Hz as tabulated in the spec: 4.9365e-5 rad/s, 0.016226 m/s^2.
    assert gyro.noise_density * np.sqrt(200.0) == pytest.approx(4.9365e-5, rel=1e-4)
    assert accel.noise_density * np.sqrt(200.0) == pytest.approx(0.016226, rel=1e-4)
    # The GPS is not specified in the paper: its sigmas are marked assumed (the 200 Hz
    # rate is the paper's common sensor rate).
    assert spec.gnss.rate_hz == 200.0
    assert all(k in spec.assumed for k in spec.values
               if k.startswith("gnss.") and k != "gnss.rate_hz")
    assert not any(k.startswith("imu.") for k in spec.assumed)


def test_motionpak_and_ssac_values():
    mp = sensors.load_preset("motionpak_tactical")
    assert mp.imu.gyro.noise_density == pytest.approx(0.5 * np.pi / 180 / 60)  # 0.5 deg/sqrt(h)
    assert mp.imu.accel.noise_density == pytest.approx(0.1 / 60)  # 0.1 m/s/sqrt(h)
    assert mp.imu.gyro.bias == pytest.approx(0.05 * units.DEG)
    assert mp.imu.gyro.scale_factor == pytest.approx(5e-3)
    assert mp.imu.gyro.bias_random_walk == pytest.approx(4.8e-6)
    assert len(mp.assumed) == len(mp.values) - 2  # all but the two rate_hz entries
    ssac = sensors.load_preset("ssac_tactical")
    assert ssac.imu.gyro.bias == pytest.approx(2.424e-6, rel=1e-3)
    assert ssac.imu.accel.bias == pytest.approx(4.903e-3, rel=1e-3)
    assert ssac.imu.gyro.noise_density == pytest.approx(5.82e-8, rel=1e-3)
    assert ssac.imu.accel.noise_density == pytest.approx(9.81e-5, rel=1e-3)
    assert ssac.gnss is None
    assert "deg/sqrt(s)" in ssac.notes  # the unit ambiguity is recorded


def test_load_preset_by_path(tmp_path):
    path = tmp_path / "mine.toml"
    path.write_text('source = "bench test"\n[imu]\ngyro_bias_deg_h = 1.0\n'
                    "accel_vrw_mg_sqrt_hz = 0.05\n")
    spec = sensors.load_preset(path)
    assert spec.name == "mine"
    assert spec.imu.gyro.bias == pytest.approx(units.DEG_PER_HOUR)
    assert spec.imu.accel.noise_density == pytest.approx(0.05 * units.MG)
    assert sensors.load_preset(str(path)).imu == spec.imu


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ('source = "x"\n[imu]\ngyro_bias_deg_hr = 1.0\n', "gyro_bias_deg_hr"),
        ('source = "x"\n[imu]\ngyro_bias_deg_h = -1.0\n', "gyro_bias_deg_h"),
        ('source = "x"\n[imu]\ngyro_bias_deg_h = "big"\n', "gyro_bias_deg_h"),
        ('source = "x"\n[imu]\ngyro_bias_deg_h = 1.0\ngyro_bias_rad_s = 1e-6\n', "twice"),
        ('source = "x"\n[imu]\ngyro_bias_markov_deg_h = 1.0\n', "bias_markov_tau"),
        ('source = "x"\nassumed = ["imu.gyro_bias_deg_s"]\n[imu]\ngyro_bias_deg_h = 1.0\n',
         "imu.gyro_bias_deg_s"),
        ('[imu]\ngyro_bias_deg_h = 1.0\n', "source"),
        ('source = "x"\n[lidar]\nrange_m = 1.0\n', "lidar"),
        ('source = "x"\n', "at least one"),
        ('source = "x"\n[gnss]\nposition_sigma_m = 3.0\nposition_bias_markov_m = 1.0\n',
         "position_bias_tau"),
        ('source = "x"\n[imu\n', "not valid TOML"),
    ],
)
def test_bad_preset_names_file_and_key(tmp_path, text, match):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(NavlibInputError, match=match) as info:
        sensors.load_preset(path)
    assert "bad.toml" in str(info.value)


def test_missing_preset():
    with pytest.raises(NavlibInputError, match=r"no_such_imu.*available.*launcher_table1"):
        sensors.load_preset("no_such_imu")
    with pytest.raises(NavlibInputError, match="not found"):
        sensors.load_preset("/nonexistent/dir/imu.toml")


def test_spec_validation():
    with pytest.raises(NavlibInputError, match="noise_density"):
        TriadSpec(noise_density=-1.0)
    with pytest.raises(NavlibInputError, match="rate_hz"):
        GnssSpec(position_sigma=1.0, rate_hz=0.0)


# --- error processes: statistics -------------------------------------------------------------


def test_white_noise_discretisation(still):
    """Point samples: sigma = N sqrt(rate); integrated: angle variance N^2 t."""
    spec = ImuSpec(gyro=TriadSpec(noise_density=1e-4), accel=TriadSpec(noise_density=2e-3))
    sim = sensors.simulate_imu(still, spec, seed=3)
    noise = sim.gyro.noise
    assert noise.shape == (still.t.size, 3)
    # 60001 x 3 samples: the sample std is good to ~0.2 %.
    assert noise.std() == pytest.approx(1e-4 * np.sqrt(100.0), rel=0.01)
    assert sim.accel.noise.std() == pytest.approx(2e-3 * 10.0, rel=0.01)
    np.testing.assert_allclose(noise.mean(axis=0), 0.0, atol=5 * 1e-3 / np.sqrt(still.t.size))
    # Neighbouring samples are uncorrelated.
    lag1 = np.mean(noise[1:] * noise[:-1]) / noise.var()
    assert abs(lag1) < 0.02
    # Angle random walk: 300 independent 2 s windows, each integrated.
    windows = noise[:60000].reshape(300, 200, 3).sum(axis=1) * 0.01
    assert windows.std() == pytest.approx(1e-4 * np.sqrt(2.0), rel=0.06)


def test_gauss_markov_stationary_statistics():
    rng = np.random.default_rng(11)
    t = np.arange(0.0, 20.0, 0.05)
    sigma, tau = 0.3, 2.0
    x = sensors.gauss_markov(t, sigma, tau, rng, n_axes=4000)  # 4000 independent runs
    # Stationary from the start: the ensemble variance is sigma^2 at every time.
    var_t = x.var(axis=1)
    assert np.all(np.abs(var_t / sigma**2 - 1.0) < 0.12)
    assert var_t.mean() == pytest.approx(sigma**2, rel=0.02)
    # Autocorrelation sigma^2 exp(-lag / tau).
    for lag_s in (0.5, 2.0, 5.0):
        m = round(lag_s / 0.05)
        cov = np.mean(x[:-m] * x[m:])
        assert cov == pytest.approx(sigma**2 * np.exp(-lag_s / tau), abs=0.01)


def test_gauss_markov_non_uniform_steps():
    """The per-step loop (irregular times) has the same exact transition."""
    rng = np.random.default_rng(5)
    t = np.array([0.0, 0.1, 0.2, 1.2, 1.25, 4.0])
    x = sensors.gauss_markov(t, 1.0, 1.0, rng, n_axes=20000)
    np.testing.assert_allclose(x.var(axis=1), 1.0, atol=0.04)
    corr = np.mean(x[:-1] * x[1:], axis=1)
    np.testing.assert_allclose(corr, np.exp(-np.diff(t)), atol=0.03)


def test_random_walk_variance_growth():
    rng = np.random.default_rng(8)
    t = np.concatenate([np.arange(0.0, 10.0, 0.01), np.arange(10.0, 100.0, 0.5)])
    x = sensors.random_walk(t, 0.2, rng, n_axes=3000)
    np.testing.assert_array_equal(x[0], 0.0)
    for k in (100, 999, len(t) - 1):
        assert x[k].var() == pytest.approx(0.04 * t[k], rel=0.08)


def test_white_noise_non_uniform_steps():
    rng = np.random.default_rng(2)
    t = np.array([0.0, 0.01, 0.03, 0.07, 0.08])
    x = sensors.white_noise(t, 0.5, rng, n_axes=50000)
    expected = 0.5 / np.sqrt(np.append(np.diff(t), 0.01))
    np.testing.assert_allclose(x.std(axis=1), expected, rtol=0.02)


# --- simulate_imu -----------------------------------------------------------------------------


def test_measurement_model_convention(rocket):
    """f_meas = (I + diag s + M) f + b + n (spec A7), checked term by term."""
    spec = ImuSpec(gyro=TriadSpec(bias=1e-3, scale_factor=1e-3, misalignment=1e-3),
                   accel=TriadSpec(bias=1e-2, scale_factor=1e-3, misalignment=2e-3,
                                   noise_density=1e-3))
    sim = sensors.simulate_imu(rocket, spec, seed=1)
    g, a = sim.gyro, sim.accel
    assert np.all(np.diag(a.misalignment) == 0) and np.all(a.misalignment[0, 1:] != 0)
    expected_f = (rocket.specific_force * (1 + a.scale_factor)
                  + np.einsum("ij,nj->ni", a.misalignment, rocket.specific_force)
                  + a.bias + a.noise)
    np.testing.assert_allclose(sim.f_b, expected_f, rtol=1e-13, atol=1e-12)
    np.testing.assert_allclose(sim.w_ib_b - rocket.angular_rate,
                               rocket.angular_rate * g.scale_factor
                               + rocket.angular_rate @ g.misalignment.T + g.bias, atol=1e-15)
    # Constant errors: bias and scale factor do not move without drift terms.
    assert np.ptp(g.bias, axis=0).max() == 0.0
    np.testing.assert_array_equal(sim.gyro.noise, 0.0)


def test_fixed_turn_on_errors(still):
    """SSAC case: exact constant biases of 0.5 deg/h and 0.5 mg on every axis."""
    spec = sensors.load_preset("ssac_tactical")
    bg = np.full(3, 0.5 * units.DEG_PER_HOUR)
    ba = np.full(3, 0.5 * units.MG)
    sim = sensors.simulate_imu(still, spec, seed=0, gyro_bias=bg, accel_bias=ba)
    np.testing.assert_allclose(sim.gyro.bias, np.broadcast_to(bg, sim.gyro.bias.shape))
    np.testing.assert_allclose((sim.f_b - still.specific_force).mean(axis=0), ba, atol=2e-5)
    with pytest.raises(NavlibInputError, match="gyro_bias"):
        sensors.simulate_imu(still, spec, seed=0, gyro_bias=[1.0, 2.0])
    with pytest.raises(NavlibInputError, match="gyro_sf"):
        sensors.simulate_imu(still, spec, seed=0, gyro_sf=[1.0, 2.0, 3.0])


def test_markov_bias_in_simulation(still):
    spec = sensors.load_preset("launcher_table1")
    sim = sensors.simulate_imu(still, spec, seed=4)
    b = sim.accel.bias
    # Correlated over the 100 s time constant: 1 s increments are tiny next to sigma.
    sigma = spec.imu.accel.bias_markov_sigma
    step = np.diff(b[::100], axis=0)
    assert step.std() == pytest.approx(sigma * np.sqrt(1 - np.exp(-2 / 100)), rel=0.1)


def test_reproducible_by_seed(rocket):
    spec = sensors.load_preset("motionpak_tactical")
    a = sensors.simulate_imu(rocket, spec, seed=42)
    b = sensors.simulate_imu(rocket, spec, seed=42)
    c = sensors.simulate_imu(rocket, spec, seed=43)
    d = sensors.simulate_imu(rocket, spec, rng=np.random.default_rng(42))
    np.testing.assert_array_equal(a.f_b, b.f_b)
    np.testing.assert_array_equal(a.w_ib_b, d.w_ib_b)
    assert not np.allclose(a.f_b, c.f_b)
    pd.testing.assert_frame_equal(a.to_frame(errors=True), b.to_frame(errors=True))
    with pytest.raises(NavlibInputError, match="seed, rng"):
        sensors.simulate_imu(rocket, spec, seed=1, rng=np.random.default_rng(1))
    with pytest.raises(NavlibInputError, match="rng"):
        sensors.simulate_imu(rocket, spec, rng=42)


def test_sources_have_separate_streams(rocket):
    """Changing the ARW level rescales the noise only; biases are unchanged."""
    base = ImuSpec(gyro=TriadSpec(bias=1e-4, noise_density=1e-4, bias_random_walk=1e-6))
    louder = ImuSpec(gyro=TriadSpec(bias=1e-4, noise_density=3e-4, bias_random_walk=1e-6))
    a = sensors.simulate_imu(rocket, base, seed=9)
    b = sensors.simulate_imu(rocket, louder, seed=9)
    np.testing.assert_array_equal(a.gyro.bias, b.gyro.bias)
    np.testing.assert_allclose(b.gyro.noise, 3 * a.gyro.noise)


def test_imu_frame_layout(rocket):
    sim = sensors.simulate_imu(rocket, sensors.load_preset("motionpak_tactical"), seed=0)
    frame = sim.to_frame()
    assert list(frame.columns) == ["t", "f_x", "f_y", "f_z", "w_x", "w_y", "w_z"]
    full = sim.to_frame(errors=True)
    assert {"b_ax", "b_gz", "s_ax", "s_gz"} <= set(full.columns)
    assert len(full) == len(rocket.t)


def test_simulate_imu_bad_input(rocket):
    with pytest.raises(NavlibInputError, match="trajectory"):
        sensors.simulate_imu(np.zeros(3), sensors.load_preset("ssac_tactical"))
    with pytest.raises(NavlibInputError, match="spec"):
        sensors.simulate_imu(rocket, "ssac_tactical")


# --- simulate_gnss ----------------------------------------------------------------------------


def test_simulate_gnss(rocket):
    spec = sensors.load_preset("launcher_table1")
    gnss = sensors.simulate_gnss(rocket, spec, rate_hz=1.0, seed=7, with_errors=True)
    assert list(gnss.columns[:8]) == ["t", "x", "y", "z", "vx", "vy", "vz", "sigma"]
    np.testing.assert_allclose(gnss["t"], np.arange(87.0))
    idx = rocket.at_rate(1.0)
    bias = gnss[["bias_x", "bias_y", "bias_z"]].to_numpy()
    resid = gnss[["x", "y", "z"]].to_numpy() - rocket.position[idx] - bias
    assert resid.std() == pytest.approx(3.0, rel=0.15)
    vres = gnss[["vx", "vy", "vz"]].to_numpy() - rocket.velocity[idx]
    assert vres.std() == pytest.approx(0.1, rel=0.15)
    assert (gnss["sigma"] == 3.0).all()
    # Markov bias: slow (tau 100 s) next to the white noise.
    assert np.abs(np.diff(bias, axis=0)).std() < 1.0
    again = sensors.simulate_gnss(rocket, spec, 1.0, seed=7)
    pd.testing.assert_frame_equal(again, gnss.iloc[:, :8])
    assert len(sensors.simulate_gnss(rocket, spec, rate_hz=10.0, seed=1)) == 861


def test_simulate_gnss_bad_input(rocket):
    with pytest.raises(NavlibInputError, match=r"ssac_tactical.*gnss"):
        sensors.simulate_gnss(rocket, sensors.load_preset("ssac_tactical"))
    with pytest.raises(NavlibInputError, match="rate_hz"):
        sensors.simulate_gnss(rocket, sensors.load_preset("launcher_table1"), rate_hz=-1.0)


def test_bias_signs_through_strapdown():
    """Sign convention end to end: a +b accelerometer bias drifts the position by
    +C_b_e b t^2 / 2, a +b gyro bias turns the body by +b t about the same body axis."""
    from navlib import strapdown

    traj = trajectories.stationary(duration_s=20.0, rate_hz=100.0)
    b_a, b_g = np.array([0.01, -0.02, 0.0]), np.array([0.0, 0.0, 1e-3])
    sim = sensors.simulate_imu(traj, ImuSpec(), seed=0, accel_bias=b_a, gyro_bias=b_g)
    res = strapdown.integrate(traj.t, sim.f_b, sim.w_ib_b, traj.position[0],
                              traj.velocity[0], traj.attitude[0])
    T = traj.t[-1]
    expected = traj.attitude[0].apply(b_a) * T**2 / 2
    # Only approximately: the gyro bias turns the body (and so the force) by up to 0.02 rad.
    np.testing.assert_allclose(res.position[-1] - traj.position[-1], expected, rtol=0,
                               atol=0.02 * np.linalg.norm(expected))
    d_att = (traj.attitude[-1].inv() * res.attitude[-1]).as_rotvec()
    # Plus the second-order coupling with the Earth rate, |Omega| |b_g| T^2 / 2 = 1.5e-5 rad.
    np.testing.assert_allclose(d_att, b_g * T, rtol=0, atol=2e-5)


@pytest.mark.parametrize(("n", "a", "axes"), [(2, 0.5, 1), (3001, np.exp(-0.005 / 100.0), 3),
                                             (20000, np.exp(-0.01 / 0.3), 7)])
def test_gauss_markov_recursion_is_lfilter_bitwise(n, a, axes):
    """The compiled recursion gives scipy.signal.lfilter's numbers bit for bit (the filter
    it replaced, kept here as the reference)."""
    from scipy.signal import lfilter

    from navlib.sensors.simulation import first_order_recursion

    drive = np.random.default_rng(n).standard_normal((n, axes))
    out = np.empty_like(drive)
    first_order_recursion(np.full(n - 1, a), drive, out)
    expected = lfilter([1.0], [1.0, -a], drive, axis=0)
    np.testing.assert_array_equal(out.view(np.int64), expected.view(np.int64))
