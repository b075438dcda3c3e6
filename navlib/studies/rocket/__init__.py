"""España, Carrizo & Giribet (2019): excitability and sensability on the sounding-rocket flight.

The experiment of the paper's §5 rebuilt from library pieces: the VS30-like trajectory
(:func:`navlib.trajectory.sounding_rocket`), the 21-state ECEF model discretised to the 1 Hz
GNSS epochs (:func:`navlib.models.ecef.ecef21_at_epochs`), and the metrics of
:mod:`navlib.metrics`. Each paper statement X1-X7 (Fig. 2) and S1-S8 (Figs. 3-5) is a function
returning a :class:`~navlib.studies.claims.ClaimResult`, evaluated by code.

The paper's statements are qualitative ("mostly in S_O", "very low", "briefly sensible");
the operational thresholds used here are constants of :mod:`~navlib.studies.rocket.flight`
(docs/assumptions.md, excitability.md §3; docs/assumptions.md):

* :data:`IN_SO` = 1/sqrt(2): a state "lies in S_O" when more than half of its unit vector's
  squared norm projects on the excited subspace (X1-X4); the same value for "sensible"
  (:data:`SENSIBLE`, S-claims).
* :data:`LOW` = 0.25: "very low" / "barely" = less than 1/16 of the squared norm.
* :data:`BRIEF_S` = 10 s: "briefly sensible"; :data:`TRANSIENT_S` = 5 s: epochs before it
  are left out of the "weakly sensible" counts (every state is sensible at t0 under the
  literal reading of docs/assumptions.md A9, and the sensible subspace is still large for a few
  epochs).

Each claim is a list of explicit checks judged by the one rule of
:mod:`navlib.studies.claims` (the headline check decides "not reproduced"), and is
registered there with its declared assumption set (:data:`ROBUSTNESS_GRID`).
The metrics are *relative* (normalised by D0 and R0) and depend strongly on the assumed
P0, GNSS sigma, eta and nu (docs/assumptions.md, excitability.md §3 "What the prototype showed"):
:func:`sensitivity_sweep` shows how much.

Modules: :mod:`~navlib.studies.rocket.flight` (trajectory, model, thresholds),
:mod:`~navlib.studies.rocket.experiment` (:func:`excitability_study`, the pad geometry, S5's
counterfactual), :mod:`~navlib.studies.rocket.claims` (X1-X7, S1-S8),
:mod:`~navlib.studies.rocket.sensitivity` (tension variants, sensitivity sweep),
:mod:`~navlib.studies.rocket.measures` (simpler measures), :mod:`~navlib.studies.rocket.reading`,
:mod:`~navlib.studies.rocket.assumptions` (robustness set, joint search, registration),
:mod:`~navlib.studies.rocket.evaluations` (the named sweep evaluations) and
:mod:`~navlib.studies.rocket.profile` (the flight profile of §5.1 / Fig. 1 checked on a
synthesised trajectory, registered as the study ``rocket_profile``).
"""

from navlib.studies.rocket import evaluations  # noqa: F401 - registers the named sweep evaluations
from navlib.studies.rocket.assumptions import (
    QUICK_ROBUSTNESS_GRID,
    ROBUSTNESS_BASELINE,
    ROBUSTNESS_GRID,
    SEARCH,
    SEARCH_PARAMETERS,
    robustness_variants,
    search_points,
)
from navlib.studies.rocket.claims import (
    BASELINE_BASIS,
    CLAIM_IDS,
    EXCITABILITY_CLAIMS,
    OTHER_PARAMETERS,
    SENSABILITY_CLAIMS,
    claim_s1,
    claim_s2,
    claim_s3,
    claim_s4,
    claim_s5,
    claim_s6,
    claim_s7,
    claim_s8,
    claim_x1,
    claim_x2,
    claim_x3,
    claim_x4,
    claim_x5,
    claim_x6,
    claim_x7,
    claim_xrank,
    claims_table,
    excitability_claims,
    sensability_claims,
    sensible_time,
)
from navlib.studies.rocket.experiment import (
    RocketAnalysis,
    direction_sensability,
    excitability_study,
    heading_direction,
    quiet_gyro_analysis,
    tangent_projections,
)
from navlib.studies.rocket.flight import (
    ATTITUDE,
    BASELINE,
    BRIEF_S,
    CONING_KEYS,
    EXCITABILITY_DEPENDS,
    FUTILE,
    GYRO_NOISE_KEYS,
    IN_SO,
    LOW,
    NOT_IMPROVED,
    ONLY_AFTER,
    PARAMETERS,
    QUIET_GYRO_SCALE,
    SEGMENT_LABELS,
    SEGMENTS,
    SENSABILITY_DEPENDS,
    SENSIBLE,
    TRANSIENT_S,
    add_coning,
    rocket_chain,
    rocket_trajectory,
)
from navlib.studies.rocket.measures import (
    DISAGREEMENT_REASONS,
    RATIO_ESTIMATED,
    measure_comparison,
    measure_disagreements,
)
from navlib.studies.rocket.profile import rocket_profile_claims
from navlib.studies.rocket.reading import (
    reading_markdown,
)
from navlib.studies.rocket.sensitivity import (
    P0_SETS,
    QUICK_GRID,
    SWEEP_BASELINE,
    SWEEP_GRID,
    TENSION_VARIANTS,
    sensitivity_sweep,
    sweep_pass_rates,
    tension_findings,
    tension_table,
)

__all__ = [
    "ATTITUDE",
    "BASELINE",
    "BASELINE_BASIS",
    "BRIEF_S",
    "CLAIM_IDS",
    "CONING_KEYS",
    "DISAGREEMENT_REASONS",
    "EXCITABILITY_CLAIMS",
    "EXCITABILITY_DEPENDS",
    "FUTILE",
    "GYRO_NOISE_KEYS",
    "IN_SO",
    "LOW",
    "NOT_IMPROVED",
    "ONLY_AFTER",
    "OTHER_PARAMETERS",
    "P0_SETS",
    "PARAMETERS",
    "QUICK_GRID",
    "QUICK_ROBUSTNESS_GRID",
    "QUIET_GYRO_SCALE",
    "RATIO_ESTIMATED",
    "ROBUSTNESS_BASELINE",
    "ROBUSTNESS_GRID",
    "SEARCH",
    "SEARCH_PARAMETERS",
    "SEGMENTS",
    "SEGMENT_LABELS",
    "SENSABILITY_CLAIMS",
    "SENSABILITY_DEPENDS",
    "SENSIBLE",
    "SWEEP_BASELINE",
    "SWEEP_GRID",
    "TENSION_VARIANTS",
    "TRANSIENT_S",
    "RocketAnalysis",
    "add_coning",
    "claim_s1",
    "claim_s2",
    "claim_s3",
    "claim_s4",
    "claim_s5",
    "claim_s6",
    "claim_s7",
    "claim_s8",
    "claim_x1",
    "claim_x2",
    "claim_x3",
    "claim_x4",
    "claim_x5",
    "claim_x6",
    "claim_x7",
    "claim_xrank",
    "claims_table",
    "direction_sensability",
    "excitability_claims",
    "excitability_study",
    "heading_direction",
    "measure_comparison",
    "measure_disagreements",
    "quiet_gyro_analysis",
    "reading_markdown",
    "robustness_variants",
    "rocket_chain",
    "rocket_profile_claims",
    "rocket_trajectory",
    "search_points",
    "sensability_claims",
    "sensible_time",
    "sensitivity_sweep",
    "sweep_pass_rates",
    "tangent_projections",
    "tension_findings",
    "tension_table",
]
