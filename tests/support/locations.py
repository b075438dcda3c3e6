"""Where the tests find the repository and the shared public flight logs beside it.

The shared logs live in ``../shared/data`` relative to the repository root (the checkout's
sibling folder ``shared``), wherever the clone is; ``NAVLIB_SHARED_DIR`` names another
``shared`` folder (a worktree placed elsewhere). Tests reach them only through
:func:`shared_file` and :func:`shared_dir`, which skip with a reason when they are absent.
"""

import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
"""The repository's root (the folder holding ``navlib/``, ``data/``, ``notebooks/``)."""

SHARED_DATA = Path(os.environ.get("NAVLIB_SHARED_DIR") or REPO.parent / "shared") / "data"
"""The public flight logs: ``../shared/data`` beside the checkout, or
``$NAVLIB_SHARED_DIR/data``."""


def shared_dir(*parts: str) -> Path:
    """A folder of :data:`SHARED_DATA` (``shared_dir("altos")``); skips the calling test with
    a reason when it is absent."""
    path = SHARED_DATA.joinpath(*parts)
    if not path.is_dir():
        pytest.skip(f"shared flight logs not found: {path} (../shared/data beside the "
                    "checkout, or set NAVLIB_SHARED_DIR)")
    return path


def shared_file(*parts: str) -> Path:
    """A file of :data:`SHARED_DATA` (``shared_file("px4", "sample_log_small.ulg")``); skips
    the calling test with a reason when it is absent."""
    path = SHARED_DATA.joinpath(*parts)
    if not path.is_file():
        pytest.skip(f"shared flight log not found: {path} (../shared/data beside the "
                    "checkout, or set NAVLIB_SHARED_DIR)")
    return path
