"""How well each state is known, in navigation axes and units: the sigma table of an assessment.

The 21-state ECEF model (:mod:`navlib.models.ecef`) carries its error state in ECEF and SI:
``[dP^e, dV^e, psi^e, b_g, b_a, s_g, s_a]``. A navigation engineer reads it in the axes of
the vehicle and the units of a data sheet. :func:`states_table` rotates the posterior
covariance ``P_k`` of the sensability's Kalman recursion (the Joseph-form recursion of
:func:`navlib.metrics.sensability`, ``SensabilityResult.P``) at each model epoch ``k`` with
the block-diagonal ``T_k``:

* position and velocity errors to north, east, down: ``dP^n = C_e^n dP^e``,
  ``dV^n = C_e^n dV^e``, with ``C_e^n`` at the reference position of the epoch
  (:func:`navlib.earth.ned_to_ecef_matrix` transposed; the NED frame's own shift with the
  position error, about ``|dP| / R_earth`` rad, is neglected);
* the attitude error to roll, pitch and yaw: with ``attitude_error="ecef"`` the model's
  ``psi^e`` is the small rotation in ``C_b^e = (I + S(psi^e)) C_hat``; in NED it is
  ``psi^n = C_e^n psi^e`` (``C_b^n = (I + S(psi^n)) C_hat_b^n``), and the roll, pitch and yaw
  errors are its components about the body x, y and z axes,
  ``dtheta^b = C_n^b psi^n = C_e^b psi^e`` (``C_b^e = C_hat (I + S(dtheta^b))``). For a level
  vehicle these equal the errors of the Euler angles roll, pitch and yaw to first order
  (the Euler-rate matrix is the identity at zero roll and pitch); unlike Euler-angle errors
  they stay defined when the nose points up (a rocket on its rail, pitch 90 deg, where roll
  and yaw are not separable). With ``attitude_error="body"`` the model state is already
  ``dtheta^b``;
* the IMU errors stay in body axes (x, y, z; for a rocket x is along its axis and y, z are
  across it: ``_along``, ``_cross_y``, ``_cross_z``).

``sigma = sqrt(diag(T_k P_k T_k'))`` in m, m/s, deg, deg/h, mg and ppm (:data:`UNITS`), at a
segment's first and last model epoch. The relative measures are read along the same rows:
a navigation state ``c' x`` (a row ``c`` of ``T_k``) is the direction ``w = D0^1/2 c /
|D0^1/2 c|`` of the normalised state, its sensability at epoch ``k`` is
``||V_k[:, :nr_k]' w||`` (Eq. 16 for a direction; a row of the identity gives the model
state's own ``s``) and its excitability over a segment ``sqrt(mean_k ||U[:, :ne-1]' w_k||^2)``
over the segment's epochs (Def. 4; a row that does not turn within the segment gives
``||U[:, :ne-1]' w||``). ``excitable`` and ``sensible`` then use the assessment's
thresholds, as :meth:`navlib.metrics.SegmentedAnalysis.state_table` does for the model states
(``docs/assumptions.md`` V3).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from navlib import earth, units
from navlib.errors import NavlibInputError

__all__ = ["EXCITABLE_MARK", "NOT_REPRESENTED", "SENSIBLE_MARK", "STATES_COLUMNS", "UNITS",
           "how_well", "navigation_state_names", "navigation_transforms", "states_table"]

UNITS = {"position": ("m", 1.0), "velocity": ("m/s", 1.0), "attitude": ("deg", units.DEG),
         "gyro_bias": ("deg/h", units.DEG_PER_HOUR), "acc_bias": ("mg", units.MG),
         "gyro_scale": ("ppm", units.PPM), "acc_scale": ("ppm", units.PPM)}
"""Group -> (unit, its size in SI) of the navigation states, in model order."""

STATES_COLUMNS = ("log", "segment", "phase", "t_start", "t_end", "state", "group", "unit",
                  "sigma_start", "sigma_end", "reduction", "excitable", "sensible", "valid")
"""Columns of :func:`states_table` (and of ``states.csv``). ``valid``: the segment's reference
motion agrees with the records (``represented`` in the segment table, docs/assumptions.md
FIT1-FIT3; always true for a plan), so its numbers describe the flight flown."""

_AXES = {"body": ("x", "y", "z"), "rocket": ("along", "cross_y", "cross_z")}
_NED = ("north", "east", "down")


def navigation_state_names(vehicle: str | None = None) -> tuple[str, ...]:
    """The 21 navigation-state names in model order (``position_north`` ... ``yaw`` ...
    ``accel_scale_z``); a rocket's IMU errors are named along and across its axis."""
    axes = _AXES["rocket" if vehicle == "rocket" else "body"]
    return (*(f"position_{a}" for a in _NED), *(f"velocity_{a}" for a in _NED),
            "roll", "pitch", "yaw",
            *(f"{prefix}_{a}" for prefix in ("gyro_bias", "accel_bias", "gyro_scale",
                                             "accel_scale") for a in axes))


