"""The compiled linear-simulation kernels (:func:`navlib.filters.linear_recursion.truth_kernel`,
:func:`navlib.filters.linear_recursion.filter_kernel`, issue 26) equal the NumPy block code they
replaced (tests/support/linear_reference.py) on a block of the paper's launcher model: noisy runs,
a per-run or shared state input, sparse updates."""

import numpy as np
import pytest
from support import linear_reference as ref

from navlib.filters import linear_recursion, prepare_linear
from navlib.kalman import psd_sqrt
from navlib.models import launcher
from navlib.trajectory import launcher_ascent

RTOL = 1e-12


@pytest.fixture(scope="module")
def prepared():
    flight = launcher_ascent(duration_s=20.0, rate_hz=20.0)          # 401 epochs
    return prepare_linear(launcher("ins_gps_att_rt", "GAP", "markov", flight),
                          update_every=3)


def rel(a, b) -> float:
    scale = np.abs(b).max()
    assert scale > 0
    return float(np.abs(a - b).max() / scale)


def _start(prepared, runs, seed):
    rng = np.random.default_rng(seed)
    work = linear_recursion.Work.of(runs, prepared.steps.n, prepared.steps.H.shape[-2])
    for a in (work.truth, work.prior):
        a[...] = np.nan                        # unwritten rows stay NaN in both paths
    block = linear_recursion.Block(256, 260, 401, 401)  # last block: the final step does not move
    work.truth[block.j0] = rng.standard_normal((runs, prepared.steps.n))
    work.prior[block.j0] = 0.5 * work.truth[block.j0]
    xi = rng.standard_normal((linear_recursion.CHUNK, runs, prepared.steps.L.shape[-1]))
    nu = rng.standard_normal((linear_recursion.CHUNK, runs, prepared.steps.H.shape[-2]))
    return work, block, (xi, nu)


@pytest.mark.parametrize("input_shape", [None, "shared", "per_run"])
def test_truth_kernel_equals_numpy(prepared, input_shape):
    runs, n = 4, prepared.steps.n
    steps = prepared.steps
    rng = np.random.default_rng(5)
    x_input = {None: None, "shared": rng.standard_normal((400, n)),
               "per_run": rng.standard_normal((400, runs, n))}[input_shape]
    work, block, draws = _start(prepared, runs, 1)
    want, _, _ = _start(prepared, runs, 1)
    linear_recursion.truth_block(steps, block, work, draws, x_input)
    ref.truth_block(steps, block, want, draws, x_input)
    moved = slice(block.j0, block.j1)
    assert np.isfinite(work.truth[moved]).all()
    assert rel(work.truth[moved], want.truth[moved]) < RTOL


def test_filter_kernel_equals_numpy(prepared):
    runs = 3
    work, block, draws = _start(prepared, runs, 2)
    want, _, _ = _start(prepared, runs, 2)
    linear_recursion.truth_block(prepared.steps, block, work, draws, None)
    ref.truth_block(prepared.steps, block, want, draws, None)
    z_add = np.zeros((401, prepared.steps.H.shape[-2]))
    R_sqrt = psd_sqrt(prepared.steps.R[:1])
    meas = linear_recursion.measure_block(prepared, block, work, draws, z_add, R_sqrt)
    linear_recursion.measure_block(prepared, block, want, draws, z_add, R_sqrt)
    assert meas.size == 47
    linear_recursion.filter_block(prepared, block, work, meas)
    ref.filter_block(prepared, block, want, meas)
    updated = meas
    assert rel(work.innov[:meas.size], want.innov[:meas.size]) < RTOL
    assert rel(work.post[updated], want.post[updated]) < RTOL
    moved = slice(block.j0, block.j1)
    assert np.isfinite(work.prior[moved]).all()
    assert rel(work.prior[moved], want.prior[moved]) < RTOL
