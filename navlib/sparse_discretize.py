"""Per-step discretisation of the sparse error models, compiled
(docs/assumptions.md "Compiled kernels"): the EKF's windows (:func:`navlib.filters.ekf.ekf`)
and the 21-state model's steps between GNSS epochs
(:func:`navlib.models.ecef.ecef21_at_epochs`).

The error models are sparse and block triangular: in the 21-state ECEF model 58
of the 441 entries of ``A`` are non-zero in the rocket's windows and only the nine
navigation rows have any (the twelve IMU parameters are random walks); the launcher models
add diagonal Markov decays. :func:`discretize_kernel` computes what
:func:`navlib.discretize.discretize_steps` does with ``method="series"`` (``F = expm(A dt)``
and Van Loan's integral of ``W = G Qc G'`` by its order-4 Taylor series) one step at a
time, with products over the non-zero entries of ``A``, ``G`` and ``Qc`` only (the Euler
steps of the launcher models stay NumPy's: two batched operations, and no compile in the
notebooks that run only those); the covariance prediction (:func:`navlib.kalman.predict_sparse`)
multiplies only the rows of ``F`` that are not diagonal. On the sounding rocket's 4300 model
steps of 0.02 s (notebook 09) the steps take 46 ms against 132 ms for the batched NumPy
code.

The exponential is the Taylor series ``sum_k (A dt)^k / k!`` summed until a term is below
``2^-53`` (infinity norm), without scaling while ``|A dt| <=`` :data:`TAYLOR_THETA` (the
rocket's steps reach 1.6, dominated by nilpotent specific-force couplings: the sixth term
is below ``1e-22``), after one scaling by ``2^-s`` and ``s`` squarings above. It differs
from :func:`~navlib.discretize.expm_taylor` (degree 12 after scaling to 0.5) by rounding,
not truncation (``tests/test_sparse_discretize.py``: within 1e-12 of the largest entry per
step, and the whole rocket EKF within the golden tolerances measured across BLAS kernels).

Helpers are inlined into the one cached kernel and the sparsity patterns are found with
NumPy (:func:`_pattern`), which keeps its first compile to about 3 CPU-s.
"""

from __future__ import annotations

import numba
import numpy as np

from navlib.cache import drop_stale_kernel_caches
from navlib.discretize import discretize_steps

__all__ = ["TAYLOR_THETA", "compile_kernel", "discretize_kernel", "discretize_window",
           "pattern_kernel"]

TAYLOR_THETA = 4.0
"""Largest ``|A dt|`` (infinity norm) summed without scaling: rounding then stays within
``e^theta u ~ 1e-14`` of the exponential's norm."""
_MAX_TERMS = 40
_SERIES_ORDER = 4              # as navlib.discretize (Van Loan's series, "series")
_EPS = 2.0**-53


@numba.njit(inline="always")
def _axpy(a, x, y):
    """``y += a x`` (vectors)."""
    for j in range(y.size):
        y[j] += a * x[j]


@numba.njit(inline="always")
def _noise(G, pairs, weights, g_start, g_rows, W):
    """``W = G Qc G'`` (n, n) as ``sum Qc[a, b] G[:, a] G[:, b]'`` over the non-zero
    ``Qc[a, b]`` (``pairs`` (p, 2), ``weights`` (p,)) and the non-zero rows of those
    columns (``g_start``, ``g_rows``: the columns of :func:`_pattern`)."""
    n = W.shape[0]
    for i in range(n):
        for j in range(n):
            W[i, j] = 0.0
    for p in range(weights.size):
        a, b = pairs[p, 0], pairs[p, 1]
        for u in range(g_start[a], g_start[a + 1]):
            i = g_rows[u]
            ci = weights[p] * G[i, a]
            for v in range(g_start[b], g_start[b + 1]):
                W[i, g_rows[v]] += ci * G[g_rows[v], b]


