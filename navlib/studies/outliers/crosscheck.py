"""The outlier beside the noise: Monte-Carlo runs with and without it, and the same outlier
through the closed-loop EKF."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd
from threadpoolctl import threadpool_limits

from navlib.covariance import sigma_in_frame
from navlib.filters import prepare_linear, simulate_ekf, simulate_linear
from navlib.filters.recovery import RecoveryScore, score_recovery
from navlib.kalman import nees_values
from navlib.models.launcher import launcher
from navlib.sensors.faults import Outlier
from navlib.studies.outliers.response import (
    DEFAULTS,
    FilterCache,
    OutlierResponse,
    adopt_filters,
    default_trajectory,
    effective_bias_model,
    outlier_response,
    record_stride,
    watch_rows,
)

__all__ = ["EKFCrossCheck", "MonteCarloOutlier", "ekf_crosscheck", "ekf_vs_covariance",
           "monte_carlo_outlier"]


@dataclass(frozen=True, eq=False)
class MonteCarloOutlier:
    """Noisy runs with an outlier: the error band, the outlier share and consistency.

    Attributes
    ----------
    t : ndarray (K,)
    error : ndarray (K, R, p)
        Watched estimation error of each run, outlier included.
    induced : ndarray (K, p)
        The outlier-induced part (identical in every run, by linearity).
    sigma : ndarray (K, p)
    score : RecoveryScore
        With ``e_pre`` from the runs' nominal errors.
    consistency : dict
        NEES/NIS fractions inside their 95 % bounds (outlier included).
    nominal_consistency : dict
        The same for the nominal runs (outlier response removed; NIS at the recorded
        update epochs).
    """

    t: np.ndarray
    error: np.ndarray
    induced: np.ndarray
    sigma: np.ndarray
    score: RecoveryScore
    consistency: dict
    nominal_consistency: dict

    @property
    def nominal_error(self) -> np.ndarray:
        return self.error - self.induced[:, None, :]

    def to_frame(self) -> pd.DataFrame:
        """Per epoch: RMS error with and without the outlier (first component), sigma."""
        e = self.error[:, :, 0]
        e0 = self.nominal_error[:, :, 0]
        return pd.DataFrame({"t": self.t, "rms": np.sqrt(np.mean(e**2, axis=1)),
                             "rms_nominal": np.sqrt(np.mean(e0**2, axis=1)),
                             "induced": self.induced[:, 0], "sigma": self.sigma[:, 0]})


def monte_carlo_outlier(solution: str, outlier: Outlier, watch: str = "roll", *, runs: int = 50,
                        seed=0, trajectory=None, biases: str = DEFAULTS["biases"],
                        bias_model: str = DEFAULTS["bias_model"],
                        window: float = DEFAULTS["window"], cache: FilterCache | None = None,
                        record_every: int | None = None,
                        progress: Callable[[int, int], None] | None = None,
                        **model_options) -> MonteCarloOutlier:
    """Monte-Carlo runs of the linear filter with an outlier (runs vectorised).

    The nominal errors are the faulty ones minus the exact noise-free outlier response, so
    one batch of runs gives both (linearity, :mod:`navlib.filters`).
    ``progress(done, total)`` is called as the batch advances.
    """
    bias_model = effective_bias_model(biases, bias_model)
    if cache is None:
        cache = FilterCache(trajectory if trajectory is not None else default_trajectory(),
                            size=1, **model_options)
    prepared = cache.get(solution, biases, bias_model)
    if record_every is None:
        record_every = record_stride(cache.trajectory, 0.05)
    sim = simulate_linear(prepared, runs=runs, seed=seed, outliers=outlier,
                          record_every=record_every, progress=progress)
    resp = simulate_linear(prepared, outliers=outlier, noise=False, initial_error=False,
                           record_every=record_every, nees=False)
    C = cache.trajectory.attitude.as_matrix()[sim.index]
    rows = watch_rows(watch, sim.state_names, C)
    truth, est, sigma = sim.project(rows)
    r_truth, r_est, _ = resp.project(rows)
    err = est - truth
    induced = (r_est - r_truth)[:, 0]
    nominal = err - induced[:, None, :]
    scalar = induced.shape[1] == 1
    score = score_recovery(sim.t, induced[:, 0] if scalar else induced,
                           t_outlier=outlier.time, window=window,
                           sigma=sigma[:, 0] if scalar else sigma,
                           nominal_error=nominal[:, :, 0] if scalar else nominal)
    return MonteCarloOutlier(sim.t, err, induced, sigma, score, sim.consistency(),
                             _nominal_consistency(sim, resp, prepared))


def _nominal_consistency(sim, resp, prepared) -> dict:
    """NEES and NIS consistency of the nominal runs: the faulty runs minus the exact outlier
    response (linearity), the NIS at the recorded update epochs."""
    error = sim.estimate - sim.truth
    error -= resp.estimate - resp.truth
    nees, dof = nees_values(error, sim.P, basis=prepared.nees_basis(sim.index))
    upd = prepared.measured[sim.index]
    innov = (sim.innovation - resp.innovation)[upd]
    S_pinv = prepared.gains.S_pinv[sim.index[upd]]
    nis = np.einsum("kri,kij,krj->kr", innov, S_pinv, innov)
    return replace(sim, nees=nees, nees_dof=dof, nis_t=sim.t[upd], nis=nis,
                   nis_dof=prepared.gains.dof[sim.index[upd]]).consistency()


@dataclass(frozen=True, eq=False)
class EKFCrossCheck:
    """Outlier-induced roll error through the EKF next to the linear filter's.

    Attributes
    ----------
    t : ndarray (K,)
        EKF epochs.
    ekf_induced : ndarray (K,)
        Roll error of the EKF run with the outlier minus that of the run without (noise-
        free sensors, no initial error), rad, in the linear convention (estimate - truth of
        the error state = the navigation roll error after correction, sign flipped).
    linear : OutlierResponse
    score_ekf : RecoveryScore
    """

    t: np.ndarray
    ekf_induced: np.ndarray
    linear: OutlierResponse
    score_ekf: RecoveryScore

    def to_frame(self) -> pd.DataFrame:
        lin = np.interp(self.t, self.linear.t, self.linear.induced[:, 0])
        return pd.DataFrame({"t": self.t, "ekf": self.ekf_induced, "linear": lin})


def ekf_crosscheck(solution: str, outlier: Outlier, *, trajectory=None,
                   biases: str = DEFAULTS["biases"], bias_model: str = DEFAULTS["bias_model"],
                   recovery_window_s: float = DEFAULTS["window"],
                   feedback_window_s: float = 0.1, cache: FilterCache | None = None,
                   **model_options) -> EKFCrossCheck:
    """Run the outlier through the closed-loop EKF (:func:`navlib.filters.simulate_ekf`,
    sensors at every sample as in the paper, noise-free so the response is isolated) and
    compare its roll response with the linear filter's.

    The run with the outlier starts from the state of the run without it at the last
    propagation window before the outlier (``simulate_ekf(..., resume=...)``: the same
    numbers as a run from the start, whose first part is the nominal run's), except for
    the RT solutions, whose closed-loop reference trajectory keeps a state of its own.
    ``cache``: prepared linear filters and responses to reuse for the linear response
    when it holds the same trajectory and model options (else a fresh one is built).
    ``recovery_window_s``: the recovery window of :func:`navlib.outliers.score_recovery`
    (both responses); ``feedback_window_s``: the EKF's longest propagation window between
    feedback corrections (``simulate_ekf(window_s=...)``)."""
    traj = trajectory if trajectory is not None else default_trajectory()
    bias_model = effective_bias_model(biases, bias_model)
    kw = dict(model="launcher", solution=solution, biases=biases, bias_model=bias_model,
              model_options=model_options or None, gnss_rate_hz=traj.rate_hz, noise=False,
              initial_error=False, window_s=feedback_window_s)
    resumable = not solution.endswith("_rt")
    before = outlier.time - float(np.max(np.diff(traj.t)))
    with threadpool_limits(1):          # small matrices, one step at a time
        nominal = simulate_ekf(traj, snapshot_before=before if resumable else None, **kw)
        faulty = simulate_ekf(traj, outliers=outlier, resume=nominal if resumable else None,
                              **kw)
    # navigation roll error (C_true = exp(S(psi)) C_hat, body axes) = truth - estimate of
    # the error state after feedback; the linear 'induced' is estimate - truth
    induced = -(faulty.errors["roll"].to_numpy() - nominal.errors["roll"].to_numpy())
    t = faulty.result.t
    lin_cache = FilterCache(traj, size=1, **model_options)
    if cache is not None:
        adopt_filters(lin_cache, cache)
    lin = outlier_response(solution, outlier, "roll", biases=biases, bias_model=bias_model,
                           window=recovery_window_s, cache=lin_cache)
    score = score_recovery(t, induced, t_outlier=outlier.time, window=recovery_window_s)
    return EKFCrossCheck(t, induced, lin, score)


def ekf_vs_covariance(trajectory, *, solution: str = "ins_gps_att",
                      biases: str = DEFAULTS["biases"], bias_model: str = DEFAULTS["bias_model"],
                      seed=0, feedback_window_s: float = 0.1, **model_options
                      ) -> pd.DataFrame:
    """One noisy closed-loop EKF run next to the covariance analysis of the same model.

    The EKF (:func:`navlib.filters.simulate_ekf`, sensors at every sample) evaluates its
    Jacobians along its own estimate; the covariance analysis
    (:func:`navlib.covariance.kalman_covariance` via :func:`navlib.filters.prepare_linear`)
    along the true trajectory. Returns a tidy frame ``t, axis, sigma_ekf, sigma_cov, error``
    for the body-axis attitude errors (rad; ``error`` is the EKF's actual navigation error)
    and the ECEF position errors (m, axes ``pos_x..z``). ``feedback_window_s``: the EKF's
    longest propagation window between feedback corrections (``simulate_ekf(window_s=...)``).
    """
    bias_model = effective_bias_model(biases, bias_model)
    with threadpool_limits(1):          # small matrices, one step at a time
        run = simulate_ekf(trajectory, solution=solution, biases=biases,
                           bias_model=bias_model, model_options=model_options or None,
                           seed=seed, gnss_rate_hz=trajectory.rate_hz,
                           window_s=feedback_window_s,
                           keep_covariance=True)
    res = run.result
    k = np.searchsorted(trajectory.t, res.t)
    C_e_b = np.swapaxes(trajectory.attitude.as_matrix()[k], 1, 2)
    names = list(res.state_names)
    psi = [names.index(f"psi_{a}") for a in "xyz"]
    pos = [names.index(f"dr_{a}") for a in "xyz"]
    sig_ekf = np.hstack([sigma_in_frame(res.P, psi, C_e_b), res.sigma[:, pos]])
    prepared = prepare_linear(launcher(solution, biases, bias_model, trajectory,
                                       **model_options), compact=True, own_model=True)
    P = prepared.covariance.P_post[k]
    sig_cov = np.hstack([sigma_in_frame(P, psi, C_e_b),
                         np.sqrt(np.diagonal(P, axis1=1, axis2=2)[:, pos])])
    e = run.errors
    err = e[["roll", "pitch", "yaw", "pos_x", "pos_y", "pos_z"]].to_numpy()
    axes = np.array(["roll", "pitch", "yaw", "pos_x", "pos_y", "pos_z"], dtype=object)
    return pd.DataFrame({"t": np.repeat(res.t, 6), "axis": np.tile(axes, res.t.size),
                         "sigma_ekf": sig_ekf.ravel(), "sigma_cov": sig_cov.ravel(),
                         "error": err.ravel()})
