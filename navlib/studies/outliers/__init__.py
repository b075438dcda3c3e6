"""Beaudoin et al. (2018) §4.2: outlier sensitivity T1-T4, Fig. 10 correlation, roll sigma.

Composes :func:`navlib.models.launcher`, :func:`navlib.filters.prepare_linear` /
:func:`~navlib.filters.simulate_linear` and :mod:`navlib.sensors.faults` into the paper's
outlier experiment (docs/assumptions.md, launcher.md §6.3, §6.4, §7.3) on the Churchill launcher
surrogate (:func:`navlib.trajectory.launcher_ascent`, 200 Hz, GPS and all aiding at every sample as
in the paper, docs/assumptions.md, launcher.md §4):

* :func:`outlier_response` — the outlier-induced error of a watched quantity (GPS position
  bias, body roll error, launcher divergence) for one solution: the linear filter's exact
  noise-free response (by linearity, what any noisy run adds), its filter sigma and the
  :func:`navlib.filters.recovery.score_recovery` verdict;
* :func:`paper_tests` — T1-T4 for both outlier shapes and their :class:`ClaimResult`
  verdicts (:func:`outlier_claims`);
* :func:`correlation_fig10` — per-axis correlation of ``T_E^B psi`` with the divergence
  ``psi_ref`` over the first 5 s (Fig. 10) and :func:`roll_sigma` — roll sigma with and
  without RT (Figs. 7, 11), with :func:`covariance_claims`;
* :func:`monte_carlo_outlier` — noisy runs with and without the outlier (the error band the
  static error hides in) and the NEES/NIS consistency of the same runs;
* :func:`ekf_crosscheck` — the same outlier through the closed-loop EKF on simulated sensor
  data (:func:`navlib.filters.simulate_ekf`, noise-free so the response is isolated).

Assumptions that matter (docs/assumptions.md, launcher.md §11): the bias model of Figs. 7-13 is not
stated (default gyro + accelerometer + GPS biases as Markov processes, ``GAP``), the A1 sign
(default +1, docs/assumptions.md, launcher.md §10b), the wind level and GPS noise
(``navlib.models.launcher.ASSUMED``), the outlier shape (default single-sample spike; the step is
reported beside it) and the recovery window (default 100 s: from the outlier to the end of the 150 s
surrogate mission).

Modules: :mod:`~navlib.studies.outliers.response` (prepared filters, watched quantities, the
response of one solution), :mod:`~navlib.studies.outliers.experiment` (T1-T4, re-scoring, the
covariance figures), :mod:`~navlib.studies.outliers.claims`,
:mod:`~navlib.studies.outliers.crosscheck` (Monte Carlo, EKF),
:mod:`~navlib.studies.outliers.sensitivity` (alternative readings),
:mod:`~navlib.studies.outliers.reading`, :mod:`~navlib.studies.outliers.assumptions`
(robustness set, registration) and :mod:`~navlib.studies.outliers.evaluations` (the named
sweep evaluations of the launcher ascent).
"""

from navlib.studies.outliers import evaluations  # noqa: F401 - registers the named sweep evaluations
from navlib.studies.outliers.assumptions import (
    ROBUSTNESS_GRID,
    study_claims,
)
from navlib.studies.outliers.claims import (
    AFFECTED,
    claim_f10,
    claim_roll_sigma,
    claim_t4_detail,
    claim_test,
    covariance_claims,
    outlier_claims,
)
from navlib.studies.outliers.crosscheck import (
    EKFCrossCheck,
    MonteCarloOutlier,
    ekf_crosscheck,
    ekf_vs_covariance,
    monte_carlo_outlier,
)
from navlib.studies.outliers.experiment import (
    correlation_fig10,
    paper_tests,
    rescore,
    roll_sigma,
    sigma_ratios,
)
from navlib.studies.outliers.reading import (
    ekf_sigma_agreement,
    reading_markdown,
)
from navlib.studies.outliers.response import (
    DEFAULTS,
    RT_ONLY_OPTIONS,
    WATCHES,
    CovarianceSummary,
    FilterCache,
    OutlierResponse,
    OutlierStudy,
    UnitResponse,
    adopt_filters,
    default_trajectory,
    effective_bias_model,
    outlier_response,
    record_stride,
    watch_rows,
)
from navlib.studies.outliers.sensitivity import (
    assumption_sensitivity,
)

__all__ = [
    "AFFECTED",
    "DEFAULTS",
    "ROBUSTNESS_GRID",
    "RT_ONLY_OPTIONS",
    "WATCHES",
    "CovarianceSummary",
    "EKFCrossCheck",
    "FilterCache",
    "MonteCarloOutlier",
    "OutlierResponse",
    "OutlierStudy",
    "UnitResponse",
    "adopt_filters",
    "assumption_sensitivity",
    "claim_f10",
    "claim_roll_sigma",
    "claim_t4_detail",
    "claim_test",
    "correlation_fig10",
    "covariance_claims",
    "default_trajectory",
    "effective_bias_model",
    "ekf_crosscheck",
    "ekf_sigma_agreement",
    "ekf_vs_covariance",
    "monte_carlo_outlier",
    "outlier_claims",
    "outlier_response",
    "paper_tests",
    "reading_markdown",
    "record_stride",
    "rescore",
    "roll_sigma",
    "sigma_ratios",
    "study_claims",
    "watch_rows",
]
