"""The one claims engine: every paper claim of every study, one verdict rule, one table.

A claim is an id, the paper's statement and value, our number(s) and a list of explicit
:class:`Check` s, each a measured value against a tolerance written in the paper's own terms
("GPS barely improves roll" -> ``roll sigma ratio >= 0.5``). The verdict is never typed: it
follows from the checks by the single rule of :func:`verdict_of`:

* **reproduced**: every check passes;
* **partly**: the headline check(s) pass and a secondary one fails;
* **not reproduced**: a headline check fails.

A claim whose checks could not be evaluated on the given input (e.g. a 30-40 min claim on a
10 min quick run) is **not evaluated**; that is a status, not a verdict.

Each claim also carries a **basis**:

* ``measured``: our number is computed from the model, the paper's statement is tested;
* ``by construction``: the claim is an input of ours (e.g. the rocket profile R1-R6, which
  the trajectory generator takes as parameters): shown, never counted as reproduced;
* ``fitted``: the claim holds at an assumption chosen to make it hold (e.g. SSAC's 45°
  eigenvector pairs from a P0 built for them).

Every study registers itself with :func:`register` (a :class:`Study`: a function returning
its baseline claims, its declared assumption set as data, and a function evaluating the
claims over that set). :func:`all_claims` runs every registered study and returns the one
table of the contract (spec api.md, "Claims"), with the **robustness** of each measured or
fitted claim: the fraction of the points of its study's declared set, varying exactly the
assumptions the claim declares in ``depends_on``, at which it is reproduced
(:func:`robustness_over`; NaN for claims by construction, where the set varies none of its
assumptions, and where its number and verdict do not move: "insensitive"), and the
**explanation** of each partly / not reproduced claim (:func:`explain`). :func:`joint_search`
reads a sweep of a whole assumption space: the point reproducing the most claims at once and
the claims that hold together nowhere.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from navlib.errors import NavlibInputError

VERDICTS = ("reproduced", "partly", "not reproduced")
"""The verdicts of :func:`verdict_of`."""
NOT_EVALUATED = "not evaluated"
"""Status of a claim whose checks could not be evaluated on the given input."""
STATUSES = (*VERDICTS, NOT_EVALUATED)
BASES = ("measured", "by construction", "fitted")
"""How a claim's number relates to our assumptions (module docstring)."""
OPS = ("<", "<=", ">", ">=", "==", "!=", "in", "out")
"""Comparisons a :class:`Check` supports (``in``/``out``: inside/outside ``[low, high]``)."""


def _fmt(x) -> str:
    if isinstance(x, (bool, np.bool_)):
        return "yes" if x else "no"
    if isinstance(x, (int, np.integer)):
        return str(int(x))
    x = float(x)
    if math.isnan(x):
        return "nan"
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    if x != 0 and (abs(x) >= 1e4 or abs(x) < 1e-3):
        return f"{x:.3g}"
    return f"{x:.4g}"


@dataclass(frozen=True)
class Check:
    """One measured value against a tolerance.

    Attributes
    ----------
    name : str
        What is checked, in the paper's terms (e.g. ``"roll sigma INS/GPS / INS-only"``).
    value : float or bool
        Our measured value (a count, a ratio, a time; booleans for yes/no facts).
    op : str
        One of :data:`OPS`.
    target : float, bool or (float, float)
        The tolerance bound (a pair for ``in``/``out``).
    headline : bool
        Whether this check carries the paper's main statement (see :func:`verdict_of`).
    """

    name: str
    value: object
    op: str
    target: object
    headline: bool = False

    def __post_init__(self):
        if self.op not in OPS:
            raise NavlibInputError(f"op: expected one of {OPS}, got {self.op!r}")
        if self.op in ("in", "out"):
            try:
                low, high = self.target
            except (TypeError, ValueError) as exc:
                raise NavlibInputError("target: 'in'/'out' need a (low, high) pair") from exc
            if not low <= high:
                raise NavlibInputError(f"target: need low <= high, got {self.target}")

    @property
    def passed(self) -> bool:
        v, t = self.value, self.target
        if isinstance(v, (float, np.floating)) and math.isnan(v):
            return False
        if self.op == "in":
            return bool(t[0] <= v <= t[1])
        if self.op == "out":
            return bool(v < t[0] or v > t[1])
        return bool({"<": v < t, "<=": v <= t, ">": v > t, ">=": v >= t, "==": v == t,
                     "!=": v != t}[self.op])

    def text(self) -> str:
        """``name: value op target -> pass/FAIL`` (``*`` marks a headline check)."""
        if self.op in ("in", "out"):
            target = f"[{_fmt(self.target[0])}, {_fmt(self.target[1])}]"
            op = "in" if self.op == "in" else "outside"
        else:
            target, op = _fmt(self.target), self.op
        mark = "*" if self.headline else ""
        return (f"{mark}{self.name}: {_fmt(self.value)} {op} {target} -> "
                f"{'pass' if self.passed else 'FAIL'}")

    def failing(self) -> Check:
        """The same check with a value that violates the tolerance (for tests: every check
        must be able to fail)."""
        t = self.target
        if isinstance(t, (bool, np.bool_)):
            bad = (not t) if self.op in ("==", ">=", "<=") else t
        elif self.op in ("in",):
            bad = t[1] + 1.0 + abs(t[1])
        elif self.op == "out":
            bad = 0.5 * (t[0] + t[1])
        elif self.op in ("<", "<="):
            bad = t + 1.0 + abs(t)
        elif self.op in (">", ">="):
            bad = t - 1.0 - abs(t)
        elif self.op == "==":
            bad = t + 1
        else:  # "!="
            bad = t
        return replace(self, value=bad)


