"""Excitability of navigation states (España, Carrizo & Giribet 2019, Eqs. 17-22, Defs. 3-4).

:func:`excitability` takes the SVD of the normalised extended observability matrix
``O~ = [H~0; H~1 F~0; ...]`` (corrected Eq. 11, docs/assumptions.md A10); the energy
spectrum ``S(u^i) = n sigma^i / tr M``; ``ne`` from ``eta`` (A14); ``e^j`` = norm of the
projection of the canonical vector ``e_j`` on the excited subspace ``span{u^i : i < ne}``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from navlib.errors import NavlibInputError
from navlib.metrics._arrays import (
    check_eta,
    check_state_names,
    check_system,
    fix_signs,
    frame_names,
    normalising_variances,
    spd,
    whiten,
)
from navlib.observability import observability_matrix

__all__ = ["ExcitabilityResult", "excitability"]


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
        First 1-based index with ``S[i] <= eta`` (``n + 1`` when none, docs/assumptions.md A14); the
        excited subspace is ``span{u^i : i < ne}``.
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
        eta = check_eta(eta)
        ne, e = _excited(self.S, self.U, eta)
        return replace(self, eta=eta, ne=ne, e=e)

    def to_frame(self) -> pd.DataFrame:
        """One row per index j: ``state``, its excitability ``e``, and the j-th direction of
        the spectrum (``direction`` = j, 1-based; ``sigma``, ``S``, ``excited`` = j < ne),
        plus ``eta``, ``ne`` and the segment limits."""
        n = self.n
        return pd.DataFrame({
            "state": frame_names(self.state_names, n),
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
    """``ne`` (docs/assumptions.md A14) and ``e^j = sqrt(sum_{i<ne} U[j, i]^2)`` (Def. 4)."""
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
        Measurement matrices at the N epochs (all are stacked, docs/assumptions.md A12).
    P0 : array (n, n)
        Symmetric positive-definite covariance whose diagonal gives ``D0`` (Eq. 11).
    R0 : array (m, m)
        Symmetric positive-definite normalising measurement covariance (may be non-diagonal).
    eta : float in (0, 1)
        Energy threshold: ``ne`` is the first 1-based ``i`` with ``S[i] <= eta`` (A14).
    state_names : sequence of str, optional
    d0 : array (n,) or (n, n), optional
        Variances (or a covariance whose diagonal is used) for ``D0`` instead of ``diag(P0)``,
        e.g. the filter covariance at the segment start (docs/assumptions.md A19, option B).

    Returns
    -------
    ExcitabilityResult

    Notes
    -----
    Normalisation per the corrected Eq. 11 (docs/assumptions.md A10): ``F~ = D0^-1/2 F D0^1/2``,
    ``H~ = R0^-1/2 H D0^1/2``. ``O~ = [H~0; H~1 F~0; H~2 F~1 F~0; ...]`` is stacked by
    :func:`navlib.observability.observability_matrix`, reduced by QR and decomposed by SVD
    (full right basis also when ``N m < n``), never by eigenvalues of
    ``O~' O~`` whose spectrum spans tens of decades (docs/assumptions.md A12). ``sigma^i`` are the
    squared singular values (zero-padded when ``N m < n``), ``S = n sigma / sum(sigma)`` (Eq. 19).
    """
    F, H = check_system(F, H)
    n, m = F.shape[-1], H.shape[1]
    P0 = spd(P0, "P0", n)
    R0 = spd(R0, "R0", m)
    eta = check_eta(eta)
    names = check_state_names(state_names, n)
    d = normalising_variances(d0, P0)
    sqrt_d = np.sqrt(d)

    F_n = F * sqrt_d / sqrt_d[:, None]
    H_n = whiten(H, np.broadcast_to(R0, (H.shape[0], m, m)), sqrt_d)
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
    U = fix_signs(Vh.T)
    ne, e = _excited(S, U, eta)
    return ExcitabilityResult(e=e, S=S, U=U, ne=ne, sigma=sigma, eta=eta, O=O, d0=d,
                              state_names=names)
