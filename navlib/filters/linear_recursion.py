"""The linear simulation's recursion a block of steps at a time, with its compiled
kernels (docs/assumptions.md "Compiled kernels").

:func:`run_recursion` is the step loop of :func:`navlib.filters.linear.simulate_linear`:
per block of :data:`CHUNK` steps the true errors (:func:`truth_kernel`), their
measurements, the filter (:func:`filter_kernel`) and the recorded epochs, into
preallocated work arrays (:class:`Work`). The NumPy code the kernels replaced is
``tests/support/linear_reference.py``.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numba
import numpy as np

from navlib.cache import drop_stale_kernel_caches
from navlib.filters.linear_preparation import LinearFilter, LinearSteps
from navlib.kalman import kernel_array, psd_sqrt

__all__ = ["CHUNK", "Block", "Work", "compile_recursion_kernels", "filter_block", "filter_kernel",
           "measure_block", "noise_blocks", "record_block", "run_recursion", "truth_block",
           "truth_kernel"]

CHUNK = 256
"""Steps per block of :func:`run_recursion`: its noise is drawn a block at a time (this fixes
the random stream), and the block's truth, measurements and NIS are formed together."""


def run_recursion(prepared, x, x_hat, z_add, x_input, k0, rng, progress, slot, upd_slot, out):
    """Steps ``k0 ..`` of :func:`_simulate`, writing into ``out`` (truth, estimate and
    innovation at the recorded epochs, NIS at the updates).

    A block of :data:`CHUNK` steps at a time: the true errors first (they do not depend on
    the estimate; :func:`truth_kernel`), then their measurements and noise in batched
    products, then the filter step by step (:func:`filter_kernel`), then the NIS and the
    recorded epochs in batched products, into preallocated work arrays. Every product and
    sum is the one a step-by-step loop forms, with the same operands; the compiled kernels
    call the BLAS numba links (SciPy's) where NumPy calls its own, so the numbers equal
    those of the plain loop to rounding (docs/assumptions.md "Compiled
    kernels").

    Parameters
    ----------
    prepared : LinearFilter
        The prepared filter (steps, gains, update epochs).
    x, x_hat : numpy.ndarray
        True error and estimate at step ``k0``, (runs, n).
    z_add : numpy.ndarray
        Deterministic term added to each measurement.
    x_input : numpy.ndarray or None
        Deterministic input added to the truth at each step.
    k0 : int
        First step.
    rng : numpy.random.Generator or None
        Noise source; None runs noise-free.
    progress : callable or None
        Called as ``progress(steps_done, N)`` after each block.
    slot, upd_slot : numpy.ndarray
        Recorded row of each step and of each update (-1: not recorded).
    out : tuple of numpy.ndarray
        Recorded truth, estimate, innovation and NIS, written in place.
    """
    steps = prepared.steps
    runs, m = x.shape[0], steps.H.shape[-2]
    N = steps.t.size
    R_sqrt = psd_sqrt(steps.R[:1]) if np.all(steps.R == steps.R[:1]) else psd_sqrt(steps.R)
    work = Work.of(runs, steps.n, m)
    current = (x, x_hat)
    blocks = noise_blocks(rng, N, (runs, steps.L.shape[-1]), (runs, m))
    for c0, draws in zip(range(0, N, CHUNK), blocks, strict=True):
        c1 = min(N, c0 + CHUNK)
        if c1 > k0:
            block = Block(c0, max(c0, k0), c1, N)
            np.copyto(work.truth[block.j0], current[0])
            np.copyto(work.prior[block.j0], current[1])
            truth_block(steps, block, work, draws, x_input)
            meas = measure_block(prepared, block, work, draws, z_add, R_sqrt)
            filter_block(prepared, block, work, meas)
            record_block(prepared, block, work, meas, slot, upd_slot, out)
            current = (work.truth[c1 - c0], work.prior[c1 - c0])
        if progress is not None:
            progress(c1, N)