def check(name: str, value, op: str, target, headline: bool = False) -> Check:
    """Shorthand for :class:`Check`."""
    return Check(name, value, op, target, headline)


def verdict_of(checks: Sequence[Check]) -> str:
    """The one verdict rule (module docstring).

    The headline checks are those flagged ``headline``; when none is flagged, the first
    check is the headline. No checks: :data:`NOT_EVALUATED`.
    """
    checks = list(checks)
    if not checks:
        return NOT_EVALUATED
    heads = [c for c in checks if c.headline] or checks[:1]
    if not all(c.passed for c in heads):
        return "not reproduced"
    return "reproduced" if all(c.passed for c in checks) else "partly"


@dataclass(frozen=True)
class ClaimResult:
    """One paper claim evaluated by code; its verdict follows from its checks.

    Attributes
    ----------
    claim_id : str
        The spec id, e.g. ``"X3"``, ``"S6"``, ``"T1"``, ``"SSAC-rank15"``.
    claim : str
        What the paper says, in one line (the *statement*).
    paper : str
        The paper's value or wording.
    ours : str
        Our number(s), formatted.
    checks : tuple of Check
        Explicit checks; empty = not evaluated on this input.
    basis : str
        One of :data:`BASES`.
    assumption : str
        The assumption(s) the verdict hinges on.
    note : str
        Why the claim is not evaluated (when it has no checks).
    depends_on : tuple of str
        The named assumptions the measured number depends on (keys of its study's
        assumption set, e.g. ``"rank_rtol"``, ``"P0"``); its robustness varies exactly
        these (:func:`robustness_over`).
    explanation : str
        A measured cause of a ``partly`` / ``not reproduced`` verdict, quoting the number a
        study experiment produced (empty: the engine derives one from the assumption set,
        :func:`explain`).
    """

    claim_id: str
    claim: str
    paper: str
    ours: str
    checks: tuple = ()
    basis: str = "measured"
    assumption: str = ""
    note: str = ""
    depends_on: tuple = ()
    explanation: str = ""

    def __post_init__(self):
        object.__setattr__(self, "checks", tuple(self.checks))
        if isinstance(self.depends_on, str):
            raise NavlibInputError("depends_on: expected a sequence of assumption names, "
                                   f"got the string {self.depends_on!r}")
        object.__setattr__(self, "depends_on", tuple(self.depends_on))
        if self.basis not in BASES:
            raise NavlibInputError(f"basis: expected one of {BASES}, got {self.basis!r}")
        bad = [c for c in self.checks if not isinstance(c, Check)]
        if bad:
            raise NavlibInputError(f"checks: expected Check objects, got {bad[:1]}")

    @property
    def statement(self) -> str:
        return self.claim

    @property
    def verdict(self) -> str:
        """:func:`verdict_of` the checks."""
        return verdict_of(self.checks)

    @property
    def reproduced(self) -> bool:
        """Reproduced *and* measured: a claim by construction or fitted never counts."""
        return self.verdict == "reproduced" and self.basis == "measured"

    def checks_text(self) -> str:
        """Readable checks, ``"; "``-separated (``*`` = headline)."""
        if not self.checks:
            return self.note or "not evaluated"
        return "; ".join(c.text() for c in self.checks)

    def headline_values(self) -> tuple:
        """The measured values of the headline check(s) (:func:`verdict_of`)."""
        heads = [c for c in self.checks if c.headline] or list(self.checks[:1])
        return tuple(c.value for c in heads)

    def as_dict(self) -> dict:
        return {"claim_id": self.claim_id, "claim": self.claim, "paper": self.paper,
                "ours": self.ours, "verdict": self.verdict, "basis": self.basis,
                "checks": self.checks_text(), "assumption": self.assumption,
                "depends_on": "; ".join(self.depends_on), "explanation": self.explanation}


