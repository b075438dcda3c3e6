"""The Kalman covariance of a linear filter along a model (docs/assumptions.md, launcher.md §6.2,
ssac.md §8 item 6): :func:`kalman_covariance` (Joseph form, pseudo-inverse of
the innovation covariance for singular ``R``), :func:`kalman_covariances` for several initial
covariances at once and the unaided :func:`ins_only_covariance`, all through
:func:`navlib.kalman.covariance_recursion`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from navlib._validation import finite_array, finite_scalar
from navlib.errors import NavlibInputError
from navlib.kalman import covariance_recursion, symmetrize
from navlib.models.base import DiscreteModel, state_indices

__all__ = ["CovarianceResult", "ins_only_covariance", "kalman_covariance", "kalman_covariances",
           "stack_steps", "state_labels"]


def state_labels(state_names, n: int) -> tuple[str, ...]:
    """The ``n`` state names as strings, ``x0, x1, ...`` when none are given.

    Parameters
    ----------
    state_names : sequence or None
        One name per state.
    n : int
        Number of states.

    Returns
    -------
    tuple of str

    Raises
    ------
    NavlibInputError
        When ``state_names`` does not hold ``n`` names.
    """
    if state_names is None:
        return tuple(f"x{i}" for i in range(n))
    names = tuple(str(s) for s in state_names)
    if len(names) != n:
        raise NavlibInputError(f"state_names: expected {n} names, got {len(names)}")
    return names


def stack_steps(value, count: int, shape: tuple, name: str) -> np.ndarray:
    """One matrix broadcast to ``count`` copies, or a stack of ``count`` matrices.

    Parameters
    ----------
    value : array_like
        A ``shape`` matrix or a stack of ``count`` of them; finite.
    count : int
        Number of steps.
    shape : tuple of int
        Shape of one matrix.
    name : str
        Argument name used in the error message.

    Returns
    -------
    ndarray (count, shape[0], shape[1])
        A read-only broadcast view for a single matrix.

    Raises
    ------
    NavlibInputError
        For another shape or a non-finite entry.
    """
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
        return state_indices(self.state_names, names)

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
    F = stack_steps(F, count - 1, (n, n), "F")
    Q = stack_steps(Q, count - 1, (n, n), "Q")
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
        H = stack_steps(H, count, (m, n), "H")
        R = stack_steps(R if R is not None else np.zeros((m, m)), count, (m, m), "R")
    return F, Q, H, R, symmetrize(P0), t, state_labels(state_names, n)


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
    :func:`kalman_covariance` and run :func:`~navlib.kalman.covariance_recursion`."""
    F, Q, H, R, P0, t, names = _inputs(F, Q, H, R, P0, t, n_epochs, state_names,
                                       stacked=stacked)
    pinv_rtol = finite_scalar(pinv_rtol, "pinv_rtol", 0.0, 1.0)
    measured = _epochs_measured(measured, t.size, update_first, H is not None)
    P_prior, P_post, _ = covariance_recursion(F, Q, H, R, P0, measured, pinv_rtol)
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
    """Unaided covariance propagation ``P_{k+1} = F_k P_k F_k' + Q_k`` (docs/assumptions.md,
    launcher.md §6.2.1).

    ``P_prior == P_post`` at every epoch.

    Parameters
    ----------
    F : ndarray (N-1, n, n) or (n, n), or DiscreteModel
        Transition matrices; a DiscreteModel supplies ``F, Q, P0, t, state_names``.
    Q : ndarray (N-1, n, n) or (n, n)
        Process noise added over each step.
    P0 : ndarray (n, n)
        Covariance at epoch 0.
    t : ndarray (N,), optional
        Epoch times (default ``0, 1, ...``); with a single ``F`` it fixes ``N``.
    n_epochs : int, optional
        ``N`` when ``F`` is a single matrix and ``t`` is not given.
    state_names : sequence of str, optional
        Labels of the states.

    Returns
    -------
    CovarianceResult
    """
    F, Q, _, _, P0, t, names = _inputs(F, Q, None, None, P0, t, n_epochs, state_names,
                                      measurements=False)
    return kalman_covariance(F, Q, None, None, P0[0], t=t, state_names=names)
