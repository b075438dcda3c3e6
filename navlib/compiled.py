"""Every compiled (numba) kernel of navlib, warmed in one call.

:func:`compile_kernels` runs each kernel once on tiny inputs: on the first run on a machine
it compiles them, afterwards it loads them from numba's disk cache (``cache=True``), so the
notebook kernels a report starts at once only load (README "Compiled kernels" gives the
costs). The kernels live beside the NumPy code they replace: the Kalman algebra
(:mod:`navlib.kalman`), the linear simulation (:mod:`navlib.filters.linear_recursion`), the
strapdown mechanisation (:mod:`navlib.strapdown_kernel`) and the every-step observability
test (:mod:`navlib.observability.sliding`).

A report warms the kernels several notebooks share before the notebooks start, in two
processes (:func:`compile_kalman_kernels` beside :func:`compile_other_kernels`).
The every-step observability window has one user in a report, Table 2 at every step
(notebook 02; the claims summary starts after it and reads the cache it wrote), so it
compiles there, on its first use, while the other core runs another notebook.
"""

from navlib import kalman, strapdown_kernel
from navlib.filters import linear_recursion
from navlib.observability import sliding


def compile_kernels() -> None:
    """Compile (first run on a machine) or load (afterwards) every kernel of navlib."""
    compile_kalman_kernels()
    compile_other_kernels()
    sliding.compile_kernel()


def compile_kalman_kernels() -> None:
    """The Kalman kernels (:func:`navlib.kalman.compile_kernels`): more than half of the
    shared kernels' first compile, so a report compiles them in a second process beside
    :func:`compile_other_kernels`."""
    kalman.compile_kernels()


def compile_other_kernels() -> None:
    """The linear simulation's and the strapdown mechanisation's kernels."""
    linear_recursion.compile_recursion_kernels()
    strapdown_kernel.compile_kernel()
