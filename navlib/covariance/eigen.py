"""The Ham & Brown (1983) normalised covariance eigen-analysis (docs/assumptions.md, ssac.md §3.6,
Silva et al. 2017 eqs. 45-46) with sign-consistent tracking through near-degenerate eigenvalues:
:func:`normalized_eigen`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.optimize import linear_sum_assignment

from navlib._validation import finite_array, finite_scalar
from navlib.covariance.frames import as_covariances
from navlib.covariance.recursion import CovarianceResult, state_labels
from navlib.errors import NavlibInputError
from navlib.kalman import symmetrize

__all__ = ["NormalizedEigenResult", "normalized_eigen"]


@dataclass(frozen=True, eq=False)
class NormalizedEigenResult:
    """Ham–Brown normalised covariance eigen-analysis over time (docs/assumptions.md, ssac.md §3.6).

    Attributes
    ----------
    t : ndarray (N,)
    eigenvalues : ndarray (N, n)
        Descending eigenvalues of ``P_n(t)``; they lie in ``[0, o]`` and sum to ``o``.
    eigenvectors : ndarray (N, n, n) or None
        Matching unit eigenvectors as columns (``eigenvectors[k][:, i]`` for
        ``eigenvalues[k, i]``), signs kept consistent over time (positive overlap with the
        previous epoch's vector of the same index). In this sorted order two modes whose
        eigenvalues cross swap columns: the paper's "X-shape" (Silva et al. Figs. 9–10).
    tracked_values : ndarray (N, n)
        Rayleigh quotients ``v' P_n v`` of the tracked vectors (equal to eigenvalues, up to
        the tracking of near-degenerate clusters).
    tracked_vectors : ndarray (N, n, n) or None
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
        """Tidy eigenvector components: ``t, mode, state, component`` (modes 1-based).

        Parameters
        ----------
        modes : sequence of int, optional
            1-based modes to keep (default all).
        tracked : bool, optional
            Use the tracked vectors instead of the sorted eigenvectors.

        Returns
        -------
        pandas.DataFrame
        """
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

    def table(self, time_s: float | None = None, modes: Sequence[int] | None = None,
              tracked: bool = False) -> pd.DataFrame:
        """Eigenvalues and eigenvector components at one epoch (Silva et al. Tables 1–2).

        Parameters
        ----------
        time_s : float, optional
            Time (s); the nearest epoch is shown, default the last.
        modes : sequence of int, optional
            1-based modes to show (default all).
        tracked : bool, optional
            Use the tracked vectors and values instead of the sorted ones.

        Returns
        -------
        pandas.DataFrame
            Rows: ``eigenvalue`` then the states; columns ``lambda_1 ...``.
        """
        k = self._epoch(time_s)
        modes = np.arange(1, self.n + 1) if modes is None else np.asarray(modes, dtype=int)
        values = (self.tracked_values if tracked else self.eigenvalues)[k, modes - 1]
        vectors = (self.tracked_vectors if tracked else self.eigenvectors)[k][:, modes - 1]
        frame = pd.DataFrame(np.vstack([values, vectors]),
                             index=["eigenvalue", *self.state_names],
                             columns=[f"lambda_{m}" for m in modes])
        frame.attrs["t"] = float(self.t[k])
        return frame

    def subspace_share(self, modes: Sequence[int], time_s: float | None = None) -> np.ndarray:
        """Norm of each state's row in the subspace spanned by ``modes`` (1-based, sorted).

        ``share[j] = ||V_S[j, :]||`` is invariant to rotations inside the subspace, so it is
        the meaningful quantity for a near-degenerate group (docs/assumptions.md, ssac.md §3.6 step
        6: compare summed or projected subspaces). 1 means state j lies wholly inside the subspace.

        Parameters
        ----------
        modes : sequence of int
            1-based modes spanning the subspace.
        time_s : float, optional
            One epoch (s); default every epoch.

        Returns
        -------
        ndarray (N, n), or (n,) when ``time_s`` is given
        """
        modes = np.asarray(modes, dtype=int)
        if modes.size == 0 or modes.min() < 1 or modes.max() > self.n:
            raise NavlibInputError(f"modes: expected 1-based mode numbers in 1..{self.n}")
        V = self.eigenvectors[:, :, modes - 1]
        share = np.sqrt(np.sum(V**2, axis=2))
        return share if time_s is None else share[self._epoch(time_s)]


def normalized_eigen(P, P0=None, *, order: float | None = None, scale: str = "diag",
                     degenerate_tol: float = 1e-4, track: bool = True, anchor: str = "end",
                     t=None, state_names=None, vectors: bool = True) -> NormalizedEigenResult:
    """Ham & Brown normalised covariance eigen-analysis (Silva et al. 2017 eqs. 45–46).

    ``P_sn(t) = D0^-1 P(t) D0^-1`` with ``D0 = sqrt(diag P0)`` (or the symmetric matrix
    square root of ``P0`` with ``scale="sqrtm"``), and ``P_n(t) = o P_sn(t) / Tr P_sn(t)``,
    so the eigenvalues lie in ``[0, o]`` and sum to ``o`` at every t — the trace-at-t
    reading of docs/assumptions.md, ssac.md §3.6, the one consistent with "the sum approaches 15".

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
    vectors : bool
        Compute the eigenvectors. With False, the eigenvalues alone (LAPACK's
        eigenvalue-only driver through ``numpy.linalg.eigvalsh``: 9 instead of 18 ms for
        1201 epochs of 15 states; equal to the other driver's to rounding), the vector fields
        None and ``track`` ignored (a panel's eigenvalue figure).

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
    Ps = as_covariances(P)
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
    t = np.arange(count, dtype=float) if t is None else finite_array(t, "t", shape=(count,))
    names = state_labels(state_names, n)
    if not vectors:
        w = np.linalg.eigvalsh(Pn)[:, ::-1].copy()
        return NormalizedEigenResult(t, w, None, w.copy(), None, order, names)
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
    # the sorted vectors' own Rayleigh quotients are the sorted eigenvalues
    tracked_w = np.einsum("kij,kij->kj", tracked_V, Pn @ tracked_V) if track else w.copy()
    return NormalizedEigenResult(t, w, V, tracked_w, tracked_V, order, names)
