"""Kalman covariance analysis: recursion, frames, correlation and normalised eigen-analysis.

* :func:`kalman_covariance` — the covariance recursion of a linear Kalman filter
  ``P-_{k+1} = F_k P+_k F_k' + Q_k`` and the Joseph-form update
  ``P+ = (I - K H) P- (I - K H)' + K R K'`` with ``K = P- H' S^+`` (docs/assumptions.md, launcher.md
  §6.2, ssac.md §8 item 6). ``S^+`` is the inverse of the innovation covariance
  when ``R`` is positive definite, else its pseudo-inverse, so ideal (noise-free) measurements ``R =
  0`` are handled exactly (the "ideal-GPS variant", docs/assumptions.md, launcher.md §6.2 item 5).
* :func:`ins_only_covariance` — the unaided baseline (docs/assumptions.md, launcher.md §6.2 item 1).
* :func:`block_in_frame`, :func:`sigma_in_frame` — a 3x3 block rotated per step, e.g. the
  attitude error in body axes ``P_body = T_E^B P_psipsi T_B^E`` (docs/assumptions.md, launcher.md
  §6.2 item 6).
* :func:`correlation`, :func:`group_correlation` — ``rho_ij(k)`` and per-axis correlation
  of two rotated groups (docs/assumptions.md, launcher.md §6.3).
* :func:`normalized_eigen` — the Ham & Brown (1983) normalised covariance eigen-analysis
  (docs/assumptions.md, ssac.md §3.6, Silva et al. 2017 eqs. 45–46) with sign-consistent tracking
  through near-degenerate eigenvalues.
* :func:`covariance_ratio`, :func:`convergence_time` — the PSINS-style "observability
  degree" ``sigma_i(t0)/sigma_i(t)`` and time-to-converge metrics (docs/assumptions.md, ssac.md §8
  item 7).
"""

from navlib.covariance.eigen import NormalizedEigenResult, normalized_eigen
from navlib.covariance.frames import (
    block_in_frame,
    convergence_time,
    correlation,
    covariance_ratio,
    group_correlation,
    sigma_in_frame,
)
from navlib.covariance.recursion import (
    CovarianceResult,
    ins_only_covariance,
    kalman_covariance,
    kalman_covariances,
)

__all__ = [
    "CovarianceResult",
    "NormalizedEigenResult",
    "block_in_frame",
    "convergence_time",
    "correlation",
    "covariance_ratio",
    "group_correlation",
    "ins_only_covariance",
    "kalman_covariance",
    "kalman_covariances",
    "normalized_eigen",
    "sigma_in_frame",
]
