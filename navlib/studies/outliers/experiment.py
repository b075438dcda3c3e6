"""The outlier experiment: T1-T4 for both outlier shapes (:func:`paper_tests`), re-scoring
with another recovery window, and the covariance figures (Fig. 10 correlation, Figs. 7 / 11
roll sigma)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np
import pandas as pd

from navlib._validation import finite_scalar
from navlib.covariance import group_correlation, sigma_in_frame
from navlib.errors import NavlibInputError
from navlib.filters.recovery import score_recovery
from navlib.studies.outliers.claims import conclusion_claims, outlier_claims
from navlib.studies.outliers.paper import PAPER_TESTS
from navlib.studies.outliers.response import (
    DEFAULTS,
    RT_ONLY_OPTIONS,
    FilterCache,
    OutlierStudy,
    default_trajectory,
    effective_bias_model,
    outlier_response,
    record_stride,
)

__all__ = ["CONCLUSION_RUNS", "correlation_fig10", "paper_tests", "rescore", "roll_sigma",
           "sigma_ratios"]

CONCLUSION_RUNS = {("C1", "ins_gps"): ("T1", "bp"), ("C1", "ins_gps_rt"): ("T1", "bp"),
                   ("C1", "ins_gps_att_rt"): ("T1", "bp"), ("C3", "ins_gps_att_rt"): ("T3", "roll")}
"""Spike runs beyond T1-T4: ``(run, solution) -> (test whose outlier is injected, watched
quantity)``. "C1": T1's GPS-velocity outlier on the solutions T1 does not run (conclusion 1,
"no solution" observes b_p); "C3": T3's RT outlier with attitude sensors (conclusion 3: the RT
only together with them). Each joins its filter's recursion of the T1-T4 responses."""


def _conclusion_requests(sol: str, outlier_time_s, biases: str) -> list[tuple]:
    """The (outlier, watch) requests of :data:`CONCLUSION_RUNS` on solution ``sol``."""
    return [(PAPER_TESTS[tid].outlier("spike", time=outlier_time_s), watch)
            for (run, s), (tid, watch) in CONCLUSION_RUNS.items()
            if s == sol and (watch != "bp" or "P" in biases.upper())]


def _capture(responses, window_first: float = 0.05, window_later: float = 5.0) -> dict:
    """T4 detail: fraction of the true roll error captured by the estimate shortly after the
    outlier and a few seconds later, for INS/GPS/att with and without RT."""
    out = {}
    for sol in ("ins_gps_att", "ins_gps_att_rt"):
        r = responses.get(("T4", sol, "spike"))
        if r is None:
            continue
        t_o = r.outlier.time
        for label, dt in (("first", window_first), ("later", window_later)):
            k = int(np.argmin(np.abs(r.t - (t_o + dt))))
            with np.errstate(invalid="ignore", divide="ignore"):
                out[f"{sol}_{label}"] = float(np.abs(r.estimate[k, 0]) / np.abs(r.truth[k, 0]))
    return out


