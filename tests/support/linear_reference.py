"""NumPy reference of the compiled linear-simulation kernels (issue 26): the block functions
of :mod:`navlib.filters.linear` that :func:`navlib.filters.linear.truth_kernel` and
:func:`navlib.filters.linear.filter_kernel` replaced, kept here (not in the library) to
compare against (tests/filters/test_linear_kernels.py) and to time against
(benchmarks/bench_kernels.py). Same arguments as the library's block functions.
"""

from __future__ import annotations

import numpy as np


def truth_block(steps, block, work, draws, x_input) -> None:
    """True errors ``x_{k+1} = x_k F_k' (+ xi_k L_k') (+ u_k)`` of a block, into
    ``work.truth`` (``work.truth[j0]`` holds ``x_{k0}``)."""
    moves = block.moves
    FT = steps.F[moves].swapaxes(-1, -2)
    j0, x = block.j0, work.truth
    noise = None
    if draws is not None:
        noise = np.matmul(draws[0][j0:j0 + FT.shape[0]], steps.L[moves].swapaxes(-1, -2),
                          out=work.noise[:FT.shape[0]])
    for i in range(FT.shape[0]):
        j = j0 + i
        np.dot(x[j], FT[i], out=x[j + 1])
        if noise is not None:
            np.add(x[j + 1], noise[i], out=x[j + 1])
        if x_input is not None:
            np.add(x[j + 1], x_input[moves.start + i], out=x[j + 1])


def filter_block(prepared, block, work, meas) -> None:
    """The filter over a block: at an update ``x^+ = x^- + (z - x^- H') K'``, then
    ``x^-_{k+1} = x^+ F'`` (``work.prior[j0]`` holds the prior at ``k0``)."""
    steps = prepared.steps
    j0, j1 = block.j0, block.j1
    update = np.full(j1 - j0, -1)
    update[meas - j0] = np.arange(meas.size)
    moves = block.moves
    HT = steps.H[block.k0:block.k1].swapaxes(-1, -2)
    KT = prepared.gains.K[block.k0:block.k1].swapaxes(-1, -2)
    FT = steps.F[moves].swapaxes(-1, -2)
    last = moves.stop - block.c0
    prior, post, innov, z = work.prior, work.post, work.innov, work.z
    hx, gain_step = work.hx, work.gain_step
    for i, p in enumerate(update.tolist()):
        j = j0 + i
        estimate = prior[j]
        if p >= 0:
            np.dot(estimate, HT[i], out=hx)
            np.subtract(z[p], hx, out=innov[p])
            np.dot(innov[p], KT[i], out=gain_step)
            estimate = np.add(estimate, gain_step, out=post[j])
        if j < last:
            np.dot(estimate, FT[i], out=prior[j + 1])