@numba.njit(inline="always")
def _expm(A, h, a_start, a_cols, live, E, T, T2):
    """``E = expm(A h)`` (module docstring) over the non-zero entries of ``A`` (``a_start``,
    ``a_cols``: its rows by :func:`_pattern`; ``live``: the rows with any). The Taylor terms
    ``T_k = A h T_(k-1) / k`` are zero outside the live rows for ``k >= 1``, so from the
    second term on only live rows and columns of ``A`` enter."""
    n = A.shape[0]
    norm = 0.0                                 # |A h| in the infinity norm
    for i in range(n):
        s = 0.0
        for u in range(a_start[i], a_start[i + 1]):
            s += abs(A[i, a_cols[u]])
        norm = max(norm, s * h)
    squarings = 0
    while norm > TAYLOR_THETA:
        norm *= 0.5
        squarings += 1
    c = h * 0.5**squarings
    for i in range(n):
        for j in range(n):
            E[i, j] = 0.0
        E[i, i] = 1.0
        if live[i]:
            for j in range(n):
                T[i, j] = 0.0
            for u in range(a_start[i], a_start[i + 1]):
                T[i, a_cols[u]] = c * A[i, a_cols[u]]
            for j in range(n):
                E[i, j] += T[i, j]
    for k in range(2, _MAX_TERMS + 1):
        ck = c / k
        t_norm = 0.0
        for i in range(n):
            if not live[i]:
                continue
            out = T2[i]
            for j in range(n):
                out[j] = 0.0
            for u in range(a_start[i], a_start[i + 1]):
                l = a_cols[u]
                if live[l]:
                    _axpy(ck * A[i, l], T[l], out)
            s = 0.0
            for j in range(n):
                E[i, j] += T2[i, j]
                s += abs(T2[i, j])
            t_norm = max(t_norm, s)
        T, T2 = T2, T
        if k + 1 > 2.0 * norm and t_norm <= _EPS:
            break
    for _ in range(squarings):
        for i in range(n):
            for j in range(n):
                T[i, j] = E[i, j]
        for i in range(n):
            for j in range(n):
                s = 0.0
                for l in range(n):
                    s += T[i, l] * T[l, j]
                E[i, j] = s


@numba.njit(inline="always")
def _van_loan(A, W, h, a_start, a_cols, live, Q, L, AL):
    """``Q = sum_(k=0..4) L_k h^(k+1) / (k+1)!`` with ``L_0 = W``,
    ``L_k = A L_(k-1) + (A L_(k-1))'`` (:func:`navlib.discretize.discretize_steps`,
    ``"series"``) over the non-zero entries of ``A`` (as :func:`_expm`; ``live`` (n,) the
    indices of the live rows first, then the others): ``A L`` is zero outside the live
    rows (``AL`` must hold zeros there on entry), so ``L_k`` (``k >= 1``) is zero where
    neither the row nor the column is live."""
    n = A.shape[0]
    n_live = 0
    while n_live < n and a_start[live[n_live] + 1] > a_start[live[n_live]]:
        n_live += 1
    for i in range(n):
        for j in range(n):
            L[i, j] = W[i, j]
            Q[i, j] = W[i, j] * h
    factor = h
    for k in range(1, _SERIES_ORDER + 1):
        for u in range(n_live):
            i = live[u]
            out = AL[i]
            for j in range(n):
                out[j] = 0.0
            for v in range(a_start[i], a_start[i + 1]):
                _axpy(A[i, a_cols[v]], L[a_cols[v]], out)
        factor = factor * h / (k + 1)
        for u in range(n_live):
            i = live[u]
            row, q_row = L[i], Q[i]
            for j in range(n):
                row[j] = AL[i, j]
            for v in range(n_live):
                row[live[v]] += AL[live[v], i]
            _axpy(factor, row, q_row)
        for u in range(n_live, n):
            i = live[u]
            if k == 1:
                for v in range(n_live, n):
                    L[i, live[v]] = 0.0
            for v in range(n_live):
                w = L[live[v], i]
                L[i, live[v]] = w
                Q[i, live[v]] += w * factor


