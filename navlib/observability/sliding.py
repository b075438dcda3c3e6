"""Singular values of eq. (6)'s local matrix at every step: the two-stack sliding window.

With blocks of ``w`` steps from ``k0``, the window of step ``k = b w + r`` is the suffix of
block ``b`` from ``r`` (``w - r`` block rows) followed by the first ``r`` block rows of block
``b + 1`` times the suffix transition, so ``O(k)`` is orthogonally equivalent to
``[Y_r; P_{r-1} Phi_r]`` (2n x n) and has its singular values (docs/assumptions.md,
"docs/assumptions.md, launcher.md §7.2"; docs/assumptions.md, launcher.md §6.1):

* suffixes ``Y_r`` (n x n, upper triangular) by the backward recursion
  ``Y_r = R([H_r; Y_{r+1} F_r])`` with ``Phi_r = F_{w-1} ... F_r``;
* prefixes ``P_j = R([P_{j-1}; H_j Psi_j])`` of the next block, ``Psi_j = F_{j-1} ... F_0``;
* per step the triangular factor of ``[Y_r; P_{r-1} Phi_r]`` and its singular values.

The whole recursion of a chunk of steps runs in one compiled kernel (numba, ``cache=True``;
docs/assumptions.md, "Compiled kernels"): Householder reductions that use the triangular
blocks (a fold of ``p`` rows into an n x n triangle costs ``2 (p + 1) n^2`` flops), a
Golub-Kahan bidiagonalisation of the n x n factor and LAPACK's ``dlasq1`` (dqds, as in the
``dgesdd`` NumPy calls) for its singular values; the products are BLAS calls. The kernel
keeps the factors transposed (``Y_r'``, ``P_j'``, lower triangular), so that each reflector
works along contiguous memory: a dot product per column, which numba may vectorise
(``fastmath={"reassoc"}`` in :func:`_reflect` only: the sums of one dot product in another
order, a rounding-level change). The kernels use numba's ``error_model="numpy"`` (IEEE
division, no division-by-zero check to compile: none of their divisors is zero) and allocate
their scratch once per chunk. The NumPy code it replaced is kept in
tests/support/sliding_reference.py to compare against.
"""

from __future__ import annotations

import numba
import numpy as np
from llvmlite import binding
from numba import types
from numba.extending import get_cython_function_address

from navlib.cache import drop_stale_kernel_caches
from navlib.errors import NavlibInputError
from navlib.kernel_copy import copy_matrix

__all__ = ["block_data", "compile_kernel", "fold", "householder", "singular_values",
           "sliding_kernel", "sliding_singular_values", "triangularize"]

_DLASQ1 = "navlib_dlasq1"
binding.add_symbol(_DLASQ1, get_cython_function_address("scipy.linalg.cython_lapack", "dlasq1"))
_dlasq1 = types.ExternalFunction(_DLASQ1, types.void(*[types.voidptr] * 5))
"""LAPACK ``dlasq1(n, d, e, work, info)``: singular values of a bidiagonal matrix (SciPy's
LAPACK, bound by a named symbol so that the kernels stay in numba's disk cache)."""


