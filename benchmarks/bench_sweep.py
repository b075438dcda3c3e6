"""Scaling of navlib.sweep: a 200-point sweep on 1 and 2 local worker processes.

Run it directly (``python benchmarks/bench_sweep.py [--points N]``); it starts its own
clusters, so it is not one of the timed cases of ``benchmarks/run.py``. Goal:
speed-up >= 1.8 on 2 cores. It prints, per configuration: wall time of the sweep (from
submission to the last result; cluster start-up excluded and shown apart), the speed-up
against 1 worker, time inside the evaluations and the shared-input builds, and the overhead
per task ``(workers x wall - evaluation - builds) / tasks``; then the round trip of an empty
task (200 no-op points, one per task). The machine load (``os.getloadavg``) is printed too,
and ``eval_cpu_share`` (CPU time / wall time inside the evaluations): on a shared machine
the workers get only part of a core each, and the speed-up is bounded by that, not by Dask.

The sweep: the ``nees`` evaluation (21-state rocket model, 20-run linear Monte Carlo per
point) over 2 spin rates x 5 GNSS sigmas x N/10 seeds; the two spin rates are the two
shared inputs (trajectory + discretisation, about 3 s each), built once each as tasks.
"""

from __future__ import annotations

import argparse
import logging
import os
import time

import pandas as pd


def _noop(i):
    return {}


def _grid(points: int) -> dict:
    seeds = max(1, points // 10)
    return {"spin_hz": [1.0, 2.0], "gnss_sigma_m": [2.0, 5.0, 10.0, 20.0, 50.0],
            "seed": list(range(seeds))}


def _row(label, frame, start_s, base_wall=None) -> dict:
    s = frame.attrs["sweep"]
    overhead = (s["n_workers"] * s["wall_s"] - s["compute_s"] - s["prepare_s"]) / s["n_tasks"]
    return {"run": label, "workers": s["n_workers"], "points": s["n_points"],
            "tasks": s["n_tasks"], "startup_s": start_s, "wall_s": s["wall_s"],
            "speed_up": (base_wall / s["wall_s"]) if base_wall else 1.0,
            "eval_s": s["compute_s"], "eval_cpu_share": s["compute_cpu_s"] / s["compute_s"],
            "build_s": s["prepare_s"],
            "overhead_ms_per_task": 1e3 * overhead}


def main(argv=None) -> int:
    from distributed import Client, LocalCluster

    import navlib.studies  # noqa: F401 - registers the named evaluation "nees"
    from navlib.sweep import sweep

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=200)
    args = parser.parse_args(argv)
    grid = _grid(args.points)
    print(f"load before: {os.getloadavg()}, cores: {os.cpu_count()}")
    rows, frames = [], {}
    t0 = time.perf_counter()
    frames["serial"] = sweep(grid, "nees", scheduler="synchronous", progress=False)
    rows.append(_row("in-process (synchronous)", frames["serial"], 0.0))
    base = None
    for workers in (1, 2):
        t0 = time.perf_counter()
        with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                          dashboard_address=":0", silence_logs=logging.ERROR) as cluster, \
                Client(cluster) as client:
            client.run(lambda: __import__("navlib.studies"))  # imports are start-up, not work
            startup = time.perf_counter() - t0
            frame = sweep(grid, "nees", scheduler=client, progress=False)
            frames[workers] = frame
            base = base or frame.attrs["sweep"]["wall_s"]
            rows.append(_row(f"{workers} worker process(es)", frame, startup, base))
            if workers == 1:
                empty = sweep({"i": list(range(200))}, _noop, scheduler=client,
                              batch_size=1, progress=False)
                trip = empty.attrs["sweep"]["wall_s"] / 200
    pd.testing.assert_frame_equal(frames["serial"], frames[1], check_exact=True)
    pd.testing.assert_frame_equal(frames["serial"], frames[2], check_exact=True)
    table = pd.DataFrame(rows)
    with pd.option_context("display.width", 200, "display.max_columns", 20,
                           "display.float_format", "{:.2f}".format):
        print(table.to_string(index=False))
    print(f"empty-task round trip (1 worker, 200 tasks of one no-op point): "
          f"{1e3 * trip:.1f} ms per task")
    print("results identical in-process, on 1 and on 2 workers: yes")
    print(f"load after: {os.getloadavg()}")
    return 0


def cases():
    """No timed case for ``benchmarks/run.py``: the scaling table needs its own clusters."""
    return []


if __name__ == "__main__":
    raise SystemExit(main())
