"""Fleet assessment: ``python -m navlib assess``, navlib.reports.fleet and the LOG argument
(navlib.io.logs)."""

from __future__ import annotations

import pandas as pd
import pytest
from support.locations import REPO, shared_file

from navlib import NavlibInputError, io
from navlib.__main__ import main
from navlib.reports import fleet

ROOT = REPO
SAMPLE = ROOT / "data" / "sample_flight"
PAIR = f"{SAMPLE / 'imu.csv'},{SAMPLE / 'gnss.csv'}"


@pytest.mark.parametrize("spec, kind, n", [("a.ulg", "ulog", 1), ("b.BIN", "dataflash", 1),
                                           ("i.csv,g.csv", "csv", 2)])
def test_parse_log(spec, kind, n):
    got_kind, paths = io.parse_log(spec)
    assert got_kind == kind and len(paths) == n


@pytest.mark.parametrize("spec", ["a.txt", "i.csv", "a.csv,b.txt", "a,b,c", ""])
def test_parse_log_rejects(spec):
    with pytest.raises(NavlibInputError):
        io.parse_log(spec)


@pytest.mark.parametrize("generation", ["version", "legacy"])
@pytest.mark.parametrize("name", ["flight.csv", "flight-18.txt"])
def test_altos_export_is_one_log_by_its_header(tmp_path, generation, name):
    from support.altos_writer import rocket_rows, write_altos

    path = tmp_path / name
    write_altos(path, rocket_rows(), generation=generation)
    kind, paths = io.parse_log(str(path))
    assert kind == "altos" and paths == (path,)
    imu, gnss = io.read_log(str(path))
    assert imu.attrs["autopilot"] == "altos" and len(gnss) > 5
    other = tmp_path / "imu.csv"
    other.write_text("t,f_x,f_y,f_z,w_x,w_y,w_z\n0,0,0,9.8,0,0,0\n")
    with pytest.raises(NavlibInputError, match=r"AltOS, FIRM, CATS"):
        io.parse_log(str(other))


def test_fleet_reports_bad_logs_and_keeps_going(tmp_path, capsys):
    bad_csv = tmp_path / "imu.csv"
    bad_csv.write_text("t,f_x\n0,1\nnot,a number\n")
    out = tmp_path / "fleet"
    bin_log = tmp_path / "flight.bin"
    bin_log.write_bytes(b"\x00" * 64)
    logs = [PAIR, str(tmp_path / "missing.ulg"), f"{bad_csv},{SAMPLE / 'gnss.csv'}",
            str(tmp_path / "notes.txt"), str(bin_log)]
    status = main(["assess", *logs, "--output", str(out), "--scheduler", "synchronous",
                   "-p", "eta", "1e-3"])
    assert status == 1
    table = pd.read_csv(out / "summary.csv", keep_default_na=False)
    assert list(table.columns) == list(fleet.SUMMARY_COLUMNS)
    assert table.aiding.tolist() == ["gnss", "", "", "", ""]
    assert table["log"].tolist() == logs
    assert table["status"].tolist() == ["ok", "failed", "failed", "failed", "failed"]
    ok = table.iloc[0]
    assert float(ok.duration_s) == pytest.approx(86.0, abs=1.0)
    assert "boost 0.0-" in ok.phases and "free_fall" in ok.phases   # since ignition
    assert ok.excitable.count("|") == int(ok.n_segments) - 1
    assert "sg_x" in ok.excitable  # the spin excites the roll gyro scale factor
    page = out / ok.page
    assert page.is_file() and "data:image/png;base64," in page.read_text()
    assert "not found" in table.error.iloc[1]
    assert table.error.iloc[2].startswith("NavlibInputError")
    assert "not found or unreadable" in table.error.iloc[3]
    assert table.error.iloc[4].startswith("NavlibInputError")  # 64 zero bytes: no DataFlash
    assert all(table.page.iloc[1:] == "")
    assert "1 of 5 flight(s) assessed" in capsys.readouterr().err


def test_fleet_all_ok_exit_zero_and_bad_options(tmp_path, capsys):
    out = tmp_path / "fleet"
    assert main(["assess", PAIR, "--output", str(out), "--scheduler", "synchronous"]) == 0
    assert pd.read_csv(out / "summary.csv").status.tolist() == ["ok"]
    assert main(["assess", PAIR, "--output", str(out), "--scheduler", "synchronous",
                 "-p", "colour", "red"]) == 2
    assert "colour" in capsys.readouterr().err
    assert main(["assess", PAIR, "--output", str(out), "--scheduler", "nowhere"]) == 2


def test_fleet_on_a_px4_log(tmp_path):
    table, pages = fleet.assess_logs([str(shared_file("px4", "sample_log_small.ulg"))],
                                     scheduler="synchronous")
    row = table.iloc[0]
    assert row.status == "ok", row.error
    assert "FlightDataWarning" in row.warnings
    assert pages[0] is not None


def test_fleet_on_a_worker_process(tmp_path):
    """Flights run as tasks on a Dask worker give the same table as in-process."""
    distributed = pytest.importorskip("distributed")
    logs = [PAIR, str(tmp_path / "missing.ulg")]
    local, _ = fleet.assess_logs(logs, scheduler="synchronous")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                  dashboard_address=":0") as cluster, \
            distributed.Client(cluster) as client:
        remote, pages = fleet.assess_logs(logs, scheduler=client)
    pd.testing.assert_frame_equal(local.drop(columns="seconds"),
                                  remote.drop(columns="seconds"))
    assert pages[0].startswith("<!DOCTYPE html>") and pages[1] is None