def noise_blocks(rng, N: int, shape_w, shape_v):
    """The noise draws ``(xi, nu)``, ``(c, *shape_w)`` and ``(c, *shape_v)``, of each block
    of :func:`run_recursion` (None for each without ``rng``).

    Drawn in the order of the plain loop (``xi`` then ``nu`` of each block, so the random
    stream is the same), into two alternating pairs of arrays, the next block on a worker
    thread while the caller runs the current one (``Generator.standard_normal`` releases
    the GIL while it fills; the draws of a 100-run batch cost about as much as its
    filter). No more is drawn than the blocks need.

    Parameters
    ----------
    rng : numpy.random.Generator or None
        Noise source.
    N : int
        Number of steps.
    shape_w, shape_v : tuple of int
        Shape of one step's process and measurement noise draw.

    Yields
    ------
    tuple of numpy.ndarray or None
        ``(xi, nu)`` of each block.
    """
    starts = range(0, N, CHUNK)
    if rng is None:
        yield from (None for _ in starts)
        return
    pairs = [(np.empty((CHUNK, *shape_w)), np.empty((CHUNK, *shape_v))) for _ in range(2)]

    def draw(i: int):
        size = min(N, starts[i] + CHUNK) - starts[i]
        xi, nu = (a[:size] for a in pairs[i % 2])
        rng.standard_normal(out=xi)
        rng.standard_normal(out=nu)
        return xi, nu

    with ThreadPoolExecutor(max_workers=1) as pool:
        pending = pool.submit(draw, 0)
        for i in range(len(starts)):
            draws = pending.result()
            if i + 1 < len(starts):
                pending = pool.submit(draw, i + 1)
            yield draws


@dataclass(frozen=True)
class Work:
    """Work arrays of :func:`run_recursion`, by step of a block: ``truth`` and ``prior``
    (estimate before the update) one step longer than the block, ``post`` (estimate after
    an update) and ``noise`` (the process noise over the step); ``z``, ``innov`` and
    ``product`` (a measurement noise or ``innov S^+``) by update of the block; ``hx`` and
    ``gain_step`` for one step."""

    truth: np.ndarray
    prior: np.ndarray
    post: np.ndarray
    noise: np.ndarray
    z: np.ndarray
    innov: np.ndarray
    product: np.ndarray
    hx: np.ndarray
    gain_step: np.ndarray

    @classmethod
    def of(cls, runs: int, n: int, m: int) -> Work:
        """Work arrays for one block.

        Parameters
        ----------
        runs : int
            Number of runs.
        n : int
            State size.
        m : int
            Measurement size.

        Returns
        -------
        Work
            Uninitialised arrays.
        """
        states, measured = (CHUNK, runs, n), (CHUNK, runs, m)
        return cls(np.empty((CHUNK + 1, runs, n)), np.empty((CHUNK + 1, runs, n)),
                   np.empty(states), np.empty(states), np.empty(measured),
                   np.empty(measured), np.empty(measured), np.empty((runs, m)),
                   np.empty((runs, n)))


@dataclass(frozen=True)
class Block:
    """Steps ``k0 .. k1-1`` of the block starting at ``c0`` (work index ``j = k - c0``),
    of ``N`` in all; ``j0``, ``j1`` their work indices and ``moves`` the steps that
    propagate (all but the last of the run)."""

    c0: int
    k0: int
    k1: int
    N: int

    @property
    def j0(self) -> int:
        return self.k0 - self.c0

    @property
    def j1(self) -> int:
        return self.k1 - self.c0

    @property
    def moves(self) -> slice:
        return slice(self.k0, min(self.k1, self.N - 1))


def _rows(index: np.ndarray):
    """``index`` (ascending) as a slice when it is evenly spaced (a view instead of a
    copy), else itself."""
    if index.size < 2:
        return slice(int(index[0]), int(index[0]) + 1) if index.size else index
    step = int(index[1] - index[0])
    if step > 0 and np.all(np.diff(index) == step):
        return slice(int(index[0]), int(index[-1]) + 1, step)
    return index


def truth_block(steps: LinearSteps, block: Block, work: Work, draws, x_input) -> None:
    """True errors ``x_{k+1} = x_k F_k' (+ xi_k L_k') (+ u_k)`` of a block, into
    ``work.truth`` (``work.truth[j0]`` holds ``x_{k0}``): the process noise of the block in
    one batched product, the recursion in :func:`truth_kernel`.

    Parameters
    ----------
    steps : LinearSteps
        The model per step.
    block : Block
        The block.
    work : Work
        Work arrays (``work.truth`` written).
    draws : tuple of numpy.ndarray or None
        The block's noise draws (:func:`noise_blocks`).
    x_input : numpy.ndarray or None
        Deterministic input per step.
    """
    moves = block.moves
    F = kernel_array(steps.F[moves])
    j0 = block.j0
    noise = _NONE
    if draws is not None:
        noise = np.matmul(draws[0][j0:j0 + F.shape[0]], steps.L[moves].swapaxes(-1, -2),
                          out=work.noise[:F.shape[0]])
    inputs = _NONE
    if x_input is not None:
        u = x_input[moves]
        inputs = kernel_array(u if u.ndim == 3 else u[:, None, :])
    truth_kernel(work.truth, F, noise, inputs, j0)


