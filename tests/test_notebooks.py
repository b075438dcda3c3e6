"""Smoke tests for every notebook in notebooks/ (picked up automatically as they are added).

The executing test is marked ``notebook`` (deselect with ``-m "not notebook"``); the checks
on the committed files (clean, parameters cell, report naming) read JSON only and stay unmarked
so they always run. Each execution goes through the report runner in quick mode into the
test's own tmp folder, so ``pytest -n 2`` is safe.
"""

import ast
import json
import logging
from pathlib import Path

import nbformat
import pytest

from navlib import reports

NOTEBOOKS = sorted((Path(__file__).resolve().parents[1] / "notebooks").glob("*.ipynb"))
IDS = [p.stem for p in NOTEBOOKS]


def _parameters_cell(nb):
    tagged = [c for c in nb.cells if "parameters" in c.get("metadata", {}).get("tags", [])]
    return tagged


@pytest.mark.parametrize("path", NOTEBOOKS, ids=IDS)
def test_committed_notebook_is_clean(path):
    nb = nbformat.read(path, as_version=4)
    nbformat.validate(nb)
    dirty = [i for i, c in enumerate(nb.cells) if c.cell_type == "code"
             and (c.get("outputs") or c.get("execution_count") is not None)]
    assert not dirty, f"{path.name}: cells {dirty} have outputs or execution counts"
    assert nb.metadata.get("kernelspec", {}).get("name") == "python3"
    # nbformat.read adds missing cell ids with a warning; the file itself must carry them
    raw = json.loads(path.read_text(encoding="utf-8"))
    assert all("id" in c for c in raw["cells"]), f"{path.name}: cells without an id"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=IDS)
def test_notebook_has_quick_parameter_and_report_name(path):
    assert reports.NOTEBOOK_PATTERN.match(path.name), (
        f"{path.name}: report notebooks are named NN_name.ipynb")
    nb = nbformat.read(path, as_version=4)
    tagged = _parameters_cell(nb)
    assert len(tagged) == 1 and tagged[0].cell_type == "code", (
        f"{path.name}: needs exactly one code cell tagged 'parameters'")
    info = next(i for i in reports.list_notebooks(path.parent) if i.name == path.stem)
    assert info.parameters.get("quick") == "False", (
        f"{path.name}: the parameters cell must set quick = False")
    assert nb.cells[0].cell_type == "markdown" and info.title != path.stem, (
        f"{path.name}: start with a markdown title")


@pytest.mark.parametrize("path", NOTEBOOKS, ids=IDS)
def test_parameters_cell_parses_for_papermill(path, caplog):
    """Every parameter line parses (papermill logs a warning mid-report otherwise, e.g. for
    an '=' or quotes inside a trailing comment)."""
    import papermill

    with caplog.at_level(logging.WARNING, logger="papermill"):
        found = papermill.inspect_notebook(str(path))
    assert "quick" in found
    assert not [r.getMessage() for r in caplog.records if "Unable to parse" in r.getMessage()]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=IDS)
def test_notebook_defines_no_function(path):
    """Notebooks are thin: figure display, conversions and readings come from navlib."""
    nb = nbformat.read(path, as_version=4)
    defined = [node.name for c in nb.cells if c.cell_type == "code"
               for node in ast.walk(ast.parse(c.source))
               if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef)]
    assert not defined, f"{path.name}: defines {defined}; put them in navlib"


@pytest.mark.notebook
@pytest.mark.parametrize("path", NOTEBOOKS, ids=IDS)
def test_notebook_runs_quick_and_draws(path, tmp_path):
    out = tmp_path / "report"
    try:
        # the report defaults: a timed-out cell fails, a stalled kernel is restarted once
        (run,) = reports.run_reports(path.parent, out, quick=True, only=[path.stem])
    except reports.ReportError as exc:
        pytest.fail(f"{exc}\n{exc.runs[-1].failure.traceback}", pytrace=False)
    assert not run.stalls, f"{path.name}: the kernel stalled: {run.stalls}"
    assert run.parameters.get("quick") is True
    executed = nbformat.read(out / run.ipynb, as_version=4)
    outputs = [o for c in executed.cells if c.cell_type == "code" for o in c.outputs]
    errors = [o for o in outputs if o.output_type == "error"]
    assert not errors
    stderr = "".join(o.get("text", "") for o in outputs
                     if o.output_type == "stream" and o.get("name") == "stderr")
    assert "Traceback" not in stderr
    pngs = [o for o in outputs if "image/png" in o.get("data", {})]
    assert pngs, f"{path.name}: no figure (image/png output) produced"
    assert (out / run.html).stat().st_size > 0
