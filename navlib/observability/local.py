"""Local observability at every step of a mission (Beaudoin et al. (2018) §3.1).

:func:`local_observability` evaluates the local observability matrix at every step of a
discrete model, either as printed in Beaudoin et al. (2018) eq. (6) (time-varying sequence
``C(k); C(k+1)A(k); ...``) or with the step's matrices frozen (PWCS, docs/assumptions.md,
launcher.md §6.1 item 2). It is vectorised over steps and split across threads; at every step of eq.
(6) it carries triangular factors from step to step (:mod:`navlib.observability.sliding`, compiled)
instead of factorising each stacked matrix.
"""

from __future__ import annotations

import contextlib
import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np
import pandas as pd

from navlib._validation import finite_scalar
from navlib.cache import memoized
from navlib.discretize import METHODS, discretize_steps
from navlib.errors import NavlibInputError
from navlib.models.base import DiscreteModel, LinearModel
from navlib.observability.matrix import condition_number
from navlib.observability.sliding import sliding_singular_values
from navlib.resolution import relative_resolution

__all__ = ["VARIANTS", "LocalObservability", "local_matrix", "local_observability"]

VARIANTS = ("time_varying", "frozen")


@dataclass(frozen=True, eq=False)
class LocalObservability:
    """Rank and conditioning of the local observability matrix at each evaluated step.

    Attributes
    ----------
    t : ndarray (K,)
        Times of the evaluated steps, s.
    step : ndarray of int (K,)
        Indices of the evaluated steps in the model's epochs.
    rank : ndarray of int (K,)
    cond : ndarray (K,)
        2-norm condition number (raw ratio, inf only when exactly singular).
    singular_values : ndarray (K, n)
        Descending, per step.
    state_names : tuple of str
    window : int
        Block rows per local matrix.
    variant : str
        ``"time_varying"`` (eq. (6) as printed) or ``"frozen"`` (PWCS at each step).
    rtol : float
        Rank tolerance relative to the largest singular value.
    """

    t: np.ndarray
    step: np.ndarray
    rank: np.ndarray
    cond: np.ndarray
    singular_values: np.ndarray
    state_names: tuple
    window: int
    variant: str
    rtol: float

    @property
    def n(self) -> int:
        return len(self.state_names)

    @property
    def rank_constant(self) -> bool:
        """Whether the rank is the same at every evaluated step (Beaudoin §4.1 statement 1)."""
        return bool(self.rank.min() == self.rank.max())

    @property
    def n_unobservable(self) -> int:
        """``n - min(rank)``: a state is observable only if it is at every step (§6.1 item 4)."""
        return int(self.n - self.rank.min())

    @property
    def max_cond(self) -> float:
        return float(np.max(self.cond))

    @property
    def log10_max_cond(self) -> float:
        """log10 of the maximum condition number over the mission (Table 2 "order")."""
        return float(np.log10(self.max_cond))

    def with_rtol(self, rtol: float) -> LocalObservability:
        """The same result re-ranked at another relative tolerance (no new SVDs)."""
        tol = finite_scalar(rtol, "rtol", low=0.0, high=1.0)
        s = self.singular_values
        rank = np.sum(s > tol * s[:, :1], axis=1)
        return LocalObservability(self.t, self.step, rank, self.cond, s, self.state_names,
                                  self.window, self.variant, tol)

    def summary(self) -> dict:
        """One table row: n, min/max rank, unobservable count, log10 max cond, constancy."""
        return {"n": self.n, "rank_min": int(self.rank.min()), "rank_max": int(self.rank.max()),
                "n_unobservable": self.n_unobservable, "rank_constant": self.rank_constant,
                "log10_max_cond": self.log10_max_cond}

    def to_frame(self) -> pd.DataFrame:
        """Tidy per-step table: ``t, step, rank, n_unobservable, cond, log10_cond``."""
        with np.errstate(divide="ignore"):
            log_cond = np.log10(self.cond)
        return pd.DataFrame({"t": self.t, "step": self.step, "rank": self.rank,
                             "n_unobservable": self.n - self.rank, "cond": self.cond,
                             "log10_cond": log_cond})


