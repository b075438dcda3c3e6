"""The vehicle class of a flight recognised from its kinematics (``docs/assumptions.md`` V1).
"""


import numpy as np

from navlib._validation import finite_scalar, reject_unknown
from navlib.segmentation.features import flight_features, window_means
from navlib.segmentation.phases import SEGMENT_DEFAULTS
from navlib.units import DEG

__all__ = ["RECOGNITION_DEFAULTS", "recognise_vehicle"]

RECOGNITION_DEFAULTS = {
    "rocket_accel_m_s2": 30.0,
    "rocket_speed_m_s": 20.0,
    "vertical_rate_m_s": 1.0,
    "vertical_max_speed_m_s": 2.0,
    "vertical_min_s": 1.0,
    "airborne_height_m": 20.0,
    "airborne_speed_m_s": 8.0,
    "road_grade_max": 0.15,
    "airborne_min_s": 1.0,
    "sideways_min_deg": 45.0,
    "sideways_min_s": 2.0,
}
"""Thresholds of :func:`recognise_vehicle` (``docs/assumptions.md`` V1; engineering choices)."""


def recognise_vehicle(trajectory, **thresholds) -> tuple[str, str]:
    """The vehicle class of a (fitted) flight from its kinematics, and why
    (``docs/assumptions.md`` V1).

    In order: ``rocket`` when the specific force exceeds ``rocket_accel_m_s2`` (30, about
    3 g, over 0.1 s) and the vertical speed ``rocket_speed_m_s`` (20); ``multicopter`` when
    the vehicle moves vertically (``|v_up| > vertical_rate_m_s``, 1) with little horizontal
    speed (``v_h < vertical_max_speed_m_s``, 2) for ``vertical_min_s`` (1 s) in all (only
    rotorcraft and rockets take off or land vertically), or flies sideways (a sideslip
    between ``sideways_min_deg`` (45) and 180 minus it, above ``hover_height_m`` of
    :data:`SEGMENT_DEFAULTS` and 3 m/s) for ``sideways_min_s`` (2 s): an aeroplane or a car
    goes where its nose points (or backwards), a multicopter in any direction;
    ``fixed-wing`` when it rises
    ``airborne_height_m`` (20) above its lowest point and climbs or descends faster than a
    road allows (``|v_up| > road_grade_max v_h``, 0.15) at ``v_h > airborne_speed_m_s`` (8)
    for ``airborne_min_s`` (1 s) in all;
    else ``ground``. A stationary record is ``ground``.

    Parameters
    ----------
    trajectory : navlib.trajectory.Trajectory
    **thresholds
        Any of :data:`RECOGNITION_DEFAULTS`.
    """
    reject_unknown(thresholds, RECOGNITION_DEFAULTS, "recognise_vehicle")
    p = {k: finite_scalar(thresholds.get(k, v), k, 0.0, low_open=True)
         for k, v in RECOGNITION_DEFAULTS.items()}
    w = window_means(flight_features(trajectory), 0.1)
    dt = (w["t_end"] - w["t_start"]).to_numpy()
    f_peak, up_peak = float(w["f_norm"].max()), float(w["v_up"].max())
    if f_peak > p["rocket_accel_m_s2"] and up_peak > p["rocket_speed_m_s"]:
        return "rocket", (f"kinematics: specific force up to {f_peak:.3g} m/s^2 and vertical "
                          f"speed up to {up_peak:.3g} m/s")
    vertical = ((w["v_up"].abs() > p["vertical_rate_m_s"])
                & (w["v_h"] < p["vertical_max_speed_m_s"])).to_numpy()
    if dt[vertical].sum() >= p["vertical_min_s"]:
        return "multicopter", (f"kinematics: {dt[vertical].sum():.3g} s of vertical motion "
                               f"(|v_up| > {p['vertical_rate_m_s']:g} m/s at horizontal speed "
                               f"below {p['vertical_max_speed_m_s']:g} m/s)")
    slip = w["sideslip"].to_numpy()
    sideways = ((slip > p["sideways_min_deg"] * DEG) & (slip < np.pi - p["sideways_min_deg"] * DEG)
                & (w["height"] >= SEGMENT_DEFAULTS["hover_height_m"]).to_numpy())
    if dt[sideways].sum() >= p["sideways_min_s"]:
        return "multicopter", (f"kinematics: {dt[sideways].sum():.3g} s of flight sideways "
                               f"(body x axis over {p['sideways_min_deg']:g} deg off the "
                               "velocity)")
    steep = ((w["v_h"] > p["airborne_speed_m_s"])
             & (w["v_up"].abs() > p["road_grade_max"] * w["v_h"])).to_numpy()
    height = float(w["height"].max())
    if height > p["airborne_height_m"] and dt[steep].sum() >= p["airborne_min_s"]:
        return "fixed-wing", (f"kinematics: {height:.3g} m of height range and "
                              f"{dt[steep].sum():.3g} s of climb or descent steeper than a road "
                              f"at over {p['airborne_speed_m_s']:g} m/s")
    return "ground", ("kinematics: no boost, no vertical take-off or landing, no airborne "
                      "climb")
