"""The Beaudoin et al. (2018) covariance claims searched jointly over their declared
assumption space (docs/assumptions.md, A-launcher-search): the named sweep evaluation
``"launcher_claims"`` judges the covariance-evolution claims and the end of §4.1 at one point,
and the space is registered with the claims engine (stored in
``data/claims_search_covariance.csv``)."""

from __future__ import annotations

import itertools

import numpy as np
import pandas as pd

from navlib.cache import memoized
from navlib.studies.claims.search import SearchSpace, factorial_points, register_search
from navlib.studies.launcher.assumptions import (
    LATERAL_BASELINE,
    NO_PITCH_KICK_DEG,
    SURVEYED_PAD_M,
)
from navlib.studies.launcher.causes import cp_mission_sigmas
from navlib.studies.launcher.claims import f1_cp_mission_claim
from navlib.studies.launcher.covariance_claims import evolution_claims
from navlib.studies.launcher.evolution import evolution_tables
from navlib.sweep import Evaluation, register
from navlib.trajectory import launcher_ascent

__all__ = ["SEARCH", "SEARCH_BASELINE", "SEARCH_CLAIMS", "SEARCH_GRID", "SEARCH_PARAMETERS",
           "search_points"]

SEARCH_GRID = {
    "gust_mps": (0.0, LATERAL_BASELINE),
    "kick_deg": (NO_PITCH_KICK_DEG, 2.5),
    "c_p": (100.0, 1000.0),
    "c_g": (100.0, 1000.0),
    "sigma0_att_deg": (0.1, 0.3),
    "sigma0_pos_m": (SURVEYED_PAD_M, 3.0),
}
"""The declared space (full factorial, 64 points), each value one a reader of the paper could
pick (A-launcher-search): the lateral motion of the ascent (no wind, or the cited 9 m/s gusts,
A-launcher-lateral), the pitch kick of the surrogate ascent (the paper's "no manoeuvres"
read literally, or our 2.5 deg gravity turn), the GPS-bias and gyro-bias time constants (the
inferred 100 s, or the longer constants the paper's references allow), the initial attitude
sigma (not given) and the initial position sigma (a surveyed pad, or our 3 m)."""
SEARCH_BASELINE = {"gust_mps": LATERAL_BASELINE, "kick_deg": 2.5, "c_p": 100.0, "c_g": 100.0,
                   "sigma0_att_deg": 0.1,
                   "sigma0_pos_m": 3.0}
"""The study's baseline point of :data:`SEARCH_GRID`."""
SEARCH_PARAMETERS = tuple(SEARCH_GRID)
SEARCH_CLAIMS = ("F1-cp-mission", "F2-roll", "F2-ideal", "R-3.8", "F3-bp", "F5-model",
                 "F5-barely", "F6-x1000", "C4-models", "C2-att")
"""The measured claims judged at each point (F5-ins-only is by construction)."""


def search_points(grid: dict | None = None) -> pd.DataFrame:
    """The points of :data:`SEARCH_GRID` (or of ``grid``; a key left out keeps its
    :data:`SEARCH_BASELINE` value) as sweep points of ``"launcher_claims"``."""
    return factorial_points(grid, SEARCH_GRID, SEARCH_BASELINE)


@memoized(maxsize=1)
def _tables(gust_mps: float, kick_deg: float, c_p: float, c_g: float) -> dict:
    """The covariance-evolution tables at every initial sigma pair of :data:`SEARCH_GRID` for
    one ascent and pair of time constants, from one stacked recursion per case (kept per
    process: the points sharing them reuse it)."""
    pairs = list(itertools.product(SEARCH_GRID["sigma0_att_deg"], SEARCH_GRID["sigma0_pos_m"]))
    kws = [{"c_p": c_p, "c_g": c_g, "sigma0_att": np.radians(a), "sigma0_pos": p}
           for a, p in pairs]
    tables = evolution_tables(launcher_ascent(gust_mps=gust_mps, kick_deg=kick_deg), kws)
    return dict(zip(pairs, tables, strict=True))


def _claims_run(_, *, gust_mps, kick_deg, c_p, c_g, sigma0_att_deg, sigma0_pos_m) -> dict:
    table = _tables(float(gust_mps), float(kick_deg), float(c_p), float(c_g))[
        (float(sigma0_att_deg), float(sigma0_pos_m))]
    cp_claim = f1_cp_mission_claim(cp_mission_sigmas(float(c_p)), float(c_p))
    claims = [*evolution_claims(table), cp_claim]
    passed = {c.claim_id: c.verdict == "reproduced" for c in claims
              if c.claim_id in SEARCH_CLAIMS}
    return {**passed, "n_reproduced": int(sum(passed.values()))}


register(Evaluation("launcher_claims", "launcher ascent: verdicts of Beaudoin et al.'s "
                    "covariance-evolution claims and the end of §4.1 (True = reproduced)",
                    SEARCH_BASELINE, (), _claims_run))

SEARCH = register_search(SearchSpace(
    "covariance", "Beaudoin et al. (2018)", SEARCH_PARAMETERS, SEARCH_CLAIMS,
    "launcher_claims", search_points, "claims_search_covariance.csv"))
"""The Beaudoin covariance space searched jointly (stored in
``data/claims_search_covariance.csv``)."""
