"""Tiny benchmark harness: each ``bench_*.py`` module exposes ``cases()`` -> list of Case.

A case times ``func`` (best of ``repeat`` runs after one warm-up) and compares it with its
``goal_s`` (the performance goal from the issue). ``ratio`` = time / goal, so a ratio
below 1 meets the goal. ``extra`` may return further columns (e.g. a FLOP-rate ratio).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cache


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
    return row


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
