"""Silva et al. (2017) assumption space searched jointly: the named sweep evaluation
``"ssac_claims"`` (one boolean per claim at a point of the declared set) and its registration
as :data:`SEARCH` (docs/assumptions.md, A-SSAC-set; stored in
``data/claims_search_ssac.csv`` by ``scripts/claims_search.py --study ssac``).

A point is one value of each declared assumption (:data:`SEARCH_GRID`). The covariance runs
depend on the P0, its attitude scale and heading prior, the gyro random-walk unit and the ZVU
noise only
(:data:`SHARED`, the shared input of a point, built once per distinct set: the 15-, 12- and
10-state runs and the P0-sensitivity rerun); the convergence reading, the rank tolerance and
the truth x0 re-judge those runs.
"""

from __future__ import annotations

import pandas as pd

from navlib.errors import NavlibInputError
from navlib.models.ssac import SITE_ALT_M, SITE_LAT_DEG
from navlib.studies.claims import NOT_EVALUATED
from navlib.studies.claims.search import SearchSpace, factorial_points, register_search
from navlib.studies.ssac.assumptions import (
    ARW_READINGS,
    BASELINE_POINT,
    ROBUSTNESS_GRID,
    initial_covariance,
    sigma_nu,
)
from navlib.studies.ssac.claims import (
    actual_claim,
    bgd_claim,
    fast5_claim,
    groups_claim,
    individual_claim,
    rank_claims,
    ssac_claims,
    static_tables,
    ten_minute_claim,
)
from navlib.studies.ssac.experiment import (
    P0_MODIFIED_ATTITUDE_SCALE,
    p0_runs,
    p0_sensitivity,
    x0_draws,
)
from navlib.studies.ssac.observability import RANK_RTOL
from navlib.sweep import Evaluation, register

__all__ = ["CLAIM_IDS", "DURATION_S", "SEARCH", "SEARCH_GRID", "SEARCH_PARAMETERS", "SEARCH_X0",
           "SHARED", "search_points"]

SEARCH_X0 = 2
"""Draws of x0 from N(0, P0) searched beside the baseline x0 (the first of the robustness
set's :data:`~navlib.studies.ssac.X0_DRAWS`; x0 enters SSAC-actual only)."""
SHARED = ("P0", "attitude_scale", "heading_prior", "arw_reading", "noise_scale")
"""The assumptions of a point's covariance runs (the sweep's shared input)."""
SEARCH_GRID = {**{k: ROBUSTNESS_GRID[k] for k in (*SHARED, "convergence", "rank_rtol")},
               "x0": ROBUSTNESS_GRID["x0"][:1 + SEARCH_X0]}
"""The SSAC assumption space searched jointly (full factorial): the declared set
:data:`~navlib.studies.ssac.ROBUSTNESS_GRID` with x0 narrowed to the baseline and
:data:`SEARCH_X0` draws."""
SEARCH_PARAMETERS = tuple(SEARCH_GRID)
"""The assumption columns of a point (:data:`SEARCH`)."""
CLAIM_IDS = ("SSAC-rank15", "SSAC-rank10", "SSAC-individual", "SSAC-groups", "SSAC-estimable",
             "SSAC-position", "SSAC-nonzero", "SSAC-fast5", "SSAC-10min", "SSAC-bgD",
             "SSAC-eq44", "SSAC-actual", "SSAC-eig6", "SSAC-pairs", "SSAC-poseig",
             "SSAC-order", "SSAC-nine", "SSAC-X", "SSAC-bgDeig", "SSAC-orientation",
             "SSAC-12state", "SSAC-10state", "SSAC-P0")
"""The claims judged at each point (every SSAC claim but SSAC-experimental, which no
assumption makes evaluable)."""
DURATION_S = 3600.0
"""Run length of a search point (the paper's 60 min)."""


