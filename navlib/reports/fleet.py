"""Many flights or missions in one run: ``python -m navlib assess`` and ``python -m navlib
plan`` (docs/sweeps.md).

Each recorded flight (a ``LOG``: :func:`navlib.io.parse_log`) goes through
:func:`navlib.studies.assess.assess_flight` as one task (:func:`navlib.parallel.map_tasks`)
with the ``-p`` keywords; each mission file through
:func:`navlib.studies.plan.plan_mission`. :func:`assess_logs` and :func:`plan_missions` return
one :data:`SUMMARY_COLUMNS` row per flight or mission and its HTML page
(:mod:`navlib.reports.pages`), with the stacked states tables (how well each state is known,
:mod:`navlib.studies.assess.states`) in the table's ``attrs["states"]``; :func:`write_fleet`
writes ``DIR/summary.csv``, ``DIR/states.csv`` and the pages.
A flight or mission that fails (unreadable log, too short, a fit that does not converge...)
gets ``status = failed`` and its error in the table; it never stops the others.
"""

from __future__ import annotations

import inspect
import time
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path

import pandas as pd

from navlib._validation import reject_unknown
from navlib.errors import NavlibInputError
from navlib.io import read_log
from navlib.parallel import map_tasks
from navlib.reports.pages import flight_page, plan_page
from navlib.studies.assess import assess_flight
from navlib.studies.assess.states import STATES_COLUMNS
from navlib.studies.plan import plan_mission

__all__ = ["SUMMARY_COLUMNS", "assess_log", "assess_logs", "plan_missions", "summary_row",
           "write_fleet"]

SUMMARY_COLUMNS = ("log", "status", "error", "vehicle", "duration_s", "t_ignition",
                   "n_segments", "phases", "events", "excitable", "sensible", "aiding",
                   "unrepresented", "warnings", "seconds", "page")
"""Columns of ``summary.csv``, in order (a mission's file name in ``log``). ``t_ignition``:
a rocket's ignition on the log's own clock, s, the zero of the ``phases`` times (which are
since the first sample for other vehicles; NaN there). ``events``: a rocket's events on that
clock, ``<event> <logged> s (detected <detected> s)`` when the flight computer logged its
states, ``<event> <detected> s (detected)`` otherwise. ``aiding``: what aided the IMU,
``gnss``, ``baro`` or ``gnss+baro`` (:data:`navlib.models.baro.AIDINGS`). ``unrepresented``
lists the segments whose reference motion departs from the records (their excitable and
sensible states do not describe the flight flown; the warnings say why)."""


def _keywords(fn, *skip: str) -> tuple[str, ...]:
    return tuple(p for p in inspect.signature(fn).parameters if p not in skip)


def _per_segment(summary: pd.DataFrame, column: str) -> str:
    return " | ".join(f"{r.segment} {r.phase}: {getattr(r, column)}"
                      for r in summary.itertuples(index=False))


def _events_text(events) -> str:
    if events is None:
        return ""

    def when(t):
        return "-" if t != t else f"{t:.2f} s"

    logged = events["t_logged"].notna().any()
    return "; ".join(f"{r.event} {when(r.t_logged)} (detected {when(r.t_detected)})" if logged
                     else f"{r.event} {when(r.t_detected)} (detected)"
                     for r in events.itertuples(index=False))


def _warning_text(w) -> str:
    return f"{w.category.__name__}: {w.message}"


