"""Per-step discretisation and covariance prediction of the EKF, compiled and sparse
(:func:`navlib.filters.ekf.ekf`; docs/assumptions.md "Compiled kernels", "EKF step kernels").

The error models of the EKF are sparse and block triangular: in the 21-state ECEF model 58
of the 441 entries of ``A`` are ever non-zero and only the nine navigation rows have
off-diagonal terms (the twelve IMU parameters are random walks); the launcher models add
diagonal Markov decays. :func:`discretize_kernel` computes what
:func:`navlib.discretize.discretize_steps` does (``"series"``: ``F = expm(A dt)`` and Van
Loan's integral by its order-4 Taylor series; ``"euler"``: ``F = I + A dt``, ``Q = W dt``,
``W = G Qc G'``) one step at a time with products that skip the zero entries of ``A``,
``G`` and of the Taylor terms; the covariance prediction
(:func:`navlib.kalman.predict_sparse`) multiplies only the rows of ``F`` that are not
diagonal.

The exponential is the Taylor series ``sum_k (A dt)^k / k!`` summed until a term is below
``2^-53`` of the sum, without scaling while ``|A dt|_1 <=`` :data:`TAYLOR_THETA` (the rocket's
steps reach 1.6, dominated by the nilpotent specific-force couplings: the sixth term is
below ``1e-22``), with one shared scaling by ``2^-s`` and ``s`` squarings above. The result
differs from :func:`~navlib.discretize.expm_taylor` (degree 12 after scaling to 0.5) by
rounding, not truncation (``tests/filters/test_ekf_steps.py`` compares both with the NumPy
code at a tolerance that holds across BLAS kernels).

Kernels use ``fastmath`` without the finite-math flags (the EKF's divergence check reads
non-finite states), element loops and :func:`numpy.empty` only, which compile in about a
second (``benchmarks/bench_ekf.py`` prints the first-compile time).
"""

from __future__ import annotations

import numba
import numpy as np

TAYLOR_THETA = 4.0
"""Largest ``|A dt|_1`` summed without scaling: rounding then stays within
``e^theta u ~ 1e-14`` of the exponential's norm."""
_MAX_TERMS = 40
_SERIES_ORDER = 4              # as navlib.discretize (Van Loan's series, "series")
_FAST = {"nsz", "arcp", "contract", "reassoc"}
_EPS = 2.0**-53


@numba.njit(cache=True, fastmath=_FAST, inline="always")
def _axpy(a, x, y):
    """``y += a x`` (vectors)."""
    for j in range(y.size):
        y[j] += a * x[j]


@numba.njit(cache=True)
def _pattern(M, transpose):
    """Compressed rows ``(start, index)`` of the entries of ``M`` (K, r, c) that are non-zero
    in any of its K matrices (of ``M``'s transposes with ``transpose``: its columns)."""
    steps, r, c = M.shape
    used = np.zeros((r, c), dtype=np.bool_)
    for s in range(steps):
        for i in range(r):
            for j in range(c):
                if M[s, i, j] != 0.0:
                    used[i, j] = True
    outer, inner = (c, r) if transpose else (r, c)
    start = np.zeros(outer + 1, dtype=np.int64)
    index = np.empty(r * c, dtype=np.int64)
    count = 0
    for a in range(outer):
        for b in range(inner):
            if used[b, a] if transpose else used[a, b]:
                index[count] = b
                count += 1
        start[a + 1] = count
    return start, index[:count]


@numba.njit(cache=True, fastmath=_FAST)
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


@numba.njit(cache=True, fastmath=_FAST)
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


@numba.njit(cache=True, fastmath=_FAST)
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


@numba.njit(cache=True, fastmath=_FAST)
def discretize_kernel(A, G, Qc, dt, series, F, Q):
    """``F[j]``, ``Q[j]`` (K, n, n) of the steps ``A[j]``, ``G[j]``, ``dt[j]`` (K, ...):
    :func:`navlib.discretize.discretize_steps` with ``method="series"`` (``series``) or
    ``"euler"``, over the non-zero entries (module docstring)."""
    steps, n = A.shape[0], A.shape[1]
    q = Qc.shape[0]
    a_start, a_cols = _pattern(A, False)
    g_start, g_rows = _pattern(G, True)
    pairs, weights = np.empty((q * q, 2), dtype=np.int64), np.empty(q * q)
    count = 0
    for a in range(q):
        for b in range(q):
            if Qc[a, b] != 0.0:
                pairs[count, 0], pairs[count, 1], weights[count] = a, b, Qc[a, b]
                count += 1
    pairs, weights = pairs[:count], weights[:count]
    live = np.empty(n, dtype=np.int64)        # live rows first (_van_loan)
    flags = np.empty(n, dtype=np.bool_)
    count = 0
    for i in range(n):
        flags[i] = a_start[i + 1] > a_start[i]
        if flags[i]:
            live[count] = i
            count += 1
    for i in range(n):
        if not flags[i]:
            live[count] = i
            count += 1
    W, T, T2 = np.empty((n, n)), np.empty((n, n)), np.zeros((n, n))
    for s in range(steps):
        h = dt[s]
        _noise(G[s], pairs, weights, g_start, g_rows, W)
        if not series:
            for i in range(n):
                for j in range(n):
                    F[s, i, j] = A[s, i, j] * h
                    Q[s, i, j] = W[i, j] * h
                F[s, i, i] += 1.0
            continue
        _expm(A[s], h, a_start, a_cols, flags, F[s], T, T2)
        for i in range(n):
            if not flags[i]:
                for j in range(n):
                    T2[i, j] = 0.0
        _van_loan(A[s], W, h, a_start, a_cols, live, Q[s], T, T2)


def discretize_window(A, G, Qc, dt, method: str):
    """``F``, ``Q`` (K, n, n) of :func:`discretize_kernel` for ``A`` (K, n, n), ``G``
    (K, n, q), ``Qc`` (q, q), ``dt`` (K,) and ``method`` ``"series"`` or ``"euler"`` (the
    EKF's own arrays: no input checks)."""
    steps, n = A.shape[0], A.shape[1]
    F, Q = np.empty((steps, n, n)), np.empty((steps, n, n))
    discretize_kernel(np.ascontiguousarray(A, dtype=float), np.ascontiguousarray(G, dtype=float),
                      np.ascontiguousarray(Qc, dtype=float), np.ascontiguousarray(dt, dtype=float),
                      method == "series", F, Q)
    return F, Q
