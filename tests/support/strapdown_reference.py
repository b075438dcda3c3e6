"""NumPy reference of the compiled strapdown kernel
(:func:`navlib.strapdown._kernel.integrate_kernel`): the vectorised mechanisation
:func:`navlib.strapdown.integrate` ran before the kernel, kept here (not in the library) to
compare against (tests/strapdown/test_strapdown_kernel.py) and to time against
(benchmarks/bench_kernels.py).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from navlib import earth
from navlib.errors import NavlibInputError
from navlib.quaternions import quat_from_rotvec, quat_mul, quat_rotate
from navlib.strapdown import (
    StrapdownResult,
    _attitude_increments,
    _body_products,
    _clock,
    _interpolate,
    _Steps,
    _translation,
)

WINDOW_S = 10.0
"""Length of the windows in which the translational recursion is solved by fixed-point
iteration on gravity; the contraction factor is about ``|Gamma| T^2 / 2`` (1.5e-4 at the
surface for 10 s)."""
PICARD_TOL_M = 1e-8
PICARD_MAX_ITER = 30


def _translation_window(h, r0, v0, f_e, f_e_mid):
    """Translation over one window with gravity at the solution's own positions.

    Fixed-point (Picard) iteration: start from gravity frozen at ``r0``, integrate with
    :func:`_translation`, re-evaluate gravity at the resulting sample and mid-step
    positions, and repeat until the positions change by less than 1e-8 m.
    """
    g = np.broadcast_to(earth.normal_gravity_ecef(r0), f_e.shape)
    g_mid = g[:-1]
    steps = _Steps.of(h)
    previous = None
    for _ in range(PICARD_MAX_ITER):
        r, v, r_mid = _translation(h, r0, v0, f_e + g, f_e_mid + g_mid, steps)
        if previous is not None and np.max(np.abs(r - previous)) < PICARD_TOL_M:
            return r, v
        previous = r
        g_all = earth.normal_gravity_ecef(np.concatenate([r, r_mid]))   # row by row
        g, g_mid = g_all[:r.shape[0]], g_all[r.shape[0]:]
    raise NavlibInputError(
        f"t: the gravity iteration did not converge within {PICARD_MAX_ITER} passes over "
        f"{h.sum():.3g} s; sample steps this long ({h.max():.3g} s) are not supported"
    )


def integrate(t, f_b, w_ib_b, r, v, q0, clock=None) -> StrapdownResult:
    """:func:`integrate` on checked inputs (``q0`` the initial attitude quaternion): for
    loops that propagate many short blocks from states they computed themselves (the
    EKF's windows, :func:`navlib.filters.ekf`, with their :func:`block_clocks`)."""
    n = t.size
    h = np.diff(t)
    lagrange, earth, earth_mid = _clock(t) if clock is None else clock
    w_mid = _interpolate(t, w_ib_b, 0.5, lagrange)
    f_mid = _interpolate(t, f_b, 0.5, lagrange)
    phi, phi_half = _attitude_increments(w_ib_b[:-1], w_mid, w_ib_b[1:], h)

    # C_k = E(t_k - t_0) C_0 B_k with B_k the running product of body increments; the
    # samples (n) and mid-steps (n - 1) rotated together
    dq = quat_from_rotvec(np.concatenate([phi, phi_half]))
    body = _body_products(dq[:n - 1])
    half = quat_mul(body[:-1], dq[n - 1:])
    both = quat_mul(np.concatenate([earth, earth_mid]),
                     quat_mul(q0, np.concatenate([body, half])))
    f_e_both = quat_rotate(both, np.concatenate([f_b, f_mid]))
    q, f_e, f_e_mid = both[:n], f_e_both[:n], f_e_both[n:]

    position = np.empty((n, 3))
    velocity = np.empty((n, 3))
    position[0], velocity[0] = r, v
    i0 = 0
    while i0 < n - 1:
        i1 = max(int(np.searchsorted(t, t[i0] + WINDOW_S, side="right")) - 1, i0 + 1)
        position[i0:i1 + 1], velocity[i0:i1 + 1] = _translation_window(
            h[i0:i1], position[i0], velocity[i0], f_e[i0:i1 + 1], f_e_mid[i0:i1])
        i0 = i1
    return StrapdownResult(t=t, position=position, velocity=velocity,
                           attitude=Rotation.from_quat(q))
