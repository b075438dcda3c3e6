"""T1-T4 (Beaudoin et al. 2018, §4.2) and Figs. 7, 10, 11 as claims judged by the one rule of
:mod:`navlib.studies.claims`."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd

from navlib.models.launcher import SOLUTION_LABELS
from navlib.studies.claims import Check, ClaimResult, check, claim
from navlib.studies.outliers.paper import PAPER_TESTS
from navlib.studies.outliers.response import OutlierResponse, OutlierStudy

__all__ = ["AFFECTED", "SAME_RANGE", "claim_c1_outlier", "claim_c3_outlier", "claim_f10",
           "claim_r424", "claim_roll_sigma", "claim_t4_detail", "claim_t4_time", "claim_test",
           "conclusion_claims", "covariance_claims", "explained", "explained_f7", "outlier_claims"]


def _fmt(r: OutlierResponse) -> str:
    s = r.score
    if s.verdict == "unaffected":
        return f"{SOLUTION_LABELS[r.solution]}: unaffected (channel absent)"
    return (f"{SOLUTION_LABELS[r.solution]}: {s.verdict} (retained {s.retained:.2f}, "
            f"tau {s.time_constant:.0f} s, residual {s.residual:.2g} = "
            f"{s.residual_vs_3sigma:.2g} x 3 sigma)")


AFFECTED = 0.1
"""An outlier "affects" a solution when the peak of the error it induces reaches this share
of the filter's sigma at the end of the window (docs/assumptions.md, A-T3-affected): a
non-zero peak alone would pass for any round-off."""


def _outcome_check(r: OutlierResponse, want: str) -> Check:
    """The paper's outcome for one solution as a check on our recovery score: "static
    error" = retained fraction above 1/e, "recovers" = at most 1/e, "affected" = a peak of
    at least :data:`AFFECTED` of the filter sigma, "unaffected" = below it."""
    label = SOLUTION_LABELS[r.solution]
    s = r.score
    if want in ("affected", "unaffected"):
        ratio = s.peak / s.sigma_end if s.sigma_end > 0 else float("nan")
        return check(f"{label}: peak of the induced error / filter sigma", ratio,
                     ">=" if want == "affected" else "<", AFFECTED, True)
    op = ">" if want == "static error" else "<="
    return check(f"{label}: retained fraction after {s.window:g} s ({want})", s.retained, op,
                 s.recovered_fraction, True)


def _base_assumption(study: OutlierStudy, shape: str) -> str:
    settings = study.settings
    return (f"linear KF, {settings.get('biases') or 'no'} biases "
            f"({settings.get('bias_model')}), {shape} outlier, window "
            f"{settings.get('window'):g} s, a1_sign {settings.get('a1_sign', 1):+g}; "
            "'recovers' = retained <= 1/e")


def claim_test(study: OutlierStudy, tid: str, shape: str = "spike") -> ClaimResult | None:
    """One of T1-T4 from the study's ``shape`` runs (None when they were not run).

    Each solution's reported outcome is a headline check on our recovery score (see
    :func:`_outcome_check`). A solution the outlier cannot reach (T3's INS/GPS has no RT
    channel) is shown but not checked: its "unaffected" holds by construction.

    Parameters
    ----------
    study : OutlierStudy
        The study with its runs.
    tid : str
        Test id, ``"T1"`` to ``"T4"``.
    shape : str, optional
        Outlier shape of the runs read.
    """
    test = PAPER_TESTS[tid]
    rs = [study.responses.get((tid, sol, shape)) for sol in test.solutions]
    if any(r is None for r in rs):
        return None
    other = "step" if shape == "spike" else "spike"
    checks = [_outcome_check(r, test.reported[r.solution]) for r in rs if r.applied]
    ours = "; ".join(_fmt(r) for r in rs)
    alt = [study.responses.get((tid, sol, other)) for sol in test.solutions]
    if all(a is not None for a in alt):
        ours += f". With a {other}: " + ", ".join(
            f"{SOLUTION_LABELS[a.solution]} {a.score.verdict}" for a in alt)
    paper = "; ".join(f"{SOLUTION_LABELS[s]}: {v}" for s, v in test.reported.items())
    absent = [SOLUTION_LABELS[r.solution] for r in rs if not r.applied]
    return claim(tid, test.description, paper, ours, checks,
                 assumption=_base_assumption(study, shape) + (
                     f"; not checked (channel absent, unaffected by construction): "
                     f"{', '.join(absent)}" if absent else ""),
                 depends_on=("window", "a1_sign"))


def claim_t4_detail(study: OutlierStudy, shape: str = "spike") -> ClaimResult | None:
    """T4's detail (Figs. 12-13): with RT the roll error is captured faster at first, then
    corrected more slowly, and the divergence is underestimated (None without the T4
    capture fractions).

    Parameters
    ----------
    study : OutlierStudy
        The study with its runs.
    shape : str, optional
        Outlier shape of the runs read.
    """
    cap = study.capture
    if not {"ins_gps_att_first", "ins_gps_att_rt_first"} <= set(cap):
        return None
    return claim(
        "T4-detail",
        "With RT the roll error is captured faster at first, then corrected more slowly; "
        "the launcher divergence is then underestimated (Figs. 12-13)",
        "faster first capture, slower correction, divergence underestimated",
        f"captured fraction after 0.05 s: RT {cap['ins_gps_att_rt_first']:.3f} vs "
        f"{cap['ins_gps_att_first']:.3f}; after 5 s: RT {cap['ins_gps_att_rt_later']:.3f} "
        f"vs {cap['ins_gps_att_later']:.3f}; estimated/true divergence (median after "
        f"+5 s) {cap.get('divergence_ratio', np.nan):.2f}",
        [check("captured fraction after 0.05 s, RT minus no RT",
               cap["ins_gps_att_rt_first"] - cap["ins_gps_att_first"], ">", 0.0, True),
         check("captured fraction after 5 s, RT minus no RT",
               cap["ins_gps_att_rt_later"] - cap["ins_gps_att_later"], "<", 0.0),
         check("estimated / true divergence after +5 s",
               cap.get("divergence_ratio", np.nan), "<", 1.0)],
        assumption=_base_assumption(study, shape), depends_on=("a1_sign",))


def outlier_claims(study: OutlierStudy, shape: str = "spike") -> list[ClaimResult]:
    """T1-T4 (:func:`claim_test`) and the T4 detail (:func:`claim_t4_detail`) from a
    study's ``shape`` runs, judged by the claims engine.

    Parameters
    ----------
    study : OutlierStudy
        The study with its runs.
    shape : str, optional
        Outlier shape of the runs read.
    """
    claims = [claim_test(study, tid, shape) for tid in PAPER_TESTS]
    claims.append(claim_t4_detail(study, shape))
    return [c for c in claims if c is not None]


SAME_RANGE = 2.0
"""Two recoveries are "within the same time range" (T4) when their time constants differ by
at most this factor (docs/assumptions.md, A-T4-time-range)."""


def _decay_text(r: OutlierResponse) -> str:
    """How the induced error of ``r`` decays, measured: retained share and time constant."""
    s = r.score
    return (f"{SOLUTION_LABELS[r.solution]} retains {s.retained:.3g} of the induced error "
            f"after {s.window:g} s (time constant {s.time_constant:.3g} s)")


def _outcome_explanation(r: OutlierResponse, want: str, magnitude: float) -> str:
    """The measured cause of one failed outcome check (:func:`_outcome_check`)."""
    s = r.score
    if want == "affected":
        ratio = s.peak / s.sigma_end if s.sigma_end > 0 else float("nan")
        return (f"{SOLUTION_LABELS[r.solution]}: the outlier moves the estimate by "
                f"{ratio:.3g} of the filter sigma; the response is linear in the outlier, so "
                f"reaching {AFFECTED:g} sigma needs {magnitude * AFFECTED / ratio:.3g} instead "
                f"of the paper's {magnitude:g} (x{AFFECTED / ratio:.3g})")
    if want == "recovers":
        return (_decay_text(r) + f": a 1/e recovery needs a window of about "
                f"{s.time_constant:.3g} s")
    return _decay_text(r) + ": the filter corrects it within the window"


def explained(result: ClaimResult, study: OutlierStudy) -> ClaimResult:
    """``result`` (one of T1-T4 or a conclusion claim) with the measured cause of each failed
    outcome check as its explanation (the engine's table; notebook 05 shows the claims
    without it).

    Parameters
    ----------
    result : ClaimResult
        The judged claim.
    study : OutlierStudy
        The study whose responses hold the measured causes.
    """
    if result.verdict in ("reproduced", "not evaluated") or result.explanation:
        return result
    texts = []
    for c in result.checks:
        if c.passed:
            continue
        for r in (*study.responses.values(), *study.conclusions.values()):
            label = SOLUTION_LABELS[r.solution]
            if r.outlier.shape == "spike" and c.name.startswith(label + ":") and \
                    r.watch != "ref_roll" and (result.claim_id, r.outlier.channel) in _RUNS:
                want = ("affected" if "peak" in c.name else
                        "recovers" if "(recovers)" in c.name else "static error")
                texts.append(_outcome_explanation(r, want, r.outlier.magnitude))
                break
    return replace(result, explanation="; ".join(dict.fromkeys(texts))) if texts else result


_RUNS = {("T1", "gnss_vel"), ("T2", "gyro_x"), ("T3", "rt_x"), ("T4", "gyro_x"),
         ("C1-bp-outlier", "gnss_vel"), ("C3-RT-outlier", "rt_x"), ("R-4.2.4", "gyro_x"),
         ("T4-time", "gyro_x")}
"""The outlier channel each claim's responses carry (T2 and T4 share the gyro spike but not
their solutions)."""


def _spike(study: OutlierStudy, key: tuple) -> OutlierResponse | None:
    return study.responses.get((*key, "spike")) if key[0].startswith("T") else \
        study.conclusions.get(key)


def claim_c1_outlier(study: OutlierStudy) -> ClaimResult | None:
    """C1-bp-outlier: conclusion 1 over all four solutions: T1's GPS-velocity outlier leaves
    a static error in the (Markov) GPS bias of every solution, not only the one T1 shows."""
    keys = [("T1", "ins_gps_att"), ("C1", "ins_gps"), ("C1", "ins_gps_rt"),
            ("C1", "ins_gps_att_rt")]
    rs = [_spike(study, k) for k in keys]
    if any(r is None for r in rs):
        return None
    return claim(
        "C1-bp-outlier", "No solution makes the GPS position bias observable: the velocity "
        "outlier leaves a static b_p error in all four solutions (conclusion 1)",
        "static error in b_p (shown for INS/GPS/att, concluded for all)",
        "; ".join(_fmt(r) for r in rs),
        [_outcome_check(r, "static error") for r in rs],
        assumption=_base_assumption(study, "spike") + "; T1's outlier on every solution",
        depends_on=("window", "a1_sign"))


def claim_c3_outlier(study: OutlierStudy) -> ClaimResult | None:
    """C3-RT-outlier: conclusion 3's reason: an RT outlier leaves a static roll error in
    INS/GPS + RT, which the attitude sensors correct (INS/GPS/att + RT)."""
    return _static_then_corrected(
        study, "C3-RT-outlier", (("T3", "ins_gps_rt"), ("C3", "ins_gps_att_rt")),
        "The RT is recommended only with attitude sensors: without them an RT outlier leaves a "
        "static roll error, with them it is corrected (conclusion 3)",
        "INS/GPS + RT sensitive to RT outliers; with attitude sensors not", "T3's RT outlier")


def claim_r424(study: OutlierStudy) -> ClaimResult | None:
    """R-4.2.4: attitude sensors overcome the RT solution's structural unobservability: the
    gyro outlier's roll error stays with INS/GPS + RT (T2) and is corrected with
    INS/GPS/att + RT (T4)."""
    return _static_then_corrected(
        study, "R-4.2.4", (("T2", "ins_gps_rt"), ("T4", "ins_gps_att_rt")),
        "Attitude sensors overcome the structural unobservability of the RT solution: the roll "
        "error it cannot correct alone is corrected with them (§4.2.4)",
        "static roll error without attitude sensors, corrected with them",
        "T2's and T4's gyro outlier")


def _static_then_corrected(study: OutlierStudy, claim_id: str, cases, statement: str,
                           paper: str, outlier_note: str) -> ClaimResult | None:
    """A claim that the first case's outlier leaves a static error and the second case's is
    corrected (the spike runs of ``cases``: (test, solution) pairs); None when a run is
    missing."""
    rs = [_spike(study, case) for case in cases]
    if any(r is None for r in rs):
        return None
    return claim(
        claim_id, statement, paper, "; ".join(_fmt(r) for r in rs),
        [_outcome_check(rs[0], "static error"), _outcome_check(rs[1], "recovers")],
        assumption=_base_assumption(study, "spike") + "; " + outlier_note,
        depends_on=("window", "a1_sign"))


def claim_t4_time(study: OutlierStudy) -> ClaimResult | None:
    """T4-time: with and without RT the roll error is corrected "within the same time range"
    (time constants within a factor :data:`SAME_RANGE`, A-T4-time-range)."""
    rs = [_spike(study, ("T4", "ins_gps_att")), _spike(study, ("T4", "ins_gps_att_rt"))]
    if any(r is None for r in rs):
        return None
    tau = [r.score.time_constant for r in rs]
    ratio = tau[1] / tau[0] if tau[0] > 0 else float("nan")
    return claim(
        "T4-time", "With and without RT the roll error is corrected within the same time "
        "range (T4, Fig. 12)", "both correct within the same time range",
        f"time constants: INS/GPS/att {tau[0]:.3g} s, + RT {tau[1]:.3g} s (ratio {ratio:.3g})",
        [check("recovery time constant RT / no RT", ratio, "in",
               (1.0 / SAME_RANGE, SAME_RANGE), True)],
        assumption=_base_assumption(study, "spike") + f"; 'same time range' = time constants "
                   f"within a factor {SAME_RANGE:g}", depends_on=("window", "a1_sign"),
        explanation="" if 1.0 / SAME_RANGE <= ratio <= SAME_RANGE else
        "; ".join(_decay_text(r) for r in rs))


def conclusion_claims(study: OutlierStudy) -> list[ClaimResult]:
    """§4.2.4, conclusions 1 and 3 and T4's time range from a study run with
    ``conclusions=True`` (:func:`~navlib.studies.outliers.paper_tests`)."""
    claims = [claim_c1_outlier(study), claim_c3_outlier(study), claim_r424(study),
              claim_t4_time(study)]
    return [c for c in claims if c is not None]


def claim_f10(correlation: pd.DataFrame, rho_threshold: float = -0.9) -> ClaimResult:
    """Fig. 10: attitude error (body axes) and launcher divergence almost perfectly
    negatively correlated over the first 5 s (median rho at most ``rho_threshold`` on every
    axis).

    Parameters
    ----------
    correlation : pandas.DataFrame
        Correlations per time and axis (columns ``t``, ``axis``, ``rho``).
    rho_threshold : float, optional
        Largest median correlation that counts as "almost perfectly negative".
    """
    rho = correlation.dropna().groupby("axis")["rho"]
    worst = rho.max()                      # closest to zero over the window
    median = rho.median()
    axes = [a for a in ("roll", "pitch", "yaw") if a in median]
    return claim(
        "F10", "Attitude error (body axes) and launcher divergence are almost perfectly "
        "negatively correlated over the first 5 s (INS/GPS + RT)", "rho ~ -1",
        ", ".join(f"{a}: median {median[a]:+.3f} (max {worst[a]:+.3f})" for a in axes),
        [check("largest per-axis median rho", float(median[axes].max()) if axes else np.nan,
               "<=", rho_threshold, True)], basis="by construction",
        assumption=f"'almost perfect' = median rho <= {rho_threshold} on every axis; by "
                   "construction (A-F10): the RT measures attitude error plus divergence "
                   "without noise, so rho is -1 whatever the wind (x1, x100, x1e4 give -1.000)",
        depends_on=("sigma_wind",))


def _rms_sigma(sigma: pd.DataFrame, solution: str, axis: str) -> float:
    """RMS of a solution's sigma about ``axis`` after its first 10 s."""
    sel = sigma[(sigma.solution == solution) & (sigma.axis == axis)]
    late = sel[sel.t >= sel.t.min() + 10.0]
    return float(np.sqrt(np.mean(late.sigma ** 2))) if len(late) else np.nan


