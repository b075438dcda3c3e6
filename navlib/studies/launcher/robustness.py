"""Beaudoin et al. (2018) claims over the declared assumption sets
(:mod:`navlib.studies.launcher.assumptions`) and the three studies' registration with the
claims engine (Fig. 1, Table 2, covariance evolution). The Table 2 results and the evolution
claims are kept in the process (:func:`navlib.cache.memoized`), shared by the baseline
claims and the robustness; so are the Table 2 claims at the baseline and over the set,
which the claims engine reads twice in a report (:func:`~navlib.studies.all_claims`, then
the joint searches)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from navlib import cache
from navlib.models.launcher import ASSUMED
from navlib.studies import claims as engine
from navlib.studies.claims import ClaimResult
from navlib.studies.launcher.assumptions import (
    COND_TOL,
    CP_MISSION_BASELINE,
    CP_MISSION_SET,
    EVOLUTION_BASELINE,
    EVOLUTION_GRID,
    LATE_S,
    LATERAL_BASELINE,
    LATERAL_LEVELS,
    LEVEL_STRIDE,
    SURVEYED_PAD_M,
    TABLE2_BASELINE,
    TABLE2_GRID,
    TABLE2_RANK_RTOLS,
    TABLE2_STRIDE,
    TOLERANCES,
    log10_cond_text,
)
from navlib.studies.launcher.causes import cp_mission_sigmas, evolution_causes
from navlib.studies.launcher.claims import conclusion_claims, f1_cp_mission_claim, fig1_claims
from navlib.studies.launcher.covariance_claims import (
    evolution_claims,
    f3_bp_claim,
    f5_model_claim,
)
from navlib.studies.launcher.evolution import covariance_evolution, evolution_grid
from navlib.studies.launcher.table2 import Table2Result, table2
from navlib.trajectory import launcher_ascent

__all__ = ["COVARIANCE_KINDS", "baseline_evolution_claims", "baseline_fig1_claims",
           "baseline_table2_claims", "evolution_robustness", "evolution_variants",
           "fig1_robustness", "lateral_match_counts", "table2_result", "table2_robustness"]

COVARIANCE_KINDS = {"sigma0_att_deg": "unstated", "sigma0_pos_m": "unstated", "c_g": "unstated",
                    "c_p": "ours", "kick_deg": "fitted", "gust_mps": "ours"}
"""Kinds of the covariance claims' assumptions (their set, cause experiments and joint
search, A-launcher-search): the initial sigmas and the gyro-bias constant are not given; the
GPS-bias constant other than the printed 100 s and the lateral level are readings and models
of ours; the ascent without a pitch programme is a fitted setup (A-F2-pitch: an orbital
ascent must pitch over), so no claim counts as holding there."""


def baseline_fig1_claims(quick: bool = False) -> list[ClaimResult]:
    """The Fig. 1 claims and the end of §4.1 (the same in both modes)."""
    return [*fig1_claims(), f1_cp_mission_claim(cp_mission_sigmas(CP_MISSION_BASELINE["c_p"]),
                                                 CP_MISSION_BASELINE["c_p"])]


def fig1_robustness(quick: bool = False) -> list:
    """``(point, claims)`` over the GPS-bias time constants of :data:`CP_MISSION_SET` (only
    the end-of-§4.1 claim depends on c_p; the Fig. 1 claims sweep it themselves)."""
    return [({"c_p": c}, [f1_cp_mission_claim(cp_mission_sigmas(c), c)])
            for c in CP_MISSION_SET]


def table2_result(quick: bool, rtol: float | None = None,
                  gust_mps: float = LATERAL_BASELINE) -> Table2Result:
    """The Table 2 of the claims: every step of the ascent (quick: 30 s at every 400th step;
    a lateral level other than the baseline: every :data:`LEVEL_STRIDE`-th step), at the
    baseline rank tolerance or at one ``rtol`` of the declared set, which re-ranks the same
    singular values (:meth:`~navlib.studies.launcher.table2.Table2Result.at_rtol`)."""
    base = _level_table2(quick, float(gust_mps))
    return base if rtol is None else base.at_rtol(rtol)


@cache.memoized(maxsize=6)
def _level_table2(quick: bool, gust_mps: float) -> Table2Result:
    """:func:`table2_result` at one lateral level, kept in the process per mode (on disk the
    baseline is notebook 02's table: :func:`navlib.cache.cached`)."""
    traj = launcher_ascent(duration_s=30.0, gust_mps=gust_mps) if quick else \
        launcher_ascent(gust_mps=gust_mps)
    stride = 400 if quick else TABLE2_STRIDE if gust_mps == LATERAL_BASELINE else LEVEL_STRIDE
    return table2(traj, stride=stride)


def lateral_match_counts(quick: bool = False) -> pd.DataFrame:
    """Matching Table 2 cells per lateral level (:data:`LATERAL_LEVELS`) and tolerance, the
    full-rank INS/GPS rows' log10 cond range over the mission and from
    :data:`~navlib.studies.launcher.assumptions.LATE_S` on, and the no-bias row's worst step
    and late order: how far the level of the lateral motion moves the table (notebook 00)."""
    rows = []
    for level in LATERAL_LEVELS:
        result = table2_result(quick, gust_mps=level)
        ins_gps = result.frame[(result.frame.solution == "ins_gps")
                               & (result.frame.n_unobservable == 0)]
        no_bias = ins_gps[ins_gps.biases == ""].iloc[0]
        rows.append({"gust_mps": level, "stride": result.stride,
                     **{f"match at {tol:g}": int(n) for tol, n in
                        result.match_counts().items()},
                     "INS/GPS log10 cond": log10_cond_text(ins_gps.log10_cond),
                     f"INS/GPS from {LATE_S:g} s": log10_cond_text(ins_gps.log10_cond_late),
                     "no-bias worst step (s)": round(float(no_bias.t_worst_s), 2),
                     f"no-bias from {LATE_S:g} s": round(float(no_bias.log10_cond_late), 1)})
    return pd.DataFrame(rows).set_index("gust_mps")


def _all_table2_claims(result: Table2Result, cond_tol: float = COND_TOL) -> list[ClaimResult]:
    return result.claims(cond_tol) + conclusion_claims(result.frame, cond_tol)


@cache.memoized(maxsize=2)
def baseline_table2_claims(quick: bool = False) -> list[ClaimResult]:
    """The Table 2 and conclusion claims at the baseline tolerances."""
    return _all_table2_claims(table2_result(quick))


@cache.memoized(maxsize=2)
def table2_robustness(quick: bool = False) -> list:
    """``(point, claims)`` over the Table 2 set, full factorial: each rank tolerance re-ranks
    the every-step table, each tolerance re-judges it (so the set is also the claims' joint
    search, :func:`~navlib.studies.claims.factorial_search`)."""
    return [({"cond_tol": tol, "rank_rtol": rtol, "gust_mps": level},
             _all_table2_claims(table2_result(quick, None if isinstance(rtol, str) else rtol,
                                              level), tol))
            for level in LATERAL_LEVELS for rtol in TABLE2_RANK_RTOLS for tol in TOLERANCES]


@cache.memoized(maxsize=1)
def evolution_variants(quick: bool) -> dict:
    """The evolution claims per initial attitude sigma (deg) of
    :func:`~navlib.studies.launcher.evolution_grid`, explained by the cause experiments
    (:func:`~navlib.studies.launcher.evolution_causes`), kept for the last mode asked."""
    causes = evolution_causes(quick)
    return {v: evolution_claims(table, causes) for v, table in evolution_grid(quick).items()}


def baseline_evolution_claims(quick: bool = False) -> list[ClaimResult]:
    """The evolution claims at the model's initial attitude sigma."""
    base = float(np.degrees(ASSUMED["sigma0_att"]))
    return next(v for k, v in evolution_variants(quick).items() if np.isclose(k, base))


@cache.memoized(maxsize=2)
def _level_evolution(gust_mps: float) -> pd.DataFrame:
    """The covariance-evolution table (every case, the model's initial sigmas) on the ascent
    at lateral level ``gust_mps`` (kept in the process, and on disk by
    :func:`~navlib.studies.launcher.covariance_evolution`)."""
    return covariance_evolution(launcher_ascent(gust_mps=gust_mps))


def evolution_robustness(quick: bool = False) -> list:
    """``(point, claims)`` over :data:`~navlib.studies.launcher.EVOLUTION_GRID`: each initial
    attitude sigma's table, F3-bp and F5-model on the surveyed-pad runs of the cause
    experiment (the :data:`~navlib.studies.launcher.assumptions.PAD_CASES` they read), and
    (full mode) every case on the ascent at each other lateral level (A-launcher-lateral)."""
    base = EVOLUTION_BASELINE["sigma0_att_deg"]
    pad = evolution_causes(quick)["surveyed_pad"]
    levels = () if quick else [g for g in LATERAL_LEVELS if g != LATERAL_BASELINE]
    return [*(({"sigma0_att_deg": base if np.isclose(k, base) else k}, v)
              for k, v in evolution_variants(quick).items()),
            ({"sigma0_pos_m": SURVEYED_PAD_M}, [f3_bp_claim(pad), f5_model_claim(pad)]),
            *(({"gust_mps": g}, evolution_claims(_level_evolution(g))) for g in levels)]


engine.register(engine.Study("fig1", "Beaudoin et al. (2018)", baseline_fig1_claims,
                             {"c_p": CP_MISSION_SET}, fig1_robustness,
                             "the end-of-§4.1 claim at each GPS-bias time constant", order=0,
                             baseline_point=CP_MISSION_BASELINE, kinds={"c_p": "ours"}))
engine.register(engine.Study(
    "table2", "Beaudoin et al. (2018)", baseline_table2_claims, TABLE2_GRID, table2_robustness,
    "full factorial: per lateral level one table (the baseline's every step, the others' "
    "every 200th), each rank tolerance re-ranks it, each tolerance re-judges it",
    order=1, baseline_point=TABLE2_BASELINE,
    kinds={"cond_tol": "ours", "rank_rtol": "ours", "gust_mps": "ours"}))
engine.register(engine.Study("covariance", "Beaudoin et al. (2018)", baseline_evolution_claims,
                             EVOLUTION_GRID, evolution_robustness,
                             "one at a time: one covariance-evolution table per initial "
                             "attitude sigma (the sigmas' recursions stacked per case), the "
                             "surveyed pad's runs, one table per other lateral level",
                             order=2, baseline_point=EVOLUTION_BASELINE,
                             kinds=COVARIANCE_KINDS))
