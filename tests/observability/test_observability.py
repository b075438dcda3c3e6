"""Observability matrix, analyze() and the local per-step test (navlib.observability)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from navlib import NavlibInputError
from navlib.observability import analyze, observability_matrix


def naive_observability(F, H, n_rows):
    """Independent reference: each block row H_k (F_{k-1} ... F_0) by explicit products."""
    n = F.shape[-1]
    rows = []
    for k in range(n_rows):
        phi = np.eye(n)
        for j in range(k):
            phi = (F[j] if F.ndim == 3 else F) @ phi
        rows.append((H[k] if H.ndim == 3 else H) @ phi)
    return np.vstack(rows)


# ---------------------------------------------------------------- observability_matrix
def test_constant_pair_has_n_block_rows_and_powers():
    rng = np.random.default_rng(1)
    F = rng.normal(size=(4, 4))
    H = rng.normal(size=(2, 4))
    O = observability_matrix(F, H)
    assert O.shape == (8, 4)
    expected = np.vstack([H @ np.linalg.matrix_power(F, k) for k in range(4)])
    np.testing.assert_allclose(O, expected, rtol=1e-12, atol=1e-12)


@settings(max_examples=25, deadline=None)
@given(n=st.integers(1, 5), m=st.integers(1, 3), N=st.integers(2, 8),
       seed=st.integers(0, 10_000))
def test_sequences_match_naive_loop(n, m, N, seed):
    rng = np.random.default_rng(seed)
    F = rng.normal(size=(N - 1, n, n))
    H = rng.normal(size=(N, m, n))
    np.testing.assert_allclose(observability_matrix(F, H), naive_observability(F, H, N),
                               rtol=1e-10, atol=1e-10)
    rows = max(1, N - 1)
    np.testing.assert_allclose(observability_matrix(F, H, n_rows=rows),
                               naive_observability(F, H, rows), rtol=1e-10, atol=1e-10)


def test_mixed_constant_and_sequence():
    rng = np.random.default_rng(2)
    F = rng.normal(size=(5, 3, 3))
    H = rng.normal(size=(1, 3))
    np.testing.assert_allclose(observability_matrix(F, H), naive_observability(F, H, 6),
                               rtol=1e-12, atol=1e-12)
    Fc = rng.normal(size=(3, 3))
    Hs = rng.normal(size=(4, 2, 3))
    np.testing.assert_allclose(observability_matrix(Fc, Hs), naive_observability(Fc, Hs, 4),
                               rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("F, H, kw", [
    (np.eye(3), np.ones((2, 4)), {}),                          # column mismatch
    (np.ones((2, 3)), np.ones((1, 3)), {}),                    # F not square
    (np.ones((4, 3, 3)), np.ones((3, 1, 3)), {}),              # N mismatch
    (np.ones((4, 3, 3)), np.ones((1, 3)), {"n_rows": 9}),      # too many rows
    (np.ones(3), np.ones((1, 3)), {}),                         # wrong ndim
    (np.full((3, 3), np.nan), np.ones((1, 3)), {}),            # NaN
])
def test_observability_matrix_rejects_bad_input(F, H, kw):
    with pytest.raises(NavlibInputError):
        observability_matrix(F, H, **kw)


# ---------------------------------------------------------------- analyze
def test_double_integrator_velocity_only_loses_position():
    dt = 0.1
    F = np.array([[1.0, dt], [0.0, 1.0]])
    res = analyze(observability_matrix(F, np.array([[0.0, 1.0]])), state_names=["p", "v"])
    assert res.rank == 1 and res.n_unobservable == 1 and not res.observable
    assert np.isinf(res.cond) or res.cond > 1e15
    np.testing.assert_allclose(np.abs(res.null_space[:, 0]), [1.0, 0.0], atol=1e-12)
    assert res.unobservable_groups == [["p"]]
    full = analyze(observability_matrix(F, np.array([[1.0, 0.0]])))
    assert full.rank == 2 and full.observable and full.null_space.shape == (2, 0)
    assert full.unobservable_groups == []
    assert np.isclose(full.cond, full.singular_values[0] / full.singular_values[-1])


def test_null_space_is_orthonormal_and_annihilated_by_O():
    rng = np.random.default_rng(3)
    # rank-4 matrix with 7 columns
    O = rng.normal(size=(20, 4)) @ rng.normal(size=(4, 7))
    res = analyze(O)
    assert res.rank == 4 and res.null_space.shape == (7, 3)
    np.testing.assert_allclose(res.null_space.T @ res.null_space, np.eye(3), atol=1e-12)
    assert np.linalg.norm(O @ res.null_space) < 1e-12 * np.linalg.norm(O)
    np.testing.assert_allclose(res.singular_values, np.linalg.svd(O, compute_uv=False))


def test_rtol_is_relative_to_largest_singular_value():
    O = np.diag([1e3, 1.0, 1e-5])
    assert analyze(O).rank == 3
    assert analyze(O, rtol=1e-9).rank == 3     # 1e-5 / 1e3 = 1e-8 > 1e-9
    assert analyze(O, rtol=1e-6).rank == 2     # 1e-8 < 1e-6
    assert analyze(O, rtol=1e-2).rank == 1
    assert analyze(1e6 * O, rtol=1e-6).rank == 2  # invariant under scaling of O
    assert np.isclose(analyze(O).cond, 1e8)
    with pytest.raises(NavlibInputError, match="rtol"):
        analyze(O, rtol=-1.0)


def test_wide_matrix_is_singular_with_infinite_cond():
    res = analyze(np.array([[1.0, 2.0, 3.0]]))
    assert res.rank == 1 and np.isinf(res.cond) and res.null_space.shape == (3, 2)


def test_exact_groups_of_a_block_decomposable_null_space():
    # states a b c d e: measure (a + b), c, (d + 2 e)... and nothing else; F = I
    H = np.array([[1.0, 1.0, 0, 0, 0], [0, 0, 1.0, 0, 0], [0, 0, 0, 1.0, 2.0]])
    res = analyze(observability_matrix(np.eye(5), H), state_names=list("abcde"))
    assert res.rank == 3
    assert sorted(res.unobservable_groups) == [["a", "b"], ["d", "e"]]
    assert res.unobservable_share[2] < 1e-8
    frame = res.to_frame()
    assert list(frame.columns[:3]) == ["state", "unobservable_share", "group"]
    assert frame.loc[frame.state == "c", "group"].item() == -1


def test_coupling_threshold_and_scale_split_weak_links():
    # Null space spanned by v1 = a + 1e-3 c and v2 = b + c: the exact grouping is {a, b, c};
    # with a threshold above the weak link, {a} separates from {b, c}.
    v1 = np.array([1.0, 0.0, 1e-3, 0.0])
    v2 = np.array([0.0, 1.0, 1.0, 0.0])
    basis = np.linalg.svd(np.vstack([v1, v2]))[2][2:]      # rows spanning the complement
    O = np.vstack([basis, 2 * basis])
    res = analyze(O, state_names=list("abcd"))
    assert res.rank == 2
    assert res.unobservable_groups == [["a", "b", "c"]]
    split = analyze(O, state_names=list("abcd"), coupling_threshold=0.01)
    assert sorted(split.unobservable_groups) == [["a"], ["b", "c"]]
    # In units where c's scale is 1e-3, v2 is almost pure c (b moves 1e-3 as much), so c is
    # unobservable on its own, which frees a from v1 as well and leaves b out.
    scaled = analyze(O, state_names=list("abcd"), coupling_threshold=0.01,
                     scale=[1.0, 1.0, 1e-3, 1.0])
    assert scaled.unobservable_groups == [["a"], ["c"]]
    assert scaled.unobservable_share[1] < 0.01
    # the exact basis itself does not depend on the scaling
    np.testing.assert_allclose(scaled.null_space @ scaled.null_space.T,
                               res.null_space @ res.null_space.T, atol=1e-12)


def test_analyze_rejects_bad_arguments():
    with pytest.raises(NavlibInputError, match="state_names"):
        analyze(np.eye(2), state_names=["a"])
    with pytest.raises(NavlibInputError, match="scale"):
        analyze(np.eye(2), scale=[1.0, 0.0])
    with pytest.raises(NavlibInputError, match="O"):
        analyze(np.ones(3))


# ---------------------------------------------------------------- local observability
def random_discrete(seed=0, N=40, n=4, m=2):
    from navlib.models import DiscreteModel

    rng = np.random.default_rng(seed)
    F = np.eye(n) + 0.1 * rng.normal(size=(N - 1, n, n))
    H = rng.normal(size=(N, m, n))
    return DiscreteModel(t=0.5 * np.arange(N), F=F, Q=np.zeros_like(F), H=H,
                         R=np.broadcast_to(np.eye(m), (N, m, m)),
                         state_names=tuple(f"s{i}" for i in range(n)))


@pytest.mark.parametrize("stride", [1, 3])
@pytest.mark.parametrize("n_jobs", [1, 2])
def test_local_time_varying_matches_per_step_matrices(stride, n_jobs):
    from navlib.observability import local_matrix, local_observability

    model = random_discrete()
    res = local_observability(model, stride=stride, n_jobs=n_jobs, chunk=5)
    N, n = model.t.size, model.n
    np.testing.assert_array_equal(res.step, np.arange(0, N - n + 1, stride))
    for i, k in enumerate(res.step):
        O = observability_matrix(model.F[k:k + n - 1], model.H[k:k + n])
        np.testing.assert_allclose(local_matrix(model, k), O, rtol=1e-12, atol=1e-12)
        s = np.linalg.svd(O, compute_uv=False)
        np.testing.assert_allclose(res.singular_values[i], s, rtol=1e-10)
        assert res.rank[i] == np.linalg.matrix_rank(O)
        assert np.isclose(res.cond[i], s[0] / s[-1])
    assert res.t[1] == model.t[stride]


def test_local_frozen_matches_pwcs_matrices():
    from navlib.observability import local_matrix, local_observability

    model = random_discrete(seed=4)
    res = local_observability(model, variant="frozen", window=3, stride=2)
    assert res.step[-1] <= model.t.size - 2
    for i, k in enumerate(res.step):
        O = observability_matrix(model.F[k], model.H[k], n_rows=3)
        np.testing.assert_allclose(local_matrix(model, k, window=3, variant="frozen"), O)
        np.testing.assert_allclose(res.singular_values[i], np.linalg.svd(O, compute_uv=False),
                                   rtol=1e-10)


def test_local_rank_drops_when_state_unobservable_and_rtol_rerank():
    from navlib.observability import local_observability

    model = random_discrete(seed=5, n=3, m=1)
    H = np.array(model.H)
    H[:, 0, 2] = 0.0                     # never measure state 2 ...
    F = np.array(model.F)
    F[:, :, 2] = 0.0                     # ... and let it feed nothing
    F[:, 2, 2] = 1.0
    from dataclasses import replace

    res = local_observability(replace(model, H=H, F=F))
    assert np.all(res.rank == 2) and res.rank_constant and res.n_unobservable == 1
    assert res.log10_max_cond > 14
    loose = res.with_rtol(0.5)
    assert loose.rank.max() <= 2 and loose.rtol == 0.5
    frame = res.to_frame()
    assert list(frame.columns) == ["t", "step", "rank", "n_unobservable", "cond", "log10_cond"]


def test_local_observability_rejects_bad_input():
    from navlib.observability import local_observability

    model = random_discrete(N=5)
    with pytest.raises(NavlibInputError, match="variant"):
        local_observability(model, variant="pwcs")
    with pytest.raises(NavlibInputError, match="window"):
        local_observability(model, window=9)
    with pytest.raises(NavlibInputError, match="model"):
        local_observability(np.eye(3))


def test_auto_coupling_threshold_absorbs_null_space_blur():
    # exact null space {a - b}; a weak direction (sigma 1e-12) plus 1e-16 noise blurs the
    # computed basis by ~1e-4, which a fixed 1e-6 threshold reads as coupling
    rng = np.random.default_rng(0)
    v_null = np.array([1.0, -1.0, 0.0, 0.0]) / np.sqrt(2)
    basis = np.linalg.svd(v_null[None])[2][1:]          # 3 rows orthogonal to the null vector
    O = np.diag([1.0, 1e-3, 1e-12]) @ basis + 1e-16 * rng.normal(size=(3, 4))
    fixed = analyze(O, state_names=list("abcd"))
    auto = analyze(O, coupling_threshold="auto", state_names=list("abcd"))
    assert fixed.rank == auto.rank == 3
    assert fixed.unobservable_groups != [["a", "b"]]
    assert auto.unobservable_groups == [["a", "b"]]
    assert 1e-6 < auto.coupling_threshold <= 0.1
    with pytest.raises(NavlibInputError, match="coupling_threshold"):
        analyze(O, coupling_threshold="exact")
