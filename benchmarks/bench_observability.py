"""Observability benchmarks (issue 3 and issue 14 performance goals).

* the full-resolution Table 2: local time-varying observability matrix (eq. 6) at every
  200 Hz step of the 150 s Churchill ascent for all 60 configurations (the 32 x 3 cells of
  the paper's table less the 36 "not applicable" ones), goal < 60 s on the 2-core machine
  (issue 14; it was 5 min in issue 3);
* the sliding window alone, one 28-state configuration at every step (30 001 steps), as the
  compiled kernel (``navlib.observability.sliding``) and as its NumPy reference
  (``tests/support/sliding_reference.py``), single-threaded, transitions included;
* one configuration's rank / condition-number curve at 1 Hz (model build included: what a
  widget does on a dropdown change), goal < 1 s.

The extra columns give the process CPU time of the (last) run, the 1-minute load average
when the case ended (the machine is shared: compare runs at similar loads), and the achieved
floating-point rate as a fraction of this machine's large-matmul rate (2000 x 2000
``numpy`` matmul, all cores). The operation counts are those of the algorithm timed (see
:func:`local_flops`): every step's sliding-window factorisation costs about
``16.7 n^3 + 6 m n^2`` flops (0.42 MFLOP for the 28-state, 12-measurement configuration),
against ``2 m n^2 (w - 1) + 2 w m n^2 + 2 n^3`` (1.08 MFLOP) for forming and factorising
the ``w m x n`` matrix as before issue 14, so a lower FLOP fraction can be a faster run.
"""

from __future__ import annotations

import os
import sys
import time
from functools import cache
from pathlib import Path

import numpy as np
from _harness import Case
from _harness import launcher_flight as trajectory

from navlib.models.launcher import launcher, launcher_steps, state_names
from navlib.observability import local_observability
from navlib.observability.local import _model_arrays
from navlib.observability.sliding import block_data, sliding_singular_values
from navlib.studies.launcher import configurations, table2

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from support import sliding_reference

_CPU_S: dict[str, float] = {}


@cache
def matmul_gflops(size: int = 2000, repeat: int = 3) -> float:
    """Best large-matmul rate of this machine, GFLOP/s."""
    rng = np.random.default_rng(0)
    a, b = rng.normal(size=(size, size)), rng.normal(size=(size, size))
    a @ b
    best = min(_timed(lambda: a @ b) for _ in range(repeat))
    return 2.0 * size**3 / best / 1e9


def _timed(func) -> float:
    start = time.perf_counter()
    func()
    return time.perf_counter() - start


def _qr_flops(p: int, n: int) -> float:
    """Householder QR (R only) of a p x n matrix, p >= n."""
    return 2.0 * p * n * n - 2.0 / 3.0 * n**3


def local_flops(n: int, m: int, n_steps: int, window: int | None = None) -> float:
    """Approximate floating-point operations of local_observability (time-varying, stride 1).

    Per step (:func:`navlib.observability.sliding.sliding_singular_values`): the suffix
    update ``R([H; Y F])`` and the prefix update ``R([P; H Psi])`` (two (m + n) x n QRs, three n x n
    products and one m x n product), the combine product ``P Phi`` and the SVD of the
    2n x n stack (QR, then bidiagonalisation of the n x n factor, ``8/3 n^3``).
    """
    w = n if window is None else window
    per_step = (2 * _qr_flops(m + n, n) + 8.0 * n**3 + 2.0 * m * n * n
                + _qr_flops(2 * n, n) + 8.0 / 3.0 * n**3)
    return per_step * max(n_steps - w + 1, 0)


def strided_flops(n: int, m: int, window: int | None = None) -> float:
    """Operations of one evaluated step on the strided path (stride > 1): forward products
    ``Phi`` (2 n^3 per block), the blocks ``H Phi``, QR of the ``w m x n`` stack, SVD."""
    w = n if window is None else window
    return (2.0 * n**3 * (w - 1) + 2.0 * m * n * n * w + _qr_flops(w * m, n)
            + 8.0 / 3.0 * n**3)


def _measurement_dim(solution: str) -> int:
    return {"ins_gps": 6, "ins_gps_att": 9, "ins_gps_rt": 9, "ins_gps_att_rt": 12}[solution]


def table2_flops() -> float:
    steps = len(trajectory())
    return sum(local_flops(len(state_names(s, b, bm)), _measurement_dim(s), steps)
               for s, b, bm in configurations())


