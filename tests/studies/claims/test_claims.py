"""The claims engine (navlib.studies.claims): checks, the one verdict rule, the registry and
the table of every claim; and, for every claim of every study, that it can fail."""

import numpy as np
import pandas as pd
import pytest

from navlib import NavlibInputError
from navlib.studies import claims as engine
from navlib.studies import launcher, outliers
from navlib.studies.claims import Check, check, claim, verdict_of, with_failed_headline
from navlib.studies.rocket import profile as rocket_profile


# ---------------------------------------------------------------- checks and the rule
@pytest.mark.parametrize("op, target, good, bad", [
    ("<", 1.0, 0.5, 1.0), ("<=", 1.0, 1.0, 1.5), (">", 0.0, 0.1, 0.0), (">=", 2, 2, 1),
    ("==", True, True, False), ("!=", 0, 1, 0), ("in", (1.0, 2.0), 1.5, 2.5),
    ("out", (1.0, 2.0), 0.5, 1.5)])
def test_check_operators_and_failing_values(op, target, good, bad):
    assert Check("x", good, op, target).passed
    assert not Check("x", bad, op, target).passed
    c = Check("x", good, op, target)
    assert not c.failing().passed                      # every tolerance can be violated
    assert "-> pass" in c.text() and "-> FAIL" in c.failing().text()


def test_check_validation_and_nan():
    with pytest.raises(NavlibInputError, match="op"):
        Check("x", 1.0, "~", 1.0)
    with pytest.raises(NavlibInputError, match="target"):
        Check("x", 1.0, "in", 1.0)
    with pytest.raises(NavlibInputError, match="low <= high"):
        Check("x", 1.0, "in", (2.0, 1.0))
    assert not Check("x", float("nan"), "<", 1.0).passed
    assert not Check("x", float("nan"), "out", (0.0, 1.0)).passed


def test_the_one_verdict_rule():
    ok, bad = check("a", 1, "==", 1), check("b", 0, "==", 1)
    head_ok, head_bad = check("h", 1, "==", 1, True), check("h", 0, "==", 1, True)
    assert verdict_of([head_ok, ok]) == "reproduced"
    assert verdict_of([head_ok, bad]) == "partly"
    assert verdict_of([head_bad, ok]) == "not reproduced"
    assert verdict_of([ok, bad]) == "partly"                 # first check is the headline
    assert verdict_of([bad, ok]) == "not reproduced"
    assert verdict_of([head_ok, head_bad, ok]) == "not reproduced"   # every headline counts
    assert verdict_of([]) == engine.NOT_EVALUATED


def test_claim_result_basis_and_frame():
    c = claim("Z1", "statement", "paper", "ours", [check("h", 1, "==", 1, True)],
              basis="by construction")
    assert c.verdict == "reproduced" and not c.reproduced    # by construction never counts
    assert c.statement == "statement"
    with pytest.raises(NavlibInputError, match="basis"):
        claim("Z2", "s", "p", "o", [], basis="assumed")
    with pytest.raises(NavlibInputError, match="checks"):
        claim("Z3", "s", "p", "o", [True])
    frame = engine.claims_frame([c, engine.not_evaluated("Z4", "s", "p", "too short")])
    assert list(frame.verdict) == ["reproduced", "not evaluated"]
    assert frame.checks.iloc[1] == "too short"
    assert with_failed_headline(c).verdict == "not reproduced"


def test_robustness_over_the_points_of_what_a_claim_depends_on():
    def result(value, deps=("a",)):
        return claim("A", "s", "p", "o", [check("h", value, ">=", 1.0)], depends_on=deps)

    base = {"a": 1, "b": 1}
    variants = [({"a": 1}, [result(1.0)]), ({"a": 2}, [result(0.5)]),
                ({"a": 3}, [result(2.0)]), ({"b": 2}, [result(0.0)])]
    rob = engine.robustness_over(variants, base)["A"]
    assert rob.fraction == pytest.approx(2 / 3)       # the b point is not A's: left out
    assert rob.varied == ("a",) and rob.note == ""
    # the same measured value everywhere: NaN "insensitive", never 1.0
    same = [({"a": v}, [result(2.0)]) for v in (1, 2, 3)]
    flat = engine.robustness_over(same, base)["A"]
    assert np.isnan(flat.fraction) and flat.note.startswith("insensitive")
    # a set that varies none of its assumptions
    other = engine.robustness_over([({"b": v}, [result(2.0 + v)]) for v in (1, 2)], base)["A"]
    assert np.isnan(other.fraction) and other.note.startswith("not varied")
    skip = engine.not_evaluated("A", "s", "p", "short", depends_on=("a",))
    assert np.isnan(engine.robustness_over([({"a": 2}, [skip])], base)["A"].fraction)
    with pytest.raises(NavlibInputError, match="depends_on"):
        claim("A", "s", "p", "o", [], depends_on="a")


