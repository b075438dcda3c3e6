"""Barometer and pad aiding of the 21-state model (navlib.models.baro, assumptions B2-B4)."""

from __future__ import annotations

import numpy as np
import pytest

from navlib import NavlibInputError, earth
from navlib.models.baro import aided_model, baro_sigma, pad_epochs
from navlib.models.ecef import ecef21_at_epochs
from navlib.studies.assess.aiding import ned_sigmas
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
    speed = abs(traj.velocity[i] @ up)
    assert speed > 100.0                   # the dynamic-pressure term matters here
    assert aided.R[k, 0, 0] == pytest.approx(baro_sigma(h - h0, speed_m_s=speed) ** 2)
    assert aided.R[k, 0, 0] > baro_sigma(h - h0) ** 2
    pad = pad_epochs(model.t, traj.t, traj.velocity)
    assert pad[0] and not pad[-1]          # the rocket rests on its rail until ignition
    assert np.all(aided.H[pad, 1:, 3:6] == np.eye(3))
    assert np.all(aided.H[~pad, 1:] == 0.0)
    both = aided_model(model, traj, "gnss+baro")
    assert both.measurement_names[:3] == ("gnss_n", "gnss_e", "baro_h")


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
