"""Beaudoin et al. (2018) observability-matrix study: Table 2, Fig. 1 and their claims.

Composes :func:`navlib.models.launcher`, :func:`navlib.observability.local_observability` and
:func:`navlib.observability.analyze` into the paper's §4.1 experiment (spec launcher.md §6.1,
§7.2): for each of the 60 configurations of Table 2 (4 solutions x (no bias + 7 bias sets x
Markov / random walk)), the local observability matrix at every 200 Hz step of the ascent,
the number of unobservable states (``n - min rank``; a state is observable only if it is at
every step, §6.1 item 4) and log10 of the maximum condition number over the mission, next to
the paper's values (``data/beaudoin2018_table2.csv``, OCR caveats in its ``.md`` sidecar).

The robust claims of spec §10c are evaluated in :meth:`Table2Result.claims`; the INS/GPS-only
rows depend on the trajectory and on the frozen / time-varying reading of eq. (6), which
:func:`variant_comparison` shows side by side. :func:`fig1_data` is the Fig. 1 analogue
(simplified model, spec §3.7, §10a).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from pathlib import Path

import numpy as np
import pandas as pd

from navlib._validation import finite_scalar
from navlib.errors import NavlibInputError
from navlib.models.launcher import BIAS_SETS, SOLUTIONS, launcher, simplified_gps_bias
from navlib.observability import analyze, local_matrix, local_observability, observability_matrix
from navlib.studies.verdict import ClaimResult

DATA_DIR = Path(__file__).resolve().parents[2] / "data"
TABLE2_CSV = DATA_DIR / "beaudoin2018_table2.csv"

SOLUTION_LABELS = {"ins_gps": "INS/GPS", "ins_gps_att": "INS/GPS + att.",
                   "ins_gps_rt": "INS/GPS + RT", "ins_gps_att_rt": "INS/GPS + att. + RT"}
"""Row-group labels of Table 2."""

SINGULAR_LOG10 = 16.0
"""log10 cond at or above which a matrix counts as numerically singular (spec §10c: 1e16)."""


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


def _cond_match(ours: np.ndarray, paper: np.ndarray, tol: float) -> np.ndarray:
    both_singular = (ours >= SINGULAR_LOG10) & (paper >= SINGULAR_LOG10)
    return both_singular | (np.abs(ours - paper) <= tol)


def describe_direction(vector, state_names, C_b_e, top: int = 3) -> str:
    """Largest components of a state-space direction, attitude parts in body axes.

    The attitude error ``psi`` (E frame) is rotated to body axes and labelled roll / pitch /
    yaw (spec §2: the body x axis is the roll axis), so the weakly observable direction of
    spec §3.8 reads as "roll".
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


