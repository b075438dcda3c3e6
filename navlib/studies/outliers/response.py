"""The outlier-induced error of one solution: the prepared linear filters of the launcher
configurations (:class:`FilterCache`), the watched quantities, the exact noise-free response
(:func:`outlier_response`) and the study's result object (:class:`OutlierStudy`)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from navlib import cache as disk_cache
from navlib.errors import NavlibInputError
from navlib.filters import LinearFilter, prepare_linear
from navlib.filters.linear import recorded_epochs, unit_responses
from navlib.filters.recovery import RecoveryScore, score_recovery
from navlib.models.launcher import SOLUTIONS, launcher
from navlib.sensors.faults import Outlier
from navlib.studies.claims import claims_frame
from navlib.studies.outliers.paper import PAPER_TESTS
from navlib.trajectory import launcher_ascent

__all__ = ["DEFAULTS", "RT_ONLY_OPTIONS", "WATCHES", "CovarianceSummary", "FilterCache",
           "OutlierResponse", "OutlierStudy", "UnitResponse", "adopt_filters", "default_trajectory",
           "effective_bias_model", "outlier_response", "record_stride", "watch_rows"]

WATCHES = ("roll", "pitch", "yaw", "bp", "ref_roll")
"""Watched quantities: body-axis attitude errors (``T_E^B psi``), the GPS position bias
(3 ECEF components, scored by their norm) and the launcher divergence roll ``psi_ref_x``."""

DEFAULTS = {"biases": "GAP", "bias_model": "markov", "window": 100.0, "averaging": 1.0}
"""Study defaults (:mod:`navlib.studies.outliers`)."""
_DISK_SCOPE = "navlib.studies.outliers"
"""The on-disk scope of the prepared filters (:class:`navlib.cache.Scope`): the study's name,
unchanged since the study became a package, so the kept filters stay valid."""


def default_trajectory(quick: bool = False):
    """The launcher ascent (150 s, 200 Hz); ``quick``: 80 s at 20 Hz for smoke runs."""
    return launcher_ascent(duration_s=80.0, rate_hz=20.0) if quick else launcher_ascent()


class FilterCache:
    """Prepared linear filters (:class:`navlib.filters.LinearFilter`) by configuration, and
    what the study reads from them.

    One launcher configuration along a 150 s, 200 Hz trajectory holds about 0.8 GB of
    matrices (prepared with ``compact=True``), so the cache keeps at most ``size`` of them
    (least recently used dropped before a new one is prepared). What the figures and
    verdicts read from a filter is kept for every configuration, also after its filter was
    dropped, and shared with caches that adopt it (:func:`adopt_filters`): its
    :class:`CovarianceSummary` (taken when it is prepared) and the projected unit
    responses of :meth:`unit_responses` (a few MB each).
    """

    KEEP_RESPONSES = 256
    """Unit responses kept (oldest dropped first): a long-lived cache (a sweep, a panel)
    stays bounded."""

    def __init__(self, trajectory, size: int = 2, **model_options):
        self.trajectory = trajectory
        self.size = int(size)
        self.model_options = model_options
        self._items: dict = {}
        self._summaries: dict = {}
        self._responses: dict = {}
        # summaries and unit responses also go to the disk cache (navlib.cache), keyed by
        # the trajectory and the model options: the claims engine (notebook 00) reads
        # those notebook 05 computed, and a second report reads them all
        self._disk = disk_cache.Scope(_DISK_SCOPE, "FilterCache", trajectory, model_options)

    def get(self, solution: str, biases: str = "GAP", bias_model: str = "markov"
            ) -> LinearFilter:
        """The prepared linear filter of one configuration (prepared and kept when not known).

        Parameters
        ----------
        solution : str
            Solution name (``"ins_gps"``, ``"ins_gps_rt"`` ...).
        biases : str, optional
            Bias states, letters of ``"GAP"``.
        bias_model : str, optional
            ``"markov"`` or ``"random_walk"``.
        """
        key = (solution, biases, bias_model)
        if key in self._items:
            value = self._items.pop(key)
        else:
            while self._items and len(self._items) >= self.size:
                self._items.pop(next(iter(self._items)))
            model = launcher(solution, biases, bias_model, self.trajectory,
                             **self.model_options)
            value = prepare_linear(model, compact=True, own_model=True)   # model not kept
            if key not in self._summaries:
                self._summaries[key] = CovarianceSummary.of(value)
                self._disk.put(("summary", key), self._summaries[key])
        self._items[key] = value
        return value

    def release(self) -> None:
        """Drop the prepared filters (what was read from them stays): frees their memory
        before a computation that prepares others, e.g. :func:`assumption_sensitivity`."""
        self._items.clear()

    def summary(self, solution: str, biases: str = "GAP", bias_model: str = "markov"
                ) -> CovarianceSummary:
        """The :class:`CovarianceSummary` of one configuration (prepared when not known).

        Parameters
        ----------
        solution : str
            Solution name.
        biases : str, optional
            Bias states, letters of ``"GAP"``.
        bias_model : str, optional
            ``"markov"`` or ``"random_walk"``.
        """
        key = (solution, biases, bias_model)
        if key not in self._summaries:
            found, summary = self._disk.get(("summary", key))
            if found:
                self._summaries[key] = summary
            else:
                self.get(*key)
        return self._summaries[key]

    def _not_on_disk(self, keys: list) -> list:
        """``keys`` of unit responses not on disk either (those found there are kept)."""
        for w in keys:
            found, response = self._disk.get(("response", *w))
            if found:
                self._responses[w] = response
        return [w for w in keys if w not in self._responses]

    def unit_responses(self, solution: str, requests: Sequence[tuple[Outlier, str]], *,
                       biases: str = "GAP", bias_model: str = "markov",
                       record_every: int = 1, also: Sequence[tuple[Outlier, str]] = ()
                       ) -> list[UnitResponse]:
        """The :class:`UnitResponse` of each ``(outlier, watch)`` request on one solution,
        at every ``record_every``-th epoch (and the last).

        Responses not kept yet are computed together at every epoch, one filter
        recursion for all of them (:func:`navlib.filters.linear.unit_responses`), and
        kept; a record stride takes their epochs of
        :func:`navlib.filters.linear.recorded_epochs`, the same numbers a run recording
        only those epochs gives. The requests ``also`` join that recursion when it runs
        (their responses are kept, on disk too, not returned): they never prepare a filter
        by themselves, and a later reader of them (the claims engine reading what
        notebook 05 computed) then prepares none either.

        Parameters
        ----------
        solution : str
            Solution name.
        requests : sequence of (Outlier, str)
            Outlier and watched quantity of each response.
        biases : str, optional
            Bias states, letters of ``"GAP"``.
        bias_model : str, optional
            ``"markov"`` or ``"random_walk"``.
        record_every : int, optional
            Record stride, samples.
        also : sequence of (Outlier, str), optional
            Requests computed in the same recursion and kept, not returned.
        """
        config = (solution, biases, bias_model)
        wanted = [(config, _unit(o), watch) for o, watch in requests]
        missing = self._not_on_disk([w for w in dict.fromkeys(wanted) if w not in self._responses])
        if missing:
            extra = [(config, _unit(o), watch) for o, watch in also]
            missing += self._not_on_disk([w for w in dict.fromkeys(extra)
                                    if w not in self._responses and w not in missing])
            units = list(dict.fromkeys(w[1] for w in missing))
            sim = unit_responses(self.get(*config), units)
            C = self.trajectory.attitude.as_matrix()
            for watch in dict.fromkeys(w[2] for w in missing):
                truth, est, sigma = sim.project(watch_rows(watch, sim.state_names, C))
                for w in missing:
                    if w[2] == watch:
                        i = units.index(w[1])
                        self._responses[w] = UnitResponse(sim.t, truth[:, i], est[:, i],
                                                          sigma, sim.applied[i])
                        self._disk.put(("response", *w), self._responses[w])
        found = [self._responses[w].every(record_every) for w in wanted]
        while len(self._responses) > max(self.KEEP_RESPONSES, len(wanted)):
            self._responses.pop(next(iter(self._responses)))
        return found


@dataclass(frozen=True, eq=False)
class CovarianceSummary:
    """The parts of one filter's posterior covariance history that the covariance figures
    and verdicts read (Figs. 7, 10, 11 and :func:`sigma_ratios`), at every epoch.

    Attributes
    ----------
    t : ndarray (N,)
    state_names : tuple of str
    variances : ndarray (N, n)
        Diagonal of ``P_post``.
    attitude_names : tuple of str
        ``psi_x..z`` and, for the RT solutions, ``psi_ref_x..z``.
    attitude : ndarray (N, a, a)
        The block of ``P_post`` of those states.
    """

    t: np.ndarray
    state_names: tuple
    variances: np.ndarray
    attitude_names: tuple
    attitude: np.ndarray

    @classmethod
    def of(cls, prepared: LinearFilter) -> CovarianceSummary:
        cov = prepared.covariance
        names = tuple(cov.state_names)
        wanted = tuple(f"{g}_{a}" for g in ("psi", "psi_ref") for a in "xyz"
                       if f"{g}_{a}" in names)
        idx = np.array([names.index(s) for s in wanted])
        P = cov.P_post
        return cls(cov.t, names, np.diagonal(P, axis1=1, axis2=2).copy(), wanted,
                   P[:, idx[:, None], idx])

    def index(self, names: Sequence[str]) -> np.ndarray:
        """Positions of ``names`` in ``attitude_names``."""
        return np.array([self.attitude_names.index(s) for s in names])


@dataclass(frozen=True, eq=False)
class UnitResponse:
    """Noise-free response of one prepared filter to an outlier of unit magnitude, projected
    on a watched quantity (:meth:`FilterCache.unit_responses`).

    Attributes
    ----------
    t : ndarray (K,)
    truth, estimate : ndarray (K, p)
        The watched error state and its estimate per unit of the outlier's magnitude.
    sigma : ndarray (K, p)
        Filter standard deviation of the watched quantity (independent of the outlier).
    applied : bool
    """

    t: np.ndarray
    truth: np.ndarray
    estimate: np.ndarray
    sigma: np.ndarray
    applied: bool

    def every(self, record_every: int) -> UnitResponse:
        """The epochs a run with ``record_every`` records."""
        if int(record_every) == 1:
            return self
        k = recorded_epochs(self.t.size, record_every)
        return UnitResponse(self.t[k], self.truth[k], self.estimate[k], self.sigma[k],
                            self.applied)


def _unit(outlier: Outlier) -> Outlier:
    """``outlier`` with magnitude 1 (the key of its unit response)."""
    return replace(outlier, magnitude=1.0)


RT_ONLY_OPTIONS = ("a1_sign", "sigma_wind")
"""Launcher options that enter only the RT block (``psi_ref``, ``A1``, wind) of
:func:`navlib.models.launcher`: the non-RT solutions do not depend on them."""


def adopt_filters(cache: FilterCache, other: FilterCache) -> None:
    """Put into ``cache`` the prepared filters and unit responses of ``other`` that are the
    same models: all of them when both use the same trajectory and model options, the
    non-RT ones when the options differ only in :data:`RT_ONLY_OPTIONS`.

    Parameters
    ----------
    cache : FilterCache
        The cache filled.
    other : FilterCache
        The cache read.
    """
    if other.trajectory is not cache.trajectory:
        return
    a, b = cache.model_options, other.model_options
    differ = {k for k in a.keys() | b.keys() if k not in a or k not in b or a[k] != b[k]}
    if differ and not differ <= set(RT_ONLY_OPTIONS):
        return
    for key, value in other._items.items():
        if not differ or not key[0].endswith("_rt"):
            cache._items.setdefault(key, value)
    for key, value in other._summaries.items():
        if not differ or not key[0].endswith("_rt"):
            cache._summaries.setdefault(key, value)
    for key, value in other._responses.items():
        if not differ or not key[0][0].endswith("_rt"):
            cache._responses.setdefault(key, value)


def record_stride(trajectory, spacing_s: float = 0.02) -> int:
    """Samples between recorded epochs about ``spacing_s`` apart (at least 1).

    Parameters
    ----------
    trajectory : Trajectory
        The trajectory (its ``rate_hz``).
    spacing_s : float, optional
        Wanted spacing, s.
    """
    return max(1, round(spacing_s * trajectory.rate_hz))


def effective_bias_model(biases: str, bias_model: str) -> str:
    """``bias_model``, or "none" for a configuration without biases.

    Parameters
    ----------
    biases : str
        Bias states, letters of ``"GAP"`` (empty: none).
    bias_model : str
        ``"markov"`` or ``"random_walk"``.
    """
    return "none" if not biases else bias_model


def watch_rows(watch: str, state_names: Sequence[str], C_b_e) -> np.ndarray:
    """Rows ``c_k`` (K, p, n) with ``c_k' x`` the watched quantity at each epoch.

    ``roll``/``pitch``/``yaw``: the body-axis attitude error ``T_E^B psi`` (row i of
    ``C_b_e'`` on the ``psi`` states, docs/assumptions.md, launcher.md §6.2 item 6); ``bp``: the
    three GPS-bias states; ``ref_roll``: ``psi_ref_x``.

    Parameters
    ----------
    watch : str
        Watched quantity, one of :data:`WATCHES`.
    state_names : sequence of str
        The model's states.
    C_b_e : numpy.ndarray
        Body -> ECEF attitude per epoch, (K, 3, 3).

    Raises
    ------
    NavlibInputError
        If ``watch`` is unknown or the model lacks its states.
    """
    if watch not in WATCHES:
        raise NavlibInputError(f"watch: expected one of {WATCHES}, got {watch!r}")
    names = list(state_names)
    C_b_e = np.asarray(C_b_e)
    K, n = C_b_e.shape[0], len(names)

    def where(items):
        missing = [s for s in items if s not in names]
        if missing:
            raise NavlibInputError(f"watch {watch!r}: the model has no state(s) {missing}")
        return [names.index(s) for s in items]

    if watch in ("roll", "pitch", "yaw"):
        axis = ("roll", "pitch", "yaw").index(watch)
        rows = np.zeros((K, 1, n))
        rows[:, 0, where(["psi_x", "psi_y", "psi_z"])] = C_b_e[:, :, axis]
        return rows
    if watch == "bp":
        rows = np.zeros((K, 3, n))
        rows[:, [0, 1, 2], where(["bp_x", "bp_y", "bp_z"])] = 1.0
        return rows
    rows = np.zeros((K, 1, n))
    rows[:, 0, where(["psi_ref_x"])] = 1.0
    return rows


@dataclass(frozen=True, eq=False)
class OutlierResponse:
    """Noise-free response of one solution to one outlier (linear mode).

    Attributes
    ----------
    solution, watch : str
    outlier : Outlier
    applied : bool
        False when the solution has no such channel (e.g. RT outlier on INS/GPS).
    t : ndarray (K,)
    truth, estimate : ndarray (K, p)
        The watched error state and its estimate (both zero before the outlier).
    induced : ndarray (K, p)
        ``estimate - truth``: the outlier-induced estimation error (minus the residual
        navigation error it leaves after feedback).
    sigma : ndarray (K, p)
        Filter standard deviation of the watched quantity.
    score : RecoveryScore
    """

    solution: str
    watch: str
    outlier: Outlier
    applied: bool
    t: np.ndarray
    truth: np.ndarray
    estimate: np.ndarray
    induced: np.ndarray
    sigma: np.ndarray
    score: RecoveryScore

    def to_frame(self) -> pd.DataFrame:
        """Tidy ``t, component, truth, estimate, induced, sigma``."""
        K, p = self.truth.shape
        comp = np.arange(p)
        return pd.DataFrame({
            "t": np.repeat(self.t, p), "component": np.tile(comp, K),
            "truth": self.truth.ravel(), "estimate": self.estimate.ravel(),
            "induced": self.induced.ravel(), "sigma": self.sigma.ravel(),
            "solution": self.solution, "watch": self.watch,
        })


def outlier_response(solution: str, outlier: Outlier, watch: str = "roll", *,
                     trajectory=None, biases: str = DEFAULTS["biases"],
                     bias_model: str = DEFAULTS["bias_model"],
                     window: float = DEFAULTS["window"], averaging: float = DEFAULTS["averaging"],
                     record_every: int = 1, cache: FilterCache | None = None,
                     **model_options) -> OutlierResponse:
    """The exact outlier-induced error of one launcher solution (linear mode).

    The response is ``outlier.magnitude`` times the filter's response to the same outlier
    of unit magnitude (:meth:`FilterCache.unit_responses`, kept in ``cache``): the linear
    Kalman filter is linear in its inputs and its gains do not depend on the data, so the
    scaling is exact (up to rounding) and other magnitudes cost no new run.

    Parameters
    ----------
    solution : str
        One of the four launcher solutions.
    outlier : Outlier
    watch : str
        See :data:`WATCHES`.
    trajectory : Trajectory, optional
        Default :func:`default_trajectory`.
    biases, bias_model : str
        Launcher configuration (``biases=""`` forces ``bias_model="none"``).
    window, averaging : float
        Recovery window and averaging length of :func:`navlib.outliers.score_recovery`, s.
    record_every : int
        Keep every n-th epoch.
    cache : FilterCache, optional
        Reuse prepared filters (its trajectory and model options win).
    **model_options
        Passed to :func:`navlib.models.launcher` (``a1_sign``, ``sigma_wind``, ...).
    """
    if solution not in SOLUTIONS:
        raise NavlibInputError(f"solution: expected one of {SOLUTIONS}, got {solution!r}")
    bias_model = effective_bias_model(biases, bias_model)
    if cache is None:
        cache = FilterCache(trajectory if trajectory is not None else default_trajectory(),
                            size=1, **model_options)
    unit, = cache.unit_responses(solution, [(outlier, watch)], biases=biases,
                                 bias_model=bias_model, record_every=record_every)
    truth, est, sigma = outlier.magnitude * unit.truth, outlier.magnitude * unit.estimate, \
        unit.sigma
    induced = est - truth
    score = score_recovery(unit.t, induced if induced.shape[1] > 1 else induced[:, 0],
                           t_outlier=outlier.time, window=window,
                           sigma=sigma if sigma.shape[1] > 1 else sigma[:, 0],
                           averaging=averaging)
    return OutlierResponse(solution, watch, outlier, bool(unit.applied), unit.t, truth, est,
                           induced, sigma, score)


@dataclass(frozen=True, eq=False)
class OutlierStudy:
    """T1-T4 responses for each outlier shape, their scores and the claim verdicts.

    Attributes
    ----------
    responses : dict
        ``(test_id, solution, shape) -> OutlierResponse``.
    capture : dict
        T4 detail (Figs. 12-13): capture fractions and divergence ratio, see
        :func:`outlier_claims`.
    claims : list of ClaimResult
    settings : dict
    conclusions : dict
        ``(run, solution) -> OutlierResponse`` of the spike runs beyond T1-T4 that the
        paper's §4.2.4 and conclusions 1 and 3 need (:data:`~navlib.studies.outliers.
        experiment.CONCLUSION_RUNS`; empty unless asked for).
    """

    responses: dict
    capture: dict
    claims: list
    settings: dict = field(default_factory=dict)
    conclusions: dict = field(default_factory=dict)

    def table(self) -> pd.DataFrame:
        """One row per (test, solution, shape): the score, the paper's outcome and ours."""
        rows = []
        for (tid, sol, shape), r in self.responses.items():
            test = PAPER_TESTS[tid]
            reported = test.reported.get(sol, "")
            if shape == "divergence":
                reported = "underestimated after a fast capture"
            rows.append({"test": tid, "figure": test.figure, "solution": sol, "shape": shape,
                         "watch": r.watch, "paper": reported, **r.score.as_dict()})
        return pd.DataFrame(rows)

    def claims_frame(self) -> pd.DataFrame:
        return claims_frame(self.claims)
