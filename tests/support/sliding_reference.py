"""NumPy reference of the compiled sliding window (issue 26): the batched NumPy code that
:func:`navlib.observability.sliding.sliding_singular_values` replaced, kept here (not in the
library) to compare against (tests/observability/test_sliding_kernels.py) and to time against
(benchmarks/bench_observability.py).
"""

from __future__ import annotations

import numpy as np

from navlib.observability.sliding import block_data


def gram_rows(X, n: int) -> np.ndarray:
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



def suffix_factors(Hb, Fb):
    """Block suffixes of eq. (6): ``Y[:, r]`` (n x n) has the Gram matrix of the block rows
    ``H_r; H_{r+1} F_r; ...; H_{w-1} F_{w-2} ... F_r`` of each block, and
    ``Phi[:, r] = F_{w-1} ... F_r`` maps step ``r`` to the next block's start.

    Backward recursion ``Y_r = R([H_r; Y_{r+1} F_r])``, one (m + n) x n QR per step.
    """
    nb, w, m, n = Hb.shape
    Y = np.empty((nb, w, n, n))
    Phi = np.empty((nb, w, n, n))
    Y[:, w - 1] = gram_rows(Hb[:, w - 1], n)
    Phi[:, w - 1] = Fb[:, w - 1]
    stack = np.empty((nb, m + n, n))
    for r in range(w - 2, -1, -1):
        stack[:, :m] = Hb[:, r]
        np.matmul(Y[:, r + 1], Fb[:, r], out=stack[:, m:])
        Y[:, r] = np.linalg.qr(stack, mode="r")
        np.matmul(Phi[:, r + 1], Fb[:, r], out=Phi[:, r])
    return Y, Phi


def prefix_factors(Hb, Fb):
    """Block prefixes of eq. (6): ``P[:, j]`` (n x n) has the Gram matrix of the first
    ``j + 1`` block rows from each block's start, ``H_0; H_1 F_0; ...; H_j F_{j-1} ... F_0``.

    Forward recursion ``P_j = R([P_{j-1}; H_j Psi_j])`` with ``Psi_j = F_{j-1} ... F_0``.
    """
    nb, w, m, n = Hb.shape
    P = np.empty((nb, max(w - 1, 0), n, n))
    if w < 2:
        return P
    P[:, 0] = gram_rows(Hb[:, 0], n)
    psi = Fb[:, 0]
    stack = np.empty((nb, n + m, n))
    for j in range(1, w - 1):
        stack[:, :n] = P[:, j - 1]
        np.matmul(Hb[:, j], psi, out=stack[:, n:])
        P[:, j] = np.linalg.qr(stack, mode="r")
        if j < w - 2:
            psi = Fb[:, j] @ psi
    return P


def sliding_singular_values(transitions, H, k0: int, K: int, window: int) -> np.ndarray:
    """Singular values of eq. (6)'s ``O(k)`` at the consecutive steps ``k0 .. k0 + K - 1``.

    Two-stack sliding window (docs/assumptions.md, launcher.md §6.1): with blocks of ``w``
    steps from ``k0``, the window of step ``k = b w + r`` is the suffix of block ``b`` from
    ``r`` (``w - r`` block rows) followed by the first ``r`` block rows of block ``b + 1``
    times the suffix transition, so ``O(k)`` is orthogonally equivalent to
    ``[Y_r; P_{r-1} Phi_r]`` (2n x n, see :func:`suffix_factors`, :func:`prefix_factors`)
    and has its singular values. Per step: two (m + n) x n QRs, four n x n products and the
    SVD of one 2n x n stack, instead of forming the ``w m x n`` matrix (``w - 1`` block
    products) and factorising it. Each factor is a backward-stable QR and the transitions
    over a window are well scaled (Euler steps ``I + A dt``), so the singular values agree
    with the direct ones to a few rounding units of ``sigma_max``
    (tests/observability/test_local_sliding.py).
    """
    n = H.shape[2]
    n_blocks = -(-K // window)
    Hb, Fb = block_data(transitions, H, k0, n_blocks, window)
    Y, Phi = suffix_factors(Hb[:-1], Fb[:-1])
    P = prefix_factors(Hb[1:], Fb[1:])
    C = np.empty((n_blocks, window, 2 * n, n))
    C[:, :, :n] = Y
    C[:, 0, n:] = 0.0
    np.matmul(P, Phi[:, 1:], out=C[:, 1:, n:])
    return np.linalg.svd(C.reshape(-1, 2 * n, n)[:K], compute_uv=False)

