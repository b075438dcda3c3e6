"""Vehicle classes and their phase words (navlib.segmentation, assumptions V1-V2)."""

from __future__ import annotations

import types

import numpy as np
import pandas as pd
import pytest
from support import vehicles

from navlib.errors import NavlibInputError
from navlib.segmentation import (
    VEHICLE_PHASES,
    VEHICLES,
    check_vehicle,
    recognise_vehicle,
    segment_flight,
    vehicle_from_log,
)
from navlib.studies.assess import assess_flight
from navlib.trajectory import sounding_rocket

ROCKET_ONLY = {"pad", "boost", "coast", "free_fall", "drogue", "main", "landed"}


def _phases(segmentation):
    return [(p, a, b) for p, a, b in
            segmentation.segments[["phase", "t_start", "t_end"]].itertuples(index=False)]


@pytest.fixture(scope="module")
def car():
    return vehicles.car()


@pytest.fixture(scope="module")
def hover():
    return vehicles.hover()


@pytest.fixture(scope="module")
def rocket():
    return sounding_rocket()


@pytest.fixture(scope="module")
def parachute():
    return vehicles.parachute_rocket()


def test_every_vehicle_has_rest_and_only_rockets_have_rocket_words():
    assert set(VEHICLE_PHASES) == set(VEHICLES)
    for vehicle, words in VEHICLE_PHASES.items():
        assert words[0] == ("pad" if vehicle == "rocket" else "rest")
        assert bool(ROCKET_ONLY & set(words)) == (vehicle == "rocket")


@pytest.fixture(scope="module")
def plane():
    return vehicles.plane()


@pytest.mark.parametrize("make, expected", [("car", "ground"), ("hover", "multicopter"),
                                            ("parachute", "rocket"), ("plane", "fixed-wing")])
def test_recognised_from_kinematics(make, expected, request):
    vehicle, reason = recognise_vehicle(request.getfixturevalue(make))
    assert vehicle == expected
    assert reason.startswith("kinematics:")


def test_sounding_rocket_and_figure_eight_drone_recognised(rocket):
    from support import flights

    assert recognise_vehicle(rocket)[0] == "rocket"
    vehicle, reason = recognise_vehicle(flights.multicopter(duration_s=60.0))
    assert vehicle == "multicopter" and "sideways" in reason  # no vertical take-off there


def test_car_never_gets_rocket_words(car):
    kinematic = {p for p, _, _ in _phases(segment_flight(car))}
    assert "powered" in kinematic          # what the rocket vocabulary called the start
    phases = _phases(segment_flight(car, vehicle="ground"))
    assert not ROCKET_ONLY & {p for p, _, _ in phases}
    assert [p for p, _, _ in phases] == ["rest", "cruise", "turn", "cruise", "rest"]
    turn = phases[2]
    assert 34.0 < turn[1] < 38.0 and 42.0 < turn[2] < 46.0   # the turn is 35-45 s


def test_multicopter_hover(hover):
    phases = _phases(segment_flight(hover, vehicle="multicopter"))
    assert [p for p, _, _ in phases] == ["rest", "climb", "hover", "descent", "rest"]
    _, start, end = phases[2]
    assert 14.0 < start < 17.0 and 39.0 < end < 42.0          # hovers 16-40 s


def test_fixed_wing_climbs_turns_and_descends(plane):
    phases = _phases(segment_flight(plane, vehicle="fixed-wing"))
    assert [p for p, _, _ in phases] == ["rest", "cruise", "climb", "cruise", "turn", "cruise",
                                         "descent", "cruise"]
    assert phases[2][1] == pytest.approx(20.0, abs=1.0)       # climbs 20-35 s
    assert phases[6][1] == pytest.approx(80.0, abs=1.0)       # descends 80-95 s


def test_rocket_descent_after_apogee(parachute):
    phases = _phases(segment_flight(parachute, vehicle="rocket"))
    assert [p for p, _, _ in phases] == ["pad", "boost", "coast", "descent"]
    assert phases[3][1] == pytest.approx(15.5, abs=0.5)        # apogee at 15.5 s
    assert phases[0][2] == pytest.approx(5.0, abs=0.5)         # ignition at 5 s


def test_rocket_on_the_pad_is_at_rest(rocket):
    """A fitted pad rarely holds still: with 1.5 m/s of velocity noise on the pad the
    kinematic labels leave rest, the rocket words do not."""
    truth = rocket
    t = truth.t
    V = np.array(truth.velocity, copy=True)
    pad = t < 17.5
    V[pad, 0] += 1.5 * np.sin(2.0 * np.pi * t[pad] / 3.0)
    V[pad, 1] += 1.5 * np.cos(2.0 * np.pi * t[pad] / 3.0)
    noisy = types.SimpleNamespace(t=t, position=truth.position, velocity=V,
                                  specific_force=truth.specific_force,
                                  angular_rate=truth.angular_rate, attitude=truth.attitude)
    assert _phases(segment_flight(noisy))[0][0] != "rest"
    phases = _phases(segment_flight(noisy, vehicle="rocket"))
    assert phases[0][0] == "pad" and phases[0][2] == pytest.approx(18.0, abs=0.5)
    assert phases[1][0] == "boost"


@pytest.mark.parametrize("attrs, expected", [
    ({"flight_states": [("boost", 0.0)]}, "rocket"),
    ({"autopilot": "ardupilot", "hardware": "ArduCopter V4.5.0"}, "multicopter"),
    ({"autopilot": "ardupilot", "hardware": "ArduPlane V3.8.2-dev (8178ab40)"}, "fixed-wing"),
    ({"autopilot": "ardupilot", "hardware": "ArduRover V4.2.0"}, "ground"),
    ({"vehicle": "Fixed-Wing"}, "fixed-wing"),
    ({"autopilot": "px4", "mav_type": 14}, "multicopter"),
    ({"autopilot": "px4", "mav_type": 1}, "fixed-wing"),
    ({"autopilot": "px4", "mav_type": 10}, "ground"),
    ({"autopilot": "px4", "mav_type": 6}, None),               # a ground control station
    ({"autopilot": "px4", "hardware": "PX4FMU_V4PRO"}, None),
    ({}, None),
])
def test_vehicle_from_log(attrs, expected):
    vehicle, reason = vehicle_from_log(attrs)
    assert vehicle == expected
    assert bool(reason) == (expected is not None)


def test_check_vehicle():
    assert check_vehicle("Fixed_Wing") == "fixed-wing"
    assert check_vehicle("multicopter") == "multicopter"
    for bad in ("car", "", None, 3):
        with pytest.raises(NavlibInputError, match="vehicle: expected one of"):
            check_vehicle(bad)
    with pytest.raises(NavlibInputError, match="vehicle"):
        segment_flight(vehicles.hover(duration_s=5.0), vehicle="boat")
    imu = pd.DataFrame({k: np.zeros(3) for k in ("t", "f_x", "f_y", "f_z", "w_x", "w_y", "w_z")})
    imu["t"] = [0.0, 1.0, 2.0]
    gnss = pd.DataFrame({"t": [0.0, 1.0, 2.0], "x": 6.4e6, "y": 0.0, "z": 0.0})
    with pytest.raises(NavlibInputError, match="vehicle: expected one of"):
        assess_flight(imu, gnss, vehicle="boat")
