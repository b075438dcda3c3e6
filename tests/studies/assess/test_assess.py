"""Tests for the assess-a-flight pipeline (navlib.studies.assess), its figures and panel."""

import subprocess
import sys
import warnings

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest
from support.locations import REPO

from navlib import io, sensors
from navlib.errors import NavlibInputError
from navlib.io import FlightDataWarning
from navlib.metrics import excitability_segment, sensability_model
from navlib.models.ecef import STATE_GROUPS, STATE_NAMES
from navlib.plots import assess as plots
from navlib.plots.figure import detached
from navlib.plots.metrics import excitability_figure, restate_sensability, sensability_figure
from navlib.studies.assess import (
    E_THRESHOLD,
    assess_flight,
    describe_inputs,
    fit_report,
    fit_residuals,
)
from navlib.trajectory import stationary
from navlib.vehicles import VEHICLE_PHASES
from navlib.widgets.assess import AssessPanel, boundaries_text, parse_boundaries
from navlib.widgets.layers import agg_canvas

ROOT = REPO
SAMPLE = ROOT / "data" / "sample_flight"


@pytest.fixture(scope="module")
def sample_records():
    return io.read_imu_csv(SAMPLE / "imu.csv"), io.read_gnss_csv(SAMPLE / "gnss.csv")


@pytest.fixture(scope="module")
def sample(sample_records):
    return assess_flight(*sample_records)


@pytest.fixture(scope="module")
def still_records():
    truth = stationary(duration_s=60.0, rate_hz=100.0)
    spec = sensors.load_preset("motionpak_tactical")
    imu = sensors.simulate_imu(truth, spec, seed=11).to_frame()
    gnss = sensors.simulate_gnss(truth, spec, seed=12)
    return imu, gnss


@pytest.fixture(scope="module")
def still(still_records):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = assess_flight(*still_records)
    return result, caught


# --------------------------------------------------------------------------- sample flight


def test_shipped_sample_is_small_and_readable(sample_records):
    imu, gnss = sample_records
    size = sum(p.stat().st_size for p in SAMPLE.iterdir())
    assert size < 2_000_000
    assert 1.0 / np.median(np.diff(imu["t"])) == pytest.approx(100.0)
    assert 1.0 / np.median(np.diff(gnss["t"])) == pytest.approx(1.0)
    assert {"vx", "vy", "vz", "sigma"} <= set(gnss.columns)
    assert "seed" in (SAMPLE / "README.md").read_text()


