"""Continuous -> discrete error models: matrix exponential, Van Loan, Euler, chaining.

For ``dx/dt = A x + G w`` with white ``w`` of power spectral density ``Qc`` and
``W = G Qc G'``:

* ``method="expm"``: ``F = expm(A dt)`` and, by Van Loan (1978),
  ``Q = int_0^dt expm(A s) W expm(A s)' ds`` from one exponential of the block matrix
  ``[[-A, W], [0, A']] dt`` (docs/assumptions.md A8);
* ``method="series"``: the same ``F``, and Van Loan's integral by its Taylor series
  ``Q = sum_k L_k dt^(k+1)/(k+1)!`` with ``L_0 = W``, ``L_k = A L_(k-1) + L_(k-1) A'``:
  no ``2n x 2n`` exponential, accurate to ``~|A dt|^5/6!`` relative over short IMU steps;
* ``method="euler"``: the papers' form ``F = I + A dt``, ``Q = W dt`` (Beaudoin et al. 2018
  eq. 1, ``A_lc = I + s_t F``).

Matrix exponentials of stacks use :func:`expm_taylor` (one shared scaling, batched
products), because :func:`scipy.linalg.expm` treats each matrix of a stack separately.
:func:`chain` multiplies per-step transitions between measurement epochs and accumulates
``Q <- Phi Q Phi' + Q_j`` (docs/assumptions.md A8: 100 IMU steps per 1 Hz GNSS epoch).
"""

from __future__ import annotations

import math

import numpy as np

from navlib.errors import NavlibInputError

__all__ = ["METHODS", "chain", "discretize_steps", "expm_taylor"]

METHODS = ("expm", "series", "euler")
"""Discretisation methods of :func:`discretize_steps`."""

_TAYLOR_DEGREE = 12
_TAYLOR_THETA = 0.5
_SERIES_ORDER = 4


_TAYLOR_BOUND = _TAYLOR_THETA ** (_TAYLOR_DEGREE + 1) / math.factorial(_TAYLOR_DEGREE + 1)
_TAYLOR_REACH = np.array([(_TAYLOR_BOUND * math.factorial(m + 1)) ** (1.0 / (m + 1))
                          for m in range(1, _TAYLOR_DEGREE)])
"""Largest norm whose degree-``m`` truncation bound ``norm^(m+1)/(m+1)!`` is within
``_TAYLOR_BOUND`` (``m = 1 .. 11``: increasing)."""


def _taylor_degree(norm):
    """The lowest Taylor degree ``m`` whose truncation bound ``norm^(m+1)/(m+1)!`` is within
    that of degree 12 at the scaling limit (``0.5^13/13!``), per norm: short steps need fewer
    terms (the 21-state model at 50 Hz, ``|A dt|_1 ~ 0.03``: degree 6) at no loss of
    accuracy."""
    return 1 + np.searchsorted(_TAYLOR_REACH, norm, side="left")


def expm_taylor(X) -> np.ndarray:
    """Batched matrix exponential of ``X`` (K, n, n) by Taylor series with scaling and squaring.

    Each matrix gets the scaling ``2^-s`` that brings its 1-norm below 0.5; the Taylor
    polynomial of degree 12, or of the lowest degree with the same bound when the scaled
    norm is smaller (:func:`_taylor_degree`), then has a truncation error below
    ``0.5^13/13! ~ 2e-14`` relative, and ``s`` squarings follow. The matrices that share a
    scaling and a degree go through the products together (batched), so a stack whose norms
    spread (a rocket's pad, boost and coast steps: 0.03-3.2) pays for each matrix's own
    terms, not the largest's (4300 steps of the 21-state model: 50 000 matrix products
    instead of 64 500). For the 21-state model at 100 Hz (``|A dt|_1 <= 1.6``) this is at
    most 14 products a matrix, about 20x faster than :func:`scipy.linalg.expm` on the stack.
    """
    X = np.asarray(X, dtype=float)
    stack = X.reshape(-1, *X.shape[-2:])
    norms = _one_norm(stack)
    squarings = _scaling(norms)
    degrees = _taylor_degree(norms / 2.0**squarings)
    groups = np.unique(np.stack([squarings, degrees], axis=1), axis=0)
    if len(groups) == 1:  # one scaling and degree: no gathering
        return _expm_scaled(X, int(groups[0, 0]), int(groups[0, 1]))
    E = np.empty_like(stack)
    for s, degree in groups:
        members = np.flatnonzero((squarings == s) & (degrees == degree))
        E[members] = _expm_scaled(stack[members], int(s), int(degree))
    return E.reshape(X.shape)


def _one_norm(X) -> np.ndarray:
    """1-norm (largest column sum) of each matrix of the stack ``X`` (K, n, n)."""
    return np.max(np.sum(np.abs(X), axis=-2), axis=-1) if X.size else np.zeros(len(X))


def _scaling(norm):
    """Squarings ``s >= 0`` that bring ``norm`` to :data:`_TAYLOR_THETA` or below."""
    norm = np.asarray(norm, dtype=float)
    with np.errstate(divide="ignore"):
        s = np.ceil(np.log2(norm / _TAYLOR_THETA))
    return np.where(norm > 0, np.maximum(s, 0), 0).astype(int)


