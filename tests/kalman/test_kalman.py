"""The compiled Kalman kernels (issue 26) equal the NumPy code they replaced
(tests/support/kalman_reference.py): one step within 1e-12 relative on random and paper cases, whole
runs (a 30 001-epoch launcher recursion, the 86 s rocket EKF) within the drift rounding
accumulates."""

import importlib

import numpy as np
import pytest
from support import kalman_reference as ref

from navlib import kalman
from navlib.filters import linear_steps
from navlib.kalman import (
    definite_noise,
    fixed_updates_kernel,
    joseph_update,
    kalman_gain,
    predict_kernel,
    propagate_kernel,
    riccati_kernel,
    update_kernel,
)
from navlib.models import launcher
from navlib.trajectory import launcher_ascent

STEP_RTOL = 1e-12
ekf_updates = importlib.import_module("navlib.filters.ekf_updates")


def rel(a, b) -> float:
    """Largest difference relative to the largest entry of the reference ``b``."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    scale = np.abs(b).max()
    return float(np.abs(a - b).max() / scale) if scale else float(np.abs(a).max())


def random_case(rng, n, m, noise):
    """A prior covariance with spread variances, a measurement matrix and ``R`` definite,
    singular (one redundant channel) or zero."""
    B = rng.standard_normal((n, n)) * np.logspace(-1, 1, n)
    P = B @ B.T + 1e-6 * np.eye(n)
    H = rng.standard_normal((m, n))
    if noise == "definite":
        C = rng.standard_normal((m, m))
        R = C @ C.T + 0.1 * np.eye(m)
    elif noise == "singular":
        C = rng.standard_normal((m, m - 1))
        R = C @ C.T
    else:
        R = np.zeros((m, m))
    return P, H, R


@pytest.mark.parametrize("noise", ["definite", "singular", "zero"])
@pytest.mark.parametrize(("n", "m"), [(5, 2), (18, 9), (28, 12)])
def test_one_step_equals_numpy(n, m, noise):
    rng = np.random.default_rng(n * 100 + m)
    for _ in range(5):
        P, H, R = random_case(rng, n, m, noise)
        definite = bool(definite_noise(R))
        assert definite == (noise == "definite")
        P_post, gains = joseph_update(P, H, R)
        want_P, want_K, want_S, want_dof = ref.joseph(P, H, R, definite)
        assert rel(P_post, want_P) < STEP_RTOL
        assert rel(gains.K, want_K) < STEP_RTOL
        assert rel(gains.S_pinv, want_S) < STEP_RTOL
        assert gains.dof == want_dof
        F = np.eye(n) + 0.1 * rng.standard_normal((n, n))
        Q = np.diag(rng.uniform(0.0, 1.0, n))
        out = np.empty((n, n))
        predict_kernel(P, F, Q, out)
        assert rel(out, ref.predict(P, F, Q)) < STEP_RTOL
        np.testing.assert_array_equal(out, out.T)


def test_batched_gain_equals_numpy_per_member_and_keeps_shapes():
    rng = np.random.default_rng(3)
    cases = [random_case(rng, 6, 3, noise) for noise in ("definite", "zero", "singular")]
    P, H, R = (np.array(c) for c in zip(*cases, strict=True))
    gains = kalman_gain(P.reshape(3, 1, 6, 6), H.reshape(3, 1, 3, 6), R.reshape(3, 1, 3, 3))
    assert gains.K.shape == (3, 1, 6, 3) and gains.dof.shape == (3, 1)
    for b, (P_b, H_b, R_b) in enumerate(cases):
        K, S_pinv, dof = ref.gain(P_b, H_b, R_b, b == 0)
        assert rel(gains.K[b, 0], K) < STEP_RTOL
        assert rel(gains.S_pinv[b, 0], S_pinv) < STEP_RTOL
        assert gains.dof[b, 0] == dof
    one = kalman_gain(P[0], H[0], R[0])
    assert one.K.shape == (6, 3) and np.ndim(one.dof) == 0
    no_meas = kalman_gain(P[0], np.zeros((0, 6)), np.zeros((0, 0)))
    assert no_meas.K.shape == (6, 0) and no_meas.dof == 0


@pytest.mark.parametrize("a", [0, 7])
def test_recursion_kernel_step_by_step_equals_numpy(a):
    """From epoch ``a`` on (``F``/``Q`` then start at the step into epoch ``a``), with
    updates at some epochs only and a zero ``R`` at one: priors, kept posteriors and gains."""
    rng = np.random.default_rng(11 + a)
    n, m, count = 8, 3, 12
    P0, H1, R1 = random_case(rng, n, m, "definite")
    F = np.eye(n) + 0.05 * rng.standard_normal((count, n, n))
    Q = np.broadcast_to(0.01 * np.eye(n), (count, n, n)).copy()
    H = np.broadcast_to(H1, (count, m, n)).copy()
    R = np.broadcast_to(R1, (count, m, m)).copy()
    R[4] = 0.0
    update = rng.uniform(size=count) < 0.6
    update[4] = True
    definite = definite_noise(R)
    slot = np.where(np.arange(count) % 3 == 0, np.arange(count) // 3, -1)
    prior, post = np.empty((count, n, n)), np.empty((4, n, n))
    K, S_pinv, dof = np.zeros((count, n, m)), np.zeros((count, m, m)), np.zeros(count, np.int64)
    last = riccati_kernel(P0, F, Q, H, R, definite, update, 1e-12, a, prior, slot, post, K,
                          S_pinv, dof)
    P = P0
    for i in range(count):
        if a + i:
            s = i - 1 if a == 0 else i
            P = ref.predict(P, F[s], Q[s])
        assert rel(prior[i], P) < 1e-11
        if update[i]:
            P, K_i, S_i, dof_i = ref.joseph(P, H[i], R[i], definite[i])
            assert rel(K[i], K_i) < 1e-11 and rel(S_pinv[i], S_i) < 1e-11
            assert dof[i] == dof_i
        else:
            assert not K[i].any() and dof[i] == 0
        if slot[i] >= 0:
            assert rel(post[slot[i]], P) < 1e-11
    assert rel(last, P) < 1e-11


@pytest.fixture(scope="module")
def launcher_steps():
    """The paper case: 28-state INS/GPS/att + RT launcher model, GAP Markov biases,
    150 s at 200 Hz (30 001 epochs), Euler steps."""
    model = launcher("ins_gps_att_rt", "GAP", "markov", launcher_ascent())
    return linear_steps(model)


def test_paper_step_equals_numpy(launcher_steps):
    """Single steps of the 28-state paper model at epochs along the flight."""
    s = launcher_steps
    P = s.P0
    definite = bool(definite_noise(s.R[0]))
    for k in (1, 2, 1000, 20000, 30000):
        P_k = ref.predict(P, s.F[k - 1], s.Q[k - 1])
        out = np.empty_like(P_k)
        predict_kernel(P, np.ascontiguousarray(s.F[k - 1]), s.Q[k - 1], out)
        assert rel(out, P_k) < STEP_RTOL
        P_post, gains = joseph_update(P_k, s.H[k], s.R[k])
        want_P, want_K, _, _ = ref.joseph(P_k, s.H[k], s.R[k], definite)
        assert rel(P_post, want_P) < STEP_RTOL
        assert rel(gains.K, want_K) < STEP_RTOL
        P = want_P


def test_paper_recursion_30001_epochs_equals_numpy(launcher_steps):
    """The whole recursion: sigmas agree within 1e-9 relative per state (measured about
    1e-12 on this model), the gains within 1e-9 of their largest entry."""
    s = launcher_steps
    measured = np.ones(s.t.size, dtype=bool)
    P_prior, P_post, gains = kalman.covariance_recursion(s.F, s.Q, s.H, s.R, s.P0[None],
                                                             measured, 1e-12, gains=True)
    want_prior, want_post, want_K, _, want_dof = ref.recursion(
        s.F, s.Q, s.H, s.R, s.P0, measured, definite_noise(s.R))
    sigma = np.sqrt(np.diagonal(P_post[0], axis1=1, axis2=2))
    want_sigma = np.sqrt(np.diagonal(want_post, axis1=1, axis2=2))
    known = want_sigma > 0                 # states without initial or process noise stay 0
    np.testing.assert_array_equal(sigma[~known], 0.0)
    assert np.max(np.abs(sigma - want_sigma)[known] / want_sigma[known]) < 1e-9
    assert rel(P_prior[0][-1], want_prior[-1]) < 1e-9
    assert rel(gains.K[0], want_K) < 1e-9
    np.testing.assert_array_equal(gains.dof[0], want_dof)


def test_fixed_updates_kernel_equals_one_call_per_update():
    """A run of updates with one design in one kernel call, and the propagation after it,
    equal the propagation and update called once per update, to the bit (the same
    compiled steps, inlined into the one kernel)."""
    rng = np.random.default_rng(4)
    n, m, steps = 6, 3, 9
    F = np.eye(n) + 0.05 * rng.standard_normal((steps, n, n))
    Q = np.stack([np.eye(n) * 1e-3] * steps)
    A = rng.standard_normal((n, n))
    P = A @ A.T + np.eye(n)
    H, R = rng.standard_normal((m, n)), np.eye(m) * 0.1
    kept, samples = np.array([5]), np.array([0, 2, 3, 7], dtype=np.int64)
    z, x = rng.standard_normal((samples.size, m)), rng.standard_normal(n)
    out = (np.empty((4, n)), np.empty((4, n, n)), np.empty((4, m)), np.empty(4),
           np.empty(4, dtype=np.int64))
    x_end, P_end = fixed_updates_kernel(x, P, F, Q, kept, 0, samples, z, H, R, True, 1e-12,
                                        *out, steps)
    K, S_pinv = np.empty((n, m)), np.empty((m, m))
    j0 = 0
    for u, j in enumerate(samples):
        x, P = propagate_kernel(x, P, F, Q, kept, j0, j)
        j0 = j
        P_post = np.empty((n, n))
        x, innov, nis, dof = update_kernel(x, P, z[u], H, R, True, 1e-12, P_post, K, S_pinv)
        P = P_post
        for got, want in zip(out, (x, P, innov, nis, dof), strict=True):
            np.testing.assert_array_equal(got[u], want)
    x, P = propagate_kernel(x, P, F, Q, kept, j0, steps)
    np.testing.assert_array_equal(x_end, x)
    np.testing.assert_array_equal(P_end, P)


def test_rocket_ekf_86_s_equals_numpy_loop(monkeypatch):
    """The 86 s sounding-rocket EKF (21 states, 100 Hz IMU, 1 Hz GNSS) with the compiled
    propagation and update against the same loop with the NumPy steps: position within
    1 mm, sigmas within 1e-9 relative, NIS within 1e-8 relative."""
    from navlib import sensors, strapdown
    from navlib.filters import ekf
    from navlib.trajectory import sounding_rocket

    traj = sounding_rocket()
    spec = sensors.load_preset("motionpak_tactical")
    imu = sensors.simulate_imu(traj, spec, seed=1)
    gnss = sensors.simulate_gnss(traj, spec, seed=2)

    def run():
        return ekf(imu, gnss, initial=strapdown.StrapdownState.from_trajectory(traj),
                   model="ecef21", model_options={"sensors": "motionpak_tactical"})

    compiled = run()
    monkeypatch.setattr(ekf_updates, "fixed_updates_kernel", ref.fixed_updates)
    numpy_run = run()
    assert np.abs(compiled.position - numpy_run.position).max() < 1e-3
    assert np.max(np.abs(compiled.sigma - numpy_run.sigma) / numpy_run.sigma) < 1e-9
    assert rel(compiled.nis, numpy_run.nis) < 1e-8


def test_definite_noise_with_a_numerically_singular_s_takes_the_pseudo_inverse():
    """``R`` positive definite but lost in rounding beside a huge ``H P H'`` of rank one:
    the LU inverse meets a zero pivot and the gain is the pseudo-inverse one (NumPy's
    ``inv`` raised a bare LinAlgError here)."""
    n, m = 3, 2
    v = np.array([1.0, 2.0, 3.0])
    P = 1e40 * np.outer(v, v)
    H = np.array([[1.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    R = np.eye(m)
    assert definite_noise(R)
    P_post, gains = joseph_update(P, H, R)
    K, S_pinv, dof = ref.gain(P, H, R, definite=False)
    assert gains.dof == dof == 1
    assert rel(gains.K, K) < STEP_RTOL and rel(gains.S_pinv, S_pinv) < STEP_RTOL
    assert np.isfinite(P_post).all() and P_post.shape == (n, n)