def claim(claim_id: str, statement: str, paper: str, ours: str, checks: Iterable[Check],
          *, basis: str = "measured", assumption: str = "", depends_on: Sequence[str] = (),
          explanation: str = "") -> ClaimResult:
    """Build a :class:`ClaimResult` (the verdict follows from ``checks``)."""
    return ClaimResult(claim_id, statement, paper, ours, tuple(checks), basis, assumption,
                       depends_on=depends_on, explanation=explanation)


def not_evaluated(claim_id: str, statement: str, paper: str, why: str, *,
                  basis: str = "measured", assumption: str = "",
                  depends_on: Sequence[str] = ()) -> ClaimResult:
    """A claim the given input cannot judge (``why`` says what is missing)."""
    return ClaimResult(claim_id, statement, paper, why, (), basis, assumption, note=why,
                       depends_on=depends_on)


def with_failed_headline(result: ClaimResult) -> ClaimResult:
    """``result`` with its headline check(s) replaced by failing values (for tests)."""
    heads = [c for c in result.checks if c.headline] or list(result.checks[:1])
    return replace(result, checks=tuple(c.failing() if c in heads else c
                                        for c in result.checks))


def claims_frame(results: Iterable[ClaimResult]) -> pd.DataFrame:
    """A table of claim results, one row per claim: ``claim_id, claim, paper, ours,
    verdict, basis, checks, assumption, depends_on, explanation``."""
    rows = [r.as_dict() for r in results]
    return pd.DataFrame(rows, columns=["claim_id", "claim", "paper", "ours", "verdict",
                                       "basis", "checks", "assumption", "depends_on",
                                       "explanation"])


@dataclass(frozen=True)
class Robustness:
    """A claim's robustness over the part of its study's assumption set that varies what the
    claim depends on (:func:`robustness_over`).

    Attributes
    ----------
    fraction : float
        Share of the evaluated points where the claim is reproduced; NaN when the set varies
        none of its assumptions, when it is never evaluated, or when its measured number is
        the same at every point ("insensitive": a fraction would then restate the baseline).
    note : str
        Why the fraction is NaN (empty otherwise).
    varied : tuple of str
        The assumptions of ``depends_on`` the set varies.
    points : tuple
        ``(point, result)`` per evaluated point of the sub-set, ``point`` restricted to
        :attr:`varied`.
    """

    fraction: float
    note: str = ""
    varied: tuple = ()
    points: tuple = ()


def _same_values(a: tuple, b: tuple) -> bool:
    if len(a) != len(b):
        return False
    for x, y in zip(a, b, strict=True):
        if isinstance(x, (float, np.floating)) or isinstance(y, (float, np.floating)):
            x, y = float(x), float(y)
            if not ((math.isnan(x) and math.isnan(y)) or math.isclose(x, y, rel_tol=1e-9,
                                                                     abs_tol=0.0)):
                return False
        elif x != y:
            return False
    return True


def _point_text(point: Mapping) -> str:
    return ", ".join(f"{k}={_fmt(v) if isinstance(v, (int, float)) else v}"
                     for k, v in point.items())


