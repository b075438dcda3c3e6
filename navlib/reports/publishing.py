"""Publishing a report: all or nothing, by an atomic swap of folders, with an index page.

Pages are written to a staging folder next to the output folder and swapped into place only
when every selected notebook succeeded (docs/reports.md). Output layout
(flat, inside the output folder)::

    index.html            per page: what it answers and its headline
                          (:mod:`navlib.reports.headlines`); then the run details
                          (status, time, mode, parameters)
    NN_name.html          the executed notebook as a static page (outputs, no code)
    NN_name.ipynb         the executed notebook (papermill output, with parameters cell)
    manifest.json         machine-readable status of every page in the folder
    README*               any README already there is kept

A run restricted with ``only`` refreshes the selected pages and keeps the other pages of the
previous report (the index lists all of them, each with the date and mode it was made in);
a full run replaces the whole report (README files excepted).
"""

from __future__ import annotations

import datetime as _dt
import html
import json
import os
import shutil
import sys
import tempfile
from collections.abc import Mapping, Sequence
from pathlib import Path

import psutil

from navlib import __version__
from navlib.errors import NavlibInputError
from navlib.reports import headlines
from navlib.reports.results import NotebookRun
from navlib.reports.signals import signals_deferred
from navlib.resources import source_checkout

__all__ = ["INDEX", "MANIFEST", "check_output_dir", "default_output_dir", "load_manifest",
           "publish", "remove_orphaned_staging", "staging_folder"]

MANIFEST = "manifest.json"
INDEX = "index.html"


def check_output_dir(output: Path, notebooks_dir: Path) -> None:
    """Refuse output folders that are not (or could not become) a report folder."""
    if output == notebooks_dir or output in notebooks_dir.parents or output == Path.cwd():
        raise NavlibInputError(
            f"output_dir: {output} would replace the notebooks or the working folder")
    if output.exists() and not output.is_dir():
        raise NavlibInputError(f"output_dir: {output} exists and is not a folder")
    if output.is_dir() and not (output / MANIFEST).exists():
        foreign = [p.name for p in output.iterdir() if not p.name.upper().startswith("README")]
        if foreign:
            raise NavlibInputError(
                f"output_dir: {output} holds files that are not a navlib report "
                f"({', '.join(sorted(foreign)[:5])}); choose an empty or new folder")


def load_manifest(output: Path) -> dict:
    """The ``manifest.json`` of a report folder (empty when missing or unreadable)."""
    try:
        data = json.loads((output / MANIFEST).read_text(encoding="utf-8"))
        return data if isinstance(data, dict) else {}
    except (OSError, ValueError):
        return {}


def _page_summary(executed: Path) -> dict:
    """``question`` and ``headline`` (HTML) of an executed notebook for the index (empty
    when it cannot be read)."""
    from navlib.reports.discovery import notebook_format  # nbformat: only when publishing

    try:
        nb = notebook_format().read(executed, as_version=4)
    except Exception:  # an unreadable notebook gets an index row without its summary
        return {"question": "", "headline": ""}
    return {"question": headlines.question(nb), "headline": headlines.headline(nb)}


def _entry(run: NotebookRun, finished: str, folder: Path) -> dict:
    summary = (_page_summary(folder / run.ipynb) if run.ipynb
               and (folder / run.ipynb).exists() else {"question": "", "headline": ""})
    return {"title": run.title, "status": run.status, "seconds": round(run.seconds, 3),
            "quick": run.parameters.get("quick") is True,
            "parameters": {k: repr(v) for k, v in run.parameters.items()},
            "html": run.html, "ipynb": run.ipynb, "finished": finished, **summary}


def _page_sections(entries: Mapping[str, dict]) -> str:
    """One section per page: its title (linked), what it answers and its headline."""
    sections = []
    for name, e in sorted(entries.items()):
        title = html.escape(str(e.get("title") or name))
        link = (f'<a href="{html.escape(e["html"])}">{title}</a>' if e.get("html") else title)
        question = e.get("question") or ""
        answer = e.get("headline") or ""
        sections.append(
            f'<section class="page" id="{html.escape(name)}"><h2>{link} '
            f'<span class="stem">{html.escape(name)}</span></h2>'
            + (f'<div class="question"><b>Answers:</b> {question}</div>' if question else "")
            + (f'<div class="headline">{answer}</div>' if answer else "")
            + "</section>")
    return "\n".join(sections)


def _index_html(entries: Mapping[str, dict], generated: str) -> str:
    rows = []
    for position, (name, e) in enumerate(sorted(entries.items()), start=1):
        link = (f'<a href="{html.escape(e["html"])}">{html.escape(name)}</a>'
                if e.get("html") else html.escape(name))
        nb_link = (f'<a href="{html.escape(e["ipynb"])}">.ipynb</a>' if e.get("ipynb") else "")
        params = ", ".join(f"{k}={v}" for k, v in e.get("parameters", {}).items())
        status = html.escape(str(e.get("status", "?")))
        rows.append(
            f'<tr class="{status}"><td>{position}</td><td>{link}</td>'
            f'<td>{html.escape(str(e.get("title", "")))}</td><td>{status}</td>'
            f'<td class="num">{float(e.get("seconds", 0.0)):.1f}</td>'
            f'<td>{"quick" if e.get("quick") else "full"}</td>'
            f'<td><code>{html.escape(params)}</code></td>'
            f'<td>{html.escape(str(e.get("finished", "")))}</td><td>{nb_link}</td></tr>')
    body = "\n".join(rows)
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>navlib reports</title>
<style>
body {{ font-family: system-ui, sans-serif; font-size: 16px; line-height: 1.45;
        max-width: 1200px; margin: 0 auto; padding: 1em 2em; }}
