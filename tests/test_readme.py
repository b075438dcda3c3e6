"""The README's promises: short, its links resolve, the test command is the one ``.ci/run``
calls, and its copy-paste examples of "Assess your flight" and "Plan a mission" run as
written (issue 34).

Each example runs in a fresh working folder (so ``assess`` and ``plan`` write their default
``./assessments`` and ``./plans`` there), with its relative paths resolved against the
repository's root, where the README says to run them; ``NAVLIB_SCHEDULER=synchronous``
keeps ``assess`` from starting a local Dask cluster (the same computation in process).
Examples using the public logs in ``../shared/data`` are skipped when that folder is absent.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys

import pandas as pd
import pytest
from support.locations import REPO

from navlib.io.logs import LOG_KINDS

README = REPO / "README.md"
TEXT = README.read_text(encoding="utf-8")
MAX_LINES = 160
PYTHON = ".venv/bin/python"


def _section(title: str) -> str:
    match = re.search(rf"^## {re.escape(title)}\n(.*?)(?=^## |\Z)", TEXT, re.S | re.M)
    assert match, f"README: no section '## {title}'"
    return match.group(1)


def _commands(title: str) -> list[str]:
    blocks = re.findall(r"```bash\n(.*?)```", _section(title), re.S)
    return [line.strip() for block in blocks for line in block.splitlines()
            if line.strip().startswith(f"{PYTHON} -m navlib ")]


ASSESS = _commands("Assess your flight")
PLAN = _commands("Plan a mission")


def test_readme_is_short_and_its_links_resolve():
    assert len(TEXT.splitlines()) <= MAX_LINES
    links = re.findall(r"\]\(([^)#]+)\)", TEXT)
    missing = [link for link in links if not link.startswith("http")
               and not (REPO / link).exists()]
    assert links and not missing, missing
    for doc in sorted((REPO / "docs").glob("*.md")):
        assert f"docs/{doc.name}" in TEXT, f"README does not link {doc.name}"


def test_readme_test_command_is_the_ci_one():
    assert re.search(r"^make test\b", _section("Two commands"), re.M)
    assert re.search(r"^make test$", (REPO / ".ci" / "run").read_text(encoding="utf-8"),
                     re.M)


def test_readme_has_one_assess_example_per_log_kind():
    kinds = {".ulg": 0, ".bin": 0, "altos": 0, "pair": 0}
    for command in ASSESS:
        log = shlex.split(command)[4]
        if "," in log:
            kinds["pair"] += 1
        elif log.endswith((".ulg", ".bin")):
            kinds[log[-4:]] += 1
        elif "altos" in log:
            kinds["altos"] += 1
    assert kinds == {".ulg": 1, ".bin": 1, "altos": 1, "pair": 1}, ASSESS
    assert len(PLAN) >= 1


def _resolved(word: str) -> str:
    """A path argument (or comma-joined pair) made absolute against the repository root;
    other words unchanged."""
    parts = word.split(",")
    if all("/" in p for p in parts):
        return ",".join(str((REPO / p).resolve()) for p in parts)
    return word


def _run(command: str, cwd) -> None:
    words = shlex.split(command)
    missing = [w for w in words if w.startswith("../shared") for p in w.split(",")
               if not (REPO / p).exists()]
    if missing:
        pytest.skip(f"public logs not beside the repository: {missing[0]}")
    argv = [sys.executable, *(_resolved(w) for w in words[1:])]
    done = subprocess.run(argv, cwd=cwd, capture_output=True, text=True, timeout=900,
                          env={**os.environ, "NAVLIB_SCHEDULER": "synchronous"})
    assert done.returncode == 0, f"{command}\n{done.stderr[-2000:]}"


@pytest.mark.parametrize("command", ASSESS)
def test_readme_assess_example_runs(command, tmp_path):
    _run(command, tmp_path)
    summary = pd.read_csv(tmp_path / "assessments" / "summary.csv")
    assert list(summary.status) == ["ok"], summary.error.tolist()
    assert (tmp_path / "assessments" / summary.page[0]).exists()


def test_readme_python_example_runs():
    """The Python example of "Assess your flight", run from the repository's root."""
    blocks = re.findall(r"```python\n(.*?)```", _section("Assess your flight"), re.S)
    assert len(blocks) == 1
    script = blocks[0] + "\nassert set(result.summary().columns) >= {'phase', 'excitable'}\n"
    done = subprocess.run([sys.executable, "-c", script], cwd=REPO, capture_output=True,
                          text=True, timeout=900)
    assert done.returncode == 0, done.stderr[-2000:]


@pytest.mark.parametrize("command", PLAN)
def test_readme_plan_example_runs(command, tmp_path):
    _run(command, tmp_path)
    summary = pd.read_csv(tmp_path / "plans" / "summary.csv")
    assert list(summary.status) == ["ok"], summary.error.tolist()


def test_assess_help_lists_every_log_form():
    """Every kind navlib.io.parse_log tells apart is in ``assess --help`` (a new kind fails
    here until the help names it), and so is the default output folder."""
    forms = {"ulog": ".ulg", "dataflash": ".bin", "altos": "AltOS", "csv": "imu.csv,gnss.csv",
             "firm": "FIRM", "cats": "CATS"}
    assert set(LOG_KINDS) == set(forms)
    done = subprocess.run([sys.executable, "-m", "navlib", "assess", "--help"],
                          capture_output=True, text=True, check=True, timeout=120)
    for text in (*forms.values(), "./assessments"):
        assert text in done.stdout, text
