"""Flight-data import: CSV readers/writers, validation messages, PX4 ULog logs."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import navlib
from navlib import earth
from navlib.io import (
    FlightDataWarning,
    check_overlap,
    combine_sigma,
    read_gnss_csv,
    read_imu_csv,
    read_ulog,
    split_at_gaps,
    write_gnss_csv,
    write_imu_csv,
)

IMU_HEADER = "t,f_x,f_y,f_z,w_x,w_y,w_z"
G = 9.80665  # standard gravity, written out here as an independent value
D2R = np.pi / 180.0


def _imu_values(n=200, rate=100.0, t0=10.0, seed=0):
    rng = np.random.default_rng(seed)
    t = t0 + np.arange(n) / rate
    f = np.array([0.02, -0.03, -9.81]) + 0.01 * rng.standard_normal((n, 3))
    w = np.array([1e-3, -2e-3, 5e-4]) + 1e-3 * rng.standard_normal((n, 3))
    return t, f, w


def _write(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text)
    return p


def _rows(*cols, fmt="{!r}"):
    return "\n".join(",".join(fmt.format(float(v)) for v in row) for row in zip(*cols, strict=True))


def _imu_csv(tmp_path, header=IMU_HEADER, scale=(1.0, 1.0, 1.0), name="imu.csv", n=200,
             rate=100.0, prefix=""):
    t, f, w = _imu_values(n, rate)
    body = _rows(t / scale[0], *(f / scale[1]).T, *(w / scale[2]).T)
    return _write(tmp_path, name, prefix + header + "\n" + body + "\n"), (t, f, w)


def _raises(match, func, *args, **kwargs):
    with pytest.raises(navlib.NavlibInputError, match=match) as info:
        func(*args, **kwargs)
    return str(info.value)


# ----------------------------------------------------------------------------- IMU CSV


def test_read_imu_canonical_columns_and_values(tmp_path):
    path, (t, f, w) = _imu_csv(tmp_path)
    imu = read_imu_csv(path)
    assert list(imu.columns) == ["t", "f_x", "f_y", "f_z", "w_x", "w_y", "w_z"]
    np.testing.assert_array_equal(imu["t"], t)
    np.testing.assert_array_equal(imu[["f_x", "f_y", "f_z"]], f)
    np.testing.assert_array_equal(imu[["w_x", "w_y", "w_z"]], w)
    assert imu.attrs["gaps"] == [] and imu.attrs["source"] == str(path)


@pytest.mark.parametrize(("header", "kw", "scale"), [
    ("time,acc_x,acc_y,acc_z,gyro_x,gyro_y,gyro_z", {}, (1, 1, 1)),
    ("Timestamp,AX,AY,AZ,GX,GY,GZ", {"time_unit": "ms", "accel_unit": "g",
                                      "gyro_unit": "deg/s"}, (1e-3, G, D2R)),
    ("time_us;xacc;yacc;zacc;xgyro;ygyro;zgyro", {"accel_unit": "mg"}, (1e-6, 1e-3 * G, 1)),
    ("timestamp,accelerometer_m_s2[0],accelerometer_m_s2[1],accelerometer_m_s2[2],"
     "gyro_rad[0],gyro_rad[1],gyro_rad[2]", {"time_unit": "us"}, (1e-6, 1, 1)),
    ("time (ms)\tf_x [g]\tf_y [g]\tf_z [g]\tw_x [deg/s]\tw_y [deg/s]\tw_z [deg/s]", {},
     (1e-3, G, D2R)),
    ("t_s  specific_force_x  specific_force_y  specific_force_z  omega_x  omega_y  omega_z",
     {}, (1, 1, 1)),
])
def test_imu_aliases_separators_and_units(tmp_path, header, kw, scale):
    sep = ";" if ";" in header else "\t" if "\t" in header else " " if "  " in header else ","
    t, f, w = _imu_values()
    cols = [t / scale[0], *(f / scale[1]).T, *(w / scale[2]).T]
    body = "\n".join(sep.join(repr(float(v)) for v in row) for row in zip(*cols, strict=True))
    path = _write(tmp_path, "imu.csv", header + "\n" + body + "\n")
    imu = read_imu_csv(path, **kw)
    np.testing.assert_allclose(imu["t"], t, rtol=1e-14)
    np.testing.assert_allclose(imu[["f_x", "f_y", "f_z"]], f, rtol=1e-14)
    np.testing.assert_allclose(imu[["w_x", "w_y", "w_z"]], w, rtol=1e-14)


def test_header_unit_contradicting_keyword_and_unknown_unit(tmp_path):
    path, _ = _imu_csv(tmp_path, header="t [s],f_x [g],f_y [g],f_z [g],w_x,w_y,w_z",
                       scale=(1, G, 1))
    msg = _raises("header says 'g'", read_imu_csv, path, accel_unit="m/s^2")
    assert "f_x [g]" in msg
    path, _ = _imu_csv(tmp_path, header="t,f_x [ft/s^2],f_y,f_z,w_x,w_y,w_z")
    _raises(r"unit 'ft/s\^2' not understood", read_imu_csv, path)
    _raises("time_unit: unit 'hours' not understood", read_imu_csv, path, time_unit="hours")


def test_comments_blank_lines_and_line_numbers(tmp_path):
    t, f, w = _imu_values(n=20)
    lines = ["# flight 42", "", IMU_HEADER, "# calibrated"]
    lines += [",".join(repr(float(v)) for v in row) for row in zip(t, *f.T, *w.T, strict=True)]
    lines.insert(10, "")  # a blank line inside the data
    lines[12] = lines[12].replace(lines[12].split(",")[3], "abc", 1)  # f_z on file line 13
    path = _write(tmp_path, "imu.csv", "\n".join(lines))
    msg = _raises("non-numeric value 'abc'", read_imu_csv, path)
    assert "column 'f_z'" in msg and "line 13" in msg and "imu.csv" in msg


def test_missing_empty_binary_and_headerless_files(tmp_path):
    _raises("file not found", read_imu_csv, tmp_path / "nope.csv")
    _raises("not a regular file", read_imu_csv, tmp_path)
    _raises("file is empty", read_imu_csv, _write(tmp_path, "e.csv", ""))
    _raises("only blank or # comment", read_imu_csv, _write(tmp_path, "c.csv", "# x\n\n"))
    _raises("no data rows after the header", read_imu_csv,
            _write(tmp_path, "h.csv", IMU_HEADER + "\n"))
    _raises("need at least 2 samples", read_imu_csv,
            _write(tmp_path, "one.csv", IMU_HEADER + "\n0,0,0,-9.8,0,0,0\n"))
    _raises("looks like data, not a header", read_imu_csv,
            _write(tmp_path, "n.csv", "0,0,0,-9.8,0,0,0\n0.01,0,0,-9.8,0,0,0\n"))
    binary = tmp_path / "log.ulg"
    binary.write_bytes(b"ULog\x01\x12\x35\x00\x00\x00")
    _raises("use read_ulog", read_imu_csv, binary)


def test_truncated_file_and_ragged_rows(tmp_path):
    path, _ = _imu_csv(tmp_path, n=50)
    text = path.read_text().rstrip("\n")
    cut = _write(tmp_path, "cut.csv", text[: text.rfind(",") - 3])  # cut mid last row
    with pytest.warns(FlightDataWarning, match=r"line 51: the last row was cut mid-write"):
        assert len(read_imu_csv(cut)) == 49
    empty_last = _write(tmp_path, "cut2.csv", text[: text.rfind(",") + 1])
    with pytest.warns(FlightDataWarning, match=r"line 51: the last row was cut"):
        assert len(read_imu_csv(empty_last)) == 49
    lines = text.split("\n")
    lines[5] += ",7.0"
    msg = _raises("row has 8 fields but the header has 7", read_imu_csv,
                  _write(tmp_path, "ragged.csv", "\n".join(lines)))
    assert "line 6" in msg


def test_missing_duplicate_and_ambiguous_columns(tmp_path):
    path, _ = _imu_csv(tmp_path, header="t,f_x,f_y,f_z,w_x,w_y,temp")
    msg = _raises("missing column", read_imu_csv, path)
    assert "'w_z'" in msg and "gyro_z" in msg
    path, _ = _imu_csv(tmp_path, header="t,ax,ax,az,gx,gy,gz")
    _raises(r"'ax'.*duplicate column: appears in fields 2 and 3", read_imu_csv, path)
    path, (_, f, _) = _imu_csv(tmp_path, header="time,timestamp,f_y,f_z,w_x,w_y,w_z")
    _raises("'time' and 'timestamp' both give 't'", read_imu_csv, path)
    _raises("missing column", read_imu_csv, path, columns={"t": "timestamp"})
    imu = read_imu_csv(path, columns={"t": "time", "f_x": "timestamp"})
    np.testing.assert_array_equal(imu["f_x"], f[:, 0])
    _raises(r"columns: unknown key\(s\) \['speed'\]", read_imu_csv, path, columns={"speed": "t"})
    _raises("no such column", read_imu_csv, path, columns={"t": "clock"})


@pytest.mark.parametrize(("cell", "what"), [
    ("", "empty cell"), ("nan", "'nan' is not a finite number"),
    ("inf", "'inf' is not a finite number"), ("1.2.3", "non-numeric value '1.2.3'"),
])
def test_bad_cells_name_column_and_line(tmp_path, cell, what):
    path, _ = _imu_csv(tmp_path, n=30)
    lines = path.read_text().split("\n")
    fields = lines[7].split(",")
    fields[5] = cell  # w_y, file line 8
    lines[7] = ",".join(fields)
    msg = _raises(re.escape(what), read_imu_csv, _write(tmp_path, "bad.csv", "\n".join(lines)))
    assert "column 'w_y'" in msg and "line 8" in msg


def test_duplicate_and_backward_timestamps(tmp_path):
    t, f, w = _imu_values(n=40)
    for k, value, what in ((12, t[11], "duplicate time stamp"), (20, t[18], "goes backwards")):
        tt = t.copy()
        tt[k] = value
        path = _write(tmp_path, "t.csv", IMU_HEADER + "\n" + _rows(tt, *f.T, *w.T))
        msg = _raises(what, read_imu_csv, path)
        assert f"line {k + 2}" in msg and "column 't'" in msg


def test_time_unit_mixups_are_named(tmp_path):
    path, _ = _imu_csv(tmp_path, scale=(1e-6, 1, 1))  # microseconds, declared as s
    _raises(r"implausible for IMU.*time_unit='us'", read_imu_csv, path)
    path, _ = _imu_csv(tmp_path, scale=(1e-3, 1, 1))
    _raises("time_unit='ms'", read_imu_csv, path)
    assert len(read_imu_csv(path, time_unit="ms")) == 200


def _gappy_imu(tmp_path):
    t, f, w = _imu_values(n=300)
    keep = np.r_[0:100, 150:200, 260:300]  # gaps of 0.51 s and 0.61 s at 100 Hz
    path = _write(tmp_path, "gap.csv", IMU_HEADER + "\n" + _rows(
        t[keep], *f[keep].T, *w[keep].T))
    return path, t[keep]


def test_gaps_warn_raise_split(tmp_path):
    path, t = _gappy_imu(tmp_path)
    with pytest.warns(FlightDataWarning, match="2 gap"):
        imu = read_imu_csv(path)
    gaps = imu.attrs["gaps"]
    assert [g["row"] for g in gaps] == [100, 150] and "segment" not in imu
    assert gaps[0]["where"] == "line 102"
    np.testing.assert_allclose([g["duration_s"] for g in gaps], [0.51, 0.61], rtol=1e-9)
    msg = _raises("2 gap", read_imu_csv, path, on_gap="raise")
    assert "line 102" in msg
    imu = read_imu_csv(path, on_gap="split")
    assert np.array_equal(np.bincount(imu["segment"]), [100, 50, 40])
    pieces = split_at_gaps(imu)
    assert [len(p) for p in pieces] == [100, 50, 40]
    assert list(pieces[1].columns) == list(imu.columns[:-1])
    np.testing.assert_array_equal(pieces[2]["t"], t[150:])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert read_imu_csv(path, max_gap_s=0.7).attrs["gaps"] == []
    with pytest.warns(FlightDataWarning, match="1 gap"):
        read_imu_csv(path, max_gap_s=0.55)
    assert len(split_at_gaps(read_imu_csv(path, max_gap_s=1.0))) == 1
    _raises("on_gap: expected one of", read_imu_csv, path, on_gap="ignore")
    _raises("max_gap_s", read_imu_csv, path, max_gap_s=-1.0)
    _raises("expected a pandas DataFrame", split_at_gaps, np.zeros(3))


def test_implausible_imu_magnitudes(tmp_path):
    path, _ = _imu_csv(tmp_path, scale=(1, G, 1))  # accelerations in g, declared m/s^2
    _raises("look like g, not m/s", read_imu_csv, path)
    assert np.isclose(read_imu_csv(path, accel_unit="g")["f_z"].median(), -9.81, atol=0.01)
    path, _ = _imu_csv(tmp_path)  # m/s^2 declared as g
    _raises("look like m/s", read_imu_csv, path, accel_unit="g")
    path, _ = _imu_csv(tmp_path, scale=(1, 1e-3 * G, 1))  # mg declared as m/s^2
    _raises("implausible; mg", read_imu_csv, path)
    t, f, w = _imu_values()
    w[:, 2] = 100.0 * D2R  # spinning at 100 deg/s, written in deg/s, declared rad/s
    path = _write(tmp_path, "spin.csv", IMU_HEADER + "\n" + _rows(t, *f.T, *(w / D2R).T))
    msg = _raises("look like deg/s", read_imu_csv, path)
    assert "column 'w_x'/'w_y'/'w_z'" in msg
    np.testing.assert_allclose(read_imu_csv(path, gyro_unit="deg/s")["w_z"], 100 * D2R)
    assert len(read_imu_csv(path, check_magnitudes=False)) == 200
    assert len(read_imu_csv(path, max_rate_rad_s=200.0)) == 200


# ----------------------------------------------------------------------------- GNSS CSV


def _gnss_values(n=30, rate=5.0):
    t = 10.0 + np.arange(n) / rate
    lat = np.deg2rad(45.0 + 1e-5 * np.arange(n))
    lon = np.deg2rad(-73.5 + 2e-5 * np.arange(n))
    alt = 100.0 + 2.0 * np.arange(n)
    return t, lat, lon, alt


def test_gnss_ecef_with_velocity_and_sigma(tmp_path):
    t, lat, lon, alt = _gnss_values()
    r = earth.geodetic_to_ecef(lat, lon, alt)
    v = np.tile([1.0, -2.0, 3.0], (t.size, 1))
    s = np.full(t.size, 2.5)
    path = _write(tmp_path, "g.csv", "time,x,y,z,vx,vy,vz,sigma\n" + _rows(t, *r.T, *v.T, s))
    gnss = read_gnss_csv(path)
    assert list(gnss.columns) == ["t", "x", "y", "z", "vx", "vy", "vz", "sigma"]
    np.testing.assert_array_equal(gnss[["x", "y", "z"]], r)
    assert gnss.attrs["position_input"] == "ecef" and gnss.attrs["velocity_input"] == "ecef"
    km = _write(tmp_path, "km.csv", "t,x,y,z\n" + _rows(t, *(r / 1e3).T))
    _raises("look(s)? like km: set length_unit='km'", read_gnss_csv, km)
    np.testing.assert_allclose(read_gnss_csv(km, length_unit="km")[["x", "y", "z"]], r)


def test_gnss_geodetic_closed_forms(tmp_path):
    # Independent points: the equator/prime meridian and the pole of the WGS-84 ellipsoid.
    a, f = 6378137.0, 1 / 298.257223563
    t = np.array([0.0, 1.0, 2.0])
    path = _write(tmp_path, "g.csv", "t,lat_deg,lon_deg,alt\n" + _rows(
        t, [0.0, 90.0, 0.0], [0.0, 0.0, 90.0], [0.0, 0.0, 1000.0]))
    gnss = read_gnss_csv(path, check_magnitudes=True)
    np.testing.assert_allclose(gnss[["x", "y", "z"]].to_numpy(),
                               [[a, 0, 0], [0, 0, a * (1 - f)], [0, a + 1000.0, 0]], atol=1e-6)
    # Radians by keyword; the same fixes as degrees.
    t, lat, lon, alt = _gnss_values()
    deg = read_gnss_csv(_write(tmp_path, "d.csv", "t,latitude_deg,longitude_deg,height\n"
                               + _rows(t, np.rad2deg(lat), np.rad2deg(lon), alt)))
    rad = read_gnss_csv(_write(tmp_path, "r.csv", "t,lat,lon,alt\n" + _rows(t, lat, lon, alt)),
                        angle_unit="rad")
    np.testing.assert_allclose(rad[["x", "y", "z"]], deg[["x", "y", "z"]], atol=1e-6)
    back = np.column_stack(earth.ecef_to_geodetic(rad[["x", "y", "z"]].to_numpy()))
    np.testing.assert_allclose(back, np.column_stack([lat, lon, alt]), atol=1e-8)
    lat_rad_deg = _write(tmp_path, "x.csv", "t,lat,lon,alt\n" + _rows(
        t, np.rad2deg(lat), np.rad2deg(lon), alt))
    _raises("look like degrees: set angle_unit='deg'", read_gnss_csv, lat_rad_deg,
            angle_unit="rad")


def test_gnss_ned_velocity_rotation(tmp_path):
    # At lat 0, lon 0: North = +z, East = +y, Down = -x (ECEF), a closed form.
    t = np.array([0.0, 1.0, 2.0])
    path = _write(tmp_path, "v.csv", "t,lat_deg,lon_deg,alt,vel_n_m_s,vel_e_m_s,vel_d_m_s\n"
                  + _rows(t, [0, 0, 0], [0, 0, 0], [0, 0, 0], [1, 0, 0], [0, 2, 0],
                          [0, 0, 3]))
    gnss = read_gnss_csv(path)
    np.testing.assert_allclose(gnss[["vx", "vy", "vz"]].to_numpy(),
                               [[0, 0, 1], [0, 2, 0], [-3, 0, 0]], atol=1e-12)
    assert gnss.attrs["velocity_input"] == "ned"


def test_gnss_ambiguities_and_missing_columns(tmp_path):
    t, lat, lon, alt = _gnss_values()
    r = earth.geodetic_to_ecef(lat, lon, alt)
    both = _write(tmp_path, "b.csv", "t,x,y,z,lat_deg,lon_deg,alt\n" + _rows(
        t, *r.T, np.rad2deg(lat), np.rad2deg(lon), alt))
    _raises("both ecef and geodetic columns", read_gnss_csv, both)
    np.testing.assert_allclose(read_gnss_csv(both, position="geodetic")[["x", "y", "z"]], r,
                               atol=1e-6)
    _raises("position: expected one of", read_gnss_csv, both, position="enu")
    v = np.zeros((t.size, 3))
    bv = _write(tmp_path, "bv.csv", "t,x,y,z,vx,vy,vz,vn,ve,vd\n" + _rows(t, *r.T, *v.T, *v.T))
    _raises("both ecef and ned columns", read_gnss_csv, bv)
    assert "vx" not in read_gnss_csv(bv, velocity="none")
    dup = _write(tmp_path, "dup.csv", "t,lat,lat_deg,lon_deg,alt\n" + _rows(
        t, lat, lat, np.rad2deg(lon), alt))
    _raises("both give the latitude", read_gnss_csv, dup)
    _raises("missing column", read_gnss_csv,
            _write(tmp_path, "m.csv", "t,lat_deg,lon_deg\n" + _rows(t, lat, lon)))
    _raises("missing column", read_gnss_csv,
            _write(tmp_path, "m2.csv", "t,x,y\n" + _rows(t, r[:, 0], r[:, 1])))
    _raises("no position columns", read_gnss_csv,
            _write(tmp_path, "np.csv", "t,speed\n" + _rows(t, alt)))
    _raises("'sigma_v'.*missing column", read_gnss_csv,
            _write(tmp_path, "s.csv", "t,x,y,z,eph\n" + _rows(t, *r.T, alt)))


def test_gnss_sigma_and_implausible_values(tmp_path):
    t, lat, lon, alt = _gnss_values()
    r = earth.geodetic_to_ecef(lat, lon, alt)
    eph, epv = np.full(t.size, 3.0), np.full(t.size, 6.0)
    gnss = read_gnss_csv(_write(tmp_path, "s.csv", "t,x,y,z,eph,epv\n" + _rows(
        t, *r.T, eph, epv)))
    np.testing.assert_allclose(gnss["sigma"], np.sqrt((2 * 9 + 36) / 3))
    np.testing.assert_allclose(combine_sigma(1.0, 1.0), 1.0)
    bad = eph.copy()
    bad[4] = 0.0
    _raises(r"'sigma'.*line 6: standard deviation must be > 0", read_gnss_csv,
            _write(tmp_path, "s0.csv", "t,x,y,z,sigma\n" + _rows(t, *r.T, bad)))
    high = alt.copy()
    high[3] = 2.0e6  # 2000 km: beyond any sounding rocket
    msg = _raises("from the Earth's centre", read_gnss_csv, _write(
        tmp_path, "h.csv", "t,lat_deg,lon_deg,alt\n" + _rows(
            t, np.rad2deg(lat), np.rad2deg(lon), high)))
    assert "line 5" in msg
    rocket = alt.copy()
    rocket[3] = 9.0e5  # 900 km apogee is accepted
    assert len(read_gnss_csv(_write(tmp_path, "rk.csv", "t,lat_deg,lon_deg,alt\n" + _rows(
        t, np.rad2deg(lat), np.rad2deg(lon), rocket)))) == t.size
    south = np.rad2deg(lat)
    south[2] = 95.0
    _raises(r"line 4: angle 95 is out of range", read_gnss_csv, _write(
        tmp_path, "la.csv", "t,lat_deg,lon_deg,alt\n" + _rows(t, south, np.rad2deg(lon), alt)))
    v = np.zeros((t.size, 3))
    v[7] = [2e4, 0, 0]
    _raises(r"line 9: speed 20000 m/s", read_gnss_csv, _write(
        tmp_path, "v.csv", "t,x,y,z,vx,vy,vz\n" + _rows(t, *r.T, *v.T)))
    ms = _write(tmp_path, "ms.csv", "t,x,y,z\n" + _rows(t * 1e3, *r.T))
    _raises("implausible for GNSS.*time_unit='ms'", read_gnss_csv, ms)


# ----------------------------------------------------------------------------- overlap


def test_check_overlap():
    imu = pd.DataFrame({"t": np.linspace(0.0, 10.0, 101)})
    gnss = pd.DataFrame({"t": np.arange(5.0, 20.0, 1.0)})
    ov = check_overlap(imu, gnss)
    assert (ov.t_start, ov.t_end, ov.duration, ov.n_gnss) == (5.0, 10.0, 5.0, 6)
    _raises("do not overlap.*GNSS spans 11..25", check_overlap, imu,
            pd.DataFrame({"t": np.arange(11.0, 26.0)}))
    _raises("less than min_overlap_s=6", check_overlap, imu, gnss, min_overlap_s=6.0)
    _raises("gnss: missing column 't'", check_overlap, imu, pd.DataFrame({"time": [1.0]}))
    _raises("imu: expected a pandas DataFrame", check_overlap, [0, 1], gnss)


def test_check_overlap_catches_different_time_bases(tmp_path):
    path, _ = _imu_csv(tmp_path)  # IMU at t = 10..12 s since power-up
    t, lat, lon, alt = _gnss_values()
    g = _write(tmp_path, "g.csv", "t,lat_deg,lon_deg,alt\n" + _rows(
        t + 345600.0, np.rad2deg(lat), np.rad2deg(lon), alt))  # GPS seconds of week
    _raises("do not overlap", check_overlap, read_imu_csv(path), read_gnss_csv(g))
    # A GNSS time unit mix-up is caught earlier, by the epoch interval.
    ms = _write(tmp_path, "ms.csv", "t,lat_deg,lon_deg,alt\n" + _rows(
        t * 1e3, np.rad2deg(lat), np.rad2deg(lon), alt))
    _raises("implausible for GNSS.*time_unit='ms'", read_gnss_csv, ms, time_unit="us")


# ----------------------------------------------------------------------------- writers


def test_imu_round_trip(tmp_path):
    path, _ = _imu_csv(tmp_path)
    imu = read_imu_csv(path)
    out = write_imu_csv(imu, tmp_path / "out.csv", time_unit="ms", accel_unit="g",
                        gyro_unit="deg/s")
    assert out.read_text().splitlines()[0].startswith("t [ms],f_x [g]")
    back = read_imu_csv(out)  # units come from the header brackets
    pd.testing.assert_frame_equal(back, imu, check_exact=False, rtol=1e-14)
    lossless = read_imu_csv(write_imu_csv(imu, tmp_path / "si.csv"))
    pd.testing.assert_frame_equal(lossless, imu, check_exact=True)
    _raises("imu: missing column", write_imu_csv, imu.drop(columns="w_z"), tmp_path / "x.csv")
    nan = imu.copy()
    nan.loc[3, "f_x"] = np.nan
    _raises(r"imu\['f_x'\]: contains NaN", write_imu_csv, nan, tmp_path / "x.csv")
    _raises("does not exist", write_imu_csv, imu, tmp_path / "no" / "x.csv")


@settings(max_examples=15, deadline=None)
@given(time_unit=st.sampled_from(["s", "ms", "us", "ns"]),
       accel_unit=st.sampled_from(["m/s^2", "g", "mg"]),
       gyro_unit=st.sampled_from(["rad/s", "deg/s"]),
       rate=st.floats(20.0, 2000.0), t0=st.floats(0.0, 1e5))
def test_imu_round_trip_any_units(tmp_path_factory, time_unit, accel_unit, gyro_unit, rate, t0):
    t, f, w = _imu_values(n=50, rate=rate, t0=t0)
    imu = pd.DataFrame({"t": t, **dict(zip(["f_x", "f_y", "f_z"], f.T, strict=True)),
                        **dict(zip(["w_x", "w_y", "w_z"], w.T, strict=True))})
    path = write_imu_csv(imu, tmp_path_factory.mktemp("rt") / "imu.csv", time_unit=time_unit,
                         accel_unit=accel_unit, gyro_unit=gyro_unit)
    back = read_imu_csv(path, time_unit=time_unit)  # agreeing keyword and header: accepted
    pd.testing.assert_frame_equal(back, imu, check_exact=False, rtol=1e-13, atol=0)


def test_windows_line_endings_and_byte_order_mark(tmp_path):
    path, (t, f, _) = _imu_csv(tmp_path)
    crlf = tmp_path / "win.csv"
    crlf.write_bytes(b"\xef\xbb\xbf" + path.read_text().replace("\n", "\r\n").encode())
    imu = read_imu_csv(crlf)
    np.testing.assert_array_equal(imu["t"], t)
    np.testing.assert_array_equal(imu["f_z"], f[:, 2])


@pytest.mark.parametrize(("position", "velocity"), [("ecef", "ecef"), ("geodetic", "ned")])
def test_gnss_round_trip(tmp_path, position, velocity):
    t, lat, lon, alt = _gnss_values()
    r = earth.geodetic_to_ecef(lat, lon, alt)
    v = np.column_stack([np.sin(t), np.cos(t), 0.1 * t])
    gnss = pd.DataFrame({"t": t, "x": r[:, 0], "y": r[:, 1], "z": r[:, 2], "vx": v[:, 0],
                         "vy": v[:, 1], "vz": v[:, 2], "sigma": np.linspace(1, 3, t.size)})
    out = write_gnss_csv(gnss, tmp_path / "g.csv", position=position, velocity=velocity)
    back = read_gnss_csv(out)
    assert back.attrs["position_input"] == position
    assert back.attrs["velocity_input"] == velocity
    pd.testing.assert_frame_equal(back, gnss, check_exact=False, rtol=0, atol=1e-6)
    minimal = write_gnss_csv(gnss[["t", "x", "y", "z"]], tmp_path / "m.csv")
    assert list(read_gnss_csv(minimal).columns) == ["t", "x", "y", "z"]
    _raises("position: expected", write_gnss_csv, gnss, tmp_path / "x.csv", position="enu")


# ----------------------------------------------------------------------------- PX4 ULog


PX4_LOGS = ("sample_log_small.ulg", "sample_px4_events.ulg")


@pytest.fixture(scope="module", params=PX4_LOGS)
def px4_log(request, px4_log_path):
    path = px4_log_path(request.param)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        imu, gnss = read_ulog(path)
    return path, imu, gnss, caught


def test_px4_logs_give_sane_data(px4_log):
    _, imu, gnss, caught = px4_log
    assert all(issubclass(w.category, FlightDataWarning) for w in caught)  # nothing foreign
    assert list(imu.columns) == ["t", "f_x", "f_y", "f_z", "w_x", "w_y", "w_z"]
    assert list(gnss.columns) == ["t", "x", "y", "z", "vx", "vy", "vz", "sigma"]
    assert min(imu["t"].iloc[0], gnss["t"].iloc[0]) == 0.0
    assert imu.attrs["t0_us"] == gnss.attrs["t0_us"] > 0
    # Gravity on the IMU at rest (first second; both logs start on the ground).
    first = imu[imu["t"] < imu["t"].iloc[0] + 1.0]
    f_b = first[["f_x", "f_y", "f_z"]].to_numpy()
    r_e = gnss[["x", "y", "z"]].to_numpy()
    lat, _, h = earth.ecef_to_geodetic(r_e)
    g_local = earth.gravity_magnitude(lat[0], h[0])
    assert abs(np.median(np.linalg.norm(f_b, axis=1)) - g_local) < 0.3
    assert np.median(f_b[:, 2]) < -9.0  # FRD: level at rest reads -g along z (down)
    assert np.abs(first[["w_x", "w_y", "w_z"]].to_numpy()).max() < 0.1
    # Positions near the Earth's surface, at a plausible height, moving slowly.
    assert np.all((h > -100.0) & (h < 2000.0))
    assert np.ptp(r_e, axis=0).max() < 1000.0
    assert np.linalg.norm(gnss[["vx", "vy", "vz"]].to_numpy(), axis=1).max() < 30.0
    assert np.all(gnss["sigma"] > 0)
    ov = check_overlap(imu, gnss)
    assert ov.duration > 5.0 and ov.n_gnss >= 25


def test_px4_field_generations_map_to_the_same_quantities(px4_log):
    pyulog = pytest.importorskip("pyulog")
    path, _, gnss, _ = px4_log
    topic = gnss.attrs["topic"]
    raw = pyulog.ULog(str(path), message_name_filter_list=[topic]).get_dataset(topic).data
    keep = raw["fix_type"] >= 3
    if "lat" in raw:  # generation 1: int 1e-7 deg, mm
        lat_deg, h = raw["lat"][keep] * 1e-7, raw["alt_ellipsoid"][keep] / 1000.0
    else:  # generation 2: float degrees, metres
        lat_deg, h = raw["latitude_deg"][keep], raw["altitude_ellipsoid_m"][keep]
    lat, _, alt = earth.ecef_to_geodetic(gnss[["x", "y", "z"]].to_numpy())
    np.testing.assert_allclose(np.rad2deg(lat), lat_deg, atol=1e-7)
    np.testing.assert_allclose(alt, h, atol=1e-3)
    v_ned = np.column_stack([raw[k][keep] for k in ("vel_n_m_s", "vel_e_m_s", "vel_d_m_s")])
    np.testing.assert_allclose(np.linalg.norm(gnss[["vx", "vy", "vz"]], axis=1),
                               np.linalg.norm(v_ned, axis=1), atol=1e-5)


def test_px4_real_log_dropout_is_reported_split_or_refused(px4_log_path):
    path = px4_log_path("sample_log_small.ulg")
    with pytest.warns(FlightDataWarning, match="sensor_combined.*1 gap"):
        imu, _ = read_ulog(path)
    assert imu.attrs["gaps"][0]["duration_s"] == pytest.approx(0.161303)
    imu, _ = read_ulog(path, on_gap="split")
    assert [len(p) for p in split_at_gaps(imu)] == [1, len(imu) - 1]
    _raises("sensor_combined', column 'timestamp', message 1: 1 gap", read_ulog, path,
            on_gap="raise")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_ulog(path, imu_max_gap_s=0.2)


def test_px4_gps_topic_choice_fix_filter_and_altitude(px4_log_path):
    sim = px4_log_path("sample_px4_events.ulg")
    _, gnss = read_ulog(sim)
    assert gnss.attrs["topic"] == "vehicle_gps_position"  # 19 Hz beats sensor_gps at 1 Hz
    assert gnss.attrs["dropped_no_fix"] == 160
    _, slow = read_ulog(sim, gps_topic="sensor_gps")
    assert slow.attrs["topic"] == "sensor_gps" and len(slow) == 22
    assert np.median(np.diff(slow["t"])) == pytest.approx(0.988, abs=0.06)
    _, all_fixes = read_ulog(sim, min_fix_type=0)
    assert len(all_fixes) == len(gnss) + 160
    small = px4_log_path("sample_log_small.ulg")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FlightDataWarning)
        _, ell = read_ulog(small)
        _, msl = read_ulog(small, altitude="msl")
        _raises(r"no usable GPS data \(no GPS topic\)", read_ulog, small, gps_topic="sensor_gps")
    assert msl.attrs["altitude_reference"] == "msl"
    r_ell = np.linalg.norm(ell[["x", "y", "z"]].to_numpy(), axis=1)
    r_msl = np.linalg.norm(msl[["x", "y", "z"]].to_numpy(), axis=1)
    np.testing.assert_allclose(r_ell - r_msl, 39.95, atol=0.1)  # geoid height near Trondheim


def test_px4_body_frame_mapping(px4_log_path):
    sim = px4_log_path("sample_px4_events.ulg")
    frd, _ = read_ulog(sim)
    flu, _ = read_ulog(sim, body_frame="flu")
    cols = ["f_x", "f_y", "f_z", "w_x", "w_y", "w_z"]
    np.testing.assert_array_equal(flu[cols].to_numpy(), frd[cols].to_numpy() * ([1, -1, -1] * 2))
    C = np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # yaw by -90 deg
    rot, _ = read_ulog(sim, body_frame=C)
    np.testing.assert_allclose(rot[["f_x", "f_y"]].to_numpy(),
                               frd[["f_y", "f_x"]].to_numpy() * [1, -1])
    _raises("reflection", read_ulog, sim, body_frame=np.diag([1.0, 1.0, -1.0]))
    _raises("not orthonormal", read_ulog, sim, body_frame=2 * np.eye(3))
    _raises("body_frame: expected one of", read_ulog, sim, body_frame="enu")


def test_px4_bad_files_and_options(tmp_path, px4_log_path):
    sim = px4_log_path("sample_px4_events.ulg")
    _raises("file not found", read_ulog, tmp_path / "none.ulg")
    _raises("file is empty", read_ulog, _write(tmp_path, "e.ulg", ""))
    _raises("not a readable PX4 ULog", read_ulog, _write(tmp_path, "a.ulg", "t,ax\n1,2\n"))
    head = tmp_path / "head.ulg"
    head.write_bytes(sim.read_bytes()[:2000])  # truncated inside the definitions
    with pytest.warns(FlightDataWarning, match="corruption"):
        _raises("no 'sensor_combined' topic", read_ulog, head)
    half = tmp_path / "half.ulg"
    half.write_bytes(sim.read_bytes()[: sim.stat().st_size // 2])  # truncated data section
    imu, gnss = read_ulog(half)
    assert 10.0 < imu["t"].iloc[-1] < 20.0 and check_overlap(imu, gnss).duration > 1.0
    _raises("gps_topic: expected one of", read_ulog, sim, gps_topic="gps")
    _raises("altitude: expected", read_ulog, sim, altitude="geoid")
    _raises("on_gap: expected", read_ulog, sim, on_gap="drop")
    _raises("imu_max_gap_s", read_ulog, sim, imu_max_gap_s=0.0)
    _raises(r"no usable GPS data.*0 with fix_type >= 9", read_ulog, sim, min_fix_type=9)


@pytest.fixture
def edited_sim_log(tmp_path, px4_log_path):
    """Make a copy of the simulation log, reduced to ``topics`` and changed by ``edit(data)``."""
    pyulog = pytest.importorskip("pyulog")
    source = px4_log_path("sample_px4_events.ulg")

    def make(edit, topics=("sensor_combined", "vehicle_gps_position", "sensor_gps")):
        ulog = pyulog.ULog(str(source), message_name_filter_list=list(topics))
        edit({(d.name, d.multi_id): d.data for d in ulog.data_list})
        path = tmp_path / "edited.ulg"
        ulog.write_ulog(str(path))
        return path

    return make


def test_px4_log_validation_names_topic_field_and_message(edited_sim_log):
    imu_key, gps_key = ("sensor_combined", 0), ("vehicle_gps_position", 0)

    def dup(data):
        data[imu_key]["timestamp"][50] = data[imu_key]["timestamp"][49]

    msg = _raises("duplicate time stamp", read_ulog, edited_sim_log(dup))
    assert "topic 'sensor_combined', column 'timestamp', message 50" in msg

    def nan(data):
        data[imu_key]["gyro_rad[1]"][7] = np.nan

    _raises(r"column 'gyro_rad\[1\]', message 7: value nan is not a finite",
            read_ulog, edited_sim_log(nan))

    def glitch(data):  # one non-physical sample: excluded, reported, not fatal
        for i in range(3):
            data[imu_key][f"gyro_rad[{i}]"][300] = 60.0

    with pytest.warns(FlightDataWarning, match=r"1 non-physical IMU sample.*message 300.*"
                                               r"'gyro_rad' norm 103.9"):
        imu, _ = read_ulog(edited_sim_log(glitch))
    (flag,) = imu.attrs["outliers"]
    assert flag["where"] == "message 300" and flag["value"] == pytest.approx(103.92, abs=0.01)
    assert not np.isclose(imu["t"], flag["t"]).any()

    def spinning(data):  # many: refused, with a hint naming keywords read_ulog has
        for i in range(3):
            data[imu_key][f"gyro_rad[{i}]"][200:400] = 60.0

    msg = _raises(r"'gyro_rad', message 200: angular rate 103.9 rad/s .* 200 of \d+ samples",
                  read_ulog, edited_sim_log(spinning))
    assert "max_rate_rad_s" in msg and "gyro_unit" not in msg

    def clip(data):
        data[imu_key]["accelerometer_clipping"][[100, 200]] = 1

    with pytest.warns(FlightDataWarning, match="'accelerometer_clipping' flags 2 sample.*"
                                               "message 100"):
        imu, _ = read_ulog(edited_sim_log(clip))
    assert imu.attrs["clipping"]["accelerometer_clipping"] == 2

    def gps_dup(data):  # (pyulog writes messages in time order: no backward steps here)
        data[gps_key]["timestamp"][300] = data[gps_key]["timestamp"][299]

    _raises("vehicle_gps_position', column 'timestamp', message 300: duplicate time stamp",
            read_ulog, edited_sim_log(gps_dup))

    def late(data):
        for key in (gps_key, ("sensor_gps", 0)):
            data[key]["timestamp"] += 100_000_000  # GNSS 100 s after the IMU record

    path = edited_sim_log(late)
    _raises("do not overlap", read_ulog, path)
    assert len(read_ulog(path, require_overlap=False)[1]) == 423

    path = edited_sim_log(lambda data: None, topics=("sensor_combined",))
    _raises(r"no usable GPS data \(no GPS topic\)", read_ulog, path)
    path = edited_sim_log(lambda data: None, topics=("sensor_gps",))
    _raises("no 'sensor_combined' topic", read_ulog, path)


def test_non_physical_imu_samples_are_excluded_by_rule(tmp_path):
    t, f, w = _imu_values(n=300)
    f[120] = [0.0, 0.0, -2000.0]                   # one 204 g sample: beyond max_accel_m_s2
    w[200] = [0.0, 0.0, 40.0]                      # one 40 rad/s sample: beyond max_rate_rad_s
    path = _write(tmp_path, "glitch.csv", IMU_HEADER + "\n" + _rows(t, *f.T, *w.T))
    with pytest.warns(FlightDataWarning, match="2 non-physical IMU sample"):
        imu = read_imu_csv(path)
    flags = imu.attrs["outliers"]
    assert [o["row"] for o in flags] == [120, 200]
    assert flags[0]["t"] == pytest.approx(t[120]) and flags[0]["value"] == pytest.approx(2000.0)
    assert "max_accel_m_s2" in flags[0]["rule"] and "max_rate_rad_s" in flags[1]["rule"]
    assert len(imu) == 298 and flags[1]["where"] == "line 202"
    # the limits and the share are keywords; a lower share refuses the record
    assert len(read_imu_csv(path, max_rate_rad_s=50.0, max_accel_m_s2=3000.0)) == 300
    _raises(r"2 of 300 samples .* max_outlier_fraction=0.001", read_imu_csv, path,
            max_outlier_fraction=0.001)
    _raises("max_outlier_fraction", read_imu_csv, path, max_outlier_fraction=2.0)
    assert len(read_imu_csv(path, check_magnitudes=False)) == 300


def test_px4_barometer_is_attached(px4_log):
    """vehicle_air_data.baro_alt_meter on the IMU's time base, near the GNSS heights."""
    _, imu, gnss, _ = px4_log
    baro = imu.attrs["baro"]
    assert list(baro.columns) == ["t", "alt_m"] and len(baro) > 5
    assert np.all(np.diff(baro["t"]) > 0)
    assert baro["t"].iloc[0] < imu["t"].iloc[-1] and baro["t"].iloc[-1] > imu["t"].iloc[0]
    _, _, h = earth.ecef_to_geodetic(gnss[["x", "y", "z"]].to_numpy())
    # MSL (standard atmosphere) against GNSS height: the geoid and the weather, not km
    assert abs(np.median(baro["alt_m"]) - np.median(h)) < 200.0
