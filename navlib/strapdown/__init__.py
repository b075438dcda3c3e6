"""ECEF strapdown mechanisation for point-sampled IMU signals.

It follows docs/assumptions.md, excitability.md Eq. 1, and A2.

The navigation equations integrated here are those of España et al. (2019, Eq. 1) in ECEF::

    dP/dt = V
    dV/dt = C_b_e f_b + gamma(P) - 2 Omega x V          (normal gravity: docs/assumptions.md A5)
    dC_b_e/dt = C_b_e S(omega_ib_b) - S(Omega) C_b_e

The IMU delivers **point samples** of ``f_b`` and ``omega_ib_b`` (not increments). Between
samples both are reconstructed by cubic Lagrange interpolation through the four nearest
samples (one-sided at the ends), which is fourth-order accurate like the integrator:

* **Attitude.** Over a step ``[t_k, t_k + h]`` the attitude factorises exactly as
  ``C(t_k + tau) = exp(-S(Omega) tau) C_k exp(S(phi(tau)))``: the Earth-rate part is a known
  rotation about ECEF z and ``phi`` is the body rotation vector relative to inertial space,
  driven by the Bortz equation in its body-rate form (docs/assumptions.md A2,
  :func:`navlib.rotations.bortz_rate`). ``phi(h)`` is integrated by classical RK4 using the
  rates at ``0, h/2, h``; RK4 on the Bortz equation is exact for rotation about a fixed
  axis, and the full equation (including the ``1/12`` coning term and its higher-order
  coefficient) handles coning. ``phi(h/2)`` only serves to rotate the mid-step specific
  force and is taken from the closed-form coning integral of the interpolating parabola.
* **Velocity and position.** The ECEF specific force ``C(tau) f_b(tau)`` is formed at
  ``0, h/2, h`` — sculling is accounted for because the body force is rotated through the
  attitude *at* each abscissa, not through a step-start attitude. The Coriolis term is
  removed exactly by the substitution ``V = exp(-2 S(Omega) t) U``; ``U`` is integrated by
  Simpson's rule (exact for quadratic acceleration) and ``P`` by Simpson's rule on ``V``.
  Normal gravity (:func:`navlib.earth.normal_gravity_ecef`, docs/assumptions.md A5) is
  evaluated at the solution's own sample and mid-step positions by fixed-point iteration
  over 10 s windows
  (contraction ``|Gamma| T^2 / 2 ~ 1.5e-4``, stopped at 1e-8 m).

The attitude recursion does not depend on position or velocity, so every step's rotation
vector is computed first and the steps are chained with a log-depth parallel prefix product
of quaternions. :func:`integrate` runs all of it as one compiled kernel
(:func:`navlib.strapdown._kernel.integrate_kernel`); :func:`step` is the same mechanisation for
one interval (gravity at predicted points instead of the iteration), for filters that
propagate sample by sample; for blocks of samples between measurement updates,
:func:`integrate` from the current state is much faster, and loops over many such blocks
call :func:`propagate` with their :func:`block_clocks`. The compiled kernel is the private
module :mod:`navlib.strapdown._kernel`; :func:`compile_kernel` compiles or loads it.

Quaternions are stored scalar-last ``(x, y, z, w)`` like :mod:`scipy.spatial.transform`,
and ``q_b_e`` rotates body vectors into ECEF.
"""

from __future__ import annotations

__all__ = ["ClosureError", "StrapdownResult", "StrapdownState", "block_clocks", "body_attitude",
           "closure_error", "compile_kernel", "integrate", "integrate_kernel", "propagate",
           "step"]

from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.spatial.transform import Rotation

from navlib import earth
from navlib._validation import finite_array, finite_scalar, increasing_times
from navlib.errors import NavlibInputError
from navlib.quaternions import earth_quat, prefix_products, quat_from_rotvec, quat_mul, quat_rotate
from navlib.rotations import bortz_rate, cross
from navlib.strapdown._kernel import PICARD_MAX_ITER, compile_kernel, integrate_kernel

