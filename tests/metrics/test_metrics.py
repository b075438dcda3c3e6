"""Excitability and sensability: closed forms, cross-checks, wrappers and argument checking."""

import numpy as np
import pandas as pd
import pytest

from navlib import NavlibInputError
from navlib.covariance import kalman_covariance
from navlib.metrics import (
    E_THRESHOLD,
    ExcitabilityResult,
    SegmentedAnalysis,
    SensabilityResult,
    check_segments,
    excitability,
    excitability_segment,
    excitability_segments,
    nu_for,
    nu_range,
    physical_bands,
    sensability,
    sensability_model,
)
from navlib.models import DiscreteModel, LinearModel


def random_system(rng, n=4, m=2, N=6, spread=0.2):
    F = np.eye(n) + spread * rng.standard_normal((N - 1, n, n))
    H = rng.standard_normal((N, m, n))
    G = rng.standard_normal((N - 1, n, n))
    Q = 0.05 * G @ np.swapaxes(G, 1, 2)
    A = rng.standard_normal((m, m))
    R = A @ A.T + m * np.eye(m)
    B = rng.standard_normal((n, n))
    P0 = B @ B.T + n * np.eye(n)
    return F, H, Q, R, P0


def physical_kf(F, H, Q, R, P0, prior_update=False):
    """Textbook covariance-form KF (standard, non-Joseph update), physical units."""
    P = P0.copy()
    posts = []
    for k in range(H.shape[0]):
        if k:
            P = F[k - 1] @ P @ F[k - 1].T + Q[k - 1]
        if k or prior_update:
            S = H[k] @ P @ H[k].T + R
            K = P @ H[k].T @ np.linalg.inv(S)
            P = P - K @ H[k] @ P
        posts.append(P)
    return np.array(posts)


# ---------------------------------------------------------------------------- excitability


def test_two_state_with_one_unobservable_state():
    # x2 never reaches the measurement: O = [h 0; h a 0; ...], the energy lives on e_1.
    F = np.array([[[0.9, 0.0], [0.0, 1.1]]] * 3)
    H = np.array([[[2.0, 0.0]]] * 4)
    P0 = np.diag([4.0, 9.0])
    R0 = np.array([[0.25]])
    ex = excitability(F, H, P0, R0)
    sigma1 = sum((2.0 * 2.0 / 0.5 * 0.9**k) ** 2 for k in range(4))  # H~ = h sqrt(p1)/sqrt(r)
    np.testing.assert_allclose(ex.sigma, [sigma1, 0.0], atol=1e-12 * sigma1)
    np.testing.assert_allclose(ex.S, [2.0, 0.0], atol=1e-14)
    assert ex.ne == 2
    np.testing.assert_allclose(ex.e, [1.0, 0.0], atol=1e-14)
    np.testing.assert_allclose(np.abs(ex.U), np.eye(2), atol=1e-14)