@numba.njit(cache=True)
def discretize_kernel(A, G, dt, pattern, F, Q):
    """``F[j]``, ``Q[j]`` (K, n, n) of the steps ``A[j]``, ``G[j]``, ``dt[j]`` (K, ...):
    :func:`navlib.discretize.discretize_steps` with ``method="series"``, over the non-zero
    entries of ``A``, ``G`` and ``Qc`` (``pattern`` of :func:`_pattern`; module
    docstring).

    Parameters
    ----------
    A, G, dt : numpy.ndarray
        Dynamics, noise input and step per step.
    pattern : tuple
        Sparsity pattern of ``A``, ``G`` and ``Qc``.
    F, Q : numpy.ndarray
        Outputs, written in place.
    """
    a_start, a_cols, live, g_start, g_rows, pairs, weights = pattern
    steps, n = A.shape[0], A.shape[1]
    flags = np.zeros(n, dtype=np.bool_)
    for i in range(n):
        flags[i] = a_start[i + 1] > a_start[i]
    W, T, T2 = np.empty((n, n)), np.empty((n, n)), np.zeros((n, n))
    for s in range(steps):
        h = dt[s]
        _noise(G[s], pairs, weights, g_start, g_rows, W)
        _expm(A[s], h, a_start, a_cols, flags, F[s], T, T2)
        for i in range(n):
            if not flags[i]:
                for j in range(n):
                    T2[i, j] = 0.0
        _van_loan(A[s], W, h, a_start, a_cols, live, Q[s], T, T2)


@numba.njit(cache=True)
def _used(A, G, a_used, g_used):
    """Flags of the entries of ``A`` (K, n, n) and ``G`` (K, n, q) that are non-zero in any
    step into ``a_used`` (n, n) and ``g_used`` (q, n) (``G`` by column)."""
    for i in range(A.shape[1]):
        for j in range(A.shape[2]):
            a_used[i, j] = False
        for j in range(G.shape[2]):
            g_used[j, i] = False
    for k in range(A.shape[0]):
        for i in range(A.shape[1]):
            for j in range(A.shape[2]):
                if A[k, i, j] != 0.0:
                    a_used[i, j] = True
            for j in range(G.shape[2]):
                if G[k, i, j] != 0.0:
                    g_used[j, i] = True


@numba.njit(cache=True)
def pattern_kernel(A, G, pairs, weights):
    """:func:`_pattern` compiled, for loops that run in a kernel
    (:mod:`navlib.filters.ekf_loop`).

    Parameters
    ----------
    A, G : ndarray (K, n, n), (K, n, q)
        The steps' dynamics and noise input.
    pairs, weights : ndarray (p, 2), (p,)
        The non-zero entries of ``Qc`` and their values.

    Returns
    -------
    tuple
        The arrays of :func:`_pattern`, for :func:`discretize_kernel`.
    """
    n, q = A.shape[1], G.shape[2]
    used, g_used = np.empty((n, n), dtype=np.bool_), np.empty((q, n), dtype=np.bool_)
    _used(A, G, used, g_used)
    a_start, g_start = np.zeros(n + 1, dtype=np.int64), np.zeros(q + 1, dtype=np.int64)
    for i in range(n):
        a_start[i + 1] = a_start[i] + used[i].sum()
    for j in range(q):
        g_start[j + 1] = g_start[j] + g_used[j].sum()
    a_cols, g_rows = np.empty(a_start[n], dtype=np.int64), np.empty(g_start[q], dtype=np.int64)
    live = np.empty(n, dtype=np.int64)
    u, front = 0, 0
    for i in range(n):
        for j in range(n):
            if used[i, j]:
                a_cols[u] = j
                u += 1
        if a_start[i + 1] > a_start[i]:
            live[front] = i
            front += 1
    for i in range(n):
        if a_start[i + 1] == a_start[i]:
            live[front] = i
            front += 1
    u = 0
    for j in range(q):
        for i in range(n):
            if g_used[j, i]:
                g_rows[u] = i
                u += 1
    return a_start, a_cols, live, g_start, g_rows, pairs, weights


