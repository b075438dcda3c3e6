"""Tests for navlib.segmentation: phases of synthetic flights, hysteresis, user edits."""

import numpy as np
import pandas as pd
import pytest
from scipy.integrate import cumulative_simpson

from navlib import earth
from navlib.errors import NavlibInputError
from navlib.segmentation import (
    PHASES,
    SEGMENT_DEFAULTS,
    flight_features,
    segment_flight,
    segments_table,
)
from navlib.trajectory import build_trajectory, launcher_ascent, sounding_rocket, stationary
from navlib.units import DEG


def ground_vehicle(accel, yaw_rate, duration_s=30.0, rate_hz=100.0, lat_deg=45.0):
    """Level ground vehicle: body x along the heading, speed and heading from the callables
    ``accel(t)`` (m/s^2, along track; integrated, clipped at rest) and ``yaw_rate(t)`` (rad/s).

    Returns a Trajectory with an exact IMU (flat local frame over the few hundred metres).
    """
    t = np.arange(0.0, duration_s + 0.5 / rate_hz, 1.0 / rate_hz)
    a_along = accel(t)
    speed = cumulative_simpson(a_along, x=t, initial=0.0)
    a_along = np.where(speed > 0, a_along, 0.0)
    speed = np.maximum(speed, 0.0)
    r = yaw_rate(t)
    psi = cumulative_simpson(r, x=t, initial=0.0)
    lat, lon = lat_deg * DEG, 10.0 * DEG
    C_n_e = earth.ned_to_ecef_matrix(lat, lon)
    heading = np.column_stack([np.cos(psi), np.sin(psi), np.zeros_like(t)])
    left = np.column_stack([-np.sin(psi), np.cos(psi), np.zeros_like(t)])
    v_n = speed[:, None] * heading
    a_n = a_along[:, None] * heading + (speed * r)[:, None] * left
    p_n = np.column_stack([cumulative_simpson(v_n[:, i], x=t, initial=0.0) for i in range(3)])
    P = earth.geodetic_to_ecef(lat, lon, 100.0) + p_n @ C_n_e.T
    c, s = np.cos(psi), np.sin(psi)
    C_b_n = np.zeros((t.size, 3, 3))
    C_b_n[:, 0, 0], C_b_n[:, 0, 1], C_b_n[:, 1, 0], C_b_n[:, 1, 1] = c, -s, s, c
    C_b_n[:, 2, 2] = 1.0
    w_eb_b = np.column_stack([np.zeros_like(t), np.zeros_like(t), r])
    return build_trajectory(t, P, v_n @ C_n_e.T, a_n @ C_n_e.T, C_n_e @ C_b_n, w_eb_b,
                            name="ground vehicle")


def window(t, start, end, value):
    """``value`` inside ``[start, end)``, 0 outside."""
    return np.where((t >= start) & (t < end), value, 0.0)


@pytest.fixture(scope="module")
def rocket():
    return sounding_rocket()


@pytest.fixture(scope="module")
def car():
    """Rest 0-5 s, 2.5 m/s^2 to 10 m/s (5-9 s), cruise, a 90-deg left turn (15-24 s)."""
    return ground_vehicle(lambda t: window(t, 5.0, 9.0, 2.5),
                          lambda t: window(t, 15.0, 24.0, 10.0 * DEG))


def test_sounding_rocket_pad_boost_coast_free_fall(rocket):
    seg = segment_flight(rocket).segments
    assert seg["phase"].tolist() == ["rest", "powered", "coast", "free_fall"]
    assert seg["t_start"].iloc[0] == pytest.approx(0.0)
    assert seg["t_end"].iloc[0] == pytest.approx(18.0, abs=0.3)      # lift-off 18.1 s
    assert seg["t_end"].iloc[1] == pytest.approx(46.0, abs=0.5)      # thrust below drag 45.7 s
    # |f| < 0.5 m/s^2 from about 60 s (the paper's free-fall segment [60, 86] s)
    assert seg["t_end"].iloc[2] == pytest.approx(rocket.events["free_flight"], abs=1.0)
    assert seg["t_end"].iloc[3] == pytest.approx(rocket.t[-1])
    # contiguous and covering the flight
    assert np.allclose(seg["t_start"].iloc[1:].to_numpy(), seg["t_end"].iloc[:-1].to_numpy())
    assert np.allclose(seg["duration"], seg["t_end"] - seg["t_start"])