def test_sample_script_is_deterministic(tmp_path):
    """The script regenerates the shipped files (seeded): GNSS and README byte for byte, the
    IMU to 1e-5 relative and 1e-4 absolute (m/s^2, rad/s; the accelerometer white noise is
    1.7e-3 m/s^2 per sample). Byte equality of the IMU does not hold across machines: the
    rocket's ODE integration differs in the last bits between CPUs from the rail exit on
    (measured up to 1.2e-5 m/s^2 between this machine and the one that wrote the files)."""
    done = subprocess.run([sys.executable, str(ROOT / "scripts" / "make_sample_flight.py"),
                           "--out", str(tmp_path)], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    for name in ("gnss.csv", "README.md"):
        assert (tmp_path / name).read_bytes() == (SAMPLE / name).read_bytes(), name
    ours, shipped = pd.read_csv(tmp_path / "imu.csv"), pd.read_csv(SAMPLE / "imu.csv")
    assert list(ours.columns) == list(shipped.columns) and ours.shape == shipped.shape
    np.testing.assert_allclose(ours.to_numpy(), shipped.to_numpy(), rtol=1e-5, atol=1e-4)


def test_sample_segments_and_fit(sample):
    table = sample.segment_table
    # the paper's segments on the flight's own clock: pad [0, 19], powered and spin [19, 60],
    # free fall [60, 86] s; the result's clock starts at the ignition (lift-off 18.1 s)
    t0 = sample.t_ignition
    assert t0 == pytest.approx(18.0, abs=0.3) and sample.options["time_zero"] == "ignition"
    assert table["phase"].tolist() == ["pad", "boost", "coast", "free_fall"]
    assert table["t_start"].iloc[0] == pytest.approx(-t0)
    assert table["t_start"].iloc[1] == 0.0 and table["t_end"].iloc[0] == 0.0
    assert table["t_end"].iloc[1] == pytest.approx(46.0 - t0, abs=0.5)
    assert table["t_end"].iloc[2] == pytest.approx(60.0 - t0, abs=1.0)
    assert sample.trajectory.t[0] == pytest.approx(-t0)
    assert sample.model.t[0] == pytest.approx(-t0)
    events = sample.events.set_index("event")        # detected only: CSV records log no state
    assert events.loc["ignition", "t_detected"] == 0.0 and events["t_logged"].isna().all()
    assert events.loc["burnout", "t_detected"] == pytest.approx(46.0 - t0, abs=0.5)
    # 1 Hz epochs inside each closed segment
    assert np.all(np.abs(table["n_epochs"] - table["duration"]) <= 1.0)
    fit = sample.fit.set_index(["quantity", "axis"])
    # the fit leaves the GNSS noise (5 m per axis) in its residuals ...
    for axis in "xyz":
        assert 3.5 < fit.loc[("GNSS position", axis), "rms"] < 6.5
    # ... and the IMU white noise on the axes free of thrust-scaled errors
    for axis in "yz":
        row = fit.loc[("specific force", axis)]
        assert 0.8 * row["white_noise"] < row["rms"] < 2.0 * row["white_noise"]
    for axis in "xyz":
        row = fit.loc[("angular rate", axis)]
        assert 0.8 * row["white_noise"] < row["rms"] < 1.5 * row["white_noise"]


def test_fit_report_matches_residual_series(sample):
    gnss_res, imu_res = sample.gnss_residuals, sample.imu_residuals
    fit = sample.fit.set_index(["quantity", "axis"])["rms"]
    for axis in "xyz":
        assert np.sqrt(np.mean(gnss_res[f"d{axis}"] ** 2)) == pytest.approx(
            fit[("GNSS position", axis)], rel=1e-6)
        assert np.sqrt(np.mean(imu_res[f"df_{axis}"] ** 2)) == pytest.approx(
            fit[("specific force", axis)], rel=1e-6)
    assert len(imu_res) == len(sample.trajectory.t)


def test_sample_tables_are_consistent(sample):
    ex = sample.excitability_frame()
    assert len(ex) == 21 * len(sample.segment_table)
    assert (ex["excitable"] == (ex["e"] >= E_THRESHOLD)).all()
    wide = sample.excitability_table()
    assert wide.shape == (21, 4) and list(wide.index) == list(STATE_NAMES)
    # the per-segment results are those of the metrics wrappers on the same model
    for (a, b), result in zip(sample.segments, sample.excitability, strict=True):
        direct = excitability_segment(sample.model, a, b, eta=sample.thresholds["eta"])
        np.testing.assert_allclose(result.e, direct.e)
    np.testing.assert_allclose(sample.sensability.s, sensability_model(sample.model).s)
    states = sample.state_table()
    assert states["s_fraction"].between(0, 1).all()
    assert (states["sensible"] == (states["s_fraction"] >= 0.5)).all()
    summary = sample.summary()
    for row in summary.itertuples():
        part = ex[ex["segment"] == row.segment]
        assert row.excitable.split(", ") == part.loc[part["excitable"], "state"].tolist()
        assert row.n_excitable == part["excitable"].sum()
    sens = sample.sensability_frame()
    assert len(sens) == 21 * len(sample.sensability.t)
    assert set(sens["phase"]) == {"pad", "boost", "coast", "free_fall"}


def test_sample_physics(sample):
    """Position and velocity are excitable in every segment; the spin-up and burn excite the
    roll-axis gyro and thrust-axis accelerometer scale factors only in the boost."""
    e = sample.excitability_table()
    assert (e.loc[["P_x", "P_y", "P_z", "V_x", "V_y", "V_z"]] > 0.95).all().all()
    boost, pad = e.columns[1], e.columns[0]
    assert e.loc["sg_x", boost] > 0.9 and e.loc["sg_x", pad] < 0.1
    assert e.loc["sa_x", boost] > 0.9 and e.loc["sa_x", pad] < 0.1
    assert (e.loc[["sg_y", "sg_z", "sa_y", "sa_z"]] < 0.1).all().all()


def test_with_settings_reuses_the_model(sample):
    t0 = sample.t_ignition            # the segments are on the result's clock
    other = sample.with_settings([30.0 - t0], eta=1e-2, nu=0.99)
    assert other.model is sample.model and other.trajectory is sample.trajectory
    np.testing.assert_allclose(other.segments, [(-t0, 30.0 - t0), (30.0 - t0, 86.0 - t0)])
    assert other.segment_table["phase"].tolist() == ["pad", "free_fall"]  # majority labels
    assert other.sensability.nu == 0.99
    # a larger eta keeps fewer directions in the excited subspace
    wider = sample.with_settings(eta=1e-2)
    for a, b in zip(wider.excitability, sample.excitability, strict=True):
        assert a.ne <= b.ne
    back = other.with_settings("auto")
    assert back.segments == sample.segments
    with pytest.raises(NavlibInputError, match="GNSS epoch"):
        sample.with_settings([(10.2 - t0, 10.8 - t0)])
    with pytest.raises(NavlibInputError, match="eta"):
        sample.with_settings(eta=0.0)


# --------------------------------------------------------------------------- stationary


def test_stationary_flight(still):
    result, caught = still
    assert result.segment_table["phase"].tolist() == ["rest"]
    # no motion: the heading is not observable; the fallback is taken and reported
    assert any(issubclass(w.category, FlightDataWarning) and "heading" in str(w.message)
               for w in caught)
    assert sum("heading_deg=0" in n for n in result.notes) == 1
    assert result.notes[0] == ("sensor preset 'motionpak_tactical': default (the records do "
                               "not say what the IMU is)")
    e = result.excitability_table().iloc[:, 0]
    assert (e[["P_x", "P_y", "P_z", "V_x", "V_y", "V_z"]] > 0.95).all()
    # at rest the horizontal accelerometer biases hide behind the tilt, the vertical one
    # does not; nothing turns, so no gyro scale factor is excited
    assert e["ba_x"] < 0.5 and e["ba_y"] < 0.5 and e["ba_z"] > E_THRESHOLD
    assert (e[["sg_x", "sg_y", "sg_z"]] < 0.05).all()
    assert e["bg_z"] < 0.1


def test_flight_ending_between_gnss_epochs(still_records):
    """Segments cover the fitted flight even when its end falls between model epochs."""
    imu, gnss = still_records
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FlightDataWarning)
        result = assess_flight(imu[imu["t"] <= 20.5], gnss)
    table = result.segment_table
    assert table["t_end"].iloc[-1] == pytest.approx(20.5)
    assert result.model.t[-1] == pytest.approx(20.0)
    assert table["n_epochs"].tolist() == [21]