def robustness_over(variants: Sequence[tuple[Mapping, Sequence[ClaimResult]]],
                    baseline: Mapping) -> dict[str, Robustness]:
    """Per claim id, its :class:`Robustness` over ``variants``.

    Parameters
    ----------
    variants : sequence of (point, results)
        ``point``: assumption name -> value (a name left out is at its ``baseline``
        value); ``results``: the claims evaluated there.
    baseline : mapping
        The baseline value of every assumption of the set.

    Notes
    -----
    A claim is judged only on the points that differ from the baseline in the assumptions
    it declares (``depends_on``), so a factorial set's other axes do not repeat it. Where
    its headline value and its verdict are the same at every such point the fraction is NaN
    with the note "insensitive" (a robustness of 1.0 there would only restate the baseline
    verdict); a verdict that moves through a secondary check is counted.
    """
    by_id: dict[str, list[tuple[dict, ClaimResult]]] = {}
    for point, results in variants:
        full = {**baseline, **point}
        for r in results:
            by_id.setdefault(r.claim_id, []).append((full, r))
    varying = {k for k in baseline
               if len({repr(p.get(k, baseline[k])) for p, _ in variants}) > 1}
    out = {}
    for cid, rows in by_id.items():
        depends = rows[0][1].depends_on
        varied = tuple(k for k in depends if k in varying)
        if not varied:
            what = ", ".join(depends) if depends else "nothing declared"
            out[cid] = Robustness(float("nan"), f"not varied: the set varies none of its "
                                                f"assumptions ({what})")
            continue
        rest = [k for k in baseline if k not in varied]
        subset = [({k: p[k] for k in varied}, r) for p, r in rows
                  if all(repr(p[k]) == repr(baseline[k]) for k in rest)]
        unique = []
        for point, r in subset:
            if all(point != q for q, _ in unique):
                unique.append((point, r))
        evaluated = [(p, r) for p, r in unique if r.verdict != NOT_EVALUATED]
        if not evaluated:
            out[cid] = Robustness(float("nan"), "not evaluated at any point of its set",
                                  varied)
            continue
        first = evaluated[0][1].headline_values()
        if len({r.verdict for _, r in evaluated}) == 1 and all(
                _same_values(r.headline_values(), first) for _, r in evaluated):
            out[cid] = Robustness(
                float("nan"), f"insensitive: the same measured value at all {len(evaluated)} "
                f"points varying {', '.join(varied)}", varied, tuple(evaluated))
            continue
        frac = float(np.mean([r.verdict == "reproduced" for _, r in evaluated]))
        out[cid] = Robustness(frac, "", varied, tuple(evaluated))
    return out


def _margin(c: Check) -> float:
    """How far a numeric check's value is inside (+) or outside (-) its tolerance."""
    v, t = c.value, c.target
    if isinstance(v, (bool, np.bool_)) or isinstance(t, (bool, np.bool_)):
        return 0.0 if c.passed else -1.0
    v = float(v)
    if math.isnan(v):
        return -math.inf
    if c.op == "in":
        return min(v - t[0], t[1] - v)
    if c.op == "out":
        return max(t[0] - v, v - t[1])
    if c.op in ("<", "<="):
        return float(t) - v
    if c.op in (">", ">="):
        return v - float(t)
    return 0.0 if c.passed else -abs(v - float(t))


def explain(result: ClaimResult, robustness: Robustness | None) -> str:
    """The ``explanation`` of a ``partly`` / ``not reproduced`` claim: its own measured
    cause when the study gave one, otherwise what the assumption-set experiment measured
    (the headline value over the points varying what the claim depends on, and where it is
    closest to or meets the paper's statement). Empty for other verdicts and where neither
    exists (the claim is then counted as unexplained, :func:`paper_summary`)."""
    if result.verdict not in ("partly", "not reproduced"):
        return ""
    if result.explanation:
        return result.explanation
    if robustness is None or not robustness.points:
        return ""
    failing = [c for c in result.checks if not c.passed]
    key = failing[0].name
    rows = []
    for point, r in robustness.points:
        same = [c for c in r.checks if c.name == key]
        if same:
            rows.append((point, same[0]))
    if not rows:
        return ""
    values = [c.value for _, c in rows]
    varied = ", ".join(robustness.varied)
    if len({_fmt(v) for v in values}) == 1:
        c = rows[0][1]
        return (f"'{key}' is {_fmt(c.value)} at all {len(rows)} points varying {varied} "
                f"(needs {_target_text(c)}): the failure does not come from {varied}")
    numbers = [float(v) for v in values if not isinstance(v, (bool, np.bool_))]
    span = (f" ranges {_fmt(min(numbers))} to {_fmt(max(numbers))}" if numbers else "")
    passing = [(p, c) for p, c in rows if c.passed]
    head = f"over {varied} ({len(rows)} points) '{key}'{span}"
    if passing:
        point, c = passing[0]
        return (f"{head}; it holds at {len(passing)}/{len(rows)} points, e.g. at "
                f"{_point_text(point)}: {_fmt(c.value)}")
    point, c = max(rows, key=lambda pc: _margin(pc[1]))
    return (f"{head}; it holds at no point: closest at {_point_text(point)} with "
            f"{_fmt(c.value)} (needs {_target_text(c)})")


