"""Navigation filters: a closed-loop INS/GNSS error-state EKF and a linear error-state
Monte-Carlo simulator (spec launcher.md §6.2-6.4; issue 5).

Linear mode — :func:`simulate_linear` (:func:`prepare_linear` caches the covariance)
    Truth error ``x_{k+1} = F_k x_k + w_k`` with ``w_k ~ N(0, Q_k)`` sampled, measured as
    ``z_k = H_k x_k + v_k`` with ``v_k ~ N(0, R_k)``, filtered by the Kalman filter of the
    same model. The covariance recursion is data independent, so it is computed once
    (:func:`navlib.covariance.kalman_covariance`, Joseph form) and shared by every run; the
    gains follow from the priors in one batched pass; the runs sit on a batch axis, so a
    step is a handful of ``(R, n) @ (n, n)`` products whatever the number of runs. Because
    everything is linear, the estimation error of a run with an outlier is the error of the
    same run without it plus the noise-free outlier response (``noise=False``), exactly —
    :mod:`navlib.outliers` uses this. Outliers on measurement channels are added to ``z``;
    IMU outliers enter as a known input on the matching noise channel,
    ``x_{k+1} += Gamma_k e_j u_k`` with ``Gamma_k = G_k dt`` (Euler, the paper's
    ``B = s_t G``) or ``int_0^dt expm(A s) ds G`` (``method="expm"``); see
    :mod:`navlib.outliers` for the signs.

EKF mode — :func:`ekf`
    Described in its docstring (ECEF strapdown nominal state, error-state covariance from
    the model's Jacobians along the estimate, GNSS / attitude / reference-trajectory
    updates, feedback resets).

Consistency helpers: :func:`chi2_bounds` (two-sided bounds of the Monte-Carlo averaged NEES
or NIS), :meth:`LinearSimulation.consistency`.

Modules: :mod:`~navlib.filters.kalman` (gains, Joseph update, NEES), :mod:`~navlib.filters.linear`
(linear mode), :mod:`~navlib.filters.ekf` (EKF mode), :mod:`~navlib.filters.measurements`
(EKF input data). The aiding-sensor simulations moved to :mod:`navlib.sensors`
(:func:`~navlib.sensors.simulate_attitude_sensor`, :class:`~navlib.sensors.ReferenceTrajectory`).
"""

from navlib.filters.ekf import EKFResult, EKFRun, ekf, simulate_ekf
from navlib.filters.kalman import (
    Gains,
    chi2_bounds,
    definite_noise,
    joseph_update,
    kalman_gain,
    kalman_gains,
    nees_basis,
    nees_values,
)
from navlib.filters.linear import (
    LinearFilter,
    LinearSimulation,
    LinearSteps,
    linear_steps,
    prepare_linear,
    simulate_linear,
)

__all__ = [
    "EKFResult",
    "EKFRun",
    "Gains",
    "LinearFilter",
    "LinearSimulation",
    "LinearSteps",
    "chi2_bounds",
    "definite_noise",
    "ekf",
    "joseph_update",
    "kalman_gain",
    "kalman_gains",
    "linear_steps",
    "nees_basis",
    "nees_values",
    "prepare_linear",
    "simulate_ekf",
    "simulate_linear",
]
