"""Kalman-filter algebra shared by the linear simulator, the EKF and
:func:`navlib.covariance.kalman_covariance`: gains with the pseudo-inverse rule and the
Joseph-form update here; :func:`symmetrize` and the square roots in
:mod:`navlib.kalman.algebra`, the NEES/NIS consistency statistics in
:mod:`navlib.kalman.consistency` (docs/assumptions.md, launcher.md §6.2-6.4), the EKF's
sparse prediction in :mod:`navlib.kalman.sparse`, all importable from here. Below both
``navlib.covariance`` and ``navlib.filters``, which import it.

The per-step algebra runs as compiled numba kernels (docs/assumptions.md
"Compiled kernels"), one per algorithm and used by every caller: :func:`_gain_kernel` and
:func:`_joseph_kernel` (one epoch), :func:`predict_kernel`, :func:`riccati_kernel` (the
covariance recursion of :func:`covariance_recursion`), :func:`propagate_kernel`
(the EKF between updates, with the sparse prediction :func:`predict_sparse`) and
:func:`update_kernel` (the EKF's updates, inlined), both called by
:func:`fixed_updates_kernel` (the EKF's runs of updates with one design, and its
propagation to a window's end).
:func:`kalman_gain` and :func:`joseph_update` keep their NumPy interface (one epoch or a
batch) around them; :func:`compile_kernels` compiles or loads
them all. The NumPy code they replaced is kept in ``tests/support/kalman_reference.py``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from navlib.cache import drop_stale_kernel_caches
from navlib.kalman.algebra import definite_noise, psd_sqrt, symmetrize
from navlib.kalman.consistency import chi2_bounds, nees_basis, nees_values
from navlib.kalman.sparse import predict_sparse
from navlib.kernel_copy import copy_matrix, copy_vector

__all__ = ["PINV_RTOL", "FactoredNoise", "Gains", "chi2_bounds", "compile_kernels",
           "covariance_recursion", "definite_noise", "fixed_updates_kernel", "joseph_update",
           "kalman_gain", "kalman_gains", "kernel_array", "nees_basis", "nees_values",
           "predict_kernel", "propagate_kernel", "psd_sqrt", "riccati_kernel", "symmetrize",
           "update_kernel"]

PINV_RTOL = 1e-12
"""Relative cut-off of the innovation-covariance pseudo-inverse; the value
:func:`navlib.covariance.kalman_covariance` uses by default, so that the gains here
reproduce its posterior covariances."""


@dataclass(frozen=True, eq=False)
class Gains:
    """Kalman gains and innovation-covariance pseudo-inverses (one epoch or a batch)."""

    K: np.ndarray          # (..., n, m)
    S_pinv: np.ndarray     # (..., m, m)
    dof: np.ndarray        # (...,) rank of S used (0 at epochs without update)


def kalman_gain(P_prior, H, R, *, pinv_rtol: float = PINV_RTOL, definite=None) -> Gains:
    """Gain ``K = P- H' S^+`` with ``S = H P- H' + R``, for one epoch or a batch.

    ``S^+`` is the inverse when ``R`` is positive definite (:func:`definite_noise`) and the
    eigen-decomposition pseudo-inverse otherwise (eigenvalues below ``pinv_rtol * max``
    dropped), which gives the optimal update in the measured subspace and no update in the
    directions with ``S = 0`` (ideal measurements, ``R = 0``). The one implementation of
    this rule (the compiled :func:`_gain_kernel`): :func:`joseph_update`,
    :func:`kalman_gains`, the EKF (:func:`navlib.filters.ekf`) and
    :func:`navlib.covariance.kalman_covariance` use it.

    Parameters
    ----------
    P_prior : ndarray (..., n, n)
    H : ndarray (..., m, n)
    R : ndarray (..., m, m)
    pinv_rtol : float
    definite : bool or ndarray (...,) of bool, optional
        :func:`definite_noise` of ``R`` when already known (computed otherwise).
    """
    P, H, R, definite, batch = _batched(P_prior, H, R, definite)
    K, S_pinv, dof = _each(P, H, R, definite, float(pinv_rtol), False)[1:]
    n, m = P.shape[-1], H.shape[-2]
    return Gains(K.reshape(*batch, n, m), S_pinv.reshape(*batch, m, m), _shaped(dof, batch))


def _batched(P_prior, H, R, definite):
    """``P- , H, R`` broadcast to one batch and flattened to (B, ., .) C-contiguous stacks,
    the definiteness of each ``R`` (B,) and the batch shape."""
    P_prior = np.asarray(P_prior, dtype=float)
    H = np.asarray(H, dtype=float)
    R = np.asarray(R, dtype=float)
    batch = np.broadcast_shapes(P_prior.shape[:-2], H.shape[:-2], R.shape[:-2])
    n, m = P_prior.shape[-1], H.shape[-2]
    definite = np.broadcast_to(definite_noise(R) if definite is None else definite, batch)

    size = int(np.prod(batch))

    def flat(a, shape):
        return kernel_array(np.broadcast_to(a, (*batch, *shape)).reshape(size, *shape))

    return (flat(P_prior, (n, n)), flat(H, (m, n)), flat(R, (m, m)),
            kernel_array(definite.reshape(size), np.bool_), batch)


def kernel_array(a, dtype=float) -> np.ndarray:
    """``a`` as a C-contiguous, writable array of ``dtype``: the one array type the kernels
    are compiled for (a read-only or strided input would compile, and cache, another
    specialisation of each kernel it reaches). Copies only when ``a`` is not one already.

    Parameters
    ----------
    a : array_like
    dtype : numpy.dtype, optional
    """
    a = np.ascontiguousarray(a, dtype=dtype)
    return a if a.flags.writeable else a.copy()


def _shaped(dof, batch):
    """The per-member dof (B,) in the batch shape (a NumPy integer for one epoch)."""
    return dof.reshape(batch) if batch else dof[0]


@numba.njit(cache=True)
def _gain_kernel(P, H, R, definite, pinv_rtol, K, S_pinv):
    """Compiled :func:`kalman_gain` of one epoch into ``K`` (n, m) and ``S_pinv`` (m, m);
    returns the rank of ``S`` used (the dof).

    ``S = sym(H P H' + R)``; ``S^-1`` when ``definite`` (:func:`_inverse`), else (or when
    ``S`` is singular in floating point) ``V diag(1/w) V'`` over the eigenvalues
    ``w > pinv_rtol max(w)`` of ``S`` (docs/assumptions.md, launcher.md §6.2)."""
    m = H.shape[0]
    PHt = np.dot(P, H.T)
    S = np.empty((m, m))
    _sym_sum(np.dot(H, PHt), R, S)
    if m == 0:
        copy_matrix(PHt, K)
        copy_matrix(S, S_pinv)
        return 0
    if definite and _inverse(S, S_pinv):
        dof = m
    else:
        w, V = np.linalg.eigh(S)
        cut = pinv_rtol * max(w[m - 1], 0.0)
        scaled = np.zeros_like(V)
        dof = 0
        for j in range(m):
            if w[j] > cut:
                inv_w = 1.0 / w[j]
                for i in range(m):
                    scaled[i, j] = V[i, j] * inv_w
                dof += 1
        copy_matrix(np.dot(scaled, V.T), S_pinv)
    copy_matrix(np.dot(PHt, S_pinv), K)
    return dof


@numba.njit(cache=True)
def _sym_sum(A, B, out):
    """``out = sym(A + B)``, i.e. ``M = A + B; (M + M') / 2`` entry by entry (the operations
    of :func:`symmetrize`); ``out`` must be neither ``A`` nor ``B``."""
    for i in range(out.shape[0]):
        for j in range(out.shape[1]):
            out[i, j] = 0.5 * ((A[i, j] + B[i, j]) + (A[j, i] + B[j, i]))


@numba.njit(cache=True)
def _inverse(S, out):
    """``out = S^-1`` by LU decomposition with partial pivoting and two triangular solves
    against the identity: the algorithm of LAPACK ``gesv`` that :func:`numpy.linalg.inv`
    calls, written out (numba's own ``solve`` takes seconds more to compile). ``S`` is the
    innovation covariance of a positive-definite ``R``; returns False (``out`` unset) when a
    pivot is nevertheless zero (``S`` singular in floating point, e.g. ``H P H'`` so large
    that ``R`` is lost in rounding), and the caller takes the pseudo-inverse."""
    m = S.shape[0]
    LU = S.copy()
    perm = np.empty(m, dtype=np.int64)
    for k in range(m):
        perm[k] = k
    for k in range(m):
        p = k                                  # first row of largest |LU[i, k]|, i >= k
        for i in range(k + 1, m):
            if abs(LU[i, k]) > abs(LU[p, k]):
                p = i
        if LU[p, k] == 0.0:
            return False
        if p != k:
            for j in range(m):
                LU[k, j], LU[p, j] = LU[p, j], LU[k, j]
            perm[k], perm[p] = perm[p], perm[k]
        for i in range(k + 1, m):
            LU[i, k] /= LU[k, k]
            for j in range(k + 1, m):
                LU[i, j] -= LU[i, k] * LU[k, j]
    out[:, :] = 0.0
    for i in range(m):
        out[i, perm[i]] = 1.0
    for i in range(m):                         # L y = P I (unit lower triangle)
        for k in range(i):
            for j in range(m):
                out[i, j] -= LU[i, k] * out[k, j]
    for i in range(m - 1, -1, -1):             # U x = y
        for k in range(i + 1, m):
            for j in range(m):
                out[i, j] -= LU[i, k] * out[k, j]
        for j in range(m):
            out[i, j] /= LU[i, i]
    return True


@numba.njit(cache=True)
def _joseph_kernel(P, H, R, definite, pinv_rtol, P_post, K, S_pinv):
    """Compiled :func:`joseph_update` of one epoch: ``P_post = sym((I - K H) P (I - K H)'
    + K R K')`` with the gain of :func:`_gain_kernel` (written to ``K``, ``S_pinv``);
    returns the dof. ``P_post`` may be ``P`` itself."""
    dof = _gain_kernel(P, H, R, definite, pinv_rtol, K, S_pinv)
    IKH = np.dot(K, H)
    n = IKH.shape[0]
    for i in range(n):
        for j in range(n):
            IKH[i, j] = (1.0 if i == j else 0.0) - IKH[i, j]
    _sym_sum(np.dot(np.dot(IKH, P), IKH.T), np.dot(np.dot(K, R), K.T), P_post)
    return dof


@numba.njit(cache=True, inline="always")
def update_kernel(x, P, z, H, R, definite, pinv_rtol, P_post, K, S_pinv):
    """The EKF's measurement update (:mod:`navlib.filters.ekf`): innovation ``z - H x``,
    :func:`_joseph_kernel` into ``P_post``, ``K``, ``S_pinv``, the corrected mean
    ``x + K innovation`` and the NIS ``innovation' S^+ innovation``; returns
    ``(x_post, innovation, nis, dof)``. Inlined into :func:`fixed_updates_kernel`, the
    EKF's one entry point (compiled there once, not a second time on its own).

    Parameters
    ----------
    x, P, z, H, R : numpy.ndarray
        Prior mean (n,) and covariance (n, n), measurement (m,), its matrix (m, n) and noise
        covariance (m, m).
    definite : bool
        Whether ``R`` is positive definite (else the pseudo-inverse update).
    pinv_rtol : float
        Relative tolerance of the pseudo-inverse of ``S``.
    P_post, K, S_pinv : numpy.ndarray
        Outputs (n, n), (n, m), (m, m), written in place.
    """
    innov = z - np.dot(H, x)
    dof = _joseph_kernel(P, H, R, definite, pinv_rtol, P_post, K, S_pinv)
    return x + np.dot(K, innov), innov, np.dot(np.dot(innov, S_pinv), innov), dof


def _each(P, H, R, definite, pinv_rtol: float, update: bool):
    """:func:`_gain_kernel` (and with ``update`` :func:`_joseph_kernel`) over a batch
    (B, ., .); returns ``(P_post, K, S_pinv, dof)`` (``P_post`` empty without ``update``)."""
    batch, n, m = P.shape[0], P.shape[1], H.shape[1]
    P_post = np.empty((batch if update else 0, n, n))
    K, S_pinv = np.empty((batch, n, m)), np.empty((batch, m, m))
    dof = np.empty(batch, dtype=np.int64)
    for b in range(batch):
        if update:
            dof[b] = _joseph_kernel(P[b], H[b], R[b], bool(definite[b]), pinv_rtol, P_post[b],
                                    K[b], S_pinv[b])
        else:
            dof[b] = _gain_kernel(P[b], H[b], R[b], bool(definite[b]), pinv_rtol, K[b],
                                  S_pinv[b])
    return P_post, K, S_pinv, dof


def joseph_update(P_prior, H, R, *, pinv_rtol: float = PINV_RTOL, definite=None):
    """Joseph-form measurement update ``P+ = (I - K H) P- (I - K H)' + K R K'`` with the
    gain of :func:`kalman_gain` (one epoch or a batch).

    The Joseph form holds for any gain, so ``P+`` stays symmetric positive semi-definite
    with a singular or zero ``R`` (docs/assumptions.md, launcher.md §6.2). Compiled
    (:func:`_joseph_kernel`, docs/assumptions.md "Compiled kernels").

    Parameters
    ----------
    P_prior, H, R, pinv_rtol, definite
        As in :func:`kalman_gain`.

    Returns
    -------
    P_post : ndarray (..., n, n)
    gains : Gains
    """
    P, H, R, definite, batch = _batched(P_prior, H, R, definite)
    P_post, K, S_pinv, dof = _each(P, H, R, definite, float(pinv_rtol), True)
    n, m = P.shape[-1], H.shape[-2]
    return P_post.reshape(*batch, n, n), Gains(K.reshape(*batch, n, m),
                                               S_pinv.reshape(*batch, m, m),
                                               _shaped(dof, batch))


@numba.njit(cache=True)
def predict_kernel(P, F, Q, out):
    """Covariance prediction ``out = sym(F P F' + Q)`` of one matrix (compiled; ``out``
    may be ``P``, not ``Q``).

    Parameters
    ----------
    P, F, Q, out : numpy.ndarray
        Covariance, transition, process noise and output, each (n, n).
    """
    _sym_sum(np.dot(np.dot(F, P), F.T), Q, out)


@numba.njit(cache=True)
def riccati_kernel(P, F, Q, H, R, definite, update, pinv_rtol, a, P_prior, slot, P_post,
                   K, S_pinv, dof):
    """The Kalman covariance recursion of one member over the epochs ``a .. a + len(update)``
    from ``P`` (the posterior at epoch ``a - 1``, or the initial covariance when ``a`` is 0):
    prediction with ``F[i], Q[i]`` into epoch ``a + i`` (``i >= 1``, or ``i >= 0`` when
    ``a > 0``: ``F``/``Q`` start at the step into epoch ``a``), Joseph update where
    ``update[i]`` (``H[i]``, ``R[i]``, ``definite[i]``). Writes the priors to ``P_prior[i]``
    (when it has rows), the posteriors to ``P_post[slot[i]]`` where ``slot[i] >= 0`` and the
    gains to ``K[i], S_pinv[i], dof[i]`` (when ``K`` has rows). Returns the last posterior.

    The recursion of :func:`covariance_recursion` (docs/assumptions.md, launcher.md §6.2), compiled
    (docs/assumptions.md "Compiled kernels").

    Parameters
    ----------
    P, F, Q, H, R : numpy.ndarray
        Starting covariance (n, n), the model per step (``F``, ``Q``) and per epoch.
    definite, update : numpy.ndarray
        Per epoch: ``R`` positive definite; an update.
    pinv_rtol : float
        Relative tolerance of the pseudo-inverse of ``S``.
    a : int
        First epoch.
    P_prior, slot, P_post, K, S_pinv, dof : numpy.ndarray
        Outputs written in place (``slot``: row of ``P_post`` per epoch, -1 not kept).
    """
    n = P.shape[0]
    m = H.shape[1]
    cur, nxt = P.copy(), np.empty((n, n))
    K_k, S_k = np.empty((n, m)), np.empty((m, m))
    for i in range(update.size):
        if a + i:
            s = i - 1 if a == 0 else i
            predict_kernel(cur, F[s], Q[s], nxt)
            cur, nxt = nxt, cur
        if P_prior.shape[0]:
            copy_matrix(cur, P_prior[i])
        if update[i]:
            d = _joseph_kernel(cur, H[i], R[i], definite[i], pinv_rtol, nxt, K_k, S_k)
            cur, nxt = nxt, cur
            if K.shape[0]:
                copy_matrix(K_k, K[i])
                copy_matrix(S_k, S_pinv[i])
                dof[i] = d
        if slot[i] >= 0:
            copy_matrix(cur, P_post[slot[i]])
    return cur


@numba.njit(cache=True)
def propagate_kernel(x, P, F, Q, kept, j0, j1):
    """The EKF's propagation (:mod:`navlib.filters.ekf`): error-state mean and covariance
    from sample ``j0`` to ``j1`` of a window (``F[j]``,
    ``Q[j]`` the step from sample j to j+1): ``x <- F x`` and ``P <- sym(F P F' + Q)``
    (:func:`predict_sparse`), compiled (docs/assumptions.md
    "Compiled kernels").

    The closed loop drives the ``kept`` (RT) states with the error of the corrected
    navigation, ``x[reset] - x_hat[reset]``: no mean drive from the not-yet-fed-back
    estimate of the reset states, so their rows take the ``kept`` columns only.
    Returns new arrays (the inputs are not written). A kernel of its own called by
    :func:`fixed_updates_kernel` (inlined twice there, its loops doubled the first
    compile).

    Parameters
    ----------
    x, P, F, Q : numpy.ndarray
        Mean (n,), covariance (n, n), transition and noise per sample step.
    kept : numpy.ndarray
        The kept (RT) states.
    j0, j1 : int
        First and last sample.
    """
    n = P.shape[0]
    x, P = x.copy(), P.copy()
    spare, FP = np.empty_like(P), np.empty_like(P)
    dense = np.empty(n, dtype=np.bool_)
    x_next = np.empty(n)
    for j in range(j0, j1):
        moving = False
        for i in range(n):
            moving = moving or x[i] != 0.0
        if moving:                             # F x (zero when the mean is: after a reset)
            for i in range(n):
                s = 0.0
                for b in range(n):
                    s += F[j, i, b] * x[b]
                x_next[i] = s
            for a in kept:
                drive = 0.0
                for b in kept:
                    drive += F[j, a, b] * x[b]
                x_next[a] = drive
            x, x_next = x_next, x
        predict_sparse(P, F[j], Q[j], spare, FP, dense)
        P, spare = spare, P
    return x, P


class FactoredNoise:
    """Process noise ``Q_k = L_k L_k'`` held as its factor ``L`` (N-1, n, q) and formed a
    slice of steps at a time (``noise[a:b]``), so a long high-rate model never holds the
    whole ``Q`` stack (:func:`navlib.filters.linear.prepare_linear` with ``compact=True``)."""

    def __init__(self, L):
        self.L = np.asarray(L, dtype=float)

    def __getitem__(self, steps: slice) -> np.ndarray:
        L = self.L[steps]
        return L @ L.swapaxes(-1, -2)


def _definite_steps(R, count: int) -> np.ndarray:
    """:func:`definite_noise` of each epoch's ``R`` (count, m, m); one test when the stack
    repeats one matrix (a broadcast constant ``R``, stride 0: the same matrix, so the same
    answer)."""
    R = np.asarray(R)
    if not count:
        return np.zeros(0, dtype=bool)
    if R.ndim == 3 and R.strides[0] == 0:
        return np.broadcast_to(definite_noise(R[0]), (count,))
    return definite_noise(R)


def covariance_recursion(F, Q, H, R, P0, measured, pinv_rtol: float, *, priors: bool = True,
                         gains: bool = False, block: int = 2048, keep=None):
    """The Joseph-form covariance recursion (docs/assumptions.md, launcher.md §6.2) for a stack of
    initial covariances ``P0`` (B, n, n) sharing ``F, Q, H, R``: the one recursion of
    :func:`navlib.covariance.kalman_covariance`, :func:`navlib.filters.prepare_linear` and
    the studies.

    Each member runs the compiled recursion
    :func:`riccati_kernel` (the prediction and Joseph update of
    every caller), so the members of a stack have the histories of their own runs, to the
    bit. The noise test of every epoch's ``R`` is one batched call before the loop. ``F``,
    ``H``, ``R`` and ``Q`` are read ``block`` steps at a time (``Q`` an array or a
    :class:`FactoredNoise`; a broadcast matrix is copied one block at a time).

    Returns ``(P_prior, P_post, Gains)``: ``P_prior`` (B, N, n, n) or None without
    ``priors``, ``P_post`` (B, N, n, n), or (B, K, n, n) at the K distinct epochs ``keep``
    in ascending order (negative indices from the end: a reader of a few epochs holds no
    history), and with ``gains`` the
    :class:`Gains` of the updates, (B, N, ...) stacks (zero gain,
    ``S_pinv`` and dof at epochs without update), else None. These are the gains
    :func:`kalman_gains` computes from the priors, to the bit (the
    same compiled kernel; docs/assumptions.md "Compiled kernels").

    Parameters
    ----------
    F, Q, H, R : numpy.ndarray
        The shared model (``Q`` may be a :class:`FactoredNoise`).
    P0 : numpy.ndarray
        Initial covariances, (B, n, n).
    measured : numpy.ndarray
        Whether each epoch has an update, (N,) bool.
    pinv_rtol : float
        Relative tolerance of the pseudo-inverse of a singular ``S``.
    priors, gains : bool, optional
        Whether to return the priors; the gains.
    block : int, optional
        Steps read at a time.
    keep : sequence of int or None, optional
        Epochs whose posteriors are kept; None keeps all.
    """
    count, (batch, n) = measured.size, P0.shape[:2]
    m = 0 if H is None else H.shape[-2]
    if H is None:
        r_definite = np.zeros(count, dtype=bool)
    else:
        r_definite = _definite_steps(R, count)
    update, r_definite = kernel_array(measured, np.bool_), kernel_array(r_definite, np.bool_)
    P_prior = np.empty((batch, count, n, n)) if priors else np.empty((batch, 0, n, n))
    kept = range(count) if keep is None else np.unique(np.asarray(keep, dtype=int) % max(count, 1))
    slot = np.full(count, -1, dtype=np.int64)
    slot[kept] = np.arange(len(kept))
    P_post = np.empty((batch, len(kept), n, n))
    rows = count if gains else 0
    K = np.zeros((batch, rows, n, m))
    S_pinv = np.zeros((batch, rows, m, m))
    dof = np.zeros((batch, rows), dtype=np.int64)
    P = np.array(P0, dtype=float)
    for a in range(0, count, block):
        b, q0 = min(count, a + block), max(a - 1, 0)
        F_block, Q_block = kernel_array(F[q0:b - 1]), kernel_array(Q[q0:b - 1])
        if H is None:
            H_block, R_block = np.zeros((b - a, 0, n)), np.zeros((b - a, 0, 0))
        else:
            H_block, R_block = kernel_array(H[a:b]), kernel_array(R[a:b])
        for j in range(batch):
            P[j] = riccati_kernel(P[j], F_block, Q_block, H_block, R_block, r_definite[a:b],
                                  update[a:b], pinv_rtol, a, P_prior[j, a:b] if priors
                                  else P_prior[j], slot[a:b], P_post[j], K[j, a:b],
                                  S_pinv[j, a:b], dof[j, a:b])
    return (P_prior if priors else None, P_post,
            Gains(K, S_pinv, dof) if gains else None)


@numba.njit(cache=True)
def fixed_updates_kernel(x, P, F, Q, kept, j0, samples, z, H, R, definite, pinv_rtol, xs, Ps,
                         innovations, nis, dofs, j_end):
    """The EKF over a run of updates with one design (:mod:`navlib.filters.ekf_updates`):
    from sample ``j0`` of a window, for each update ``u``, :func:`propagate_kernel` to
    sample ``samples[u]`` and :func:`update_kernel` with ``z[u]``, ``H``, ``R``; the
    posterior mean, covariance, innovation, NIS and dof of update ``u`` into ``xs[u]``,
    ``Ps[u]``, ``innovations[u]``, ``nis[u]``, ``dofs[u]``; then :func:`propagate_kernel`
    to sample ``j_end`` (no step when it is the last update's sample; with no updates,
    the propagation alone). The same compiled steps as one call per update, without
    Python between them (docs/assumptions.md "Compiled kernels"); the EKF's one compiled
    entry point (its update is inlined: compiled once, here).
    Returns ``(x, P)`` at ``j_end``.

    Parameters
    ----------
    x, P, F, Q : numpy.ndarray
        Mean and covariance at ``j0``, transition and noise per sample step.
    kept : numpy.ndarray
        The kept (RT) states.
    j0, j_end : int
        First and last sample.
    samples, z, H, R : numpy.ndarray
        Sample and measurement of each update, the one design's ``H`` and ``R``.
    definite : bool
        Whether ``R`` is positive definite.
    pinv_rtol : float
        Relative tolerance of the pseudo-inverse of ``S``.
    xs, Ps, innovations, nis, dofs : numpy.ndarray
        Outputs per update, written in place.
    """
    n, m = P.shape[0], H.shape[0]
    K, S_pinv = np.empty((n, m)), np.empty((m, m))
    for u in range(samples.size):
        x, P = propagate_kernel(x, P, F, Q, kept, j0, samples[u])
        j0 = samples[u]
        x, innovation, nis_u, dof = update_kernel(x, P, z[u], H, R, definite, pinv_rtol,
                                                  Ps[u], K, S_pinv)
        copy_vector(x, xs[u])
        copy_vector(innovation, innovations[u])
        nis[u], dofs[u] = nis_u, dof
        P = Ps[u]
    return propagate_kernel(x, P, F, Q, kept, j0, j_end)


def compile_kernels() -> None:
    """Run each compiled kernel once on tiny inputs: compiles them on the first run on a
    machine (README "Compiled kernels" gives the cost) and loads them from numba's
    disk cache afterwards, so processes started later (notebook kernels of a report) only
    load."""
    n, m = 2, 1
    P, H, R = np.eye(n), np.ones((1, m, n)), np.ones((1, m, m))
    steps = np.eye(n)[None]
    riccati_kernel(P, steps, steps, H, R, np.ones(1, dtype=np.bool_), np.ones(1, dtype=np.bool_),
                   PINV_RTOL, 0, np.empty((0, n, n)), np.zeros(1, dtype=np.int64),
                   np.empty((1, n, n)), np.empty((1, n, m)), np.empty((1, m, m)),
                   np.empty(1, dtype=np.int64))
    joseph_update(P, H[0], R[0])
    kalman_gain(P, H[0], R[0])
    fixed_updates_kernel(np.zeros(n), P, steps, steps, np.arange(1), 0, np.ones(1, dtype=np.int64),
                         np.zeros((1, m)), H[0], R[0], True, PINV_RTOL, np.empty((1, n)),
                         np.empty((1, n, n)), np.empty((1, m)), np.empty(1),
                         np.empty(1, dtype=np.int64), 1)


def kalman_gains(P_prior, H, R, measured, pinv_rtol: float = PINV_RTOL) -> Gains:
    """Batched gains of :func:`kalman_gain` at all epochs at once.

    The rule of :func:`navlib.covariance.kalman_covariance`, so the Joseph update with these
    gains reproduces its posteriors.

    Parameters
    ----------
    P_prior : ndarray (N, n, n)
    H, R, pinv_rtol
        As in :func:`kalman_gain`.
    measured : ndarray (N,) of bool
        Epochs with an update; the others get zero gain and dof.

    Returns
    -------
    Gains
    """
    gains = kalman_gain(P_prior, H, R, pinv_rtol=pinv_rtol)
    measured = np.asarray(measured, dtype=bool)
    gains.K[~measured] = 0.0
    return Gains(gains.K, gains.S_pinv, np.where(measured, gains.dof, 0))


drop_stale_kernel_caches(__name__, globals())  # numba checks only this file (numba #1833)
