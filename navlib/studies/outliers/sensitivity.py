"""T1-T4 under alternative readings of the paper (bias model, A1 sign, wind...)."""

from __future__ import annotations

from collections.abc import Sequence

import pandas as pd

from navlib.studies.outliers.experiment import paper_tests
from navlib.studies.outliers.paper import PAPER_TESTS
from navlib.studies.outliers.response import (
    DEFAULTS,
    FilterCache,
    adopt_filters,
    default_trajectory,
)

__all__ = ["assumption_sensitivity"]


def assumption_sensitivity(variants: dict, trajectory=None, *,
                           tests: Sequence[str] = ("T1", "T2", "T3", "T4"),
                           window: float = DEFAULTS["window"],
                           outlier_time_s: float | None = None,
                           cache_size: int = 1, cache: FilterCache | None = None
                           ) -> pd.DataFrame:
    """Spike-outlier verdicts of T1-T4 under alternative readings of the paper.

    Parameters
    ----------
    variants : dict
        Name -> keywords of :func:`paper_tests` (``biases``, ``bias_model``) and of
        :func:`navlib.models.launcher` (``a1_sign``, ``sigma_wind``, ...).
    trajectory : Trajectory, optional
        Default: that of ``cache``, else :func:`default_trajectory`.
    cache_size : int
        Prepared filters kept while a variant runs (none after it: later variants need
        only its responses).
    cache : FilterCache, optional
        Filters and responses already computed (e.g. by :func:`paper_tests`): a variant
        reuses those of the same model (same trajectory and options; the non-RT solutions
        also when only the RT-only options ``a1_sign``/``sigma_wind`` differ), so does a
        later variant with the earlier variants' non-RT responses.

    Returns
    -------
    DataFrame
        One row per variant, test and solution: ``verdict``, ``retained``,
        ``time_constant``, the paper's outcome and whether they agree, plus each test's
        claim verdict.
    """
    traj = trajectory if trajectory is not None else (
        cache.trajectory if cache is not None else default_trajectory())
    pool = [cache] if cache is not None else []
    rows = []
    for name, kw in variants.items():
        kw = dict(kw)
        study_kw = {k: kw.pop(k) for k in ("biases", "bias_model") if k in kw}
        variant_cache = FilterCache(traj, size=cache_size, **kw)
        for other in pool:
            adopt_filters(variant_cache, other)
        st = paper_tests(cache=variant_cache, shapes=("spike",), tests=tests, window=window,
                         outlier_time_s=outlier_time_s, divergence=False, **study_kw, **kw)
        variant_cache.release()
        pool = [*pool[:1 if cache is not None else 0], variant_cache]
        claim = {c.claim_id: c.verdict for c in st.claims}
        for (tid, sol, _shape), r in st.responses.items():
            want = PAPER_TESTS[tid].reported[sol]
            got = r.score.verdict
            agree = (got != "unaffected") if want == "affected" else (got == want)
            rows.append({"variant": name, "test": tid, "solution": sol, "paper": want,
                         "ours": got, "agree": agree, "retained": r.score.retained,
                         "time_constant": r.score.time_constant,
                         "claim_verdict": claim.get(tid, "")})
    return pd.DataFrame(rows)
