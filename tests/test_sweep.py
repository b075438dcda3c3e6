"""navlib.sweep: grids, named evaluations, serial == cluster, resume after interruption."""

from __future__ import annotations

import sys

import numpy as np
import pandas as pd
import pytest

from navlib import NavlibInputError, sweep
from navlib.filters.monte_carlo import monte_carlo_linear
from navlib.metrics import sensability_model
from navlib.models.launcher import launcher
from navlib.observability import local_observability
from navlib.parallel import map_tasks
from navlib.studies.rocket import rocket_chain
from navlib.trajectory import launcher_ascent


def _quadratic(a, b, tag="x"):
    """A cheap deterministic evaluation with float, int, bool and string results."""
    x = np.linalg.norm(np.arange(1.0, 4.0) * a) + np.sqrt(b)
    return {"y": float(x), "n": int(a * 10), "big": bool(x > 3.0), "label": f"{tag}{a}"}


class _Recorder:
    """Counts calls (synchronous scheduler only) and fails on request."""

    def __init__(self, fail_at=None):
        self.calls = []
        self.fail_at = fail_at

    def __call__(self, a, b):
        if (a, b) == self.fail_at:
            raise RuntimeError("interrupted")
        self.calls.append((a, b))
        return _quadratic(a, b)


GRID = {"a": [0.5, 1.0, 2.0], "b": [1.0, 4.0]}


def test_grid_points_product_order_and_frame():
    points = sweep.grid_points({"a": [1, 2], "b": ["x", "y", "z"]})
    assert list(points.columns) == ["a", "b"]
    assert points.values.tolist() == [[1, "x"], [1, "y"], [1, "z"], [2, "x"], [2, "y"],
                                      [2, "z"]]
    frame = pd.DataFrame({"a": [3.0, 1.0], "b": [1, 2]})
    assert sweep.grid_points(frame).equals(frame)


@pytest.mark.parametrize("grid, match", [
    ({"a": 1.0}, "list of values"),
    ({"a": "abc"}, "list of values"),
    ({"a": []}, "no values"),
    ({}, "no points"),
    ({"a": [1.0, 1]}, "repeats"),
    ([1, 2], "dict of value lists"),
    (pd.DataFrame(), "no points"),
])
def test_grid_validation(grid, match):
    with pytest.raises(NavlibInputError, match=match):
        sweep.sweep(grid, _quadratic, scheduler="synchronous")


def test_evaluate_and_scheduler_validation(tmp_path):
    with pytest.raises(NavlibInputError, match=r"unknown evaluation.*'sensability'"):
        sweep.sweep(GRID, "no_such_thing", scheduler="synchronous")
    with pytest.raises(NavlibInputError, match=r"expected a navlib\.sweep\.Evaluation"):
        sweep.register(_quadratic)
    with pytest.raises(NavlibInputError, match="unknown keyword"):
        sweep.sweep({"spin_hz": [1.0], "gyro_colour": ["red"]}, "sensability",
                    scheduler="synchronous")
    with pytest.raises(NavlibInputError, match="callable"):
        sweep.sweep(GRID, 3.0, scheduler="synchronous")
    with pytest.raises(NavlibInputError, match="scheduler"):
        sweep.sweep(GRID, _quadratic, scheduler="my-laptop")
    with pytest.raises(NavlibInputError, match="scheduler"):
        sweep.sweep(GRID, _quadratic, scheduler=8786)
    with pytest.raises(NavlibInputError, match=r"\.parquet"):
        sweep.sweep(GRID, _quadratic, scheduler="synchronous", output=tmp_path / "r.csv")
    with pytest.raises(NavlibInputError, match="mapping"):
        sweep.sweep(GRID, lambda a, b: a + b, scheduler="synchronous")
    with pytest.raises(NavlibInputError, match="repeat parameter"):
        sweep.sweep(GRID, lambda a, b: {"a": a}, scheduler="synchronous")
    with pytest.raises(NavlibInputError, match="number, bool or string"):
        sweep.sweep(GRID, lambda a, b: {"v": [a, b]}, scheduler="synchronous")
    with pytest.raises(NavlibInputError, match="batch_size"):
        sweep.sweep(GRID, _quadratic, scheduler="synchronous", batch_size=0)


