"""Run every benchmark module (``benchmarks/bench_*.py``) and print one table.

Usage: ``python benchmarks/run.py [substring ...]`` (only cases whose name contains one of
the substrings). Ratio = time / goal; below 1 meets the goal from the issue.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pandas as pd

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from _harness import time_case  # noqa: E402


def load_cases():
    for path in sorted(HERE.glob("bench_*.py")):
        spec = importlib.util.spec_from_file_location(path.stem, path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        yield from module.cases()


def main(argv: list[str]) -> int:
    rows = []
    for case in load_cases():
        if argv and not any(s in case.name for s in argv):
            continue
        print(f"running {case.name} ...", file=sys.stderr, flush=True)
        rows.append(time_case(case))
    if not rows:
        print("no benchmark matched", file=sys.stderr)
        return 1
    table = pd.DataFrame(rows)
    with pd.option_context("display.width", 200, "display.max_columns", 20,
                           "display.float_format", "{:.4g}".format):
        print(table.to_string(index=False))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
