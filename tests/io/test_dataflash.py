"""navlib.io.read_dataflash: ArduPilot .bin logs, generated here and the public ones."""

import subprocess
import sys
import warnings

import numpy as np
import pandas as pd
import pytest
from scipy.spatial.transform import Rotation
from support.dataflash_writer import write_flight
from support.flights import dataflash_flight
from support.locations import REPO, shared_file

from navlib import NavlibInputError, earth, io
from navlib.studies.assess import assess_flight

ROOT = REPO


def _public(name):
    return shared_file("ardupilot", name)


@pytest.fixture(scope="module")
def flight():
    return dataflash_flight()


@pytest.fixture(scope="module")
def bin4(flight, tmp_path_factory):
    _, imu, _, geo, att = flight
    path = tmp_path_factory.mktemp("df") / "flight4.bin"
    write_flight(path, imu, geo, att, layout="4.x", imu_instances=(0, 1))
    return path


def test_generated_log_round_trip(flight, bin4):
    truth, imu_in, _, geo, _ = flight
    imu, gnss = io.read_dataflash(bin4)
    assert len(imu) == len(imu_in) and len(gnss) == len(geo)
    np.testing.assert_allclose(imu["t"], imu_in["t"] - imu_in["t"][0], atol=1e-6)
    for col in ("f_x", "f_y", "f_z", "w_x", "w_y", "w_z"):
        np.testing.assert_allclose(imu[col], imu_in[col], rtol=1e-6, atol=1e-6)
    r = earth.geodetic_to_ecef(np.radians(geo["lat_deg"]), np.radians(geo["lon_deg"]),
                               geo["alt_m"])
    assert np.abs(gnss[["x", "y", "z"]].to_numpy() - r).max() < 0.02   # 1e-7 deg, cm
    g = truth.at_rate(5.0)
    assert np.abs(gnss[["vx", "vy", "vz"]].to_numpy() - truth.velocity[g]).max() < 1e-3
    assert imu.attrs["autopilot"] == "ardupilot"
    assert imu.attrs["hardware"].startswith("ArduCopter V4.5.0")
    assert imu.attrs["instance"] == 0 and gnss.attrs["altitude_reference"] == "msl"
    att = imu.attrs["attitude"]
    C_n_e = earth.ned_to_ecef_matrix(*truth.geodetic[0][:1], *truth.geodetic[1][:1])
    q = Rotation.from_quat(att[["qx", "qy", "qz", "qw"]].to_numpy()[:1])
    err = (Rotation.from_matrix(C_n_e) * q).inv() * truth.attitude[:1]
    assert np.degrees(err.magnitude()[0]) < 1e-3


def test_instances_of_both_layouts(flight, tmp_path, bin4):
    _, imu_in, _, geo, _ = flight
    imu1, _ = io.read_dataflash(bin4, imu_instance=1)
    np.testing.assert_allclose(imu1["w_x"], imu_in["w_x"] + 1e-3, atol=1e-6)
    path = tmp_path / "flight3.bin"
    write_flight(path, imu_in, geo, layout="3.x", imu_instances=(0, 1))
    imu, _ = io.read_dataflash(path)
    assert imu.attrs["instance"] == 0 and imu.attrs["attitude"] is None
    imu2, _ = io.read_dataflash(path, imu_instance=1)
    np.testing.assert_allclose(imu2["w_x"], imu_in["w_x"] + 1e-3, atol=1e-6)
    with pytest.raises(NavlibInputError, match=r"no 'IMU' instance 2; instances are \[0, 1\]"):
        io.read_dataflash(path, imu_instance=2)


def test_generated_log_is_assessed(bin4, flight):
    imu, gnss = io.read_dataflash(bin4)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = assess_flight(imu, gnss)
    assert result.options["preset"] == "pixhawk_mems"
    assert result.options["attitude_source"] == "log"
    assert result.segment_table["phase"].iloc[0] == "rest"


def test_damaged_bytes_are_counted_not_printed(bin4, tmp_path, capfd):
    """pymavlink's compiled indexer printed a 'bad header' line per damaged byte to the
    process's stderr, past Python's redirection (found by tests/fuzz)."""
    data = bytearray(bin4.read_bytes())
    data[20_000:20_300] = bytes(300)
    path = tmp_path / "zeroed.bin"
    path.write_bytes(bytes(data))
    with pytest.warns(io.FlightDataWarning, match=r"pymavlink skipped bad bytes \(\d+ byte"):
        imu, _ = io.read_dataflash(path)
    assert len(imu) > 100
    out, err = capfd.readouterr()
    assert "bad header" not in out + err and not err.strip()


@pytest.mark.parametrize("content, match", [
    (b"", "file is empty"),
    (b"time,ax\n0,1\n" * 50, "no 'IMU' messages"),
])
def test_bad_files(tmp_path, content, match):
    path = tmp_path / "bad.bin"
    path.write_bytes(content)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with pytest.raises(NavlibInputError, match=match):
            io.read_dataflash(path)
    # a foreign file's bytes have no record headers: counted in a warning, never printed
    assert bool(content) == any("pymavlink skipped bad bytes (" in str(w.message)
                                for w in caught)


