"""Kalman covariance analysis: recursion, frames, correlation and normalised eigen-analysis.

* :func:`kalman_covariance` — the covariance recursion of a linear Kalman filter
  ``P-_{k+1} = F_k P+_k F_k' + Q_k`` and the Joseph-form update
  ``P+ = (I - K H) P- (I - K H)' + K R K'`` with ``K = P- H' S^+`` (spec launcher.md §6.2,
  ssac.md §8 item 6). ``S^+`` is the inverse of the innovation covariance when ``R`` is
  positive definite, else its pseudo-inverse, so ideal (noise-free) measurements ``R = 0``
  are handled exactly (the "ideal-GPS variant", launcher.md §6.2 item 5).
* :func:`ins_only_covariance` — the unaided baseline (launcher.md §6.2 item 1).
* :func:`block_in_frame`, :func:`sigma_in_frame` — a 3x3 block rotated per step, e.g. the
  attitude error in body axes ``P_body = T_E^B P_psipsi T_B^E`` (launcher.md §6.2 item 6).
* :func:`correlation`, :func:`group_correlation` — ``rho_ij(k)`` and per-axis correlation
  of two rotated groups (launcher.md §6.3).
* :func:`normalized_eigen` — the Ham & Brown (1983) normalised covariance eigen-analysis
  (ssac.md §3.6, Silva et al. 2017 eqs. 45–46) with sign-consistent tracking through
  near-degenerate eigenvalues.
* :func:`covariance_ratio`, :func:`convergence_time` — the PSINS-style "observability
  degree" ``sigma_i(t0)/sigma_i(t)`` and time-to-converge metrics (ssac.md §8 item 7).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.optimize import linear_sum_assignment

from navlib._validation import finite_array, finite_scalar
from navlib.errors import NavlibInputError
from navlib.kalman import (
    Gains,
    definite_noise,
    kernel_array,
    riccati_kernel,
    symmetrize,
)
from navlib.models.base import DiscreteModel, _indices

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
    "symmetrize",
]


def _names(state_names, n: int) -> tuple[str, ...]:
    if state_names is None:
        return tuple(f"x{i}" for i in range(n))
    names = tuple(str(s) for s in state_names)
    if len(names) != n:
        raise NavlibInputError(f"state_names: expected {n} names, got {len(names)}")
    return names


def _stack(value, count: int, shape: tuple, name: str) -> np.ndarray:
    """One matrix broadcast to ``count`` copies, or a stack of ``count`` matrices."""
    arr = finite_array(value, name)
    if arr.ndim == 2 and arr.shape == shape:
        return np.broadcast_to(arr, (count, *shape))
    if arr.ndim == 3 and arr.shape == (count, *shape):
        return arr
    raise NavlibInputError(
        f"{name}: expected shape {shape} or ({count}, {shape[0]}, {shape[1]}), got {arr.shape}"
    )


@dataclass(frozen=True, eq=False)
class CovarianceResult:
    """Covariance history of a Kalman filter at its epochs.

    Attributes
    ----------
    t : ndarray (N,)
        Epoch times, s.
    P_prior, P_post : ndarray (N, n, n)
        Covariance before and after the measurement update at each epoch (equal at epochs
        without an update).
    measured : ndarray (N,) of bool
        Epochs at which an update was made.
    state_names : tuple of str
    """

    t: np.ndarray
    P_prior: np.ndarray
    P_post: np.ndarray
    measured: np.ndarray
    state_names: tuple[str, ...]

    @property
    def n(self) -> int:
        return len(self.state_names)

    @property
    def sigma(self) -> np.ndarray:
        """Posterior standard deviations ``sqrt(diag P_post)``, (N, n)."""
        return np.sqrt(np.clip(np.diagonal(self.P_post, axis1=1, axis2=2), 0.0, None))

    @property
    def sigma_prior(self) -> np.ndarray:
        """Prior standard deviations ``sqrt(diag P_prior)``, (N, n)."""
        return np.sqrt(np.clip(np.diagonal(self.P_prior, axis1=1, axis2=2), 0.0, None))

    def index(self, names: Sequence[str]) -> np.ndarray:
        """Positions of ``names`` in ``state_names``."""
        return _indices(self.state_names, names)

    def to_frame(self, which: str = "post") -> pd.DataFrame:
        """Tidy table with columns ``t, state, sigma`` (``which`` = "post" or "prior")."""
        if which not in ("post", "prior"):
            raise NavlibInputError(f"which: expected 'post' or 'prior', got {which!r}")
        sigma = self.sigma if which == "post" else self.sigma_prior
        return pd.DataFrame({
            "t": np.repeat(self.t, self.n),
            "state": np.tile(np.array(self.state_names, dtype=object), self.t.size),
            "sigma": sigma.ravel(),
        })


def _inputs(F, Q, H, R, P0, t, n_epochs, state_names, measurements=True, stacked=False):
    """Resolve a DiscreteModel or plain arrays into stacks (N-1 F/Q, N H/R, B P0): ``P0``
    is one (n, n) matrix (B = 1), or with ``stacked`` a (B, n, n) stack or B matrices."""
    if isinstance(F, DiscreteModel):
        model = F
        Q = model.Q if Q is None else Q
        H = model.H if H is None and measurements else H
        R = model.R if R is None and measurements else R
        P0 = (model.P0 if not stacked else [model.P0]) if P0 is None else P0
        t = model.t if t is None else t
        state_names = model.state_names if state_names is None else state_names
        F = model.F
    if Q is None or P0 is None:
        raise NavlibInputError("Q and P0 are required (directly or from a DiscreteModel)")
    F = finite_array(F, "F")
    if F.ndim == 2:
        if t is None and n_epochs is None:
            raise NavlibInputError("t or n_epochs: needed when F is a single matrix")
        count = len(t) if t is not None else int(n_epochs)
        if count < 1:
            raise NavlibInputError(f"n_epochs: need at least 1 epoch, got {count}")
    elif F.ndim == 3:
        count = F.shape[0] + 1
    else:
        raise NavlibInputError(f"F: expected (n, n) or (N-1, n, n), got shape {F.shape}")
    n = F.shape[-1]
    if F.shape[-2] != n:
        raise NavlibInputError(f"F: matrices must be square, got shape {F.shape}")
    F = _stack(F, count - 1, (n, n), "F")
    Q = _stack(Q, count - 1, (n, n), "Q")
    P0 = _initial(P0, n) if stacked else finite_array(P0, "P0", shape=(n, n))[None]
    if t is None:
        t = np.arange(count, dtype=float)
    else:
        t = finite_array(t, "t", ndim=1)
        if t.size != count:
            raise NavlibInputError(f"t: expected {count} epochs, got {t.size}")
    if H is not None:
        H = finite_array(H, "H")
        m = H.shape[-2] if H.ndim >= 2 else -1
        H = _stack(H, count, (m, n), "H")
        R = _stack(R if R is not None else np.zeros((m, m)), count, (m, m), "R")
    return F, Q, H, R, symmetrize(P0), t, _names(state_names, n)


def _initial(P0, n: int) -> np.ndarray:
    """Initial covariances as a (B, n, n) stack, B >= 1."""
    P0 = finite_array(P0, "P0")
    if P0.ndim != 3 or P0.shape[0] < 1 or P0.shape[1:] != (n, n):
        raise NavlibInputError(f"P0: expected B >= 1 initial covariances of shape ({n}, {n}), "
                               f"got shape {P0.shape}")
    return P0


def _epochs_measured(measured, count: int, update_first: bool, has_h: bool) -> np.ndarray:
    """The update epochs of :func:`kalman_covariance` (all by default, epoch 0 only when
    ``update_first``; none without ``H``)."""
    if measured is None:
        measured = np.ones(count, dtype=bool)
        measured[0] = bool(update_first)
    else:
        measured = np.asarray(measured, dtype=bool)
        if measured.shape != (count,):
            raise NavlibInputError(f"measured: expected {count} booleans, got {measured.shape}")
        measured = measured.copy()
        if not update_first:
            measured[0] = False
    if not has_h:
        measured[:] = False
    return measured


class FactoredNoise:
    """Process noise ``Q_k = L_k L_k'`` held as its factor ``L`` (N-1, n, q) and formed a
    slice of steps at a time (``noise[a:b]``), so a long high-rate model never holds the
    whole ``Q`` stack (:func:`navlib.filters.linear.prepare_linear` with ``compact=True``)."""

    def __init__(self, L):
        self.L = np.asarray(L, dtype=float)

    def __getitem__(self, steps: slice) -> np.ndarray:
        L = self.L[steps]
        return L @ L.swapaxes(-1, -2)


def _recursion(F, Q, H, R, P0, measured, pinv_rtol: float, *, priors: bool = True,
               gains: bool = False, block: int = 2048, keep=None):
    """The Joseph-form recursion of :func:`kalman_covariance` for a stack of initial
    covariances ``P0`` (B, n, n) sharing ``F, Q, H, R``.

    Each member runs the compiled recursion
    :func:`navlib.kalman.riccati_kernel` (the prediction and Joseph update of
    every caller), so the members of a stack have the histories of their own runs, to the
    bit. The noise test of every epoch's ``R`` is one batched call before the loop. ``F``,
    ``H``, ``R`` and ``Q`` are read ``block`` steps at a time (``Q`` an array or a
    :class:`FactoredNoise`; a broadcast matrix is copied one block at a time).

    Returns ``(P_prior, P_post, Gains)``: ``P_prior`` (B, N, n, n) or None without
    ``priors``, ``P_post`` (B, N, n, n), or (B, K, n, n) at the K distinct epochs ``keep``
    in ascending order (negative indices from the end: a reader of a few epochs holds no
    history), and with ``gains`` the
    :class:`~navlib.kalman.Gains` of the updates, (B, N, ...) stacks (zero gain,
    ``S_pinv`` and dof at epochs without update), else None. These are the gains
    :func:`navlib.kalman.kalman_gains` computes from the priors, to the bit (the
    same compiled kernel; docs/assumptions.md "Compiled kernels").
    """

    count, (batch, n) = measured.size, P0.shape[:2]
    m = 0 if H is None else H.shape[-2]
    if H is None:
        r_definite = np.zeros(count, dtype=bool)
    else:
        r_definite = definite_noise(R) if count else np.zeros(0, dtype=bool)
    update, r_definite = kernel_array(measured, np.bool_), kernel_array(r_definite, np.bool_)
    P_prior = np.empty((batch, count, n, n)) if priors else np.empty((batch, 0, n, n))
    kept = range(count) if keep is None else np.unique(np.asarray(keep, dtype=int) % max(count, 1))
    slot = np.full(count, -1, dtype=np.int64)
    slot[kept] = np.arange(len(kept))
    P_post = np.empty((batch, len(kept), n, n))
    rows = count if gains else 0
    K = np.zeros((batch, rows, n, m))
    S_pinv = np.zeros((batch, rows, m, m))
    dof = np.zeros((batch, rows), dtype=np.int64)
    P = np.array(P0, dtype=float)
    for a in range(0, count, block):
        b, q0 = min(count, a + block), max(a - 1, 0)
        F_block, Q_block = kernel_array(F[q0:b - 1]), kernel_array(Q[q0:b - 1])
        if H is None:
            H_block, R_block = np.zeros((b - a, 0, n)), np.zeros((b - a, 0, 0))
        else:
            H_block, R_block = kernel_array(H[a:b]), kernel_array(R[a:b])
        for j in range(batch):
            P[j] = riccati_kernel(P[j], F_block, Q_block, H_block, R_block, r_definite[a:b],
                                  update[a:b], pinv_rtol, a, P_prior[j, a:b] if priors
                                  else P_prior[j], slot[a:b], P_post[j], K[j, a:b],
                                  S_pinv[j, a:b], dof[j, a:b])
    return (P_prior if priors else None, P_post,
            Gains(K, S_pinv, dof) if gains else None)


def kalman_covariances(F, Q=None, H=None, R=None, P0=None, *, update_first: bool = True,
                       measured=None, t=None, n_epochs: int | None = None,
                       state_names=None, pinv_rtol: float = 1e-12) -> list[CovarianceResult]:
    """:func:`kalman_covariance` for several initial covariances sharing ``F, Q, H, R``.

    The points of an assumption set that differ only in ``P0`` (initial sigmas) share the
    model; their recursions run as one, stacked over the initial covariances, and give the
    same histories as separate :func:`kalman_covariance` calls, to the bit, at a fraction
    of the per-step cost.

    Parameters
    ----------
    F, Q, H, R, update_first, measured, t, n_epochs, state_names, pinv_rtol
        As :func:`kalman_covariance` (``H`` None: INS-only, as :func:`ins_only_covariance`).
    P0 : ndarray (B, n, n) or sequence of B (n, n) arrays
        The initial covariances (default: the DiscreteModel's one).

    Returns
    -------
    list of CovarianceResult
        One per initial covariance, in order.
    """
    return _run(F, Q, H, R, P0, update_first, measured, t, n_epochs, state_names, pinv_rtol,
                stacked=True)


def _run(F, Q, H, R, P0, update_first, measured, t, n_epochs, state_names, pinv_rtol,
         stacked: bool) -> list[CovarianceResult]:
    """Validate the inputs of :func:`kalman_covariances` (``stacked``) or
    :func:`kalman_covariance` and run :func:`_recursion`."""
    F, Q, H, R, P0, t, names = _inputs(F, Q, H, R, P0, t, n_epochs, state_names,
                                       stacked=stacked)
    pinv_rtol = finite_scalar(pinv_rtol, "pinv_rtol", 0.0, 1.0)
    measured = _epochs_measured(measured, t.size, update_first, H is not None)
    P_prior, P_post, _ = _recursion(F, Q, H, R, P0, measured, pinv_rtol)
    return [CovarianceResult(t, prior, post, measured, names)
            for prior, post in zip(P_prior, P_post, strict=True)]


def kalman_covariance(F, Q=None, H=None, R=None, P0=None, *, update_first: bool = True,
                      measured=None, t=None, n_epochs: int | None = None,
                      state_names=None, pinv_rtol: float = 1e-12) -> CovarianceResult:
    """Kalman-filter covariance recursion with the Joseph-form update.

    Parameters
    ----------
    F : ndarray (N-1, n, n) or (n, n), or DiscreteModel
        Transition matrices, ``F[k]`` maps epoch k to k+1. A :class:`DiscreteModel`
        supplies ``F, Q, H, R, P0, t, state_names`` (explicit arguments override).
    Q : ndarray (N-1, n, n) or (n, n)
        Process noise added over each step.
    H : ndarray (N, m, n) or (m, n), optional
        Measurement matrices; None for no measurements (INS-only).
    R : ndarray (N, m, m) or (m, m), optional
        Measurement-noise covariance; may be singular or zero (ideal measurements).
    P0 : ndarray (n, n)
        Initial covariance: the prior at epoch 0 when ``update_first`` (updated there), else
        the posterior at epoch 0.
    update_first : bool
        Whether epoch 0 has a measurement update.
    measured : array of bool (N,), optional
        Epochs with an update (default: all; epoch 0 only when ``update_first``).
    t : ndarray (N,), optional
        Epoch times (default ``0, 1, ...``); with a single ``F`` it fixes ``N``.
    n_epochs : int, optional
        ``N`` when ``F`` is a single matrix and ``t`` is not given.
    state_names : sequence of str, optional
    pinv_rtol : float
        Relative cut-off of the innovation-covariance pseudo-inverse, used at epochs whose
        ``R`` is not positive definite (eigenvalues below ``pinv_rtol * max`` are dropped).

    Returns
    -------
    CovarianceResult

    Notes
    -----
    The gain ``K = P- H' S^+`` with ``S = H P- H' + R``. When ``R`` is positive definite,
    ``S^+ = S^-1``; otherwise ``S^+`` is the eigen-decomposition pseudo-inverse, which
    gives the optimal update in the measured subspace and leaves directions with ``S`` = 0
    unchanged (:func:`navlib.kalman.joseph_update`, the one implementation of
    this rule). The Joseph form holds for any gain, so the result
    stays symmetric positive semi-definite with ``R = 0`` (ideal measurements drive
    ``H P+ H'`` to zero exactly).
    """
    return _run(F, Q, H, R, P0, update_first, measured, t, n_epochs, state_names, pinv_rtol,
                stacked=False)[0]


def ins_only_covariance(F, Q=None, P0=None, *, t=None, n_epochs: int | None = None,
                        state_names=None) -> CovarianceResult:
    """Unaided covariance propagation ``P_{k+1} = F_k P_k F_k' + Q_k`` (launcher.md §6.2.1).

    Same arguments as :func:`kalman_covariance` without the measurement ones; ``P0`` is the
    covariance at epoch 0 and ``P_prior == P_post`` at every epoch.
    """
    F, Q, _, _, P0, t, names = _inputs(F, Q, None, None, P0, t, n_epochs, state_names,
                                      measurements=False)
    return kalman_covariance(F, Q, None, None, P0[0], t=t, state_names=names)


def _covariances(P) -> np.ndarray:
    if isinstance(P, CovarianceResult):
        return P.P_post
    P = finite_array(P, "P")
    if P.ndim == 2:
        P = P[None]
    if P.ndim != 3 or P.shape[1] != P.shape[2]:
        raise NavlibInputError(f"P: expected (N, n, n) covariances, got shape {P.shape}")
    return P


def _state_index(P, idx, name: str) -> np.ndarray:
    n = P.shape[-1]
    if isinstance(idx, str):
        idx = [idx]
    idx = list(idx)
    if idx and isinstance(idx[0], str):
        raise NavlibInputError(f"{name}: state names need a CovarianceResult; got arrays")
    idx = np.asarray(idx, dtype=int)
    if idx.ndim != 1 or idx.size == 0 or idx.min() < -n or idx.max() >= n:
        raise NavlibInputError(f"{name}: expected state indices in [0, {n}), got {idx}")
    return idx


def _resolve(P, idx, name: str) -> np.ndarray:
    """State indices from names (needs a CovarianceResult) or integers."""
    if isinstance(P, CovarianceResult):
        labels = [idx] if isinstance(idx, str) else list(idx)
        if labels and isinstance(labels[0], str):
            return P.index(labels)
    return _state_index(_covariances(P), idx, name)


def _rotations(C, count: int, size: int, name: str) -> np.ndarray | None:
    if C is None:
        return None
    if hasattr(C, "as_matrix"):
        C = C.as_matrix()
    C = finite_array(C, name)
    return _stack(C, count, (size, size), name)


def block_in_frame(P, states, C=None) -> np.ndarray:
    """Covariance of a group of states expressed in another frame, per epoch.

    ``P_b = C P_block C'`` with ``C`` the rotation from the states' frame to the wanted
    one, e.g. ``C = T_E^B`` turns the ECEF attitude-error block into body axes
    (spec launcher.md §6.2 item 6: ``P_body = T_E^B P_psipsi T_B^E``).

    Parameters
    ----------
    P : CovarianceResult or ndarray (N, n, n)
        Covariance history (the posterior of a result).
    states : sequence of str or int
        The group (names need a CovarianceResult), e.g. the three attitude errors.
    C : ndarray (k, k) or (N, k, k) or scipy Rotation, optional
        Rotation to apply; None keeps the frame.

    Returns
    -------
    ndarray (N, k, k)
    """
    idx = _resolve(P, states, "states")
    P = _covariances(P)
    block = P[:, idx[:, None], idx]
    C = _rotations(C, P.shape[0], idx.size, "C")
    return block if C is None else symmetrize(C @ block @ np.swapaxes(C, 1, 2))


def sigma_in_frame(P, states, C=None) -> np.ndarray:
    """Standard deviations of a rotated group, (N, k): ``sqrt(diag(C P_block C'))``.

    E.g. roll/pitch/yaw error sigma in body axes from an ECEF attitude-error block with
    ``C = T_E^B`` per epoch (spec launcher.md §6.2 item 6).
    """
    block = block_in_frame(P, states, C)
    return np.sqrt(np.clip(np.diagonal(block, axis1=1, axis2=2), 0.0, None))


def correlation(P, i=None, j=None) -> np.ndarray:
    """Correlation coefficients ``rho_ij = P_ij / sqrt(P_ii P_jj)`` over time (launcher.md §6.3).

    Parameters
    ----------
    P : CovarianceResult or ndarray (N, n, n)
    i, j : str or int, optional
        Two states; when omitted the full correlation matrices are returned.

    Returns
    -------
    ndarray (N,) for a pair, (N, n, n) otherwise. Entries with a zero variance are NaN.
    """
    if (i is None) != (j is None):
        raise NavlibInputError("i, j: give both states or neither")
    if i is not None:
        a = _resolve(P, [i], "i")[0]
        b = _resolve(P, [j], "j")[0]
        P = _covariances(P)
        den = np.sqrt(P[:, a, a] * P[:, b, b])
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(den > 0, P[:, a, b] / np.where(den > 0, den, 1.0), np.nan)
    P = _covariances(P)
    d = np.sqrt(np.clip(np.diagonal(P, axis1=1, axis2=2), 0.0, None))
    den = d[:, :, None] * d[:, None, :]
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(den > 0, P / np.where(den > 0, den, 1.0), np.nan)


def group_correlation(P, states_a, states_b, C_a=None, C_b=None) -> np.ndarray:
    """Per-axis correlation of two rotated 3-vectors of states (launcher.md §6.3 item 2).

    With ``a = C_a x_a`` and ``b = C_b x_b`` (e.g. ``C_a = T_E^B`` for an ECEF attitude
    error and ``C_b = I`` for a body-axis one), returns
    ``rho_k = cov(a_k, b_k) / sqrt(var a_k var b_k)`` for each axis k.

    Returns
    -------
    ndarray (N, k)
    """
    ia = _resolve(P, states_a, "states_a")
    ib = _resolve(P, states_b, "states_b")
    if ia.size != ib.size:
        raise NavlibInputError(f"states_a, states_b: groups differ in size ({ia.size}, {ib.size})")
    P = _covariances(P)
    count = P.shape[0]
    eye = np.eye(ia.size)
    C_a = _rotations(C_a, count, ia.size, "C_a")
    C_b = _rotations(C_b, count, ib.size, "C_b")
    C_a = np.broadcast_to(eye, (count, *eye.shape)) if C_a is None else C_a
    C_b = np.broadcast_to(eye, (count, *eye.shape)) if C_b is None else C_b
    Paa = C_a @ P[:, ia[:, None], ia] @ np.swapaxes(C_a, 1, 2)
    Pbb = C_b @ P[:, ib[:, None], ib] @ np.swapaxes(C_b, 1, 2)
    Pab = C_a @ P[:, ia[:, None], ib] @ np.swapaxes(C_b, 1, 2)
    den = np.sqrt(np.clip(np.diagonal(Paa, axis1=1, axis2=2) * np.diagonal(Pbb, axis1=1,
                                                                             axis2=2), 0, None))
    cross = np.diagonal(Pab, axis1=1, axis2=2)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(den > 0, cross / np.where(den > 0, den, 1.0), np.nan)


def covariance_ratio(sigma) -> np.ndarray:
    """PSINS-style observability degree ``sigma_i(t0) / sigma_i(t)``, (N, n).

    1 means no information gained on state i since t0; large values mean the state was
    estimated. A zero ``sigma_i(t)`` gives inf (a zero initial sigma gives NaN).

    Parameters
    ----------
    sigma : CovarianceResult or ndarray (N, n)
    """
    if isinstance(sigma, CovarianceResult):
        sigma = sigma.sigma
    sigma = finite_array(sigma, "sigma", ndim=2)
    if np.any(sigma < 0):
        raise NavlibInputError("sigma: standard deviations must be non-negative")
    with np.errstate(divide="ignore", invalid="ignore"):
        return sigma[:1] / sigma


def convergence_time(t, sigma, fraction: float = 0.95) -> np.ndarray:
    """Time at which each state has made ``fraction`` of its total sigma reduction.

    ``t_c = min { t : sigma(s) <= sigma_0 - fraction (sigma_0 - sigma_end) for all s >= t }``
    (ssac.md §8 item 7). States with no net reduction get NaN.

    Parameters
    ----------
    t : ndarray (N,)
    sigma : ndarray (N, n)
    fraction : float in (0, 1]

    Returns
    -------
    ndarray (n,)
    """
    t = finite_array(t, "t", ndim=1)
    sigma = finite_array(sigma, "sigma", shape=(t.size, None))
    fraction = finite_scalar(fraction, "fraction", 0.0, 1.0, low_open=True)
    level = sigma[0] - fraction * (sigma[0] - sigma[-1])
    above = sigma > level * (1.0 + 1e-12)
    # last epoch still above the level; convergence is the next one
    last_above = np.where(above.any(axis=0), t.size - 1 - np.argmax(above[::-1], axis=0), -1)
    out = t[np.minimum(last_above + 1, t.size - 1)].astype(float)
    out[sigma[-1] >= sigma[0]] = np.nan
    return out


@dataclass(frozen=True, eq=False)
class NormalizedEigenResult:
    """Ham–Brown normalised covariance eigen-analysis over time (ssac.md §3.6).

    Attributes
    ----------
    t : ndarray (N,)
    eigenvalues : ndarray (N, n)
        Descending eigenvalues of ``P_n(t)``; they lie in ``[0, o]`` and sum to ``o``.
    eigenvectors : ndarray (N, n, n)
        Matching unit eigenvectors as columns (``eigenvectors[k][:, i]`` for
        ``eigenvalues[k, i]``), signs kept consistent over time (positive overlap with the
        previous epoch's vector of the same index). In this sorted order two modes whose
        eigenvalues cross swap columns: the paper's "X-shape" (Silva et al. Figs. 9–10).
    tracked_values : ndarray (N, n)
        Rayleigh quotients ``v' P_n v`` of the tracked vectors (equal to eigenvalues, up to
        the tracking of near-degenerate clusters).
    tracked_vectors : ndarray (N, n, n)
        Eigenvectors followed by continuity from the anchor epoch (default the last, where
        mode i is the i-th largest): each mode keeps its index through crossings; inside a
        cluster of near-equal eigenvalues (gap below ``degenerate_tol * o``) the vectors are
        the orthonormal basis of the cluster's subspace closest to the neighbouring epoch's
        vectors (orthogonal Procrustes), so they vary smoothly instead of jumping.
    order : float
        The normalising order ``o``.
    state_names : tuple of str
    """

    t: np.ndarray
    eigenvalues: np.ndarray
    eigenvectors: np.ndarray
    tracked_values: np.ndarray
    tracked_vectors: np.ndarray
    order: float
    state_names: tuple[str, ...]

    @property
    def n(self) -> int:
        return len(self.state_names)

    def _epoch(self, time: float | None) -> int:
        if time is None:
            return self.t.size - 1
        time = finite_scalar(time, "time")
        return int(np.argmin(np.abs(self.t - time)))

    def to_frame(self, tracked: bool = False) -> pd.DataFrame:
        """Tidy eigenvalue history: ``t, mode, eigenvalue`` (mode 1 = largest / first)."""
        values = self.tracked_values if tracked else self.eigenvalues
        return pd.DataFrame({
            "t": np.repeat(self.t, self.n),
            "mode": np.tile(np.arange(1, self.n + 1), self.t.size),
            "eigenvalue": values.ravel(),
        })

    def components_frame(self, modes: Sequence[int] | None = None,
                         tracked: bool = False) -> pd.DataFrame:
        """Tidy eigenvector components: ``t, mode, state, component`` (modes 1-based)."""
        modes = np.arange(1, self.n + 1) if modes is None else np.asarray(modes, dtype=int)
        if modes.size == 0 or modes.min() < 1 or modes.max() > self.n:
            raise NavlibInputError(f"modes: expected 1-based mode numbers in 1..{self.n}")
        vectors = (self.tracked_vectors if tracked else self.eigenvectors)[:, :, modes - 1]
        count = self.t.size
        return pd.DataFrame({
            "t": np.repeat(self.t, self.n * modes.size),
            "state": np.tile(np.repeat(np.array(self.state_names, dtype=object), modes.size),
                             count),
            "mode": np.tile(modes, count * self.n),
            "component": vectors.ravel(),
        })

    def table(self, time: float | None = None, modes: Sequence[int] | None = None,
              tracked: bool = False) -> pd.DataFrame:
        """Eigenvalues and eigenvector components at one epoch (Silva et al. Tables 1–2).

        Rows are states plus a first row ``eigenvalue``; columns ``lambda_1 ...``.
        ``time`` defaults to the last epoch.
        """
        k = self._epoch(time)
        modes = np.arange(1, self.n + 1) if modes is None else np.asarray(modes, dtype=int)
        values = (self.tracked_values if tracked else self.eigenvalues)[k, modes - 1]
        vectors = (self.tracked_vectors if tracked else self.eigenvectors)[k][:, modes - 1]
        frame = pd.DataFrame(np.vstack([values, vectors]),
                             index=["eigenvalue", *self.state_names],
                             columns=[f"lambda_{m}" for m in modes])
        frame.attrs["t"] = float(self.t[k])
        return frame

    def subspace_share(self, modes: Sequence[int], time: float | None = None) -> np.ndarray:
        """Norm of each state's row in the subspace spanned by ``modes`` (1-based, sorted).

        ``share[j] = ||V_S[j, :]||`` is invariant to rotations inside the subspace, so it is
        the meaningful quantity for a near-degenerate group (ssac.md §3.6 step 6: compare
        summed or projected subspaces). 1 means state j lies wholly inside the subspace.
        Returns (N, n) over time, or (n,) when ``time`` is given.
        """
        modes = np.asarray(modes, dtype=int)
        if modes.size == 0 or modes.min() < 1 or modes.max() > self.n:
            raise NavlibInputError(f"modes: expected 1-based mode numbers in 1..{self.n}")
        V = self.eigenvectors[:, :, modes - 1]
        share = np.sqrt(np.sum(V**2, axis=2))
        return share if time is None else share[self._epoch(time)]


def normalized_eigen(P, P0=None, *, order: float | None = None, scale: str = "diag",
                     degenerate_tol: float = 1e-4, track: bool = True, anchor: str = "end",
                     t=None, state_names=None) -> NormalizedEigenResult:
    """Ham & Brown normalised covariance eigen-analysis (Silva et al. 2017 eqs. 45–46).

    ``P_sn(t) = D0^-1 P(t) D0^-1`` with ``D0 = sqrt(diag P0)`` (or the symmetric matrix
    square root of ``P0`` with ``scale="sqrtm"``), and ``P_n(t) = o P_sn(t) / Tr P_sn(t)``,
    so the eigenvalues lie in ``[0, o]`` and sum to ``o`` at every t — the trace-at-t
    reading of ssac.md §3.6, the one consistent with "the sum approaches 15".

    Parameters
    ----------
    P : CovarianceResult or ndarray (N, n, n)
        Covariance history (posterior ``P+`` of a result, as in the paper).
    P0 : ndarray (n, n), optional
        Normalising covariance; default the first epoch's ``P_prior`` of a result.
    order : float, optional
        ``o``, default n.
    scale : {"diag", "sqrtm"}
    degenerate_tol : float
        Eigenvalues closer than ``degenerate_tol * o`` are one cluster for tracking.
    track : bool
        Compute the tracked vectors (about 0.25 ms per epoch for 15 states); with False the
        tracked fields repeat the sorted ones (fast path for interactive use).
    anchor : {"end", "start"}
        Epoch where tracked mode i is the i-th largest eigenvector; tracking runs from there
        through the others. ``"end"`` (default) labels the modes by their steady-state order
        and runs backwards, which suits covariance histories that start from a degenerate
        ``P_n(0)`` (a diagonal ``P0`` normalises to ``I``: all eigenvalues equal).
    t, state_names : optional, taken from a CovarianceResult when given one.

    Returns
    -------
    NormalizedEigenResult

    Notes
    -----
    Sorted order: ``numpy.linalg.eigh`` per epoch (batched), sorted descending, each column's
    sign flipped to a non-negative dot product with the previous epoch's column (the first
    epoch: largest-magnitude component positive). When two eigenvalues cross, the sorted
    columns exchange directions — the X-shape of Silva et al. Figs. 9–10; their sum
    (the projector onto the pair) is unaffected, see
    :meth:`NormalizedEigenResult.subspace_share`.

    Tracked order: starting from the sorted basis at the anchor epoch, the vectors of the
    epoch already tracked are assigned to the next epoch's clusters by maximum squared
    projection (Hungarian assignment, each cluster receiving as many vectors as its
    dimension), then replaced by the Procrustes-closest basis of the cluster subspace,
    which makes the sign consistent as well.
    """
    if isinstance(P, CovarianceResult):
        t = P.t if t is None else t
        state_names = P.state_names if state_names is None else state_names
        P0 = P.P_prior[0] if P0 is None else P0
    Ps = _covariances(P)
    count, n = Ps.shape[0], Ps.shape[1]
    if P0 is None:
        raise NavlibInputError("P0: the normalising covariance is required with plain arrays")
    P0 = finite_array(P0, "P0", shape=(n, n))
    order = float(n) if order is None else finite_scalar(order, "order", 0.0, low_open=True)
    degenerate_tol = finite_scalar(degenerate_tol, "degenerate_tol", 0.0)
    if anchor not in ("end", "start"):
        raise NavlibInputError(f"anchor: expected 'end' or 'start', got {anchor!r}")
    if scale == "diag":
        d0 = np.sqrt(np.diag(P0))
        if np.any(d0 <= 0):
            raise NavlibInputError("P0: diagonal must be positive to normalise")
        Psn = Ps / d0[:, None] / d0[None, :]
    elif scale == "sqrtm":
        w0, V0 = np.linalg.eigh(symmetrize(P0))
        if w0[0] <= 0:
            raise NavlibInputError("P0: must be positive definite for scale='sqrtm'")
        inv_root = (V0 / np.sqrt(w0)) @ V0.T
        Psn = inv_root @ Ps @ inv_root
    else:
        raise NavlibInputError(f"scale: expected 'diag' or 'sqrtm', got {scale!r}")
    trace = np.trace(Psn, axis1=1, axis2=2)
    if np.any(trace <= 0):
        raise NavlibInputError("P: covariance with zero trace cannot be normalised")
    Pn = symmetrize(order * Psn / trace[:, None, None])
    w, V = np.linalg.eigh(Pn)
    w, V = w[:, ::-1].copy(), V[:, :, ::-1].copy()
    # sign consistency of the sorted columns
    first = V[0]
    pivot = np.argmax(np.abs(first), axis=0)
    V[0] *= np.where(first[pivot, np.arange(n)] < 0, -1.0, 1.0)
    flips = np.where(np.einsum("kij,kij->kj", V[1:], V[:-1]) < 0, -1.0, 1.0)
    V[1:] *= np.cumprod(flips, axis=0)[:, None, :]  # chained: each column vs the flipped one
    tracked_V = V.copy()
    forward = anchor == "start"
    # the clusters of every epoch at once: label[k, i] numbers the cluster of sorted mode i
    # (a gap above degenerate_tol * o starts a new one), first[k, i] marks its first mode
    labels = np.zeros((count, n), dtype=int)
    labels[:, 1:] = np.cumsum(-np.diff(w, axis=1) > degenerate_tol * order, axis=1)
    first = np.diff(labels, axis=1, prepend=-1) != 0
    for k in (range(1, count) if forward else range(count - 2, -1, -1)) if track else ():
        prev, cur = tracked_V[k - 1 if forward else k + 1], V[k]
        M = cur.T @ prev  # overlaps: rows current sorted vectors, columns previous tracked
        label = labels[k]
        new = np.empty_like(prev)
        if label[-1] == n - 1:  # all eigenvalues separated: assign by maximum overlap
            rows, cols = linear_sum_assignment(-np.abs(M))
            new[:, cols] = cur[:, rows] * np.where(M[rows, cols] < 0, -1.0, 1.0)
            tracked_V[k] = new
            continue
        # squared projection of each previous vector onto each cluster's subspace; every
        # sorted position is a slot of its cluster, so a cluster receives as many previous
        # vectors as its dimension
        starts = np.flatnonzero(first[k])
        sizes = np.bincount(label)
        proj = np.add.reduceat(M**2, starts, axis=0)
        rows, cols = linear_sum_assignment(-proj[label])
        single = sizes[label[rows]] == 1
        r1, c1 = rows[single], cols[single]
        new[:, c1] = cur[:, r1] * np.where(M[r1, c1] < 0, -1.0, 1.0)
        multi = np.flatnonzero(sizes > 1)
        # Procrustes per cluster: the basis of span(cur[:, c]) closest to prev[:, mine] is
        # cur[:, c] W Z' with W S Z' = svd(cur[:, c]' prev[:, mine]); all clusters of the
        # epoch in one batched SVD (padded with identity blocks)
        size = sizes[multi].max()
        blocks = np.broadcast_to(np.eye(size), (multi.size, size, size)).copy()
        members = []
        for b, i in enumerate(multi):
            c = np.arange(starts[i], starts[i] + sizes[i])
            mine = cols[label[rows] == i]
            blocks[b, :c.size, :c.size] = M[c][:, mine]
            members.append((c, mine))
        W, _, Zt = np.linalg.svd(blocks)
        polar = W @ Zt
        for b, (c, mine) in enumerate(members):
            new[:, mine] = cur[:, c] @ polar[b, :c.size, :c.size]
        tracked_V[k] = new
    tracked_w = np.einsum("kil,kij,kjl->kl", tracked_V, Pn, tracked_V)
    t = np.arange(count, dtype=float) if t is None else finite_array(t, "t", shape=(count,))
    return NormalizedEigenResult(t, w, V, tracked_w, tracked_V, order, _names(state_names, n))
