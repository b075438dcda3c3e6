"""The España et al. (2019) reproduction on the sounding-rocket flight: claims, the X3 / S6-S7
tension, the sensitivity sweep and the comparison with the simpler measures."""

from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from navlib import NavlibInputError, earth, metrics
from navlib.rotations import unskew
from navlib.studies import rocket
from navlib.studies.claims import STATUSES as VERDICTS


@pytest.fixture(scope="module")
def baseline():
    return rocket.excitability_study()


def test_chain_shapes_and_cache(baseline):
    model = baseline.model
    assert model.t.size == 87 and model.F.shape == (86, 21, 21)
    np.testing.assert_allclose(model.t, np.arange(87.0))
    again = rocket.rocket_chain()
    assert again.F is model.F  # discretised once, shared
    wider = rocket.rocket_chain(gnss_sigma_m=10.0, sigma_p0_m=100.0)
    assert wider.F is model.F
    assert wider.R[0, 0, 0] == 100.0 and wider.P0[0, 0] == 1e4


def test_claims_table_is_complete_and_valid(baseline):
    table = rocket.claims_table(baseline)
    assert list(table["claim_id"]) == list(rocket.CLAIM_IDS)
    assert set(table["verdict"]) <= set(VERDICTS)
    assert table["ours"].str.len().min() > 10 and table["assumption"].str.len().min() > 10
    assert list(rocket.claims_table(baseline, "excitability")["claim_id"]) == \
        list(rocket.CLAIM_IDS[:7])
    with pytest.raises(NavlibInputError, match="which"):
        rocket.claims_table(baseline, "both")


def test_baseline_outcomes(baseline):
    """The reproduction at the spec §5 baseline: what holds and what does not (numbers in
    the notebooks). A change here means the model or the metrics changed."""
    e = baseline.e()
    # X3/X4: scale factors along the spinning, thrusting axis
    assert e.loc["sg_x", "tau2"] > 0.9 > 0.1 > e.loc["sg_x", ["tau1", "tau3"]].max()
    assert e.loc["sa_x", "tau1"] < e.loc["sa_x", "tau2"] < rocket.IN_SO
    # X2: at rest only the tilt plane is excited; attitude dark in free fall
    share = e.loc[["theta_x", "theta_y", "theta_z"], "tau1"] / rocket.tangent_projections(baseline)
    np.testing.assert_allclose(share, share.mean(), rtol=0.02)  # e ~ 0.9 x projection
    assert e.loc[["theta_x", "theta_y", "theta_z"], "tau3"].max() < 0.05
    verdicts = dict(zip(*rocket.claims_table(baseline)[["claim_id", "verdict"]].T.values,
                        strict=True))
    assert verdicts["X3"] == verdicts["X4"] == "reproduced"
    # s(theta_x), s(theta_y) already rise on the pad: "only after" fails (A-S4-only-after)
    assert verdicts["S4"] == "partly"
    assert verdicts["S7"] == "not reproduced"  # sg_x becomes sensible: the tension
    s_sgx = baseline.sensability.s[:, rocket.flight.STATE_NAMES.index("sg_x")]
    assert np.all(s_sgx[40:] > 0.99)


def test_every_claim_fails_when_its_headline_fails(baseline):
    """Fed a result whose headline check fails, each of X1-X7, S1-S8 says "not
    reproduced" (the rule lives in navlib.studies.claims, tested in test_claims.py)."""
    from navlib.studies.claims import with_failed_headline

    for c in rocket.excitability_claims(baseline) + rocket.sensability_claims(baseline):
        assert c.checks, c.claim_id
        assert with_failed_headline(c).verdict == "not reproduced", c.claim_id


def test_robustness_grid_reuses_and_counts():
    grid = {"eta": (1e-2, 1e-3), "nu": (0.985,), "p0": ("baseline (30 m, 3 m/s)",),
            "sigma_sg_ppm": (5000.0,), "spin_hz": (2.0,)}
    variants = rocket.robustness_variants(grid)
    assert len(variants) == 2 and all(len(v) == 15 for _, v in variants)
    assert [p["eta"] for p, _ in variants] == [1e-2, 1e-3]
    with pytest.raises(NavlibInputError, match="grid"):
        rocket.robustness_variants({"gamma": (1,)})