def paper_tests(trajectory=None, *, shapes: Sequence[str] = ("spike", "step"),
                tests: Sequence[str] = ("T1", "T2", "T3", "T4"),
                biases: str = DEFAULTS["biases"], bias_model: str = DEFAULTS["bias_model"],
                window: float = DEFAULTS["window"], record_every: int | None = None,
                cache: FilterCache | None = None, divergence: bool = True,
                outlier_time_s: float | None = None, reuse: OutlierStudy | None = None,
                conclusions: bool = False, **model_options) -> OutlierStudy:
    """Run T1-T4 (docs/assumptions.md, launcher.md §6.4) on the launcher surrogate and judge the
    claims.

    Parameters
    ----------
    trajectory : Trajectory, optional
        Default :func:`default_trajectory` (150 s, 200 Hz).
    shapes : sequence of {"spike", "step", "pulse"}
        Outlier shapes to run (the pulse needs ``PaperTest.outlier(duration=...)``, so only
        spike and step are offered here).
    tests : sequence of str
        Tests to run; T1 (GPS position bias) is skipped when ``biases`` has no ``P``.
    biases, bias_model, window, **model_options
        As in :func:`outlier_response`.
    record_every : int, optional
        Default: keep epochs about 20 ms apart.
    divergence : bool
        Also report the T4 launcher-divergence response (Fig. 13). It is computed either
        way, in the recursion of the other responses of its filter, and kept in ``cache``
        (and the disk cache): a later study of the same model that reports it (the claims
        engine's ``a1_sign = -1`` reading after :func:`assumption_sensitivity`) then
        prepares no filter.
    outlier_time_s : float, optional
        Outlier time, s (default the paper's 50 s).
    reuse : OutlierStudy, optional
        A study on the same trajectory and configuration whose model options differ at
        most in the RT-only ones (:data:`RT_ONLY_OPTIONS`): its non-RT responses are the
        same and are taken over instead of rerun.
    conclusions : bool
        Also run the spikes of :data:`CONCLUSION_RUNS` (in the same recursions) and judge
        the claims they carry (:func:`~navlib.studies.outliers.claims.conclusion_claims`).
        Without it they are run all the same, in the recursions that run anyway, and kept
        in ``cache`` (and the disk cache) only: the claims engine's study of the same
        models (:mod:`~navlib.studies.outliers.assumptions`) then prepares no filter.
    """
    traj = trajectory if trajectory is not None else (
        cache.trajectory if cache is not None else default_trajectory())
    cache = cache if cache is not None else FilterCache(traj, size=1, **model_options)
    if record_every is None:
        record_every = record_stride(traj)
    for shape in shapes:
        if shape not in ("spike", "step"):
            raise NavlibInputError(f"shapes: expected 'spike' or 'step', got {shape!r}")
    unknown = [tid for tid in tests if tid not in PAPER_TESTS]
    if unknown:
        raise NavlibInputError(f"tests: unknown {unknown}; expected some of {list(PAPER_TESTS)}")
    # group by solution so each prepared filter is built once
    jobs = {}
    for tid in tests:
        if PAPER_TESTS[tid].watch == "bp" and "P" not in biases.upper():
            continue          # T1 watches the GPS-bias states: not applicable without them
        for sol in PAPER_TESTS[tid].solutions:
            jobs.setdefault(sol, []).append(tid)
    same = {}
    if reuse is not None:
        mine = {"biases": biases, "bias_model": effective_bias_model(biases, bias_model),
                "rate_hz": traj.rate_hz, "duration_s": float(traj.t[-1] - traj.t[0]),
                **model_options}
        theirs = dict(reuse.settings)
        keys = (set(mine) | set(theirs)) - {"window", "shapes"}
        differ = {k for k in keys if mine.get(k) != theirs.get(k)}
        if differ - set(RT_ONLY_OPTIONS):
            raise NavlibInputError(f"reuse: the studies differ in {sorted(differ)}, not only "
                                   f"in the RT-only options {RT_ONLY_OPTIONS}")
        same = {k: r for k, r in reuse.responses.items() if not k[1].endswith("_rt")
                and (outlier_time_s is None or r.outlier.time == outlier_time_s)}
    responses = {}
    for sol, tids in jobs.items():
        requests = [(PAPER_TESTS[tid].outlier(shape, time=outlier_time_s), PAPER_TESTS[tid].watch)
                    for tid in tids for shape in shapes if (tid, sol, shape) not in same]
        if "T4" in tids and sol == "ins_gps_att_rt":
            requests.append((PAPER_TESTS["T4"].outlier("spike", time=outlier_time_s), "ref_roll"))
        runs = (_conclusion_requests(sol, outlier_time_s, biases)
                if reuse is None or sol.endswith("_rt") else [])
        if conclusions:
            requests, runs = requests + runs, []
        if requests:              # one recursion for all of this filter's responses
            # (without ``conclusions`` their runs join it too, kept but not judged: the
            # claims engine judges them on the same filters after notebook 05)
            cache.unit_responses(sol, requests, biases=biases,
                                 bias_model=effective_bias_model(biases, bias_model),
                                 record_every=record_every, also=runs)
        for tid in tids:
            test = PAPER_TESTS[tid]
            for shape in shapes:
                if (tid, sol, shape) in same:
                    old = same[(tid, sol, shape)]
                    induced = old.induced if old.induced.shape[1] > 1 else old.induced[:, 0]
                    sigma = old.sigma if old.sigma.shape[1] > 1 else old.sigma[:, 0]
                    responses[(tid, sol, shape)] = replace(old, score=score_recovery(
                        old.t, induced, t_outlier=old.outlier.time, window=window,
                        sigma=sigma, averaging=DEFAULTS["averaging"]))
                    continue
                responses[(tid, sol, shape)] = outlier_response(
                    sol, test.outlier(shape, time=outlier_time_s), test.watch, biases=biases,
                    bias_model=bias_model, window=window, record_every=record_every,
                    cache=cache)
            if tid == "T4" and sol == "ins_gps_att_rt" and divergence:
                responses[("T4", sol, "divergence")] = outlier_response(
                    sol, test.outlier("spike", time=outlier_time_s), "ref_roll", biases=biases,
                    bias_model=bias_model, window=window, record_every=record_every,
                    cache=cache)
    extra = {}
    for (run, sol), (tid, watch) in CONCLUSION_RUNS.items() if conclusions else ():
        if watch == "bp" and "P" not in biases.upper():
            continue
        old = reuse.conclusions.get((run, sol)) if reuse is not None else None
        if old is not None and not sol.endswith("_rt"):
            extra[(run, sol)] = _rescored(old, window)
            continue
        extra[(run, sol)] = outlier_response(
            sol, PAPER_TESTS[tid].outlier("spike", time=outlier_time_s), watch, biases=biases,
            bias_model=bias_model, window=window, record_every=record_every, cache=cache)
    capture = _capture(responses)
    div = responses.get(("T4", "ins_gps_att_rt", "divergence"))
    if div is not None:
        k = div.t >= div.outlier.time + 5.0
        with np.errstate(invalid="ignore", divide="ignore"):
            capture["divergence_ratio"] = float(np.median(np.abs(div.estimate[k, 0])
                                                          / np.abs(div.truth[k, 0])))
    settings = {"biases": biases, "bias_model": effective_bias_model(biases, bias_model),
                "window": window, "shapes": tuple(shapes), "rate_hz": traj.rate_hz,
                "duration_s": float(traj.t[-1] - traj.t[0]), **model_options}
    study = OutlierStudy(responses, capture, [], settings, extra)
    return OutlierStudy(responses, capture, _claims(study), settings, extra)


