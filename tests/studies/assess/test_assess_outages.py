"""The assessment's model aids its epochs with the GNSS fixes that exist and were kept
(docs/assumptions.md Q5): gaps and dropped fixes are outages, sensability falls inside
them, long ones are named; and the flight figure that shows them."""

from __future__ import annotations

import warnings
from dataclasses import replace

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest
from support.flights import multicopter, records
from support.locations import shared_file

from navlib import earth, io
from navlib.errors import NavlibInputError
from navlib.metrics import S_THRESHOLD
from navlib.models.ecef import ecef21_at_epochs, epoch_samples
from navlib.plots.assess import flight_figure
from navlib.studies.assess import assess_flight
from navlib.studies.assess.outages import gnss_outages, measured_epochs
from navlib.trajectory import stationary

OUTAGE = (30.0, 56.0)
"""The generated outage: no fix strictly between these times (26 s, in the survey)."""
FROZEN = (70.0, 76.0)
"""A held position: the fixes in this window repeat the one at its start."""


@pytest.fixture(scope="module")
def flight():
    truth = multicopter(90.0, 100.0, pad_s=10.0)
    imu, gnss = records(truth, seed=3, gnss_rate_hz=5.0)
    _, _, alt = earth.ecef_to_geodetic(truth.position[::10])
    imu.attrs["baro"] = pd.DataFrame({"t": truth.t[::10], "alt_m": alt - 47.0})
    return imu, gnss


def _assess(imu, gnss):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return assess_flight(imu, gnss, preset="pixhawk_mems")


@pytest.fixture(scope="module")
def with_outage(flight):
    imu, gnss = flight
    t = gnss["t"].to_numpy()
    cut = gnss[(t <= OUTAGE[0]) | (t >= OUTAGE[1])].reset_index(drop=True)
    held = (cut["t"] > FROZEN[0]) & (cut["t"] < FROZEN[1])
    first = int(np.flatnonzero(cut["t"] >= FROZEN[0])[0])
    cut.loc[held, ["x", "y", "z"]] = cut.loc[first, ["x", "y", "z"]].to_numpy(dtype=float)
    return _assess(imu, cut)


def _position_s(result):
    se = result.sensability
    cols = [result.state_names.index(n) for n in ("P_x", "P_y", "P_z")]
    return se.t, se.s[:, cols].min(axis=1)


def test_each_kept_fix_aids_the_epoch_nearest_it():
    epochs = np.arange(11.0)
    fixes = np.r_[np.arange(0.0, 3.05, 0.1), np.arange(7.0, 10.05, 0.1)]   # 3..7 s missing
    assert measured_epochs(epochs, fixes).tolist() == [True] * 4 + [False] * 3 + [True] * 4
    # fixes half-way between epochs: each aids one epoch, none aids two
    assert measured_epochs(epochs, epochs[:-1] + 0.5).sum() == 10
    # a fix far outside the epochs aids none
    assert not measured_epochs(epochs, [-3.0, 14.0]).any()


def test_epochs_are_a_grid_in_time_whatever_the_log_rate():
    uniform = np.arange(0.0, 10.0 + 1e-9, 0.01)
    assert epoch_samples(uniform, 1.0).tolist() == list(range(0, 1001, 100))
    # 100 Hz, then 10 Hz (an AltOS export in descent): still one epoch a second
    slowing = np.r_[np.arange(0.0, 2.0, 0.01), np.arange(2.0, 6.0 + 1e-9, 0.1)]
    assert slowing[epoch_samples(slowing, 1.0)] == pytest.approx(np.arange(7.0))
    # a grid finer than the samples takes each sample once
    assert np.all(np.diff(epoch_samples(slowing, 20.0)) >= 1)


