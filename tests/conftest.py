"""Shared pytest setup (keep it small).

Figures built in tests render off-screen (Agg). Notebook kernels are unaffected: the report
runner starts them with the inline backend whatever MPLBACKEND says.
"""

from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")

REPO_ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="session")
def repo_root() -> Path:
    """The source checkout: ``notebooks/``, ``data/``, ``reports/`` live here."""
    return REPO_ROOT
