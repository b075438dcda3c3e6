"""Outlier definitions, injection, mapping onto the error models, recovery scoring and the
T1-T4 / Fig. 10 / roll-sigma study on a short launcher flight."""

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from navlib import NavlibInputError
from navlib.filters.recovery import score_recovery, scores_frame
from navlib.models import ecef21, launcher
from navlib.sensors.faults import (
    CHANNELS,
    LINEAR_NAMES,
    Outlier,
    expand_channel,
    inject,
    linear_mapping,
)
from navlib.studies import outliers as study
from navlib.studies.claims import STATUSES as VERDICTS
from navlib.studies.outliers.paper import PAPER_TESTS
from navlib.trajectory import launcher_ascent, sounding_rocket


@pytest.fixture(scope="module")
def flight():
    return launcher_ascent(duration_s=40.0, rate_hz=20.0)


@pytest.fixture(scope="module")
def cache(flight):
    return study.FilterCache(flight, size=4)


def test_outlier_validation():
    with pytest.raises(NavlibInputError, match="channel"):
        Outlier("gps_vel_x", 50.0, 3.0)
    with pytest.raises(NavlibInputError, match="shape"):
        Outlier("gyro_x", 50.0, 0.002, "ramp")
    with pytest.raises(NavlibInputError, match="duration"):
        Outlier("gyro_x", 50.0, 0.002, "pulse")
    with pytest.raises(NavlibInputError, match="duration"):
        Outlier("gyro_x", 50.0, 0.002, "step", duration=1.0)
    with pytest.raises(NavlibInputError, match="magnitude"):
        Outlier("gyro_x", 50.0, np.nan)
    assert expand_channel("gnss_vel") == ("gnss_vel_x", "gnss_vel_y", "gnss_vel_z")
    assert len(CHANNELS) == 18


def test_profiles():
    t = np.arange(0.0, 10.0, 0.1)
    spike = Outlier("gyro_x", 5.02, 2.0).profile(t)
    assert spike.sum() == 2.0 and spike[50] == 2.0
    step = Outlier("gyro_x", 5.0, 2.0, "step").profile(t)
    assert np.all(step[:50] == 0) and np.all(step[50:] == 2.0)
    pulse = Outlier("gyro_x", 5.0, 2.0, "pulse", duration=1.0).profile(t)
    assert np.count_nonzero(pulse) == 10 and pulse[50] == 2.0 and pulse[60] == 0.0
    assert not Outlier("gyro_x", 50.0, 2.0).profile(t).any()      # outside the samples
    assert "spike at 5.02 s" in Outlier("gyro_x", 5.02, 2.0).label()


def test_inject_adds_to_the_named_axes():
    t = np.arange(0.0, 2.0, 0.5)
    values = np.ones((t.size, 3))
    out = inject(values, t, [Outlier("gnss_vel", 1.0, 3.0), Outlier("gyro_y", 1.0, 7.0)],
                 "gnss_vel")
    assert np.allclose(out[2], 4.0) and np.allclose(out[[0, 1, 3]], 1.0)
    assert np.allclose(values, 1.0)          # a copy
    with pytest.raises(NavlibInputError, match="kind"):
        inject(values, t, [], "lidar")


def test_linear_mapping_names_and_absent_channels(flight, rocket):
    m = launcher("ins_gps_att_rt", "GAP", "markov", flight)
    mp = linear_mapping("gnss_vel_y", m.measurement_names, m.noise_names)
    assert (mp.target, mp.name, mp.sign) == ("measurement", "dv_m_y", -1.0)
    mp = linear_mapping("rt_x", m.measurement_names, m.noise_names)
    assert (mp.name, mp.sign) == ("psi_ref_m_x", 1.0)
    mp = linear_mapping("gyro_z", m.measurement_names, m.noise_names)
    assert (mp.target, mp.name) == ("noise", "wg_z")
    plain = launcher("ins_gps", "GA", "markov", flight)
    assert linear_mapping("rt_x", plain.measurement_names, plain.noise_names).index is None
    e = ecef21(rocket)
    assert linear_mapping("gnss_pos_x", e.measurement_names, e.noise_names).name == "gnss_x"
    assert linear_mapping("gyro_x", e.measurement_names, e.noise_names).sign == -1.0


@pytest.fixture(scope="module")
def rocket():
    return sounding_rocket()


def test_imu_signs_follow_the_bias_columns(flight, rocket):
    """The documented sign of each IMU noise channel is that of its column relative to the
    bias column: a measurement error acts exactly like a bias of the same value."""
    lm = launcher("ins_gps", "GA", "markov", flight)
    em = ecef21(rocket)
    for model, bias_names in ((lm, {"gyro": "bg", "accel": "ba"}),
                              (em, {"gyro": "bg", "accel": "ba"})):
        for kind, prefix in bias_names.items():
            for a in "xyz":
                mp = linear_mapping(f"{kind}_{a}", model.measurement_names, model.noise_names)
                g = model.G[10][:9, mp.index]          # navigation rows
                b = model.A[10][:9, model.state_names.index(f"{prefix}_{a}")]
                np.testing.assert_allclose(mp.sign * g, b, atol=1e-15)
    assert set(LINEAR_NAMES) == {"gnss_vel", "gnss_pos", "att", "rt", "gyro", "accel"}


