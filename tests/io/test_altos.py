"""navlib.io.read_altos: AltOS CSV exports written here (both generations) and the shared ones."""

import warnings

import numpy as np
import pandas as pd
import pytest
from support.altos_writer import IMU, rocket_rows, write_altos
from support.locations import shared_file

from navlib import NavlibInputError, earth, io, units
from navlib.io.altos import TELEMEGA_RANGE, looks_like_altos

SHARED = ("2018-04-08-serial-1257-flight-0014.csv", "2019-05-04-serial-1257-flight-0017.csv",
          "2019-05-26-serial-1257-flight-0018.csv")


def _read(path, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", io.FlightDataWarning)   # gaps under drogue
        return io.read_altos(path, **kw)


@pytest.fixture(scope="module")
def rows():
    return rocket_rows()


@pytest.fixture(scope="module", params=["version", "legacy"])
def export(request, rows, tmp_path_factory):
    folder = tmp_path_factory.mktemp("altos")
    path = folder / f"2019-05-26-serial-1257-flight-0018-{request.param}.csv"
    write_altos(path, rows, generation=request.param)
    return request.param, path


def _samples(rows):
    """The IMU samples the export holds: rows that do not repeat the previous row's IMU."""
    values = rows[list(IMU)].to_numpy()
    new = np.r_[True, np.any(values[1:] != values[:-1], axis=1)]
    return rows[new]


def test_imu_units_axes_and_repeated_rows(export, rows):
    generation, path = export
    imu, _ = _read(path)
    want = _samples(rows)
    assert list(imu.columns) == ["t", "f_x", "f_y", "f_z", "w_x", "w_y", "w_z"]
    assert imu.attrs["repeated_rows"] == len(rows) - len(want) > 0
    np.testing.assert_allclose(imu["t"], want["time"])
    np.testing.assert_allclose(imu[["f_x", "f_y", "f_z"]],
                               want[["accel_x", "accel_y", "accel_z"]], atol=1e-9)
    np.testing.assert_allclose(imu[["w_x", "w_y", "w_z"]],
                               np.radians(want[["gyro_roll", "gyro_pitch", "gyro_yaw"]]),
                               atol=1e-12)
    pad = imu[imu["t"] < 0.0]
    assert pad["f_x"].mean() == pytest.approx(9.87)            # nose up on the pad: +g on x
    assert imu.attrs["format"] == f"altos-{generation}"
    assert imu.attrs["hardware"] == "TeleMega serial 1257"
    assert imu.attrs["range"] == TELEMEGA_RANGE
    assert imu.attrs["body_frame"] == "along-across-through"
    tilt, baro = imu.attrs["tilt"], imu.attrs["baro"]
    np.testing.assert_allclose(tilt["t"], imu["t"])
    np.testing.assert_allclose(tilt["tilt"], np.radians(want["tilt"]), atol=1e-12)
    np.testing.assert_allclose(baro["alt_m"], want["baro_altitude"])
    high_g = imu.attrs["high_g"]           # the writer's `acceleration` column: accel_x here
    np.testing.assert_allclose(high_g["t"], imu["t"])
    np.testing.assert_allclose(high_g["f_x"], want["accel_x"])


@pytest.mark.parametrize("name", SHARED)
def test_shared_high_g_column_is_along_x(name):
    """The shared exports' `acceleration` (high-g, pad reading removed) reads about 0 on the
    pad and tracks accel_x in the boost within the sensors' 5 %: the same axis, same sign."""
    imu, _ = _read(shared_file("altos", name))
    high_g = imu.attrs["high_g"].set_index("t")["f_x"].reindex(imu["t"]).to_numpy()
    pad = imu["t"].to_numpy() < -0.1
    assert abs(np.median(high_g[pad])) < 0.6
    boost = (imu["f_x"].to_numpy() > 60.0) & (imu["f_x"].to_numpy() < 150.0) & \
        (imu["t"].to_numpy() < 4.0)
    ratio = (high_g[boost] + 9.8) / imu["f_x"].to_numpy()[boost]
    assert boost.sum() > 50 and 0.95 < np.median(ratio) < 1.0


def test_gps_fixes_are_changes_not_rows(export, rows):
    _, path = export
    _, gnss = _read(path)
    first = rows.groupby("gps_second").time.min()
    assert list(gnss.columns) == ["t", "x", "y", "z"]
    np.testing.assert_allclose(gnss["t"], first.to_numpy())
    one = rows.groupby("gps_second").first()
    r = earth.geodetic_to_ecef(np.radians(one["latitude"]), np.radians(one["longitude"]),
                               one["gps_altitude"])
    np.testing.assert_allclose(gnss[["x", "y", "z"]], r, atol=1e-6)
    assert gnss.attrs["altitude_reference"] == "msl" and gnss.attrs["dropped_no_fix"] == 0


def test_both_generations_agree_and_states_only_in_the_newer(rows, tmp_path):
    frames = {}
    for generation in ("version", "legacy"):
        path = tmp_path / f"{generation}.csv"
        write_altos(path, rows, generation=generation)
        frames[generation] = _read(path)
    (imu_v, gnss_v), (imu_l, gnss_l) = frames["version"], frames["legacy"]
    pd.testing.assert_frame_equal(imu_v, imu_l)
    pd.testing.assert_frame_equal(gnss_v, gnss_l)
    states = imu_v.attrs["flight_states"]
    assert list(states["state"]) == ["boost", "coast", "drogue", "landed"]
    np.testing.assert_allclose(states["t"], [-0.3, 2.0, 6.0, 12.0])
    assert imu_l.attrs["flight_states"] is None
    assert imu_l.attrs["hardware"] == "TeleMega"            # no serial column nor file name


def test_fix_with_too_few_satellites_is_dropped(tmp_path):
    rows = rocket_rows(low_sat_second=4)
    path = tmp_path / "lowsat.csv"
    write_altos(path, rows)
    _, gnss = _read(path)
    assert gnss.attrs["dropped_no_fix"] == 1
    assert len(gnss) == rows["gps_second"].nunique() - 1
    assert not np.any(np.isclose(gnss["t"], rows.loc[rows.gps_second == 4, "time"].min()))


@pytest.mark.parametrize("board, match", [
    ("telemetrum", r"missing IMU column\(s\) \['accel_x', .*'gyro_yaw'\] \(no gyro: a "
                   r"TeleMetrum"),
])
@pytest.mark.parametrize("generation", ["version", "legacy"])
def test_boards_without_gyro_or_gps_are_refused(rows, tmp_path, board, match, generation):
    path = tmp_path / f"{board}.csv"
    write_altos(path, rows, generation=generation, board=board)
    assert looks_like_altos(path)
    with pytest.raises(NavlibInputError, match=match):
        io.read_altos(path)


@pytest.mark.parametrize("generation", ["version", "legacy"])
def test_easymega_without_gps_reads_imu_and_barometer(rows, tmp_path, generation):
    path = tmp_path / "easymega.csv"
    write_altos(path, rows, generation=generation, board="easymega")
    imu, gnss = io.read_log(str(path))
    assert gnss is None and len(imu) > 100
    baro = imu.attrs["baro"]
    np.testing.assert_allclose(baro.alt_m.iloc[0], rows.baro_altitude.iloc[0])


def test_repeated_time_with_new_values_names_the_line(rows, tmp_path):
    bad = rows.copy()
    k = int(np.flatnonzero(bad.time.to_numpy() == 1.0)[0])
    bad.loc[k + 1, "time"] = bad.loc[k, "time"]
    path = tmp_path / "dup.csv"
    write_altos(path, bad)
    with pytest.raises(NavlibInputError, match=rf"column 'time', line {k + 3}: duplicate time"):
        io.read_altos(path)


@pytest.mark.parametrize("text, match", [
    ("a,b,c\n1,2,3\n", "not an AltOS CSV export"),
    ("#version,serial,flight,call,time,state\n", "no data rows"),
    ("", "file is empty"),
])
def test_foreign_and_empty_files(tmp_path, text, match):
    path = tmp_path / "x.csv"
    path.write_text(text)
    with pytest.raises(NavlibInputError, match=match):
        io.read_altos(path)


def test_recognised_by_header_not_name(rows, tmp_path):
    path = tmp_path / "flight.txt"
    write_altos(path, rows, generation="legacy")
    assert looks_like_altos(path)
    other = tmp_path / "imu.csv"
    other.write_text("t,f_x,f_y,f_z,w_x,w_y,w_z\n0,0,0,9.8,0,0,0\n")
    assert not looks_like_altos(other) and not looks_like_altos(tmp_path / "absent.csv")


# --------------------------------------------------------------------------- shared flights


def _shared(name):
    return shared_file("altos", name)


@pytest.mark.parametrize("name", SHARED)
def test_shared_flights(name):
    path = _shared(name)
    imu, gnss = _read(path)
    assert imu.attrs["hardware"] == "TeleMega serial 1257"
    dt = np.diff(imu["t"])
    assert np.median(dt) == pytest.approx(0.01, abs=1e-9)            # 100 Hz in boost
    assert np.median(np.diff(gnss["t"])) == pytest.approx(1.0, abs=0.05)   # 1 Hz fixes
    assert imu["t"].iloc[0] == pytest.approx(-0.3) and imu["t"].iloc[-1] > 120.0
    assert np.mean(imu["f_x"].to_numpy()[:10]) == pytest.approx(9.9, abs=0.3)
    assert np.abs(imu[["w_x", "w_y", "w_z"]].to_numpy()).max() <= (
        TELEMEGA_RANGE["gyro_rad_s"] * 1.01)
    _, _, h = earth.ecef_to_geodetic(gnss[["x", "y", "z"]].to_numpy())
    baro = imu.attrs["baro"]["alt_m"].to_numpy()
    assert abs(h[0] - baro[0]) < 150.0        # both MSL: GPS against standard atmosphere
    states = imu.attrs["flight_states"]
    if imu.attrs["format"] == "altos-version":
        assert {"boost", "coast", "drogue", "main", "landed"} <= set(states["state"])
    else:
        assert states is None


@pytest.mark.parametrize("name", SHARED)
def test_shared_flights_roll_sign_against_the_magnetometer(name):
    """The roll rate is right-handed about body x: a fixed field seen from the body turns
    by minus the integrated roll angle in the (y, z) plane (coast, where the roll is fast)."""
    path = _shared(name)
    imu, _ = _read(path)
    text = path.read_text().splitlines()
    head = [h.strip().lstrip("#") for h in text[0].split(",")]
    raw = pd.read_csv(path, skiprows=1, header=None, skipinitialspace=True)
    t = raw[head.index("time")].to_numpy(dtype=float)
    mag = raw[[head.index("mag_y"), head.index("mag_z")]].to_numpy(dtype=float)
    sel = (t > 4.0) & (t < 18.0)
    m = mag[sel] - mag[sel].mean(axis=0)
    turned = np.unwrap(np.arctan2(m[:, 1], m[:, 0]))
    seg = imu[(imu["t"] > 4.0) & (imu["t"] < 18.0)]
    rolled = np.sum(seg["w_x"].to_numpy()[:-1] * np.diff(seg["t"].to_numpy()))
    assert abs(rolled) > units.deg2rad(720.0)
    assert (turned[-1] - turned[0]) / rolled == pytest.approx(-1.0, abs=0.1)


def _short_header(path, names):
    """The export at ``path`` with ``names`` left out of its header only (the rows keep
    every field): a header of fewer columns than every row."""
    lines = path.read_text().splitlines()
    head = lines[0].split(",")
    lines[0] = ",".join(h for h in head if h.strip().lower().lstrip("#") not in names)
    path.write_text("\n".join(lines) + "\n")
    return len(head), len(lines[0].split(","))


@pytest.mark.parametrize("missing", [("gyro_roll", "gyro_pitch", "gyro_yaw", "mag_x", "mag_y",
                                      "mag_z"), ("mag_x", "mag_y", "mag_z", "tilt")])
def test_header_shorter_than_its_rows_by_the_imu_block_is_read(rows, tmp_path, missing):
    full = tmp_path / "full.csv"
    write_altos(full, rows)
    imu_full, gnss_full = _read(full)
    path = tmp_path / "short.csv"
    write_altos(path, rows)
    n_rows, n_head = _short_header(path, missing)
    assert n_rows - n_head == len(missing)
    with pytest.warns(io.FlightDataWarning, match=(
            rf"the header names {n_head} columns but every row has {n_rows} fields; the "
            rf"{len(missing)} extra fields are read as the AltOS IMU block the header lacks "
            rf"\({', '.join(missing)}, after accel_z\)")):
        imu, gnss = io.read_altos(path)
    pd.testing.assert_frame_equal(imu, imu_full)
    pd.testing.assert_frame_equal(gnss, gnss_full)


def test_header_shorter_than_its_rows_by_other_columns_is_refused(rows, tmp_path):
    path = tmp_path / "short.csv"
    write_altos(path, rows)
    n_rows, n_head = _short_header(path, ("pdop", "hdop"))
    with pytest.raises(NavlibInputError, match=(
            rf"the header names {n_head} columns but every row has {n_rows} fields; the 2 extra "
            r"field\(s\) are not the AltOS gyro/magnetometer/tilt block .* \(it names the whole "
            r"block\), so which field is which cannot be told")):
        io.read_altos(path)
    write_altos(path, rows)
    _short_header(path, ("gyro_roll", "gyro_pitch", "gyro_yaw", "mag_x", "mag_y", "mag_z",
                         "tilt", "pdop"))
    with pytest.raises(NavlibInputError, match=r"the 8 extra field\(s\) are not the AltOS "
                                               r".*it lacks \['gyro_roll'"):
        io.read_altos(path)


def test_cut_last_row_of_a_short_header_export_is_dropped(rows, tmp_path):
    path = tmp_path / "cut.csv"
    write_altos(path, rows)
    _short_header(path, ("gyro_roll", "gyro_pitch", "gyro_yaw", "mag_x", "mag_y", "mag_z"))
    text = path.read_text().rstrip("\n")
    n_lines = text.count("\n") + 1
    path.write_text(text[:-30])             # the last row cut mid-write
    with pytest.warns(io.FlightDataWarning, match=rf"line {n_lines}: the last row was cut "
                                                  r"mid-write"):
        imu, _ = io.read_altos(path)
    assert len(imu) > 100


@pytest.mark.parametrize("generation", ["version", "legacy"])
def test_easymega_export_with_a_cut_last_row_is_read_without_it(rows, tmp_path, generation):
    """An EasyMega export whose logger lost power mid-write: the cut last row is dropped with
    a warning naming its line, the rest read (it was refused as 'truncated')."""
    path = tmp_path / "easymega.csv"
    write_altos(path, rows, generation=generation, board="easymega")
    whole, _ = _read(path)
    text = path.read_text().rstrip("\n")
    n_lines = text.count("\n") + 1
    path.write_text(text[: text.rindex(",") - 3])
    with pytest.warns(io.FlightDataWarning, match=rf"line {n_lines}: the last row was cut "
                                                  r"mid-write \(\d+ of \d+ fields"):
        imu, gnss = io.read_altos(path)
    assert gnss is None and len(imu) in (len(whole), len(whole) - 1)
    assert imu.attrs["baro"] is not None