_OMEGA = earth.OMEGA_E


# --- inter-sample reconstruction --------------------------------------------------------------


def _interpolate(t, x, frac, lagrange=None):
    """Cubic Lagrange value of ``x`` at ``t_k + frac (t_{k+1} - t_k)`` for every interval k.

    Uses the four samples ``k-1 .. k+2`` (shifted inwards at the ends; fewer when N < 4).
    ``lagrange``: :func:`_lagrange` of ``t, frac`` when already computed (signals on the
    same clock share it). Returns (N-1, 3).
    """
    idx, weights = _lagrange(t, frac) if lagrange is None else lagrange
    return np.einsum("kj,kjd->kd", weights, x[idx])


def _lagrange(t, frac):
    """Sample indices (N-1, p) and weights (..., N-1, p) of :func:`_interpolate` for times
    ``t`` (..., N) (several blocks of one length at once, the same numbers as one by one)."""
    n = t.shape[-1]
    p = min(4, n)
    start = np.clip(np.arange(n - 1) - 1, 0, n - p)
    idx = start[:, None] + np.arange(p)  # (N-1, p)
    nodes = t[..., idx]
    target = t[..., :-1] + frac * np.diff(t, axis=-1)
    weights = np.ones((*t.shape[:-1], n - 1, p))
    for j in range(p):
        for m in range(p):
            if m != j:
                weights[..., j] *= ((target - nodes[..., m])
                                    / (nodes[..., j] - nodes[..., m]))
    return idx, weights


def _clock(t):
    """What :func:`propagate` needs of the sample times (..., N) alone: the mid-step
    :func:`_lagrange` weights and the Earth rotations since ``t[0]`` at the samples and
    mid-steps (several blocks of one length at once, the same numbers as one by one)."""
    t0 = t[..., :1]
    return (_lagrange(t, 0.5), earth_quat(t - t0),
            earth_quat(t[..., :-1] + 0.5 * np.diff(t, axis=-1) - t0))


def block_clocks(t, bounds) -> list:
    """What :func:`propagate` needs of the sample times of each block of a long run.

    Parameters
    ----------
    t : ndarray (N,)
        Sample times of the whole run, s (checked by the caller, strictly increasing).
    bounds : sequence of int
        Sample indices of the block boundaries, increasing; block ``i`` is
        ``t[bounds[i]:bounds[i + 1] + 1]`` (consecutive blocks share their boundary sample).

    Returns
    -------
    list
        One clock per block, to pass as ``clock`` to :func:`propagate`: the mid-step cubic
        Lagrange samples and weights and the Earth rotations since the block's first
        sample. Blocks of one length are computed together, giving the same numbers as
        one by one.
    """
    b0 = np.asarray(bounds[:-1])
    sizes = np.diff(bounds) + 1
    clocks = [None] * b0.size
    for n in np.unique(sizes).tolist():
        sel = np.flatnonzero(sizes == n)
        (idx, weights), earth, earth_mid = _clock(t[b0[sel, None] + np.arange(n)])
        for w, i in enumerate(sel.tolist()):
            clocks[i] = (idx, weights[w]), earth[w], earth_mid[w]
    return clocks


def _rotation_vector_rk4(w0, wm, w1, h):
    """Body rotation vector over ``[0, h]`` from rates at ``0, h/2, h`` (RK4 on Bortz, A2).

    ``w*`` are (..., 3), ``h`` is (...,) or scalar. Exact for a fixed rotation axis.
    """
    h = np.asarray(h, dtype=float)[..., None]
    k2 = bortz_rate(0.5 * h * w0, wm)
    k3 = bortz_rate(0.5 * h * k2, wm)
    k4 = bortz_rate(h * k3, w1)
    return h / 6.0 * (w0 + 2.0 * k2 + 2.0 * k3 + k4)


