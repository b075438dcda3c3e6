"""The compiled strapdown mechanisation (:func:`navlib.strapdown._kernel.integrate_kernel`)
equals the vectorised NumPy code it replaced (tests/support/strapdown_reference.py): one EKF window
and one interval within 1e-12 relative, the 86 s sounding-rocket flight within the drift
rounding accumulates."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from support import strapdown_reference as ref

from navlib import filters, strapdown
from navlib.quaternions import quat_from_matrix
from navlib.trajectory import launcher_ascent, sounding_rocket

STEP_RTOL = 1e-12


@pytest.fixture(scope="module")
def rocket():
    return sounding_rocket()


def _start(traj, k):
    return (np.array(traj.position[k]), np.array(traj.velocity[k]),
            traj.attitude[k].as_quat())


def _rel(a, b):
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


@pytest.mark.parametrize(("first", "count"), [(0, 2), (0, 11), (1234, 11), (3000, 101)])
def test_block_equals_numpy(rocket, first, count):
    """A block of ``count`` samples (one interval, an EKF window of 0.1 s, a 1 s window)
    with a perturbed IMU: position and velocity within 1e-12 relative of their change over
    the block, attitude within 1e-12 rad."""
    rng = np.random.default_rng(first)
    sl = slice(first, first + count)
    t = rocket.t[sl]
    f_b = rocket.specific_force[sl] + 0.1 * rng.standard_normal((count, 3))
    w_b = rocket.angular_rate[sl] + 0.01 * rng.standard_normal((count, 3))
    r, v, q = _start(rocket, first)
    got = strapdown.propagate(t, f_b, w_b, r, v, q)
    want = ref.integrate(t, f_b, w_b, r, v, q)
    assert _rel(got.position - r, want.position - r) < STEP_RTOL
    assert _rel(got.velocity, want.velocity) < STEP_RTOL
    assert (got.attitude.inv() * want.attitude).magnitude().max() < STEP_RTOL


def test_86_s_flight_equals_numpy(rocket):
    """The whole 86 s flight at 100 Hz (nine 10 s gravity windows): within 1e-9 m and
    1e-11 m/s of the NumPy mechanisation, far inside the closure error of the scheme."""
    args = (rocket.t, rocket.specific_force, rocket.angular_rate, *_start(rocket, 0))
    got = strapdown.propagate(*args)
    want = ref.integrate(*args)
    assert np.abs(got.position - want.position).max() < 1e-9
    assert np.abs(got.velocity - want.velocity).max() < 1e-11
    assert (got.attitude.inv() * want.attitude).magnitude().max() < 1e-13


def test_quaternion_of_a_matrix_is_scipys():
    """The compiled :func:`navlib.quaternions.quat_from_matrix` gives scipy's quaternion to
    the bit on random rotations, and scipy's projection for a matrix that is not one."""
    C = Rotation.random(2000, random_state=3).as_matrix()
    got = np.array([quat_from_matrix(c) for c in C])
    np.testing.assert_array_equal(got, Rotation.from_matrix(C).as_quat())
    np.testing.assert_array_equal(quat_from_matrix(1.001 * C[0]),
                                  Rotation.from_matrix(1.001 * C[0]).as_quat())


def test_read_only_inputs_use_the_one_compiled_specialisation():
    """Read-only inputs (the stationary trajectory's broadcast positions, a broadcast
    attitude matrix, the times of the EKF's windows) are passed to the kernels as the
    writeable C arrays they are compiled for (``compile_kernel``), so a notebook never
    compiles a second specialisation."""
    from navlib.quaternions import _matrix_quat_kernel
    from navlib.strapdown._kernel import integrate_kernel
    from navlib.trajectory import stationary

    still = stationary(duration_s=2.0)
    assert not still.position[0].flags.writeable
    strapdown.closure_error(still)
    strapdown.closure_error(sounding_rocket(), duration_s=1.0)
    C = np.broadcast_to(still.C_b_e()[0], (2, 3, 3))[0]
    np.testing.assert_array_equal(quat_from_matrix(C), Rotation.from_matrix(C).as_quat())
    quat_from_matrix(np.eye(3))
    short = launcher_ascent(duration_s=2.0)
    filters.simulate_ekf(short, solution="ins_gps_att", biases="GAP", bias_model="markov",
                         seed=0, gnss_rate_hz=short.rate_hz, window_s=0.1)
    assert len(integrate_kernel.signatures) == 1
    assert len(_matrix_quat_kernel.signatures) == 1