def test_stationary_without_fallback_names_the_heading(still_records):
    with pytest.raises(NavlibInputError, match="heading_deg"):
        assess_flight(*still_records, heading_fallback_deg=None)


def test_describe_inputs(still_records):
    table = describe_inputs(*still_records).set_index("record")
    assert table.loc["imu", "samples"] == 6001
    assert table.loc["gnss", "rate_hz"] == pytest.approx(1.0)
    assert table.loc["overlap", "duration_s"] == pytest.approx(60.0)


# --------------------------------------------------------------------------- bad input


def _bad_inputs(imu, gnss):
    shifted = gnss.assign(t=gnss["t"] + 1000.0)
    pieces = imu.assign(segment=(imu["t"] > 10).astype(int))
    return [
        ((imu.to_numpy(), gnss), {}, "imu: expected a pandas DataFrame"),
        ((imu.drop(columns="w_z"), gnss), {}, r"missing column\(s\) \['w_z'\]"),
        ((imu, gnss.drop(columns="y")), {}, "gnss: missing column"),
        ((imu, shifted), {}, "do not overlap"),
        ((imu[imu["t"] <= 1.5], gnss), {}, "overlap for 1.5 s only"),
        ((imu, gnss[gnss["t"] <= 2.0]), {}, "3 epoch"),
        ((pieces.assign(t=pieces["t"] * 0.01), gnss), {},
         r"into 2 spans .* none could be assessed"),
        ((imu, gnss), {"eta": 0.0}, "eta"),
        ((imu, gnss), {"nu": 1.5}, "nu"),
        ((imu, gnss), {"min_fraction": -0.1}, "min_fraction"),
        ((imu, gnss), {"preset": 3}, "preset"),
        ((imu, gnss), {"preset": "no_such_imu"}, "unknown sensor preset"),
        ((imu, gnss), {"gnss_rate_hz": -1.0}, "gnss_rate_hz"),
        ((imu, gnss), {"fit_options": {"knots": 3}}, "unknown keyword"),
        ((imu, gnss), {"segment_options": {"rest": 3}}, "unknown keyword"),
        ((imu, gnss), {"model_options": {"gnss_sigma_m": 3}}, "gnss_sigma_m"),
    ]


