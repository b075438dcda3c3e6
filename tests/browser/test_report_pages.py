"""Report pages as a reader sees them, in the same headless Chromium (issues 13 and 34).

Pages made by ``python -m navlib report --quick`` (00_claims, 03_excitability,
07_assess_flight and index.html) and one flight page of ``python -m navlib assess``, opened
with every network request refused:

* the panels' last figures are on the page (complete, not blank), with no "model not found"
  / "Error displaying widget" and no widget script requested (issue 13);
* no code cell and no input or output prompt is shown (the executed notebooks keep them);
* every image is drawn at its own aspect ratio (rendered width / height within 3 % of the
  PNG's), none wider than the window;
* text and tables are readable at 100 % zoom (computed font size at least 13 px);
* index.html says, for each page, what it answers and shows a headline;
* the flight page's title is the log's file name, not its path;
* no internal timing (a panel's update milliseconds, a notebook's run time) is shown;
* 00_claims leads with its claims: its first table of claims (a ``claim_id`` column) starts
  within the first screen, and a flight page with its "how well" table of states and units
  (the segment verdicts, ``excitable``, after it).

Each page is screenshot (full page) into the test's temporary folder; the path is printed.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from labharness import INSTRUMENT_JS, PANEL_JS, REPO, WIDGET_ERRORS

pytestmark = pytest.mark.browser

REPORTED = ("00_claims", "03_excitability", "07_assess_flight")
PANEL_PAGES = ("03_excitability", "07_assess_flight")
WIDGET_SCRIPTS = ("jupyter-widgets", "html-manager", "embed-amd", "unpkg")
VIEWPORT = {"width": 1400, "height": 1000}
ASPECT_TOLERANCE = 0.03
MIN_FONT_PX = 13.0
SAMPLE_LOG = "data/sample_flight/imu.csv,data/sample_flight/gnss.csv"

IMAGES_JS = """
() => [...document.images].filter((img) => img.offsetParent !== null).map((img) => {
  const box = img.getBoundingClientRect();
  return {w: img.naturalWidth, h: img.naturalHeight, rw: box.width, rh: box.height,
          alt: img.alt || img.className || img.src.slice(0, 40)};
})
"""
CODE_JS = """
() => document.querySelectorAll(
  ".jp-CodeCell .jp-InputArea, .jp-InputPrompt, .jp-OutputPrompt, .jp-Cell-inputWrapper " +
  ".jp-CodeMirrorEditor, .input_area, .prompt").length
"""
FONTS_JS = """
() => [...document.querySelectorAll("p, li, td, th")].filter((e) => e.offsetParent !== null
        && e.textContent.trim()).map((e) => parseFloat(getComputedStyle(e).fontSize))
