"""Beaudoin et al. (2018) covariance evolution: the filter sigmas of Figs. 2, 3, 5, 6
(docs/assumptions.md, launcher.md §7.3), one stacked recursion per case over the initial sigmas of
the declared set."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pandas as pd

from navlib import cache
from navlib.covariance import sigma_in_frame
from navlib.errors import NavlibInputError
from navlib.filters import linear_steps
from navlib.kalman import PINV_RTOL, FactoredNoise, covariance_recursion, symmetrize
from navlib.models.launcher import ASSUMED, launcher, sensor_values
from navlib.studies.launcher.assumptions import EVOLUTION_GRID, PAD_CASES, SURVEYED_PAD_M
from navlib.trajectory import launcher_ascent

__all__ = ["EVOLUTION_CASES", "covariance_evolution", "evolution_grid", "evolution_tables"]

EVOLUTION_CASES = {
    "gps/none": ("ins_gps", "", "none", "kf", 1.0),
    "ins-only/none": ("ins_gps", "", "none", "ins_only", 1.0),
    "ideal-gps/none": ("ins_gps", "", "none", "ideal", 1.0),
    "gps/GAP/markov": ("ins_gps", "GAP", "markov", "kf", 1.0),
    "att/GAP/markov": ("ins_gps_att", "GAP", "markov", "kf", 1.0),
    "att/GAP/random_walk": ("ins_gps_att", "GAP", "random_walk", "kf", 1.0),
    "ins-only/GAP/markov": ("ins_gps_att", "GAP", "markov", "ins_only", 1.0),
    "att/GAP/markov x1000": ("ins_gps_att", "GAP", "markov", "kf", 1000.0),
    "att/GAP/random_walk x1000": ("ins_gps_att", "GAP", "random_walk", "kf", 1000.0),
    "ins-only/GAP/markov x1000": ("ins_gps_att", "GAP", "markov", "ins_only", 1000.0),
}
"""The covariance runs of Figs. 2, 3, 5, 6 (spec launcher.md §7.3): name -> (solution,
biases, bias model, aiding, gyro-bias-stability factor). Aiding ``kf`` = the solution's
measurements at every sample, ``ins_only`` = no update (:func:`navlib.covariance.
ins_only_covariance`, same F and Q), ``ideal`` = the GPS with zero noise. Which solution the
paper's Fig. 5 uses is not stated: INS/GPS + attitude sensors with GAP, the configuration of
§4.2.2 (Fig. 3)."""


def covariance_evolution(trajectory=None, cases=None, *, quick: bool = False,
                         **model_kw) -> pd.DataFrame:
    """Final filter sigmas of the covariance-evolution cases (Figs. 2, 3, 5, 6).

    Parameters
    ----------
    trajectory : Trajectory, optional
        Default the launcher ascent (150 s, 200 Hz); ``quick``: 80 s at 20 Hz.
    cases : mapping, optional
        Name -> (solution, biases, bias_model, aiding, gyro-bias factor); default
        :data:`EVOLUTION_CASES`.
    **model_kw
        Passed to :func:`navlib.models.launcher`.

    Returns
    -------
    DataFrame
        One row per case: ``case, solution, biases, bias_model, aiding, gyro_factor`` and
        the sigma at the end of the run (RMS over the three axes) of ``roll, pitch, yaw``
        (body axes, rad), ``gyro_bias`` (rad/s), ``accel_bias`` (m/s^2), ``gps_bias`` (m)
        (NaN where the model has no such state), and their initial values ``*_0``.
    """
    return _evolution_tables(trajectory, cases, quick, [model_kw])[0]


def _evolution_tables(trajectory, cases, quick: bool, model_kws,
                      also: tuple | None = None) -> list[pd.DataFrame]:
    """:func:`covariance_evolution` for several ``model_kw`` that differ only in the initial
    sigmas (``sigma0_*``, which enter P0 alone): the per-step F, L, H, R of each case are
    built once and every variant's recursion runs in one stacked recursion over the
    variants' P0 (the recursion of :func:`navlib.covariance.kalman_covariances`, the same
    numbers as one recursion per variant; :func:`_evolution_rows`).

    ``also``: ``(names, model_kw)``, some of the cases at one more such variant, run in the
    same stacked recursions when the tables are built and kept on disk as
    :func:`covariance_evolution` of those cases (not returned).
    """
    if trajectory is None:
        trajectory = launcher_ascent(duration_s=80.0, rate_hz=20.0) if quick \
            else launcher_ascent()
    cases = EVOLUTION_CASES if cases is None else dict(cases)
    # each variant's table is also kept on disk (navlib.cache): the claims engine reads
    # the tables notebook 02 computed (evolution_grid), a variant missing there is built
    kept = cache.Scope(__name__, "covariance_evolution", trajectory, cases)
    tables = dict(enumerate(kept.get(kw) for kw in model_kws))
    todo = [i for i, (found, _) in tables.items() if not found]
    if todo:
        built, extra = _evolution_build(trajectory, cases, [model_kws[i] for i in todo], also)
        for i, table in zip(todo, built, strict=True):
            kept.put(model_kws[i], table)
            tables[i] = (True, table)
        if also is not None:
            names, kw = also
            cache.Scope(__name__, "covariance_evolution", trajectory,
                        {name: cases[name] for name in names}).put(kw, extra)
    return [table for _, table in tables.values()]


def evolution_tables(trajectory, model_kws, cases=None) -> list[pd.DataFrame]:
    """:func:`covariance_evolution` on ``trajectory`` for each keyword set of ``model_kws``
    (the sets may differ only in the initial sigmas ``sigma0_*``: one stacked recursion per
    case serves them all)."""
    return _evolution_tables(trajectory, cases, False, list(model_kws))


def _evolution_build(trajectory, cases, model_kws, also=None
                     ) -> tuple[list[pd.DataFrame], pd.DataFrame | None]:
    """The tables of :func:`_evolution_tables`, computed, and the table of its ``also``
    variant (None without one)."""
    names, also_kw = ((), None) if also is None else (tuple(also[0]), also[1])
    shared = {k: v for k, v in model_kws[0].items() if not k.startswith("sigma0_")}
    if any({k: v for k, v in kw.items() if not k.startswith("sigma0_")} != shared
           for kw in [*model_kws, *([also_kw] if names else [])]):  # pragma: no cover
        raise NavlibInputError("model_kws: variants may differ only in sigma0_*")
    gyro_bias = sensor_values()["gyro_bias"]
    C_e_b = np.swapaxes(trajectory.attitude.as_matrix(), 1, 2)
    # the cases that share a model (solution, biases, bias model, gyro factor) are run one
    # after the other on its steps, built once (the model is built only to be prepared:
    # linear_steps may form F and Gamma in its arrays); the rows keep the order of ``cases``
    by_model: dict[tuple, list] = {}
    for order, (name, (solution, biases, bias_model, aiding, factor)) in \
            enumerate(cases.items()):
        if aiding not in ("kf", "ins_only", "ideal"):
            raise NavlibInputError(f"cases[{name!r}]: aiding must be 'kf', 'ins_only' or "
                                   f"'ideal', got {aiding!r}")
        by_model.setdefault((solution, biases, bias_model, factor), []).append(
            (order, (name, solution, biases, bias_model, aiding, factor)))
    rows = [[None] * len(cases) for _ in model_kws]
    also_rows = [None] * len(names)
    for (solution, biases, bias_model, factor), model_cases in by_model.items():
        extra = {"gyro_bias": gyro_bias * factor} if factor != 1.0 else {}
        config = (solution, biases, bias_model)
        steps = linear_steps(launcher(*config, trajectory, **model_kws[0], **extra),
                             with_q=False, own_model=True)
        P0s = [steps.P0, *(_variant_P0(config, trajectory, {**kw, **extra})
                           for kw in model_kws[1:])]
        for order, case in model_cases:
            also_P0 = [_variant_P0(config, trajectory, {**also_kw, **extra})] \
                if case[0] in names else []
            case_rows = _evolution_rows(case, steps, [*P0s, *also_P0], C_e_b)
            for variant, row in enumerate(case_rows[:len(model_kws)]):
                rows[variant][order] = row
            if also_P0:
                also_rows[names.index(case[0])] = case_rows[-1]
        del steps
    return [pd.DataFrame(r) for r in rows], pd.DataFrame(also_rows) if names else None


def _variant_P0(config: tuple, trajectory, model_kw: dict) -> np.ndarray:
    """P0 of :func:`navlib.models.launcher` with ``model_kw``, symmetrised as
    :func:`navlib.filters.linear_steps` does. P0 depends on the configuration and the sigmas
    only, so the model is built on the trajectory's first two samples."""
    head = SimpleNamespace(t=trajectory.t[:2], attitude=trajectory.attitude[:2],
                           specific_force=trajectory.specific_force[:2])
    P0 = np.asarray(launcher(*config, head, **model_kw).P0, dtype=float)
    return 0.5 * (P0 + P0.T)


