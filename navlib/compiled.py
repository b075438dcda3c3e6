"""Every compiled (numba) kernel of navlib, warmed in one call.

:func:`compile_kernels` runs each kernel once on tiny inputs: on the first run on a machine
it compiles them, afterwards it loads them from numba's disk cache (``cache=True``), so the
notebook kernels a report starts at once only load (docs/performance.md, "Compiled
kernels", gives the costs). The kernels live beside the NumPy code they replace: the Kalman algebra
(:mod:`navlib.kalman`), the linear simulation (:mod:`navlib.filters.linear_recursion`), the
strapdown mechanisation (:mod:`navlib.strapdown`), the every-step observability
test (:mod:`navlib.observability.sliding`) and the 21-state EKF's compiled loop
(:mod:`navlib.filters.ekf_loop`, which no notebook of the report runs).

A report warms the kernels several notebooks share (:func:`compile_shared_kernels`) in a
process of its own while its longest notebook starts: Table 2 at every step (notebook 02;
the claims summary starts after it and reads the cache it wrote) uses none of them before
its every-step observability window, the one kernel only it uses, which it compiles on
first use.
"""

import numpy as np

from navlib import kalman, sparse_discretize, strapdown
from navlib.filters import ekf_loop, linear_recursion
from navlib.observability import sliding
from navlib.sensors import simulation

__all__ = ["compile_kernels", "compile_shared_kernels"]


def compile_kernels() -> None:
    """Compile (first run on a machine) or load (afterwards) every kernel of navlib."""
    compile_shared_kernels()
    sliding.compile_kernel()
    ekf_loop.compile_kernel()


def compile_shared_kernels() -> None:
    """The kernels several notebooks of a report use: the Kalman algebra
    (:func:`navlib.kalman.compile_kernels`), the linear simulation, the strapdown
    mechanisation, the sensor errors' Gauss-Markov recursion and the sparse model steps
    (the 21-state model of every rocket notebook)."""
    kalman.compile_kernels()
    linear_recursion.compile_recursion_kernels()
    strapdown.compile_kernel()
    sparse_discretize.compile_kernel()
    simulation.first_order_recursion(np.ones(1), np.ones((2, 1)), np.empty((2, 1)))
