"""Shared pytest setup (keep it small).

Figures built in tests render off-screen (Agg). Notebook kernels are unaffected: the report
runner starts them with the inline backend whatever MPLBACKEND says.

The on-disk cache (navlib.cache) is off for the whole run, kernels and subprocesses
included (they inherit the environment), so no test depends on entries left by an earlier
run; tests/test_cache.py turns it on in a folder of its own.
"""

import os

import matplotlib
import pytest
from support.locations import shared_file

matplotlib.use("Agg")
os.environ["NAVLIB_NO_CACHE"] = "1"


@pytest.fixture(scope="session")
def px4_log_path():
    """Locate a public PX4 sample log (``../shared/data/px4``, :mod:`support.locations`) by
    file name; skip with a reason when it is absent."""
    return lambda name: shared_file("px4", name)
