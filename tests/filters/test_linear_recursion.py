"""The block-wise linear simulation gives the numbers of the plain step-by-step filter loop
(bitwise on the reference machine; compared across paths at ``paths.CROSS_PATH_RTOL``): noise
drawn block by block in the same stream, the truth, the measurements and the NIS formed in
batched products, the filter step by step."""

import dataclasses

import numpy as np
import pytest
from support.paths import assert_same_numbers

from navlib.filters import linear, linear_preparation, prepare_linear, simulate_linear
from navlib.kalman import psd_sqrt
from navlib.models import launcher
from navlib.sensors.faults import Outlier
from navlib.trajectory import launcher_ascent

BLOCK = 256


@pytest.fixture(scope="module")
def flight():
    return launcher_ascent(duration_s=30.0, rate_hz=20.0)      # 601 epochs: 3 blocks


def plain_loop(prepared, x, z_add, x_input, rng, record):
    """The recursion one step at a time with fresh arrays, noise drawn per block of
    ``BLOCK`` steps (``xi`` then ``nu``); returns truth, estimate, innovation (recorded
    epochs, NaN without update) and NIS (updates)."""
    steps, mask, gains = prepared.steps, prepared.measured, prepared.gains
    N, runs, m = steps.t.size, x.shape[0], steps.H.shape[-2]
    R_sqrt = psd_sqrt(steps.R)
    x_hat = np.zeros_like(x)
    truth, est, innov_rec, nis = [], [], [], []
    for c0 in range(0, N, BLOCK):
        c1 = min(N, c0 + BLOCK)
        if rng is not None:
            xi = rng.standard_normal((c1 - c0, runs, steps.L.shape[-1]))
            nu = rng.standard_normal((c1 - c0, runs, m))
        for k in range(c0, c1):
            innov = np.full((runs, m), np.nan)
            if mask[k]:
                z = x @ steps.H[k].T + z_add[k]
                if rng is not None:
                    z += nu[k - c0] @ R_sqrt[k].T
                innov = z - x_hat @ steps.H[k].T
                x_hat = x_hat + innov @ gains.K[k].T
                nis.append(np.sum((innov @ gains.S_pinv[k]) * innov, axis=1))
            truth.append(x)
            est.append(x_hat)
            innov_rec.append(innov)
            if k < N - 1:
                x = x @ steps.F[k].T
                if rng is not None:
                    x += xi[k - c0] @ steps.L[k].T
                if x_input is not None:
                    x += x_input[k]
                x_hat = x_hat @ steps.F[k].T
    return (np.array(truth)[record], np.array(est)[record], np.array(innov_rec)[record],
            np.array(nis))


def assert_same_as_loop(sim, expected):
    for name, want in zip(("truth", "estimate", "innovation", "nis"), expected, strict=True):
        assert_same_numbers(getattr(sim, name), want, name)


@pytest.mark.parametrize(("update_every", "record_every"), [(1, 1), (3, 7), (2, 1)])
def test_noisy_runs_equal_the_plain_loop(flight, update_every, record_every):
    """Monte-Carlo runs with process and measurement noise, an IMU and a measurement
    outlier, sparse updates and records, a time-varying R (per-epoch square roots); the
    caller's generator is left where the loop leaves it."""
    model = launcher("ins_gps_att", "GAP", "markov", flight)
    prepared = prepare_linear(model, update_every=update_every)
    scale = 1.0 + 0.3 * np.sin(np.arange(flight.t.size))[:, None, None]
    prepared = linear_preparation.LinearFilter(
        dataclasses.replace(prepared.steps, R=prepared.steps.R * scale), prepared.measured,
        prepared.gains, prepared.covariance)
    outs = (Outlier("gyro_x", 9.0, 0.01), Outlier("gnss_vel", 16.0, 3.0, "step"))
    mine = np.random.default_rng(3)
    sim = simulate_linear(prepared, runs=5, rng=mine, outliers=outs, record_every=record_every,
                          nees=False)
    rng = np.random.default_rng(3)
    x = rng.standard_normal((5, prepared.steps.n)) @ psd_sqrt(prepared.steps.P0).T
    z_add, x_input, _ = linear._outlier_inputs(prepared.steps, outs)
    expected = plain_loop(prepared, x, z_add, x_input, rng, sim.index)
    assert_same_as_loop(sim, expected)
    assert mine.standard_normal() == rng.standard_normal()      # drew no more than the loop


def test_unit_responses_equal_the_plain_loop(flight):
    """Noise-free responses, per-run inputs, started at the first input (mid-block)."""
    prepared = prepare_linear(launcher("ins_gps_att_rt", "GAP", "markov", flight),
                              update_every=2)
    outs = [Outlier("gyro_y", 14.0, 1.0), Outlier("rt_x", 18.0, 1.0, "step"),
            Outlier("gnss_pos_z", 13.3, 1.0)]
    sim = linear.unit_responses(prepared, outs, record_every=3)
    inputs = [linear._outlier_inputs(prepared.steps, (o,)) for o in outs]
    z_add = np.stack([z for z, _, _ in inputs], axis=1)
    zero = np.zeros((flight.t.size - 1, prepared.steps.n))
    x_input = np.stack([zero if u is None else u for _, u, _ in inputs], axis=1)
    expected = plain_loop(prepared, np.zeros((3, prepared.steps.n)), z_add, x_input, None,
                          sim.index)
    assert_same_as_loop(sim, expected)
