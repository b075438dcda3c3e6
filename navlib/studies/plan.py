"""Plan a mission before it flies: which states will the filter estimate, and when?

The assessment of a recorded flight (:mod:`navlib.studies.assess`) applied to the
trajectory a mission file describes (:func:`navlib.trajectory.from_mission`) instead of a
fitted one::

    mission file  ->  trajectory (exact IMU)  ->  21-state ECEF model at the GNSS epochs,
    without measurements inside the outage windows  ->  segments (navlib.segmentation)
    ->  excitability per segment, sensability over time (navlib.metrics)

:func:`plan_mission` returns a :class:`MissionPlan`: a
:class:`~navlib.studies.assess.FlightAssessment` (same segment table, summary, figures and
``with_settings``) with the mission, its outage windows and a :meth:`MissionPlan.timeline` of
when each state first becomes excitable and sensible. A GNSS outage is modelled as epochs
whose measurement matrix is zero (no information), so the covariance recursion runs through
it on the IMU alone (assumption M6). ``python -m navlib plan`` writes the plans' summary and
pages with :mod:`navlib.reports.fleet`; :func:`plan_point` is the picklable evaluation of a
trade study through :func:`navlib.sweep.sweep`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import ClassVar

import numpy as np
import pandas as pd

from navlib import sensors
from navlib._validation import finite_scalar, reject_unknown
from navlib.errors import NavlibInputError
from navlib.metrics import E_THRESHOLD, MIN_FRACTION, S_THRESHOLD, check_thresholds
from navlib.models.baro import aided_model, without_gnss
from navlib.models.ecef import ecef21_at_epochs
from navlib.segmentation import SEGMENT_DEFAULTS, segment_flight
from navlib.studies.assess import (
    MODEL_STEP_S,
    FlightAssessment,
    automatic_segment_table,
    describe_inputs,
    segment_pairs,
)
from navlib.studies.assess.aiding import sigma_note
from navlib.trajectory.mission import Mission, from_mission, load_mission, with_values

__all__ = ["VEHICLE_PRESETS", "MissionPlan", "plan_beside_flight", "plan_mission", "plan_point",
           "timeline_reading", "trade_reading"]

VEHICLE_PRESETS = {"rocket": "motionpak_tactical", "multicopter": "pixhawk_mems",
                   "fixed-wing": "pixhawk_mems", "ground": "pixhawk_mems"}
"""Sensor preset of a mission that names none: the tactical-grade unit of the rocket study
for rockets, the Pixhawk-class MEMS for the others."""
TRANSIENT_S = 5.0
"""Start-up transient left out of the timeline's sensability columns, s (the reading of the
rocket study's "weakly sensible" counts, ``navlib.studies.rocket.TRANSIENT_S``)."""
DEFAULT_GNSS_RATE_HZ = 1.0
"""GNSS rate when neither the mission, the call nor the preset gives one, Hz."""
DEFAULT_GNSS_SIGMA_M = 5.0
"""GNSS position sigma when neither the mission, the call nor the preset gives one, m."""

_SI_UNITS = {"position": "m", "velocity": "m/s", "attitude": "rad", "gyro_bias": "rad/s",
             "acc_bias": "m/s^2", "gyro_scale": "1", "acc_scale": "1"}


def _fit_columns() -> pd.DataFrame:
    return pd.DataFrame(columns=["quantity", "axis", "rms", "unit", "white_noise"])


