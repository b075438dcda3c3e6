"""The compiled sliding window of navlib.observability.sliding against its NumPy reference
(tests/support/sliding_reference.py): each reduction and one window within 1e-12 relative,
whole runs of the Table 2 configurations within the measured spread (ranks exactly)."""

import numpy as np
import pytest
from support import sliding_reference as reference

from navlib.models.launcher import launcher
from navlib.observability.local import _model_arrays
from navlib.observability.sliding import (
    fold,
    singular_values,
    sliding_singular_values,
    triangularize,
)
from navlib.resolution import relative_resolution
from navlib.trajectory import launcher_ascent

STEP_RTOL = 1e-12
EPS = np.finfo(float).eps
RUN_ULPS = 100.0
"""Whole runs: singular values within this many ulps of each step's sigma_max (as
tests/observability/test_local_sliding.py allows against a direct SVD); measured on all 60 Table 2
configurations over the 150 s ascent: at most 39 ulps (2026-12-02)."""


def assert_close(got, want, rtol=STEP_RTOL):
    np.testing.assert_allclose(got, want, rtol=0, atol=rtol * np.abs(want).max())


@pytest.mark.parametrize("p, n", [(40, 28), (12, 28), (1, 5), (9, 9), (30, 4)])
def test_triangularize_equals_numpy_qr(p, n):
    A = np.random.default_rng(p * n).normal(size=(p, n))
    Rt = np.empty((n, n))
    triangularize(A.T.copy(), Rt)          # both transposed
    want = np.zeros((n, n))
    want[:min(p, n)] = np.linalg.qr(A, mode="r")
    assert_close(Rt.T, want)


@pytest.mark.parametrize("p, n", [(12, 28), (28, 28), (1, 1), (3, 7)])
def test_fold_equals_numpy_qr_of_the_stack(p, n):
    rng = np.random.default_rng(p + n)
    R, X = np.triu(rng.normal(size=(n, n))), rng.normal(size=(p, n))
    got = R.T.copy()
    fold(got, X.T.copy())                  # both transposed
    assert_close(got.T, np.linalg.qr(np.vstack([R, X]), mode="r"))


@pytest.mark.parametrize("n", [1, 2, 3, 12, 28])
def test_singular_values_equal_numpy_svd(n):
    rng = np.random.default_rng(n)
    A = np.triu(rng.normal(size=(n, n))) * np.logspace(0, -8, n)  # graded, as O(k)'s factors
    s = np.empty(n)
    assert singular_values(A.copy(), s, np.empty(6 * n), np.empty(2, np.int32)) == 0
    assert_close(s, np.linalg.svd(A, compute_uv=False))


def _random_pair(N, m, n, seed):
    rng = np.random.default_rng(seed)
    F = np.eye(n) + 0.1 * rng.normal(size=(N - 1, n, n))
    H = rng.normal(size=(N, m, n))
    return (lambda idx: F[idx]), H


@pytest.mark.parametrize("m, n, window", [(3, 7, 3), (2, 5, 5), (6, 6, 1), (1, 4, 6)])
def test_one_window_equals_the_numpy_reference(m, n, window):
    """Every step of one block and its successor: each step's spectrum within 1e-12."""
    transitions, H = _random_pair(3 * window + 1, m, n, seed=m * n + window)
    K = 2 * window
    got = sliding_singular_values(transitions, H, 0, K, window)
    want = reference.sliding_singular_values(transitions, H, 0, K, window)
    for k in range(K):
        assert_close(got[k], want[k])


@pytest.mark.parametrize("config", [("ins_gps_att_rt", "GAP", "markov"),
                                    ("ins_gps", "GA", "random_walk"),
                                    ("ins_gps_att_rt", "GAP", "random_walk")])
def test_whole_run_equals_the_numpy_reference(config):
    """4 s of the ascent (801 steps, windows across the chunk's blocks): ranks equal, every
    singular value within :data:`RUN_ULPS` of sigma_max."""
    model = launcher(*config, trajectory=launcher_ascent(duration_s=4.0))
    _, transitions, H = _model_arrays(model, "euler")
    n, K = model.n, H.shape[0] - model.n + 1
    got = sliding_singular_values(transitions, H, 0, K, n)
    want = reference.sliding_singular_values(transitions, H, 0, K, n)
    ulps = np.abs(got - want).max(axis=1) / (EPS * want[:, 0])
    assert ulps.max() <= RUN_ULPS
    tol = relative_resolution((n * H.shape[1], n))
    np.testing.assert_array_equal((got > tol * got[:, :1]).sum(1),
                                  (want > tol * want[:, :1]).sum(1))
