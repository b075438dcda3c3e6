"""Comparing two code paths that compute the same numbers.

Two routes to one result (block-wise vs step by step, batched vs one at a time, compact vs
full preparation, gains kept by the recursion vs gains recomputed from its priors) may order
their floating-point operations differently on another CPU or BLAS kernel even where they
are bitwise equal here (they are, on the reference machine, with the OpenBLAS kernels
SkylakeX, Haswell and Sandybridge and with one or two threads). So they are compared at
``CROSS_PATH_RTOL`` of each array's largest magnitude: far below any change of the algorithm
(a changed noise value moves these arrays by 1e-3 and more), far above reordered round-off.
Bitwise comparisons stay where bitwise is the point: the same path run twice, a cached
result against a fresh one.
"""

import numpy as np

CROSS_PATH_RTOL = 1e-9


def assert_same_numbers(got, want, name: str = "", rtol: float = CROSS_PATH_RTOL) -> None:
    """``got`` equals ``want`` (same shape, NaN where NaN) to ``rtol`` times the largest
    finite ``|want|``."""
    got, want = np.asarray(got), np.asarray(want)
    assert got.shape == want.shape, f"{name}: shape {got.shape} != {want.shape}"
    assert np.array_equal(np.isnan(got), np.isnan(want)), f"{name}: NaN pattern differs"
    finite = np.isfinite(want)
    scale = np.abs(want[finite]).max(initial=0.0)
    np.testing.assert_allclose(got[finite], want[finite], rtol=0, atol=rtol * scale,
                               err_msg=name)