def test_environment_variable_selects_scheduler(monkeypatch):
    monkeypatch.setenv(sweep.SCHEDULER_ENV, "synchronous")
    frame = sweep.sweep(GRID, _quadratic)
    assert frame.attrs["sweep"]["n_workers"] == 1
    monkeypatch.setenv(sweep.SCHEDULER_ENV, "nowhere")
    with pytest.raises(NavlibInputError, match="nowhere"):
        sweep.sweep(GRID, _quadratic)


def test_serial_sweep_rows_and_columns():
    frame = sweep.sweep(GRID, _quadratic, scheduler="synchronous", batch_size=4)
    assert list(frame.columns) == ["a", "b", "y", "n", "big", "label"]
    assert len(frame) == 6 and frame.attrs["sweep"]["n_tasks"] == 2
    for row in frame.itertuples():
        assert row.y == _quadratic(row.a, row.b)["y"]
    assert frame.label.tolist() == ["x0.5", "x0.5", "x1.0", "x1.0", "x2.0", "x2.0"]


def test_named_covariance_matches_direct_computation():
    """The 'covariance' evaluation is the rocket chain's information recursion."""
    grid = {"gnss_sigma_m": [2.0, 10.0], "sigma_sg_ppm": [1000.0]}
    frame = sweep.sweep(grid, "covariance", scheduler="synchronous")
    for row in frame.itertuples():
        model = rocket_chain(2.0, "ecef", None, row.gnss_sigma_m, sigma_sg_ppm=1000.0)
        se = sensability_model(model)
        assert row.sigma_end_P_x == pytest.approx(se.sigma[-1, 0], rel=1e-12)
        assert row.sigma_end_sg_x == pytest.approx(se.sigma[-1, 15], rel=1e-12)
        assert row.ratio_sg_x == pytest.approx(1000e-6 / se.sigma[-1, 15], rel=1e-12)
    # a bigger GNSS sigma leaves a bigger final position sigma
    assert frame.sigma_end_P_x.iloc[1] > frame.sigma_end_P_x.iloc[0]
    # the named evaluation called directly gives the same row
    direct = sweep.EVALUATIONS["covariance"](gnss_sigma_m=2.0, sigma_sg_ppm=1000.0)
    assert direct["sigma_end_P_x"] == frame.sigma_end_P_x.iloc[0]


def test_named_evaluations_run_on_a_small_grid():
    ex = sweep.sweep({"eta": [1e-1, 1e-4]}, "excitability", scheduler="synchronous")
    # a larger energy threshold excites fewer directions
    assert (ex.ne_tau2.iloc[0] <= ex.ne_tau2.iloc[1])
    assert ex.filter(regex="^e_").to_numpy().max() <= 1.0 + 1e-12
    nees = sweep.sweep({"seed": [0, 1]}, "nees", scheduler="synchronous")
    assert nees.nees_in_bounds.between(0.0, 1.0).all()
    assert nees.nees_end.iloc[0] != nees.nees_end.iloc[1]  # seeds matter
    obs = sweep.sweep({"solution": ["ins_gps_att"], "bias_model": ["markov"],
                       "duration_s": [40.0], "rate_hz": [20.0], "stride": [20]},
                      "observability", scheduler="synchronous")
    model = launcher("ins_gps_att", "GAP", "markov",
                     trajectory=launcher_ascent(duration_s=40.0, rate_hz=20.0))
    direct = local_observability(model, stride=20)
    assert obs.n_states.iloc[0] == model.n
    assert obs.n_unobservable.iloc[0] == direct.n_unobservable
    assert obs.log10_cond.iloc[0] == pytest.approx(direct.log10_max_cond, rel=1e-9)