def block_data(transitions, H, k0: int, n_blocks: int, window: int):
    """``H`` (n_blocks + 1, w, m, n) and ``F`` (n_blocks + 1, w, n, n) of the steps from
    ``k0`` in blocks of ``w``; past the mission ``H = 0`` and ``F = I``, which only steps
    without a complete window read. Inside the mission both are the caller's steps as they
    are (``H`` a view when it is contiguous, ``F`` the array ``transitions`` returns).

    Parameters
    ----------
    transitions : callable
        ``transitions(idx)`` returns the (len(idx), n, n) steps ``F_k`` at the indices.
    H : ndarray (N, m, n)
        Measurement matrices of the mission.
    k0 : int
        First step.
    n_blocks : int
        Blocks after the first.
    window : int
        Steps per block ``w``.

    Returns
    -------
    Hb, Fb : ndarray
    """
    m, n = H.shape[1:]
    size = (n_blocks + 1) * window
    shape = (n_blocks + 1, window)
    if k0 + size <= H.shape[0]:
        Hs = np.ascontiguousarray(H[k0:k0 + size], dtype=float)
    else:
        Hs = np.zeros((size, m, n))
        Hs[:H.shape[0] - k0] = H[k0:]
    inside = min(size, H.shape[0] - 1 - k0)
    F = np.ascontiguousarray(transitions(np.arange(k0, k0 + inside)), dtype=float)
    if inside == size:
        Fs = F
    else:
        Fs = np.empty((size, n, n))
        Fs[:inside] = F
        Fs[inside:] = np.eye(n)
    return Hs.reshape(*shape, m, n), Fs.reshape(*shape, n, n)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def householder(alpha, x):
    """Reflector ``I - tau [1; v] [1; v]'`` mapping ``[alpha; x]`` to ``[beta; 0]``
    (LAPACK ``dlarfg``): returns ``(beta, tau)`` and overwrites ``x`` with ``v``; ``tau = 0``
    (no reflection) when ``x`` is zero.

    Parameters
    ----------
    alpha : float
        First entry of the vector.
    x : ndarray (p,)
        The rest; overwritten with ``v``.

    Returns
    -------
    beta, tau : float
    """
    scale = 0.0
    for i in range(x.size):
        scale = max(scale, abs(x[i]))
    if scale == 0.0:
        return alpha, 0.0
    squares = 0.0
    for i in range(x.size):
        squares += (x[i] / scale) ** 2
    beta = -np.copysign(np.hypot(alpha, scale * np.sqrt(squares)), alpha)
    inverse = 1.0 / (alpha - beta)
    for i in range(x.size):
        x[i] *= inverse
    return beta, (beta - alpha) / beta


@numba.njit(cache=True, nogil=True, fastmath={"reassoc"}, error_model="numpy")
def _reflect(head, tails, v, tau):
    """Apply the reflector ``(tau, [1; v])`` to columns given transposed: column ``c`` is
    ``head[c]`` followed by the last ``v.size`` entries of ``tails[c]`` (a dot product and
    an update along contiguous memory per column)."""
    start = tails.shape[1] - v.size
    for c in range(head.size):
        row = tails[c, start:]
        w = head[c]
        for i in range(v.size):
            w += row[i] * v[i]
        w *= tau
        head[c] -= w
        for i in range(v.size):
            row[i] -= w * v[i]


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _reflect_rows(top, rows, column, v, tau, work):
    """Apply the reflector ``(tau, [1; v])`` to ``[top; rows[:p, column + 1:]]`` in place
    (``p = v.size``, ``top`` the length-L row right of the pivot), row by row."""
    L = top.size
    w = work[:L]
    for c in range(L):
        w[c] = top[c]
    for i in range(v.size):
        vi = v[i]
        row = rows[i, column + 1:]
        for c in range(L):
            w[c] += vi * row[c]
    for c in range(L):
        w[c] *= tau
        top[c] -= w[c]
    for i in range(v.size):
        vi = v[i]
        row = rows[i, column + 1:]
        for c in range(L):
            row[c] -= vi * w[c]