def test_explanation_quotes_the_set_experiment():
    def result(value):
        return claim("A", "s", "p", "o", [check("h", value, ">=", 1.0)], depends_on=("a",))

    base = {"a": 1}
    variants = [({"a": 1}, [result(0.5)]), ({"a": 2}, [result(0.8)])]
    rob = engine.robustness_over(variants, base)["A"]
    text = engine.explain(result(0.5), rob)
    assert "closest at a=2 with 0.8" in text and "holds at no point" in text
    variants.append(({"a": 3}, [result(1.5)]))
    text = engine.explain(result(0.5), engine.robustness_over(variants, base)["A"])
    assert "holds at 1/3 points" in text and "a=3: 1.5" in text
    assert engine.explain(result(1.5), rob) == ""                 # reproduced: none
    own = claim("A", "s", "p", "o", [check("h", 0.1, ">=", 1.0)], explanation="measured 0.1")
    assert engine.explain(own, rob) == "measured 0.1"
    assert engine.explain(result(0.5), None) == ""                # nothing measured: none


def test_cause_follows_where_the_claim_holds():
    """paper: it holds nowhere measured; ours: once only readings or models of ours change;
    unstated: only where a quantity the paper does not give changes."""
    kinds = {"tol": "ours", "sigma": "unstated"}
    assert engine.cause_of("not reproduced", [], kinds) == "paper"
    assert engine.cause_of("partly", [{}], kinds) == "paper"
    assert engine.cause_of("not reproduced", [{"tol": 1.0}], kinds) == "ours"
    assert engine.cause_of("partly", [{"sigma": 2.0}], kinds) == "unstated"
    assert engine.cause_of("partly", [{"sigma": 2.0, "tol": 1.0}], kinds) == "unstated"
    assert engine.cause_of("partly", [{"sigma": 2.0}, {"tol": 1.0}], kinds) == "ours"
    assert engine.cause_of("not reproduced", [{"other": 1}], kinds) == "unstated"
    assert engine.cause_of("reproduced", [], kinds) == ""
    assert engine.cause_of(engine.NOT_EVALUATED, [], kinds) == ""
    with pytest.raises(NavlibInputError, match="kinds"):
        engine.Study("bad", "p", lambda quick: [], kinds={"a": "theirs"})


def test_cause_column_reads_the_robustness_points(monkeypatch):
    from navlib.studies.claims import registry

    def result(value):
        return claim("CAUSE-1", "s", "p", "o", [check("h", value, ">=", 1.0)],
                     depends_on=("a",))

    def study(kind, values):
        return engine.Study("cause_t", "P", lambda quick: [result(0.5)], {"a": (1, 2)},
                            lambda quick: [({"a": 1}, [result(0.5)]),
                                           ({"a": 2}, [result(values)])],
                            baseline_point={"a": 1}, kinds={"a": kind})

    for kind, value, cause in (("ours", 2.0, "ours"), ("unstated", 2.0, "unstated"),
                               ("ours", 0.7, "paper")):
        monkeypatch.setitem(registry._REGISTRY, "cause_t", study(kind, value))
        table = engine.all_claims(only=["cause_t"])
        assert table.cause.tolist() == [cause]
        summary = engine.paper_summary(table)
        assert summary.loc["P", f"cause {cause}"] == 1


