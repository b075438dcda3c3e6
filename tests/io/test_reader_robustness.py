"""No bare exception from any reader: truncated and mutated files give NavlibInputError or a read.

Small valid files are made once (AltOS exports of both generations, DataFlash logs of both
time-stamp generations, IMU/GNSS CSV files, and a PX4 ULog cut from a shared sample log to
its first second, skipped when that log is absent); hypothesis then cuts them at random
offsets, overwrites random bytes, damages the header line, and checks that each reader either
returns or raises :class:`navlib.NavlibInputError` (a ``ValueError``), never anything else.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from support.altos_writer import rocket_rows, write_altos
from support.dataflash_writer import write_flight

from navlib import NavlibInputError, io


@dataclass(frozen=True)
class Original:
    """A valid file and its reader (``repr`` names the file only: hypothesis prints it)."""

    name: str
    reader: object = field(repr=False)
    data: bytes = field(repr=False)


SETTINGS = settings(max_examples=60, deadline=None, derandomize=True,
                    suppress_health_check=[HealthCheck.function_scoped_fixture])


def _dataflash(path, layout):
    t = np.arange(0.0, 3.0, 0.02)
    imu = pd.DataFrame({"t": t, "f_x": 0.1 * np.sin(t), "f_y": 0.0 * t, "f_z": -9.8 + 0 * t,
                        "w_x": 0.01 * np.cos(t), "w_y": 0.0 * t, "w_z": 0.02 + 0 * t})
    tg = np.arange(0.0, 3.0, 0.2)
    geo = pd.DataFrame({"t": tg, "lat_deg": 47.4 + 1e-6 * tg, "lon_deg": 8.5 + 0 * tg,
                        "alt_m": 500.0 + tg, "vn": 0.1 + 0 * tg, "ve": 0 * tg, "vd": -1 + 0 * tg})
    att = pd.DataFrame({"t": tg, "roll_deg": 0 * tg, "pitch_deg": 0 * tg, "yaw_deg": 10 + tg})
    baro = pd.DataFrame({"t": tg, "alt_m": tg})
    write_flight(path, imu, geo, att, layout=layout, imu_instances=(0, 1), baro=baro)


def _csv_pair(folder):
    t = np.arange(0.0, 3.0, 0.01)
    imu = pd.DataFrame({"t": t, "f_x": 0 * t, "f_y": 0 * t, "f_z": -9.8 + 0 * t,
                        "w_x": 0 * t, "w_y": 0 * t, "w_z": 0.01 + 0 * t})
    tg = np.arange(0.0, 3.0, 0.2)
    gnss = pd.DataFrame({"t": tg, "x": 4.2e6 + tg, "y": 0.7e6 + 0 * tg, "z": 4.7e6 + 0 * tg})
    io.write_imu_csv(imu, folder / "imu.csv")
    io.write_gnss_csv(gnss, folder / "gnss.csv")


def _ulog(path, px4_log_path):
    pyulog = pytest.importorskip("pyulog")
    source = px4_log_path("sample_log_small.ulg")
    log = pyulog.ULog(str(source), message_name_filter_list=[
        "sensor_combined", "vehicle_gps_position", "sensor_gps", "vehicle_attitude",
        "vehicle_air_data"])
    t0 = min(d.data["timestamp"][0] for d in log.data_list)
    for d in log.data_list:
        keep = d.data["timestamp"] < t0 + 1_500_000
        d.data = {k: v[keep] for k, v in d.data.items()}
    log.write_ulog(str(path))


@pytest.fixture(scope="module")
def originals(tmp_path_factory):
    """name -> (reader, file bytes) of every small valid file."""
    folder = tmp_path_factory.mktemp("valid")
    rows = rocket_rows(t_drogue=1.5, t_end=4.0)
    files = {}
    for generation in ("version", "legacy"):
        path = folder / f"altos_{generation}.csv"
        write_altos(path, rows, generation=generation)
        files[f"altos_{generation}"] = (io.read_altos, path)
    for layout in ("4.x", "TimeMS"):
        path = folder / f"dataflash_{layout}.bin"
        _dataflash(path, layout)
        files[f"dataflash_{layout}"] = (io.read_dataflash, path)
    _csv_pair(folder)
    files["imu_csv"] = (io.read_imu_csv, folder / "imu.csv")
    files["gnss_csv"] = (io.read_gnss_csv, folder / "gnss.csv")
    return {name: Original(name, reader, path.read_bytes())
            for name, (reader, path) in files.items()}


@pytest.fixture(scope="module")
def ulog_original(tmp_path_factory, px4_log_path):
    path = tmp_path_factory.mktemp("valid_ulog") / "small.ulg"
    _ulog(path, px4_log_path)
    return Original("ulog", io.read_ulog, path.read_bytes())


def _mutate(data: bytes, draw) -> bytes:
    """One damage of ``data``, drawn by hypothesis."""
    kind = draw(st.sampled_from(["cut", "flip", "header", "block"]))
    n = len(data)
    if kind == "cut":
        return data[:draw(st.integers(0, n - 1))]
    if kind == "flip":
        out = bytearray(data)
        for _ in range(draw(st.integers(1, 8))):
            out[draw(st.integers(0, n - 1))] = draw(st.integers(0, 255))
        return bytes(out)
    if kind == "header":
        end = data.find(b"\n")
        end = min(n, 400) if end < 0 else end
        start = draw(st.integers(0, max(0, end - 1)))
        stop = draw(st.integers(start, end))
        junk = draw(st.binary(max_size=12))
        return data[:start] + junk + data[stop:]
    start = draw(st.integers(0, n - 1))
    return data[:start] + draw(st.binary(min_size=1, max_size=64)) + data[start + 64:]


def _check(reader, data: bytes, path) -> None:
    path.write_bytes(data)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            reader(path)
        except NavlibInputError:
            pass


def test_unmutated_files_read(originals, tmp_path):
    for name, original in originals.items():
        path = tmp_path / name
        path.write_bytes(original.data)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            out = original.reader(path)
        frames = out if isinstance(out, tuple) else (out,)
        assert all(len(f) >= 2 for f in frames), name


@SETTINGS
@given(data=st.data())
@pytest.mark.parametrize("name", ["altos_version", "altos_legacy", "dataflash_4.x",
                                  "dataflash_TimeMS", "imu_csv", "gnss_csv"])
def test_damaged_files_raise_only_navlib_input_error(originals, tmp_path, name, data):
    original = originals[name]
    _check(original.reader, _mutate(original.data, data.draw), tmp_path / f"damaged_{name}")


@SETTINGS
@given(data=st.data())
def test_damaged_ulog_raises_only_navlib_input_error(ulog_original, tmp_path, data):
    _check(ulog_original.reader, _mutate(ulog_original.data, data.draw),
           tmp_path / "damaged.ulg")


def test_ulog_topic_without_timestamp_is_named(ulog_original, tmp_path):
    """A damaged format definition that loses ``timestamp`` (found by the test above)."""
    head = b"sensor_combined:uint64_t timestamp;"
    assert head in ulog_original.data
    path = tmp_path / "no_timestamp.ulg"
    path.write_bytes(ulog_original.data.replace(head, head.replace(b"timestamp", b"timestamq")))
    with pytest.raises(NavlibInputError, match="topic 'sensor_combined': no 'timestamp' field"):
        io.read_ulog(path)


def test_ulog_damaged_message_at_the_end_does_not_hang(ulog_original, tmp_path):
    """A message of type 0 declaring more bytes than remain, right after the definitions:
    pyulog's corruption recovery seeks back and re-reads forever (found by the test above);
    the reader's read budget turns that into a NavlibInputError."""
    data = ulog_original.data
    p = 16
    while data[p + 2] not in b"ALC":            # walk the definitions to their end
        p += 3 + int.from_bytes(data[p:p + 2], "little")
    assert p > 9000
    path = tmp_path / "loops.ulg"
    path.write_bytes(data[:p] + (9000).to_bytes(2, "little") + b"\x00" + bytes(100))
    with pytest.raises(NavlibInputError, match="keeps re-reading the same bytes"):
        io.read_ulog(path)
