"""The stored joint searches of the papers' assumption spaces (scripts/claims_search.py): each
header names the command and the navlib version, a random sample of each stored search's
points recomputes to the same verdicts, and the search reads the best point and the
conflicts from it."""

import numpy as np
import pandas as pd
import pytest

import navlib.studies  # noqa: F401 - the studies register their search spaces
from navlib import NavlibInputError
from navlib.studies import claims as engine
from navlib.sweep import sweep


@pytest.mark.parametrize("name", list(engine.SEARCH_SPACES))
def test_stored_search_recomputes_on_a_random_sample(name):
    space = engine.search_space(name)
    frame, header = engine.stored_search(name)
    assert header["command"].startswith("python scripts/claims_search.py")
    assert header["navlib"]
    points = space.points()
    assert len(frame) == len(points)
    pd.testing.assert_frame_equal(frame[list(space.parameters)], points, check_dtype=False)
    rows = np.random.default_rng().choice(len(frame), size=2, replace=False)
    again = sweep(points.iloc[rows].reset_index(drop=True), space.evaluation,
                  scheduler="synchronous")
    ids = list(space.claim_ids)
    stored = frame.iloc[rows].reset_index(drop=True)
    assert (again[ids].astype(bool).to_numpy() == stored[ids].astype(bool).to_numpy()).all()


def test_unknown_search_is_named():
    with pytest.raises(NavlibInputError, match="known"):
        engine.search_space("no such paper")


def test_joint_search_reads_best_point_and_conflicts():
    frame = pd.DataFrame({"a": [1, 2, 3], "X": [True, False, True], "Y": [False, True, False],
                          "Z": [True, True, False]})
    js = engine.joint_search(frame, ["a"], ["X", "Y", "Z"])
    assert js.best == {"a": 1} and js.n_reproduced == 2 and js.n_points == 3
    assert list(js.conflicts[["claim_a", "claim_b"]].itertuples(index=False, name=None)) == \
        [("X", "Y")]
    assert js.held == {"X": 2, "Y": 1, "Z": 2}
    with pytest.raises(NavlibInputError, match="missing"):
        engine.joint_search(frame, ["b"], ["X"])


def _study(name, points, baseline):
    """A registered study whose claim A holds where x > 0 and B where y > 0."""
    def claims_at(point):
        full = {**baseline, **point}
        return [engine.claim(cid, "statement", "paper", f"{key} = {full[key]}",
                             [engine.check("value", 1.0 if full[key] > 0 else 0.0, ">=", 1.0)],
                             depends_on=(key,))
                for cid, key in (("A", "x"), ("B", "y"))]

    return engine.Study(name, "a paper", lambda quick: claims_at({}),
                        {"x": (-1.0, 1.0), "y": (-1.0, 1.0)},
                        lambda quick: [(p, claims_at(p)) for p in points],
                        baseline_point=baseline)


def test_a_factorial_declared_set_is_its_own_joint_search(monkeypatch):
    from navlib.studies.claims import registry

    baseline = {"x": 1.0, "y": -1.0}
    factorial = [{"x": x, "y": y} for x in (-1.0, 1.0) for y in (-1.0, 1.0)]
    monkeypatch.setattr(registry, "_REGISTRY", {})  # the papers' studies are not run here
    monkeypatch.setitem(registry._REGISTRY, "fact", _study("fact", factorial, baseline))
    frame = engine.factorial_search("fact")
    assert list(frame.columns) == ["x", "y", "A", "B"] and len(frame) == 4
    assert frame.A.tolist() == [False, False, True, True]
    found = engine.joint_search(frame, ["x", "y"], ["A", "B"])
    assert found.best == {"x": 1.0, "y": 1.0} and found.n_reproduced == 2
    searches = {s.name: s for s in engine.joint_searches()}
    assert set(searches) == {*engine.SEARCH_SPACES, "fact"}  # the stored ones, then in process
    assert searches["fact"].claim_ids == ("A", "B")
    assert searches["fact"].baseline.to_dict() == baseline
    # one at a time from the baseline: A and B are never varied together, so no joint search
    one_at_a_time = [{"x": -1.0}, {"y": 1.0}]
    monkeypatch.setitem(registry._REGISTRY, "fact", _study("fact", one_at_a_time, baseline))
    assert engine.factorial_search("fact") is None
    assert "fact" not in {s.name for s in engine.joint_searches()}


def test_paper_summary_adds_searches_that_share_no_assumption():
    def table(name, paper, parameter, passed):
        frame = pd.DataFrame({parameter: [1, 2], "C" + name: passed})
        return engine.SearchTable(name, paper, "test", frame, (parameter,), ("C" + name,),
                                  pd.Series({parameter: 1}))

    searches = [table("a", "P", "x", [True, False]), table("b", "P", "y", [False, True]),
                table("c", "Q", "x", [False, False])]
    summary = engine.paper_joint_summary(searches).set_index("paper")
    assert summary.loc["P", ["claims", "reproduced", "points"]].tolist() == [2, 2, "2 x 2"]
    assert summary.loc["P", "joint"] and summary.loc["Q", "reproduced"] == 0
    shared = engine.paper_joint_summary([searches[0], table("b", "P", "x", [False, True])])
    assert not shared.joint.iloc[0]          # both vary x: the sum is only an upper bound
