"""Reader options from the command line and from navlib.io.read_log (issue 35): the
``--read KEY VALUE`` flag and ``-p read_options {...}`` of ``assess``, routed to the LOG's
reader; unknown keywords refused naming those the reader takes; and the old address
navlib.quality still importing, with a DeprecationWarning."""

from __future__ import annotations

import importlib
import sys

import numpy as np
import pytest

from navlib import NavlibInputError, io
from navlib.__main__ import _parser, assess_options
from navlib.io.logs import reader_keywords

RATE = 100.0


def _write_imu(path, w_x=0.2, n=400):
    t = np.arange(n) / RATE
    rows = "".join(f"{a:.3f},0.1,0.2,-9.81,{w_x * np.sin(a) + 0.1:.5f},0.01,0.02\n" for a in t)
    path.write_text("t,f_x,f_y,f_z,w_x,w_y,w_z\n" + rows)
    return path


def _write_baro(path, n=400):
    t = np.arange(n) / RATE
    path.write_text("t,pressure_pa\n" + "".join(f"{a:.3f},{95_000 - a:.2f}\n" for a in t))
    return path


def _options(*argv):
    return assess_options(_parser().parse_args(["assess", "f.csv", *argv]))


def test_read_flag_and_parameter_give_the_reader_options():
    assert _options("--read", "max_rate_rad_s", "60", "--read", "on_gap", "split"
                    )["read_options"] == {"max_rate_rad_s": 60, "on_gap": "split"}
    assert _options("-p", "read_options", '{"max_rate_rad_s": 60}', "--read", "keep_held",
                    "true")["read_options"] == {"max_rate_rad_s": 60, "keep_held": True}
    with pytest.raises(NavlibInputError, match=r"--read max_rate_rad_s: given twice"):
        _options("-p", "read_options", '{"max_rate_rad_s": 60}', "--read", "max_rate_rad_s",
                 "50")
    with pytest.raises(NavlibInputError, match=r"-p read_options: expected a JSON object"):
        _options("-p", "read_options", "60")
    assert "read_options" not in _options()


def test_assess_help_documents_the_reader_options(capsys):
    with pytest.raises(SystemExit):
        _parser().parse_args(["assess", "--help"])
    text = capsys.readouterr().out
    assert "--read KEY VALUE" in text and "--read max_rate_rad_s 60" in text
    assert "max_faulty_time_fraction" in text


def test_read_log_routes_options_to_the_csv_readers(tmp_path):
    """A 4000 deg/s (70 rad/s) spin refused under the default 35 rad/s limit is read when the
    limit is raised from the LOG's options; the options reach only the readers taking them."""
    imu_path = _write_imu(tmp_path / "imu.csv", w_x=0.0)
    spin = imu_path.read_text().replace(",0.10000,", ",70.0,")
    imu_path.write_text(spin)
    log = f"{imu_path},{_write_baro(tmp_path / 'baro.csv')}"
    with pytest.raises(NavlibInputError, match=r"exceeds max_rate_rad_s=35"):
        io.read_log(log)
    imu, gnss = io.read_log(log, max_rate_rad_s=150.0, time_unit="s")
    assert gnss is None and len(imu) == 400 and imu.w_x.max() == pytest.approx(70.0)
    with pytest.raises(NavlibInputError, match=r"read options \['imu_instance'\]: not a keyword "
                                               r"of the csv reader .* it takes \[.*'keep_held'"):
        io.read_log(log, imu_instance=1)


def test_reader_keywords_per_kind():
    assert "imu_instance" in reader_keywords("dataflash")["dataflash"]
    assert "max_rate_rad_s" in reader_keywords("altos")["altos"]
    assert "gyro_unit" not in reader_keywords("firm")["firm"]      # FIRM's own units
    assert set(reader_keywords("csv")) == {"imu", "gnss", "baro"}


def test_old_quality_address_warns_and_still_works():
    sys.modules.pop("navlib.quality", None)
    with pytest.warns(DeprecationWarning, match=r"navlib.quality moved to navlib.io.quality"):
        old = importlib.import_module("navlib.quality")
    from navlib.io import quality

    assert old.check_records is quality.check_records
    assert old.load_thresholds()["gnss"] == quality.load_thresholds()["gnss"]


def test_fleet_takes_read_options_and_names_a_wrong_one(tmp_path):
    from navlib.reports import fleet

    with pytest.raises(NavlibInputError, match=r"read_options: expected a mapping"):
        fleet.assess_logs(["a.csv"], {"read_options": 60})
    log = f"{_write_imu(tmp_path / 'imu.csv')},{_write_baro(tmp_path / 'baro.csv')}"
    row, page = fleet.assess_log(log, {"read_options": {"imu_instance": 1}})
    assert row["status"] == "failed" and page is None
    assert "read options ['imu_instance']: not a keyword of the csv reader" in row["error"]


def test_plan_flight_takes_reader_options(tmp_path, capsys):
    from navlib.__main__ import main

    log = f"{_write_imu(tmp_path / 'imu.csv')},{_write_baro(tmp_path / 'baro.csv')}"
    status = main(["plan", "hpr_rocket", "--flight", log, "--read", "imu_instance", "1",
                   "--output", str(tmp_path / "plans")])
    assert status == 2
    assert ("read options ['imu_instance']: not a keyword of the csv reader"
            in capsys.readouterr().err)