def _claims(study: OutlierStudy) -> list:
    """T1-T4 and the T4 detail, and the conclusion claims where their runs were made."""
    return outlier_claims(study) + (conclusion_claims(study) if study.conclusions else [])


def _rescored(r, window: float):
    """``r`` scored with another recovery window."""
    induced = r.induced if r.induced.shape[1] > 1 else r.induced[:, 0]
    sigma = r.sigma if r.sigma.shape[1] > 1 else r.sigma[:, 0]
    return replace(r, score=score_recovery(r.t, induced, t_outlier=r.outlier.time,
                                           window=window, sigma=sigma,
                                           averaging=DEFAULTS["averaging"]))


def rescore(study: OutlierStudy, window: float) -> OutlierStudy:
    """The same responses scored with another recovery window (no new filter run).

    Parameters
    ----------
    study : OutlierStudy
        The study.
    window : float
        Recovery window, s.

    Returns
    -------
    OutlierStudy

    Raises
    ------
    NavlibInputError
        If ``window`` is not a positive number.
    """
    window = finite_scalar(window, "window", 0.0, low_open=True)
    responses = {key: _rescored(r, window) for key, r in study.responses.items()}
    extra = {key: _rescored(r, window) for key, r in study.conclusions.items()}
    settings = {**study.settings, "window": window}
    new = OutlierStudy(responses, study.capture, [], settings, extra)
    return OutlierStudy(responses, study.capture, _claims(new), settings, extra)


def correlation_fig10(trajectory=None, *, duration: float = 5.0,
                      solution: str = "ins_gps_rt", biases: str = DEFAULTS["biases"],
                      bias_model: str = DEFAULTS["bias_model"],
                      cache: FilterCache | None = None, **model_options) -> pd.DataFrame:
    """Correlation of the body-axis attitude error ``T_E^B psi`` with the divergence
    ``psi_ref`` per axis over the first ``duration`` seconds (Fig. 10, docs/assumptions.md,
    launcher.md §6.3).

    Returns a tidy frame ``t, axis, rho`` (axis ``roll``/``pitch``/``yaw``); epochs where
    either variance is zero (the pad: ``psi_ref`` starts exactly known) are NaN.

    Parameters
    ----------
    trajectory : Trajectory or None, optional
        Reference trajectory (default the launcher ascent).
    duration : float, optional
        Time span, s.
    solution : str, optional
        Solution with the RT.
    biases : str, optional
        Bias states, letters of ``"GAP"``.
    bias_model : {"markov", "random_walk"}, optional
        Bias model.
    cache : FilterCache or None, optional
        Prepared filters to reuse.
    **model_options
        Keywords of :func:`navlib.models.launcher.launcher`.
    """
    duration = finite_scalar(duration, "duration", 0.0, low_open=True)
    bias_model = effective_bias_model(biases, bias_model)
    if cache is None:
        traj = trajectory if trajectory is not None else default_trajectory()
        cache = FilterCache(traj, size=1, **model_options)
    cov = cache.summary(solution, biases, bias_model)
    if "psi_ref_x" not in cov.attitude_names:
        raise NavlibInputError(f"solution: {solution!r} has no launcher divergence "
                               "(psi_ref); use an RT solution")
    t = cov.t
    keep = t <= t[0] + duration + 1e-9
    C_e_b = np.swapaxes(cache.trajectory.attitude.as_matrix(), 1, 2)
    psi = cov.index([f"psi_{a}" for a in "xyz"])
    ref = cov.index([f"psi_ref_{a}" for a in "xyz"])
    rho = group_correlation(cov.attitude[keep], psi, ref, C_a=C_e_b[keep])
    return pd.DataFrame({
        "t": np.repeat(t[keep], 3),
        "axis": np.tile(np.array(["roll", "pitch", "yaw"], dtype=object), keep.sum()),
        "rho": rho.ravel(),
    })


