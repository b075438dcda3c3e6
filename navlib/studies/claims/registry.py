"""The registry of studies (:func:`studies`) and each study's claims in the one table's layout
(:func:`study_frame`); the table itself is :func:`navlib.studies.claims.table.all_claims`."""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import pandas as pd

from navlib.errors import NavlibInputError
from navlib.studies.claims.robustness import (
    KINDS,
    Robustness,
    cause_of,
    changed_points,
    explain,
    robustness_over,
)

__all__ = ["COLUMNS", "STUDY_MODULES", "Study", "factorial_search", "register", "studies",
           "study_frame", "study_robustness"]


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
    kinds : mapping
        Per assumption the study declares (its grid, its cause experiments and searches),
        whether it is a reading or model of ours (``"ours"``) or a quantity the paper does not
        give (``"unstated"``): :data:`~navlib.studies.claims.robustness.KINDS`, read by the
        ``cause`` column (:func:`~navlib.studies.claims.robustness.cause_of`).
    """

    name: str
    paper: str
    baseline: Callable
    grid: Mapping = field(default_factory=dict)
    robustness: Callable | None = None
    grid_note: str = ""
    order: int = 0
    baseline_point: Mapping = field(default_factory=dict)
    kinds: Mapping = field(default_factory=dict)

    def __post_init__(self):
        bad = {k: v for k, v in self.kinds.items() if v not in KINDS}
        if bad:
            raise NavlibInputError(f"kinds: expected values in {KINDS}, got {bad}")
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


STUDY_MODULES = ("rocket", "launcher", "outliers", "ssac")
"""The modules (or packages) under :mod:`navlib.studies` that register claims, in table
order."""


def studies() -> dict[str, Study]:
    """The registered studies (imports the :data:`STUDY_MODULES`, which register
    themselves; imported here, not at the top, because they import this engine)."""
    for name in STUDY_MODULES:
        importlib.import_module(f"navlib.studies.{name}")
    order = {name: i for i, name in enumerate(STUDY_MODULES)}
    return dict(sorted(_REGISTRY.items(),
                       key=lambda kv: (order.get(kv[1].module, len(order)), kv[1].order)))


COLUMNS = ["study", "paper_ref", "claim_id", "statement", "paper", "ours", "verdict", "basis",
           "robustness", "cause", "checks", "assumption", "depends_on", "explanation",
           "robustness_note"]


def study_robustness(study: Study, quick: bool = False) -> dict[str, Robustness]:
    """:func:`robustness_over` the study's declared set (empty when it declares none).

    Parameters
    ----------
    study : Study
        The study.
    quick : bool, optional
        Quick settings.

    Returns
    -------
    dict of str to Robustness
    """
    if study.robustness is None:
        return {}
    return robustness_over(study.robustness(quick), study.baseline_at(quick))


def study_frame(study: Study, quick: bool = False, robustness: bool = True) -> pd.DataFrame:
    """One study's claims in the :func:`all_claims` layout.

    Parameters
    ----------
    study : Study
        The study.
    quick : bool, optional
        Quick settings.
    robustness : bool, optional
        Whether to judge robustness over the declared set.

    Returns
    -------
    pandas.DataFrame
    """
    results = study.baseline(quick)
    rob = study_robustness(study, quick) if robustness else {}
    rows = []
    for r in results:
        res = rob.get(r.claim_id)
        holds_at = changed_points(res, study.baseline_at(quick))
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
                     "cause": cause_of(r.verdict, holds_at, study.kinds),
                     "checks": r.checks_text(), "assumption": r.assumption,
                     "depends_on": "; ".join(r.depends_on), "explanation": explain(r, res),
                     "robustness_note": note})
    return pd.DataFrame(rows, columns=COLUMNS)


def factorial_search(name: str, quick: bool = False) -> pd.DataFrame | None:
    """Study ``name``'s claims at every point of its declared set, as a joint-search frame.

    When the study evaluates its set as a full factorial (every combination of the values
    its points take), its robustness points are a joint search of that space already, in
    process: one row per point (the :attr:`Study.grid` columns, a name a point leaves out at
    its baseline value) and one boolean column per measured claim judged at every point
    (True = reproduced), for :func:`~navlib.studies.claims.joint_search`. None when the set
    is evaluated one assumption at a time (such points cannot show which claims hold
    together) or the study declares none.

    Parameters
    ----------
    name : str
        Study name.
    quick : bool, optional
        Quick settings.
    """
    study = studies()[name]
    if study.robustness is None or not study.grid:
        return None
    baseline = study.baseline_at(quick)
    measured = [r.claim_id for r in study.baseline(quick) if r.basis == "measured"]
    rows = []
    for point, results in study.robustness(quick):
        verdicts = {r.claim_id: r.verdict == "reproduced" for r in results}
        rows.append({**{k: baseline[k] for k in study.grid}, **point, **verdicts})
    frame = pd.DataFrame(rows)
    keys = list(study.grid)
    levels = [frame[k].map(repr).nunique() for k in keys]
    distinct = len(frame[keys].map(repr).drop_duplicates())
    if distinct != len(frame) or distinct != int(pd.Series(levels).prod()) or distinct < 2:
        return None
    claims = [c for c in measured if c in frame.columns and frame[c].notna().all()]
    return frame[keys + claims].astype({c: bool for c in claims})
