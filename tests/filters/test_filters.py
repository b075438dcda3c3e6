"""Filters: linear error-state Monte Carlo (gains, consistency, linearity, outlier inputs) and
the closed-loop EKF (noise-free closure, sigma against the covariance analysis, consistency,
input errors)."""

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.spatial.transform import Rotation

from navlib import NavlibInputError, filters, kalman
from navlib.covariance import kalman_covariance
from navlib.filters.measurements import GnssPosition
from navlib.models import ecef21, launcher
from navlib.models.base import DiscreteModel, Nominal
from navlib.models.ecef import Ecef21ErrorState
from navlib.rotations import exp_so3, log_so3
from navlib.sensors.faults import Outlier, channel_profile, linear_mapping
from navlib.trajectory import launcher_ascent, sounding_rocket


@pytest.fixture(scope="module")
def short_launcher():
    """The first 20 s of the ascent at 20 Hz, without wind (``gust_mps=0``): the closure
    tolerances below were set on the smooth ascent; the gusts' body rates add 3e-7 rad of
    20 Hz strapdown discretisation error to the noise-free attitude (A-launcher-lateral)."""
    return launcher_ascent(duration_s=20.0, rate_hz=20.0, gust_mps=0.0)


@pytest.fixture(scope="module")
def rocket():
    return sounding_rocket()


def test_gains_reproduce_joseph_posteriors_with_singular_r(short_launcher):
    """The batched gains give back kalman_covariance's posteriors, also with the noise-free
    RT pseudo-measurement (R singular: pseudo-inverse path)."""
    for solution in ("ins_gps", "ins_gps_att_rt"):
        prep = filters.prepare_linear(launcher(solution, "GAP", "markov", short_launcher))
        cov, K = prep.covariance, prep.gains.K
        n = cov.n
        for k in (0, 7, 150, len(cov.t) - 1):
            H, R = prep.steps.H[k], prep.steps.R[k]
            IKH = np.eye(n) - K[k] @ H
            P = IKH @ cov.P_prior[k] @ IKH.T + K[k] @ R @ K[k].T
            np.testing.assert_allclose(P, cov.P_post[k], rtol=1e-8,
                                       atol=1e-12 * np.abs(cov.P_post[k]).max())


def test_chi2_bounds_known_values():
    lo, hi = kalman.chi2_bounds(3, runs=1)
    assert lo == pytest.approx(0.2158, abs=1e-4) and hi == pytest.approx(9.348, abs=1e-3)
    lo, hi = kalman.chi2_bounds(3, runs=100)
    assert lo < 3 < hi and hi - lo < 1.0
    with pytest.raises(NavlibInputError, match="runs"):
        kalman.chi2_bounds(3, runs=0)


@pytest.mark.parametrize("solution,biases", [("ins_gps", "GA"), ("ins_gps_att_rt", "GAP")])
def test_monte_carlo_nees_nis_inside_chi2_bounds(short_launcher, solution, biases):
    """Consistency evidence: on nominal data the run-averaged NEES and NIS stay inside their
    95 % chi-square bounds at most epochs and average to their degrees of freedom."""
    model = launcher(solution, biases, "markov", short_launcher)
    sim = filters.simulate_linear(model, runs=200, seed=11)
    c = sim.consistency()
    assert c["nis"] >= 0.9 and c["nees"] >= 0.85
    assert 0.95 < c["nis_mean_over_dof"] < 1.05
    assert 0.9 < c["nees_mean_over_dof"] < 1.1
    # the RT pseudo-measurement is noise-free: one 3-D direction of P is singular
    if solution.endswith("_rt"):
        assert sim.nees_dof[-1] == model.n - 3


