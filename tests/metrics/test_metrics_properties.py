"""Property tests of the excitability and sensability metrics (spec excitability.md §6 item 10).

Systems are drawn from a seed plus small sizes, so every example is cheap; matrices have
physical-looking spreads of scale (states from 1e-4 to 1e3 units) to exercise the D0
normalisation.
"""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from navlib.metrics import excitability, nu_for, nu_range, sensability

SETTINGS = settings(max_examples=40, deadline=None)


@st.composite
def systems(draw, max_n=5, max_m=3, max_N=6, diagonal_P0=False):
    n = draw(st.integers(1, max_n))
    m = draw(st.integers(1, max_m))
    N = draw(st.integers(1, max_N))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    scale = 10.0 ** rng.uniform(-4, 3, n)  # state units
    F = (np.eye(n) + 0.3 * rng.standard_normal((N - 1, n, n))) * scale[:, None] / scale
    H = rng.standard_normal((N, m, n)) / scale
    G = rng.standard_normal((N - 1, n, n)) * scale[:, None] * 0.1
    Q = G @ np.swapaxes(G, 1, 2)
    A = rng.standard_normal((m, m))
    R = A @ A.T + 0.5 * np.eye(m)
    if diagonal_P0:
        P0 = np.diag(scale**2 * rng.uniform(0.5, 2.0, n))
    else:
        B = rng.standard_normal((n, n))
        P0 = (B @ B.T + n * np.eye(n)) * np.outer(scale, scale)
    return {"F": F, "H": H, "Q": Q, "R": R, "P0": P0, "rng": rng}


def transformed(system, T):
    """The same system in coordinates x' = T x (T diagonal)."""
    Ti = np.diag(1.0 / np.diag(T))
    return {**system, "F": T @ system["F"] @ Ti, "H": system["H"] @ Ti,
            "Q": T @ system["Q"] @ T, "P0": T @ system["P0"] @ T}


def ex_of(s, eta=1e-3):
    return excitability(s["F"], s["H"], s["P0"], s["R"], eta=eta)


def se_of(s, nu=0.985, **kw):
    return sensability(s["F"], s["H"], s["Q"], s["R"], s["P0"], nu=nu, **kw)


# ------------------------------------------------------------------------------ sensability


@SETTINGS
@given(systems(), st.floats(0.05, 1.0), st.booleans())
def test_r_is_monotone_and_ends_at_one(s, nu, prior_update):
    se = se_of(s, nu, prior_update=prior_update)
    assert np.all(se.r[:, -1] == 1.0)
    assert np.all(np.diff(se.r, axis=1) >= -1e-15)
    assert np.all((se.r > 0) & (se.r <= 1.0))
    assert np.all(se.eigenvalues > 0) and np.all(np.diff(se.eigenvalues, axis=1) <= 0)
    assert np.all((se.nr >= 1) & (se.nr <= se.n))
    idx = np.arange(se.r.shape[0])
    assert np.all(se.r[idx, se.nr - 1] >= nu)
    assert np.all((se.nr == 1) | (se.r[idx, np.maximum(se.nr - 2, 0)] < nu))
    assert np.all((se.s >= 0) & (se.s <= 1 + 1e-12))


@SETTINGS
@given(st.integers(1, 8), st.floats(0.01, 0.99), st.integers(0, 2**32 - 1), st.integers(1, 5))
def test_equal_eigenvalues_make_every_component_sensible(n, frac, seed, N):
    # F = I, H = I, R = P0 / c: I~_k = (1 + k c) I at every epoch; nu from the paper's rule.
    rng = np.random.default_rng(seed)
    P0 = np.diag(10.0 ** rng.uniform(-3, 3, n))
    c = rng.uniform(0.1, 10.0)
    nu = nu_for(n, frac / n)
    assert nu_range(n)[0] < nu < 1.0
    se = sensability(np.tile(np.eye(n), (N - 1, 1, 1)), np.eye(n), np.zeros((N - 1, n, n)),
                     P0 / c, P0, nu=nu)
    np.testing.assert_allclose(se.eigenvalues, (1 + c * np.arange(N))[:, None]
                               * np.ones(n), rtol=1e-10)
    np.testing.assert_array_equal(se.nr, n)
    np.testing.assert_allclose(se.s, 1.0, rtol=1e-12)


