"""The sliding-window per-step test of navlib.observability (every step of eq. (6)) against
straightforward per-step numpy: ``matrix_rank`` / ``cond`` / ``svd`` of the stacked ``O(k)``.

Stated accuracy: every singular value within ``SIGMA_TOL * eps * sigma_max`` of the direct
SVD (both are backward-stable factorisations of the same matrix), hence the rank exactly and
the condition number to a relative ``SIGMA_TOL * eps * cond`` on full-rank steps; on
rank-deficient steps both condition numbers are numerically singular (>= 1 / rtol).
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from navlib import NavlibInputError
from navlib.models import DiscreteModel
from navlib.models.launcher import launcher, launcher_steps
from navlib.observability import local_matrix, local_observability
from navlib.trajectory import launcher_ascent

EPS = np.finfo(float).eps
SIGMA_TOL = 100.0
"""Singular values agree to this many ulps of sigma_max (measured on every 11th step of the
60 Table 2 configurations over 1.5 s: at most 41; the condition number of full-rank steps to
at most 5 eps cond)."""


@pytest.fixture(scope="module")
def ascent():
    """The first 1.5 s of the Churchill ascent (301 samples at 200 Hz)."""
    return launcher_ascent(duration_s=1.5)


def assert_close_to_sigma_max(s, ref):
    """Singular values ``s`` (..., n) within ``SIGMA_TOL`` ulps of each row's sigma_max."""
    error = np.abs(s - ref).max(axis=-1) / (EPS * ref[..., 0])
    assert np.all(error <= SIGMA_TOL), f"{error.max():.1f} ulps of sigma_max"


def direct(model, k, rtol):
    """Independent per-step reference: the stacked O(k) through numpy.linalg."""
    O = local_matrix(model, k)
    tol = rtol * np.linalg.svd(O, compute_uv=False)[0]
    return (np.linalg.matrix_rank(O, tol=tol), np.linalg.cond(O),
            np.linalg.svd(O, compute_uv=False))


def assert_matches_direct(model, res, steps):
    for k in steps:
        i = int(np.flatnonzero(res.step == k)[0])
        rank, cond, s = direct(model, k, res.rtol)
        assert res.rank[i] == rank, (model.name, k)
        assert_close_to_sigma_max(res.singular_values[i], s)
        if rank == model.n:
            assert abs(res.cond[i] / cond - 1) <= SIGMA_TOL * EPS * cond, (model.name, k)
        else:
            assert min(res.cond[i], cond) >= 1 / res.rtol, (model.name, k)


@pytest.mark.parametrize("config, unobservable", [
    (("ins_gps", "", "none"), 0),
    (("ins_gps", "GA", "random_walk"), 0),            # full rank, cond ~1e12
    (("ins_gps", "P", "random_walk"), 3),             # b_p against dr: 3 unobservable
    (("ins_gps_att", "GAP", "markov"), 0),
    (("ins_gps_att_rt", "GAP", "random_walk"), 3),    # time-varying H (RT rows), n = 28
    (("ins_gps_rt", "AP", "markov"), 0),
])
def test_every_step_matches_direct_numpy(ascent, config, unobservable):
    model = launcher(*config, trajectory=ascent)
    n = model.n
    # small chunks: many pieces (two threads), the block boundaries r = 0, 1, w - 1 and
    # the last steps, whose windows end at the mission's last sample
    res = local_observability(model, n_jobs=2, chunk=3 * n)
    assert res.step.size == ascent.t.size - n + 1
    assert res.n_unobservable == unobservable and res.rank_constant
    last = res.step[-1]
    steps = sorted({0, 1, n - 1, n, n + 1, 2 * n - 1, 3 * n, 3 * n + 1, last - 1, last,
                    *range(5, last, 37)})
    assert_matches_direct(model, res, steps)


def test_every_step_equals_the_strided_path(ascent):
    """Stride 1 (sliding window) against stride 7 (the per-step stacking of before) on the
    same steps, a rank-deficient and a full-rank configuration."""
    for config in [("ins_gps_att", "AP", "random_walk"), ("ins_gps_rt", "G", "markov")]:
        model = launcher(*config, trajectory=ascent)
        every, strided = local_observability(model), local_observability(model, stride=7)
        np.testing.assert_array_equal(every.step[::7], strided.step)
        np.testing.assert_array_equal(every.rank[::7], strided.rank)
        assert_close_to_sigma_max(every.singular_values[::7], strided.singular_values)


@pytest.mark.parametrize("config", [("ins_gps_att_rt", "GAP", "random_walk"),
                                    ("ins_gps", "GP", "markov"), ("ins_gps_rt", "A", "markov")])
def test_launcher_steps_are_the_models_euler_steps(ascent, config):
    """:func:`launcher_steps` computes the steps asked for, bitwise the Euler transitions
    of :func:`launcher`'s ``A`` stack, so the every-step test gives the same numbers; it
    refuses another discretisation."""
    model, steps = launcher(*config, trajectory=ascent), launcher_steps(*config,
                                                                        trajectory=ascent)
    assert steps.state_names == model.state_names and steps.n == model.n
    idx = np.array([[0, 1, 2], [150, 7, ascent.t.size - 2]])
    F = model.discretize(method="euler").F
    np.testing.assert_array_equal(steps.transitions(idx), F[idx])
    H = np.asarray(model.H)
    np.testing.assert_array_equal(np.asarray(steps.H), H)     # formed on demand (RT) or not
    if H.ndim == 3:
        np.testing.assert_array_equal(steps.H[idx], H[idx])
        np.testing.assert_array_equal(steps.H[5:9], H[5:9])
        np.testing.assert_array_equal(steps.H[7], H[7])
    a, b = local_observability(model), local_observability(steps)
    np.testing.assert_array_equal(a.singular_values, b.singular_values)
    np.testing.assert_array_equal(local_matrix(model, 40), local_matrix(steps, 40))
    with pytest.raises(NavlibInputError, match="euler"):
        local_observability(steps, stride=50, method="expm")


@settings(max_examples=30, deadline=None)
@given(n=st.integers(1, 6), m=st.integers(1, 3), extra=st.integers(0, 3),
       N=st.integers(2, 40), chunk=st.integers(1, 9), seed=st.integers(0, 10_000))
def test_random_models_any_window_and_chunk(n, m, extra, N, chunk, seed):
    window = -(-n // m) + extra          # at least n rows: the sliding path
    if N < window + 1:
        N = window + 1
    rng = np.random.default_rng(seed)
    F = np.eye(n) + 0.3 * rng.normal(size=(N - 1, n, n))
    H = rng.normal(size=(N, m, n))
    model = DiscreteModel(t=np.arange(N) * 0.1, F=F, Q=np.zeros_like(F), H=H,
                          R=np.broadcast_to(np.eye(m), (N, m, m)),
                          state_names=tuple(f"s{i}" for i in range(n)))
    res = local_observability(model, window=window, chunk=chunk, n_jobs=2)
    assert res.step.size == N - window + 1
    for i, k in enumerate(res.step):
        O = local_matrix(model, k, window=window)
        assert_close_to_sigma_max(res.singular_values[i], np.linalg.svd(O, compute_uv=False))