@dataclass(frozen=True, eq=False)
class MissionPlan(FlightAssessment):
    """A :class:`~navlib.studies.assess.FlightAssessment` of a planned trajectory.

    ``fit`` is empty and the residual frames are None (nothing was fitted); ``inputs``
    describes the planned IMU samples and the GNSS epochs outside the outages.

    Attributes
    ----------
    mission : Mission
        The checked mission (:func:`navlib.trajectory.mission.load_mission`).
    outages : tuple of (float, float)
        GNSS outage windows of the model, s.
    """

    mission: Mission | None = None
    outages: tuple = ()
    TRANSIENT_S: ClassVar[float] = TRANSIENT_S

    def outage_mask(self, t) -> np.ndarray:
        """True at the times ``t`` inside an outage window."""
        t = np.asarray(t, dtype=float)
        out = np.zeros(t.shape, dtype=bool)
        for a, b in self.outages:
            out |= (t >= a) & (t <= b)
        return out

    def timeline(self, transient_s: float = TRANSIENT_S) -> pd.DataFrame:
        """When each state becomes excitable and sensible, one row per state (model order).

        Columns: ``state``, ``paper_id``, ``group``, ``excitable_from_s`` (start of the first
        segment where ``e >= e_threshold``; NaN: never), ``excitable_segments`` (those
        segments), ``sensible_from_s`` (first epoch after the start-up transient with
        ``s >= s_threshold``; NaN: never), ``sensible_share`` (share of the epochs after
        the transient with it), ``sensible_share_outage`` (the same inside the outage
        windows; NaN without outages), ``sigma_end`` (posterior 1-sigma at the last
        epoch) and its SI ``unit`` (m, m/s, rad, rad/s, m/s^2, 1; the same in navigation
        axes and data-sheet units, per segment: :meth:`states_table`). The first
        ``transient_s`` seconds are left out of the sensability columns: at the first
        epochs the information is still the normalised prior, in which every state looks
        sensible (assumption M6).
        """
        transient_s = finite_scalar(transient_s, "transient_s", 0.0)
        table = self.state_table()
        names = list(self.state_names)
        se = self.sensability
        after = se.t >= se.t[0] + transient_s
        if not after.any():
            raise NavlibInputError(f"transient_s: {transient_s:g} s covers the whole mission")
        ok = (se.s >= self.settings["s_threshold"]) & after[:, None]
        inside = self.outage_mask(se.t) & after
        rows = []
        for j, name in enumerate(names):
            part = table[table["state"] == name]
            exc = part[part["excitable"]]
            first = np.flatnonzero(ok[:, j])
            rows.append({
                "state": name, "paper_id": part["paper_id"].iloc[0],
                "group": part["group"].iloc[0],
                "excitable_from_s": float(exc["t_start"].min()) if len(exc) else np.nan,
                "excitable_segments": ", ".join(f"{r.segment} {r.phase}"
                                                for r in exc.itertuples()) or "-",
                "sensible_from_s": float(se.t[first[0]]) if first.size else np.nan,
                "sensible_share": float(ok[after, j].mean()),
                "sensible_share_outage": float(ok[inside, j].mean()) if inside.any()
                else np.nan,
                "sigma_end": float(se.sigma[-1, j]), "unit": _SI_UNITS[part["group"].iloc[0]]})
        return pd.DataFrame(rows)


def _gnss_settings(mission: Mission, spec, gnss_rate_hz, gnss_sigma_m):
    gnss = getattr(spec, "gnss", None)
    rate = gnss_rate_hz if gnss_rate_hz is not None else mission.gnss_rate_hz
    if rate is None:
        rate = gnss.rate_hz if gnss is not None and gnss.rate_hz else DEFAULT_GNSS_RATE_HZ
    sigma = gnss_sigma_m if gnss_sigma_m is not None else mission.gnss_sigma_m
    if sigma is None:
        sigma = gnss.position_sigma if gnss is not None and gnss.position_sigma > 0 \
            else DEFAULT_GNSS_SIGMA_M
    return (finite_scalar(rate, "gnss_rate_hz", 0.0, low_open=True),
            finite_scalar(sigma, "gnss_sigma_m", 0.0, low_open=True))


