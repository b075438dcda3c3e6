"""The EKF's compiled sparse steps (navlib.sparse_discretize, navlib.kalman.predict_sparse)
and the 21-state model's compiled Jacobians (navlib.models._ecef21_kernel) against the NumPy
code: per step within 1e-12 of each matrix's largest entry (rounding only;
the NumPy products go through whichever BLAS kernel is loaded), and the whole 86 s rocket
EKF against the same loop with NumPy steps within the golden tolerances of
tests/regression/tolerances.toml ``[ekf.*]`` (measured across BLAS kernels)."""

import importlib
import tomllib
from pathlib import Path

import numpy as np
import pytest
from support import kalman_reference as ref

from navlib import sensors, strapdown
from navlib.discretize import discretize_steps
from navlib.filters import ekf
from navlib.kalman import predict_sparse
from navlib.models.base import Nominal
from navlib.models.ecef import Ecef21ErrorState, ecef21_jacobians
from navlib.sparse_discretize import _PATTERNS, TAYLOR_THETA, _pattern, discretize_window
from navlib.trajectory import sounding_rocket

STEP_RTOL = 1e-12
ekf_module = importlib.import_module("navlib.filters.ekf")
ekf_updates = importlib.import_module("navlib.filters.ekf_updates")


def rel(a, b) -> float:
    """Largest difference relative to the largest entry of ``b``, per matrix of a stack."""
    a, b = np.asarray(a), np.asarray(b)
    return float(np.max(np.abs(a - b).max(axis=(-1, -2)) / np.abs(b).max(axis=(-1, -2))))


@pytest.fixture(scope="module")
def rocket():
    return sounding_rocket()


def _rocket_model(traj):
    """``A``, ``G`` of the 21-state model along the whole rocket flight and its ``Qc``."""
    A, G = ecef21_jacobians(traj.position, traj.C_b_e(), traj.specific_force,
                            traj.angular_rate)
    return (A[:-1], G[:-1], Ecef21ErrorState.build("motionpak_tactical").Qc,
            np.diff(traj.t))


def _block_model(rng, steps, n=12, live=5, decay=True):
    """A random sparse block-triangular model: ``live`` rows with couplings, the others
    diagonal (Markov decay, or random walks without ``decay``)."""
    A = np.zeros((steps, n, n))
    A[:, :live, :] = rng.standard_normal((steps, live, n)) * (rng.random((live, n)) < 0.5)
    if decay:
        A[:, np.arange(live, n), np.arange(live, n)] = -rng.random(n - live)
    G = np.zeros((steps, n, n - 2))
    G[:, 1:, :] = rng.standard_normal((steps, n - 1, n - 2)) * (rng.random((n - 1, n - 2)) < 0.3)
    M = rng.standard_normal((n - 2, n - 2))
    return A, G, M @ M.T, rng.uniform(0.005, 0.02, steps)