@SETTINGS
@given(systems(diagonal_P0=True), st.floats(0.01, 0.99))
def test_sensability_is_one_at_t0_under_the_literal_reading(s, frac):
    n = s["P0"].shape[0]
    se = se_of(s, nu=nu_for(n, frac / n))
    np.testing.assert_allclose(se.information[0], np.eye(n), atol=1e-12)
    np.testing.assert_allclose(se.s[0], 1.0, rtol=1e-12)
    np.testing.assert_allclose(se.sigma[0], np.sqrt(np.diag(s["P0"])), rtol=1e-12)


@SETTINGS
@given(systems(), st.booleans())
def test_normalised_recursion_equals_the_transformed_physical_one(s, prior_update):
    F, H, Q, R, P0 = s["F"], s["H"], s["Q"], s["R"], s["P0"]
    se = se_of(s, prior_update=prior_update)
    # physical information recursion (Eq. 10) in the problem's own units
    J = np.swapaxes(H, 1, 2) @ np.linalg.solve(R, H)
    info = np.linalg.inv(P0) + (J[0] if prior_update else 0.0)
    infos = [info]
    for k in range(1, H.shape[0]):
        info = np.linalg.inv(F[k - 1] @ np.linalg.inv(info) @ F[k - 1].T + Q[k - 1]) + J[k]
        infos.append(info)
    sqrt_d = np.sqrt(np.diag(P0))
    expected = np.array(infos) * np.outer(sqrt_d, sqrt_d)
    scale = np.max(np.abs(expected), axis=(1, 2), keepdims=True)
    np.testing.assert_allclose(se.information / scale, expected / scale, atol=1e-8)


@SETTINGS
@given(systems(), st.data())
def test_sensability_is_invariant_to_sign_flips_and_state_scaling(s, data):
    n = s["P0"].shape[0]
    signs = np.array(data.draw(st.lists(st.sampled_from([-1.0, 1.0]), min_size=n, max_size=n)))
    scales = 10.0 ** np.array(data.draw(st.lists(st.floats(-3, 3), min_size=n, max_size=n)))
    base = se_of(s)
    for T in (np.diag(signs), np.diag(signs * scales)):
        other = se_of(transformed(s, T))
        top = base.eigenvalues[:, :1]
        np.testing.assert_allclose(other.eigenvalues / top, base.eigenvalues / top, rtol=1e-7,
                                   atol=1e-10)
        np.testing.assert_array_equal(other.nr, base.nr)
        np.testing.assert_allclose(other.s, base.s, atol=1e-6)
        np.testing.assert_allclose(other.sigma, base.sigma * np.abs(np.diag(T)), rtol=1e-7)


# ------------------------------------------------------------------------------ excitability


@SETTINGS
@given(systems(), st.floats(1e-6, 0.9))
def test_spectrum_sums_to_n_and_e_lies_in_unit_interval(s, eta):
    ex = ex_of(s, eta)
    n = ex.n
    assert np.sum(ex.S) == np.float64(n) or abs(np.sum(ex.S) - n) < 1e-12 * n
    assert np.all(np.diff(ex.S) <= 1e-12) and np.all(ex.S >= 0)
    assert np.all((ex.e >= 0) & (ex.e <= 1 + 1e-12))
    assert 1 <= ex.ne <= n + 1
    assert np.all(ex.S[: ex.ne - 1] > eta)
    assert ex.ne == n + 1 or ex.S[ex.ne - 1] <= eta
    # sum_j e_j^2 = dim of the excited subspace
    np.testing.assert_allclose(np.sum(ex.e**2), ex.ne - 1, atol=1e-10)
    np.testing.assert_allclose(ex.U.T @ ex.U, np.eye(n), atol=1e-10)


