"""The 21-state ECEF model's Jacobians along the EKF's windows as one compiled kernel
(docs/assumptions.md "Compiled kernels").

:func:`ecef21_jacobians_kernel` writes what :func:`navlib.models.ecef.ecef21_jacobians` returns
(docs/assumptions.md A4-A7; the gravity Jacobian of :func:`navlib.earth.gravity_jacobian_ecef`,
A5) into buffers the EKF reuses over its windows: the NumPy function builds about thirty
(N, 21, 21) temporaries a window, which made it a sixth of the EKF's time per sample
(issue 37). Every entry is the same formula, so the two agree to rounding
(``tests/test_sparse_discretize.py``). Element loops only (no array expressions), which
keeps the first compile short.
"""

from __future__ import annotations

import math

import numba

from navlib import earth
from navlib.cache import drop_stale_kernel_caches

_GM = earth.GM
_J2_K = 1.5 * earth.J2 * earth.GM * earth.A**2
_OMEGA = earth.OMEGA_E


@numba.njit(cache=True)
def ecef21_jacobians_kernel(position, C_b_e, f_b, w_ib_b, body, A, G):
    """``A[k]`` (21, 21) and ``G[k]`` (21, 18) of every sample ``k`` of ``position`` (K, 3),
    ``C_b_e`` (K, 3, 3), ``f_b``, ``w_ib_b`` (K, 3), for the body attitude error when
    ``body`` else the ECEF one (:func:`navlib.models.ecef.ecef21_jacobians`); every entry
    of ``A[:K]``, ``G[:K]`` is written."""
    for k in range(position.shape[0]):
        a, g = A[k], G[k]
        for i in range(21):
            for j in range(21):
                a[i, j] = 0.0
            for j in range(18):
                g[i, j] = 0.0
        C, f, w = C_b_e[k], f_b[k], w_ib_b[k]
        x, y, z = position[k, 0], position[k, 1], position[k, 2]
        r2 = x * x + y * y + z * z
        r = math.sqrt(r2)
        s = z * z / r2
        r3, r5, r7 = r**3, r**5, r**7
        for i in range(3):
            a[i, 3 + i] = 1.0
            ri = position[k, i]
            coef = 3.0 if i == 2 else 1.0
            h = (coef - 5.0 * s) / r5
            for j in range(3):
                rj = position[k, j]
                eye = 1.0 if i == j else 0.0
                central = -_GM * (eye / r3 - 3.0 * ri * rj / r5)
                ds = -2.0 * s * rj / r2 + (2.0 * z / r2 if j == 2 else 0.0)
                dh = (coef - 5.0 * s) * (-5.0 * rj / r7) + (-5.0 * ds / r5)
                centrifugal = _OMEGA**2 if i == j and i < 2 else 0.0
                a[3 + i, j] = central + -_J2_K * (eye * h + ri * dh) + centrifugal
            for j in range(3):
                a[3 + i, 12 + j] = -C[i, j]
                a[3 + i, 18 + j] = -C[i, j] * f[j]
                g[3 + i, j] = C[i, j]
        # -2 S(Omega) and -S(Omega) with Omega = (0, 0, OMEGA)
        a[3, 4], a[4, 3] = 2.0 * _OMEGA, -2.0 * _OMEGA
        if body:
            # -C S(f), -S(w), -I, -diag(w), I
            a[6, 7], a[6, 8] = w[2], -w[1]
            a[7, 6], a[7, 8] = -w[2], w[0]
            a[8, 6], a[8, 7] = w[1], -w[0]
            for i in range(3):
                a[3 + i, 6] = -(C[i, 1] * f[2] - C[i, 2] * f[1])
                a[3 + i, 7] = -(C[i, 2] * f[0] - C[i, 0] * f[2])
                a[3 + i, 8] = -(C[i, 0] * f[1] - C[i, 1] * f[0])
                a[6 + i, 9 + i] = -1.0
                a[6 + i, 15 + i] = -w[i]
                g[6 + i, 3 + i] = 1.0
        else:
            # -S(C f), -S(Omega), -C, -C diag(w), C
            fe0 = C[0, 0] * f[0] + C[0, 1] * f[1] + C[0, 2] * f[2]
            fe1 = C[1, 0] * f[0] + C[1, 1] * f[1] + C[1, 2] * f[2]
            fe2 = C[2, 0] * f[0] + C[2, 1] * f[1] + C[2, 2] * f[2]
            a[3, 7], a[3, 8] = fe2, -fe1
            a[4, 6], a[4, 8] = -fe2, fe0
            a[5, 6], a[5, 7] = fe1, -fe0
            a[6, 7], a[7, 6] = _OMEGA, -_OMEGA
            for i in range(3):
                for j in range(3):
                    a[6 + i, 9 + j] = -C[i, j]
                    a[6 + i, 15 + j] = -C[i, j] * w[j]
                    g[6 + i, 3 + j] = C[i, j]
        for i in range(12):
            g[9 + i, 6 + i] = 1.0


drop_stale_kernel_caches(__name__, globals())  # numba checks only this file (numba #1833)
