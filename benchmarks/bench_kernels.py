"""Benchmarks of the compiled Kalman kernels (issue 26), each beside the NumPy code it
replaced (``tests/support/kalman_reference.py``):

* ``kernels.riccati_28``: 2000 epochs of the covariance recursion with the Joseph update
  (28 states, 12 measurements at every epoch, the size of the launcher's INS/GPS/att + RT
  model), compiled (:func:`navlib.kalman.riccati_kernel`) and NumPy
  (``numpy_riccati_28``). Goal 2000 x 14 us: the 2.9x of the issue's prototype over 42 us.
* ``kernels.ekf_propagate_21``: the EKF's propagation between updates over 2000 IMU samples
  of a 21-state model, compiled (:func:`navlib.kalman.propagate_kernel`) and NumPy.
* ``kernels.linear_block_28``: one block of the linear Monte-Carlo simulation (256 steps,
  100 runs, 28-state launcher INS/GPS/att + RT model, update at every step): the true-error
  and filter recursions, compiled (:func:`navlib.filters.linear_recursion.truth_kernel`,
  :func:`navlib.filters.linear_recursion.filter_kernel`) and NumPy (``numpy_linear_block_28``, the
  block code in ``tests/support/linear_reference.py``); ``..._4runs`` the same with 4 runs (the size
  of a batch of unit outlier responses). No goal in the issue: 10 us (100 runs) and 2 us
  (4 runs) per step, about a quarter of the NumPy block's time.
* ``kernels.strapdown_window_21``: 100 EKF feedback windows of the strapdown mechanisation
  (0.1 s at 200 Hz, 21 samples each, along the launcher ascent), compiled
  (:func:`navlib.strapdown._kernel.integrate_kernel` through ``strapdown.propagate``) and
  NumPy (``numpy_strapdown_window_21``, ``tests/support/strapdown_reference.py``). No goal in the
  issue: 1 us per sample.
* ``kernels.compile_cold`` / ``kernels.compile_warm``: a fresh interpreter that runs
  :func:`navlib.compiled.compile_kernels` (every kernel), with an empty numba cache
  folder (the first run on a machine: every kernel compiled) and then with that folder filled (later
  runs: loaded from disk); the import alone is ``kernels.import_only``.

Times are the best of 3; the machine is shared, so read ``uptime`` beside them.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from functools import cache
from pathlib import Path

import numpy as np
from _harness import Case

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from support import kalman_reference as ref  # noqa: E402
from support import linear_reference, strapdown_reference  # noqa: E402

from navlib import strapdown  # noqa: E402
from navlib.filters import linear_recursion, prepare_linear  # noqa: E402
from navlib.kalman import propagate_kernel, psd_sqrt, riccati_kernel  # noqa: E402
from navlib.models import launcher  # noqa: E402
from navlib.trajectory import launcher_ascent  # noqa: E402

STEPS = 2000


@cache
def _riccati_case(n: int = 28, m: int = 12):
    rng = np.random.default_rng(0)
    F = np.eye(n) + 0.01 * rng.standard_normal((STEPS, n, n))
    L = 0.01 * rng.standard_normal((n, n))
    Q = np.ascontiguousarray(np.broadcast_to(L @ L.T, (STEPS, n, n)))
    H = np.ascontiguousarray(np.broadcast_to(rng.standard_normal((m, n)), (STEPS, m, n)))
    R = np.ascontiguousarray(np.broadcast_to(0.1 * np.eye(m), (STEPS, m, m)))
    return F, Q, H, R, np.eye(n), np.ones(STEPS, dtype=bool)


def _riccati_compiled():
    F, Q, H, R, P0, update = _riccati_case()
    n, m = P0.shape[0], H.shape[1]
    prior, post = np.empty((STEPS, n, n)), np.empty((STEPS, n, n))
    riccati_kernel(P0, F, Q, H, R, update, update, 1e-12, 0, prior, np.arange(STEPS), post,
                   np.empty((0, n, m)), np.empty((0, m, m)), np.empty(0, dtype=np.int64))


def _riccati_numpy():
    F, Q, H, R, P0, update = _riccati_case()
    ref.recursion(F, Q, H, R, P0, update, update)


@cache
def _ekf_case(n: int = 21):
    rng = np.random.default_rng(1)
    F = np.eye(n) + 0.01 * rng.standard_normal((STEPS, n, n))
    Q = np.ascontiguousarray(np.broadcast_to(1e-6 * np.eye(n), (STEPS, n, n)))
    return rng.standard_normal(n), np.eye(n), F, Q, np.arange(15, 21)


def _ekf_compiled():
    x, P, F, Q, kept = _ekf_case()
    propagate_kernel(x, P, F, Q, kept, 0, STEPS)


def _ekf_numpy():
    x, P, F, Q, kept = _ekf_case()
    ref.propagate(x, P, F, Q, kept)


@cache
def _linear_case(runs: int = 100):
    flight = launcher_ascent(duration_s=14.0, rate_hz=20.0)        # 281 epochs: one block
    prepared = prepare_linear(launcher("ins_gps_att_rt", "GAP", "markov", flight))
    steps = prepared.steps
    rng = np.random.default_rng(2)
    work = linear_recursion.Work.of(runs, steps.n, steps.H.shape[-2])
    block = linear_recursion.Block(0, 0, linear_recursion.CHUNK, steps.t.size)
    draws = (rng.standard_normal((linear_recursion.CHUNK, runs, steps.L.shape[-1])),
             rng.standard_normal((linear_recursion.CHUNK, runs, steps.H.shape[-2])))
    work.truth[0] = rng.standard_normal((runs, steps.n))
    work.prior[0] = 0.0
    meas = np.flatnonzero(prepared.measured[:linear_recursion.CHUNK])
    linear_recursion.measure_block(prepared, block, work, draws,
                          np.zeros((steps.t.size, steps.H.shape[-2])),
                          psd_sqrt(steps.R[:1]))
    return prepared, block, work, draws, meas


def _linear_compiled(runs: int = 100):
    prepared, block, work, draws, meas = _linear_case(runs)
    linear_recursion.truth_block(prepared.steps, block, work, draws, None)
    linear_recursion.filter_block(prepared, block, work, meas)


def _linear_numpy(runs: int = 100):
    prepared, block, work, draws, meas = _linear_case(runs)
    linear_reference.truth_block(prepared.steps, block, work, draws, None)
    linear_reference.filter_block(prepared, block, work, meas)


@cache
def _strapdown_windows(windows: int = 100, samples: int = 21):
    flight = launcher_ascent()
    out = []
    for w in range(windows):
        sl = slice(w * (samples - 1), w * (samples - 1) + samples)
        out.append((flight.t[sl], flight.specific_force[sl], flight.angular_rate[sl],
                    np.array(flight.position[sl.start]), np.array(flight.velocity[sl.start]),
                    flight.attitude[sl.start].as_quat()))
    return out


def _strapdown(integrate):
    for window in _strapdown_windows():
        integrate(*window)


_WARM_UP = "from navlib.compiled import compile_kernels; compile_kernels()"


def _fresh_process(code: str, cache_dir: str) -> float:
    env = dict(os.environ, NUMBA_CACHE_DIR=cache_dir)
    start = time.perf_counter()
    subprocess.run([sys.executable, "-c", code], check=True, env=env, cwd=ROOT)
    return time.perf_counter() - start


def _compile_cases() -> list[Case]:
    folder = tempfile.mkdtemp(prefix="navlib-numba-")

    def cold():
        for path in Path(folder).rglob("*.nb*"):
            path.unlink()
        _fresh_process(_WARM_UP, folder)

    return [
        Case("kernels.import_only", "fresh interpreter, import navlib.filters",
             lambda: _fresh_process("import navlib.filters", folder), 10.0, repeat=1,
             warmup=False),
        Case("kernels.compile_cold", "fresh interpreter, empty numba cache", cold, 30.0,
             repeat=1, warmup=False),
        Case("kernels.compile_warm", "fresh interpreter, numba cache filled",
             lambda: _fresh_process(_WARM_UP, folder), 10.0, repeat=1, warmup=False),
    ]


def cases() -> list[Case]:
    per_step = f"{STEPS} steps"
    return [
        Case("kernels.riccati_28", f"{per_step}, 28 states, 12 meas", _riccati_compiled,
             STEPS * 14e-6),
        Case("kernels.numpy_riccati_28", f"{per_step} (NumPy reference)", _riccati_numpy,
             STEPS * 14e-6),
        Case("kernels.ekf_propagate_21", f"{per_step}, 21 states", _ekf_compiled,
             STEPS * 5e-6),
        Case("kernels.numpy_ekf_propagate_21", f"{per_step} (NumPy reference)", _ekf_numpy,
             STEPS * 5e-6),
        Case("kernels.linear_block_28", "256 steps x 100 runs, truth + filter, 28 states",
             _linear_compiled, 256 * 10e-6),
        Case("kernels.numpy_linear_block_28", "the same (NumPy reference)", _linear_numpy,
             256 * 10e-6),
        Case("kernels.linear_block_28_4runs", "256 steps x 4 runs (a unit-response batch)",
             lambda: _linear_compiled(4), 256 * 2e-6),
        Case("kernels.numpy_linear_block_28_4runs", "the same (NumPy reference)",
             lambda: _linear_numpy(4), 256 * 2e-6),
        Case("kernels.strapdown_window_21", "100 windows x 21 samples (0.1 s at 200 Hz)",
             lambda: _strapdown(strapdown.propagate), 100 * 21 * 1e-6),
        Case("kernels.numpy_strapdown_window_21", "the same (NumPy reference)",
             lambda: _strapdown(strapdown_reference.integrate), 100 * 21 * 1e-6),
        *_compile_cases(),
    ]