def _target_text(c: Check) -> str:
    if c.op in ("in", "out"):
        return f"{c.op} [{_fmt(c.target[0])}, {_fmt(c.target[1])}]"
    return f"{c.op} {_fmt(c.target)}"


# --------------------------------------------------------------------------------------------
# the registry
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Study:
    """A study registered with the engine.

    Attributes
    ----------
    name : str
        Short name (``"rocket"``, ``"table2"``, ...).
    paper : str
        Citation of the paper.
    baseline : callable
        ``baseline(quick) -> list[ClaimResult]`` at the study's baseline assumptions.
    grid : mapping
        The declared assumption set (data): name -> values. Empty when none applies.
    robustness : callable, optional
        ``robustness(quick) -> [(point, results), ...]``: the claims at points of
        :attr:`grid` (each point a mapping of assumption name -> value), judged by
        :func:`robustness_over`.
    grid_note : str
        How the grid is evaluated (factorial, one at a time, what is reused).
    order : int
        Position among the studies of the same module.
    baseline_point : mapping or callable
        The baseline value of every assumption of :attr:`grid` (a callable:
        ``baseline_point(quick)``, for studies whose quick mode has another baseline).
    """

    name: str
    paper: str
    baseline: Callable
    grid: Mapping = field(default_factory=dict)
    robustness: Callable | None = None
    grid_note: str = ""
    order: int = 0
    baseline_point: Mapping = field(default_factory=dict)

    def __post_init__(self):
        if self.robustness is not None:
            for quick in (False, True):
                missing = [k for k in self.grid if k not in self.baseline_at(quick)]
                if missing:
                    raise NavlibInputError(f"baseline_point: no baseline value for {missing}")

    def baseline_at(self, quick: bool) -> Mapping:
        """:attr:`baseline_point` in the given mode."""
        point = self.baseline_point
        return point(quick) if callable(point) else point

    @property
    def module(self) -> str:
        """The study module (or package) under :mod:`navlib.studies` that registered it."""
        parts = getattr(self.baseline, "__module__", "").split(".")
        return parts[2] if parts[:2] == ["navlib", "studies"] and len(parts) > 2 else parts[-1]


_REGISTRY: dict[str, Study] = {}


def register(study: Study) -> Study:
    """Add (or replace) a study in the registry."""
    if not isinstance(study, Study):
        raise NavlibInputError("study: expected a navlib.studies.claims.Study")
    _REGISTRY[study.name] = study
    return study


STUDY_MODULES = ("rocket_profile", "rocket", "launcher", "outliers", "ssac")
"""The modules under :mod:`navlib.studies` that register claims, in table order."""


def studies() -> dict[str, Study]:
    """The registered studies (imports the :data:`STUDY_MODULES`, which register
    themselves)."""
    import importlib

    for name in STUDY_MODULES:
        importlib.import_module(f"navlib.studies.{name}")
    order = {name: i for i, name in enumerate(STUDY_MODULES)}
    return dict(sorted(_REGISTRY.items(),
                       key=lambda kv: (order.get(kv[1].module, len(order)), kv[1].order)))


COLUMNS = ["study", "paper_ref", "claim_id", "statement", "paper", "ours", "verdict", "basis",
           "robustness", "checks", "assumption", "depends_on", "explanation",
           "robustness_note"]


def study_robustness(study: Study, quick: bool = False) -> dict[str, Robustness]:
    """:func:`robustness_over` the study's declared set (empty when it declares none)."""
    if study.robustness is None:
        return {}
    return robustness_over(study.robustness(quick), study.baseline_at(quick))


