"""Panel latency in the browser: slider release -> new image on the page.

Starts JupyterLab (default settings, kernel comms over subshells) and Debian's chromium as
the browser tests do (``tests/browser/labharness.py``), runs notebooks 01, 02, 03, 04, 06,
07 and 09 in quick mode and moves their thresholds (eta, nu, rank tolerance, s threshold),
segment limits (tau2 on the rocket flight of 03, the boundaries of 07) and trajectory,
latitude, duration and outage-length sliders ten times each by keyboard, measuring in the page
from the key press to the ``load`` of the first and of the last new image. Prints the
median and max per control beside the panel's own update time in the kernel and the goals
(thresholds: 100 ms; segments, trajectory, latitude, duration: 300 ms) and
the load average. ``benchmarks/bench_panels.py`` times every control without a browser.

Usage: ``python benchmarks/bench_browser.py [--repeats N]`` (needs the ``[browser]`` extra
and /usr/bin/chromium; ``make test-browser`` prints the same table from its own moves).
Not a timed case of ``benchmarks/run.py``: :func:`cases` is empty.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
MOVES = {
    "01_trajectory_synthesis": ("spin [Hz]", "burnout [s]"),
    "02_observability_matrix": ("log10 rank rtol", "inspected time [s]"),
    "03_excitability": ("η", "τ2 [s]"),
    "04_sensability": ("ν",),
    "06_stationary_alignment": ("latitude [deg]", "duration [min]"),
    "07_assess_flight": ("η (excitability)", "ν (sensability)", "boundaries [s]"),
    "09_plan_mission": ("ν (sensability)", "sensible if s ≥", "outage length [s]"),
}


def cases() -> list:
    """No case for ``benchmarks/run.py``: this benchmark drives a browser (run it alone)."""
    return []


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=10)
    args = parser.parse_args(argv)
    sys.path.insert(0, str(HERE.parent / "tests" / "browser"))
    from labharness import (
        LabServer,
        NotebookPage,
        latency_table,
        launch_chromium,
        quick_copies,
    )
    from playwright.sync_api import sync_playwright

    moves = []
    with tempfile.TemporaryDirectory(prefix="navlib-bench-browser-") as tmp:
        root = Path(tmp)
        quick_copies(root, list(MOVES))
        server = LabServer(root).start()
        try:
            with sync_playwright() as playwright:
                context = launch_chromium(playwright, root / "profile")
                for name, controls in MOVES.items():
                    nb = NotebookPage.open(context, server, name)
                    seconds = nb.run_all()
                    nb.scroll_to_widgets()
                    print(f"{name}: ran in {seconds:.0f} s", file=sys.stderr, flush=True)
                    first = nb.panel_state(0)
                    for control in nb.controls(0):
                        if control["description"] not in controls:
                            continue
                        for k in range(args.repeats):
                            move = nb.move(0, control, "keyboard", first=first,
                                           undo=k % 2 == 1)
                            if move is None:  # disabled
                                print(f"  {control['description']}: cannot move",
                                      file=sys.stderr)
                                break
                            moves.append(move)
                            if move.failed():
                                print(f"  {control['description']}: {move.outcome}",
                                      file=sys.stderr)
                    nb.page.close()
                context.close()
        finally:
            server.stop()
    print(latency_table(moves))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
