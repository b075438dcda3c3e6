"""The metrics of a discretised model over time segments, and the thresholds that read them.

:func:`sensability_model`, :func:`excitability_segment` and :func:`excitability_segments`
feed a :class:`~navlib.models.DiscreteModel` to the metrics (segments of docs/assumptions.md A12,
the D0 choice of A19); :func:`check_segments` and :func:`in_segment` define which epochs a segment
stacks; :func:`check_thresholds` and the defaults :data:`E_THRESHOLD`, :data:`S_THRESHOLD`,
:data:`MIN_FRACTION` read the results.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from navlib._validation import finite_array, finite_scalar
from navlib.errors import NavlibInputError
from navlib.metrics._arrays import check_d0, check_eta, check_nu
from navlib.metrics.excitation import ExcitabilityResult, excitability
from navlib.metrics.sensing import SensabilityResult, sensability

__all__ = ["E_THRESHOLD", "LOW", "MIN_FRACTION", "S_THRESHOLD", "THRESHOLD_KEYS",
           "check_discrete_model", "check_segments", "check_thresholds", "excitability_segment",
           "excitability_segments", "in_segment", "sensability_model"]


def _model_P0(model, P0) -> np.ndarray:
    if P0 is not None:
        return P0
    if getattr(model, "P0", None) is None:
        raise NavlibInputError("P0: the model has no default P0; pass one")
    return model.P0


def check_discrete_model(model) -> None:
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

    Parameters
    ----------
    model : DiscreteModel
        Supplies ``t``, ``F``, ``Q``, ``H``, ``R`` and ``state_names``.
    P0 : ndarray (n, n), optional
        Covariance at the first epoch used (default ``model.P0``).
    nu : float in (0, 1]
        Threshold of Def. 1 (docs/assumptions.md A11).
    prior_update : bool
        Whether ``P0`` is a prior updated at the first epoch (docs/assumptions.md A9; see
        :func:`sensability`).
    t_start, t_end : float, optional
        Keep the epochs in ``[t_start, t_end]`` (s); ``P0`` applies at the first of them.

    Returns
    -------
    SensabilityResult
    """
    check_discrete_model(model)
    if t_start is not None or t_end is not None:
        model = model.window(model.t[0] if t_start is None else t_start,
                             model.t[-1] if t_end is None else t_end)
    return sensability(model.F, model.H, model.Q, model.R, _model_P0(model, P0), nu=nu,
                       prior_update=prior_update, state_names=model.state_names, t=model.t)


def _filter_variances(P_filter, model, P0, k: int, t_a: float) -> np.ndarray:
    """Variances at model epoch ``k`` (time ``t_a``) from a filter covariance (docs/assumptions.md
    A19)."""
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
        (docs/assumptions.md A12).
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
    check_discrete_model(model)
    d0 = check_d0(d0)
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

    Parameters
    ----------
    model : DiscreteModel
        The discretised model.
    segments : sequence of (float, float)
        ``(t_start, t_end)`` pairs (s).
    eta : float in (0, 1)
        Energy threshold of the excited subspace (docs/assumptions.md A14).
    d0 : {"global", "filter"}
        D0 from ``P0`` or from the filter covariance at each segment start (docs/assumptions.md
        A19).
    sensability : SensabilityResult, optional
        Of the same model, reused for ``d0="filter"``.
    span : (float, float), optional
        Interval the segments must lie in (default the model epochs).

    Returns
    -------
    tuple of ExcitabilityResult
        One per segment.
    """
    check_discrete_model(model)
    segs = check_segments(segments, model.t, span)
    return tuple(excitability_segment(model, a, b, eta=eta, d0=d0, P_filter=sensability)
                 for a, b in segs)


# ----------------------------------------------------------------- thresholds, segments


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

    Parameters
    ----------
    eta : float in (0, 1)
        Excitability energy threshold (A14).
    nu : float in (0, 1]
        Sensability threshold (Def. 1, A11).
    e_threshold, s_threshold, min_fraction : float in [0, 1]
        The reading shares (:data:`E_THRESHOLD`, :data:`S_THRESHOLD`,
        :data:`MIN_FRACTION`).

    Returns
    -------
    dict
        ``{key: float}`` for the keys of :data:`THRESHOLD_KEYS`.

    Raises
    ------
    NavlibInputError
        Naming the first value that is not finite or lies outside its range.
    """
    return {"eta": check_eta(eta), "nu": check_nu(nu),
            "e_threshold": finite_scalar(e_threshold, "e_threshold", 0.0, 1.0),
            "s_threshold": finite_scalar(s_threshold, "s_threshold", 0.0, 1.0),
            "min_fraction": finite_scalar(min_fraction, "min_fraction", 0.0, 1.0)}


def in_segment(t, t_start: float, t_end: float, open_start: bool = False) -> np.ndarray:
    """Boolean mask of the times ``t`` in the closed segment ``[t_start, t_end]`` (1 ns
    tolerance; ``(t_start, t_end]`` with ``open_start``), the epochs a segment stacks (A12).

    Parameters
    ----------
    t : array_like
        Times (s).
    t_start, t_end : float
        Segment bounds (s).
    open_start : bool, optional
        Leave out a time at ``t_start``.

    Returns
    -------
    ndarray of bool, shaped like ``t``
    """
    t = np.asarray(t, dtype=float)
    low = t > t_start + _TOL if open_start else t >= t_start - _TOL
    return low & (t <= t_end + _TOL)


def check_segments(segments, t, span=None) -> tuple[tuple[float, float], ...]:
    """``segments`` as ``(t_start, t_end)`` float pairs, each inside ``span`` (default the
    first and last of the epochs ``t``) and holding at least two epochs of ``t``.

    Parameters
    ----------
    segments : sequence of (float, float)
        ``(t_start, t_end)`` pairs (s).
    t : array_like
        The model epochs (s).
    span : (float, float), optional
        Interval the segments must lie in.

    Returns
    -------
    tuple of (float, float)

    Raises
    ------
    NavlibInputError
        For no segments, a malformed pair, or a segment outside ``span`` or holding fewer
        than two epochs (naming it).
    """
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