def _evolution_rows(case: tuple, steps, P0s, C_e_b) -> list[dict]:
    """The rows of one case (name, solution, biases, bias model, aiding, gyro factor) for
    every initial covariance of ``P0s``, from one stacked recursion.

    The recursion of :func:`navlib.covariance.kalman_covariances` (an update at every epoch,
    epoch 0 included, the default pseudo-inverse cut-off) with ``Q = L L'`` formed a block at
    a time, keeping the posteriors of the first and the last epoch only, the two a row
    reads: the same numbers, to the bit, without the (B, N, n, n) histories.
    """
    aiding = case[4]
    H, R = (None, None) if aiding == "ins_only" else \
        (steps.H, steps.R if aiding == "kf" else np.zeros_like(steps.R))
    measured = np.full(steps.t.size, H is not None)
    _, ends, _ = covariance_recursion(steps.F, FactoredNoise(steps.L), H, R,
                                      symmetrize(np.stack(P0s)), measured, PINV_RTOL,
                                      priors=False, keep=[0, -1])
    return [_evolution_row(*case, steps.state_names, P, C_e_b) for P in ends]


def _evolution_row(name, solution, biases, bias_model, aiding, factor, state_names, ends,
                   C_e_b) -> dict:
    """One row of :func:`covariance_evolution` from the case's posterior covariances at
    the first and the last epoch, ``ends`` (2, n, n)."""
    names = list(state_names)
    psi = [names.index(f"psi_{a}") for a in "xyz"]
    att = sigma_in_frame(ends, psi, C_e_b[[0, -1]])
    row = {"case": name, "solution": solution, "biases": biases, "bias_model": bias_model,
           "aiding": aiding, "gyro_factor": factor}
    for i, axis in enumerate(("roll", "pitch", "yaw")):
        row[axis], row[f"{axis}_0"] = float(att[-1, i]), float(att[0, i])
    for label, prefix in (("gyro_bias", "bg_"), ("accel_bias", "ba_"), ("gps_bias", "bp_")):
        idx = [names.index(f"{prefix}{a}") for a in "xyz"] if f"{prefix}x" in names else []
        sig = sigma_in_frame(ends, idx) if idx else None
        row[label] = float(np.sqrt(np.mean(sig[-1] ** 2))) if idx else np.nan
        row[f"{label}_0"] = float(np.sqrt(np.mean(sig[0] ** 2))) if idx else np.nan
    return row



def evolution_grid(quick: bool = False) -> dict[float, pd.DataFrame]:
    """:func:`covariance_evolution` at each initial attitude sigma of :data:`EVOLUTION_GRID`
    (deg -> table; quick mode: the baseline only), from one stacked recursion per case.

    The claims engine judges the evolution claims on these tables; notebook 02 shows them,
    and their tables are kept in the disk cache, so a report computes them once.
    """
    base = float(np.degrees(ASSUMED["sigma0_att"]))
    values = (base,) if quick else EVOLUTION_GRID["sigma0_att_deg"]
    kws = [{} if np.isclose(v, base) else {"sigma0_att": np.radians(v)} for v in values]
    # the surveyed-pad cause experiment (A-F3-pad) is two of these cases at another initial
    # position sigma: stacked with them, and kept for the claims engine's cause experiments
    pad = (PAD_CASES, {"sigma0_pos": SURVEYED_PAD_M})
    return dict(zip(values, _evolution_tables(None, None, quick, kws, also=pad), strict=True))