@numba.njit(cache=True, nogil=True, error_model="numpy")
def fold(Rt, Xt):
    """``R`` becomes the triangular factor of ``[R; X]``, both given transposed: ``Rt``
    (n, n, lower triangular) is updated, ``Xt`` (n, p) overwritten. One reflector per
    column over ``R``'s diagonal entry and ``X``'s column: ``2 (p + 1) n^2`` flops.

    Parameters
    ----------
    Rt : ndarray (n, n)
        ``R'``, lower triangular; updated in place.
    Xt : ndarray (n, p)
        ``X'``; overwritten.
    """
    for j in range(Rt.shape[0]):
        v = Xt[j]
        beta, tau = householder(Rt[j, j], v)
        if tau != 0.0:
            Rt[j, j] = beta
            _reflect(Rt[j + 1:, j], Xt[j + 1:], v, tau)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def triangularize(At, Rt):
    """``Rt`` (n, n) becomes the transposed upper triangular factor of ``A`` (p, n), given
    transposed as ``At`` (n, p), zero beyond column ``min(p, n)`` (Householder QR); ``At`` is
    overwritten.

    Parameters
    ----------
    At : ndarray (n, p)
        ``A'``; overwritten.
    Rt : ndarray (n, n)
        Receives ``R'``.
    """
    n, p = At.shape
    for j in range(min(p - 1, n)):
        v = At[j, j + 1:]
        beta, tau = householder(At[j, j], v)
        if tau != 0.0:
            At[j, j] = beta
            _reflect(At[j + 1:, j], At[j + 1:], v, tau)
    Rt[:] = 0.0
    for c in range(n):
        for i in range(min(c + 1, p)):
            Rt[c, i] = At[c, i]


@numba.njit(cache=True, nogil=True, error_model="numpy")
def singular_values(A, s, work, lapack_ints):
    """Singular values of the square ``A`` (n, n; overwritten) into ``s``, descending.

    Golub-Kahan bidiagonalisation by reflectors from the left (columns) and the right (rows),
    then LAPACK ``dlasq1`` on the bidiagonal. ``work`` (at least ``6 n`` floats) and
    ``lapack_ints`` (two int32: ``dlasq1``'s ``n`` and ``info``) are scratch, allocated once
    per kernel run.

    Parameters
    ----------
    A : ndarray (n, n)
        Overwritten.
    s : ndarray (n,)
        Receives the singular values.
    work : ndarray (>= 6 n,)
        Float scratch.
    lapack_ints : ndarray (2,) of int32
        Integer scratch of ``dlasq1``.

    Returns
    -------
    int
        ``dlasq1``'s ``info`` (0: converged).
    """
    n = A.shape[0]
    e, v, lasq = work[:n], work[n:2 * n], work[2 * n:6 * n]  # e[:n - 1] all set below
    for j in range(n):
        below = v[:n - j - 1]
        for i in range(below.size):
            below[i] = A[j + 1 + i, j]
        s[j], tau = householder(A[j, j], below)
        if tau != 0.0:
            _reflect_rows(A[j, j + 1:], A[j + 1:], j, below, tau, lasq)
        if j < n - 2:
            right = v[:n - j - 2]
            for i in range(right.size):
                right[i] = A[j, j + 2 + i]
            e[j], tau = householder(A[j, j + 1], right)
            if tau != 0.0:
                _reflect(A[j + 1:, j + 1], A[j + 1:], right, tau)
        elif j == n - 2:
            e[j] = A[j, j + 1]
    lapack_ints[0] = n
    _dlasq1(lapack_ints.ctypes, s.ctypes, e.ctypes, lasq.ctypes, lapack_ints[1:].ctypes)
    return lapack_ints[1]


