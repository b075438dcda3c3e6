"""Fleet assessment: many recorded flights assessed as Dask tasks, one summary table.

Public contract (spec ``api.md``, "Scale")::

    python -m navlib assess LOG [LOG ...] --output DIR [--scheduler ADDR] [-p key value ...]

Each ``LOG`` is a PX4 ``.ulg`` file, an ArduPilot DataFlash ``.bin`` file (read with
``navlib.io.read_dataflash``), an Altus Metrum AltOS CSV export (recognised by its header,
read with ``navlib.io.read_altos``) or an ``imu.csv,gnss.csv`` pair; each
flight goes through :func:`navlib.studies.assess.assess_flight` as one task
(:func:`navlib.parallel.map_tasks`), with the ``-p`` keywords (a ULog's ``MAV_TYPE`` parameter
is attached as ``imu.attrs["mav_type"]`` so the vehicle class comes from the log,
:func:`navlib.segmentation.vehicle_from_log`). :func:`assess_logs` returns one
row per flight and :func:`write_fleet` writes ``DIR/summary.csv`` plus one HTML page per
assessed flight (tables and the figures of notebook 07 as embedded PNG). A flight that fails
(unreadable log, too short, a fit that does not converge...) gets ``status = failed`` and its
error in the table; it never stops the others.
"""

from __future__ import annotations

import base64
import html
import inspect
import io as _io
import time
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path

import pandas as pd

from navlib import io
from navlib._validation import reject_unknown
from navlib.errors import NavlibInputError
from navlib.io.altos import looks_like_altos
from navlib.parallel import map_tasks
from navlib.studies.assess import assess_flight

__all__ = ["SUMMARY_COLUMNS", "assess_log", "assess_logs", "flight_page", "parse_log",
           "write_fleet"]

SUMMARY_COLUMNS = ("log", "status", "error", "vehicle", "duration_s", "n_segments", "phases",
                   "excitable", "sensible", "warnings", "seconds", "page")
"""Columns of ``summary.csv``, in order."""
KINDS = ("ulog", "dataflash", "altos", "csv")


def parse_log(spec: str) -> tuple[str, tuple[Path, ...]]:
    """The kind (``ulog``, ``dataflash``, ``altos``, ``csv``) and file(s) of a ``LOG`` argument.

    One file is a ``.ulg`` or ``.bin`` by its suffix, an AltOS export by its first line
    (:func:`navlib.io.altos.looks_like_altos`), whatever its name.
    """
    if not isinstance(spec, str) or not spec.strip():
        raise NavlibInputError(f"log: expected a file name, got {spec!r}")
    parts = [p.strip() for p in spec.split(",")]
    if len(parts) == 2:
        if not all(p.lower().endswith(".csv") for p in parts):
            raise NavlibInputError(f"log {spec!r}: a pair must be 'imu.csv,gnss.csv'")
        return "csv", (Path(parts[0]), Path(parts[1]))
    if len(parts) != 1:
        raise NavlibInputError(f"log {spec!r}: expected one .ulg/.bin file, an AltOS .csv "
                               "export or an 'imu.csv,gnss.csv' pair")
    suffix = Path(parts[0]).suffix.lower()
    if suffix == ".ulg":
        return "ulog", (Path(parts[0]),)
    if suffix == ".bin":
        return "dataflash", (Path(parts[0]),)
    if looks_like_altos(parts[0]):
        return "altos", (Path(parts[0]),)
    raise NavlibInputError(f"log {spec!r}: unknown kind; expected .ulg, .bin, an AltOS .csv "
                           "export (header '#version,...' or 'time,acceleration,...') or "
                           "'imu.csv,gnss.csv'")


def _assess_keywords() -> tuple[str, ...]:
    return tuple(p for p in inspect.signature(assess_flight).parameters if p not in
                 ("imu", "gnss"))


