"""Where the tests find the repository and the shared public flight logs beside it."""

from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
"""The repository's root (the folder holding ``navlib/``, ``data/``, ``notebooks/``)."""
