"""Allan deviation (allantools) and our noise-term fit: recovery of known white-noise and
rate-random-walk levels from generated static data, unresolved terms, units, presets."""

import math

import numpy as np
import pandas as pd
import pytest

from navlib import NavlibInputError
from navlib.sensors import (
    allan_deviation,
    fit_allan,
    load_preset,
    random_walk,
    white_noise,
    write_allan_preset,
)
from navlib.sensors.allan import BI_FACTOR, datasheet_units
from navlib.units import DEG, HOUR

AXES = ["w_x", "w_y", "w_z", "f_x", "f_y", "f_z"]
N_TRUE = 1e-3        # white noise density: rad/s/sqrt(Hz) (gyros), m/s^2/sqrt(Hz) (accels)
K_TRUE = 1e-3        # rate random walk: rad/s/sqrt(s), m/s^2/sqrt(s)
DURATION_S = 3600.0  # one hour: 1200 crossover times (3 N^2 / K^2 = 3 s)


def _static(seed, rate_hz, duration_s=DURATION_S, n=N_TRUE, k=K_TRUE):
    rng = np.random.default_rng(seed)
    t = np.arange(int(duration_s * rate_hz)) / rate_hz
    x = white_noise(t, n, rng, 6) + random_walk(t, k, rng, 6)
    imu = pd.DataFrame(x, columns=AXES)
    imu.insert(0, "t", t)
    return imu


@pytest.mark.parametrize("rate_hz", [100.0, 200.0])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_fit_recovers_white_noise_and_rate_random_walk_within_10_percent(seed, rate_hz):
    fit = fit_allan(_static(seed, rate_hz))
    assert list(fit.index) == AXES
    err_n = (fit["random_walk"] / N_TRUE - 1.0).abs()
    err_k = (fit["rate_random_walk"] / K_TRUE - 1.0).abs()
    assert err_n.max() < 0.10, err_n.to_dict()
    assert err_k.max() < 0.10, err_k.to_dict()
    # no flicker floor in these data: the bias instability is not resolved, with a reason
    assert fit["bias_instability"].isna().all()
    assert fit["reason"].str.contains("bias_instability").all()
    assert (fit["rms_log_error"] < 0.01).all()   # 2.3 % in deviation, cluster-weighted


def test_short_white_record_leaves_the_rate_random_walk_unresolved():
    fit = fit_allan(_static(5, 100.0, duration_s=60.0, k=0.0))
    assert (fit["random_walk"] / N_TRUE - 1.0).abs().max() < 0.05
    assert fit["rate_random_walk"].isna().all()
    assert fit["reason"].str.contains("rate_random_walk").all()


def test_a_dropped_sample_is_accepted_and_counted():
    imu = _static(4, 100.0, duration_s=600.0).drop(index=[1000]).reset_index(drop=True)
    adev = allan_deviation(imu)
    assert adev.attrs["irregular_intervals"] == 1
    assert (fit_allan(adev)["random_walk"] / N_TRUE - 1.0).abs().max() < 0.05


def test_allan_deviation_frame_and_its_fit_agree():
    imu = _static(3, 50.0, duration_s=600.0)
    adev = allan_deviation(imu)
    assert list(adev.columns) == ["tau_s", *AXES]
    assert adev["tau_s"].iloc[0] == pytest.approx(1 / 50.0)
    assert adev.attrs["duration_s"] == pytest.approx(600.0)
    # white-noise slope: sigma(tau) = N / sqrt(tau) at short tau
    assert adev["w_x"].iloc[0] == pytest.approx(N_TRUE / math.sqrt(1 / 50.0), rel=0.02)
    pd.testing.assert_frame_equal(fit_allan(adev), fit_allan(imu), check_like=True)


def test_bias_instability_floor_is_converted():
    """A flat Allan deviation (bias instability only, with white noise to set the start):
    B = floor / 0.664."""
    tau = np.logspace(-2, 3, 60)
    floor = 1e-5
    adev = pd.DataFrame({"tau_s": tau, "w_x": np.sqrt((1e-5) ** 2 / tau + floor**2)})
    adev.attrs["duration_s"] = 1e5
    fit = fit_allan(adev)
    assert fit.loc["w_x", "bias_instability"] == pytest.approx(floor / BI_FACTOR, rel=1e-3)
    assert fit.loc["w_x", "random_walk"] == pytest.approx(1e-5, rel=1e-3)
    assert np.isnan(fit.loc["w_x", "rate_random_walk"])


def test_datasheet_units():
    fit = pd.DataFrame({"random_walk": [1.0 * DEG / math.sqrt(HOUR)],
                        "bias_instability": [2.0 * DEG / HOUR],
                        "rate_random_walk": [3.0 * DEG / HOUR / math.sqrt(HOUR)]},
                       index=pd.Index(["w_x"], name="axis"))
    out = datasheet_units(fit)
    assert out.loc["w_x", ["random_walk", "bias_instability", "rate_random_walk"]].tolist() \
        == pytest.approx([1.0, 2.0, 3.0])
    assert out.loc["w_x", "unit_random_walk"] == "deg/√h"


def test_fitted_spec_written_as_a_preset(tmp_path):
    fit = fit_allan(_static(0, 100.0, duration_s=1800.0))
    path = write_allan_preset(fit, tmp_path / "my_imu.toml", name="my_imu",
                              source="generated static record", base="pixhawk_mems")
    spec = load_preset(path)
    base = load_preset("pixhawk_mems")
    assert spec.imu.gyro.noise_density == pytest.approx(fit.loc[["w_x", "w_y", "w_z"],
                                                                "random_walk"].mean())
    assert spec.imu.accel.bias_random_walk == pytest.approx(
        fit.loc[["f_x", "f_y", "f_z"], "rate_random_walk"].mean())
    assert spec.imu.gyro.bias_markov_sigma == 0.0        # unresolved: left out
    assert spec.imu.gyro.bias == base.imu.gyro.bias      # turn-on values from the base
    assert spec.gnss == base.gnss
    assert spec.imu.rate_hz == pytest.approx(100.0)


def test_allan_figure_draws_measured_fit_and_asymptotes():
    from navlib.plots.allan import allan_figure

    fit = fit_allan(_static(1, 50.0, duration_s=600.0))
    fig = allan_figure(fit)
    gyro, accel = fig.axes
    assert len(gyro.lines) == 3 * 2 + 3 * 2    # points + fit + 2 resolved asymptotes
    assert gyro.get_xscale() == "log" and accel.get_yscale() == "log"


@pytest.mark.parametrize(("imu", "words"), [
    ([1, 2, 3], "imu: expected a pandas DataFrame"),
    (pd.DataFrame({"t": np.arange(500) / 10.0}), "needs a 't' column and at least one"),
    (pd.DataFrame({"t": np.arange(50) / 10.0, "w_x": 0.0}), "at least 100 samples"),
    (pd.DataFrame({"t": np.r_[np.arange(200), np.arange(300, 500)] / 10.0, "w_x": 0.0}),
     "row 200 (t = 30 s) follows a gap"),
    (pd.DataFrame({"t": np.arange(0, 1000, 2) / 10.0, "w_x": 0.0}).drop(index=[5, 9]),
     "2 interval(s) longer than 1.5 steps"),
    (pd.DataFrame({"t": np.arange(500) / 10.0, "w_x": np.r_[np.nan, np.zeros(499)]}),
     "column 'w_x' contains NaN"),
])
def test_bad_records_say_what_was_expected(imu, words):
    with pytest.raises(NavlibInputError) as info:
        fit_allan(imu)
    assert words in str(info.value)