def _expm_scaled(X, squarings: int, degree: int) -> np.ndarray:
    """``expm(X)`` by the degree-``degree`` Taylor polynomial of ``X / 2^squarings``
    (Horner) and ``squarings`` squarings: one scaling and degree for the whole stack."""
    X = X / 2.0**squarings
    diag = np.arange(X.shape[-1])
    E = X / degree
    E[..., diag, diag] += 1.0
    for k in range(degree - 1, 0, -1):  # Horner: E <- I + X E / k
        E = X @ E
        E *= 1.0 / k
        E[..., diag, diag] += 1.0
    for _ in range(squarings):
        E = E @ E
    return E


def _as_steps(matrix, n_steps: int, name: str) -> np.ndarray:
    matrix = np.asarray(matrix, dtype=float)
    if matrix.ndim == 2:
        return np.broadcast_to(matrix, (n_steps, *matrix.shape))
    if matrix.ndim == 3 and matrix.shape[0] == n_steps:
        return matrix
    raise NavlibInputError(
        f"{name}: expected one matrix or a stack of {n_steps} matrices, got shape {matrix.shape}"
    )


def discretize_steps(A, G, Qc, dt_s, method: str = "expm", *, W=None):
    """Per-step transition and process-noise matrices.

    Parameters
    ----------
    A : ndarray (n, n) or (K, n, n)
        Continuous dynamics, held constant over each step.
    G : ndarray (n, q) or (K, n, q)
        Noise input matrix.
    Qc : ndarray (q, q)
        Power spectral density of the white noise ``w``.
    dt_s : float or ndarray (K,)
        Step lengths, s.
    method : {"expm", "series", "euler"}
        See the module docstring.
    W : ndarray (K, n, n), optional
        ``G Qc G'`` of each step given directly (then ``G`` and ``Qc`` are not used): a
        time average of ``G Qc G'`` over a step differs from ``G_mean Qc G_mean'`` when
        ``G`` rotates within the step.

    Returns
    -------
    F, Q : ndarray (K, n, n)
    """
    if method not in METHODS:
        raise NavlibInputError(f"method: expected one of {METHODS}, got {method!r}")
    A = np.asarray(A, dtype=float)
    dt_s = np.atleast_1d(np.asarray(dt_s, dtype=float))
    n_steps = A.shape[0] if A.ndim == 3 else dt_s.size
    if dt_s.size == 1:
        dt_s = np.full(n_steps, dt_s[0])
    if dt_s.size != n_steps or np.any(~np.isfinite(dt_s)) or np.any(dt_s <= 0):
        raise NavlibInputError(f"dt_s: expected {n_steps} positive finite step(s)")
    A = _as_steps(A, n_steps, "A")
    if W is None:
        G = _as_steps(G, n_steps, "G")
        W = G @ np.asarray(Qc, dtype=float) @ np.swapaxes(G, 1, 2)
    else:
        W = _as_steps(W, n_steps, "W")
    n = A.shape[-1]
    step = dt_s[:, None, None]
    if method == "euler":
        F = A * step
        F += np.eye(n)  # bitwise I + A dt, one (N, n, n) temporary fewer
        return F, W * step
    if method == "series":
        F = expm_taylor(A * step)
        L, Q, factor = W, W * step, step
        for k in range(1, _SERIES_ORDER + 1):
            AL = A @ L
            L = AL + np.swapaxes(AL, 1, 2)
            factor = factor * step / (k + 1)
            Q = Q + L * factor
    else:
        block = np.zeros((n_steps, 2 * n, 2 * n))
        block[:, :n, :n] = -A * step
        block[:, :n, n:] = W * step
        block[:, n:, n:] = np.swapaxes(A, 1, 2) * step
        E = expm_taylor(block)
        F = np.swapaxes(E[:, n:, n:], 1, 2)
        Q = F @ E[:, :n, n:]
    return F, 0.5 * (Q + np.swapaxes(Q, 1, 2))


def chain(F_steps, Q_steps, epochs):
    """Combine per-step ``F``, ``Q`` into transitions between measurement epochs.

    Parameters
    ----------
    F_steps, Q_steps : ndarray (K, n, n)
        Step ``j`` maps sample ``j`` to ``j + 1``.
    epochs : ndarray of int (M,)
        Increasing sample indices of the measurement epochs (``epochs[-1] <= K``).

    Returns
    -------
    F, Q : ndarray (M-1, n, n)
        ``F[i]`` maps epoch ``i`` to ``i + 1``; ``Q[i]`` is the accumulated process noise.
        Intervals of equal length are chained together in one batched loop.
    """
    epochs = np.asarray(epochs)
    if epochs.ndim != 1 or epochs.size < 2 or np.any(np.diff(epochs) <= 0):
        raise NavlibInputError("epochs: expected at least 2 strictly increasing sample indices")
    if epochs[0] < 0 or epochs[-1] > len(F_steps):
        raise NavlibInputError(f"epochs: indices must lie in [0, {len(F_steps)}]")
    n = F_steps.shape[-1]
    starts, lengths = epochs[:-1], np.diff(epochs)
    F = np.empty((starts.size, n, n))
    Q = np.empty((starts.size, n, n))
    for length in np.unique(lengths):
        sel = np.flatnonzero(lengths == length)
        Fi = F_steps[starts[sel]].copy()
        Qi = Q_steps[starts[sel]].copy()
        for j in range(1, int(length)):
            Phi = F_steps[starts[sel] + j]
            Fi = Phi @ Fi
            Qi = Phi @ Qi @ np.swapaxes(Phi, 1, 2) + Q_steps[starts[sel] + j]
        F[sel], Q[sel] = Fi, Qi
    return F, 0.5 * (Q + np.swapaxes(Q, 1, 2))