def _half_step_rotation_vector(w0, wm, w1, h):
    """Body rotation vector over ``[0, h/2]`` for the parabola through ``w0, wm, w1``.

    ``phi = int w + 1/2 int alpha x w`` in closed form for ``w = a + b tau + c tau^2``:
    ``a T + b T^2/2 + c T^3/3 + (a x b) T^3/12 + (a x c) T^4/12 + (b x c) T^5/60`` with
    ``T = h/2``. The omitted third-order Bortz term is ``O(|phi|^2 |w_perp| T)``; this
    vector only rotates the mid-step specific force, so the error does not accumulate.
    """
    h = np.asarray(h, dtype=float)[..., None]
    b = (4.0 * wm - 3.0 * w0 - w1) / h
    c = 2.0 * (w0 - 2.0 * wm + w1) / h**2
    T = 0.5 * h
    return (w0 * T + b * T**2 / 2.0 + c * T**3 / 3.0 + cross(w0, b) * T**3 / 12.0
            + cross(w0, c) * T**4 / 12.0 + cross(b, c) * T**5 / 60.0)


def _attitude_increments(w0, wm, w1, h):
    """Body rotation vectors over the full step (RK4 on Bortz) and over its first half."""
    return _rotation_vector_rk4(w0, wm, w1, h), _half_step_rotation_vector(w0, wm, w1, h)


def _turn(angle):
    """``(cos, sin)`` of rotation angles (...,), for :func:`_rotate_z`."""
    return np.cos(angle), np.sin(angle)


def _rotate_z(x, turn):
    """Rotate vectors (..., 3) about ECEF z by the angles of ``turn`` (:func:`_turn`)."""
    c, s = turn
    out = np.empty_like(x)
    out[..., 0] = c * x[..., 0] - s * x[..., 1]
    out[..., 1] = s * x[..., 0] + c * x[..., 1]
    out[..., 2] = x[..., 2]
    return out


@dataclass(frozen=True, eq=False)
class _Steps:
    """What :func:`_translation` needs of the steps ``h`` (M,) alone, the same at each
    gravity iteration of a window: ``h/6``, ``h/24`` (M, 1) and the Coriolis rotations
    ``R(t)'`` (``turn``) and ``R(t)`` (``back``) at the samples and then the mid-steps
    (2M + 1,), which are rotated together."""

    h6: np.ndarray
    h24: np.ndarray
    turn: tuple
    back: tuple

    @classmethod
    def of(cls, h) -> _Steps:
        s = np.concatenate([[0.0], np.cumsum(h)])
        s_both = np.concatenate([s, s[:-1] + 0.5 * h])
        two_omega = 2.0 * _OMEGA
        hh = h[:, None]
        return cls(hh / 6.0, hh / 24.0, _turn(two_omega * s_both), _turn(-two_omega * s_both))


def _translation(h, r0, v0, a, a_mid, steps=None):
    """Position and velocity over consecutive steps for a known acceleration history.

    Solves ``dV/dt = a(t) - 2 Omega x V``, ``dP/dt = V`` with ``a`` (M+1, 3) at the sample
    times and ``a_mid`` (M, 3) at the mid-steps, ``h`` (M,) the steps. The Coriolis term is
    exact through ``V = R(t) U``, ``R(t) = exp(-2 S(Omega) t)``, ``dU/dt = R(t)^T a``; ``U``
    is integrated by Simpson's rule (exact for quadratic ``a``) and ``P`` by Simpson's rule
    on ``V`` (exact for cubic ``V``). Returns ``P``, ``V`` (M+1, 3) and the mid-step
    positions (M, 3), which only serve to evaluate gravity there. ``steps``:
    :meth:`_Steps.of` ``h`` when already computed.
    """
    steps = _Steps.of(h) if steps is None else steps
    m = h.shape[0] + 1
    both = _rotate_z(np.concatenate([a, a_mid]), steps.turn)
    at, at_mid = both[:m], both[m:]
    u, u_mid = _simpson_integral(at, at_mid, steps)
    both = _rotate_z(np.concatenate([u, u_mid]) + v0, steps.back)
    v, v_mid = both[:m], both[m:]
    r, r_mid = _simpson_integral(v, v_mid, steps)
    return r + r0, v, r_mid + r0