def _model_arrays(model, method: str):
    """Per-step transition source and H stack of a discrete or continuous model.

    Returns ``(t, transitions, H)`` where ``transitions(idx)`` gives ``F[idx]`` for an
    integer index array. A
    :class:`~navlib.models.base.DiscreteModel` supplies its ``F``; a step source (``t``,
    ``H``, ``state_names``, ``method`` and a ``transitions(idx)`` method, e.g.
    :class:`~navlib.models.launcher.LauncherSteps`) computes the steps asked for; a trajectory
    :class:`~navlib.models.base.LinearModel` is discretised lazily, chunk by chunk, with
    :func:`navlib.discretize.discretize_steps` (``method``), without forming ``Q``.
    """
    if isinstance(model, DiscreteModel):
        F = np.asarray(model.F)
        return np.asarray(model.t), (lambda idx: F[idx]), np.asarray(model.H)
    if callable(getattr(model, "transitions", None)):  # a step source (LauncherSteps)
        if method != model.method:
            raise NavlibInputError(f"method: the model's transitions are {model.method!r} "
                                   f"steps, got method={method!r}")
        t, H = np.asarray(model.t), model.H    # H may form its matrices on demand
        if np.ndim(H) == 2:
            H = np.broadcast_to(np.asarray(H), (t.size, *np.shape(H)))
        return t, model.transitions, H
    if isinstance(model, LinearModel):
        if not model.time_varying:
            raise NavlibInputError(
                "model: a constant LinearModel has no steps; discretize it first "
                "(model.discretize(dt_s=...)) or use observability_matrix for a PWCS pair"
            )
        if method not in METHODS:
            raise NavlibInputError(f"method: expected one of {METHODS}, got {method!r}")
        t = np.asarray(model.t)
        n_samples = t.size
        A = np.asarray(model.A)
        dt = np.diff(t)
        zero_W = np.zeros((model.n, model.n))  # no noise: only F is used

        def transitions(idx):
            flat = np.ravel(idx)
            A_part = A[flat] if A.ndim == 3 else np.broadcast_to(A, (flat.size, *A.shape))
            F = discretize_steps(A_part, None, None, dt[flat], method, W=zero_W)[0]
            return F.reshape(*np.shape(idx), *F.shape[1:])

        H = np.asarray(model.H)
        if H.ndim == 2:
            H = np.broadcast_to(H, (n_samples, *H.shape))
        return t, transitions, H
    raise NavlibInputError(
        f"model: expected a DiscreteModel or a trajectory LinearModel, got {type(model).__name__}"
    )



def _stack_time_varying_strided(transitions, H, steps, window):
    """Local matrices of eq. (6) at scattered steps, by forward products ``Phi(k+j, k)``."""
    m, n = H.shape[1:]
    K = steps.size
    O = np.empty((K, window, m, n))
    phi = np.broadcast_to(np.eye(n), (K, n, n))
    F = transitions(steps[:, None] + np.arange(window - 1))     # (K, window - 1, n, n)
    for j in range(window):
        O[:, j] = np.matmul(H[steps + j], phi)
        if j + 1 < window:
            phi = np.matmul(F[:, j], phi)
    return O.reshape(K, window * m, n)


def _stack_frozen(transitions, H, steps, window):
    """PWCS local matrices ``[H_k; H_k F_k; ...; H_k F_k^(w-1)]`` at ``steps``."""
    F = transitions(steps)
    block = H[steps]
    m, n = block.shape[1:]
    O = np.empty((steps.size, window, m, n))
    O[:, 0] = block
    for j in range(1, window):
        block = np.matmul(block, F)
        O[:, j] = block
    return O.reshape(steps.size, window * m, n)


def _evaluable_steps(n_epochs: int, window: int, variant: str) -> int:
    """Number of leading epochs with a complete local window."""
    return n_epochs - window + 1 if variant == "time_varying" else n_epochs - 1


def _sliding(variant: str, stride: int, window: int, m: int, n: int) -> bool:
    """Whether :func:`~navlib.observability.sliding.sliding_singular_values` applies: every
    step of eq. (6), and a window with at least as many rows as states (else ``O(k)`` has
    fewer than ``n`` singular values, padded with exact zeros below)."""
    return variant == "time_varying" and stride == 1 and window * m >= n


