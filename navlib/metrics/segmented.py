"""The paper's whole analysis of one discretised model (España et al. §4-6).

:class:`SegmentedAnalysis`: excitability per segment, sensability per epoch, the thresholds
that read them (eta, nu and the shares :data:`~navlib.metrics.E_THRESHOLD`,
:data:`~navlib.metrics.S_THRESHOLD`, :data:`~navlib.metrics.MIN_FRACTION`), tidy frame
views and :meth:`SegmentedAnalysis.with_settings`, which re-reads other segments or
thresholds on the same model. The rocket study
(:class:`navlib.studies.rocket.RocketAnalysis`) and the flight assessment
(:class:`navlib.studies.assess.FlightAssessment`) are thin subclasses.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from navlib.metrics._arrays import check_d0
from navlib.metrics.segments import (
    E_THRESHOLD,
    MIN_FRACTION,
    S_THRESHOLD,
    THRESHOLD_KEYS,
    check_discrete_model,
    check_segments,
    check_thresholds,
    excitability_segments,
    in_segment,
    sensability_model,
)
from navlib.metrics.sensing import SensabilityResult, physical_bands

__all__ = ["SegmentedAnalysis"]


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
        check_discrete_model(model)
        th = check_thresholds(eta, nu, e_threshold, s_threshold, min_fraction)
        d0 = check_d0(d0)
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
        """Indices of the model epochs in ``[t_a, t_b]`` (``(t_a, t_b]`` with ``open_start``).

        Parameters
        ----------
        t_a, t_b : float
            Interval bounds (s, the model's clock).
        open_start : bool, optional
            Leave out an epoch at ``t_a``.

        Returns
        -------
        ndarray of int
        """
        return np.flatnonzero(in_segment(self.model.t, t_a, t_b, open_start))

    def at(self, t_s: float) -> int:
        """Index of the model epoch nearest the time ``t_s``, s."""
        return int(np.argmin(np.abs(self.model.t - t_s)))

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

        Parameters
        ----------
        segments : sequence of (float, float), optional
            New ``(t_start, t_end)`` segments (s).
        eta, nu, d0, e_threshold, s_threshold, min_fraction : optional
            New thresholds and D0 choice, as in :meth:`build` (checked by
            :func:`check_thresholds`).

        Returns
        -------
        SegmentedAnalysis
            Of the same class as ``self``, sharing the model.
        """
        given = {"eta": eta, "nu": nu, "e_threshold": e_threshold, "s_threshold": s_threshold,
                 "min_fraction": min_fraction}
        th = check_thresholds(**{**self.thresholds,
                                 **{k: v for k, v in given.items() if v is not None}})
        d0 = self.settings["d0"] if d0 is None else check_d0(d0)
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
