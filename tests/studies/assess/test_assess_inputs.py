"""The IMU checks of an assessment that run before the data-quality checks
(navlib.studies.assess.inputs.check_imu_record, docs/assumptions.md Q6): two inputs a user
met that gave a bare NumPy error or blamed the GNSS (issue 39)."""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pytest
from support.locations import REPO

from navlib import NavlibInputError, io
from navlib.io import quality
from navlib.studies.assess import assess_flight
from navlib.studies.assess.inputs import MIN_IMU_SAMPLES

SAMPLE = REPO / "data" / "sample_flight"


@pytest.fixture(scope="module")
def gnss():
    return io.read_gnss_csv(SAMPLE / "gnss.csv")


def test_an_imu_csv_of_two_rows_names_the_imu_and_the_samples_needed(tmp_path, gnss):
    """Was a ValueError from np.gradient inside the GNSS jump check."""
    path = tmp_path / "imu.csv"
    path.write_text("\n".join((SAMPLE / "imu.csv").read_text().splitlines()[:3]) + "\n")
    imu = io.read_imu_csv(path)
    assert len(imu) == 2
    with pytest.raises(NavlibInputError,
                       match=rf"^imu: 2 sample\(s\); an assessment needs at least "
                             rf"{MIN_IMU_SAMPLES} IMU samples"):
        assess_flight(imu, gnss)


def test_an_accelerometer_reading_zeros_is_named_before_the_gnss_checks(tmp_path, gnss):
    """Was refused blaming the GNSS fixes (or the levelling of the fit), never the
    accelerometer."""
    imu = io.read_imu_csv(SAMPLE / "imu.csv")
    imu[["f_x", "f_y", "f_z"]] = 0.0
    with pytest.raises(NavlibInputError) as caught:
        assess_flight(imu, gnss)
    text = str(caught.value)
    assert text.startswith("imu f_x, f_y, f_z: the accelerometer never reads 0.5 g")
    assert "f_x reads 0 in every sample" in text and "at most 0 m/s^2" in text
    assert "gnss" not in text.lower()
    # the same record as a file is refused by its reader, naming the dead accelerometer
    frame = pd.read_csv(SAMPLE / "imu.csv")
    frame[[c for c in frame.columns if c.startswith("f_")]] = 0.0
    path = tmp_path / "imu.csv"
    frame.to_csv(path, index=False)
    with pytest.raises(NavlibInputError) as caught:
        io.read_imu_csv(path)
    text = str(caught.value)
    assert "(f_x)" in text and "gravity alone reads 9.8 m/s^2 at rest" in text
    assert "gnss" not in text.lower()


def test_a_record_that_reaches_half_a_g_once_is_not_refused_by_that_check(gnss):
    """The rule is the peak (a rocket may coast for most of its samples): one sample at
    0.6 g in a record otherwise falling freely passes check_imu_record."""
    from navlib.studies.assess.inputs import check_imu_record

    t = np.arange(0.0, 5.0, 0.01)
    f = np.zeros((t.size, 3))
    f[100, 2] = -0.6 * 9.80665
    imu = pd.DataFrame({"t": t, "f_x": f[:, 0], "f_y": f[:, 1], "f_z": f[:, 2],
                        "w_x": 0 * t, "w_y": 0 * t, "w_z": 0 * t})
    check_imu_record(imu)
    imu.loc[100, "f_z"] = -0.4 * 9.80665
    with pytest.raises(NavlibInputError, match=r"never reads 0\.5 g"):
        check_imu_record(imu)


def test_a_non_finite_imu_value_is_named():
    t = np.arange(0.0, 5.0, 0.01)
    imu = pd.DataFrame({"t": t, "f_x": 0 * t, "f_y": 0 * t, "f_z": -9.8 + 0 * t,
                        "w_x": 0 * t, "w_y": 0 * t, "w_z": 0 * t})
    imu.loc[7, "w_y"] = np.nan
    with pytest.raises(NavlibInputError, match=r"imu: column 'w_y' is not finite at row 7"):
        assess_flight(imu, pd.DataFrame({"t": t[::50], "x": 4.2e6, "y": 0.7e6, "z": 4.7e6}))


def test_gnss_faults_on_an_imu_record_shorter_than_the_jerk_smoothing(gnss):
    """navlib.io.quality.gnss_faults on its own (public): an IMU record of fewer samples than the
    jerk bound's moving average (0.1 s) gave np.gradient's ValueError."""
    t = np.arange(5) * 0.001 + float(gnss.t.iloc[0])
    imu = pd.DataFrame({"t": t, "f_x": 9.8 + 0 * t, "f_y": 0 * t, "f_z": 0 * t,
                        "w_x": 0 * t, "w_y": 0 * t, "w_z": 0 * t})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        bad, findings = quality.gnss_faults(imu, gnss, 5.0)
    assert bad.shape == (len(gnss),)
    assert list(findings.columns) == list(quality.FINDING_COLUMNS)


def _still(seconds=5.0, rate=100.0):
    t = np.arange(0.0, seconds, 1.0 / rate)
    imu = pd.DataFrame({"t": t, "f_x": 0 * t, "f_y": 0 * t, "f_z": -9.8 + 0 * t,
                        "w_x": 0 * t, "w_y": 0 * t, "w_z": 1e-3 + 0 * t})
    tg = t[::20]
    gnss = pd.DataFrame({"t": tg, "x": 4.2e6 + 0 * tg, "y": 0.7e6 + 0 * tg,
                         "z": 4.7e6 + 0 * tg})
    return imu, gnss


def test_imu_times_out_of_order_are_named_before_the_quality_checks():
    """A DataFrame in another order than time: scipy's maximum_filter1d raised
    RuntimeError('incorrect filter size') inside the GNSS jump check."""
    imu, gnss = _still()
    shuffled = imu.sample(frac=1.0, random_state=1).reset_index(drop=True)
    for call in (lambda: assess_flight(shuffled, gnss),
                 lambda: quality.check_records(shuffled, gnss),
                 lambda: quality.gnss_faults(shuffled, gnss, 5.0)):
        with pytest.raises(NavlibInputError, match=r"imu column 't': times must be strictly "
                                                   r"increasing"):
            call()


@pytest.mark.parametrize("rows", [0, 1])
def test_quality_checks_of_a_record_of_fewer_than_two_rows(rows):
    """check_records on its own: ValueError from NumPy (an empty maximum, NaN to int)."""
    imu, gnss = _still()
    with pytest.raises(NavlibInputError, match=rf"imu column 't': need at least 2 samples, "
                                               rf"got {rows}"):
        quality.check_records(imu.iloc[:rows], gnss)


def test_gnss_positions_far_from_the_earth_are_named_before_the_quality_checks():
    """A GNSS record of zeros: refused as '99.2 % of the fixes are faulty' (frozen)."""
    imu, gnss = _still()
    gnss[["x", "y", "z"]] = 0.0
    with pytest.raises(NavlibInputError, match=r"^gnss: the position of row 0 \(t = 0 s\) is "
                                               r"0 m from the Earth's centre, and 25 of 25"):
        assess_flight(imu, gnss)
