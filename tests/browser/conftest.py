"""Fixtures of the browser tests: one JupyterLab server and one headless Chromium per session.

Run with ``make test-browser`` (installs the ``[browser]`` extra, and Debian's chromium with
apt-get when it is missing). ``make test`` deselects the ``browser`` marker.
"""

from __future__ import annotations

import pytest
from labharness import MOVES, LabServer, latency_table, launch_chromium, quick_copies


@pytest.fixture(scope="session")
def lab(tmp_path_factory):
    """A JupyterLab server on 127.0.0.1 serving quick copies of the panel notebooks."""
    root = tmp_path_factory.mktemp("lab")
    quick_copies(root)
    server = LabServer(root).start()
    yield server
    server.stop()


@pytest.fixture(scope="session")
def browser(tmp_path_factory):
    """A persistent Chromium context (fresh profile) driven by Playwright."""
    sync_api = pytest.importorskip("playwright.sync_api")
    with sync_api.sync_playwright() as playwright:
        context = launch_chromium(playwright, tmp_path_factory.mktemp("chromium-profile"))
        yield context
        context.close()


def pytest_terminal_summary(terminalreporter):
    """Print the latency table of the moves (a benchmark, not an assertion)."""
    if not MOVES:
        return
    terminalreporter.write_sep("=", "widget latency in the browser (slider release -> image)")
    terminalreporter.write_line(latency_table(MOVES))