def study_frame(study: Study, quick: bool = False, robustness: bool = True) -> pd.DataFrame:
    """One study's claims in the :func:`all_claims` layout."""
    results = study.baseline(quick)
    rob = study_robustness(study, quick) if robustness else {}
    rows = []
    for r in results:
        res = rob.get(r.claim_id)
        if r.basis == "by construction":
            frac, note = float("nan"), "by construction"
        elif res is None:
            frac, note = float("nan"), ("no assumption set declared" if robustness
                                        else "not computed")
        else:
            frac, note = res.fraction, res.note
        rows.append({"study": study.name, "paper_ref": study.paper, "claim_id": r.claim_id,
                     "statement": r.claim, "paper": r.paper, "ours": r.ours,
                     "verdict": r.verdict, "basis": r.basis, "robustness": frac,
                     "checks": r.checks_text(), "assumption": r.assumption,
                     "depends_on": "; ".join(r.depends_on), "explanation": explain(r, res),
                     "robustness_note": note})
    return pd.DataFrame(rows, columns=COLUMNS)


def all_claims(quick: bool = False, only: Sequence[str] | None = None,
               robustness: bool = True) -> pd.DataFrame:
    """Every claim of every registered study, one row each (spec api.md, "Claims").

    Parameters
    ----------
    quick : bool
        Smoke-test mode: each study runs its quick settings (shorter runs, smaller grids);
        claims a quick run cannot judge are "not evaluated".
    only : sequence of str, optional
        Study names (default all, see :func:`studies`).
    robustness : bool
        Evaluate each study's declared assumption set (the ``robustness`` column).

    Returns
    -------
    DataFrame
        ``study, paper_ref, claim_id, statement, paper, ours, verdict, basis, robustness,
        checks, assumption, depends_on, explanation, robustness_note``; ``claim_id``
        unique.
    """
    registry = studies()
    names = list(registry) if only is None else list(only)
    unknown = [n for n in names if n not in registry]
    if unknown:
        raise NavlibInputError(f"only: unknown studies {unknown}; expected some of "
                               f"{list(registry)}")
    frame = pd.concat([study_frame(registry[n], quick, robustness) for n in names],
                      ignore_index=True)
    dup = frame["claim_id"][frame["claim_id"].duplicated()].tolist()
    if dup:  # pragma: no cover - registry integrity
        raise NavlibInputError(f"claims: duplicate claim ids {dup}")
    return frame


def counts(table: pd.DataFrame) -> pd.DataFrame:
    """Claims per paper by verdict and basis (for the summary page)."""
    return table.pivot_table(index=["paper_ref", "basis"], columns="verdict",
                             values="claim_id", aggfunc="count", fill_value=0)


@dataclass(frozen=True)
class JointSearch:
    """Which assumptions reproduce a paper's claims at once (:func:`joint_search`).

    Attributes
    ----------
    best : dict
        The assumption point reproducing the most claims (first in grid order on a tie).
    n_reproduced : int
        Claims reproduced there, of :attr:`claims`.
    n_points : int
        Points searched.
    claims : tuple of str
        The claims counted.
    held : dict
        Per claim, the number of points where it is reproduced.
    conflicts : DataFrame
        ``claim_a, claim_b, points_a, points_b`` for every pair that each hold somewhere
        but together nowhere in the space searched.
    """

    best: dict
    n_reproduced: int
    n_points: int
    claims: tuple
    held: dict
    conflicts: pd.DataFrame


def joint_search(frame: pd.DataFrame, parameters: Sequence[str],
                 claim_ids: Sequence[str]) -> JointSearch:
    """The best point and the conflicting claims of a sweep of an assumption space.

    Parameters
    ----------
    frame : DataFrame
        One row per point: the ``parameters`` columns and one boolean column per claim
        (True = reproduced), e.g. :func:`navlib.sweep.sweep` with the ``"claims"``
        evaluation.
    parameters : sequence of str
        The assumption columns.
    claim_ids : sequence of str
        The claim columns to count.
    """
    missing = [c for c in (*parameters, *claim_ids) if c not in frame.columns]
    if missing:
        raise NavlibInputError(f"frame: missing columns {missing}")
    if not len(frame):
        raise NavlibInputError("frame: no points")
    passed = frame[list(claim_ids)].astype(bool)
    count = passed.sum(axis=1)
    i = int(np.argmax(count.to_numpy()))
    held = {c: int(passed[c].sum()) for c in claim_ids}
    rows = []
    for k, a in enumerate(claim_ids):
        for b in claim_ids[k + 1:]:
            if held[a] and held[b] and not (passed[a] & passed[b]).any():
                rows.append({"claim_a": a, "claim_b": b, "points_a": held[a],
                             "points_b": held[b]})
    best = {p: frame[p].iloc[i] for p in parameters}
    return JointSearch(best, int(count.iloc[i]), len(frame), tuple(claim_ids), held,
                       pd.DataFrame(rows, columns=["claim_a", "claim_b", "points_a",
                                                   "points_b"]))


