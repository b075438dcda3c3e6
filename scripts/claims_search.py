"""Search the papers' assumption spaces jointly for the sets reproducing the most claims at once.

Runs :func:`navlib.studies.claims.run_search` for each registered search space (a paper's
claims at every point of its declared assumption set, through :func:`navlib.sweep.sweep`, so
``--scheduler`` may be a Dask address) and writes its ``data/`` file (e.g.
``data/claims_search_rocket.csv``) with the command line and the navlib version in its
header. ``tests/studies/claims/test_claims_search.py`` recomputes a random sample of each
stored search's points; notebook 00 reads them::

    python scripts/claims_search.py [--study NAME ...] [--scheduler synchronous|processes|tcp://host:8786]
"""

from __future__ import annotations

import argparse
import shlex
import sys
import time
from pathlib import Path

DATA = Path(__file__).resolve().parents[1] / "data"


def main(argv=None) -> int:
    import navlib
    import navlib.studies
    from navlib.studies import claims

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--study", action="append", choices=list(claims.SEARCH_SPACES),
                        help="search only this space (repeatable; default: every one)")
    parser.add_argument("--scheduler", default="synchronous",
                        help="navlib.sweep scheduler (default synchronous)")
    args = parser.parse_args(argv)
    command = "python scripts/claims_search.py " + " ".join(
        shlex.quote(a) for a in (sys.argv[1:] if argv is None else argv))
    for name in args.study or list(claims.SEARCH_SPACES):
        start = time.perf_counter()
        frame = claims.run_search(name, scheduler=args.scheduler)
        path = DATA / claims.search_space(name).file
        with path.open("w", encoding="utf-8", newline="") as handle:
            handle.write(f"# command: {command.strip()}\n# navlib: {navlib.__version__}\n")
            frame.to_csv(handle, index=False)
        print(f"{name}: wrote {len(frame)} points to {path} "
              f"({time.perf_counter() - start:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
