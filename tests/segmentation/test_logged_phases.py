"""A rocket's phases from its flight computer's logged states, with the detected events beside
them (navlib.segmentation.logged)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from support import vehicles

from navlib.errors import NavlibInputError
from navlib.segmentation import segment_flight
from navlib.segmentation.logged import flight_events, logged_segments


@pytest.fixture(scope="module")
def parachute():
    """Pad 0-5 s, boost 5-8 s, coast to the apogee at 15.5 s, parachute descent to 60 s."""
    return vehicles.parachute_rocket()


# what an AltOS export of that flight would log (state names as AltOS writes them; the
# logger's times differ from the motion by stated amounts: boost detected 0.2 s late, the
# drogue fired 0.5 s after the apogee)
LOGGED = pd.DataFrame({"t": [0.0, 5.2, 7.0, 8.0, 16.0, 40.0],
                       "state": ["pad", "boost", "fast", "coast", "drogue", "main"]})


def test_logged_states_become_rocket_words():
    table = logged_segments(LOGGED, 0.0, 60.0)
    assert table["phase"].tolist() == ["pad", "boost", "coast", "drogue", "main"]  # fast+coast
    assert table["t_start"].tolist() == [0.0, 5.2, 7.0, 16.0, 40.0]
    assert table["t_end"].tolist() == [5.2, 7.0, 16.0, 40.0, 60.0]
    np.testing.assert_allclose(table["duration"], table["t_end"] - table["t_start"])


def test_logged_states_clipped_to_the_span():
    table = logged_segments(LOGGED, 6.0, 30.0)   # boost already running at the span's start
    assert table["phase"].tolist() == ["boost", "coast", "drogue"]
    assert table["t_start"].iloc[0] == 6.0 and table["t_end"].iloc[-1] == 30.0
    pairs = [("boost", 1.0), ("invalid", 2.0), ("landed", 9.0)]   # (state, t) pairs
    assert logged_segments(pairs, 0.0, 10.0)["phase"].tolist() == ["boost", "landed"]
    assert logged_segments([("landed", 20.0)], 0.0, 10.0) is None


@pytest.mark.parametrize("bad", [pd.DataFrame({"time": [0.0], "state": ["boost"]}), 5])
def test_logged_states_refuse_bad_input(bad):
    with pytest.raises(NavlibInputError, match="flight_states"):
        logged_segments(bad, 0.0, 10.0)


def test_segments_follow_the_log_and_events_sit_side_by_side(parachute):
    seg = segment_flight(parachute, vehicle="rocket", flight_states=LOGGED)
    assert seg.source == "logged"
    assert seg.segments["phase"].tolist() == ["pad", "boost", "coast", "drogue", "main"]
    assert seg.detected["phase"].tolist() == ["pad", "boost", "coast", "descent"]
    assert seg.phase_at([1.0, 6.0, 12.0, 20.0, 50.0]).tolist() == [
        "pad", "boost", "coast", "drogue", "main"]
    events = seg.events.set_index("event")
    assert events.loc["ignition", "t_logged"] == 5.2
    assert events.loc["ignition", "t_detected"] == pytest.approx(5.0, abs=0.3)
    # the fixture's thrust fades smoothly after 8 s (a PCHIP velocity): the specific force
    # along the path falls below the powered threshold (2 m/s^2, 1.5 with hysteresis) later
    assert 8.0 < events.loc["burnout", "t_detected"] < 10.0
    assert events.loc["apogee", "t_logged"] == 16.0                  # the drogue's start
    assert events.loc["apogee", "t_detected"] == pytest.approx(15.5, abs=0.1)
    assert events.loc["main", "t_logged"] == 40.0 and np.isnan(events.loc["main", "t_detected"])
    np.testing.assert_allclose(events["difference"], events["t_detected"] - events["t_logged"])


def test_without_states_the_events_are_detected_only(parachute):
    seg = segment_flight(parachute, vehicle="rocket")
    assert seg.source == "detected" and seg.detected is None
    assert seg.events["t_logged"].isna().all()
    assert seg.events.set_index("event").loc["apogee", "t_detected"] == pytest.approx(15.5,
                                                                                       abs=0.1)
    assert segment_flight(parachute, vehicle="multicopter", flight_states=LOGGED).events is None


def test_second_burn_gets_its_own_events():
    detected = pd.DataFrame({"phase": ["pad", "boost", "coast", "boost", "coast"],
                             "t_start": [0.0, 2.0, 5.0, 9.0, 12.0],
                             "t_end": [2.0, 5.0, 9.0, 12.0, 30.0]})
    events = flight_events(detected, 25.0)
    assert events["event"].tolist() == ["ignition", "ignition 2", "burnout", "burnout 2",
                                        "apogee"]
    assert events["t_detected"].tolist() == [2.0, 9.0, 5.0, 12.0, 25.0]


def test_shifted_moves_every_time(parachute):
    seg = segment_flight(parachute, vehicle="rocket", flight_states=LOGGED)
    moved = seg.shifted(5.2)
    np.testing.assert_allclose(moved.segments["t_start"], seg.segments["t_start"] - 5.2)
    np.testing.assert_allclose(moved.detected["t_end"], seg.detected["t_end"] - 5.2)
    np.testing.assert_allclose(moved.features["t"], seg.features["t"] - 5.2)
    assert moved.events.set_index("event").loc["ignition", "t_logged"] == pytest.approx(0.0)
    assert moved.phase_at([0.5]).tolist() == ["boost"]