def paper_summary(table: pd.DataFrame) -> pd.DataFrame:
    """Per paper: measured claims reproduced, explained (partly / not reproduced with a
    measured ``explanation``) and unexplained, and the claims by construction, fitted and not
    evaluated (the summary notebook's first table)."""
    rows = []
    for paper, group in table.groupby("paper_ref", sort=False):
        measured = group[group.basis == "measured"]
        failing = group[group.verdict.isin(["partly", "not reproduced"])]
        explained = failing.explanation.fillna("").str.len() > 0
        rows.append({"paper": paper, "claims": len(group),
                     "reproduced": int((measured.verdict == "reproduced").sum()),
                     "explained": int(explained.sum()),
                     "unexplained": int((~explained).sum()),
                     "by construction": int((group.basis == "by construction").sum()),
                     "fitted": int((group.basis == "fitted").sum()),
                     "not evaluated": int((group.verdict == NOT_EVALUATED).sum())})
    return pd.DataFrame(rows).set_index("paper")


def summary_markdown(table: pd.DataFrame) -> str:
    """A short generated reading of :func:`all_claims` (no typed numbers)."""
    lines = []
    measured = table[table.basis == "measured"]
    n = len(table)
    by_v = measured.verdict.value_counts()
    lines.append(f"**{n} claims** from {table.paper_ref.nunique()} papers; "
                 f"{len(measured)} measured, "
                 f"{int((table.basis == 'by construction').sum())} by construction, "
                 f"{int((table.basis == 'fitted').sum())} fitted.")
    lines.append("Measured claims: " + ", ".join(
        f"{int(by_v.get(v, 0))} {v}" for v in STATUSES if by_v.get(v, 0)) + ".")
    rob = measured.robustness.dropna()
    if len(rob):
        lines.append(
            f"Robustness over the declared assumption sets ({len(rob)} measured claims with "
            f"a set): median {rob.median():.2f}; {int((rob >= 0.9).sum())} reproduce in at "
            f"least 90 % of their set, {int((rob == 0).sum())} in none.")
        fragile = measured[(measured.verdict == "reproduced") & (measured.robustness < 0.5)]
        if len(fragile):
            lines.append("Reproduced at the baseline but in less than half of the set: "
                         + ", ".join(f"{r.claim_id} ({r.robustness:.2f})"
                                     for r in fragile.itertuples()) + ".")
    return "\n\n".join(lines)


_READING_ORDER = (("reproduced", "Reproduced"), ("partly", "Partly"),
                  ("not reproduced", "Not reproduced"), (NOT_EVALUATED, "Not evaluated"))


def reading_markdown(results: Iterable[ClaimResult], lines: Sequence[str] = (),
                     robustness: Mapping[str, float] | None = None) -> str:
    """A generated "Reading" for a notebook: the claims grouped by verdict, each
    partly / not reproduced one with the checks that failed, then ``lines`` (further
    sentences the study computed). No number in it is typed, so a ``-p`` override never
    leaves a stale sentence.

    ``robustness``: claim id -> fraction of its assumption set where it reproduces.
    """
    results = list(results)
    out = []
    for verdict, label in _READING_ORDER:
        group = [r for r in results if r.verdict == verdict]
        if not group:
            continue
        out.append(f"**{label}** ({len(group)}):")
        for r in group:
            tag = "" if r.basis == "measured" else f" *({r.basis})*"
            rob = ""
            if robustness and not math.isnan(robustness.get(r.claim_id, float("nan"))):
                rob = f" — reproduces in {robustness[r.claim_id]:.0%} of its assumption set"
            failed = [c.text().replace("*", "\\*") for c in r.checks if not c.passed]
            why = f": {'; '.join(failed)}" if failed and verdict != "reproduced" else ""
            if verdict == NOT_EVALUATED:
                why = f": {r.note}"
            out.append(f"* **{r.claim_id}**{tag} — {r.claim}{why}{rob}")
        out.append("")
    if lines:
        out += [f"* {line}" for line in lines]
    return "\n".join(out).strip()
