"""The robustness sets of all_claims share builds across their points; every shared path
must give exactly the numbers of the unshared one on this machine (the same code run twice
or cached: bitwise is the point). The claims table against its stored reference is a golden
test (tests/regression/test_claims_golden.py)."""

import numpy as np
import pytest

from navlib import NavlibInputError
from navlib.covariance import ins_only_covariance, kalman_covariance, kalman_covariances
from navlib.models.base import DiscreteModel
from navlib.studies import rocket
from navlib.studies import ssac as study_ssac


def _system(n=5, m=2, count=40, seed=3):
    """Time-varying F, H; R definite at some epochs, singular or zero at others."""
    rng = np.random.default_rng(seed)
    F = np.eye(n) + 0.1 * rng.standard_normal((count - 1, n, n))
    Q = np.broadcast_to(1e-3 * np.eye(n), (count - 1, n, n))
    H = rng.standard_normal((count, m, n))
    R = np.array(np.broadcast_to(0.2 * np.eye(m), (count, m, m)))
    R[::4] = 0.0
    R[1::4, 0, 0] = 0.0
    P0s = []
    for _ in range(3):
        A = rng.standard_normal((n, n))
        P0s.append(A @ A.T + 0.1 * np.eye(n))
    return F, Q, H, R, np.stack(P0s), rng.random(count) < 0.7


def _same(a, b):
    np.testing.assert_array_equal(a.P_prior, b.P_prior)
    np.testing.assert_array_equal(a.P_post, b.P_post)
    np.testing.assert_array_equal(a.measured, b.measured)


@pytest.mark.parametrize("options", [{}, {"update_first": False}, {"measured": "mask"}])
def test_stacked_recursion_equals_separate_runs(options):
    F, Q, H, R, P0s, mask = _system()
    options = {k: (mask if v == "mask" else v) for k, v in options.items()}
    stacked = kalman_covariances(F, Q, H, R, P0s, **options)
    assert len(stacked) == len(P0s)
    for P0, result in zip(P0s, stacked, strict=True):
        _same(result, kalman_covariance(F, Q, H, R, P0, **options))
    # the members differ (a recursion that used only the first P0 would fail above)
    assert not np.allclose(stacked[0].P_post[1], stacked[1].P_post[1])
    for P0, result in zip(P0s, kalman_covariances(F, Q, None, None, list(P0s)), strict=True):
        _same(result, ins_only_covariance(F, Q, P0))


def test_stacked_recursion_takes_a_model_and_rejects_bad_p0():
    F, Q, H, R, P0s, _ = _system()
    model = DiscreteModel(np.arange(F.shape[0] + 1.0), F, Q, H, R,
                          tuple(f"x{i}" for i in range(5)), ("y0", "y1"), P0s[0])
    (only,) = kalman_covariances(model)
    _same(only, kalman_covariance(model))
    _same(kalman_covariances(model, P0=P0s[1:])[1], kalman_covariance(model, P0=P0s[2]))
    for bad in (P0s[0], P0s[:, :3, :3], np.zeros((0, 5, 5))):
        with pytest.raises(NavlibInputError, match="P0"):
            kalman_covariances(F, Q, H, R, bad)


def test_ssac_p0_runs_equal_separate_runs():
    points = [("matched", 1.0), ("generic", 0.5), ("matched", 10.0)]
    for n_states in (15, 12):
        stacked = study_ssac.p0_runs(points, 300.0, n_states=n_states, track=True)
        for (P0, scale), study in zip(points, stacked, strict=True):
            single = study_ssac.covariance_run(300.0, P0=P0, attitude_scale=scale,
                                               n_states=n_states, track=True)
            _same(study.covariance, single.covariance)
            np.testing.assert_array_equal(study.eigen.eigenvalues, single.eigen.eigenvalues)
            np.testing.assert_array_equal(study.eigen.tracked_vectors,
                                          single.eigen.tracked_vectors)
            assert study.model.parameters["P0_variant"] == P0
    for bad in ([], ["matched"], 3):
        with pytest.raises(NavlibInputError, match="initial"):
            study_ssac.p0_runs(bad)


def test_p0_sensitivity_reuses_the_rerun():
    base, modified = study_ssac.p0_runs([("generic", 2.0), ("matched", 10.0)], 300.0,
                                        track=False)
    assert np.array_equal(study_ssac.modified_run(base).covariance.P_post,
                          modified.covariance.P_post)
    reused = study_ssac.p0_sensitivity(base, modified=modified)
    assert reused.equals(study_ssac.p0_sensitivity(base))


def test_rocket_robustness_equals_separate_analyses():
    grid = {"eta": (1e-2, 1e-4), "nu": (0.98, 0.99), "sigma_sg_ppm": (1000.0, 5000.0)}
    variants = rocket.robustness_variants(grid)
    points = [(sg, eta, nu) for sg in grid["sigma_sg_ppm"] for eta in grid["eta"]
              for nu in grid["nu"]]
    assert len(variants) == len(points)
    for (sg, eta, nu), (point, results) in zip(points, variants, strict=True):
        assert (point["sigma_sg_ppm"], point["eta"], point["nu"]) == (sg, eta, nu)
        a = rocket.excitability_study(eta=eta, nu=nu, sigma_sg_ppm=sg)
        direct = rocket.excitability_claims(a) + rocket.sensability_claims(
            a, rocket.quiet_gyro_analysis(rocket.excitability_study(sigma_sg_ppm=sg)).with_settings(
                eta=eta, nu=nu))
        assert [(r.claim_id, r.ours, r.checks_text()) for r in results] == \
            [(r.claim_id, r.ours, r.checks_text()) for r in direct]
