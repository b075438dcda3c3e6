"""Copies inside the compiled (numba) kernels, entry by entry.

A kernel that assigns an array to a slice (``dst[:, :] = src``) makes numba compile a shape
check whose error message formats both shapes: that string formatting was about half of the
first compile of navlib's kernels (README "Compiled kernels"). The kernels of
:mod:`navlib.kalman` and :mod:`navlib.observability.sliding` copy with these instead.
"""

from __future__ import annotations

import numba

__all__ = ["copy_matrix", "copy_vector"]


@numba.njit(cache=True, nogil=True)
def copy_matrix(src, dst):
    """``dst[:, :] = src`` entry by entry (matrices of one shape)."""
    for i in range(src.shape[0]):
        for j in range(src.shape[1]):
            dst[i, j] = src[i, j]


@numba.njit(cache=True, nogil=True)
def copy_vector(src, dst):
    """``dst[:] = src`` entry by entry (vectors of one length)."""
    for i in range(src.shape[0]):
        dst[i] = src[i]