_NONE = np.zeros((0, 1, 0))
"""An absent noise or input of :func:`truth_kernel` (no rows)."""


@numba.njit(cache=True)
def _rows_times(X, A, out):
    """``out = X A'`` for rows ``X`` (R, n) and ``A`` (p, n), one BLAS product (we tried
    skipping the zeros of the sparse ``A``: no faster for 100 runs, docs/assumptions.md
    "Compiled kernels")."""
    np.dot(X, A.T, out)


@numba.njit(cache=True)
def truth_kernel(x, F, noise, inputs, j0):
    """The true-error recursion of a block, compiled (docs/assumptions.md "Compiled
    kernels"): ``x[j0+i+1] = x[j0+i] F[i]' (+ noise[i]) (+ inputs[i])`` for each step ``i``
    of ``F`` (s, n, n); ``x`` (., R, n), ``noise`` (s, R, n) or no rows, ``inputs``
    (s, R, n) or (s, 1, n) (the same input for every run) or no rows. The NumPy code it
    replaced is ``tests/support/linear_reference.py``.

    Parameters
    ----------
    x : numpy.ndarray
        True errors, written in place.
    F : numpy.ndarray
        Transition matrices.
    noise : numpy.ndarray
        Process noise per step and run.
    inputs : numpy.ndarray
        Inputs per step.
    j0 : int
        Work index of the block's first step.
    """
    runs, n = x.shape[1], x.shape[2]
    for i in range(F.shape[0]):
        j = j0 + i
        _rows_times(x[j], F[i], x[j + 1])
        # sums entry by entry: ``x[j + 1] += noise[i]`` assigns an array to a slice, whose
        # compiled shape check took about 4 s of the first compile (navlib.kernel_copy)
        if noise.shape[0]:
            for r in range(runs):
                for c in range(n):
                    x[j + 1, r, c] += noise[i, r, c]
        if inputs.shape[0]:
            for r in range(runs):
                u = 0 if inputs.shape[1] == 1 else r
                for c in range(n):
                    x[j + 1, r, c] += inputs[i, u, c]


def measure_block(prepared: LinearFilter, block: Block, work: Work, draws, z_add,
                   R_sqrt) -> np.ndarray:
    """Measurements ``z_k = x_k H_k' + z_add_k (+ nu_k R_k^(1/2)')`` at the block's
    updates, into ``work.z`` (one row per update); returns the updates' work indices.

    Parameters
    ----------
    prepared : LinearFilter
        The prepared filter.
    block : Block
        The block.
    work : Work
        Work arrays (``work.z`` written).
    draws : tuple of numpy.ndarray or None
        The block's noise draws.
    z_add : numpy.ndarray
        Deterministic term added to each measurement.
    R_sqrt : numpy.ndarray
        Square roots of the measurement covariances, (1, m, m) or (N, m, m).

    Returns
    -------
    numpy.ndarray
        Work indices of the block's updates.
    """
    steps = prepared.steps
    meas = np.flatnonzero(prepared.measured[block.k0:block.k1]) + block.j0
    if meas.size:
        z, k, j = work.z[:meas.size], _rows(meas + block.c0), _rows(meas)
        np.matmul(work.truth[j], steps.H[k].swapaxes(-1, -2), out=z)
        add = z_add[k]
        np.add(z, add[:, None, :] if add.ndim == 2 else add, out=z)
        if draws is not None:
            Rs = R_sqrt[0].T if R_sqrt.shape[0] == 1 else R_sqrt[k].swapaxes(-1, -2)
            np.add(z, np.matmul(draws[1][j], Rs, out=work.product[:meas.size]), out=z)
    return meas


def compile_recursion_kernels() -> None:
    """:func:`truth_kernel` and :func:`filter_kernel` on tiny inputs: compiles them on the
    first run on a machine, loads them from numba's disk cache afterwards (README
    "Compiled kernels")."""
    x = np.zeros((2, 1, 1))
    F = np.ones((1, 1, 1))
    truth_kernel(x, F, _NONE, _NONE, 0)
    filter_kernel(x, x.copy(), x.copy(), x.copy(), F, F, F, np.zeros(1, dtype=np.int64), 0, 1)