_PATTERNS: dict = {}
""":func:`_pattern` by the non-zero flags and ``Qc`` it was found from (the EKF's windows
repeat a handful)."""


def _pattern(A, G, Qc):
    """The non-zero entries of a window's ``A`` (K, n, n) (in any step; rows: ``start``,
    ``columns``, and the row order with the rows that have any first), of ``G`` (K, n, q)
    (by column: ``start``, ``rows``) and of ``Qc`` (``pairs`` (p, 2), ``weights`` (p,)),
    kept in :data:`_PATTERNS`."""
    used = np.empty(A.shape[1:], dtype=np.bool_)
    g_used = np.empty((G.shape[2], G.shape[1]), dtype=np.bool_)
    _used(A, G, used, g_used)
    key = (used.tobytes(), g_used.tobytes(), used.shape, g_used.shape, Qc.tobytes())
    found = _PATTERNS.get(key)
    if found is None:
        a_start = np.concatenate([[0], np.cumsum(used.sum(axis=1))]).astype(np.int64)
        live = np.argsort(~used.any(axis=1), kind="stable").astype(np.int64)
        g_start = np.concatenate([[0], np.cumsum(g_used.sum(axis=1))]).astype(np.int64)
        pairs = np.argwhere(Qc != 0.0).astype(np.int64)
        found = (a_start, np.nonzero(used)[1].astype(np.int64), live, g_start,
                 np.nonzero(g_used)[1].astype(np.int64), pairs, Qc[pairs[:, 0], pairs[:, 1]])
        if len(_PATTERNS) >= 64:
            _PATTERNS.clear()
        _PATTERNS[key] = found
    return found


def discretize_window(A, G, Qc, dt, method: str, out=None):
    """``F``, ``Q`` (K, n, n) of the steps ``A`` (K, n, n), ``G`` (K, n, q), ``dt`` (K,)
    with ``Qc`` (q, q) (the EKF's own arrays: no input checks): :func:`discretize_kernel`
    for ``method="series"``, written into the first K steps of ``out`` ``(F, Q)`` when given
    (the EKF reuses one pair of buffers over its windows); ``"euler"`` (``I + A dt``,
    ``G Qc G' dt``: a few batched NumPy operations) is
    :func:`navlib.discretize.discretize_steps`'s.

    Parameters
    ----------
    A, G, Qc, dt : numpy.ndarray
        Dynamics (K, n, n), noise input (K, n, q), noise PSD (q, q) and steps (K,), s.
    method : {"series", "euler", "expm"}
        Discretisation.
    out : tuple of numpy.ndarray or None, optional
        Buffers ``(F, Q)`` to write into.

    Returns
    -------
    tuple of numpy.ndarray
        ``(F, Q)``.
    """
    if method != "series":
        return discretize_steps(A, G, Qc, dt, method=method)
    A, G = np.ascontiguousarray(A, dtype=float), np.ascontiguousarray(G, dtype=float)
    steps, n = A.shape[0], A.shape[1]
    if out is None:
        F, Q = np.empty((steps, n, n)), np.empty((steps, n, n))
    else:
        F, Q = out[0][:steps], out[1][:steps]
    discretize_kernel(A, G, np.ascontiguousarray(dt, dtype=float),
                      _pattern(A, G, np.asarray(Qc, dtype=float)), F, Q)
    return F, Q


def compile_kernel() -> None:
    """Run :func:`discretize_kernel` once on a one-step two-state model: compiles it (about
    3 CPU-s) on the first run on a machine, loads it from numba's disk cache afterwards
    (README "Compiled kernels")."""
    discretize_window(np.zeros((1, 2, 2)), np.zeros((1, 2, 1)), np.eye(1), np.ones(1),
                      "series")


drop_stale_kernel_caches(__name__, globals())  # numba checks only this file (numba #1833)
