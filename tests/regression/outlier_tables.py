"""What notebook 05 and the outlier study show, as one long table, for before/after checks.

:func:`notebook_values` executes the code cells of ``notebooks/05_outlier_sensitivity.ipynb``
in this process (``display`` collects the shown objects instead of rendering them) and
flattens every table, Markdown text and widget status the notebook shows into rows
``item, row, column, value``; :func:`claim_values` does the same for the claims engine's
outlier study (:func:`navlib.studies.outliers.assumptions._variants`: baseline and robustness set).
Numbers are written with 17 significant digits, text as it is.

``python tests/outlier_tables.py`` rewrites the reference files in ``tests/regression/data/``
(only ever at a commit whose results are the reference).
"""

from __future__ import annotations

import json
import math
import re
import sys
from pathlib import Path

import IPython.display
import numpy as np
import pandas as pd
from golden import text_differences

ROOT = Path(__file__).resolve().parents[2]
DATA = Path(__file__).resolve().parent / "data"
NOTEBOOK = ROOT / "notebooks" / "05_outlier_sensitivity.ipynb"
COLUMNS = ["item", "row", "column", "value"]


def _cell(value) -> str:
    if isinstance(value, (bool, np.bool_)):
        return str(bool(value))
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        return repr(float(value)) if math.isfinite(value) else str(float(value))
    return str(value)


def _rows(item: str, obj) -> list[tuple]:
    if isinstance(obj, pd.Series):
        obj = obj.to_frame()
    if isinstance(obj, pd.DataFrame):
        return [(item, str(r), str(c), _cell(v)) for r, row in obj.iterrows()
                for c, v in row.items()]
    if hasattr(obj, "data") and isinstance(obj.data, str):          # Markdown
        return [(item, "", "text", obj.data)]
    return [(item, "", "type", type(obj).__name__)]


def notebook_values(quick: bool) -> pd.DataFrame:
    """Run notebook 05's code cells (``quick`` as its parameter) and flatten what it shows."""
    import matplotlib

    matplotlib.use("Agg")
    nb = json.loads(NOTEBOOK.read_text())
    shown: list = []
    scope = {"__name__": "__main__"}
    capture = lambda *objs, **_kw: shown.extend(objs)  # noqa: E731 - one-line sink
    # navlib.plots.figure.show displays through IPython.display.display: capture it there too
    original, IPython.display.display = IPython.display.display, capture
    try:
        for cell in nb["cells"]:
            if cell["cell_type"] != "code":
                continue
            source = "".join(cell["source"]).replace(
                "from IPython.display import Markdown, display",
                "from IPython.display import Markdown")
            if "parameters" in cell.get("metadata", {}).get("tags", []):
                source += f"\nquick = {quick}\n"
            scope["display"] = capture
            exec(compile(source, "notebook-05", "exec"), scope)
    finally:
        IPython.display.display = original
    rows = []
    for i, obj in enumerate(shown):
        rows += _rows(f"shown {i}", obj)
    # the same results unrounded
    # the status mark carries the update's own time (data-ms): a measurement, not a result
    status = re.sub(r' data-ms="[^"]*"', "", scope["panel"].status.value)
    rows.append(("panel", "", "status", status))
    rows += _rows("study claims", scope["study"].claims_frame())
    rows += _rows("study table", scope["study"].table())
    rows += _rows("capture", pd.Series(scope["study"].capture, name="value"))
    if "sens" in scope:
        rows += _rows("sensitivity", scope["sens"])
    for solution, check in scope.get("checks", {}).items():
        rows += _rows(f"ekf {solution}", pd.DataFrame(
            {"ekf": check.score_ekf.as_dict(), "linear": check.linear.score.as_dict()}))
    rows += _rows("monte carlo", pd.Series(scope["mc"].score.as_dict(), name="score"))
    return pd.DataFrame(rows, columns=COLUMNS)


def claim_values(quick: bool) -> pd.DataFrame:
    """The claims engine's outlier study: every (window, a1_sign) variant's claims and the
    robustness fractions."""
    from navlib.studies import outliers
    from navlib.studies.claims import claims_frame, studies, study_robustness

    outliers.assumptions._variants.cache_clear()
    rows = []
    for (window, sign), claims in outliers.assumptions._variants(quick).items():
        frame = claims_frame(claims)[["claim_id", "ours", "verdict", "checks"]]
        rows += _rows(f"variant {window:g} {sign:+g}", frame.set_index("claim_id"))
    robustness = study_robustness(studies()["outliers"], quick)
    rows += _rows("robustness", pd.Series({k: r.fraction for k, r in robustness.items()},
                                          name="fraction"))
    return pd.DataFrame(rows, columns=COLUMNS)


def _numbers(frame: pd.DataFrame) -> pd.Series:
    return pd.to_numeric(frame.value, errors="coerce")


def _scales(want: pd.DataFrame) -> np.ndarray:
    """Per row: the largest |number| of its item and column in ``want`` (the scale a number
    near zero is compared on)."""
    numbers = _numbers(want).abs()
    finite = numbers.where(np.isfinite(numbers))
    return finite.groupby([want["item"], want["column"]]).transform("max").to_numpy()


def _same_rows(got: pd.DataFrame, want: pd.DataFrame) -> bool:
    return list(got[["item", "row", "column"]].itertuples(index=False)) == list(
        want[["item", "row", "column"]].itertuples(index=False))


def differences(got: pd.DataFrame, want: pd.DataFrame, rtol: float) -> list[str]:
    """Rows that differ: numbers by more than ``rtol`` times the largest |number| of their
    item and column, text with :func:`golden.text_differences` (words exactly, numbers in it
    to their printed precision)."""
    if not _same_rows(got, want):
        return ["the tables have different rows: "
                f"{len(got)} now, {len(want)} in the reference"]
    out = []
    keys = want[["item", "row", "column"]].itertuples(index=False)
    for g, w, scale, key in zip(got.value, want.value, _scales(want), keys, strict=True):
        try:
            a, b = float(g), float(w)
        except ValueError:
            out += [f"{tuple(key)}: {d}" for d in text_differences(g, w)]
            continue
        if not (a == b or (math.isnan(a) and math.isnan(b))
                or abs(a - b) <= rtol * max(abs(a), abs(b), scale)):
            out.append(f"{tuple(key)}: {a!r} != {b!r}")
    return out


def spread(got: pd.DataFrame, want: pd.DataFrame) -> float:
    """Largest relative distance of the numbers (on the scale of :func:`differences`); inf
    when the rows or a text differ beyond its printed precision."""
    if not _same_rows(got, want) or differences(got, want, rtol=math.inf):
        return math.inf
    a, b = _numbers(got).to_numpy(), _numbers(want).to_numpy()
    scale = np.fmax(np.fmax(np.abs(a), np.abs(b)), _scales(want))
    both = np.isfinite(a) & np.isfinite(b) & (scale > 0)
    return float(np.max(np.abs(a - b)[both] / scale[both], initial=0.0))


def reference(name: str) -> pd.DataFrame:
    return pd.read_csv(DATA / name, dtype=str, keep_default_na=False)


if __name__ == "__main__":
    DATA.mkdir(exist_ok=True)
    sys.path.insert(0, str(ROOT))
    which = sys.argv[1:] or ["quick", "full", "claims-quick", "claims-full"]
    for name in which:
        quick = name.endswith("quick")
        frame = claim_values(quick) if name.startswith("claims") else notebook_values(quick)
        frame.to_csv(DATA / f"outliers_{name.replace('-', '_')}.csv", index=False)
        print(name, len(frame), "rows")
