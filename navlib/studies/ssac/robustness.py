"""Silva et al. (2017) claims over the declared assumption set
(:mod:`navlib.studies.ssac.assumptions`) and the study's registration with the claims engine.

The P0 points differ in P0 alone, so their 15-, 12- and 10-state runs are stacked
recursions (:func:`~navlib.studies.ssac.p0_runs`); the grid is evaluated once per mode and
kept in the process (:func:`navlib.cache.memoized`), shared by the baseline claims and the
robustness.
"""

from __future__ import annotations

from navlib import cache
from navlib.models.ssac import SITE_ALT_M, SITE_LAT_DEG
from navlib.studies import claims as engine
from navlib.studies.claims import ClaimResult
from navlib.studies.ssac.assumptions import (
    ARW_READINGS,
    BASELINE_POINT,
    QUICK_DURATION_S,
    ROBUSTNESS_GRID,
    initial_covariance,
    sigma_nu,
)
from navlib.studies.ssac.claims import actual_claim, ssac_claims, static_tables
from navlib.studies.ssac.eigen_claims import orientation_claim
from navlib.studies.ssac.experiment import (
    CONVERGENCE_DEFAULT,
    P0_MODIFIED_ATTITUDE_SCALE,
    covariance_run,
    orientation_table,
    p0_runs,
    p0_sensitivity,
    x0_draws,
)
from navlib.studies.ssac.observability import RANK_RTOL

__all__ = ["baseline_claims", "grid_claims", "robustness_claims"]


def _depending(results: list[ClaimResult], name: str) -> list[ClaimResult]:
    return [r for r in results if name in r.depends_on]


def _rerun(duration_s: float, tables, imu=None, sigma_nu=None) -> list[ClaimResult]:
    """The claims on the matched-P0 runs (15, 12, 10 states and the P0-sensitivity rerun)
    with the gyro noise ``imu`` or the ZVU noise ``sigma_nu`` of a one-at-a-time point."""
    runs = {"track": False, "imu": imu, "sigma_nu": sigma_nu}
    study, modified = p0_runs([("matched", 1.0), ("matched", P0_MODIFIED_ATTITUDE_SCALE)],
                              duration_s, **runs)
    return ssac_claims(study, tables=tables,
                       reduced=covariance_run(duration_s, n_states=12, **runs),
                       reduced10=covariance_run(duration_s, n_states=10, **runs),
                       p0_table=p0_sensitivity(study, modified=modified))