def test_linearity_outlier_response_is_exact(short_launcher):
    """Faulty run minus nominal run (same seed) equals the noise-free response."""
    model = filters.prepare_linear(launcher("ins_gps_rt", "GA", "markov", short_launcher))
    outs = [Outlier("gyro_x", 10.0, 0.002), Outlier("rt_x", 12.0, 0.002, "step")]
    faulty = filters.simulate_linear(model, runs=3, seed=5, outliers=outs)
    nominal = filters.simulate_linear(model, runs=3, seed=5)
    resp = filters.simulate_linear(model, outliers=outs, noise=False, initial_error=False)
    diff = faulty.error - nominal.error
    scale = np.abs(resp.error).max(axis=(0, 1))
    np.testing.assert_allclose(diff, np.broadcast_to(resp.error, diff.shape),
                               atol=1e-9 * scale.max())
    assert faulty.applied == (True, True)


def test_gyro_outlier_enters_through_minus_T_B_E(short_launcher):
    """A roll-gyro spike u over one Euler step adds -T_B^E [u dt, 0, 0] to psi (ECEF)."""
    model = launcher("ins_gps", "", "none", short_launcher)
    t = short_launcher.t
    k = int(np.argmin(np.abs(t - 10.0)))
    u = 0.002
    resp = filters.simulate_linear(model, outliers=Outlier("gyro_x", 10.0, u), noise=False,
                                   initial_error=False, record_every=1)
    psi = resp.state_index(["psi_x", "psi_y", "psi_z"])
    dt = t[k + 1] - t[k]
    expected = -short_launcher.attitude[k].as_matrix()[:, 0] * u * dt
    np.testing.assert_allclose(resp.truth[k + 1, 0, psi], expected, rtol=1e-12)
    assert np.all(resp.truth[: k + 1] == 0.0)