def test_rocket_spin_and_despin_are_not_turns(rocket):
    """The 2 Hz roll about the path axis and the de-spin at 73 s are not turns."""
    seg = segment_flight(rocket)
    f = seg.features
    coast = f[f["t"] > 47.0]
    assert (coast["rate"] > 6.0).all()                 # spinning fast ...
    assert (coast["rate_across"] < 5 * DEG).all()      # ... about the path axis
    assert set(coast["phase"]) == {"coast", "free_fall"}


def test_stationary_is_one_rest_segment():
    traj = stationary(duration_s=120.0, rate_hz=50.0)
    seg = segment_flight(traj).segments
    assert seg["phase"].tolist() == ["rest"]
    assert seg["t_start"].iloc[0] == 0.0 and seg["t_end"].iloc[0] == pytest.approx(120.0)


def test_launcher_stage_separation_is_a_short_free_fall():
    """1.4 s below 0.5 m/s^2 and 1 s of drag: one unpowered run, kept as free fall."""
    traj = launcher_ascent()
    seg = segment_flight(traj).segments
    assert seg["phase"].tolist() == ["powered", "free_fall", "powered"]
    sep = traj.events
    assert seg["t_start"].iloc[1] == pytest.approx(sep["stage1_burnout"], abs=0.5)
    assert seg["t_end"].iloc[1] == pytest.approx(sep["stage2_ignition"], abs=0.5)


def test_ground_vehicle_rest_accelerate_cruise_turn(car):
    seg = segment_flight(car).segments
    assert seg["phase"].tolist() == ["rest", "powered", "cruise", "turn", "cruise"]
    expected_ends = [5.0, 9.0, 15.0, 24.0, 30.0]
    assert np.allclose(seg["t_end"], expected_ends, atol=0.25)


def test_features_of_a_level_turn(car):
    f = flight_features(car)
    turning = f[(f["t"] > 16) & (f["t"] < 23)]
    assert np.allclose(turning["rate_across"], 10 * DEG, rtol=1e-6)
    assert np.allclose(turning["path_rate"], 10 * DEG, rtol=1e-6)
    assert np.allclose(turning["speed"], 10.0, rtol=1e-6)
    # weight supported: the lateral specific force is g and the centripetal 10 m/s * r
    # (up to Coriolis, 2 Omega 10 m/s = 1.5e-3 m/s^2)
    assert np.allclose(turning["f_lateral"],
                       np.hypot(turning["gravity"], 10.0 * 10 * DEG), atol=3e-3)
    at_rest = f[f["t"] < 4.9]
    assert np.allclose(at_rest["f_norm"], at_rest["gravity"], rtol=1e-9)
    assert np.all(at_rest["speed"] == 0.0)


def test_short_excursions_are_merged():
    """A 1 s turn disappears into the cruise at min_duration_s=2, appears at 0.5."""
    traj = ground_vehicle(lambda t: window(t, 1.0, 5.0, 2.5),
                          lambda t: window(t, 12.0, 13.0, 10.0 * DEG), duration_s=20.0)
    merged = segment_flight(traj).segments
    assert "turn" not in merged["phase"].tolist()
    assert (merged["duration"] >= SEGMENT_DEFAULTS["min_duration_s"]).all()
    kept = segment_flight(traj, min_duration_s=0.5).segments
    turn = kept[kept["phase"] == "turn"]
    assert len(turn) == 1
    assert turn["duration"].iloc[0] == pytest.approx(1.0, abs=0.2)


def test_hysteresis_prevents_chatter():
    """An acceleration oscillating about the powered threshold: chatter without hysteresis,
    one powered segment with it."""
    thr = SEGMENT_DEFAULTS["powered_accel_m_s2"]

    def accel(t):
        return window(t, 2.0, 12.0, thr + 0.3 * np.sin(2 * np.pi * (t - 2.0) / 0.8))

    traj = ground_vehicle(accel, lambda t: 0.0 * t, duration_s=16.0)
    chatter = segment_flight(traj, hysteresis=0.0, min_duration_s=0.1).segments
    assert (chatter["phase"] == "powered").sum() >= 5
    steady = segment_flight(traj, hysteresis=0.25, min_duration_s=0.1).segments
    assert steady["phase"].tolist() == ["rest", "powered", "cruise"]
    assert steady["t_start"].iloc[1] == pytest.approx(2.0, abs=0.2)
    assert steady["t_end"].iloc[1] == pytest.approx(12.0, abs=0.3)


