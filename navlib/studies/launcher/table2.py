"""Beaudoin et al. (2018) Table 2: the local observability matrix of each of the 60
configurations at every 200 Hz step of the ascent (docs/assumptions.md, launcher.md §6.1, §7.2),
next to the paper's values (``data/beaudoin2018_table2.csv``, OCR caveats in its ``.md`` sidecar),
and one configuration over the mission."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import partial
from pathlib import Path

import numpy as np
import pandas as pd

from navlib import cache
from navlib._validation import finite_scalar
from navlib.errors import NavlibInputError
from navlib.models.launcher import (
    BIAS_SETS,
    SOLUTION_LABELS,
    SOLUTIONS,
    launcher,
    launcher_steps,
)
from navlib.observability import analyze, local_matrix, local_observability
from navlib.parallel import map_tasks
from navlib.resources import data_dir
from navlib.studies.claims import ClaimResult
from navlib.studies.launcher.assumptions import (
    COND_TOL,
    LATE_S,
    TABLE2_RANK_RTOLS,
    TOLERANCES,
)
from navlib.studies.launcher.claims import cond_match, match_counts, table2_claim_results
from navlib.trajectory import launcher_ascent

__all__ = ["DATA_DIR", "RANK_COLUMNS", "TABLE2_CSV", "Table2Result", "configurations",
           "describe_direction", "inspect_step", "mission_observability", "paper_table2", "table2",
           "variant_comparison"]

DATA_DIR = data_dir()
TABLE2_CSV = DATA_DIR / "beaudoin2018_table2.csv"


def configurations(solutions=SOLUTIONS) -> list[tuple[str, str, str]]:
    """Table 2's configurations in paper order: ``(solution, biases, bias_model)``.

    60 for all four solutions: per solution the no-bias row and the seven bias sets with the
    Markov and the random-walk model (the paper's "—" cells are not configurations).
    """
    unknown = [s for s in solutions if s not in SOLUTIONS]
    if unknown:
        raise NavlibInputError(f"solutions: unknown {unknown}; expected some of {SOLUTIONS}")
    out = []
    for solution in solutions:
        for biases in BIAS_SETS:
            models = ("none",) if not biases else ("markov", "random_walk")
            out += [(solution, biases, model) for model in models]
    return out


def paper_table2(path=None) -> pd.DataFrame:
    """The paper's Table 2 as stored in ``data/beaudoin2018_table2.csv`` (one row per config).

    Columns ``solution, biases, bias_model, n_states, n_unobservable, log10_cond, note``.
    """
    path = TABLE2_CSV if path is None else Path(path)
    if not path.is_file():
        raise NavlibInputError(f"path: no Table 2 file at {path}")
    frame = pd.read_csv(path, dtype={"biases": str, "note": str}, keep_default_na=False)
    frame["n_unobservable"] = frame["n_unobservable"].astype(int)
    frame["log10_cond"] = frame["log10_cond"].astype(float)
    return frame



def describe_direction(vector, state_names, C_b_e, top: int = 3) -> str:
    """Largest components of a state-space direction, attitude parts in body axes.

    The attitude error ``psi`` (E frame) is rotated to body axes and labelled roll / pitch /
    yaw (docs/assumptions.md, launcher.md §2: the body x axis is the roll axis), so the weakly
    observable direction of docs/assumptions.md, launcher.md §3.8 reads as "roll".

    Parameters
    ----------
    vector : numpy.ndarray
        State-space direction, (n,).
    state_names : sequence of str
        The model's states.
    C_b_e : numpy.ndarray
        Body -> ECEF attitude, (3, 3).
    top : int, optional
        Number of components listed.

    Returns
    -------
    str
    """
    v = np.asarray(vector, dtype=float)
    names = list(state_names)
    labels, values = [], []
    for group, new in (("psi_", "psi_"), ("psi_ref_", "psi_ref_")):
        idx = [names.index(f"{group}{a}") for a in "xyz"] if f"{group}x" in names else None
        if idx is None:
            continue
        part = C_b_e.T @ v[idx] if group == "psi_" else v[idx]
        labels += [f"{new}{axis}" for axis in ("roll", "pitch", "yaw")]
        values += list(part)
        for i in idx:
            names[i] = None
    for name, value in zip(names, v, strict=True):
        if name is not None:
            labels.append(name)
            values.append(value)
    values = np.asarray(values)
    order = np.argsort(-np.abs(values))[:top]
    return ", ".join(f"{labels[i]} {values[i]:+.2f}" for i in order)


def _mid_step_analysis(model, res, trajectory, window, variant, method, rtol,
                       rank_rtols=()) -> dict:
    """Unobservable groups and weakest direction of O(k) at the mission's middle step, and
    the groups at each of ``rank_rtols`` (``groups@<rtol>``) from the same matrix."""
    k = int(res.step[res.step.size // 2])
    O = local_matrix(model, k, window=window, variant=variant, method=method)

    def analysis(tol):
        return analyze(O, rtol=tol, state_names=model.state_names, coupling_threshold="auto")

    def groups(a):
        return "; ".join("{" + ", ".join(g) + "}" for g in a.unobservable_groups)

    a = analysis(res.rtol if rtol is None else rtol)
    return {"groups": groups(a),
            "weakest": describe_direction(a.weakest_direction, model.state_names,
                                          trajectory.attitude[k].as_matrix()),
            **{f"groups@{tol:g}": groups(analysis(tol)) for tol in rank_rtols}}


RANK_COLUMNS = ("n_unobservable", "rank_constant", "groups")
"""The columns of a Table 2 row that depend on the rank tolerance."""


@dataclass(frozen=True, eq=False)
class Table2Result:
    """Our Table 2 beside the paper's.

    Attributes
    ----------
    frame : pandas.DataFrame
        One row per configuration: ``solution, biases, bias_model, n_states,
        n_unobservable, log10_cond, rank_constant, t_worst_s, log10_cond_late, groups,
        weakest`` (ours; ``t_worst_s`` = time after lift-off of the largest condition number,
        ``log10_cond_late`` = the largest from :data:`~navlib.studies.launcher.assumptions.
        LATE_S` on; at the middle of the mission: ``groups`` = coupled unobservable states,
        ``weakest`` = largest components of the least observable direction, attitude in body
        axes), ``paper_unobservable, paper_log10_cond``, ``match_unobservable``,
        ``match_cond`` and ``match``.
    variant, method : str
        Local-matrix reading (``time_varying`` = eq. (6), ``frozen`` = PWCS) and
        discretisation (``euler`` = the paper's ``I + s_t F``).
    stride, window : int
        Evaluated every ``stride``-th step; block rows per local matrix (None = n).
    cond_tol : float
        Tolerance on log10 cond for a match (both >= 16 also match).
    n_steps : int
        Trajectory samples; ``duration_s`` the mission length.
    rank_rtols : dict
        Per further rank tolerance of the same computation (``table2(rank_rtols=...)``):
        its :data:`RANK_COLUMNS` frame (same row order), read by :meth:`at_rtol`.
    """

    frame: pd.DataFrame
    variant: str
    method: str
    stride: int
    window: int | None
    cond_tol: float
    n_steps: int
    duration_s: float
    rank_rtols: dict = field(default_factory=dict)

    def at_rtol(self, rtol: float) -> Table2Result:
        """The same table ranked at another relative tolerance of ``rank_rtols`` (the same
        singular values at the same steps: no new computation): :data:`RANK_COLUMNS` and the
        matches change, the condition numbers and weakest directions do not."""
        key = finite_scalar(rtol, "rtol", low=0.0, high=1.0)
        if key not in self.rank_rtols:
            raise NavlibInputError(f"rtol: this table was ranked at {sorted(self.rank_rtols)} "
                                   f"besides its own tolerance, got {rtol!r}")
        frame = self.frame.copy()
        for column in RANK_COLUMNS:
            frame[column] = self.rank_rtols[key][column].to_numpy()
        frame["match_unobservable"] = frame.n_unobservable == frame.paper_unobservable
        frame["match"] = frame.match_unobservable & frame.match_cond
        return replace(self, frame=frame, rank_rtols={})

    def wide(self) -> pd.DataFrame:
        """Paper layout: 32 rows (solution x bias set), ours / paper per bias model."""
        f = self.frame.copy()
        f["cell"] = [f"{o} / {p}" for o, p in zip(f.n_unobservable, f.paper_unobservable,
                                                   strict=True)]
        f["cond_cell"] = [f"{o:.1f} / {p:g}" for o, p in zip(f.log10_cond, f.paper_log10_cond,
                                                             strict=True)]
        rows = []
        for (solution, biases), group in f.groupby(["solution", "biases"], sort=False):
            row = {"solution": SOLUTION_LABELS[solution],
                   "biases": (biases or "—") + ("+Ref" if solution.endswith("_rt") else ""),
                   "n": int(group.n_states.iloc[0])}
            for model, label in (("none", "none"), ("markov", "Markov"),
                                 ("random_walk", "RW")):
                sel = group[group.bias_model == model]
                row[f"unobs {label}"] = sel.cell.iloc[0] if len(sel) else "—"
                row[f"log10 cond {label}"] = sel.cond_cell.iloc[0] if len(sel) else "—"
                row[f"match {label}"] = ("yes" if sel.match.iloc[0] else "NO") if len(sel) \
                    else "—"
            rows.append(row)
        return pd.DataFrame(rows)

    def claims(self, cond_tol: float | None = None) -> list[ClaimResult]:
        """The §4.1 statements (docs/assumptions.md, launcher.md §7.2, robust targets of §10c),
        judged by :mod:`navlib.studies.claims` at ``cond_tol`` (default the result's)."""
        tol = self.cond_tol if cond_tol is None else finite_scalar(cond_tol, "cond_tol", 0.0)
        return table2_claim_results(self.frame, tol, self.variant)

    def match_counts(self, tolerances=None) -> pd.Series:
        """Matching configurations at several tolerances (decades), :data:`TOLERANCES`."""
        return match_counts(self.frame, TOLERANCES if tolerances is None else tolerances)


def _config_model(config, trajectory, model_kw, method):
    """The launcher model of one ``(solution, biases, bias_model)`` configuration as the
    observability test reads it: its Euler steps computed chunk by chunk
    (:func:`~navlib.models.launcher.launcher_steps`), or the continuous model that
    ``method`` discretises."""
    solution, biases, bias_model = config
    build = launcher_steps if method == "euler" else launcher
    return build(solution, biases, bias_model, trajectory=trajectory, **model_kw)


def _model_row(config, model, trajectory, *, window, variant, stride, rtol, method,
               n_jobs, rank_rtols=()) -> dict:
    """Our Table 2 row of one configuration from its model; for each of ``rank_rtols`` also
    the unobservable count, rank constancy and groups at that tolerance
    (``n_unobservable@<rtol>``...: the same singular values re-ranked)."""
    solution, biases, bias_model = config
    res = local_observability(model, window=window, variant=variant, stride=stride,
                              rtol=rtol, method=method, n_jobs=n_jobs)
    row = {"solution": solution, "biases": biases, "bias_model": bias_model,
           "n_states": model.n, "n_unobservable": res.n_unobservable,
           "log10_cond": res.log10_max_cond, "rank_constant": res.rank_constant,
           "t_worst_s": float(res.t[int(np.argmax(res.cond))] - trajectory.t[0]),
           "log10_cond_late": _late_log10_cond(res, trajectory.t[0]),
           **_mid_step_analysis(model, res, trajectory, window, variant, method, rtol,
                                rank_rtols)}
    for tol in rank_rtols:
        other = res.with_rtol(tol)
        row[f"n_unobservable@{tol:g}"] = other.n_unobservable
        row[f"rank_constant@{tol:g}"] = other.rank_constant
    return row


def _late_log10_cond(res, t0: float) -> float:
    """log10 of the largest condition number at the evaluated steps from :data:`LATE_S` after
    lift-off ``t0`` on (NaN when none is that late)."""
    late = res.t - t0 >= LATE_S
    return float(np.log10(res.cond[late].max())) if late.any() else float("nan")


def _config_row(config, trajectory, *, model_kw, **options) -> dict:
    """Our Table 2 row of one configuration (one task of the ``scheduler`` run)."""
    return _model_row(config, _config_model(config, trajectory, model_kw, options["method"]),
                      trajectory, **options)


def _local_rows(configs, trajectory, progress, model_kw, options) -> list[dict]:
    """The rows one configuration after the other (each analysed by ``n_jobs`` threads)."""
    rows = []
    for i, config in enumerate(configs):
        if progress is not None:
            progress(i, len(configs), config)
        rows.append(_config_row(config, trajectory, model_kw=model_kw, **options))
    return rows


@cache.cached
def _table2_rows(trajectory, configs, model_kw: dict, options: dict) -> list[dict]:
    """The rows of :func:`table2` computed here (:func:`_local_rows`), kept in the disk
    cache (:mod:`navlib.cache`): notebook 02 and the claims engine evaluate the same table
    at the same stride, so a report computes it once."""
    return _local_rows(configs, trajectory, None, model_kw, options)


def table2(trajectory=None, *, variant: str = "time_varying", stride: int = 1,
           window: int | None = None, rtol: float | None = None, method: str = "euler",
           solutions=SOLUTIONS, cond_tol: float = COND_TOL, n_jobs: int | None = None,
           progress=None, scheduler=None, rank_rtols=None, **model_kw) -> Table2Result:
    """Regenerate Table 2 (docs/assumptions.md, launcher.md §6.1, §7.2).

    Parameters
    ----------
    trajectory : Trajectory, optional
        Default :func:`navlib.trajectory.launcher_ascent` (150 s at 200 Hz).
    variant : {"time_varying", "frozen"}
        Eq. (6) as printed, or the model frozen at each step (the paper's "piecewise
        constant model"); docs/assumptions.md, launcher.md §6.1 item 2 asks for both.
    stride : int
        Evaluate every ``stride``-th step (1 = every 200 Hz step, the paper's test).
    window, rtol, method, n_jobs
        Passed to :func:`navlib.observability.local_observability`.
    solutions : sequence of str
        Subset of the four solutions (default all: 60 configurations).
    cond_tol : float
        |log10 cond - paper| allowed for a match (default half a decade; numerically
        singular pairs always match).
    progress : callable, optional
        Called as ``progress(i, total, config)`` before each configuration (local run).
    scheduler : optional
        Run the configurations as Dask tasks (:func:`navlib.parallel.map_tasks`: a Client, an
        address ``tcp://host:port``, ``"processes"``...), the trajectory scattered once to
        the workers; default None: here, ``n_jobs`` threads per configuration.
    rank_rtols : sequence of float, optional
        Further relative rank tolerances at which the same singular values are also ranked
        (:meth:`Table2Result.at_rtol`); default the numbers of
        :data:`~navlib.studies.launcher.assumptions.TABLE2_RANK_RTOLS`, so that the claims'
        rank-tolerance robustness comes from this one computation.
    **model_kw
        Passed to :func:`navlib.models.launcher` (e.g. ``a1_sign``, ``c_p``).

    Returns
    -------
    Table2Result
    """
    cond_tol = finite_scalar(cond_tol, "cond_tol", low=0.0)
    if trajectory is None:
            trajectory = launcher_ascent()
    configs = configurations(solutions)
    if rank_rtols is None:
        rank_rtols = [tol for tol in TABLE2_RANK_RTOLS if not isinstance(tol, str)]
    rank_rtols = tuple(finite_scalar(tol, "rank_rtols", low=0.0, high=1.0)
                       for tol in rank_rtols)
    options = {"window": window, "variant": variant, "stride": stride, "rtol": rtol,
               "method": method, "rank_rtols": rank_rtols}
    if scheduler is not None:  # one task per configuration (navlib.parallel.map_tasks)
        rows = map_tasks(partial(_config_row, n_jobs=1, model_kw=model_kw, **options),
                         configs, scheduler, shared={"trajectory": trajectory}, desc="Table 2")
    elif progress is not None:
        rows = _local_rows(configs, trajectory, progress, model_kw,
                           {**options, "n_jobs": n_jobs})
    else:
        rows = _table2_rows(trajectory, configs, model_kw, {**options, "n_jobs": n_jobs})
    ours = pd.DataFrame(rows)
    further = {tol: pd.DataFrame({c: ours.pop(f"{c}@{tol:g}") for c in RANK_COLUMNS})
               for tol in rank_rtols}
    paper = paper_table2().rename(columns={"n_unobservable": "paper_unobservable",
                                           "log10_cond": "paper_log10_cond",
                                           "n_states": "paper_n_states"})
    frame = ours.merge(paper, on=["solution", "biases", "bias_model"], how="left",
                       validate="one_to_one")
    if (frame.paper_n_states != frame.n_states).any():  # pragma: no cover - data integrity
        raise NavlibInputError("data: Table 2 state counts disagree with the models")
    frame = frame.drop(columns="paper_n_states")
    frame["match_unobservable"] = frame.n_unobservable == frame.paper_unobservable
    frame["match_cond"] = cond_match(frame.log10_cond.to_numpy(),
                                      frame.paper_log10_cond.to_numpy(), cond_tol)
    frame["match"] = frame.match_unobservable & frame.match_cond
    t = np.asarray(trajectory.t)
    return Table2Result(frame=frame, variant=variant, method=method, stride=int(stride),
                        window=window, cond_tol=cond_tol, n_steps=t.size,
                        duration_s=float(t[-1] - t[0]), rank_rtols=further)



def variant_comparison(trajectory=None, solution: str = "ins_gps", *, stride: int = 1,
                       **kw) -> pd.DataFrame:
    """One solution's Table 2 rows under both readings of eq. (6), beside the paper.

    Columns ``biases, bias_model, paper_unobservable, paper_log10_cond`` and, for each
    variant, ``unobs_<variant>, log10_cond_<variant>``. Spec §10c: the INS/GPS-only rows
    depend strongly on the trajectory and the method.

    Parameters
    ----------
    trajectory : Trajectory or None, optional
        Reference trajectory (default the launcher ascent).
    solution : str, optional
        One of :data:`~navlib.models.launcher.SOLUTIONS`.
    stride : int, optional
        Evaluated every ``stride``-th step.
    **kw
        Other keywords of :func:`~navlib.studies.launcher.table2`.

    Returns
    -------
    pandas.DataFrame
    """
    if trajectory is None:
            trajectory = launcher_ascent()
    parts = []
    for variant in ("time_varying", "frozen"):
        f = table2(trajectory, variant=variant, stride=stride, solutions=[solution],
                   **kw).frame
        parts.append(f[["biases", "bias_model", "paper_unobservable", "paper_log10_cond",
                        "n_unobservable", "log10_cond"]].rename(
            columns={"n_unobservable": f"unobs_{variant}",
                     "log10_cond": f"log10_cond_{variant}"}))
    return parts[0].merge(parts[1], on=["biases", "bias_model", "paper_unobservable",
                                        "paper_log10_cond"])



def mission_observability(solution: str = "ins_gps_att_rt", biases: str = "GAP",
                          bias_model: str = "markov", trajectory=None, *, stride: int = 200,
                          variant: str = "time_varying", rtol: float | None = None,
                          window: int | None = None, method: str = "euler", **model_kw):
    """Rank and condition number over the mission for one configuration.

    Default ``stride=200``: one evaluation per second of the 200 Hz ascent (each local
    matrix still uses consecutive 5 ms steps). Returns
    :class:`navlib.observability.LocalObservability` (``to_frame()`` for plotting).

    Parameters
    ----------
    solution : str, optional
        One of :data:`~navlib.models.launcher.SOLUTIONS`.
    biases : str, optional
        Bias states, letters of ``"GAP"``.
    bias_model : {"markov", "random_walk"}, optional
        Bias model.
    trajectory : Trajectory or None, optional
        Reference trajectory (default the launcher ascent).
    stride : int, optional
        Evaluated every ``stride``-th step.
    variant : str, optional
        Reading of eq. (6).
    rtol : float or None, optional
        Relative rank tolerance.
    window : int or None, optional
        Block rows per local matrix (None: n).
    method : {"euler", "exact"}, optional
        Discretisation.
    **model_kw
        Keywords of :func:`navlib.models.launcher.launcher`.
    """
    model = _config_model((solution, biases, bias_model), trajectory, model_kw, method)
    return local_observability(model, window=window, variant=variant, stride=stride,
                               rtol=rtol, method=method)


def inspect_step(solution: str, biases: str, bias_model: str, trajectory, step: int, *,
                 variant: str = "time_varying", rtol: float | None = None,
                 scale=None, coupling_threshold: float = 1e-6, method: str = "euler",
                 **model_kw):
    """:func:`navlib.observability.analyze` of the local matrix at one step (null space,
    groups) for one configuration; ``scale="P0"`` scales states by ``sqrt(diag P0)``.

    Parameters
    ----------
    solution, biases, bias_model : str
        The configuration.
    trajectory : Trajectory
        Reference trajectory.
    step : int
        Step analysed.
    variant : str, optional
        Reading of eq. (6).
    rtol : float or None, optional
        Relative rank tolerance.
    scale : str, numpy.ndarray or None, optional
        State scaling (``"P0"``: ``sqrt(diag P0)``).
    coupling_threshold : float, optional
        Smallest coupling that joins two states in a group.
    method : {"euler", "exact"}, optional
        Discretisation.
    **model_kw
        Keywords of :func:`navlib.models.launcher.launcher`.

    Returns
    -------
    navlib.observability.ObservabilityAnalysis
    """
    model = launcher(solution, biases, bias_model, trajectory=trajectory, **model_kw)
    O = local_matrix(model, step, variant=variant, method=method)
    if isinstance(scale, str):
        if scale != "P0":
            raise NavlibInputError(f"scale: expected 'P0', an array or None, got {scale!r}")
        sigma = np.sqrt(np.diag(model.P0))
        scale = np.where(sigma > 0, sigma, 1.0)
    return analyze(O, rtol=rtol, state_names=model.state_names, scale=scale,
                   coupling_threshold=coupling_threshold)