def test_missing_file_and_no_fix(tmp_path, flight):
    with pytest.raises(NavlibInputError, match=r"does not exist|not found|no such"):
        io.read_dataflash(tmp_path / "absent.bin")
    _, imu, _, geo, _ = flight
    path = tmp_path / "nofix.bin"
    write_flight(path, imu, geo, gps_status=1)
    with pytest.raises(NavlibInputError, match=r"no usable GPS data .* 0 with Status >= 3"):
        io.read_dataflash(path)


def test_glitch_in_dataflash_is_excluded(tmp_path, flight):
    _, imu, _, geo, _ = flight
    bad = imu.copy()
    bad.loc[300, "w_z"] = 49.0
    path = tmp_path / "glitch.bin"
    write_flight(path, bad, geo)
    with pytest.warns(io.FlightDataWarning, match="1 non-physical IMU sample.*message 300"):
        read, _ = io.read_dataflash(path)
    assert read.attrs["outliers"][0]["value"] == pytest.approx(49.0, rel=1e-3)
    assert len(read) == len(imu) - 1


# --------------------------------------------------------------------------- public logs


def test_public_sitl_copter_log_is_read_and_assessed():
    path = _public("sitl_copter_flight.bin")
    imu, gnss = io.read_dataflash(path)
    assert 1.0 / np.median(np.diff(imu["t"])) == pytest.approx(25.0, rel=0.01)
    assert imu.attrs["hardware"].startswith("ArduCopter V4.7")
    assert len(gnss) > 200 and {"vx", "vy", "vz"} <= set(gnss.columns)
    assert imu.attrs["attitude"] is not None and len(imu.attrs["attitude"]) > 500
    imu1, _ = io.read_dataflash(path, imu_instance=1)
    assert len(imu1) == len(imu)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = assess_flight(imu, gnss)
    assert result.options["preset"] == "pixhawk_mems"
    assert result.options["attitude_source"] == "log"
    assert len(result.segment_table) >= 2
    assert set(result.segment_table["phase"]) - {"rest"}


def test_public_pymavlink_fixture_3x_layout():
    path = _public("pymavlink_test.bin")
    imu, gnss = io.read_dataflash(path, require_overlap=False)
    imu2, _ = io.read_dataflash(path, imu_instance=1, require_overlap=False)
    assert imu.attrs["hardware"].startswith("ArduPlane V3.8")
    assert len(imu) == len(imu2) > 20 and len(gnss) >= 2
    assert not np.allclose(imu["w_x"], imu2["w_x"])
    r = np.linalg.norm(gnss[["x", "y", "z"]].to_numpy(), axis=1)
    assert np.all((r > 6.3e6) & (r < 6.4e6))


@pytest.mark.notebook
def test_notebook_runs_on_a_dataflash_log(bin4, tmp_path):
    done = subprocess.run(
        [sys.executable, "-m", "navlib", "report", "--quick", "--only", "07_assess_flight",
         "-p", "log_path", str(bin4), "-p", "read_options", '{"imu_instance": 1}',
         "-p", "fit_options", '{"max_bridge_s": 2}', "--output", str(tmp_path / "rep")],
        capture_output=True, text=True, timeout=900, cwd=ROOT)
    assert done.returncode == 0, done.stdout + done.stderr
    html = (tmp_path / "rep" / "07_assess_flight.html").read_text()
    assert "pixhawk_mems" in html and "autopilot" in html


# ------------------------------------------------------------ TimeMS generation, barometer


def test_timems_log_reads_like_timeus(flight, tmp_path, bin4):
    """A log of the TimeMS generation (IMU/IMU2, GPS with Week/T, CTUN BarAlt) gives the
    frames of the TimeUS generation, to the millisecond its clock resolves."""
    _, imu_in, _, geo, att = flight
    baro = pd.DataFrame({"t": geo["t"], "alt_m": geo["alt_m"] - geo["alt_m"].iloc[0]})
    path = tmp_path / "timems.bin"
    write_flight(path, imu_in, geo, att, layout="TimeMS", imu_instances=(0, 1), baro=baro,
                 message="APM:Copter V3.2.1 (test)")
    imu, gnss = io.read_dataflash(path)
    ref_imu, ref_gnss = io.read_dataflash(bin4)
    assert imu.attrs["time_field"] == "TimeMS" and ref_imu.attrs["time_field"] == "TimeUS"
    assert len(imu) == len(ref_imu) and len(gnss) == len(ref_gnss)
    np.testing.assert_allclose(imu["t"], ref_imu["t"], atol=1e-3)
    np.testing.assert_allclose(gnss["t"], ref_gnss["t"], atol=1e-3)
    for col in ("f_x", "w_x", "w_z"):
        np.testing.assert_allclose(imu[col], ref_imu[col], atol=1e-6)
    np.testing.assert_allclose(gnss[["x", "y", "z"]], ref_gnss[["x", "y", "z"]], atol=0.02)
    assert imu.attrs["hardware"] == "APM:Copter V3.2.1 (test)"
    assert imu.attrs["attitude"] is not None and len(imu.attrs["attitude"]) == len(att)
    np.testing.assert_allclose(imu.attrs["baro"]["alt_m"], baro["alt_m"], atol=1e-4)
    imu2, _ = io.read_dataflash(path, imu_instance=1)
    np.testing.assert_allclose(imu2["w_x"], imu_in["w_x"] + 1e-3, atol=1e-6)