table {{ border-collapse: collapse; font-size: 14px; }}
th, td {{ border-bottom: 1px solid #ccc; padding: 0.3em 0.8em; text-align: left;
          vertical-align: top; }}
td.num {{ text-align: right; }} tr.failed {{ background: #fdd; }}
section.page {{ border-top: 1px solid #ddd; padding: 0.4em 0 0.8em; }}
section.page h2 {{ font-size: 1.2em; margin: 0.4em 0; }}
.stem {{ color: #777; font-size: 0.75em; font-weight: normal; }}
.question p, .headline p {{ margin: 0.3em 0; }}
.headline {{ overflow-x: auto; }}
</style></head><body>
<h1>navlib reports</h1>
<p>Which parts of the navigation state can a flight estimate, and how well; and which claims
of the three papers navlib reproduces. Each page below says the question it answers and
shows its headline result; open it for the figures, tables and the reasoning.</p>
{_page_sections(entries)}
<h2>Run details</h2>
<p>Generated {html.escape(generated)} by <code>python -m navlib report</code>
(navlib {html.escape(__version__)}, Python {html.escape(sys.version.split()[0])}).
Each page is an executed notebook; “quick” pages ran with shrunken durations for
smoke testing.</p>
<table><thead><tr><th>#</th><th>notebook</th><th>title</th><th>status</th><th>time, s</th>
<th>mode</th><th>parameters</th><th>finished</th><th>source</th></tr></thead>
<tbody>
{body}
</tbody></table></body></html>
"""


def publish(staging: Path, output: Path, runs: Sequence[NotebookRun], partial: bool) -> None:
    """Carry over what stays of the old report, write index + manifest, swap in.

    A ``partial`` run (``only`` given) keeps the other pages of the old report; a full run
    keeps only README files, so pages of deleted or renamed notebooks disappear.
    """
    finished = _dt.datetime.now(_dt.UTC).strftime("%Y-%m-%d %H:%M:%S UTC")
    old_entries: dict = {}
    if output.is_dir():
        old_entries = load_manifest(output).get("notebooks", {}) if partial else {}
        for item in output.iterdir():
            target = staging / item.name
            keep = partial or item.name.upper().startswith("README")
            if not keep or item.name in (MANIFEST, INDEX) or target.exists():
                continue
            if item.is_dir():
                shutil.copytree(item, target, symlinks=True)
            else:
                shutil.copy2(item, target, follow_symlinks=False)
    entries = {name: e for name, e in old_entries.items()
               if isinstance(e, dict) and e.get("html") and (staging / e["html"]).exists()}
    entries.update({r.name: _entry(r, finished, staging) for r in runs})
    manifest = {"generator": "navlib report", "generated": finished, "notebooks": entries}
    (staging / MANIFEST).write_text(json.dumps(manifest, indent=1), encoding="utf-8")
    (staging / INDEX).write_text(_index_html(entries, finished), encoding="utf-8")

    if not output.exists():
        os.replace(staging, output)
        return
    retired = Path(tempfile.mkdtemp(prefix=f".{output.name}.old-", dir=output.parent))
    retired.rmdir()
    with signals_deferred():  # an interrupt between the two renames would lose the report
        os.replace(output, retired)
        try:
            os.replace(staging, output)
        except OSError:
            os.replace(retired, output)  # put the good report back
            raise
    shutil.rmtree(retired, ignore_errors=True)


def staging_folder(output: Path) -> Path:
    """A new staging folder ``.NAME.tmp-PID-xxxx`` next to ``output`` (the name
    :func:`remove_orphaned_staging` recognises), readable like a report folder."""
    staging = Path(tempfile.mkdtemp(prefix=f".{output.name}.tmp-{os.getpid()}-",
                                    dir=output.parent))
    umask = os.umask(0)
    os.umask(umask)
    staging.chmod(0o777 & ~umask)  # mkdtemp makes it private; a report folder is not
    return staging


def remove_orphaned_staging(output: Path) -> None:
    """Delete staging folders of earlier runs whose process is gone (killed with SIGKILL,
    which no handler can catch). A folder is named ``.NAME.tmp-PID-xxxx`` by its run."""
    for folder in output.parent.glob(f".{output.name}.tmp-*"):
        pid = folder.name.removeprefix(f".{output.name}.tmp-").split("-")[0]
        if folder.is_dir() and pid.isdigit() and not psutil.pid_exists(int(pid)):
            shutil.rmtree(folder, ignore_errors=True)


def default_output_dir() -> Path:
    """``reports/`` of the source checkout; for an installed wheel, ``reports/`` in the
    current folder (never inside the installed package)."""
    checkout = source_checkout()
    return (checkout if checkout is not None else Path.cwd()) / "reports"
