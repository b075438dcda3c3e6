"""Mission planning (navlib.studies.plan and python -m navlib plan): outages, timeline,
the command line and the trade-study evaluation."""


import numpy as np
import pandas as pd
import pytest
from support.locations import REPO

from navlib import NavlibInputError
from navlib.__main__ import main
from navlib.studies.plan import VEHICLE_PRESETS, plan_beside_flight, plan_mission, plan_point
from navlib.sweep import sweep

POSITION = ("P_x", "P_y", "P_z")


@pytest.fixture(scope="module")
def multicopter_pair():
    """The multicopter survey with its 48-63 s outage and without any."""
    return (plan_mission("multicopter_survey", outages=[]),
            plan_mission("multicopter_survey"))


def test_outage_lowers_position_sensability_inside_and_not_outside(multicopter_pair):
    clear, outage = multicopter_pair
    assert outage.outages == ((48.0, 63.0),)
    t = clear.sensability.t
    np.testing.assert_array_equal(t, outage.sensability.t)
    idx = [clear.state_names.index(s) for s in POSITION]
    s_clear, s_out = clear.sensability.s[:, idx], outage.sensability.s[:, idx]
    before, inside, after = t < 48.0, (t >= 48.0) & (t <= 63.0), t > 80.0
    np.testing.assert_array_equal(s_out[before], s_clear[before])   # causal: identical
    assert np.all(s_out[inside].mean(axis=0) < s_clear[inside].mean(axis=0) - 0.1)
    # recovered some seconds after the outage (the filter re-converges on GNSS)
    np.testing.assert_allclose(s_out[after].mean(axis=0), s_clear[after].mean(axis=0),
                               atol=0.03)
    sigma_clear, sigma_out = clear.sensability.sigma[:, idx], outage.sensability.sigma[:, idx]
    assert np.all(sigma_out[inside].max(axis=0) > 10 * sigma_clear[inside].max(axis=0))


def test_outage_epochs_carry_no_measurement(multicopter_pair):
    _, outage = multicopter_pair
    t = np.asarray(outage.model.t)
    silent = ~np.any(np.asarray(outage.model.H) != 0.0, axis=(1, 2))
    np.testing.assert_array_equal(silent, (t >= 48.0) & (t <= 63.0))
    gnss_row = outage.inputs.set_index("record").loc["gnss"]
    assert gnss_row["samples"] == np.count_nonzero(~silent)


def test_timeline_reads_the_metrics(multicopter_pair):
    clear, outage = multicopter_pair
    timeline = outage.timeline()
    assert list(timeline["state"]) == list(outage.state_names)
    table = outage.state_table()
    for row in timeline.itertuples(index=False):
        exc = table[(table["state"] == row.state) & table["excitable"]]
        assert (np.isnan(row.excitable_from_s) if exc.empty
                else row.excitable_from_s == exc["t_start"].min())
    starts = timeline["sensible_from_s"].dropna()
    assert (starts >= 5.0).all()                 # the start-up transient is left out
    se = outage.sensability
    for row in timeline.dropna(subset=["sensible_from_s"]).itertuples(index=False):
        j = outage.state_names.index(row.state)
        first = np.flatnonzero((se.t >= 5.0) & (se.s[:, j] >= outage.settings["s_threshold"]))
        assert row.sensible_from_s == se.t[first[0]]
    pos = timeline.set_index("state").loc[list(POSITION)]
    assert np.all(pos["sensible_share_outage"] < pos["sensible_share"])
    assert clear.timeline()["sensible_share_outage"].isna().all()


def test_defaults_and_given_presets():
    rocket = plan_mission("sounding_rocket")
    assert rocket.options["preset"] == "motionpak_tactical"     # the mission's own
    assert rocket.options["gnss_rate_hz"] == 1.0 and rocket.options["gnss_sigma_m"] == 5.0
    assert list(rocket.segment_table["phase"])[:2] == ["pad", "boost"]
    table = {"vehicle": "ground", "site": {"lat_deg": 10.0, "lon_deg": 20.0},
             "waypoint": [{"north_m": 0.0}, {"north_m": 150.0}]}
    ground = plan_mission(table)
    assert ground.options["preset"] == VEHICLE_PRESETS["ground"]
    assert ground.options["gnss_rate_hz"] == 5.0                # the preset's GNSS rate


@pytest.mark.parametrize(("kwargs", "words"), [
    ({"outages": [(200.0, 210.0)]}, "outages[0]: starts at 200 s, after the mission ends"),
    ({"outages": [(5.0, 1.0)]}, "outages[0] end_s"),
    ({"outages": [(0.0, 1000.0)]}, "cover every GNSS epoch"),
    ({"sensors_preset": "no_such_preset"}, "unknown sensor preset"),
    ({"changes": {"rocket.spin_hz": -1.0}}, "[rocket] spin_hz"),
])
def test_bad_plan_input(kwargs, words):
    with pytest.raises(NavlibInputError) as info:
        plan_mission("sounding_rocket", **kwargs)
    assert words in str(info.value)