"""
FIRST_TABLE_JS = """
(column) => {
  const heads = (table) => [...table.querySelectorAll("th")].map((th) => th.textContent.trim());
  const table = [...document.querySelectorAll("table")].find(
    (t) => !column || heads(t).includes(column));
  if (!table) return null;
  return {top: table.getBoundingClientRect().top + window.scrollY, heads: heads(table)};
}
"""


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    """A quick report of :data:`REPORTED`; ``NAVLIB_TEST_REPORT=DIR`` reuses the report in
    DIR instead (e.g. one ``python -m navlib report --quick`` made), the pages being
    checked are the same."""
    reuse = os.environ.get("NAVLIB_TEST_REPORT")
    if reuse:
        return Path(reuse)
    out = tmp_path_factory.mktemp("report")
    subprocess.run([sys.executable, "-m", "navlib", "report", "--quick", "--only", *REPORTED,
                    "--output", str(out)], cwd=REPO, check=True, timeout=1800)
    return out


@pytest.fixture(scope="module")
def assessment(tmp_path_factory):
    """The folder ``python -m navlib assess`` writes for the shipped sample flight when no
    --output is given (./assessments of the working folder)."""
    cwd = tmp_path_factory.mktemp("assess")
    log = ",".join(str(REPO / part) for part in SAMPLE_LOG.split(","))
    subprocess.run([sys.executable, "-m", "navlib", "assess", log], cwd=cwd, check=True,
                   timeout=900, env={**os.environ, "NAVLIB_SCHEDULER": "synchronous"})
    pages = sorted((cwd / "assessments").glob("*.html"))
    assert len(pages) == 1, pages
    return pages[0]


def _open(browser, path, shots):
    page = browser.new_page()
    page.set_viewport_size(VIEWPORT)
    refused, console = [], []
    page.route("**/*", lambda route: route.continue_() if route.request.url.startswith(
        "file:") else (refused.append(route.request.url), route.abort())[-1])
    page.on("console", lambda msg: msg.type == "error" and console.append(msg.text))
    page.add_init_script(INSTRUMENT_JS)
    page.goto(path.as_uri(), wait_until="load")
    page.wait_for_timeout(500)
    shot = shots / f"{path.stem}.png"
    page.screenshot(path=str(shot), full_page=True)
    print(f"\n{path.name}: screenshot {shot}")
    return page, refused, console


def _check_reading(page, name):
    """No code, images at their own aspect ratio and within the window, readable fonts."""
    assert page.evaluate(CODE_JS) == 0, f"{name}: code cells or prompts on the page"
    images = page.evaluate(IMAGES_JS)
    for img in images:
        assert img["w"] > 0 and img["rh"] > 0, (name, img)
        natural, rendered = img["w"] / img["h"], img["rw"] / img["rh"]
        assert abs(rendered / natural - 1.0) < ASPECT_TOLERANCE, (
            f"{name}: image {img['alt']} drawn at aspect {rendered:.3f}, its own is "
            f"{natural:.3f}")
        assert img["rw"] <= VIEWPORT["width"], (name, img)
    fonts = page.evaluate(FONTS_JS)
    assert fonts, f"{name}: no text found"
    small = sorted(f for f in fonts if f < MIN_FONT_PX)
    assert not small, f"{name}: {len(small)} text elements below {MIN_FONT_PX} px: {small[:5]}"
    return images


@pytest.fixture(scope="module")
def shots(tmp_path_factory):
    return tmp_path_factory.mktemp("screenshots")


@pytest.mark.parametrize("name", REPORTED)
def test_report_page_reads_as_results(report, browser, shots, name):
    page, _, _ = _open(browser, report / f"{name}.html", shots)
    try:
        images = _check_reading(page, name)
        assert images, f"{name}: no figure on the page"
        assert "/" not in page.title(), page.title()
    finally:
        page.close()


TIMING_TEXT = re.compile(r"update \d+ ms \(compute|\(first call; cached afterwards\)"
                         r"|[\d.]+ s, of which|claims in \d+ s\b|\bplan_s\b")
"""Internal timings the notebooks and panels print (kept in the executed notebooks)."""


@pytest.mark.parametrize("name", REPORTED)
def test_report_page_shows_no_internal_timing(report, browser, shots, name):
    page, _, _ = _open(browser, report / f"{name}.html", shots)
    try:
        text = page.evaluate("() => document.body.innerText")
        assert not TIMING_TEXT.search(text), TIMING_TEXT.search(text).group(0)
    finally:
        page.close()


def test_claims_table_leads_the_claims_page(report, browser, shots):
    page, _, _ = _open(browser, report / "00_claims.html", shots)
    try:
        claims = page.evaluate(FIRST_TABLE_JS, "claim_id")
        assert claims is not None, "00_claims: no table of claims (a claim_id column)"
        assert claims["top"] < VIEWPORT["height"], (
            f"00_claims: the first table of claims starts {claims['top']:.0f} px down, "
            f"below the first screen ({VIEWPORT['height']} px)")
    finally:
        page.close()


def test_index_says_what_each_page_answers(report, browser, shots):
    page, _, _ = _open(browser, report / "index.html", shots)
    try:
        _check_reading(page, "index.html")
        sections = page.evaluate("""() => [...document.querySelectorAll("section.page")].map(
            (s) => ({id: s.id, question: s.querySelector(".question")?.textContent || "",
                     headline: s.querySelector(".headline")?.textContent || "",
                     link: s.querySelector("h2 a")?.getAttribute("href") || ""}))""")
        assert set(REPORTED) <= {s["id"] for s in sections}
        for s in sections:
            assert s["link"] == f"{s['id']}.html", s
            assert len(s["question"]) > 40, s
            assert s["headline"].strip(), f"{s['id']}: no headline on the index"
        by_id = {s["id"]: s for s in sections}
        assert "claims" in by_id["00_claims"]["headline"]
        assert "excitable" in by_id["07_assess_flight"]["headline"]  # the segment verdicts
    finally:
        page.close()


def test_flight_page_reads_as_results(assessment, browser, shots):
    page, _, _ = _open(browser, assessment, shots)
    try:
        images = _check_reading(page, assessment.name)
        assert len(images) >= 4
        assert page.title() == "imu.csv + gnss.csv"
        first = page.evaluate(FIRST_TABLE_JS, "")
        assert first is not None and first["top"] < VIEWPORT["height"], first
        assert first["heads"][:3] == ["state", "unit", "start"], first  # how well, in units
        verdicts = page.evaluate(FIRST_TABLE_JS, "excitable")  # the segment verdicts follow
        assert verdicts is not None and verdicts["top"] > first["top"], verdicts
    finally:
        page.close()


@pytest.mark.parametrize("name", PANEL_PAGES)
def test_report_page_shows_the_panels_offline(report, browser, shots, name):
    page, refused, console = _open(browser, report / f"{name}.html", shots)
    try:
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
