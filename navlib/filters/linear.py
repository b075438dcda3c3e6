"""Linear error-state Monte-Carlo simulator (spec launcher.md §6.2-6.4; issue 5).

:func:`simulate_linear` (:func:`prepare_linear` caches the covariance).

Truth error ``x_{k+1} = F_k x_k + w_k`` with ``w_k ~ N(0, Q_k)`` sampled, measured as
``z_k = H_k x_k + v_k`` with ``v_k ~ N(0, R_k)``, filtered by the Kalman filter of the
same model. The covariance recursion is data independent, so it is computed once
(:func:`navlib.covariance.kalman_covariance`, Joseph form) and shared by every run; the
gains follow from the priors in one batched pass; the runs sit on a batch axis, and the
step-by-step recursions of the truth and of the filter run as compiled kernels
(:func:`truth_kernel`, :func:`filter_kernel`; issue 26), one BLAS product per step and no
Python between them. Because
everything is linear, the estimation error of a run with an outlier is the error of the
same run without it plus the noise-free outlier response (``noise=False``), exactly —
:mod:`navlib.outliers` uses this. Outliers on measurement channels are added to ``z``;
IMU outliers enter as a known input on the matching noise channel,
``x_{k+1} += Gamma_k e_j u_k`` with ``Gamma_k = G_k dt`` (Euler, the paper's
``B = s_t G``) or ``int_0^dt expm(A s) ds G`` (``method="expm"``); see
:mod:`navlib.outliers` for the signs.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace

import numba
import numpy as np
import pandas as pd
from threadpoolctl import threadpool_limits

from navlib._validation import finite_array
from navlib.covariance import CovarianceResult, FactoredNoise, symmetrize
from navlib.covariance import _recursion as _covariance_recursion
from navlib.discretize import discretize_steps
from navlib.errors import NavlibInputError
from navlib.kalman import (
    _PINV_RTOL,
    Gains,
    _psd_sqrt,
    chi2_bounds,
    kernel_array,
    nees_basis,
    nees_values,
)
from navlib.kalman import compile_kernels as _kalman_compile_kernels
from navlib.models.base import DiscreteModel, LinearModel
from navlib.outliers import Outlier, as_outliers, channel_profile, linear_mapping

METHODS = ("euler", "expm")

_ONE_THREAD = 1
"""BLAS threads of the covariance recursion and of the simulation (``threadpoolctl``).
Their matrices are small (n <= 30) and come one step or one epoch at a time: OpenBLAS's
threads inside each of those calls only synchronise, and on a loaded machine a batched
eigen-decomposition of the recorded covariances ran up to 25 times slower with them
(notebook 05 profile, issue 14). One thread gives the same numbers."""

_MEMORY_BUDGET = 100e6
"""Bytes of recorded truth + estimate histories :func:`simulate_linear` aims at when it
chooses ``record_every`` itself."""


def _phi1_series(A, dt, order: int = 6) -> np.ndarray:
    """``int_0^dt expm(A s) ds = dt sum_j (A dt)^j / (j+1)!`` by its series, (K, n, n)."""
    step = np.asarray(dt, dtype=float)[:, None, None]
    X = A * step
    term = np.broadcast_to(np.eye(A.shape[-1]), A.shape).copy()
    total = term.copy()
    for j in range(1, order + 1):
        term = X @ term / (j + 1)
        total = total + term
    return total * step


@dataclass(frozen=True, eq=False)
class LinearSteps:
    """A linear error model at its steps, ready for simulation.

    Attributes
    ----------
    t : ndarray (N,)
    F, Q : ndarray (N-1, n, n)
    L : ndarray (N-1, n, q)
        Process-noise factor, ``Q_k = L_k L_k'``.
    Gamma : ndarray (N-1, n, q_in) or None
        Noise input matrices (deterministic input ``u`` on the noise channels adds
        ``Gamma_k u_k`` over step k); None when the model has no ``G``.
    H : ndarray (N, m, n)
    R : ndarray (N, m, m)
    P0 : ndarray (n, n)
    state_names, measurement_names, noise_names : tuple of str
    """

    t: np.ndarray
    F: np.ndarray
    Q: np.ndarray
    L: np.ndarray
    Gamma: np.ndarray | None
    H: np.ndarray
    R: np.ndarray
    P0: np.ndarray
    state_names: tuple[str, ...]
    measurement_names: tuple[str, ...]
    noise_names: tuple[str, ...]

    @property
    def n(self) -> int:
        return len(self.state_names)


def linear_steps(model, *, method: str = "euler", P0=None, noise_input=None,
                 noise_names: Sequence[str] = (), with_q: bool = True) -> LinearSteps:
    """Per-step ``F, Q`` (and the noise factor / input) of a model for :func:`simulate_linear`.

    Parameters
    ----------
    model : LinearModel (trajectory model) or DiscreteModel
    method : {"euler", "expm"}
        For a LinearModel: the papers' ``F = I + A dt``, ``Q = G Qc G' dt`` (Beaudoin eq. 1,
        ``A_lc = I + s_t F``; default), or the zero-order-hold exponential with the Van
        Loan ``Q`` (batched series, :func:`navlib.discretize.discretize_steps`). The
        matrices over step k are those of sample k.
    P0 : ndarray (n, n), optional
        Initial covariance (default the model's).
    noise_input, noise_names
        For a DiscreteModel: ``Gamma`` (N-1, n, q) and its channel names, needed only for
        IMU outliers.
    with_q : bool
        False: no ``Q`` for the Euler form of a LinearModel (``steps.Q`` None), where it is
        ``L_k L_k'`` and can be formed a block of steps at a time.
    """
    if method not in METHODS:
        raise NavlibInputError(f"method: expected one of {METHODS}, got {method!r}")
    if isinstance(model, LinearModel):
        if model.t is None:
            raise NavlibInputError(
                "model: a constant LinearModel has no time axis; call model.discretize(dt=..., "
                "n_epochs=...) and pass the DiscreteModel"
            )
        t = np.asarray(model.t, dtype=float)
        N, n = t.size, model.n
        A = np.broadcast_to(model.A, (N, n, n))[:-1]
        G = np.broadcast_to(model.G, (N, *model.G.shape[-2:]))[:-1]
        dt = np.diff(t)
        Qc = np.asarray(model.Qc, dtype=float)
        if method == "euler":
            F = A * dt[:, None, None]
            F += np.eye(n)                   # in place: the same sums as eye + A dt
            Gamma = G * dt[:, None, None]
            L = G @ _psd_sqrt(Qc)
            L *= np.sqrt(dt)[:, None, None]  # in place: one (N-1, n, q) array, not two
            Q = FactoredNoise(L)[:] if with_q else None
        else:
            F, Q = discretize_steps(A, G, Qc, dt, method="series")
            Gamma = _phi1_series(A, dt) @ G
            L = _psd_sqrt(Q)
        H = np.broadcast_to(model.H, (N, *model.H.shape[-2:]))
        R = np.broadcast_to(model.R, (N, *model.R.shape[-2:]))
        P0 = model.P0 if P0 is None else P0
        names = (model.state_names, tuple(model.measurement_names), tuple(model.noise_names))
    elif isinstance(model, DiscreteModel):
        t, F, Q, H, R = model.t, model.F, model.Q, model.H, model.R
        L = _psd_sqrt(Q)
        Gamma = None
        if noise_input is not None:
            Gamma = finite_array(noise_input, "noise_input")
            if Gamma.ndim != 3 or Gamma.shape[:2] != F.shape[:2]:
                raise NavlibInputError(
                    f"noise_input: expected shape ({F.shape[0]}, {F.shape[1]}, q), got "
                    f"{Gamma.shape}"
                )
            if len(noise_names) != Gamma.shape[2]:
                raise NavlibInputError("noise_names: one name per noise_input column needed")
        P0 = model.P0 if P0 is None else P0
        names = (model.state_names, tuple(model.measurement_names), tuple(noise_names))
    else:
        raise NavlibInputError(
            f"model: expected a navlib LinearModel or DiscreteModel, got {type(model).__name__}"
        )
    if P0 is None:
        raise NavlibInputError("P0: the model has no default initial covariance; pass P0")
    n = F.shape[-1]
    P0 = finite_array(P0, "P0", (n, n))
    return LinearSteps(np.asarray(t, dtype=float), F, Q, L, Gamma, H, R, symmetrize(P0), *names)


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
        truth = np.einsum("kpn,krn->krp", rows, self.truth)
        est = np.einsum("kpn,krn->krp", rows, self.estimate)
        var = np.einsum("kpn,knm,kpm->kp", rows, self.P, rows)
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
        """Tidy table ``t, run, state, truth, estimate, error, sigma``."""
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


def _measured_mask(N: int, update_every, measured) -> np.ndarray:
    if measured is not None:
        mask = np.asarray(measured, dtype=bool)
        if mask.shape != (N,):
            raise NavlibInputError(f"measured: expected {N} booleans, got shape {mask.shape}")
        return mask.copy()
    every = int(update_every)
    if every < 1:
        raise NavlibInputError(f"update_every: expected an integer >= 1, got {update_every}")
    mask = np.zeros(N, dtype=bool)
    mask[::every] = True
    return mask


@dataclass(frozen=True, eq=False)
class LinearFilter:
    """A linear model with its (data-independent) Kalman covariance and gains.

    Built by :func:`prepare_linear`; :func:`simulate_linear` reuses it across calls (the
    covariance recursion dominates the cost of a short Monte-Carlo batch).

    Attributes
    ----------
    steps : LinearSteps
    measured : ndarray (N,) of bool
        Update epochs.
    gains : Gains
    covariance : navlib.covariance.CovarianceResult
        Prior and posterior covariances at every epoch (posteriors only, ``P_prior``
        None, when prepared with ``compact=True``).
    """

    steps: LinearSteps
    measured: np.ndarray
    gains: Gains
    covariance: object
    _nees_bases: dict = field(default_factory=dict, init=False, repr=False)

    @property
    def t(self) -> np.ndarray:
        return self.steps.t

    def nees_basis(self, index) -> tuple:
        """:func:`nees_basis` of the posterior covariances at the epochs ``index``, cached
        (it does not depend on the data, so every simulation recorded at the same epochs
        shares it)."""
        index = np.asarray(index)
        key = index.tobytes()
        if key not in self._nees_bases:
            self._nees_bases.clear()          # keep one: (K, n, n) eigenvectors are large
            self._nees_bases[key] = nees_basis(self.covariance.P_post[index])
        return self._nees_bases[key]

    @property
    def state_names(self) -> tuple[str, ...]:
        return tuple(self.steps.state_names)


def prepare_linear(model, *, method: str = "euler", update_every: int = 1, measured=None,
                   P0=None, noise_input=None, noise_names: Sequence[str] = (),
                   compact: bool = False) -> LinearFilter:
    """Discretise a model and run its Kalman covariance recursion once.

    Parameters as in :func:`simulate_linear`. The covariance is that of
    :func:`navlib.covariance.kalman_covariance` (Joseph form), and the gains are those of
    :func:`navlib.kalman.kalman_gains` from its priors, both from one recursion
    (:func:`_blockwise_covariance`). BLAS runs on one thread here (:data:`_ONE_THREAD`).

    ``compact=True`` keeps what :func:`simulate_linear` needs and drops the rest: the
    filter keeps no prior covariances
    (``covariance.P_prior`` is None) and no process noise (``steps.Q`` is None; the noise
    is sampled through ``steps.L``; the Euler ``Q`` is never formed whole). For a 28-state
    model at 200 Hz over 150 s that is about 0.8 GB held instead of 1.2 GB, and about
    1.2 GB at most while preparing (the model's own matrices included) instead of 1.7 GB.
    """
    if isinstance(model, LinearFilter):
        return model
    steps = linear_steps(model, method=method, P0=P0, noise_input=noise_input,
                         noise_names=noise_names, with_q=not compact)
    mask = _measured_mask(steps.t.size, update_every, measured)
    with threadpool_limits(_ONE_THREAD):
        cov, gains = _blockwise_covariance(steps, mask, priors=not compact)
    if compact:
        steps = replace(steps, Q=None)
    return LinearFilter(steps, mask, gains, cov)


def _blockwise_covariance(steps: LinearSteps, mask, block: int = 2048, priors: bool = False):
    """:func:`navlib.covariance.kalman_covariance` and its gains in one recursion.

    The recursion (:func:`navlib.covariance._recursion`) keeps the gain of each update
    (the :func:`navlib.kalman.kalman_gains` of its prior, to the bit) and reads the
    process noise ``block`` epochs at a time; when ``steps.Q`` is None it forms ``Q = L L'``
    one block at a time (:class:`navlib.covariance.FactoredNoise`), and without ``priors`` it
    keeps no prior covariances. Returns ``(CovarianceResult, Gains)``.
    """
    noise = FactoredNoise(steps.L) if steps.Q is None else steps.Q
    P_prior, P_post, gains = _covariance_recursion(
        steps.F, noise, steps.H, steps.R, steps.P0[None], mask, _PINV_RTOL, priors=priors,
        gains=True, block=block)
    cov = CovarianceResult(steps.t, None if P_prior is None else P_prior[0], P_post[0],
                           mask.copy(), tuple(steps.state_names))
    return cov, Gains(gains.K[0], gains.S_pinv[0], gains.dof[0])


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
        record_every = max(1, int(np.ceil(steps.t.size * per_epoch / _MEMORY_BUDGET)))
    if initial_error:
        x = rng.standard_normal((runs, steps.n)) @ _psd_sqrt(steps.P0).T
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
    the last."""
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
    with threadpool_limits(_ONE_THREAD):
        _recursion(prepared, x, x_hat, z_add, x_input, k0, rng, progress, slot, upd_slot,
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


_CHUNK = 256
"""Steps per block of :func:`_recursion`: its noise is drawn a block at a time (this fixes
the random stream), and the block's truth, measurements and NIS are formed together."""


def _recursion(prepared, x, x_hat, z_add, x_input, k0, rng, progress, slot, upd_slot, out):
    """Steps ``k0 ..`` of :func:`_simulate`, writing into ``out`` (truth, estimate and
    innovation at the recorded epochs, NIS at the updates).

    A block of :data:`_CHUNK` steps at a time: the true errors first (they do not depend on
    the estimate; :func:`truth_kernel`), then their measurements and noise in batched
    products, then the filter step by step (:func:`filter_kernel`), then the NIS and the
    recorded epochs in batched products, into preallocated work arrays. Every product and
    sum is the one a step-by-step loop forms, with the same operands; the compiled kernels
    call the BLAS numba links (SciPy's) where NumPy calls its own, so the numbers equal
    those of the plain loop to rounding (issue 14, issue 26; docs/assumptions.md "Compiled
    kernels").
    """
    steps = prepared.steps
    runs, m = x.shape[0], steps.H.shape[-2]
    N = steps.t.size
    R_sqrt = _psd_sqrt(steps.R[:1]) if np.all(steps.R == steps.R[:1]) else _psd_sqrt(steps.R)
    work = _Work.of(runs, steps.n, m)
    current = (x, x_hat)
    blocks = _noise_blocks(rng, N, (runs, steps.L.shape[-1]), (runs, m))
    for c0, draws in zip(range(0, N, _CHUNK), blocks, strict=True):
        c1 = min(N, c0 + _CHUNK)
        if c1 > k0:
            block = _Block(c0, max(c0, k0), c1, N)
            np.copyto(work.truth[block.j0], current[0])
            np.copyto(work.prior[block.j0], current[1])
            _truth_block(steps, block, work, draws, x_input)
            meas = _measure_block(prepared, block, work, draws, z_add, R_sqrt)
            _filter_block(prepared, block, work, meas)
            _record_block(prepared, block, work, meas, slot, upd_slot, out)
            current = (work.truth[c1 - c0], work.prior[c1 - c0])
        if progress is not None:
            progress(c1, N)


def _noise_blocks(rng, N: int, shape_w, shape_v):
    """The noise draws ``(xi, nu)``, ``(c, *shape_w)`` and ``(c, *shape_v)``, of each block
    of :func:`_recursion` (None for each without ``rng``).

    Drawn in the order of the plain loop (``xi`` then ``nu`` of each block, so the random
    stream is the same), into two alternating pairs of arrays, the next block on a worker
    thread while the caller runs the current one (``Generator.standard_normal`` releases
    the GIL while it fills; the draws of a 100-run batch cost about as much as its
    filter). No more is drawn than the blocks need.
    """
    starts = range(0, N, _CHUNK)
    if rng is None:
        yield from (None for _ in starts)
        return
    pairs = [(np.empty((_CHUNK, *shape_w)), np.empty((_CHUNK, *shape_v))) for _ in range(2)]

    def draw(i: int):
        size = min(N, starts[i] + _CHUNK) - starts[i]
        xi, nu = (a[:size] for a in pairs[i % 2])
        rng.standard_normal(out=xi)
        rng.standard_normal(out=nu)
        return xi, nu

    with ThreadPoolExecutor(max_workers=1) as pool:
        pending = pool.submit(draw, 0)
        for i in range(len(starts)):
            draws = pending.result()
            if i + 1 < len(starts):
                pending = pool.submit(draw, i + 1)
            yield draws


@dataclass(frozen=True)
class _Work:
    """Work arrays of :func:`_recursion`, by step of a block: ``truth`` and ``prior``
    (estimate before the update) one step longer than the block, ``post`` (estimate after
    an update) and ``noise`` (the process noise over the step); ``z``, ``innov`` and
    ``product`` (a measurement noise or ``innov S^+``) by update of the block; ``hx`` and
    ``gain_step`` for one step."""

    truth: np.ndarray
    prior: np.ndarray
    post: np.ndarray
    noise: np.ndarray
    z: np.ndarray
    innov: np.ndarray
    product: np.ndarray
    hx: np.ndarray
    gain_step: np.ndarray

    @classmethod
    def of(cls, runs: int, n: int, m: int) -> _Work:
        states, measured = (_CHUNK, runs, n), (_CHUNK, runs, m)
        return cls(np.empty((_CHUNK + 1, runs, n)), np.empty((_CHUNK + 1, runs, n)),
                   np.empty(states), np.empty(states), np.empty(measured),
                   np.empty(measured), np.empty(measured), np.empty((runs, m)),
                   np.empty((runs, n)))


@dataclass(frozen=True)
class _Block:
    """Steps ``k0 .. k1-1`` of the block starting at ``c0`` (work index ``j = k - c0``),
    of ``N`` in all; ``j0``, ``j1`` their work indices and ``moves`` the steps that
    propagate (all but the last of the run)."""

    c0: int
    k0: int
    k1: int
    N: int

    @property
    def j0(self) -> int:
        return self.k0 - self.c0

    @property
    def j1(self) -> int:
        return self.k1 - self.c0

    @property
    def moves(self) -> slice:
        return slice(self.k0, min(self.k1, self.N - 1))


def _rows(index: np.ndarray):
    """``index`` (ascending) as a slice when it is evenly spaced (a view instead of a
    copy), else itself."""
    if index.size < 2:
        return slice(int(index[0]), int(index[0]) + 1) if index.size else index
    step = int(index[1] - index[0])
    if step > 0 and np.all(np.diff(index) == step):
        return slice(int(index[0]), int(index[-1]) + 1, step)
    return index


def _truth_block(steps: LinearSteps, block: _Block, work: _Work, draws, x_input) -> None:
    """True errors ``x_{k+1} = x_k F_k' (+ xi_k L_k') (+ u_k)`` of a block, into
    ``work.truth`` (``work.truth[j0]`` holds ``x_{k0}``): the process noise of the block in
    one batched product, the recursion in :func:`truth_kernel`."""
    moves = block.moves
    F = kernel_array(steps.F[moves])
    j0 = block.j0
    noise = _NONE
    if draws is not None:
        noise = np.matmul(draws[0][j0:j0 + F.shape[0]], steps.L[moves].swapaxes(-1, -2),
                          out=work.noise[:F.shape[0]])
    inputs = _NONE
    if x_input is not None:
        u = x_input[moves]
        inputs = kernel_array(u if u.ndim == 3 else u[:, None, :])
    truth_kernel(work.truth, F, noise, inputs, j0)


_NONE = np.zeros((0, 1, 0))
"""An absent noise or input of :func:`truth_kernel` (no rows)."""


@numba.njit(cache=True)
def _rows_times(X, A, out):
    """``out = X A'`` for rows ``X`` (R, n) and ``A`` (p, n), one BLAS product (we tried
    skipping the zeros of the sparse ``A``: no faster for 100 runs, docs/assumptions.md
    "Compiled kernels")."""
    np.dot(X, A.T, out)


@numba.njit(cache=True)
def truth_kernel(x, F, noise, inputs, j0):
    """The true-error recursion of a block, compiled (docs/assumptions.md "Compiled
    kernels"): ``x[j0+i+1] = x[j0+i] F[i]' (+ noise[i]) (+ inputs[i])`` for each step ``i``
    of ``F`` (s, n, n); ``x`` (., R, n), ``noise`` (s, R, n) or no rows, ``inputs``
    (s, R, n) or (s, 1, n) (the same input for every run) or no rows. The NumPy code it
    replaced is ``tests/linear_reference.py``."""
    runs = x.shape[1]
    for i in range(F.shape[0]):
        j = j0 + i
        _rows_times(x[j], F[i], x[j + 1])
        if noise.shape[0]:
            x[j + 1] += noise[i]
        if inputs.shape[0]:
            for r in range(runs):
                x[j + 1, r] += inputs[i, 0 if inputs.shape[1] == 1 else r]


def _measure_block(prepared: LinearFilter, block: _Block, work: _Work, draws, z_add,
                   R_sqrt) -> np.ndarray:
    """Measurements ``z_k = x_k H_k' + z_add_k (+ nu_k R_k^(1/2)')`` at the block's
    updates, into ``work.z`` (one row per update); returns the updates' work indices."""
    steps = prepared.steps
    meas = np.flatnonzero(prepared.measured[block.k0:block.k1]) + block.j0
    if meas.size:
        z, k, j = work.z[:meas.size], _rows(meas + block.c0), _rows(meas)
        np.matmul(work.truth[j], steps.H[k].swapaxes(-1, -2), out=z)
        add = z_add[k]
        np.add(z, add[:, None, :] if add.ndim == 2 else add, out=z)
        if draws is not None:
            Rs = R_sqrt[0].T if R_sqrt.shape[0] == 1 else R_sqrt[k].swapaxes(-1, -2)
            np.add(z, np.matmul(draws[1][j], Rs, out=work.product[:meas.size]), out=z)
    return meas


def compile_kernels() -> None:
    """:func:`navlib.kalman.compile_kernels` and the linear simulation's
    :func:`truth_kernel` and :func:`filter_kernel` on tiny inputs: compiles them on the
    first run on a machine, loads them from numba's disk cache afterwards (README
    "Compiled kernels")."""
    _kalman_compile_kernels()
    x = np.zeros((2, 1, 1))
    F = np.ones((1, 1, 1))
    truth_kernel(x, F, _NONE, _NONE, 0)
    filter_kernel(x, x.copy(), x.copy(), x.copy(), F, F, F, np.zeros(1, dtype=np.int64), 0, 1)


def _filter_block(prepared: LinearFilter, block: _Block, work: _Work, meas) -> None:
    """The filter over a block (:func:`filter_kernel`; ``work.prior[j0]`` holds the prior
    at ``k0``)."""
    steps = prepared.steps
    update = np.full(block.j1 - block.j0, -1, dtype=np.int64)
    update[meas - block.j0] = np.arange(meas.size)
    moves = block.moves
    filter_kernel(work.prior, work.post, work.innov, work.z,
                  kernel_array(steps.H[block.k0:block.k1]),
                  kernel_array(prepared.gains.K[block.k0:block.k1]),
                  kernel_array(steps.F[moves]), update, block.j0, moves.stop - block.c0)


@numba.njit(cache=True)
def filter_kernel(prior, post, innov, z, H, K, F, update, j0, last):
    """The linear Kalman filter over the steps of a block, compiled (docs/assumptions.md
    "Compiled kernels"). At step ``i`` (work index ``j = j0 + i``) with
    ``update[i] = p >= 0``: ``innov[p] = z[p] - x^- H[i]'`` and
    ``x^+ = x^- + innov[p] K[i]'`` into ``post[j]`` (rows are runs); then, while
    ``j < last``, ``x^-_{j+1} = x F[i]'`` into ``prior[j + 1]``. The NumPy code it replaced
    is ``tests/linear_reference.py``."""
    runs, n = prior.shape[1], prior.shape[2]
    step = np.empty((runs, n))
    for i in range(update.size):
        j = j0 + i
        estimate = prior[j]
        p = update[i]
        if p >= 0:
            _rows_times(estimate, H[i], innov[p])
            for r in range(runs):
                for c in range(innov.shape[2]):
                    innov[p, r, c] = z[p, r, c] - innov[p, r, c]
            _rows_times(innov[p], K[i], step)
            for r in range(runs):
                for c in range(n):
                    post[j, r, c] = estimate[r, c] + step[r, c]
            estimate = post[j]
        if j < last:
            _rows_times(estimate, F[i], prior[j + 1])


def _record_block(prepared: LinearFilter, block: _Block, work: _Work, meas, slot, upd_slot,
                  out) -> None:
    """NIS ``(z - x^- H') S^+ (z - x^- H')'`` at the block's updates and the recorded
    truth, estimate and innovation of the block into ``out``."""
    truth_rec, est_rec, innov_rec, nis = out
    c0 = block.c0
    if meas.size:
        innov = work.innov[:meas.size]
        weighted = np.matmul(innov, prepared.gains.S_pinv[_rows(meas + c0)],
                             out=work.product[:meas.size])
        nis[_rows(upd_slot[meas + c0])] = np.sum(np.multiply(weighted, innov, out=weighted),
                                                 axis=2)
        kept = slot[meas + c0] >= 0
        innov_rec[_rows(slot[meas[kept] + c0])] = innov[_rows(np.flatnonzero(kept))]
    rec = np.flatnonzero(slot[block.k0:block.k1] >= 0) + block.j0
    truth_rec[_rows(slot[rec + c0])] = work.truth[_rows(rec)]
    updated = prepared.measured[rec + c0]
    for pick, source in ((updated, work.post), (~updated, work.prior)):
        est_rec[_rows(slot[rec[pick] + c0])] = source[_rows(rec[pick])]
