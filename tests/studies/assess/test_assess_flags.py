"""``python -m navlib assess`` flags (--preset, --vehicle, --initial-attitude,
--launch-elevation, --launch-azimuth, -p over several words) and the shared real logs'
vehicle words and GNSS warnings."""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pytest
from support.locations import REPO, shared_file

from navlib import io
from navlib.__main__ import _negative_angles, _parser, assess_options, main
from navlib.errors import NavlibInputError
from navlib.reports import fleet
from navlib.segmentation import VEHICLE_PHASES
from navlib.studies.assess import assess_flight

ROOT = REPO
SAMPLE = ROOT / "data" / "sample_flight"
PAIR = f"{SAMPLE / 'imu.csv'},{SAMPLE / 'gnss.csv'}"


def _options(*words):
    argv = _negative_angles(["assess", "a.ulg", "--output", "out", *words])
    return assess_options(_parser().parse_args(argv))


def test_flags_map_onto_assess_keywords_and_fit_options():
    got = _options("--preset", "pixhawk_mems", "--vehicle", "rocket",
                   "--initial-attitude=-30,80,0", "--launch-elevation", "84",
                   "--launch-azimuth", "100", "-p", "eta", "1e-2")
    assert got == {"eta": 1e-2, "preset": "pixhawk_mems", "vehicle": "rocket",
                   "fit_options": {"initial_attitude_deg": (-30.0, 80.0, 0.0),
                                   "launch_elevation_deg": 84.0,
                                   "launch_azimuth_deg": 100.0}}
    assert _options() == {}
    # a negative yaw as its own word, which argparse alone takes for an option
    assert _options("--initial-attitude", "-30,80,0")["fit_options"] == {
        "initial_attitude_deg": (-30.0, 80.0, 0.0)}


def test_p_value_over_several_words_is_joined():
    got = _options("-p", "fit_options", '{"max_bridge_s":', "2,", '"level_s":', "0.5}",
                   "--launch-elevation", "80")
    assert got == {"fit_options": {"max_bridge_s": 2, "level_s": 0.5,
                                   "launch_elevation_deg": 80.0}}


@pytest.mark.parametrize("words, match", [
    (("-p", "eta", "1e-3", "flight.ulg"), r"-p eta: the value came as 2 shell words"),
    (("-p", "eta"), r"-p eta: no value given"),
    (("-p", "eta", "1", "-p", "eta", "2"), "given twice"),
    (("--initial-attitude", "10,20"), r"--initial-attitude: expected YAW,PITCH,ROLL"),
    (("--initial-attitude", "a,b,c"), r"--initial-attitude: expected YAW,PITCH,ROLL"),
    (("--preset", "x", "-p", "preset", "y"), r"--preset: also given as -p preset"),
    (("-p", "fit_options", "[1, 2]"), r"-p fit_options: expected a JSON object"),
    (("-p", "fit_options", '{"launch_azimuth_deg": 3}', "--launch-azimuth", "4"),
     "launch_azimuth_deg given both"),
])
def test_bad_flags_are_named(words, match):
    with pytest.raises(NavlibInputError, match=match):
        _options(*words)


def test_help_lists_the_flags(capsys):
    with pytest.raises(SystemExit):
        main(["assess", "--help"])
    out = capsys.readouterr().out
    for flag in ("--preset", "--vehicle", "--initial-attitude", "--launch-elevation",
                 "--launch-azimuth", "-p KEY [VALUE ...]"):
        assert flag in out
    assert "rocket,multicopter,fixed-wing,ground" in out


def test_cli_vehicle_and_split_json_reach_the_summary(tmp_path, capsys):
    out = tmp_path / "fleet"
    status = main(["assess", PAIR, "--output", str(out), "--scheduler", "synchronous",
                   "--vehicle", "rocket", "-p", "segment_options", '{"min_duration_s":', "3}"])
    assert status == 0, capsys.readouterr().err
    table = pd.read_csv(out / "summary.csv", keep_default_na=False)
    assert list(table.columns) == list(fleet.SUMMARY_COLUMNS)
    assert list(table.columns[:5]) == ["log", "status", "error", "vehicle", "duration_s"]
    row = table.iloc[0]
    assert row.vehicle == "rocket"
    assert row.phases.split(";")[0].startswith("pad -18.")    # the pad before ignition
    assert row.phases.split("; ")[1].startswith("boost 0.0-")
    assert float(row.t_ignition) == pytest.approx(18.1, abs=0.3)
    assert "vehicle" in (out / row.page).read_text()