def test_score_exponential_and_static():
    t = np.arange(0.0, 200.0, 0.1)
    d = np.where(t >= 50.0, np.exp(-(t - 50.0) / 20.0), 0.0)
    s = score_recovery(t, d, t_outlier=50.0, window=100.0, averaging=0.1)
    assert s.verdict == "recovers" and s.peak == pytest.approx(1.0)
    assert s.time_constant == pytest.approx(20.0, rel=0.01)
    static = score_recovery(t, np.where(t >= 50, 1.0, 0.0), t_outlier=50.0, window=100.0,
                            sigma=np.full(t.size, 2.0))
    assert static.verdict == "static error" and static.time_constant == np.inf
    assert static.residual_vs_3sigma == pytest.approx(1 / 6)
    assert static.pre_error == pytest.approx(2.0)
    none = score_recovery(t, np.zeros(t.size), t_outlier=50.0, window=10.0)
    assert none.verdict == "unaffected"
    # e_pre from Monte-Carlo nominal errors (K, R)
    nominal = np.full((t.size, 4), 0.5)
    s2 = score_recovery(t, d, t_outlier=50.0, window=100.0, nominal_error=nominal)
    assert s2.pre_error == pytest.approx(0.5)
    # window clipped to the data; vector quantities scored by their norm
    s3 = score_recovery(t, np.stack([d, d], axis=1), t_outlier=50.0, window=1e4)
    assert s3.window == pytest.approx(t[-1] - 50.0) and s3.peak == pytest.approx(np.sqrt(2))
    frame = scores_frame({"a": s, "b": static})
    assert list(frame.case) == ["a", "b"] and "retained" in frame


def test_score_errors():
    t = np.arange(0.0, 10.0, 0.1)
    with pytest.raises(NavlibInputError, match="t_outlier"):
        score_recovery(t, np.zeros(t.size), t_outlier=20.0, window=1.0)
    with pytest.raises(NavlibInputError, match="induced"):
        score_recovery(t, np.zeros(5), t_outlier=2.0, window=1.0)
    with pytest.raises(NavlibInputError, match="nominal_error"):
        score_recovery(t, np.zeros(t.size), t_outlier=2.0, window=1.0,
                       nominal_error=np.zeros((3, 2)))


@settings(max_examples=40, deadline=None)
@given(scale=st.floats(1e-9, 1e6), tau=st.floats(0.5, 1e4), sign=st.sampled_from([-1, 1]))
def test_score_is_scale_and_sign_invariant(scale, tau, sign):
    t = np.arange(0.0, 120.0, 0.5)
    d = np.where(t >= 10.0, np.exp(-(t - 10.0) / tau), 0.0)
    a = score_recovery(t, d, t_outlier=10.0, window=100.0)
    b = score_recovery(t, sign * scale * d, t_outlier=10.0, window=100.0)
    assert a.verdict == b.verdict
    assert b.retained == pytest.approx(a.retained, rel=1e-9)
    assert 0.0 <= b.retained <= 1.0
    assert (a.verdict == "recovers") == (a.retained <= np.exp(-1))


def test_gyro_spike_truth_jump_is_rate_times_step(cache, flight):
    """The linear-mode IMU mapping: a roll-gyro spike u moves the true body roll error by
    -u dt, at once."""
    out = Outlier("gyro_x", 20.0, 0.002)
    r = study.outlier_response("ins_gps", out, "roll", cache=cache)
    k = int(np.argmin(np.abs(r.t - 20.0)))
    dt = flight.t[1] - flight.t[0]
    assert r.truth[k + 1, 0] == pytest.approx(-0.002 * dt, rel=1e-3)
    assert np.all(r.truth[:k + 1] == 0) and r.applied


def test_t1_to_t4_structure_on_a_short_flight(cache):
    st_ = study.paper_tests(cache=cache, window=15.0, shapes=("spike", "step"),
                             outlier_time_s=20.0)
    table = st_.table()
    assert set(table.test) == {"T1", "T2", "T3", "T4"}
    t3 = table[(table.test == "T3")]
    assert set(t3[t3.solution == "ins_gps"].verdict) == {"unaffected"}
    assert "unaffected" not in set(t3[t3.solution == "ins_gps_rt"].verdict)
    # a step keeps injecting: nothing decays
    assert set(table[table["shape"] == "step"].query("verdict != 'unaffected'").verdict) == {
        "static error"}
    # INS/GPS keeps the gyro-induced roll error (roll weakly observable, spec §3.8)
    t2 = table[(table.test == "T2") & (table.solution == "ins_gps") & (table["shape"] == "spike")]
    assert t2.verdict.iloc[0] == "static error" and t2.retained.iloc[0] > 0.8
    ids = [c.claim_id for c in st_.claims]
    assert ids[:4] == ["T1", "T2", "T3", "T4"]
    assert all(c.verdict in VERDICTS for c in st_.claims)
    assert st_.claims_frame().shape[0] == len(st_.claims)