def summary_row(label: str, build) -> tuple[dict, str | None]:
    """One :data:`SUMMARY_COLUMNS` row for ``label``; never raises for a bad input.

    ``build(warning_texts)`` returns the :class:`~navlib.studies.assess.FlightAssessment`
    (or mission plan) and its HTML page; ``warning_texts()`` gives the warnings caught so far.
    The row gets the status, vehicle, duration, phases, excitable and sensible states per
    segment, every warning caught and the seconds taken; a failure goes in ``error``. Besides
    the columns, ``row["states"]`` holds the result's
    :meth:`~navlib.studies.assess.FlightAssessment.states_table` (None when it failed).

    Parameters
    ----------
    label : str
        Name of the log or mission.
    build : callable
        ``build(warning_texts) -> (result, page)``.

    Returns
    -------
    tuple of (dict, str or None)
        The row and the HTML page (None when it failed).
    """
    start = time.perf_counter()
    row = dict.fromkeys(SUMMARY_COLUMNS, "")
    row.update(log=label, status="failed", duration_s=float("nan"), n_segments=0,
               t_ignition=float("nan"), states=None)
    page = None
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            result, page = build(lambda: [_warning_text(w) for w in caught])
            summary = result.summary()
            seg = result.segment_table
            row.update(status="ok", vehicle=result.vehicle,
                       aiding=str(getattr(result, "options", {}).get("aiding", "gnss")),
                       duration_s=float(seg.t_end.max() - seg.t_start.min()),
                       n_segments=len(seg),
                       phases="; ".join(f"{r.phase} {r.t_start:.1f}-{r.t_end:.1f} s"
                                        for r in seg.itertuples(index=False)),
                       excitable=_per_segment(summary, "excitable"),
                       sensible=_per_segment(summary, "sensible"),
                       t_ignition=result.t_ignition, events=_events_text(result.events),
                       states=result.states_table(label))
            if "represented" in seg.columns:
                row["unrepresented"] = "; ".join(
                    f"{r.segment} {r.phase} {r.t_start:.1f}-{r.t_end:.1f} s"
                    for r in seg.itertuples(index=False) if not r.represented)
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

    Parameters
    ----------
    log : str
        Log specification (path, or path with a reader).
    options : Mapping or None, optional
        Keywords of :func:`navlib.studies.assess.assess_flight`.
    """
    options = dict(options or {})
    read_options = options.pop("read_options", None) or {}

    def build(warning_texts):
        imu, gnss = read_log(log, **read_options)
        result = assess_flight(imu, gnss, **options)
        return result, flight_page(log, result, warning_texts())

    return summary_row(log, build)


def _task(log: str, options: Mapping) -> tuple[dict, str | None]:
    return assess_log(log, options)


def _checked_labels(labels, what: str) -> list:
    labels = list(labels)
    if not labels or not all(isinstance(x, str) for x in labels):
        raise NavlibInputError(f"{what}: expected one or more file names, got {labels!r}")
    return labels


def assess_logs(logs: Sequence[str], options: Mapping | None = None, scheduler=None,
                progress: bool = False) -> tuple[pd.DataFrame, list]:
    """Assess flights as Dask tasks (:func:`navlib.parallel.map_tasks`).

    ``options`` are keywords of :func:`navlib.studies.assess.assess_flight` (checked here,
    before any task runs) and ``read_options``, keywords of the log's reader
    (:func:`navlib.io.read_log`). Returns the summary table (one row per log, in order) and the
    HTML pages (None for failed flights).

    Parameters
    ----------
    logs : sequence of str
        Log specifications.
    options : Mapping or None, optional
        Keywords of :func:`navlib.studies.assess.assess_flight`.
    scheduler : optional
        Dask scheduler (:func:`navlib.parallel.map_tasks`).
    progress : bool, optional
        Show a progress bar.

    Raises
    ------
    NavlibInputError
        If ``options`` names an unknown keyword.
    """
    logs = _checked_labels(logs, "logs")
    options = dict(options or {})
    reject_unknown(options, (*_keywords(assess_flight, "imu", "gnss"), "read_options"),
                   "assess options (-p)")
    if not isinstance(options.get("read_options") or {}, Mapping):
        raise NavlibInputError(f"read_options: expected a mapping of reader keyword -> value "
                               f"(navlib.io.read_log), got {options['read_options']!r}")
    results = map_tasks(_task, logs, scheduler, shared={"options": options},
                        progress=progress, desc="flights")
    return _table([row for row, _ in results]), [page for _, page in results]


def plan_missions(missions: Sequence[str], options: Mapping | None = None,
                  flight: str | None = None) -> tuple[pd.DataFrame, list]:
    """Plan each mission file (in turn); returns the summary table (one row per mission)
    and the HTML pages (None for a mission that failed).

    ``options``: keywords of :func:`navlib.studies.plan.plan_mission`, checked before any
    mission runs; ``aiding`` may name several aidings (``"gnss,baro"``): each mission is then
    planned once per aiding, one row each (``log``: ``mission (aiding baro)``), so a rocket
    with and without a GNSS receiver is compared in one run. ``flight``: a recorded flight
    (a ``LOG``) assessed once with the plan's sensor preset and shown beside every plan
    (:func:`navlib.studies.plan.plan_beside_flight`), read with ``options["read_options"]``
    (keywords of its reader, :func:`navlib.io.read_log`).

    Parameters
    ----------
    missions : sequence of str
        Mission files.
    options : Mapping or None, optional
        Keywords of :func:`navlib.studies.plan.plan_mission`, and ``read_options`` for the
        flight's reader.
    flight : str or None, optional
        A recorded flight shown beside every plan.

    Raises
    ------
    NavlibInputError
        If ``options`` names an unknown keyword or ``read_options`` is not a mapping.
    """
    missions = _checked_labels(missions, "missions")
    options = dict(options or {})
    read_options = options.pop("read_options", None) or {}
    if not isinstance(read_options, Mapping):
        raise NavlibInputError(f"read_options: expected a mapping of reader keyword -> value "
                               f"(navlib.io.read_log), got {read_options!r}")
    reject_unknown(options, _keywords(plan_mission, "mission"), "plan options (-p)")
    aidings = _aidings(options.pop("aiding", None))
    flown = None
    if flight is not None:
        imu, gnss = read_log(flight, **read_options)
        flown = (flight, assess_flight(imu, gnss, preset=options.get("sensors_preset")))

    def row(mission: str, aiding: str | None) -> tuple[dict, str | None]:
        label = mission if len(aidings) == 1 else f"{mission} (aiding {aiding})"

        def build(warning_texts):
            plan = plan_mission(mission, **options, aiding=aiding)
            return plan, plan_page(label, plan, warning_texts(), flown)

        return summary_row(label, build)

    rows = [row(m, a) for m in missions for a in aidings]
    return _table([r for r, _ in rows]), [p for _, p in rows]


def _table(rows: list[dict]) -> pd.DataFrame:
    """The summary table of ``rows``; their states tables, stacked, in ``attrs["states"]``."""
    table = pd.DataFrame(rows, columns=list(SUMMARY_COLUMNS))
    states = [row["states"] for row in rows if row.get("states") is not None]
    table.attrs["states"] = (pd.concat(states, ignore_index=True) if states else
                             pd.DataFrame(columns=list(STATES_COLUMNS)))
    return table


def _aidings(value) -> list:
    """The ``aiding`` option of :func:`plan_missions`: None (each mission's own), one name, or
    several (a list, or names joined by commas: ``-p aiding gnss,baro``), each planned."""
    if value is None:
        return [None]
    names = value.split(",") if isinstance(value, str) else value
    if not isinstance(names, list | tuple) or not names or not all(
            isinstance(n, str) and n.strip() for n in names):
        raise NavlibInputError(f"aiding: expected gnss, baro, gnss+baro or several of them "
                               f"(gnss,baro), got {value!r}")
    return [n.strip() for n in names]


def _page_name(index: int, log: str) -> str:
    stem = Path(log.split(",")[0]).stem or "flight"
    safe = "".join(c if c.isalnum() or c in "-_" else "_" for c in stem)
    return f"{index + 1:03d}_{safe}.html"


def write_fleet(table: pd.DataFrame, pages: Sequence, output) -> Path:
    """Write ``output/summary.csv``, ``output/states.csv`` (the stacked states tables of
    ``table.attrs["states"]``, one row per log x segment x state, when present) and one HTML
    page per assessed flight or planned mission; returns the summary CSV.

    Parameters
    ----------
    table : pandas.DataFrame
        Summary table (``attrs["states"]`` optional).
    pages : sequence of str or None
        HTML page per row.
    output : pathlib.Path
        Output folder (created).
    """
    output = Path(output)
    output.mkdir(parents=True, exist_ok=True)
    table = table.copy()
    for i, (log, page) in enumerate(zip(table["log"], pages, strict=True)):
        if page is not None:
            name = _page_name(i, log)
            (output / name).write_text(page, encoding="utf-8")
            table.loc[i, "page"] = name
    path = output / "summary.csv"
    states = table.attrs.get("states")
    table.attrs = {}
    table.to_csv(path, index=False)
    if states is not None:
        states.to_csv(output / "states.csv", index=False)
    return path
