"""The declared assumption set of the outlier claims (recovery window, A1 sign), the claims
at each of its points, and the study's registration with the claims engine."""

from __future__ import annotations

from collections.abc import Sequence

from navlib.cache import memoized
from navlib.studies import claims as engine
from navlib.studies.claims import ClaimResult
from navlib.studies.outliers.claims import covariance_claims, explained, explained_f7
from navlib.studies.outliers.experiment import (
    correlation_fig10,
    paper_tests,
    rescore,
    roll_sigma,
    sigma_ratios,
)
from navlib.studies.outliers.response import (
    DEFAULTS,
    FilterCache,
    OutlierStudy,
    adopt_filters,
    default_trajectory,
)

__all__ = ["ROBUSTNESS_GRID", "study_claims"]

ROBUSTNESS_GRID = {"window": (30.0, 50.0, 100.0), "a1_sign": (1.0, -1.0)}
"""The declared assumption set of T1-T4, F7, F10, F11 (full factorial, 6 points): the
recovery window the paper leaves open (30 s to the 100 s left of the mission) and the sign
of A1 (printed +1, the text's -1, spec §10b). Windows re-score the same responses; the -1
sign re-prepares only the two RT filters. Spike outliers only (notebook 05 adds the step)."""


def study_claims(cache: FilterCache, window: float = DEFAULTS["window"],
                 outlier_time_s: float | None = None, shapes: Sequence[str] = ("spike", "step"),
                 reuse: OutlierStudy | None = None, conclusions: bool = False,
                 **settings) -> tuple[OutlierStudy, list]:
    """T1-T4 and Figs. 7, 10, 11 on the filters of ``cache`` (``settings``: ``biases``,
    ``bias_model``; ``conclusions``: also the claims of §4.2.4, conclusions 1 and 3 and T4's
    time range, :func:`~navlib.studies.outliers.claims.conclusion_claims`): (the outlier
    study with its claims, the covariance claims)."""
    st = paper_tests(cache=cache, window=window, outlier_time_s=outlier_time_s, shapes=shapes,
                     reuse=reuse, conclusions=conclusions, **settings, **cache.model_options)
    corr = correlation_fig10(cache=cache, **settings)
    sig = roll_sigma(cache=cache, **settings)
    ratios = sigma_ratios("ins_gps", "ins_gps_rt", cache=cache, **settings)
    return st, covariance_claims(corr, sig, ratios)


@memoized(maxsize=1)
def _variants(quick: bool) -> dict:
    """Claims per (window, a1_sign) of :data:`ROBUSTNESS_GRID` (baseline: 100 s, +1)."""
    traj = default_trajectory(quick)
    windows = (30.0,) if quick else ROBUSTNESS_GRID["window"]
    out, previous, first = {}, None, None
    for sign in ROBUSTNESS_GRID["a1_sign"]:
        cache = FilterCache(traj, size=1, a1_sign=sign)
        if previous is not None:
            adopt_filters(cache, previous)
        previous = None
        st, cov = study_claims(cache, window=max(windows), shapes=("spike",), reuse=first,
                               conclusions=True)
        first = first or st
        for window in windows:
            rescored = st if window == max(windows) else rescore(st, window)
            out[(window, sign)] = [explained(c, rescored) for c in rescored.claims] + [
                explained_f7(c) for c in cov]
        previous = cache
        del cache
    return out


def _baseline_claims(quick: bool = False) -> list[ClaimResult]:
    v = _variants(quick)
    return v[(30.0 if quick else DEFAULTS["window"], 1.0)]


def _baseline_point(quick: bool) -> dict:
    return {"window": 30.0 if quick else DEFAULTS["window"], "a1_sign": 1.0}


def _robustness(quick: bool = False) -> list:
    return [({"window": w, "a1_sign": sign}, claims)
            for (w, sign), claims in _variants(quick).items()]


engine.register(engine.Study("outliers", "Beaudoin et al. (2018)", _baseline_claims,
                             ROBUSTNESS_GRID, _robustness,
                             "full factorial; windows re-score, -1 re-prepares the RT filters",
                             baseline_point=_baseline_point,
                             kinds={"window": "ours", "a1_sign": "ours"}))