def _groups() -> list[str]:
    return [group for group in UNITS for _ in range(3)]


def navigation_transforms(analysis) -> np.ndarray:
    """``T_k`` (N, 21, 21) at the model epochs: model error state (ECEF, SI) -> navigation
    state (NED, body axes, SI); module docstring. The reference position and attitude are
    the trajectory's samples nearest each epoch."""
    model, trajectory = analysis.model, analysis.trajectory
    if trajectory is None:
        raise NavlibInputError("analysis: the navigation axes need the reference trajectory")
    if len(analysis.state_names) != 21:
        raise NavlibInputError(f"analysis: expected the 21-state ECEF model, got "
                               f"{len(analysis.state_names)} states")
    t_ref = np.asarray(trajectory.t, dtype=float)
    t = np.asarray(model.t, dtype=float)
    right = np.clip(np.searchsorted(t_ref, t), 1, t_ref.size - 1)
    nearest = np.where(np.abs(t_ref[right] - t) < np.abs(t - t_ref[right - 1]), right, right - 1)
    lat, lon, _ = earth.ecef_to_geodetic(np.asarray(trajectory.position)[nearest])
    C_e_n = np.swapaxes(earth.ned_to_ecef_matrix(lat, lon), -1, -2)
    T = np.zeros((t.size, 21, 21))
    T[:, 0:3, 0:3] = C_e_n
    T[:, 3:6, 3:6] = C_e_n
    if analysis.settings.get("attitude_error", "ecef") == "ecef":
        T[:, 6:9, 6:9] = np.swapaxes(trajectory.attitude[nearest].as_matrix(), -1, -2)
    else:
        T[:, 6:9, 6:9] = np.eye(3)
    T[:, 9:, 9:] = np.eye(12)
    return T


def _directions(T: np.ndarray, d0: np.ndarray) -> np.ndarray:
    """Rows of ``T`` as unit directions of the normalised state ``D0^-1/2 x``."""
    w = T * np.sqrt(d0)
    return w / np.linalg.norm(w, axis=-1, keepdims=True)


