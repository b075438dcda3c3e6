"""The 21-state ECEF model (spec excitability.md A4-A8): Jacobians against finite
differences of the nonlinear model, discretisation against fine-step integration, and the
relation psi = C_hat dtheta between the two attitude-error frames."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from navlib import NavlibInputError, earth
from navlib.models import ecef
from navlib.models.base import HOLDS
from navlib.rotations import skew, unskew
from navlib.trajectory import build_trajectory

NOISE = {  # spec excitability.md §5 (SI)
    "arw_rad_sqrt_s": 1.45e-4, "vrw_m_s_sqrt_s": 1.67e-3, "bg_rw_rad_s_sqrt_s": 4.8e-6,
    "ba_rw_m_s2_sqrt_s": 1e-4, "sg_rw_per_sqrt_s": 1e-5, "sa_rw_per_sqrt_s": 1e-5,
}


def spinning_trajectory(rate_hz=100.0, duration=2.0, spin_hz=1.5, accel=30.0):
    """Accelerating, spinning (and nodding) flight with lateral weave, exact IMU."""
    t = np.arange(0.0, duration + 0.5 / rate_hz, 1.0 / rate_hz)
    lat, lon = np.radians(-5.92), np.radians(-35.16)
    C_n_e = earth.ned_to_ecef_matrix(lat, lon)
    north, east, up = C_n_e[:, 0], C_n_e[:, 1], -C_n_e[:, 2]
    d = 0.8 * up + 0.6 * north
    wl, al = 0.7, 40.0
    pos = (earth.geodetic_to_ecef(lat, lon, 100.0) + np.outer(0.5 * accel * t**2, d)
           + np.outer(al * np.sin(wl * t), east))
    vel = np.outer(accel * t, d) + np.outer(al * wl * np.cos(wl * t), east)
    acc = np.outer(np.full_like(t, accel), d) - np.outer(al * wl**2 * np.sin(wl * t), east)
    R0 = Rotation.from_matrix(C_n_e) * Rotation.from_euler("y", -80, degrees=True)
    w0, alpha, beta, nu = 2 * np.pi * spin_hz, 2.0, 0.1, 3.0
    Rx = Rotation.from_rotvec(np.outer(w0 * t + 0.5 * alpha * t**2, [1, 0, 0]))
    Ry = Rotation.from_rotvec(np.outer(beta * np.sin(nu * t), [0, 1, 0]))
    w_eb_b = (Ry.inv().apply(np.outer(w0 + alpha * t, [1, 0, 0]))
              + np.outer(beta * nu * np.cos(nu * t), [0, 1, 0]))
    return build_trajectory(t, pos, vel, acc, (R0 * Rx * Ry).as_matrix(), w_eb_b)


@pytest.fixture(scope="module")
def traj():
    return spinning_trajectory()


# ---- nonlinear model (España Eq. 1 with the spec-A7 IMU inverse model), independent code ----

def _derivatives(P, V, C, params, f_hat, w_hat):
    b_g, b_a, s_g, s_a = params
    f_b = (f_hat - b_a) / (1.0 + s_a)
    w_ib_b = (w_hat - b_g) / (1.0 + s_g)
    omega = np.array([0.0, 0.0, earth.OMEGA_E])
    dP = V
    dV = C @ f_b + earth.normal_gravity_ecef(P) - 2.0 * np.cross(omega, V)
    dC = C @ skew(w_ib_b) - skew(omega) @ C
    return dP, dV, dC


def _error_rate(x, P_r, V_r, C_r, f_hat, w_hat, frame):
    """Rate of the error state x (21,) at the reference sample, from the nonlinear model."""
    P, V = P_r + x[0:3], V_r + x[3:6]
    R = Rotation.from_rotvec(x[6:9]).as_matrix()
    C = R @ C_r if frame == "ecef" else C_r @ R
    params = (x[9:12], x[12:15], x[15:18], x[18:21])
    dP, dV, dC = _derivatives(P, V, C, params, f_hat, w_hat)
    dP_r, dV_r, dC_r = _derivatives(P_r, V_r, C_r, (np.zeros(3),) * 4, f_hat, w_hat)
    if frame == "ecef":  # R = C C_r'; d(psi)/dt = unskew(R_dot R') up to O(psi^2)
        R_dot = dC @ C_r.T + C @ dC_r.T
        d_att = unskew(R_dot @ R.T)
    else:  # R = C_r' C; d(dtheta)/dt = unskew(R' R_dot) up to O(dtheta^2)
        R_dot = dC_r.T @ C + C_r.T @ dC
        d_att = unskew(R.T @ R_dot)
    return np.concatenate([dP - dP_r, dV - dV_r, d_att, np.zeros(12)])


STEPS = np.repeat([1.0, 0.1, 1e-4, 1e-5, 1e-3, 1e-4, 1e-4], 3)


@pytest.mark.parametrize("frame", ["ecef", "body"])
@pytest.mark.parametrize("k", [0, 77, 160])
def test_jacobian_matches_finite_differences(traj, frame, k):
    A, G = ecef.ecef21_jacobians(traj.position, traj.C_b_e(), traj.specific_force,
                                 traj.angular_rate, frame)
    args = (traj.position[k], traj.velocity[k], traj.C_b_e()[k], traj.specific_force[k],
            traj.angular_rate[k], frame)
    A_fd = np.empty((21, 21))
    for j in range(21):
        dx = np.zeros(21)
        dx[j] = STEPS[j]
        A_fd[:, j] = (_error_rate(dx, *args) - _error_rate(-dx, *args)) / (2 * STEPS[j])
    scale = np.maximum(np.abs(A_fd).max(axis=0, keepdims=True), 1e-6)
    np.testing.assert_array_less(np.abs(A[k] - A_fd) / scale, 1e-6)
    # the structure of Eq. 24: parameter rows are zero, noise input blockdiag(B_kin, I12)
    assert not A[k, 9:].any()
    np.testing.assert_array_equal(G[k, 9:, 6:], np.eye(12))
    C = traj.C_b_e()[k]
    np.testing.assert_allclose(G[k, 3:6, 0:3], C)
    np.testing.assert_allclose(G[k, 6:9, 3:6], C if frame == "ecef" else np.eye(3))


def test_frames_related_by_psi_equals_C_dtheta(traj):
    """A_ecef = T A_body T' + T_dot T' with T = blockdiag(I, I, C_hat, I12) (spec A4)."""
    C = traj.C_b_e()
    A_e, G_e = ecef.ecef21_jacobians(traj.position, C, traj.specific_force,
                                     traj.angular_rate, "ecef")
    A_b, G_b = ecef.ecef21_jacobians(traj.position, C, traj.specific_force,
                                     traj.angular_rate, "body")
    n = len(traj)
    T = np.broadcast_to(np.eye(21), (n, 21, 21)).copy()
    T[:, 6:9, 6:9] = C
    T_dot = np.zeros((n, 21, 21))
    w_eb_b = traj.angular_rate - np.einsum("nji,j->ni", C, earth.EARTH_RATE_ECEF)
    T_dot[:, 6:9, 6:9] = C @ skew(w_eb_b)
    A_expected = T @ A_b @ np.swapaxes(T, 1, 2) + T_dot @ np.swapaxes(T, 1, 2)
    np.testing.assert_allclose(A_e, A_expected, atol=1e-9)
    np.testing.assert_allclose(G_e, T @ G_b, atol=1e-12)


def _rk4_transition(A_steps, dt, substeps):
    n = A_steps.shape[-1]
    Phi = np.eye(n)
    h = dt / substeps
    for A in A_steps:
        for _ in range(substeps):
            k1 = A @ Phi
            k2 = A @ (Phi + 0.5 * h * k1)
            k3 = A @ (Phi + 0.5 * h * k2)
            k4 = A @ (Phi + h * k3)
            Phi = Phi + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return Phi


def _rk4_noise(A_steps, W_steps, dt, substeps):
    n = A_steps.shape[-1]
    Q = np.zeros((n, n))
    h = dt / substeps

    def rate(A, W, Q):
        return A @ Q + Q @ A.T + W

    for A, W in zip(A_steps, W_steps, strict=True):
        for _ in range(substeps):
            k1 = rate(A, W, Q)
            k2 = rate(A, W, Q + 0.5 * h * k1)
            k3 = rate(A, W, Q + 0.5 * h * k2)
            k4 = rate(A, W, Q + h * k3)
            Q = Q + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return Q


@pytest.mark.parametrize("frame", ["ecef", "body"])
def test_discretised_epochs_match_fine_step_integration(traj, frame):
    model = ecef.ecef21(traj, NOISE, attitude_error=frame)
    epochs = traj.at_rate(1.0)
    fast = model.discretize(epochs=epochs, method="series", hold="left")
    ref = model.discretize(epochs=epochs, method="expm", hold="left")
    np.testing.assert_allclose(fast.t, [0.0, 1.0, 2.0])
    span = slice(epochs[0], epochs[1])
    Phi = _rk4_transition(model.A[span], 0.01, 10)
    scale = np.abs(Phi).max(axis=0)
    np.testing.assert_array_less(np.abs(fast.F[0] - Phi) / scale, 1e-9)
    np.testing.assert_array_less(np.abs(ref.F[0] - Phi) / scale, 1e-9)
    W = np.einsum("kiq,qr,kjr->kij", model.G[span], model.Qc, model.G[span])
    Q = _rk4_noise(model.A[span], W, 0.01, 10)
    d = np.sqrt(np.diag(Q))
    np.testing.assert_allclose(fast.Q[0] / np.outer(d, d), Q / np.outer(d, d), atol=1e-8)
    np.testing.assert_allclose(ref.Q[0] / np.outer(d, d), Q / np.outer(d, d), atol=1e-8)
    np.testing.assert_allclose(fast.H[0], np.hstack([np.eye(3), np.zeros((3, 18))]))
    np.testing.assert_allclose(fast.R[0], 25.0 * np.eye(3))


def test_hold_converges_to_continuous_model():
    """Against RK4 on the continuous A(t): holding the left sample over each IMU step is
    first order (error halves when the rate doubles), the two-sample mean second order."""
    fine = spinning_trajectory(rate_hz=3200.0, duration=1.0)
    A_fine = ecef.ecef21(fine, NOISE).A
    Phi = np.eye(21)
    h = 2.0 / 3200  # RK4 step; its midpoint is the next 3200 Hz sample
    for j in range(0, len(fine) - 2, 2):
        A0, Am, A1 = A_fine[j], A_fine[j + 1], A_fine[j + 2]
        k1 = A0 @ Phi
        k2 = Am @ (Phi + 0.5 * h * k1)
        k3 = Am @ (Phi + 0.5 * h * k2)
        k4 = A1 @ (Phi + h * k3)
        Phi = Phi + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    scale = np.abs(Phi).max(axis=0)
    errors = {}
    for rate in (100.0, 200.0):
        traj = spinning_trajectory(rate_hz=rate, duration=1.0)
        model = ecef.ecef21(traj, NOISE)
        for hold in HOLDS:
            dm = model.discretize(epochs=[0, len(traj) - 1], method="series", hold=hold)
            errors[hold, rate] = np.max(np.abs(dm.F[0] - Phi) / scale)
    assert 1.7 < errors["left", 100.0] / errors["left", 200.0] < 2.3
    assert 3.4 < errors["mean", 100.0] / errors["mean", 200.0] < 4.6
    assert errors["mean", 100.0] < 2e-3 < errors["left", 100.0]


def test_model_contents_and_parameters(traj):
    model = ecef.ecef21(traj, NOISE, gnss_sigma_m=3.0, sigma_sg_ppm=300.0)
    assert model.state_names == ecef.STATE_NAMES
    assert ecef.PAPER_IDS["sg_x"] == "e16" and ecef.PAPER_IDS["sa_x"] == "e19"
    assert model.A.shape == (len(traj), 21, 21) and model.G.shape == (len(traj), 21, 18)
    assert model.Qc.shape == (18, 18) and len(model.noise_names) == 18
    sigma0 = np.sqrt(np.diag(model.P0))
    np.testing.assert_allclose(sigma0[[0, 3, 6, 9, 12, 15, 18]],
                               [30.0, 3.0, np.radians(1.0), np.radians(0.05), 0.02, 3e-4, 1e-3])
    np.testing.assert_allclose(model.R, 9.0 * np.eye(3))
    np.testing.assert_allclose(np.diag(model.Qc)[[0, 3, 6, 9, 12, 15]],
                               np.square([1.67e-3, 1.45e-4, 4.8e-6, 1e-4, 1e-5, 1e-5]))
    assert model.parameters["sigma_sg_ppm"] == 300.0
    assert model.parameters["attitude_error"] == "ecef"
    # scale-factor columns scale with the measured signals (spec A7)
    k = 50
    np.testing.assert_allclose(model.A[k, 6:9, 15:18],
                               -traj.C_b_e()[k] * traj.angular_rate[k][None, :])


def test_default_preset_gives_the_spec_values(traj):
    """Preset motionpak_tactical = spec excitability.md §5 (noise densities and P0)."""
    noise = ecef.imu_noise_densities()
    for key, value in NOISE.items():
        np.testing.assert_allclose(noise[key], value, rtol=0.01)
    model = ecef.ecef21(traj)
    assert model.parameters["sensors"] == "motionpak_tactical"
    np.testing.assert_allclose(model.P0, ecef.initial_covariance(), rtol=1e-12)
    np.testing.assert_allclose(ecef.initial_covariance(), ecef.initial_covariance(NOISE))
    assert ecef.parameter_sigmas("motionpak_tactical") == pytest.approx(
        {"sigma_bg_deg_s": 0.05, "sigma_ba_m_s2": 0.02, "sigma_sg_ppm": 5000.0,
         "sigma_sa_ppm": 1000.0})


def test_markov_bias_folds_into_the_random_walk():
    from navlib.sensors import ImuSpec, TriadSpec

    gyro = TriadSpec(bias=1e-4, noise_density=1e-5, bias_markov_sigma=2e-5,
                     bias_markov_tau=100.0, bias_random_walk=1e-7)
    noise = ecef.imu_noise_densities(ImuSpec(gyro=gyro, accel=TriadSpec(noise_density=1e-3)))
    np.testing.assert_allclose(noise["bg_rw_rad_s_sqrt_s"],
                               np.sqrt(1e-14 + 2 * 4e-10 / 100.0))
    sig = ecef.parameter_sigmas(ImuSpec(gyro=gyro, accel=TriadSpec()))
    assert sig["sigma_bg_deg_s"] == pytest.approx(np.degrees(1e-4))
    assert sig["sigma_ba_m_s2"] == ecef.P0_DEFAULTS["sigma_ba_m_s2"]  # zero -> default


def test_cached_epoch_model_is_reused(traj):
    a = ecef.ecef21_at_epochs(traj, sensors=NOISE, attitude_error="body")
    b = ecef.ecef21_at_epochs(traj, sensors=dict(NOISE), attitude_error="body")
    assert a is b
    assert not a.F.flags.writeable
    c = ecef.ecef21_at_epochs(traj, sensors=NOISE, attitude_error="ecef")
    assert c is not a and c.F.shape == (2, 21, 21)
    np.testing.assert_array_equal(c.P0, ecef.initial_covariance())
    P0 = ecef.initial_covariance(sigma_theta0_deg=2.0)
    assert P0[6, 6] == pytest.approx(np.radians(2.0) ** 2) and P0[0, 0] == 900.0


@pytest.mark.parametrize("kwargs, word", [
    ({"attitude_error": "ned"}, "attitude_error"),
    ({"gnss_sigma_m": -1.0}, "gnss_sigma_m"),
    ({"sigma_p0_m": 0.0}, "sigma_p0_m"),
    ({"sigma_pos": 3.0}, "sigma_pos"),
])
def test_bad_input_names_the_argument(traj, kwargs, word):
    with pytest.raises((NavlibInputError, TypeError), match=word):
        ecef.ecef21(traj, NOISE, **kwargs)


def test_bad_sensors_and_epochs(traj):
    with pytest.raises(NavlibInputError, match="missing"):
        ecef.ecef21(traj, {"arw_rad_sqrt_s": 1e-4})
    with pytest.raises(NavlibInputError, match="sensors"):
        ecef.ecef21(traj, object())
    model = ecef.ecef21(traj, NOISE)
    with pytest.raises(NavlibInputError, match="epochs"):
        model.discretize(epochs=[0, 10_000])
    with pytest.raises(NavlibInputError, match="method"):
        model.discretize(epochs=[0, 100], method="rk4")
    with pytest.raises(NavlibInputError, match="hold"):
        model.discretize(epochs=[0, 100], hold="right")
