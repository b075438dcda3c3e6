"""The result of an assessment (:class:`FlightAssessment`) and its segment table."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from navlib.errors import NavlibInputError
from navlib.metrics import (
    SegmentedAnalysis,
    in_segment,
)
from navlib.models.ecef import PAPER_IDS, STATE_GROUPS
from navlib.segmentation import (
    Segmentation,
    segments_table,
)
from navlib.studies.assess import states
from navlib.studies.assess.agreement import AGREEMENT_COLUMNS, segment_agreement

__all__ = ["FlightAssessment", "automatic_segment_table", "segment_pairs", "with_agreement"]

_GROUP_OF = {name: group for group, names in STATE_GROUPS.items() for name in names}


def _label(row) -> str:
    return f"{int(row.segment)} {row.phase} {row.t_start:.4g}-{row.t_end:.4g} s"


@dataclass(frozen=True, eq=False)
class FlightAssessment(SegmentedAnalysis):
    """Everything :func:`assess_flight` computed, with tidy views.

    A :class:`navlib.metrics.SegmentedAnalysis` (``model``: the 21-state ECEF model
    discretised at the GNSS epochs; ``trajectory``: the fitted reference trajectory, exact
    IMU, ``parameters["fit_residuals"]``; ``segments``; ``excitability`` one per segment in
    the order of ``segment_table``; ``sensability`` over the whole flight, ``P0`` at the
    first epoch; ``settings`` and ``thresholds``: ``eta``, ``nu``, ``e_threshold``,
    ``s_threshold``, ``min_fraction``) whose segments carry the flight phases, with:

    Attributes
    ----------
    inputs : DataFrame
        :func:`describe_inputs` of the records.
    fit : DataFrame
        :func:`fit_report` of the residuals.
    automatic : Segmentation
        The automatic segmentation (features and phases), whatever segments were used.
    segment_table : DataFrame
        The segments assessed: ``segment`` (1-based), ``phase``, ``t_start``, ``t_end``,
        ``duration``, ``n_epochs`` (GNSS epochs of the model inside that a kept fix aids)
        and the fit's agreement with the records
        (:func:`~navlib.studies.assess.agreement.segment_agreement`):
        ``fit_f_rms`` (m/s^2), ``fit_w_rms`` (rad/s), ``fit_gnss_rms`` (m), ``represented``
        and ``fit_reason`` (empty when represented). The excitability and sensability of a
        segment that is not represented describe a motion that was not flown: the long
        frames and :meth:`summary` carry ``valid = represented``.
    options : dict
        Assumed values: ``preset``, ``gnss_rate_hz``, ``gnss_sigma_m``, fit and segmentation
        options, model options.
    gnss_residuals, imu_residuals : DataFrame
        Fit residuals over time (:func:`fit_residuals`); a flight aided by its barometer
        adds ``baro_dynamic_m`` to the GNSS frame, the static-pressure error expected of
        each barometric row at the reference's speed (docs/assumptions.md B7).
    notes : tuple of str
        Assumptions and fallbacks taken (preset, initial attitude, levelling window, bridged
        holes, excluded samples, an assumed heading, a split record).
    spans : tuple of FlightAssessment
        When the record was split at long holes: every span's assessment in time order
        (this one among them); empty otherwise.
    quality : DataFrame or None
        The data-quality findings of the whole record (:func:`navlib.io.quality.check_records`:
        saturated IMU samples, frozen, disagreeing or jumping GNSS fixes, all dropped
        before the fit); each ``message`` was also issued as a
        :class:`~navlib.io.FlightDataWarning`.
    gnss_outages : DataFrame or None
        Spans without a kept GNSS fix longer than ``[gnss] outage_report_s`` of
        ``data/quality.toml`` (:func:`navlib.studies.assess.outages.gnss_outages`:
        ``t_start``, ``t_end``, ``duration``, s). The model has no measurement at the epochs
        no kept fix aids, whatever their length (assumption Q5).
    logged : dict
        What the reader attached beside the IMU, inside the flight, for comparison with the
        reference: ``baro`` (``t, alt_m``), ``tilt`` (``t, tilt``: body x from vertical,
        rad), ``attitude`` (``t, qw, qx, qy, qz``, body -> NED); keys the log lacks are
        absent.

    Every time (``segment_table``, the trajectory, the model epochs, the residuals, the
    automatic segmentation) is on the result's clock: seconds since a rocket's ignition, since
    the record's first sample for other vehicles; :attr:`t_ignition` (``options["t_zero"]``)
    is that zero on the log's own clock (:mod:`navlib.studies.assess.clock`).

    The long frames name each segment by ``segment`` (1-based) and ``phase``, and each state
    by ``state``, ``paper_id`` (e1..e21) and ``group``; the wide
    :meth:`~navlib.metrics.SegmentedAnalysis.excitability_table` labels its columns
    ``"<segment> <phase> <t_start>-<t_end> s"``; :meth:`to_frame` is the per-segment
    :meth:`~navlib.metrics.SegmentedAnalysis.summary`.
    """

    inputs: pd.DataFrame
    fit: pd.DataFrame
    automatic: Segmentation
    segment_table: pd.DataFrame
    options: dict = field(default_factory=dict)
    gnss_residuals: pd.DataFrame | None = None
    imu_residuals: pd.DataFrame | None = None
    notes: tuple[str, ...] = ()
    spans: tuple = ()
    quality: pd.DataFrame | None = None
    gnss_outages: pd.DataFrame | None = None
    logged: dict = field(default_factory=dict)

    @property
    def vehicle(self) -> str:
        """The vehicle class whose words name the phases (``options["vehicle"]``)."""
        return self.options.get("vehicle", "")

    @property
    def t_ignition(self) -> float:
        """A rocket's ignition on the log's own clock, s: the zero of every time of this
        result (:mod:`navlib.studies.assess.clock`); NaN when the zero is the first sample
        (other vehicles, a record without boost) or the times are the mission's own."""
        if self.options.get("time_zero") == "ignition":
            return float(self.options["t_zero"])
        return float("nan")

    @property
    def events(self) -> pd.DataFrame | None:
        """A rocket's events (ignition, burnout, apogee, main deployment, landing), logged
        by its flight computer and detected from the kinematics side by side, on this
        result's clock (:func:`navlib.segmentation.logged.flight_events`); None for other
        vehicles."""
        events = getattr(self.automatic, "events", None)
        return None if events is None else events.copy()

    @property
    def labels(self) -> tuple[str, ...]:
        return tuple(_label(r) for r in self.segment_table.itertuples(index=False))

    def _segment_keys(self) -> dict:
        return {"segment": self.segment_table["segment"].to_numpy(),
                "phase": self.segment_table["phase"].to_numpy()}

    def _state_columns(self) -> dict:
        return {**super()._state_columns(),
                "paper_id": [PAPER_IDS[s] for s in self.state_names],
                "group": [_GROUP_OF[s] for s in self.state_names]}

    def to_frame(self) -> pd.DataFrame:
        """The per-segment :meth:`~navlib.metrics.SegmentedAnalysis.summary`."""
        return self.summary()

    def states_table(self, log: str = "") -> pd.DataFrame:
        """How well each state is known, one row per segment x state in navigation axes and
        units (position and velocity north/east/down, roll/pitch/yaw, IMU errors per body
        axis; m, m/s, deg, deg/h, mg, ppm): :func:`navlib.studies.assess.states.states_table`,
        the table ``python -m navlib assess`` writes to ``states.csv``."""
        return states.states_table(self, log)

    def _agreement(self, column: str, default) -> dict:
        """``segment -> segment_table[column]``; ``default`` for every segment of a table
        without it (a planned motion is the motion by construction)."""
        table = self.segment_table
        values = table[column] if column in table.columns else [default] * len(table)
        return dict(zip(table["segment"], values, strict=True))

    def _validity(self, frame: pd.DataFrame) -> pd.DataFrame:
        frame["valid"] = frame["segment"].map(self._agreement("represented", True)).astype(bool)
        return frame

    def excitability_frame(self) -> pd.DataFrame:
        """:meth:`~navlib.metrics.SegmentedAnalysis.excitability_frame` with ``valid``: the
        segment is represented by the reference motion (``segment_table``), so its numbers
        describe the flight flown."""
        return self._validity(super().excitability_frame())

    def summary(self) -> pd.DataFrame:
        """:meth:`~navlib.metrics.SegmentedAnalysis.summary` with ``valid`` (as in
        :meth:`excitability_frame`) and ``fit_reason``."""
        frame = self._validity(super().summary())
        frame["fit_reason"] = frame["segment"].map(self._agreement("fit_reason", ""))
        return frame

    def _segment_changes(self, segments) -> dict:
        """``segments`` as in :func:`assess_flight` (None keeps the current ones; ``"auto"``
        returns to the automatic segmentation)."""
        if segments is None:
            return {}
        if isinstance(segments, str) and segments == "auto":
            segments = self.automatic.segments
        table = _segment_table(segments, self.model, self.automatic, self.trajectory.t)
        if self.imu_residuals is not None:
            table, _ = with_agreement(table, self.trajectory, self.imu_residuals,
                                      self.gnss_residuals, self.options["fit_bounds"])
        return {"segment_table": table, "segments": segment_pairs(table)}