def _check_outages(outages, t_end: float, where: str) -> tuple:
    out = []
    for i, pair in enumerate(outages):
        if not isinstance(pair, Sequence) or isinstance(pair, str) or len(pair) != 2:
            raise NavlibInputError(f"outages[{i}]: expected (start_s, end_s), got {pair!r}")
        a = finite_scalar(pair[0], f"outages[{i}] start_s", 0.0)
        b = finite_scalar(pair[1], f"outages[{i}] end_s", a, low_open=True)
        if a >= t_end:
            raise NavlibInputError(f"{where} outages[{i}]: starts at {a:g} s, after the "
                                   f"mission ends ({t_end:.6g} s)")
        out.append((a, b))
    return tuple(sorted(out))


def _planned_records(trajectory, model) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The planned IMU samples and the GNSS epochs that carry a measurement, as the
    readers' frames (for :func:`navlib.studies.assess.describe_inputs`)."""
    frame = trajectory.to_frame()
    imu = frame[["t", "f_x", "f_y", "f_z", "w_x", "w_y", "w_z"]]
    k = np.searchsorted(frame["t"].to_numpy(), np.asarray(model.t)[model.measured])
    gnss = frame.iloc[k][["t", "x", "y", "z"]].reset_index(drop=True)
    return imu, gnss


