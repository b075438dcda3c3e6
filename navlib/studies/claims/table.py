"""The one table of every claim (:func:`all_claims`, docs/library.md): every registered
study's claims (:mod:`navlib.studies.claims.registry`) with the causes the stored joint
searches (:mod:`navlib.studies.claims.search`) read."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import pandas as pd

from navlib.errors import NavlibInputError
from navlib.studies.claims.registry import Study, studies, study_frame
from navlib.studies.claims.robustness import cause_of
from navlib.studies.claims.search import SEARCH_SPACES, stored_search

__all__ = ["all_claims", "searched_causes"]


def all_claims(quick: bool = False, only: Sequence[str] | None = None,
               robustness: bool = True) -> pd.DataFrame:
    """Every claim of every registered study, one row each (docs/library.md).

    Parameters
    ----------
    quick : bool
        Smoke-test mode: each study runs its quick settings (shorter runs, smaller grids);
        claims a quick run cannot judge are "not evaluated".
    only : sequence of str, optional
        Study names (default all, see :func:`studies`).
    robustness : bool
        Evaluate each study's declared assumption set (the ``robustness`` column).

    Returns
    -------
    DataFrame
        ``study, paper_ref, claim_id, statement, paper, ours, verdict, basis, robustness,
        cause, checks, assumption, depends_on, explanation, robustness_note``; ``claim_id``
        unique. ``cause`` (partly / not reproduced claims): ``paper``, ``ours`` or
        ``unstated`` (:func:`~navlib.studies.claims.robustness.cause_of`) from the claim's
        robustness points and the stored joint searches that judge it
        (:func:`searched_causes`).
    """
    registry = studies()
    names = list(registry) if only is None else list(only)
    unknown = [n for n in names if n not in registry]
    if unknown:
        raise NavlibInputError(f"only: unknown studies {unknown}; expected some of "
                               f"{list(registry)}")
    frame = pd.concat([study_frame(registry[n], quick, robustness) for n in names],
                      ignore_index=True)
    dup = frame["claim_id"][frame["claim_id"].duplicated()].tolist()
    if dup:  # pragma: no cover - registry integrity
        raise NavlibInputError(f"claims: duplicate claim ids {dup}")
    return searched_causes(frame, registry)


def searched_causes(frame: pd.DataFrame, registry: Mapping[str, Study]) -> pd.DataFrame:
    """``frame`` with the ``cause`` of each ``paper`` row re-read from the stored joint
    searches (:data:`~navlib.studies.claims.search.SEARCH_SPACES`) that judge the claim: the
    points where it holds there, restricted to what they change from the search's baseline.
    A missing stored file leaves the row as it is."""
    kinds = {k: v for study in registry.values() for k, v in study.kinds.items()}
    frame = frame.copy()
    for name, space in SEARCH_SPACES.items():
        rows = frame.index[(frame.cause == "paper") & frame.claim_id.isin(space.claim_ids)]
        if not len(rows):
            continue
        try:
            stored, _ = stored_search(name)
        except NavlibInputError:
            continue
        base = space.points({}).iloc[0]
        params = list(space.parameters)
        if not set(params) <= set(stored.columns):  # a file older than its space: not read
            continue
        for i in rows:
            cid = frame.at[i, "claim_id"]
            if cid not in stored.columns:
                continue
            held = stored[stored[cid].astype(bool)]
            points = [{k: v for k, v in row.items() if repr(v) != repr(base[k])}
                      for row in held[params].to_dict("records")]
            frame.at[i, "cause"] = cause_of(frame.at[i, "verdict"], points, kinds)
    return frame