def _mid_step_analysis(model, res, trajectory, window, variant, method, rtol) -> dict:
    """Unobservable groups and weakest direction of O(k) at the mission's middle step."""
    k = int(res.step[res.step.size // 2])
    O = local_matrix(model, k, window=window, variant=variant, method=method)
    a = analyze(O, rtol=res.rtol if rtol is None else rtol, state_names=model.state_names,
                coupling_threshold="auto")
    return {"groups": "; ".join("{" + ", ".join(g) + "}" for g in a.unobservable_groups),
            "weakest": describe_direction(a.weakest_direction, model.state_names,
                                          trajectory.attitude[k].as_matrix())}


@dataclass(frozen=True, eq=False)
class Table2Result:
    """Our Table 2 beside the paper's.

    Attributes
    ----------
    frame : pandas.DataFrame
        One row per configuration: ``solution, biases, bias_model, n_states,
        n_unobservable, log10_cond, rank_constant, groups, weakest`` (ours; at the middle
        of the mission: ``groups`` = coupled unobservable states, ``weakest`` = largest
        components of the least observable direction, attitude in body axes),
        ``paper_unobservable,
        paper_log10_cond``, ``match_unobservable``, ``match_cond`` and ``match``.
    variant, method : str
        Local-matrix reading (``time_varying`` = eq. (6), ``frozen`` = PWCS) and
        discretisation (``euler`` = the paper's ``I + s_t F``).
    stride, window : int
        Evaluated every ``stride``-th step; block rows per local matrix (None = n).
    cond_tol : float
        Tolerance on log10 cond for a match (both >= 16 also match).
    n_steps : int
        Trajectory samples; ``duration_s`` the mission length.
    """

    frame: pd.DataFrame
    variant: str
    method: str
    stride: int
    window: int | None
    cond_tol: float
    n_steps: int
    duration_s: float

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

    def claims(self) -> list[ClaimResult]:
        """Verdicts for the §4.1 statements (spec launcher.md §7.2, robust targets of §10c)."""
        return table2_claims(self.frame, self.cond_tol, self.variant)


def _config_row(config, trajectory, *, window, variant, stride, rtol, method, n_jobs,
                model_kw) -> dict:
    """Our Table 2 row of one ``(solution, biases, bias_model)`` configuration."""
    solution, biases, bias_model = config
    model = launcher(solution, biases, bias_model, trajectory=trajectory, **model_kw)
    res = local_observability(model, window=window, variant=variant, stride=stride,
                              rtol=rtol, method=method, n_jobs=n_jobs)
    return {"solution": solution, "biases": biases, "bias_model": bias_model,
            "n_states": model.n, "n_unobservable": res.n_unobservable,
            "log10_cond": res.log10_max_cond, "rank_constant": res.rank_constant,
            **_mid_step_analysis(model, res, trajectory, window, variant, method, rtol)}


def table2(trajectory=None, *, variant: str = "time_varying", stride: int = 1,
           window: int | None = None, rtol: float | None = None, method: str = "euler",
           solutions=SOLUTIONS, cond_tol: float = 1.0, n_jobs: int | None = None,
           progress=None, scheduler=None, **model_kw) -> Table2Result:
    """Regenerate Table 2 (spec launcher.md §6.1, §7.2).

    Parameters
    ----------
    trajectory : Trajectory, optional
        Default :func:`navlib.trajectory.launcher_ascent` (150 s at 200 Hz).
    variant : {"time_varying", "frozen"}
        Eq. (6) as printed, or the model frozen at each step (the paper's "piecewise
        constant model"); spec §6.1 item 2 asks for both.
    stride : int
        Evaluate every ``stride``-th step (1 = every 200 Hz step, the paper's test).
    window, rtol, method, n_jobs
        Passed to :func:`navlib.observability.local_observability`.
    solutions : sequence of str
        Subset of the four solutions (default all: 60 configurations).
    cond_tol : float
        |log10 cond - paper| allowed for a match (numerically singular pairs always match).
    progress : callable, optional
        Called as ``progress(i, total, config)`` before each configuration (local run).
    scheduler : optional
        Run the configurations as Dask tasks (:func:`navlib.sweep.map_tasks`: a Client, an
        address ``tcp://host:port``, ``"processes"``...), the trajectory scattered once to
        the workers; default None: here, ``n_jobs`` threads per configuration.
    **model_kw
        Passed to :func:`navlib.models.launcher` (e.g. ``a1_sign``, ``c_p``).

    Returns
    -------
    Table2Result
    """
    cond_tol = finite_scalar(cond_tol, "cond_tol", low=0.0)
    if trajectory is None:
        from navlib.trajectory import launcher_ascent

        trajectory = launcher_ascent()
    configs = configurations(solutions)
    options = {"window": window, "variant": variant, "stride": stride, "rtol": rtol,
               "method": method, "model_kw": model_kw}
    if scheduler is not None:  # one task per configuration (navlib.sweep.map_tasks)
        from navlib.sweep import map_tasks

        rows = map_tasks(partial(_config_row, n_jobs=1, **options), configs, scheduler,
                         shared={"trajectory": trajectory}, desc="Table 2")
    else:
        rows = []
        for i, config in enumerate(configs):
            if progress is not None:
                progress(i, len(configs), config)
            rows.append(_config_row(config, trajectory, n_jobs=n_jobs, **options))
    ours = pd.DataFrame(rows)
    paper = paper_table2().rename(columns={"n_unobservable": "paper_unobservable",
                                           "log10_cond": "paper_log10_cond",
                                           "n_states": "paper_n_states"})
    frame = ours.merge(paper, on=["solution", "biases", "bias_model"], how="left",
                       validate="one_to_one")
    if (frame.paper_n_states != frame.n_states).any():  # pragma: no cover - data integrity
        raise NavlibInputError("data: Table 2 state counts disagree with the models")
    frame = frame.drop(columns="paper_n_states")
    frame["match_unobservable"] = frame.n_unobservable == frame.paper_unobservable
    frame["match_cond"] = _cond_match(frame.log10_cond.to_numpy(),
                                      frame.paper_log10_cond.to_numpy(), cond_tol)
    frame["match"] = frame.match_unobservable & frame.match_cond
    t = np.asarray(trajectory.t)
    return Table2Result(frame=frame, variant=variant, method=method, stride=int(stride),
                        window=window, cond_tol=cond_tol, n_steps=t.size,
                        duration_s=float(t[-1] - t[0]))


def _verdict(n_ok: int, n_total: int) -> str:
    if n_total == 0:
        return "not applicable"
    return "reproduced" if n_ok == n_total else ("partly" if n_ok > 0 else "not reproduced")


def _rows(frame, **where):
    sel = np.ones(len(frame), dtype=bool)
    for key, value in where.items():
        col = frame[key]
        sel &= col.isin(value).to_numpy() if isinstance(value, (list, tuple, set)) \
            else (col == value).to_numpy()
    return frame[sel]


def _pair_frame(frame, left: str, right: str, bias_sets) -> pd.DataFrame:
    """Rows of ``left`` and ``right`` solutions side by side, same biases and bias model."""
    key = ["biases", "bias_model"]
    cols = [*key, "log10_cond", "n_unobservable"]
    a = _rows(frame, solution=left, biases=list(bias_sets))[cols]
    b = _rows(frame, solution=right, biases=list(bias_sets))[cols]
    return a.merge(b, on=key, suffixes=("_" + left, "_" + right))


def table2_claims(frame: pd.DataFrame, cond_tol: float = 1.0,
                  variant: str = "time_varying") -> list[ClaimResult]:
    """Evaluate the §4.1 statements on a Table 2 frame (see :class:`Table2Result`)."""
    out = []
    how = f"local O(k) at every evaluated step, {variant} reading of eq. (6), Euler form"

    # T2-1: random-walk GPS bias -> exactly 3 unobservable, cond >= 1e16, in every solution
    rw_p = _rows(frame, bias_model="random_walk", biases=["P", "GP", "AP", "GAP"])
    ok = rw_p[(rw_p.n_unobservable == 3) & (rw_p.log10_cond >= SINGULAR_LOG10)]
    per_solution = [f"{s}: {sorted(set(g.n_unobservable))} unobs., log10 cond "
                    f"{g.log10_cond.min():.1f}-{g.log10_cond.max():.1f}"
                    for s, g in rw_p.groupby("solution", sort=False)]
    bad = sorted(set(rw_p.solution) - set(ok.solution)) if len(ok) < len(rw_p) else []
    out.append(ClaimResult(
        "T2-RW-P", "Random-walk GPS bias: exactly 3 unobservable states, cond >= 1e16, in all "
        "solutions", "3 unobservable, log10 cond 17-18 in all 16 rows",
        f"{len(ok)}/{len(rw_p)} rows; " + "; ".join(per_solution),
        _verdict(len(ok), len(rw_p)),
        how + (f"; extra unobservable directions in {bad}" if bad else "")))

    # T2-2: the 3 unobservable states are b_p against dr (mid-mission null space)
    pairs = "{dr_x, bp_x}; {dr_y, bp_y}; {dr_z, bp_z}"
    has = rw_p[rw_p.groups.str.contains("bp_", regex=False)]
    exact = rw_p[rw_p.groups.apply(lambda g: set(g.split("; ")) == set(pairs.split("; ")))]
    out.append(ClaimResult(
        "T2-bp-dr", "The unobservable subspace is the GPS bias against the position error",
        "the 3 components of b_p cannot be separated from dr",
        f"null space exactly {{dr_i, bp_i}} pairs in {len(exact)}/{len(rw_p)} RW+P rows; "
        f"b_p in the null space in {len(has)}/{len(rw_p)}",
        _verdict(len(exact), len(rw_p)), "null space of O(k) at the mid-mission step"))

    # T2-3: Markov -> full rank everywhere
    markov = _rows(frame, bias_model="markov")
    ok = markov[markov.n_unobservable == 0]
    worst = markov.loc[markov.n_unobservable.idxmax()]
    out.append(ClaimResult(
        "T2-Markov", "Markov biases: every solution observable (0 unobservable)",
        "0 in all 28 Markov rows", f"{len(ok)}/{len(markov)} rows full rank"
        + ("" if len(ok) == len(markov) else
           f"; worst {worst.solution}/{worst.biases}: {worst.n_unobservable} unobservable"),
        _verdict(len(ok), len(markov)), how))

    # T2-4: rank constant over the mission
    ok = frame[frame.rank_constant]
    out.append(ClaimResult(
        "T2-rank-constant", "The rank does not change during the mission",
        "constant for every configuration", f"{len(ok)}/{len(frame)} configurations",
        _verdict(len(ok), len(frame)), how))

    # T2-5: attitude sensors lower cond without RT (rows without P)
    no_p = ["", "G", "A", "GA"]
    pair = _pair_frame(frame, "ins_gps", "ins_gps_att", no_p)
    lower = pair[pair.log10_cond_ins_gps_att < pair.log10_cond_ins_gps]
    detail = ", ".join(f"{(r.biases or '-')}/{r.bias_model[:2]}: {r.log10_cond_ins_gps:.1f}"
                       f"->{r.log10_cond_ins_gps_att:.1f}" for r in pair.itertuples())
    out.append(ClaimResult(
        "T2-att-noRT", "Without RT (and without b_p), attitude sensors lower the condition "
        "number", "log10 cond 5 -> 2 (3 -> ~0 with no bias)",
        f"lower in {len(lower)}/{len(pair)} rows ({detail})",
        _verdict(len(lower), len(pair)), how))

    # T2-6: with RT, attitude sensors do not change cond (full-rank rows)
    pair = _pair_frame(frame, "ins_gps_rt", "ins_gps_att_rt", BIAS_SETS)
    pair = pair[(pair.n_unobservable_ins_gps_rt == 0) & (pair.n_unobservable_ins_gps_att_rt == 0)]
    delta = pair.log10_cond_ins_gps_rt - pair.log10_cond_ins_gps_att_rt
    same = pair[np.abs(delta) <= cond_tol]
    detail = ", ".join(f"{(r.biases or '-')}/{r.bias_model[:2]}: {r.log10_cond_ins_gps_rt:.1f}"
                       f" vs {r.log10_cond_ins_gps_att_rt:.1f}" for r in pair.itertuples())
    out.append(ClaimResult(
        "T2-att-RT", "With RT, attitude sensors do not change the condition number",
        "log10 cond 5 with and without attitude sensors",
        f"within {cond_tol:g} order in {len(same)}/{len(pair)} full-rank rows ({detail})",
        _verdict(len(same), len(pair)),
        how + "; where they differ, the RT-only value is the larger one"
        if (delta >= -cond_tol).all() else how))

    # T2-7: unobservable <=> cond >= 1e17 (printed 17/18), otherwise cond <= 1e5
    full = frame[frame.n_unobservable == 0]
    deficient = frame[frame.n_unobservable > 0]
    ok_full = full[full.log10_cond <= 5.0 + cond_tol]
    ok_def = deficient[deficient.log10_cond >= SINGULAR_LOG10]
    out.append(ClaimResult(
        "T2-threshold", "Rank-deficient configurations have cond >= 1e17, the others <= 1e5",
        "17-18 vs <= 5", f"deficient >= 1e16: {len(ok_def)}/{len(deficient)}; full rank "
        f"<= 1e{5 + cond_tol:g}: {len(ok_full)}/{len(full)} (max "
        f"{full.log10_cond.max():.1f})", _verdict(len(ok_def) + len(ok_full), len(frame)),
        how + f"; {cond_tol:g} order(s) of tolerance on the paper's 1e5"))

    # T2-8: the INS/GPS-only rows (soft target, spec §10c)
    ins = _rows(frame, solution="ins_gps")
    ok = ins[ins.match]
    weakest = ins[ins.biases == ""].weakest.iloc[0] if len(ins) else "?"
    out.append(ClaimResult(
        "T2-ins-gps", "INS/GPS-only rows: full rank with log10 cond 3 (no bias) / 5, except "
        "3 unobservable with RW b_p", "0 unobservable, 3 / 5 (18/17 with RW b_p)",
        f"{len(ok)}/{len(ins)} rows match; no-bias log10 cond "
        f"{ins[ins.biases == ''].log10_cond.iloc[0]:.1f}" if len(ins) else "not computed",
        _verdict(len(ok), len(ins)),
        "depends on the trajectory and the method: the least observable direction is the "
        f"body-roll attitude error ({weakest}), seen only through lateral specific force and "
        "attitude change within n steps of 5 ms (spec §3.8, §10c); see variant_comparison"))
    return out


def variant_comparison(trajectory=None, solution: str = "ins_gps", *, stride: int = 1,
                       **kw) -> pd.DataFrame:
    """One solution's Table 2 rows under both readings of eq. (6), beside the paper.

    Columns ``biases, bias_model, paper_unobservable, paper_log10_cond`` and, for each
    variant, ``unobs_<variant>, log10_cond_<variant>``. Spec §10c: the INS/GPS-only rows
    depend strongly on the trajectory and the method.
    """
    if trajectory is None:
        from navlib.trajectory import launcher_ascent

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


# --------------------------------------------------------------------------------------------
# Fig. 1: simplified model
# --------------------------------------------------------------------------------------------
def fig1_data(c_p=None, s_t: float = 0.005, rtol: float | None = None) -> pd.DataFrame:
    """Condition number of the simplified model's observability matrix vs ``c_p`` (Fig. 1).

    Parameters
    ----------
    c_p : array of float, optional
        GPS-bias time constants, s (``inf`` allowed); default 10^-2 .. 10^4 (25 points)
        plus ``inf``.
    s_t : float
        Sampling time, s.

    Returns
    -------
    pandas.DataFrame
        ``c_p, rank, cond, log10_cond, cond_per_cp_st`` (the last is ``cond s_t / c_p``,
        which tends to ~1.171 for ``c_p >> s_t``, spec §10a).
    """
    values = np.concatenate([np.logspace(-2, 4, 25), [np.inf]]) if c_p is None \
        else np.atleast_1d(np.asarray(c_p, dtype=float))
    rows = []
    for c in values:
        A, C = simplified_gps_bias(c, s_t)
        res = analyze(observability_matrix(A, C), rtol=rtol)
        rows.append({"c_p": c, "rank": res.rank, "cond": res.cond,
                     "log10_cond": res.log10_cond,
                     "cond_per_cp_st": res.cond * s_t / c if np.isfinite(c) else np.nan})
    return pd.DataFrame(rows)


def fig1_claims(data: pd.DataFrame | None = None, s_t: float = 0.005) -> list[ClaimResult]:
    """Fig. 1 / §4.1 statements on the simplified model (spec §3.7, §10a)."""
    data = fig1_data(s_t=s_t) if data is None else data
    finite = data[np.isfinite(data.c_p)]
    large = finite[finite.c_p >= 100 * s_t]
    slope = np.polyfit(np.log10(large.c_p), np.log10(large.cond), 1)[0]
    ratio = large.cond_per_cp_st
    infinite = data[~np.isfinite(data.c_p)]
    return [
        ClaimResult("F1-full-rank", "O is full rank only if s_t/c_p != 0",
                    "full rank for finite c_p, rank-deficient as c_p -> inf",
                    f"rank 6 for all {len(finite)} finite c_p; rank "
                    f"{int(infinite['rank'].iloc[0]) if len(infinite) else '?'} at c_p = inf",
                    "reproduced" if (finite["rank"] == 6).all() and len(infinite)
                    and (infinite["rank"] == 3).all() else "not reproduced",
                    "numpy matrix_rank tolerance"),
        ClaimResult("F1-proportional", "The condition number is proportional to c_p",
                    "straight line on Fig. 1",
                    f"log-log slope {slope:.4f} for c_p >= {100 * s_t:g} s; cond s_t/c_p = "
                    f"{ratio.min():.4f}-{ratio.max():.4f}",
                    "reproduced" if abs(slope - 1) < 0.01 else "not reproduced",
                    "2-norm condition number of the 6-block-row O of eq. (7), s_t = 5 ms"),
    ]


# --------------------------------------------------------------------------------------------
# one configuration over the mission
# --------------------------------------------------------------------------------------------
def mission_observability(solution: str = "ins_gps_att_rt", biases: str = "GAP",
                          bias_model: str = "markov", trajectory=None, *, stride: int = 200,
                          variant: str = "time_varying", rtol: float | None = None,
                          window: int | None = None, method: str = "euler", **model_kw):
    """Rank and condition number over the mission for one configuration.

    Default ``stride=200``: one evaluation per second of the 200 Hz ascent (each local
    matrix still uses consecutive 5 ms steps). Returns
    :class:`navlib.observability.LocalObservability` (``to_frame()`` for plotting).
    """
    model = launcher(solution, biases, bias_model, trajectory=trajectory, **model_kw)
    return local_observability(model, window=window, variant=variant, stride=stride,
                               rtol=rtol, method=method)


def inspect_step(solution: str, biases: str, bias_model: str, trajectory, step: int, *,
                 variant: str = "time_varying", rtol: float | None = None,
                 scale=None, coupling_threshold: float = 1e-6, method: str = "euler",
                 **model_kw):
    """:func:`navlib.observability.analyze` of the local matrix at one step (null space,
    groups) for one configuration; ``scale="P0"`` scales states by ``sqrt(diag P0)``."""
    model = launcher(solution, biases, bias_model, trajectory=trajectory, **model_kw)
    O = local_matrix(model, step, variant=variant, method=method)
    if isinstance(scale, str):
        if scale != "P0":
            raise NavlibInputError(f"scale: expected 'P0', an array or None, got {scale!r}")
        sigma = np.sqrt(np.diag(model.P0))
        scale = np.where(sigma > 0, sigma, 1.0)
    return analyze(O, rtol=rtol, state_names=model.state_names, scale=scale,
                   coupling_threshold=coupling_threshold)