def plan_mission(mission, sensors_preset: str | None = None, *, changes: Mapping | None = None,
                 outages=None, gnss_rate_hz: float | None = None,
                 gnss_sigma_m: float | None = None, segments=None, eta: float = 1e-3,
                 nu: float = 0.985, e_threshold: float = E_THRESHOLD,
                 s_threshold: float = S_THRESHOLD, min_fraction: float = MIN_FRACTION,
                 segment_options: Mapping | None = None, model_options: Mapping | None = None,
                 model_step_s: float | None = MODEL_STEP_S,
                 aiding: str | None = None) -> MissionPlan:
    """Which states a mission lets the filter estimate, segment by segment and over time.

    Parameters
    ----------
    mission : str, Path, mapping or Mission
        A mission file, an example name (``navlib.trajectory.mission.list_missions()``), a
        mapping or a loaded :class:`~navlib.trajectory.mission.Mission`.
    sensors_preset : str, optional
        Sensor preset name or file; None: the mission's ``sensors``, else
        :data:`VEHICLE_PRESETS` of its vehicle class.
    changes : mapping, optional
        Mission values to change first (:func:`navlib.trajectory.mission.with_values`:
        ``{"rocket.spin_hz": 1.0}``).
    outages : sequence of (start_s, end_s), optional
        GNSS outage windows; None: the mission's ``[gnss] outages``.
    gnss_rate_hz, gnss_sigma_m : float, optional
        GNSS rate and position sigma of the model; None: the mission's, else the preset's,
        else :data:`DEFAULT_GNSS_RATE_HZ` / :data:`DEFAULT_GNSS_SIGMA_M`.
    segments, eta, nu, e_threshold, s_threshold, min_fraction, segment_options, \
model_options, model_step_s
        As in :func:`navlib.studies.assess.assess_flight`.
    aiding : {"gnss", "baro", "gnss+baro"}, optional
        What aids the IMU (:func:`navlib.models.baro.aided_model`: GNSS position; the
        barometer and the pad's zero velocity; GNSS north/east with the barometer). None:
        the mission's ``[gnss] aiding``, else ``gnss``. Outages remove the GNSS rows only.

    Returns
    -------
    MissionPlan

    Raises
    ------
    NavlibInputError
        A bad mission (naming the key, phase or waypoint), an unknown preset, outage
        windows that do not fit the mission, bad thresholds or segments.
    """
    thresholds = check_thresholds(eta, nu, e_threshold, s_threshold, min_fraction)
    if changes:
        table = with_values(mission, changes)
        where = mission.where if isinstance(mission, Mission) else "mission"
        mission = load_mission(table)
        mission = replace(mission, where=where)
    elif not isinstance(mission, Mission):
        mission = load_mission(mission)
    preset = sensors_preset or mission.sensors or VEHICLE_PRESETS[mission.vehicle]
    if not isinstance(preset, str):
        raise NavlibInputError(f"sensors_preset: expected a preset name or file, got "
                               f"{preset!r}")
    spec = sensors.load_preset(preset)
    segment_options = dict(segment_options or {})
    reject_unknown(segment_options, SEGMENT_DEFAULTS, "segment_options")
    model_options = dict(model_options or {})
    if "gnss_sigma_m" in model_options:
        raise NavlibInputError("model_options: pass gnss_sigma_m as its own keyword")
    if model_step_s is not None:
        model_step_s = finite_scalar(model_step_s, "model_step_s", 0.0, low_open=True)

    trajectory = from_mission(mission)
    rate, sigma = _gnss_settings(mission, spec, gnss_rate_hz, gnss_sigma_m)
    rate = min(rate, trajectory.rate_hz)
    windows = _check_outages(mission.outages if outages is None else outages,
                             float(trajectory.t[-1]), mission.where)
    model = ecef21_at_epochs(trajectory, rate, sensors=preset, gnss_sigma_m=sigma,
                             max_step_s=model_step_s, **model_options)
    aiding = aiding if aiding is not None else mission.table.get("gnss", {}).get("aiding",
                                                                                 "gnss")
    model = aided_model(model, trajectory, aiding, gnss_sigma_m=sigma)
    t_model = np.asarray(model.t)
    inside = np.zeros(t_model.size, dtype=bool)
    for a, b in windows:
        inside |= (t_model >= a) & (t_model <= b)
    model = without_gnss(model, inside)
    if not model.measured.any():
        raise NavlibInputError("outages: cover every GNSS epoch of the mission; nothing "
                               "would be measured")

    seg_opts = dict(segment_options)
    seg_opts["min_duration_s"] = max(seg_opts.get("min_duration_s", 2.0), 2.0 / rate)
    automatic = segment_flight(trajectory, vehicle=mission.vehicle, **seg_opts)
    table, merged = automatic_segment_table(
        automatic.segments if segments is None else segments, model, automatic, trajectory.t,
        automatic_segments=segments is None)
    imu, gnss = _planned_records(trajectory, model)
    notes = [f"sensor preset {preset!r}: " + ("given" if sensors_preset else
                                              "the mission's" if mission.sensors else
                                              f"default for a {mission.vehicle}"),
             f"planned trajectory of mission {mission.name!r} ({mission.where}); nothing "
             "fitted, the IMU is exact"]
    notes += [f"GNSS outage {a:g}-{b:g} s: no GNSS measurement at the model epochs inside"
              for a, b in windows]
    notes += merged
    if aiding != "gnss":
        notes.append(sigma_note(model, trajectory, aiding))
    options = {"preset": preset, "gnss_rate_hz": rate, "gnss_sigma_m": sigma, "aiding": aiding,
               "outages": windows, "vehicle": mission.vehicle, "mission": mission.name,
               "segment_options": seg_opts, "model_options": model_options,
               "model_step_s": model_step_s, "imu_rate_hz": trajectory.rate_hz,
               "heading_deg": None}
    settings = {"attitude_error": model_options.get("attitude_error", "ecef"),
                "preset": preset, "gnss_sigma_m": sigma}
    return MissionPlan.build(
        model, segment_pairs(table), trajectory=trajectory, **thresholds, settings=settings,
        inputs=describe_inputs(imu, gnss), fit=_fit_columns(), automatic=automatic,
        segment_table=table, options=options, notes=tuple(notes), mission=mission,
        outages=windows)


# --------------------------------------------------------------------------- planned beside flown