def claim_roll_sigma(cid: str, sigma: pd.DataFrame, ratios: pd.Series | None = None,
                     ratio_threshold: float = 0.5, improved: float = 0.9
                     ) -> ClaimResult | None:
    """Fig. 7 (``cid`` "F7", INS/GPS) or Fig. 11 ("F11", INS/GPS/att): the RT greatly lowers
    the roll sigma (RMS ratio RT / no RT at most ``ratio_threshold``); for Fig. 7 pitch, yaw
    and (with ``ratios`` from :func:`sigma_ratios`) every non-attitude state keep a ratio of
    at least ``improved``. None when ``sigma`` lacks the two solutions.

    Parameters
    ----------
    cid : {"F7", "F11"}
        Which figure.
    sigma : pandas.DataFrame
        Sigma histories with a ``solution`` column, rad.
    ratios : pandas.Series or None, optional
        :func:`sigma_ratios` of the other states.
    ratio_threshold : float, optional
        Largest RMS ratio RT / no RT that counts as "greatly lowered".
    improved : float, optional
        Smallest ratio that counts as "not improved".
    """
    (a, b), text = {"F7": (("ins_gps", "ins_gps_rt"), "INS/GPS"),
                    "F11": (("ins_gps_att", "ins_gps_att_rt"), "INS/GPS/att")}[cid]
    if not {a, b} <= set(sigma.solution):
        return None
    r = {ax: _rms_sigma(sigma, b, ax) / _rms_sigma(sigma, a, ax)
         for ax in ("roll", "pitch", "yaw")}
    ours = "RMS sigma after 10 s, RT / no RT: " + ", ".join(
        f"{ax} {v:.2g}" for ax, v in r.items())
    checks = [check("roll sigma RT / no RT", r["roll"], "<=", ratio_threshold, True)]
    paper = "roll sigma greatly reduced"
    if cid == "F7":
        paper += "; all other estimates not improved"
        checks.append(check("smallest of pitch, yaw sigma RT / no RT",
                            min(r["pitch"], r["yaw"]), ">=", improved))
        if ratios is not None:
            others = ratios[[not s.startswith("psi") for s in ratios.index]]
            better = others[others < improved]
            checks.append(check("non-attitude states improved by the RT", len(better),
                                "==", 0))
            ours += (f"; other states improved (ratio < {improved}): "
                     + (", ".join(f"{s} {v:.2f}" for s, v in better.items())
                        if len(better) else "none"))
    else:
        paper += " even with attitude sensors"
    return claim(
        cid, f"The RT greatly lowers the roll sigma of {text}", paper, ours, checks,
        assumption=f"'greatly' = ratio <= {ratio_threshold}; 'not improved' = ratio >= "
                   f"{improved}", depends_on=("a1_sign",))