def test_tangent_projections_and_heading(baseline):
    """ECEF axes at the assumed site: 0.58 / 0.82 / 0.99 (spec §3 prototype)."""
    np.testing.assert_allclose(rocket.tangent_projections(baseline), [0.58, 0.82, 0.99],
                               atol=0.01)
    v = rocket.heading_direction(baseline)
    lat, lon, _ = earth.ecef_to_geodetic(baseline.trajectory.position[0])
    np.testing.assert_allclose(v[6:9], -earth.ned_to_ecef_matrix(lat, lon)[:, 2])
    assert not v[:6].any() and not v[9:].any()


def test_direction_sensability_matches_canonical_components(baseline):
    se = baseline.sensability
    for j in (0, 7, 15):
        e_j = np.zeros(21)
        e_j[j] = 3.0  # scale does not matter
        np.testing.assert_allclose(rocket.direction_sensability(se, e_j), se.s[:, j],
                                   atol=1e-12)
    with pytest.raises(NavlibInputError, match="v"):
        rocket.direction_sensability(se, np.zeros(21))


def test_with_eta_and_nu_equal_recomputation(baseline):
    fast = baseline.with_eta(1e-2).with_nu(0.99)
    slow = rocket.excitability_study(eta=1e-2, nu=0.99)
    np.testing.assert_allclose(fast.e(), slow.e())
    np.testing.assert_allclose(fast.sensability.s, slow.sensability.s)
    assert fast.settings["eta"] == 1e-2 and fast.settings["nu"] == 0.99


def test_filter_d0_uses_the_covariance_at_each_segment_start(baseline):
    ex = metrics.excitability_segments(baseline.model, rocket.SEGMENTS, 1e-3, "filter",
                                       baseline.sensability)
    k = baseline.at(19.0)
    np.testing.assert_allclose(ex[1].d0, baseline.sensability.sigma[k] ** 2)
    assert not np.allclose(ex[1].e, baseline.excitability[1].e)


def test_frames_give_the_same_position_velocity_metrics(baseline):
    body = rocket.excitability_study(attitude_error="body")
    # psi = C dtheta is a time-varying change of the attitude coordinates only, so P/V
    # sensability (all epochs) agrees closely; attitude components differ (spec A4)
    np.testing.assert_allclose(body.sensability.sigma[:, :6], baseline.sensability.sigma[:, :6],
                               rtol=0.02)
    assert not np.allclose(body.e()["tau2"][6:9], baseline.e()["tau2"][6:9], atol=0.1)


def test_coning_keeps_the_flight_path_and_an_exact_imu():
    traj = rocket.rocket_trajectory(2.0)
    coned = rocket.add_coning(traj, coning_deg=3.0, coning_hz=0.5)
    np.testing.assert_array_equal(coned.position, traj.position)
    f_e = np.einsum("nij,nj->ni", traj.C_b_e(), traj.specific_force)
    f_e_coned = np.einsum("nij,nj->ni", coned.C_b_e(), coned.specific_force)
    np.testing.assert_allclose(f_e_coned, f_e, atol=1e-9)
    k = np.searchsorted(traj.t, 40.0)
    lateral = np.hypot(*coned.specific_force[k, 1:])
    assert lateral == pytest.approx(np.linalg.norm(f_e[k]) * np.sin(np.radians(3.0)), rel=1e-3)
    # body rate vs central differences of the attitude (O(dt^2) at 12.6 rad/s spin)
    C = coned.C_b_e()
    dt = coned.t[1] - coned.t[0]
    for k in (3000, 5000):
        w_fd = unskew(C[k].T @ (C[k + 1] - C[k - 1]) / (2 * dt))
        w = coned.angular_rate[k] - C[k].T @ earth.EARTH_RATE_ECEF
        np.testing.assert_allclose(w_fd, w, rtol=5e-3, atol=1e-3)
    with pytest.raises(NavlibInputError, match="coning_deg"):
        rocket.add_coning(traj, coning_deg=45.0)


