"""Covariance recursion, frames, correlation and the Ham–Brown eigen-analysis."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from navlib import NavlibInputError
from navlib.covariance import (
    block_in_frame,
    convergence_time,
    correlation,
    covariance_ratio,
    group_correlation,
    ins_only_covariance,
    kalman_covariance,
    normalized_eigen,
    sigma_in_frame,
)
from navlib.models.base import DiscreteModel


def _random_system(seed, n=6, m=2, N=60):
    rng = np.random.default_rng(seed)
    F = np.eye(n) + 0.1 * rng.normal(size=(N - 1, n, n))
    G = rng.normal(size=(N - 1, n, n))
    Q = 0.01 * G @ np.swapaxes(G, 1, 2)
    H = rng.normal(size=(N, m, n))
    L = rng.normal(size=(N, m, m))
    R = L @ np.swapaxes(L, 1, 2) + 0.1 * np.eye(m)
    B = rng.normal(size=(n, n))
    P0 = B @ B.T + np.eye(n)
    return F, Q, H, R, P0


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_joseph_matches_standard_form_and_information_form(seed):
    F, Q, H, R, P0 = _random_system(seed)
    res = kalman_covariance(F, Q, H, R, P0)
    n = P0.shape[0]
    P = P0
    for k in range(len(res.t)):
        if k:
            P = F[k - 1] @ P @ F[k - 1].T + Q[k - 1]
        np.testing.assert_allclose(res.P_prior[k], P, rtol=1e-9, atol=1e-12)
        # standard (non-Joseph) form
        K = P @ H[k].T @ np.linalg.inv(H[k] @ P @ H[k].T + R[k])
        P_std = (np.eye(n) - K @ H[k]) @ P
        # information form
        info = np.linalg.inv(P) + H[k].T @ np.linalg.solve(R[k], H[k])
        np.testing.assert_allclose(res.P_post[k], P_std, rtol=1e-8, atol=1e-10)
        np.testing.assert_allclose(res.P_post[k], np.linalg.inv(info), rtol=1e-8, atol=1e-10)
        P = res.P_post[k]
    assert np.allclose(res.sigma, np.sqrt(np.diagonal(res.P_post, axis1=1, axis2=2)))


def test_update_first_false_keeps_p0_as_posterior():
    F, Q, H, R, P0 = _random_system(3, N=5)
    res = kalman_covariance(F, Q, H, R, P0, update_first=False)
    np.testing.assert_allclose(res.P_post[0], P0)
    assert not res.measured[0] and res.measured[1:].all()


def test_ideal_measurements_r_zero_stable():
    F, Q, H, _, P0 = _random_system(4, N=400)
    res = kalman_covariance(F, Q, H, np.zeros((2, 2)), P0)
    HPH = np.einsum("kij,kjl,kml->kim", H, res.P_post, H)
    assert np.abs(HPH).max() < 1e-8 * np.abs(res.P_post).max()
    assert np.all(np.isfinite(res.P_post))
    assert np.linalg.eigvalsh(res.P_post).min() > -1e-9 * np.abs(res.P_post).max()
    # the limit of small R agrees with R = 0
    res_small = kalman_covariance(F, Q, H, 1e-10 * np.eye(2), P0)
    np.testing.assert_allclose(res_small.sigma, res.sigma, rtol=1e-3, atol=1e-6)


def test_singular_r_uses_pseudo_inverse_when_a_channel_is_redundant():
    # two identical noise-free channels: S is singular, the update must still be correct
    n = 3
    F = np.eye(n)
    Q = 1e-4 * np.eye(n)
    H = np.array([[1.0, 0, 0], [1.0, 0, 0]])
    res = kalman_covariance(F, Q, H, np.zeros((2, 2)), np.eye(n), n_epochs=10)
    assert res.sigma[-1, 0] < 1e-9
    np.testing.assert_allclose(res.sigma[:, 1], np.sqrt(1 + 1e-4 * np.arange(10)))


def test_ins_only_equals_pure_propagation_and_accepts_model():
    F, Q, H, R, P0 = _random_system(5)
    res = ins_only_covariance(F, Q, P0)
    P = P0
    for k in range(len(res.t)):
        if k:
            P = F[k - 1] @ P @ F[k - 1].T + Q[k - 1]
        np.testing.assert_allclose(res.P_post[k], P, rtol=1e-10)
    assert not res.measured.any()
    np.testing.assert_array_equal(res.P_prior, res.P_post)
    model = DiscreteModel(np.arange(60.0), F, Q, H, R, tuple("abcdef"), P0=P0)
    np.testing.assert_allclose(ins_only_covariance(model).P_post, res.P_post)
    np.testing.assert_allclose(kalman_covariance(model).P_post,
                               kalman_covariance(F, Q, H, R, P0).P_post)
    frame = kalman_covariance(model).to_frame()
    assert list(frame.columns) == ["t", "state", "sigma"] and len(frame) == 60 * 6


def test_bad_inputs_raise_named_errors():
    F, Q, H, R, P0 = _random_system(6)
    with pytest.raises(NavlibInputError, match="P0"):
        kalman_covariance(F, Q, H, R, P0[:3, :3])
    with pytest.raises(NavlibInputError, match="H"):
        kalman_covariance(F, Q, H[:10], R, P0)
    with pytest.raises(NavlibInputError, match="n_epochs"):
        kalman_covariance(F[0], Q[0], H[0], R[0], P0)
    with pytest.raises(NavlibInputError, match="state_names"):
        kalman_covariance(F, Q, H, R, P0, state_names=["a"])


def test_rotated_block_and_group_correlation():
    rng = np.random.default_rng(7)
    B = rng.normal(size=(50, 6, 6))
    P = B @ np.swapaxes(B, 1, 2) + np.eye(6)
    C = Rotation.random(50, random_state=1)
    block = block_in_frame(P, [0, 1, 2], C)
    Cm = C.as_matrix()
    np.testing.assert_allclose(block, Cm @ P[:, :3, :3] @ np.swapaxes(Cm, 1, 2), atol=1e-12)
    # trace is frame-invariant
    np.testing.assert_allclose(np.sum(sigma_in_frame(P, [0, 1, 2], C) ** 2, axis=1),
                               np.trace(P[:, :3, :3], axis1=1, axis2=2))
    # group correlation without rotation is the per-pair correlation
    rho = group_correlation(P, [0, 1, 2], [3, 4, 5])
    for a in range(3):
        np.testing.assert_allclose(rho[:, a], correlation(P, a, a + 3))
    # a vector and its own rotated copy are perfectly correlated
    x = rng.normal(size=(3, 3))
    Pfull = np.zeros((1, 6, 6))
    Cx = Rotation.random(random_state=2).as_matrix()
    T = np.vstack([np.eye(3), Cx.T])  # b = C' a, so C b = a
    Pfull[0] = T @ (x @ x.T + np.eye(3)) @ T.T
    np.testing.assert_allclose(group_correlation(Pfull, [0, 1, 2], [3, 4, 5], C_b=Cx), 1.0)
    full = correlation(P)
    np.testing.assert_allclose(np.diagonal(full, axis1=1, axis2=2), 1.0)
    assert np.all(np.abs(full) <= 1 + 1e-12)


def test_covariance_ratio_and_convergence_time():
    t = np.arange(11.0)
    sigma = np.column_stack([10.0 / (1 + t), np.full(11, 2.0), 1 + 0.01 * t])
    ratio = covariance_ratio(sigma)
    np.testing.assert_allclose(ratio[:, 0], 1 + t)
    np.testing.assert_allclose(ratio[:, 1], 1.0)
    tc = convergence_time(t, sigma, fraction=0.5)
    # 10/(1+t) <= 10 - 0.5 (10 - 10/11) = 5.4545 from t = 1 on
    assert tc[0] == 1.0
    assert np.isnan(tc[1]) and np.isnan(tc[2])


@settings(max_examples=30, deadline=None)
@given(st.integers(2, 8), st.integers(0, 10_000))
def test_ham_brown_eigenvalues_sum_to_order_and_lie_in_range(n, seed):
    rng = np.random.default_rng(seed)
    B = rng.normal(size=(5, n, n)) * rng.uniform(1e-3, 1e3, size=n)
    P = B @ np.swapaxes(B, 1, 2) + 1e-9 * np.eye(n)
    P0 = np.diag(rng.uniform(0.1, 10.0, size=n))
    res = normalized_eigen(P, P0)
    np.testing.assert_allclose(res.eigenvalues.sum(axis=1), n, rtol=1e-10)
    assert res.eigenvalues.min() >= -1e-9 and res.eigenvalues.max() <= n + 1e-9
    assert np.all(np.diff(res.eigenvalues, axis=1) <= 1e-12)
    np.testing.assert_allclose(res.tracked_values.sum(axis=1), n, rtol=1e-10)
    alone = normalized_eigen(P, P0, vectors=False)  # the eigenvalue-only driver
    np.testing.assert_allclose(alone.eigenvalues, res.eigenvalues, rtol=0, atol=1e-12 * n)
    assert alone.eigenvectors is None and alone.tracked_vectors is None


def _crossing_example(N=201):
    """Eigenvectors rotating in the (x0, x1) plane; eigenvalues 3 - s and 2 + s cross."""
    s = np.linspace(0.0, 2.0, N)
    theta = 0.3 * s
    c, d = np.cos(theta), np.sin(theta)
    V = np.zeros((N, 3, 3))
    V[:, 0, 0], V[:, 1, 0] = c, d
    V[:, 0, 1], V[:, 1, 1] = -d, c
    V[:, 2, 2] = 1.0
    lam = np.column_stack([3.0 - s, 2.0 + s, np.full(N, 0.5)])
    P = np.einsum("kij,kj,klj->kil", V, lam, V)
    return s, V, lam, P


def test_tracking_follows_branches_through_a_crossing():
    s, V, lam, P = _crossing_example()
    res = normalized_eigen(P, np.eye(3), t=s, anchor="start")
    scale = 3.0 / lam.sum(axis=1)
    # tracked mode 0 follows branch "3 - s" throughout, with a constant sign
    np.testing.assert_allclose(res.tracked_values[:, 0], lam[:, 0] * scale, atol=1e-9)
    dots = np.einsum("ki,ki->k", res.tracked_vectors[:, :, 0], V[:, :, 0])
    # exact except at the crossing itself, where any vector of the plane is an eigenvector
    assert np.all(np.abs(np.abs(dots) - 1) < 1e-4)
    assert np.sum(np.abs(np.abs(dots) - 1) > 1e-9) <= 1
    assert np.all(np.sign(dots) == np.sign(dots[0]))
    # consecutive tracked vectors never jump
    steps = np.einsum("kij,kij->kj", res.tracked_vectors[1:], res.tracked_vectors[:-1])
    assert steps.min() > 0.99
    # the sorted order shows the X-shape: column 0 swaps branch after the crossing
    sorted_steps = np.einsum("kij,kij->kj", res.eigenvectors[1:], res.eigenvectors[:-1])
    assert sorted_steps.min() >= 0.0  # sign-consistent sorted columns
    first = np.abs(np.einsum("ki,ki->k", res.eigenvectors[:, :, 0], V[:, :, 0]))
    assert first[10] > 0.999 and first[-10] < 1e-3
    # while the projector onto the pair (subspace share) stays put
    np.testing.assert_allclose(res.subspace_share([1, 2])[:, 2], 0.0, atol=1e-12)
    np.testing.assert_allclose(res.subspace_share([1, 2])[:, :2], 1.0, atol=1e-12)
    table = res.table(time_s=2.0)
    assert list(table.index) == ["eigenvalue", "x0", "x1", "x2"]


def test_tracking_inside_an_exactly_degenerate_cluster_is_smooth():
    # a 2-D eigenspace with equal eigenvalues: eigh's basis is arbitrary, tracking is not
    N = 50
    rng = np.random.default_rng(0)
    P = np.zeros((N, 3, 3))
    for k in range(N):
        Qr = np.linalg.qr(rng.normal(size=(2, 2)))[0]
        P[k, :2, :2] = Qr @ np.diag([2.0, 2.0]) @ Qr.T
        P[k, 2, 2] = 0.5 + 0.01 * k
    res = normalized_eigen(P, np.eye(3))
    steps = np.einsum("kij,kij->kj", res.tracked_vectors[1:], res.tracked_vectors[:-1])
    assert steps.min() > 1 - 1e-9