def _singular_values_chunk(transitions, H, steps, window, variant, stride):
    m, n = H.shape[1:]
    if _sliding(variant, stride, window, m, n):
        return sliding_singular_values(transitions, H, int(steps[0]), steps.size, window)
    if variant == "frozen":
        O = _stack_frozen(transitions, H, steps, window)
    else:
        O = _stack_time_varying_strided(transitions, H, steps, window)
    if O.shape[1] > O.shape[2]:
        # Singular values of the small triangular factor: same values, and the bidiagonal
        # iteration no longer crawls on the graded tall matrices (up to 4x faster here).
        O = np.linalg.qr(O, mode="r")
    return np.linalg.svd(O, compute_uv=False)


@memoized(maxsize=1)
def _blas_controller():
    """threadpoolctl's view of the loaded BLAS libraries (scanned once: ~10 ms a scan), or
    ``None`` when ``threadpoolctl`` is not installed."""
    try:
        from threadpoolctl import ThreadpoolController  # optional: present with scipy's stack
    except ImportError:
        return None
    return ThreadpoolController()


def _blas_single_thread():
    """Context limiting BLAS to one thread (our threads split the work instead).

    OpenBLAS threading inside the many small LAPACK calls of a batched SVD is slower than
    one thread and collapses when other processes load the cores; ``threadpoolctl`` (an
    optional dependency) switches it off. Returns ``None`` when it is not installed.
    """
    controller = _blas_controller()
    return None if controller is None else controller.limit(limits=1)


