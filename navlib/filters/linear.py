"""Linear error-state Monte-Carlo simulator (docs/assumptions.md, launcher.md §6.2-6.4).

:func:`simulate_linear` (:func:`prepare_linear` caches the covariance).

Truth error ``x_{k+1} = F_k x_k + w_k`` with ``w_k ~ N(0, Q_k)`` sampled, measured as
``z_k = H_k x_k + v_k`` with ``v_k ~ N(0, R_k)``, filtered by the Kalman filter of the
same model. The covariance recursion is data independent, so it is computed once
(:func:`navlib.covariance.kalman_covariance`, Joseph form) and shared by every run; the
gains follow from the priors in one batched pass; the runs sit on a batch axis, and the
step-by-step recursions of the truth and of the filter run as compiled kernels
(:mod:`navlib.filters.linear_recursion`), one BLAS product per step and no
Python between them. Because
everything is linear, the estimation error of a run with an outlier is the error of the
same run without it plus the noise-free outlier response (``noise=False``), exactly —
:mod:`navlib.sensors.faults` uses this. Outliers on measurement channels are added to ``z``;
IMU outliers enter as a known input on the matching noise channel,
``x_{k+1} += Gamma_k e_j u_k`` with ``Gamma_k = G_k dt`` (Euler, the paper's
``B = s_t G``) or ``int_0^dt expm(A s) ds G`` (``method="expm"``); see
:mod:`navlib.sensors.faults` for the signs.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
from threadpoolctl import threadpool_limits

from navlib.errors import NavlibInputError
from navlib.filters.linear_preparation import (
    ONE_THREAD,
    LinearFilter,
    LinearSteps,
    prepare_linear,
)
from navlib.filters.linear_recursion import run_recursion
from navlib.kalman import chi2_bounds, nees_values, psd_sqrt
from navlib.sensors.faults import Outlier, as_outliers, channel_profile, linear_mapping

__all__ = ["MEMORY_BUDGET", "LinearSimulation", "recorded_epochs", "simulate_linear",
           "unit_responses"]

MEMORY_BUDGET = 100e6
"""Bytes of recorded truth + estimate histories :func:`simulate_linear` aims at when it
chooses ``record_every`` itself."""


@dataclass(frozen=True, eq=False)
class LinearSimulation:
    """Monte-Carlo runs of the linear error-state filter (:func:`simulate_linear`).

    Attributes
    ----------
    t : ndarray (K,)
        Recorded epochs, s.
    truth, estimate : ndarray (K, R, n)
        True error state and its posterior estimate per run.
    P : ndarray (K, n, n)
        Posterior covariance (shared by all runs).
    nees : ndarray (K, R) or None
        ``(x_hat - x)' P^+ (x_hat - x)`` per run, with ``nees_dof`` (K,) degrees of freedom
        (None when not computed: ``simulate_linear(..., nees=False)``,
        :func:`unit_responses`).
    nis_t : ndarray (M,)
        Update epochs.
    nis : ndarray (M, R)
        Normalised innovation squared per run, with ``nis_dof`` (M,).
    innovation : ndarray (K, R, m)
        Innovations at recorded epochs (NaN where no update).
    state_names, measurement_names : tuple of str
    outliers : tuple of Outlier
    applied : tuple of bool
        Whether each outlier's channels exist in the model (False: it had no effect).
    index : ndarray (K,)
        Model step index of each recorded epoch.
    """

    t: np.ndarray
    truth: np.ndarray
    estimate: np.ndarray
    P: np.ndarray
    nees: np.ndarray | None
    nees_dof: np.ndarray | None
    nis_t: np.ndarray
    nis: np.ndarray
    nis_dof: np.ndarray
    innovation: np.ndarray
    state_names: tuple[str, ...]
    measurement_names: tuple[str, ...]
    outliers: tuple
    applied: tuple
    index: np.ndarray

    @property
    def runs(self) -> int:
        return self.truth.shape[1]

    @property
    def n(self) -> int:
        return len(self.state_names)

    @property
    def error(self) -> np.ndarray:
        """Estimation error ``x_hat - x`` (K, R, n); with feedback it is minus the residual
        navigation error left after the correction."""
        return self.estimate - self.truth

    @property
    def sigma(self) -> np.ndarray:
        """Posterior standard deviations (K, n)."""
        return np.sqrt(np.clip(np.diagonal(self.P, axis1=1, axis2=2), 0.0, None))

    def state_index(self, names: Sequence[str]) -> np.ndarray:
        lookup = {s: i for i, s in enumerate(self.state_names)}
        missing = [s for s in names if s not in lookup]
        if missing:
            raise NavlibInputError(f"unknown state(s) {missing}; have {list(self.state_names)}")
        return np.array([lookup[s] for s in names], dtype=int)

    def project(self, rows):
        """Linear combinations ``c' x`` of the state, e.g. a body-axis attitude error.

        Parameters
        ----------
        rows : ndarray (p, n) or (K, p, n)
            One row per watched quantity, constant or per recorded epoch.

        Returns
        -------
        truth, estimate : ndarray (K, R, p)
        sigma : ndarray (K, p)
        """
        rows = np.asarray(rows, dtype=float)
        if rows.ndim == 2:
            rows = np.broadcast_to(rows, (self.t.size, *rows.shape))
        if rows.shape[0] != self.t.size or rows.shape[-1] != self.n:
            raise NavlibInputError(
                f"rows: expected (p, {self.n}) or ({self.t.size}, p, {self.n}), got {rows.shape}"
            )
        # only the states some row weighs: a watched quantity is a few of them (e.g. the
        # three attitude errors), and the other terms of each sum are exact zeros
        cols = np.flatnonzero(np.any(rows != 0, axis=(0, 1)))
        rows = rows[..., cols]
        truth = np.einsum("kpn,krn->krp", rows, self.truth[..., cols])
        est = np.einsum("kpn,krn->krp", rows, self.estimate[..., cols])
        var = np.einsum("kpn,knm,kpm->kp", rows, self.P[:, cols[:, None], cols], rows)
        return truth, est, np.sqrt(np.clip(var, 0.0, None))

    def consistency(self, alpha: float = 0.05) -> dict:
        """Fraction of epochs whose run-averaged NEES / NIS lie inside the chi-square bounds
        (NaN for a NEES not computed)."""
        out = {}
        for key, values, dof in (("nees", self.nees, self.nees_dof),
                                 ("nis", self.nis, self.nis_dof)):
            if values is None:
                out[key] = np.nan
                continue
            valid = dof > 0
            if not valid.any():
                out[key] = np.nan
                continue
            lo, hi = chi2_bounds(dof[valid], self.runs, alpha)
            mean = values[valid].mean(axis=1)
            out[key] = float(np.mean((mean >= lo) & (mean <= hi)))
            out[f"{key}_mean_over_dof"] = float(np.mean(mean / dof[valid]))
        return out

    def to_frame(self, states: Sequence[str] | None = None, runs=None) -> pd.DataFrame:
        """Tidy table ``t, run, state, truth, estimate, error, sigma``.

        Parameters
        ----------
        states : sequence of str or None, optional
            States kept; None: all.
        runs : int, sequence of int or None, optional
            Runs kept; None: all.

        Returns
        -------
        pandas.DataFrame
        """
        idx = self.state_index(states) if states is not None else np.arange(self.n)
        r = np.arange(self.runs) if runs is None else np.atleast_1d(np.asarray(runs, int))
        K, R, S = self.t.size, r.size, idx.size
        tr = self.truth[:, r][:, :, idx]
        es = self.estimate[:, r][:, :, idx]
        sg = np.broadcast_to(self.sigma[:, None, idx], (K, R, S))
        return pd.DataFrame({
            "t": np.repeat(self.t, R * S),
            "run": np.tile(np.repeat(r, S), K),
            "state": np.tile(np.array(self.state_names, dtype=object)[idx], K * R),
            "truth": tr.ravel(), "estimate": es.ravel(), "error": (es - tr).ravel(),
            "sigma": sg.ravel(),
        })

    def nees_frame(self) -> pd.DataFrame:
        """Run-averaged NEES per recorded epoch with its degrees of freedom and 95 % bounds."""
        if self.nees is None:
            raise NavlibInputError("nees_frame: this simulation has no NEES (nees=False)")
        lo, hi = chi2_bounds(self.nees_dof, self.runs)
        return pd.DataFrame({"t": self.t, "nees": self.nees.mean(axis=1),
                             "dof": self.nees_dof, "lower": lo, "upper": hi})

    def nis_frame(self) -> pd.DataFrame:
        """Run-averaged NIS per update epoch with its degrees of freedom and 95 % bounds."""
        lo, hi = chi2_bounds(self.nis_dof, self.runs)
        return pd.DataFrame({"t": self.nis_t, "nis": self.nis.mean(axis=1),
                             "dof": self.nis_dof, "lower": lo, "upper": hi})


def simulate_linear(model, *, runs: int = 1, seed=None, rng=None, outliers=None,
                    noise: bool = True, initial_error: bool = True, method: str = "euler",
                    update_every: int = 1, measured=None, record_every: int | None = None,
                    P0=None, noise_input=None, noise_names: Sequence[str] = (),
                    progress: Callable[[int, int], None] | None = None,
                    nees: bool = True) -> LinearSimulation:
    """Monte-Carlo simulation of the linear error-state Kalman filter, runs vectorised.

    Parameters
    ----------
    model : LinearModel (trajectory model), DiscreteModel or LinearFilter
        E.g. ``navlib.models.launcher(...)`` or ``navlib.models.ecef21(traj)``; a
        :class:`LinearFilter` from :func:`prepare_linear` reuses its covariance and gains
        (``method``, ``update_every``, ``measured``, ``P0``, ``noise_input`` are then
        ignored).
    runs : int
        Number of Monte-Carlo runs (batch axis).
    seed, rng
        Randomness: a seed for a fresh ``numpy.random.default_rng`` or a Generator.
    outliers : Outlier or sequence of Outlier, optional
        Injected as described in the module docstring; channels the model lacks are
        reported in ``applied`` and have no effect.
    noise : bool
        Sample process and measurement noise (False: deterministic response).
    initial_error : bool
        Draw the initial true error from ``N(0, P0)`` (False: start at zero).
    method : {"euler", "expm"}
        Discretisation of a LinearModel (see :func:`linear_steps`).
    update_every : int
        Measurement update at every ``update_every``-th step (ignored with ``measured``).
    measured : array of bool (N,), optional
        Update epochs explicitly.
    record_every : int, optional
        Keep every ``record_every``-th epoch in the result (the last is always kept).
        Default: 1 when the histories fit in about 100 MB, else the smallest step that does.
    P0 : ndarray (n, n), optional
        Initial covariance (default the model's).
    noise_input, noise_names
        Noise input matrices for a DiscreteModel (IMU outliers only).
    progress : callable(done, total), optional
        Called every few hundred steps (e.g. to advance a progress bar).
    nees : bool
        Compute the NEES of the recorded epochs (default). False leaves ``nees`` and
        ``nees_dof`` None: a noise-free response has no use for them, and their
        eigen-decompositions of the recorded covariances cost more than the run.

    Returns
    -------
    LinearSimulation

    Notes
    -----
    Epoch 0 is updated when ``measured[0]``: the prior there is ``x_hat = 0``, ``P0``.
    Propagation over step k uses ``F_k``, the noise ``L_k xi_k`` and the IMU outlier input
    ``Gamma_k u(t_k)``. The covariance and gains are the same for every run.
    """
    outliers = as_outliers(outliers)
    prepared = prepare_linear(model, method=method, update_every=update_every,
                              measured=measured, P0=P0, noise_input=noise_input,
                              noise_names=noise_names)
    steps = prepared.steps
    runs = int(runs)
    if runs < 1:
        raise NavlibInputError(f"runs: expected >= 1, got {runs}")
    if rng is not None and seed is not None:
        raise NavlibInputError("seed, rng: give one of them, not both")
    rng = rng if rng is not None else np.random.default_rng(seed)
    z_add, x_input, applied = _outlier_inputs(steps, outliers)
    if record_every is None:
        per_epoch = 2 * 8 * runs * steps.n
        record_every = max(1, int(np.ceil(steps.t.size * per_epoch / MEMORY_BUDGET)))
    if initial_error:
        x = rng.standard_normal((runs, steps.n)) @ psd_sqrt(steps.P0).T
    else:
        x = np.zeros((runs, steps.n))
    return _simulate(prepared, x, z_add, x_input, recorded_epochs(steps.t.size, record_every),
                     rng if noise else None, outliers, applied, progress, nees)


def unit_responses(model, outliers, *, record_every: int = 1) -> LinearSimulation:
    """Noise-free responses of the linear filter to each outlier at unit magnitude.

    Run ``i`` of the result is the response (true error and estimate, from a zero initial
    error, no noise) to ``outliers[i]`` with its magnitude replaced by 1 in the channel's SI
    unit; all runs share one recursion. The response to the same outlier of magnitude ``a``
    is exactly ``a`` times run ``i``: the recursion is linear in its inputs and its gains
    do not depend on the data (they come from the covariance recursion, which sees only
    the model, :func:`prepare_linear`). That holds for this linear Kalman filter, not for
    the EKF, whose Jacobians follow its own estimate.

    Parameters
    ----------
    model : LinearModel, DiscreteModel or LinearFilter
        As in :func:`simulate_linear` (prepared with its defaults unless a LinearFilter).
    outliers : sequence of Outlier
        One per run; each may name a channel kind (all three axes at once).
    record_every : int
        Keep every n-th epoch (the last is always kept).

    Returns
    -------
    LinearSimulation
        ``runs = len(outliers)``, ``outliers`` the unit outliers; ``nees`` is None.
    """
    units = tuple(Outlier(o.channel, o.time, 1.0, o.shape, o.duration)
                  for o in as_outliers(outliers))
    if not units:
        raise NavlibInputError("outliers: need at least one Outlier")
    prepared = prepare_linear(model)
    steps = prepared.steps
    inputs = [_outlier_inputs(steps, (o,)) for o in units]
    z_add = np.stack([z for z, _, _ in inputs], axis=1)                # (N, C, m)
    x_input = None
    if any(u is not None for _, u, _ in inputs):
        zero = np.zeros((steps.t.size - 1, steps.n))
        x_input = np.stack([zero if u is None else u for _, u, _ in inputs], axis=1)
    applied = tuple(a[0] for _, _, a in inputs)
    x = np.zeros((len(units), steps.n))
    return _simulate(prepared, x, z_add, x_input, recorded_epochs(steps.t.size, record_every),
                     None, units, applied, None, False)


def _outlier_inputs(steps: LinearSteps, outliers) -> tuple:
    """Outliers -> measurement additions ``z_add`` (N, m), the state input over each step
    (N-1, n) or None, and whether each outlier reaches the model (module docstring)."""
    t = steps.t
    z_add = np.zeros((t.size, steps.H.shape[-2]))
    u_cols, u_vals = [], []
    applied = []
    for o in outliers:
        ok = False
        for ch in o.channels:
            mp = linear_mapping(ch, steps.measurement_names, steps.noise_names)
            if mp.target == "noise" and steps.Gamma is None:
                raise NavlibInputError(
                    f"outliers: IMU channel {ch!r} needs the model's noise input; pass a "
                    "LinearModel or noise_input= with noise_names="
                )
            if mp.index is None:
                continue
            values = mp.sign * channel_profile((o,), ch, t)
            ok = True
            if mp.target == "measurement":
                z_add[:, mp.index] += values
            else:
                u_cols.append(mp.index)
                u_vals.append(values[:-1])
        applied.append(ok)
    x_input = None
    if u_cols:
        B = steps.Gamma[:, :, np.array(u_cols)]                # (N-1, n, c)
        x_input = np.einsum("knc,ck->kn", B, np.array(u_vals))
    return z_add, x_input, tuple(applied)


def recorded_epochs(N: int, record_every) -> np.ndarray:
    """The epochs :func:`simulate_linear` records of ``N``: every ``record_every``-th and
    the last.

    Parameters
    ----------
    N : int
        Number of epochs.
    record_every : int
        Record stride.

    Returns
    -------
    numpy.ndarray

    Raises
    ------
    NavlibInputError
        If ``record_every`` is below 1.
    """
    record_every = int(record_every)
    if record_every < 1:
        raise NavlibInputError(f"record_every: expected >= 1, got {record_every}")
    rec = np.arange(0, N, record_every)
    return rec if rec[-1] == N - 1 else np.append(rec, N - 1)


def _simulate(prepared: LinearFilter, x, z_add, x_input, rec, rng, outliers, applied,
              progress, with_nees: bool) -> LinearSimulation:
    """The filter recursion over a batch of runs (true error ``x`` (R, n) at epoch 0).

    ``z_add`` (N, m) or per run (N, R, m) and ``x_input`` (N-1, n) or (N-1, R, n) are the
    outlier inputs; ``rng`` None: no noise (a deterministic run from zero stays exactly
    zero until the first input, so the recursion starts there).
    """
    steps, mask, gains = prepared.steps, prepared.measured, prepared.gains
    t = steps.t
    N, n = t.size, steps.n
    runs, m = x.shape[0], steps.H.shape[-2]
    slot = np.full(N, -1)
    slot[rec] = np.arange(rec.size)

    truth_rec = np.empty((rec.size, runs, n))
    est_rec = np.empty((rec.size, runs, n))
    innov_rec = np.full((rec.size, runs, m), np.nan)
    upd = np.flatnonzero(mask)
    nis = np.empty((upd.size, runs))
    upd_slot = np.full(N, -1)
    upd_slot[upd] = np.arange(upd.size)

    x_hat = np.zeros((runs, n))
    k0 = 0
    if rng is None and not np.any(x):
        per_step = tuple(range(1, z_add.ndim))
        active = np.flatnonzero(np.any(z_add != 0, axis=per_step) & mask)
        if x_input is not None:
            active = np.concatenate([active, np.flatnonzero(np.any(x_input != 0,
                                                                   axis=per_step))])
        k0 = int(active.min()) if active.size else N
        before = rec[rec < k0]
        truth_rec[slot[before]] = 0.0
        est_rec[slot[before]] = 0.0
        upd_before = upd[upd < k0]
        nis[upd_slot[upd_before]] = 0.0
        innov_rec[slot[upd_before[slot[upd_before] >= 0]]] = 0.0
    with threadpool_limits(ONE_THREAD):
        run_recursion(prepared, x, x_hat, z_add, x_input, k0, rng, progress, slot, upd_slot,
                   (truth_rec, est_rec, innov_rec, nis))
        P_post = prepared.covariance.P_post
        P_rec = P_post if rec.size == N else P_post[rec]
        nees = nees_dof = None
        if with_nees:
            nees, nees_dof = nees_values(est_rec - truth_rec, P_rec,
                                         basis=prepared.nees_basis(rec))
    return LinearSimulation(
        t=t[rec], truth=truth_rec, estimate=est_rec, P=P_rec, nees=nees, nees_dof=nees_dof,
        nis_t=t[upd], nis=nis, nis_dof=gains.dof[upd], innovation=innov_rec,
        state_names=tuple(steps.state_names), measurement_names=tuple(steps.measurement_names),
        outliers=tuple(outliers), applied=tuple(applied), index=rec,
    )