def search_points(grid: dict | None = None) -> pd.DataFrame:
    """The points of :data:`SEARCH_GRID` (or of ``grid``: a key left out keeps its
    :data:`~navlib.studies.ssac.BASELINE_POINT` value) as :func:`navlib.sweep.sweep` points
    of the ``"ssac_claims"`` evaluation."""
    points = factorial_points(grid, SEARCH_GRID, BASELINE_POINT)
    for key in SEARCH_PARAMETERS:
        unknown = [v for v in points[key].unique().tolist() if v not in ROBUSTNESS_GRID[key]]
        if unknown:
            raise NavlibInputError(f"grid[{key!r}]: {unknown} not in the declared set "
                                   f"{list(ROBUSTNESS_GRID[key])}")
    return points


def _prepare(P0, attitude_scale, heading_prior, arw_reading, noise_scale):
    """The runs of a point's covariance assumptions and the claims judged on them at the
    baseline convergence reading, rank tolerance and x0: the 15-state run with its 12- and
    10-state counterparts (each with the point's heading prior,
    :func:`~navlib.studies.ssac.assumptions.initial_covariance`) and the P0-sensitivity
    rerun."""
    arw = ARW_READINGS[arw_reading]
    runs = {"track": False, "imu": None if arw is None else {"gyro_arw": arw},
            "sigma_nu": sigma_nu(noise_scale)}
    study, modified = p0_runs([initial_covariance(P0, attitude_scale, heading_prior),
                               ("matched", P0_MODIFIED_ATTITUDE_SCALE)], DURATION_S, **runs)
    reduced = {n: p0_runs([initial_covariance(P0, attitude_scale, heading_prior, n)],
                          DURATION_S, n_states=n, **runs)[0] for n in (12, 10)}
    orientation = static_tables(SITE_LAT_DEG, SITE_ALT_M, DURATION_S)[2]
    claims = ssac_claims(study, tables=static_tables(SITE_LAT_DEG, SITE_ALT_M, DURATION_S,
                                                     RANK_RTOL, orientation),
                         reduced=reduced[12], reduced10=reduced[10],
                         p0_table=p0_sensitivity(study, modified=modified))
    return {"study": study, "orientation": orientation, "x0": x0_draws(study),
            "convergence": study.convergence_table().set_index("state"),
            "claims": {c.claim_id: c for c in claims}}


def _claims_run(prepared, P0, attitude_scale, heading_prior, arw_reading, noise_scale,
                convergence, rank_rtol, x0):
    """One boolean per claim of :data:`CLAIM_IDS` (True = reproduced) and their count: the
    prepared claims with those reading the convergence reading, the rank tolerance or x0
    judged again at this point (as :func:`~navlib.studies.ssac.ssac_claims` judges them)."""
    study, conv = prepared["study"], prepared["convergence"]
    obs, groups, _ = static_tables(SITE_LAT_DEG, SITE_ALT_M, DURATION_S, rank_rtol,
                                   prepared["orientation"])
    results = dict(prepared["claims"])
    labels = ROBUSTNESS_GRID["x0"]
    again = [*rank_claims(obs, rank_rtol), individual_claim(study, rank_rtol),
             groups_claim(groups, SITE_LAT_DEG, SITE_ALT_M, rank_rtol),
             fast5_claim(conv, convergence), ten_minute_claim(conv, convergence),
             bgd_claim(study, conv, convergence)]
    if x0 != labels[0]:
        again.append(actual_claim(study, prepared["x0"][labels.index(x0) - 1]))
    results.update((r.claim_id, r) for r in again)
    if any(results[cid].verdict == NOT_EVALUATED for cid in CLAIM_IDS):
        raise NavlibInputError("ssac_claims: a searched claim was not evaluated")
    passed = {cid: results[cid].verdict == "reproduced" for cid in CLAIM_IDS}
    return {**passed, "n_reproduced": int(sum(passed.values()))}


register(Evaluation("ssac_claims", "SSAC ZVU alignment: verdicts of Silva et al.'s claims "
                    "(True = reproduced) at a point of the declared assumption set",
                    {k: BASELINE_POINT[k] for k in SEARCH_PARAMETERS}, SHARED, _claims_run,
                    _prepare))

SEARCH = register_search(SearchSpace(
    "ssac", "Silva, Hemerly & Leite Filho (2017)", SEARCH_PARAMETERS, CLAIM_IDS,
    "ssac_claims", search_points, "claims_search_ssac.csv"))
"""The Silva et al. assumption space searched jointly (stored in
``data/claims_search_ssac.csv``)."""
