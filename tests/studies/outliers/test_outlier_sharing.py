"""The work the outlier study shares: unit responses scaled by the magnitude, one
recursion for several responses, the compact block-wise filter preparation, the cache's
kept responses and covariance summaries, and the EKF run resumed from a snapshot."""

import numpy as np
import pytest
from support.paths import assert_same_numbers

from navlib import NavlibInputError
from navlib.filters import linear, linear_preparation, prepare_linear, simulate_ekf, simulate_linear
from navlib.models import launcher
from navlib.sensors.faults import Outlier
from navlib.studies import outliers as study
from navlib.trajectory import launcher_ascent


@pytest.fixture(scope="module")
def flight():
    return launcher_ascent(duration_s=40.0, rate_hz=20.0)


@pytest.fixture(scope="module")
def prepared(flight):
    return prepare_linear(launcher("ins_gps_att_rt", "GAP", "markov", flight))


@pytest.mark.parametrize("outlier", [
    Outlier("gyro_x", 20.0, 0.0037), Outlier("rt_x", 18.0, -0.002, "step"),
    Outlier("gnss_vel", 21.0, 3.0, "pulse", duration=1.5), Outlier("att_y", 19.0, 0.01)])
def test_scaled_unit_response_equals_a_direct_run(prepared, outlier):
    """a x (response to a unit outlier) = the response simulated with magnitude a."""
    direct = simulate_linear(prepared, outliers=outlier, noise=False, initial_error=False,
                             record_every=3)
    unit = linear.unit_responses(prepared, [outlier], record_every=3)
    assert unit.outliers[0].magnitude == 1.0 and unit.nees is None
    scale = np.abs(direct.estimate).max()
    assert scale > 0
    for name in ("truth", "estimate"):
        np.testing.assert_allclose(outlier.magnitude * getattr(unit, name),
                                   getattr(direct, name), rtol=0, atol=1e-12 * scale)
    assert_same_numbers(unit.P, direct.P, "P")
    assert unit.applied == direct.applied == (True,)


def test_one_recursion_for_several_responses(prepared):
    outs = [Outlier("gyro_x", 20.0, 1.0), Outlier("rt_x", 25.0, 1.0, "step"),
            Outlier("gnss_pos_z", 15.0, 1.0)]
    batch = linear.unit_responses(prepared, outs)
    for i, o in enumerate(outs):
        alone = linear.unit_responses(prepared, [o])
        np.testing.assert_allclose(batch.estimate[:, i], alone.estimate[:, 0], rtol=0,
                                   atol=1e-13 * np.abs(alone.estimate).max())
    with pytest.raises(NavlibInputError, match="outliers"):
        linear.unit_responses(prepared, [])


def test_study_response_is_the_scaled_unit_response(flight):
    cache = study.FilterCache(flight, size=1)
    out = Outlier("gyro_x", 20.0, 0.002)
    r = study.outlier_response("ins_gps", out, "roll", cache=cache, record_every=2)
    double = study.outlier_response("ins_gps", Outlier("gyro_x", 20.0, -0.004), "roll",
                                    cache=cache, record_every=2)
    np.testing.assert_allclose(double.induced, -2.0 * r.induced, rtol=1e-13)
    assert double.score.retained == pytest.approx(r.score.retained, rel=1e-12)
    direct = simulate_linear(cache.get("ins_gps"), outliers=out, noise=False,
                             initial_error=False, record_every=2)
    rows = study.watch_rows("roll", direct.state_names,
                            flight.attitude.as_matrix()[direct.index])
    truth, est, sigma = direct.project(rows)
    np.testing.assert_allclose(r.induced, (est - truth)[:, 0], rtol=0,
                               atol=1e-12 * np.abs(r.induced).max())
    assert_same_numbers(r.sigma, sigma, "sigma")
    np.testing.assert_array_equal(r.t, direct.t)


def test_cache_keeps_responses_and_summaries_after_release(flight):
    cache = study.FilterCache(flight, size=1)
    out = Outlier("rt_x", 20.0, 0.002)
    first = study.outlier_response("ins_gps_rt", out, "roll", cache=cache)
    corr = study.correlation_fig10(cache=cache)
    cache.release()
    assert not cache._items
    again = study.outlier_response("ins_gps_rt", out, "roll", cache=cache)
    np.testing.assert_array_equal(again.induced, first.induced)
    assert study.correlation_fig10(cache=cache).equals(corr)
    assert not cache._items                         # nothing was prepared again
    with pytest.raises(NavlibInputError, match="psi_ref"):
        study.correlation_fig10(cache=cache, solution="ins_gps")