def test_gps_time_of_week_is_not_taken_for_boot_time(flight, tmp_path):
    """Without T, a GPS TimeMS beside Week is GPS time: refused, naming the fields."""
    from support.dataflash_writer import LAYOUTS
    _, imu_in, _, geo, _ = flight
    saved = LAYOUTS["TimeMS"]["GPS"]
    LAYOUTS["TimeMS"]["GPS"] = ("BIHBLLe", "Status,TimeMS,Week,NSats,Lat,Lng,Alt")
    try:
        path = tmp_path / "no_t.bin"
        write_flight(path, imu_in, geo, layout="TimeMS")
    finally:
        LAYOUTS["TimeMS"]["GPS"] = saved
    with pytest.raises(NavlibInputError, match=r"message 'GPS' instance 0: no time field"):
        io.read_dataflash(path)


def test_baro_of_timeus_logs(flight, tmp_path, bin4):
    _, imu_in, _, geo, _ = flight
    assert io.read_dataflash(bin4)[0].attrs["baro"] is None
    baro = pd.DataFrame({"t": geo["t"], "alt_m": 3.0 + geo["alt_m"] - geo["alt_m"].iloc[0]})
    for layout in ("4.x", "3.x"):
        path = tmp_path / f"baro{layout}.bin"
        write_flight(path, imu_in, geo, layout=layout, baro=baro)
        got = io.read_dataflash(path)[0].attrs["baro"]
        np.testing.assert_allclose(got["t"], baro["t"] - imu_in["t"][0], atol=1e-6)
        np.testing.assert_allclose(got["alt_m"], baro["alt_m"], atol=1e-4)


def test_public_legacy_timems_log():
    path = _public("legacy_copter_log171.bin")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", io.FlightDataWarning)
        imu, gnss = io.read_dataflash(path)
    assert imu.attrs["time_field"] == "TimeMS"
    assert imu.attrs["hardware"].startswith("APM:Copter V3.3")
    assert 1.0 / np.median(np.diff(imu["t"])) == pytest.approx(49.0, rel=0.03)
    assert 1.0 / np.median(np.diff(gnss["t"])) == pytest.approx(5.0, rel=0.03)
    assert imu["t"].iloc[-1] - imu["t"].iloc[0] > 200.0
    assert gnss["t"].iloc[0] >= imu["t"].iloc[0] and gnss["t"].iloc[-1] > 200.0
    assert imu.attrs["attitude"] is not None and len(imu.attrs["baro"]) > 1000
    r = np.linalg.norm(gnss[["x", "y", "z"]].to_numpy(), axis=1)
    assert np.all((r > 6.3e6) & (r < 6.4e6))


def test_field_declared_as_text_is_refused(flight, tmp_path):
    """A damaged FMT that declares GPS Status as char[4] holding text: named, no TypeError."""
    from support.dataflash_writer import LAYOUTS
    _, imu_in, _, geo, _ = flight
    saved = LAYOUTS["4.x"]["GPS"]
    LAYOUTS["4.x"]["GPS"] = ("QBnLLeffff", saved[1])
    try:
        path = tmp_path / "text_status.bin"
        write_flight(path, imu_in, geo, gps_status="ok")
    finally:
        LAYOUTS["4.x"]["GPS"] = saved
    with pytest.raises(NavlibInputError, match=r"message 'GPS' instance 0: field\(s\) "
                                               r"\['Status'\] do not hold numbers"):
        io.read_dataflash(path)


def test_shifted_fmt_record_does_not_hang(bin4, tmp_path):
    """One byte inserted before the Length byte of the ATT FMT record (so it reads 0 and the
    rest of the record shifts) made pymavlink parse the same bytes forever (found by
    tests/io/test_reader_robustness.py); the reader refuses such a log at once."""
    data = bin4.read_bytes()
    fmt_att = data.index(b"\xa3\x95\x80" + bytes([0x83]))
    assert data[fmt_att + 5:fmt_att + 9] == b"ATT\x00"
    path = tmp_path / "shifted.bin"
    path.write_bytes(data[:fmt_att + 4] + b"\x00" + data[fmt_att + 4:])
    with pytest.raises(NavlibInputError, match="does not move the parser forward"):
        io.read_dataflash(path)