# ---------------------------------------------------------------- the registry and the table
def test_registry_and_table_contract():
    studies = engine.studies()
    assert {"rocket_profile", "rocket", "fig1", "table2", "covariance", "outliers",
            "ssac"} <= set(studies)
    table = engine.all_claims(only=["rocket_profile", "fig1"])
    assert list(table.columns) == engine.COLUMNS
    assert table.claim_id.is_unique
    assert set(table.verdict) <= set(engine.STATUSES) and set(table.basis) <= set(engine.BASES)
    assert (table[table.study == "rocket_profile"].basis == "by construction").all()
    assert table[table.study == "rocket_profile"].robustness.isna().all()  # no set declared
    summary = engine.paper_summary(table)
    assert {"reproduced", "explained", "unexplained", "cause paper", "cause ours",
            "cause unstated"} <= set(summary.columns)
    assert set(table.cause) <= {"", *engine.CAUSES}
    text = engine.summary_markdown(table)
    assert "claims" in text and "by construction" in text
    assert engine.counts(table).to_numpy().sum() == len(table)
    with pytest.raises(NavlibInputError, match="only"):
        engine.all_claims(only=["nope"])
    with pytest.raises(NavlibInputError, match="study"):
        engine.register("rocket")


# ---------------------------------------------------------------- every claim can fail
def _assert_can_fail(results):
    for c in results:
        assert c.checks, f"{c.claim_id} has no checks"
        assert with_failed_headline(c).verdict == "not reproduced", c.claim_id
        for k in c.checks:
            assert not k.failing().passed, (c.claim_id, k.name)


def test_profile_claims_fail_on_another_flight():
    from navlib.trajectory import sounding_rocket

    traj = sounding_rocket(ignition_s=10.0, spin_hz=2.0)
    results = rocket_profile.rocket_profile_claims(traj)
    assert {c.claim_id: c.verdict for c in results}["R1"] == "not reproduced"
    _assert_can_fail(results)


def test_fig1_claims_can_fail():
    _assert_can_fail(launcher.fig1_claims())


def _evolution(roll=0.9, pitch=0.2, bp_rw=1.0, gyro_rw=2.0, aided_gyro=0.99,
               x1000=0.3, model_1000=1.1, roll_att=0.1, roll_gps=0.9, gyro_gps=1.0,
               att_rw=1.0):
    """A hand-made covariance_evolution table (ratios to INS-only = the given values)."""
    rows = []

    def row(case, **v):
        base = {"roll": 1.0, "pitch": 1.0, "yaw": 1.0, "gyro_bias": 1.0, "accel_bias": 1.0,
                "gps_bias": 1.0, "gps_bias_0": 4.0}
        rows.append({"case": case, **base, **v})

    row("ins-only/none")
    row("gps/none", roll=roll, pitch=pitch, yaw=pitch)
    row("ideal-gps/none", roll=roll, pitch=pitch, yaw=pitch)
    row("ins-only/GAP/markov")
    row("gps/GAP/markov", roll=roll_gps, gyro_bias=gyro_gps)
    row("att/GAP/markov", roll=roll_att, gyro_bias=aided_gyro)
    row("att/GAP/random_walk", gyro_bias=aided_gyro * gyro_rw, gps_bias=bp_rw,
        roll=roll_att * att_rw, pitch=att_rw, yaw=att_rw)
    row("ins-only/GAP/markov x1000", gyro_bias=1.0)
    row("att/GAP/markov x1000", gyro_bias=x1000)
    row("att/GAP/random_walk x1000", gyro_bias=x1000 * model_1000)
    return pd.DataFrame(rows)


def test_evolution_claims_follow_the_table():
    good = {c.claim_id: c for c in launcher.evolution_claims(_evolution())}
    assert good["F2-roll"].verdict == "reproduced"
    assert good["C4-models"].verdict == good["F5-ins-only"].verdict == "reproduced"
    assert good["F5-ins-only"].basis == "by construction" and not good["F5-ins-only"].reproduced
    assert good["F3-bp"].verdict == "reproduced"
    assert good["F6-x1000"].verdict == "reproduced"
    assert good["F5-barely"].verdict == "reproduced"
    # Fig. 5 ("aiding barely reduces the gyro-bias sigma") and conclusion 2 ("gyro bias
    # observable only with attitude sensors") cannot both hold in full
    assert good["C2-att"].verdict == "partly"
    bad = {c.claim_id: c for c in launcher.evolution_claims(_evolution(
        roll=0.1, pitch=0.2, bp_rw=1.5, gyro_rw=1.0, aided_gyro=0.3, x1000=0.9,
        roll_att=0.9, roll_gps=0.2, att_rw=1.5))}
    assert set(bad) == set(good)
    for cid in ("F2-roll", "F2-ideal", "R-3.8", "F3-bp", "F5-model", "F5-ins-only", "F5-barely",
                "F6-x1000", "C4-models", "C2-att"):
        assert bad[cid].verdict == "not reproduced", (cid, bad[cid].checks_text())
    _assert_can_fail(good.values())