def test_tension_table_mechanism():
    table = rocket.tension_table({"baseline": {}, "sg 300": {"sigma_sg_ppm": 300.0},
                                  "sg 50": {"sigma_sg_ppm": 50.0}})
    assert list(table["variant"]) == ["baseline", "sg 300", "sg 50"]
    # roll drift = sigma_sg * int |omega_x| dt over tau2: proportional to sigma_sg
    np.testing.assert_allclose(table["roll_drift_deg"] / table["sigma_sg_ppm"],
                               table["roll_drift_deg"].iloc[0] / 5000.0)
    assert table["e16_tau2"].is_monotonic_decreasing
    assert table["max_theta_growth"].is_monotonic_decreasing
    assert table.loc[0, "X3"] == "reproduced" and table.loc[2, "X3"] != "reproduced"
    assert table.loc[2, "sg_x_sensible_s"] == 0.0 < table.loc[0, "sg_x_sensible_s"]
    findings = rocket.tension_findings(table)
    assert any("X3 reproduced in 1 of 3" in f for f in findings)


def test_sweep_rows_match_direct_analysis(baseline):
    sweep = rocket.sensitivity_sweep({"eta": (1e-2,), "nu": (0.99,)}, progress=False)
    assert list(sweep["factor"]) == ["baseline", "eta", "nu"]
    assert set(rocket.CLAIM_IDS) <= set(sweep.columns)
    assert sweep[list(rocket.CLAIM_IDS)].dtypes.eq(bool).all()
    direct = rocket.claims_table(baseline)
    expected = dict(zip(direct["claim_id"], direct["verdict"] == "reproduced", strict=True))
    assert sweep.iloc[0][list(rocket.CLAIM_IDS)].to_dict() == expected
    assert sweep.loc[0, "n_reproduced"] == sum(expected.values())
    nu_row = rocket.claims_table(baseline.with_nu(0.99))
    assert sweep.iloc[2]["S2"] == (nu_row.set_index("claim_id").loc["S2", "verdict"]
                                   == "reproduced")
    rates = rocket.sweep_pass_rates(sweep)
    assert rates.between(0, 1).all() and len(rates) == 15


def test_sweep_grid_mode_and_bad_input():
    grid = rocket.sensitivity_sweep({"eta": (1e-2, 1e-3), "nu": (0.98, 0.99)}, mode="grid",
                                    progress=False)
    assert len(grid) == 4 and set(grid["factor"]) == {"grid"}
    with pytest.raises(NavlibInputError, match="unknown"):
        rocket.sensitivity_sweep({"lever_arm": (1.0,)}, progress=False)
    with pytest.raises(NavlibInputError, match="p0"):
        rocket.sensitivity_sweep({"p0": ("tiny",)}, progress=False)
    with pytest.raises(NavlibInputError, match="mode"):
        rocket.sensitivity_sweep(mode="random", progress=False)


def test_imu_grade_scales_noise_and_parameter_sigmas():
    scaled, sigmas = rocket.sensitivity._graded(None, 10.0)
    assert scaled["arw_rad_sqrt_s"][0] == pytest.approx(10 * 1.454e-4, rel=1e-3)
    assert sigmas["sigma_sg_ppm"] == pytest.approx(50000.0)
    assert rocket.sensitivity._graded("motionpak_tactical", 1.0) == ("motionpak_tactical", {})


def test_measure_comparison(baseline):
    comp = rocket.measure_comparison(baseline)
    se = baseline.sensability
    np.testing.assert_allclose(comp["ratio_end"], se.sigma[0] / se.sigma[-1])
    np.testing.assert_allclose(comp["s_end"], se.s[-1])
    assert comp["hb_share"].between(0, 1 + 1e-12).all()
    # sg_x: every measure agrees it is estimated; sa_y: every measure agrees it is not
    row = comp.set_index("state")
    assert row.loc["sg_x", ["excited", "sensible_end", "ratio_estimated", "hb_estimated"]].all()
    assert not row.loc["sa_y", ["excited", "sensible_end", "ratio_estimated",
                                "hb_estimated"]].any()
    dis = rocket.measure_disagreements(comp)
    assert set(dis["why"]) <= set(rocket.DISAGREEMENT_REASONS.values())
    flagged = set(dis.loc[dis["disagreement"] == "ratio estimated, not sensible", "state"])
    expected = set(comp.loc[comp["ratio_estimated"] & ~comp["sensible_end"], "state"])
    assert flagged == expected and len(flagged) > 0


