"""How a filter recovers from an injected outlier (Beaudoin et al. 2018 §4.2;
docs/assumptions.md, launcher.md §6.4): the numeric verdict the paper lacks.

Recovery score (:func:`score_recovery`; the outliers are those of
:mod:`navlib.sensors.faults`). For a watched
scalar (or vector, scored by its Euclidean norm) let ``d(t)`` be the **outlier-induced
error**: the estimation error of the faulty run minus that of the nominal run with the same
noise. In the linear mode ``d`` is exact and noise-independent (it is the noise-free
response); in the EKF mode it is the difference of two runs with the same seeds. With the
outlier time ``t_o``, the recovery window ``W`` and the averaging length ``Delta``:

* ``peak = max |d(t)|`` over ``[t_o, t_o + W]``;
* ``residual = mean |d(t)|`` over ``[t_o + W - Delta, t_o + W]`` — the error left after
  the recovery window;
* ``retained = residual / peak``;
* ``residual_vs_pre = residual / e_pre`` with ``e_pre`` the RMS nominal estimation error
  over ``[t_o - Delta, t_o)`` (Monte-Carlo RMS, or the filter sigma when no runs are given);
* ``residual_vs_3sigma = residual / (3 sigma(t_o + W))``.

Classification: **"recovers"** when ``retained <= exp(-1)``, i.e. the injected error
decayed by at least one e-folding within the window — equivalently the effective time
constant ``tau = W / ln(1 / retained)`` is at most the window; otherwise **"static
error"**. The threshold is a property of the decay, not of the paper's outcomes: an
observable state corrected by a filter of bandwidth ``1/tau_f`` loses ``1 - exp(-W/tau_f)``
of the injected error, a weakly observable one keeps almost all of it (``tau`` of several
windows). ``recovered_fraction`` changes the threshold. The two ratios say how the left-over
error compares with the error the filter had anyway and with its own 3-sigma: a static error
below ``e_pre`` is invisible in a single noisy run, one above 3 sigma is a filter that is
confidently wrong. A channel the
solution does not have (e.g. ``rt_x`` for INS/GPS) gives ``peak = 0`` and the verdict
``"unaffected"``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from navlib._validation import finite_array, finite_scalar
from navlib.errors import NavlibInputError

__all__ = ["VERDICT_CLASSES", "RecoveryScore", "score_recovery", "scores_frame"]

VERDICT_CLASSES = ("recovers", "static error", "unaffected")


@dataclass(frozen=True)
class RecoveryScore:
    """Numeric outcome of one outlier test on one watched quantity (module docstring).

    Attributes
    ----------
    peak, residual : float
        Largest and final (window-averaged) outlier-induced error, in the quantity's unit.
    retained : float
        ``residual / peak`` (NaN when unaffected).
    time_constant : float
        Effective decay time ``window / ln(1 / retained)``, s (inf when nothing decayed).
    pre_error : float
        RMS nominal error just before the outlier.
    sigma_end : float
        Filter sigma at the end of the recovery window.
    residual_vs_pre, residual_vs_3sigma : float
    verdict : str
        ``"recovers"``, ``"static error"`` or ``"unaffected"``.
    t_outlier, window, recovered_fraction : float
        The settings used.
    """

    peak: float
    residual: float
    retained: float
    time_constant: float
    pre_error: float
    sigma_end: float
    residual_vs_pre: float
    residual_vs_3sigma: float
    verdict: str
    t_outlier: float
    window: float
    recovered_fraction: float

    def as_dict(self) -> dict:
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


def _norm(x) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    return np.abs(x) if x.ndim == 1 else np.linalg.norm(x, axis=-1)


def score_recovery(t, induced, *, t_outlier: float, window: float, sigma=None,
                   nominal_error=None, averaging: float = 1.0,
                   recovered_fraction: float = float(np.exp(-1.0)),
                   unaffected_tol: float = 0.0
                   ) -> RecoveryScore:
    """Score how an outlier-induced error decays (definition in the module docstring).

    Parameters
    ----------
    t : ndarray (K,)
        Times, s.
    induced : ndarray (K,) or (K, p)
        Outlier-induced error ``d(t)`` of the watched quantity (a vector is scored by its
        Euclidean norm).
    t_outlier, window : float
        Outlier time and recovery window, s; the window is clipped to the data.
    sigma : ndarray (K,) or (K, p), optional
        Filter standard deviation of the watched quantity (root-sum-square for a vector).
    nominal_error : ndarray, optional
        Nominal (outlier-free) estimation errors laid out like ``induced`` with an optional
        run axis after time: (K,) or (K, R) for a scalar, (K, p) or (K, R, p) for a
        vector. Their RMS over
        ``[t_o - averaging, t_o)`` is ``e_pre``. Without it ``e_pre`` is the sigma there.
    averaging : float
        ``Delta``, s: length of the final averaging window and of the pre-outlier window.
    recovered_fraction : float
        Threshold on ``retained`` for "recovers" (default ``exp(-1)``: one e-folding).
    unaffected_tol : float
        Peaks at or below this value count as "unaffected".
    """
    t = finite_array(t, "t", ndim=1)
    d = _norm(induced)
    if d.shape != t.shape:
        raise NavlibInputError(f"induced: expected {t.size} samples, got shape {d.shape}")
    t_outlier = finite_scalar(t_outlier, "t_outlier")
    window = finite_scalar(window, "window", 0.0, low_open=True)
    averaging = finite_scalar(averaging, "averaging", 0.0, low_open=True)
    recovered_fraction = finite_scalar(recovered_fraction, "recovered_fraction", 0.0, 1.0,
                                       low_open=True)
    if not t[0] <= t_outlier < t[-1]:
        raise NavlibInputError(f"t_outlier: {t_outlier} s is outside the data "
                               f"[{t[0]:g}, {t[-1]:g}) s")
    t_end = min(t_outlier + window, float(t[-1]))
    window = t_end - t_outlier
    during = (t >= t_outlier - 1e-9) & (t <= t_end + 1e-9)
    final = (t >= t_end - averaging - 1e-9) & (t <= t_end + 1e-9)
    before = (t >= t_outlier - averaging - 1e-9) & (t < t_outlier - 1e-9)
    peak = float(d[during].max())
    residual = float(d[final].mean())
    k_end = int(np.flatnonzero(t <= t_end + 1e-9)[-1])
    sig = None
    if sigma is not None:
        sig = np.asarray(sigma, dtype=float)
        sig = sig if sig.ndim == 1 else np.sqrt(np.sum(sig**2, axis=-1))
        if sig.shape != t.shape:
            raise NavlibInputError(f"sigma: expected {t.size} samples, got {sig.shape}")
    sigma_end = float(sig[k_end]) if sig is not None else np.nan
    if nominal_error is not None:
        e = np.asarray(nominal_error, dtype=float)
        vector = np.ndim(induced) == 2
        if e.shape[0] != t.size or e.ndim not in ((2, 3) if vector else (1, 2)):
            raise NavlibInputError(
                f"nominal_error: expected ({t.size}[, R]{', p' if vector else ''}), got "
                f"{e.shape}"
            )
        e = _norm(e) if vector else np.abs(e)               # (K,) or (K, R)
        pre = float(np.sqrt(np.mean(e[before] ** 2))) if before.any() else np.nan
    elif sig is not None and before.any():
        pre = float(np.sqrt(np.mean(sig[before] ** 2)))
    else:
        pre = np.nan
    with np.errstate(divide="ignore", invalid="ignore"):
        retained = residual / peak if peak > 0 else np.nan
        tau = (window / np.log(1.0 / retained) if 0 < retained < 1
               else (0.0 if retained == 0 else np.inf)) if peak > 0 else np.nan
        vs_pre = residual / pre if pre > 0 else np.nan
        vs_3s = residual / (3.0 * sigma_end) if sigma_end > 0 else np.nan
    if peak <= unaffected_tol:
        verdict = "unaffected"
    elif retained <= recovered_fraction:
        verdict = "recovers"
    else:
        verdict = "static error"
    return RecoveryScore(peak, residual, float(retained), float(tau), pre, sigma_end,
                         float(vs_pre),
                         float(vs_3s), verdict, t_outlier, window, recovered_fraction)


def scores_frame(scores: dict) -> pd.DataFrame:
    """Table of named :class:`RecoveryScore` objects, one row each."""
    return pd.DataFrame([{"case": name, **s.as_dict()} for name, s in scores.items()])