@cache.memoized(maxsize=1)
def grid_claims(quick: bool) -> list[tuple[dict, list[ClaimResult]]]:
    """``(point, claims)`` over :data:`~navlib.studies.ssac.ROBUSTNESS_GRID` (quick mode:
    the P0 runs, the gyro-noise reading and the ZVU noise at the baseline only). The P0
    points differ in P0 alone, so the 15-, 12- and 10-state runs (with the P0-sensitivity
    rerun, the same for every point: :func:`~navlib.studies.ssac.modified_run`) are three
    stacked recursions (:func:`~navlib.studies.ssac.p0_runs`); the convergence,
    rank-tolerance and x0 points re-judge the baseline run, a heading-prior point is one more
    P0 in each stacked recursion (:func:`~navlib.studies.ssac.assumptions.initial_covariance`)
    judging every claim read from the run, an IMU orientation point reruns the
    orientation table. Kept in the process for the last mode asked."""
    duration = QUICK_DURATION_S if quick else 3600.0
    tables = static_tables(SITE_LAT_DEG, SITE_ALT_M, duration)
    points = [(p0, scale) for p0 in ROBUSTNESS_GRID["P0"]
              for scale in ROBUSTNESS_GRID["attitude_scale"]
              if not quick or (p0, scale) == ("matched", 1.0)]
    priors = [k for k in ROBUSTNESS_GRID["heading_prior"]
              if k != BASELINE_POINT["heading_prior"]]
    runs = p0_runs([*points, ("matched", P0_MODIFIED_ATTITUDE_SCALE),
                    *(initial_covariance("matched", 1.0, k) for k in priors)], duration,
                   track=False)
    full, modified, headings = runs[:len(points)], runs[len(points)], runs[len(points) + 1:]
    small = {n: p0_runs([*points, *(initial_covariance("matched", 1.0, k, n) for k in priors)],
                        duration, n_states=n, track=False) for n in (12, 10)}
    reduced, heading12 = small[12][:len(points)], small[12][len(points):]
    reduced10, heading10 = small[10][:len(points)], small[10][len(points):]
    out, base = [], None
    for (p0, scale), study, r12, r10 in zip(points, full, reduced, reduced10, strict=True):
        kw = {"reduced": r12, "reduced10": r10,
              "p0_table": p0_sensitivity(study, modified=modified)}
        out.append(({"P0": p0, "attitude_scale": scale}, ssac_claims(study, tables=tables,
                                                                    **kw)))
        if (p0, scale) == ("matched", 1.0):
            base = (study, kw)
    study, kw = base
    # the convergence and rank-tolerance points keep only the claims depending on them; the
    # reduced filters' claims do not (RUN_DEPS), so their truth-model runs are not re-read
    judged = {**kw, "reduced": None, "reduced10": None}
    for k, run, r12, r10 in zip(priors, headings, heading12, heading10, strict=True):
        out.append(({"heading_prior": k}, _depending(ssac_claims(
            run, tables=tables, reduced=r12, reduced10=r10,
            p0_table=p0_sensitivity(run, modified=modified)), "heading_prior")))
    for reading in ROBUSTNESS_GRID["convergence"]:
        if reading != CONVERGENCE_DEFAULT:
            out.append(({"convergence": reading}, _depending(
                ssac_claims(study, tables=tables, convergence=reading, **judged),
                "convergence")))
    for rtol in ROBUSTNESS_GRID["rank_rtol"]:
        if rtol != RANK_RTOL:
            out.append(({"rank_rtol": rtol}, _depending(
                ssac_claims(study, tables=static_tables(SITE_LAT_DEG, SITE_ALT_M, duration,
                                                        rtol, tables[2]),
                            rank_rtol=rtol, **judged), "rank_rtol")))
    for label, x0 in zip(ROBUSTNESS_GRID["x0"][1:], x0_draws(study), strict=True):
        out.append(({"x0": label}, [actual_claim(study, x0)]))
    for ypr in ROBUSTNESS_GRID["imu_orientation"][1:]:
        out.append(({"imu_orientation": ypr},
                    [orientation_claim(orientation_table(ypr, duration))]))
    if not quick:
        for reading, arw in ARW_READINGS.items():
            if arw is not None:
                out.append(({"arw_reading": reading}, _depending(
                    _rerun(duration, tables, imu={"gyro_arw": arw}), "arw_reading")))
        for scale in ROBUSTNESS_GRID["noise_scale"]:
            if scale != BASELINE_POINT["noise_scale"]:
                out.append(({"noise_scale": scale}, _depending(
                    _rerun(duration, tables, sigma_nu=sigma_nu(scale)), "noise_scale")))
    return out


def baseline_claims(quick: bool = False) -> list[ClaimResult]:
    """The claims at the baseline point (matched P0, attitude scale 1)."""
    return next(results for point, results in grid_claims(quick)
                if point == {"P0": "matched", "attitude_scale": 1.0})


def robustness_claims(quick: bool = False) -> list:
    """Every ``(point, claims)`` of :func:`grid_claims`."""
    return grid_claims(quick)


engine.register(engine.Study("ssac", "Silva, Hemerly & Leite Filho (2017)", baseline_claims,
                             ROBUSTNESS_GRID, robustness_claims,
                             "P0 x attitude scale factorial (stacked recursions per state "
                             "count); convergence reading, rank tolerance, gyro-noise unit, ZVU "
                             "noise, x0 and IMU orientation one at a time from the baseline",
                             baseline_point=BASELINE_POINT,
                             kinds={"P0": "unstated", "attitude_scale": "unstated",
                                    "heading_prior": "unstated",
                                    "convergence": "ours", "rank_rtol": "ours",
                                    "arw_reading": "ours", "noise_scale": "unstated",
                                    "x0": "unstated", "imu_orientation": "unstated"}))
