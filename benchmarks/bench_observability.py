"""Observability benchmarks (issue 3 performance goals).

* the full-resolution Table 2: local time-varying observability matrix (eq. 6) at every
  200 Hz step of the 150 s Churchill ascent for all 60 configurations (the 32 x 3 cells of
  the paper's table less the 36 "not applicable" ones), goal < 5 min;
* one configuration's rank / condition-number curve at 1 Hz (model build included: what a
  widget does on a dropdown change), goal < 1 s.

The extra columns give the achieved floating-point rate (approximate operation count of the
block recursion, Householder QR and SVD of the triangular factor) as a fraction of this
machine's large-matmul rate (2000 x 2000 ``numpy`` matmul, all cores).
"""

from __future__ import annotations

import time
from functools import cache

import numpy as np
from _harness import Case
from _harness import launcher_flight as trajectory

from navlib.models.launcher import launcher, state_names
from navlib.observability import local_observability
from navlib.studies.launcher import configurations, table2


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


def local_flops(n: int, m: int, n_steps: int, window: int | None = None) -> float:
    """Approximate floating-point operations of local_observability (time-varying, stride 1).

    Per step: block recursion ``2 m n^2 (w - 1)``, Householder QR of the ``w m x n`` stack
    ``2 p n^2 - 2/3 n^3`` and bidiagonalisation of the ``n x n`` factor ``8/3 n^3``.
    """
    w = n if window is None else window
    p = w * m
    per_step = 2.0 * m * n * n * (w - 1) + 2.0 * p * n * n - 2.0 / 3.0 * n**3 + 8.0 / 3.0 * n**3
    return per_step * max(n_steps - w + 1, 0)


def _measurement_dim(solution: str) -> int:
    return {"ins_gps": 6, "ins_gps_att": 9, "ins_gps_rt": 9, "ins_gps_att_rt": 12}[solution]


def table2_flops() -> float:
    steps = len(trajectory())
    return sum(local_flops(len(state_names(s, b, bm)), _measurement_dim(s), steps)
               for s, b, bm in configurations())


def curve_flops(solution="ins_gps_att_rt", biases="GAP", stride=200) -> float:
    n, m = len(state_names(solution, biases, "markov")), _measurement_dim(solution)
    evaluated = len(range(0, len(trajectory()) - n + 1, stride))
    # strided path: forward products Phi (2 n^3 per block) instead of the block recursion
    per_step = local_flops(n, m, n) + 2.0 * n**3 * (n - 1)
    return per_step * evaluated


def _rate_columns(flops: float):
    def extra(best: float) -> dict:
        gflops = flops / best / 1e9
        peak = matmul_gflops()
        return {"gflop": flops / 1e9, "gflops": gflops, "matmul_gflops": peak,
                "frac_of_matmul": gflops / peak}
    return extra


def run_table2():
    return table2(trajectory(), variant="time_varying", stride=1)


def run_curve():
    model = launcher("ins_gps_att_rt", "GAP", "markov", trajectory=trajectory())
    return local_observability(model, stride=200)


def cases():
    trajectory()
    return [
        Case("observability: Table 2 full resolution (60 configs x 30001 steps, eq. 6)",
             "150 s @ 200 Hz", run_table2, goal_s=300.0, repeat=1, warmup=False,
             extra=_rate_columns(table2_flops()),
             notes="model builds and mid-mission null spaces included"),
        Case("observability: 1 Hz rank/cond curve, ins_gps_att_rt GAP markov (28 states)",
             "150 points", run_curve, goal_s=1.0, repeat=3,
             extra=_rate_columns(curve_flops()), notes="model build included"),
    ]
