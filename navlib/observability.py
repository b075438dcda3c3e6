"""Observability matrices, their rank / condition / null space, and the local test per step.

Contract: spec api.md "Observability".

* :func:`observability_matrix` stacks ``H0; H1 F0; H2 F1 F0; ...`` for a time-varying pair, or
  ``H; H F; ...; H F^(n-1)`` for a constant (piecewise-constant, PWCS) pair.
* :func:`analyze` gives rank (tolerance relative to the largest singular value), the 2-norm
  condition number, the singular values, an orthonormal null-space basis and its split into
  groups of coupled states (with an optional state scaling and a coupling threshold, because an
  exact null space can link physical groups through tiny Earth-rate terms, spec ssac.md §3.3).
* :func:`local_observability` evaluates the local observability matrix at every step of a
  discrete model, either as printed in Beaudoin et al. (2018) eq. (6) (time-varying sequence
  ``C(k); C(k+1)A(k); ...``) or with the step's matrices frozen (PWCS, spec launcher.md §6.1
  item 2). It is vectorised over steps and split across threads (see :func:`local_observability`);
  at every step of eq. (6) it carries QR factors from step to step (a sliding window,
  :func:`_sliding_singular_values`) instead of factorising each stacked matrix.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from functools import cache

import numpy as np
import pandas as pd

from navlib._validation import finite_array, finite_scalar
from navlib.errors import NavlibInputError
from navlib.resolution import relative_resolution

VARIANTS = ("time_varying", "frozen")


# --------------------------------------------------------------------------------------------
# observability matrix
# --------------------------------------------------------------------------------------------
def _matrix_or_stack(value, name: str) -> np.ndarray:
    arr = finite_array(value, name)
    if arr.ndim not in (2, 3):
        raise NavlibInputError(
            f"{name}: expected one matrix (2-D) or a stack of matrices (3-D), got shape {arr.shape}"
        )
    return arr


def observability_matrix(F, H, n_rows: int | None = None) -> np.ndarray:
    """Stack the observability matrix of a discrete pair (spec api.md; Beaudoin eq. (6)).

    Parameters
    ----------
    F : ndarray (n, n) or (N-1, n, n)
        One transition matrix (constant / PWCS pair) or a sequence where ``F[k]`` maps step
        ``k`` to ``k + 1``.
    H : ndarray (m, n) or (N, m, n)
        One measurement matrix or a sequence ``H[k]`` at step ``k``.
    n_rows : int, optional
        Number of block rows. Default: ``n`` for a constant pair, ``N`` (all steps the
        sequences allow) otherwise. At most ``N`` when either argument is a sequence.

    Returns
    -------
    O : ndarray (n_rows * m, n)
        Block rows ``H0; H1 F0; H2 F1 F0; ...`` (constant pair: ``H; H F; H F^2; ...``).
    """
    F = _matrix_or_stack(F, "F")
    H = _matrix_or_stack(H, "H")
    n = F.shape[-1]
    if F.shape[-2] != n:
        raise NavlibInputError(f"F: matrices must be square, got shape {F.shape}")
    if H.shape[-1] != n:
        raise NavlibInputError(f"H: expected {n} columns to match F, got shape {H.shape}")
    limits = []
    if F.ndim == 3:
        limits.append(F.shape[0] + 1)
    if H.ndim == 3:
        limits.append(H.shape[0])
    if F.ndim == 3 and H.ndim == 3 and H.shape[0] != F.shape[0] + 1:
        raise NavlibInputError(
            f"H: a sequence of {F.shape[0]} transitions needs {F.shape[0] + 1} measurement "
            f"matrices, got {H.shape[0]}"
        )
    n_max = min(limits) if limits else None
    if n_rows is None:
        n_rows = n if n_max is None else n_max
    else:
        n_rows = int(finite_scalar(n_rows, "n_rows", low=1))
        if n_max is not None and n_rows > n_max:
            raise NavlibInputError(f"n_rows: the sequences allow at most {n_max}, got {n_rows}")
    blocks = []
    phi = np.eye(n)
    for k in range(n_rows):
        Hk = H[k] if H.ndim == 3 else H
        blocks.append(Hk @ phi)
        if k + 1 < n_rows:
            phi = (F[k] if F.ndim == 3 else F) @ phi
    return np.vstack(blocks)


# --------------------------------------------------------------------------------------------
# analysis of one matrix
# --------------------------------------------------------------------------------------------
def _condition(s: np.ndarray, n: int) -> np.ndarray:
    """2-norm condition number sigma_max / sigma_min over the last axis (inf when singular).

    ``s`` holds the singular values (descending). A matrix with fewer than ``n`` singular
    values (fewer rows than columns) or a zero smallest value is singular.
    """
    if s.shape[-1] < n:
        return np.full(s.shape[:-1], np.inf)
    with np.errstate(divide="ignore", invalid="ignore"):
        cond = s[..., 0] / s[..., -1]
    return np.where(s[..., -1] > 0, cond, np.inf)


def _coupling_groups(null_space: np.ndarray, scale: np.ndarray | None, threshold: float):
    """Finest split of the state set into groups that the unobservable subspace couples.

    In scaled coordinates ``z = x / scale`` the null space is ``Z = diag(1/scale) N``; ``P``
    is the orthogonal projector onto it. ``share_i = sqrt(P_ii)`` is the cosine between
    state axis ``i`` and the subspace. State ``i`` takes part when ``share_i > threshold``;
    states ``i, j`` are coupled when ``|P_ij| > threshold * max(share_i, share_j)``, i.e. the
    smaller projection has more than ``threshold`` along the larger one. For a
    one-dimensional subspace this couples exactly the participating states. With
    ``threshold -> 0`` the groups are the exact block decomposition of the subspace (``P``
    block-diagonal), which does not depend on the scaling.
    """
    n, d = null_space.shape
    if d == 0:
        return [], np.zeros(n)
    Z = null_space if scale is None else null_space / scale[:, None]
    Q, _ = np.linalg.qr(Z)
    P = Q @ Q.T
    share = np.sqrt(np.clip(np.diag(P), 0.0, None))
    members = np.flatnonzero(share > threshold)
    adjacency = np.abs(P) > threshold * np.maximum.outer(share, share)
    groups, seen = [], set()
    for start in members:
        if start in seen:
            continue
        stack, group = [start], []
        seen.add(start)
        while stack:
            i = stack.pop()
            group.append(i)
            for j in members:
                if j not in seen and adjacency[i, j]:
                    seen.add(j)
                    stack.append(j)
        groups.append(sorted(group))
    return groups, share


@dataclass(frozen=True, eq=False)
class ObservabilityResult:
    """Rank, conditioning and unobservable subspace of one observability matrix.

    Attributes
    ----------
    rank : int
        Number of singular values above ``rtol * sigma_max``.
    n : int
        Number of states (columns of O).
    cond : float
        2-norm condition number ``sigma_max / sigma_min`` (inf when a singular value is
        exactly zero or O has fewer rows than columns). Like MATLAB's ``cond``, it is the raw
        ratio: a numerically rank-deficient O gives ~1e16-1e18 (Beaudoin et al. Table 2).
    singular_values : ndarray (min(M, n),)
        Descending.
    null_space : ndarray (n, n - rank)
        Orthonormal basis (physical coordinates) of the right singular vectors beyond the rank.
    unobservable_groups : list of list of str
        States coupled inside the unobservable subspace (states with no share left out), from
        the scaled projector at ``coupling_threshold`` (see :func:`analyze`).
    unobservable_share : ndarray (n,)
        ``sqrt(P_ii)`` of the scaled projector: cosine between each state axis and the
        unobservable subspace (0 = fully observable direction, 1 = entirely unobservable).
    weakest_direction : ndarray (n,)
        Unit right singular vector of the smallest singular value: the least observable
        state combination (physical coordinates), whatever the rank.
    state_names : tuple of str
    rtol, coupling_threshold : float
    scale : ndarray (n,) or None
    """

    rank: int
    n: int
    cond: float
    singular_values: np.ndarray
    null_space: np.ndarray
    unobservable_groups: list
    unobservable_share: np.ndarray
    weakest_direction: np.ndarray
    state_names: tuple
    rtol: float
    coupling_threshold: float
    scale: np.ndarray | None = None

    @property
    def n_unobservable(self) -> int:
        """``n - rank``."""
        return self.n - self.rank

    @property
    def observable(self) -> bool:
        return self.rank == self.n

    @property
    def log10_cond(self) -> float:
        return float(np.log10(self.cond))

    def to_frame(self) -> pd.DataFrame:
        """One row per state: its unobservable share, group label and null-space weights.

        Columns: ``state``, ``unobservable_share``, ``group`` (index into
        ``unobservable_groups`` or -1), ``null_1 .. null_d`` (the exact basis).
        """
        label = {name: g for g, names in enumerate(self.unobservable_groups) for name in names}
        frame = pd.DataFrame({
            "state": list(self.state_names),
            "unobservable_share": self.unobservable_share,
            "group": [label.get(name, -1) for name in self.state_names],
        })
        for j in range(self.null_space.shape[1]):
            frame[f"null_{j + 1}"] = self.null_space[:, j]
        return frame

    def summary(self) -> dict:
        """Rank, unobservable count, cond and groups as a flat dict (one table row)."""
        return {"n": self.n, "rank": self.rank, "n_unobservable": self.n_unobservable,
                "cond": self.cond, "log10_cond": self.log10_cond,
                "groups": "; ".join("{" + ", ".join(g) + "}" for g in self.unobservable_groups)}


def _state_names(state_names, n: int) -> tuple:
    if state_names is None:
        return tuple(f"x{i}" for i in range(n))
    names = tuple(str(s) for s in state_names)
    if len(names) != n:
        raise NavlibInputError(f"state_names: expected {n} names, got {len(names)}")
    if len(set(names)) != n:
        raise NavlibInputError("state_names: names must be unique")
    return names


def _rtol(rtol, shape) -> float:
    if rtol is None:
        return relative_resolution(shape)
    return finite_scalar(rtol, "rtol", low=0.0, high=1.0)


def analyze(O, rtol: float | None = None, state_names: Sequence[str] | None = None,
            scale=None, coupling_threshold: float | str = 1e-6) -> ObservabilityResult:
    """Rank, condition number, singular values and unobservable subspace of ``O``.

    Parameters
    ----------
    O : ndarray (M, n)
        Observability matrix (e.g. from :func:`observability_matrix`).
    rtol : float, optional
        Rank tolerance relative to the largest singular value: ``rank = #{s_i > rtol s_1}``.
        Default ``max(M, n) * eps`` (numpy ``matrix_rank``).
    state_names : sequence of str, optional
        Column labels; default ``x0, x1, ...``.
    scale : array (n,), optional
        Positive state scales for the grouping, e.g. ``sqrt(diag(P0))``: the null space is
        judged in units of these scales (spec ssac.md §3.3). Rank, cond and ``null_space``
        are always those of the unscaled ``O``.
    coupling_threshold : float or "auto"
        Threshold on the scaled projector onto the unobservable subspace (see
        ``ObservabilityResult.unobservable_share``): a state takes part when its share exceeds
        it, two states are coupled when the smaller projection has more than this along the
        larger. Near 0 gives the exact decomposition; ~0.01-0.1 after P0 scaling gives the
        "physical" groups. ``"auto"``: ten times the perturbation bound of the computed null
        space (Wedin: ``sin(angle) <= ||E|| / sigma_rank`` with ``||E|| = sqrt(max(M, n)) eps
        sigma_1``), at least 1e-6 and at most 0.1; use it when weakly observable directions
        (small ``sigma_rank``) blur the basis.

    Returns
    -------
    ObservabilityResult
    """
    O = finite_array(O, "O", ndim=2)
    M, n = O.shape
    if n == 0 or M == 0:
        raise NavlibInputError(f"O: expected a non-empty matrix, got shape {O.shape}")
    names = _state_names(state_names, n)
    tol = _rtol(rtol, O.shape)
    auto = isinstance(coupling_threshold, str)
    if auto and coupling_threshold != "auto":
        raise NavlibInputError(
            "coupling_threshold: expected a number in [0, 1] or 'auto', got "
            f"{coupling_threshold!r}")
    threshold = 0.0 if auto else finite_scalar(coupling_threshold, "coupling_threshold",
                                               low=0.0, high=1.0)
    if scale is not None:
        scale = finite_array(scale, "scale", shape=(n,))
        if np.any(scale <= 0):
            raise NavlibInputError("scale: state scales must be positive")
    try:
        # a complete V needs full matrices only when O has fewer rows than columns
        _, s, Vt = np.linalg.svd(O, full_matrices=M < n)
    except np.linalg.LinAlgError as exc:  # pragma: no cover - SVD of finite input converges
        raise NavlibInputError(f"O: SVD did not converge ({exc})") from exc
    rank = int(np.sum(s > tol * s[0])) if s[0] > 0 else 0
    null_space = Vt[rank:].T.copy()
    if auto:
        gap = s[rank - 1] if rank > 0 else s[0]
        bound = np.sqrt(max(M, n)) * np.finfo(float).eps * s[0] / gap if gap > 0 else 0.1
        threshold = float(np.clip(10.0 * bound, 1e-6, 0.1))
    groups, share = _coupling_groups(null_space, scale, threshold)
    return ObservabilityResult(
        rank=rank, n=n, cond=float(_condition(s, n)), singular_values=s,
        null_space=null_space, unobservable_groups=[[names[i] for i in g] for g in groups],
        unobservable_share=share, weakest_direction=Vt[n - 1].copy(), state_names=names,
        rtol=tol, coupling_threshold=threshold,
        scale=scale,
    )


# --------------------------------------------------------------------------------------------
# local observability at every step of a mission
# --------------------------------------------------------------------------------------------
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
    :class:`~navlib.models.base.DiscreteModel` supplies its ``F``; a trajectory
    :class:`~navlib.models.base.LinearModel` is discretised lazily, chunk by chunk, with
    :func:`navlib.discretize.discretize_steps` (``method``), without forming ``Q``.
    """
    from navlib.discretize import METHODS, discretize_steps
    from navlib.models.base import DiscreteModel, LinearModel

    if isinstance(model, DiscreteModel):
        F = np.asarray(model.F)
        return np.asarray(model.t), (lambda idx: F[idx]), np.asarray(model.H)
    if isinstance(model, LinearModel):
        if not model.time_varying:
            raise NavlibInputError(
                "model: a constant LinearModel has no steps; discretize it first "
                "(model.discretize(dt=...)) or use observability_matrix for a PWCS pair"
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


def _gram_rows(X, n: int) -> np.ndarray:
    """``n`` rows with the Gram matrix ``X' X`` of each stack ``X`` (..., p, n).

    The R factor of ``X`` when ``p > n``, else ``X`` followed by zero rows: the singular
    values are those of ``X`` (padded with zeros up to ``n``).
    """
    p = X.shape[-2]
    if p > n:
        return np.linalg.qr(X, mode="r")
    out = np.zeros((*X.shape[:-2], n, n))
    out[..., :p, :] = X
    return out


def _block_data(transitions, H, k0: int, n_blocks: int, window: int):
    """``H`` (n_blocks + 1, w, m, n) and ``F`` (n_blocks + 1, w, n, n) of the steps from
    ``k0`` in blocks of ``w``; past the mission ``H = 0`` and ``F = I``, which only steps
    without a complete window read."""
    m, n = H.shape[1:]
    idx = np.arange(k0, k0 + (n_blocks + 1) * window)
    Hs = np.zeros((idx.size, m, n))
    inside = idx[idx < H.shape[0]]
    Hs[:inside.size] = H[inside]
    Fs = np.empty((idx.size, n, n))
    inside = idx[idx < H.shape[0] - 1]
    Fs[:inside.size] = transitions(inside)
    Fs[inside.size:] = np.eye(n)
    shape = (n_blocks + 1, window)
    return Hs.reshape(*shape, m, n), Fs.reshape(*shape, n, n)


def _suffix_factors(Hb, Fb):
    """Block suffixes of eq. (6): ``Y[:, r]`` (n x n) has the Gram matrix of the block rows
    ``H_r; H_{r+1} F_r; ...; H_{w-1} F_{w-2} ... F_r`` of each block, and
    ``Phi[:, r] = F_{w-1} ... F_r`` maps step ``r`` to the next block's start.

    Backward recursion ``Y_r = R([H_r; Y_{r+1} F_r])``, one (m + n) x n QR per step.
    """
    nb, w, m, n = Hb.shape
    Y = np.empty((nb, w, n, n))
    Phi = np.empty((nb, w, n, n))
    Y[:, w - 1] = _gram_rows(Hb[:, w - 1], n)
    Phi[:, w - 1] = Fb[:, w - 1]
    stack = np.empty((nb, m + n, n))
    for r in range(w - 2, -1, -1):
        stack[:, :m] = Hb[:, r]
        np.matmul(Y[:, r + 1], Fb[:, r], out=stack[:, m:])
        Y[:, r] = np.linalg.qr(stack, mode="r")
        np.matmul(Phi[:, r + 1], Fb[:, r], out=Phi[:, r])
    return Y, Phi


def _prefix_factors(Hb, Fb):
    """Block prefixes of eq. (6): ``P[:, j]`` (n x n) has the Gram matrix of the first
    ``j + 1`` block rows from each block's start, ``H_0; H_1 F_0; ...; H_j F_{j-1} ... F_0``.

    Forward recursion ``P_j = R([P_{j-1}; H_j Psi_j])`` with ``Psi_j = F_{j-1} ... F_0``.
    """
    nb, w, m, n = Hb.shape
    P = np.empty((nb, max(w - 1, 0), n, n))
    if w < 2:
        return P
    P[:, 0] = _gram_rows(Hb[:, 0], n)
    psi = Fb[:, 0]
    stack = np.empty((nb, n + m, n))
    for j in range(1, w - 1):
        stack[:, :n] = P[:, j - 1]
        np.matmul(Hb[:, j], psi, out=stack[:, n:])
        P[:, j] = np.linalg.qr(stack, mode="r")
        if j < w - 2:
            psi = Fb[:, j] @ psi
    return P


def _sliding_singular_values(transitions, H, k0: int, K: int, window: int) -> np.ndarray:
    """Singular values of eq. (6)'s ``O(k)`` at the consecutive steps ``k0 .. k0 + K - 1``.

    Two-stack sliding window (docs/assumptions.md, launcher.md §6.1): with blocks of ``w``
    steps from ``k0``, the window of step ``k = b w + r`` is the suffix of block ``b`` from
    ``r`` (``w - r`` block rows) followed by the first ``r`` block rows of block ``b + 1``
    times the suffix transition, so ``O(k)`` is orthogonally equivalent to
    ``[Y_r; P_{r-1} Phi_r]`` (2n x n, see :func:`_suffix_factors`, :func:`_prefix_factors`)
    and has its singular values. Per step: two (m + n) x n QRs, four n x n products and the
    SVD of one 2n x n stack, instead of forming the ``w m x n`` matrix (``w - 1`` block
    products) and factorising it. Each factor is a backward-stable QR and the transitions
    over a window are well scaled (Euler steps ``I + A dt``), so the singular values agree
    with the direct ones to a few rounding units of ``sigma_max`` (tests/test_local_sliding.py).
    """
    n = H.shape[2]
    n_blocks = -(-K // window)
    Hb, Fb = _block_data(transitions, H, k0, n_blocks, window)
    Y, Phi = _suffix_factors(Hb[:-1], Fb[:-1])
    P = _prefix_factors(Hb[1:], Fb[1:])
    C = np.empty((n_blocks, window, 2 * n, n))
    C[:, :, :n] = Y
    C[:, 0, n:] = 0.0
    np.matmul(P, Phi[:, 1:], out=C[:, 1:, n:])
    return np.linalg.svd(C.reshape(-1, 2 * n, n)[:K], compute_uv=False)


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
    """Whether :func:`_sliding_singular_values` applies: every step of eq. (6), and a window
    with at least as many rows as states (else ``O(k)`` has fewer than ``n`` singular values,
    padded with exact zeros below)."""
    return variant == "time_varying" and stride == 1 and window * m >= n


def _singular_values_chunk(transitions, H, steps, window, variant, stride):
    m, n = H.shape[1:]
    if _sliding(variant, stride, window, m, n):
        return _sliding_singular_values(transitions, H, int(steps[0]), steps.size, window)
    if variant == "frozen":
        O = _stack_frozen(transitions, H, steps, window)
    else:
        O = _stack_time_varying_strided(transitions, H, steps, window)
    if O.shape[1] > O.shape[2]:
        # Singular values of the small triangular factor: same values, and the bidiagonal
        # iteration no longer crawls on the graded tall matrices (up to 4x faster here).
        O = np.linalg.qr(O, mode="r")
    return np.linalg.svd(O, compute_uv=False)


@cache
def _blas_controller():
    """threadpoolctl's view of the loaded BLAS libraries (scanned once: ~10 ms a scan), or
    ``None`` when ``threadpoolctl`` is not installed."""
    try:
        from threadpoolctl import ThreadpoolController
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

    Implements Beaudoin et al. (2018) §3.1 / spec launcher.md §6.1: at step ``k`` the local
    matrix is eq. (6), ``O(k) = [H_k; H_{k+1} F_k; ...; H_{k+w-1} F_{k+w-2} ... F_k]``
    (``variant="time_varying"``), or the model frozen at step ``k``,
    ``[H_k; H_k F_k; ...; H_k F_k^(w-1)]`` (``variant="frozen"``, PWCS), with ``w = n`` block
    rows by default.

    Time-varying at every step (``stride=1``, ``w m >= n``): the singular values come from
    the sliding-window factors of :func:`_sliding_singular_values` (docs/assumptions.md,
    launcher.md §6.1), equal to those of an SVD of each stacked ``O(k)`` to a few rounding
    units of its largest singular value, hence the same ranks and the same finite condition
    numbers (to a relative ``~eps * cond``); an exactly singular ``O(k)`` gets a condition
    number of the order of ``1 / eps`` either way (its digits are rounding noise). Otherwise
    each evaluated ``O(k)`` is stacked and factorised (QR, then the SVD of the n x n factor).

    Parameters
    ----------
    model : DiscreteModel or LinearModel
        A discrete model (``t, F, H``), or a trajectory LinearModel that is discretised here
        chunk by chunk with ``method`` (no ``Q`` is formed, so a long 200 Hz mission fits in
        memory).
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
    return LocalObservability(t=t[steps], step=steps, rank=rank, cond=_condition(s, n),
                              singular_values=s, state_names=state_names, window=window,
                              variant=variant, rtol=tol)


def local_matrix(model, step: int, window: int | None = None,
                 variant: str = "time_varying", *, method: str = "euler") -> np.ndarray:
    """The local observability matrix ``O(step)`` of :func:`local_observability`.

    Feed it to :func:`analyze` to see the null space and unobservable groups at one step.
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
