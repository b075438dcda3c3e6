"""The fit's agreement with the records, per segment: is the reference motion the one flown?

An assessment reads excitability and sensability along a reference motion (the fitted
trajectory). Where that motion departs from the records, those numbers describe a flight
that did not happen. :func:`smoothed_residuals` forms recorded minus reference after the
fit's IMU calibration (:func:`fit_calibration`, one scale and bias per axis), averaged over
``moving_average_s``; :func:`segment_agreement` reduces them per segment (the worst axis)
and checks them against the bounds of ``data/quality.toml`` ``[fit]``
(:func:`fit_bounds`), naming a likely cause for every segment outside them
(docs/assumptions.md FIT1-FIT3, FIT8, B7).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from navlib import earth, units
from navlib.io import quality
from navlib.metrics import in_segment
from navlib.trajectory.liftoff import moving_average
from navlib.units import DEG

__all__ = ["AGREEMENT_COLUMNS", "AXES", "POWERED_PHASES", "axis_regression", "fit_bounds",
           "fit_calibration", "segment_agreement", "smoothed_residuals"]

AXES = "xyz"
POWERED_PHASES = ("powered", "boost")
"""Phases whose specific-force bound is ``specific_force_powered_mps2`` (thrust transients
and motor vibration that a 1 s average does not remove)."""
AGREEMENT_COLUMNS = ("fit_f_rms", "fit_w_rms", "fit_gnss_rms", "represented", "fit_reason")
"""Columns :func:`segment_agreement` adds to the segment table."""


def fit_bounds(overrides=None) -> dict:
    """The ``[fit]`` section of ``data/quality.toml`` (overrides as in
    :func:`navlib.io.quality.load_thresholds`, e.g. ``{"fit": {"gnss_m": 20}}``)."""
    return quality.load_thresholds(overrides)["fit"]


def fit_calibration(trajectory) -> dict:
    """The IMU calibration the fit estimated (``parameters["fit_residuals"]``), per axis:
    ``{"accel": {"scale", "bias"}, "gyro": {"scale", "bias"}}`` with ``recorded = scale *
    true + bias`` (scale 1 and bias 0 where the fit estimated none)."""
    res = getattr(trajectory, "parameters", {}).get("fit_residuals", {})
    return {name: {"scale": [float(v) for v in res.get(f"{name}_scale", np.ones(3))],
                   "bias": [float(v) for v in res.get(f"{name}_bias_{unit}", np.zeros(3))]}
            for name, unit in (("accel", "mps2"), ("gyro", "rad_s"))}


def smoothed_residuals(t, f_rec, f_ref, w_rec, w_ref, calibration, window_s):
    """Recorded minus reference specific force and rate, each recorded axis corrected by
    the ``calibration`` of :func:`fit_calibration` (``(recorded - bias) / scale``), both
    averaged over ``window_s`` (:func:`moving_average`): ``(df, dw)``, each (N, 3).

    Parameters
    ----------
    t : numpy.ndarray
        Times, s.
    f_rec, f_ref : numpy.ndarray
        Recorded and reference specific force, m/s^2, (N, 3).
    w_rec, w_ref : numpy.ndarray
        Recorded and reference angular rate, rad/s, (N, 3).
    calibration : dict
        Result of :func:`fit_calibration`.
    window_s : float
        Averaging window, s.
    """
    out = []
    for name, rec, ref in (("accel", f_rec, f_ref), ("gyro", w_rec, w_ref)):
        cal = calibration[name]
        corrected = (rec - np.asarray(cal["bias"])) / np.asarray(cal["scale"])
        out.append(moving_average(t, corrected - ref, window_s))
    return out[0], out[1]


def axis_regression(recorded, reference):
    """Per axis, the least-squares ``recorded ~ scale * reference + bias`` and the
    correlation of the two: ``(scale, bias, r)``, arrays of 3 (NaN where the reference
    does not vary).

    Parameters
    ----------
    recorded, reference : numpy.ndarray
        Samples, (N, 3).
    """
    scale, bias, r = np.full(3, np.nan), np.full(3, np.nan), np.full(3, np.nan)
    for a in range(3):
        x, y = reference[:, a], recorded[:, a]
        if x.size < 3 or np.std(x) == 0 or np.std(y) == 0:
            continue
        scale[a], bias[a] = np.polyfit(x, y, 1)
        r[a] = np.corrcoef(x, y)[0, 1]
    return scale, bias, r


def _rms_worst(x):
    if x.shape[0] == 0:
        return np.nan
    return float(np.sqrt(np.mean(x**2, axis=0)).max())


def segment_agreement(table, trajectory, imu_residuals, gnss_residuals, bounds):
    """The fit's agreement with the records in each segment of ``table``.

    Parameters
    ----------
    table : DataFrame
        Segment table (``segment``, ``phase``, ``t_start``, ``t_end``).
    trajectory : Trajectory
        The reference motion.
    imu_residuals, gnss_residuals : DataFrame
        Of :func:`navlib.studies.assess.fit_residuals`: ``df_x_avg ... dw_z_avg`` (after the
        fit's calibration), ``turn_deg``; ``dx, dy, dz`` at the GNSS epochs and, for
        barometric rows, ``baro_dynamic_m`` (their expected static-pressure error, B7).
    bounds : dict
        :func:`fit_bounds`.

    Returns
    -------
    columns : DataFrame
        One row per segment: ``fit_f_rms`` (m/s^2) and ``fit_w_rms`` (rad/s), the RMS of
        the worst axis; ``fit_gnss_rms`` (m, 3-D; NaN without fixes in the segment);
        ``represented`` (every residual within its bound and the rotation resolved by the
        sample rate); ``fit_reason`` (empty when represented, else the residuals, their
        bounds and the likely cause).
    messages : list of str
        The ``fit_reason`` of every unrepresented segment, prefixed by the segment.
    """
    t = imu_residuals["t"].to_numpy(dtype=float)
    df = imu_residuals[[f"df_{a}_avg" for a in AXES]].to_numpy(dtype=float)
    dw = imu_residuals[[f"dw_{a}_avg" for a in AXES]].to_numpy(dtype=float)
    turn = imu_residuals["turn_deg"].to_numpy(dtype=float)
    coning = (imu_residuals["coning_deg"].to_numpy(dtype=float),
              imu_residuals["resolved"].to_numpy(dtype=bool)) \
        if "resolved" in imu_residuals else (np.zeros_like(turn), np.ones(turn.size, bool))
    t_g = gnss_residuals["t"].to_numpy(dtype=float)
    d_g = gnss_residuals[[f"d{a}" for a in AXES]].to_numpy(dtype=float)
    q_err = (gnss_residuals["baro_dynamic_m"].to_numpy(dtype=float)
             if "baro_dynamic_m" in gnss_residuals else None)
    rows, messages = [], []
    for row in table.itertuples(index=False):
        sel = in_segment(t, row.t_start, row.t_end)
        sel_g = in_segment(t_g, row.t_start, row.t_end)
        f_rms, w_rms = _rms_worst(df[sel]), _rms_worst(dw[sel])
        g_rms = (float(np.sqrt(np.mean(np.sum(d_g[sel_g] ** 2, axis=1))))
                 if sel_g.any() else np.nan)
        powered = any(word in POWERED_PHASES for word in str(row.phase).split("+"))
        f_bound = bounds["specific_force_powered_mps2" if powered else "specific_force_mps2"]
        w_bound = bounds["angular_rate_deg_s"] * DEG
        fast = float(np.mean(turn[sel] > bounds["max_turn_per_sample_deg"])) if sel.any() \
            else 0.0
        outside = []
        if f_rms > f_bound:
            outside.append(f"specific force {f_rms:.3g} m/s^2 RMS (bound {f_bound:g})")
        if w_rms > w_bound:
            outside.append(f"angular rate {w_rms / DEG:.3g} deg/s RMS (bound "
                           f"{bounds['angular_rate_deg_s']:g})")
        if g_rms > bounds["gnss_m"]:
            outside.append(f"GNSS position {g_rms:.3g} m RMS (bound {bounds['gnss_m']:g})")
        unresolved = fast > bounds["turn_fraction"]
        reason = ""
        if outside or unresolved:
            causes = _causes(sel, sel_g, fast, (turn, coning), t, df, dw, trajectory,
                             (t_g, d_g, q_err), bounds, (f_rms > f_bound, w_rms > w_bound))
            shown = "; ".join(outside) if outside else "residuals within bounds"
            reason = f"{shown}; likely cause: {'; '.join(causes)}"
            messages.append(f"segment {int(row.segment)} {row.phase} {row.t_start:.6g}-"
                            f"{row.t_end:.6g} s is not represented by the reference motion: "
                            f"{reason}")
        rows.append({"fit_f_rms": f_rms, "fit_w_rms": w_rms, "fit_gnss_rms": g_rms,
                     "represented": not reason, "fit_reason": reason})
    return pd.DataFrame(rows, columns=list(AGREEMENT_COLUMNS)), messages


def _causes(sel, sel_g, fast, rotation, t, df, dw, trajectory, rows, bounds, imu_out):
    """Likely causes of one segment's disagreement, in words (module docstring); the axis
    regressions only for the sensor (accelerometer, gyro) outside its bound, ``imu_out``;
    ``rotation``: the recorded turn and coning per sample, deg; ``rows``: the position rows'
    times, residuals and expected static-pressure error (None for GNSS rows)."""
    t_g, d_g, q_err = rows
    causes = [] if q_err is None else _high_dynamic_pressure(sel_g, t_g, d_g, q_err,
                                                             trajectory, bounds)
    turn, (coning, resolved) = rotation
    rate = 1.0 / float(np.median(np.diff(t[sel]))) if sel.sum() > 1 else np.nan
    if fast > bounds["turn_fraction"]:
        causes.append(f"rotation per sample beyond what the log rate resolves ({fast:.0%} of "
                      f"its samples turn by more than {bounds['max_turn_per_sample_deg']:g} deg,"
                      f" up to {np.max(turn[sel]):.0f} deg, at {rate:.3g} Hz)")
    moving = ~resolved[sel]
    if any(imu_out) and moving.any():
        t_moving = t[sel][moving]
        causes.append(f"a rotation the fit does not resolve ({moving.sum()} of its "
                      f"samples, {t_moving[0]:.6g}-{t_moving[-1]:.6g} s, its axis moving by up "
                      f"to {np.max(coning[sel]):.2g} deg within a sample at {rate:.3g} Hz): "
                      "the reference does not follow the IMU there (FIT7)")
    window = bounds["moving_average_s"]
    for name, label, d_avg, ref, out in (
            ("accel", "accelerometer", df, trajectory.specific_force, imu_out[0]),
            ("gyro", "gyro", dw, trajectory.angular_rate, imu_out[1])):
        if not out:
            continue
        ref_avg = moving_average(t, ref, window)[sel]
        scale, bias, r = axis_regression(ref_avg + d_avg[sel], ref_avg)
        strong = np.abs(r) >= bounds["cause_correlation"]
        for a in np.flatnonzero(strong & (scale < 0)):
            causes.append(f"axis convention (the recorded {label} {AXES[a]} runs against the "
                          f"reference motion: scale {scale[a]:.3g})")
        off = strong & (scale > 0) & (np.abs(scale - 1.0) > bounds["cause_scale"])
        if name == "accel":
            off |= strong & (np.abs(bias) > bounds["cause_bias_mps2"])
        if off.any():
            what = "scale or bias" if name == "accel" else "scale"
            causes.append(f"{label} {what} (recorded against reference, after the fit's "
                          "calibration: " + ", ".join(
                              f"{AXES[a]} scale {scale[a]:.4g} bias {bias[a]:.3g}"
                              for a in np.flatnonzero(off)) + ")")
    around = np.flatnonzero(sel_g)
    if around.size:
        around = np.arange(max(around[0] - 1, 0), min(around[-1] + 2, t_g.size))
    else:
        around = np.flatnonzero(in_segment(t_g, t[sel][0] - bounds["gnss_gap_s"],
                                           t[sel][-1] + bounds["gnss_gap_s"])) if sel.any() \
            else around
    gaps = np.flatnonzero(np.diff(t_g[around]) > bounds["gnss_gap_s"])
    if gaps.size:
        k = around[gaps[np.argmax(np.diff(t_g[around])[gaps])]]
        causes.append(f"a GNSS outage of {t_g[k + 1] - t_g[k]:.3g} s ({t_g[k]:.6g}-"
                      f"{t_g[k + 1]:.6g} s): the IMU carries the motion across it and the fixes "
                      "on either side (a receiver re-acquiring) disagree with it")
    if sel_g.sum() >= 3:
        v = np.column_stack([np.interp(t_g[sel_g], trajectory.t, trajectory.velocity[:, i])
                             for i in range(3)])
        d = d_g[sel_g]
        vv = float(np.sum(v * v))
        if vv > 0:
            lag = -float(np.sum(d * v)) / vv       # recorded P(t) = P(t - lag)
            left = float(np.sum((d + lag * v) ** 2))
            if abs(lag) > bounds["gnss_lag_s"] and left <= 0.5 * float(np.sum(d**2)):
                causes.append(f"GNSS lag ({lag:.2g} s: the fixes trail the reference motion)"
                              if q_err is None else
                              f"a lag of the position rows ({lag:.2g} s: the rows, whose "
                              "height is the barometer's, trail the reference motion)")
        reference = np.column_stack([np.interp(t_g[sel_g], trajectory.t,
                                               trajectory.position[:, i]) for i in range(3)])
        moved = np.linalg.norm(np.diff(reference, axis=0), axis=1)
        fixes = d + reference
        same = np.linalg.norm(np.diff(fixes, axis=0), axis=1) <= bounds["held_fix_m"]
        if np.any(same & (moved > bounds["held_fix_motion_m"])):
            n = int(np.count_nonzero(same & (moved > bounds["held_fix_motion_m"])))
            causes.append(f"a held GNSS fix ({n} fix(es) repeat the previous one while the "
                          "reference moves)")
    if q_err is None and not imu_out[0]:
        causes += _receiver_dynamics(sel_g, t_g, d_g, trajectory, bounds)
    return causes or ["not identified (no fast rotation, axis sign, calibration, GNSS "
                      "outage, GNSS lag, held fix or receiver dynamics explains it)"]


def _receiver_dynamics(sel_g, t_g, d_g, trajectory, bounds) -> list[str]:
    """The cause "GNSS receiver error at high dynamics" (docs/assumptions.md FIT8): the fixes
    taken while the reference accelerates beyond ``receiver_accel_g``, or within
    ``receiver_recovery_s`` after, carry at least half of the segment's squared GNSS
    residual (called only where the specific force agrees with the IMU, so the motion the
    fixes disagree with is the one the accelerometers recorded)."""
    if not sel_g.any():
        return []
    t = np.asarray(trajectory.t, dtype=float)
    accel = np.linalg.norm(np.gradient(np.asarray(trajectory.velocity, dtype=float), t,
                                       axis=0), axis=1)
    limit = bounds["receiver_accel_g"] * units.G0
    t_high = t[accel > limit]
    if t_high.size == 0:
        return []
    t_s = t_g[sel_g]
    last = np.searchsorted(t_high, t_s, side="right") - 1
    since = np.where(last >= 0, t_s - t_high[np.maximum(last, 0)], np.inf)
    near = since <= bounds["receiver_recovery_s"]
    d2 = np.sum(d_g[sel_g] ** 2, axis=1)
    if not near.any() or d2[near].sum() < 0.5 * d2.sum():
        return []
    return [f"GNSS receiver error at high dynamics (the fixes at {t_s[near][0]:.6g}-"
            f"{t_s[near][-1]:.6g} s, taken while or within "
            f"{bounds['receiver_recovery_s']:g} s after the reference accelerated beyond "
            f"{bounds['receiver_accel_g']:g} g, up to {accel.max() / units.G0:.3g} g, carry "
            f"{d2[near].sum() / d2.sum():.0%} of the segment's squared GNSS residual, up to "
            f"{np.sqrt(d2[near].max()):.3g} m, where the reference follows the recorded "
            "specific force: the receiver's navigation filter beyond its dynamic model)"]


def _high_dynamic_pressure(sel_g, t_g, d_g, q_err, trajectory, bounds) -> list[str]:
    """The cause "barometer at high dynamic pressure" (docs/assumptions.md B7, FIT3): the
    segment's barometric rows whose expected static-pressure error ``q_err`` exceeds the
    position bound carry, in their vertical residual alone, at least half of the segment's
    squared position residual (the barometer explains no horizontal residual)."""
    if not sel_g.any():
        return []
    t_s, d_s = t_g[sel_g], d_g[sel_g]
    d2 = np.sum(d_s**2, axis=1)
    P = np.column_stack([np.interp(t_s, trajectory.t, trajectory.position[:, i])
                         for i in range(3)])
    lat, lon, _ = earth.ecef_to_geodetic(P)
    up = -earth.ned_to_ecef_matrix(lat, lon)[..., 2].reshape(-1, 3)
    d_up = np.einsum("ki,ki->k", d_s, up)
    high = q_err[sel_g] > bounds["gnss_m"]
    if not high.any() or np.sum(d_up[high] ** 2) < 0.5 * d2.sum():
        return []
    return [f"barometer at high dynamic pressure (the barometric rows at {t_s[high][0]:.6g}-"
            f"{t_s[high][-1]:.6g} s, where the reference's speed makes a static-pressure error "
            f"of up to {q_err[sel_g].max():.3g} m expected (B7), carry "
            f"{np.sum(d_up[high] ** 2) / d2.sum():.0%} of the segment's squared position "
            f"residual in their height, up to {np.max(np.abs(d_up[high])):.3g} m)"]
