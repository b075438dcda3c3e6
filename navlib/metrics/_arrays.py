"""Checks and normalisation shared by the excitability and sensability metrics.

Shapes follow docs/library.md; the normalisation is the corrected Eq. 11 (docs/assumptions.md A10):
``D0 = diag(diag(P0))``, ``H~ = R0^-1/2 H D0^1/2``.
"""

from __future__ import annotations

import numpy as np

from navlib._validation import finite_array, finite_scalar
from navlib.errors import NavlibInputError

D0_CHOICES = ("global", "filter")


# --------------------------------------------------------------------------- validation


def square_stack(value, name: str) -> np.ndarray:
    arr = finite_array(value, name, ndim=3)
    if arr.shape[1] != arr.shape[2]:
        raise NavlibInputError(f"{name}: expected a stack of square matrices (K, n, n), "
                               f"got shape {arr.shape}")
    return arr


def check_system(F, H) -> tuple[np.ndarray, np.ndarray]:
    """``F`` (N-1, n, n) and ``H`` (N, m, n); a single (m, n) ``H`` is used at every epoch."""
    F = square_stack(F, "F")
    n_epochs, n = F.shape[0] + 1, F.shape[-1]
    H = finite_array(H, "H")
    if H.ndim == 2:
        H = np.broadcast_to(H, (n_epochs, *H.shape))
    if H.ndim != 3 or H.shape[0] != n_epochs or H.shape[2] != n or H.shape[1] < 1:
        raise NavlibInputError(
            f"H: expected shape (N, m, n) = ({n_epochs}, m, {n}) with N = len(F) + 1, "
            f"or one (m, {n}) matrix; got {H.shape}"
        )
    return F, H


def spd(value, name: str, size: int | None = None) -> np.ndarray:
    """A symmetric positive-definite (size, size) matrix, else NavlibInputError naming it."""
    arr = finite_array(value, name, ndim=2)
    if arr.shape[0] != arr.shape[1] or (size is not None and arr.shape[0] != size):
        want = f"({size}, {size})" if size is not None else "square"
        raise NavlibInputError(f"{name}: expected a {want} matrix, got shape {arr.shape}")
    check_covariances(arr[None], name)
    return 0.5 * (arr + arr.T)


def check_covariances(stack: np.ndarray, name: str, definite: bool = True) -> None:
    """Symmetric (to round-off) positive definite, or semi-definite when ``definite`` is False,
    matrices; else a NavlibInputError naming the first bad one (``name[k]`` in a stack)."""
    if stack.shape[0] == 0:
        return

    def label(k) -> str:
        return f"{name}[{int(k)}]" if stack.shape[0] > 1 else name

    scale = np.maximum(np.max(np.abs(stack), axis=(1, 2)), np.finfo(float).tiny)
    asym = np.max(np.abs(stack - np.swapaxes(stack, 1, 2)), axis=(1, 2)) > 1e-9 * scale
    if np.any(asym):
        raise NavlibInputError(f"{label(np.flatnonzero(asym)[0])}: must be symmetric")
    if definite:
        try:
            np.linalg.cholesky(stack)
            return
        except np.linalg.LinAlgError:
            low = np.linalg.eigvalsh(stack)[:, 0]
            k = np.argmin(low / scale)
            raise NavlibInputError(f"{label(k)}: must be positive definite (smallest "
                                   f"eigenvalue {low[k]:g})") from None
    low = np.linalg.eigvalsh(0.5 * (stack + np.swapaxes(stack, 1, 2)))[:, 0]
    bad = np.flatnonzero(low < -1e-9 * scale)
    if bad.size:
        raise NavlibInputError(f"{label(bad[0])}: must be positive semi-definite "
                               f"(smallest eigenvalue {low[bad[0]]:g})")


def measurement_noise(R, n_epochs: int, m: int) -> np.ndarray:
    """``R`` as an (N, m, m) stack of SPD matrices (one (m, m) matrix is repeated)."""
    R = finite_array(R, "R")
    if R.ndim == 2:
        R = np.broadcast_to(R, (n_epochs, *R.shape))
    if R.ndim != 3 or R.shape != (n_epochs, m, m):
        raise NavlibInputError(
            f"R: expected shape ({m}, {m}) or ({n_epochs}, {m}, {m}), got {R.shape}"
        )
    check_covariances(R, "R")
    return 0.5 * (R + np.swapaxes(R, 1, 2))


def normalising_variances(d0, P0: np.ndarray) -> np.ndarray:
    """Diagonal of ``D0``: from ``P0`` by default, else ``d0`` as (n,) variances or (n, n)."""
    n = P0.shape[0]
    if d0 is None:
        return np.diag(P0).copy()
    d = finite_array(d0, "d0")
    if d.shape == (n, n):
        d = np.diag(d).copy()
    if d.shape != (n,):
        raise NavlibInputError(f"d0: expected ({n},) variances or an ({n}, {n}) covariance, "
                               f"got shape {d.shape}")
    if np.any(d <= 0):
        raise NavlibInputError(f"d0: variances must be positive, got min {d.min():g}")
    return d


def check_state_names(state_names, n: int) -> tuple[str, ...] | None:
    if state_names is None:
        return None
    names = tuple(str(name) for name in state_names)
    if len(names) != n:
        raise NavlibInputError(f"state_names: expected {n} names, got {len(names)}")
    return names


def frame_names(state_names, n: int) -> list[str]:
    return list(state_names) if state_names is not None else [f"x{j + 1}" for j in range(n)]


def check_eta(eta) -> float:
    eta = finite_scalar(eta, "eta", 0.0, 1.0, low_open=True)
    if eta >= 1.0:
        raise NavlibInputError(f"eta: must lie in (0, 1), got {eta}")
    return eta


def check_nu(nu) -> float:
    return finite_scalar(nu, "nu", 0.0, 1.0, low_open=True)


# --------------------------------------------------------------------------- normalisation


def whiten(H: np.ndarray, R: np.ndarray, sqrt_d: np.ndarray) -> np.ndarray:
    """``L^-1 H D0^1/2`` with ``R = L L'`` (Cholesky), batched over epochs.

    Cholesky whitening differs from the symmetric ``R^-1/2`` by an orthogonal factor on the
    left, which changes neither ``H~' H~`` nor the right singular vectors and singular values
    of the stacked ``O~`` (docs/assumptions.md A10).
    """
    L = np.linalg.cholesky(R)
    return np.linalg.solve(L, H * sqrt_d)


def fix_signs(V: np.ndarray) -> np.ndarray:
    """Columns (last axis) signed so their largest-magnitude entry is positive, for
    reproducible plots of ``u^i`` / ``v^i`` (the metrics use squares and do not care)."""
    pivot = np.take_along_axis(V, np.argmax(np.abs(V), axis=-2)[..., None, :], axis=-2)
    return V * np.where(pivot < 0, -1.0, 1.0)


def n_states(n) -> int:
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise NavlibInputError(f"n: expected a positive integer number of states, got {n!r}")
    return int(n)


def check_d0(d0) -> str:
    if d0 not in D0_CHOICES:
        raise NavlibInputError(f"d0: expected one of {D0_CHOICES}, got {d0!r}")
    return d0
