"""Silva, Hemerly & Leite Filho (2017) SSAC study: observability, estimability, eigen-analysis.

Composes :func:`navlib.models.ssac`, :mod:`navlib.observability`, :mod:`navlib.covariance`
and :mod:`navlib.covariance.estimability` into the paper's experiments (docs/assumptions.md,
ssac.md §3–§5) and
evaluates each claim in code (judged by :mod:`navlib.studies.claims`):

* :mod:`.observability` — ranks of the 15-, 12- and 10-state models (docs/assumptions.md, ssac.md
  §3.1), the exact null space against the analytic vectors of §3.3 and the grouping of the
  unobservable subspace under three readings (exact, P0-scaled, equivalence-scaled);
* :mod:`.experiment` — the 60 min, 1 Hz covariance run with ZVU updates
  (:func:`covariance_run`; several initial covariances of one model stacked:
  :func:`p0_runs`), the closed-form limits (eq. 44 and the classical ``b_a/g``,
  ``b_gE/(Omega cos L)``), the Ham–Brown eigen-analysis, the P0-sensitivity experiment,
  the rotated IMU and the actual error of a noise-free run;
* :mod:`.claims`, :mod:`.eigen_claims` — one function per claim, :func:`ssac_claims` all;
* :mod:`.assumptions` — the declared assumption set; :mod:`.robustness` — the claims over
  it and the registration with the claims engine;
* :mod:`.search` — the declared space searched jointly (the ``"ssac_claims"`` sweep
  evaluation, :data:`SEARCH`);
* :mod:`.reading` — the notebook's generated reading.

All numbers come from the reconstructed model (docs/assumptions.md, ssac.md §2.3) with the assumed
P0, Q and R of docs/assumptions.md, ssac.md §4.4; the paper's own values were lost from the seed
text.
"""

from navlib.models.ssac import SITE_ALT_M, SITE_LAT_DEG
from navlib.studies.ssac.assumptions import (
    ARW_READINGS,
    BASELINE_POINT,
    ORIENTATIONS,
    QUICK_DURATION_S,
    ROBUSTNESS_GRID,
    X0_BASELINE,
)
from navlib.studies.ssac.claims import (
    ADEQUATE,
    FAST,
    MEDIUM,
    actual_claim,
    claims_table,
    dropped_coupling,
    ssac_claims,
    static_tables,
)
from navlib.studies.ssac.experiment import (
    CONVERGENCE,
    CONVERGENCE_DEFAULT,
    ORIENTATION_DEG,
    P0_MODIFIED_ATTITUDE_SCALE,
    PAIRS,
    POSITION,
    STATE_GROUPS,
    X0_DRAWS,
    X0_SEED,
    SSACStudy,
    actual_error,
    actual_sigmas,
    closed_form_limits,
    covariance_run,
    modified_run,
    orientation_table,
    p0_runs,
    p0_sensitivity,
    pair_structure,
    subspace_drift,
    x0_draws,
    x_shape_events,
)
from navlib.studies.ssac.observability import (
    GROUP_THRESHOLD,
    PAPER_GROUPS,
    PAPER_RANKS,
    RANK_RTOL,
    analytic_null_vectors,
    equivalence_scale,
    grouping_table,
    null_space_table,
    observability_summary,
    observability_table,
)
from navlib.studies.ssac.reading import reading_markdown
from navlib.studies.ssac.robustness import grid_claims
from navlib.studies.ssac.search import SEARCH, SEARCH_GRID, search_points

__all__ = [
    "ADEQUATE", "ARW_READINGS", "BASELINE_POINT", "CONVERGENCE", "CONVERGENCE_DEFAULT", "FAST",
    "GROUP_THRESHOLD", "MEDIUM", "ORIENTATIONS", "ORIENTATION_DEG", "P0_MODIFIED_ATTITUDE_SCALE",
    "PAIRS", "PAPER_GROUPS", "PAPER_RANKS", "POSITION", "QUICK_DURATION_S", "RANK_RTOL",
    "ROBUSTNESS_GRID", "SEARCH", "SEARCH_GRID", "SITE_ALT_M", "SITE_LAT_DEG", "STATE_GROUPS",
    "X0_BASELINE", "X0_DRAWS", "X0_SEED", "SSACStudy", "actual_claim", "actual_error",
    "actual_sigmas",
    "analytic_null_vectors", "claims_table", "closed_form_limits", "covariance_run",
    "dropped_coupling",
    "equivalence_scale", "grid_claims", "grouping_table", "modified_run", "null_space_table",
    "observability_summary", "observability_table", "orientation_table", "p0_runs",
    "p0_sensitivity", "pair_structure", "reading_markdown", "search_points", "ssac_claims",
    "static_tables", "subspace_drift", "x0_draws", "x_shape_events",
]
