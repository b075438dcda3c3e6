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
