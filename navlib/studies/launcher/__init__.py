"""Beaudoin et al. (2018) observability-matrix study: Table 2, Fig. 1, the covariance
figures 2, 3, 5, 6 and their claims.

Composes :func:`navlib.models.launcher`, :func:`navlib.observability.local_observability` and
:func:`navlib.observability.analyze` into the paper's §4.1 experiment (docs/assumptions.md,
launcher.md §6.1, §7.2): for each of the 60 configurations of Table 2 (4 solutions x (no bias + 7
bias sets x Markov / random walk)), the local observability matrix at every 200 Hz step of the
ascent, the number of unobservable states (``n - min rank``; a state is observable only if it is at
every step, §6.1 item 4) and log10 of the maximum condition number over the mission, next to
the paper's values (``data/beaudoin2018_table2.csv``, OCR caveats in its ``.md`` sidecar).

* :mod:`.table2` — the Table 2 experiment (:func:`table2`, :class:`Table2Result`), the
  readings of eq. (6) side by side (:func:`variant_comparison`: the INS/GPS-only rows
  depend on the trajectory and on the frozen / time-varying reading) and one configuration
  over the mission;
* :mod:`.fig1` — the Fig. 1 analogue (simplified model, docs/assumptions.md, launcher.md §3.7,
  §10a);
* :mod:`.evolution` — the covariance runs of Figs. 2, 3, 5, 6 (docs/assumptions.md, launcher.md
  §7.3);
* :mod:`.claims` — the robust claims of docs/assumptions.md, launcher.md §10c, conclusions 1 and 3
  and Fig. 1 with the end of §4.1; :mod:`.covariance_claims` — the covariance evolution (conclusions
  2 and 4), one function per claim; :mod:`.causes` — the small experiments that measure the
  causes of the partly / not reproduced ones;
* :mod:`.assumptions` — the paper's words as numbers and the declared assumption sets;
  :mod:`.robustness` — the claims over them and the registration with the claims engine;
* :mod:`.search` — the covariance claims' joint search (``"launcher_claims"``);
* :mod:`.reading` — the notebook's generated reading.
"""

from navlib.studies.launcher.assumptions import (
    BARELY,
    COND_TOL,
    EVOLUTION_BASELINE,
    EVOLUTION_DEPENDS,
    EVOLUTION_GRID,
    HIGH_LOG10,
    IDENTICAL,
    LATERAL_LEVELS,
    LOW_LOG10,
    RESOLVED_LOG10,
    SINGULAR_LOG10,
    STRONG,
    TABLE2_BASELINE,
    TABLE2_GRID,
    TABLE2_RANK_RTOLS,
    TABLE2_STRIDE,
    TOLERANCES,
    log10_cond_text,
)
from navlib.studies.launcher.causes import cp_mission_sigmas, evolution_causes
from navlib.studies.launcher.claims import (
    conclusion_claims,
    fig1_claims,
    match_counts,
    table2_claim_results,
)
from navlib.studies.launcher.covariance_claims import EvolutionTable, evolution_claims
from navlib.studies.launcher.evolution import (
    EVOLUTION_CASES,
    covariance_evolution,
    evolution_grid,
    evolution_tables,
)
from navlib.studies.launcher.fig1 import fig1_data
from navlib.studies.launcher.reading import reading_markdown
from navlib.studies.launcher.robustness import (
    evolution_variants,
    lateral_match_counts,
    table2_result,
)
from navlib.studies.launcher.search import SEARCH, SEARCH_GRID, search_points
from navlib.studies.launcher.table2 import (
    DATA_DIR,
    TABLE2_CSV,
    Table2Result,
    configurations,
    describe_direction,
    inspect_step,
    mission_observability,
    paper_table2,
    table2,
    variant_comparison,
)

__all__ = [
    "BARELY",
    "COND_TOL",
    "DATA_DIR",
    "EVOLUTION_BASELINE",
    "EVOLUTION_CASES",
    "EVOLUTION_DEPENDS",
    "EVOLUTION_GRID",
    "HIGH_LOG10",
    "IDENTICAL",
    "LATERAL_LEVELS",
    "LOW_LOG10",
    "RESOLVED_LOG10",
    "SEARCH",
    "SEARCH_GRID",
    "SINGULAR_LOG10",
    "STRONG",
    "TABLE2_BASELINE",
    "TABLE2_CSV",
    "TABLE2_GRID",
    "TABLE2_RANK_RTOLS",
    "TABLE2_STRIDE",
    "TOLERANCES",
    "EvolutionTable",
    "Table2Result",
    "conclusion_claims",
    "configurations",
    "covariance_evolution",
    "cp_mission_sigmas",
    "describe_direction",
    "evolution_causes",
    "evolution_claims",
    "evolution_grid",
    "evolution_tables",
    "evolution_variants",
    "fig1_claims",
    "fig1_data",
    "inspect_step",
    "lateral_match_counts",
    "log10_cond_text",
    "match_counts",
    "mission_observability",
    "paper_table2",
    "reading_markdown",
    "search_points",
    "table2",
    "table2_claim_results",
    "table2_result",
    "variant_comparison",
]