def _simpson_integral(x, x_mid, steps):
    """The integral of ``x`` from the first sample to each sample (M+1, 3) and to each
    mid-step (M, 3), by Simpson's rule on ``x`` at the samples and mid-steps (exact for
    quadratic ``x``)."""
    dx = steps.h6 * (x[:-1] + 4.0 * x_mid + x[1:])
    integral = np.empty_like(x)
    integral[0] = 0.0
    np.cumsum(dx, axis=0, out=integral[1:])
    return integral, integral[:-1] + steps.h24 * (5.0 * x[:-1] + 8.0 * x_mid - x[1:])



# --- public API ---------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class StrapdownState:
    """Navigation state at one instant: ECEF position (m), velocity (m/s), attitude.

    ``q_b_e`` is the body -> ECEF unit quaternion, scalar-last (scipy order).
    """

    t: float
    position: np.ndarray
    velocity: np.ndarray
    q_b_e: np.ndarray

    @property
    def attitude(self) -> Rotation:
        """Body -> ECEF rotation."""
        return Rotation.from_quat(self.q_b_e)

    @classmethod
    def from_trajectory(cls, trajectory, index: int = 0) -> StrapdownState:
        """The true state of a :class:`navlib.trajectory.Trajectory` at sample ``index``."""
        return cls(
            t=float(trajectory.t[index]),
            position=np.array(trajectory.position[index], dtype=float),
            velocity=np.array(trajectory.velocity[index], dtype=float),
            q_b_e=trajectory.attitude[index].as_quat(),
        )


def step(state: StrapdownState, f_b, w_ib_b, dt_s: float, *, f_mid=None, w_mid=None
         ) -> StrapdownState:
    """Propagate one IMU interval (the per-sample form of :func:`integrate`).

    Parameters
    ----------
    state : StrapdownState
        State at the start of the interval.
    f_b, w_ib_b : array_like (2, 3)
        Point samples of specific force (m/s^2) and inertial body rate (rad/s) at the start
        and at the end of the interval.
    dt_s : float
        Interval length, s (> 0).
    f_mid, w_mid : array_like (3,), optional
        Samples at mid-interval. By default the mean of the two samples is used (linear
        reconstruction, second order in ``dt_s``); pass a cubic interpolation through the
        neighbouring samples, as :func:`integrate` does, for fourth order.

    Returns
    -------
    StrapdownState
        The state at ``state.t + dt_s``.

    Notes
    -----
    Input checking is limited to shapes and ``dt_s``; see the module docstring for the
    mechanisation (docs/assumptions.md A2). Gravity is evaluated at the points
    ``P + tau V + tau^2/2 f_e`` predicted from the start state. Each call costs a few hundred
    microseconds of NumPy overhead; to propagate a block of samples (e.g. between GNSS
    epochs) call :func:`integrate` with ``state.position, state.velocity, state.q_b_e``.
    """
    f_b = np.asarray(f_b, dtype=float)
    w_ib_b = np.asarray(w_ib_b, dtype=float)
    if f_b.shape != (2, 3):
        raise NavlibInputError(f"f_b: expected shape (2, 3), got {f_b.shape}")
    if w_ib_b.shape != (2, 3):
        raise NavlibInputError(f"w_ib_b: expected shape (2, 3), got {w_ib_b.shape}")
    if not dt_s > 0.0:
        raise NavlibInputError(f"dt_s: must be > 0, got {dt_s}")
    f_mid = 0.5 * (f_b[0] + f_b[1]) if f_mid is None else np.asarray(f_mid, dtype=float)
    w_mid = 0.5 * (w_ib_b[0] + w_ib_b[1]) if w_mid is None else np.asarray(w_mid, dtype=float)

    phi, phi_half = _attitude_increments(w_ib_b[0], w_mid, w_ib_b[1], dt_s)
    q0 = state.q_b_e
    q_mid = quat_mul(earth_quat(0.5 * dt_s), quat_mul(q0, quat_from_rotvec(phi_half)))
    q1 = quat_mul(earth_quat(dt_s), quat_mul(q0, quat_from_rotvec(phi)))
    q1 = q1 / np.linalg.norm(q1)
    f_e = np.stack([quat_rotate(q0, f_b[0]), quat_rotate(q1, f_b[1])])
    f_e_mid = quat_rotate(q_mid, f_mid)
    # Gravity at the points predicted from the start state (no Picard iteration here).
    tau = np.array([0.0, 0.5 * dt_s, dt_s])[:, None]
    g = earth.normal_gravity_ecef(state.position + tau * state.velocity + 0.5 * tau**2 * f_e[0])
    r, v, _ = _translation(np.array([dt_s]), state.position, state.velocity,
                           f_e + g[[0, 2]], (f_e_mid + g[1])[None])
    r1, v1 = r[1], v[1]
    return StrapdownState(t=state.t + dt_s, position=r1, velocity=v1, q_b_e=q1)


