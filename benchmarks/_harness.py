"""Tiny benchmark harness: each ``bench_*.py`` module exposes ``cases()`` -> list of Case.

A case times ``func`` (best of ``repeat`` runs after one warm-up) and compares it with its
``goal_s`` (the performance goal from the issue). ``ratio`` = time / goal, so a ratio
below 1 meets the goal. ``extra`` may return further columns (e.g. a FLOP-rate ratio) and
``table`` a table of the case's own, printed when the case has run. :func:`run_jobs` spreads
a module's independent runs over worker processes.
"""

from __future__ import annotations

import importlib.util
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path

import pandas as pd


@dataclass
class Case:
    name: str
    size: str
    func: Callable[[], object]
    goal_s: float
    repeat: int = 3
    warmup: bool = True
    extra: Callable[[float], dict] | None = None
    notes: str = field(default="")
    table: Callable[[], pd.DataFrame] | None = None


def time_case(case: Case) -> dict:
    """Run one case and return its table row."""
    if case.warmup:
        case.func()
    best = float("inf")
    for _ in range(case.repeat):
        start = time.perf_counter()
        case.func()
        best = min(best, time.perf_counter() - start)
    row = {"name": case.name, "size": case.size, "time_s": best, "goal_s": case.goal_s,
           "ratio": best / case.goal_s}
    if case.extra is not None:
        row.update(case.extra(best))
    if case.notes:
        row["notes"] = case.notes
    if case.table is not None:
        with pd.option_context("display.width", 200, "display.max_columns", 30,
                               "display.float_format", "{:.4g}".format):
            print(f"{case.name}:\n{case.table().to_string(index=False)}\n", flush=True)
    return row


@cache
def _module(path: str):
    spec = importlib.util.spec_from_file_location(Path(path).stem, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _job(path: str, name: str, args: tuple):
    return getattr(_module(path), name)(*args)


def run_jobs(path: str, name: str, jobs: Sequence[tuple], workers: int = 2) -> list:
    """``[module.name(*args) for args in jobs]`` in ``workers`` processes, for the benchmark
    module at ``path`` (``run.py`` loads modules from their files, so worker processes find
    the function by file and name rather than by pickling it). Jobs return plain data
    (arrays, numbers): the module's own classes are not importable by name."""
    with ProcessPoolExecutor(workers) as pool:
        return list(pool.map(_job, [path] * len(jobs), [name] * len(jobs), jobs))


@cache
def rocket_flight():
    """The default sounding-rocket trajectory, built once per benchmark run."""
    from navlib.trajectory import sounding_rocket

    return sounding_rocket()


@cache
def launcher_flight():
    """The default launcher ascent, built once per benchmark run."""
    from navlib.trajectory import launcher_ascent

    return launcher_ascent()
