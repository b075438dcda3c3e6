"""Preparation of the linear error-state filter: a model at its steps and its Kalman
covariance and gains, computed once (docs/assumptions.md, launcher.md §6.2; Beaudoin et al. 2018 eq.
1).

:func:`linear_steps` discretises a model (Euler as in the paper, or the zero-order-hold
exponential); :func:`prepare_linear` runs the covariance recursion
(:func:`navlib.kalman.covariance_recursion`, Joseph form) once and keeps the gains,
shared by every Monte-Carlo run of :func:`navlib.filters.linear.simulate_linear`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np
from threadpoolctl import threadpool_limits

from navlib._validation import finite_array
from navlib.covariance import CovarianceResult
from navlib.discretize import discretize_steps
from navlib.errors import NavlibInputError
from navlib.kalman import (
    PINV_RTOL,
    FactoredNoise,
    Gains,
    covariance_recursion,
    nees_basis,
    psd_sqrt,
    symmetrize,
)
from navlib.models.base import DiscreteModel, LinearModel

__all__ = ["METHODS", "ONE_THREAD", "LinearFilter", "LinearSteps", "linear_steps", "prepare_linear"]

METHODS = ("euler", "expm")

ONE_THREAD = 1
"""BLAS threads of the covariance recursion and of the simulation (``threadpoolctl``).
Their matrices are small (n <= 30) and come one step or one epoch at a time: OpenBLAS's
threads inside each of those calls only synchronise, and on a loaded machine a batched
eigen-decomposition of the recorded covariances ran up to 25 times slower with them
(notebook 05 profile). One thread gives the same numbers."""


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
                 noise_names: Sequence[str] = (), with_q: bool = True,
                 own_model: bool = False) -> LinearSteps:
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
    own_model : bool
        The Euler form may overwrite the model's time-varying ``A`` and ``G`` (N, ., .)
        with ``F`` and ``Gamma`` (the same products, in place): for a model built only to
        be prepared, which is not used afterwards (:class:`navlib.studies.outliers.
        FilterCache`). Saves two new arrays of the model's size, whose first touch (about
        0.3-0.6 s for the 190 MB ``F`` of a 28-state model at 200 Hz over 150 s on a busy
        machine) cost more than their products.
    """
    if method not in METHODS:
        raise NavlibInputError(f"method: expected one of {METHODS}, got {method!r}")
    if isinstance(model, LinearModel):
        if model.t is None:
            raise NavlibInputError(
                "model: a constant LinearModel has no time axis; call model.discretize(dt_s=..., "
                "n_epochs=...) and pass the DiscreteModel"
            )
        t = np.asarray(model.t, dtype=float)
        N, n = t.size, model.n
        A = np.broadcast_to(model.A, (N, n, n))[:-1]
        G = np.broadcast_to(model.G, (N, *model.G.shape[-2:]))[:-1]
        dt = np.diff(t)
        Qc = np.asarray(model.Qc, dtype=float)
        if method == "euler":
            step = dt[:, None, None]
            F = _in_place(model.A, own_model)
            F = np.multiply(A, step, out=F)
            F += np.eye(n)                   # in place: the same sums as eye + A dt
            L = G @ psd_sqrt(Qc)             # before Gamma, which may overwrite G
            L *= np.sqrt(dt)[:, None, None]  # in place: one (N-1, n, q) array, not two
            Gamma = np.multiply(G, step, out=_in_place(model.G, own_model))
            Q = FactoredNoise(L)[:] if with_q else None
        else:
            F, Q = discretize_steps(A, G, Qc, dt, method="series")
            Gamma = _phi1_series(A, dt) @ G
            L = psd_sqrt(Q)
        H = np.broadcast_to(model.H, (N, *model.H.shape[-2:]))
        R = np.broadcast_to(model.R, (N, *model.R.shape[-2:]))
        P0 = model.P0 if P0 is None else P0
        names = (model.state_names, tuple(model.measurement_names), tuple(model.noise_names))
    elif isinstance(model, DiscreteModel):
        t, F, Q, H, R = model.t, model.F, model.Q, model.H, model.R
        L = psd_sqrt(Q)
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


def _in_place(matrices, own: bool):
    """The first N-1 of the model's own time-varying ``matrices`` (N, ., .) to overwrite
    (``own``, and they are a writable C-contiguous stack), else None (a new array)."""
    matrices = np.asarray(matrices)
    if own and matrices.ndim == 3 and matrices.dtype == float and matrices.flags.writeable \
            and matrices.flags.c_contiguous:
        return matrices[:-1]
    return None


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
                   compact: bool = False, own_model: bool = False) -> LinearFilter:
    """Discretise a model and run its Kalman covariance recursion once.

    Parameters as in :func:`simulate_linear`. The covariance is that of
    :func:`navlib.covariance.kalman_covariance` (Joseph form), and the gains are those of
    :func:`navlib.kalman.kalman_gains` from its priors, both from one recursion
    (:func:`_blockwise_covariance`). BLAS runs on one thread here (:data:`ONE_THREAD`).

    ``compact=True`` keeps what :func:`simulate_linear` needs and drops the rest: the
    filter keeps no prior covariances
    (``covariance.P_prior`` is None) and no process noise (``steps.Q`` is None; the noise
    is sampled through ``steps.L``; the Euler ``Q`` is never formed whole). For a 28-state
    model at 200 Hz over 150 s that is about 0.8 GB held instead of 1.2 GB, and about
    1.2 GB at most while preparing (the model's own matrices included) instead of 1.7 GB.
    ``own_model=True``: the model was built for this preparation only and may be
    overwritten (:func:`linear_steps`); the filter then holds no new ``F`` or noise input.
    """
    if isinstance(model, LinearFilter):
        return model
    steps = linear_steps(model, method=method, P0=P0, noise_input=noise_input,
                         noise_names=noise_names, with_q=not compact, own_model=own_model)
    mask = _measured_mask(steps.t.size, update_every, measured)
    with threadpool_limits(ONE_THREAD):
        cov, gains = _blockwise_covariance(steps, mask, priors=not compact)
    if compact:
        steps = replace(steps, Q=None)
    return LinearFilter(steps, mask, gains, cov)


def _blockwise_covariance(steps: LinearSteps, mask, block: int = 2048, priors: bool = False):
    """:func:`navlib.covariance.kalman_covariance` and its gains in one recursion.

    The recursion (:func:`navlib.kalman.covariance_recursion`) keeps the gain of each update
    (the :func:`navlib.kalman.kalman_gains` of its prior, to the bit) and reads the
    process noise ``block`` epochs at a time; when ``steps.Q`` is None it forms ``Q = L L'``
    one block at a time (:class:`navlib.kalman.FactoredNoise`), and without ``priors`` it
    keeps no prior covariances. Returns ``(CovarianceResult, Gains)``.
    """
    noise = FactoredNoise(steps.L) if steps.Q is None else steps.Q
    P_prior, P_post, gains = covariance_recursion(
        steps.F, noise, steps.H, steps.R, steps.P0[None], mask, PINV_RTOL, priors=priors,
        gains=True, block=block)
    cov = CovarianceResult(steps.t, None if P_prior is None else P_prior[0], P_post[0],
                           mask.copy(), tuple(steps.state_names))
    return cov, Gains(gains.K[0], gains.S_pinv[0], gains.dof[0])
