"""Saturation and GNSS-fault checks (navlib.io.quality, data/quality.toml, assumptions Q1-Q4)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import given
from hypothesis import strategies as st
from support import vehicles
from support.flights import multicopter, records

from navlib import earth, sensors
from navlib.errors import NavlibInputError
from navlib.io.gnss_faults import baro_lag, grid_minimum
from navlib.io.quality import (
    check_records,
    gnss_faults,
    imu_saturation,
    load_thresholds,
)
from navlib.studies.assess import assess_flight
from navlib.units import DEG

LIMIT = 2000.0 * DEG


@pytest.fixture(scope="module")
def truth():
    return multicopter(duration_s=90.0)


@pytest.fixture(scope="module")
def recs(truth):
    return records(truth)


@pytest.fixture(scope="module")
def pixhawk():
    return sensors.load_preset("pixhawk_mems")


def _clip(imu, t0, n, value=LIMIT, column="w_x"):
    """``n`` samples of ``column`` from ``t0`` on set to ``value`` (a clipped gyro)."""
    out = imu.copy()
    out.attrs = dict(imu.attrs)
    k = int(np.searchsorted(out["t"].to_numpy(), t0))
    out.loc[k:k + n - 1, column] = value
    return out, out["t"].to_numpy()[k:k + n]


def test_thresholds_are_data_and_overridable():
    p = load_thresholds()
    assert set(p) == {"saturation", "gnss", "fit"}
    assert p["gnss"]["frozen_min_duration_s"] > 0
    q = load_thresholds({"gnss": {"jump_min_m": 20}})
    assert q["gnss"]["jump_min_m"] == 20.0
    for bad, match in (({"gps": {}}, "unknown keyword"),
                       ({"gnss": {"jump_m": 1}}, "unknown keyword"),
                       ({"gnss": {"jump_min_m": -1}}, "jump_min_m"),
                       ({"gnss": 3}, "expected a mapping")):
        with pytest.raises(NavlibInputError, match=match):
            load_thresholds(bad)


def test_preset_carries_the_range(pixhawk):
    assert pixhawk.imu.gyro.range == pytest.approx(LIMIT)
    assert pixhawk.imu.accel.range == pytest.approx(16 * 9.80665)
    assert sensors.load_preset("motionpak_tactical").imu.gyro.range is None


def test_gyro_at_its_limit_is_reported_with_times(recs, pixhawk):
    imu, _ = recs
    clipped, times = _clip(imu, 40.0, 8)
    clipped, more = _clip(clipped, 70.0, 4, value=-LIMIT, column="w_z")
    saturated, found = imu_saturation(clipped, pixhawk)
    assert np.count_nonzero(saturated) == 12
    assert found.set_index("channel").loc["w_z", "t_last"] == pytest.approx(more[-1])
    assert set(found["channel"]) == {"w_x", "w_z"}
    row = found.set_index("channel").loc["w_x"]
    assert row["check"] == "saturation" and row["n"] == 8
    assert row["t_first"] == pytest.approx(times[0]) and row["t_last"] == pytest.approx(times[-1])
    assert "gyro w_x at its +-2000 deg/s limit" in row["message"]
    assert f"8 samples ({100 * 8 / len(imu):.2g} %) at 40.0 s" in row["message"]
    assert not imu_saturation(imu, pixhawk)[0].any()        # the clean record has none


def test_flat_top_without_a_known_range(recs):
    imu, _ = recs
    clipped, _ = _clip(imu, 40.0, 8)
    saturated, found = imu_saturation(clipped)                  # no preset, no log range
    assert np.count_nonzero(saturated) == 8
    assert found["check"].tolist() == ["flat top"]
    assert "flat at 2000 deg/s" in found["message"].iloc[0]
    both, _ = _clip(clipped, 60.0, 3, value=-LIMIT)
    saturated, found = imu_saturation(both)
    assert np.count_nonzero(saturated) == 11
    assert "flat at 2000 and -2000 deg/s: 11 samples" in found["message"].iloc[0]
    # a value repeated at a small extreme is quantisation, not a clip
    low, _ = _clip(imu, 40.0, 8, value=float(imu["w_x"].max()) + 0.1)
    assert not imu_saturation(low)[0].any()


def test_the_logs_range_overrides_the_preset(recs, pixhawk):
    imu, _ = recs
    clipped, _ = _clip(imu, 40.0, 5, value=1000.0 * DEG)
    clipped.attrs["range"] = {"gyro_rad_s": 1000.0 * DEG, "accel_m_s2": None}
    saturated, found = imu_saturation(clipped, pixhawk)
    assert np.count_nonzero(saturated) == 5
    assert "+-1000 deg/s limit: 5 samples" in found["message"].iloc[0]
    assert "(range from the log)" in found["message"].iloc[0]
    clipped.attrs["range"] = "1000 deg/s"
    with pytest.raises(NavlibInputError, match=r"imu.attrs\['range'\]"):
        imu_saturation(clipped, pixhawk)


def test_saturated_samples_are_dropped_and_too_many_refused(recs, pixhawk):
    imu, gnss = recs
    clipped, times = _clip(imu, 40.0, 8)
    checked = check_records(clipped, gnss, pixhawk, 2.0)
    assert len(checked.imu) == len(imu) - 8
    assert not np.isin(checked.imu["t"], times).any()
    assert checked.imu.attrs == clipped.attrs
    assert len(checked.gnss) == len(gnss)
    many, _ = _clip(imu, 40.0, int(0.06 * len(imu)))
    with pytest.raises(NavlibInputError, match=r"imu: 6 % of the samples are saturated"):
        check_records(many, gnss, pixhawk, 2.0)


def test_assessment_warns_and_fits_across_the_clipped_samples(recs):
    imu, gnss = recs
    clipped, times = _clip(imu, 40.0, 8)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = assess_flight(clipped, gnss, preset="pixhawk_mems")
    texts = [str(w.message) for w in caught]
    assert any("gyro w_x at its +-2000 deg/s limit: 8 samples" in m for m in texts)
    assert result.quality["check"].tolist() == ["saturation"]
    assert not np.isin(result.trajectory.t, times).any()
    # the fit bridges the dropped samples from their neighbours: the true rate there
    truth_rate = np.interp(times, result.trajectory.t, result.trajectory.angular_rate[:, 0])
    assert np.all(np.abs(truth_rate) < 50 * DEG)


# --------------------------------------------------------------------------- GNSS


def _frozen(gnss, t0, t1):
    out = gnss.copy()
    t = out["t"].to_numpy()
    k = int(np.searchsorted(t, t0))
    span = (t >= t0) & (t <= t1)
    for c in ("x", "y", "z"):
        out.loc[span, c] = out[c].iloc[k]
    return out, int(np.count_nonzero(span))


def test_frozen_fix_while_moving(recs):
    imu, gnss = recs
    frozen, n = _frozen(gnss, 40.0, 60.0)
    bad, found = gnss_faults(imu, frozen, 2.0)
    assert np.count_nonzero(bad) == n - 1                  # the first fix was real
    assert found["check"].tolist() == ["gnss frozen"]
    message = found["message"].iloc[0]
    assert "GNSS position frozen for 20 s at 40.0-60.0 s" in message
    assert "while the GNSS velocity reads" in message


def test_frozen_fix_without_velocity_columns(recs):
    imu, gnss = recs
    frozen, n = _frozen(gnss.drop(columns=["vx", "vy", "vz"]), 40.0, 60.0)
    bad, found = gnss_faults(imu, frozen, 2.0)
    assert np.count_nonzero(bad) == n - 1
    assert "the next fresh fix lies" in found["message"].iloc[0]


def test_frozen_fix_judged_by_the_gyros():
    """A car turning through the last 10 s of its record while the receiver repeats one
    position (no velocity columns, no fresh fix after): only the IMU can tell."""
    car = vehicles.car(duration_s=80.0)
    imu, gnss = records(car, seed=3)
    gnss = gnss[gnss["t"] <= 45.0].drop(columns=["vx", "vy", "vz"])
    frozen, n = _frozen(gnss, 35.0, 45.0)
    bad, found = gnss_faults(imu, frozen, 2.0)
    assert np.count_nonzero(bad) == n - 1
    assert "while the gyros read" in found["message"].iloc[0]


def test_repeated_fix_at_rest_is_not_a_fault(recs):
    imu, gnss = recs
    still, _ = _frozen(gnss, 1.0, 8.0)                    # on the pads until 10 s
    bad, found = gnss_faults(imu, still, 2.0)
    assert not bad.any() and found.empty


def _with_baro(imu, truth):
    """The true height (300 m off, a barometer's own zero) as ``attrs["baro"]`` at 10 Hz."""
    _, _, h = earth.ecef_to_geodetic(truth.position[::25])
    out = imu.copy()
    out.attrs = dict(imu.attrs)
    out.attrs["baro"] = pd.DataFrame({"t": truth.t[::25], "alt_m": h - 300.0})
    return out


def _drift(gnss, from_s, rate_m_s):
    out = gnss.copy()
    P = out[["x", "y", "z"]].to_numpy()
    up = P[0] / np.linalg.norm(P[0])
    dz = rate_m_s * np.clip(out["t"].to_numpy() - from_s, 0.0, None)
    out[["x", "y", "z"]] = P + dz[:, None] * up
    return out


def test_gnss_altitude_against_the_barometer(truth, recs):
    imu, gnss = recs
    baro_imu = _with_baro(imu, truth)
    bad, found = gnss_faults(baro_imu, gnss, 2.0)
    assert not bad.any() and found.empty                    # agreeing: nothing
    late = _drift(gnss, 70.0, 1.5)                          # 30 m over the last 20 s
    bad, found = gnss_faults(baro_imu, late, 2.0)
    assert found["check"].tolist() == ["gnss altitude"]
    t_bad = late["t"].to_numpy()[bad]
    assert t_bad.min() > 70.0 and bad.sum() > 30
    assert found["message"].iloc[0].endswith("excluded")
    assert "disagrees with the barometer" in found["message"].iloc[0]
    # a drift over most of the flight is reported, not excluded: which sensor is wrong?
    early = _drift(gnss, 10.0, 1.0)
    bad, found = gnss_faults(baro_imu, early, 2.0)
    assert not bad.any()
    assert "kept: more than 25 % of the fixes disagree" in found["message"].iloc[0]


def test_gnss_jump(recs):
    imu, gnss = recs
    bad, found = gnss_faults(imu, gnss, 2.0)
    assert not bad.any() and found.empty                    # no false alarm on clean fixes
    jumped = gnss.copy()
    k = int(np.searchsorted(jumped["t"].to_numpy(), 50.0))
    jumped.loc[k, "x"] += 40.0
    bad, found = gnss_faults(imu, jumped, 2.0)
    assert np.flatnonzero(bad).tolist() == [k]
    assert found["check"].tolist() == ["gnss jump"]
    assert "at 50.0 s" in found["message"].iloc[0]


def test_too_much_faulty_time_refused_saying_how_to_change_the_threshold(recs, pixhawk):
    imu, gnss = recs
    frozen, _ = _frozen(gnss, 15.0, 80.0)       # 65 of the record's 90 s
    with pytest.raises(NavlibInputError, match=(
            r"gnss: faulty fixes cover 65 s of the GNSS record's 90 s \(72.2 %: 65 s of "
            r"excluded fixes\), leaving 25 s usable; .*max_faulty_time_fraction = 0.5; .*"
            r"-p quality_thresholds '\{\"gnss\": \{\"max_faulty_time_fraction\": 0.8\}\}'"
            r".*GNSS position frozen for 65 s")):
        check_records(imu, frozen, pixhawk, 2.0)
    checked = check_records(imu, frozen, pixhawk, 2.0,
                            {"gnss": {"max_faulty_time_fraction": 0.8}})
    assert len(checked.gnss) == len(gnss) - (np.count_nonzero(
        (gnss.t >= 15.0) & (gnss.t <= 80.0)) - 1)


def test_faulty_gnss_is_measured_by_time_not_rows(recs, pixhawk):
    """A receiver logged at 20 Hz while frozen for 20 s (400 rows) among 5 Hz fixes: most of
    the rows are faulty, a fifth of the time is; the flight is kept, the stretch dropped."""
    imu, gnss = recs
    t = gnss["t"].to_numpy()
    frozen_t = np.arange(40.0, 60.0, 0.05)
    inside = (t >= 40.0) & (t < 60.0)
    k = int(np.flatnonzero(inside)[0])
    fast = pd.DataFrame({c: np.interp(frozen_t, t, gnss[c]) for c in gnss.columns})
    fast[["x", "y", "z"]] = gnss[["x", "y", "z"]].iloc[k].to_numpy()
    fast["t"] = frozen_t
    record = pd.concat([gnss[~inside], fast]).sort_values("t").reset_index(drop=True)
    rows_bad = len(fast) - 1
    assert rows_bad / len(record) > 0.5                 # most rows repeat the frozen fix
    checked = check_records(imu, record, pixhawk, 2.0)
    assert len(checked.gnss) == len(record) - rows_bad
    assert "GNSS position frozen for 19.9 s" in checked.warnings[0]


def test_assessment_excludes_a_frozen_span(recs):
    imu, gnss = recs
    frozen, n = _frozen(gnss, 40.0, 60.0)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = assess_flight(imu, frozen)
    assert any("GNSS position frozen for 20 s" in str(w.message) for w in caught)
    assert len(result.gnss_residuals) == len(gnss) - (n - 1)
    assert result.gnss_residuals["d3"].max() < 15.0          # the fit follows the fresh fixes
    assert result.vehicle == "multicopter"


def test_a_short_barometer_record_is_said_not_taken_for_a_disagreement(truth, recs):
    imu, gnss = recs
    short = _with_baro(imu, truth)
    baro = short.attrs["baro"]
    short.attrs["baro"] = baro[baro["t"] <= 14.0]
    climbing = _drift(gnss, 20.0, 1.0)                       # 70 m after the barometer ends
    bad, found = gnss_faults(short, climbing, 2.0)
    assert not bad.any()
    assert found["channel"].tolist() == ["barometer coverage"]
    assert "covers only 0.0-14.0 s of the GNSS span 0.0-90.0 s (16 %)" in \
        found["message"].iloc[0]


def test_sounding_rocket_with_a_frozen_receiver_keeps_its_phases():
    """A real receiver's failure: a receiver repeating one position for 26 s with a valid fix near
    apogee gave a second "powered" phase. Found by the spin the gyros read, dropped, and the
    phases are the paper's again; with the check switched off they are not."""
    from navlib import io

    sample = Path(__file__).resolve().parents[2] / "data" / "sample_flight"
    imu, gnss = io.read_imu_csv(sample / "imu.csv"), io.read_gnss_csv(sample / "gnss.csv")
    frozen, _ = _frozen(gnss.drop(columns=["vx", "vy", "vz"]), 50.0, 76.0)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = assess_flight(imu, frozen)
        blind = assess_flight(imu, frozen,
                              quality_thresholds={"gnss": {"frozen_min_duration_s": 1e6}})
    assert any("GNSS position frozen for 26 s at 50.0-76.0 s" in str(w.message)
               and "the gyros read" in str(w.message) for w in caught)
    assert result.segment_table["phase"].tolist() == ["pad", "boost", "coast", "free_fall"]
    assert blind.segment_table["phase"].tolist().count("boost") > 1


def test_the_old_faulty_share_key_is_read_under_its_new_name():
    with pytest.warns(DeprecationWarning, match=r"\[gnss\] max_excluded_fraction is now "
                                                r"max_faulty_time_fraction"):
        p = load_thresholds({"gnss": {"max_excluded_fraction": 0.7}})
    assert p["gnss"]["max_faulty_time_fraction"] == 0.7
    assert "max_excluded_fraction" not in p["gnss"]


@given(st.floats(-1.9, 1.9), st.floats(0.1, 100.0))
def test_grid_minimum_is_the_vertex_of_a_parabola(c, k):
    """On a quadratic the parabola through the grid minimum and its neighbours is the
    quadratic itself: its vertex is found exactly, wherever it lies between grid points."""
    x = 0.05 * np.arange(-40, 41)
    assert grid_minimum(x, k * (x - c) ** 2 + 3.0) == pytest.approx(c, abs=1e-9)


def test_grid_minimum_at_an_edge_is_the_edge():
    x = np.linspace(-2.0, 2.0, 41)
    assert grid_minimum(x, x) == -2.0


@pytest.mark.parametrize("lag_s", [0.0, 1.5])
def test_a_slow_vehicle_shows_no_gnss_lag_against_its_barometer(truth, recs, lag_s):
    """A multicopter survey (climbs of a few m/s): its GNSS altitude against the barometer
    is noise; moved back by any lag within the scan it changes by less than the GNSS sigma,
    so no lag is read into it, stamped late or not (FIT6)."""
    imu, gnss = recs
    rng = np.random.default_rng(3)
    _, _, h = truth.geodetic
    imu = imu.copy()
    imu.attrs = {**imu.attrs, "baro": pd.DataFrame({"t": truth.t, "alt_m": h + rng.normal(
        0.0, 0.3, h.size)})}
    late = gnss.assign(t=gnss["t"] + lag_s)
    lag, rows = baro_lag(imu, late, sigma_m=5.0)
    assert lag == 0.0 and rows == []

