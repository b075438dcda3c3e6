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
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy import stats

from navlib._validation import finite_array, finite_scalar
from navlib.covariance import kalman_covariance
from navlib.discretize import discretize_steps
from navlib.errors import NavlibInputError
from navlib.models.base import DiscreteModel, LinearModel
from navlib.outliers import as_outliers, channel_profile, linear_mapping
from navlib.rotations import skew, unskew

__all__ = [
    "EKFResult",
    "EKFRun",
    "LinearFilter",
    "LinearSimulation",
    "ReferenceTrajectory",
    "chi2_bounds",
    "ekf",
    "kalman_gains",
    "linear_steps",
    "nees_basis",
    "nees_values",
    "prepare_linear",
    "simulate_attitude_sensor",
    "simulate_ekf",
    "simulate_linear",
]

METHODS = ("euler", "expm")

_PINV_RTOL = 1e-12
"""Relative cut-off of the innovation-covariance pseudo-inverse; the value
:func:`navlib.covariance.kalman_covariance` uses by default, so that the gains here
reproduce its posterior covariances."""

_MEMORY_BUDGET = 100e6
"""Bytes of recorded truth + estimate histories :func:`simulate_linear` aims at when it
chooses ``record_every`` itself."""


def _sym(P):
    return 0.5 * (P + np.swapaxes(P, -1, -2))


def _psd_sqrt(M) -> np.ndarray:
    """Batched symmetric square root ``L`` with ``L L' = M`` for PSD ``M`` (..., n, n)."""
    w, V = np.linalg.eigh(_sym(M))
    return V * np.sqrt(np.clip(w, 0.0, None))[..., None, :]


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
                 noise_names: Sequence[str] = ()) -> LinearSteps:
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
            F = np.eye(n) + A * dt[:, None, None]
            Gamma = G * dt[:, None, None]
            L = (G @ _psd_sqrt(Qc)) * np.sqrt(dt)[:, None, None]
            Q = L @ np.swapaxes(L, 1, 2)
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
    return LinearSteps(np.asarray(t, dtype=float), F, Q, L, Gamma, H, R, _sym(P0), *names)


@dataclass(frozen=True, eq=False)
class Gains:
    """Kalman gains and innovation-covariance pseudo-inverses at every epoch."""

    K: np.ndarray          # (N, n, m)
    S_pinv: np.ndarray     # (N, m, m)
    dof: np.ndarray        # (N,) rank of S used (0 at epochs without update)


def kalman_gains(P_prior, H, R, measured, pinv_rtol: float = _PINV_RTOL) -> Gains:
    """Batched gains ``K = P- H' S^+`` with ``S = H P- H' + R`` (all epochs at once).

    ``S^+`` is the inverse when ``R`` is positive definite and the eigen-decomposition
    pseudo-inverse (eigenvalues below ``pinv_rtol * max`` dropped) otherwise — the rule of
    :func:`navlib.covariance.kalman_covariance`, so the Joseph update with these gains
    reproduces its posteriors. Epochs with ``measured`` False get zero gain.
    """
    P_prior = np.asarray(P_prior)
    N = P_prior.shape[0]
    m = H.shape[-2]
    PHt = P_prior @ np.swapaxes(H, 1, 2)
    S = _sym(H @ PHt + R)
    w, V = np.linalg.eigh(S)
    keep = w > pinv_rtol * np.maximum(w[:, -1:], 0.0)
    inv_w = np.where(keep, 1.0 / np.where(keep, w, 1.0), 0.0)
    S_pinv = (V * inv_w[:, None, :]) @ np.swapaxes(V, 1, 2)
    r_min = np.linalg.eigvalsh(R).min(axis=-1)
    definite = r_min > 1e-12 * np.maximum(np.abs(R).max(axis=(-1, -2)), 1e-300)
    if definite.any():
        S_pinv[definite] = np.linalg.inv(S[definite])
        keep[definite] = True
    K = PHt @ S_pinv
    measured = np.asarray(measured, dtype=bool)
    K[~measured] = 0.0
    dof = np.where(measured, keep.sum(axis=1), 0)
    if m == 0:
        dof = np.zeros(N, dtype=int)
    return Gains(K, S_pinv, dof)


def chi2_bounds(dof, runs: int = 1, alpha: float = 0.05):
    """Two-sided ``1 - alpha`` bounds of a Monte-Carlo averaged NEES or NIS.

    The average over ``runs`` independent runs of a chi-square statistic with ``dof``
    degrees of freedom is ``chi2(runs dof) / runs`` (Bar-Shalom, Li & Kirubarajan 2001,
    §5.4); returns ``(lower, upper)`` (arrays when ``dof`` is one).
    """
    dof = np.asarray(dof, dtype=float)
    runs = int(runs)
    if runs < 1:
        raise NavlibInputError(f"runs: expected >= 1, got {runs}")
    alpha = finite_scalar(alpha, "alpha", 0.0, 1.0, low_open=True)
    total = runs * dof
    lo = np.where(total > 0, stats.chi2.ppf(alpha / 2, np.maximum(total, 1)) / runs, 0.0)
    hi = np.where(total > 0, stats.chi2.ppf(1 - alpha / 2, np.maximum(total, 1)) / runs, 0.0)
    return lo, hi


def nees_basis(P, rtol: float = 1e-10):
    """The data-independent part of :func:`nees_values` for covariances (K, n, n).

    Returns ``(scale, active, V, inv_w, dof)``: the standard deviations used to scale ``P``
    to a correlation matrix, the states with non-zero variance, the eigenvectors of that
    matrix, the inverse of its kept eigenvalues (0 for dropped directions) and the kept
    rank. Computed once per covariance history and reused for every error history
    (:func:`simulate_linear` caches it on the :class:`LinearFilter`).
    """
    d = np.sqrt(np.clip(np.diagonal(P, axis1=1, axis2=2), 0.0, None))
    active = d > 0
    safe = np.where(active, d, 1.0)
    C = P / safe[:, :, None] / safe[:, None, :]
    C = np.where(active[:, :, None] & active[:, None, :], C, 0.0)
    w, V = np.linalg.eigh(_sym(C))
    keep = w > rtol * np.maximum(w[:, -1:], 0.0)
    inv_w = np.where(keep, 1.0 / np.where(keep, w, 1.0), 0.0)
    return safe, active, V, inv_w, keep.sum(axis=1)


def nees_values(err, P, rtol: float = 1e-10, basis=None):
    """NEES ``e' P^+ e`` of errors (K, R, n) against covariances (K, n, n); returns the
    NEES (K, R) and its degrees of freedom (K,).

    Scaled to a correlation matrix first (states of very different units); directions with
    (relative) zero variance are left out, and the degrees of freedom are the kept rank.
    ``basis``: :func:`nees_basis` of ``P`` when already computed (``P`` and ``rtol`` are
    then not used).
    """
    safe, active, V, inv_w, dof = basis if basis is not None else nees_basis(P, rtol)
    en = np.where(active[:, None, :], err / safe[:, None, :], 0.0)
    proj = en @ V
    return (proj**2 @ inv_w[:, :, None])[..., 0], dof


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
    nees : ndarray (K, R)
        ``(x_hat - x)' P^+ (x_hat - x)`` per run, with ``nees_dof`` (K,) degrees of freedom.
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
    nees: np.ndarray
    nees_dof: np.ndarray
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
        """Fraction of epochs whose run-averaged NEES / NIS lie inside the chi-square bounds."""
        out = {}
        for key, values, dof in (("nees", self.nees, self.nees_dof),
                                 ("nis", self.nis, self.nis_dof)):
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
        Prior and posterior covariances at every epoch.
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
                   P0=None, noise_input=None, noise_names: Sequence[str] = ()
                   ) -> LinearFilter:
    """Discretise a model and run its Kalman covariance recursion once.

    Parameters as in :func:`simulate_linear`. The covariance is
    :func:`navlib.covariance.kalman_covariance` (Joseph form), the gains
    :func:`kalman_gains` from its priors.
    """
    if isinstance(model, LinearFilter):
        return model
    steps = linear_steps(model, method=method, P0=P0, noise_input=noise_input,
                         noise_names=noise_names)
    mask = _measured_mask(steps.t.size, update_every, measured)
    cov = kalman_covariance(steps.F, steps.Q, steps.H, steps.R, steps.P0, measured=mask,
                            t=steps.t, state_names=steps.state_names)
    return LinearFilter(steps, mask, kalman_gains(cov.P_prior, steps.H, steps.R, mask), cov)


