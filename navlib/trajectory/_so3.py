"""Cumulative B-splines on SO(3): a smooth attitude with no singular attitude (private).

The attitude is written on the rotation group itself, never through three angles, so a
vertical ascent, a loop, a tumble or a swinging, spinning descent under a parachute all
have the same regular form (docs/assumptions.md, "fit — attitude spline on SO(3)").
With control rotations ``C_0 .. C_{m-1}`` and the B-spline basis ``B_l`` of degree ``k``
on a clamped knot vector, the cumulative basis ``lambda_i(t) = sum_{l >= i} B_l(t)`` gives

``C(t) = C_0 prod_{i=1}^{m-1} exp(S(lambda_i(t) d_i)),   d_i = log(C_{i-1}^T C_i)``

(Kim, Kim & Shin 1995; the form of continuous-time visual-inertial calibration tools).
In the knot interval whose first active basis function is ``s`` only ``k`` factors differ
from the identity or a whole increment: ``C(t) = C_s prod_{j=1}^{k} A_j`` with
``A_j = exp(S(lambda_{s+j}(t) d_{s+j}))``. The body rate (``dC/dt = C S(omega)``) and the
angular acceleration follow in closed form from the recursion

``omega_j = A_j^T omega_{j-1} + lambda'_j d_j``,
``alpha_j = A_j^T alpha_{j-1} + (A_j^T omega_{j-1}) x (lambda'_j d_j) + lambda''_j d_j``

with ``omega_0 = alpha_0 = 0``; no finite differences. A rotation at a constant rate about
a fixed axis is represented exactly (the cumulative basis reproduces linear functions), so
any amount of spin costs nothing; the increments ``d_i`` must stay below pi, which the
caller's knots ensure
(:func:`navlib.trajectory.position_spline.place_knots` with a turn budget).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.interpolate import BSpline
from scipy.linalg import cho_solve_banded, cholesky_banded
from scipy.spatial.transform import Rotation, Slerp
from threadpoolctl import threadpool_limits

from navlib.quaternions import quat_from_rotvec, quat_mul, quat_rotate

_STEP = 1e-6
"""Rotation (rad) of the finite-difference Jacobian of the fit (its fixed point is exact:
only the residuals decide where Gauss-Newton stops)."""
_ONE_THREAD = 1
"""BLAS threads of the banded Cholesky factorisation: with bandwidth 17 OpenBLAS's blocked
code starts threads that only synchronise, and on the loaded 2-core machine one
factorisation of a 4-minute record took 0.4-6 s instead of a few milliseconds."""


def basis(x, knots, k, nu):
    """Sparse (N, m) matrix of the ``nu``-th derivatives of the degree-``k`` B-spline basis.

    Derivatives come from the lower-degree basis through the standard recursion
    ``B'_{i,d} = d B_{i,d-1}/(t_{i+d}-t_i) - d B_{i+1,d-1}/(t_{i+d+1}-t_{i+1})``.
    """
    x = np.minimum(x, np.nextafter(knots[-1], -np.inf))  # the last interval is half-open
    out = BSpline.design_matrix(x, knots, k - nu)
    for d in range(k - nu + 1, k + 1):
        m = knots.size - d - 1
        i = np.arange(m)
        den0, den1 = knots[i + d] - knots[i], knots[i + d + 1] - knots[i + 1]
        a = np.where(den0 > 0, d / np.where(den0 > 0, den0, 1.0), 0.0)
        b = np.where(den1 > 0, -d / np.where(den1 > 0, den1, 1.0), 0.0)
        M = sp.csr_array((np.r_[a, b], (np.r_[i, i + 1], np.r_[i, i])), shape=(m + 1, m))
        out = out @ M
    return sp.csr_array(out)


def _local(x, knots, k, order):
    """First active function ``s`` (N,) and the cumulative basis ``lambda_{s+j}`` with its
    derivatives up to ``order``, each (N, k) for j = 1..k."""
    x = np.minimum(x, np.nextafter(knots[-1], -np.inf))
    design = BSpline.design_matrix(x, knots, k)
    s = design.indices[::k + 1].copy()
    out = []
    for nu in range(order + 1):
        B = basis(x, knots, k, nu).tocsr()
        rows = np.repeat(np.arange(x.size), np.diff(B.indptr))
        local = np.zeros((x.size, k + 1))
        pos = B.indices - s[rows]
        inside = (pos >= 0) & (pos <= k)
        local[rows[inside], pos[inside]] = B.data[inside]
        # lambda_{s+j} = sum_{l >= j} B_{s+l}, j = 1..k (lambda_s = 1 has no derivative)
        out.append(np.cumsum(local[:, :0:-1], axis=1)[:, ::-1])
    return s, out


def _qlog(q):
    """Rotation vectors of unit quaternions (..., 4), scalar last (angle in [0, pi])."""
    q = np.where(q[..., 3:] < 0.0, -q, q)
    v = q[..., :3]
    n = np.linalg.norm(v, axis=-1)
    big = n > 1e-12
    scale = np.where(big, 2.0 * np.arctan2(n, q[..., 3]) / np.where(big, n, 1.0),
                     2.0 / q[..., 3])
    return scale[..., None] * v


def _qconj(q):
    return q * np.array([-1.0, -1.0, -1.0, 1.0])


class SO3Spline:
    """Cumulative B-spline ``C(t)`` on SO(3) of degree ``k`` (module docstring).

    Parameters
    ----------
    knots : ndarray
        Clamped knot vector (end knots repeated ``k + 1`` times).
    k : int
        Degree (5: body rate C^3, angular acceleration C^2).
    control : ndarray (m, 4)
        Control rotations as unit quaternions (scalar last, scipy's order),
        ``m = knots.size - k - 1``.
    """

    def __init__(self, knots, k, control):
        self.knots = np.asarray(knots, dtype=float)
        self.k = int(k)
        self.control = np.asarray(control, dtype=float)

    def increments(self, control=None):
        """``d_i = log(C_{i-1}^T C_i)`` (m, 3), ``d_0 = 0``."""
        c = self.control if control is None else control
        d = np.zeros((c.shape[0], 3))
        d[1:] = _qlog(quat_mul(_qconj(c[:-1]), c[1:]))
        return d

    def _chain(self, s, lam, control, dlam=None, d2lam=None):
        d = self.increments(control)
        q = control[s]
        w = np.zeros((s.size, 3)) if dlam is not None else None
        alpha = np.zeros((s.size, 3)) if d2lam is not None else None
        for j in range(self.k):
            dj = d[s + j + 1]
            A = quat_from_rotvec(lam[:, j, None] * dj)
            q = quat_mul(q, A)
            if w is None:
                continue
            At = _qconj(A)
            rate = dlam[:, j, None] * dj
            w_turned = quat_rotate(At, w)
            if alpha is not None:
                alpha = (quat_rotate(At, alpha) + np.cross(w_turned, rate)
                         + d2lam[:, j, None] * dj)
            w = w_turned + rate
        return q / np.linalg.norm(q, axis=1, keepdims=True), w, alpha

    def evaluate(self, t, order=1):
        """Attitude (N, 3, 3) and, for ``order`` >= 1, the body rate ``omega`` (N, 3) with
        ``dC/dt = C S(omega)``; for ``order`` = 2 also the angular acceleration (N, 3)."""
        s, lams = _local(np.asarray(t, dtype=float), self.knots, self.k, order)
        q, w, alpha = self._chain(s, lams[0], self.control, *lams[1:])
        C = Rotation.from_quat(q).as_matrix()
        return (C, *(v for v in (w, alpha) if v is not None))

    @classmethod
    def fit(cls, t, attitude, knots, k, iterations=3):
        """Least-squares spline through attitude samples (Gauss-Newton on SO(3)).

        Minimises ``sum_n |log(C(t_n)^T C_n)|^2`` over the control rotations (right
        perturbations ``C_i exp(S(delta_i))``). Start: the samples interpolated at the
        Greville abscissae (exact for a constant-rate rotation about a fixed axis). The
        Jacobian, by finite differences with the control points coloured modulo ``k + 1``
        (each sample sees ``k + 1`` consecutive ones, so ``3 (k + 1)`` spline evaluations
        give all of it), is formed once; its banded normal matrix serves every step.

        Parameters
        ----------
        t : ndarray (N,)
            Sample times inside ``[knots[0], knots[-1]]``.
        attitude : scipy Rotation of length N
            The samples ``C_n``.
        knots : ndarray
            Clamped knot vector; every knot interval must hold samples.
        k : int
            Degree.
        iterations : int
            Gauss-Newton steps.
        """
        t = np.asarray(t, dtype=float)
        m = knots.size - k - 1
        greville = np.convolve(knots[1:-1], np.ones(k) / k, mode="valid")[:m]
        control = Slerp(t, attitude)(np.clip(greville, t[0], t[-1])).as_quat()
        spline = cls(knots, k, control)
        s, (lam,) = _local(t, knots, k, 0)
        q_n = attitude.as_quat()

        def residual(ctrl):
            q, _, _ = spline._chain(s, lam, ctrl)
            return _qlog(quat_mul(_qconj(q), q_n))

        r = residual(control)
        width = 3 * (k + 1)
        J = np.empty((t.size, 3, width))
        colour = np.arange(m) % (k + 1)
        offset = (np.arange(k + 1)[:, None] - s[None, :]) % (k + 1)   # (colour, sample)
        rows = np.arange(t.size)
        for c in range(k + 1):
            chosen = colour == c
            for a in range(3):
                step = np.zeros(3)
                step[a] = _STEP
                ctrl = control.copy()
                ctrl[chosen] = quat_mul(ctrl[chosen], quat_from_rotvec(step))
                J[rows, :, 3 * offset[c] + a] = (residual(ctrl) - r) / _STEP
        with threadpool_limits(_ONE_THREAD):
            factor = cholesky_banded(_banded_normal(J, s, 3 * m))
        for _ in range(iterations):
            g = _gradient(J, r, s, 3 * m)
            delta = -cho_solve_banded((factor, False), g).reshape(m, 3)
            control = quat_mul(control, quat_from_rotvec(delta))
            r = residual(control)
            if np.abs(delta).max() < 1e-12:
                break
        spline.control = control
        return spline


def _groups(s):
    """Start index of each run of equal ``s`` (samples are sorted in time) and its value."""
    first = np.flatnonzero(np.r_[True, s[1:] != s[:-1]])
    return first, s[first]


def _banded_normal(J, s, n):
    """Upper banded storage of ``J^T J`` for per-sample Jacobian blocks ``J`` (N, 3, w)
    whose columns start at ``3 s``."""
    w = J.shape[2]
    first, s_u = _groups(s)
    # each knot interval's rows stacked (zero-padded) into one matrix: one product per
    # interval instead of one per sample
    count = np.diff(np.r_[first, s.size])
    stacked = np.zeros((first.size, count.max(), 3, w))
    row = np.arange(s.size) - np.repeat(first, count)
    stacked[np.repeat(np.arange(first.size), count), row] = J
    stacked = stacked.reshape(first.size, -1, w)
    blocks = np.swapaxes(stacked, 1, 2) @ stacked
    ab = np.zeros((w, n))
    start = 3 * s_u
    for p in range(w):
        for q in range(p, w):
            ab[w - 1 + p - q, start + q] += blocks[:, p, q]
    # a relative ridge keeps a control point that only one sample sees definite
    ab[-1] += 1e-12 * ab[-1].max()
    return ab


def _gradient(J, r, s, n):
    """``J^T r`` (n,) for per-sample blocks."""
    first, s_u = _groups(s)
    local = np.add.reduceat(np.einsum("nri,nr->ni", J, r), first, axis=0)
    g = np.zeros(n)
    for i in range(J.shape[2]):
        g[3 * s_u + i] += local[:, i]
    return g