def test_plan_command_writes_summary_and_pages(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text('vehicle = "ground"\n[site]\nlat_deg = 1.0\nlon_deg = 2.0\n'
                   '[[waypoint]]\nnorth_m = 0.0\n[[waypoint]]\nnorth_m = 0.0\n',
                   encoding="utf-8")
    out = tmp_path / "plans"
    status = main(["plan", "sounding_rocket", str(bad), "--sensors", "ssac_tactical",
                   "--output", str(out), "-p", "s_threshold", "0.8"])
    assert status == 1
    summary = pd.read_csv(out / "summary.csv")
    ok, failed = summary.iloc[0], summary.iloc[1]
    assert (ok["status"], ok["vehicle"], ok["n_segments"]) == ("ok", "rocket", 4)
    page = (out / ok["page"]).read_text(encoding="utf-8")
    assert "Timeline" in page and "ssac_tactical" in page and "data:image/png" in page
    assert failed["status"] == "failed" and "bad.toml waypoint 1" in failed["error"]
    assert "1 of 2 mission(s) planned" in capsys.readouterr().err
    assert main(["plan", "sounding_rocket", "--output", str(out), "-p", "speed", "1"]) == 2


def test_trade_study_through_sweep():
    grid = {"mission": ["sounding_rocket"], "sensors_preset": ["motionpak_tactical",
                                                                "pixhawk_mems"]}
    table = sweep(grid, plan_point, scheduler="synchronous")
    assert list(table["sensors_preset"]) == ["motionpak_tactical", "pixhawk_mems"]
    direct = plan_point("sounding_rocket", "pixhawk_mems")
    assert table.iloc[1]["n_sensible"] == direct["n_sensible"]
    assert table.iloc[1]["sigma_end_P_x"] == pytest.approx(direct["sigma_end_P_x"])
    # a MEMS gyro leaves the attitude less certain than the tactical unit at the end
    assert table.iloc[1]["sigma_end_theta_z"] > table.iloc[0]["sigma_end_theta_z"]


def test_segment_inside_an_outage_is_joined_or_refused():
    plan = plan_mission("ground_vehicle")            # a turn lies inside the 40-52 s outage
    joined = [n for n in plan.notes if "lies inside a GNSS outage" in n]
    assert len(joined) == 1
    silent = ~np.any(np.asarray(plan.model.H) != 0.0, axis=(1, 2))
    t = np.asarray(plan.model.t)
    for a, b in plan.segments:
        assert np.any(~silent & (t >= a) & (t <= b))
    with pytest.raises(NavlibInputError, match=r"segment 2 \(turn, 42\.\.50 s\) lies inside"):
        plan_mission("ground_vehicle", segments=[(0.0, 42.0), (42.0, 50.0), (50.0, 121.0)])


SAMPLE = REPO / "data" / "sample_flight"


@pytest.fixture(scope="module")
def sample_flight():
    from navlib import io
    from navlib.studies.assess import assess_flight

    return assess_flight(io.read_imu_csv(SAMPLE / "imu.csv"),
                         io.read_gnss_csv(SAMPLE / "gnss.csv"), preset="motionpak_tactical")


def test_planned_beside_flown_per_phase(sample_flight):
    """The sample flight was simulated from the sounding-rocket profile the rocket mission
    describes: per phase the plan expects what the flight delivers."""
    table = plan_beside_flight(plan_mission("sounding_rocket"), sample_flight)
    assert list(table["phase"]) == ["pad", "boost", "coast", "free_fall"]
    assert (table["planned_excitable"] == table["flown_excitable"]).all()
    assert (table["planned_sensible"] == table["flown_sensible"]).all()
    assert (table["sensible_only_planned"] == "-").all()
    other = plan_beside_flight(plan_mission("multicopter_survey"), sample_flight)
    turn = other.set_index("phase").loc["turn"]
    assert turn["flown_segments"] == "-" and turn["planned_segments"] != "-"
    with pytest.raises(NavlibInputError, match="flight: expected a FlightAssessment"):
        plan_beside_flight(plan_mission("sounding_rocket"), "flight.ulg")


def test_plan_command_with_a_flight(tmp_path):
    out = tmp_path / "plans"
    flight = f"{SAMPLE / 'imu.csv'},{SAMPLE / 'gnss.csv'}"
    assert main(["plan", "sounding_rocket", "--flight", flight, "--output", str(out)]) == 0
    page = (out / pd.read_csv(out / "summary.csv")["page"][0]).read_text(encoding="utf-8")
    assert "Planned beside flown" in page and "sensible_only_flown" in page
    states = pd.read_csv(out / "states.csv")        # how well, in navigation axes and units
    assert set(states["log"]) == {"sounding_rocket"} and "gyro_bias_along" in set(states["state"])
    assert len(states) == 21 * pd.read_csv(out / "summary.csv")["n_segments"][0]


def test_plan_panel_replans_only_for_the_mission_controls():
    from navlib.widgets.plan import plan_panel

    panel = plan_panel(plan_mission("sounding_rocket"))
    model = panel.plan.model
    panel.controls["s_threshold"].value = 0.8
    assert panel.plan.model is model and panel.plan.settings["s_threshold"] == 0.8
    assert panel.controls["outage_start"].disabled  # no outage: its start means nothing
    plan = panel.plan
    panel.controls["outage_start"].value = 30.0
    assert panel.plan is plan                       # nothing re-planned
    panel.controls["outage_length"].value = 10.0
    assert panel.plan.outages == ((30.0, 40.0),)
    assert not panel.controls["outage_start"].disabled
    assert panel.plan.settings["s_threshold"] == 0.8            # kept across a re-plan
    panel.controls["outage_start"].value = 86.0                 # at the end: refused
    assert "Not applied" in panel.status.value and panel.plan.outages == ((30.0, 40.0),)
    assert "timeline" in panel.parts and "summary" in panel.parts
    assert plan_panel(plan_mission("ground_vehicle")).controls["spin_hz"].disabled
