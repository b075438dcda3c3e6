"""Navigation filters: a closed-loop INS/GNSS error-state EKF and a linear error-state
Monte-Carlo simulator (docs/assumptions.md, launcher.md §6.2-6.4).

Linear mode — :func:`simulate_linear` (:func:`prepare_linear` caches the covariance)
    Monte-Carlo runs of the Kalman filter of a linear error model on sampled truth errors,
    runs vectorised, with exact outlier responses by linearity; described in
    :mod:`navlib.filters.linear`.

EKF mode — :func:`ekf`
    Described in its docstring (ECEF strapdown nominal state, error-state covariance from
    the model's Jacobians along the estimate, GNSS / attitude / reference-trajectory
    updates, feedback resets).

Consistency helpers (in :mod:`navlib.kalman`): :func:`~navlib.kalman.chi2_bounds`
(two-sided bounds of the Monte-Carlo averaged NEES or NIS), :meth:`LinearSimulation.consistency`.

Modules: :mod:`~navlib.kalman` (gains, Joseph update, NEES), linear mode in
:mod:`~navlib.filters.linear_preparation` (discretisation, covariance and gains),
:mod:`~navlib.filters.linear` (the simulation) and :mod:`~navlib.filters.linear_recursion`
(its compiled step recursion), EKF mode in :mod:`~navlib.filters.ekf` (the loop),
:mod:`~navlib.filters.ekf_updates` (updates within a feedback window),
:mod:`~navlib.filters.simulate` (simulated scenarios) and
:mod:`~navlib.filters.measurements` (the EKF's measurement classes and input data). The
aiding-sensor simulations moved to :mod:`navlib.sensors`
(:func:`~navlib.sensors.simulate_attitude_sensor`, :class:`~navlib.sensors.ReferenceTrajectory`).
"""

from navlib.filters.ekf import EKFResult, ekf
from navlib.filters.linear import LinearSimulation, simulate_linear
from navlib.filters.linear_preparation import (
    LinearFilter,
    LinearSteps,
    linear_steps,
    prepare_linear,
)
from navlib.filters.simulate import EKFRun, simulate_ekf

__all__ = [
    "EKFResult",
    "EKFRun",
    "LinearFilter",
    "LinearSimulation",
    "LinearSteps",
    "ekf",
    "linear_steps",
    "prepare_linear",
    "simulate_ekf",
    "simulate_linear",
]
