"""Generated readings (navlib.studies.design, .plan, .outliers): every number in the text
comes from the table."""

from types import SimpleNamespace

import numpy as np
import pandas as pd

from navlib.studies.design import (
    observability_grid_reading,
    sensability_grid_reading,
    with_gyro_observability,
)
from navlib.studies.outliers import ekf_sigma_agreement
from navlib.studies.plan import timeline_reading, trade_reading


def _rocket_grid():
    rows = []
    for spin in (1.0, 2.0):
        for sigma_sg in (300.0, 3000.0):
            for gnss in (2.0, 10.0):
                rows.append({"spin_hz": spin, "sigma_sg_ppm": sigma_sg, "gnss_sigma_m": gnss,
                             "s_frac_sg_x": 0.8 if sigma_sg > 1000 and spin > 1.5 else 0.1,
                             "ratio_sg_x": sigma_sg / 100.0, "s_end_roll": spin / 2.0,
                             "sigma_end_roll_deg": gnss / spin})
    return pd.DataFrame(rows)


def test_sensability_grid_reading_counts_cells_and_points():
    text = sensability_grid_reading(_rocket_grid()).splitlines()
    assert text[0].startswith("sg_x is sensible on at least half of the epochs")
    assert "in 1 of 4 cells" in text[0]
    assert " ".join(text[1:3]).split() == ["spin_hz", "2.0", "3000.0"]  # smallest per spin
    assert "ranges 3.00 .. 30.00" in text[3]
    assert text[4].startswith("roll axis sensible at the end in 4 of 8 points")
    assert "spans 1.0 .. 10.0 deg" in text[4]
    none = sensability_grid_reading(_rocket_grid().assign(s_frac_sg_x=0.0))
    assert none.splitlines()[0] == "sg_x is sensible on half of the epochs in no cell of this grid"


def test_gyro_observability_and_its_reading():
    grid = pd.DataFrame({
        "solution": ["ins_gps", "ins_gps", "ins_gps_att", "ins_gps_att"],
        "bias_model": ["markov", "markov", "markov", "markov"], "biases": ["G", "GAP"] * 2,
        "n_unobservable": [0, 2, 0, 0], "log10_cond": [5.0, 9.0, 4.0, 4.2],
        "unobs_bg_x": [1e-12, 0.3, 0.0, 0.0], "unobs_bg_y": [0.0, 1e-9, 0.0, 0.0],
        "unobs_bg_z": [0.0, 0.0, 2e-7, 0.0]})
    table = with_gyro_observability(grid)
    assert list(table.gyro_unobservable_share) == [1e-12, 0.3, 2e-7, 0.0]
    assert list(table.gyro_observable) == [True, False, True, True]
    assert "gyro_observable" not in grid  # the input is left as it was
    lines = observability_grid_reading(table).splitlines()
    assert lines[0].startswith("gyro biases observable (rank, mid-mission) in 1 of 2 ")
    assert lines[1] == ("median log10 cond over the bias sets: best ('ins_gps_att', 'markov') "
                        "(4.1), worst ('ins_gps', 'markov') (7.0)")
    assert lines[2] == ("ins_gps, markov, GAP: 2 unobservable state(s), gyro-bias share in the "
                        "null space 3.0e-01")


def test_timeline_and_trade_readings():
    timeline = pd.DataFrame({"state": ["P_x", "V_x", "bg_x", "sg_x"],
                             "group": ["position", "velocity", "gyro_bias", "gyro_scale"],
                             "sensible_from_s": [1.0, 2.5, 30.0, np.nan],
                             "sensible_share": [0.9, 0.8, 0.2, 0.0],
                             "sensible_share_outage": [0.25, 0.1, 0.0, 0.0]})
    plans = {"calm": SimpleNamespace(timeline=lambda: timeline, outages=()),
             "outage": SimpleNamespace(timeline=lambda: timeline, outages=((10.0, 20.0),))}
    lines = timeline_reading(plans).splitlines()
    assert lines[0] == ("calm: 3 of 4 states become sensible at some epoch; last to do so: "
                        "P_x at 1.0 s, V_x at 2.5 s, bg_x at 30.0 s; never: sg_x")
    assert lines[2] == ("    inside the outage(s) the position states are sensible at 25% of "
                        "the epochs against 90% over the mission")
    trade = pd.DataFrame({"sensors_preset": ["a", "b"], "sigma_end_theta_z": [2e-3, 1e-3],
                          "n_sensible_end": [5, 7]})
    assert trade_reading(trade) == ("smallest final heading-axis sigma: b (0.001 rad); states "
                                    "sensible at the end per preset: a 5, b 7")


def test_ekf_sigma_agreement_leaves_out_the_start():
    frame = pd.DataFrame({"t": [0.5, 2.0, 3.0, 2.0, 3.0], "axis": ["roll", "roll", "roll",
                                                                  "pos_x", "pos_x"],
                          "sigma_ekf": [9.0, 1.1, 0.9, 2.0, 2.0],
                          "sigma_cov": [1.0, 1.0, 1.0, 2.0, 2.0],
                          "error": [100.0, 1.1, -0.9, 2.0, -2.0]})
    table = ekf_sigma_agreement(frame)
    assert list(table.index) == ["roll", "pos_x"]
    assert np.allclose(table.sigma_ratio_max_dev, [0.1, 0.0])
    assert np.allclose(table.rms_normalised_error, [1.0, 1.0])
