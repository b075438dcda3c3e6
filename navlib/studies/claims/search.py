"""Joint searches of the papers' assumption spaces: which declared assumptions reproduce the
most claims at once, and which claims hold together nowhere.

A study declares its space as a :class:`SearchSpace` (registered with
:func:`register_search`): the sweep points of its declared assumptions, the named sweep
evaluation (:func:`navlib.sweep.register`, one boolean column per claim) that judges the
claims at a point, and the ``data/`` file that stores the full search.
``scripts/claims_search.py`` runs :func:`run_search` (through :func:`navlib.sweep.sweep`, so on
a Dask cluster as well as here) and writes the file with the command line and the navlib
version; notebook 00 reads it with :func:`stored_search` and judges it with
:func:`~navlib.studies.claims.joint_search`; a test recomputes a random sample of its points.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import pandas as pd

from navlib._validation import reject_unknown
from navlib.errors import NavlibInputError
from navlib.resources import data_dir
from navlib.studies.claims.registry import factorial_search, studies
from navlib.studies.claims.robustness import joint_search
from navlib.sweep import sweep

__all__ = ["SEARCH_SPACES", "SearchSpace", "SearchTable", "factorial_points", "joint_searches",
           "paper_joint_summary", "register_search", "run_search", "search_space", "stored_search"]


@dataclass(frozen=True)
class SearchSpace:
    """The declared assumption space of one paper's claims, searched jointly.

    Attributes
    ----------
    name : str
        The search's name (a paper's study, e.g. ``"rocket"``).
    paper : str
        The paper, as in the claims table's ``paper_ref``.
    parameters : tuple of str
        The assumption columns of a point.
    claim_ids : tuple of str
        The claims judged at each point (one boolean column each).
    evaluation : str
        The named sweep evaluation judging the claims at a point.
    points : callable
        ``points(grid=None)``: the points of the space as a DataFrame of ``parameters``
        (``grid`` narrows it, for tests and samples; ``points({})`` is the baseline point
        alone).
    file : str
        The stored search's file name under ``data/``.
    """

    name: str
    paper: str
    parameters: tuple
    claim_ids: tuple
    evaluation: str
    points: Callable
    file: str


SEARCH_SPACES: dict[str, SearchSpace] = {}
"""Registered spaces by name, in registration order."""


def register_search(space: SearchSpace) -> SearchSpace:
    """Register ``space`` under its name (a study's package does this on import)."""
    SEARCH_SPACES[space.name] = space
    return space


def search_space(name: str) -> SearchSpace:
    """The registered space ``name``; NavlibInputError naming the known ones otherwise."""
    if name not in SEARCH_SPACES:
        raise NavlibInputError(f"search {name!r}: unknown; known: {list(SEARCH_SPACES)}")
    return SEARCH_SPACES[name]


def factorial_points(grid: Mapping | None, declared: Mapping,
                     baseline: Mapping) -> pd.DataFrame:
    """The full-factorial points of a declared assumption space, one column per assumption.

    ``declared`` maps each assumption to its values; ``grid`` (None: all of ``declared``)
    narrows it to some names and values, a name it leaves out keeping its ``baseline``
    value, so ``factorial_points({}, ...)`` is the baseline point alone. Columns come in
    ``declared`` order, the last varying fastest.
    """
    grid = dict(declared) if grid is None else dict(grid)
    reject_unknown(grid, declared, "grid")
    grid = {**{name: (baseline[name],) for name in declared}, **grid}
    return pd.DataFrame(list(itertools.product(*(grid[name] for name in declared))),
                        columns=list(declared))


def run_search(name: str, grid: dict | None = None, scheduler=None,
               output=None) -> pd.DataFrame:
    """The claims of search ``name`` at every point of its space (or of ``grid``), through
    :func:`navlib.sweep.sweep` (``scheduler`` and ``output`` as there)."""
    space = search_space(name)
    return sweep(space.points(grid), space.evaluation, scheduler=scheduler, output=output)


def stored_search(name: str) -> tuple[pd.DataFrame, dict]:
    """The stored search table of ``name`` and its header (``command``, ``navlib`` version)."""
    path = data_dir() / search_space(name).file
    if not path.exists():
        raise NavlibInputError(f"{path} is missing: run scripts/claims_search.py --study {name}")
    header = {}
    with path.open(encoding="utf-8") as handle:
        for line in handle:
            if not line.startswith("#"):
                break
            key, _, value = line[1:].partition(":")
            header[key.strip()] = value.strip()
    return pd.read_csv(path, comment="#"), header


@dataclass(frozen=True)
class SearchTable:
    """One joint search as notebook 00 shows it (:func:`joint_searches`).

    Attributes
    ----------
    name, paper : str
        The search (a :data:`SEARCH_SPACES` name, or the study searched in process) and the
        paper.
    source : str
        Where the table comes from (the stored file's command line and navlib version, or
        the study's factorial set evaluated in this process).
    frame : DataFrame
        One row per point: the ``parameters`` columns and a boolean column per claim.
    parameters, claim_ids : tuple of str
    baseline : Series
        The baseline point (the ``parameters``).
    """

    name: str
    paper: str
    source: str
    frame: pd.DataFrame
    parameters: tuple
    claim_ids: tuple
    baseline: pd.Series


def joint_searches(quick: bool = False) -> list[SearchTable]:
    """Every joint search of the papers' assumption spaces: the stored searches of
    :data:`SEARCH_SPACES`, then, for each study whose measured claims no stored search
    judges, its declared set when the study evaluates it as a full factorial
    (:func:`~navlib.studies.claims.registry.factorial_search`, in process: the Beaudoin
    Table 2 claims over the rounding of a printed order and the rank tolerance, and the
    outlier claims over the recovery window and the sign of A1)."""
    out = []
    for name, space in SEARCH_SPACES.items():
        frame, header = stored_search(name)
        out.append(SearchTable(name, space.paper,
                               f"{header['command']} (navlib {header['navlib']})", frame,
                               space.parameters, space.claim_ids, space.points({}).iloc[0]))
    searched = {c for space in SEARCH_SPACES.values() for c in space.claim_ids}
    for name, study in studies().items():
        frame = factorial_search(name, quick)
        if frame is None:
            continue
        parameters = tuple(study.grid)
        claims = tuple(c for c in frame.columns[len(parameters):] if c not in searched)
        if claims:
            baseline = study.baseline_at(quick)
            out.append(SearchTable(
                name, study.paper, f"the study's declared set, full factorial, in process "
                f"({study.grid_note})", frame[[*parameters, *claims]], parameters, claims,
                pd.Series({k: baseline[k] for k in parameters})))
    return out


def paper_joint_summary(searches: list[SearchTable]) -> pd.DataFrame:
    """Per paper, its joint searches together: the claims searched, the number reproduced at
    each search's best point, and their sum. When a paper's searches share no assumption,
    the union of their best points is one assumption set and the sum is what it reproduces
    (``joint`` True: the paper's best joint set); when they share one, the sum is only an
    upper bound (``joint`` False).

    Returns
    -------
    DataFrame
        ``paper, searches, points, claims, reproduced, conflicts, joint``, one row per paper.
    """
    rows: dict[str, dict] = {}
    for search in searches:
        found = joint_search(search.frame, search.parameters, search.claim_ids)
        row = rows.setdefault(search.paper, {"paper": search.paper, "searches": [],
                                             "points": [], "claims": 0, "reproduced": 0,
                                             "conflicts": 0, "parameters": []})
        row["searches"].append(search.name)
        row["points"].append(found.n_points)
        row["claims"] += len(found.claims)
        row["reproduced"] += found.n_reproduced
        row["conflicts"] += len(found.conflicts)
        row["parameters"].extend(search.parameters)
    out = []
    for row in rows.values():
        parameters = row.pop("parameters")
        out.append({**row, "searches": ", ".join(row["searches"]),
                    "points": " x ".join(str(n) for n in row["points"]),
                    "joint": len(parameters) == len(set(parameters))})
    return pd.DataFrame(out, columns=["paper", "searches", "points", "claims", "reproduced",
                                      "conflicts", "joint"])