def simulate_linear(model, *, runs: int = 1, seed=None, rng=None, outliers=None,
                    noise: bool = True, initial_error: bool = True, method: str = "euler",
                    update_every: int = 1, measured=None, record_every: int | None = None,
                    P0=None, noise_input=None, noise_names: Sequence[str] = (),
                    progress: Callable[[int, int], None] | None = None, scheduler=None,
                    runs_per_task: int = 25) -> LinearSimulation:
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
    scheduler : optional
        Split the runs into Dask tasks of ``runs_per_task`` runs
        (:func:`navlib.sweep.monte_carlo_linear`: seeds from ``SeedSequence(seed)``, results
        independent of the scheduler; ``progress`` is then a progress bar of the tasks);
        default None: one vectorised batch here.

    Returns
    -------
    LinearSimulation

    Notes
    -----
    Epoch 0 is updated when ``measured[0]``: the prior there is ``x_hat = 0``, ``P0``.
    Propagation over step k uses ``F_k``, the noise ``L_k xi_k`` and the IMU outlier input
    ``Gamma_k u(t_k)``. The covariance and gains are the same for every run.
    """
    if scheduler is not None:
        from navlib.sweep import monte_carlo_linear

        return monte_carlo_linear(model, runs=runs, seed=seed, runs_per_task=runs_per_task,
                                  scheduler=scheduler, record_every=record_every,
                                  **({"rng": rng} if rng is not None else {}),
                                  outliers=outliers, noise=noise, initial_error=initial_error,
                                  method=method, update_every=update_every, measured=measured,
                                  P0=P0, noise_input=noise_input, noise_names=noise_names)
    outliers = as_outliers(outliers)
    prepared = prepare_linear(model, method=method, update_every=update_every,
                              measured=measured, P0=P0, noise_input=noise_input,
                              noise_names=noise_names)
    steps, mask, gains = prepared.steps, prepared.measured, prepared.gains
    runs = int(runs)
    if runs < 1:
        raise NavlibInputError(f"runs: expected >= 1, got {runs}")
    if rng is not None and seed is not None:
        raise NavlibInputError("seed, rng: give one of them, not both")
    rng = rng if rng is not None else np.random.default_rng(seed)
    t, F, L, H, R = steps.t, steps.F, steps.L, steps.H, steps.R
    N, n = t.size, steps.n
    m = H.shape[-2]

    # outliers -> measurement additions (N, m) and noise-channel inputs (N-1, q_in)
    z_add = np.zeros((N, m))
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
            if mp.target == "measurement":
                ok = True
                z_add[:, mp.index] += values
            else:
                ok = True
                u_cols.append(mp.index)
                u_vals.append(values[:-1])
        applied.append(ok)
    if u_cols:
        cols = np.array(u_cols)
        B = steps.Gamma[:, :, cols]                       # (N-1, n, c)
        x_input = np.einsum("knc,ck->kn", B, np.array(u_vals))
    else:
        x_input = None

    if record_every is None:
        per_epoch = 2 * 8 * runs * n
        record_every = max(1, int(np.ceil(N * per_epoch / _MEMORY_BUDGET)))
    record_every = int(record_every)
    if record_every < 1:
        raise NavlibInputError(f"record_every: expected >= 1, got {record_every}")
    rec = np.arange(0, N, record_every)
    if rec[-1] != N - 1:
        rec = np.append(rec, N - 1)
    slot = np.full(N, -1)
    slot[rec] = np.arange(rec.size)

    R_sqrt = _psd_sqrt(R[:1]) if np.all(R == R[:1]) else _psd_sqrt(R)
    const_R = R_sqrt.shape[0] == 1
    q = L.shape[-1]

    truth_rec = np.empty((rec.size, runs, n))
    est_rec = np.empty((rec.size, runs, n))
    innov_rec = np.full((rec.size, runs, m), np.nan)
    upd = np.flatnonzero(mask)
    nis = np.empty((upd.size, runs))
    upd_slot = np.full(N, -1)
    upd_slot[upd] = np.arange(upd.size)

    if initial_error:
        x = rng.standard_normal((runs, n)) @ _psd_sqrt(steps.P0).T
    else:
        x = np.zeros((runs, n))
    x_hat = np.zeros((runs, n))
    # a deterministic response from zero stays exactly zero until the first outlier input:
    # start the recursion there and write the zero histories directly
    k0 = 0
    if not noise and not initial_error:
        active = np.flatnonzero(np.any(z_add != 0, axis=1) & mask)
        if x_input is not None:
            active = np.concatenate([active, np.flatnonzero(np.any(x_input != 0, axis=1))])
        k0 = int(active.min()) if active.size else N
        before = rec[rec < k0]
        truth_rec[slot[before]] = 0.0
        est_rec[slot[before]] = 0.0
        upd_before = upd[upd < k0]
        nis[upd_slot[upd_before]] = 0.0
        innov_rec[slot[upd_before[slot[upd_before] >= 0]]] = 0.0
    chunk = 256
    K_all, S_pinv = gains.K, gains.S_pinv
    for c0 in range(0, N, chunk):
        c1 = min(N, c0 + chunk)
        if noise:
            xi = rng.standard_normal((c1 - c0, runs, q))
            nu_noise = rng.standard_normal((c1 - c0, runs, m))
        for k in range(max(c0, k0), c1):
            if mask[k]:
                Hk = H[k]
                z = x @ Hk.T + z_add[k]
                if noise:
                    z += nu_noise[k - c0] @ (R_sqrt[0] if const_R else R_sqrt[k]).T
                innov = z - x_hat @ Hk.T
                x_hat = x_hat + innov @ K_all[k].T
                nis[upd_slot[k]] = np.sum((innov @ S_pinv[k]) * innov, axis=1)
                if slot[k] >= 0:
                    innov_rec[slot[k]] = innov
            if slot[k] >= 0:
                truth_rec[slot[k]] = x
                est_rec[slot[k]] = x_hat
            if k < N - 1:
                Fk = F[k].T
                x = x @ Fk
                if noise:
                    x += xi[k - c0] @ L[k].T
                if x_input is not None:
                    x += x_input[k]
                x_hat = x_hat @ Fk
        if progress is not None:
            progress(c1, N)
    P_rec = prepared.covariance.P_post[rec]
    nees, nees_dof = nees_values(est_rec - truth_rec, P_rec, basis=prepared.nees_basis(rec))
    return LinearSimulation(
        t=t[rec], truth=truth_rec, estimate=est_rec, P=P_rec, nees=nees, nees_dof=nees_dof,
        nis_t=t[upd], nis=nis, nis_dof=gains.dof[upd], innovation=innov_rec,
        state_names=tuple(steps.state_names), measurement_names=tuple(steps.measurement_names),
        outliers=outliers, applied=tuple(applied), index=rec,
    )


# =============================================================================================
# Closed-loop error-state EKF
# =============================================================================================

FAMILIES = ("launcher", "ecef21")
"""Error-model families the EKF runs with: Beaudoin's launcher models
(:func:`navlib.models.launcher`) and España's 21-state ECEF model
(:func:`navlib.models.ecef21`)."""

_GROUP_STATES = {
    "launcher": {"att": "psi", "vel": "dv", "pos": "dr", "bg": "bg", "ba": "ba", "bp": "bp"},
    "ecef21": {"att": "theta", "vel": "V", "pos": "P", "bg": "bg", "ba": "ba", "sg": "sg",
               "sa": "sa"},
}
_AXES = ("x", "y", "z")


class _BlockTrajectory:
    """The few Trajectory attributes the model builders read, for a block of the estimate.

    ``navlib.models.launcher`` reads ``t``, ``attitude.as_matrix()`` and ``specific_force``;
    ``navlib.models.ecef21`` also ``position``, ``angular_rate``, ``C_b_e()`` and
    ``rate_hz``. Here they hold the filter's nominal (estimated) trajectory and corrected
    IMU signals, so the Jacobians are evaluated along the estimate (an EKF).
    """

    def __init__(self, t, position, C_b_e, f_b, w_ib_b):
        self.t = t
        self.position = position
        self._C = C_b_e
        self.specific_force = f_b
        self.angular_rate = w_ib_b
        self.attitude = self

    def as_matrix(self):
        return self._C

    def C_b_e(self):
        return self._C

    @property
    def rate_hz(self) -> float:
        return float(1.0 / np.median(np.diff(self.t)))


@dataclass(frozen=True, eq=False)
class _Family:
    """Error-state layout of one model family and how it maps onto the nominal state."""

    name: str
    model: LinearModel                 # built once, for names, Qc, P0, R, parameters
    options: dict
    idx: dict                          # group -> index array (3,)
    kept: np.ndarray                   # non-reset states (reference-trajectory block)
    decay: dict                        # parameter group -> (3,) continuous rate (1/s)
    nav_sign: float                    # +1: error = true - estimate (ecef21); -1: est - true

    @property
    def state_names(self):
        return self.model.state_names

    @property
    def n(self) -> int:
        return self.model.n

    def correct_imu(self, params, f_b, w_ib_b, dt_from_start):
        """Compensate IMU samples with the parameter estimates, decayed per sample."""
        def value(group):
            if group not in params:
                return 0.0
            rate = self.decay[group]
            return params[group][None, :] * np.exp(rate[None, :] * dt_from_start[:, None])
        f = f_b - value("ba")
        w = w_ib_b - value("bg")
        if "sa" in params:
            f = f / (1.0 + params["sa"])
        if "sg" in params:
            w = w / (1.0 + params["sg"])
        return f, w

    def jacobians(self, t, position, C_b_e, f_b, w_ib_b):
        """``A`` (K, n, n), ``G`` (K, n, q), ``H`` (K, m, n) along the nominal samples."""
        block = _BlockTrajectory(t, position, C_b_e, f_b, w_ib_b)
        if self.name == "launcher":
            from navlib.models.launcher import launcher

            m = launcher(trajectory=block, **self.options)
            H = np.broadcast_to(m.H, (t.size, *m.H.shape[-2:]))
            return m.A, m.G, H
        from navlib.models.ecef import ecef21_jacobians

        A, G = ecef21_jacobians(position, C_b_e, f_b, w_ib_b,
                                self.options.get("attitude_error", "ecef"))
        return A, G, np.broadcast_to(self.model.H, (t.size, *self.model.H.shape))


def _family(model: str, trajectory_block, options: dict) -> _Family:
    if model == "launcher":
        from navlib.models.launcher import launcher

        m = launcher(trajectory=trajectory_block, **options)
    elif model == "ecef21":
        from navlib.models.ecef import ecef21

        opts = dict(options)
        sensors = opts.pop("sensors", None)
        m = ecef21(trajectory_block, sensors, **opts)
        options = dict(options)
    else:
        raise NavlibInputError(f"model: expected one of {FAMILIES}, got {model!r}")
    names = m.state_names
    groups = _GROUP_STATES[model]
    idx = {}
    for group, prefix in groups.items():
        cand = [f"{prefix}_{a}" for a in _AXES]
        if all(c in names for c in cand):
            idx[group] = np.array([names.index(c) for c in cand])
    kept = np.array([i for i, s in enumerate(names)
                     if (s.startswith("x") and s[1:].isdigit()) or s.startswith("psi_ref")],
                    dtype=int)
    A0 = np.asarray(m.A[0] if m.A.ndim == 3 else m.A)
    decay = {}
    for group in ("bg", "ba", "sg", "sa", "bp"):
        if group in idx:
            block = A0[np.ix_(idx[group], idx[group])]
            decay[group] = np.diag(block).copy()
    return _Family(model, m, options, idx, kept, decay, -1.0 if model == "launcher" else 1.0)


def _imu_arrays(imu):
    if isinstance(imu, pd.DataFrame):
        cols = ["t", "f_x", "f_y", "f_z", "w_x", "w_y", "w_z"]
        missing = [c for c in cols if c not in imu.columns]
        if missing:
            raise NavlibInputError(f"imu: missing column(s) {missing}")
        t = imu["t"].to_numpy(float)
        f = imu[cols[1:4]].to_numpy(float)
        w = imu[cols[4:7]].to_numpy(float)
    else:
        try:
            t, f, w = imu.t, imu.f_b, imu.w_ib_b
        except AttributeError as exc:
            raise NavlibInputError(
                "imu: expected a navlib.sensors.ImuSimulation or a DataFrame with t, f_x.. w_z"
            ) from exc
    from navlib._validation import increasing_times

    t = increasing_times(t, "imu.t")
    return t, finite_array(f, "imu.f_b", (t.size, 3)), finite_array(w, "imu.w_ib_b", (t.size, 3))


def _epoch_index(t_imu, t_meas, name: str) -> np.ndarray:
    """Nearest IMU sample of each measurement time (within half a sample)."""
    t_meas = finite_array(t_meas, f"{name}.t", ndim=1)
    k = np.clip(np.searchsorted(t_imu, t_meas), 1, t_imu.size - 1)
    k = np.where(np.abs(t_imu[k - 1] - t_meas) <= np.abs(t_imu[k] - t_meas), k - 1, k)
    half = 0.5 * np.median(np.diff(t_imu))
    bad = np.flatnonzero(np.abs(t_imu[k] - t_meas) > half + 1e-9)
    if bad.size:
        raise NavlibInputError(
            f"{name}: epoch at t = {t_meas[bad[0]]:g} s is not on an IMU sample "
            f"(IMU spans {t_imu[0]:g}..{t_imu[-1]:g} s)"
        )
    return k


def _rotations(data, name: str):
    """(t, (K, 3, 3)) from ``(t, Rotation)`` or a DataFrame ``t, qx, qy, qz, qw``."""
    from scipy.spatial.transform import Rotation

    if isinstance(data, pd.DataFrame):
        cols = ["qx", "qy", "qz", "qw"]
        missing = [c for c in ["t", *cols] if c not in data.columns]
        if missing:
            raise NavlibInputError(f"{name}: missing column(s) {missing}")
        return data["t"].to_numpy(float), Rotation.from_quat(data[cols].to_numpy()).as_matrix()
    try:
        t, rot = data
    except (TypeError, ValueError) as exc:
        raise NavlibInputError(f"{name}: expected (t, Rotation) or a DataFrame t, qx..qw") from exc
    mats = rot.as_matrix() if hasattr(rot, "as_matrix") else finite_array(rot, name)
    return np.asarray(t, dtype=float), np.asarray(mats).reshape(-1, 3, 3)


def _rotvec(C) -> np.ndarray:
    """Rotation vectors of rotation matrices (..., 3, 3) (log map; closed form, with the
    scipy conversion near pi where the closed form loses accuracy)."""
    C = np.asarray(C, dtype=float)
    cos = np.clip(0.5 * (np.trace(C, axis1=-2, axis2=-1) - 1.0), -1.0, 1.0)
    theta = np.arccos(cos)
    v = unskew(C)                                   # sin(theta) * axis
    small = theta < 1e-4
    factor = np.where(small, 1.0 + theta**2 / 6.0, theta / np.where(small, 1.0, np.sin(theta)))
    out = factor[..., None] * v
    near_pi = theta > 3.0
    if np.any(near_pi):
        from scipy.spatial.transform import Rotation

        out[near_pi] = Rotation.from_matrix(C[near_pi]).as_rotvec()
    return out


def _exp(phi) -> np.ndarray:
    """Rotation matrices ``exp(S(phi))`` of rotation vectors (..., 3) (Rodrigues)."""
    phi = np.asarray(phi, dtype=float)
    theta2 = np.sum(phi * phi, axis=-1)
    theta = np.sqrt(theta2)
    small = theta < 1e-4
    safe = np.where(small, 1.0, theta)
    a = np.where(small, 1.0 - theta2 / 6.0, np.sin(safe) / safe)
    b = np.where(small, 0.5 - theta2 / 24.0, (1.0 - np.cos(safe)) / safe**2)
    K = skew(phi)
    return np.eye(3) + a[..., None, None] * K + b[..., None, None] * (K @ K)


@dataclass(frozen=True, eq=False)
class EKFResult:
    """Output of :func:`ekf` at the measurement-update epochs (posterior, after correction).

    Attributes
    ----------
    t : ndarray (K,)
    position, velocity : ndarray (K, 3)
        Estimated ECEF position (m) and velocity (m/s).
    C_b_e : ndarray (K, 3, 3)
        Estimated body -> ECEF attitude.
    parameters : dict
        Parameter estimates (K, 3) by group: ``bg``, ``ba`` (+ ``sg``, ``sa`` for ecef21,
        ``bp`` for launcher models with the GPS bias, in the model's convention: minus the
        GPS position bias, spec launcher.md §3.1 ``C_lc``).
    kept : ndarray (K, n_kept)
        Estimates of the non-reset states (the reference-trajectory block), names in
        ``kept_names``.
    sigma : ndarray (K, n)
        Posterior error-state standard deviations.
    P : ndarray (K, n, n) or None
        Posterior covariances when ``keep_covariance``.
    innovation : ndarray (K, m)
        Innovations (NaN for rows not measured at that epoch).
    nis : ndarray (K,), nis_dof : ndarray (K,)
    state_names, measurement_names, kept_names : tuple of str
    model : str
    """

    t: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    C_b_e: np.ndarray
    parameters: dict
    kept: np.ndarray
    sigma: np.ndarray
    P: np.ndarray | None
    innovation: np.ndarray
    nis: np.ndarray
    nis_dof: np.ndarray
    state_names: tuple[str, ...]
    measurement_names: tuple[str, ...]
    kept_names: tuple[str, ...]
    model: str

    @property
    def attitude(self):
        from scipy.spatial.transform import Rotation

        return Rotation.from_matrix(self.C_b_e)

    def sigma_of(self, names: Sequence[str]) -> np.ndarray:
        lookup = {s: i for i, s in enumerate(self.state_names)}
        missing = [s for s in names if s not in lookup]
        if missing:
            raise NavlibInputError(f"unknown state(s) {missing}")
        return self.sigma[:, [lookup[s] for s in names]]

    def errors(self, trajectory) -> pd.DataFrame:
        """Navigation errors against a reference trajectory sampled on the same clock.

        Columns ``t``, ``pos_x..z`` (estimate - truth, ECEF m), ``vel_x..z`` (m/s),
        ``att_x..z`` (ECEF rotation vector of ``C_true C_hat'``, rad: the ``psi`` of
        ``C_true = (I + S(psi)) C_hat``), ``roll, pitch, yaw`` (that vector in body axes,
        ``T_E^B psi``, spec launcher.md §6.2 item 6).
        """
        k = _epoch_index(np.asarray(trajectory.t, dtype=float), self.t, "result")
        C = trajectory.attitude[k].as_matrix()
        psi = _rotvec(C @ np.swapaxes(self.C_b_e, 1, 2))
        body = np.einsum("kji,kj->ki", C, psi)
        dp = self.position - trajectory.position[k]
        dv = self.velocity - trajectory.velocity[k]
        cols = {"t": self.t}
        for name, arr in (("pos", dp), ("vel", dv), ("att", psi)):
            for i, a in enumerate(_AXES):
                cols[f"{name}_{a}"] = arr[:, i]
        for i, a in enumerate(("roll", "pitch", "yaw")):
            cols[a] = body[:, i]
        return pd.DataFrame(cols)

    def to_frame(self) -> pd.DataFrame:
        """Tidy estimates: ``t``, ECEF ``x, y, z, vx, vy, vz``, quaternion ``qx..qw``,
        parameters ``<group>_<axis>``, NIS."""
        from scipy.spatial.transform import Rotation

        q = Rotation.from_matrix(self.C_b_e).as_quat()
        cols = {"t": self.t}
        for i, a in enumerate(_AXES):
            cols[a] = self.position[:, i]
        for i, a in enumerate(_AXES):
            cols[f"v{a}"] = self.velocity[:, i]
        for i, a in enumerate(("qx", "qy", "qz", "qw")):
            cols[a] = q[:, i]
        for group, values in self.parameters.items():
            for i, a in enumerate(_AXES):
                cols[f"{group}_{a}"] = values[:, i]
        for j, name in enumerate(self.kept_names):
            cols[name] = self.kept[:, j]
        cols["nis"] = self.nis
        cols["nis_dof"] = self.nis_dof
        return pd.DataFrame(cols)

    def sigma_frame(self) -> pd.DataFrame:
        """Tidy ``t, state, sigma``."""
        n = len(self.state_names)
        return pd.DataFrame({
            "t": np.repeat(self.t, n),
            "state": np.tile(np.array(self.state_names, dtype=object), self.t.size),
            "sigma": self.sigma.ravel(),
        })


_MEAS_KINDS = {
    "launcher": {"att": "psi_m_", "gnss_vel": "dv_m_", "gnss_pos": "dr_m_", "rt": "psi_ref_m_"},
    "ecef21": {"gnss_pos": "gnss_", "gnss_vel": "gnss_v"},
}


def _joseph_update(P, H, R, innov):
    """Joseph-form update with the pseudo-inverse rule of kalman_covariance; returns
    ``(P_post, K, S_pinv, dof)``."""
    PHt = P @ H.T
    S = _sym(H @ PHt + R)
    r_min = np.linalg.eigvalsh(R).min() if R.size else 0.0
    if R.size and r_min > 1e-12 * max(np.abs(R).max(), 1e-300):
        S_pinv = np.linalg.inv(S)
        dof = S.shape[0]
    else:
        w, V = np.linalg.eigh(S)
        keep = w > _PINV_RTOL * max(w[-1], 0.0)
        S_pinv = (V[:, keep] / w[keep]) @ V[:, keep].T
        dof = int(keep.sum())
    K = PHt @ S_pinv
    IKH = np.eye(P.shape[0]) - K @ H
    return _sym(IKH @ P @ IKH.T + K @ R @ K.T), K, S_pinv, dof


def ekf(imu, gnss=None, *, initial, model: str = "launcher", solution: str = "ins_gps",
        biases: str = "GA", bias_model: str = "markov", model_options: dict | None = None,
        P0=None, attitude=None, reference=None, gnss_velocity_sigma: float | None = None,
        initial_parameters: dict | None = None, method: str | None = None,
        window_s: float = 0.1, keep_covariance: bool = False) -> EKFResult:
    """Closed-loop (feedback) INS/GNSS error-state extended Kalman filter in ECEF.

    * **Nominal state**: ECEF position, velocity and attitude propagated by the strapdown
      mechanisation (:func:`navlib.strapdown.integrate`) on the IMU samples, after
      compensating them with the current parameter estimates (gyro/accelerometer biases,
      and scale factors for the 21-state model); Markov parameter estimates decay with
      their model time constant between updates.
    * **Error state**: the states of the chosen error model, ``launcher`` (Beaudoin et al.
      2018 eq. 1-5, 8: ``psi, dv, dr`` [``bg, ba, bp``] [RT block], ``solution``,
      ``biases``, ``bias_model`` as in :func:`navlib.models.launcher`) or ``ecef21``
      (España et al. 2019 Eq. 24). Its covariance is propagated with the model's ``F``,
      ``Q`` whose Jacobians are evaluated **along the estimate** (the nominal trajectory
      and corrected IMU signals, through the model builder), sample by sample.
    * **Updates**: GNSS position and velocity (launcher: ``z = INS - GNSS``, with the GPS
      bias estimate removed from the position; ecef21: ``z = GNSS - INS``, position only
      unless ``gnss_velocity_sigma`` is given); the attitude sensor for ``*_att``
      solutions (``z = rotvec(C_att C_hat')``, ECEF); the reference-trajectory
      pseudo-measurement for ``*_rt`` solutions (eq. 8, ``z = rotvec(C_hat' C_ref)``, body
      axes, noise-free); Joseph form, pseudo-inverse of the innovation covariance when
      ``R`` is singular (as :func:`navlib.covariance.kalman_covariance`).
    * **Feedback**: position, velocity, attitude and the IMU/GNSS parameters are corrected
      with the error-state estimate and those states are zeroed; the reference-trajectory
      states (the launcher's divergence from its reference, spec launcher.md §3.4) have no
      nominal counterpart and keep their estimate. Corrections are fed back at the end of
      each propagation window (every measurement epoch when epochs are at least
      ``window_s`` apart, else every ``window_s``); within a window the error-state mean
      is carried by the linearised model, as in a linearised KF. The attitude reset
      ignores the second-order covariance Jacobian ``I - S(psi)/2``.

    Parameters
    ----------
    imu : navlib.sensors.ImuSimulation or DataFrame (t, f_x, f_y, f_z, w_x, w_y, w_z)
        Measured IMU samples (point samples, SI).
    gnss : DataFrame, optional
        ``t, x, y, z`` ECEF position (m) and optionally ``vx, vy, vz`` (m/s); epochs on IMU
        samples.
    initial : navlib.strapdown.StrapdownState
        Nominal state at the first IMU sample.
    model : {"launcher", "ecef21"}
    solution, biases, bias_model
        Launcher configuration (ignored for ecef21).
    model_options : dict, optional
        Keywords of the model builder (``sigma_gps_vel``, ``a1_sign``, ... for launcher;
        ``sensors``, ``gnss_sigma_m``, ``attitude_error``, P0 sigmas for ecef21).
    P0 : ndarray (n, n), optional
        Initial error covariance (default the model's).
    attitude : (t, Rotation) or DataFrame (t, qx, qy, qz, qw), optional
        Attitude-sensor body -> ECEF attitudes (``*_att`` solutions).
    reference : (t, Rotation) or callable, optional
        Reference-trajectory attitudes for ``*_rt`` solutions, or a callable
        ``reference(k, t_k, C_nav_prev) -> (3, 3)`` called at every IMU sample with the
        posterior navigation attitude of the previous call (None at the first; see
        :class:`ReferenceTrajectory`).
    gnss_velocity_sigma : float, optional
        ecef21 only: use GNSS velocity with this sigma (m/s).
    initial_parameters : dict, optional
        Initial parameter estimates (3,) by group (``bg``, ``ba``, ``sg``, ``sa``, ``bp``);
        default zero.
    method : {"euler", "expm"}, optional
        Per-step discretisation (default ``euler`` for launcher models as in the paper,
        ``expm`` — batched series — for ecef21).
    window_s : float
        Longest propagation window between feedback corrections when updates are denser.
    keep_covariance : bool
        Keep the full posterior covariances in the result.

    Returns
    -------
    EKFResult
    """
    t, f_meas, w_meas = _imu_arrays(imu)
    N = t.size
    opts = dict(model_options or {})
    if model == "launcher":
        opts.update(solution=solution, biases=biases, bias_model=bias_model)
        opts.setdefault("s_t", float(np.median(np.diff(t))))
    method = method or ("euler" if model == "launcher" else "expm")
    if method not in METHODS:
        raise NavlibInputError(f"method: expected one of {METHODS}, got {method!r}")
    window_s = finite_scalar(window_s, "window_s", 0.0, low_open=True)
    r0 = finite_array(initial.position, "initial.position", (3,))
    v0 = finite_array(initial.velocity, "initial.velocity", (3,))
    C0 = initial.attitude.as_matrix()
    probe = _BlockTrajectory(t[:2], np.array([r0, r0]), np.array([C0, C0]), f_meas[:2],
                             w_meas[:2])
    fam = _family(model, probe, opts)
    n = fam.n
    P = fam.model.P0 if P0 is None else finite_array(P0, "P0", (n, n))
    P = _sym(np.array(P, dtype=float))
    Qc = np.asarray(fam.model.Qc, dtype=float)

    # measurement rows of the model, by kind
    meas_names = list(fam.model.measurement_names)
    R_model = np.asarray(fam.model.R, dtype=float)
    if R_model.ndim == 3:
        R_model = R_model[0]
    extra_vel = model == "ecef21" and gnss_velocity_sigma is not None
    if extra_vel:
        gnss_velocity_sigma = finite_scalar(gnss_velocity_sigma, "gnss_velocity_sigma", 0.0,
                                            low_open=True)
        meas_names += [f"gnss_v{a}" for a in _AXES]
        R_model = np.block([[R_model, np.zeros((R_model.shape[0], 3))],
                            [np.zeros((3, R_model.shape[0])),
                             gnss_velocity_sigma**2 * np.eye(3)]])
    rows = {}
    for kind, prefix in _MEAS_KINDS[model].items():
        sel = [i for i, s in enumerate(meas_names) if s.startswith(prefix)
               and s[len(prefix):] in _AXES]
        if len(sel) == 3:
            rows[kind] = np.array(sel)

    # measurement data on IMU samples
    events = {}            # sample index -> list of (kind, value)

    def add(kind, k_idx, values):
        for k, v in zip(k_idx, values, strict=True):
            events.setdefault(int(k), []).append((kind, v))

    if gnss is not None:
        if not isinstance(gnss, pd.DataFrame) or not {"t", "x", "y", "z"} <= set(gnss.columns):
            raise NavlibInputError("gnss: expected a DataFrame with columns t, x, y, z")
        kg = _epoch_index(t, gnss["t"].to_numpy(float), "gnss")
        add("gnss_pos", kg, gnss[["x", "y", "z"]].to_numpy(float))
        if "gnss_vel" in rows and {"vx", "vy", "vz"} <= set(gnss.columns):
            add("gnss_vel", kg, gnss[["vx", "vy", "vz"]].to_numpy(float))
    if "att" in rows:
        if attitude is None:
            raise NavlibInputError(f"attitude: solution {solution!r} needs attitude-sensor data")
        ta, Ca = _rotations(attitude, "attitude")
        add("att", _epoch_index(t, ta, "attitude"), Ca)
    ref_callable = ref_nav = None
    if "rt" in rows:
        if reference is None:
            raise NavlibInputError(f"reference: solution {solution!r} needs reference-"
                                   "trajectory attitudes or a ReferenceTrajectory")
        if callable(reference):
            ref_callable = reference
            for k in range(N):
                events.setdefault(k, []).append(("rt", None))
        else:
            tr, Cr = _rotations(reference, "reference")
            add("rt", _epoch_index(t, tr, "reference"), Cr)
    if not events:
        raise NavlibInputError("gnss: no measurements; give GNSS (or aiding) data")
    update_idx = np.array(sorted(events))

    # windows: boundaries at update samples at least window_s apart (last sample closes)
    bounds = [0]
    for k in update_idx:
        if k > bounds[-1] and t[k] - t[bounds[-1]] >= window_s - 1e-9:
            bounds.append(int(k))
    if bounds[-1] != N - 1:
        bounds.append(N - 1)

    params = {g: np.zeros(3) for g in fam.decay}
    for g, v in (initial_parameters or {}).items():
        if g not in params:
            raise NavlibInputError(f"initial_parameters: model has no parameter group {g!r}")
        params[g] = finite_array(v, f"initial_parameters[{g!r}]", (3,)).copy()
    x = np.zeros(n)                      # error-state mean (kept states persist)
    reset = np.ones(n, dtype=bool)
    reset[fam.kept] = False
    kept = fam.kept
    pos_i, vel_i, att_i = fam.idx["pos"], fam.idx["vel"], fam.idx["att"]
    att_body = model == "ecef21" and opts.get("attitude_error", "ecef") == "body"
    s = fam.nav_sign

    def corrected(r, v, C, dx):
        """Nominal (K, ...) corrected with error-state means dx (K, n)."""
        r2 = r + s * dx[:, pos_i]
        v2 = v + s * dx[:, vel_i]
        E = _exp(dx[:, att_i])
        C2 = C @ E if att_body else E @ C
        return r2, v2, C2

    out_t, out_r, out_v, out_C, out_sig, out_P = [], [], [], [], [], []
    out_par = {g: [] for g in params}
    out_kept, out_innov, out_nis, out_dof = [], [], [], []
    m_all = len(meas_names)
    state = (r0, v0, C0)
    from navlib import strapdown

    for w0, w1 in itertools.pairwise(bounds):
        sl = slice(w0, w1 + 1)
        tw = t[sl]
        f_c, w_c = fam.correct_imu(params, f_meas[sl], w_meas[sl], tw - tw[0])
        nav = strapdown.integrate(tw, f_c, w_c, state[0], state[1], state[2])
        Cw = nav.attitude.as_matrix()
        A, G, Hw = fam.jacobians(tw, nav.position, Cw, f_c, w_c)
        if extra_vel:
            Hv = np.zeros((tw.size, 3, n))
            Hv[:, :, vel_i] = np.eye(3)
            Hw = np.concatenate([Hw, Hv], axis=1)
        F, Q = discretize_steps(A[:-1], G[:-1], Qc, np.diff(tw),
                                method="euler" if method == "euler" else "series")
        rec = []   # (local index, dx, P)
        for j in range(tw.size):
            k = w0 + j
            if k in events and (j > 0 or k == 0):
                zs, sel = [], []
                for kind, value in events[k]:
                    if kind not in rows:
                        continue
                    C_hat = Cw[j]
                    if kind == "gnss_pos":
                        gps = value
                        if model == "launcher":
                            z = nav.position[j] - gps
                            if "bp" in params:
                                z = z - params["bp"] * np.exp(fam.decay["bp"] * (tw[j] - tw[0]))
                        else:
                            z = gps - nav.position[j]
                    elif kind == "gnss_vel":
                        z = (nav.velocity[j] - value if model == "launcher"
                             else value - nav.velocity[j])
                    elif kind == "att":
                        z = _rotvec(value @ C_hat.T)
                    else:   # rt
                        if ref_callable is not None:
                            C_ref = np.asarray(ref_callable(k, t[k], ref_nav), dtype=float)
                        else:
                            C_ref = value
                        z = _rotvec(C_hat.T @ C_ref)
                    zs.append(z)
                    sel.append(rows[kind])
                if sel:
                    sel = np.concatenate(sel)
                    z = np.concatenate(zs)
                    Hk = Hw[j][sel]
                    Rk = R_model[np.ix_(sel, sel)]
                    innov = z - Hk @ x
                    P, K, S_pinv, dof = _joseph_update(P, Hk, Rk, innov)
                    x = x + K @ innov
                    full = np.full(m_all, np.nan)
                    full[sel] = innov
                    if ref_callable is not None:
                        ref_nav = _exp(x[att_i]) @ Cw[j]      # posterior navigation attitude
                    rec.append((j, x.copy(), P.copy() if keep_covariance else None,
                                np.sqrt(np.clip(np.diag(P), 0, None)), full,
                                float(innov @ S_pinv @ innov), dof))
            if j < tw.size - 1:
                x_next = F[j] @ x
                if kept.size:
                    # the closed loop drives the kept (RT) states with the error of the
                    # corrected navigation, x[reset] - x_hat[reset]: no mean drive from
                    # the not-yet-fed-back estimate of the reset states
                    x_next[kept] = F[j][np.ix_(kept, kept)] @ x[kept]
                x = x_next
                P = _sym(F[j] @ P @ F[j].T + Q[j])
        # record the corrected estimates of this window's updates
        if rec:
            jj = np.array([r[0] for r in rec])
            dx = np.array([r[1] for r in rec])
            r2, v2, C2 = corrected(nav.position[jj], nav.velocity[jj], Cw[jj], dx)
            out_t.append(tw[jj])
            out_r.append(r2)
            out_v.append(v2)
            out_C.append(C2)
            for g in params:
                nominal = params[g][None, :] * np.exp(fam.decay[g][None, :]
                                                      * (tw[jj] - tw[0])[:, None])
                out_par[g].append(nominal + dx[:, fam.idx[g]])
            out_kept.append(dx[:, fam.kept])
            out_sig.append(np.array([r[3] for r in rec]))
            if keep_covariance:
                out_P.append(np.array([r[2] for r in rec]))
            out_innov.append(np.array([r[4] for r in rec]))
            out_nis.append(np.array([r[5] for r in rec]))
            out_dof.append(np.array([r[6] for r in rec]))
        # feedback at the window end
        r_end, v_end, C_end = corrected(nav.position[-1:], nav.velocity[-1:], Cw[-1:], x[None])
        state = (r_end[0], v_end[0], C_end[0])
        span = tw[-1] - tw[0]
        for g in params:
            params[g] = params[g] * np.exp(fam.decay[g] * span) + x[fam.idx[g]]
        x = np.where(reset, 0.0, x)

    cat = np.concatenate
    return EKFResult(
        t=cat(out_t), position=cat(out_r), velocity=cat(out_v), C_b_e=cat(out_C),
        parameters={g: cat(v) for g, v in out_par.items()},
        kept=cat(out_kept), sigma=cat(out_sig), P=cat(out_P) if keep_covariance else None,
        innovation=cat(out_innov), nis=cat(out_nis), nis_dof=cat(out_dof),
        state_names=tuple(fam.state_names), measurement_names=tuple(meas_names),
        kept_names=tuple(fam.state_names[i] for i in fam.kept), model=model,
    )


class ReferenceTrajectory:
    """Reference-trajectory attitudes for the RT pseudo-measurement in EKF simulations.

    The launcher flies the true trajectory ``C(t)``; the on-board reference attitude
    differs from it by the divergence ``d`` (body axes): ``C_ref = C exp(S(d))``, so that
    ``rotvec(C_hat' C_ref) = T_E^B psi + d`` is Beaudoin's eq. (8). ``d`` is the
    ``psi_ref`` block of the closed-loop attitude dynamics of the RT augmentation
    (spec launcher.md §3.4, :func:`navlib.models.launcher.rt_dynamics_matrix`),
    ``x_a' = M x_a + a1_sign [T_E^B psi; 0] + [0; omega_wind]``, integrated with the
    paper's Euler steps. It is driven by white wind rates of ``sigma_wind`` rad/s per
    sample and by the **actual** navigation attitude error ``psi`` of the filter that calls
    it (``C = (I + S(psi)) C_nav``: the control steers with the navigation attitude), so
    truth and filter model agree. Outliers on the ``rt`` channels are added to the emitted
    ``d`` only (the stored reference is wrong, the vehicle is not).

    Call it as ``reference(k, t_k, C_nav_prev)`` at increasing IMU samples, with the
    navigation attitude the control used since the previous call (the posterior after that
    call's update; None at the first call) — what :func:`ekf` does. ``history()`` returns
    the true divergence at the calls.
    """

    def __init__(self, trajectory, *, sigma_wind: float = 0.01, a1_sign: float = 1.0,
                 seed=None, rng=None, outliers=None, noise: bool = True):
        from navlib.models.launcher import rt_dynamics_matrix

        self._C = trajectory.attitude.as_matrix()
        self._t = np.asarray(trajectory.t, dtype=float)
        self._M = rt_dynamics_matrix()
        self._sigma = finite_scalar(sigma_wind, "sigma_wind", 0.0)
        if a1_sign not in (1, -1, 1.0, -1.0):
            raise NavlibInputError(f"a1_sign: expected +1 or -1, got {a1_sign}")
        self._a1 = float(a1_sign)
        self._rng = rng if rng is not None else np.random.default_rng(seed)
        self._noise = bool(noise)
        outliers = as_outliers(outliers)
        self._add = np.stack([channel_profile(outliers, f"rt_{a}", self._t) for a in _AXES],
                             axis=1)
        self._x = np.zeros(10)
        self._last = None        # sample index of the previous call
        self._hist_t, self._hist_d = [], []

    def __call__(self, k, t_k, C_nav_prev):
        k = int(k)
        if self._last is not None:
            k_prev = self._last
            if k <= k_prev:
                raise NavlibInputError("reference: calls must come at increasing samples")
            dt = self._t[k] - self._t[k_prev]
            drive = np.zeros(10)
            if C_nav_prev is not None:
                C_prev = self._C[k_prev]
                psi = _rotvec(C_prev @ np.asarray(C_nav_prev).T)
                drive[:3] = self._a1 * (C_prev.T @ psi)
            if self._noise and self._sigma > 0:
                drive[7:] = self._sigma * self._rng.standard_normal(3)
            self._x = self._x + dt * (self._M @ self._x + drive)
        self._last = k
        d = self._x[7:].copy()
        self._hist_t.append(self._t[k])
        self._hist_d.append(d)
        return self._C[k] @ _exp(d + self._add[k])

    def history(self) -> pd.DataFrame:
        """True divergence ``d`` (body axes, rad) at the calls: ``t, ref_x, ref_y, ref_z``."""
        d = np.array(self._hist_d).reshape(-1, 3)
        return pd.DataFrame({"t": np.array(self._hist_t), "ref_x": d[:, 0], "ref_y": d[:, 1],
                             "ref_z": d[:, 2]})


def simulate_attitude_sensor(trajectory, sigma: float, rate_hz: float | None = None,
                             seed=None, *, rng=None, outliers=None):
    """Attitude-sensor fixes ``C_att = exp(S(n)) C`` with white ECEF-axis noise ``n``.

    Generic attitude reference sensor of Beaudoin et al. §2.2 (white noise only, Table 1:
    1 deg per axis); ``att`` outliers (:mod:`navlib.outliers`) are added to ``n``.

    Returns
    -------
    t : ndarray (K,)
    C_att : ndarray (K, 3, 3)
        Measured body -> ECEF attitudes.
    """
    sigma = finite_scalar(sigma, "sigma", 0.0)
    rng = rng if rng is not None else np.random.default_rng(seed)
    idx = (np.arange(len(trajectory.t)) if rate_hz is None
           else trajectory.at_rate(finite_scalar(rate_hz, "rate_hz", 0.0, low_open=True)))
    t = np.asarray(trajectory.t, dtype=float)[idx]
    noise = sigma * rng.standard_normal((idx.size, 3))
    from navlib.outliers import inject

    noise = inject(noise, t, as_outliers(outliers), "att")
    return t, _exp(noise) @ trajectory.attitude[idx].as_matrix()


@dataclass(frozen=True, eq=False)
class EKFRun:
    """One simulated EKF run: the result and what it was fed.

    Attributes
    ----------
    result : EKFResult
    errors : DataFrame
        ``result.errors(trajectory)``.
    truth_parameters : dict
        True parameter histories at the result epochs in the model's convention (``bg``,
        ``ba`` body-axis biases; ``bp`` minus the GPS position bias).
    reference : DataFrame or None
        True launcher divergence (RT solutions).
    initial_error : ndarray (n_nav,)
        The drawn initial navigation error (position, velocity, attitude).
    """

    result: EKFResult
    errors: pd.DataFrame
    truth_parameters: dict
    reference: pd.DataFrame | None
    initial_error: np.ndarray


def simulate_ekf(trajectory, *, sensors="launcher_table1", model: str = "launcher",
                 solution: str = "ins_gps", biases: str = "GA", bias_model: str = "markov",
                 model_options: dict | None = None, gnss_rate_hz: float | None = None,
                 outliers=None, seed=None, initial_error: bool = True, noise: bool = True,
                 window_s: float = 0.1, keep_covariance: bool = False,
                 gnss_velocity_sigma: float | None = None) -> EKFRun:
    """Simulate sensors along ``trajectory``, inject outliers and run :func:`ekf`.

    The IMU and GNSS come from :func:`navlib.sensors.simulate_imu` /
    :func:`~navlib.sensors.simulate_gnss` with the preset ``sensors``; the attitude sensor
    from :func:`simulate_attitude_sensor` (the preset's sigma), the reference trajectory from
    :class:`ReferenceTrajectory`. ``outliers`` are added to those data (EKF-mode injection of
    :mod:`navlib.outliers`). The initial nominal state is the truth perturbed by a draw from
    the model's ``P0`` navigation block (``initial_error``). With ``noise=False`` the
    sensors are error-free (a deterministic run, e.g. to isolate an outlier response).

    Seeds: one ``numpy.random.SeedSequence(seed)`` spawns independent streams for the IMU,
    GNSS, attitude sensor, reference trajectory and initial error, so a run with an
    outlier and one without share every noise realisation.

    Parameters
    ----------
    trajectory : Trajectory
        Truth; the IMU samples are its samples.
    sensors : str or navlib.sensors.SensorSpec
        Sensor preset of the simulated data (default ``launcher_table1``). The GNSS
        position bias is simulated only when the filter estimates it (launcher ``P``), so
        truth and filter model agree; for ``ecef21`` the model's noise densities default to
        the same preset.
    model, solution, biases, bias_model, model_options, window_s, keep_covariance,
    gnss_velocity_sigma
        As in :func:`ekf`.
    gnss_rate_hz : float, optional
        GNSS fix rate (default the preset's; the paper's launcher uses every sample).
    outliers : Outlier or sequence of Outlier, optional
    seed : int, optional
    initial_error, noise : bool

    Returns
    -------
    EKFRun
    """
    from navlib import sensors as sensor_lib
    from navlib import strapdown
    from navlib.outliers import inject

    outliers = as_outliers(outliers)
    spec = sensor_lib.load_preset(sensors) if isinstance(sensors, str) else sensors
    seq = np.random.SeedSequence(seed)
    g_imu, g_gnss, g_att, g_ref, g_init = (np.random.default_rng(s) for s in seq.spawn(5))
    if model != "launcher" or "P" not in biases.upper():
        # truth matches the filter model: no GNSS position bias unless it is estimated
        from dataclasses import replace

        spec = replace(spec, gnss=replace(spec.gnss, position_bias_markov=0.0))
    if noise:
        imu = sensor_lib.simulate_imu(trajectory, spec, rng=g_imu)
        gnss = sensor_lib.simulate_gnss(trajectory, spec, rate_hz=gnss_rate_hz, rng=g_gnss,
                                        with_errors=True)
    else:
        quiet = sensor_lib.SensorSpec(name="noise-free", source="",
                                      imu=sensor_lib.ImuSpec(),
                                      gnss=sensor_lib.GnssSpec(rate_hz=spec.gnss.rate_hz))
        imu = sensor_lib.simulate_imu(trajectory, quiet, rng=g_imu)
        gnss = sensor_lib.simulate_gnss(trajectory, quiet, rate_hz=gnss_rate_hz, rng=g_gnss,
                                        with_errors=True)
    t = imu.t
    imu_df = pd.DataFrame({"t": t})
    f_b = inject(imu.f_b, t, outliers, "accel")
    w_b = inject(imu.w_ib_b, t, outliers, "gyro")
    for i, a in enumerate(_AXES):
        imu_df[f"f_{a}"] = f_b[:, i]
    for i, a in enumerate(_AXES):
        imu_df[f"w_{a}"] = w_b[:, i]
    tg = gnss["t"].to_numpy(float)
    gnss = gnss.copy()
    gnss[["x", "y", "z"]] = inject(gnss[["x", "y", "z"]].to_numpy(), tg, outliers, "gnss_pos")
    gnss[["vx", "vy", "vz"]] = inject(gnss[["vx", "vy", "vz"]].to_numpy(), tg, outliers,
                                      "gnss_vel")

    opts = dict(model_options or {})
    if model == "ecef21" and isinstance(sensors, str):
        opts.setdefault("sensors", sensors)      # the filter assumes the simulated sensors
    attitude = reference = None
    if model == "launcher" and solution.startswith("ins_gps_att"):
        sigma_att = opts.get("sigma_att", spec.attitude_sigma or 0.0)
        attitude = simulate_attitude_sensor(trajectory, sigma_att if noise else 0.0, rng=g_att,
                                            outliers=outliers)
    if model == "launcher" and solution.endswith("_rt"):
        from navlib.models.launcher import ASSUMED

        reference = ReferenceTrajectory(
            trajectory, sigma_wind=opts.get("sigma_wind", ASSUMED["sigma_wind"]),
            a1_sign=opts.get("a1_sign", 1.0), rng=g_ref, outliers=outliers, noise=noise)

    # initial error from the model's P0 navigation block (the model's sign convention)
    truth0 = strapdown.StrapdownState.from_trajectory(trajectory, 0)
    probe = _BlockTrajectory(t[:2], trajectory.position[:2], trajectory.attitude[:2].as_matrix(),
                             trajectory.specific_force[:2], trajectory.angular_rate[:2])
    if model == "launcher":
        fopts = {**opts, "solution": solution, "biases": biases, "bias_model": bias_model,
                 "s_t": float(np.median(np.diff(t)))}
    else:
        fopts = opts
    fam = _family(model, probe, fopts)
    nav = np.concatenate([fam.idx["pos"], fam.idx["vel"], fam.idx["att"]])
    P_nav = fam.model.P0[np.ix_(nav, nav)]
    dx0 = (g_init.standard_normal(9) @ _psd_sqrt(P_nav).T) if initial_error else np.zeros(9)
    s = fam.nav_sign
    C0 = trajectory.attitude[0].as_matrix()
    body = model == "ecef21" and opts.get("attitude_error", "ecef") == "body"
    C_hat0 = C0 @ _exp(-dx0[6:9]) if body else _exp(-dx0[6:9]) @ C0
    # error = s (true - estimate) for position/velocity; C_true = exp(S(psi)) C_hat
    initial = strapdown.StrapdownState(
        t=truth0.t, position=truth0.position - s * dx0[:3],
        velocity=truth0.velocity - s * dx0[3:6],
        q_b_e=_as_quat(C_hat0))
    result = ekf(imu_df, gnss, initial=initial, model=model, solution=solution, biases=biases,
                 bias_model=bias_model, model_options=opts, attitude=attitude,
                 reference=reference, window_s=window_s, keep_covariance=keep_covariance,
                 gnss_velocity_sigma=gnss_velocity_sigma)
    k = _epoch_index(t, result.t, "result")
    truth_par = {}
    if "bg" in fam.idx:
        truth_par["bg"] = imu.gyro.bias[k]
    if "ba" in fam.idx:
        truth_par["ba"] = imu.accel.bias[k]
    if "bp" in fam.idx:
        kg = np.searchsorted(tg, result.t)
        kg = np.clip(kg, 0, tg.size - 1)
        truth_par["bp"] = -gnss[["bias_x", "bias_y", "bias_z"]].to_numpy()[kg]
    return EKFRun(result, result.errors(trajectory), truth_par,
                  reference.history() if reference is not None else None, dx0)


def _as_quat(C) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    return Rotation.from_matrix(C).as_quat()