@pytest.fixture(scope="module")
def client():
    distributed = pytest.importorskip("distributed")
    import cloudpickle

    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=":0")
    with distributed.Client(cluster) as c:
        yield c
    cluster.close()


def test_cluster_results_equal_serial_exactly(client):
    grid = {"spin_hz": [2.0], "gnss_sigma_m": [3.0, 15.0], "sigma_sg_ppm": [500.0, 5000.0]}
    serial = sweep.sweep(grid, "sensability", scheduler="synchronous")
    parallel = sweep.sweep(grid, "sensability", scheduler=client, batch_size=1)
    assert parallel.attrs["sweep"]["n_workers"] == 2
    pd.testing.assert_frame_equal(serial, parallel, check_exact=True)
    serial = sweep.sweep(GRID, _quadratic, scheduler="synchronous")
    parallel = sweep.sweep(GRID, _quadratic, scheduler=client, batch_size=1)
    pd.testing.assert_frame_equal(serial, parallel, check_exact=True)


def test_map_tasks_in_order_with_shared(client):
    out = map_tasks(_scaled, [1.0, 2.0, 3.0], client, shared={"factor": np.arange(3.0)})
    assert [o.tolist() for o in out] == [[0.0, 1.0, 2.0], [0.0, 2.0, 4.0], [0.0, 3.0, 6.0]]


def _scaled(x, factor):
    return x * factor


def test_resume_skips_finished_points(tmp_path):
    out = tmp_path / "study.parquet"
    first = sweep.sweep({"a": [0.5, 1.0], "b": [1.0, 4.0]}, _Recorder(), scheduler="synchronous",
                        output=out)
    assert out.exists() and len(first) == 4
    rec = _Recorder()
    full = sweep.sweep(GRID, rec, scheduler="synchronous", output=out)
    assert sorted(rec.calls) == [(2.0, 1.0), (2.0, 4.0)]
    assert full.attrs["sweep"]["n_computed"] == 2
    fresh = sweep.sweep(GRID, _quadratic, scheduler="synchronous")
    pd.testing.assert_frame_equal(full, fresh, check_exact=True)
    stored = pd.read_parquet(out)
    pd.testing.assert_frame_equal(stored, fresh, check_exact=True)


def test_resume_after_interruption(tmp_path):
    out = tmp_path / "study.parquet"
    with pytest.raises(RuntimeError, match="interrupted"):
        sweep.sweep(GRID, _Recorder(fail_at=(2.0, 1.0)), scheduler="synchronous", output=out,
                    batch_size=1)
    assert not out.exists()  # only the finished tasks, in the parts folder
    assert len(list((tmp_path / "study.parquet.parts").glob("part-*.parquet"))) == 4
    rec = _Recorder()
    frame = sweep.sweep(GRID, rec, scheduler="synchronous", output=out, batch_size=1)
    assert sorted(rec.calls) == [(2.0, 1.0), (2.0, 4.0)]
    pd.testing.assert_frame_equal(frame, sweep.sweep(GRID, _quadratic,
                                                     scheduler="synchronous"))
    assert not (tmp_path / "study.parquet.parts").exists()


def test_output_of_another_sweep_is_refused(tmp_path):
    out = tmp_path / "study.parquet"
    sweep.sweep(GRID, _quadratic, scheduler="synchronous", output=out)
    with pytest.raises(NavlibInputError, match="another sweep"):
        sweep.sweep({"a": [1.0]}, _quadratic, scheduler="synchronous", output=out)
    (tmp_path / "junk.parquet").write_text("not parquet")
    with pytest.raises(NavlibInputError, match="not a readable Parquet"):
        sweep.sweep(GRID, _quadratic, scheduler="synchronous",
                    output=tmp_path / "junk.parquet")


# --------------------------------------------------------------------------- study hooks