def test_bad_split_value_fails_with_exit_status_2(tmp_path, capsys):
    status = main(["assess", PAIR, "--output", str(tmp_path), "-p", "eta", "1e-3", "2e-3"])
    assert status == 2
    assert "-p eta: the value came as 2 shell words" in capsys.readouterr().err


def test_saturation_reaches_the_warnings_column_and_the_thresholds_the_cli(tmp_path):
    """A flat-topped roll gyro in the sample flight: warned with its times in summary.csv;
    with max_fraction lowered through -p (JSON over several words) the flight is refused."""
    imu = pd.read_csv(SAMPLE / "imu.csv")
    column = next(c for c in imu.columns if c.startswith("w_x"))
    k = int(np.searchsorted(imu.iloc[:, 0].to_numpy(), 30.0))
    imu.loc[k:k + 7, column] = 1500.0 * np.pi / 180.0
    path = tmp_path / "imu.csv"
    imu.to_csv(path, index=False)
    log = f"{path},{SAMPLE / 'gnss.csv'}"
    assert main(["assess", log, "--output", str(tmp_path / "a"), "--scheduler",
                 "synchronous"]) == 0
    row = pd.read_csv(tmp_path / "a" / "summary.csv", keep_default_na=False).iloc[0]
    assert "gyro w_x flat at 1500 deg/s: 8 samples (0.093 %) at 30.0-30.1 s" in row.warnings
    assert main(["assess", log, "--output", str(tmp_path / "b"), "--scheduler",
                 "synchronous", "-p", "quality_thresholds", '{"saturation":',
                 '{"max_fraction":', "0.0005}}"]) == 1
    row = pd.read_csv(tmp_path / "b" / "summary.csv", keep_default_na=False).iloc[0]
    assert row.status == "failed"
    assert "0.093 % of the samples are saturated, more than the 0.05 %" in row.error


# --------------------------------------------------------------------------- shared logs


def _assess_log(reader, path):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        imu, gnss = reader(path)
        result = assess_flight(imu, gnss)
    return imu, result, [str(w.message) for w in caught]


def test_sitl_copter_speaks_multicopter():
    _, result, _ = _assess_log(io.read_dataflash,
                                  shared_file("ardupilot", "sitl_copter_flight.bin"))
    assert result.vehicle == "multicopter"
    assert "ArduCopter" in result.options["vehicle_reason"]
    phases = set(result.segment_table["phase"])
    assert phases <= set(VEHICLE_PHASES["multicopter"])
    assert {"rest", "climb", "hover"} <= phases


def _px4_baro(path, imu):
    """The barometric altitude of a ULog (``vehicle_air_data``) as ``imu.attrs["baro"]``,
    when the reader does not attach it."""
    from pyulog import ULog

    data = ULog(str(path), ["vehicle_air_data"]).data_list[0].data
    t = (data["timestamp"].astype(np.int64) - imu.attrs["t0_us"]) * 1e-6
    return pd.DataFrame({"t": t, "alt_m": data["baro_alt_meter"].astype(float)})


def test_octocopter_speaks_multicopter_and_checks_its_gnss_altitude():
    path = shared_file("px4", "octocopter_log83.ulg")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        imu, gnss = io.read_ulog(path)
        if imu.attrs.get("baro") is None:
            imu.attrs["baro"] = _px4_baro(path, imu)
        result = assess_flight(imu, gnss)
    texts = [str(w.message) for w in caught]
    assert result.vehicle == "multicopter"
    assert set(result.segment_table["phase"]) <= set(VEHICLE_PHASES["multicopter"])
    # the barometer topic stops at 13.8 s of a 72 s flight: said, not taken for a 44 m error
    assert any("GNSS altitude disagrees with the barometer" in t
               or "the barometer record covers only" in t for t in texts)
    assert "gnss altitude" in set(result.quality["check"])


def test_px4_vehicle_type_from_the_log_in_a_fleet(tmp_path):
    """The PX4 SITL log barely moves (kinematics would say ground); its MAV_TYPE 2 says
    quadrotor, and the fleet row says multicopter."""
    path = shared_file("px4", "sample_px4_events.ulg")
    assert main(["assess", str(path), "--output", str(tmp_path), "--scheduler",
                 "synchronous"]) == 0
    row = pd.read_csv(tmp_path / "summary.csv", keep_default_na=False).iloc[0]
    assert row.vehicle == "multicopter"
    phases = [p.rsplit(" ", 2)[0] for p in row.phases.split("; ")]
    assert set(phases) <= set(VEHICLE_PHASES["multicopter"])
    assert "MAV_TYPE 2" in (tmp_path / row.page).read_text()
