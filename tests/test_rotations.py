"""Skew-matrix identities and the Bortz rotation-vector equation (spec excitability.md A2, A3)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

from navlib.rotations import bortz_coefficient, bortz_rate, cross, skew, unskew

vec3 = arrays(np.float64, 3, elements=st.floats(-1e3, 1e3))


@settings(max_examples=100, deadline=None)
@given(vec3, vec3)
def test_skew_is_cross_product(v, u):
    S = skew(v)
    np.testing.assert_allclose(S @ u, np.cross(v, u), rtol=1e-12, atol=1e-9)
    np.testing.assert_array_equal(cross(v, u), np.cross(v, u))
    np.testing.assert_array_equal(S, -S.T)
    np.testing.assert_allclose(S @ v, 0.0, atol=1e-9)
    np.testing.assert_array_equal(unskew(S), v)


@settings(max_examples=50, deadline=None)
@given(vec3, vec3)
def test_skew_identities(v, u):
    # S(v)^2 = v v^T - |v|^2 I ;  S(v) S(u) - S(u) S(v) = S(v x u)
    np.testing.assert_allclose(skew(v) @ skew(v), np.outer(v, v) - (v @ v) * np.eye(3),
                               rtol=1e-12, atol=1e-6)
    np.testing.assert_allclose(skew(v) @ skew(u) - skew(u) @ skew(v), skew(np.cross(v, u)),
                               rtol=1e-12, atol=1e-6)


def test_skew_rotation_covariance_and_batches():
    rng = np.random.default_rng(1)
    R = Rotation.random(5, random_state=rng).as_matrix()
    v = rng.normal(size=(5, 3))
    # R S(v) R^T = S(R v)
    lhs = R @ skew(v) @ np.swapaxes(R, -1, -2)
    np.testing.assert_allclose(lhs, skew(np.einsum("nij,nj->ni", R, v)), atol=1e-14)
    assert skew(rng.normal(size=(2, 4, 3))).shape == (2, 4, 3, 3)
    a, b = rng.normal(size=(2, 1, 3)), rng.normal(size=(4, 3))
    np.testing.assert_allclose(cross(a, b), np.cross(a, b), rtol=1e-15)
    np.testing.assert_allclose(unskew(skew(v)), v)
    # unskew takes the skew part of a general matrix.
    M = rng.normal(size=(3, 3))
    np.testing.assert_allclose(unskew(M), unskew(0.5 * (M - M.T)))


def test_skew_matches_rodrigues():
    """exp(S(theta)) from the Rodrigues series equals scipy's rotation-vector map (A2)."""
    theta = np.array([0.3, -1.2, 2.0])
    t = np.linalg.norm(theta)
    S = skew(theta)
    C = np.eye(3) + np.sin(t) / t * S + (1 - np.cos(t)) / t**2 * S @ S
    np.testing.assert_allclose(C, Rotation.from_rotvec(theta).as_matrix(), atol=1e-14)


def test_bortz_coefficient_limits_and_continuity():
    assert bortz_coefficient(0.0) == pytest.approx(1.0 / 12.0, rel=1e-15)
    a = np.array([0.2 * (1 - 1e-12), 0.2 * (1 + 1e-12), 1e-3])
    c = bortz_coefficient(a)
    assert abs(c[0] - c[1]) < 1e-14  # series and closed form meet at the switch
    assert c[2] == pytest.approx(1 / 12 + 1e-6 / 720, rel=1e-14)
    # Closed form vs a long series: 1/12 + a^2/720 + a^4/30240 + ...
    x = np.array([0.01, 0.1, 0.199, 0.201, 0.3])
    series = 1 / 12 + x**2 / 720 + x**4 / 30240 + x**6 / 1209600 + x**8 / 47900160
    np.testing.assert_allclose(bortz_coefficient(x), series, rtol=1e-11)
    # Blows up towards 2 pi (spec A3) like 1 / (2 pi eps).
    eps = 1e-6
    assert bortz_coefficient(2 * np.pi - eps) == pytest.approx(1 / (2 * np.pi * eps), rel=1e-5)


def test_bortz_rate_special_cases():
    w = np.array([0.1, -0.2, 0.3])
    np.testing.assert_allclose(bortz_rate(np.zeros(3), w), w)
    # Rotation about a fixed axis: theta parallel to w gives dtheta/dt = w exactly.
    np.testing.assert_allclose(bortz_rate(2.5 * w / np.linalg.norm(w), w), w, atol=1e-15)
    assert bortz_rate(np.zeros((4, 7, 3)), np.ones((4, 7, 3))).shape == (4, 7, 3)


def _body_rate(t):
    """A non-commuting body rate: spin about x, plus coning in y-z, plus a slow ramp."""
    return np.array([1.5 + 0.4 * np.sin(0.7 * t), 0.8 * np.cos(3.0 * t), 0.8 * np.sin(3.0 * t)
                     + 0.1 * t])


def _integrate_dcm(C0, t_end, t_eval):
    def rhs(t, y):
        C = y.reshape(3, 3)
        return (C @ skew(_body_rate(t))).ravel()

    sol = solve_ivp(rhs, (0.0, t_end), C0.ravel(), t_eval=t_eval, method="DOP853",
                    rtol=1e-12, atol=1e-13)
    return sol.y.T.reshape(-1, 3, 3)


def _integrate_theta(rate, theta0, t_end, t_eval):
    sol = solve_ivp(rate, (0.0, t_end), theta0, t_eval=t_eval, method="DOP853",
                    rtol=1e-12, atol=1e-13)
    return sol.y.T


def test_bortz_rate_matches_dcm_integration():
    """Spec A2: C = exp(S(theta)) with dtheta/dt = bortz_rate(theta, omega_b) is the attitude
    obtained by integrating dC/dt = C S(omega_b). The printed ECEF-rate form with '+1/2'
    must fail the same check, the ECEF-rate form with '-1/2' must pass it."""
    theta0 = np.array([0.2, -0.4, 0.5])
    C0 = Rotation.from_rotvec(theta0).as_matrix()
    t_end = 1.6
    t_eval = np.linspace(0.0, t_end, 33)
    C_ref = _integrate_dcm(C0, t_end, t_eval)

    theta = _integrate_theta(lambda t, th: bortz_rate(th, _body_rate(t)), theta0, t_end, t_eval)
    norms = np.linalg.norm(theta, axis=1)
    assert norms.max() > 1.5  # large angles exercised, far from the series branch
    assert norms.max() < 2 * np.pi - 0.5
    C_bortz = Rotation.from_rotvec(theta).as_matrix()
    assert np.max(np.abs(C_bortz - C_ref)) < 1e-9

    def ecef_form(sign):
        def rate(t, th):
            w_e = Rotation.from_rotvec(th).apply(_body_rate(t))
            c = bortz_coefficient(np.linalg.norm(th))
            return w_e + sign * 0.5 * np.cross(th, w_e) + c * np.cross(th, np.cross(th, w_e))

        th = _integrate_theta(rate, theta0, t_end, t_eval)
        return np.max(np.abs(Rotation.from_rotvec(th).as_matrix() - C_ref))

    assert ecef_form(-1.0) < 1e-9
    assert ecef_form(+1.0) > 0.1
