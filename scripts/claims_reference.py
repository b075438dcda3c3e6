"""Compare :func:`navlib.studies.all_claims` with its stored reference (or write one).

The reference ``tests/regression/data/claims_reference.csv`` holds, per claim of the studies
below, the strings the notebooks show: ``claim_id, ours, verdict, basis, robustness, checks``
(robustness as ``repr`` of the float). It was written at the commit before the robustness
sets shared their builds (``--write``) and rewritten when a declared set grew (issue 36: the
lateral level in the covariance set, the heading prior in SSAC's, robustness only); a
full-mode comparison takes about a minute, too long for the test suite, which compares
quick mode (tests/regression/test_claims_golden.py)
and checks the shared-build paths against the unshared ones on reduced sets
(tests/studies/claims/test_claims_sharing.py)::

    python scripts/claims_reference.py            # compare, exit 1 on any difference
    python scripts/claims_reference.py --write    # (re)write the reference
    python scripts/claims_reference.py --quick    # quick mode against its own reference
"""

from __future__ import annotations

import argparse
import csv
import sys
import time
from pathlib import Path

DATA = Path(__file__).resolve().parents[1] / "tests" / "regression" / "data"
STUDIES = ("rocket", "covariance", "ssac")
"""The studies whose robustness sets share builds (one trajectory and model per robustness set)."""
FIELDS = ("claim_id", "ours", "verdict", "basis", "robustness", "checks")


def reference_path(quick: bool) -> Path:
    """The stored table of full (or quick) mode."""
    return DATA / ("claims_reference_quick.csv" if quick else "claims_reference.csv")


def current_rows(quick: bool, studies=STUDIES) -> list[dict]:
    """The :data:`FIELDS` of every claim of ``studies`` as strings."""
    from navlib.studies import all_claims

    table = all_claims(quick=quick, only=list(studies))
    return [{"claim_id": r.claim_id, "ours": r.ours, "verdict": r.verdict, "basis": r.basis,
             "robustness": repr(float(r.robustness)), "checks": r.checks}
            for r in table.itertuples()]


def read_rows(path: Path) -> list[dict]:
    with path.open(newline="", encoding="utf-8") as handle:
        return list(csv.DictReader(handle))


def write_rows(path: Path, rows: list[dict]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.DictWriter(handle, fieldnames=FIELDS)
        writer.writeheader()
        writer.writerows(rows)


def differences(reference: list[dict], current: list[dict]) -> list[str]:
    """One line per claim or field that differs: words exactly, numbers to one unit of their
    last printed digit (``tests/regression/golden.py``; empty: the same tables)."""
    sys.path.insert(0, str(DATA.parent))
    from golden import rows_differences

    return rows_differences(current, reference, key="claim_id")


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help="write the reference")
    parser.add_argument("--quick", action="store_true", help="quick mode")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    rows = current_rows(args.quick)
    elapsed = time.perf_counter() - start
    path = reference_path(args.quick)
    if args.write:
        write_rows(path, rows)
        print(f"wrote {len(rows)} claims to {path} ({elapsed:.1f} s)")
        return 0
    diff = differences(read_rows(path), rows)
    print("\n".join(diff) if diff else f"{len(rows)} claims identical to {path.name} "
          f"({elapsed:.1f} s)")
    return 1 if diff else 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
