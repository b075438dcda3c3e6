"""Search the España assumption space jointly for the set reproducing the most claims at once.

Runs :func:`navlib.studies.rocket.assumption_search` (X1-X7 and S1-S8 at every point of the
declared assumption set, through :func:`navlib.sweep.sweep`, so ``--scheduler`` may be a Dask
address) and writes ``data/claims_search_rocket.csv`` with the command line and the navlib
version in its header. ``tests/test_claims_search.py`` recomputes a random sample of its
points; notebook 00 reads it::

    python scripts/claims_search.py [--scheduler synchronous|processes|tcp://host:8786]
"""

from __future__ import annotations

import argparse
import shlex
import sys
import time
from pathlib import Path

DATA = Path(__file__).resolve().parents[1] / "data"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scheduler", default="synchronous",
                        help="navlib.sweep scheduler (default synchronous)")
    args = parser.parse_args(argv)
    import navlib
    from navlib.studies import rocket

    start = time.perf_counter()
    frame = rocket.assumption_search(scheduler=args.scheduler)
    command = "python scripts/claims_search.py " + " ".join(
        shlex.quote(a) for a in (sys.argv[1:] if argv is None else argv))
    path = DATA / rocket.SEARCH_FILE
    with path.open("w", encoding="utf-8", newline="") as handle:
        handle.write(f"# command: {command.strip()}\n# navlib: {navlib.__version__}\n")
        frame.to_csv(handle, index=False)
    print(f"wrote {len(frame)} points to {path} ({time.perf_counter() - start:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
