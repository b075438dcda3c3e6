"""Generic estimability readings of a covariance run (navlib.covariance.estimability)."""

import numpy as np
from scipy.linalg import subspace_angles

from navlib.covariance.estimability import (
    dominant_changes,
    noise_free_error,
    projector_drift,
    settling_time,
    sparse_basis,
    split_modes,
    subspace_shares,
)


def test_subspace_shares_of_coordinate_and_diagonal_modes():
    V = np.array([[1.0, 0.0], [0.0, np.sqrt(0.5)], [0.0, np.sqrt(0.5)], [0.0, 0.0]])
    np.testing.assert_allclose(subspace_shares(V), [1.0, np.sqrt(0.5), np.sqrt(0.5), 0.0])


def test_split_modes_puts_the_modes_along_the_states_last():
    V = np.eye(4)[:, [2, 0, 3, 1]]  # mode 0 is state 2, mode 2 is state 3
    others, along = split_modes(V, [2, 3], 4)
    assert list(along) == [0, 2] and list(others) == [1, 3]


def test_projector_drift_is_zero_for_a_rotation_inside_the_subspace():
    angles = np.linspace(0.0, np.pi / 3, 5)
    V = np.zeros((5, 3, 3))
    V[:, 0, 0], V[:, 1, 0] = np.cos(angles), np.sin(angles)
    V[:, 0, 1], V[:, 1, 1] = -np.sin(angles), np.cos(angles)
    V[:, 2, 2] = 1.0
    assert projector_drift(V, [0, 1], 0) < 1e-15
    assert projector_drift(V, [0], 0) > 0.5


def test_dominant_changes_reports_the_swap():
    V = np.repeat(np.eye(2)[None], 4, axis=0)
    V[2:] = V[2:][:, :, ::-1]  # the two modes swap states at epoch 2
    events = dominant_changes(V, [[0], [1]], [0, 1], 1)
    assert len(events) == 1
    k, cols, before, after = events[0]
    assert k == 2 and list(cols) == [0, 1]
    assert list(before) == [0, 1] and list(after) == [1, 0]


def test_settling_time_reads_the_last_epoch_above_the_band():
    t = np.arange(6.0)
    sigma = np.array([[4.0, 1.0], [3.0, 1.0], [2.0, 1.0], [1.2, 1.0], [1.0, 1.0], [1.0, 1.0]])
    np.testing.assert_array_equal(settling_time(t, sigma, 1.05), [4.0, np.nan])


def test_noise_free_error_uses_the_kalman_gain():
    rng = np.random.default_rng(3)
    n, m, N = 3, 1, 6
    F = np.eye(n) + 0.1 * rng.standard_normal((n, n))
    H = rng.standard_normal((m, n))
    R = np.array([[0.2]])
    A = rng.standard_normal((N, n, n))
    P_prior = A @ np.swapaxes(A, 1, 2) + np.eye(n)
    x0 = rng.standard_normal(n)
    e = noise_free_error(F, H, R, P_prior, x0)
    want = np.empty((N, n))
    for k in range(N):
        S = H @ P_prior[k] @ H.T + R
        K = P_prior[k] @ H.T @ np.linalg.inv(S)
        want[k] = (np.eye(n) - K @ H) @ (x0 if k == 0 else F @ want[k - 1])
    np.testing.assert_allclose(e, want, rtol=1e-12, atol=1e-14)


def test_sparse_basis_spans_the_subspace_with_unit_pivots():
    V = np.array([[1.0, 1.0], [2.0, 0.0], [0.0, 3.0], [1.0, 1.0]])
    B = sparse_basis(V)
    assert B.shape == (4, 2)
    assert np.degrees(subspace_angles(B, V).max()) < 1e-10
    np.testing.assert_allclose(B[:2], np.eye(2), atol=1e-14)