def test_bad_inputs_are_named(still_records):
    for args, kwargs, match in _bad_inputs(*still_records):
        with pytest.raises(NavlibInputError, match=match):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", FlightDataWarning)
                assess_flight(*args, **kwargs)


def test_bad_segments_are_named(still):
    result, _ = still
    with pytest.raises(NavlibInputError, match=r"segment 1 .* holds 1 GNSS epoch"):
        result.with_settings([0.3, 0.6])
    with pytest.raises(NavlibInputError, match="leaves the flight span"):
        result.with_settings([(5.0, 80.0)])


def test_fit_helpers_reject_foreign_objects(still, still_records):
    result, _ = still
    with pytest.raises(NavlibInputError, match="fit_residuals"):
        fit_report(stationary(duration_s=10.0))
    imu, gnss = still_records
    with pytest.raises(NavlibInputError, match="IMU times"):
        fit_residuals(result.trajectory, imu.iloc[::2], gnss)


# --------------------------------------------------------------------------- figures, panel


def test_figures_draw(sample):
    for fig in (plots.phases_figure(sample), plots.fit_residuals_figure(sample),
                plots.estimable_figure(sample), excitability_figure(sample),
                sensability_figure(sample, ["bg_x", "bg_y", "bg_z"])):
        assert fig.axes
        plt.close(fig)
    t0 = sample.t_ignition
    edited = sample.with_settings(pd.DataFrame({"phase": ["pad", "flight"],
                                                "t_start": [-t0, 0.0],
                                                "t_end": [0.0, 86.0 - t0]}))
    fig = plots.phases_figure(edited)
    assert "1 pad" in [t.get_text() for t in fig.axes[0].texts]
    plt.close(fig)


def test_panel_updates_and_reports_errors(sample):
    panel = AssessPanel(sample)
    assert panel.status.value.startswith("ok: 4 segment(s)")
    panel.controls["boundaries"].value = "18, 46, 200"
    assert "outside the flight span" in panel.status.value
    assert panel.assessment.segments == sample.segments          # last good result kept
    panel.controls["boundaries"].value = "-10; 0"
    np.testing.assert_allclose(panel.assessment.segments[:2],
                               [(-sample.t_ignition, -10.0), (-10.0, 0.0)])
    panel.controls["eta"].value = 1e-2
    assert panel.assessment.thresholds["eta"] == pytest.approx(1e-2)
    panel.controls["boundaries"].value = "auto"
    assert panel.assessment.segments == sample.segments
    plt.close("all")


