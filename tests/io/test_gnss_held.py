"""A GNSS receiver that froze: its rows repeat one fix (held), logged faster than its fresh
fixes (the PSAS L-12 flight: 26 s frozen in boost at 20 Hz, 57.6 % of the rows). Read from a
CSV file, the held rows are dropped with their count and lines, the flight is assessed with
the frozen stretch as a GNSS outage; a receiver frozen over most of the record is refused by
the time it covers, saying how to accept more (assumptions Q4, Q7)."""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pytest
from support.flights import multicopter, records

from navlib import NavlibInputError, io
from navlib.io import quality
from navlib.studies.assess import assess_flight


@pytest.fixture(scope="module")
def recs():
    return records(multicopter(duration_s=90.0))


def _frozen_csv(folder, imu, gnss, t0, t1, rate_hz=20.0):
    """``imu.csv,gnss.csv`` with the fix at ``t0`` repeated at ``rate_hz`` until ``t1``."""
    t = gnss["t"].to_numpy()
    k = int(np.searchsorted(t, t0))
    held_t = np.arange(t[k], t1, 1.0 / rate_hz)
    held = pd.DataFrame(np.repeat(gnss.iloc[[k]].to_numpy(), held_t.size, axis=0),
                        columns=gnss.columns).assign(t=held_t)
    out = pd.concat([gnss[(t < t[k]) | (t >= t1)], held]).sort_values("t")
    imu_path = io.write_imu_csv(imu, folder / "imu.csv")
    gnss_path = io.write_gnss_csv(out.reset_index(drop=True), folder / "gnss.csv")
    return f"{imu_path},{gnss_path}", held_t.size - 1, len(out)


def test_frozen_stretch_is_an_outage_of_an_assessed_flight(recs, tmp_path):
    imu, gnss = recs
    log, n_held, n_rows = _frozen_csv(tmp_path, imu, gnss, 30.0, 56.0)
    assert n_held / n_rows > 0.5                        # most rows are the frozen fix
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        imu_r, gnss_r = io.read_log(log)
        result = assess_flight(imu_r, gnss_r)
    texts = [str(w.message) for w in caught]
    assert any(f"{n_held} of {n_rows} GNSS rows repeat the previous row's fix exactly (a fix "
               "held between the receiver's updates; the longest hold 26 s), at line" in m
               for m in texts), texts
    outage = result.gnss_outages
    assert len(outage) == 1
    assert outage.t_start.iloc[0] == pytest.approx(30.0, abs=0.3)
    assert outage.t_end.iloc[0] == pytest.approx(56.0, abs=0.3)


def test_receiver_frozen_over_most_of_the_record_is_refused_by_time(recs, tmp_path):
    imu, gnss = recs
    log, _, _ = _frozen_csv(tmp_path, imu, gnss, 10.0, 80.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", io.FlightDataWarning)
        imu_r, gnss_r = io.read_log(log)
        with pytest.raises(NavlibInputError, match=(
                r"gnss: faulty fixes cover 70 s of the GNSS record's 90 s \(77.7 %: 70 s of 1 "
                r"fix\(es\) held at least 2 s while the vehicle moved \(the longest 70 s from "
                r"10.0 s\)\), leaving 20 s usable; .* -p quality_thresholds "
                r".*max_faulty_time_fraction.: 0.85")):
            assess_flight(imu_r, gnss_r)


def test_a_hold_at_rest_is_no_fault_a_hold_in_motion_is(recs, tmp_path):
    """8 s of one fix repeated on the pad (the vehicle still: the repeats may be the truth)
    count as no faulty time; 8 s repeated in flight do (a 5 % threshold shows it), told by
    the next fresh fix 50 m away where the IMU alone cannot (a steady circle: 1.2 deg/s)."""
    imu, gnss = recs
    strict = {"gnss": {"max_faulty_time_fraction": 0.05}}
    for t0, refused in ((1.0, False), (40.0, True)):
        folder = tmp_path / f"t{t0:g}"
        folder.mkdir()
        log, _, _ = _frozen_csv(folder, imu, gnss, t0, t0 + 8.0)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", io.FlightDataWarning)
            imu_r, gnss_r = io.read_log(log)
            if refused:
                with pytest.raises(NavlibInputError, match=r"held at least 2 s while the "
                                                           r"vehicle moved"):
                    quality.check_records(imu_r, gnss_r, thresholds=strict)
            else:
                checked = quality.check_records(imu_r, gnss_r, thresholds=strict)
                assert len(checked.gnss) == len(gnss_r)
