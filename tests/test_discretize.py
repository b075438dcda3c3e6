"""Discretisation: closed forms, Van Loan against quadrature, chaining, model subset."""

import numpy as np
import pytest
from scipy.integrate import quad_vec
from scipy.linalg import expm

from navlib import NavlibInputError
from navlib.discretize import chain, discretize_steps, expm_taylor
from navlib.models import LinearModel


def double_integrator(q=2.0):
    A = np.array([[0.0, 1.0], [0.0, 0.0]])
    G = np.array([[0.0], [1.0]])
    return A, G, np.array([[q]])


def test_double_integrator_closed_form():
    A, G, Qc = double_integrator(q=2.0)
    dt = 0.3
    F, Q = discretize_steps(A, G, Qc, dt)
    np.testing.assert_allclose(F[0], [[1.0, dt], [0.0, 1.0]], atol=1e-14)
    expected = 2.0 * np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]])
    np.testing.assert_allclose(Q[0], expected, rtol=1e-12)


def test_van_loan_matches_quadrature_on_random_system():
    rng = np.random.default_rng(1)
    A = rng.normal(size=(4, 4))
    G = rng.normal(size=(4, 2))
    Qc = np.diag([0.3, 1.7])
    dt = 0.2
    F, Q = discretize_steps(A, G, Qc, dt)
    integrand = lambda s: expm(A * s) @ G @ Qc @ G.T @ expm(A * s).T  # noqa: E731
    Q_quad, _ = quad_vec(integrand, 0.0, dt, epsabs=1e-13)
    np.testing.assert_allclose(F[0], expm(A * dt), rtol=1e-12)
    np.testing.assert_allclose(Q[0], Q_quad, rtol=1e-9, atol=1e-14)


def test_series_van_loan_matches_block_exponential_over_short_steps():
    rng = np.random.default_rng(4)
    A = rng.normal(size=(6, 5, 5))
    G = rng.normal(size=(6, 5, 2))
    Qc = np.diag([0.5, 2.0])
    F_ref, Q_ref = discretize_steps(A, G, Qc, 0.01, method="expm")
    F, Q = discretize_steps(A, G, Qc, 0.01, method="series")
    np.testing.assert_allclose(F, F_ref, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(Q, Q_ref, rtol=0, atol=1e-9 * np.abs(Q_ref).max())


def test_euler_form_is_first_order():
    A, G, Qc = double_integrator(q=1.0)
    F, Q = discretize_steps(A, G, Qc, 0.1, method="euler")
    np.testing.assert_allclose(F[0], np.eye(2) + A * 0.1)
    np.testing.assert_allclose(Q[0], G @ Qc @ G.T * 0.1)


def test_chain_equals_single_long_step_for_constant_model():
    rng = np.random.default_rng(2)
    A = 0.3 * rng.normal(size=(3, 3))
    G = rng.normal(size=(3, 3))
    Qc = np.eye(3)
    F_steps, Q_steps = discretize_steps(np.broadcast_to(A, (10, 3, 3)), G, Qc, 0.01)
    F, Q = chain(F_steps, Q_steps, [0, 4, 10])
    F_long, Q_long = discretize_steps(A, G, Qc, 0.06)
    np.testing.assert_allclose(F[1], F_long[0], rtol=1e-12)
    np.testing.assert_allclose(Q[1], Q_long[0], rtol=1e-10)


def test_time_varying_model_discretises_at_epochs_and_subsets():
    t = np.linspace(0.0, 2.0, 201)
    w = 0.5 * np.sin(t)
    A = np.zeros((t.size, 2, 2))
    A[:, 0, 1], A[:, 1, 0] = w, -w
    model = LinearModel(("a", "b"), A, np.eye(2), 0.01 * np.eye(2), np.array([[1.0, 0.0]]),
                        np.eye(1), t=t, P0=np.diag([1.0, 4.0]))
    disc = model.discretize(epochs=np.arange(0, 201, 100))
    assert disc.F.shape == (2, 2, 2) and disc.H.shape == (3, 1, 2)
    np.testing.assert_allclose(disc.t, [0.0, 1.0, 2.0])
    # a rotation generator stays a rotation: F orthogonal
    np.testing.assert_allclose(disc.F[0] @ disc.F[0].T, np.eye(2), atol=1e-12)
    sub = model.subset(["b"])
    assert sub.state_names == ("b",) and sub.A.shape == (201, 1, 1) and sub.P0[0, 0] == 4.0
    window = disc.window(0.5, 2.0)
    np.testing.assert_allclose(window.t, [1.0, 2.0])


def test_bad_input_is_named():
    A, G, Qc = double_integrator()
    with pytest.raises(NavlibInputError, match="method"):
        discretize_steps(A, G, Qc, 0.1, method="rk4")
    with pytest.raises(NavlibInputError, match="dt"):
        discretize_steps(A, G, Qc, -0.1)
    with pytest.raises(NavlibInputError, match="epochs"):
        chain(np.ones((3, 2, 2)), np.ones((3, 2, 2)), [0, 2, 1])
    model = LinearModel(("p", "v"), A, G, Qc, np.array([[1.0, 0.0]]), np.eye(1))
    with pytest.raises(NavlibInputError, match="unknown state"):
        model.subset(["p", "w"])
    with pytest.raises(NavlibInputError, match="dt"):
        model.discretize()


def test_batched_taylor_expm_matches_scipy():
    from scipy.linalg import expm

    rng = np.random.default_rng(3)
    X = rng.normal(size=(5, 21, 21)) * np.array([0.01, 0.3, 1.0, 3.0, 8.0])[:, None, None]
    X[2, 9:] = 0.0  # augmented-state structure: constant parameters
    E = expm_taylor(X)
    for k in range(5):
        ref = expm(X[k])
        np.testing.assert_allclose(E[k], ref, rtol=1e-11, atol=1e-12 * np.abs(ref).max())
    np.testing.assert_array_equal(expm_taylor(np.zeros((2, 3, 3))), [np.eye(3)] * 2)


def test_taylor_expm_of_a_stack_is_each_matrix_on_its_own():
    """Each matrix of a stack gets its own scaling and degree (a stack of small and large
    norms): the stack's exponentials are those of each matrix alone, bit for bit, and the
    lowest degree within the bound is read from the table as the bound's loop finds it."""
    import math

    from navlib.discretize import _TAYLOR_BOUND, _taylor_degree

    rng = np.random.default_rng(5)
    scales = np.repeat([1e-4, 0.02, 0.2, 0.45, 1.5, 6.0], 3)
    X = rng.normal(size=(scales.size, 9, 9)) * scales[:, None, None] / 9.0
    E = expm_taylor(X)
    for k in range(scales.size):
        np.testing.assert_array_equal(E[k], expm_taylor(X[k:k + 1])[0])
        np.testing.assert_array_equal(E[k], expm_taylor(X[k]))
    assert expm_taylor(np.zeros((0, 9, 9))).shape == (0, 9, 9)
    for norm in np.geomspace(1e-8, 0.5, 400):
        loop = next((m for m in range(1, 12)
                     if norm ** (m + 1) / math.factorial(m + 1) <= _TAYLOR_BOUND), 12)
        assert _taylor_degree(norm) == loop
