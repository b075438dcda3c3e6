"""Failure classes of real logs on generated multicopter flights.

Each case is either assessed correctly or refused with a NavlibInputError naming the
problem: IMU holes of 0.2, 0.7 and 10 s, 10 Hz and 2 Hz IMUs, motor vibration at rest, a
flight starting in the air with the autopilot's attitude logged, one glitch sample. A
hypothesis test then throws holes, rates and glitches at reader + assessment together.
"""

import warnings

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation
from support.flights import logged_attitude, multicopter, records

from navlib import NavlibInputError, io
from navlib.studies.assess import assess_flight, choose_preset, describe_inputs
from navlib.trajectory.fit import MIN_IMU_RATE_HZ

PAD_S = 8.0


@pytest.fixture(scope="module")
def truth():
    return multicopter(32.0, 100.0, pad_s=PAD_S)


@pytest.fixture(scope="module")
def recs(truth):
    return records(truth, seed=3)


def _assess(imu, gnss, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return assess_flight(imu, gnss, preset="pixhawk_mems", **kw)


def _drop(imu, t0, length):
    t = imu["t"].to_numpy()
    out = imu[~((t > t0) & (t < t0 + length))].reset_index(drop=True)
    out.attrs = dict(imu.attrs)
    return out


def _pad_is_rest(result, at_least_s):
    first = result.segment_table.iloc[0]
    assert first["phase"] == "rest"
    assert first["t_end"] - first["t_start"] >= at_least_s
    assert first["t_end"] <= PAD_S + 1.0


def test_clean_flight_reference(recs):
    result = _assess(*recs)
    _pad_is_rest(result, PAD_S - 1.5)
    assert result.options["attitude_source"] in ("estimated", "keyword")
    assert any(n.startswith("levelled over") for n in result.notes)
    # the accelerometer bias (0.1 m/s^2 class) is estimated, not taken for motion
    traj = result.trajectory
    pad = traj.t < PAD_S - 1.0
    assert np.linalg.norm(traj.velocity[pad], axis=1).max() < 0.3
    bias = traj.parameters["fit_residuals"]["accel_bias_mps2"]
    assert 0.0 < np.linalg.norm(bias) < 0.5


def test_in_air_start_without_attitude_is_refused_by_name(recs):
    imu, gnss = recs
    air = imu[imu["t"] >= 15.0].reset_index(drop=True)
    with pytest.raises(NavlibInputError, match=r"no window of level_s=1 s where the vehicle "
                                               r"is at rest.*GNSS acceleration.*autopilot"):
        _assess(air, gnss[gnss["t"] >= 15.0].reset_index(drop=True))


def test_heading_keyword_holds_at_the_start_when_levelled_later(truth, recs):
    imu, gnss = recs
    quiet_late = imu.copy()
    early = quiet_late["t"] < 3.0                          # a shaky start: level later
    quiet_late.loc[early, ["f_x", "f_y", "f_z"]] += 3.0 * np.random.default_rng(0).standard_normal(
        (int(early.sum()), 3))
    heading = 17.19                                        # the truth's yaw at the start
    result = _assess(quiet_late, gnss, fit_options={"heading_deg": heading})
    level = result.trajectory.parameters["fit_residuals"]["level"]
    assert level["t_start"] >= 2.0
    assert result.options["heading_deg"] == pytest.approx(heading, abs=3.0)


@pytest.mark.parametrize("length", [0.2, 0.7])
def test_short_holes_are_bridged_with_a_stated_bound(recs, length):
    imu, gnss = recs
    result = _assess(_drop(imu, 4.0, length), gnss)
    holes = result.trajectory.parameters["fit_residuals"]["imu_holes"]
    assert len(holes) == 1
    assert holes[0]["duration_s"] == pytest.approx(length + 0.01, abs=0.011)
    assert 0.0 <= holes[0]["attitude_bound_deg"] < 1.0
    assert 0.0 <= holes[0]["position_bound_m"] < 1.0
    assert any("bridged" in n for n in result.notes)
    _pad_is_rest(result, PAD_S - 1.5)        # the hole does not turn the pad into motion
    # the fit bridges the hole: the trajectory is sampled at the recorded times only
    assert not np.any((result.trajectory.t > 4.0 + 1e-6)
                      & (result.trajectory.t < 4.0 + length - 1e-6))


def test_long_hole_splits_into_separately_assessed_spans(truth, recs):
    imu, gnss = recs
    imu = imu.copy()
    imu.attrs["attitude"] = logged_attitude(truth)   # the second span starts in the air
    with pytest.warns(io.FlightDataWarning, match="split into 2 spans"):
        result = assess_flight(_drop(imu, 14.0, 10.0), gnss, preset="pixhawk_mems")
    assert len(result.spans) == 2
    (a, b) = result.spans
    assert a.trajectory.t[-1] <= 14.0 and b.trajectory.t[0] >= 24.0
    assert result.trajectory is a.trajectory    # the longer span is the result
    assert any("split into 2 spans" in n for n in result.notes)
    assert b.options["attitude_source"] == "log"


def test_long_hole_without_a_usable_second_span_is_named(recs):
    imu, gnss = recs
    gnss_short = gnss[gnss["t"] < 20.0].reset_index(drop=True)
    with pytest.warns(io.FlightDataWarning, match="not assessed"):
        result = assess_flight(_drop(imu, 14.0, 10.0), gnss_short, preset="pixhawk_mems")
    assert result.trajectory.t[-1] <= 14.0
    assert any("not assessed" in n and "24" in n for n in result.notes)


def test_ten_hz_imu_is_assessed(recs):
    imu, gnss = recs
    slow = imu.iloc[::10].reset_index(drop=True)
    result = _assess(slow, gnss)
    assert result.options["imu_rate_hz"] == pytest.approx(10.0)
    _pad_is_rest(result, PAD_S - 2.5)


def test_two_hz_imu_is_refused_with_rate_minimum_and_reason(recs):
    imu, gnss = recs
    with pytest.raises(NavlibInputError, match=rf"median rate 2 Hz is below the minimum "
                                               rf"{MIN_IMU_RATE_HZ:g} Hz.*knot interval"):
        _assess(imu.iloc[::50].reset_index(drop=True), gnss)


def test_vibration_at_rest_is_levelled(truth):
    # armed multicopter on its pads: 1-1.6 m/s^2 spread, mean |f| at gravity
    imu, gnss = records(truth, seed=4, vibration_mps2=0.8)
    pad = imu["t"] < PAD_S - 1
    spread = np.linalg.norm(imu.loc[pad, ["f_x", "f_y", "f_z"]].std().to_numpy())
    assert 1.0 < spread < 1.6
    result = _assess(imu, gnss)
    level = result.trajectory.parameters["fit_residuals"]["level"]
    assert level["t_end"] <= PAD_S + 1.0
    assert level["spread_mps2"] == pytest.approx(spread, rel=0.2)
    _pad_is_rest(result, PAD_S - 3.0)
    # the start attitude is right to the level the sensor errors allow (0.1 m/s^2 of
    # accelerometer bias tilts by 0.6 deg; the heading rests on weak horizontal motion)
    err = (result.trajectory.attitude[0].inv() * truth.attitude[0]).magnitude()
    assert np.degrees(err) < 4.0


def test_in_air_start_uses_the_logged_attitude(truth, recs):
    imu, gnss = recs
    t0 = 15.0
    air = imu[imu["t"] >= t0].reset_index(drop=True)
    air.attrs["attitude"] = logged_attitude(truth)
    result = _assess(air, gnss[gnss["t"] >= t0].reset_index(drop=True))
    assert result.options["attitude_source"] == "log"
    assert any("autopilot's own attitude" in n for n in result.notes)
    assert result.options["t_zero"] == pytest.approx(t0, abs=0.02)   # times since the start
    k = int(np.searchsorted(truth.t, result.trajectory.t[0] + result.options["t_zero"]))
    err = (result.trajectory.attitude[0].inv() * truth.attitude[k]).magnitude()
    assert np.degrees(err) < 4.0       # the fit's correction moves the logged start (biases)
    assert result.segment_table["phase"].iloc[0] != "rest"


def test_logged_attitude_ignored_on_request(truth, recs):
    imu, gnss = recs
    imu = imu.copy()
    imu.attrs["attitude"] = logged_attitude(truth)
    result = _assess(imu, gnss, fit_options={"use_logged_attitude": False})
    assert result.options["attitude_source"] != "log"


def test_one_glitch_sample_is_excluded_and_reported(tmp_path, recs):
    imu, gnss = recs
    bad = imu.copy()
    bad.loc[500, "w_x"] = 49.0
    path = io.write_imu_csv(bad, tmp_path / "imu.csv")
    with pytest.warns(io.FlightDataWarning, match=r"1 non-physical IMU sample.*line 502"):
        read = io.read_imu_csv(path)
    (flag,) = read.attrs["outliers"]
    assert flag["t"] == pytest.approx(imu["t"][500]) and flag["value"] > 49.0
    assert len(read) == len(imu) - 1
    result = _assess(read, gnss)
    assert describe_inputs(read, gnss).set_index("record").loc["imu", "outliers"] == 1
    assert any("excluded by the reader" in n and "5 s" in n for n in result.notes)


def test_many_glitches_refuse_with_keywords_that_exist(tmp_path, recs):
    imu, _ = recs
    bad = imu.copy()
    bad.loc[100:200, "w_x"] = 49.0
    path = io.write_imu_csv(bad, tmp_path / "imu.csv")
    # glitches in a calm rad/s record: the units are right, so no deg/s hint (issue 35)
    with pytest.raises(NavlibInputError, match=r"101 of \d+ samples .* units look right: .* "
                                               r"larger max_rate_rad_s"):
        io.read_imu_csv(path)


def test_preset_follows_the_log():
    frame = pd.DataFrame({"t": [0.0]})
    assert choose_preset(frame)[0] == "motionpak_tactical"
    frame.attrs.update(autopilot="px4", hardware="PX4_FMU_V5")
    assert choose_preset(frame) == ("pixhawk_mems", "px4 log (PX4_FMU_V5)")
    assert choose_preset(frame, "launcher_table1")[0] == "launcher_table1"


# --------------------------------------------------------------------------- property


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    truth = multicopter(16.0, 50.0, pad_s=5.0)
    imu, gnss = records(truth, seed=9)
    return imu, gnss, tmp_path_factory.mktemp("prop")


@settings(max_examples=8, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(step=st.sampled_from([1, 2, 5, 10, 25]),
       holes=st.lists(st.tuples(st.floats(0.5, 15.0), st.floats(0.05, 12.0)), max_size=2),
       gnss_hole=st.one_of(st.none(), st.tuples(st.floats(0.0, 15.0), st.floats(0.5, 8.0))),
       glitches=st.lists(st.integers(0, 799), max_size=3),
       glitch_value=st.sampled_from([49.0, -80.0, 1e4]))
def test_assess_raises_only_navlib_errors(small, step, holes, gnss_hole, glitches,
                                          glitch_value):
    imu, gnss, folder = small
    if gnss_hole is not None:
        gnss = _drop(gnss, *gnss_hole)
    bad = imu.copy()
    for k in glitches:
        bad.loc[k, "w_z"] = glitch_value
    bad = bad.iloc[::step].reset_index(drop=True)
    for t0, length in holes:
        bad = _drop(bad, t0, length)
    if len(bad) < 2:
        return
    path = io.write_imu_csv(bad, folder / "imu.csv")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            read = io.read_imu_csv(path)
        except NavlibInputError:
            return                                   # the reader refused it: fine
        try:
            result = assess_flight(read, gnss)
        except NavlibInputError as exc:
            assert str(exc)
            return
    assert len(result.summary()) >= 1
    assert np.all(np.isfinite(result.trajectory.position))


def test_rotation_helper_is_a_rotation(truth):
    q = logged_attitude(truth)[["qx", "qy", "qz", "qw"]].to_numpy()
    assert np.allclose(np.linalg.norm(q, axis=1), 1.0)
    assert Rotation.from_quat(q).single is False


def test_gnss_gap_split_by_the_reader_is_bridged(recs):
    imu, gnss = recs
    holed = _drop(gnss, 18.0, 4.0)
    holed["segment"] = (holed["t"] > 18.0).astype(int)    # as read with on_gap="split"
    result = _assess(imu, holed)
    assert not result.spans and result.trajectory.t[-1] == pytest.approx(imu["t"].iloc[-1])
    _pad_is_rest(result, PAD_S - 1.5)
