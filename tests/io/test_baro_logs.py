"""Barometer CSV files, FIRM and CATS exports and the LOG dispatch of flights without GNSS
(navlib.io.baro, navlib.io.firm, navlib.io.cats, navlib.io.logs)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from support.locations import REPO

from navlib import NavlibInputError, io
from navlib.io.baro import pressure_altitude, read_baro_csv

ROCKETS = next((p for p in (REPO.parent / "shared", REPO.parents[1] / "shared")
                if p.is_dir()), REPO.parent / "shared") / "data" / "rockets"
FIRM_LOG = ROCKETS / "firm_jackpot3" / "jackpot_launch_3.csv"
CATS_LOG = ROCKETS / "hedy_cats_vega" / "imu.csv"

RATE = 100.0


def _imu_rows(n=400):
    t = np.arange(n) / RATE
    return t, np.tile([0.0, 0.0, -9.81], (n, 1)), np.zeros((n, 3))


def _write_imu(path, n=400):
    t, f, w = _imu_rows(n)
    lines = ["t,f_x,f_y,f_z,w_x,w_y,w_z"]
    lines += [f"{a:.3f},{b[0]},{b[1]},{b[2]},{c[0]},{c[1]},{c[2]}"
              for a, b, c in zip(t, f, w, strict=True)]
    path.write_text("\n".join(lines) + "\n")
    return path


def _write_baro(path, header="t,pressure_pa,temperature_c", n=400, scale=1.0, temp="20"):
    t = np.arange(n) / RATE
    p = 95_000.0 - 10.0 * t
    path.write_text(header + "\n" + "".join(f"{a:.3f},{b * scale:.3f},{temp}\n"
                                            for a, b in zip(t, p, strict=True)))
    return path


def test_pressure_altitude_is_the_standard_atmosphere():
    # ISA: 101325 Pa at 0 m, 89875 Pa at 1000 m, 79495 Pa at 2000 m (ISO 2533 table)
    assert pressure_altitude([101_325.0, 89_874.6, 79_495.2]) == pytest.approx(
        [0.0, 1000.0, 2000.0], abs=0.5)


def test_baro_csv_pressure_altitude_and_units(tmp_path):
    baro = read_baro_csv(_write_baro(tmp_path / "baro.csv"))
    assert list(baro.columns) == ["t", "alt_m", "pressure_pa", "temperature_c"]
    assert baro.alt_m.iloc[0] == pytest.approx(pressure_altitude(95_000.0))
    assert baro.attrs["altitude_input"] == "pressure"
    hpa = read_baro_csv(_write_baro(tmp_path / "hpa.csv", "time,pressure [hPa],temp",
                                    scale=0.01))
    np.testing.assert_allclose(hpa.alt_m, baro.alt_m, atol=1e-6)
    alt = tmp_path / "alt.csv"
    alt.write_text("timestamp_ms,altitude_m\n0,100\n100,101\n200,103\n")
    got = read_baro_csv(alt)
    np.testing.assert_allclose(got.t, [0.0, 0.1, 0.2])
    np.testing.assert_allclose(got.alt_m, [100.0, 101.0, 103.0])


def test_baro_csv_errors_say_what_is_wrong(tmp_path):
    with pytest.raises(NavlibInputError, match=r"look like hPa"):
        read_baro_csv(_write_baro(tmp_path / "a.csv", "t,pressure,temp", scale=0.01))
    bad = tmp_path / "b.csv"
    bad.write_text("t,humidity\n0,1\n1,2\n")
    with pytest.raises(NavlibInputError, match=r"needs a pressure column .* or an altitude"):
        read_baro_csv(bad)


def test_baro_csv_all_empty_optional_column_is_ignored(tmp_path):
    baro = read_baro_csv(_write_baro(tmp_path / "b.csv", temp=""))
    assert "temperature_c" not in baro.columns and len(baro) == 400


def test_log_pairs_and_triples_with_a_barometer(tmp_path):
    imu_path = _write_imu(tmp_path / "imu.csv")
    baro_path = _write_baro(tmp_path / "baro.csv")
    gnss_path = tmp_path / "gnss.csv"
    gnss_path.write_text("t,lat_deg,lon_deg\n" + "".join(
        f"{k * 0.5:.1f},45.0,{7.0 + 1e-6 * k}\n" for k in range(8)))
    assert io.parse_log(f"{imu_path},{baro_path}") == ("csv", (imu_path, baro_path))
    imu, gnss = io.read_log(f"{imu_path},{baro_path}")
    assert gnss is None and len(imu.attrs["baro"]) == 400
    imu, gnss = io.read_log(f"{imu_path},{gnss_path},{baro_path}")
    assert gnss.attrs["height_source"] == "baro"
    _, swapped = io.read_log(f"{imu_path},{baro_path},{gnss_path}")
    pd.testing.assert_frame_equal(swapped, gnss)
    _, _, h = io_geodetic(gnss)
    np.testing.assert_allclose(h, np.interp(gnss.t, imu.attrs["baro"].t,
                                            imu.attrs["baro"].alt_m), atol=1e-3)
    with pytest.raises(NavlibInputError,
                       match=r"missing column: latitude and longitude but no height.*barometer"):
        io.read_log(f"{imu_path},{gnss_path}")


def io_geodetic(gnss):
    from navlib.earth import ecef_to_geodetic

    return ecef_to_geodetic(gnss[["x", "y", "z"]].to_numpy())


def test_single_csv_that_is_no_export_says_what_it_has(tmp_path):
    imu_path = _write_imu(tmp_path / "imu.csv")
    with pytest.raises(NavlibInputError, match=r"has IMU columns; .*'imu.csv,baro.csv'"):
        io.parse_log(str(imu_path))
    notes = tmp_path / "notes.csv"
    notes.write_text("a,b\n1,2\n")
    with pytest.raises(NavlibInputError, match=r"no IMU columns") as err:
        io.parse_log(str(notes))
    assert "unknown kind" not in str(err.value)


FIRM_HEADER = ("state_letter,timestamp_seconds,temperature_celsius,pressure_pascals,"
               "raw_acceleration_x_gs,raw_acceleration_y_gs,raw_acceleration_z_gs,"
               "raw_angular_rate_x_deg_per_s,raw_angular_rate_y_deg_per_s,"
               "raw_angular_rate_z_deg_per_s,predicted_apogee")


def test_firm_log_is_recognised_and_read_in_si(tmp_path):
    path = tmp_path / "launch.csv"
    t = 779.0 + np.arange(300) / 92.0
    path.write_text(FIRM_HEADER + "\n" + "".join(
        f"S,{a:.5f},49.5,{92585.0 - k:.2f},-0.7071,0.7071,0.0,0.1,-0.2,0.3,\n"
        for k, a in enumerate(t)))
    assert io.parse_log(str(path)) == ("firm", (path,))
    imu, gnss = io.read_log(str(path))
    assert gnss is None and imu.attrs["vehicle"] == "rocket"
    np.testing.assert_allclose(imu[["f_x", "f_y"]].iloc[0], [-0.7071 * 9.80665,
                                                            0.7071 * 9.80665])
    np.testing.assert_allclose(imu.w_z, np.deg2rad(0.3))
    assert imu.attrs["baro"].alt_m.iloc[-1] > imu.attrs["baro"].alt_m.iloc[0]


def _write_cats(folder, gnss=True, baro=True):
    folder.mkdir()
    t = -0.5 + np.arange(400) / RATE
    (folder / "imu.csv").write_text("ts,id,Ax,Ay,Az,Gx,Gy,Gz\n" + "".join(
        f"{a:.3f},IMU0,0.1,-9.8,0.2,1.0,0.0,-1.0\n" for a in t))
    if baro:
        (folder / "baro.csv").write_text("ts,id,T,P\n" + "".join(
            f"{a:.3f},BARO0,20.0,{99_600 - 10 * k}\n" for k, a in enumerate(t)))
    if gnss:   # a fix every 0.5 s, logged every 0.1 s (held in between); 193 satellites
        (folder / "gnssInfo.csv").write_text("ts,latitude,longitude,satellites\n" + "".join(
            f"{a:.3f},39.39,{-8.2885 + 1e-5 * (k // 5)},{193 if k < 5 else 9}\n"
            for k, a in enumerate(t[::10])))     # reported with the first fix
    return folder / "imu.csv"


def test_cats_export_reads_its_folder_and_drops_held_fixes(tmp_path):
    path = _write_cats(tmp_path / "cats")
    assert io.parse_log(str(path)) == ("cats", (path,))
    with pytest.warns(io.FlightDataWarning) as caught:
        imu, gnss = io.read_log(str(path))
    messages = [str(w.message) for w in caught]
    assert imu.attrs["vehicle"] == "rocket" and len(imu.attrs["baro"]) == 400
    np.testing.assert_allclose(imu.w_x, np.deg2rad(1.0))
    assert gnss.attrs["height_source"] == "baro"
    # 8 fixes each logged 5 times: 32 held rows; the first fix reports 193 satellites
    assert len(gnss) == 8 and gnss.attrs["held_fixes_dropped"] == 32
    assert gnss.attrs["implausible_rows"] == 1
    assert any("32 of 40 GNSS rows repeat the previous row's fix exactly (a fix held "
               "between the receiver's updates; the longest hold 0.4 s), at line 3, line 4, "
               "line 5, line 6, line 8 and 27 more: not new measurements, dropped" in m
               for m in messages), messages
    assert any("column 'satellites': 1 of 40 GNSS rows report more than 100 satellites (up "
               "to 193; about 60 can be above the horizon), at line 2: an implausible count; "
               "their positions are kept" in m for m in messages), messages
    only = _write_cats(tmp_path / "no_gnss", gnss=False)
    assert io.read_log(str(only))[1] is None
    lacking = _write_cats(tmp_path / "no_baro", baro=False)
    with pytest.raises(NavlibInputError, match=r"barometer 'baro.csv' is not beside it"):
        io.read_log(str(lacking))


@pytest.mark.skipif(not FIRM_LOG.is_file(), reason=f"shared FIRM log absent ({FIRM_LOG})")
def test_shared_firm_log_reads_without_gnss():
    imu, gnss = io.read_log(str(FIRM_LOG))
    assert gnss is None
    baro = imu.attrs["baro"]
    rise = baro.alt_m.max() - baro.alt_m.iloc[:100].median()
    assert 1000.0 < rise < 1300.0   # README: barometric apogee 1131 m above the pad


@pytest.mark.skipif(not CATS_LOG.is_file(), reason=f"shared CATS log absent ({CATS_LOG})")
def test_shared_cats_export_reads_gnss_with_barometric_height():
    _, gnss = io.read_log(str(CATS_LOG))
    assert gnss.attrs["height_source"] == "baro"
    # README: many rows repeat the position, the first rows report 193 satellites
    assert gnss.attrs["held_fixes_dropped"] == 234      # of 388 rows (the issue counted 235)
    assert gnss.attrs["implausible_rows"] > 0 and gnss.attrs["too_few_satellites"] > 0


def _moving_imu(n=400, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(n) / RATE
    f = np.column_stack([0.3 * np.sin(t), 0.2 * np.cos(t), -9.81 - 20.0 * (t > 2.0)])
    w = np.column_stack([np.sin(3 * t), 0.5 * np.cos(2 * t), 0.2 * t])
    return t, f + 0.01 * rng.standard_normal(f.shape), w + 1e-3 * rng.standard_normal(w.shape)


def _write_rows(path, t, f, w):
    path.write_text("t,f_x,f_y,f_z,w_x,w_y,w_z\n" + "".join(
        f"{a:.3f},{b[0]:.6f},{b[1]:.6f},{b[2]:.6f},{c[0]:.6f},{c[1]:.6f},{c[2]:.6f}\n"
        for a, b, c in zip(t, f, w, strict=True)))
    return path


def test_dead_imu_is_refused_by_name(tmp_path):
    t, f, w = _moving_imu()
    assert len(io.read_imu_csv(_write_rows(tmp_path / "ok.csv", t, f, w))) == 400
    with pytest.raises(NavlibInputError, match=r"'f_x'/'f_y'/'f_z'.*dead accelerometer: the "
                                               r"specific force never exceeds 0 m/s\^2 over "
                                               r"400 samples"):
        io.read_imu_csv(_write_rows(tmp_path / "a.csv", t, 0.0 * f, w))
    w_stuck = w.copy()
    w_stuck[:, 1] = 0.25
    with pytest.raises(NavlibInputError, match=r"column 'w_y': stuck gyro axis: all 400 "
                                               r"samples read 0.25"):
        io.read_imu_csv(_write_rows(tmp_path / "g.csv", t, f, w_stuck))
    rest = np.zeros_like(w)     # a quiet gyro at rest reads one value: not judged
    assert len(io.read_imu_csv(_write_rows(tmp_path / "r.csv", t, f[:, [0, 1, 2]] * 0 +
                                           [0.0, 0.0, -9.81], rest))) == 400


def test_altos_dead_imu_is_named_and_an_empty_tilt_column_ignored(tmp_path):
    from support.altos_writer import rocket_rows, write_altos

    rows = rocket_rows()
    path = tmp_path / "empty_tilt.csv"
    write_altos(path, rows.assign(tilt=np.nan))
    imu, gnss = io.read_altos(path)
    assert imu.attrs["tilt"] is None and len(gnss) > 5
    dead = rows.assign(accel_x=0.0, accel_y=0.0, accel_z=0.0, tilt=np.nan)
    write_altos(path, dead)
    with pytest.raises(NavlibInputError, match=r"'accel_x'/'accel_y'/'accel_z'.*dead "
                                               r"accelerometer") as err:
        io.read_altos(path)
    assert "magnetometer" not in str(err.value)      # it reads a field: alive
    write_altos(path, dead.assign(mag_x=0.0, mag_y=0.0, mag_z=0.0))
    with pytest.raises(NavlibInputError, match=(
            r"dead accelerometer: the specific force never exceeds 0 m/s\^2 over .* samples, "
            r".*; the magnetometer 'mag_x'/'mag_y'/'mag_z' reads 0 on every axis in all "
            r"\d+ rows too: the IMU looks unpowered")):
        io.read_altos(path)
    write_altos(path, rows.assign(mag_x=0.0, mag_y=0.0, mag_z=0.0))
    with pytest.warns(io.FlightDataWarning, match=r"the magnetometer 'mag_x'/'mag_y'/'mag_z' "
                                                  r"reads 0 on every axis .*: a dead "
                                                  r"magnetometer \(navlib does not use it\)"):
        io.read_altos(path)


def test_deg_s_hint_only_when_the_rates_look_like_deg_s(tmp_path):
    t, f, w = _moving_imu()
    w = 0.3 * w                            # a calm flight: median rate about 0.3 rad/s
    tumble = w.copy()
    tumble[300:340] = [40.0, 5.0, 0.0]     # a break-up at 2300 deg/s, logged in rad/s
    with pytest.raises(NavlibInputError, match=r"median rate .* units look right: a vehicle "
                                               r"this fast .* needs a larger max_rate_rad_s "
                                               r"\(e.g. max_rate_rad_s=43; python -m navlib "
                                               r"assess LOG --read max_rate_rad_s 43\)") as err:
        io.read_imu_csv(_write_rows(tmp_path / "tumble.csv", t, f, tumble))
    assert "look like deg/s" not in str(err.value)
    assert len(io.read_imu_csv(_write_rows(tmp_path / "tumble.csv", t, f, tumble),
                               max_rate_rad_s=43.0)) == 400
    with pytest.raises(NavlibInputError, match=r"look like deg/s"):
        io.read_imu_csv(_write_rows(tmp_path / "deg.csv", t, f, np.rad2deg(w) + 60.0))


def test_duplicated_time_stamps_are_reported_with_their_lines(tmp_path):
    t, f, w = _moving_imu()
    t = t.copy()
    t[[50, 120, 121]] = t[[49, 119, 119]]
    # rows 50, 120, 121 are file lines 52, 122, 123 (the header is line 1)
    with pytest.raises(NavlibInputError, match=r"line 52: duplicate time stamp 0.49 \(same as "
                                               r"line 51\); 3 duplicated time stamps in all, "
                                               r"at line 52, line 122, line 123"):
        io.read_imu_csv(_write_rows(tmp_path / "dup.csv", t, f, w))


def test_gnss_satellite_column_empty_is_ignored(tmp_path):
    """An optional satellite-count column left empty (all cells, or some) drops no row."""
    path = tmp_path / "gnss.csv"
    path.write_text("t,lat_deg,lon_deg,alt,satellites\n" + "".join(
        f"{k:.1f},39.39,{-8.2885 + 1e-5 * k},100.0,\n" for k in range(10)))
    assert len(io.read_gnss_csv(path)) == 10
    path.write_text("t,lat_deg,lon_deg,alt,nsat\n" + "".join(
        f"{k:.1f},39.39,{-8.2885 + 1e-5 * k},100.0,{9 if k % 2 else ''}\n" for k in range(10)))
    assert len(io.read_gnss_csv(path)) == 10