def test_observability_matrix_is_the_normalised_stack():
    rng = np.random.default_rng(3)
    F, H, _, R, P0 = random_system(rng, n=5, m=2, N=7)
    ex = excitability(F, H, P0, R)
    sqrt_d = np.sqrt(np.diag(P0))
    R_inv_half = np.linalg.inv(np.linalg.cholesky(R))
    rows, Phi = [], np.eye(5)
    for k in range(7):
        rows.append(R_inv_half @ H[k] @ Phi * sqrt_d)
        if k < 6:
            Phi = F[k] @ Phi
    np.testing.assert_allclose(ex.O, np.vstack(rows), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(np.sort(ex.sigma), np.sort(np.linalg.eigvalsh(ex.O.T @ ex.O)),
                               rtol=1e-9)


def test_symmetric_inverse_square_root_of_R0_gives_the_same_metrics():
    # The paper writes R0^-1/2; Cholesky whitening differs by an orthogonal left factor.
    rng = np.random.default_rng(4)
    F, H, _, R, P0 = random_system(rng, n=4, m=3, N=5)
    ex = excitability(F, H, P0, R, eta=0.2)
    w, V = np.linalg.eigh(R)
    R_inv_half = (V / np.sqrt(w)) @ V.T
    sqrt_d = np.sqrt(np.diag(P0))
    rows, Phi = [], np.eye(4)
    for k in range(5):
        rows.append(R_inv_half @ H[k] @ Phi * sqrt_d)
        if k < 4:
            Phi = F[k] @ Phi
    _, s, Vh = np.linalg.svd(np.vstack(rows))
    np.testing.assert_allclose(ex.sigma, s**2, rtol=1e-10)
    assert 1 < ex.ne <= 4
    np.testing.assert_allclose(ex.e, np.linalg.norm(Vh.T[:, : ex.ne - 1], axis=1), atol=1e-10)


def test_wide_observability_matrix_is_padded_with_zero_energy():
    # One scalar measurement of four states: rank 1, S = [4, 0, 0, 0].
    h = np.array([[1.0, -2.0, 0.5, 3.0]])
    P0 = np.diag([1.0, 0.25, 4.0, 1.0])
    ex = excitability(np.zeros((0, 4, 4)), h[None], P0, np.eye(1))
    np.testing.assert_allclose(ex.S, [4.0, 0, 0, 0], atol=1e-12)
    assert ex.ne == 2 and ex.U.shape == (4, 4)
    h_n = h[0] * np.sqrt(np.diag(P0))
    np.testing.assert_allclose(ex.e, np.abs(h_n) / np.linalg.norm(h_n), rtol=1e-12)
    np.testing.assert_allclose(ex.U.T @ ex.U, np.eye(4), atol=1e-12)


def test_ne_is_n_plus_one_when_no_direction_is_below_eta():
    ex = excitability(np.array([np.eye(2)]), np.eye(2), np.eye(2), np.eye(2), eta=0.5)
    assert ex.ne == 3
    np.testing.assert_allclose(ex.e, 1.0)


def test_with_eta_matches_a_fresh_computation():
    rng = np.random.default_rng(5)
    F, H, _, R, P0 = random_system(rng, n=6, m=1, N=4)
    base = excitability(F, H, P0, R, eta=1e-3)
    for eta in (0.5, 0.1, 1e-2, 1e-6):
        fresh = excitability(F, H, P0, R, eta=eta)
        again = base.with_eta(eta)
        assert again.ne == fresh.ne
        np.testing.assert_allclose(again.e, fresh.e, atol=1e-12)


def test_d0_overrides_the_diagonal_of_P0():
    rng = np.random.default_rng(6)
    F, H, _, R, P0 = random_system(rng)
    d = rng.uniform(0.5, 3.0, 4)
    a = excitability(F, H, P0, R, d0=d)
    b = excitability(F, H, np.diag(d), R)
    c = excitability(F, H, P0, R, d0=np.diag(d) + 0.1 * (np.ones((4, 4)) - np.eye(4)))
    for other in (b, c):
        np.testing.assert_allclose(a.S, other.S, rtol=1e-12)
        np.testing.assert_allclose(a.e, other.e, atol=1e-12)


def test_excitability_frame():
    ex = excitability(np.array([np.eye(2)]), np.eye(2), np.eye(2), np.eye(2),
                      state_names=["p", "v"])
    frame = ex.to_frame()
    assert list(frame["state"]) == ["p", "v"]
    assert {"e", "direction", "sigma", "S", "excited", "eta", "ne"} <= set(frame.columns)
    assert isinstance(ex, ExcitabilityResult)


# ---------------------------------------------------------------------------- sensability


@pytest.mark.parametrize("prior_update", [False, True])
def test_scalar_random_walk_closed_form(prior_update):
    p0, q, r, N = 4.0, 0.5, 2.0, 6
    F, H, Q = np.ones((N - 1, 1, 1)), np.ones((N, 1, 1)), np.full((N - 1, 1, 1), q)
    se = sensability(F, H, Q, np.array([[r]]), np.array([[p0]]), prior_update=prior_update)
    p = p0 if not prior_update else 1.0 / (1.0 / p0 + 1.0 / r)
    expected = [p]
    for _ in range(N - 1):
        p = 1.0 / (1.0 / (p + q) + 1.0 / r)
        expected.append(p)
    expected = np.array(expected)
    np.testing.assert_allclose(se.sigma[:, 0], np.sqrt(expected), rtol=1e-13)
    np.testing.assert_allclose(se.eigenvalues[:, 0], p0 / expected, rtol=1e-13)
    np.testing.assert_allclose(se.s, 1.0)
    np.testing.assert_array_equal(se.nr, 1)


def test_two_state_closed_form_r_and_s():
    # F = I, Q = 0, only x1 measured: I~_k = diag(1 + k p1/r, 1) under the literal reading.
    p1, p2, r, N = 9.0, 4.0, 1.0, 5
    se = sensability(np.tile(np.eye(2), (N - 1, 1, 1)), np.array([[1.0, 0.0]]),
                     np.zeros((N - 1, 2, 2)), np.array([[r]]), np.diag([p1, p2]), nu=0.985)
    lam1 = 1.0 + np.arange(N) * p1 / r
    np.testing.assert_allclose(se.eigenvalues, np.column_stack([lam1, np.ones(N)]), rtol=1e-12)
    r1 = np.sqrt(lam1 / (lam1 + 1.0))
    np.testing.assert_allclose(se.r[:, 0], r1, rtol=1e-12)
    expected_nr = np.where(r1 >= 0.985, 1, 2)
    np.testing.assert_array_equal(se.nr, expected_nr)
    # epoch 0: equal eigenvalues, r1 = 0.707 < nu, both sensible; later x2 drops out once
    # r1 >= nu (lam1 >= 32.6, from k = 4 with p1/r = 9).
    np.testing.assert_allclose(se.s[:, 0], 1.0)
    np.testing.assert_allclose(se.s[:, 1], np.where(expected_nr == 1, 0.0, 1.0), atol=1e-12)
    np.testing.assert_allclose(se.sigma[:, 0], np.sqrt(p1 / lam1), rtol=1e-12)
    np.testing.assert_allclose(se.sigma[:, 1], 2.0)


@pytest.mark.parametrize("prior_update", [False, True])
def test_sensability_matches_a_standard_kalman_filter(prior_update):
    rng = np.random.default_rng(7)
    F, H, Q, R, P0 = random_system(rng, n=5, m=2, N=9)
    se = sensability(F, H, Q, R, P0, prior_update=prior_update)
    P = physical_kf(F, H, Q, R, P0, prior_update)
    np.testing.assert_allclose(se.P, P, rtol=1e-9, atol=1e-12)
    # against the project's Joseph-form recursion in physical units as well
    cov = kalman_covariance(F, Q, H, R, P0, update_first=prior_update)
    np.testing.assert_allclose(se.sigma, cov.sigma, rtol=1e-9)
    # information form of Eq. 10b, physical, then normalised: I~ = D0^1/2 I D0^1/2
    D_half = np.diag(np.sqrt(np.diag(P0)))
    info = np.linalg.inv(P0)
    if prior_update:
        info = info + H[0].T @ np.linalg.solve(R, H[0])
    infos = [info]
    for k in range(1, 9):
        info = np.linalg.inv(F[k - 1] @ np.linalg.inv(info) @ F[k - 1].T + Q[k - 1])
        info = info + H[k].T @ np.linalg.solve(R, H[k])
        infos.append(info)
    np.testing.assert_allclose(se.information, D_half @ np.array(infos) @ D_half, rtol=1e-8)


def test_time_varying_R_stack():
    rng = np.random.default_rng(8)
    F, H, Q, R, P0 = random_system(rng, n=3, m=2, N=4)
    R_stack = np.array([R * (1 + k) for k in range(4)])
    se = sensability(F, H, Q, R_stack, P0)
    cov = kalman_covariance(F, Q, H, R_stack, P0, update_first=False)
    np.testing.assert_allclose(se.sigma, cov.sigma, rtol=1e-9)


def test_with_nu_and_frames():
    rng = np.random.default_rng(9)
    F, H, Q, R, P0 = random_system(rng, n=4, m=1, N=5)
    se = sensability(F, H, Q, R, P0, nu=0.9, state_names=list("abcd"), t=np.arange(5) * 2.0)
    for nu in (0.5, 0.99, 1.0):
        fresh = sensability(F, H, Q, R, P0, nu=nu)
        np.testing.assert_array_equal(se.with_nu(nu).nr, fresh.nr)
        np.testing.assert_allclose(se.with_nu(nu).s, fresh.s, atol=1e-12)
    frame = se.to_frame()
    assert len(frame) == 20 and list(frame.columns) == ["t", "state", "s", "sigma", "nr"]
    assert list(frame["state"][:4]) == list("abcd") and frame["t"].iloc[-1] == 8.0
    bands = physical_bands(se, k=2)
    np.testing.assert_allclose(bands["upper"], 2 * frame["sigma"])
    np.testing.assert_allclose(bands["lower"], -2 * frame["sigma"])
    assert isinstance(se, SensabilityResult)


def test_nu_helpers():
    assert nu_for(21, 0.0178) == pytest.approx(0.985, abs=1e-4)
    low, high = nu_range(21)
    assert low == pytest.approx(np.sqrt(20 / 21)) and high == 1.0
    assert low < nu_for(21, 1e-6) < nu_for(21, 1 / 21 - 1e-9) < 1.0
    for eps in (0.0, -0.1, 1 / 21, 0.5):
        with pytest.raises(NavlibInputError, match="eps"):
            nu_for(21, eps)
    for n in (0, -3, 2.5, True):
        with pytest.raises(NavlibInputError, match="n:"):
            nu_range(n)


# ---------------------------------------------------------------------------- model wrappers


@pytest.fixture(scope="module")
def pv_model() -> DiscreteModel:
    """Position/velocity random walk with position fixes, 1 Hz over 0..20 s."""
    A = np.array([[0.0, 1.0], [0.0, 0.0]])
    model = LinearModel(("p", "v"), A, np.array([[0.0], [1.0]]), np.array([[0.01]]),
                        np.array([[1.0, 0.0]]), np.array([[4.0]]), P0=np.diag([100.0, 1.0]))
    return model.discretize(dt_s=1.0, n_epochs=21)


def test_excitability_segment_equals_the_array_call(pv_model):
    ex = excitability_segment(pv_model, 5.0, 12.0, eta=1e-2)
    w = pv_model.window(5.0, 12.0)
    direct = excitability(w.F, w.H, pv_model.P0, pv_model.R[0], eta=1e-2)
    np.testing.assert_allclose(ex.e, direct.e)
    assert ex.state_names == ("p", "v") and (ex.t_start, ex.t_end) == (5.0, 12.0)
    assert w.t.size == 8 and ex.O.shape == (8, 2)


def test_filter_d0_from_results_matrices_and_default(pv_model):
    se = sensability_model(pv_model)
    variances = se.sigma[5] ** 2
    expected = excitability_segment(pv_model, 5.0, 12.0, d0="filter", P_filter=se.P[5])
    np.testing.assert_allclose(expected.d0, variances)
    cov = kalman_covariance(pv_model, update_first=False)
    for P_filter in (None, se, se.P, cov):
        got = excitability_segment(pv_model, 5.0, 12.0, d0="filter", P_filter=P_filter)
        np.testing.assert_allclose(got.d0, variances, rtol=1e-9)
        np.testing.assert_allclose(got.e, expected.e, atol=1e-9)
    glob = excitability_segment(pv_model, 5.0, 12.0)
    np.testing.assert_allclose(glob.d0, [100.0, 1.0])


def test_sensability_model_defaults_and_window(pv_model):
    se = sensability_model(pv_model, nu=nu_for(2, 0.1))
    assert se.state_names == ("p", "v") and se.t.size == 21
    np.testing.assert_allclose(se.s[0], 1.0)  # literal reading, diagonal P0 (spec A9)
    part = sensability_model(pv_model, t_start=10.0)
    assert part.t[0] == 10.0 and part.t.size == 11
    assert isinstance(part.to_frame(), pd.DataFrame)


# ---------------------------------------------------------------------------- segmented analysis

PV_SEGMENTS = ((2.0, 8.0), (8.0, 20.0))


@pytest.fixture(scope="module")
def pv_analysis(pv_model):
    return SegmentedAnalysis.build(pv_model, PV_SEGMENTS, eta=1e-2, nu=0.9,
                                   settings={"what": "pv"})


def test_segmented_analysis_is_the_wrappers(pv_model, pv_analysis):
    a = pv_analysis
    assert a.segments == PV_SEGMENTS and a.labels == ("tau1", "tau2")
    for (t_a, t_b), ex in zip(PV_SEGMENTS, a.excitability, strict=True):
        np.testing.assert_array_equal(ex.e, excitability_segment(pv_model, t_a, t_b,
                                                                 eta=1e-2).e)
    np.testing.assert_array_equal(a.sensability.s, sensability_model(pv_model, nu=0.9).s)
    assert a.thresholds == {"eta": 1e-2, "nu": 0.9, "e_threshold": E_THRESHOLD,
                            "s_threshold": E_THRESHOLD, "min_fraction": 0.5}
    assert a.settings["what"] == "pv" and a.settings["d0"] == "global"
    assert not a.settings["prior_update"] and a.state_names == ("p", "v")


@pytest.mark.parametrize("change", [
    {"segments": ((0.0, 10.0), (10.0, 20.0))}, {"eta": 1e-1}, {"nu": 0.99},
    {"d0": "filter"}, {"e_threshold": 0.9, "s_threshold": 0.5, "min_fraction": 0.2},
])
def test_with_settings_equals_a_new_build(pv_model, pv_analysis, change):
    fast = pv_analysis.with_settings(**change)
    slow = SegmentedAnalysis.build(pv_model, change.get("segments", PV_SEGMENTS), **{
        **pv_analysis.thresholds, **{k: v for k, v in change.items() if k != "segments"}})
    assert fast.model is pv_model and fast.segments == slow.segments
    assert fast.thresholds == slow.thresholds
    assert fast.settings["d0"] == slow.settings["d0"] and fast.settings["what"] == "pv"
    for a, b in zip(fast.excitability, slow.excitability, strict=True):
        np.testing.assert_array_equal(a.e, b.e)
        assert a.ne == b.ne
    np.testing.assert_array_equal(fast.sensability.s, slow.sensability.s)
    pd.testing.assert_frame_equal(fast.state_table(), slow.state_table())
    if "segments" not in change and "d0" not in change:  # re-thresholded, no new SVD
        assert all(a.U is b.U for a, b in zip(fast.excitability, pv_analysis.excitability,
                                              strict=True))
    assert fast.sensability.V is pv_analysis.sensability.V


def test_segmented_frames(pv_analysis):
    a = pv_analysis
    long = a.excitability_frame()
    assert len(long) == 4 and list(long["segment"]) == ["tau1", "tau1", "tau2", "tau2"]
    assert (long["excitable"] == (long["e"] >= E_THRESHOLD)).all()
    assert a.excitability_table().loc["v", "tau2"] == a.excitability[1].e[1]
    spectrum = a.spectrum_frame()
    np.testing.assert_allclose(spectrum.groupby("segment")["S"].sum(), 2.0)
    bands = a.sensability_frame(k=3.0)
    by_time = bands[bands["state"] == "p"].set_index("t")["segment"]
    # epochs 0 and 1 lie outside; the boundary epoch 8 belongs to the later segment
    assert by_time[0.0] == by_time[1.0] == "" and by_time[2.0] == by_time[7.0] == "tau1"
    assert by_time[8.0] == by_time[20.0] == "tau2"
    np.testing.assert_allclose(bands["upper"], 3.0 * bands["sigma"])
    states = a.state_table()
    k = a.epochs(8.0, 20.0)
    assert k[0] == 8 and k.size == 13 and a.epochs(8.0, 20.0, open_start=True).size == 12
    share = np.mean(a.sensability.s[k, 1] >= E_THRESHOLD)
    assert states.iloc[3]["s_fraction"] == share
    assert states.iloc[3]["sensible"] == (share >= 0.5)
    assert states.iloc[3]["sigma_ratio"] == a.sensability.sigma[20, 1] / a.sensability.sigma[8, 1]
    summary = a.summary()
    assert list(summary["n_epochs"]) == [7, 13] and list(summary["segment"]) == ["tau1", "tau2"]
    assert summary.loc[1, "n_sensible"] == states.iloc[2:]["sensible"].sum()


@pytest.mark.parametrize(("segments", "match"), [
    (5.0, "pairs"), ([], "at least one"), ([(8.0, 2.0)], r"segments\[0\]: need"),
    ([(0.0, 8.0), (8.0, 25.0)], r"segments\[1\].*outside"),
    ([(0.0, 8.0), (8.2, 8.9)], r"segments\[1\].*holds 0 epoch"),
])
def test_bad_segments_are_named(pv_model, pv_analysis, segments, match):
    with pytest.raises(NavlibInputError, match=match):
        check_segments(segments, pv_model.t)
    with pytest.raises(NavlibInputError, match=match):
        pv_analysis.with_settings(segments)
    with pytest.raises(NavlibInputError, match=match):
        excitability_segments(pv_model, segments)


def test_bad_settings_are_named(pv_model, pv_analysis):
    for kwargs, match in (({"eta": 1.0}, "eta"), ({"nu": 0.0}, "nu"), ({"d0": "local"}, "d0"),
                          ({"e_threshold": 1.5}, "e_threshold"),
                          ({"min_fraction": -0.1}, "min_fraction")):
        with pytest.raises(NavlibInputError, match=match):
            pv_analysis.with_settings(**kwargs)
        with pytest.raises(NavlibInputError, match=match):
            SegmentedAnalysis.build(pv_model, PV_SEGMENTS, **kwargs)
    with pytest.raises(NavlibInputError, match="DiscreteModel"):
        SegmentedAnalysis.build(np.eye(2), PV_SEGMENTS)


def test_wrapper_argument_errors(pv_model):
    no_p0 = DiscreteModel(pv_model.t, pv_model.F, pv_model.Q, pv_model.H, pv_model.R,
                          pv_model.state_names)
    with pytest.raises(NavlibInputError, match="P0"):
        sensability_model(no_p0)
    with pytest.raises(NavlibInputError, match="d0"):
        excitability_segment(pv_model, 0.0, 5.0, d0="local")
    with pytest.raises(NavlibInputError, match="t_b"):
        excitability_segment(pv_model, 5.0, 5.0)
    with pytest.raises(NavlibInputError, match="window"):
        excitability_segment(pv_model, 30.0, 40.0)
    with pytest.raises(NavlibInputError, match="P_filter"):
        excitability_segment(pv_model, 5.0, 9.0, d0="filter", P_filter=np.eye(3))
    with pytest.raises(NavlibInputError, match="model"):
        sensability_model(np.eye(2))
    with pytest.raises(NavlibInputError, match="result"):
        physical_bands(np.eye(2))


# ---------------------------------------------------------------------------- validation


def good():
    rng = np.random.default_rng(10)
    return random_system(rng, n=3, m=2, N=4)


@pytest.mark.parametrize(("change", "name"), [
    (lambda a: {**a, "F": a["F"][0]}, "F"),
    (lambda a: {**a, "F": a["F"][:, :2]}, "F"),
    (lambda a: {**a, "H": a["H"][:3]}, "H"),
    (lambda a: {**a, "H": np.full((4, 2, 3), np.nan)}, "H"),
    (lambda a: {**a, "P0": -a["P0"]}, "P0"),
    (lambda a: {**a, "P0": a["P0"] + np.triu(np.ones((3, 3)), 1)}, "P0"),
    (lambda a: {**a, "P0": np.eye(2)}, "P0"),
    (lambda a: {**a, "R0": np.diag([1.0, 0.0])}, "R0"),
    (lambda a: {**a, "eta": 0.0}, "eta"),
    (lambda a: {**a, "eta": 1.0}, "eta"),
    (lambda a: {**a, "eta": "x"}, "eta"),
    (lambda a: {**a, "state_names": ["a"]}, "state_names"),
    (lambda a: {**a, "d0": [1.0, -1.0, 1.0]}, "d0"),
    (lambda a: {**a, "d0": [1.0, 1.0]}, "d0"),
])
def test_excitability_rejects_bad_arguments(change, name):
    F, H, _, R, P0 = good()
    args = change({"F": F, "H": H, "P0": P0, "R0": R, "eta": 1e-3})
    with pytest.raises(NavlibInputError, match=name):
        excitability(**args)


def test_zero_observability_matrix_is_a_clear_error():
    with pytest.raises(NavlibInputError, match="zero"):
        excitability(np.tile(np.eye(2), (3, 1, 1)), np.zeros((4, 1, 2)), np.eye(2), np.eye(1))


@pytest.mark.parametrize(("change", "name"), [
    (lambda a: {**a, "Q": a["Q"][:2]}, "Q"),
    (lambda a: {**a, "Q": -a["Q"] - np.eye(3)}, r"Q\[0\]"),
    (lambda a: {**a, "Q": a["Q"] + np.triu(np.ones((3, 3)), 1)}, "Q"),
    (lambda a: {**a, "R": np.zeros((2, 2))}, "R"),
    (lambda a: {**a, "R": np.tile(np.eye(2), (3, 1, 1))}, "R"),
    (lambda a: {**a, "R": np.stack([np.eye(2), np.eye(2), -np.eye(2), np.eye(2)])},
     r"R\[2\]"),
    (lambda a: {**a, "nu": 0.0}, "nu"),
    (lambda a: {**a, "nu": 1.01}, "nu"),
    (lambda a: {**a, "t": np.arange(3.0)}, "t"),
    (lambda a: {**a, "P0": np.ones((3, 3))}, "P0"),
])
def test_sensability_rejects_bad_arguments(change, name):
    F, H, Q, R, P0 = good()
    args = change({"F": F, "H": H, "Q": Q, "R": R, "P0": P0, "nu": 0.985})
    with pytest.raises(NavlibInputError, match=name):
        sensability(**args)


def test_singular_transition_without_noise_is_named():
    F = np.zeros((2, 2, 2))
    with pytest.raises(NavlibInputError, match="epoch 1"):
        sensability(F, np.array([[1.0, 0.0]]), np.zeros((2, 2, 2)), np.eye(1), np.eye(2))


def test_single_epoch_and_signed_vectors():
    rng = np.random.default_rng(11)
    F, H, Q, R, P0 = random_system(rng, n=3, m=2, N=1)
    se = sensability(F, H, Q, R, P0, prior_update=True)
    ex = excitability(F, H, P0, R)
    assert se.s.shape == (1, 3) and ex.ne <= 3
    for V in (ex.U, se.V[0]):
        pivot = V[np.argmax(np.abs(V), axis=0), np.arange(3)]
        assert np.all(pivot > 0)
    np.testing.assert_allclose(se.V[0] @ np.diag(se.eigenvalues[0]) @ se.V[0].T,
                               se.information[0], rtol=1e-10)


def test_generic_figures_draw_the_analysis_thresholds(pv_analysis):
    import matplotlib.pyplot as plt

    from navlib.plots import metrics as mplots

    strict = pv_analysis.with_settings(e_threshold=0.9, s_threshold=0.6)
    fig = mplots.excitability_figure(strict)
    lines = {ln.get_gid(): ln.get_ydata()[0] for ln in fig.axes[0].get_lines()}
    assert lines["e_threshold"] == 0.9
    assert mplots.excitability_figure(strict.with_settings(eta=1e-1), fig) is fig  # in place
    again = mplots.excitability_figure(pv_analysis, fig)  # another threshold line: redrawn
    assert [ln.get_ydata()[0] for ln in again.axes[0].get_lines()
            if ln.get_gid() == "e_threshold"] == [E_THRESHOLD]
    sens = mplots.sensability_figure(strict, ["v"])
    assert 0.6 in [ln.get_ydata()[0] for ln in sens.axes[0].get_lines()]
    plt.close("all")


def test_generic_plots_do_not_load_a_study():
    import subprocess
    import sys

    code = ("import sys, navlib.plots.metrics, navlib.metrics; "
            "print(sorted(m for m in sys.modules if m.startswith('navlib.studies')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "[]"