def test_covariance_claims_fail_without_correlation_or_roll_gain():
    t = np.linspace(0.0, 5.0, 6)
    corr = pd.DataFrame({"t": np.repeat(t, 3), "axis": np.tile(["roll", "pitch", "yaw"], 6),
                         "rho": 0.1})
    ts = np.linspace(0.0, 30.0, 31)
    sig = pd.concat([pd.DataFrame({"t": ts, "solution": s, "axis": ax, "sigma": 1.0})
                     for s in ("ins_gps", "ins_gps_rt", "ins_gps_att", "ins_gps_att_rt")
                     for ax in ("roll", "pitch", "yaw")], ignore_index=True)
    results = outliers.covariance_claims(corr, sig, pd.Series({"dr_x": 1.0, "psi_x": 0.1}))
    assert {c.claim_id: c.verdict for c in results} == {
        "F10": "not reproduced", "F7": "not reproduced", "F11": "not reproduced"}
    _assert_can_fail(results)


def test_table2_claims_can_fail():
    paper = launcher.paper_table2()
    frame = paper.rename(columns={"n_unobservable": "paper_unobservable",
                                  "log10_cond": "paper_log10_cond"})
    frame["n_unobservable"] = frame.paper_unobservable
    frame["log10_cond"] = frame.paper_log10_cond
    frame["rank_constant"] = True
    frame["groups"] = np.where(frame.paper_unobservable > 0,
                               "{dr_x, bp_x}; {dr_y, bp_y}; {dr_z, bp_z}", "")
    frame["weakest"] = "psi_roll +1.00"
    paper_self = {c.claim_id: c for c in launcher.table2_claim_results(frame)}
    # the paper's own table passes its own statements except where it contradicts itself
    for cid in ("T2-table", "T2-RW-P", "T2-bp-dr", "T2-Markov", "T2-rank-constant",
                "T2-threshold", "T2-ins-gps"):
        assert paper_self[cid].verdict == "reproduced", (cid, paper_self[cid].checks_text())
    shifted = frame.assign(log10_cond=frame.log10_cond + 0.75)
    moved = {c.claim_id: c for c in launcher.table2_claim_results(shifted)}
    assert moved["T2-table"].verdict == "partly"           # counts equal, orders off
    assert moved["T2-ins-gps"].verdict == "not reproduced"
    assert launcher.match_counts(shifted)[1.0] == len(frame)
    _assert_can_fail(paper_self.values())


def test_outlier_claims_can_fail_and_t3_does_not_count_the_absent_channel():
    traj = outliers.default_trajectory(quick=True)
    cache = outliers.FilterCache(traj, size=4)
    st, cov = outliers.study_claims(cache, window=20.0, outlier_time_s=30.0, shapes=("spike",))
    t3 = next(c for c in st.claims if c.claim_id == "T3")
    assert len(t3.checks) == 1 and "INS/GPS + RT" in t3.checks[0].name
    assert "not checked" in t3.assumption
    _assert_can_fail(st.claims + cov)
    longer = outliers.rescore(st, 40.0)
    assert longer.settings["window"] == 40.0
    assert [c.claim_id for c in longer.claims] == [c.claim_id for c in st.claims]
    r = next(iter(longer.responses.values()))
    assert r.score.window == 40.0
    # the non-RT responses of a study that differs only in RT-only options are reused
    again = outliers.paper_tests(cache=cache, window=20.0, outlier_time_s=30.0, shapes=("spike",),
                                 reuse=st)
    key = ("T2", "ins_gps", "spike")
    assert again.responses[key].score == st.responses[key].score
    with pytest.raises(NavlibInputError, match="reuse"):
        outliers.paper_tests(cache=cache, window=20.0, outlier_time_s=30.0, biases="GA", reuse=st)
