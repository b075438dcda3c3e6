"""Benchmarks of navlib.metrics (goals: benchmarks/run.py).

* ``metrics.rocket_chain``: the whole chain on the VS30-like flight — 21-state ECEF model along
  86 s at 100 Hz, chaining to the 1 Hz GNSS epochs, sensability at all 87 epochs and
  excitability for the three segments. Goal 2 s. The trajectory itself is built once, outside
  the timing (it is the trajectory module's cost, not the chain's).
* ``metrics.widget_eta_segments``: a widget change (new eta and new segment limits) on the
  cached discretised model: three ``excitability_segment`` calls. Goal 100 ms.
* ``metrics.widget_nu``: a new nu on an existing sensability result. Goal 100 ms.
* ``metrics.sensability`` / ``metrics.excitability_3seg``: the metrics alone on random but
  realistically scaled matrices (n = 21, 86 epochs, 3 GNSS rows, the spec §5 sigmas). Their
  goal is the widget budget, 100 ms.

IMU noise densities are the spec excitability.md §5 baseline, passed explicitly.
"""

from __future__ import annotations

from functools import cache

import numpy as np
from _harness import Case, rocket_flight
from scipy.linalg import expm

from navlib import metrics
from navlib.models.base import DiscreteModel

SEGMENTS = ((0.0, 19.0), (19.0, 60.0), (60.0, 86.0))
NOISE = {"arw_rad_sqrt_s": 1.45e-4, "vrw_m_s_sqrt_s": 1.67e-3, "bg_rw_rad_s_sqrt_s": 4.8e-6,
         "ba_rw_m_s2_sqrt_s": 1e-4, "sg_rw_per_sqrt_s": 1e-5, "sa_rw_per_sqrt_s": 1e-5}
SIGMA0 = np.repeat([30.0, 3.0, np.radians(1.0), np.radians(0.05), 0.02, 5e-3, 1e-3], 3)


def random_model(n_epochs: int = 86, seed: int = 0) -> DiscreteModel:
    """1 Hz transitions ``T expm(A_k) T^-1`` with states in the spec's physical units."""
    rng = np.random.default_rng(seed)
    n = SIGMA0.size
    A = 0.1 * rng.standard_normal((n_epochs - 1, n, n))
    T = np.diag(SIGMA0)
    F = T @ expm(A) @ np.linalg.inv(T)
    G = 0.05 * rng.standard_normal((n_epochs - 1, n, n)) * SIGMA0[:, None]
    Q = G @ np.swapaxes(G, 1, 2)
    H = np.zeros((n_epochs, 3, n))
    H[:, :, :3] = np.eye(3)
    R = np.broadcast_to(25.0 * np.eye(3), (n_epochs, 3, 3))
    names = tuple(f"e{i + 1}" for i in range(n))
    return DiscreteModel(np.arange(n_epochs, dtype=float), F, Q, H, R, names,
                         P0=np.diag(SIGMA0**2))


def discretised_rocket():
    """The uncached model chain (the ``ecef21_at_epochs`` cache would hide its cost)."""
    from navlib.models.ecef import ecef21

    trajectory = rocket_flight()
    return ecef21(trajectory, NOISE).discretize(epochs=trajectory.at_rate(1.0), method="series",
                                                hold="mean")


def rocket_chain():
    model = discretised_rocket()
    se = metrics.sensability_model(model)
    return se, [metrics.excitability_segment(model, a, b) for a, b in SEGMENTS]


@cache
def cached_rocket_model() -> DiscreteModel:
    """What a widget holds: the discretised model, built once."""
    return discretised_rocket()


def widget_eta_segments():
    model = cached_rocket_model()
    return [metrics.excitability_segment(model, a, b, eta=3e-4)
            for a, b in ((0.0, 17.0), (17.0, 50.0), (50.0, 86.0))]


def cases() -> list[Case]:
    model = random_model()
    se_rocket = None

    def widget_nu():
        nonlocal se_rocket
        if se_rocket is None:
            se_rocket = metrics.sensability_model(cached_rocket_model())
        return se_rocket.with_nu(0.99)

    return [
        Case("metrics.sensability", "86 epochs x 21 states (random)",
             lambda: metrics.sensability_model(model), goal_s=0.1),
        Case("metrics.excitability_3seg", "3 segments, 21 states (random)",
             lambda: [metrics.excitability_segment(model, a, b) for a, b in SEGMENTS],
             goal_s=0.1),
        Case("metrics.rocket_chain", "8601 IMU steps -> 87 epochs x 21, 3 segments",
             rocket_chain, goal_s=2.0, repeat=2,
             notes="model + discretisation + sensability + excitability; trajectory prebuilt"),
        Case("metrics.widget_eta_segments", "3 new segments + eta, cached model",
             widget_eta_segments, goal_s=0.1),
        Case("metrics.widget_nu", "87 x 21 (rocket)", widget_nu, goal_s=0.1),
    ]
