"""WGS-84 Earth model: conversions, local frame, normal gravity and its Jacobian.

Independent references: the closed-form Somigliana normal gravity, the ellipsoid's own
surface normal, finite differences, and the WGS-84 J4 term added here (not in navlib) to
show that the J2 model's departure from Somigliana is exactly the truncated J4 part.
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from navlib import earth

LATS = np.radians(np.linspace(-90.0, 90.0, 37))
LONS = np.radians(np.array([-180.0, -123.4, -45.0, 0.0, 17.0, 90.0, 179.9]))

# Somigliana closed form for WGS-84 (NIMA TR8350.2, Eq. 4-1).
GAMMA_EQUATOR = 9.7803253359
SOMIGLIANA_K = 0.00193185265241
# WGS-84 normal-field fourth zonal harmonic (TR8350.2 Table 3.6), used only as a cross-check.
J4 = -0.237091222e-5


def somigliana(lat):
    s2 = np.sin(lat) ** 2
    return GAMMA_EQUATOR * (1.0 + SOMIGLIANA_K * s2) / np.sqrt(1.0 - earth.E2 * s2)


def j4_acceleration(r_e, h=0.5):
    """Gradient of the J4 potential term by central differences (independent of navlib)."""

    def potential(r):
        rr = np.linalg.norm(r, axis=-1)
        s = r[..., 2] / rr
        p4 = (35.0 * s**4 - 30.0 * s**2 + 3.0) / 8.0
        return -earth.GM / rr * J4 * (earth.A / rr) ** 4 * p4

    out = np.zeros_like(r_e)
    for i in range(3):
        e = np.zeros(3)
        e[i] = h
        out[..., i] = (potential(r_e + e) - potential(r_e - e)) / (2.0 * h)
    return out


# --- geodetic <-> ECEF --------------------------------------------------------------------


@pytest.mark.parametrize("alt", [-11000.0, 0.0, 629.0, 4.0e4, 1.0e6, 3.6e7])
def test_geodetic_round_trip_grid_including_poles(alt):
    lat, lon = np.meshgrid(LATS, LONS, indexing="ij")
    lat2, lon2, alt2 = earth.ecef_to_geodetic(earth.geodetic_to_ecef(lat, lon, alt))
    np.testing.assert_allclose(lat2, lat, atol=1e-12)
    np.testing.assert_allclose(alt2, alt, atol=1e-6)
    # Longitude is undefined at the poles; elsewhere it must come back (mod 2 pi).
    away = np.abs(np.cos(lat)) > 1e-9
    dlon = np.angle(np.exp(1j * (lon2 - lon)))
    assert np.max(np.abs(dlon[away])) < 1e-12


@settings(max_examples=200, deadline=None)
@given(
    st.floats(-90.0, 90.0), st.floats(-180.0, 180.0), st.floats(-1.0e4, 2.0e7),
)
def test_geodetic_round_trip_property(lat_deg, lon_deg, alt):
    lat, lon = np.radians(lat_deg), np.radians(lon_deg)
    r = earth.geodetic_to_ecef(lat, lon, alt)
    lat2, lon2, alt2 = earth.ecef_to_geodetic(r)
    # Compare positions: robust to the longitude singularity at the poles.
    np.testing.assert_allclose(earth.geodetic_to_ecef(lat2, lon2, alt2), r, atol=1e-6)
    assert abs(alt2 - alt) < 1e-6


def test_known_points():
    np.testing.assert_allclose(earth.geodetic_to_ecef(0.0, 0.0, 0.0), [earth.A, 0, 0])
    np.testing.assert_allclose(earth.geodetic_to_ecef(np.pi / 2, 0.3, 0.0), [0, 0, earth.B],
                               atol=1e-9)
    np.testing.assert_allclose(earth.geodetic_to_ecef(-np.pi / 2, 0.0, 100.0),
                               [0, 0, -earth.B - 100.0], atol=1e-9)
    lat, lon, alt = earth.ecef_to_geodetic([0.0, 0.0, earth.B + 5.0])
    assert lat == pytest.approx(np.pi / 2, abs=1e-15)
    assert alt == pytest.approx(5.0, abs=1e-8)
    lat, lon, alt = earth.ecef_to_geodetic([0.0, -earth.A - 7.0, 0.0])
    assert (lat, lon, alt) == pytest.approx((0.0, -np.pi / 2, 7.0), abs=1e-9)


def test_broadcast_shapes():
    r = earth.geodetic_to_ecef(LATS[:, None], LONS[None, :], 10.0)
    assert r.shape == (LATS.size, LONS.size, 3)
    lat, lon, alt = earth.ecef_to_geodetic(r)
    assert lat.shape == lon.shape == alt.shape == (LATS.size, LONS.size)


# --- NED frame and radii of curvature ------------------------------------------------------


def test_C_n_e_orthonormal_right_handed():
    lat, lon = np.meshgrid(LATS, LONS, indexing="ij")
    C_n_e = earth.ned_to_ecef_matrix(lat, lon)
    assert C_n_e.shape == (*lat.shape, 3, 3)
    eye = np.broadcast_to(np.eye(3), C_n_e.shape)
    np.testing.assert_allclose(np.swapaxes(C_n_e, -1, -2) @ C_n_e, eye, atol=1e-15)
    np.testing.assert_allclose(np.linalg.det(C_n_e), 1.0, atol=1e-14)


def test_C_n_e_axes_match_geodetic_derivatives():
    """Down is the ellipsoid normal; North and East follow increasing latitude, longitude."""
    lat = np.radians(np.array([-89.0, -60.0, -23.2, 0.0, 12.0, 45.0, 58.7, 89.0]))
    lon = np.radians(np.array([10.0, -170.0, -45.9, 0.0, 100.0, -94.1, 33.0, 5.0]))
    alt = 1234.0
    C_n_e = earth.ned_to_ecef_matrix(lat, lon)
    h = 1e-7
    d_lat = earth.geodetic_to_ecef(lat + h, lon, alt) - earth.geodetic_to_ecef(lat - h, lon, alt)
    d_lon = earth.geodetic_to_ecef(lat, lon + h, alt) - earth.geodetic_to_ecef(lat, lon - h, alt)
    d_alt = earth.geodetic_to_ecef(lat, lon, alt + 1.0) - earth.geodetic_to_ecef(lat, lon, alt)
    unit = lambda v: v / np.linalg.norm(v, axis=-1, keepdims=True)  # noqa: E731
    np.testing.assert_allclose(C_n_e[..., :, 0], unit(d_lat), atol=1e-8)
    np.testing.assert_allclose(C_n_e[..., :, 1], unit(d_lon), atol=1e-8)
    np.testing.assert_allclose(C_n_e[..., :, 2], -unit(d_alt), atol=1e-12)
    # Down is anti-parallel to the gradient of x^2/a^2 + y^2/a^2 + z^2/b^2 at the surface.
    r0 = earth.geodetic_to_ecef(lat, lon, 0.0)
    grad = r0 / np.array([earth.A**2, earth.A**2, earth.B**2])
    np.testing.assert_allclose(C_n_e[..., :, 2], -unit(grad), atol=1e-12)


def test_radii_of_curvature_match_arc_lengths():
    lat = np.radians(np.linspace(-85.0, 85.0, 35))
    r_m, r_n = earth.radii_of_curvature(lat)
    h = 1e-6
    arc_lat = np.linalg.norm(
        earth.geodetic_to_ecef(lat + h, 0.0, 0.0) - earth.geodetic_to_ecef(lat - h, 0.0, 0.0),
        axis=-1,
    ) / (2 * h)
    arc_lon = np.linalg.norm(
        earth.geodetic_to_ecef(lat, h, 0.0) - earth.geodetic_to_ecef(lat, -h, 0.0), axis=-1
    ) / (2 * h)
    np.testing.assert_allclose(r_m, arc_lat, rtol=1e-8)
    np.testing.assert_allclose(r_n * np.cos(lat), arc_lon, rtol=1e-8)
    assert r_m[0] < r_n[0]
    np.testing.assert_allclose(earth.radii_of_curvature(0.0), (earth.A * (1 - earth.E2), earth.A))


# --- normal gravity -------------------------------------------------------------------------


def test_normal_gravity_vs_somigliana_at_surface():
    """The J2 model departs from Somigliana by its truncated J4 part only.

    J2-only: up to 1.2e-4 m/s^2 at the poles and 4.8e-5 at the equator (J4 truncation, not a
    bug); with the WGS-84 J4 term added here the agreement is better than 1e-6 m/s^2.
    """
    lat = np.radians(np.linspace(-90.0, 90.0, 181))
    r_e = earth.geodetic_to_ecef(lat, 0.7, 0.0)
    reference = somigliana(lat)
    g_j2 = earth.gravity_magnitude(lat, 0.0)
    assert np.max(np.abs(g_j2 - reference)) < 1.5e-4
    assert abs(g_j2[90] - reference[90]) < 6e-5  # equator
    g_j4 = np.linalg.norm(earth.normal_gravity_ecef(r_e) + j4_acceleration(r_e), axis=-1)
    assert np.max(np.abs(g_j4 - reference)) < 1e-6


def test_normal_gravity_is_normal_to_the_ellipsoid():
    """The ellipsoid is an equipotential of normal gravity: gamma points along Down."""
    lat, lon = np.meshgrid(LATS, LONS, indexing="ij")
    r_e = earth.geodetic_to_ecef(lat, lon, 0.0)
    down = earth.ned_to_ecef_matrix(lat, lon)[..., :, 2]
    for gamma, tol in ((earth.normal_gravity_ecef(r_e), 7e-6),
                       (earth.normal_gravity_ecef(r_e) + j4_acceleration(r_e), 1e-7)):
        cos = np.sum(gamma * down, axis=-1) / np.linalg.norm(gamma, axis=-1)
        assert np.max(np.arccos(np.clip(cos, -1.0, 1.0))) < tol


def test_centrifugal_term_included():
    """Spec A5: gamma = gravitation + Omega^2 (x, y, 0); nothing at the poles."""
    r_eq = earth.geodetic_to_ecef(0.0, 0.0, 0.0)
    diff = earth.normal_gravity_ecef(r_eq) - earth.gravitation_ecef(r_eq)
    np.testing.assert_allclose(diff, [earth.OMEGA_E**2 * earth.A, 0.0, 0.0], rtol=1e-12)
    r_pole = earth.geodetic_to_ecef(np.pi / 2, 0.0, 0.0)
    np.testing.assert_allclose(earth.normal_gravity_ecef(r_pole),
                               earth.gravitation_ecef(r_pole), atol=1e-12)
    # Central term alone: GM / r^2 at the pole plus the J2 term (3 J2 GM a^2 / r^4 there).
    b = earth.B
    expected = earth.GM / b**2 * (1.0 - 3.0 * earth.J2 * earth.A**2 / b**2)
    assert np.linalg.norm(earth.gravitation_ecef(r_pole)) == pytest.approx(expected, rel=1e-12)


def test_free_air_gradient():
    lat = np.radians(np.array([-60.0, -23.2, 0.0, 45.0, 80.0]))
    g0 = earth.gravity_magnitude(lat, 0.0)
    g1 = earth.gravity_magnitude(lat, 100.0)
    gradient = (g1 - g0) / 100.0
    np.testing.assert_allclose(gradient, -3.086e-6, rtol=0.01)


@pytest.mark.parametrize("alt", [0.0, 629.0, 8.0e4, 1.0e6])
def test_gravity_jacobian_vs_central_differences(alt):
    lat, lon = np.meshgrid(np.radians([-90.0, -52.3, -23.2, 0.0, 31.0, 58.7, 90.0]),
                           np.radians([-94.1, 0.0, 135.0]), indexing="ij")
    r_e = earth.geodetic_to_ecef(lat, lon, alt)
    jac = earth.gravity_jacobian_ecef(r_e)
    assert jac.shape == (*lat.shape, 3, 3)
    h = 10.0
    fd = np.zeros_like(jac)
    for j in range(3):
        e = np.zeros(3)
        e[j] = h
        fd[..., :, j] = (earth.normal_gravity_ecef(r_e + e) - earth.normal_gravity_ecef(r_e - e))
        fd[..., :, j] /= 2 * h
    # Entries are ~3e-6 s^-2; central differences with h = 10 m are good to ~1e-14 s^-2.
    np.testing.assert_allclose(jac, fd, rtol=0, atol=1e-13)
    # Curl-free gravitation plus a symmetric centrifugal term: the Jacobian is symmetric.
    np.testing.assert_allclose(jac, np.swapaxes(jac, -1, -2), atol=1e-18)


def test_gravity_jacobian_structure_far_away():
    """Far from the Earth J2 fades: -GM/r^3 (I - 3 r r^T / r^2) plus the centrifugal term."""
    r = np.array([1.0, 2.0, 3.0]) * 1e8
    rn = np.linalg.norm(r)
    expected = -earth.GM / rn**3 * (np.eye(3) - 3.0 * np.outer(r, r) / rn**2)
    expected += earth.OMEGA_E**2 * np.diag([1.0, 1.0, 0.0])
    np.testing.assert_allclose(earth.gravity_jacobian_ecef(r), expected, rtol=0, atol=1e-16)


def test_normal_gravity_point_is_bitwise_the_array_form():
    """The scalar form of the launcher ascent's right-hand side gives the array form's
    three components to the bit, on the ground, in orbit and at the poles."""
    rng = np.random.default_rng(7)
    points = rng.normal(size=(3000, 3))
    points *= rng.uniform(6.35e6, 7.5e6, size=(3000, 1)) / np.linalg.norm(points, axis=1,
                                                                         keepdims=True)
    points[:2] = [[0.0, 0.0, 6356752.3], [0.0, 0.0, -6356752.3]]
    for r in points:
        got = earth.normal_gravity_point(*(float(c) for c in r))
        np.testing.assert_array_equal(np.array(got), earth.normal_gravity_ecef(r))