@pytest.mark.parametrize("solution", ["ins_gps", "ins_gps_att_rt"])
def test_compact_preparation_is_the_same_filter(flight, solution):
    model = launcher(solution, "GAP", "markov", flight)
    full = prepare_linear(model)
    compact = prepare_linear(model, compact=True)
    assert compact.covariance.P_prior is None and compact.steps.Q is None
    assert_same_numbers(compact.covariance.P_post, full.covariance.P_post, "P_post")
    for name in ("K", "S_pinv", "dof"):
        assert_same_numbers(getattr(compact.gains, name), getattr(full.gains, name), name)
    for block in (7, 800):            # 801 epochs: a last block of one epoch
        cov, gains = linear_preparation._blockwise_covariance(full.steps, full.measured,
                                                              block=block)
        assert_same_numbers(cov.P_post, full.covariance.P_post, f"P_post, block {block}")
        assert_same_numbers(gains.K, full.gains.K, f"K, block {block}")
    a = simulate_linear(compact, runs=4, seed=2, outliers=Outlier("gyro_x", 10.0, 0.01))
    b = simulate_linear(full, runs=4, seed=2, outliers=Outlier("gyro_x", 10.0, 0.01))
    assert_same_numbers(a.estimate, b.estimate, "estimate")
    assert_same_numbers(a.nees, b.nees, "nees")


@pytest.mark.parametrize("update_every", [1, 3])
def test_recursion_gains_are_those_of_the_priors(flight, update_every):
    """The gains prepare_linear keeps from its covariance recursion are kalman_gains of the
    recorded priors (S^+ at the update epochs: elsewhere it is not kept; two paths, compared
    at ``paths.CROSS_PATH_RTOL``)."""
    from navlib.kalman import kalman_gains

    model = launcher("ins_gps_att_rt", "GAP", "markov", flight)   # singular R: pseudo-inverse
    full = prepare_linear(model, update_every=update_every)
    want = kalman_gains(full.covariance.P_prior, full.steps.H, full.steps.R, full.measured)
    assert_same_numbers(full.gains.K, want.K, "K")
    np.testing.assert_array_equal(full.gains.dof, want.dof)
    measured = full.measured
    assert_same_numbers(full.gains.S_pinv[measured], want.S_pinv[measured], "S_pinv")
    assert not full.gains.S_pinv[~measured].any()


def test_simulation_without_nees(prepared):
    sim = simulate_linear(prepared, runs=2, seed=0, nees=False)
    assert sim.nees is None and sim.nees_dof is None
    c = sim.consistency()
    assert np.isnan(c["nees"]) and c["nis"] > 0
    with pytest.raises(NavlibInputError, match="NEES"):
        sim.nees_frame()


@pytest.mark.parametrize("solution", ["ins_gps", "ins_gps_att"])
def test_resumed_ekf_run_equals_the_run_from_the_start(solution):
    traj = launcher_ascent(duration_s=20.0, rate_hz=50.0)
    out = Outlier("gyro_x", 8.0, 0.002)
    kw = dict(solution=solution, biases="GAP", noise=False, initial_error=False,
              gnss_rate_hz=50.0)
    whole = simulate_ekf(traj, outliers=out, **kw)
    nominal = simulate_ekf(traj, snapshot_before=8.0 - 0.02, **kw)
    assert nominal.result.snapshot.t < 8.0 - 0.02
    resumed = simulate_ekf(traj, outliers=out, resume=nominal, **kw)
    for name in ("t", "position", "velocity", "C_b_e", "sigma", "innovation", "nis"):
        np.testing.assert_array_equal(getattr(resumed.result, name),
                                      getattr(whole.result, name), err_msg=name)
    assert resumed.errors.equals(whole.errors)
    assert not np.array_equal(resumed.result.C_b_e, nominal.result.C_b_e)
    with pytest.raises(NavlibInputError, match="not before"):
        simulate_ekf(traj, outliers=Outlier("gyro_x", 5.0, 0.002), resume=nominal, **kw)
    with pytest.raises(NavlibInputError, match="snapshot_before"):
        simulate_ekf(traj, resume=whole, **kw)


def test_no_snapshot_with_the_closed_loop_reference():
    traj = launcher_ascent(duration_s=10.0, rate_hz=20.0)
    with pytest.raises(NavlibInputError, match="posterior"):
        simulate_ekf(traj, solution="ins_gps_rt", biases="GA", noise=False,
                     initial_error=False, gnss_rate_hz=20.0, snapshot_before=5.0)


def test_conclusion_runs_kept_without_conclusions(flight, monkeypatch):
    """paper_tests without ``conclusions`` (notebook 05) still runs the conclusion spikes in
    its recursions and keeps them: the same study with ``conclusions`` (the claims engine)
    then prepares no filter, and its conclusions are those of a study run alone."""
    kw = dict(shapes=("spike",), outlier_time_s=20.0, window=15.0)
    first = study.FilterCache(flight, size=1)
    study.paper_tests(cache=first, **kw)
    first.release()
    shared = study.FilterCache(flight, size=1)
    study.adopt_filters(shared, first)

    def no_preparation(*_args, **_kwargs):
        raise AssertionError("a filter was prepared")

    with monkeypatch.context() as patch:
        patch.setattr(study.response, "prepare_linear", no_preparation)
        got = study.paper_tests(cache=shared, conclusions=True, **kw)
    alone = study.paper_tests(cache=study.FilterCache(flight, size=1), conclusions=True, **kw)
    assert got.conclusions.keys() == alone.conclusions.keys() and got.conclusions
    for key, r in alone.conclusions.items():
        np.testing.assert_allclose(got.conclusions[key].induced, r.induced, rtol=0,
                                   atol=1e-12 * max(np.abs(r.induced).max(), 1e-300))
    assert [c.verdict for c in got.claims] == [c.verdict for c in alone.claims]