def with_agreement(table, trajectory, imu_residuals, gnss_residuals, bounds):
    """``table`` with the :data:`~navlib.studies.assess.agreement.AGREEMENT_COLUMNS` of
    :func:`~navlib.studies.assess.agreement.segment_agreement`, and its messages.

    Parameters
    ----------
    table : DataFrame
        The segment table (:func:`automatic_segment_table`).
    trajectory : Trajectory
        The fitted reference motion.
    imu_residuals, gnss_residuals : DataFrame
        Recorded minus reference (:func:`~navlib.studies.assess.fit.fit_residuals`).
    bounds : dict
        The ``[fit]`` bounds (:func:`~navlib.studies.assess.agreement.fit_bounds`).

    Returns
    -------
    table : DataFrame
        ``table`` with the agreement columns (any old ones replaced).
    messages : list of str
        One warning per segment that is not represented.
    """
    columns, messages = segment_agreement(table, trajectory, imu_residuals, gnss_residuals,
                                          bounds)
    table = table.drop(columns=[c for c in AGREEMENT_COLUMNS if c in table.columns])
    return pd.concat([table.reset_index(drop=True), columns], axis=1), messages


def segment_pairs(table: pd.DataFrame) -> tuple[tuple[float, float], ...]:
    return tuple((float(a), float(b)) for a, b in zip(table["t_start"], table["t_end"],
                                                      strict=True))


