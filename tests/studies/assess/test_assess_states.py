"""How well each state is known, in navigation axes and units (navlib.studies.assess.states),
and the clock since ignition, read back from ``states.csv`` and ``summary.csv`` of
``python -m navlib assess``."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pandas as pd
import pytest
from support.locations import shared_file

from navlib import sensors, units
from navlib.__main__ import main
from navlib.io import FlightDataWarning
from navlib.models.ecef import P0_DEFAULTS, parameter_sigmas
from navlib.studies.assess import assess_flight
from navlib.studies.assess.states import (
    EXCITABLE_MARK,
    NOT_REPRESENTED,
    SENSIBLE_MARK,
    STATES_COLUMNS,
    how_well,
    navigation_state_names,
)
from navlib.trajectory import stationary

ALTOS = ("2019-05-04-serial-1257-flight-0017.csv", "2019-05-26-serial-1257-flight-0018.csv",
         "2018-04-08-serial-1257-flight-0014.csv")
PRESET = "motionpak_tactical"
GNSS_SIGMA_M = 0.05
QUIET = f"""name = "quiet_alignment"
source = "test preset: the MotionPak turn-on errors, nearly noiseless sensors, 5 cm fixes"
[imu]
rate_hz = 100.0
gyro_bias_deg_s = 0.05
accel_bias_m_s2 = 0.02
gyro_scale_factor_ppm = 5000.0
accel_scale_factor_ppm = 1000.0
gyro_arw_deg_sqrt_h = 0.001
accel_vrw_m_s_sqrt_h = 0.001
gyro_bias_rw_rad_s_sqrt_s = 1.0e-9
accel_bias_rw_m_s2_sqrt_s = 1.0e-9
gyro_scale_factor_rw_per_sqrt_s = 1.0e-9
accel_scale_factor_rw_per_sqrt_s = 1.0e-9
[gnss]
rate_hz = 1.0
position_sigma_m = {GNSS_SIGMA_M}
velocity_sigma_m_s = 0.01
"""
"""A sensor preset whose only large errors are the turn-on biases and scale factors: white
noise and random walks small enough that the static alignment reaches its limit."""


@pytest.fixture(scope="module")
def static_run(tmp_path_factory):
    """A level vehicle standing 120 s (heading north) with 1 Hz fixes of 5 cm noise and the
    :data:`QUIET` sensors, assessed through the command line; returns the output folder, the
    truth and the preset file."""
    folder = tmp_path_factory.mktemp("static")
    preset = folder / "quiet.toml"
    preset.write_text(QUIET, encoding="utf-8")
    truth = stationary(duration_s=120.0, rate_hz=100.0)
    spec = sensors.load_preset(preset)
    sensors.simulate_imu(truth, spec, seed=3).to_frame().to_csv(folder / "imu.csv",
                                                               index=False)
    sensors.simulate_gnss(truth, spec, rate_hz=1.0, seed=4).to_csv(folder / "gnss.csv",
                                                                 index=False)
    out = folder / "out"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FlightDataWarning)     # heading fallback at rest
        status = main(["assess", f"{folder / 'imu.csv'},{folder / 'gnss.csv'}", "--output",
                       str(out), "--scheduler", "synchronous", "--preset", str(preset)])
    assert status == 0
    return out, truth, preset


def test_static_alignment_tilt_is_the_accelerometer_bias_over_g(static_run):
    """At rest the velocity measures ``g tilt + b_a`` per horizontal axis, to about
    5e-5 m/s^2 here (5 cm fixes over 120 s), nothing separates the two, and the gyro bias
    follows from the tilt's drift. With priors ``s_t`` (tilt, ``sigma_theta0_deg``) and
    ``s_b`` (accelerometer bias, the preset's turn-on), the posterior of a quantity known
    only through ``g tilt + b`` is ``s_t s_b / sqrt(g^2 s_t^2 + s_b^2)`` for the tilt (about
    ``s_b / g``) and ``g s_t s_b / sqrt(g^2 s_t^2 + s_b^2)`` for the bias (about ``s_b``).
    Measured: 0.2 % and 0.01 % from them (the gyro white noise and the finite fixes keep
    the tilt a little above its limit; with the MotionPak's own noise, 0.5 deg/sqrt(h) ARW
    and 1e-4 m/s^2/sqrt(s) bias walk, the tilt ends 5 % above it)."""
    out, truth, preset = static_run
    table = pd.read_csv(out / "states.csv")
    assert list(table.columns) == list(STATES_COLUMNS)
    assert len(table) == 21 * table["segment"].nunique()
    assert table["state"].tolist()[:21] == list(navigation_state_names("ground"))
    last = table[table["segment"] == table["segment"].max()].set_index("state")
    units_of = last["unit"].to_dict()
    assert {units_of[s] for s in ("position_north", "position_down")} == {"m"}
    assert units_of["velocity_east"] == "m/s" and units_of["roll"] == "deg"
    assert units_of["gyro_bias_x"] == "deg/h" and units_of["accel_bias_y"] == "mg"
    assert units_of["gyro_scale_z"] == units_of["accel_scale_x"] == "ppm"

    g = float(np.linalg.norm(truth.specific_force[0]))           # what the IMU reads at rest
    s_t = P0_DEFAULTS["sigma_theta0_deg"] * units.DEG
    s_b = parameter_sigmas(sensors.load_preset(preset))["sigma_ba_m_s2"]
    tilt = s_t * s_b / np.hypot(g * s_t, s_b)
    bias = g * tilt
    for state in ("roll", "pitch"):                              # level, heading north
        assert last.loc[state, "sigma_end"] == pytest.approx(tilt / units.DEG, rel=0.01)
    for state in ("accel_bias_x", "accel_bias_y"):
        assert last.loc[state, "sigma_end"] == pytest.approx(bias / units.MG, rel=0.01)
    first = table[table["segment"] == 1].set_index("state")
    assert first.loc["roll", "sigma_start"] == pytest.approx(P0_DEFAULTS["sigma_theta0_deg"])
    assert first.loc["accel_bias_y", "sigma_start"] == pytest.approx(s_b / units.MG)
    # the fixes pin the position well below their own noise after two minutes at 1 Hz
    assert (last.loc[["position_north", "position_east", "position_down"], "sigma_end"]
            < GNSS_SIGMA_M).all()
    np.testing.assert_allclose(table["reduction"], 1 - table["sigma_end"] / table["sigma_start"])


def test_static_summary_clock_starts_at_the_first_sample(static_run):
    out, _, _ = static_run
    summary = pd.read_csv(out / "summary.csv")
    assert summary["vehicle"].iloc[0] == "ground" and np.isnan(summary["t_ignition"].iloc[0])
    assert summary["phases"].iloc[0].startswith("rest 0.0-")


def test_states_table_reads_the_model_states_when_nothing_turns():
    """The navigation rows of a level, north-facing vehicle at rest are the model's own
    states up to sign and order (ECEF -> NED is the only rotation): the same sigma."""
    truth = stationary(duration_s=30.0, rate_hz=100.0)
    spec = sensors.load_preset(PRESET)
    imu = sensors.simulate_imu(truth, spec, seed=5).to_frame()
    gnss = sensors.simulate_gnss(truth, spec, seed=6)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FlightDataWarning)
        result = assess_flight(imu, gnss, preset=PRESET)
    nav = result.states_table("still")
    model = result.state_table()
    # IMU errors: no rotation at all, identical numbers and flags
    imu_rows = nav["group"].isin(["gyro_bias", "acc_bias", "gyro_scale", "acc_scale"])
    scale = nav.loc[imu_rows, "unit"].map({"deg/h": units.DEG_PER_HOUR, "mg": units.MG,
                                           "ppm": units.PPM}).to_numpy()
    np.testing.assert_allclose(nav.loc[imu_rows, "sigma_end"].to_numpy() * scale,
                               model["sigma_end"].to_numpy()[9:], rtol=1e-9)
    np.testing.assert_array_equal(nav.loc[imu_rows, "excitable"], model["excitable"][9:])
    np.testing.assert_array_equal(nav.loc[imu_rows, "sensible"], model["sensible"][9:])
    # position: a rotation keeps the total variance
    pos = nav["group"] == "position"
    assert np.sum(nav.loc[pos, "sigma_end"] ** 2) == pytest.approx(
        np.sum(model["sigma_end"].to_numpy()[:3] ** 2), rel=1e-9)


def _altos(name):
    return shared_file("altos", name)


@pytest.fixture(scope="module")
def altos_run(tmp_path_factory):
    paths = [str(_altos(name)) for name in ALTOS]
    out = tmp_path_factory.mktemp("altos")
    status = main(["assess", *paths, "--output", str(out), "--scheduler", "synchronous"])
    return out, paths, status


def test_altos_flights_phases_since_ignition(altos_run):
    """Real TeleMega flights: rocket words, the logged states (drogue, main) where the
    computer logged them, the ignition on the log's clock at the thrust onset the recorded
    specific force shows (AltOS counts from boost detection; its buffer starts 0.3 s before,
    labelled boost, so the boost starts at the record's first row, -0.24 to -0.2 s before the
    ignition, and the logged ignition is that row), detected at 0 s."""
    out, paths, status = altos_run
    assert status == 0
    summary = pd.read_csv(out / "summary.csv").set_index("log")
    for path in paths:
        row = summary.loc[path]
        assert row["vehicle"] == "rocket"
        phases = [p.split(" ")[0] for p in row["phases"].split("; ")]
        assert phases[0].split("+")[0] == "boost" and row["phases"].startswith("boost")
        start = float(row["phases"].split(" ")[1].rsplit("-", 1)[0])
        assert -0.3 <= start <= 0.0                  # the buffer before the thrust onset
        assert "coast" in "+".join(phases).split("+")
        assert -0.3 < row["t_ignition"] < 0.1 and start == pytest.approx(
            -0.3 - row["t_ignition"], abs=0.06)          # printed to 0.1 s
        if "2018-04-08" not in path:                       # the newer export logs its states
            assert {"drogue", "main"} <= set(phases)
            assert re.match(r"ignition -0\.2\d s \(detected 0\.00 s\)", row["events"])
            assert "apogee " in row["events"] and "main " in row["events"]
        else:
            assert row["events"].startswith("ignition 0.00 s (detected)")
    states = pd.read_csv(out / "states.csv")
    assert set(states["log"]) == set(paths)
    assert set(states["unit"]) == {"m", "m/s", "deg", "deg/h", "mg", "ppm"}
    assert {"position_north", "velocity_down", "roll", "gyro_bias_along",
            "accel_scale_cross_z"} <= set(states["state"])
    boost = states[states["phase"].str.startswith("boost")
                   & (states["state"] == "accel_scale_along")]
    assert boost["t_start"].between(-0.3, 0.0).all()          # from the first row
    assert (boost["sigma_end"] < boost["sigma_start"]).all()   # the thrust shows the scale


def test_assessment_states_table_matches_the_csv_columns():
    """Every rocket word the segmentation may give is one of its vehicle's words."""
    from navlib.segmentation import VEHICLE_PHASES
    from navlib.segmentation.logged import LOGGED_WORDS

    assert set(LOGGED_WORDS.values()) <= set(VEHICLE_PHASES["rocket"])
    assert navigation_state_names("rocket")[9:12] == ("gyro_bias_along", "gyro_bias_cross_y",
                                                      "gyro_bias_cross_z")


def test_both_attitude_error_definitions_give_the_same_roll_pitch_yaw(tmp_path):
    """``psi^e = C_hat dtheta^b`` relates the model's two attitude errors (spec A4): rotated
    to body roll, pitch and yaw (ECEF -> NED -> body, or nothing for the body error) the two
    models must give the same sigma and flags, although the body-to-ECEF rotation of a
    level vehicle is far from the identity."""
    preset = tmp_path / "quiet.toml"
    preset.write_text(QUIET, encoding="utf-8")
    spec = sensors.load_preset(preset)
    truth = stationary(duration_s=30.0, rate_hz=100.0)
    imu = sensors.simulate_imu(truth, spec, seed=7).to_frame()
    gnss = sensors.simulate_gnss(truth, spec, rate_hz=1.0, seed=8)
    tables = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FlightDataWarning)
        for error in ("ecef", "body"):
            result = assess_flight(imu, gnss, preset=str(preset),
                                   model_options={"attitude_error": error})
            tables.append(result.states_table().set_index("state"))
    ecef, body = tables
    np.testing.assert_allclose(ecef["sigma_end"], body["sigma_end"], rtol=1e-4)
    np.testing.assert_array_equal(ecef["excitable"], body["excitable"])
    assert ecef.loc["roll", "sigma_end"] < 0.5 * ecef.loc["roll", "sigma_start"]   # levelled


    rows = []
    for seg, (phase, t0, t1) in enumerate([("pad", -2.0, 0.0), ("boost", 0.0, 3.5)], start=1):
        for k, (state, unit) in enumerate([("position_north", "m"), ("roll", "deg")]):
            rows.append({"log": "", "segment": seg, "phase": phase, "t_start": t0, "t_end": t1,
                         "state": state, "unit": unit, "sigma_start": 10.0 * seg + k,
                         "sigma_end": 1.23456 * seg + k, "excitable": k == 0 or seg == 2,
                         "sensible": k == 0})
    out = how_well(pd.DataFrame(rows))
    assert list(out.columns) == ["state", "unit", "start", "1 pad -2.0..0.0 s",
                                 "2 boost 0.0..3.5 s"]
    assert list(out["start"]) == ["10", "11"]
    assert list(out["1 pad -2.0..0.0 s"]) == [f"1.23 {SENSIBLE_MARK}", "2.23"]
    assert list(out["2 boost 0.0..3.5 s"]) == [f"2.47 {SENSIBLE_MARK}", f"3.47 {EXCITABLE_MARK}"]


def test_how_well_drops_the_verdicts_of_an_unrepresented_segment():
    rows = [{"log": "", "segment": 1, "phase": "descent", "t_start": 20.0, "t_end": 90.0,
             "state": "roll", "unit": "deg", "sigma_start": 5.0, "sigma_end": 1.0,
             "excitable": True, "sensible": True, "valid": False}]
    out = how_well(pd.DataFrame(rows))
    assert list(out.columns)[-1] == "1 descent 20.0..90.0 s" + NOT_REPRESENTED
    assert list(out.iloc[:, -1]) == ["1"]