@pytest.mark.parametrize("frame", ["ecef", "body"])
def test_compiled_jacobians_equal_numpy(rocket, frame):
    """``Ecef21ErrorState.jacobians`` (the compiled kernel the EKF calls) equals
    :func:`ecef21_jacobians` along the rocket flight for both attitude errors, with the same
    zero entries (rounding only: 1e-12 of each matrix's largest entry)."""
    sl = slice(0, 8601, 7)
    bias = np.linspace(0.0, 0.01, sl.stop // 7 + 1)[:, None]
    nominal = Nominal(rocket.t[sl], rocket.position[sl], rocket.velocity[sl],
                      rocket.C_b_e()[sl], rocket.specific_force[sl] + bias,
                      rocket.angular_rate[sl] - bias, {})
    A, G = Ecef21ErrorState.build("motionpak_tactical", attitude_error=frame).jacobians(nominal)
    A_ref, G_ref = ecef21_jacobians(nominal.position, nominal.C_b_e, nominal.f_b,
                                    nominal.w_ib_b, frame)
    assert rel(A, A_ref) < STEP_RTOL
    np.testing.assert_array_equal(G, G_ref)
    np.testing.assert_array_equal(A != 0.0, A_ref != 0.0)


def test_kept_patterns_are_those_of_their_window():
    """A window whose non-zero entries differ from an earlier one's gets its own pattern
    from :data:`_PATTERNS` (the cache is keyed by the entries, not by the shapes)."""
    rng = np.random.default_rng(7)
    A, G, Qc, _ = _block_model(rng, 5)
    first = _pattern(A, G, Qc)
    A2 = A.copy()
    A2[:, 0, :] = 0.0
    second = _pattern(A2, G, Qc)
    assert not np.array_equal(first[0], second[0])
    assert _pattern(A, G, Qc) is first and len(_PATTERNS) >= 2


def test_rocket_steps_equal_discretize_steps(rocket):
    """The whole rocket flight (``|A dt|_1`` up to 1.6 in the boost): ``F`` and ``Q`` of the
    sparse kernel equal the batched NumPy discretisation (degree-12 Taylor after scaling)."""
    A, G, Qc, dt = _rocket_model(rocket)
    assert np.abs(A * dt[:, None, None]).sum(axis=1).max() > 1.0
    F, Q = discretize_window(A, G, Qc, dt, "series")
    F_ref, Q_ref = discretize_steps(A, G, Qc, dt, method="series")
    assert rel(F, F_ref) < STEP_RTOL
    assert rel(Q, Q_ref) < STEP_RTOL


@pytest.mark.parametrize("hold, max_step_s", [("mean", None), ("mean", 0.05), ("left", 0.03)])
def test_epoch_model_steps_equal_the_numpy_steps(rocket, hold, max_step_s, monkeypatch):
    """:func:`ecef21_at_epochs` with the compiled sparse steps equals the same chain of
    NumPy steps whose noise is built as before (``G`` averaged over one IMU step; over a
    decimated step the mean of the two ends' ``W``, here carried as ``[G_0, G_1]`` with
    ``Qc / 2``): F and Q per 1 Hz epoch within 1e-12 of each matrix's largest entry."""
    from navlib.models import ecef

    monkeypatch.setenv("NAVLIB_NO_CACHE", "1")
    model = ecef.ecef21_at_epochs(rocket, 1.0, hold=hold, max_step_s=max_step_s)
    Qc = ecef._constant_parts(None, "ecef", 5.0, {})["Qc"]

    def numpy_steps(A, G, Qc_held, dt, method):
        q = Qc.shape[0]
        if G.shape[2] == 2 * q:  # decimated: the mean of the two ends' W, as before
            W = 0.5 * sum(g @ Qc @ np.swapaxes(g, 1, 2) for g in (G[..., :q], G[..., q:]))
        else:
            W = G @ Qc_held @ np.swapaxes(G, 1, 2)
        return discretize_steps(A, None, None, dt, "series", W=W)

    monkeypatch.setattr(ecef, "discretize_window", numpy_steps)
    ecef._cached_chain.cache_clear()
    reference = ecef.ecef21_at_epochs(rocket, 1.0, hold=hold, max_step_s=max_step_s)
    ecef._cached_chain.cache_clear()
    assert rel(model.F, reference.F) < STEP_RTOL
    assert rel(model.Q, reference.Q) < STEP_RTOL


def test_epoch_model_does_not_depend_on_its_blocks(rocket, monkeypatch):
    """The streamed build gives the same model, bit for bit, whatever the block size
    (docs/performance.md "Model blocks"): each step is discretised on its own (the sparse
    pattern of a block only skips exact zeros) and epochs are chained within a block."""
    from navlib.models import ecef

    monkeypatch.setenv("NAVLIB_NO_CACHE", "1")
    built = []
    for samples in (20_000, 1_000, 333):
        monkeypatch.setattr(ecef, "STREAM_SAMPLES", samples)
        ecef._cached_chain.cache_clear()
        built.append(ecef.ecef21_at_epochs(rocket, 1.0, max_step_s=0.02))
    ecef._cached_chain.cache_clear()
    for model in built[1:]:
        np.testing.assert_array_equal(model.F, built[0].F)
        np.testing.assert_array_equal(model.Q, built[0].Q)


@pytest.mark.parametrize("scale", [1.0, 10.0 * TAYLOR_THETA])
@pytest.mark.parametrize("decay", [True, False])
def test_block_model_steps_equal_discretize_steps(scale, decay):
    """Random sparse models with Markov or random-walk rows, and steps long enough to need
    the scaling and squaring (``|A dt|`` above :data:`TAYLOR_THETA`, infinity norm);
    ``out`` buffers longer than the window are filled in their first steps."""
    rng = np.random.default_rng(5)
    A, G, Qc, dt = _block_model(rng, 40, decay=decay)
    dt = dt * scale
    out = (np.full((50, 12, 12), np.nan), np.full((50, 12, 12), np.nan))
    F, Q = discretize_window(A, G, Qc, dt, "series", out)
    assert F.base is out[0] and np.isnan(out[0][40:]).all()
    F_ref, Q_ref = discretize_steps(A, G, Qc, dt, method="series")
    if scale > 1.0:
        assert np.abs(A * dt[:, None, None]).sum(axis=2).max() > TAYLOR_THETA
    assert rel(F, F_ref) < STEP_RTOL
    assert rel(Q, Q_ref) < STEP_RTOL


def test_predict_sparse_equals_numpy():
    """``sym(F P F' + Q)`` with full and diagonal rows of ``F`` (and into ``P`` itself)."""
    rng = np.random.default_rng(6)
    n = 10
    F = np.diag(rng.uniform(0.5, 1.0, n))
    F[:4] += rng.standard_normal((4, n))
    M = rng.standard_normal((n, n))
    P, Q = M @ M.T, np.diag(rng.random(n))
    want = ref.predict(P, F, Q)
    out, FP, dense = np.empty((n, n)), np.empty((n, n)), np.empty(n, dtype=np.bool_)
    predict_sparse(P, F, Q, out, FP, dense)
    np.testing.assert_array_equal(dense, np.arange(n) < 4)
    assert rel(out, want) < STEP_RTOL
    np.testing.assert_array_equal(out, out.T)
    predict_sparse(P, F, Q, P, FP, dense)
    np.testing.assert_array_equal(P, out)


def _ekf_tolerances():
    path = Path(__file__).resolve().parent / "regression" / "tolerances.toml"
    entry = tomllib.loads(path.read_text())["ekf"]
    return {group: entry[group]["tolerance"] for group in ("position", "velocity", "attitude",
                                                           "nis")}


def test_rocket_ekf_equals_numpy_steps(rocket, monkeypatch):
    """The 86 s rocket EKF with the compiled sparse discretisation and propagation against
    the same loop with NumPy's (:func:`navlib.discretize.discretize_steps` and the NumPy
    propagation and update of tests/support/kalman_reference.py): the final errors (position,
    velocity, attitude, relative to the largest of each group) and the mean NIS within the
    golden tolerances, which hold across BLAS kernels; sigmas within 1e-6 relative."""
    spec = sensors.load_preset("motionpak_tactical")
    imu = sensors.simulate_imu(rocket, spec, seed=1)
    gnss = sensors.simulate_gnss(rocket, spec, seed=2)

    def run():
        result = ekf(imu, gnss, initial=strapdown.StrapdownState.from_trajectory(rocket),
                     model="ecef21", model_options={"sensors": "motionpak_tactical"})
        err = result.errors(rocket)
        final = {g: err[[f"{g[:3]}_{a}" for a in "xyz"]].to_numpy()[-1]
                 for g in ("position", "velocity", "attitude")}
        return result, {**final, "nis": np.array([np.mean(result.nis)])}

    compiled, got = run()

    def numpy_steps(A, G, Qc, dt, method, out=None):
        return discretize_steps(A, G, Qc, dt, method=method)

    monkeypatch.setattr(ekf_module, "discretize_window", numpy_steps)
    monkeypatch.setattr(ekf_updates, "fixed_updates_kernel", ref.fixed_updates)
    numpy_run, want = run()
    for group, tol in _ekf_tolerances().items():
        assert np.abs(got[group] - want[group]).max() <= tol * np.abs(want[group]).max(), group
    assert np.max(np.abs(compiled.sigma - numpy_run.sigma) / numpy_run.sigma) < 1e-6
