"""Numerical resolution: which printed numbers are round-off and must not be shown as digits.

A singular value or residual below ``max(M, N) * eps`` of the largest singular value of an
M x N matrix is indistinguishable from zero in double precision (numpy.linalg.matrix_rank's
default tolerance); its digits change with the BLAS kernel, the thread count and the CPU.
Texts and report tables print such values as a bound ("< 1e-14 of the largest"), never as
digits (docs/assumptions.md, "Numerical resolution").
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["format_resolved", "relative_resolution"]


def relative_resolution(shape) -> float:
    """``max(shape) * eps``: the resolution of singular values relative to the largest."""
    return max(shape) * float(np.finfo(float).eps)


def format_resolved(value: float, scale: float, rtol: float, fmt: str = ".2g",
                    of: str | None = "the largest") -> str:
    """``value`` formatted with ``fmt``, or ``"< 1e-14 of the largest"`` when
    ``|value| <= rtol * scale`` (the bound is ``rtol`` rounded up to a power of ten).

    Parameters
    ----------
    value, scale : float
        The number and the scale it is resolved against (e.g. the largest singular value).
    rtol : float
        Relative resolution, e.g. :func:`relative_resolution` of the matrix.
    fmt : str
        Format of a resolved value.
    of : str or None
        Words naming the scale (None: the bound alone, for a scale of 1 in the value's unit).
    """
    if abs(value) <= rtol * abs(scale):
        bound = f"< {10.0 ** math.ceil(math.log10(rtol)):.0e}"
        return f"{bound} of {of}" if of else bound
    return format(value, fmt)