def roll_sigma(trajectory=None, *, pairs=(("ins_gps", "ins_gps_rt"),
                                          ("ins_gps_att", "ins_gps_att_rt")),
               biases: str = DEFAULTS["biases"], bias_model: str = DEFAULTS["bias_model"],
               stride: int | None = None, cache: FilterCache | None = None,
               **model_options) -> pd.DataFrame:
    """Body-axis attitude-error sigma of each solution (Figs. 7 and 11, docs/assumptions.md,
    launcher.md §6.2 item 6).

    Returns a tidy frame ``t, solution, axis, sigma`` (rad), every ``stride``-th epoch
    (default about 20 ms apart).

    Parameters
    ----------
    trajectory : Trajectory or None, optional
        Reference trajectory (default the launcher ascent).
    pairs : sequence of (str, str), optional
        ``(without RT, with RT)`` solution pairs.
    biases : str, optional
        Bias states, letters of ``"GAP"``.
    bias_model : {"markov", "random_walk"}, optional
        Bias model.
    stride : int or None, optional
        Record stride, samples.
    cache : FilterCache or None, optional
        Prepared filters to reuse.
    **model_options
        Keywords of :func:`navlib.models.launcher.launcher`.
    """
    bias_model = effective_bias_model(biases, bias_model)
    if cache is None:
        traj = trajectory if trajectory is not None else default_trajectory()
        cache = FilterCache(traj, size=1, **model_options)
    traj = cache.trajectory
    stride = stride or record_stride(traj)
    C_e_b = np.swapaxes(traj.attitude.as_matrix(), 1, 2)[::stride]
    frames = []
    for sol in dict.fromkeys(s for pair in pairs for s in pair):
        cov = cache.summary(sol, biases, bias_model)
        psi = cov.index([f"psi_{a}" for a in "xyz"])
        sig = sigma_in_frame(cov.attitude[::stride], psi, C_e_b)
        t = cov.t[::stride]
        frames.append(pd.DataFrame({
            "t": np.repeat(t, 3), "solution": sol,
            "axis": np.tile(np.array(["roll", "pitch", "yaw"], dtype=object), t.size),
            "sigma": sig.ravel(),
        }))
    return pd.concat(frames, ignore_index=True)


def sigma_ratios(a: str = "ins_gps", b: str = "ins_gps_rt", *, cache: FilterCache,
                 biases: str = DEFAULTS["biases"], bias_model: str = DEFAULTS["bias_model"],
                 after: float = 10.0) -> pd.Series:
    """RMS sigma of solution ``b`` over that of ``a`` for every common state, after
    ``after`` seconds (< 1: ``b`` estimates the state better).

    Parameters
    ----------
    a, b : str
        Solutions compared (``b`` over ``a``).
    cache : FilterCache
        Prepared filters.
    biases : str, optional
        Bias states, letters of ``"GAP"``.
    bias_model : {"markov", "random_walk"}, optional
        Bias model.
    after : float, optional
        Start of the RMS, s.

    Returns
    -------
    pandas.Series
    """
    bias_model = effective_bias_model(biases, bias_model)
    ca = cache.summary(a, biases, bias_model)
    cb = cache.summary(b, biases, bias_model)
    keep = ca.t >= ca.t[0] + after
    common = [s for s in ca.state_names if s in cb.state_names]
    ia = [ca.state_names.index(s) for s in common]
    ib = [cb.state_names.index(s) for s in common]

    def rms(cov, idx):
        return np.sqrt(np.mean(cov.variances[keep][:, idx], axis=0))

    with np.errstate(invalid="ignore", divide="ignore"):
        return pd.Series(rms(cb, ib) / rms(ca, ia), index=common, name=f"{b}/{a}")