def _mav_type(path: Path) -> int | None:
    """The ``MAV_TYPE`` parameter of a PX4 ULog (the vehicle type), or None."""
    from pyulog import ULog  # optional dependency, imported where read_ulog needs it too

    try:
        value = ULog(str(path), []).initial_parameters.get("MAV_TYPE")
    except Exception:  # a log read_ulog accepted but whose header pyulog cannot re-read
        return None
    return None if value is None else int(value)


def _read(kind: str, paths: tuple[Path, ...]):
    if kind == "ulog":
        imu, gnss = io.read_ulog(paths[0])
        if imu.attrs.get("mav_type") is None:
            imu.attrs["mav_type"] = _mav_type(paths[0])
        return imu, gnss
    if kind == "csv":
        return io.read_imu_csv(paths[0]), io.read_gnss_csv(paths[1])
    if kind == "altos":
        return io.read_altos(paths[0])
    return io.read_dataflash(paths[0])


def _per_segment(summary: pd.DataFrame, column: str) -> str:
    return " | ".join(f"{r.segment} {r.phase}: {getattr(r, column)}"
                      for r in summary.itertuples(index=False))


def _figure_png(fig) -> str:
    import matplotlib.pyplot as plt  # heavy; flight_page selected the Agg backend first

    buf = _io.BytesIO()
    fig.savefig(buf, format="png", dpi=80)
    plt.close(fig)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def flight_page(log: str, result, warning_texts: Sequence[str]) -> str:
    """A self-contained HTML page of one assessed flight (tables, figures as PNG)."""
    import matplotlib  # heavy; the Agg backend must be chosen before pyplot is imported

    matplotlib.use("Agg", force=False)
    from navlib.plots import assess as aplots  # imports pyplot: after the backend choice
    from navlib.plots.metrics import excitability_figure  # imports pyplot, as above

    figures = [("Flight phases", aplots.phases_figure(result)),
               ("Excitability per segment", excitability_figure(result)),
               ("Which states each segment could estimate", aplots.estimable_figure(result)),
               ("Fit residuals", aplots.fit_residuals_figure(result))]
    parts = [f"<h1>Flight assessment: {html.escape(log)}</h1>",
             "<p>Generated by <code>python -m navlib assess</code> "
             "(navlib.studies.assess.assess_flight, 21-state ECEF model). The statements are "
             "about the linearised model along the fitted trajectory under the stated preset "
             "and thresholds.</p>",
             "<h2>Assumed</h2>", pd.DataFrame([{k: result.options.get(k) for k in (
                 "vehicle", "preset", "gnss_rate_hz", "gnss_sigma_m", "heading_deg")}]
                                               ).to_html(index=False),
             "<h2>Inputs</h2>", result.inputs.to_html(index=False),
             "<h2>Segments and estimable states</h2>", result.summary().to_html(index=False)]
    notes = [*warning_texts, *result.notes]
    if notes:
        parts.append("<h2>Warnings and notes</h2><ul>"
                     + "".join(f"<li>{html.escape(str(n))}</li>" for n in notes) + "</ul>")
    for title, fig in figures:
        parts.append(f"<h2>{html.escape(title)}</h2>"
                     f'<img alt="{html.escape(title)}" src="data:image/png;base64,'
                     f'{_figure_png(fig)}">')
    parts.append("<h2>Fit residuals (table)</h2>" + result.fit.to_html(index=False))
    return ("<!DOCTYPE html><html><head><meta charset='utf-8'><title>"
            f"{html.escape(log)}</title><style>body{{font-family:sans-serif;max-width:1100px;"
            "margin:auto}} table{border-collapse:collapse;font-size:small} td,th{border:1px "
            "solid #ccc;padding:2px 6px} img{max-width:100%}</style></head><body>"
            + "\n".join(parts) + "</body></html>")


def _warning_text(w) -> str:
    return f"{w.category.__name__}: {w.message}"