@dataclass(frozen=True, eq=False)
class StrapdownResult:
    """Integrated navigation solution at the IMU sample times.

    Attributes
    ----------
    t : ndarray (N,)
    position, velocity : ndarray (N, 3)
        ECEF, m and m/s.
    attitude : scipy.spatial.transform.Rotation, length N
        Body -> ECEF.
    """

    t: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    attitude: Rotation

    def state(self, index: int) -> StrapdownState:
        """The solution at sample ``index`` as a :class:`StrapdownState`."""
        return StrapdownState(t=float(self.t[index]), position=self.position[index].copy(),
                              velocity=self.velocity[index].copy(),
                              q_b_e=self.attitude[index].as_quat())

    def to_frame(self) -> pd.DataFrame:
        """Tidy DataFrame: t, ECEF x/y/z, vx/vy/vz, scalar-last quaternion qx..qw."""
        q = self.attitude.as_quat()
        return pd.DataFrame({
            "t": self.t,
            "x": self.position[:, 0], "y": self.position[:, 1], "z": self.position[:, 2],
            "vx": self.velocity[:, 0], "vy": self.velocity[:, 1], "vz": self.velocity[:, 2],
            "qx": q[:, 0], "qy": q[:, 1], "qz": q[:, 2], "qw": q[:, 3],
        })


def _attitude_quat(attitude0) -> np.ndarray:
    """A single body -> ECEF attitude as a unit quaternion (Rotation, 3x3 matrix or quat)."""
    if isinstance(attitude0, Rotation):
        if not attitude0.single:
            raise NavlibInputError("attitude0: expected a single Rotation, got a stack")
        return attitude0.as_quat()
    arr = finite_array(attitude0, "attitude0")
    if arr.shape == (3, 3):
        if not np.allclose(arr.T @ arr, np.eye(3), atol=1e-6) or np.linalg.det(arr) < 0:
            raise NavlibInputError("attitude0: 3x3 matrix is not a proper rotation")
        return Rotation.from_matrix(arr).as_quat()
    if arr.shape == (4,):
        norm = np.linalg.norm(arr)
        if abs(norm - 1.0) > 1e-6:
            raise NavlibInputError(f"attitude0: quaternion norm must be 1, got {norm}")
        return arr / norm
    raise NavlibInputError(
        "attitude0: expected a scipy Rotation, a (3, 3) matrix or a scalar-last quaternion (4,),"
        f" got shape {arr.shape}"
    )