@numba.njit(cache=True, nogil=True, error_model="numpy")
def sliding_kernel(Hb, Fb, K, out):
    """Singular values (``out``, K x n) of ``O(k)`` at the first ``K`` steps of the blocks
    ``Hb`` (nb + 1, w, m, n), ``Fb`` (nb + 1, w, n, n) of :func:`block_data` (module
    docstring).

    Parameters
    ----------
    Hb, Fb : ndarray
        The blocks of :func:`block_data`.
    K : int
        Steps evaluated.
    out : ndarray (K, n)
        Receives the singular values.

    Returns
    -------
    int
        Steps whose ``dlasq1`` did not converge.
    """
    w, m, n = Hb.shape[1], Hb.shape[2], Hb.shape[3]
    Yt, Phi = np.empty((w, n, n)), np.empty((w, n, n))    # Yt[r] = Y_r', Phi[r] = Phi_r (r > 0)
    Pt = np.empty((max(w - 1, 1), n, n))                    # Pt[j] = P_j'
    stack, rows = np.empty((n, m + n)), np.empty((n, m))    # [H_r; Y F_r]', (H_j Psi_j)'
    Xt, psi, product = np.empty((n, n)), np.empty((n, n)), np.empty((n, n))
    work, lapack_ints = np.empty(6 * n), np.empty(2, np.int32)
    failed = 0
    for b in range(Hb.shape[0] - 1):
        copy_matrix(Hb[b, w - 1].T, rows)
        triangularize(rows, Yt[w - 1])
        copy_matrix(Fb[b, w - 1], Phi[w - 1])
        for r in range(w - 2, -1, -1):
            copy_matrix(Hb[b, r].T, stack[:, :m])
            np.dot(Fb[b, r].T, Yt[r + 1], product)
            copy_matrix(product, stack[:, m:])
            triangularize(stack, Yt[r])
            if r > 0:
                np.dot(Phi[r + 1], Fb[b, r], Phi[r])
        if w > 1:
            copy_matrix(Hb[b + 1, 0].T, rows)
            triangularize(rows, Pt[0])
            copy_matrix(Fb[b + 1, 0], psi)
        for j in range(1, w - 1):
            copy_matrix(Pt[j - 1], Pt[j])
            np.dot(psi.T, Hb[b + 1, j].T, rows)
            fold(Pt[j], rows)
            if j < w - 2:
                np.dot(Fb[b + 1, j], psi, product)
                psi, product = product, psi
        for r in range(min(w, K - b * w)):
            if r > 0:
                np.dot(Phi[r].T, Pt[r - 1], Xt)
                fold(Yt[r], Xt)
            failed += singular_values(Yt[r], out[b * w + r], work, lapack_ints) != 0
    return failed


def sliding_singular_values(transitions, H, k0: int, K: int, window: int) -> np.ndarray:
    """Singular values (K, n) of eq. (6)'s ``O(k)`` at the consecutive steps
    ``k0 .. k0 + K - 1`` (``window * m >= n``), by the two-stack sliding window (module
    docstring): per step two folds of ``m`` rows, one of ``n`` rows, four n x n products and
    the singular values of one n x n triangle, instead of forming the ``w m x n`` matrix
    (``w - 1`` block products) and factorising it. Each reduction is backward stable and the
    transitions over a window are well scaled (Euler steps ``I + A dt``), so the singular
    values agree with the direct ones to a few rounding units of ``sigma_max``
    (tests/observability/test_local_sliding.py).

    Parameters
    ----------
    transitions : callable
        ``transitions(idx)`` returns the (len(idx), n, n) steps ``F_k`` at the indices.
    H : ndarray (N, m, n)
        Measurement matrices of the mission.
    k0 : int
        First step.
    K : int
        Consecutive steps evaluated.
    window : int
        Block rows ``w`` of ``O(k)``.

    Returns
    -------
    ndarray (K, n)
        Descending singular values per step.
    """
    n = H.shape[2]
    n_blocks = -(-K // window)
    Hb, Fb = block_data(transitions, H, k0, n_blocks, window)
    s = np.empty((K, n))
    if sliding_kernel(Hb, Fb, K, s):  # pragma: no cover - dqds of finite input converges
        raise NavlibInputError("O(k): the singular values (LAPACK dlasq1) did not converge")
    return s


def compile_kernel() -> None:
    """Run :func:`sliding_kernel` once on a two-state, two-step window: compiles it (about
    7 CPU-s) on the first run on a machine, loads it from numba's disk cache afterwards
    (README "Compiled kernels")."""
    sliding_singular_values(lambda k: np.broadcast_to(np.eye(2), (k.size, 2, 2)),
                            np.ones((4, 1, 2)), 0, 2, 2)


drop_stale_kernel_caches(__name__, globals())  # numba checks only this file (numba #1833)
