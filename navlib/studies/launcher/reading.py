"""Beaudoin et al. (2018) generated reading: the notebook's text on the Fig. 1, Table 2 and
covariance-evolution claims."""

from __future__ import annotations

from navlib.studies import claims as engine
from navlib.studies.launcher.covariance_claims import evolution_claims
from navlib.studies.launcher.table2 import Table2Result

__all__ = ["reading_markdown"]


def reading_markdown(result: Table2Result | None = None, fig1=None, evolution=None) -> str:
    """The notebook's generated reading: Fig. 1, Table 2 and covariance-evolution claims with
    the Table 2 match count at several tolerances (:func:`engine.reading_markdown`)."""
    results, lines = [], []
    results += list(fig1 or [])
    if result is not None:
        results += result.claims()
        counts = result.match_counts()
        lines.append("Table 2 configurations matching the paper (count and order): "
                     + ", ".join(f"{n}/{len(result.frame)} within {tol:g} decade"
                                 for tol, n in counts.items())
                     + f"; the verdicts use {result.cond_tol:g}.")
    if evolution is not None:
        results += evolution_claims(evolution)
    return engine.reading_markdown(results, lines)
