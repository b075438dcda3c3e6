"""Robustness of a claim over its study's declared assumption set (:func:`robustness_over`),
the measured explanation of a partly / not reproduced claim (:func:`explain`) and the joint
search of a swept assumption space (:func:`joint_search`)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from navlib.errors import NavlibInputError
from navlib.studies.claims.records import NOT_EVALUATED, Check, ClaimResult, fmt

__all__ = ["CAUSES", "KINDS", "JointSearch", "Robustness", "cause_of", "changed_points", "explain",
           "joint_search", "robustness_over"]


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
    return ", ".join(f"{k}={fmt(v) if isinstance(v, (int, float)) else v}"
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


CAUSES = ("paper", "ours", "unstated")
"""Whose a partly / not reproduced claim is (:func:`cause_of`)."""
KINDS = ("ours", "unstated", "fitted")
"""Kinds of a declared assumption: ``ours`` = a reading or a model of ours (a rank
tolerance, the sign of A1, the surrogate ascent), ``unstated`` = a quantity the paper does
not give (an initial sigma, a threshold eta, a time constant), ``fitted`` = a setup chosen to
make claims hold that contradicts the paper's own (the near-vertical ascent without a pitch
programme, A-F2-pitch): a point changing it never counts as where a claim holds."""


def cause_of(verdict: str, holds_at: Sequence[Mapping], kinds: Mapping) -> str:
    """Whose a ``partly`` / ``not reproduced`` claim is, from measurements.

    Parameters
    ----------
    verdict : str
        The claim's verdict at the baseline.
    holds_at : sequence of mapping
        The points where a measurement found the claim reproduced, each restricted to the
        assumptions it changes from the baseline (its robustness points, a stored joint
        search).
    kinds : mapping
        Assumption name -> one of :data:`KINDS` (an undeclared name counts as
        ``unstated``; a point changing a ``fitted`` one is left out).

    Returns
    -------
    str
        ``""`` for a reproduced or not evaluated claim; ``"paper"`` when it holds nowhere the
        measurements looked (the paper's own setup fails it, as far as the declared sets
        reach); ``"ours"`` when it holds once only readings or models of ours change;
        ``"unstated"`` when every point where it holds changes a quantity the paper does not
        give.
    """
    if verdict not in ("partly", "not reproduced"):
        return ""
    points = [p for p in holds_at
              if p and not any(kinds.get(k) == "fitted" for k in p)]
    if not points:
        return "paper"
    if any(all(kinds.get(k, "unstated") == "ours" for k in p) for p in points):
        return "ours"
    return "unstated"


def changed_points(robustness: Robustness | None, baseline: Mapping) -> list[dict]:
    """The points of ``robustness`` where its claim is reproduced, each restricted to the
    assumptions that differ from ``baseline`` (for :func:`cause_of`)."""
    if robustness is None:
        return []
    return [{k: v for k, v in point.items() if repr(v) != repr(baseline.get(k))}
            for point, r in robustness.points if r.verdict == "reproduced"]


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
    if len({fmt(v) for v in values}) == 1:
        c = rows[0][1]
        return (f"'{key}' is {fmt(c.value)} at all {len(rows)} points varying {varied} "
                f"(needs {_target_text(c)}): the failure does not come from {varied}")
    numbers = [float(v) for v in values if not isinstance(v, (bool, np.bool_))]
    span = (f" ranges {fmt(min(numbers))} to {fmt(max(numbers))}" if numbers else "")
    passing = [(p, c) for p, c in rows if c.passed]
    head = f"over {varied} ({len(rows)} points) '{key}'{span}"
    if passing:
        point, c = passing[0]
        return (f"{head}; it holds at {len(passing)}/{len(rows)} points, e.g. at "
                f"{_point_text(point)}: {fmt(c.value)}")
    point, c = max(rows, key=lambda pc: _margin(pc[1]))
    return (f"{head}; it holds at no point: closest at {_point_text(point)} with "
            f"{fmt(c.value)} (needs {_target_text(c)})")


def _target_text(c: Check) -> str:
    if c.op in ("in", "out"):
        return f"{c.op} [{fmt(c.target[0])}, {fmt(c.target[1])}]"
    return f"{c.op} {fmt(c.target)}"



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