def test_expm_noise_input_matches_block_exponential(short_launcher):
    model = launcher("ins_gps", "GA", "markov", short_launcher)
    steps = filters.linear_steps(model, method="expm")
    k = 100
    dt = model.t[k + 1] - model.t[k]
    n, q = model.n, model.G.shape[-1]
    block = np.zeros((n + q, n + q))
    block[:n, :n] = model.A[k] * dt
    block[:n, n:] = model.G[k] * dt
    E = expm(block)
    np.testing.assert_allclose(steps.F[k], E[:n, :n], rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(steps.Gamma[k], E[:n, n:], rtol=1e-9, atol=1e-16)
    np.testing.assert_allclose(steps.L[k] @ steps.L[k].T, steps.Q[k], rtol=1e-6,
                               atol=1e-12 * np.abs(steps.Q[k]).max())


def test_discrete_model_needs_noise_input_for_imu_outliers(short_launcher):
    model = launcher("ins_gps", "GA", "markov", short_launcher)
    steps = filters.linear_steps(model)
    dm = DiscreteModel(steps.t, steps.F, steps.Q, steps.H, steps.R, model.state_names,
                       model.measurement_names, model.P0)
    with pytest.raises(NavlibInputError, match="noise input"):
        filters.simulate_linear(dm, outliers=Outlier("gyro_x", 5.0, 0.01))
    ok = filters.simulate_linear(dm, outliers=Outlier("gyro_x", 5.0, 0.01), noise=False,
                                 initial_error=False, noise_input=steps.Gamma,
                                 noise_names=model.noise_names)
    ref = filters.simulate_linear(model, outliers=Outlier("gyro_x", 5.0, 0.01), noise=False,
                                  initial_error=False)
    np.testing.assert_allclose(ok.truth, ref.truth)
    meas = filters.simulate_linear(dm, outliers=Outlier("gnss_vel", 5.0, 3.0), noise=False,
                                   initial_error=False)
    assert meas.applied == (True,) and np.abs(meas.estimate).max() > 0


def test_update_every_and_record_every(short_launcher):
    model = launcher("ins_gps", "GA", "markov", short_launcher)
    sim = filters.simulate_linear(model, runs=2, seed=0, update_every=10, record_every=7)
    assert sim.nis_t.size == int(np.ceil(len(short_launcher.t) / 10))
    assert sim.t[-1] == short_launcher.t[-1] and np.all(np.diff(sim.index[:-1]) == 7)
    frame = sim.to_frame(states=["psi_x"], runs=[1])
    assert set(frame.columns) >= {"t", "run", "state", "truth", "estimate", "sigma"}
    assert len(frame) == sim.t.size


def test_bad_arguments(short_launcher):
    model = launcher("ins_gps", "GA", "markov", short_launcher)
    with pytest.raises(NavlibInputError, match="runs"):
        filters.simulate_linear(model, runs=0)
    with pytest.raises(NavlibInputError, match="seed, rng"):
        filters.simulate_linear(model, seed=1, rng=np.random.default_rng(1))
    with pytest.raises(NavlibInputError, match="method"):
        filters.simulate_linear(model, method="rk4")
    with pytest.raises(NavlibInputError, match="measured"):
        filters.simulate_linear(model, measured=[True, False])
    with pytest.raises(NavlibInputError, match="model"):
        filters.simulate_linear("launcher")


def test_rotation_helpers_match_scipy():
    rng = np.random.default_rng(3)
    axes = rng.normal(size=(50, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    angles = np.repeat([1e-7, 1e-5, 1e-3, 0.5, 2.0, 2.9, 3.05, 3.13, 0.0, 1.0], 5)
    phi = axes * angles[:, None]
    C = exp_so3(phi)
    np.testing.assert_allclose(C, Rotation.from_rotvec(phi).as_matrix(), atol=1e-13)
    np.testing.assert_allclose(log_so3(C), phi, atol=1e-9)


# --- EKF --------------------------------------------------------------------------------------


def test_ekf_noise_free_closure(short_launcher):
    """Exact IMU, exact GNSS, no initial error: the closed loop stays on the truth."""
    run = filters.simulate_ekf(short_launcher, solution="ins_gps_att", biases="GAP",
                               noise=False, initial_error=False, gnss_rate_hz=20.0)
    e = run.errors
    assert np.abs(e[["pos_x", "pos_y", "pos_z"]].to_numpy()).max() < 1e-3
    assert np.abs(e[["vel_x", "vel_y", "vel_z"]].to_numpy()).max() < 1e-4
    assert np.abs(e[["att_x", "att_y", "att_z"]].to_numpy()).max() < 1e-7


def test_ekf_sigma_matches_covariance_analysis(short_launcher):
    """The EKF's posterior sigma equals the linear covariance analysis along the truth
    (launcher model, Euler steps, GNSS + attitude sensor at every sample)."""
    run = filters.simulate_ekf(short_launcher, solution="ins_gps_att", biases="GA", seed=2,
                               gnss_rate_hz=20.0)
    model = launcher("ins_gps_att", "GA", "markov", short_launcher)
    steps = filters.linear_steps(model)
    cov = kalman_covariance(steps.F, steps.Q, steps.H, steps.R, steps.P0, t=steps.t)
    k = np.searchsorted(cov.t, run.result.t)
    ratio = run.result.sigma / cov.sigma[k]
    assert np.abs(ratio - 1).max() < 0.02


def test_ekf_consistency_rocket(rocket):
    """21-state EKF on the sounding rocket (1 Hz GNSS position): normalised navigation
    errors over a few runs have RMS near 1 and the NIS averages its dimension."""
    z = []
    nis = []
    for seed in range(4):
        run = filters.simulate_ekf(rocket, sensors="motionpak_tactical", model="ecef21",
                                   seed=seed, model_options={"sensors": "motionpak_tactical"})
        e = run.errors
        sig = run.result.sigma_of(["P_x", "P_y", "P_z", "V_x", "V_y", "V_z"])
        err = e[["pos_x", "pos_y", "pos_z", "vel_x", "vel_y", "vel_z"]].to_numpy()
        z.append(err / sig)
        nis.append(run.result.nis / run.result.nis_dof)
    rms = np.sqrt(np.mean(np.concatenate(z) ** 2))
    assert 0.7 < rms < 1.4
    assert 0.8 < np.mean(np.concatenate(nis)) < 1.25


def test_ekf_reference_trajectory_consistency(short_launcher):
    """With the RT pseudo-measurement (noise-free, closed-loop divergence) the attitude
    errors stay consistent with the filter sigma."""
    run = filters.simulate_ekf(short_launcher, solution="ins_gps_rt", biases="GA", seed=4,
                               gnss_rate_hz=20.0)
    e = run.errors[["att_x", "att_y", "att_z"]].to_numpy()[1:]
    sig = run.result.sigma_of(["psi_x", "psi_y", "psi_z"])[1:]
    # epoch 0: the noise-free RT update with psi_ref = 0 exactly pins the attitude
    assert run.result.sigma_of(["psi_x"])[0, 0] < 1e-15
    assert np.sqrt(np.mean((e / sig) ** 2)) < 2.0
    assert run.reference is not None and len(run.reference) == len(short_launcher.t)
    assert run.result.kept.shape[1] == 10


def test_ekf_input_errors(short_launcher):
    from navlib.sensors import load_preset, simulate_gnss, simulate_imu
    from navlib.strapdown import StrapdownState

    spec = load_preset("launcher_table1")
    imu = simulate_imu(short_launcher, spec, seed=0)
    gnss = simulate_gnss(short_launcher, spec, seed=0)
    init = StrapdownState.from_trajectory(short_launcher)
    with pytest.raises(NavlibInputError, match="attitude"):
        filters.ekf(imu, gnss, initial=init, solution="ins_gps_att")
    with pytest.raises(NavlibInputError, match="reference"):
        filters.ekf(imu, gnss, initial=init, solution="ins_gps_rt")
    with pytest.raises(NavlibInputError, match="gnss"):
        filters.ekf(imu, gnss.drop(columns="z"), initial=init)
    bad = gnss.copy()
    bad["t"] = bad["t"] + 0.03
    with pytest.raises(NavlibInputError, match="not on an IMU sample"):
        filters.ekf(imu, bad, initial=init)
    with pytest.raises(NavlibInputError, match="model"):
        filters.ekf(imu, gnss, initial=init, model="ned15")
    res = filters.ekf(imu, gnss, initial=init)
    frame = res.to_frame()
    assert {"t", "x", "vx", "qw", "bg_x", "nis"} <= set(frame.columns)
    assert len(res.sigma_frame()) == res.t.size * len(res.state_names)


def test_ecef21_model_builds_at_block(rocket):
    """The EKF's error-state model gives the builder's own Jacobians on the reference, and
    the GNSS measurement its H."""
    model = ecef21(rocket)
    nominal = Nominal(rocket.t[:5], rocket.position[:5], rocket.velocity[:5],
                      rocket.C_b_e()[:5], rocket.specific_force[:5], rocket.angular_rate[:5], {})
    es = Ecef21ErrorState.build()
    A, G = es.jacobians(nominal)
    H = np.stack([GnssPosition(es, [0], rocket.position[:1]).evaluate(0, nominal, j)[1]
                  for j in range(5)])
    np.testing.assert_allclose(A, model.A[:5])
    np.testing.assert_allclose(G, model.G[:5])
    assert H.shape == (5, 3, 21)


def test_noise_free_response_matches_a_hand_recursion(short_launcher):
    """The deterministic response (which starts its recursion at the first outlier input and
    writes the exact zeros before it) equals the filter recursion run by hand from epoch 0;
    innovations and NIS before the outlier are 0, and the cached NEES basis gives the same
    NEES as a fresh one."""
    prepared = filters.prepare_linear(launcher("ins_gps_rt", "GA", "markov", short_launcher))
    out = Outlier("rt_x", 12.0, 0.002)
    resp = filters.simulate_linear(prepared, outliers=out, noise=False, initial_error=False,
                                   record_every=3)
    steps, K = prepared.steps, prepared.gains.K
    mp = linear_mapping("rt_x", steps.measurement_names, steps.noise_names)
    z_add = np.zeros((steps.t.size, steps.H.shape[1]))
    z_add[:, mp.index] = mp.sign * channel_profile((out,), "rt_x", steps.t)
    x = np.zeros(steps.n)
    x_hat = np.zeros(steps.n)
    truth, est, innovations = [], [], []
    for k in range(steps.t.size):
        innov = steps.H[k] @ x + z_add[k] - steps.H[k] @ x_hat
        x_hat = x_hat + K[k] @ innov
        truth.append(x)
        est.append(x_hat)
        innovations.append(innov)
        if k < steps.t.size - 1:
            x, x_hat = steps.F[k] @ x, steps.F[k] @ x_hat
    np.testing.assert_allclose(resp.truth[:, 0], np.array(truth)[resp.index], atol=1e-15)
    np.testing.assert_allclose(resp.estimate[:, 0], np.array(est)[resp.index], atol=1e-15)
    np.testing.assert_allclose(resp.innovation[:, 0], np.array(innovations)[resp.index],
                               atol=1e-15)
    before = resp.nis_t < 12.0
    assert before.any() and np.all(resp.nis[before] == 0.0) and np.all(resp.nis[~before] >= 0)
    nees, dof = kalman.nees_values(resp.error, resp.P)
    np.testing.assert_array_equal(resp.nees, nees)
    np.testing.assert_array_equal(resp.nees_dof, dof)
    assert prepared.nees_basis(resp.index) is prepared.nees_basis(resp.index)


def test_launcher_error_state_is_the_builder_model(short_launcher):
    """The launcher's error-state model has the builder's states, noise, P0 and measurement
    rows, and its Jacobians along a trajectory are the builder's A and G; the layout finds
    the navigation, bias and reference groups and keeps the RT block out of the reset."""
    from navlib.models.launcher import LauncherErrorState

    model = launcher("ins_gps_att_rt", "GAP", "markov", short_launcher)
    es = LauncherErrorState.build("ins_gps_att_rt", "GAP", "markov",
                                  step_s=model.parameters["s_t"])
    nominal = Nominal(short_launcher.t, short_launcher.position, short_launcher.velocity,
                      short_launcher.C_b_e(), short_launcher.specific_force,
                      short_launcher.angular_rate, {})
    A, G = es.jacobians(nominal)
    np.testing.assert_array_equal(A, model.A)
    np.testing.assert_array_equal(G, model.G)
    np.testing.assert_array_equal(es.Qc, model.Qc)
    np.testing.assert_array_equal(es.P0, model.P0)
    assert es.state_names == model.state_names
    assert sum((r.names for r in es.measurements.values()), ()) == model.measurement_names
    sigmas = np.repeat([r.sigma for r in es.measurements.values()], 3)
    np.testing.assert_array_equal(np.diag(model.R), sigmas**2)
    names = np.array(model.state_names)
    assert list(names[es.groups["attitude"]]) == ["psi_x", "psi_y", "psi_z"]
    assert list(names[es.groups["bp"]]) == ["bp_x", "bp_y", "bp_z"]
    assert list(names[es.groups["reference"]]) == ["psi_ref_x", "psi_ref_y", "psi_ref_z"]
    assert list(names[~es.reset]) == [*(f"x{i}" for i in range(19, 26)),
                                      "psi_ref_x", "psi_ref_y", "psi_ref_z"]
    np.testing.assert_allclose(es.decay["bg"], -1.0 / model.parameters["c_g"])


@pytest.mark.parametrize("frame", ["ecef", "body"])
def test_correct_feeds_back_the_error_estimate(rocket, frame):
    """``correct`` moves position and velocity by ``nav_sign dx``, the parameters by ``dx``,
    and rotates the attitude by ``exp(S(dx_att))`` on the side of the model's attitude
    error (ECEF ``psi``: left; body ``dtheta``: right)."""
    es = Ecef21ErrorState.build(attitude_error=frame)
    k = slice(100, 103)
    nominal = Nominal(rocket.t[k], rocket.position[k], rocket.velocity[k], rocket.C_b_e()[k],
                      rocket.specific_force[k], rocket.angular_rate[k],
                      {g: np.zeros((3, 3)) for g in es.parameters})
    dx = np.random.default_rng(0).normal(scale=1e-2, size=(3, 21))
    out = es.correct(nominal, dx)
    np.testing.assert_allclose(out.position - nominal.position, dx[:, 0:3], atol=1e-8)
    np.testing.assert_allclose(out.velocity - nominal.velocity, dx[:, 3:6], atol=1e-12)
    np.testing.assert_array_equal(out.parameters["sa"], dx[:, 18:21])
    C, C2 = nominal.C_b_e, out.C_b_e
    rel = C2 @ np.swapaxes(C, 1, 2) if frame == "ecef" else np.swapaxes(C, 1, 2) @ C2
    np.testing.assert_allclose(log_so3(rel), dx[:, 6:9], atol=1e-14)


def test_ekf_takes_an_error_state_model(short_launcher):
    """A configured error-state model runs the same filter as its family name."""
    from navlib.models.launcher import LauncherErrorState
    from navlib.sensors import load_preset, simulate_gnss, simulate_imu
    from navlib.strapdown import StrapdownState

    spec = load_preset("launcher_table1")
    imu = simulate_imu(short_launcher, spec, seed=3)
    gnss = simulate_gnss(short_launcher, spec, seed=4, rate_hz=5.0)
    init = StrapdownState.from_trajectory(short_launcher)
    by_name = filters.ekf(imu, gnss, initial=init, biases="GAP", bias_model="random_walk")
    es = LauncherErrorState.build("ins_gps", "GAP", "random_walk",
                                  step_s=float(np.median(np.diff(imu.t))))
    by_model = filters.ekf(imu, gnss, initial=init, model=es)
    np.testing.assert_array_equal(by_model.position, by_name.position)
    np.testing.assert_array_equal(by_model.sigma, by_name.sigma)
    assert by_model.model == "launcher" and set(by_model.parameters) == {"bg", "ba", "bp"}


@pytest.mark.parametrize("frame", ["ecef", "body"])
def test_reset_jacobian_maps_the_attitude_error_across_the_feedback(frame):
    """After feeding back a 0.1 rad attitude correction ``a``, the residual error of a truth
    ``a + delta`` away is ``J delta`` to first order in ``delta`` (left/right Jacobian of
    SO(3) to first order in ``a``); the opposite sign misses by ``|a| |delta|``."""
    es = Ecef21ErrorState.build(attitude_error=frame)
    rng = np.random.default_rng(5)
    C_hat = exp_so3(rng.normal(size=3))
    dx = np.zeros(21)
    dx[6:9] = a = np.array([0.06, -0.05, 0.06])
    J = es.reset_jacobian(dx)[6:9, 6:9]
    np.testing.assert_array_equal(np.delete(np.delete(es.reset_jacobian(dx), np.s_[6:9], 0),
                                            np.s_[6:9], 1), np.eye(18))
    for _ in range(5):
        delta = rng.normal(scale=1e-4, size=3)
        if frame == "ecef":
            C = exp_so3(a + delta) @ C_hat
            left = log_so3(C @ (exp_so3(a) @ C_hat).T)
        else:
            C = C_hat @ exp_so3(a + delta)
            left = log_so3((C_hat @ exp_so3(a)).T @ C)
        miss = np.linalg.norm(left - J @ delta) / np.linalg.norm(delta)
        wrong = np.linalg.norm(left - (2 * np.eye(3) - J) @ delta) / np.linalg.norm(delta)
        assert miss < 0.01 < 0.05 < wrong


def test_ekf_takes_a_new_measurement_as_one_object(short_launcher):
    """A measurement the model does not declare, given with its rows, runs the same filter
    as the model's own rows (GNSS velocity on the 21-state model) and its rows follow the
    model's in the result; bad epochs are rejected."""
    from navlib.filters.measurements import GnssVelocity
    from navlib.models.base import MeasurementRows
    from navlib.sensors import load_preset, simulate_gnss, simulate_imu
    from navlib.strapdown import StrapdownState

    spec = load_preset("launcher_table1")
    imu = simulate_imu(short_launcher, spec, seed=5)
    gnss = simulate_gnss(short_launcher, spec, seed=6, rate_hz=5.0)
    init = StrapdownState.from_trajectory(short_launcher)
    declared = filters.ekf(imu, gnss, initial=init, model="ecef21", gnss_velocity_sigma=0.2)
    es = Ecef21ErrorState.build()
    kg = np.searchsorted(imu.t, gnss["t"].to_numpy() - 1e-9)
    np.testing.assert_allclose(imu.t[kg], gnss["t"], atol=1e-9)
    velocity = GnssVelocity(es, kg, gnss[["vx", "vy", "vz"]].to_numpy(),
                            rows=MeasurementRows(("gnss_vx", "gnss_vy", "gnss_vz"), 0.2))
    extra = filters.ekf(imu, gnss, initial=init, model=es, measurements=[velocity])
    assert extra.measurement_names == declared.measurement_names
    np.testing.assert_array_equal(extra.position, declared.position)
    np.testing.assert_array_equal(extra.innovation, declared.innovation)
    with pytest.raises(NavlibInputError, match="declares no rows"):
        GnssVelocity(es, kg, gnss[["vx", "vy", "vz"]].to_numpy())
    bad = GnssVelocity(es, kg + imu.t.size, gnss[["vx", "vy", "vz"]].to_numpy(),
                       rows=MeasurementRows(("vx", "vy", "vz"), 0.2))
    with pytest.raises(NavlibInputError, match="IMU sample"):
        filters.ekf(imu, gnss, initial=init, model=es, measurements=[bad])


def test_a_diverged_ekf_state_is_a_clear_error():
    from navlib.filters.ekf import _window_nominal

    t = np.arange(3) * 0.01
    state = (np.array([np.nan, 0.0, 0.0]), np.zeros(3), np.eye(3))
    with pytest.raises(NavlibInputError, match=r"diverged.*t = 0\.000 s"):
        _window_nominal(None, t, np.zeros((3, 3)), np.zeros((3, 3)), state, {}, None)


def test_own_model_steps_are_the_same_numbers(short_launcher):
    """``own_model=True`` writes ``F`` and ``Gamma`` into the model's own ``A`` and ``G``:
    the same products (to the bit) and the same prepared filter, without new arrays."""
    def model():
        return launcher("ins_gps_att_rt", "GAP", "markov", short_launcher)

    ref = filters.prepare_linear(model(), compact=True)
    owned = model()
    got = filters.prepare_linear(owned, compact=True, own_model=True)
    for name in ("F", "Gamma", "L"):
        np.testing.assert_array_equal(getattr(got.steps, name), getattr(ref.steps, name))
    assert np.shares_memory(got.steps.F, owned.A) and np.shares_memory(got.steps.Gamma, owned.G)
    np.testing.assert_array_equal(got.covariance.P_post, ref.covariance.P_post)
    np.testing.assert_array_equal(got.gains.K, ref.gains.K)
    constant = launcher("ins_gps", "GAP", "markov", short_launcher)     # A per sample, H fixed
    steps = filters.linear_steps(constant, own_model=False)
    assert not np.shares_memory(steps.F, constant.A)
