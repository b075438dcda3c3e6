"""Shared pytest setup (keep it small).

Figures built in tests render off-screen (Agg). Notebook kernels are unaffected: the report
runner starts them with the inline backend whatever MPLBACKEND says.

The on-disk cache (navlib.cache) is off for the whole run, kernels and subprocesses
included (they inherit the environment), so no test depends on entries left by an earlier
run; tests/test_cache.py turns it on in a folder of its own.
"""

import os
from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")
os.environ["NAVLIB_NO_CACHE"] = "1"

PX4_DIR = Path(
    os.environ.get("NAVLIB_PX4_DIR")
    or Path(__file__).resolve().parents[2] / "shared" / "data" / "px4"
)
"""The public PX4 sample logs: ``../shared/data/px4`` beside the checkout, or NAVLIB_PX4_DIR."""


@pytest.fixture(scope="session")
def px4_log_path():
    """Locate a PX4 sample log by file name; skip cleanly when it is absent."""

    def locate(name: str) -> Path:
        path = PX4_DIR / name
        if not path.is_file():
            pytest.skip(f"PX4 sample log not found: {path} (set NAVLIB_PX4_DIR)")
        return path

    return locate
