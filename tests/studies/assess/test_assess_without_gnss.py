"""Flights without GNSS through ``python -m navlib assess``: a simulated high-power
rocket's IMU with a barometer made from its heights, and the shared FIRM and CATS Vega flights
(assumptions B1-B5)."""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pytest
from support.flights import exact_records, records
from support.locations import REPO

from navlib.__main__ import main
from navlib.earth import ecef_to_geodetic
from navlib.io import write_imu_csv
from navlib.io.baro import ISA_EXPONENT, ISA_LAPSE_K_M, ISA_P0_PA, ISA_T0_K
from navlib.studies.assess import assess_flight
from navlib.trajectory.mission import from_mission

ROCKETS = next((p for p in (REPO.parent / "shared", REPO.parents[1] / "shared")
                if p.is_dir()), REPO.parent / "shared") / "data" / "rockets"
FIRM_LOG = ROCKETS / "firm_jackpot3" / "jackpot_launch_3.csv"
CATS_LOG = ROCKETS / "hedy_cats_vega" / "imu.csv"


def _hpr_records(folder):
    """``imu.csv`` and ``baro.csv`` of the simulated high-power rocket (2 s on the pad, apogee
    near 940 m): the barometer is the standard-atmosphere pressure of the GNSS heights."""
    imu, gnss = records(from_mission("hpr_rocket"), seed=3)
    imu_path = write_imu_csv(imu, folder / "imu.csv")
    _, _, h = ecef_to_geodetic(gnss[["x", "y", "z"]].to_numpy())
    p = ISA_P0_PA * (1.0 - h * ISA_LAPSE_K_M / ISA_T0_K) ** (1.0 / ISA_EXPONENT)
    baro_path = folder / "baro.csv"
    pd.DataFrame({"time": gnss.t, "pressure [hPa]": p / 100.0}).to_csv(baro_path, index=False)
    return imu_path, baro_path


def _row(tmp_path, logs):
    out = tmp_path / "fleet"
    status = main(["assess", *logs, "--output", str(out), "--scheduler", "synchronous"])
    table = pd.read_csv(out / "summary.csv", keep_default_na=False)
    return status, table, out


def test_imu_and_barometer_pair_is_assessed_with_baro_aiding(tmp_path):
    imu, baro = _hpr_records(tmp_path)
    status, table, out = _row(tmp_path, [f"{imu},{baro}"])
    row = table.iloc[0]
    assert status == 0 and row.status == "ok" and row.aiding == "baro"
    page = (out / row.page).read_text(encoding="utf-8")
    assert "horizontal position and velocity are unobservable" in page


@pytest.mark.skipif(not (FIRM_LOG.is_file() and CATS_LOG.is_file()),
                    reason=f"shared rocket logs absent ({ROCKETS})")
def test_shared_firm_and_cats_flights_are_assessed(tmp_path):
    status, table, _ = _row(tmp_path, [str(FIRM_LOG), str(CATS_LOG)])
    assert status == 0 and table.status.tolist() == ["ok", "ok"]
    assert table.aiding.tolist() == ["baro", "gnss+baro"]
    assert table.vehicle.tolist() == ["rocket", "rocket"]
    assert "boost" in table.phases.iloc[0] and "descent" in table.phases.iloc[1]


@pytest.mark.parametrize("gaps", [(1068.0,), (3246.0, 1068.0)])
def test_pre_launch_buffer_before_a_long_gap_is_split_off_with_a_note(tmp_path, gaps):
    """Pre-launch buffers of 1.5 s on the pad, each followed by a long gap (the 1068 s and
    3246 s met on real logs), before the flight's record: split off with a note, the flight
    assessed on its own clock."""
    imu_path, baro_path = _hpr_records(tmp_path)
    imu, baro = pd.read_csv(imu_path), pd.read_csv(baro_path)
    imu_parts, baro_parts, shift = [], [], 0.0
    for gap in gaps:
        imu_parts.append(imu.iloc[:150].assign(**{imu.columns[0]: imu.iloc[:150, 0] + shift}))
        baro_parts.append(baro.iloc[:8].assign(**{baro.columns[0]: baro.iloc[:8, 0] + shift}))
        shift += gap
    imu.iloc[:, 0] += shift
    baro.iloc[:, 0] += shift
    pd.concat([*imu_parts, imu]).to_csv(imu_path, index=False)
    pd.concat([*baro_parts, baro]).to_csv(baro_path, index=False)
    status, table, _ = _row(tmp_path, [f"{imu_path},{baro_path}"])
    row = table.iloc[0]
    assert status == 0 and row.aiding == "baro"
    spans = len(gaps) + 1
    assert f"split into {spans} spans" in row.warnings, row.warnings
    assert row.warnings.count("(no barometer reference rows in this span (0): a piece of "
                              "the record the barometer aiding could not level") == len(gaps)
    assert row.phases.startswith("pad ")          # on the clock since ignition
    assert row.t_ignition > shift


def test_barometer_rows_are_weighed_at_the_reference_speed():
    """B7: a barometer whose static-pressure error jumps on at the highest speed (a port 5
    times worse than the declared coefficient, up to 96 m low for 4 s) also reads a climb
    rate 90 m/s too low there, so weighing its rows by its own climb rate trusted them most
    where they were worst and bent the reference 15 m off the truth. Weighed at the
    reference's climb rate the reference stays within 5 m, and the segments the rows miss
    name the barometer at high dynamic pressure."""
    truth = from_mission("hpr_rocket")
    imu, _ = exact_records(truth, sigma_f=0.05, sigma_w=0.002, seed=1)
    imu = imu[imu["t"] <= 40.0].reset_index(drop=True)
    _, _, h = ecef_to_geodetic(truth.position)
    v = np.linalg.norm(truth.velocity, axis=1)
    fast = (truth.t >= truth.t[np.argmax(v)]) & (v > 0.6 * v.max())
    fault = np.where(fast, -0.1 * v**2 / (2.0 * 9.80665), 0.0)
    imu.attrs = {"baro": pd.DataFrame({"t": truth.t, "alt_m": h + fault})}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = assess_flight(imu, None, preset="pixhawk_mems", vehicle="rocket")
    traj = result.trajectory
    k = np.searchsorted(truth.t, traj.t + result.options["t_zero"])
    _, _, h_ref = ecef_to_geodetic(traj.position)
    assert np.abs(h_ref - h[k]).max() < 5.0
    assert "baro_dynamic_m" in result.gnss_residuals
    missed = result.segment_table[~result.segment_table["represented"]]
    assert len(missed) and missed["fit_reason"].str.contains(
        "barometer at high dynamic pressure").all()