def _rgba(fig) -> np.ndarray:
    canvas = agg_canvas(fig)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba()).copy()


def test_restated_sensability_figure_draws_as_a_new_one(sample):
    """Another state group put on a sensability figure in place, laid out again, draws
    pixel for pixel as a figure built for it (curves, bands, their limits, labels)."""
    states = STATE_GROUPS["gyro_scale"]
    with detached():
        fig = sensability_figure(sample, STATE_GROUPS["attitude"], title="t")
        built = sensability_figure(sample, states, title="t")
    _rgba(fig)
    lines = restate_sensability(fig, sample, states)
    assert [ln.axes.get_ylabel() for ln in lines] == [f"s({s})" for s in states]
    np.testing.assert_array_equal(_rgba(fig), _rgba(built))
    with pytest.raises(ValueError, match="3 rows, not 2"):
        restate_sensability(fig, sample, states[:2])


def test_panel_group_change_relabels_in_place_and_keeps_each_layout(sample):
    """The state group changes the kept sensability figure (no new figure): its labels and
    units follow the group, and a group shown before gets its own layout back."""
    panel = AssessPanel(sample)
    fig = panel._figures["sensability"].fig
    positions = [ax.get_position().bounds for ax in fig.axes]
    panel.controls["group"].value = "gyro_scale"
    assert panel._figures["sensability"].fig is fig
    labels = [ax.get_ylabel() for ax in fig.axes]
    assert labels[:3] == ["s(sg_x)", "s(sg_y)", "s(sg_z)"] and "ppm" in labels[3]
    scale_positions = [ax.get_position().bounds for ax in fig.axes]
    assert scale_positions != positions           # wider tick labels: laid out again
    panel.controls["group"].value = "attitude"
    np.testing.assert_allclose([ax.get_position().bounds for ax in fig.axes], positions)
    panel.controls["group"].value = "gyro_scale"
    np.testing.assert_allclose([ax.get_position().bounds for ax in fig.axes], scale_positions)
    plt.close("all")


def test_boundary_text_round_trip(sample):
    assert parse_boundaries(boundaries_text(sample)) == [b for _, b in sample.segments[:-1]]
    assert parse_boundaries(" ") == "auto"
    with pytest.raises(NavlibInputError, match="boundary times"):
        parse_boundaries("18, x")


# --------------------------------------------------------------------------- PX4 logs


def test_px4_simulated_flight_assessment(px4_log_path):
    path = px4_log_path("sample_px4_events.ulg")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        imu, gnss = io.read_ulog(path)
        result = assess_flight(imu, gnss)
    assert result.options["gnss_rate_hz"] == pytest.approx(19.2, abs=0.5)
    assert result.options["gnss_sigma_m"] < 1.0          # the log's own eph/epv
    # read_ulog attaches the log's MAV_TYPE (2, quadrotor): the phases are a multicopter's
    assert imu.attrs["mav_type"] == 2 and result.vehicle == "multicopter"
    assert set(result.segment_table["phase"]) <= set(VEHICLE_PHASES["multicopter"])
    assert "rest" in set(result.segment_table["phase"])  # a quasi-static drone flight
    # the log says what it is and carries the autopilot's attitude: both are used, said so
    assert result.options["preset"] == "pixhawk_mems"
    assert result.options["attitude_source"] == "log"
    assert any("autopilot's own attitude" in n for n in result.notes)
    assert not any("heading_deg=0" in str(w.message) for w in caught)
    summary = result.summary()
    assert (summary["n_excitable"] >= 6).all()           # position and velocity at least