def _by_phase(analysis) -> dict:
    """Phase -> (segment labels, excitable states, sensible states) of an analysis, over all
    its segments of that phase (a state counts when it qualifies in any of them)."""
    table = analysis.state_table()
    out = {}
    for phase in dict.fromkeys(analysis.segment_table["phase"]):
        part = table[table["phase"] == phase]
        segs = analysis.segment_table[analysis.segment_table["phase"] == phase]
        out[phase] = (
            [f"{r.t_start:.4g}-{r.t_end:.4g} s" for r in segs.itertuples(index=False)],
            [s for s in analysis.state_names if part.loc[part["state"] == s, "excitable"].any()],
            [s for s in analysis.state_names if part.loc[part["state"] == s, "sensible"].any()])
    return out


def plan_beside_flight(plan: MissionPlan, flight: FlightAssessment) -> pd.DataFrame:
    """Which states the plan expected to be estimable and which the flight delivered, per
    phase (a planned mission beside the recorded flight of the same vehicle).

    One row per phase found in either (plan phases first): ``phase``, ``planned_segments``,
    ``flown_segments`` (their spans), ``planned_excitable``, ``flown_excitable``,
    ``planned_sensible``, ``flown_sensible`` (comma-separated states that are excitable or
    sensible in at least one segment of that phase, at each analysis's own thresholds),
    ``sensible_only_planned`` and ``sensible_only_flown`` (the differences). A phase
    missing on one side shows ``-`` there.

    Parameters
    ----------
    plan : MissionPlan
        Result of :func:`plan_mission`.
    flight : FlightAssessment
        Result of :func:`~navlib.studies.assess.assess_flight` for the same vehicle.

    Returns
    -------
    pandas.DataFrame

    Raises
    ------
    NavlibInputError
        If either is of the wrong type or their models' states differ.
    """
    if not isinstance(plan, MissionPlan):
        raise NavlibInputError(f"plan: expected a MissionPlan (plan_mission), got "
                               f"{type(plan).__name__}")
    if not isinstance(flight, FlightAssessment):
        raise NavlibInputError(f"flight: expected a FlightAssessment (assess_flight), got "
                               f"{type(flight).__name__}")
    if list(plan.state_names) != list(flight.state_names):
        raise NavlibInputError("flight: its model's states differ from the plan's; compare "
                               "assessments of the same (21-state ECEF) model")
    planned, flown = _by_phase(plan), _by_phase(flight)
    none = ([], [], [])

    def text(names):
        return ", ".join(names) or "-"

    rows = []
    for phase in dict.fromkeys([*planned, *flown]):
        p_seg, p_exc, p_sen = planned.get(phase, none)
        f_seg, f_exc, f_sen = flown.get(phase, none)
        rows.append({"phase": phase, "planned_segments": text(p_seg),
                     "flown_segments": text(f_seg), "planned_excitable": text(p_exc),
                     "flown_excitable": text(f_exc), "planned_sensible": text(p_sen),
                     "flown_sensible": text(f_sen),
                     "sensible_only_planned": text([x for x in p_sen if x not in f_sen]),
                     "sensible_only_flown": text([x for x in f_sen if x not in p_sen])})
    return pd.DataFrame(rows)


# --------------------------------------------------------------------------- trade study