def test_table2_on_the_cluster_equals_local(client):
    from navlib.studies.launcher import table2

    traj = launcher_ascent(duration_s=20.0, rate_hz=20.0)
    kw = {"stride": 10, "solutions": ("ins_gps_att",)}
    local = table2(traj, **kw)
    remote = table2(traj, scheduler=client, **kw)
    assert len(remote.frame) == 15
    pd.testing.assert_frame_equal(local.frame, remote.frame, check_exact=True)


def test_rocket_sensitivity_sweep_on_the_cluster_equals_local(client):
    from navlib.studies.rocket import sensitivity_sweep

    grid = {"eta": (1e-2, 1e-4), "gnss_sigma_m": (15.0,)}
    local = sensitivity_sweep(grid, progress=False)
    remote = sensitivity_sweep(grid, progress=False, scheduler=client)
    pd.testing.assert_frame_equal(local, remote, check_exact=True)


def test_monte_carlo_split_over_tasks(client):
    from navlib.filters import simulate_linear

    model = launcher("ins_gps", "G", "markov",
                     trajectory=launcher_ascent(duration_s=10.0, rate_hz=20.0))
    serial = monte_carlo_linear(model, runs=7, seed=3, scheduler="synchronous", runs_per_task=3)
    remote = monte_carlo_linear(model, runs=7, seed=3, scheduler=client, runs_per_task=3)
    assert serial.runs == 7
    for name in ("truth", "estimate", "nees", "nis", "innovation", "P"):
        np.testing.assert_array_equal(getattr(serial, name), getattr(remote, name))
    # chunk 2 (runs 3-5) is one plain batch drawn from the second child seed
    child = np.random.SeedSequence(3).spawn(3)[1]
    alone = simulate_linear(model, runs=3, seed=child, record_every=1)
    np.testing.assert_array_equal(serial.truth[:, 3:6], alone.truth)
    with pytest.raises(NavlibInputError, match="rng"):
        monte_carlo_linear(model, runs=4, rng=np.random.default_rng(0), scheduler="synchronous")


# --------------------------------------------------------------------------- heat maps


def _study():
    return sweep.sweep({"a": [0.5, 1.0, 2.0], "b": [1.0, 4.0], "tag": ["x", "y"]}, _quadratic,
                       scheduler="synchronous")


def test_pivot_selects_and_combines():
    frame = _study()
    table = sweep.pivot(frame, "a", "b", "y", fixed={"tag": "x"})
    assert table.shape == (2, 3)
    assert table.loc[4.0, 2.0] == _quadratic(2.0, 4.0)["y"]
    both = sweep.pivot(frame, "a", "b", "big", agg="max")
    assert set(np.unique(both.to_numpy())) <= {0.0, 1.0}
    for kwargs, match in (({"x": "a", "y": "a", "value": "y"}, "differ"),
                          ({"x": "a", "y": "zz", "value": "y"}, "unknown column"),
                          ({"x": "a", "y": "b", "value": "label"}, "not numeric"),
                          ({"x": "a", "y": "b", "value": "y", "agg": "sum"}, "agg"),
                          ({"x": "a", "y": "b", "value": "y", "fixed": {"tag": "q"}},
                           "no point")):
        with pytest.raises(NavlibInputError, match=match):
            sweep.pivot(frame, **kwargs)


def test_heatmap_annotates_the_pivot_values():
    import matplotlib.pyplot as plt

    from navlib.plots.figure import detached
    from navlib.plots.sweep import heatmap, heatmaps_figure

    frame = _study()
    fig = heatmap(frame, "a", "b", "y", fixed={"tag": "y"}, threshold=3.0)
    texts = sorted(float(t.get_text()) for t in fig.axes[0].texts)
    expected = sorted(float(f"{v:.3g}") for v in
                      sweep.pivot(frame, "a", "b", "y", fixed={"tag": "y"}).to_numpy().ravel())
    assert texts == expected
    n_outlined = sum(1 for p in fig.axes[0].patches if p.get_edgecolor()[0] == 1.0)
    assert n_outlined == int((sweep.pivot(frame, "a", "b", "y").to_numpy() >= 3.0).sum())
    plt.close(fig)
    fig = heatmaps_figure(frame, "a", "b", ["y", "n"])
    assert len(fig.axes) == 4  # two maps, two colour bars
    plt.close(fig)
    held = plt.get_fignums()
    with detached():
        heatmap(frame, "a", "b", "y")
        heatmaps_figure(frame, "a", "b", ["y", "n"])
    assert plt.get_fignums() == held  # detached figures stay out of pyplot


