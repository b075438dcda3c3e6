"""Every measured Silva et al. (2017) claim can fail: changing an input the claim declares in
``depends_on`` moves its measured number, and for a defensible value of one such input the
verdict flips (docs/assumptions.md, A-SSAC-set). Claims no such input moves are "by
construction". The joint search re-judges its points as ``ssac_claims`` does."""

import numpy as np
import pytest

import navlib.studies  # noqa: F401 - registers the SSAC search space
from navlib.models.ssac import ssac as ssac_model
from navlib.studies import claims as engine
from navlib.studies import ssac as S
from navlib.studies.ssac import search
from navlib.studies.ssac.eigen_claims import orientation_claim

DURATION_S = 3600.0


def _claims(study, **options):
    return {c.claim_id: c for c in S.ssac_claims(study, **options)}


def _tables(rtol):
    return S.static_tables(S.SITE_LAT_DEG, S.SITE_ALT_M, DURATION_S, rtol)


@pytest.fixture(scope="module")
def runs():
    """Baseline and one-input-changed 60 min runs, with their claims (reduced runs made)."""
    cases = {"base": {}, "generic P0": {"P0": "generic"}, "attitude x0.5": {
        "attitude_scale": 0.5}, "attitude x3": {"attitude_scale": 3.0},
        "ARW deg/sqrt(s)": {"imu": {"gyro_arw": S.ARW_READINGS["deg/sqrt(s)"]}},
        "ZVU noise x2": {"sigma_nu": 0.02}, "ZVU noise x10": {"sigma_nu": 0.1}}
    out = {}
    for name, kw in cases.items():
        study = S.covariance_run(DURATION_S, track=False, **kw)
        out[name] = (study, _claims(study, tables=_tables(S.RANK_RTOL)))
    return out


def _headline(claim, i=0):
    return claim.checks[i].value


# (claim, changed input, check index, verdict flips at that input)
MOVES = [
    ("SSAC-estimable", "generic P0", 0, True),
    ("SSAC-position", "ZVU noise x2", 0, False),
    ("SSAC-position", "ZVU noise x10", 0, True),
    ("SSAC-nonzero", "attitude x0.5", 0, False),
    ("SSAC-fast5", "generic P0", 0, True),
    ("SSAC-10min", "generic P0", 1, False),
    ("SSAC-bgD", "ZVU noise x10", 0, True),
    ("SSAC-eq44", "attitude x3", 0, True),
    ("SSAC-actual", "generic P0", 0, False),
    ("SSAC-eig6", "ARW deg/sqrt(s)", 0, True),
    ("SSAC-pairs", "generic P0", 0, True),
    ("SSAC-poseig", "ARW deg/sqrt(s)", 0, True),
    ("SSAC-nine", "generic P0", 1, True),
    ("SSAC-X", "attitude x3", 2, True),          # the exchange nearest 50 min: 54.0 -> 31.4
    ("SSAC-bgDeig", "ARW deg/sqrt(s)", 0, True),
    ("SSAC-12state", "ZVU noise x2", 1, False),
    ("SSAC-10state", "ZVU noise x2", 0, False),
    ("SSAC-P0", "generic P0", 1, True),
]


@pytest.mark.parametrize(("cid", "case", "index", "flips"), MOVES,
                         ids=[f"{m[0]}-{m[1]}" for m in MOVES])
def test_measured_claim_moves_with_an_input_it_depends_on(runs, cid, case, index, flips):
    base, moved = runs["base"][1][cid], runs[case][1][cid]
    assert base.basis in ("measured", "fitted")
    assert base.depends_on                                  # it declares what it reads
    assert _headline(moved, index) != pytest.approx(_headline(base, index), rel=1e-6)
    assert (moved.verdict != base.verdict) is flips


def test_every_measured_ssac_claim_has_a_moving_input():
    """No measured claim is left without a test that moves it (or an audit test)."""
    audited = {"SSAC-rank15", "SSAC-rank10", "SSAC-groups", "SSAC-order",
               "SSAC-orientation"}                         # tested below
    measured = {c.claim_id for c in S.ssac_claims(S.covariance_run(600.0, track=False))
                if c.basis in ("measured", "fitted") and c.verdict != engine.NOT_EVALUATED}
    long_only = {"SSAC-bgD", "SSAC-eig6", "SSAC-X", "SSAC-bgDeig"}
    assert measured | long_only <= {m[0] for m in MOVES} | audited


def test_rank_claims_flip_at_a_coarse_tolerance(runs):
    study, base = runs["base"]
    coarse = _claims(study, rank_rtol=1e-3, tables=_tables(1e-3))
    for cid in ("SSAC-rank15", "SSAC-rank10"):
        assert base[cid].verdict == "reproduced"
        assert _headline(coarse[cid]) == _headline(base[cid]) - 1
        assert coarse[cid].verdict == "not reproduced"


