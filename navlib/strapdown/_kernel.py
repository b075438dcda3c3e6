"""The strapdown mechanisation of :func:`navlib.strapdown.integrate` as one compiled kernel
(docs/assumptions.md, excitability.md Eq. 1, A2, A5; docs/assumptions.md "Compiled kernels").

:func:`integrate_kernel` runs the fourth-order scheme the module docstring of
:mod:`navlib.strapdown` describes over a block of samples: cubic Lagrange mid-step samples,
RK4 on the Bortz equation and the closed-form half-step rotation vector, the chain of body
increments by the same log-depth prefix product, the specific force rotated to ECEF at the
samples and mid-steps, and the translation with the exact Coriolis substitution, Simpson's
rule and gravity at the solution's own points by fixed-point iteration over
:data:`WINDOW_S` windows. Every formula is written out in the order of the NumPy code it
replaced (``tests/support/strapdown_reference.py``), so results agree to rounding; each interval
costs a few hundred floating-point operations instead of a few hundred NumPy calls per
block, which made the EKF's 0.1 s windows Python-bound.

The kernels use element loops, :func:`numpy.empty` and views only: no array expressions,
reductions, slice assignments or :func:`numpy.searchsorted`, whose numba implementations
each compile on first use: they made about half of the first compile (13.6 CPU-s with
them, about 7 without, for the same numbers to the bit; issue 26).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from navlib import earth
from navlib.cache import drop_stale_kernel_caches
from navlib.quaternions import quat_from_matrix

WINDOW_S = 10.0
"""Length of the windows in which the translational recursion is solved by fixed-point
iteration on gravity; the contraction factor is about ``|Gamma| T^2 / 2`` (1.5e-4 at the
surface for 10 s)."""
PICARD_TOL_M = 1e-8
"""The iteration stops when no position changes by this much (m) between passes."""
PICARD_MAX_ITER = 30
"""Passes of the iteration before :func:`integrate_kernel` reports no convergence."""

_OMEGA = earth.OMEGA_E
_GM = earth.GM
_J2_K = 1.5 * earth.J2 * earth.GM * earth.A**2
_CENTRIFUGAL = earth.OMEGA_E**2


@numba.njit(cache=True)
def _cross(a, b, out):
    """``out = a x b`` for (3,) vectors."""
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]


@numba.njit(cache=True)
def _norm3(a):
    return math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])


@numba.njit(cache=True)
def _bortz_rate(theta, w, out):
    """:func:`navlib.rotations.bortz_rate` of one rotation vector into ``out``."""
    a = _norm3(theta)
    if abs(a) < 0.2:
        a2 = a * a
        c = 1.0 / 12.0 + a2 * (1.0 / 720.0 + a2 * (1.0 / 30240.0 + a2 * (1.0 / 1209600.0
                                                                          + a2 / 47900160.0)))
    else:
        half = 0.5 * a
        c = (1.0 - half / math.tan(half)) / (a * a)
    txw, ttxw = np.empty(3), np.empty(3)
    _cross(theta, w, txw)
    _cross(theta, txw, ttxw)
    for i in range(3):
        out[i] = w[i] + 0.5 * txw[i] + c * ttxw[i]


@numba.njit(cache=True)
def _increments(w0, wm, w1, h, phi, phi_half):
    """RK4 on the Bortz equation over ``[0, h]`` and the closed-form rotation vector over
    ``[0, h/2]`` (:func:`navlib.strapdown._attitude_increments`) into ``phi``,
    ``phi_half``."""
    arg, k2, k3, k4 = np.empty(3), np.empty(3), np.empty(3), np.empty(3)
    for i in range(3):
        arg[i] = 0.5 * h * w0[i]
    _bortz_rate(arg, wm, k2)
    for i in range(3):
        arg[i] = 0.5 * h * k2[i]
    _bortz_rate(arg, wm, k3)
    for i in range(3):
        arg[i] = h * k3[i]
    _bortz_rate(arg, w1, k4)
    for i in range(3):
        phi[i] = h / 6.0 * (w0[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
    b, c = np.empty(3), np.empty(3)
    for i in range(3):
        b[i] = (4.0 * wm[i] - 3.0 * w0[i] - w1[i]) / h
        c[i] = 2.0 * (w0[i] - 2.0 * wm[i] + w1[i]) / h**2
    T = 0.5 * h
    w0b, w0c, bc = np.empty(3), np.empty(3), np.empty(3)
    _cross(w0, b, w0b)
    _cross(w0, c, w0c)
    _cross(b, c, bc)
    for i in range(3):
        phi_half[i] = (w0[i] * T + b[i] * T**2 / 2.0 + c[i] * T**3.0 / 3.0
                       + w0b[i] * T**3.0 / 12.0 + w0c[i] * T**4.0 / 12.0
                       + bc[i] * T**5.0 / 60.0)


@numba.njit(cache=True)
def _quat_from_rotvec(phi, out):
    """:func:`navlib.quaternions.quat_from_rotvec` of one rotation vector into ``out``."""
    angle = _norm3(phi)
    half = 0.5 * angle
    k = 0.5 - angle**2 / 48.0 if angle < 1e-4 else math.sin(half) / angle
    for i in range(3):
        out[i] = k * phi[i]
    out[3] = math.cos(half)


@numba.njit(cache=True)
def _quat_mul(p, q, out):
    """:func:`navlib.quaternions.quat_mul` of two quaternions into ``out`` (not ``p`` or
    ``q``)."""
    out[0] = p[3] * q[0] + p[0] * q[3] + p[1] * q[2] - p[2] * q[1]
    out[1] = p[3] * q[1] - p[0] * q[2] + p[1] * q[3] + p[2] * q[0]
    out[2] = p[3] * q[2] + p[0] * q[1] - p[1] * q[0] + p[2] * q[3]
    out[3] = p[3] * q[3] - p[0] * q[0] - p[1] * q[1] - p[2] * q[2]


@numba.njit(cache=True)
def _quat_rotate(q, v, out):
    """:func:`navlib.quaternions.quat_rotate`: ``C(q) v`` into ``out``."""
    uv, uuv = np.empty(3), np.empty(3)
    _cross(q[:3], v, uv)
    _cross(q[:3], uv, uuv)
    for i in range(3):
        out[i] = v[i] + 2.0 * (q[3] * uv[i] + uuv[i])


@numba.njit(cache=True)
def _prefix_products(q):
    """:func:`navlib.quaternions.prefix_products` in place on (N, 4): the same Hillis–Steele
    scan (each pass reads the previous pass's values), then normalised."""
    tmp = np.empty(4)
    shift = 1
    while shift < q.shape[0]:
        for k in range(q.shape[0] - 1, shift - 1, -1):
            _quat_mul(q[k - shift], q[k], tmp)
            for i in range(4):
                q[k, i] = tmp[i]
        shift *= 2
    for k in range(q.shape[0]):
        norm = math.sqrt(q[k, 0] * q[k, 0] + q[k, 1] * q[k, 1] + q[k, 2] * q[k, 2]
                         + q[k, 3] * q[k, 3])
        for i in range(4):
            q[k, i] /= norm


@numba.njit(cache=True)
def _gravity(r, out):
    """:func:`navlib.earth.normal_gravity_ecef` (central, J2 and centrifugal) at one ECEF
    position into ``out`` (docs/assumptions.md A5)."""
    r2 = r[0] ** 2 + r[1] ** 2 + r[2] ** 2
    norm = math.sqrt(r2)
    s = r[2] ** 2 / r2
    r3, r5 = norm**3.0, norm**5.0
    for i in range(3):
        a_coef = 3.0 if i == 2 else 1.0
        centrifugal = _CENTRIFUGAL * r[i] * (0.0 if i == 2 else 1.0)
        out[i] = (-_GM * r[i] / r3 + -_J2_K * r[i] * (a_coef - 5.0 * s) / r5) + centrifugal


@numba.njit(cache=True)
def _rotate_rows(x, cos_turn, sin_turn, first, sign, out):
    """Rotate each row ``k`` of ``x`` (K, 3) about ECEF z by the angle of cosine
    ``cos_turn[first + k]`` and sine ``sign * sin_turn[first + k]`` into ``out``."""
    for k in range(x.shape[0]):
        c, s = cos_turn[first + k], sign * sin_turn[first + k]
        out[k, 0] = c * x[k, 0] - s * x[k, 1]
        out[k, 1] = s * x[k, 0] + c * x[k, 1]
        out[k, 2] = x[k, 2]


@numba.njit(cache=True)
def _add_row(x, row):
    """``x += row`` for ``x`` (K, 3) and ``row`` (3,)."""
    for k in range(x.shape[0]):
        for i in range(3):
            x[k, i] += row[i]


@numba.njit(cache=True)
def _simpson_integral(h, x, x_mid, integral, integral_mid):
    """:func:`navlib.strapdown._simpson_integral`: the integral of ``x`` (M+1, 3) from the
    first sample to each sample into ``integral`` (M+1, 3) and to each mid-step into
    ``integral_mid`` (M, 3), by Simpson's rule on ``x`` and ``x_mid`` (M, 3) over the
    steps ``h`` (M,)."""
    for i in range(3):
        integral[0, i] = 0.0
    for k in range(h.shape[0]):
        for i in range(3):
            integral[k + 1, i] = integral[k, i] + h[k] / 6.0 * (x[k, i] + 4.0 * x_mid[k, i]
                                                                + x[k + 1, i])
    for k in range(h.shape[0]):
        for i in range(3):
            integral_mid[k, i] = integral[k, i] + h[k] / 24.0 * (5.0 * x[k, i]
                                                                 + 8.0 * x_mid[k, i]
                                                                 - x[k + 1, i])


@numba.njit(cache=True)
def _translation(h, r0, v0, a, a_mid, cos_turn, sin_turn, r, v, r_mid):
    """:func:`navlib.strapdown._translation` over one window (steps ``h`` (M,), ``a``
    (M+1, 3), ``a_mid`` (M, 3); ``cos_turn``, ``sin_turn`` of ``2 Omega s`` at the samples
    and then the mid-steps) into ``r``, ``v`` (M+1, 3) and ``r_mid`` (M, 3)."""
    m = h.shape[0] + 1
    at, at_mid = np.empty((m, 3)), np.empty((m - 1, 3))
    _rotate_rows(a, cos_turn, sin_turn, 0, 1.0, at)
    _rotate_rows(a_mid, cos_turn, sin_turn, m, 1.0, at_mid)
    u, u_mid = np.empty((m, 3)), np.empty((m - 1, 3))
    _simpson_integral(h, at, at_mid, u, u_mid)
    _add_row(u, v0)
    _add_row(u_mid, v0)
    v_mid = np.empty((m - 1, 3))
    _rotate_rows(u, cos_turn, sin_turn, 0, -1.0, v)
    _rotate_rows(u_mid, cos_turn, sin_turn, m, -1.0, v_mid)
    _simpson_integral(h, v, v_mid, r, r_mid)
    _add_row(r, r0)
    _add_row(r_mid, r0)


@numba.njit(cache=True)
def _translation_window(h, r0, v0, f_e, f_e_mid, r, v):
    """Translation over one window with gravity at the solution's own positions by
    fixed-point iteration (:data:`PICARD_TOL_M`); False when it does not converge within
    :data:`PICARD_MAX_ITER` passes."""
    m = h.shape[0] + 1
    s_both = np.empty(2 * m - 1)
    s_both[0] = 0.0
    for k in range(m - 1):
        s_both[k + 1] = s_both[k] + h[k]
    for k in range(m - 1):
        s_both[m + k] = s_both[k] + 0.5 * h[k]
    cos_turn, sin_turn = np.empty(2 * m - 1), np.empty(2 * m - 1)
    for k in range(2 * m - 1):
        cos_turn[k] = math.cos(2.0 * _OMEGA * s_both[k])
        sin_turn[k] = math.sin(2.0 * _OMEGA * s_both[k])
    g0 = np.empty(3)
    _gravity(r0, g0)
    a, a_mid = np.empty((m, 3)), np.empty((m - 1, 3))
    for k in range(m):
        for i in range(3):
            a[k, i] = f_e[k, i] + g0[i]
    for k in range(m - 1):
        for i in range(3):
            a_mid[k, i] = f_e_mid[k, i] + g0[i]
    previous, r_mid, g = np.empty((m, 3)), np.empty((m - 1, 3)), np.empty(3)
    for iteration in range(PICARD_MAX_ITER):
        _translation(h, r0, v0, a, a_mid, cos_turn, sin_turn, r, v, r_mid)
        converged = iteration > 0
        for k in range(m):
            for i in range(3):
                # written so that a NaN does not converge (like np.max(...) < tol)
                if not abs(r[k, i] - previous[k, i]) < PICARD_TOL_M:
                    converged = False
                previous[k, i] = r[k, i]
        if converged:
            return True
        for k in range(m):
            _gravity(r[k], g)
            for i in range(3):
                a[k, i] = f_e[k, i] + g[i]
        for k in range(m - 1):
            _gravity(r_mid[k], g)
            for i in range(3):
                a_mid[k, i] = f_e_mid[k, i] + g[i]
    return False


@numba.njit(cache=True)
def integrate_kernel(t, f_b, w_b, r0, v0, q0, idx, weights, earth_q, earth_mid, position,
                     velocity, q):
    """The strapdown mechanisation over samples ``t`` (N,) from ``r0, v0, q0``: the
    specific force ``f_b`` and rate ``w_b`` (N, 3), the mid-step Lagrange samples ``idx``
    (N-1, p) and ``weights`` (N-1, p) and the Earth rotations since ``t[0]`` at the samples
    ``earth_q`` (N, 4) and mid-steps ``earth_mid`` (N-1, 4)
    (:func:`navlib.strapdown._clock`); writes ``position``, ``velocity`` (N, 3) and the
    attitude quaternions ``q`` (N, 4). Returns the first sample of a gravity window that
    did not converge, or -1."""
    n = t.shape[0]
    f_mid, w_mid = np.empty((n - 1, 3)), np.empty((n - 1, 3))
    for k in range(n - 1):
        for i in range(3):
            w_sum, f_sum = 0.0, 0.0
            for j in range(idx.shape[1]):
                w_sum += weights[k, j] * w_b[idx[k, j], i]
                f_sum += weights[k, j] * f_b[idx[k, j], i]
            w_mid[k, i], f_mid[k, i] = w_sum, f_sum
    body = np.empty((n, 4))
    for i in range(4):
        body[0, i] = 1.0 if i == 3 else 0.0
    dq_half = np.empty((n - 1, 4))
    phi, phi_half = np.empty(3), np.empty(3)
    for k in range(n - 1):
        _increments(w_b[k], w_mid[k], w_b[k + 1], t[k + 1] - t[k], phi, phi_half)
        _quat_from_rotvec(phi, body[k + 1])
        _quat_from_rotvec(phi_half, dq_half[k])
    _prefix_products(body[1:])
    tmp, tmp2 = np.empty(4), np.empty(4)
    f_e, f_e_mid = np.empty((n, 3)), np.empty((n - 1, 3))
    for k in range(n):
        _quat_mul(q0, body[k], tmp)
        _quat_mul(earth_q[k], tmp, q[k])
        _quat_rotate(q[k], f_b[k], f_e[k])
    for k in range(n - 1):
        _quat_mul(body[k], dq_half[k], tmp)
        _quat_mul(q0, tmp, tmp2)
        _quat_mul(earth_mid[k], tmp2, tmp)
        _quat_rotate(tmp, f_mid[k], f_e_mid[k])
    r_start, v_start = np.empty(3), np.empty(3)
    for i in range(3):
        position[0, i], velocity[0, i] = r0[i], v0[i]
    i0 = 0
    while i0 < n - 1:
        # the last sample within WINDOW_S of t[i0], at least the next one
        i1 = i0 + 1
        while i1 + 1 < n and t[i1 + 1] <= t[i0] + WINDOW_S:
            i1 += 1
        h = np.empty(i1 - i0)
        for k in range(i1 - i0):
            h[k] = t[i0 + k + 1] - t[i0 + k]
        for i in range(3):
            r_start[i], v_start[i] = position[i0, i], velocity[i0, i]
        if not _translation_window(h, r_start, v_start, f_e[i0:i1 + 1], f_e_mid[i0:i1],
                                   position[i0:i1 + 1], velocity[i0:i1 + 1]):
            return i0
        i0 = i1
    return -1


def compile_kernel() -> None:
    """Run :func:`integrate_kernel` once on a two-sample block (and the compiled
    :func:`navlib.quaternions.quat_from_matrix` the EKF calls at each window): compiles
    them on the first run on a machine, loads them from numba's disk cache afterwards
    (README "Compiled kernels")."""
    t = np.array([0.0, 0.01])
    zeros = np.zeros((2, 3))
    r0 = np.array([earth.A, 0.0, 0.0])
    integrate_kernel(t, zeros, zeros, r0, np.zeros(3), np.array([0.0, 0.0, 0.0, 1.0]),
                     np.zeros((1, 2), dtype=np.int64), np.full((1, 2), 0.5),
                     np.tile([0.0, 0.0, 0.0, 1.0], (2, 1)), np.array([[0.0, 0.0, 0.0, 1.0]]),
                     np.empty((2, 3)), np.empty((2, 3)), np.empty((2, 4)))
    quat_from_matrix(np.eye(3))


drop_stale_kernel_caches(__name__, globals())  # numba checks only this file (numba #1833)