def summary_row(label: str, columns: Sequence[str], build) -> tuple[dict, str | None]:
    """One summary row of ``columns`` for ``label``; never raises for a bad input.

    ``build(warning_texts)`` returns the :class:`~navlib.studies.assess.FlightAssessment`
    (or mission plan) and its HTML page; ``warning_texts()`` gives the warnings caught so far.
    The row gets the status, vehicle, duration, phases, excitable and sensible states per
    segment, every warning caught and the seconds taken; a failure goes in ``error``.
    """
    start = time.perf_counter()
    row = dict.fromkeys(columns, "")
    row.update(log=label, status="failed", duration_s=float("nan"), n_segments=0)
    page = None
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            result, page = build(lambda: [_warning_text(w) for w in caught])
            summary = result.summary()
            seg = result.segment_table
            row.update(status="ok", vehicle=result.vehicle,
                       duration_s=float(seg.t_end.max() - seg.t_start.min()),
                       n_segments=len(seg),
                       phases="; ".join(f"{r.phase} {r.t_start:.1f}-{r.t_end:.1f} s"
                                        for r in seg.itertuples(index=False)),
                       excitable=_per_segment(summary, "excitable"),
                       sensible=_per_segment(summary, "sensible"))
        except Exception as exc:  # a bad input is reported, never stops the others
            row["error"] = f"{type(exc).__name__}: {exc}"
    row["warnings"] = " | ".join(sorted({_warning_text(w) for w in caught}))
    row["seconds"] = round(time.perf_counter() - start, 2)
    return row, page


def assess_log(log: str, options: Mapping | None = None) -> tuple[dict, str | None]:
    """Assess one flight; never raises for a bad flight.

    Returns
    -------
    row : dict
        The :data:`SUMMARY_COLUMNS` (``page`` is filled in by :func:`write_fleet`).
    page : str or None
        The flight's HTML page (None when it failed).
    """
    def build(warning_texts):
        kind, paths = parse_log(log)
        imu, gnss = _read(kind, paths)
        result = assess_flight(imu, gnss, **dict(options or {}))
        return result, flight_page(log, result, warning_texts())

    return summary_row(log, SUMMARY_COLUMNS, build)


def _task(log: str, options: Mapping) -> tuple[dict, str | None]:
    return assess_log(log, options)


def assess_logs(logs: Sequence[str], options: Mapping | None = None, scheduler=None,
                progress: bool = False) -> tuple[pd.DataFrame, list]:
    """Assess flights as Dask tasks (:func:`navlib.parallel.map_tasks`).

    ``options`` are keywords of :func:`navlib.studies.assess.assess_flight` (checked here,
    before any task runs). Returns the summary table (one row per log, in order) and the
    HTML pages (None for failed flights).
    """
    logs = list(logs)
    if not logs or not all(isinstance(x, str) for x in logs):
        raise NavlibInputError(f"logs: expected one or more file names, got {logs!r}")
    options = dict(options or {})
    reject_unknown(options, _assess_keywords(), "assess options (-p)")
    results = map_tasks(_task, logs, scheduler, shared={"options": options},
                        progress=progress, desc="flights")
    table = pd.DataFrame([row for row, _ in results], columns=list(SUMMARY_COLUMNS))
    return table, [page for _, page in results]


def _page_name(index: int, log: str) -> str:
    stem = Path(log.split(",")[0]).stem or "flight"
    safe = "".join(c if c.isalnum() or c in "-_" else "_" for c in stem)
    return f"{index + 1:03d}_{safe}.html"


def write_fleet(table: pd.DataFrame, pages: Sequence, output) -> Path:
    """Write ``output/summary.csv`` and one HTML page per assessed flight; returns the CSV."""
    output = Path(output)
    output.mkdir(parents=True, exist_ok=True)
    table = table.copy()
    for i, (log, page) in enumerate(zip(table["log"], pages, strict=True)):
        if page is not None:
            name = _page_name(i, log)
            (output / name).write_text(page, encoding="utf-8")
            table.loc[i, "page"] = name
    path = output / "summary.csv"
    table.to_csv(path, index=False)
    return path
