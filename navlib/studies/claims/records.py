"""The claim record: a :class:`Check` (a measured value against a tolerance), the one
verdict rule (:func:`verdict_of`) and the :class:`ClaimResult` a study returns per claim."""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from navlib.errors import NavlibInputError

__all__ = ["BASES", "NOT_EVALUATED", "OPS", "STATUSES", "VERDICTS", "Check", "ClaimResult", "check",
           "claim", "claims_frame", "fmt", "not_evaluated", "verdict_of", "with_failed_headline"]

VERDICTS = ("reproduced", "partly", "not reproduced")
"""The verdicts of :func:`verdict_of`."""
NOT_EVALUATED = "not evaluated"
"""Status of a claim whose checks could not be evaluated on the given input."""
STATUSES = (*VERDICTS, NOT_EVALUATED)
BASES = ("measured", "by construction", "fitted")
"""How a claim's number relates to our assumptions (module docstring)."""
OPS = ("<", "<=", ">", ">=", "==", "!=", "in", "out")
"""Comparisons a :class:`Check` supports (``in``/``out``: inside/outside ``[low, high]``)."""


def fmt(x) -> str:
    """A checked value as printed in a check's text (yes/no, integers, 4 significant
    digits, 3 in scientific notation outside [1e-3, 1e4))."""
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
            target = f"[{fmt(self.target[0])}, {fmt(self.target[1])}]"
            op = "in" if self.op == "in" else "outside"
        else:
            target, op = fmt(self.target), self.op
        mark = "*" if self.headline else ""
        return (f"{mark}{self.name}: {fmt(self.value)} {op} {target} -> "
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
    """Shorthand for :class:`Check`.

    Parameters
    ----------
    name : str
        What is checked.
    value : float or bool
        Our number.
    op : str
        Comparison (``"<="``, ``">="``, ``"=="``, ``"in"``, ``"out"`` ...).
    target : float, bool or tuple
        The paper's number or range.
    headline : bool, optional
        Whether the verdict rests on this check.

    Returns
    -------
    Check
    """
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
    """Build a :class:`ClaimResult` (the verdict follows from ``checks``).

    Parameters
    ----------
    claim_id : str
        Id of the claim.
    statement : str
        What the paper says.
    paper : str
        The paper's numbers.
    ours : str
        Our numbers.
    checks : iterable of Check
        The checks.
    basis : {"measured", "by construction", "fitted"}, optional
        How the number relates to our assumptions (:data:`BASES`).
    assumption : str, optional
        Assumptions of the reading.
    depends_on : sequence of str, optional
        Assumptions that can move the verdict.
    explanation : str, optional
        Measured cause of a miss.

    Returns
    -------
    ClaimResult
    """
    return ClaimResult(claim_id, statement, paper, ours, tuple(checks), basis, assumption,
                       depends_on=depends_on, explanation=explanation)


def not_evaluated(claim_id: str, statement: str, paper: str, why: str, *,
                  basis: str = "measured", assumption: str = "",
                  depends_on: Sequence[str] = ()) -> ClaimResult:
    """A claim the given input cannot judge (``why`` says what is missing).

    Parameters
    ----------
    claim_id : str
        Id of the claim.
    statement : str
        What the paper says.
    paper : str
        The paper's numbers.
    why : str
        What is missing.
    basis : {"measured", "by construction", "fitted"}, optional
        How the number would relate to our assumptions (:data:`BASES`).
    assumption : str, optional
        Assumptions of the reading.
    depends_on : sequence of str, optional
        Assumptions that can move the verdict.

    Returns
    -------
    ClaimResult
    """
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

