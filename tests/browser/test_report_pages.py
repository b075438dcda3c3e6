"""The HTML report keeps what the panels showed (issue 13): pages made by
``python -m navlib report --quick`` opened in the same headless Chromium with every network
request refused. The panels' last figures must be on the page (complete, not blank), with
no "model not found" / "Error displaying widget" and no widget script requested.
"""

from __future__ import annotations

import subprocess
import sys

import pytest
from labharness import INSTRUMENT_JS, PANEL_JS, REPO, WIDGET_ERRORS

pytestmark = pytest.mark.browser

REPORTED = ("03_excitability", "07_assess_flight")
WIDGET_SCRIPTS = ("jupyter-widgets", "html-manager", "embed-amd", "unpkg")


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    out = tmp_path_factory.mktemp("report")
    subprocess.run([sys.executable, "-m", "navlib", "report", "--quick", "--only", *REPORTED,
                    "--output", str(out)], cwd=REPO, check=True, timeout=1800)
    return out


@pytest.mark.parametrize("name", REPORTED)
def test_report_page_shows_the_panels_offline(report, browser, name):
    page = browser.new_page()
    refused, console = [], []
    page.route("**/*", lambda route: route.continue_() if route.request.url.startswith(
        "file:") else (refused.append(route.request.url), route.abort())[-1])
    page.on("console", lambda msg: msg.type == "error" and console.append(msg.text))
    page.add_init_script(INSTRUMENT_JS)
    try:
        page.goto((report / f"{name}.html").as_uri(), wait_until="load")
        page.wait_for_timeout(500)
        text = page.evaluate("() => document.body.textContent")
        assert [e for e in WIDGET_ERRORS if e in text] == []
        assert page.evaluate("document.querySelectorAll('.navlib-panel').length") >= 1
        state = page.evaluate(PANEL_JS, [0, 0])
        shown = [img for img in state["images"] if img["visible"]]
        assert shown, f"{name}: no panel figure on the report page"
        for img in shown:
            assert img["complete"] and img["w"] > 100 and img["ink"] > 0.002, img["name"]
        assert not [u for u in refused if any(s in u for s in WIDGET_SCRIPTS)], refused
        # what else the page asked the network for (nbconvert's require.js / MathJax CDN)
        # is printed, not failed: the panels do not need it
        print(f"\n{name}: {len(shown)} panel figures shown offline; refused requests: "
              f"{sorted(set(refused)) or 'none'}; console errors: {len(console)}")
    finally:
        page.close()
