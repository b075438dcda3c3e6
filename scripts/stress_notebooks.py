"""Stress the report runner: execute notebooks in quick mode many times and count stalls.

A *stall* is a run in which the runner waited on a kernel that had already finished (or
stopped answering). Used to find why report runs hung (a lost kernel wake-up) and to show the fix::

    python scripts/stress_notebooks.py --runs 20 --only 02            # bounded runner
    python scripts/stress_notebooks.py --runs 5                        # every notebook 5x
    python scripts/stress_notebooks.py --runs 20 --only 02 --runner papermill
    python scripts/stress_notebooks.py ... --load 1                    # + 1 busy process

``--runner bounded`` (default) is the report runner (:mod:`navlib.reports.kernel_watch`): stalls
are the watchdog's restarts, *lost* the kernel messages whose ZeroMQ wake-up never came (found
when a 0.25 s poll slice expired; recovered, not stalls). ``--runner papermill`` is plain
papermill with jupyter_client's channels (the runner before the fix), given a per-cell limit so
a stall ends: a stall there is a cell whose client-side duration exceeds the kernel's own reply
time by more than ``--lag`` seconds (the reply sat unread: *lost* counts those cells), or a
timed-out cell. ``--load N`` starts N busy processes for the duration (the issue's "other core
busy").
Prints one row per run and a summary table; not part of the test suite.
"""

from __future__ import annotations

import argparse
import datetime as dt
import multiprocessing
import sys
import tempfile
import time
from pathlib import Path

import nbformat

from navlib import reports
from navlib.reports.execution import Kernels, Settings, execute
from navlib.reports.kernel_watch import KernelWatch

ROOT = Path(__file__).resolve().parents[1]


def _busy() -> None:
    while True:
        pass


def _reply_lags(executed: Path, min_lag_s: float) -> list[tuple[int, float, float]]:
    """(cell, client duration, kernel reply time) of cells whose reply sat unread."""
    lags = []
    for k, cell in enumerate(nbformat.read(executed, as_version=4).cells):
        timing = cell.metadata.get("execution", {})
        duration = cell.metadata.get("papermill", {}).get("duration")
        if duration is None or "shell.execute_reply" not in timing:
            continue
        busy = timing.get("iopub.status.busy") or timing.get("iopub.execute_input")
        if busy is None:
            continue

        def parse(stamp):
            return dt.datetime.fromisoformat(stamp.replace("Z", "+00:00"))

        kernel_s = (parse(timing["shell.execute_reply"]) - parse(busy)).total_seconds()
        if duration - kernel_s > min_lag_s:
            lags.append((k, round(duration, 2), round(kernel_s, 2)))
    return lags


def run_papermill(info, out: Path, timeout_s: float, min_lag_s: float) -> dict:
    """One run with plain papermill (the runner before the bounded kernel watch)."""
    import papermill
    from jupyter_client.manager import AsyncKernelManager

    from navlib.reports import kernel_watch

    base = kernel_watch._classes().kernel_manager  # same kernel command, plain client and channels
    plain = type("PlainKernelManager", (base,), {
        "watch": None, "client": AsyncKernelManager.client})
    executed = out / f"{info.name}.ipynb"
    error = ""
    try:
        papermill.execute_notebook(
            str(info.path), str(executed), parameters={"quick": True}, kernel_name="python3",
            cwd=str(info.path.parent), progress_bar=False, execution_timeout=timeout_s,
            kernel_manager_class=plain)
    except Exception as exc:  # a stall ends as a timeout; other errors are reported
        error = f"{type(exc).__name__}: {str(exc).splitlines()[0][:80]}"
    lags = _reply_lags(executed, min_lag_s) if executed.exists() else []
    stalled = bool(lags) or "Timeout" in error
    return {"stalls": int(stalled), "lost": len(lags), "error": error, "detail": lags}


def run_bounded(info, out: Path, timeout_s: float) -> dict:
    """One run through the report runner's execution (watchdog + sliced polling)."""
    settings = Settings(quick=True, parameters={}, fail_fast=False, timeout_s=timeout_s,
                        jobs=1, env={})
    run = execute(info, out, {"quick": True}, settings, Kernels())
    error = "" if run.ok else run.failure.describe()
    return {"stalls": len(run.stalls) + int(not run.ok and "Stalled" in error),
            "lost": run.lost_wakeups, "error": error, "detail": list(run.stalls)}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5, help="runs per notebook")
    parser.add_argument("--only", nargs="+", default=None, help="notebooks (stem or NN)")
    parser.add_argument("--runner", choices=["bounded", "papermill"], default="bounded")
    parser.add_argument("--load", type=int, default=0, help="busy processes to start")
    parser.add_argument("--timeout", type=float, default=120.0, help="per-cell limit, s")
    parser.add_argument("--lag", type=float, default=5.0,
                        help="papermill runner: unread-reply time that counts as a stall, s")
    args = parser.parse_args(argv)

    selected = reports.select_notebooks(reports.list_notebooks(ROOT / "notebooks"), args.only)
    busy = [multiprocessing.Process(target=_busy, daemon=True) for _ in range(args.load)]
    for process in busy:
        process.start()
    totals = {info.name: {"runs": 0, "stalls": 0, "lost": 0, "failed": 0, "seconds": 0.0}
              for info in selected}
    try:
        for repeat in range(args.runs):
            for info in selected:
                with tempfile.TemporaryDirectory() as tmp:
                    start = time.perf_counter()
                    if args.runner == "papermill":
                        row = run_papermill(info, Path(tmp), args.timeout, args.lag)
                    else:
                        row = run_bounded(info, Path(tmp), args.timeout)
                    seconds = time.perf_counter() - start
                total = totals[info.name]
                total["runs"] += 1
                total["stalls"] += row["stalls"]
                total["lost"] += row["lost"]
                total["failed"] += int(bool(row["error"]))
                total["seconds"] += seconds
                print(f"{repeat + 1:3d} {info.name:28s} {seconds:7.1f} s  stalls "
                      f"{row['stalls']}  lost {row['lost']}  {row['error']} "
                      f"{row['detail'] or ''}", flush=True)
    finally:
        for process in busy:
            process.terminate()
    print(f"\nrunner={args.runner} load={args.load} timeout={args.timeout:.0f} s "
          f"(python {sys.version.split()[0]}, {KernelWatch.__module__})")
    print(f"{'notebook':28s} {'runs':>5s} {'stalls':>7s} {'lost':>5s} {'failed':>7s} "
          f"{'mean s':>7s}")
    for name, t in totals.items():
        print(f"{name:28s} {t['runs']:5d} {t['stalls']:7d} {t['lost']:5d} {t['failed']:7d} "
              f"{t['seconds'] / max(t['runs'], 1):7.1f}")
    runs = sum(t["runs"] for t in totals.values())
    stalls = sum(t["stalls"] for t in totals.values())
    print(f"{'all':28s} {runs:5d} {stalls:7d}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