def test_frames_are_tidy(baseline):
    ex = baseline.excitability_frame()
    assert len(ex) == 63 and set(ex["segment"]) == {"tau1", "tau2", "tau3"}
    assert ex.loc[ex["state"] == "sg_x", "paper_id"].unique().tolist() == ["e16"]
    spec = baseline.spectrum_frame()
    assert len(spec) == 63 and np.allclose(spec.groupby("segment")["S"].sum(), 21.0)
    bands = baseline.sensability_frame()
    assert isinstance(bands, pd.DataFrame) and {"lower", "upper"} <= set(bands.columns)


def test_bad_input(baseline):
    with pytest.raises(NavlibInputError, match="attitude_error"):
        rocket.excitability_study(attitude_error="ned")
    with pytest.raises(NavlibInputError, match="segments"):
        rocket.excitability_study(segments=[(10.0, 5.0)])
    with pytest.raises(NavlibInputError, match="segments"):
        rocket.excitability_study(segments=[(0.0, 100.0)])
    two = replace(baseline, segments=baseline.segments[:2],
                  excitability=baseline.excitability[:2])
    with pytest.raises(NavlibInputError, match="three segments"):
        rocket.claim_x1(two)
    with pytest.raises(NavlibInputError, match="unknown"):
        rocket.excitability_study(sigma_pos=3.0)
    with pytest.raises(NavlibInputError, match="spin_hz"):
        rocket.rocket_trajectory(-1.0)


def test_metrics_on_custom_segments():
    a = rocket.excitability_study(segments=[(0, 10), (10, 30)], eta=1e-2)
    assert a.labels == ("tau1", "tau2") and len(a.excitability) == 2
    assert isinstance(a.excitability[0], metrics.ExcitabilityResult)


def test_excitability_figure_updates_in_place(baseline):
    import matplotlib.pyplot as plt

    from navlib.plots import metrics as mplots

    fig = mplots.excitability_figure(baseline)
    heights = [p.get_height() for p in fig.axes[0].patches]
    np.testing.assert_allclose(heights, np.concatenate([e.e for e in baseline.excitability]))
    other = baseline.with_eta(1e-1)
    assert mplots.excitability_figure(other, fig) is fig
    np.testing.assert_allclose([p.get_height() for p in fig.axes[0].patches],
                               np.concatenate([e.e for e in other.excitability]))
    assert "1e-01" in fig.axes[1].get_title()
    plt.close(fig)


def test_panels_recompute_only_what_changes(baseline):
    from navlib.widgets.metrics import ExcitabilityPanel, SensabilityPanel

    panel = ExcitabilityPanel(dpi=30)
    chain = panel.analysis.model
    panel.controls["eta"].value = 1e-2
    assert panel.analysis.model is chain and panel.analysis.settings["eta"] == 1e-2
    np.testing.assert_allclose(panel.analysis.e(), baseline.with_eta(1e-2).e())
    panel.controls["tau1"].value = (0.0, 10.0)
    assert panel.analysis.segments[0] == (0.0, 10.0)
    assert panel.image.value[:4] == b"\x89PNG" and "X1" in panel.table.value
    assert set(panel.last_timing) == {"compute_ms", "render_ms", "table_ms", "total_ms"}
    panel.controls["tau2"].value = (5.0, 5.0)  # empty segment: message, no crash
    assert "Invalid input" in panel.status.value
    sens = SensabilityPanel(dpi=30)
    low = metrics.nu_range(21)[0]
    assert sens.controls["nu"].min > low and f"{low:.4f}" in sens.range_note.value
    sens.controls["nu"].value = 0.99
    np.testing.assert_allclose(sens.analysis.sensability.s, baseline.with_nu(0.99).sensability.s)
    sens.controls["states"].value = ("bg_x",)
    assert "S7" in sens.table.value


def test_sensability_evaluation_carries_the_covariance_columns():
    """The "sensability" sweep evaluation returns the columns of "covariance" from the same
    recursion, equal to the bit (notebook 08 runs one sweep for both)."""
    from navlib.sweep import EVALUATIONS

    point = {"spin_hz": 1.0, "sigma_sg_ppm": 300.0, "gnss_sigma_m": 2.0}
    both = EVALUATIONS["sensability"](**point)
    alone = EVALUATIONS["covariance"](**point)
    assert alone and {k: both[k] for k in alone} == alone
