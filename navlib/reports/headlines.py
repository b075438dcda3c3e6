"""What each report page answers and its headline, for ``index.html``.

* The **question** is the notebook's own: the ``**Question.**`` paragraph of its first
  markdown cell (every report notebook opens with one), else its title.
* The **headline** is read from the executed notebook, never typed: the outputs of the cells
  tagged :data:`HEADLINE_TAG` when the notebook has any; else the first generated text
  (a ``text/markdown`` output, e.g. the claims summary or a notebook's claims reading) with
  the next table when it is short (the claims reproduced, explained and unexplained per
  paper); else the last table of the page (e.g. a flight's segments with their excitable and
  sensible states). A long text shows the verdict counts of a claims reading
  (``**Reproduced** (4):`` ...) or its first lines, the rest behind a "more" toggle; a
  table of more than 12 rows is folded the same way.
"""

from __future__ import annotations

import html
import re

__all__ = ["HEADLINE_TAG", "headline", "question"]

HEADLINE_TAG = "headline"
"""Cell tag: the cell's outputs are the page's headline on ``index.html``."""

_QUESTION = re.compile(r"\*\*Question\.\*\*\s*(.+?)(?:\n\s*\n|$)", re.S)
_VERDICT_HEADING = re.compile(r"^\*\*([^*]+)\*\*\s*\((\d+)\):", re.M)
_SHORT_LINES = 4
_LONG_TABLE_ROWS = 12


def _text(value) -> str:
    return "".join(value) if isinstance(value, list) else str(value or "")


def _markdown_html(text: str) -> str:
    import mistune  # nbconvert's markdown renderer: loaded only when an index is written

    return mistune.html(text)


def question(nb) -> str:
    """The question a notebook answers (HTML): its ``**Question.**`` paragraph, else ""."""
    for cell in nb.cells:
        if cell.cell_type == "markdown":
            found = _QUESTION.search(_text(cell.source))
            if not found:
                return ""
            text = _markdown_html(" ".join(found.group(1).split())).strip()
            return text.removeprefix("<p>").removesuffix("</p>")  # one inline sentence
    return ""


def _outputs(cell) -> list[dict]:
    return [o for o in cell.get("outputs", ()) if o.get("output_type") in
            ("display_data", "execute_result", "stream")]


def _output_html(out) -> str:
    data = out.get("data", {})
    if "text/markdown" in data:
        return _long_markdown(_text(data["text/markdown"]))
    if "text/html" in data and "<table" in _text(data["text/html"]):
        table = _text(data["text/html"])
        rows = _rows(out)
        if rows > _LONG_TABLE_ROWS:
            return f"<details><summary>table of {rows} rows</summary>{table}</details>"
        return table
    if "image/png" in data:
        return (f'<img style="max-width:100%;height:auto" '
                f'src="data:image/png;base64,{_text(data["image/png"]).strip()}">')
    text = _text(data.get("text/plain", out.get("text", "")))
    return f"<pre>{html.escape(text)}</pre>" if text.strip() else ""


def _long_markdown(text: str) -> str:
    """Markdown as HTML; past :data:`_SHORT_LINES` lines, a summary (verdict counts of a
    claims reading, else the first lines) and the whole text behind a toggle."""
    lines = [ln for ln in text.strip().splitlines() if ln.strip()]
    if len(lines) <= _SHORT_LINES:
        return _markdown_html(text)
    counts = _VERDICT_HEADING.findall(text)
    summary = (" · ".join(f"{word} {n}" for word, n in counts) if counts
               else None)
    head = (f"<p><b>{html.escape(summary)}</b></p>" if summary
            else _markdown_html("\n".join(lines[:_SHORT_LINES])))
    return f"{head}<details><summary>more</summary>{_markdown_html(text)}</details>"


def headline(executed) -> str:
    """The headline of an executed notebook as HTML ("" when it shows nothing to lead
    with); see the module docstring for the rule."""
    cells = [c for c in executed.cells if c.cell_type == "code"]
    tagged = [c for c in cells if HEADLINE_TAG in c.get("metadata", {}).get("tags", ())]
    if tagged:
        return "".join(_output_html(o) for c in tagged for o in _outputs(c))
    outputs = [o for c in cells for o in _outputs(c)]
    tables = [i for i, o in enumerate(outputs)
              if 'class="dataframe' in _text(o.get("data", {}).get("text/html", ""))]
    for i, out in enumerate(outputs):
        if "text/markdown" in out.get("data", {}):
            after = [k for k in tables if k > i][:1]
            short = [k for k in after if _rows(outputs[k]) <= _LONG_TABLE_ROWS]
            return "".join(_output_html(outputs[k]) for k in (i, *short))
    return _output_html(outputs[tables[-1]]) if tables else ""


def _rows(out) -> int:
    """Body rows of a table output (its ``<tr>`` less the header row)."""
    return _text(out.get("data", {}).get("text/html", "")).count("<tr") - 1