def _segment_table(segments, model, automatic: Segmentation, t_flight) -> pd.DataFrame:
    """Normalise ``segments`` (inside the fitted flight ``t_flight``) and count the model
    epochs with a measurement each holds (at least 2 needed; epochs inside a GNSS outage do
    not count, assumption Q5; the last epoch may precede the flight's end)."""
    table = segments_table(segments, float(t_flight[0]), float(t_flight[-1]), automatic)
    counts = _epoch_counts(table, np.asarray(model.t)[model.measured])
    for k, (count, row) in enumerate(zip(counts, table.itertuples(index=False), strict=True)):
        if count < 2:
            raise NavlibInputError(
                f"segments: segment {k + 1} ({row.phase}, {row.t_start:.6g}..{row.t_end:.6g} s)"
                f" holds {count} GNSS epoch(s) of the model; each segment needs at least 2 "
                f"(epochs every {np.median(np.diff(model.t)):.3g} s)")
    table.insert(0, "segment", np.arange(1, len(table) + 1))
    table["n_epochs"] = counts
    return table


def _epoch_counts(table: pd.DataFrame, t) -> list[int]:
    """Model epochs at ``t`` inside each segment."""
    return [int(np.count_nonzero(in_segment(t, a, b)))
            for a, b in zip(table["t_start"], table["t_end"], strict=True)]


def _joined_phase(first: str, second: str) -> str:
    """The phase of two joined segments in time order: ``"boost+coast"`` (the words of both,
    once each), so a boost inside a GNSS outage is still named where the flight starts."""
    words = [*str(first).split("+"), *str(second).split("+")]
    return "+".join(dict.fromkeys(words))


def automatic_segment_table(segments, model, automatic: Segmentation, t_flight, *,
                            automatic_segments: bool) -> tuple[pd.DataFrame, list[str]]:
    """:func:`_segment_table` of ``segments``, with each automatic segment that holds fewer
    than two measured epochs of the model (a short phase between GNSS fixes, or one inside a
    GNSS outage: rows of ``model.H`` that are zero) joined to the segment before it (after
    it, for the first; the joined segment takes both phase words, :func:`_joined_phase`), with
    a note: excitability needs measurements (assumptions V1, M6).
    Segments the user gave (``automatic_segments=False``) are refused instead, naming the
    segment. Returns the table and the notes."""
    t = np.asarray(model.t)
    measured = model.measured
    table = segments_table(segments, float(t_flight[0]), float(t_flight[-1]), automatic)
    entries = [[r.phase, float(r.t_start), float(r.t_end)]
               for r in table.itertuples(index=False)]
    notes = []
    k = 0
    while k < len(entries) and len(entries) > 1:
        phase, a, b = entries[k]
        count = int(np.count_nonzero(measured & in_segment(t, a, b)))
        if count >= 2:
            k += 1
            continue
        outage = count < np.count_nonzero(in_segment(t, a, b))
        why = ("lies inside a GNSS outage (no measurement, no excitability)" if outage else
               f"holds {count} GNSS epoch(s) of the model; each segment needs at least 2")
        if not automatic_segments:
            raise NavlibInputError(f"segments: segment {k + 1} ({phase}, {a:.6g}..{b:.6g} s) "
                                   f"{why}; join it to a neighbour")
        other = k - 1 if k > 0 else k + 1
        notes.append(f"segment {phase} {a:.6g}-{b:.6g} s {why}: joined to the "
                     f"{entries[other][0]} segment next to it")
        lo, hi = min(k, other), max(k, other)
        entries[lo] = [_joined_phase(entries[lo][0], entries[hi][0]), entries[lo][1],
                       entries[hi][2]]
        del entries[hi]
        k = lo
    return _segment_table([tuple(e) for e in entries], model, automatic, t_flight), notes

