"""What index.html says of each page (navlib.reports.headlines): the notebook's question and
a headline read from its outputs, by the documented rule."""

import nbformat
from nbformat.v4 import new_code_cell, new_markdown_cell, new_notebook, new_output

from navlib.reports.headlines import headline, question


def _table(rows: int, marker: str) -> dict:
    body = "".join(f"<tr><td>{marker} {i}</td></tr>" for i in range(rows))
    return new_output("display_data", data={"text/html": (
        f'<table class="dataframe"><thead><tr><th>c</th></tr></thead>{body}</table>'),
        "text/plain": "table"})


def _markdown(text: str) -> dict:
    return new_output("display_data", data={"text/markdown": text, "text/plain": "md"})


def _notebook(*cells) -> nbformat.NotebookNode:
    nb = new_notebook()
    nb.cells.append(new_markdown_cell("# Title\n**Question.** Which *states*\ncan we "
                                      "estimate?\n\nThe rest of the introduction."))
    for outputs, tags in cells:
        cell = new_code_cell("x = 1")
        cell.outputs = outputs
        if tags:
            cell.metadata["tags"] = tags
        nb.cells.append(cell)
    return nb


def test_question_is_the_question_paragraph():
    assert question(_notebook()) == "Which <em>states</em> can we estimate?"
    nb = _notebook()
    nb.cells[0].source = "# Title only"
    assert question(nb) == ""


def test_tagged_cells_are_the_headline():
    nb = _notebook(([_markdown("first text")], []), ([_table(2, "tagged")], ["headline"]),
                   ([_table(3, "last")], []))
    text = headline(nb)
    assert "tagged 1" in text and "first text" not in text and "last" not in text


def test_first_text_with_the_next_short_table():
    nb = _notebook(([_table(2, "before")], []),
                   ([_markdown("**82 claims**"), _table(3, "per paper")], []),
                   ([_table(3, "later")], []))
    text = headline(nb)
    assert "<strong>82 claims</strong>" in text and "per paper 2" in text
    assert "before" not in text and "later" not in text
    long = _notebook(([_markdown("summary"), _table(40, "long")], []))
    assert "long" not in headline(long)


def test_last_table_without_text():
    nb = _notebook(([_table(2, "import")], []), ([_table(4, "segments")], []))
    text = headline(nb)
    assert "segments 3" in text and "import" not in text
    assert headline(_notebook()) == ""


def test_long_reading_shows_its_verdict_counts_and_folds_the_rest():
    reading = ("**Reproduced** (2):\n* **X1** ok\n* **X2** ok\n\n"
               "**Not reproduced** (1):\n* **X3** off by 10 %\n")
    text = headline(_notebook(([_markdown(reading)], ["headline"])))
    assert text.startswith("<p><b>Reproduced 2 · Not reproduced 1</b></p><details>")
    assert "off by 10 %" in text
    folded = headline(_notebook(([_table(30, "row")], ["headline"])))
    assert folded.startswith("<details><summary>table of 30 rows</summary>")