def _body_products(dq):
    """The chain ``B_k`` (N + 1, 4) of body increments ``dq`` (N, 4), ``B_0 = 1``."""
    body = np.empty((dq.shape[0] + 1, 4))
    body[0] = (0.0, 0.0, 0.0, 1.0)
    body[1:] = prefix_products(dq)
    return body


def body_attitude(t, w_ib_b) -> Rotation:
    """Gyro-only attitude chain ``B_k`` of :func:`integrate`: ``C_k = E(t_k - t_0) C_0 B_k``.

    ``B_k`` is the body's rotation from ``t[0]`` to ``t[k]`` relative to inertial space
    (same fourth-order increments as :func:`integrate`), so any initial attitude ``C_0`` can
    be applied afterwards without integrating again (the flight fit levels at a later
    window). ``E`` is the Earth rotation ``exp(-S(Omega) (t_k - t_0))``.
    """
    t = increasing_times(t, "t")
    w_ib_b = finite_array(w_ib_b, "w_ib_b", (t.size, 3))
    h = np.diff(t)
    phi, _ = _attitude_increments(w_ib_b[:-1], _interpolate(t, w_ib_b, 0.5), w_ib_b[1:], h)
    return Rotation.from_quat(_body_products(quat_from_rotvec(phi)))


def integrate(t, f_b, w_ib_b, position0, velocity0, attitude0) -> StrapdownResult:
    """Integrate point-sampled IMU signals in ECEF from an initial state.

    Parameters
    ----------
    t : array_like (N,)
        Sample times, s, strictly increasing (non-uniform spacing is allowed).
    f_b : array_like (N, 3)
        Specific force in body axes, m/s^2 (point samples).
    w_ib_b : array_like (N, 3)
        Inertial angular rate in body axes, rad/s (point samples).
    position0, velocity0 : array_like (3,)
        ECEF position (m) and velocity (m/s) at ``t[0]``.
    attitude0 : Rotation, (3, 3) matrix or (4,) scalar-last quaternion
        Body -> ECEF attitude at ``t[0]``.

    Returns
    -------
    StrapdownResult

    Notes
    -----
    Fourth-order scheme described in the module docstring (docs/assumptions.md,
    excitability.md Eq. 1, A2, A5). Closure on the exact IMU of
    ``navlib.trajectory.sounding_rocket()`` (100 Hz) is
    checked by ``tests/strapdown/test_strapdown.py``.
    """
    t = increasing_times(t, "t")
    n = t.size
    f_b = finite_array(f_b, "f_b", (n, 3))
    w_ib_b = finite_array(w_ib_b, "w_ib_b", (n, 3))
    r = finite_array(position0, "position0", (3,))
    v = finite_array(velocity0, "velocity0", (3,))
    if np.linalg.norm(r) < 1e5:
        raise NavlibInputError("position0: expected an ECEF position in m (|r| >= 100 km)")
    return propagate(t, f_b, w_ib_b, r, v, _attitude_quat(attitude0))