@SETTINGS
@given(systems())
def test_ispc_are_orthogonal_with_energy_sigma(s):
    ex = ex_of(s)
    o = ex.ispc
    gram = o.T @ o
    np.testing.assert_allclose(gram, np.diag(ex.sigma), atol=1e-9 * ex.sigma[0])
    np.testing.assert_allclose(np.sum(o**2, axis=0), ex.sigma, rtol=1e-9,
                               atol=1e-12 * ex.sigma[0])


@SETTINGS
@given(systems(), st.floats(1e-6, 0.5), st.floats(1e-6, 0.5))
def test_smaller_eta_never_lowers_excitability(s, eta_a, eta_b):
    low, high = sorted((eta_a, eta_b))
    ex = ex_of(s, high)
    np.testing.assert_array_less(ex.e - 1e-12, ex.with_eta(low).e)


@SETTINGS
@given(systems(), st.integers(1, 4), st.floats(1e-8, 1e-2))
def test_rank_deficient_observability_gives_zero_excitability_states(s, hidden, eta):
    # Append states that neither reach the measured ones nor the measurements.
    rng = s["rng"]
    F, H, P0 = s["F"], s["H"], s["P0"]
    N, n, m = H.shape[0], F.shape[-1], H.shape[1]
    F_big = np.zeros((N - 1, n + hidden, n + hidden))
    F_big[:, :n, :n] = F
    F_big[:, n:, n:] = rng.standard_normal((N - 1, hidden, hidden))
    F_big[:, n:, :n] = rng.standard_normal((N - 1, hidden, n))  # measured -> hidden only
    H_big = np.concatenate([H, np.zeros((N, m, hidden))], axis=2)
    P0_big = np.eye(n + hidden) * np.max(np.diag(P0))
    P0_big[:n, :n] = P0
    ex = excitability(F_big, H_big, P0_big, s["R"], eta=eta)
    np.testing.assert_allclose(ex.e[n:], 0.0, atol=1e-8)
    np.testing.assert_allclose(ex.sigma[n:], 0.0, atol=1e-12 * ex.sigma[0])
    assert ex.ne <= n + 1


@SETTINGS
@given(systems(), st.data())
def test_null_space_of_O_is_outside_the_excited_subspace(s, data):
    # A generic rank-deficient case: a measurement blind to a random direction z of x0
    # at every epoch (H_k Phi_k z = 0), not aligned with any state axis.
    F, H = s["F"], s["H"]
    n = F.shape[-1]
    if n < 2:
        return
    rng = s["rng"]
    z = rng.standard_normal(n)
    Phi = np.eye(n)
    H_blind = H.copy()
    for k in range(H.shape[0]):
        w = Phi @ z
        H_blind[k] -= np.outer(H[k] @ w, w) / (w @ w)
        if k < H.shape[0] - 1:
            Phi = F[k] @ Phi
    ex = excitability(F, H_blind, s["P0"], s["R"], eta=data.draw(st.floats(1e-8, 1e-3)))
    z_n = z / np.sqrt(np.diag(s["P0"]))  # the blind direction in normalised coordinates
    z_n /= np.linalg.norm(z_n)
    assert ex.sigma[-1] <= 1e-18 * ex.sigma[0] + 1e-300
    np.testing.assert_allclose(ex.U[:, : ex.ne - 1].T @ z_n, 0.0, atol=1e-6)


@SETTINGS
@given(systems(), st.data())
def test_excitability_is_invariant_to_sign_flips_and_state_scaling(s, data):
    n = s["P0"].shape[0]
    signs = np.array(data.draw(st.lists(st.sampled_from([-1.0, 1.0]), min_size=n, max_size=n)))
    scales = 10.0 ** np.array(data.draw(st.lists(st.floats(-3, 3), min_size=n, max_size=n)))
    base = ex_of(s, eta=1e-3)
    for T in (np.diag(signs), np.diag(signs * scales)):
        other = ex_of(transformed(s, T), eta=1e-3)
        np.testing.assert_allclose(other.S, base.S, rtol=1e-8, atol=1e-12)
        assert other.ne == base.ne
        np.testing.assert_allclose(other.e, base.e, atol=1e-7)