def plan_point(mission, sensors_preset: str | None = None, spin_hz: float | None = None,
               outage_start_s: float | None = None, outage_s: float = 0.0,
               s_threshold: float = S_THRESHOLD, e_threshold: float = E_THRESHOLD,
               min_fraction: float = MIN_FRACTION, model_step_s: float | None = MODEL_STEP_S
               ) -> dict:
    """One point of a mission trade study (a picklable evaluation for
    :func:`navlib.sweep.sweep`).

    ``spin_hz`` changes a rocket's ``[rocket] spin_hz``; ``outage_start_s`` with
    ``outage_s > 0`` replaces the mission's outages by that one window. Returns
    ``n_excitable`` / ``n_sensible`` (states excitable or sensible in at least one segment),
    ``n_sensible_end`` (states with ``s >= s_threshold`` at the last epoch) and, per
    state, ``share_<state>`` (share of epochs sensible) and ``sigma_end_<state>`` (SI).

    Parameters
    ----------
    mission : Mission, Mapping or path-like
        The mission.
    sensors_preset : str or None, optional
        Sensor preset; None: the mission's.
    spin_hz : float or None, optional
        Rocket roll rate, Hz; None: the mission's.
    outage_start_s : float or None, optional
        Start of the one GNSS outage, s.
    outage_s : float, optional
        Its length, s (0: the mission's outages).
    s_threshold, e_threshold : float, optional
        Sensability and excitability thresholds.
    min_fraction : float, optional
        Smallest share of a segment's epochs with ``s >= s_threshold`` for a state to count as
        sensible in it.
    model_step_s : float or None, optional
        Step of the error model, s.

    Returns
    -------
    dict
    """
    changes = {"rocket.spin_hz": spin_hz} if spin_hz is not None else None
    outages = None
    if outage_start_s is not None and outage_s > 0:
        outages = [(outage_start_s, outage_start_s + outage_s)]
    plan = plan_mission(mission, sensors_preset, changes=changes, outages=outages,
                        s_threshold=s_threshold, e_threshold=e_threshold,
                        min_fraction=min_fraction, model_step_s=model_step_s)
    table = plan.state_table()
    timeline = plan.timeline()
    se = plan.sensability
    out = {"n_excitable": int(table.groupby("state")["excitable"].any().sum()),
           "n_sensible": int(table.groupby("state")["sensible"].any().sum()),
           "n_sensible_end": int((se.s[-1] >= s_threshold).sum())}
    for row in timeline.itertuples(index=False):
        out[f"share_{row.state}"] = row.sensible_share
        out[f"sigma_end_{row.state}"] = row.sigma_end
    return out


def timeline_reading(plans: Mapping[str, object], last: int = 3) -> str:
    """When the states of each planned mission become sensible.

    Parameters
    ----------
    plans : mapping
        Mission name -> plan (:func:`navlib.studies.plan.plan_mission`), read through its
        ``timeline()`` (assumption M6: the start-up transient is left out) and ``outages``.
    last : int
        How many of the latest states to become sensible are named.

    Returns
    -------
    str
        Per mission: how many states become sensible at some epoch, the ``last`` ones to
        do so and those that never do; for a mission with GNSS outages, the share of the
        epochs with the position states sensible inside the outages against the mission.
    """
    lines = []
    for name, plan in plans.items():
        tl = plan.timeline()
        never = tl[tl["sensible_from_s"].isna()]["state"].tolist()
        late = tl.dropna(subset=["sensible_from_s"]).sort_values("sensible_from_s").tail(last)
        lines.append(f"{name}: {len(tl) - len(never)} of {len(tl)} states become sensible at "
                     f"some epoch; last to do so: "
                     + ", ".join(f"{r.state} at {r.sensible_from_s:.1f} s"
                                 for r in late.itertuples())
                     + (f"; never: {', '.join(never)}" if never else ""))
        if plan.outages:
            pos = tl[tl["group"] == "position"]
            lines.append(f"    inside the outage(s) the position states are sensible at "
                         f"{100 * pos['sensible_share_outage'].mean():.0f}% of the epochs "
                         f"against {100 * pos['sensible_share'].mean():.0f}% over the mission")
    return "\n".join(lines)


def trade_reading(trade: pd.DataFrame) -> str:
    """The sensor trade study of one mission (``sweep`` of ``plan_point`` over
    ``sensors_preset``): the preset with the smallest final heading-axis sigma
    (``sigma_end_theta_z``, rad) and the number of states sensible at the end per preset."""
    best = trade.sort_values("sigma_end_theta_z").iloc[0]
    return (f"smallest final heading-axis sigma: {best.sensors_preset} "
            f"({best.sigma_end_theta_z:.3g} rad); states sensible at the end per preset: "
            + ", ".join(f"{r.sensors_preset} {r.n_sensible_end}" for r in trade.itertuples()))