def local_observability(model, window: int | None = None, variant: str = "time_varying",
                        stride: int = 1, rtol: float | None = None, *, method: str = "euler",
                        n_jobs: int | None = None, chunk: int = 1024) -> LocalObservability:
    """Local observability test at every (or every ``stride``-th) step of a mission.

    Implements Beaudoin et al. (2018) §3.1 / docs/assumptions.md, launcher.md §6.1: at step ``k``
    the local matrix is eq. (6), ``O(k) = [H_k; H_{k+1} F_k; ...; H_{k+w-1} F_{k+w-2} ... F_k]``
    (``variant="time_varying"``), or the model frozen at step ``k``, ``[H_k; H_k F_k; ...; H_k
    F_k^(w-1)]`` (``variant="frozen"``, PWCS), with ``w = n`` block rows by default.

    Time-varying at every step (``stride=1``, ``w m >= n``): the singular values come from
    the sliding-window factors of
    :func:`~navlib.observability.sliding.sliding_singular_values` (compiled; docs/assumptions.md,
    launcher.md §6.1), equal to those of an SVD of each stacked ``O(k)`` to a few rounding units of
    its largest singular value, hence the same ranks and the same finite condition numbers (to a
    relative ``~eps * cond``); an exactly singular ``O(k)`` gets a condition number of the order of
    ``1 / eps`` either way (its digits are rounding noise). Otherwise each evaluated ``O(k)`` is
    stacked and factorised (QR, then the SVD of the n x n factor).

    Parameters
    ----------
    model : DiscreteModel, LinearModel or step source
        A discrete model (``t, F, H``), a trajectory LinearModel that is discretised here
        chunk by chunk with ``method`` (no ``Q`` is formed, so a long 200 Hz mission fits in
        memory), or a step source whose ``transitions(idx)`` computes the ``method`` steps
        asked for (:func:`navlib.models.launcher.launcher_steps`: no ``A`` stack at all).
    window : int, optional
        Block rows per local matrix (default ``n``).
    variant : {"time_varying", "frozen"}
    stride : int
        Evaluate every ``stride``-th step (e.g. 200 for 1 Hz on a 200 Hz mission); the
        matrices still use the model's own steps.
    rtol : float, optional
        Rank tolerance relative to the largest singular value of each ``O(k)``; default
        ``max(window * m, n) * eps`` (numpy ``matrix_rank``).
    method : {"euler", "expm"}
        Discretisation of a LinearModel (default the paper's Euler form ``I + s_t F``).
    n_jobs : int, optional
        Threads over chunks of steps (BLAS limited to one thread each through
        ``threadpoolctl``); default all cores when ``threadpoolctl`` is installed, else 1.
    chunk : int
        Steps per batch (bounds memory: ``chunk * window * m * n`` floats, or about
        ``8 chunk n^2`` on the sliding path, which rounds it to whole windows).

    Returns
    -------
    LocalObservability
        Steps ``k`` whose window fits inside the mission: ``k <= N - w`` (time-varying) or
        ``k <= N - 2`` (frozen).
    """
    if variant not in VARIANTS:
        raise NavlibInputError(f"variant: expected one of {VARIANTS}, got {variant!r}")
    t, transitions, H = _model_arrays(model, method)
    n_epochs, m, n = H.shape
    state_names = tuple(model.state_names)
    window = n if window is None else int(finite_scalar(window, "window", low=1))
    stride = int(finite_scalar(stride, "stride", low=1))
    chunk = int(finite_scalar(chunk, "chunk", low=1))
    n_eval = _evaluable_steps(n_epochs, window, variant)
    if n_eval < 1:
        raise NavlibInputError(
            f"window: {window} block rows need at least {window + 1} epochs for variant "
            f"{variant!r}; the model has {n_epochs}"
        )
    tol = rtol if rtol is not None else relative_resolution((window * m, n))
    tol = finite_scalar(tol, "rtol", low=0.0, high=1.0)
    steps = np.arange(0, n_eval, stride)
    if _sliding(variant, stride, window, m, n):  # whole blocks of the sliding window
        chunk = max(chunk // window, 1) * window
    pieces = [steps[i:i + chunk] for i in range(0, steps.size, chunk)]
    limit = _blas_single_thread()
    if n_jobs is None:
        jobs = 1 if limit is None else max(1, os.cpu_count() or 1)
    else:
        jobs = int(finite_scalar(n_jobs, "n_jobs", low=1))

    def work(piece):
        return _singular_values_chunk(transitions, H, piece, window, variant, stride)

    with limit if limit is not None else contextlib.nullcontext():
        if jobs > 1 and len(pieces) > 1:
            with ThreadPoolExecutor(jobs) as pool:
                parts = list(pool.map(work, pieces))
        else:
            parts = [work(piece) for piece in pieces]
    s = np.concatenate(parts)
    if s.shape[1] < n:  # fewer rows than states: pad with exact zeros
        s = np.concatenate([s, np.zeros((s.shape[0], n - s.shape[1]))], axis=1)
    rank = np.sum(s > tol * s[:, :1], axis=1)
    return LocalObservability(t=t[steps], step=steps, rank=rank, cond=condition_number(s, n),
                              singular_values=s, state_names=state_names, window=window,
                              variant=variant, rtol=tol)


def local_matrix(model, step: int, window: int | None = None,
                 variant: str = "time_varying", *, method: str = "euler") -> np.ndarray:
    """The local observability matrix ``O(step)`` of :func:`local_observability`.

    Feed it to :func:`analyze` to see the null space and unobservable groups at one step.

    Parameters
    ----------
    model : DiscreteModel, LinearModel or step source
        As in :func:`local_observability`.
    step : int
        The model step whose window starts the matrix.
    window : int, optional
        Block rows (default ``n``).
    variant : {"time_varying", "frozen"}
        As in :func:`local_observability`.
    method : {"euler", "expm"}
        Discretisation of a LinearModel.

    Returns
    -------
    ndarray (window * m, n)
    """
    if variant not in VARIANTS:
        raise NavlibInputError(f"variant: expected one of {VARIANTS}, got {variant!r}")
    t, transitions, H = _model_arrays(model, method)
    n = H.shape[2]
    window = n if window is None else int(finite_scalar(window, "window", low=1))
    n_eval = _evaluable_steps(t.size, window, variant)
    step = int(finite_scalar(step, "step", low=0))
    if step >= n_eval:
        raise NavlibInputError(f"step: must be below {max(n_eval, 0)} for window {window}, "
                               f"got {step}")
    stack = _stack_frozen if variant == "frozen" else _stack_time_varying_strided
    return stack(transitions, H, np.array([step]), window)[0]