def test_sweep_panel_fixes_and_reports_bad_choices():
    from navlib.widgets.sweep import sweep_panel

    frame = _study()
    panel = sweep_panel(frame, x="a", y="b", value="y")
    assert set(panel.values) == {"y", "n", "big"}
    assert list(panel.parts) == ["heatmap"]
    first = panel.parts["heatmap"].value
    assert bytes(first[:4]) == b"\x89PNG"
    assert [panel.controls[f"fix:{p}"].disabled for p in ("a", "b", "tag")] == \
        [True, True, False]
    panel.controls["fix:tag"].value = "y"
    assert panel.fixed() == {"tag": "y"}
    shown = panel.parts["heatmap"].value
    assert shown != first
    panel.controls["y"].value = "a"
    assert "must differ" in panel.status.value
    assert panel.parts["heatmap"].value == shown  # the last good map stays
    with pytest.raises(NavlibInputError, match="parameter"):
        sweep_panel(frame.drop(columns="tag").assign(), parameters=["a"])
    frame.attrs = {}
    with pytest.raises(NavlibInputError, match="not a sweep result"):
        sweep_panel(frame)


def test_read_back_a_saved_sweep(tmp_path):
    out = tmp_path / "s.parquet"
    frame = sweep.sweep(GRID, _quadratic, scheduler="synchronous", output=out)
    back = sweep.read(out)
    assert sweep.parameter_columns(back) == ["a", "b"]
    pd.testing.assert_frame_equal(back, frame)
    with pytest.raises(NavlibInputError, match="no sweep result"):
        sweep.read(tmp_path / "none.parquet")


def test_address_and_thread_schedulers_equal_serial(client):
    serial = sweep.sweep(GRID, _quadratic, scheduler="synchronous")
    by_address = sweep.sweep(GRID, _quadratic, scheduler=client.scheduler.address)
    pd.testing.assert_frame_equal(serial, by_address, check_exact=True)
    threads = sweep.sweep(GRID, _quadratic, scheduler="threads")
    pd.testing.assert_frame_equal(serial, threads, check_exact=True)
    assert threads.attrs["sweep"]["n_workers"] >= 1


def test_named_claims_and_outliers_match_the_studies():
    from navlib.sensors.faults import Outlier
    from navlib.studies import rocket
    from navlib.studies.outliers import outlier_response

    claims = sweep.EVALUATIONS["claims"](nu=0.99)
    analysis = rocket.excitability_study(nu=0.99)
    table = rocket.claims_table(analysis)
    expected = dict(zip(table["claim_id"], table["verdict"] == "reproduced", strict=True))
    assert {k: claims[k] for k in expected} == expected
    frame = sweep.sweep({"solution": ["ins_gps", "ins_gps_att"], "duration_s": [40.0],
                         "rate_hz": [20.0], "time_s": [20.0], "window_s": [15.0]},
                        "outliers", scheduler="synchronous")
    traj = launcher_ascent(duration_s=40.0, rate_hz=20.0)
    for row in frame.itertuples():
        direct = outlier_response(row.solution, Outlier("gyro_x", 20.0, 0.002), "roll",
                                  trajectory=traj, window=15.0).score
        assert row.verdict == direct.verdict
        assert row.retained == pytest.approx(direct.retained, rel=1e-9)