def explained_f7(result: ClaimResult) -> ClaimResult:
    """F7 with the measured cause of its failed "not improved" checks (engine's table)."""
    if result.claim_id != "F7" or result.verdict == "reproduced" or result.explanation:
        return result
    values = {c.name: c.value for c in result.checks}
    return replace(result, explanation=(
        f"the RT lowers pitch/yaw as much as roll (smallest pitch, yaw ratio "
        f"{values.get('smallest of pitch, yaw sigma RT / no RT', np.nan):.3g}, roll "
        f"{values.get('roll sigma RT / no RT', np.nan):.3g}): its pseudo-measurement (eq. 8) "
        "observes attitude error plus divergence on all three axes without noise, so it "
        "improves every axis; the paper's 'all other estimates are not improved' fits an RT "
        "on roll only, the simplification its future work proposes"))


def covariance_claims(correlation: pd.DataFrame, sigma: pd.DataFrame,
                      ratios: pd.Series | None = None, rho_threshold: float = -0.9,
                      ratio_threshold: float = 0.5, improved: float = 0.9
                      ) -> list[ClaimResult]:
    """Fig. 10 (:func:`claim_f10`) and Figs. 7 / 11 (:func:`claim_roll_sigma`), judged by
    the claims engine.

    "Greatly reduced" = an RMS sigma ratio RT / no RT at most ``ratio_threshold``; Fig. 7's
    "all other estimates are not improved" = pitch, yaw and (with ``ratios`` from
    :func:`sigma_ratios`) every non-attitude state keep a ratio of at least ``improved``.

    Parameters
    ----------
    correlation : pandas.DataFrame
        Correlations for Fig. 10 (:func:`claim_f10`).
    sigma : pandas.DataFrame
        Sigma histories for Figs. 7 and 11.
    ratios : pandas.Series or None, optional
        :func:`sigma_ratios` of the other states.
    rho_threshold, ratio_threshold, improved : float, optional
        Thresholds of :func:`claim_f10` and :func:`claim_roll_sigma`.
    """
    claims = [claim_f10(correlation, rho_threshold)]
    claims += [claim_roll_sigma(cid, sigma, ratios, ratio_threshold, improved)
               for cid in ("F7", "F11")]
    return [c for c in claims if c is not None]
