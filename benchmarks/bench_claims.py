"""Per-study cost of :func:`navlib.studies.all_claims` in full mode (notebook 00).

Each case runs ``all_claims(only=[study])`` (baseline claims and the study's declared
robustness set) in a fresh subprocess, so no cache of another case or run helps it; the
time is measured inside the subprocess after the imports. ``cpu_s`` is the subprocess's CPU
time over the same span: on the shared two-core machine it moves less with the load than
the wall time. Goal: the notebook-00 share of the < 90 s report (the whole notebook, every
study together, gets 7.5 s; see ``bench_notebooks.py``).

Usage: ``python benchmarks/run.py claims`` (all) or ``python benchmarks/run.py
claims/covariance`` (one study).
"""

from __future__ import annotations

import json
import subprocess
import sys

from _harness import Case

STUDIES = ("rocket", "covariance", "ssac")
"""The studies whose robustness sets share builds across their points."""
GOAL_S = 7.5
_CHILD = """
import json, time
from navlib.studies import all_claims
wall, cpu = time.perf_counter(), time.process_time()
all_claims(only=[{study!r}])
print(json.dumps([time.perf_counter() - wall, time.process_time() - cpu]))
"""


def run_study(study: str, cpu: dict) -> None:
    """``all_claims(only=[study])`` in a subprocess; its CPU seconds go to ``cpu``."""
    out = subprocess.run([sys.executable, "-c", _CHILD.format(study=study)], check=True,
                         capture_output=True, text=True)
    wall, cpu[study] = json.loads(out.stdout.strip().splitlines()[-1])
    cpu[f"{study}/wall"] = wall


def cases() -> list[Case]:
    cpu: dict = {}
    return [Case(f"claims/{study}", "full mode, baseline + robustness set",
                 lambda s=study: run_study(s, cpu), GOAL_S, repeat=1, warmup=False,
                 extra=lambda _t, s=study: {"in_process_s": cpu.get(f"{s}/wall"),
                                            "cpu_s": cpu.get(s)},
                 notes="goal: notebook 00's whole share of the 90 s report")
            for study in STUDIES]
