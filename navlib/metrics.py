"""Excitability and sensability of navigation states (España, Carrizo & Giribet 2019).

Both metrics take plain arrays in physical units (spec api.md "Metrics"), so any model can
feed them, and both work in the normalised coordinates of the corrected Eq. 11
(spec excitability.md A10)::

    D0 = diag(diag(P0)),   F~ = D0^-1/2 F D0^1/2,   H~ = R0^-1/2 H D0^1/2,
    P~ = D0^-1/2 P D0^-1/2,   Q~ = D0^-1/2 Q D0^-1/2,   I~ = P~^-1 = D0^1/2 I D0^1/2.

* :func:`excitability` (Eqs. 17-22, Defs. 3-4): SVD of the normalised extended observability
  matrix ``O~ = [H~0; H~1 F~0; ...]``; the energy spectrum ``S(u^i) = n sigma^i / tr M``;
  ``ne`` from ``eta`` (A14); ``e^j`` = norm of the projection of the canonical vector ``e_j``
  on the excited subspace ``span{u^i : i < ne}``.
* :func:`sensability` (Eqs. 10, 12-16, Defs. 1-2): the Kalman information recursion, the
  eigen-decomposition of ``I~_k`` at every epoch, ``r^i_k`` (Eq. 15), ``nr_k`` from ``nu``
  and ``s^j_k`` = norm of the projection of ``e_j`` on the practically sensible subspace.

Helpers: :func:`nu_for` / :func:`nu_range` (spec A11), model wrappers
:func:`excitability_segment` / :func:`excitability_segments` (segments, D0 choice of A19) and
:func:`sensability_model`, and :func:`physical_bands` (the k-sigma bands of Figs. 3-5).

:class:`SegmentedAnalysis` is the paper's whole analysis of one discretised model (§4-6):
excitability per segment, sensability per epoch, the thresholds that read them (eta, nu and
the shares :data:`E_THRESHOLD`, :data:`S_THRESHOLD`, :data:`MIN_FRACTION`), tidy frame views
and :meth:`SegmentedAnalysis.with_settings`, which re-reads other segments or thresholds on
the same model. The rocket study (:class:`navlib.studies.rocket.RocketAnalysis`) and the
flight assessment (:class:`navlib.studies.assess.FlightAssessment`) are thin subclasses.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from navlib._validation import finite_array, finite_scalar
from navlib.covariance import kalman_covariance
from navlib.errors import NavlibInputError
from navlib.observability import observability_matrix

__all__ = [
    "E_THRESHOLD",
    "LOW",
    "MIN_FRACTION",
    "S_THRESHOLD",
    "ExcitabilityResult",
    "SegmentedAnalysis",
    "SensabilityResult",
    "check_segments",
    "check_thresholds",
    "excitability",
    "excitability_segment",
    "excitability_segments",
    "in_segment",
    "nu_for",
    "nu_range",
    "physical_bands",
    "sensability",
    "sensability_model",
]

D0_CHOICES = ("global", "filter")


# --------------------------------------------------------------------------- validation


def _square_stack(value, name: str) -> np.ndarray:
    arr = finite_array(value, name, ndim=3)
    if arr.shape[1] != arr.shape[2]:
        raise NavlibInputError(f"{name}: expected a stack of square matrices (K, n, n), "
                               f"got shape {arr.shape}")
    return arr


def _system(F, H) -> tuple[np.ndarray, np.ndarray]:
    """``F`` (N-1, n, n) and ``H`` (N, m, n); a single (m, n) ``H`` is used at every epoch."""
    F = _square_stack(F, "F")
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


def _spd(value, name: str, size: int | None = None) -> np.ndarray:
    """A symmetric positive-definite (size, size) matrix, else NavlibInputError naming it."""
    arr = finite_array(value, name, ndim=2)
    if arr.shape[0] != arr.shape[1] or (size is not None and arr.shape[0] != size):
        want = f"({size}, {size})" if size is not None else "square"
        raise NavlibInputError(f"{name}: expected a {want} matrix, got shape {arr.shape}")
    _check_covariances(arr[None], name)
    return 0.5 * (arr + arr.T)


def _check_covariances(stack: np.ndarray, name: str, definite: bool = True) -> None:
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


def _measurement_noise(R, n_epochs: int, m: int) -> np.ndarray:
    """``R`` as an (N, m, m) stack of SPD matrices (one (m, m) matrix is repeated)."""
    R = finite_array(R, "R")
    if R.ndim == 2:
        R = np.broadcast_to(R, (n_epochs, *R.shape))
    if R.ndim != 3 or R.shape != (n_epochs, m, m):
        raise NavlibInputError(
            f"R: expected shape ({m}, {m}) or ({n_epochs}, {m}, {m}), got {R.shape}"
        )
    _check_covariances(R, "R")
    return 0.5 * (R + np.swapaxes(R, 1, 2))


def _variances(d0, P0: np.ndarray) -> np.ndarray:
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


def _state_names(state_names, n: int) -> tuple[str, ...] | None:
    if state_names is None:
        return None
    names = tuple(str(name) for name in state_names)
    if len(names) != n:
        raise NavlibInputError(f"state_names: expected {n} names, got {len(names)}")
    return names


def _frame_names(state_names, n: int) -> list[str]:
    return list(state_names) if state_names is not None else [f"x{j + 1}" for j in range(n)]


def _eta(eta) -> float:
    eta = finite_scalar(eta, "eta", 0.0, 1.0, low_open=True)
    if eta >= 1.0:
        raise NavlibInputError(f"eta: must lie in (0, 1), got {eta}")
    return eta


def _nu(nu) -> float:
    return finite_scalar(nu, "nu", 0.0, 1.0, low_open=True)


# --------------------------------------------------------------------------- normalisation


def _whiten(H: np.ndarray, R: np.ndarray, sqrt_d: np.ndarray) -> np.ndarray:
    """``L^-1 H D0^1/2`` with ``R = L L'`` (Cholesky), batched over epochs.

    Cholesky whitening differs from the symmetric ``R^-1/2`` by an orthogonal factor on the
    left, which changes neither ``H~' H~`` nor the right singular vectors and singular values
    of the stacked ``O~`` (spec excitability.md A10).
    """
    L = np.linalg.cholesky(R)
    return np.linalg.solve(L, H * sqrt_d)


def _fix_signs(V: np.ndarray) -> np.ndarray:
    """Columns (last axis) signed so their largest-magnitude entry is positive, for
    reproducible plots of ``u^i`` / ``v^i`` (the metrics use squares and do not care)."""
    pivot = np.take_along_axis(V, np.argmax(np.abs(V), axis=-2)[..., None, :], axis=-2)
    return V * np.where(pivot < 0, -1.0, 1.0)


# --------------------------------------------------------------------------- excitability


@dataclass(frozen=True, eq=False)
class ExcitabilityResult:
    """Excitability of each state over one segment (España et al. Defs. 3-4).

    Attributes
    ----------
    e : ndarray (n,)
        ``e^j = ||pi^O(e_j)||`` in [0, 1]: share of state ``j`` in the excited subspace.
    S : ndarray (n,)
        Energy spectrum ``S(u^i) = n sigma^i / sum(sigma)`` (Eq. 19), non-increasing; sums to n.
    U : ndarray (n, n)
        Columns ``u^i``: right singular vectors of ``O~`` (eigenvectors of the Gramian).
    ne : int
        First 1-based index with ``S[i] <= eta`` (``n + 1`` when none, spec A14); the excited
        subspace is ``span{u^i : i < ne}``.
    sigma : ndarray (n,)
        Squared singular values of ``O~`` (eigenvalues of ``M = O~' O~``), descending.
    eta : float
    O : ndarray (N m, n)
        The normalised extended observability matrix ``O~`` (Eq. 17 with A10).
    d0 : ndarray (n,)
        Diagonal of ``D0`` (variances) used for the normalisation.
    state_names : tuple of str or None
    t_start, t_end : float or None
        Segment limits, when known.
    """

    e: np.ndarray
    S: np.ndarray
    U: np.ndarray
    ne: int
    sigma: np.ndarray
    eta: float
    O: np.ndarray
    d0: np.ndarray
    state_names: tuple[str, ...] | None = None
    t_start: float | None = None
    t_end: float | None = None

    @property
    def n(self) -> int:
        return self.e.size

    @property
    def ispc(self) -> np.ndarray:
        """Output principal components ``o^i = O~ u^i`` as columns (Eq. 18)."""
        return self.O @ self.U

    def with_eta(self, eta: float) -> ExcitabilityResult:
        """The same segment with another threshold ``eta`` (no new SVD)."""
        eta = _eta(eta)
        ne, e = _excited(self.S, self.U, eta)
        return replace(self, eta=eta, ne=ne, e=e)

    def to_frame(self) -> pd.DataFrame:
        """One row per index j: ``state``, its excitability ``e``, and the j-th direction of
        the spectrum (``direction`` = j, 1-based; ``sigma``, ``S``, ``excited`` = j < ne),
        plus ``eta``, ``ne`` and the segment limits."""
        n = self.n
        return pd.DataFrame({
            "state": _frame_names(self.state_names, n),
            "e": self.e,
            "direction": np.arange(1, n + 1),
            "sigma": self.sigma,
            "S": self.S,
            "excited": np.arange(1, n + 1) < self.ne,
            "eta": self.eta,
            "ne": self.ne,
            "t_start": np.nan if self.t_start is None else self.t_start,
            "t_end": np.nan if self.t_end is None else self.t_end,
        })


def _excited(S: np.ndarray, U: np.ndarray, eta: float) -> tuple[int, np.ndarray]:
    """``ne`` (spec A14) and ``e^j = sqrt(sum_{i<ne} U[j, i]^2)`` (Def. 4)."""
    below = np.flatnonzero(S <= eta)
    ne = int(below[0]) + 1 if below.size else S.size + 1
    return ne, np.linalg.norm(U[:, : ne - 1], axis=1)


def excitability(F, H, P0, R0, eta: float = 1e-3, state_names: Sequence[str] | None = None,
                 d0=None) -> ExcitabilityResult:
    """Excitability of each state over the epochs of one segment (España et al. Eqs. 17-22).

    Parameters
    ----------
    F : array (N-1, n, n)
        Transitions between the measurement epochs of the segment, physical units.
    H : array (N, m, n) or (m, n)
        Measurement matrices at the N epochs (all are stacked, spec A12).
    P0 : array (n, n)
        Symmetric positive-definite covariance whose diagonal gives ``D0`` (Eq. 11).
    R0 : array (m, m)
        Symmetric positive-definite normalising measurement covariance (may be non-diagonal).
    eta : float in (0, 1)
        Energy threshold: ``ne`` is the first 1-based ``i`` with ``S[i] <= eta`` (A14).
    state_names : sequence of str, optional
    d0 : array (n,) or (n, n), optional
        Variances (or a covariance whose diagonal is used) for ``D0`` instead of ``diag(P0)``,
        e.g. the filter covariance at the segment start (spec A19, option B).

    Returns
    -------
    ExcitabilityResult

    Notes
    -----
    Normalisation per the corrected Eq. 11 (spec A10): ``F~ = D0^-1/2 F D0^1/2``,
    ``H~ = R0^-1/2 H D0^1/2``. ``O~ = [H~0; H~1 F~0; H~2 F~1 F~0; ...]`` is stacked by
    :func:`navlib.observability.observability_matrix`, reduced by QR and decomposed by SVD
    (full right basis also when ``N m < n``), never by eigenvalues of
    ``O~' O~`` whose spectrum spans tens of decades (spec A12). ``sigma^i`` are the squared
    singular values (zero-padded when ``N m < n``), ``S = n sigma / sum(sigma)`` (Eq. 19).
    """
    F, H = _system(F, H)
    n, m = F.shape[-1], H.shape[1]
    P0 = _spd(P0, "P0", n)
    R0 = _spd(R0, "R0", m)
    eta = _eta(eta)
    names = _state_names(state_names, n)
    d = _variances(d0, P0)
    sqrt_d = np.sqrt(d)

    F_n = F * sqrt_d / sqrt_d[:, None]
    H_n = _whiten(H, np.broadcast_to(R0, (H.shape[0], m, m)), sqrt_d)
    O = observability_matrix(F_n, H_n)
    if not np.all(np.isfinite(O)):
        raise NavlibInputError("F: the normalised transition products overflow; "
                               "check the units of F and P0")
    R_factor = np.linalg.qr(O, mode="r")
    _, singular, Vh = np.linalg.svd(R_factor, full_matrices=True)
    sigma = np.zeros(n)
    sigma[: singular.size] = singular**2
    total = sigma.sum()
    if not total > 0:
        raise NavlibInputError("F, H: the observability matrix is zero (no state reaches any "
                               "measurement), so the energy spectrum S is undefined")
    S = n * sigma / total
    U = _fix_signs(Vh.T)
    ne, e = _excited(S, U, eta)
    return ExcitabilityResult(e=e, S=S, U=U, ne=ne, sigma=sigma, eta=eta, O=O, d0=d,
                              state_names=names)


# --------------------------------------------------------------------------- sensability


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
        False: ``P0`` is the posterior at the first epoch (spec A9, literal reading);
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
        nu = _nu(nu)
        nr, s = _sensible(self.r, self.V, nu)
        return replace(self, nu=nu, nr=nr, s=s)

    def to_frame(self) -> pd.DataFrame:
        """Tidy long format: one row per (epoch, state) with ``t``, ``state``, ``s``,
        ``sigma`` (physical 1-sigma) and ``nr``."""
        N, n = self.s.shape
        return pd.DataFrame({
            "t": np.repeat(self.t, n),
            "state": np.tile(_frame_names(self.state_names, n), N),
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
        Threshold for ``nr`` (Def. 1); see :func:`nu_for` for the proposed value (spec A11).
    prior_update : bool
        False (default, literal reading of spec A9): ``P0`` is the posterior at epoch 0, so
        ``I_0 = P0^-1`` and, with a diagonal ``P0`` and an admissible ``nu``, every
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
    H' R^-1 H``, run in the normalised coordinates of the corrected Eq. 11 (spec A10), where it
    is the transformed physical recursion: ``I~ = D0^1/2 I D0^1/2``. ``R0`` cancels from
    ``H~' R~^-1 H~``, so sensability needs none. Numerically the measurements are whitened
    (``W_k = L_k^-1 H_k D0^1/2`` with ``R_k = L_k L_k'``), the covariance form with the
    Joseph update (:func:`navlib.covariance.kalman_covariance`) gives ``P~_k`` without
    inverting ``P-``, and ``I~_k = P~_k^-1`` follows by batched Cholesky inversion
    (algebraically equal to the information form of Eq. 10b). The ``I~_k`` are
    eigen-decomposed in one batched ``eigh`` after the recursion.
    """
    F, H = _system(F, H)
    n_epochs, m, n = H.shape
    Q = _square_stack(Q, "Q")
    if Q.shape != F.shape:
        raise NavlibInputError(f"Q: expected shape {F.shape} like F, got {Q.shape}")
    _check_covariances(Q, "Q", definite=False)
    R = _measurement_noise(R, n_epochs, m)
    P0 = _spd(P0, "P0", n)
    nu = _nu(nu)
    names = _state_names(state_names, n)
    if t is None:
        t = np.arange(n_epochs, dtype=float)
    else:
        t = finite_array(t, "t", shape=(n_epochs,))

    d = np.diag(P0).copy()
    sqrt_d = np.sqrt(d)
    F_n = F * sqrt_d / sqrt_d[:, None]
    Q_n = Q / np.outer(sqrt_d, sqrt_d)
    W = _whiten(H, R, sqrt_d)
    covariance = kalman_covariance(F_n, Q_n, W, np.eye(m), P0 / np.outer(sqrt_d, sqrt_d),
                                   update_first=bool(prior_update))
    P_n = covariance.P_post
    info = _information(P_n)

    lam, V = np.linalg.eigh(info)
    lam, V = lam[:, ::-1], _fix_signs(V[:, :, ::-1])
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
    """Open interval of admissible ``nu`` for n states: ``(sqrt(1 - 1/n), 1)`` (spec A11).

    Below the lower bound, equal eigenvalues (``r^i = sqrt(i/n)``) would leave a component
    outside the sensible subspace.
    """
    n = _n_states(n)
    return float(np.sqrt(1.0 - 1.0 / n)), 1.0


def nu_for(n: int, eps: float) -> float:
    """The paper's proposed ``nu = sqrt(1 - 1/n + eps)``, valid for ``0 < eps < 1/n`` (A11).

    For n = 21 the paper's ``nu = 0.985`` corresponds to ``eps = 0.0178``.
    """
    n = _n_states(n)
    eps = finite_scalar(eps, "eps", 0.0, low_open=True)
    if eps >= 1.0 / n:
        raise NavlibInputError(f"eps: must lie in (0, 1/n) = (0, {1.0 / n:.6g}), got {eps}")
    return float(np.sqrt(1.0 - 1.0 / n + eps))


def _n_states(n) -> int:
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise NavlibInputError(f"n: expected a positive integer number of states, got {n!r}")
    return int(n)


def physical_bands(result: SensabilityResult, k: float = 2.0) -> pd.DataFrame:
    """Tidy frame of the physical ``±k sigma`` bands beside the sensability (Figs. 3-5).

    Columns ``t``, ``state``, ``s``, ``sigma``, ``nr``, ``lower`` (= -k sigma), ``upper``
    (= +k sigma).
    """
    if not isinstance(result, SensabilityResult):
        raise NavlibInputError(f"result: expected a SensabilityResult, got "
                               f"{type(result).__name__}")
    k = finite_scalar(k, "k", 0.0, low_open=True)
    frame = result.to_frame()
    frame["lower"] = -k * frame["sigma"]
    frame["upper"] = k * frame["sigma"]
    return frame


def _model_P0(model, P0) -> np.ndarray:
    if P0 is not None:
        return P0
    if getattr(model, "P0", None) is None:
        raise NavlibInputError("P0: the model has no default P0; pass one")
    return model.P0


def _check_model(model) -> None:
    missing = [a for a in ("t", "F", "Q", "H", "R", "state_names", "window")
               if not hasattr(model, a)]
    if missing:
        raise NavlibInputError(f"model: expected a DiscreteModel (missing {missing}); call "
                               "model.discretize(...) first")


def sensability_model(model, P0=None, nu: float = 0.985, prior_update: bool = False,
                      t_start: float | None = None, t_end: float | None = None
                      ) -> SensabilityResult:
    """:func:`sensability` of a :class:`~navlib.models.DiscreteModel` (its ``t``, ``F``,
    ``Q``, ``H``, ``R`` and ``state_names``; ``P0`` defaults to ``model.P0``).

    ``t_start``/``t_end`` restrict it to the epochs in that closed interval; ``P0`` then
    applies at the first of them.
    """
    _check_model(model)
    if t_start is not None or t_end is not None:
        model = model.window(model.t[0] if t_start is None else t_start,
                             model.t[-1] if t_end is None else t_end)
    return sensability(model.F, model.H, model.Q, model.R, _model_P0(model, P0), nu=nu,
                       prior_update=prior_update, state_names=model.state_names, t=model.t)


def _filter_variances(P_filter, model, P0, k: int, t_a: float) -> np.ndarray:
    """Variances at model epoch ``k`` (time ``t_a``) from a filter covariance (spec A19)."""
    n = len(model.state_names)
    if P_filter is None:
        return sensability_model(model, P0).sigma[k] ** 2
    if hasattr(P_filter, "t"):
        t = np.asarray(P_filter.t, dtype=float)
        hit = np.flatnonzero(np.abs(t - model.t[k]) <= 1e-6)
        if hit.size == 0:
            raise NavlibInputError(f"P_filter: has no epoch at the segment start {t_a} s "
                                   f"(model epoch {model.t[k]} s)")
        for attribute in ("P_post", "P", "covariance"):
            if hasattr(P_filter, attribute):
                return np.diagonal(np.asarray(getattr(P_filter, attribute))[hit[0]]).copy()
        if hasattr(P_filter, "sigma"):
            return np.asarray(P_filter.sigma, dtype=float)[hit[0]] ** 2
        raise NavlibInputError("P_filter: a result object needs `P_post`, `P`, `covariance` "
                               "or `sigma`")
    P = finite_array(P_filter, "P_filter")
    if P.shape == (n, n):
        return np.diag(P).copy()
    if P.ndim == 3 and P.shape == (model.t.size, n, n):
        return np.diag(P[k]).copy()
    raise NavlibInputError(f"P_filter: expected ({n}, {n}) at the segment start or "
                           f"({model.t.size}, {n}, {n}) along the model epochs, got {P.shape}")


def excitability_segment(model, t_a: float, t_b: float, P0=None, R0=None, eta: float = 1e-3,
                         d0: str = "global", P_filter=None) -> ExcitabilityResult:
    """:func:`excitability` of a :class:`~navlib.models.DiscreteModel` over ``[t_a, t_b]``.

    Parameters
    ----------
    model : DiscreteModel
        Discretised at its measurement epochs; all epochs in the closed interval are stacked
        (spec A12).
    t_a, t_b : float
        Segment limits, s.
    P0 : array (n, n), optional
        Global covariance (default ``model.P0``).
    R0 : array (m, m), optional
        Normalising measurement covariance (default ``model.R[0]``, the same for every
        segment so that segments compare).
    eta : float in (0, 1)
    d0 : {"global", "filter"}
        Spec A19: ``"global"`` (option A, default) takes ``D0`` from ``P0``; ``"filter"``
        (option B) from the filter covariance at the segment start.
    P_filter : optional
        For ``d0="filter"``: an (n, n) covariance at the segment start, an (N, n, n) stack
        along the model epochs, or a result with ``t`` and ``P_post``/``P``/``sigma`` (a
        :class:`navlib.covariance.CovarianceResult` or :class:`SensabilityResult`).
        Default: the recursion of :func:`sensability_model` from ``P0`` at the model's first
        epoch.
    """
    _check_model(model)
    d0 = _d0(d0)
    t_a = finite_scalar(t_a, "t_a")
    t_b = finite_scalar(t_b, "t_b")
    if t_b <= t_a:
        raise NavlibInputError(f"t_b: must be after t_a = {t_a}, got {t_b}")
    P0 = _model_P0(model, P0)
    R0 = np.asarray(model.R[0]) if R0 is None else R0
    segment = model.window(t_a, t_b)
    variances = None
    if d0 == "filter":
        k = int(np.flatnonzero(model.t >= segment.t[0] - 1e-9)[0])
        variances = _filter_variances(P_filter, model, P0, k, t_a)
    result = excitability(segment.F, segment.H, P0, R0, eta=eta,
                          state_names=model.state_names, d0=variances)
    return replace(result, t_start=t_a, t_end=t_b)


def excitability_segments(model, segments, eta: float = 1e-3, d0: str = "global",
                          sensability: SensabilityResult | None = None, span=None) -> tuple:
    """:func:`excitability_segment` for each ``(t_start, t_end)`` of ``segments`` (A12, A19).

    ``segments`` are checked by :func:`check_segments` (inside ``span``, default the model
    epochs). ``d0="filter"`` takes D0 from the filter covariance at each segment start; pass
    the ``sensability`` result of the same model to reuse its covariance recursion.
    """
    _check_model(model)
    segs = check_segments(segments, model.t, span)
    return tuple(excitability_segment(model, a, b, eta=eta, d0=d0, P_filter=sensability)
                 for a, b in segs)


# --------------------------------------------------------------------------- segmented analysis


E_THRESHOLD = float(1.0 / np.sqrt(2.0))
"""Default reading of the excitability: a state lies (mostly) in the excited subspace when
``e >= 1/sqrt(2)``, i.e. more than half of its unit vector's squared norm projects on it."""
S_THRESHOLD = E_THRESHOLD
"""Default reading of the sensability: the same share of the practically sensible subspace."""
MIN_FRACTION = 0.5
"""Default share of a segment's epochs with ``s >= s_threshold`` for a state to count as
sensible in that segment."""
LOW = 0.25
"""Share below which a state is "barely" in a subspace: ``e^2`` (or ``s^2``) < 1/16."""
THRESHOLD_KEYS = ("eta", "nu", "e_threshold", "s_threshold", "min_fraction")
"""The thresholds a :class:`SegmentedAnalysis` keeps in its ``settings``."""
_TOL = 1e-9


def check_thresholds(eta: float = 1e-3, nu: float = 0.985, e_threshold: float = E_THRESHOLD,
                     s_threshold: float = S_THRESHOLD,
                     min_fraction: float = MIN_FRACTION) -> dict:
    """The thresholds of a :class:`SegmentedAnalysis` as a dict of floats (keys
    :data:`THRESHOLD_KEYS`), or a NavlibInputError naming the bad one.

    ``eta`` in (0, 1) (A14), ``nu`` in (0, 1] (Def. 1, A11), the reading shares
    ``e_threshold``, ``s_threshold`` and ``min_fraction`` in [0, 1].
    """
    return {"eta": _eta(eta), "nu": _nu(nu),
            "e_threshold": finite_scalar(e_threshold, "e_threshold", 0.0, 1.0),
            "s_threshold": finite_scalar(s_threshold, "s_threshold", 0.0, 1.0),
            "min_fraction": finite_scalar(min_fraction, "min_fraction", 0.0, 1.0)}


def in_segment(t, t_start: float, t_end: float, open_start: bool = False) -> np.ndarray:
    """Boolean mask of the times ``t`` in the closed segment ``[t_start, t_end]`` (1 ns
    tolerance; ``(t_start, t_end]`` with ``open_start``), the epochs a segment stacks (A12)."""
    t = np.asarray(t, dtype=float)
    low = t > t_start + _TOL if open_start else t >= t_start - _TOL
    return low & (t <= t_end + _TOL)


def check_segments(segments, t, span=None) -> tuple[tuple[float, float], ...]:
    """``segments`` as ``(t_start, t_end)`` float pairs, each inside ``span`` (default the
    first and last of the epochs ``t``) and holding at least two epochs of ``t``; else a
    NavlibInputError naming the segment."""
    t = np.asarray(t, dtype=float)
    first, last = (t[0], t[-1]) if span is None else (float(span[0]), float(span[1]))
    try:
        segs = tuple((float(a), float(b)) for a, b in segments)
    except (TypeError, ValueError) as exc:
        raise NavlibInputError("segments: expected a sequence of (t_start, t_end) pairs") \
            from exc
    if not segs:
        raise NavlibInputError("segments: need at least one segment")
    for i, (a, b) in enumerate(segs):
        if not (np.isfinite(a) and np.isfinite(b)) or b <= a:
            raise NavlibInputError(f"segments[{i}]: need t_start < t_end, got ({a}, {b})")
        if a < first - _TOL or b > last + _TOL:
            raise NavlibInputError(f"segments[{i}]: ({a}, {b}) s lies outside the flight "
                                   f"[{first:g}, {last:g}] s")
        count = int(np.count_nonzero(in_segment(t, a, b)))
        if count < 2:
            every = f" (epochs every {np.median(np.diff(t)):.3g} s)" if t.size > 1 else ""
            raise NavlibInputError(f"segments[{i}]: ({a}, {b}) s holds {count} epoch(s) of the "
                                   f"model; a segment needs at least 2{every}")
    return segs


@dataclass(frozen=True, eq=False)
class SegmentedAnalysis:
    """Excitability per segment and sensability per epoch of one discretised model, with the
    thresholds that read them (España et al. §4-6).

    Build one with :meth:`build`; :meth:`with_settings` re-reads it with other segments,
    thresholds or D0 choice on the same model (new SVDs only for new segments or D0, none
    for a new eta, no new eigen-decomposition for a new nu).

    Attributes
    ----------
    model : DiscreteModel
        Discretised at its measurement epochs, with ``P0``.
    trajectory : Trajectory or None
        The flight the model is linearised about (its span bounds the segments).
    segments : tuple of (float, float)
        ``(t_start, t_end)`` of each segment, s.
    excitability : tuple of ExcitabilityResult
        One per segment (:func:`excitability_segments`).
    sensability : SensabilityResult
        Over all model epochs, ``P0`` at the first (:func:`sensability_model`).
    settings : dict
        The thresholds (:data:`THRESHOLD_KEYS`), ``d0`` (A19) and ``prior_update`` (A9), plus
        the caller's descriptive choices (attitude-error frame, sensor preset, GNSS sigma...).
    """

    model: object
    trajectory: object
    segments: tuple
    excitability: tuple
    sensability: SensabilityResult
    settings: dict

    @classmethod
    def build(cls, model, segments, *, trajectory=None, eta: float = 1e-3, nu: float = 0.985,
              d0: str = "global", prior_update: bool = False,
              e_threshold: float = E_THRESHOLD, s_threshold: float = S_THRESHOLD,
              min_fraction: float = MIN_FRACTION, settings=None, **fields):
        """Run the metrics of ``model`` over ``segments``.

        Parameters
        ----------
        model : DiscreteModel
            With ``P0`` (:func:`sensability_model`).
        segments : sequence of (t_start, t_end)
            Checked by :func:`check_segments` inside the trajectory's span (or the model's).
        trajectory : Trajectory, optional
        eta, nu, e_threshold, s_threshold, min_fraction : float
            :func:`check_thresholds`.
        d0 : {"global", "filter"}
            D0 of the excitability per segment (A19); ``"filter"`` uses the sensability's
            covariance recursion at each segment start.
        prior_update : bool
            Sensability with ``P0`` as a prior updated at the first epoch (A9).
        settings : mapping, optional
            Descriptive choices kept in ``settings`` beside the thresholds.
        **fields
            The further fields of a subclass.
        """
        _check_model(model)
        th = check_thresholds(eta, nu, e_threshold, s_threshold, min_fraction)
        d0 = _d0(d0)
        span = _span(trajectory)
        segs = check_segments(segments, model.t, span)
        se = sensability_model(model, nu=th["nu"], prior_update=prior_update)
        ex = excitability_segments(model, segs, th["eta"], d0, se, span)
        return cls(model=model, trajectory=trajectory, segments=segs, excitability=ex,
                   sensability=se, settings={**dict(settings or {}), **th, "d0": d0,
                                             "prior_update": bool(prior_update)}, **fields)

    # ----- identities

    @property
    def state_names(self) -> tuple[str, ...]:
        return tuple(self.model.state_names)

    @property
    def thresholds(self) -> dict:
        """``eta``, ``nu``, ``e_threshold``, ``s_threshold``, ``min_fraction``."""
        return {k: self.settings[k] for k in THRESHOLD_KEYS}

    @property
    def labels(self) -> tuple[str, ...]:
        """Column labels of the segments in wide tables: ``tau1, tau2, ...``."""
        return tuple(f"tau{i + 1}" for i in range(len(self.segments)))

    def _segment_keys(self) -> dict:
        """Columns naming each segment in the long frames (one value per segment)."""
        return {"segment": list(self.labels)}

    def _state_columns(self) -> dict:
        """Columns describing each state in the long frames (one value per state)."""
        return {"state": list(self.state_names)}

    def epochs(self, t_a: float, t_b: float, open_start: bool = False) -> np.ndarray:
        """Indices of the model epochs in ``[t_a, t_b]`` (``(t_a, t_b]`` with ``open_start``)."""
        return np.flatnonzero(in_segment(self.model.t, t_a, t_b, open_start))

    def at(self, time: float) -> int:
        """Index of the model epoch nearest ``time``."""
        return int(np.argmin(np.abs(self.model.t - time)))

    # ----- frame views

    def excitability_table(self) -> pd.DataFrame:
        """Wide table: states (rows, model order) by segments (columns :attr:`labels`),
        values ``e``."""
        return pd.DataFrame({label: ex.e for label, ex in zip(self.labels, self.excitability,
                                                              strict=True)},
                            index=pd.Index(self.state_names, name="state"))

    def excitability_frame(self) -> pd.DataFrame:
        """Long table, one row per (segment, state): the segment's key columns (``segment``
        ...), ``t_start``, ``t_end``, the state's columns (``state`` ...), ``e``,
        ``excitable`` (``e >= e_threshold``), ``ne`` and ``eta``."""
        keys, states = self._segment_keys(), self._state_columns()
        e_threshold = self.settings["e_threshold"]
        frames = [pd.DataFrame({**{k: v[i] for k, v in keys.items()}, "t_start": a,
                                "t_end": b, **states, "e": ex.e,
                                "excitable": ex.e >= e_threshold, "ne": ex.ne, "eta": ex.eta})
                  for i, ((a, b), ex) in enumerate(zip(self.segments, self.excitability,
                                                       strict=True))]
        return pd.concat(frames, ignore_index=True)

    to_frame = excitability_frame

    def spectrum_frame(self) -> pd.DataFrame:
        """Tidy energy spectra: the segment's key columns, ``direction`` (1-based), ``S``,
        ``excited``, ``ne``."""
        keys = self._segment_keys()
        frames = [ex.to_frame()[["direction", "S", "excited", "ne"]].assign(
                      **{k: v[i] for k, v in keys.items()})
                  for i, ex in enumerate(self.excitability)]
        return pd.concat(frames, ignore_index=True)

    def sensability_frame(self, k: float = 2.0) -> pd.DataFrame:
        """Long table over time (:func:`physical_bands`): ``t``, ``state``, ``s``, ``sigma``,
        ``nr``, ``lower``, ``upper`` (the physical ``k``-sigma band), plus the key columns of
        the segment holding each epoch (NaN or "" outside the segments; an epoch on a
        boundary belongs to the later segment)."""
        frame = physical_bands(self.sensability, k)
        t = self.sensability.t
        index = np.full(t.size, -1)
        for i, (a, b) in enumerate(self.segments):
            index[in_segment(t, a, b)] = i
        index = np.repeat(index, len(self.state_names))
        for name, values in self._segment_keys().items():
            values = np.asarray(values)
            fill = np.nan if values.dtype.kind in "iuf" else ""
            frame[name] = np.where(index >= 0, values[index], fill)
        return frame

    def state_table(self) -> pd.DataFrame:
        """:meth:`excitability_frame` with, per (segment, state), ``s_fraction`` (share of the
        segment's epochs with ``s >= s_threshold``), ``sensible`` (``s_fraction >=
        min_fraction``), ``sigma_start``, ``sigma_end`` (physical posterior 1-sigma at the
        segment's first and last epoch, SI) and their ``sigma_ratio``."""
        long = self.excitability_frame()
        se = self.sensability
        s_ok = se.s >= self.settings["s_threshold"]
        fraction, start, end = [], [], []
        for a, b in self.segments:
            sel = self.epochs(a, b)
            fraction.append(s_ok[sel].mean(axis=0))
            start.append(se.sigma[sel[0]])
            end.append(se.sigma[sel[-1]])
        long["s_fraction"] = np.concatenate(fraction)
        long["sensible"] = long["s_fraction"] >= self.settings["min_fraction"]
        long["sigma_start"] = np.concatenate(start)
        long["sigma_end"] = np.concatenate(end)
        long["sigma_ratio"] = long["sigma_end"] / long["sigma_start"]
        return long

    def summary(self) -> pd.DataFrame:
        """One row per segment: its key columns, limits, ``n_epochs``, ``ne``, and the states
        it could estimate by each metric: ``excitable`` and ``sensible`` (comma-separated
        state names at the thresholds), with their counts."""
        table = self.state_table()
        n = len(self.state_names)
        keys = self._segment_keys()
        rows = []
        for i, (a, b) in enumerate(self.segments):
            part = table.iloc[i * n:(i + 1) * n]
            excitable = part.loc[part["excitable"], "state"].tolist()
            sensible = part.loc[part["sensible"], "state"].tolist()
            rows.append({**{k: v[i] for k, v in keys.items()}, "t_start": a, "t_end": b,
                         "n_epochs": self.epochs(a, b).size, "ne": int(part["ne"].iloc[0]),
                         "n_excitable": len(excitable), "excitable": ", ".join(excitable) or "-",
                         "n_sensible": len(sensible), "sensible": ", ".join(sensible) or "-"})
        return pd.DataFrame(rows)

    # ----- re-reading

    def _segment_changes(self, segments) -> dict:
        """The fields that change with new ``segments`` (None: none), checked."""
        if segments is None:
            return {}
        return {"segments": check_segments(segments, self.model.t, _span(self.trajectory))}

    def with_settings(self, segments=None, *, eta: float | None = None,
                      nu: float | None = None, d0: str | None = None,
                      e_threshold: float | None = None, s_threshold: float | None = None,
                      min_fraction: float | None = None):
        """The same model with other segments, thresholds or D0 choice (None keeps each).

        New segments or a new ``d0`` redo the small per-segment SVDs; a new ``eta`` only
        re-thresholds them (:meth:`ExcitabilityResult.with_eta`), a new ``nu`` the stored
        eigen-decompositions (:meth:`SensabilityResult.with_nu`).
        """
        given = {"eta": eta, "nu": nu, "e_threshold": e_threshold, "s_threshold": s_threshold,
                 "min_fraction": min_fraction}
        th = check_thresholds(**{**self.thresholds,
                                 **{k: v for k, v in given.items() if v is not None}})
        d0 = self.settings["d0"] if d0 is None else _d0(d0)
        changes = self._segment_changes(segments)
        if changes or d0 != self.settings["d0"]:
            ex = excitability_segments(self.model, changes.get("segments", self.segments),
                                       th["eta"], d0, self.sensability, _span(self.trajectory))
        else:
            ex = tuple(e.with_eta(th["eta"]) for e in self.excitability)
        se = self.sensability if th["nu"] == self.sensability.nu else \
            self.sensability.with_nu(th["nu"])
        return replace(self, **changes, excitability=ex, sensability=se,
                       settings={**self.settings, **th, "d0": d0})

    def with_eta(self, eta: float):
        """Same analysis with another eta (no new SVD)."""
        return self.with_settings(eta=eta)

    def with_nu(self, nu: float):
        """Same analysis with another nu (no new eigen-decomposition)."""
        return self.with_settings(nu=nu)


def _span(trajectory) -> tuple[float, float] | None:
    """First and last time of ``trajectory`` (None without one: the model epochs bound)."""
    return None if trajectory is None else (float(trajectory.t[0]), float(trajectory.t[-1]))


def _d0(d0) -> str:
    if d0 not in D0_CHOICES:
        raise NavlibInputError(f"d0: expected one of {D0_CHOICES}, got {d0!r}")
    return d0