def states_table(analysis, log: str = "") -> pd.DataFrame:
    """One row per segment x navigation state: how well the state is known at the segment's
    start and end, and whether it is excitable and sensible there (module docstring).

    Parameters
    ----------
    analysis : FlightAssessment
        An assessment (:func:`~navlib.studies.assess.assess_flight`) or a mission plan.
    log : str
        The ``log`` column (the flight's file or the mission).

    Returns
    -------
    DataFrame
        :data:`STATES_COLUMNS`: ``log``, ``segment``, ``phase``, ``t_start``, ``t_end`` (s,
        the segment table's clock), ``state`` (:func:`navigation_state_names`), ``group``,
        ``unit``, ``sigma_start`` and ``sigma_end`` (1-sigma in ``unit`` at the segment's
        first and last model epoch), ``reduction`` (``1 - sigma_end / sigma_start``;
        negative when the uncertainty grew), ``excitable``, ``sensible``, ``valid``
        (:data:`STATES_COLUMNS`).
    """
    se = analysis.sensability
    settings = analysis.settings
    T = navigation_transforms(analysis)
    names = navigation_state_names(getattr(analysis, "vehicle", None))
    groups = _groups()
    unit_names = [UNITS[g][0] for g in groups]
    scale = np.array([UNITS[g][1] for g in groups])
    w_sens = _directions(T, se.d0)
    keep = np.arange(se.V.shape[-1])[None, :] < se.nr[:, None]
    table = analysis.segment_table
    valid = (table["represented"].to_numpy(dtype=bool) if "represented" in table.columns
             else np.ones(len(table), dtype=bool))
    frames = []
    for row, (a, b), ex, held in zip(table.itertuples(index=False), analysis.segments,
                                     analysis.excitability, valid, strict=True):
        sel = analysis.epochs(a, b)
        ends = sel[[0, -1]]
        P = np.einsum("kij,kjl,kil->ki", T[ends], se.P[ends], T[ends])
        sigma = np.sqrt(np.clip(P, 0.0, None)) / scale
        w_ex = _directions(T[sel], ex.d0)
        e = np.sqrt(np.mean(np.sum((w_ex @ ex.U[:, :ex.ne - 1]) ** 2, axis=-1), axis=0))
        s = np.linalg.norm(w_sens[sel] @ (se.V[sel] * keep[sel][:, None, :]), axis=-1)
        fraction = np.mean(s >= settings["s_threshold"], axis=0)
        frames.append(pd.DataFrame({
            "log": log, "segment": int(row.segment), "phase": row.phase,
            "t_start": float(row.t_start), "t_end": float(row.t_end), "state": names,
            "group": groups, "unit": unit_names, "sigma_start": sigma[0], "sigma_end": sigma[1],
            "reduction": 1.0 - sigma[1] / sigma[0], "excitable": e >= settings["e_threshold"],
            "sensible": fraction >= settings["min_fraction"], "valid": bool(held)}))
    return pd.concat(frames, ignore_index=True)[list(STATES_COLUMNS)]


SENSIBLE_MARK, EXCITABLE_MARK = "\u25cf", "\u25cb"
"""Marks of :func:`how_well`: sensible (the measurements pin the state down), excitable only
(the motion makes it observable, the measurements do not pin it down)."""
NOT_REPRESENTED = " (not represented)"
"""Ending of a :func:`how_well` segment heading whose reference motion departs from the
records."""


def how_well(states: pd.DataFrame) -> pd.DataFrame:
    """The compact "what this flight can estimate and how well" table of a
    :func:`states_table`: one row per navigation state (with its unit), the 1-sigma at the
    flight's start, then the 1-sigma at the end of each segment, written to three
    significant digits and marked :data:`SENSIBLE_MARK` where the state is sensible in that
    segment and :data:`EXCITABLE_MARK` where it is only excitable. A segment whose reference
    motion departs from the records (``valid`` false) gets no marks and a heading ending in
    :data:`NOT_REPRESENTED`: its verdicts would describe a motion that was not flown.

    Parameters
    ----------
    states : DataFrame
        A :func:`states_table` (one log).

    Returns
    -------
    DataFrame
        Columns ``state``, ``unit``, ``start``, then one per segment named
        ``"<segment> <phase> <t_start>..<t_end> s"``.
    """
    first = states[states["segment"] == states["segment"].iloc[0]]
    out = pd.DataFrame({"state": first["state"].to_numpy(), "unit": first["unit"].to_numpy(),
                        "start": [f"{v:.3g}" for v in first["sigma_start"]]})
    for (segment, phase, t0, t1), rows in states.groupby(
            ["segment", "phase", "t_start", "t_end"], sort=False):
        held = bool(rows["valid"].all()) if "valid" in rows.columns else True
        marks = np.where(rows["sensible"], SENSIBLE_MARK,
                         np.where(rows["excitable"], EXCITABLE_MARK, ""))
        if not held:
            marks = np.full(len(rows), "")
        heading = f"{segment} {phase} {t0:.1f}..{t1:.1f} s" + ("" if held else NOT_REPRESENTED)
        out[heading] = [
            f"{v:.3g} {m}".rstrip() for v, m in zip(rows["sigma_end"], marks, strict=True)]
    return out
