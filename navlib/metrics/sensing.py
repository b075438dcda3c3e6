"""Sensability of navigation states (España, Carrizo & Giribet 2019, Eqs. 10, 12-16, Defs. 1-2).

:func:`sensability` runs the Kalman information recursion, eigen-decomposes the normalised
information ``I~_k = D0^1/2 I_k D0^1/2`` at every epoch (corrected Eq. 11, docs/assumptions.md A10),
takes ``r^i_k`` (Eq. 15), ``nr_k`` from ``nu`` and ``s^j_k`` = norm of the projection of ``e_j`` on
the practically sensible subspace. :func:`nu_for` / :func:`nu_range` give admissible ``nu``
(docs/assumptions.md A11); :func:`physical_bands` the k-sigma bands of Figs. 3-5.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from navlib._validation import finite_array, finite_scalar
from navlib.covariance import kalman_covariance
from navlib.errors import NavlibInputError
from navlib.metrics._arrays import (
    check_covariances,
    check_nu,
    check_state_names,
    check_system,
    fix_signs,
    frame_names,
    measurement_noise,
    n_states,
    spd,
    square_stack,
    whiten,
)

__all__ = ["SensabilityResult", "nu_for", "nu_range", "physical_bands", "sensability"]


@dataclass(frozen=True, eq=False)
class SensabilityResult:
    """Sensability of each state at every epoch (España et al. Defs. 1-2).

    Attributes
    ----------
    t : ndarray (N,)
        Epoch times, s (epoch indices when no times were given).
    s : ndarray (N, n)
        ``s^j_k = ||pi_s(e_j)||`` in [0, 1] (Eq. 16).
    eigenvalues : ndarray (N, n)
        Eigenvalues ``lambda^i_k`` of the normalised information ``I~_k``, descending.
    V : ndarray (N, n, n)
        Matching eigenvectors ``v^i_k`` as columns.
    r : ndarray (N, n)
        ``r^i_k = sqrt(sum_{j<=i} lambda^j / sum_j lambda^j)`` (Eq. 15); ``r^n = 1``.
    nr : ndarray (N,) of int
        First 1-based ``i`` with ``r^i_k >= nu`` (Def. 1).
    sigma : ndarray (N, n)
        Physical posterior standard deviations ``sqrt(diag P_k)``.
    P : ndarray (N, n, n)
        Physical posterior covariances.
    information : ndarray (N, n, n)
        Normalised information ``I~_k = D0^1/2 P_k^-1 D0^1/2``.
    d0 : ndarray (n,)
        Diagonal of ``D0``.
    nu : float
    prior_update : bool
        False: ``P0`` is the posterior at the first epoch (docs/assumptions.md A9, literal reading);
        True: ``P0`` is a prior updated with the first measurement.
    state_names : tuple of str or None
    """

    t: np.ndarray
    s: np.ndarray
    eigenvalues: np.ndarray
    V: np.ndarray
    r: np.ndarray
    nr: np.ndarray
    sigma: np.ndarray
    P: np.ndarray
    information: np.ndarray
    d0: np.ndarray
    nu: float
    prior_update: bool
    state_names: tuple[str, ...] | None = None

    @property
    def n(self) -> int:
        return self.s.shape[1]

    def with_nu(self, nu: float) -> SensabilityResult:
        """The same recursion with another threshold ``nu`` (no new eigen-decomposition)."""
        nu = check_nu(nu)
        nr, s = _sensible(self.r, self.V, nu)
        return replace(self, nu=nu, nr=nr, s=s)

    def to_frame(self) -> pd.DataFrame:
        """Tidy long format: one row per (epoch, state) with ``t``, ``state``, ``s``,
        ``sigma`` (physical 1-sigma) and ``nr``."""
        N, n = self.s.shape
        return pd.DataFrame({
            "t": np.repeat(self.t, n),
            "state": np.tile(frame_names(self.state_names, n), N),
            "s": self.s.ravel(),
            "sigma": self.sigma.ravel(),
            "nr": np.repeat(self.nr, n),
        })


def _sensible(r: np.ndarray, V: np.ndarray, nu: float) -> tuple[np.ndarray, np.ndarray]:
    """``nr_k`` (Def. 1) and ``s^j_k = sqrt(sum_{i<=nr} V[k, j, i]^2)`` (Eq. 16)."""
    nr = np.argmax(r >= nu, axis=1) + 1
    keep = np.arange(r.shape[1]) < nr[:, None]
    s = np.sqrt(np.einsum("kji,ki->kj", V**2, keep))
    return nr, s


def _information(P_n: np.ndarray) -> np.ndarray:
    """Batched ``P~^-1`` through Cholesky factors; a non-definite ``P~`` names its epoch."""
    try:
        L = np.linalg.cholesky(P_n)
    except np.linalg.LinAlgError:
        bad = int(np.flatnonzero(np.linalg.eigvalsh(P_n)[:, 0] <= 0)[0])
        raise NavlibInputError(
            f"F, Q: the posterior covariance at epoch {bad} is not positive definite "
            "(singular F with zero Q?), so the information matrix is undefined"
        ) from None
    L_inv = np.linalg.inv(L)
    info = np.swapaxes(L_inv, 1, 2) @ L_inv
    return 0.5 * (info + np.swapaxes(info, 1, 2))


def sensability(F, H, Q, R, P0, nu: float = 0.985, prior_update: bool = False,
                state_names: Sequence[str] | None = None, t=None) -> SensabilityResult:
    """Sensability of each state at every measurement epoch (España et al. Eqs. 10-16).

    Parameters
    ----------
    F : array (N-1, n, n)
        ``F[k]`` maps epoch k to k+1, physical units.
    H : array (N, m, n) or (m, n)
    Q : array (N-1, n, n)
        Process noise added over each step (symmetric positive semi-definite).
    R : array (N, m, m) or (m, m)
        Measurement-noise covariance, symmetric positive definite.
    P0 : array (n, n)
        Symmetric positive-definite covariance at the first epoch; ``D0 = diag(diag(P0))``.
    nu : float in (0, 1]
        Threshold for ``nr`` (Def. 1); see :func:`nu_for` for the proposed value
        (docs/assumptions.md A11).
    prior_update : bool
        False (default, literal reading of docs/assumptions.md A9): ``P0`` is the posterior at epoch
        0, so ``I_0 = P0^-1`` and, with a diagonal ``P0`` and an admissible ``nu``, every
        sensability is 1 at epoch 0. True: ``P0`` is a prior updated with ``H_0, R_0``.
    state_names : sequence of str, optional
    t : array (N,), optional
        Epoch times, s.

    Returns
    -------
    SensabilityResult

    Notes
    -----
    Recursion (Eq. 10): ``P-_{k+1} = F_k P_k F_k' + Q_k``, ``I_{k+1} = (P-_{k+1})^-1 +
    H' R^-1 H``, run in the normalised coordinates of the corrected Eq. 11 (docs/assumptions.md
    A10), where it is the transformed physical recursion: ``I~ = D0^1/2 I D0^1/2``. ``R0`` cancels
    from ``H~' R~^-1 H~``, so sensability needs none. Numerically the measurements are whitened
    (``W_k = L_k^-1 H_k D0^1/2`` with ``R_k = L_k L_k'``), the covariance form with the Joseph
    update (:func:`navlib.covariance.kalman_covariance`) gives ``P~_k`` without inverting ``P-``,
    and ``I~_k = P~_k^-1`` follows by batched Cholesky inversion (algebraically equal to the
    information form of Eq. 10b). The ``I~_k`` are eigen-decomposed in one batched ``eigh`` after
    the recursion.
    """
    F, H = check_system(F, H)
    n_epochs, m, n = H.shape
    Q = square_stack(Q, "Q")
    if Q.shape != F.shape:
        raise NavlibInputError(f"Q: expected shape {F.shape} like F, got {Q.shape}")
    check_covariances(Q, "Q", definite=False)
    R = measurement_noise(R, n_epochs, m)
    P0 = spd(P0, "P0", n)
    nu = check_nu(nu)
    names = check_state_names(state_names, n)
    if t is None:
        t = np.arange(n_epochs, dtype=float)
    else:
        t = finite_array(t, "t", shape=(n_epochs,))

    d = np.diag(P0).copy()
    sqrt_d = np.sqrt(d)
    F_n = F * sqrt_d / sqrt_d[:, None]
    Q_n = Q / np.outer(sqrt_d, sqrt_d)
    W = whiten(H, R, sqrt_d)
    covariance = kalman_covariance(F_n, Q_n, W, np.eye(m), P0 / np.outer(sqrt_d, sqrt_d),
                                   update_first=bool(prior_update))
    P_n = covariance.P_post
    info = _information(P_n)

    lam, V = np.linalg.eigh(info)
    lam, V = lam[:, ::-1], fix_signs(V[:, :, ::-1])
    cumulative = np.cumsum(np.clip(lam, 0.0, None), axis=1)
    r = np.sqrt(cumulative / cumulative[:, -1:])
    nr, s = _sensible(r, V, nu)
    P = P_n * np.outer(sqrt_d, sqrt_d)
    sigma = np.sqrt(np.diagonal(P, axis1=1, axis2=2))
    return SensabilityResult(t=t, s=s, eigenvalues=lam, V=V, r=r, nr=nr, sigma=sigma, P=P,
                             information=info, d0=d, nu=nu, prior_update=bool(prior_update),
                             state_names=names)


# --------------------------------------------------------------------------- helpers


def nu_range(n: int) -> tuple[float, float]:
    """Open interval of admissible ``nu`` for n states: ``(sqrt(1 - 1/n), 1)`` (docs/assumptions.md
    A11).

    Below the lower bound, equal eigenvalues (``r^i = sqrt(i/n)``) would leave a component
    outside the sensible subspace.
    """
    n = n_states(n)
    return float(np.sqrt(1.0 - 1.0 / n)), 1.0


def nu_for(n: int, eps: float) -> float:
    """The paper's proposed ``nu = sqrt(1 - 1/n + eps)``, valid for ``0 < eps < 1/n`` (A11).

    For n = 21 the paper's ``nu = 0.985`` corresponds to ``eps = 0.0178``.

    Parameters
    ----------
    n : int
        Number of states.
    eps : float
        Margin, in ``(0, 1/n)``.

    Returns
    -------
    float

    Raises
    ------
    NavlibInputError
        When ``eps`` lies outside ``(0, 1/n)``.
    """
    n = n_states(n)
    eps = finite_scalar(eps, "eps", 0.0, low_open=True)
    if eps >= 1.0 / n:
        raise NavlibInputError(f"eps: must lie in (0, 1/n) = (0, {1.0 / n:.6g}), got {eps}")
    return float(np.sqrt(1.0 - 1.0 / n + eps))


def physical_bands(result: SensabilityResult, k: float = 2.0) -> pd.DataFrame:
    """Tidy frame of the physical ``±k sigma`` bands beside the sensability (Figs. 3-5).

    Parameters
    ----------
    result : SensabilityResult
        Sensability of a model (its covariances give ``sigma``).
    k : float, optional
        Band half-width in standard deviations (default 2).

    Returns
    -------
    pandas.DataFrame
        Columns ``t``, ``state``, ``s``, ``sigma``, ``nr``, ``lower`` (= -k sigma),
        ``upper`` (= +k sigma).
    """
    if not isinstance(result, SensabilityResult):
        raise NavlibInputError(f"result: expected a SensabilityResult, got "
                               f"{type(result).__name__}")
    k = finite_scalar(k, "k", 0.0, low_open=True)
    frame = result.to_frame()
    frame["lower"] = -k * frame["sigma"]
    frame["upper"] = k * frame["sigma"]
    return frame