def curve_flops(solution="ins_gps_att_rt", biases="GAP", stride=200) -> float:
    n, m = len(state_names(solution, biases, "markov")), _measurement_dim(solution)
    evaluated = len(range(0, len(trajectory()) - n + 1, stride))
    return strided_flops(n, m) * evaluated


def _cpu_timed(name: str, func):
    """``func`` recording its process CPU time (all threads) under ``name``."""
    def run():
        start = time.process_time()
        out = func()
        _CPU_S[name] = time.process_time() - start
        return out
    return run


def _rate_columns(name: str, flops: float):
    def extra(best: float) -> dict:
        gflops = flops / best / 1e9
        peak = matmul_gflops()
        return {"cpu_s": _CPU_S.get(name, float("nan")), "load_1min": os.getloadavg()[0],
                "gflop": flops / 1e9, "gflops": gflops, "matmul_gflops": peak,
                "frac_of_matmul": gflops / peak}
    return extra


def _cpu_columns(name: str):
    def extra(best: float) -> dict:
        return {"cpu_s": _CPU_S.get(name, float("nan")), "load_1min": os.getloadavg()[0]}
    return extra


def run_table2():
    return table2(trajectory(), variant="time_varying", stride=1)


def run_curve():
    model = launcher_steps("ins_gps_att_rt", "GAP", "markov", trajectory=trajectory())
    return local_observability(model, stride=200)


def _inputs(build):
    """The sliding window's inputs of the 60 configurations, chunk by chunk (model,
    transitions, :func:`block_data`), without the kernel: ``launcher`` (an ``A`` stack per
    model, discretised per chunk) against ``launcher_steps`` (the steps computed per chunk)."""
    def run():
        for config in configurations():
            t, transitions, H = _model_arrays(build(*config, trajectory=trajectory()), "euler")
            n = H.shape[2]
            chunk = 1024 // n * n
            for k0 in range(0, t.size - n + 1, chunk):
                block_data(transitions, H, k0, -(-chunk // n), n)
    return run


@cache
def _sliding_inputs():
    model = launcher("ins_gps_att_rt", "GAP", "markov", trajectory=trajectory())
    return _model_arrays(model, "euler")[1:], model.n


def _sliding(function):
    """Every step of the 28-state configuration in chunks of 36 windows, one thread."""
    def run():
        (transitions, H), n = _sliding_inputs()
        K, chunk = H.shape[0] - n + 1, 36 * n
        return [function(transitions, H, k, min(chunk, K - k), n) for k in range(0, K, chunk)]
    return run


def cases():
    trajectory()
    return [
        Case("observability: Table 2 full resolution (60 configs x 30001 steps, eq. 6)",
             "150 s @ 200 Hz", _cpu_timed("table2", run_table2), goal_s=60.0, repeat=1,
             warmup=False, extra=_rate_columns("table2", table2_flops()),
             notes="model builds and mid-mission null spaces included"),
        Case("observability: sliding window, compiled kernel (ins_gps_att_rt GAP markov)",
             "30001 steps, 28 states", _cpu_timed("sliding", _sliding(sliding_singular_values)),
             goal_s=5.0, repeat=2, extra=_rate_columns("sliding", local_flops(28, 12, 30001)),
             notes="one thread; transitions included"),
        Case("observability: sliding window, NumPy reference (tests/support/sliding_reference.py)",
             "30001 steps, 28 states",
             _cpu_timed("sliding_numpy", _sliding(sliding_reference.sliding_singular_values)),
             goal_s=5.0, repeat=2,
             extra=_rate_columns("sliding_numpy", local_flops(28, 12, 30001)),
             notes="one thread; transitions included"),
        Case("observability: Table 2 inputs, A stack per model (launcher)",
             "60 configs x 30001 steps", _cpu_timed("inputs_A", _inputs(launcher)),
             goal_s=10.0, repeat=2, extra=_cpu_columns("inputs_A"),
             notes="one thread; no kernel"),
        Case("observability: Table 2 inputs, steps per chunk (launcher_steps)",
             "60 configs x 30001 steps", _cpu_timed("inputs_steps", _inputs(launcher_steps)),
             goal_s=10.0, repeat=2, extra=_cpu_columns("inputs_steps"),
             notes="one thread; no kernel"),
        Case("observability: 1 Hz rank/cond curve, ins_gps_att_rt GAP markov (28 states)",
             "150 points", _cpu_timed("curve", run_curve), goal_s=1.0, repeat=3,
             extra=_rate_columns("curve", curve_flops()), notes="model build included"),
    ]