def test_individual_observability_is_by_construction(runs):
    """The ZVU measures the velocity errors, so no input moves the count: by construction."""
    counts = set()
    for study, _ in runs.values():
        for rtol in (1e-12, 1e-6, 1e-3):
            c = S.ssac_claims(study, rank_rtol=rtol, tables=_tables(rtol))
            c = next(r for r in c if r.claim_id == "SSAC-individual")
            counts.add(tuple(ch.value for ch in c.checks))
            assert c.basis == "by construction"
    assert counts == {(3, 0)}


def test_groups_explanation_measures_the_earth_rate_coupling(runs):
    """At the site the exact null space has 4 blocks; at the equator (no Omega sin L
    terms) 5: the explanation quotes both, measured."""
    groups = runs["base"][1]["SSAC-groups"]
    assert groups.verdict == "not reproduced"
    site = S.grouping_table(S.SITE_LAT_DEG, S.SITE_ALT_M).iloc[0]
    equator = S.grouping_table(0.0, S.SITE_ALT_M).iloc[0]
    assert int(equator["n_groups"]) > int(site["n_groups"])
    assert f"has {int(site['n_groups'])} blocks" in groups.explanation
    assert f"it has {int(equator['n_groups'])}" in groups.explanation


def test_order_numbers_move_with_the_noise(runs):
    base, moved = runs["base"][1]["SSAC-order"], runs["ZVU noise x10"][1]["SSAC-order"]
    assert base.ours != moved.ours


def test_orientation_shares_move_with_the_imu_orientation():
    base = S.orientation_table(duration_s=600.0)
    other = S.orientation_table((75.0, -40.0, 25.0), duration_s=600.0)
    assert not np.allclose(base.body_share, other.body_share, atol=1e-3)


def test_orientation_claim_fails_for_a_level_imu_turned_in_heading():
    """SSAC-orientation ("every axis of a rotated IMU has a non-estimable portion") holds for
    the tilted orientations of the declared set and fails for the level one turned only in
    heading (in the set too): its vertical axis keeps no portion."""
    assert S.ORIENTATIONS[0] == S.ORIENTATION_DEG
    verdicts = {ypr: orientation_claim(S.orientation_table(ypr, duration_s=600.0))
                for ypr in S.ORIENTATIONS}
    assert [v.verdict for v in verdicts.values()] == ["reproduced"] * 3 + ["not reproduced"]
    level = verdicts[(45.0, 0.0, 0.0)].checks[0].value
    assert level < 1e-3 < verdicts[S.ORIENTATION_DEG].checks[0].value


def test_reduced_filters_read_against_the_15_state_truth(runs):
    """SSAC-12state and -10state read the reduced filters' actual errors on the 15-state
    truth: the 12-state one, whose own sigmas match the 15-state ones, is far off (the
    explanation quotes the dropped coupling and the vertical channel, measured on A); the
    10-state one is inadequate."""
    study, claims = runs["base"]
    reduced12 = S.covariance_run(DURATION_S, n_states=12, track=False)
    value, kept, dropped = S.dropped_coupling(study, reduced12)
    assert 0.0 < value < 1e-3 and dropped not in reduced12.state_names
    assert claims["SSAC-12state"].verdict == "not reproduced"
    assert f"{value:.2g} 1/s, {dropped} -> {kept}" in claims["SSAC-12state"].explanation
    assert "dvD <- dh" in claims["SSAC-12state"].explanation
    assert claims["SSAC-10state"].verdict == "reproduced"
    own = S.covariance_run(DURATION_S, n_states=10, track=False).covariance.sigma[-1]
    names = list(S.covariance_run(60.0, n_states=10, track=False).state_names)
    actual = S.actual_sigmas(study, S.covariance_run(DURATION_S, n_states=10, track=False))
    assert (actual >= own * (1.0 - 1e-6)).all()        # the truth never helps a filter
    assert (actual / own).max() > 100.0, names


def test_noise_scale_is_in_the_declared_set():
    assert "noise_scale" in S.ROBUSTNESS_GRID
    assert all("noise_scale" in c.depends_on for c in S.ssac_claims(
        S.covariance_run(600.0, track=False)) if "P0" in c.depends_on)


def _heading_p0(n_states, P0, attitude_scale, factor):
    """The named P0 with its psiD sigma times ``factor``, built here from the model."""
    model = ssac_model(n_states, S.SITE_LAT_DEG, S.SITE_ALT_M, P0=P0,
                       attitude_scale=attitude_scale)
    scale = np.ones(model.n)
    scale[model.state_names.index("psiD")] = factor
    return np.asarray(model.P0) * np.outer(scale, scale)


