"""Beaudoin et al. (2018) Fig. 1: condition number of the simplified model's observability
matrix against the GPS-bias time constant (docs/assumptions.md, launcher.md §3.7, §10a)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from navlib.models.launcher import simplified_gps_bias
from navlib.observability import analyze, observability_matrix

__all__ = ["fig1_data"]


def fig1_data(c_p=None, s_t: float = 0.005, rtol: float | None = None) -> pd.DataFrame:
    """Condition number of the simplified model's observability matrix vs ``c_p`` (Fig. 1).

    Parameters
    ----------
    c_p : array of float, optional
        GPS-bias time constants, s (``inf`` allowed); default 10^-2 .. 10^4 (25 points)
        plus ``inf``.
    s_t : float
        Sampling time, s.

    Returns
    -------
    pandas.DataFrame
        ``c_p, rank, cond, log10_cond, cond_per_cp_st`` (the last is ``cond s_t / c_p``,
        which tends to ~1.171 for ``c_p >> s_t``, docs/assumptions.md, launcher.md §10a).
    """
    values = np.concatenate([np.logspace(-2, 4, 25), [np.inf]]) if c_p is None \
        else np.atleast_1d(np.asarray(c_p, dtype=float))
    rows = []
    for c in values:
        A, C = simplified_gps_bias(c, s_t)
        res = analyze(observability_matrix(A, C), rtol=rtol)
        rows.append({"c_p": c, "rank": res.rank, "cond": res.cond,
                     "log10_cond": res.log10_cond,
                     "cond_per_cp_st": res.cond * s_t / c if np.isfinite(c) else np.nan})
    return pd.DataFrame(rows)
