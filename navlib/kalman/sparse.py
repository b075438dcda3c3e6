"""The EKF's sparse covariance prediction, a compiled kernel of :mod:`navlib.kalman`
(docs/assumptions.md "Compiled kernels"): :func:`predict_sparse` forms ``sym(F P F' + Q)``
over the rows of ``F`` that hold off-diagonal entries only."""

from __future__ import annotations

import numba

__all__ = ["predict_sparse"]


@numba.njit(cache=True)
def predict_sparse(P, F, Q, out, FP, dense):
    """``out = sym(F P F' + Q)`` of one step over the rows of ``F`` with off-diagonal
    entries (flagged in ``dense`` (n,) here; ``FP`` (n, n) scratch): ``(F P)_i`` is
    ``F_ii P_i`` on a diagonal row, a pair of rows with a diagonal row ``j`` is
    ``(F P)_ij F_jj`` and only pairs of full rows take a dot product (the EKF's error
    models: 9 full rows of 21 in the ECEF model), so equal to :func:`predict_kernel` to
    rounding. ``out`` may be ``P``."""
    n = P.shape[0]
    for i in range(n):
        full = False
        for j in range(n):
            if j != i and F[i, j] != 0.0:
                full = True
                break
        dense[i] = full
        row = FP[i]
        if full:
            for j in range(n):
                row[j] = 0.0
            for l in range(n):
                f = F[i, l]
                if f != 0.0:
                    p_row = P[l]
                    for j in range(n):
                        row[j] += f * p_row[j]
        else:
            f = F[i, i]
            p_row = P[i]
            for j in range(n):
                row[j] = f * p_row[j]
    for i in range(n):
        fp_row = FP[i]
        for j in range(i, n):
            if not dense[j]:
                m = fp_row[j] * F[j, j]
            elif not dense[i]:
                m = FP[j, i] * F[i, i]
            else:
                f_row = F[j]
                m = 0.0
                for l in range(n):
                    m += fp_row[l] * f_row[l]
            s = m + 0.5 * (Q[i, j] + Q[j, i])
            out[i, j] = s
            out[j, i] = s