def test_fig10_and_roll_sigma(cache):
    corr = study.correlation_fig10(cache=cache)
    rho = corr.dropna()
    assert set(rho.axis) == {"roll", "pitch", "yaw"}
    assert rho.rho.max() < -0.9                              # near -1 over the first 5 s
    assert corr.t.max() <= 5.0 + 1e-9
    sig = study.roll_sigma(cache=cache)
    ratios = study.sigma_ratios("ins_gps", "ins_gps_rt", cache=cache)
    claims = {c.claim_id: c for c in study.covariance_claims(corr, sig, ratios)}
    assert claims["F10"].verdict == "reproduced"
    assert claims["F7"].verdict in ("reproduced", "partly")
    roll = sig[sig.axis == "roll"].groupby("solution").sigma.last()
    assert roll["ins_gps_rt"] < 0.5 * roll["ins_gps"]
    assert roll["ins_gps_att_rt"] < roll["ins_gps_att"]


def test_monte_carlo_outlier_decomposition(cache):
    out = PAPER_TESTS["T2"].outlier()
    out = Outlier(out.channel, 20.0, out.magnitude)
    calls = []
    mc = study.monte_carlo_outlier("ins_gps", out, runs=20, seed=3, window=15.0, cache=cache,
                                   progress=lambda d, n: calls.append((d, n)))
    assert calls and calls[-1][0] == calls[-1][1]
    # nominal = faulty - induced; the nominal runs are consistent
    assert mc.nominal_consistency["nees"] > 0.8
    assert np.allclose(mc.error - mc.nominal_error, mc.induced[:, None, :])
    assert mc.score.pre_error > 0 and set(mc.to_frame().columns) >= {"rms", "rms_nominal"}


def test_watch_rows_errors(flight):
    m = launcher("ins_gps", "GA", "markov", flight)
    C = flight.attitude.as_matrix()[:3]
    with pytest.raises(NavlibInputError, match="watch"):
        study.watch_rows("heading", m.state_names, C)
    with pytest.raises(NavlibInputError, match="no state"):
        study.watch_rows("bp", m.state_names, C)
    rows = study.watch_rows("roll", m.state_names, C)
    assert rows.shape == (3, 1, m.n)
    # the roll row is the first row of T_E^B on psi
    np.testing.assert_allclose(rows[:, 0, :3], np.swapaxes(C, 1, 2)[:, 0, :])


def test_rt_only_options_leave_the_non_rt_models_unchanged(flight):
    """The premise of the filter reuse across assumption variants: ``a1_sign`` and
    ``sigma_wind`` change only the RT solutions."""
    for sol in ("ins_gps", "ins_gps_att"):
        a = launcher(sol, "GAP", "markov", flight)
        b = launcher(sol, "GAP", "markov", flight, a1_sign=-1.0, sigma_wind=0.001)
        for name in ("A", "G", "Qc", "H", "R", "P0"):
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    a = launcher("ins_gps_rt", "GAP", "markov", flight)
    b = launcher("ins_gps_rt", "GAP", "markov", flight, a1_sign=-1.0)
    assert not np.array_equal(a.A, b.A)


def test_assumption_sensitivity_reuses_filters_without_changing_results(flight):
    variants = {"printed": dict(a1_sign=1.0), "text": dict(a1_sign=-1.0),
                "calm": dict(a1_sign=1.0, sigma_wind=0.001)}
    kw = dict(tests=("T2", "T4"), window=15.0, outlier_time_s=20.0)
    fresh = study.assumption_sensitivity(variants, flight, **kw)
    shared = study.FilterCache(flight, size=4, a1_sign=1.0)
    study.paper_tests(cache=shared, tests=("T2", "T4"), window=15.0, outlier_time_s=20.0)
    reused = study.assumption_sensitivity(variants, **kw, cache=shared)
    pd.testing.assert_frame_equal(fresh, reused)
    # the text's A1 variant takes the non-RT filters of the shared cache as they are
    other = study.FilterCache(flight, a1_sign=-1.0)
    study.adopt_filters(other, shared)
    assert {k[0] for k in other._items} == {"ins_gps", "ins_gps_att"}
    assert other.get("ins_gps") is shared.get("ins_gps")
