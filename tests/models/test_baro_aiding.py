"""Barometer and pad aiding of the 21-state model (navlib.models.baro, assumptions B2-B4)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from navlib import NavlibInputError, earth, units
from navlib.models.baro import (
    BARO_PRESSURE_COEFFICIENT,
    aided_model,
    baro_sigma,
    mach_number,
    pad_epochs,
    static_pressure_error_m,
)
from navlib.models.ecef import ecef21_at_epochs
from navlib.studies.assess.aiding import (
    baro_rows_weighted,
    ned_sigmas,
    reference_speed,
    row_dynamic_error,
)
from navlib.trajectory import sounding_rocket


@pytest.fixture(scope="module")
def rocket():
    traj = sounding_rocket()
    return traj, ecef21_at_epochs(traj, 1.0, max_step_s=0.05)


def test_gnss_aiding_is_the_model_as_built(rocket):
    traj, model = rocket
    assert aided_model(model, traj, "gnss") is model
    with pytest.raises(NavlibInputError, match="aiding"):
        aided_model(model, traj, "lidar")


def test_baro_rows_measure_height_and_the_pad_only(rocket):
    traj, model = rocket
    aided = aided_model(model, traj, "baro")
    assert aided.measurement_names == ("baro_h", "zupt_x", "zupt_y", "zupt_z")
    np.testing.assert_array_equal(aided.F, model.F)
    k = 30
    i = np.searchsorted(traj.t, model.t[k])
    lat, lon, h = earth.ecef_to_geodetic(traj.position[i])
    up = -earth.ned_to_ecef_matrix(lat, lon)[:, 2]
    np.testing.assert_allclose(aided.H[k, 0, :3], up, atol=1e-12)
    assert np.all(aided.H[k, 0, 3:] == 0.0)
    h0 = earth.ecef_to_geodetic(traj.position[0])[2]
    speed = abs(traj.velocity[i] @ up)     # without GNSS: the reference's climb rate (B7)
    assert speed > 100.0                   # the dynamic-pressure term matters here
    assert aided.R[k, 0, 0] == pytest.approx(
        baro_sigma(h - h0, speed_m_s=speed, altitude_m=h) ** 2)
    assert aided.R[k, 0, 0] > baro_sigma(h - h0) ** 2
    pad = pad_epochs(model.t, traj.t, traj.velocity)
    assert pad[0] and not pad[-1]          # the rocket rests on its rail until ignition
    assert np.all(aided.H[pad, 1:, 3:6] == np.eye(3))
    assert np.all(aided.H[~pad, 1:] == 0.0)
    both = aided_model(model, traj, "gnss+baro")
    assert both.measurement_names[:3] == ("gnss_n", "gnss_e", "baro_h")
    # with GNSS the horizontal velocity is measured: the whole speed weighs the barometer
    full = np.linalg.norm(traj.velocity[i])
    assert both.R[k, 2, 2] == pytest.approx(
        baro_sigma(h - h0, speed_m_s=full, altitude_m=h) ** 2)


def test_static_pressure_error_grows_through_the_transonic_range():
    """B7: ``C_P q_c / (rho g0)`` with the Prandtl-Glauert factor held from Mach 0.8 to
    1.17: the low-speed ``C_P v^2 / (2 g0)``, growing up to Mach 1.17, continuous at Mach 1,
    larger than the incompressible term from Mach 0.5 to 1.5."""
    low = static_pressure_error_m(30.0)
    assert low == pytest.approx(BARO_PRESSURE_COEFFICIENT * 30.0**2 / (2 * units.G0), rel=0.01)
    a0 = 30.0 / mach_number(30.0)
    assert a0 == pytest.approx(340.3, abs=0.2)                  # ISA sea level
    assert mach_number(a0, 5000.0) > 1.0                        # colder aloft
    mach = np.linspace(0.05, 2.5, 400)
    e = static_pressure_error_m(mach * a0)
    incompressible = BARO_PRESSURE_COEFFICIENT * (mach * a0) ** 2 / (2 * units.G0)
    assert np.all(np.diff(e[mach <= 1.17]) > 0)          # beyond, 1/sqrt(M^2 - 1) falls
    transonic = (mach >= 0.5) & (mach <= 1.5)
    assert np.all(e[transonic] > incompressible[transonic])
    below, above = static_pressure_error_m(a0 * np.array([0.999999, 1.000001]))
    assert above == pytest.approx(below, rel=1e-4)              # q_c continuous at Mach 1
    # the Prandtl-Glauert factor: 1/sqrt(1 - M^2) at Mach 0.6, held at 1/0.6 at Mach 1
    qc = (1.0 + 0.2 * 0.36) ** 3.5 - 1.0
    assert static_pressure_error_m(0.6 * a0) == pytest.approx(
        BARO_PRESSURE_COEFFICIENT / 0.8 * qc * 287.053 * 288.15 / units.G0, rel=1e-6)
    at_one = static_pressure_error_m(a0)
    assert at_one == pytest.approx(
        BARO_PRESSURE_COEFFICIENT / 0.6 * (1.2**3.5 - 1.0) * 287.053 * 288.15 / units.G0,
        rel=1e-6)
    assert baro_sigma(0.0, speed_m_s=a0) == pytest.approx(np.hypot(1.0, at_one))


def test_without_gnss_the_horizontal_sigma_grows_and_the_vertical_stays(rocket):
    traj, model = rocket
    baro = ned_sigmas(aided_model(model, traj, "baro"), traj)
    gnss = ned_sigmas(model, traj)
    p, v = baro["position_m"], baro["velocity_m_s"]
    # vertical: bounded by the barometer (1 m + 1 % of the height change)
    h_end = earth.ecef_to_geodetic(traj.position[-1])[2] - earth.ecef_to_geodetic(
        traj.position[0])[2]
    assert p[-1, 2] < baro_sigma(h_end)
    # horizontal: not measured after the pad, so larger than at its start and than with GNSS
    assert np.all(p[-1, :2] > p[0, :2]) and np.all(p[-1, :2] > 3 * gnss["position_m"][-1, :2])
    assert np.all(v[-1, :2] > 2 * v[-1, 2])


def test_barometer_rows_take_the_reference_climb_rate_not_their_own(rocket):
    """B7: :func:`baro_rows_weighted` weighs each row at the climb rate of the fitted
    reference (its horizontal velocity is dead reckoning without GNSS); rows outside the
    reference keep the sigma at rest."""
    traj, _ = rocket
    t = np.r_[traj.t[::200], traj.t[-1] + 1.0]
    P = np.vstack([traj.position[::200], traj.position[-1]])
    rows = pd.DataFrame({"t": t, "x": P[:, 0], "y": P[:, 1], "z": P[:, 2],
                         "sigma": 1.0})
    rows.attrs["height_source"] = "baro"
    out = baro_rows_weighted(rows, traj)
    assert out.attrs == rows.attrs and out["sigma"].iloc[-1] == pytest.approx(
        baro_sigma(earth.ecef_to_geodetic(P[-1])[2] - earth.ecef_to_geodetic(P[0])[2]))
    climb = reference_speed(t, traj, "baro")
    speed = reference_speed(t, traj, "gnss+baro")
    k = int(np.argmax(climb))
    assert climb[k] > 100.0 and climb[-1] == 0.0
    assert np.all(speed >= climb - 1e-9)
    _, _, h = earth.ecef_to_geodetic(P)
    assert out["sigma"].iloc[k] == pytest.approx(
        baro_sigma(h[k] - h[0], speed_m_s=climb[k], altitude_m=h[k]))
    assert row_dynamic_error(t, traj, "baro")[k] == pytest.approx(
        static_pressure_error_m(climb[k], h[k]), rel=1e-6)