def test_model_at_given_epochs_matches_the_sample_grid():
    traj = stationary(duration_s=6.0, rate_hz=50.0)
    grid = ecef21_at_epochs(traj, 1.0)
    given = ecef21_at_epochs(traj, 1.0, epochs=tuple(range(0, 301, 50)))
    assert given.t.tolist() == grid.t.tolist()
    np.testing.assert_allclose(given.F, grid.F, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(given.Q, grid.Q, rtol=1e-12, atol=1e-30)
    for bad in ([3], [0, 0, 5], [0, 400], [0.0, 50.0]):
        with pytest.raises(NavlibInputError, match="epochs:"):
            ecef21_at_epochs(traj, 1.0, epochs=bad)


def test_outages_are_the_long_spans_without_a_fix():
    got = gnss_outages([2.0, 3.0, 4.0, 20.0, 21.0], 0.0, 30.0, 5.0)
    assert got.to_dict("list") == {"t_start": [4.0, 21.0], "t_end": [20.0, 30.0],
                                   "duration": [16.0, 9.0]}
    assert gnss_outages([2.0, 3.0], 0.0, 6.0, 5.0).empty


def test_gap_and_held_fixes_are_outages_on_the_result(with_outage):
    outages = with_outage.gnss_outages
    assert len(outages) == 2
    first, second = outages.itertuples(index=False)
    assert (first.t_start, first.t_end) == pytest.approx(OUTAGE, abs=1e-6)
    assert first.duration == pytest.approx(26.0, abs=1e-6)
    # the held fixes after the first one of the window were dropped by the quality check
    assert second.t_start == pytest.approx(FROZEN[0], abs=0.21)
    assert second.t_end == pytest.approx(FROZEN[1], abs=0.21)
    note = next(n for n in with_outage.notes if "GNSS outage" in n)
    assert "30..56 s (26 s)" in note
    t = np.asarray(with_outage.model.t)
    measured = np.any(np.asarray(with_outage.model.H) != 0.0, axis=(1, 2))
    assert not measured[(t > OUTAGE[0] + 0.2) & (t < OUTAGE[1] - 0.2)].any()
    assert measured[(t < OUTAGE[0] - 0.2) | ((t > OUTAGE[1] + 0.2) & (t < FROZEN[0]))].all()
    # the segment table counts the measured epochs only, and a segment given inside the
    # outage is refused
    table = with_outage.segment_table
    row = table[(table["t_start"] < 40.0) & (table["t_end"] > 40.0)].iloc[0]
    inside = min(row.t_end, OUTAGE[1]) - max(row.t_start, OUTAGE[0])
    assert row.n_epochs <= (row.duration - inside) * 5.0 + 2
    with pytest.raises(NavlibInputError, match="segment 2"):
        with_outage.with_settings([(0.0, 35.0), (35.0, 50.0), (50.0, 90.0)])


def test_position_sensability_falls_inside_the_outage(flight, with_outage):
    t, s = _position_s(with_outage)
    before = s[(t > OUTAGE[0] - 5.0) & (t <= OUTAGE[0])]
    inside = s[(t > OUTAGE[0]) & (t < OUTAGE[1])]
    assert before.min() >= S_THRESHOLD
    assert inside.min() < S_THRESHOLD
    assert inside.min() < before.min() - 0.1
    # with every fix at the nominal rate, position stays sensible through the same window
    t_all, s_all = _position_s(_assess(*flight))
    assert s_all[(t_all > OUTAGE[0]) & (t_all < OUTAGE[1])].min() >= S_THRESHOLD


def test_flight_figure_shows_the_records_and_marks(with_outage):
    table = with_outage.segment_table.copy()
    table["represented"] = [k != 1 for k in range(len(table))]
    table["fit_reason"] = ["" if k != 1 else "axis convention" for k in range(len(table))]
    fig = flight_figure(replace(with_outage, segment_table=table))
    assert len(fig.axes) == 6
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert "reference" in labels and "GNSS (kept fixes)" in labels
    baro = next(label for label in labels if label.startswith("barometer"))
    # the median offset to the reference: the 47 m given, within the fit's height error
    assert float(baro.split()[1]) == pytest.approx(47.0, abs=2.0)
    assert "GNSS outage (no kept fix)" in labels
    assert "segment the fit does not represent" in labels
    # a short mark on the panel (the reasons are in the segment table and the warnings: a
    # long reason once squeezed the panels into a third of the figure's width)
    assert [t.get_text() for t in fig.axes[0].texts].count("not represented") == 1
    fig.canvas.draw()
    assert all(ax.get_position().width > 0.6 for ax in fig.axes)
    hatched = [p for p in fig.axes[3].patches if p.get_hatch() == "xx"]
    assert len(hatched) == len(with_outage.gnss_outages)
    plt.close(fig)
    # without the columns of the fit check, nothing is marked as unrepresented
    fig = flight_figure(with_outage)
    assert not [p for p in fig.axes[0].patches if p.get_hatch() == "////"]
    plt.close(fig)
    # a flight without GNSS: its position rows are the barometer's, and say so
    options = {**with_outage.options, "aiding": "baro"}
    fig = flight_figure(replace(with_outage, options=options))
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert "baro rows (kept fixes)" in labels and "GNSS (kept fixes)" not in labels
    assert fig.axes[3].get_ylabel() == "baro rows − ref [m]"
    plt.close(fig)


def test_altos_descent_at_10_hz_keeps_one_epoch_a_second():
    path = shared_file("altos", "2019-05-26-serial-1257-flight-0018.csv")
    imu, gnss = io.read_altos(path)
    result = _assess(imu, gnss)
    t = np.asarray(result.model.t)
    assert np.diff(t).max() == pytest.approx(1.0, abs=0.11)      # the IMU logs 10 Hz late
    t_fix = result.gnss_residuals["t"].to_numpy()          # the fixes the checks kept
    measured = np.any(np.asarray(result.model.H) != 0.0, axis=(1, 2))
    # every epoch with a kept fix within half a second is measured, and only those (over the
    # residuals' fixes, those inside the reference: a fix just after its end aids the last
    # epoch, measured_epochs)
    near = np.array([np.min(np.abs(t_fix - x)) <= 0.5 for x in t])
    inside = t <= t_fix[-1] + 0.5
    assert np.array_equal(measured[inside], near[inside])
    # the fixes trail the barometer by about half a second (FIT6): moved back by the lag,
    # the boost fixes agree with the barometer and aid the model; without the lag they were
    # excluded as disagreeing with it and the boost was a 6.8 s outage
    lag = result.quality[result.quality["check"] == "gnss lag"]
    assert len(lag) == 1 and "trail the barometer by 0." in lag["message"].iloc[0]
    assert measured[t < 3.0].sum() >= 2
    assert result.gnss_outages.empty or result.gnss_outages["t_start"].iloc[0] > 3.0