def test_search_point_judges_as_ssac_claims():
    """A non-baseline point of the joint search, with a heading prior on the generic P0 (the
    factor multiplies its psiD sigma too, A-SSAC-eq44-prior), gives the verdicts of
    ssac_claims on runs from that P0."""
    point = dict(P0="generic", attitude_scale=2.0, heading_prior=2.0,
                 arw_reading="deg/sqrt(h)", noise_scale=0.5, convergence="t99",
                 rank_rtol=1e-6, x0=S.ROBUSTNESS_GRID["x0"][2])
    prepared = search._prepare(*(point[k] for k in search.SHARED))
    row = search._claims_run(prepared, **point)
    study = prepared["study"]
    np.testing.assert_allclose(study.model.P0, _heading_p0(15, "generic", 2.0, 2.0))
    psid = study.model.state_names.index("psiD")
    assert np.degrees(np.sqrt(study.model.P0[psid, psid])) == pytest.approx(4.0)
    reduced = {n: S.covariance_run(DURATION_S, n_states=n, P0=_heading_p0(n, "generic", 2.0,
                                                                         2.0),
                                   sigma_nu=0.005, track=False) for n in (12, 10)}
    ref = _claims(study, convergence="t99", rank_rtol=1e-6, tables=S.static_tables(
        S.SITE_LAT_DEG, S.SITE_ALT_M, DURATION_S, 1e-6),
        reduced=reduced[12], reduced10=reduced[10],
        p0_table=S.p0_sensitivity(study, modified=S.covariance_run(
            DURATION_S, attitude_scale=S.P0_MODIFIED_ATTITUDE_SCALE, sigma_nu=0.005,
            track=False)))
    ref["SSAC-actual"] = S.actual_claim(study, S.x0_draws(study)[1])
    assert {cid: row[cid] for cid in search.CLAIM_IDS} == \
        {cid: ref[cid].verdict == "reproduced" for cid in search.CLAIM_IDS}
    assert len(S.search_points()) == 2 * 3 * 3 * 2 * 3 * 4 * 4 * (1 + search.SEARCH_X0)
    assert "heading_prior" in search.SHARED


def test_eq44_explanation_predicts_where_the_verdict_flips():
    """The explanation's threshold (initial psiD sigma >= 2.06 classic limits) is where the
    verdict flips: attitude sigmas x2.0 fail, x2.1 reproduce."""
    below, above = (S.ssac_claims(S.covariance_run(DURATION_S, attitude_scale=scale,
                                                   track=False), reduced=None, reduced10=None)
                    for scale in (2.0, 2.1))
    below, above = ({c.claim_id: c for c in r}["SSAC-eq44"] for r in (below, above))
    assert "at least 2.06 times" in below.explanation
    assert below.verdict == "not reproduced" and above.verdict == "reproduced"


def test_eq44_moves_through_the_declared_heading_prior():
    """SSAC-eq44 declares the initial heading sigma it hinges on (A-SSAC-eq44-prior): the
    matched prior gives 1/sqrt(2) of the classic limit, x3 the limit within 10 %."""
    from navlib.studies.ssac.assumptions import BASELINE_POINT, HEADING_PRIORS
    from navlib.studies.ssac.robustness import baseline_claims, grid_claims

    assert BASELINE_POINT["heading_prior"] == 1.0 and 3.0 in HEADING_PRIORS
    eq44 = {p.get("heading_prior", 1.0): r for p, rs in grid_claims(True) for r in rs
            if r.claim_id == "SSAC-eq44" and set(p) <= {"heading_prior", "P0",
                                                          "attitude_scale"}}
    assert "heading_prior" in eq44[1.0].depends_on
    assert eq44[1.0].headline_values()[0] == pytest.approx(1.0 / np.sqrt(2.0), rel=1e-3)
    assert eq44[1.0].verdict == eq44[2.0].verdict == "not reproduced"
    assert eq44[3.0].verdict == "reproduced"
    assert eq44[3.0].headline_values()[0] == pytest.approx(3.0 / np.sqrt(10.0), rel=1e-3)
    rob = engine.study_robustness(engine.studies()["ssac"], quick=True)["SSAC-eq44"]
    assert "heading_prior" in rob.varied
    # the prior is part of P0: every claim read from the run declares it, and it moves the
    # fitted 45 deg pairs (SSAC-pairs) and the actual-error ratio off their verdicts
    heads = {p["heading_prior"]: {r.claim_id: r for r in rs} for p, rs in grid_claims(True)
             if set(p) == {"heading_prior"}}
    base = {r.claim_id: r for r in baseline_claims(True)}
    assert set(heads[2.0]) == {cid for cid, r in base.items() if "P0" in r.depends_on}
    pairs = [base["SSAC-pairs"], heads[2.0]["SSAC-pairs"]]
    assert pairs[1].headline_values()[0] > 10.0 > pairs[0].headline_values()[0]
    assert [r.verdict for r in pairs] == ["reproduced", "not reproduced"]
    assert heads[3.0]["SSAC-actual"].verdict == "not reproduced"
    frame = engine.study_frame(engine.studies()["ssac"], quick=True)
    assert frame.set_index("claim_id").at["SSAC-eq44", "cause"] == "unstated"


def test_x_shape_checks_the_exchange_the_paper_describes(runs):
    """SSAC-X reads the exchange nearest the paper's ~50 min (54.0 min here), not the first
    one (26 min), and says which."""
    x = runs["base"][1]["SSAC-X"]
    assert x.checks[2].name.startswith("exchange nearest")
    assert x.checks[2].value == pytest.approx(54.0, abs=0.5)
    assert "the exchange at 54.0 min" in x.ours and "exchange 3 of 3" in x.ours
    assert x.verdict == "reproduced"
