"""Summaries of the claims table for notebooks and reports: counts per paper, the summary
page's paper table and markdown, and a notebook's generated reading."""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence

import pandas as pd

from navlib.studies.claims.records import NOT_EVALUATED, STATUSES, ClaimResult
from navlib.studies.claims.robustness import CAUSES

__all__ = ["counts", "full_text", "paper_summary", "reading_markdown", "summary_markdown"]


def counts(table: pd.DataFrame) -> pd.DataFrame:
    """Claims per paper by verdict and basis (for the summary page)."""
    return table.pivot_table(index=["paper_ref", "basis"], columns="verdict",
                             values="claim_id", aggfunc="count", fill_value=0)


def paper_summary(table: pd.DataFrame) -> pd.DataFrame:
    """Per paper: measured claims reproduced, explained (partly / not reproduced with a
    measured ``explanation``) and unexplained, the partly / not reproduced ones by ``cause``
    (``cause paper``, ``cause ours``, ``cause unstated``: whose they are,
    :func:`~navlib.studies.claims.robustness.cause_of`), and the claims by construction,
    fitted and not evaluated (the summary notebook's first table)."""
    rows = []
    for paper, group in table.groupby("paper_ref", sort=False):
        measured = group[group.basis == "measured"]
        failing = group[group.verdict.isin(["partly", "not reproduced"])]
        explained = failing.explanation.fillna("").str.len() > 0
        rows.append({"paper": paper, "claims": len(group),
                     "reproduced": int((measured.verdict == "reproduced").sum()),
                     "explained": int(explained.sum()),
                     "unexplained": int((~explained).sum()),
                     **{f"cause {c}": int((failing.cause == c).sum()) for c in CAUSES},
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


def full_text(frame: pd.DataFrame):
    """``frame`` styled for a notebook page: every text in full (no truncation), wrapped,
    left- and top-aligned, numbers at 2 decimals, NaN blank, no index (notebook 00's claims
    tables, whose explanations run to several sentences)."""
    return (frame.style.hide(axis="index").format(precision=2, na_rep="")
            .set_properties(**{"white-space": "pre-wrap", "text-align": "left",
                               "vertical-align": "top"}))
