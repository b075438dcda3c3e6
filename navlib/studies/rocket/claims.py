"""The paper's statements X1-X7 (Fig. 2) and S1-S8 (Figs. 3-5), one function per claim, each
judged by the one rule of :mod:`navlib.studies.claims`."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np
import pandas as pd

from navlib.errors import NavlibInputError
from navlib.models.ecef import STATE_GROUPS, STATE_NAMES
from navlib.resolution import relative_resolution
from navlib.studies.claims import ClaimResult, check, claim, claims_frame
from navlib.studies.rocket.experiment import (
    RocketAnalysis,
    direction_sensability,
    heading_direction,
    quiet_gyro_analysis,
    tangent_projections,
)
from navlib.studies.rocket.flight import (
    ATTITUDE,
    BRIEF_S,
    EXCITABILITY_DEPENDS,
    FUTILE,
    IN_SO,
    LOW,
    NOT_IMPROVED,
    ONLY_AFTER,
    PARAMETERS,
    QUIET_GYRO_SCALE,
    SEGMENT_LABELS,
    SENSABILITY_DEPENDS,
    SENSIBLE,
    TRANSIENT_S,
)

__all__ = ["BASELINE_BASIS", "CLAIM_IDS", "EXCITABILITY_CLAIMS", "OTHER_PARAMETERS",
           "SENSABILITY_CLAIMS", "claim_s1", "claim_s2", "claim_s3", "claim_s4", "claim_s5",
           "claim_s6", "claim_s7", "claim_s8", "claim_x1", "claim_x2", "claim_x3", "claim_x4",
           "claim_x5", "claim_x6", "claim_x7", "claim_xrank", "claims_table", "excitability_claims",
           "sensability_claims", "sensible_time"]


def _require_three(analysis: RocketAnalysis) -> None:
    if len(analysis.segments) != 3:
        raise NavlibInputError(
            f"segments: the paper's claims need three segments (pad, powered, free fall); "
            f"the analysis has {len(analysis.segments)}")


def _e(analysis: RocketAnalysis, state: str, segment: int) -> float:
    return float(analysis.excitability[segment].e[STATE_NAMES.index(state)])


def _s(analysis: RocketAnalysis, state: str) -> np.ndarray:
    return analysis.sensability.s[:, STATE_NAMES.index(state)]


def _sigma(analysis: RocketAnalysis, state: str) -> np.ndarray:
    return analysis.sensability.sigma[:, STATE_NAMES.index(state)]


def _fmt(values: dict, digits: int = 2) -> str:
    return ", ".join(f"{k} {v:.{digits}f}" for k, v in values.items())


def _assumption(analysis: RocketAnalysis, extra: str = "") -> str:
    s = analysis.settings
    text = (f"eta={s['eta']:g}, D0={s['d0']}, R0=({s['gnss_sigma_m']:g} m)^2 I, "
            f"{s['attitude_error']} attitude error, spin {s['spin_hz']:g} Hz")
    return f"{text}; {extra}" if extra else text


def _sens_assumption(analysis: RocketAnalysis, extra: str = "") -> str:
    s = analysis.settings
    text = (f"nu={s['nu']:g}, P0 posterior at t0 (A9)" if not s["prior_update"]
            else f"nu={s['nu']:g}, P0 prior updated at t0 (A9)")
    text += f", {s['attitude_error']} attitude error, spin {s['spin_hz']:g} Hz"
    return f"{text}; {extra}" if extra else text


# --------------------------------------------------------------------------- X1-X7 (Fig. 2)


def claim_x1(analysis: RocketAnalysis) -> ClaimResult:
    """X1: e1-e6 (P, V) lie mostly in S_O in all three segments (GNSS)."""
    _require_three(analysis)
    states = STATE_GROUPS["position"] + STATE_GROUPS["velocity"]
    mins = {lab: min(_e(analysis, s, i) for s in states) for i, lab in enumerate(SEGMENT_LABELS)}
    checks = [check("min e(P, V) over tau1-tau3", min(mins.values()), ">=", IN_SO, True)]
    return claim("X1", "P and V (e1-e6) lie mostly in S_O in all three segments",
                 "e1-e6 high in tau1, tau2, tau3", f"min e: {_fmt(mins)}", checks,
                 assumption=_assumption(analysis, "sigma_P0/sigma_V0 vs R0 (small P0 breaks "
                                                  "it)"))


def claim_x2(analysis: RocketAnalysis) -> ClaimResult:
    """X2: attitude (e7-e9) in S_O in tau1 and tau2, barely excited in tau3."""
    _require_three(analysis)
    checks = [check(f"min e(attitude) in {lab}", min(_e(analysis, s, i) for s in ATTITUDE),
                    ">=", IN_SO, True) for i, lab in enumerate(SEGMENT_LABELS[:2])]
    checks.append(check("max e(attitude) in tau3 ('barely')",
                        max(_e(analysis, s, 2) for s in ATTITUDE), "<", LOW))
    ours = "; ".join(f"{lab}: " + "/".join(f"{_e(analysis, s, i):.2f}" for s in ATTITUDE)
                     for i, lab in enumerate(SEGMENT_LABELS))
    return claim("X2", "Attitude in S_O in tau1 and tau2, barely excites the innovations in "
                 "tau3", "e7-e9 high in tau1, tau2; low in tau3", f"e7/e8/e9 {ours}", checks,
                 assumption=_assumption(analysis, "heading is not excited at rest (only the "
                                                  "tilt plane), so ECEF components ~ their "
                                                  "tangent-plane projections"))


def claim_x3(analysis: RocketAnalysis) -> ClaimResult:
    """X3: e16 (x-gyro scale factor) becomes excitable in tau2."""
    _require_three(analysis)
    e = [_e(analysis, "sg_x", i) for i in range(3)]
    checks = [check("e16 in tau2", e[1], ">=", IN_SO, True),
              check("e16 tau2 - tau1", e[1] - e[0], ">", 0.0),
              check("e16 tau2 - tau3", e[1] - e[2], ">", 0.0)]
    return claim("X3", "x-gyro scale factor (e16) becomes excitable in tau2 (acceleration "
                 "with spin)", "e16 high in tau2 only",
                 f"e16 {_fmt(dict(zip(SEGMENT_LABELS, e, strict=True)))}", checks,
                 assumption=_assumption(analysis, "needs a large spin x sigma_sg"))


def claim_x4(analysis: RocketAnalysis) -> ClaimResult:
    """X4: e19 (x-accelerometer scale factor) more excitable in tau2 than tau1, still < 1/√2."""
    _require_three(analysis)
    e = [_e(analysis, "sa_x", i) for i in range(3)]
    checks = [check("e19 tau2 - tau1", e[1] - e[0], ">", 0.0, True),
              check("e19 in tau2 (predominantly in S_NO)", e[1], "<", IN_SO)]
    return claim("X4", "x-accelerometer scale factor (e19) more excitable in tau2 than tau1 "
                 "but predominantly in S_NO", "e19 tau2 > tau1, < 1/sqrt(2)",
                 f"e19 {_fmt(dict(zip(SEGMENT_LABELS, e, strict=True)))}", checks,
                 assumption=_assumption(analysis, "thrust ~110 m/s^2 x sigma_sa"))


OTHER_PARAMETERS = tuple(p for p in PARAMETERS if p not in ("sg_x", "sa_x"))
"""IMU parameters other than e16 and e19 (X5, X6)."""


def claim_x5(analysis: RocketAnalysis) -> ClaimResult:
    """X5: all other IMU parameters very low in every segment."""
    _require_three(analysis)
    top = {lab: max(OTHER_PARAMETERS, key=lambda p, i=i: _e(analysis, p, i))
           for i, lab in enumerate(SEGMENT_LABELS)}
    worst = max(_e(analysis, p, i) for i, p in enumerate(top.values()))
    ours = ", ".join(f"{lab} max {_e(analysis, p, i):.2f} ({p})"
                     for i, (lab, p) in enumerate(top.items()))
    return claim("X5", "All other IMU parameters very low in every segment",
                 "e10-e15, e17, e18, e20, e21 ~ 0", ours,
                 [check("max e(other parameters), all segments", worst, "<", LOW, True)],
                 assumption=_assumption(analysis, f"'very low' = e < {LOW}; sigma_bg0 vs "
                                                  "sigma_theta0 sets the pad gyro-bias share"))


def _rms(analysis: RocketAnalysis, states: Sequence[str], segment: int) -> float:
    return float(np.sqrt(np.mean([_e(analysis, s, segment) ** 2 for s in states])))


def claim_x6(analysis: RocketAnalysis) -> ClaimResult:
    """X6: among the low values, biases higher in tau1, scale factors higher in tau2."""
    _require_three(analysis)
    biases = [p for p in OTHER_PARAMETERS if p.startswith("b")]
    scales = [p for p in OTHER_PARAMETERS if p.startswith("s")]
    rb = [_rms(analysis, biases, i) for i in range(3)]
    rs = [_rms(analysis, scales, i) for i in range(3)]
    checks = [check("segment with the largest rms e of the biases", int(np.argmax(rb)) + 1,
                    "==", 1, True),
              check("segment with the largest rms e of the scale factors",
                    int(np.argmax(rs)) + 1, "==", 2, True)]
    ours = (f"rms e biases {'/'.join(f'{v:.3f}' for v in rb)}, scale factors "
            f"{'/'.join(f'{v:.3f}' for v in rs)} (tau1/tau2/tau3)")
    return claim("X6", "Among the low values, biases relatively higher in tau1 and scale "
                 "factors in tau2", "biases: tau1; scale factors: tau2", ours, checks,
                 assumption=_assumption(analysis, "rms over the non-e16/e19 parameters"))


def claim_x7(analysis: RocketAnalysis) -> ClaimResult:
    """X7: tau3 (free fall) unfavourable for in-flight IMU recalibration."""
    _require_three(analysis)
    r = [_rms(analysis, PARAMETERS, i) for i in range(3)]
    top = max(_e(analysis, p, 2) for p in PARAMETERS)
    checks = [check("max e(IMU parameters) in tau3", top, "<", LOW, True),
              check("rms e(parameters) tau3 - tau1", r[2] - r[0], "<", 0.0),
              check("rms e(parameters) tau3 - tau2", r[2] - r[1], "<", 0.0)]
    ours = f"rms e of the 12 parameters {'/'.join(f'{v:.3f}' for v in r)}, max tau3 {top:.2f}"
    return claim("X7", "Free fall (tau3) is unfavourable for in-flight recalibration",
                 "IMU parameters not excitable in tau3", ours, checks,
                 assumption=_assumption(analysis))


def claim_xrank(analysis: RocketAnalysis) -> ClaimResult:
    """España §4: a rank-deficient O_tau leaves a subspace with zero excitability. An
    identity of the SVD (basis "by construction"); the counts show where it applies."""
    _require_three(analysis)
    deficient, bounds = [], []
    for ex in analysis.excitability:
        singular = np.sqrt(np.clip(ex.sigma, 0.0, None))
        resolution = relative_resolution(ex.O.shape)
        beyond = singular <= resolution * singular[0]
        deficient.append(int(beyond.sum()))
        # S_i = n sigma_i^2 / sum(sigma^2) <= n resolution^2 beyond the rank: the computed S
        # there is round-off below that bound (its digits differ between machines)
        bounds.append(len(singular) * resolution**2 if beyond.any() else 0.0)
    checks = [check("segments whose O_tau is rank-deficient", sum(d > 0 for d in deficient),
                    ">=", 1, True),
              check("bound n (max(M, n) eps)^2 on the energy S of a direction beyond the rank",
                    max(bounds), "<=", analysis.excitability[0].eta)]
    ours = ("directions beyond the numerical rank of O_tau per segment: "
            + "/".join(str(d) for d in deficient))
    return claim("X-rank", "A rank-deficient O_tau leaves a subspace with zero excitability",
                 "zero excitability where rank O_tau < n (§4)", ours, checks,
                 basis="by construction",
                 assumption="rank = singular values above the numerical resolution of O_tau "
                            "(navlib.resolution); zero energy there is an identity of the SVD",
                 depends_on=("rank_tolerance",))


# --------------------------------------------------------------------------- S1-S8 (Figs 3-5)


def _pad(analysis: RocketAnalysis) -> np.ndarray:
    """Pad epochs after t0: (tau1 start, ignition] (or tau1 end when earlier)."""
    t_a, t_b = analysis.segments[0]
    ignition = analysis.trajectory.events.get("ignition", t_b)
    return analysis.epochs(t_a, min(t_b, ignition), open_start=True)


def sensible_time(analysis: RocketAnalysis, state: str, epochs: np.ndarray) -> float:
    """Seconds (epoch count x GNSS period) with s >= SENSIBLE among ``epochs``.

    Parameters
    ----------
    analysis : RocketAnalysis
        The analysis.
    state : str
        State name.
    epochs : numpy.ndarray
        Epoch indices considered.
    """
    if epochs.size == 0:
        return 0.0
    period = float(np.median(np.diff(analysis.model.t)))
    return float(np.count_nonzero(_s(analysis, state)[epochs] >= SENSIBLE) * period)


def claim_s1(analysis: RocketAnalysis) -> ClaimResult:
    """S1: x-position sensability high from the very beginning."""
    _require_three(analysis)
    k = analysis.epochs(*analysis.segments[0], open_start=True)
    s = _s(analysis, "P_x")
    ours = f"min s(P_x) tau1 {s[k].min():.2f}; whole flight {s[1:].min():.2f}"
    return claim("S1", "x-position sensability high from the very beginning",
                 "s(P_x) high from t0", ours,
                 [check("min s(P_x) over tau1", float(s[k].min()), ">=", SENSIBLE, True)],
                 assumption=_sens_assumption(analysis, "epoch t0 left out (s = 1 there by "
                                                       "A9)"))


def claim_s2(analysis: RocketAnalysis) -> ClaimResult:
    """S2: V_x sensability: valley before 5 s, rise near 12 s, ~1 after 55 s."""
    _require_three(analysis)
    t = analysis.model.t
    s = _s(analysis, "V_x")
    k1 = analysis.epochs(*analysis.segments[0], open_start=True)
    kv = k1[np.argmin(s[k1])]
    t_v = float(t[kv])
    late = analysis.epochs(55.0, analysis.segments[2][1])
    rise = analysis.epochs(10.0, 16.0)
    gain = float(s[rise].max() - s[kv]) if rise.size else float("nan")
    mean_late = float(s[late].mean()) if late.size else float("nan")
    checks = [check("time of the V_x valley in tau1, s", t_v, "<=", 5.0, True),
              check("s(V_x) at the valley (deep)", float(s[kv]), "<", SENSIBLE, True),
              check("rise of s(V_x) by 10-16 s above the valley", gain, ">=", 0.2),
              check("mean s(V_x) after 55 s (~1)", mean_late, ">=", 0.9)]
    ours = (f"valley {s[kv]:.2f} at {t_v:.0f} s, max 10-16 s {s[rise].max():.2f}, "
            f"mean after 55 s {mean_late:.2f}")
    return claim("S2", "x-velocity sensability: deep valley before 5 s, rise near 12 s, ~1 "
                 "after 55 s", "valley < 5 s; rise ~12 s; ~1 after 55 s", ours, checks,
                 assumption=_sens_assumption(analysis, "valley timing set by sigma_V0 vs "
                                                       "GNSS sigma"))


def claim_s3(analysis: RocketAnalysis) -> ClaimResult:
    """S3: the V_x 2-sigma band grows after the valley, shrinks after ~12 s, min after 55 s."""
    _require_three(analysis)
    t = analysis.model.t
    s, sig = _s(analysis, "V_x"), _sigma(analysis, "V_x")
    k1 = analysis.epochs(*analysis.segments[0], open_start=True)
    kv = int(k1[np.argmin(s[k1])])
    after = analysis.epochs(t[kv], t[kv] + 7.0, open_start=True)
    k12, k55 = analysis.at(12.0), analysis.at(55.0)
    grow = float(sig[after].max() / sig[kv]) if after.size else float("nan")
    t_min = float(t[int(np.argmin(sig))])
    checks = [check("time of the smallest V_x band, s", t_min, ">=", 55.0, True),
              check("band at 55 s / band at 12 s", float(sig[k55] / sig[k12]), "<", 1.0),
              check("largest band within 7 s after the valley / band at the valley", grow,
                    ">", 1.02)]
    ours = (f"2sigma(V_x) {2 * sig[kv]:.2f} m/s at the valley ({t[kv]:.0f} s), "
            f"max {2 * sig[after].max() if after.size else np.nan:.2f} in the next 7 s, "
            f"{2 * sig[k12]:.2f} at 12 s, {2 * sig[k55]:.2f} at 55 s, min at {t_min:.0f} s")
    return claim("S3", "The V_x 2-sigma band lags the sensability: grows after the valley, "
                 "shrinks after ~12 s, minimum after 55 s",
                 "grow / shrink after 12 s / min after 55 s", ours, checks,
                 assumption=_sens_assumption(analysis))


def claim_s4(analysis: RocketAnalysis) -> ClaimResult:
    """S4: on the pad each attitude component is more sensible the larger its tangent-plane
    projection; q_x and q_y grow only after lift-off."""
    _require_three(analysis)
    pad = _pad(analysis)
    proj = tangent_projections(analysis)
    mean_pad = np.array([_s(analysis, s)[pad].mean() for s in ATTITUDE])
    t_lift = analysis.segments[1][0]
    after = analysis.epochs(t_lift, t_lift + 10.0, open_start=True)
    mean_after = np.array([_s(analysis, s)[after].mean() for s in ATTITUDE])
    same_order = bool(np.array_equal(np.argsort(mean_pad), np.argsort(proj)))
    # "only after": on the pad (after the start-up transient) s(theta_x), s(theta_y) must not
    # already rise by a comparable amount (A-S4-only-after)
    late_pad = pad[analysis.model.t[pad] > analysis.model.t[0] + TRANSIENT_S]
    pad_rise = [float(_s(analysis, s)[late_pad[-1]] - _s(analysis, s)[late_pad[0]])
                if late_pad.size else float("nan") for s in ATTITUDE[:2]]
    gain = mean_after[:2] - mean_pad[:2]
    checks = [check("pad order of s(theta) follows the tangent projection", same_order,
                    "==", True, True),
              check("gain of s(theta_x) in the 10 s after lift-off",
                    float(gain[0]), ">", 0.0),
              check("gain of s(theta_y) in the 10 s after lift-off",
                    float(gain[1]), ">", 0.0),
              check("largest rise of s(theta_x), s(theta_y) on the pad / its gain after "
                    "lift-off (only after)",
                    float(max(r / g if g > 0 else np.inf for r, g in zip(pad_rise, gain,
                                                                          strict=True))),
                    "<", ONLY_AFTER)]
    ours = (f"pad mean s {'/'.join(f'{v:.2f}' for v in mean_pad)} vs projections "
            f"{'/'.join(f'{v:.2f}' for v in proj)}; 10 s after lift-off "
            f"{'/'.join(f'{v:.2f}' for v in mean_after)}; rise on the pad "
            f"{'/'.join(f'{v:.3f}' for v in pad_rise)}")
    only_after = checks[-1]
    explanation = "" if only_after.passed else (
        f"on the pad (after the {TRANSIENT_S:g} s transient) s(theta_x), s(theta_y) already "
        f"rise by {pad_rise[0]:.3f} / {pad_rise[1]:.3f}, against {gain[0]:.3f} / "
        f"{gain[1]:.3f} in the 10 s after lift-off (ratio {only_after.value:.3g}): their "
        "rise starts before lift-off")
    return claim("S4", "On the pad the IMU is an inclinometer: attitude components more "
                 "sensible the larger their tangent-plane projection; q_x, q_y grow only "
                 "after lift-off", "order by projection; q_x, q_y rise only after 19 s", ours,
                 checks,
                 assumption=_sens_assumption(analysis, "components in ECEF axes (A4 b); "
                                             f"'only after' = pad rise < {ONLY_AFTER:g} of "
                                             "the gain after lift-off (A-S4-only-after)"),
                 depends_on=SENSABILITY_DEPENDS, explanation=explanation)


def _heading_at_ignition(analysis: RocketAnalysis) -> float:
    pad = _pad(analysis)
    heading = direction_sensability(analysis.sensability, heading_direction(analysis))
    return float(heading[int(pad[-1])])


def claim_s5(analysis: RocketAnalysis, quiet: RocketAnalysis | None = None) -> ClaimResult:
    """S5: gyro noise and bias hide the Earth rate: excitability at rest does not become
    sensability (heading not sensible on the pad), *because of* the gyro errors: with them
    scaled down (``quiet``, :func:`quiet_gyro_analysis`) the heading becomes sensible.

    Parameters
    ----------
    analysis : RocketAnalysis
        The analysis.
    quiet : RocketAnalysis or None, optional
        The counterfactual run with scaled-down gyro errors; None computes it.
    """
    _require_three(analysis)
    pad = _pad(analysis)
    heading = direction_sensability(analysis.sensability, heading_direction(analysis))
    k_end = int(pad[-1])
    P = analysis.sensability.P[k_end, 6:9, 6:9]
    v = heading_direction(analysis)[6:9]
    sigma_heading = float(np.degrees(np.sqrt(v @ P @ v)))
    excited = [s for s in STATE_NAMES if _e(analysis, s, 0) >= IN_SO]
    not_sensible = [s for s in excited if _s(analysis, s)[pad].mean() < SENSIBLE]
    late_pad = pad[analysis.model.t[pad] > analysis.model.t[0] + TRANSIENT_S]
    gyro = STATE_GROUPS["gyro_bias"]
    gyro_max = max(float(_s(analysis, s)[late_pad].max()) for s in gyro) if late_pad.size \
        else float("nan")
    quiet = quiet_gyro_analysis(analysis) if quiet is None else quiet
    quiet_heading = _heading_at_ignition(quiet)
    checks = [check("s(heading) at ignition", float(heading[k_end]), "<", SENSIBLE, True),
              check(f"s(heading) at ignition with the gyro noise and bias x{QUIET_GYRO_SCALE:g}"
                    " (the cause removed)", quiet_heading, ">=", SENSIBLE, True),
              check("max s(gyro bias) on the pad", gyro_max, "<", SENSIBLE),
              check("states excitable at rest but not sensible on the pad",
                    len(not_sensible), ">=", 1)]
    ours = (f"heading s {heading[k_end]:.2f}, 1sigma {sigma_heading:.1f} deg at "
            f"{analysis.model.t[k_end]:.0f} s ({quiet_heading:.2f} with the gyro noise and "
            f"bias x{QUIET_GYRO_SCALE:g}); excitable at rest but not sensible: "
            f"{', '.join(not_sensible) or 'none'}")
    explanation = ""
    if quiet_heading < SENSIBLE:
        explanation = (f"with the gyro ARW, bias random walk and initial bias sigma scaled by "
                       f"{QUIET_GYRO_SCALE:g} the heading sensability at ignition is "
                       f"{quiet_heading:.3g} (baseline {heading[k_end]:.3g}), still below "
                       f"{SENSIBLE:.4g}: in our model the gyro errors are not what keeps the "
                       "heading insensible on the pad")
    return claim("S5", "Gyro noise and bias hide the Earth rate: high excitability at rest "
                 "does not become sensability", "heading not sensible on the pad", ours,
                 checks, assumption=_sens_assumption(analysis, "ARW, sigma_bg0 >> Earth rate "
                                                               "(15 deg/h); the cause tested "
                                                               "by removing it (A-S5-cause)"),
                 depends_on=SENSABILITY_DEPENDS, explanation=explanation)


def claim_s6(analysis: RocketAnalysis) -> ClaimResult:
    """S6: attitude sensability high through tau2 as the band shrinks; declines in tau3 as
    the band grows."""
    _require_three(analysis)
    (a2, b2), (a3, b3) = analysis.segments[1], analysis.segments[2]
    k2 = analysis.epochs(a2, b2)
    i2a, i2b, i3a, i3b = (analysis.at(x) for x in (a2, b2, a3, b3))
    sens = {s: _s(analysis, s) for s in ATTITUDE}
    sig = {s: _sigma(analysis, s) for s in ATTITUDE}
    checks = [
        check("min over theta of mean s in tau2", min(sens[s][k2].mean() for s in ATTITUDE),
              ">=", SENSIBLE, True),
        check("max over theta of band(tau2 end) / band(tau2 start)",
              max(sig[s][i2b] / sig[s][i2a] for s in ATTITUDE), "<", 1.0, True),
        check("max over theta of s(tau3 end) - s(tau3 start)",
              max(sens[s][i3b] - sens[s][i3a] for s in ATTITUDE), "<", 0.0),
        check("min over theta of band(tau3 end) / band(tau3 start)",
              min(sig[s][i3b] / sig[s][i3a] for s in ATTITUDE), ">", 1.0),
    ]
    ratio = {s: float(sig[s][k2].max() / sig[s][0]) for s in ATTITUDE}
    ours = ("mean s tau2 " + "/".join(f"{sens[s][k2].mean():.2f}" for s in ATTITUDE)
            + "; max sigma/sigma0 in tau2 " + "/".join(f"{v:.1f}" for v in ratio.values())
            + "; s at tau3 start->end " + "/".join(
                f"{sens[s][i3a]:.2f}->{sens[s][i3b]:.2f}" for s in ATTITUDE))
    return claim("S6", "Attitude sensability high through tau2 as its band shrinks; declines "
                 "in free fall as the band grows",
                 "high in tau2, band shrinks; declines in tau3", ours, checks,
                 assumption=_sens_assumption(analysis, "spin x sigma_sg drives the roll band "
                                                       "(the X3 tension)"))


def claim_s7(analysis: RocketAnalysis) -> ClaimResult:
    """S7: IMU parameters weakly sensible; one gyro bias briefly sensible in tau2 without
    improving its a-priori bound."""
    _require_three(analysis)
    t = analysis.model.t
    later = np.flatnonzero(t > t[0] + TRANSIENT_S)
    times = {p: sensible_time(analysis, p, later) for p in PARAMETERS}
    k2 = analysis.epochs(*analysis.segments[1])
    gyro = STATE_GROUPS["gyro_bias"]
    brief = {g: sensible_time(analysis, g, k2) for g in gyro}
    candidates = [g for g in gyro if 0 < brief[g] <= BRIEF_S]
    ratio = {g: float(_sigma(analysis, g)[-1] / _sigma(analysis, g)[0]) for g in gyro}
    longest = max(times, key=times.get)
    checks = [check(f"longest sensible time of an IMU parameter ({longest}), s",
                    times[longest], "<=", BRIEF_S, True),
              check("gyro biases briefly (0-10 s) sensible in tau2", len(candidates), ">=", 1),
              check("min sigma_end/sigma_0 of those gyro biases",
                    min((ratio[g] for g in candidates), default=float("nan")), ">=",
                    NOT_IMPROVED)]
    ours = (f"longest sensible parameter {longest} {times[longest]:.0f} s; gyro-bias sensible "
            f"time in tau2 {_fmt(brief, 0)} s; sigma_end/sigma0 {_fmt(ratio)}")
    return claim("S7", "IMU parameters weakly sensible; a gyro bias briefly sensible in tau2 "
                 "without improving its 2-sigma bound",
                 "one b_g component briefly sensible (x or y, A18)", ours, checks,
                 assumption=_sens_assumption(analysis, f"'briefly' <= {BRIEF_S:g} s"))


def claim_s8(analysis: RocketAnalysis) -> ClaimResult:
    """S8: in-flight recalibration futile; an exciting trajectory is necessary but not
    sufficient for sensability."""
    _require_three(analysis)
    t = analysis.model.t
    ratio = {p: float(_sigma(analysis, p)[-1] / _sigma(analysis, p)[0]) for p in PARAMETERS}
    calibrated = [p for p, r in ratio.items() if r < FUTILE]
    excited_not_sensible = []
    for i, (a, b) in enumerate(analysis.segments):
        k = analysis.epochs(a, b)
        excited_not_sensible += [f"{s}@tau{i + 1}" for s in STATE_NAMES
                                 if _e(analysis, s, i) >= IN_SO
                                 and _s(analysis, s)[k].mean() < SENSIBLE]
    later = np.flatnonzero(t > t[0] + TRANSIENT_S)
    never_excited = [s for s in STATE_NAMES
                     if all(_e(analysis, s, i) < IN_SO for i in range(3))]
    sensible_unexcited = [s for s in never_excited
                          if sensible_time(analysis, s, later) > BRIEF_S]
    best = min(ratio, key=ratio.get)
    checks = [check(f"smallest sigma_end/sigma_0 of an IMU parameter ({best})", ratio[best],
                    ">=", FUTILE, True),
              check("excited but not sensible (state, segment) pairs",
                    len(excited_not_sensible), ">=", 1),
              check("states sensible > 10 s without being excited", len(sensible_unexcited),
                    "==", 0)]
    listed = ", ".join(f"{p} {ratio[p]:.2f}" for p in calibrated) or "none"
    ours = (f"calibrated in flight: {listed}"
            f"; excited but not sensible: {', '.join(excited_not_sensible[:4]) or 'none'}"
            f"{' ...' if len(excited_not_sensible) > 4 else ''}; sensible without excitation: "
            f"{', '.join(sensible_unexcited) or 'none'}")
    return claim("S8", "In-flight recalibration is futile; an exciting trajectory is necessary "
                 "but not sufficient", "no parameter improves; excitation necessary, not "
                 "sufficient", ours, checks,
                 assumption=_sens_assumption(analysis, f"'calibrated' = sigma_end/sigma0 < "
                                                       f"{FUTILE}"))


EXCITABILITY_CLAIMS = (claim_x1, claim_x2, claim_x3, claim_x4, claim_x5, claim_x6, claim_x7)
SENSABILITY_CLAIMS = (claim_s1, claim_s2, claim_s3, claim_s4, claim_s5, claim_s6, claim_s7,
                      claim_s8)
CLAIM_IDS = tuple(f"X{i}" for i in range(1, 8)) + tuple(f"S{i}" for i in range(1, 9))


BASELINE_BASIS = ("fitted", "the baseline (sigma_V0 3 m/s, sigma_sg 5000 ppm, eta 1e-3) is "
                  "the set at which X1-X7 were made to hold, so X1-X7 are fitted there "
                  "(A-rocket-baseline)")
"""Basis of X1-X7 at the baseline and why (docs/assumptions.md, A-rocket-baseline)."""


def excitability_claims(analysis: RocketAnalysis) -> list[ClaimResult]:
    """X1-X7 (Fig. 2) evaluated on ``analysis``; basis "fitted" (:data:`BASELINE_BASIS`)."""
    basis, why = BASELINE_BASIS
    return [replace(c, depends_on=EXCITABILITY_DEPENDS, basis=basis,
                    assumption=f"{c.assumption}; {why}")
            for c in (claim(analysis) for claim in EXCITABILITY_CLAIMS)]


def sensability_claims(analysis: RocketAnalysis, quiet: RocketAnalysis | None = None
                       ) -> list[ClaimResult]:
    """S1-S8 (Figs. 3-5) evaluated on ``analysis`` (``quiet``: S5's counterfactual run,
    :func:`quiet_gyro_analysis`, computed when not given).

    Parameters
    ----------
    analysis : RocketAnalysis
        The analysis.
    quiet : RocketAnalysis or None, optional
        S5's counterfactual run; None computes it.
    """
    out = [claim_s5(analysis, quiet) if claim is claim_s5 else claim(analysis)
           for claim in SENSABILITY_CLAIMS]
    return [replace(c, depends_on=c.depends_on or SENSABILITY_DEPENDS) for c in out]


def claims_table(analysis: RocketAnalysis, which: str = "all") -> pd.DataFrame:
    """Table of claim results: ``which`` = ``"excitability"``, ``"sensability"`` or ``"all"``.

    Parameters
    ----------
    analysis : RocketAnalysis
        The analysis.
    which : {"excitability", "sensability", "all"}, optional
        Which claims.

    Returns
    -------
    pandas.DataFrame

    Raises
    ------
    NavlibInputError
        If ``which`` is unknown.
    """
    if which not in ("excitability", "sensability", "all"):
        raise NavlibInputError(f"which: expected 'excitability', 'sensability' or 'all', "
                               f"got {which!r}")
    results = []
    if which in ("excitability", "all"):
        results += excitability_claims(analysis)
    if which in ("sensability", "all"):
        results += sensability_claims(analysis)
    return claims_frame(results)
