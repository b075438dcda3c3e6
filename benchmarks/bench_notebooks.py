"""Per-notebook cost of a full-mode report (issue 14, point 5): wall time and peak kernel
memory of each ``notebooks/NN_*.ipynb``.

Each case runs ``python -m navlib report --only NN --output <temp dir>`` in a subprocess
(papermill execution plus the HTML export, kernel start included) once, with no warm-up, and
polls the subprocess tree with :mod:`psutil` every 0.2 s: ``peak_kernel_gb`` is the largest
resident set size seen for the kernel process (the ``ipykernel`` child), so a peak shorter
than the polling period can be missed. Goals: notebook 05 < 30 s (the issue's own goal); every
other notebook gets an equal share of the remaining 60 s of the < 90 s report goal.

Usage: ``python benchmarks/run.py notebook`` (only these cases) or
``python benchmarks/run.py notebook/05`` (one notebook). Takes about the time of a full
``make report`` (several minutes).
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _harness import Case

from navlib.resources import notebooks_dir

POLL_S = 0.2
REPORT_GOAL_S = 90.0
GOALS_S = {"05": 30.0}


def _kernel_rss(proc) -> int:
    """Largest resident set size (bytes) of an ipykernel process under ``proc``."""
    import psutil

    best = 0
    try:
        children = psutil.Process(proc.pid).children(recursive=True)
    except psutil.NoSuchProcess:
        return 0
    for child in children:
        try:
            if any("ipykernel" in part for part in child.cmdline()):
                best = max(best, child.memory_info().rss)
        except (psutil.NoSuchProcess, psutil.AccessDenied):
            continue
    return best


def run_notebook(number: str, peaks: dict) -> float:
    """Run one notebook in full mode in a subprocess; record its kernel peak in ``peaks``."""
    with tempfile.TemporaryDirectory(prefix="navlib-bench-") as out:
        start = time.perf_counter()
        proc = subprocess.Popen([sys.executable, "-m", "navlib", "report", "--only", number,
                                 "--output", out], stdout=subprocess.DEVNULL,
                                stderr=subprocess.PIPE, text=True)
        peak = 0
        while proc.poll() is None:
            peak = max(peak, _kernel_rss(proc))
            time.sleep(POLL_S)
        elapsed = time.perf_counter() - start
        err = proc.stderr.read()
        if proc.returncode != 0:
            raise RuntimeError(f"notebook {number} failed:\n{err[-2000:]}")
    peaks[number] = peak
    return elapsed


def cases() -> list[Case]:
    paths = sorted(Path(notebooks_dir()).glob("[0-9][0-9]_*.ipynb"))
    others = [p for p in paths if p.name[:2] not in GOALS_S]
    share = (REPORT_GOAL_S - sum(GOALS_S.values())) / max(len(others), 1)
    peaks: dict[str, int] = {}
    out = []
    for path in paths:
        number = path.name[:2]
        goal = GOALS_S.get(number, share)
        out.append(Case(
            f"notebook/{path.stem}", "full mode", lambda n=number: run_notebook(n, peaks),
            goal, repeat=1, warmup=False,
            extra=lambda _t, n=number: {"peak_kernel_gb": peaks.get(n, 0) / 1e9},
            notes="05: issue goal; others: share of the 90 s report"
            if number == "05" else ""))
    return out