def test_segments_have_known_phases_and_phase_at(rocket):
    seg = segment_flight(rocket)
    assert set(seg.features["phase"]) <= set(PHASES)
    assert seg.phase_at([5.0, 30.0, 50.0, 80.0]).tolist() == ["rest", "powered", "coast",
                                                             "free_fall"]
    assert seg.thresholds["turn_rate_deg_s"] == SEGMENT_DEFAULTS["turn_rate_deg_s"]


def test_segment_flight_rejects_bad_input(rocket):
    with pytest.raises(NavlibInputError, match="unknown keyword"):
        segment_flight(rocket, rest_speed=1.0)
    with pytest.raises(NavlibInputError, match="turn_rate_deg_s"):
        segment_flight(rocket, turn_rate_deg_s=-1.0)
    with pytest.raises(NavlibInputError, match="hysteresis"):
        segment_flight(rocket, hysteresis=1.5)
    with pytest.raises(NavlibInputError, match="trajectory"):
        segment_flight(np.zeros((10, 3)))


# --------------------------------------------------------------------------- user edits


@pytest.fixture(scope="module")
def auto(rocket):
    return segment_flight(rocket)


def test_boundaries_with_and_without_ends(auto):
    a = segments_table([18.0, 46.0], 0.0, 86.0, auto)
    b = segments_table([0.0, 18.0, 46.0, 86.0], 0.0, 86.0, auto)
    pd.testing.assert_frame_equal(a, b)
    assert a["phase"].tolist() == ["rest", "powered", "free_fall"]  # majority labels
    assert a[["t_start", "t_end"]].to_numpy().tolist() == [[0, 18], [18, 46], [46, 86]]
    unnamed = segments_table(np.array([30.0]), 0.0, 86.0)
    assert unnamed["phase"].tolist() == ["segment 1", "segment 2"]


def test_edited_frame_round_trip(auto):
    edited = auto.to_frame()
    edited.loc[1, "t_end"] = 40.0
    edited.loc[2, "t_start"] = 40.0
    edited.loc[2, "phase"] = "late boost + coast"
    table = segments_table(edited, 0.0, 86.0, auto)
    assert table["phase"].tolist() == ["rest", "powered", "late boost + coast", "free_fall"]
    assert table["t_end"].tolist()[:2] == [pytest.approx(18.1), 40.0]
    assert segments_table(auto, 0.0, 86.0).equals(auto.segments)


def test_windows_with_gaps_and_phases(auto):
    table = segments_table([("pad", 5.0, 15.0), (60.0, 80.0), {"t_start": 20, "t_end": 30}],
                           0.0, 86.0, auto)
    assert table["phase"].tolist() == ["pad", "powered", "free_fall"]   # sorted by start
    assert table["duration"].tolist() == [10.0, 10.0, 20.0]


@pytest.mark.parametrize("segments, match", [
    ([46.0, 18.0], "strictly increasing"),
    ([18.0, 90.0], "outside the flight span"),
    ([(0.0, 20.0), (10.0, 30.0)], "overlaps"),
    ([(10.0, 10.0)], "empty"),
    ([(-5.0, 10.0)], "leaves the flight span"),
    ([], "empty"),
    ("0, 18", "expected a DataFrame"),
    ([("rest", 0.0)], "t_start"),
    ([(1, 2, 3, 4)], "expected"),
    ([(None, 0.0, 5.0), ("", 5.0, 9.0)], "phase must be a non-empty string"),
    (pd.DataFrame({"start": [0.0]}), "missing column"),
    ([0.0, float("nan")], "finite"),
])
def test_bad_segments_are_named(segments, match):
    with pytest.raises(NavlibInputError, match=match):
        segments_table(segments, 0.0, 86.0)