def propagate(t, f_b, w_ib_b, r, v, q0, clock=None) -> StrapdownResult:
    """:func:`integrate` without its input checks, for loops over many short blocks.

    The same compiled mechanisation (module docstring; docs/assumptions.md,
    excitability.md Eq. 1, A2, A5) for callers that propagate blocks from states they
    computed themselves, such as the
    EKF's windows (:func:`navlib.filters.ekf`).

    Parameters
    ----------
    t : ndarray (N,)
        Sample times, s, strictly increasing (not checked).
    f_b, w_ib_b : ndarray (N, 3)
        Specific force (m/s^2) and inertial body rate (rad/s), finite (not checked).
    r, v : ndarray (3,)
        ECEF position (m) and velocity (m/s) at ``t[0]``.
    q0 : ndarray (4,)
        Body -> ECEF unit quaternion at ``t[0]``, scalar-last.
    clock : tuple, optional
        This block's entry of :func:`block_clocks` (computed here when not given).

    Returns
    -------
    StrapdownResult

    Raises
    ------
    NavlibInputError
        When the gravity iteration does not converge (sample steps of many seconds).
    """
    n = t.size
    (idx, weights), earth_q, earth_mid = _clock(t) if clock is None else clock
    position, velocity, q = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 4))
    # C-contiguous and writeable: the one type the kernel is compiled for
    # (:func:`navlib.strapdown._kernel.compile_kernel`); a read-only view (a broadcast
    # trajectory row, a cached array) would be a second specialisation, compiled on first use
    inputs = (np.require(a, float, "CW")
              for a in (t, f_b, w_ib_b, r, v, q0, weights, earth_q, earth_mid))
    t_c, f_c, w_c, r_c, v_c, q_c, weights_c, earth_c, earth_mid_c = inputs
    failed = integrate_kernel(t_c, f_c, w_c, r_c, v_c, q_c, np.require(idx, np.int64, "CW"),
                              weights_c, earth_c, earth_mid_c, position, velocity, q)
    if failed >= 0:
        h = np.diff(t[failed:])
        raise NavlibInputError(
            f"t: the gravity iteration did not converge within {PICARD_MAX_ITER} passes from "
            f"{t[failed]:.6g} s; sample steps this long ({h.max():.3g} s) are not supported")
    return StrapdownResult(t=t, position=position, velocity=velocity,
                           attitude=Rotation.from_quat(q))
@dataclass(frozen=True, eq=False)
class ClosureError:
    """Difference between a strapdown re-integration and the trajectory it came from.

    Attributes
    ----------
    t : ndarray (N,)
    position_error, velocity_error, attitude_error : ndarray (N,)
        Norms of the position (m) and velocity (m/s) differences and the angle (rad) of
        ``C_true^T C_integrated``.
    position_m, velocity_m_s, attitude_rad : float
        Their maxima over the run.
    """

    t: np.ndarray
    position_error: np.ndarray
    velocity_error: np.ndarray
    attitude_error: np.ndarray

    @property
    def position_m(self) -> float:
        return float(np.max(self.position_error))

    @property
    def velocity_m_s(self) -> float:
        return float(np.max(self.velocity_error))

    @property
    def attitude_rad(self) -> float:
        return float(np.max(self.attitude_error))

    def to_frame(self) -> pd.DataFrame:
        """Tidy DataFrame: t, position_error_m, velocity_error_m_s, attitude_error_rad."""
        return pd.DataFrame({"t": self.t, "position_error_m": self.position_error,
                             "velocity_error_m_s": self.velocity_error,
                             "attitude_error_rad": self.attitude_error})


def closure_error(trajectory, *, duration_s: float | None = None) -> ClosureError:
    """Integrate a trajectory's own exact IMU from its initial state and compare.

    Parameters
    ----------
    trajectory : navlib.trajectory.Trajectory
    duration_s : float, optional
        Only integrate the first ``duration_s`` seconds (default: all of it).

    Returns
    -------
    ClosureError
        Position, velocity and attitude error along the run and their maxima.
    """
    n = len(trajectory.t)
    if duration_s is not None:
        duration_s = finite_scalar(duration_s, "duration_s", 0.0, low_open=True)
        n = int(np.searchsorted(trajectory.t, trajectory.t[0] + duration_s, side="right"))
        if n < 2:
            raise NavlibInputError(f"duration_s: {duration_s} s covers fewer than 2 samples")
    sl = slice(0, n)
    res = integrate(trajectory.t[sl], trajectory.specific_force[sl],
                    trajectory.angular_rate[sl], trajectory.position[0],
                    trajectory.velocity[0], trajectory.attitude[0])
    d_att = (trajectory.attitude[sl].inv() * res.attitude).magnitude()
    return ClosureError(
        t=res.t,
        position_error=np.linalg.norm(res.position - trajectory.position[sl], axis=1),
        velocity_error=np.linalg.norm(res.velocity - trajectory.velocity[sl], axis=1),
        attitude_error=d_att,
    )