def filter_block(prepared: LinearFilter, block: Block, work: Work, meas) -> None:
    """The filter over a block (:func:`filter_kernel`; ``work.prior[j0]`` holds the prior
    at ``k0``).

    Parameters
    ----------
    prepared : LinearFilter
        The prepared filter.
    block : Block
        The block.
    work : Work
        Work arrays.
    meas : numpy.ndarray
        Work indices of the block's updates (:func:`measure_block`).
    """
    steps = prepared.steps
    update = np.full(block.j1 - block.j0, -1, dtype=np.int64)
    update[meas - block.j0] = np.arange(meas.size)
    moves = block.moves
    filter_kernel(work.prior, work.post, work.innov, work.z,
                  kernel_array(steps.H[block.k0:block.k1]),
                  kernel_array(prepared.gains.K[block.k0:block.k1]),
                  kernel_array(steps.F[moves]), update, block.j0, moves.stop - block.c0)


@numba.njit(cache=True)
def filter_kernel(prior, post, innov, z, H, K, F, update, j0, last):
    """The linear Kalman filter over the steps of a block, compiled (docs/assumptions.md
    "Compiled kernels"). At step ``i`` (work index ``j = j0 + i``) with
    ``update[i] = p >= 0``: ``innov[p] = z[p] - x^- H[i]'`` and
    ``x^+ = x^- + innov[p] K[i]'`` into ``post[j]`` (rows are runs); then, while
    ``j < last``, ``x^-_{j+1} = x F[i]'`` into ``prior[j + 1]``. The NumPy code it replaced
    is ``tests/support/linear_reference.py``.

    Parameters
    ----------
    prior, post : numpy.ndarray
        Prior and posterior estimates per work index, written in place.
    innov : numpy.ndarray
        Innovations per update, written in place.
    z : numpy.ndarray
        Measurements per update.
    H, K, F : numpy.ndarray
        Measurement matrices, gains and transition matrices per step.
    update : numpy.ndarray
        Update row of each step, -1 without update.
    j0 : int
        Work index of the block's first step.
    last : int
        Work index after which no prior is propagated.
    """
    runs, n = prior.shape[1], prior.shape[2]
    step = np.empty((runs, n))
    for i in range(update.size):
        j = j0 + i
        estimate = prior[j]
        p = update[i]
        if p >= 0:
            _rows_times(estimate, H[i], innov[p])
            for r in range(runs):
                for c in range(innov.shape[2]):
                    innov[p, r, c] = z[p, r, c] - innov[p, r, c]
            _rows_times(innov[p], K[i], step)
            for r in range(runs):
                for c in range(n):
                    post[j, r, c] = estimate[r, c] + step[r, c]
            estimate = post[j]
        if j < last:
            _rows_times(estimate, F[i], prior[j + 1])


def record_block(prepared: LinearFilter, block: Block, work: Work, meas, slot, upd_slot,
                  out) -> None:
    """NIS ``(z - x^- H') S^+ (z - x^- H')'`` at the block's updates and the recorded
    truth, estimate and innovation of the block into ``out``.

    Parameters
    ----------
    prepared : LinearFilter
        The prepared filter.
    block : Block
        The block.
    work : Work
        Work arrays.
    meas : numpy.ndarray
        Work indices of the block's updates.
    slot, upd_slot : numpy.ndarray
        Recorded row of each step and of each update (-1: not recorded).
    out : tuple of numpy.ndarray
        Recorded truth, estimate, innovation and NIS, written in place.
    """
    truth_rec, est_rec, innov_rec, nis = out
    c0 = block.c0
    if meas.size:
        innov = work.innov[:meas.size]
        weighted = np.matmul(innov, prepared.gains.S_pinv[_rows(meas + c0)],
                             out=work.product[:meas.size])
        nis[_rows(upd_slot[meas + c0])] = np.sum(np.multiply(weighted, innov, out=weighted),
                                                 axis=2)
        kept = slot[meas + c0] >= 0
        innov_rec[_rows(slot[meas[kept] + c0])] = innov[_rows(np.flatnonzero(kept))]
    rec = np.flatnonzero(slot[block.k0:block.k1] >= 0) + block.j0
    truth_rec[_rows(slot[rec + c0])] = work.truth[_rows(rec)]
    updated = prepared.measured[rec + c0]
    for pick, source in ((updated, work.post), (~updated, work.prior)):
        est_rec[_rows(slot[rec[pick] + c0])] = source[_rows(rec[pick])]


drop_stale_kernel_caches(__name__, globals())  # numba checks only this file (numba #1833)
