"""The declared assumption set of the rocket claims (robustness), the stored joint search of
that space, and the study's registration with the claims engine."""

from __future__ import annotations

import itertools

import pandas as pd

from navlib._validation import reject_unknown
from navlib.cache import memoized
from navlib.errors import NavlibInputError
from navlib.models.ecef import P0_DEFAULTS
from navlib.studies import claims as engine
from navlib.studies.claims import ClaimResult
from navlib.studies.claims.search import SearchSpace, factorial_points, register_search
from navlib.studies.rocket.claims import (
    CLAIM_IDS,
    claim_xrank,
    excitability_claims,
    sensability_claims,
)
from navlib.studies.rocket.experiment import excitability_study, quiet_gyro_analysis
from navlib.studies.rocket.flight import BASELINE
from navlib.studies.rocket.sensitivity import P0_SETS

__all__ = ["QUICK_ROBUSTNESS_GRID", "ROBUSTNESS_BASELINE", "ROBUSTNESS_GRID", "SEARCH",
           "SEARCH_PARAMETERS", "robustness_variants", "search_points"]

ROBUSTNESS_GRID = {
    "eta": (1e-2, 1e-3, 1e-4),
    "nu": (0.98, 0.985, 0.99),
    "p0": tuple(P0_SETS),
    "sigma_sg_ppm": (1000.0, 5000.0),
    "spin_hz": (1.0, 2.0),
}
"""The plausible assumption set of X1-X7 / S1-S8 (full factorial, 108 points): the paper
gives none of eta, nu, P0, sigma_sg or the spin. 12 discretised analyses (spin x P0 x
sigma_sg); eta and nu re-threshold the stored SVDs and eigen-decompositions."""
QUICK_ROBUSTNESS_GRID = {"eta": (1e-2, 1e-3, 1e-4), "nu": (0.98, 0.985, 0.99),
                         "p0": ("baseline (30 m, 3 m/s)",), "sigma_sg_ppm": (5000.0,),
                         "spin_hz": (2.0,)}
"""Quick mode: eta x nu at the baseline P0, sigma_sg and spin (no new discretisation)."""


def robustness_variants(grid: dict | None = None, sensors=None
                        ) -> list[tuple[dict, list[ClaimResult]]]:
    """``(point, X1-X7 and S1-S8)`` at every point of ``grid`` (default
    :data:`ROBUSTNESS_GRID`; a key left out keeps its :data:`BASELINE` value)."""
    grid = ROBUSTNESS_GRID if grid is None else dict(grid)
    reject_unknown(grid, ROBUSTNESS_GRID, "grid")
    grid = {"eta": (BASELINE["eta"],), "nu": (BASELINE["nu"],),
            "p0": ("baseline (30 m, 3 m/s)",), "sigma_sg_ppm": (BASELINE["sigma_sg_ppm"],),
            "spin_hz": (BASELINE["spin_hz"],), **grid}
    out = []
    for spin, p0, sg in itertools.product(grid["spin_hz"], grid["p0"], grid["sigma_sg_ppm"]):
        if p0 not in P0_SETS:
            raise NavlibInputError(f"grid['p0']: unknown set {p0!r}; use {list(P0_SETS)}")
        base = excitability_study(spin, sensors=sensors, sigma_sg_ppm=sg, **P0_SETS[p0])
        quiet = quiet_gyro_analysis(base, sensors=sensors)
        for eta, nu in itertools.product(grid["eta"], grid["nu"]):
            a = base.with_settings(eta=eta, nu=nu)
            point = {"eta": eta, "nu": nu, "p0": p0, "sigma_sg_ppm": sg, "spin_hz": spin}
            out.append((point, excitability_claims(a)
                        + sensability_claims(a, quiet.with_settings(eta=eta, nu=nu))))
    return out


ROBUSTNESS_BASELINE = {"eta": BASELINE["eta"], "nu": BASELINE["nu"],
                       "p0": "baseline (30 m, 3 m/s)", "sigma_sg_ppm": BASELINE["sigma_sg_ppm"],
                       "spin_hz": BASELINE["spin_hz"]}
"""The baseline point of :data:`ROBUSTNESS_GRID`."""


SEARCH_PARAMETERS = ("eta", "nu", "sigma_p0_m", "sigma_v0_m_s", "sigma_sg_ppm", "spin_hz")
"""The assumption columns of a point of the España joint search (:data:`SEARCH`)."""


def search_points(grid: dict | None = None) -> pd.DataFrame:
    """The points of :data:`ROBUSTNESS_GRID` (the declared assumption space, full factorial)
    as :func:`navlib.sweep.sweep` points of its ``"claims"`` evaluation."""
    points = factorial_points(grid, ROBUSTNESS_GRID, ROBUSTNESS_BASELINE)
    unknown = [p0 for p0 in points["p0"] if p0 not in P0_SETS]
    if unknown:
        raise NavlibInputError(f"grid['p0']: unknown set {unknown[0]!r}; use {list(P0_SETS)}")
    sets = [{**P0_DEFAULTS, **P0_SETS[p0]} for p0 in points.pop("p0")]
    for column in ("sigma_p0_m", "sigma_v0_m_s"):
        points[column] = [p[column] for p in sets]
    return points[list(SEARCH_PARAMETERS)]


# the claims engine asks for both twice in a report (all_claims, then the joint searches'
# factorial_search): kept in the process per mode
@memoized(maxsize=2)
def _baseline_claims(quick: bool = False) -> list[ClaimResult]:
    a = excitability_study()
    return [*excitability_claims(a), claim_xrank(a), *sensability_claims(a)]


@memoized(maxsize=2)
def _robustness(quick: bool = False) -> list:
    return robustness_variants(QUICK_ROBUSTNESS_GRID if quick else ROBUSTNESS_GRID)


engine.register(engine.Study(
    "rocket", "España, Carrizo & Giribet (2019)", _baseline_claims, ROBUSTNESS_GRID,
    _robustness, "full factorial; eta/nu reuse the stored SVDs and eigen-decompositions; "
    "each claim judged on the points varying its depends_on",
    order=1, baseline_point=ROBUSTNESS_BASELINE,
    kinds={"eta": "unstated", "nu": "unstated", "p0": "unstated", "sigma_sg_ppm": "unstated",
           "spin_hz": "unstated"}))

SEARCH = register_search(SearchSpace(
    "rocket", "España, Carrizo & Giribet (2019)", SEARCH_PARAMETERS, CLAIM_IDS, "claims",
    search_points, "claims_search_rocket.csv"))
"""The España assumption space searched jointly (X1-X7 and S1-S8 at every point of
:data:`ROBUSTNESS_GRID`; stored in ``data/claims_search_rocket.csv``)."""
