"""The observability matrix of a discrete pair and the analysis of one such matrix.

Contract: docs/library.md.

* :func:`observability_matrix` stacks ``H0; H1 F0; H2 F1 F0; ...`` for a time-varying pair, or
  ``H; H F; ...; H F^(n-1)`` for a constant (piecewise-constant, PWCS) pair.
* :func:`analyze` gives rank (tolerance relative to the largest singular value), the 2-norm
  condition number, the singular values, an orthonormal null-space basis and its split into
  groups of coupled states (with an optional state scaling and a coupling threshold, because an
  exact null space can link physical groups through tiny Earth-rate terms, docs/assumptions.md,
  ssac.md §3.3).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from navlib._validation import finite_array, finite_scalar
from navlib.errors import NavlibInputError
from navlib.resolution import relative_resolution

__all__ = ["ObservabilityResult", "analyze", "condition_number", "observability_matrix"]


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
    """Stack the observability matrix of a discrete pair (docs/library.md; Beaudoin eq.
    (6)).

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
def condition_number(s: np.ndarray, n: int) -> np.ndarray:
    """2-norm condition number sigma_max / sigma_min over the last axis (inf when singular).

    A matrix with fewer than ``n`` singular values (fewer rows than columns) or a zero
    smallest value is singular.

    Parameters
    ----------
    s : ndarray (..., k)
        Singular values, descending along the last axis.
    n : int
        Number of columns of the matrix.

    Returns
    -------
    ndarray (...)
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
        judged in units of these scales (docs/assumptions.md, ssac.md §3.3). Rank, cond and
        ``null_space`` are always those of the unscaled ``O``.
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
        rank=rank, n=n, cond=float(condition_number(s, n)), singular_values=s,
        null_space=null_space, unobservable_groups=[[names[i] for i in g] for g in groups],
        unobservable_share=share, weakest_direction=Vt[n - 1].copy(), state_names=names,
        rtol=tol, coupling_threshold=threshold,
        scale=scale,
    )

