"""Run the workbook notebooks headlessly and publish them as HTML (the report command).

Contract: spec/api.md "Reports — command line". :func:`run_reports` executes every
``NN_*.ipynb`` of a notebooks folder with papermill (kernel ``python3``, always launched with
the interpreter running navlib, cwd = the notebooks folder so relative paths work), exports
each executed notebook to HTML with nbconvert (inputs shown) and writes an ``index.html``
linking the pages with their status and run time.

Publishing is all-or-nothing: pages are written to a staging folder next to the output
folder and swapped into place only when every selected notebook succeeded. On failure the
staging folder is deleted, the previous report stays untouched and :class:`ReportError`
names the notebook and the failing cell.

Output layout (flat, inside the output folder)::

    index.html            table: notebook, title, status, time, mode, parameters
    NN_name.html          the executed notebook as a static page (inputs shown)
    NN_name.ipynb         the executed notebook (papermill output, with parameters cell)
    manifest.json         machine-readable status of every page in the folder
    README*               any README already there is kept

A run restricted with ``only`` refreshes the selected pages and keeps the other pages of the
previous report (the index lists all of them, each with the date and mode it was made in);
a full run replaces the whole report (README files excepted).

Notebooks run one after the other, or up to ``jobs`` at once (each in its own kernel, on
a worker thread of the runner; the guarantees above hold for each, and Ctrl-C or SIGTERM
stops them all). Kernels are started with BLAS/OpenMP thread counts that share the cores
between them, and with ``NAVLIB_NO_CACHE=1`` when ``cache=False`` (:mod:`navlib.cache`).

Parameters: ``quick=True`` and explicit ``parameters`` are injected only into notebooks whose
tagged ``parameters`` cell assigns that name (so papermill never warns about unknown
parameters and ``-p imu_path x.csv`` reaches only the notebooks that read flight data); a
parameter that no selected notebook defines is rejected as a likely typo.
"""

from __future__ import annotations

import ast
import contextlib
import dataclasses
import datetime as _dt
import html
import json
import math
import os
import queue as queue_module
import re
import shutil
import signal
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from navlib.errors import NavlibInputError
from navlib.kernel_watch import KernelWatch, NotebookAborted, execute_notebook, kill_all_kernels
from navlib.resources import notebooks_dir, source_checkout

NOTEBOOK_PATTERN = re.compile(r"^(\d{2})_\w+\.ipynb$")
"""Notebooks taking part in the report: ``NN_name.ipynb`` (two digits, underscore)."""

MANIFEST = "manifest.json"
INDEX = "index.html"
_ANSI = re.compile(r"\x1b\[[0-9;]*[A-Za-z]")

DEFAULT_CELL_TIMEOUT_S = 600.0
"""Per-cell time limit of a report run, s: the heaviest full-mode cell takes about a minute
on an unloaded 2-core machine, so ten minutes only ever stops a runaway cell."""

_ABORT_NAMES = {"timeout": "CellTimeout", "stall": "KernelStalled", "died": "KernelDied"}


# --------------------------------------------------------------------------- results


@dataclass(frozen=True)
class NotebookInfo:
    """A report notebook found on disk.

    Attributes
    ----------
    name : str
        File stem, e.g. ``"07_assess_flight"``.
    path : Path
        Absolute path of the source notebook.
    title : str
        Text of the first markdown heading (the stem when there is none).
    parameters : dict
        Name -> default source text of each assignment in the tagged ``parameters`` cell
        (empty when the notebook has no such cell).
    after : tuple of str
        The notebook's metadata ``{"navlib": {"after": ["02", ...]}}`` (numbers or stems):
        in a run that includes them it starts only when they have finished (the claims
        summary ``00_claims`` after 02 and 05, whose results its studies then read from the
        disk cache, :mod:`navlib.cache`); others run beside it meanwhile.
    """

    name: str
    path: Path
    title: str
    parameters: dict[str, str] = field(default_factory=dict)
    after: tuple[str, ...] = ()


@dataclass(frozen=True)
class CellFailure:
    """Where and how a notebook failed.

    ``cell_index`` is the 0-based index in the *source* notebook (markdown cells count).
    ``-1`` marks a failure not located in a cell (kernel died, HTML export error).
    """

    cell_index: int
    ename: str
    evalue: str
    source: str = ""
    traceback: str = ""

    def describe(self) -> str:
        """One-line description: cell, first source line, exception."""
        if self.cell_index < 0:
            where = "outside a cell"
        else:
            first = next((ln.strip() for ln in self.source.splitlines() if ln.strip()), "")
            if len(first) > 60:
                first = first[:57] + "..."
            where = f"cell {self.cell_index} (0-based)" + (f" `{first}`" if first else "")
        return f"{where}: {self.ename}: {self.evalue}"


@dataclass(frozen=True)
class NotebookRun:
    """Outcome of executing one notebook.

    Attributes
    ----------
    name : str
        Notebook stem.
    status : str
        ``"ok"`` or ``"failed"`` (in progress calls only: ``"restarting"`` announcing a
        restart after a stall, ``"stopped"`` for a run cut short because another notebook
        failed under ``fail_fast``).
    seconds : float
        Wall time of the papermill execution (kernel start included), s.
    parameters : dict
        The parameters injected into this notebook.
    html : str or None
        File name of the HTML page inside the output folder (None when failed).
    ipynb : str or None
        File name of the executed notebook inside the output folder (None when failed).
    failure : CellFailure or None
        Set when ``status == "failed"``.
    stalls : tuple of str
        Stalls met on the way (each ended by killing the kernel); a run that stalled once
        and then succeeded is ``ok`` with one entry here.
    lost_wakeups : int
        Kernel messages whose ZeroMQ wake-up never came, found when a 0.25 s poll slice
        expired (recovered, not stalls; see :mod:`navlib.kernel_watch`).
    """

    name: str
    status: str
    seconds: float
    parameters: dict[str, object]
    html: str | None = None
    ipynb: str | None = None
    failure: CellFailure | None = None
    title: str = ""
    stalls: tuple[str, ...] = ()
    lost_wakeups: int = 0

    @property
    def ok(self) -> bool:
        return self.status == "ok"


class ReportInterrupted(BaseException):
    """The run was interrupted (Ctrl-C or SIGTERM; a BaseException, like KeyboardInterrupt,
    so no handler of ordinary errors swallows it); its kernels were stopped, its staging
    folder removed and the previous report left untouched. ``signum`` names the signal."""

    def __init__(self, signum: int):
        self.signum = int(signum)
        super().__init__(f"interrupted by {signal.Signals(self.signum).name}: kernels "
                         "stopped, nothing published, the previous report was left untouched")


class ReportError(RuntimeError):
    """At least one notebook failed; nothing was published.

    ``runs`` holds every :class:`NotebookRun` that ran to its end (in name order), failed
    ones with their :class:`CellFailure`; runs stopped because of ``fail_fast`` are left
    out.
    """

    def __init__(self, runs: Sequence[NotebookRun]):
        self.runs = list(runs)
        failed = [r for r in self.runs if not r.ok]
        lines = [f"{len(failed)} notebook(s) failed; the previous report was left untouched"]
        lines += [f"  {r.name}: {r.failure.describe()}" for r in failed if r.failure]
        super().__init__("\n".join(lines))


Progress = Callable[[int, int, str, "NotebookRun | None"], None]
"""``progress(position, total, name, run)``: called with ``run=None`` when notebook number
``position`` (1-based, in the order notebooks start) starts and with its
:class:`NotebookRun` when it ends; always from the thread that called :func:`run_reports`,
also when several notebooks run at once (their events then interleave)."""


# --------------------------------------------------------------------------- discovery


def _parameter_defaults(nb) -> dict[str, str]:
    """Name -> default source text of the assignments in the tagged ``parameters`` cell."""
    for cell in nb.cells:
        if cell.cell_type == "code" and "parameters" in cell.get("metadata", {}).get("tags", []):
            source = cell.source
            try:
                tree = ast.parse(source)
            except SyntaxError:
                return {}
            out: dict[str, str] = {}
            for node in tree.body:
                targets = node.targets if isinstance(node, ast.Assign) else (
                    [node.target] if isinstance(node, ast.AnnAssign) and node.value else [])
                for target in targets:
                    if isinstance(target, ast.Name):
                        out[target.id] = ast.get_source_segment(source, node.value) or ""
            return out
    return {}


def _title(nb, fallback: str) -> str:
    for cell in nb.cells:
        if cell.cell_type == "markdown":
            for line in cell.source.splitlines():
                if line.startswith("#"):
                    return line.lstrip("#").strip()
    return fallback


def _read_notebook(path: Path):
    import nbformat

    try:
        return nbformat.read(path, as_version=4)
    except Exception as exc:  # nbformat raises several unrelated types for bad files
        raise NavlibInputError(f"notebook {path}: cannot be read ({exc})") from exc


def list_notebooks(notebooks_dir) -> list[NotebookInfo]:
    """The report notebooks (``NN_*.ipynb``) of ``notebooks_dir``, sorted by name."""
    folder = Path(notebooks_dir)
    if not folder.is_dir():
        raise NavlibInputError(f"notebooks_dir: {folder} is not a folder")
    infos = []
    for path in sorted(folder.iterdir()):
        if path.is_file() and NOTEBOOK_PATTERN.match(path.name):
            nb = _read_notebook(path)
            after = nb.metadata.get("navlib", {}).get("after", ())
            if isinstance(after, str) or not all(isinstance(a, str) for a in after):
                raise NavlibInputError(f"notebook {path}: metadata navlib.after must be a "
                                       f"list of notebook names or numbers, got {after!r}")
            infos.append(NotebookInfo(path.stem, path.resolve(), _title(nb, path.stem),
                                      _parameter_defaults(nb), tuple(after)))
    return infos


def _matching(entry, available: Sequence[NotebookInfo]) -> list[str]:
    """Names of the notebooks an ``--only`` entry selects (stem, ``NN`` prefix, file name
    or path)."""
    key = Path(str(entry)).name.removesuffix(".ipynb")
    return [nb.name for nb in available
            if nb.name == key or (key.isdigit() and int(nb.name[:2]) == int(key))]


def _dependencies(info: NotebookInfo, selected: Sequence[NotebookInfo]) -> set[str]:
    """The notebooks of ``selected`` that ``info`` starts after (its ``after`` entries
    matched as ``--only`` entries; entries matching none are ignored)."""
    return {name for entry in info.after for name in _matching(entry, selected)
            if name != info.name}


def select_notebooks(available: Sequence[NotebookInfo],
                     only: Iterable[str] | None) -> list[NotebookInfo]:
    """Filter ``available`` by ``only`` entries (stem, ``NN`` prefix, file name or path).

    Raises NavlibInputError listing the available notebooks for an entry matching none.
    """
    if only is None:
        return list(available)
    only = [only] if isinstance(only, str) else list(only)
    wanted: set[str] = set()
    for entry in only:
        hits = _matching(entry, available)
        if not hits:
            names = ", ".join(nb.name for nb in available) or "(none)"
            raise NavlibInputError(
                f"only: no notebook matches {entry!r}; available: {names}")
        wanted.update(hits)
    return [nb for nb in available if nb.name in wanted]


# --------------------------------------------------------------------------- parameters


def parse_parameter_value(text: str):
    """A ``-p`` value: a JSON or Python literal when it parses as one, else the string.

    ``2.5`` -> float, ``true``/``True`` -> bool, ``[1, 2]`` -> list, ``null``/``None`` ->
    None, ``Churchill`` -> ``"Churchill"``. Text that starts like a container (``[ { (``) but
    does not parse raises NavlibInputError rather than silently becoming a string.
    """
    for parse in (json.loads, ast.literal_eval):
        try:
            return parse(text)
        except (ValueError, SyntaxError, TypeError, MemoryError, RecursionError):
            pass
    if text.strip()[:1] in "[{(" and text.strip():
        raise NavlibInputError(f"parameter value {text!r}: looks like a list/dict/tuple but "
                               "does not parse as JSON or a Python literal")
    return text


def parse_parameters(pairs: Iterable[Sequence[str]], cwd=None) -> dict[str, object]:
    """Turn ``-p key value`` pairs into a parameter dict.

    Values go through :func:`parse_parameter_value`. A string value naming an existing file
    or folder relative to ``cwd`` (default: the current directory) is made absolute, because
    notebooks run with the notebooks folder as their working directory. A parameter whose
    name ends in ``_path`` must name an existing file or folder: a missing one is refused
    here, naming the folder it was looked up in, rather than inside the notebook.
    """
    base = Path.cwd() if cwd is None else Path(cwd)
    out: dict[str, object] = {}
    for pair in pairs:
        if len(pair) != 2:
            raise NavlibInputError(f"parameter: expected 'key value', got {list(pair)}")
        key, text = pair
        if not key.isidentifier():
            hint = ""
            if "=" in key:
                k, _, v = key.partition("=")
                hint = f" (write: -p {k} {v})"
            raise NavlibInputError(
                f"parameter name {key!r}: must be a Python identifier{hint}")
        value = parse_parameter_value(text)
        if isinstance(value, str) and value:
            candidate = Path(value) if Path(value).is_absolute() else base / value
            if candidate.exists():
                value = str(candidate.resolve())
            elif key.endswith("_path"):
                raise NavlibInputError(
                    f"parameter {key}: {value!r} not found (looked in {candidate.parent})")
        out[key] = value
    return out


def _parameters_for(info: NotebookInfo, quick: bool,
                    parameters: Mapping[str, object]) -> dict[str, object]:
    chosen: dict[str, object] = {}
    if quick and "quick" in info.parameters:
        chosen["quick"] = True
    chosen.update({k: v for k, v in parameters.items() if k in info.parameters})
    return chosen


# --------------------------------------------------------------------------- execution


def _failure_from(exc: BaseException, executed_path: Path, source_nb) -> CellFailure:
    """Map a papermill error, an aborted run or any other error to a CellFailure.

    The failing cell is located by its error output in the saved executed notebook (papermill
    adds its injected-parameters cell and error banners, so indices differ) and mapped to
    the source notebook through its cell id, or by source text if ids are missing.
    """
    import nbformat
    from papermill.exceptions import PapermillExecutionError

    if not isinstance(exc, PapermillExecutionError | NotebookAborted):
        return CellFailure(-1, type(exc).__name__, str(exc))
    index = -1
    failing = None
    try:
        executed = nbformat.read(executed_path, as_version=4)
        failing = next(c for c in executed.cells if c.cell_type == "code"
                       and any(o.get("output_type") == "error" for o in c.get("outputs", [])))
        ids = [c.get("id") for c in source_nb.cells]
        if failing.get("id") in ids:
            index = ids.index(failing.get("id"))
    except (OSError, StopIteration, ValueError):
        pass
    source = getattr(exc, "source", None) or (failing.source if failing else "")
    if index < 0:
        sources = [c.source for c in source_nb.cells]
        index = sources.index(source) if source in sources else -1
    if isinstance(exc, NotebookAborted):
        return CellFailure(index, _ABORT_NAMES[exc.kind], str(exc), source)
    tb = _ANSI.sub("", "\n".join(exc.traceback or []))
    return CellFailure(index, exc.ename, exc.evalue, source, tb)


def _export_html(executed_path: Path, html_path: Path, title: str) -> None:
    """The executed notebook as a static page; widget outputs (the panels) are replaced by
    the HTML of their final state (:func:`navlib.widgets.static.freeze_widgets`: last
    figures as inline PNG, settings as text), so the page needs no kernel, no widget
    script and no network to show them."""
    import nbformat
    from nbconvert import HTMLExporter

    from navlib.widgets.static import freeze_widgets

    nb = nbformat.read(executed_path, as_version=4)
    freeze_widgets(nb)
    exporter = HTMLExporter(template_name="lab", exclude_input=False)
    body, _ = exporter.from_notebook_node(nb, resources={"metadata": {"name": title}})
    html_path.write_text(body, encoding="utf-8")


_STOPPED = "stopped: another notebook failed and fail_fast was set"
_EVENT_WAIT_S = 0.25  # the main thread's wait for worker events (signals are handled between)
_JOIN_S = 30.0  # how long stopped workers get to finish after their kernels were killed
BLAS_THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
"""Thread-count variables :func:`kernel_environment` sets for each kernel."""

MALLOC_VARIABLES = {"MALLOC_MMAP_THRESHOLD_": "1073741824", "MALLOC_TRIM_THRESHOLD_": "1073741824"}
"""glibc allocator settings :func:`kernel_environment` gives each kernel: arrays below 1 GiB
come from the heap and freed memory up to 1 GiB stays there, so the next array of a
recursion or a study reuses it instead of a fresh ``mmap`` whose pages fault in again (the
default returns every array above 32 MB to the system). On the 2-core reference machine a
page fault of a fresh array cost about 0.2 ms: notebook 05 spent 33 of its 108 s in the
kernel (system time) by default and 10 of 82 s with these, for about 0.2 GB more peak
memory (1.98 GB in the report kernel). Other C libraries ignore them."""


def available_cpus() -> int:
    """CPUs this process may run on (its affinity mask where the platform has one)."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def kernel_environment(jobs: int, cache: bool = True) -> dict[str, str]:
    """Variables added to each kernel's environment when ``jobs`` kernels run at once.

    Each BLAS/OpenMP pool gets ``max(1, cpus // jobs)`` threads so the kernels together do
    not oversubscribe the cores, and the allocator keeps freed arrays for reuse
    (:data:`MALLOC_VARIABLES`); a variable already set in this process's environment is
    left to the user. ``cache=False`` adds ``NAVLIB_NO_CACHE=1`` (:mod:`navlib.cache`).
    """
    threads = str(max(1, available_cpus() // max(1, jobs)))
    wanted = {**dict.fromkeys(BLAS_THREAD_VARIABLES, threads), **MALLOC_VARIABLES}
    env = {name: value for name, value in wanted.items() if not os.environ.get(name)}
    if not cache:
        env["NAVLIB_NO_CACHE"] = "1"
    return env


@dataclass(frozen=True)
class _Settings:
    """What every notebook of one run is executed with."""

    quick: bool
    parameters: Mapping[str, object]
    fail_fast: bool
    timeout_s: float | None
    jobs: int
    env: Mapping[str, str]


class _Kernels:
    """The kernel watches of one run: :meth:`stop` kills the running kernels and refuses
    new ones (a kernel launched while it runs is killed by its watch as it starts)."""

    def __init__(self):
        self._lock = threading.Lock()
        self._watches: set[KernelWatch] = set()
        self.stopped = False

    def watch(self) -> KernelWatch | None:
        """A new watch for the next kernel (None once the run is stopped)."""
        with self._lock:
            if self.stopped:
                return None
            watch = KernelWatch()
            self._watches.add(watch)
            return watch

    def release(self, watch: KernelWatch) -> None:
        with self._lock:
            self._watches.discard(watch)

    def stop(self) -> None:
        with self._lock:
            self.stopped = True
            watches = list(self._watches)
        for watch in watches:
            watch.stop()
            watch.kill_kernel()

    def stop_if_running(self, workers: Sequence[threading.Thread]) -> None:
        """After the run (or on its way out through an exception): stop what still runs
        and give the workers :data:`_JOIN_S` to return."""
        if any(w.is_alive() for w in workers):
            self.stop()
        deadline = time.monotonic() + _JOIN_S
        for worker in workers:
            if worker.ident is not None:
                worker.join(max(0.0, deadline - time.monotonic()))


def _execute(info: NotebookInfo, staging: Path, params: dict, settings: _Settings,
             kernels: _Kernels, on_restart: Callable[[CellFailure], None] | None = None
             ) -> NotebookRun:
    """Run one notebook; a stalled kernel gets one restart of the whole notebook. A run cut
    short by :meth:`_Kernels.stop` (another notebook failed under ``fail_fast``) is
    ``"stopped"``."""
    executed = staging / f"{info.name}.ipynb"
    source_nb = _read_notebook(info.path)
    start = time.perf_counter()
    stalls: list[str] = []
    lost = 0

    def ended(status: str, failure: CellFailure | None = None, seconds: float | None = None,
              **pages) -> NotebookRun:
        seconds = time.perf_counter() - start if seconds is None else seconds
        return NotebookRun(info.name, status, seconds, params, failure=failure,
                           title=info.title, stalls=tuple(stalls), lost_wakeups=lost, **pages)

    for attempt in (1, 2):
        watch = kernels.watch()
        if watch is None:
            return ended("stopped", CellFailure(-1, "Stopped", _STOPPED))
        try:
            execute_notebook(info.path, executed, parameters=params, cwd=info.path.parent,
                             timeout_s=settings.timeout_s, watch=watch, env=settings.env)
        except Exception as exc:  # any failure of the run is reported, not raised
            lost += watch.lost_wakeups
            failure = _failure_from(exc, executed, source_nb)
            if kernels.stopped:
                return ended("stopped", dataclasses.replace(failure, evalue=_STOPPED))
            stalled = isinstance(exc, NotebookAborted) and exc.kind == "stall"
            if stalled and attempt == 1:
                stalls.append(failure.describe())
                if on_restart:
                    on_restart(failure)
                continue
            if stalled:
                failure = dataclasses.replace(failure, evalue=f"{failure.evalue} (also on the "
                                              "first run, before the kernel was restarted)")
            return ended("failed", failure)
        finally:
            kernels.release(watch)
        lost += watch.lost_wakeups
        break
    seconds = time.perf_counter() - start
    try:
        _export_html(executed, staging / f"{info.name}.html", info.title)
    except Exception as exc:  # nbconvert errors are varied; report them as a failed page
        return ended("failed", CellFailure(-1, type(exc).__name__, f"HTML export: {exc}"),
                     seconds)
    return ended("ok", None, seconds, html=f"{info.name}.html", ipynb=f"{info.name}.ipynb")


# --------------------------------------------------------------------------- publishing


def _check_output_dir(output: Path, notebooks_dir: Path) -> None:
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


def _load_manifest(output: Path) -> dict:
    try:
        data = json.loads((output / MANIFEST).read_text(encoding="utf-8"))
        return data if isinstance(data, dict) else {}
    except (OSError, ValueError):
        return {}


def _entry(run: NotebookRun, finished: str) -> dict:
    return {"title": run.title, "status": run.status, "seconds": round(run.seconds, 3),
            "quick": run.parameters.get("quick") is True,
            "parameters": {k: repr(v) for k, v in run.parameters.items()},
            "html": run.html, "ipynb": run.ipynb, "finished": finished}


def _index_html(entries: Mapping[str, dict], generated: str) -> str:
    from navlib import __version__

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
body {{ font-family: system-ui, sans-serif; margin: 2em; }}
table {{ border-collapse: collapse; }}
th, td {{ border-bottom: 1px solid #ccc; padding: 0.3em 0.8em; text-align: left; }}
td.num {{ text-align: right; }} tr.failed {{ background: #fdd; }}
</style></head><body>
<h1>navlib reports</h1>
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


def _publish(staging: Path, output: Path, runs: Sequence[NotebookRun], partial: bool) -> None:
    """Carry over what stays of the old report, write index + manifest, swap in.

    A ``partial`` run (``only`` given) keeps the other pages of the old report; a full run
    keeps only README files, so pages of deleted or renamed notebooks disappear.
    """
    finished = _dt.datetime.now(_dt.UTC).strftime("%Y-%m-%d %H:%M:%S UTC")
    old_entries: dict = {}
    if output.is_dir():
        old_entries = _load_manifest(output).get("notebooks", {}) if partial else {}
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
    entries.update({r.name: _entry(r, finished) for r in runs})
    manifest = {"generator": "navlib report", "generated": finished, "notebooks": entries}
    (staging / MANIFEST).write_text(json.dumps(manifest, indent=1), encoding="utf-8")
    (staging / INDEX).write_text(_index_html(entries, finished), encoding="utf-8")

    if not output.exists():
        os.replace(staging, output)
        return
    retired = Path(tempfile.mkdtemp(prefix=f".{output.name}.old-", dir=output.parent))
    retired.rmdir()
    with _signals_deferred():  # an interrupt between the two renames would lose the report
        os.replace(output, retired)
        try:
            os.replace(staging, output)
        except OSError:
            os.replace(retired, output)  # put the good report back
            raise
    shutil.rmtree(retired, ignore_errors=True)


def run_reports(notebooks_dir, output_dir, *, quick: bool = False,
                only: Iterable[str] | None = None,
                parameters: Mapping[str, object] | None = None,
                progress: Progress | None = None, fail_fast: bool = False,
                timeout_s: float | None = DEFAULT_CELL_TIMEOUT_S, jobs: int = 1,
                cache: bool = True) -> list[NotebookRun]:
    """Execute the report notebooks and publish them into ``output_dir``.

    Parameters
    ----------
    notebooks_dir : path
        Folder holding ``NN_*.ipynb``; it is also the notebooks' working directory.
    output_dir : path
        Report folder; created, or replaced on success (see module docstring: a run with
        ``only`` keeps the other pages, a full run keeps only README files).
    quick : bool
        Inject ``quick=True`` (into notebooks that define ``quick``).
    only : iterable of str, optional
        Notebook stems or ``NN`` prefixes (see :func:`select_notebooks`).
    parameters : mapping, optional
        Extra parameters, each injected into the notebooks whose parameters cell defines it;
        they override ``quick``.
    progress : callable, optional
        See :data:`Progress`.
    fail_fast : bool
        Stop at the first failing notebook instead of running the rest (notebooks running
        alongside it are stopped; they are left out of the returned runs).
    timeout_s : float or None
        Per-cell time limit, s (default :data:`DEFAULT_CELL_TIMEOUT_S`; None: no limit). A
        cell over the limit fails the notebook. Independently of it, a kernel that stops
        answering (idle without replying, or never starting a cell) is a stall: the kernel
        is killed and the notebook re-run once, then the notebook fails
        (:mod:`navlib.kernel_watch`).
    jobs : int
        Notebooks run at once, each in its own kernel (capped at the number selected; 1:
        one after the other, in name order). Longest first, by the times in the output
        folder's previous manifest (or that of :func:`default_output_dir`; name order
        without one); each kernel gets
        ``cpus // jobs`` BLAS/OpenMP threads (:func:`kernel_environment`).
    cache : bool
        False: the kernels run with ``NAVLIB_NO_CACHE=1``, so every trajectory and model
        is rebuilt and nothing is stored (:mod:`navlib.cache`).

    Returns
    -------
    list of NotebookRun
        One per selected notebook, in name order; all ``ok``.

    Raises
    ------
    NavlibInputError
        Unknown ``only`` entry, parameter defined by no selected notebook, bad folders.
    ReportError
        A notebook failed; the output folder was not touched.
    ReportInterrupted
        Ctrl-C or SIGTERM (when called from the main thread): the kernels were stopped, the
        staging folder removed, the output folder not touched.
    """
    notebooks = Path(notebooks_dir).resolve()
    output = Path(output_dir).resolve()
    parameters = dict(parameters or {})
    for key in parameters:
        if not isinstance(key, str) or not key.isidentifier():
            raise NavlibInputError(f"parameters: name {key!r} is not a Python identifier")
    if timeout_s is not None and not timeout_s > 0:
        raise NavlibInputError(f"timeout_s: must be > 0 s, got {timeout_s}")
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise NavlibInputError(f"jobs: expected a whole number >= 1, got {jobs!r}")
    selected = select_notebooks(list_notebooks(notebooks), only)
    if not selected:
        raise NavlibInputError(f"notebooks_dir: no NN_*.ipynb notebooks in {notebooks}")
    defined = set().union(*(nb.parameters for nb in selected))
    unknown = sorted(set(parameters) - defined)
    if unknown:
        raise NavlibInputError(
            f"parameters: {unknown} defined by none of the selected notebooks; "
            f"their parameters are {sorted(defined)}")
    _check_output_dir(output, notebooks)
    output.parent.mkdir(parents=True, exist_ok=True)

    jobs = min(jobs, len(selected))
    settings = _Settings(quick, parameters, fail_fast, timeout_s, jobs,
                         kernel_environment(jobs, cache))
    queue = _queue_order(selected, output) if jobs > 1 else list(selected)
    _remove_orphaned_staging(output)
    staging = Path(tempfile.mkdtemp(prefix=f".{output.name}.tmp-{os.getpid()}-",
                                    dir=output.parent))
    umask = os.umask(0)
    os.umask(umask)
    staging.chmod(0o777 & ~umask)  # mkdtemp makes it private; a report folder is not
    try:
        with _signals_interrupt():
            if jobs > 1:
                _compile_kernels()
            runs = _run_all(selected, queue, staging, settings, progress)
            _publish(staging, output, runs, partial=only is not None)
        return runs
    except (ReportInterrupted, KeyboardInterrupt):
        kill_all_kernels()
        raise
    finally:
        if staging.exists():
            shutil.rmtree(staging, ignore_errors=True)


def _compile_kernels() -> None:
    """Compile navlib's numba kernels (or load them from numba's disk cache) before kernels
    that run at once start: otherwise each of them compiles the same kernels on a machine's
    first run (README "Compiled kernels")."""
    # imported here: the runner itself needs neither numba nor NumPy otherwise
    from navlib.filters.linear import compile_kernels

    compile_kernels()


def _remove_orphaned_staging(output: Path) -> None:
    """Delete staging folders of earlier runs whose process is gone (killed with SIGKILL,
    which no handler can catch). A folder is named ``.NAME.tmp-PID-xxxx`` by its run."""
    import psutil

    for folder in output.parent.glob(f".{output.name}.tmp-*"):
        pid = folder.name.removeprefix(f".{output.name}.tmp-").split("-")[0]
        if folder.is_dir() and pid.isdigit() and not psutil.pid_exists(int(pid)):
            shutil.rmtree(folder, ignore_errors=True)


def _queue_order(selected: Sequence[NotebookInfo], output: Path) -> list[NotebookInfo]:
    """Longest first, by the ``seconds`` of the previous manifest in ``output`` or, when it
    has none (a new folder), in :func:`default_output_dir` (the last ``make report``);
    notebooks it does not time come first, in name order (they may be long). A notebook
    that starts :attr:`~NotebookInfo.after` others comes after them."""
    entries: dict = {}
    for folder in (output, default_output_dir()):
        entries = _load_manifest(folder).get("notebooks", {})
        if entries:
            break

    def seconds(info: NotebookInfo) -> float:
        entry = entries.get(info.name)
        try:
            return float(entry["seconds"])
        except (TypeError, KeyError, ValueError):
            return math.inf

    return sorted(selected, key=lambda info: (bool(_dependencies(info, selected)),
                                              -seconds(info)))  # stable: ties by name


class _Pending:
    """The queue of :func:`_run_all`: each worker takes the first notebook whose
    :func:`_dependencies` have finished, waiting while none is ready."""

    def __init__(self, queue: Sequence[NotebookInfo]):
        self._items = list(queue)
        self._waits = {info.name: _dependencies(info, queue) for info in queue}
        self._finished: set[str] = set()
        self._running = self._started = 0
        self._ready = threading.Condition()

    def take(self, stopped: Callable[[], bool]):
        """``(position, info)`` of the next notebook (position: its rank among the started
        ones), or ``(0, None)`` when none is left or ``stopped()``. A notebook whose
        dependencies can never finish (a cycle) is taken when nothing else runs."""
        with self._ready:
            while self._items and not stopped():
                ready = [i for i, info in enumerate(self._items)
                         if self._waits[info.name] <= self._finished]
                if ready or not self._running:
                    self._running += 1
                    self._started += 1
                    return self._started, self._items.pop(ready[0] if ready else 0)
                self._ready.wait(_EVENT_WAIT_S)
            return 0, None

    def finished(self, info: NotebookInfo) -> None:
        with self._ready:
            self._running -= 1
            self._finished.add(info.name)
            self._ready.notify_all()


def _run_all(selected: Sequence[NotebookInfo], queue: Sequence[NotebookInfo], staging: Path,
             settings: _Settings, progress: Progress | None) -> list[NotebookRun]:
    """Execute the notebooks of ``queue`` (in that order) on ``settings.jobs`` worker
    threads into ``staging``; their runs in the order of ``selected``, or ReportError
    with them unless all are ok.

    Only the calling thread reports progress (workers post their events to it), so
    progress lines never interleave mid-line and Ctrl-C / SIGTERM reach it while it
    waits. On any exception here (an interrupt included) the kernels are stopped and the
    workers joined before it propagates, so nothing writes into ``staging`` afterwards.
    """
    events: queue_module.SimpleQueue = queue_module.SimpleQueue()
    kernels = _Kernels()
    pending = _Pending(queue)
    total = len(queue)

    def work():
        while not kernels.stopped:
            position, info = pending.take(lambda: kernels.stopped)
            if info is None:
                return
            params = _parameters_for(info, settings.quick, settings.parameters)

            def restarting(failure, position=position, info=info, params=params):
                events.put((position, info.name, NotebookRun(
                    info.name, "restarting", 0.0, params, failure=failure)))

            events.put((position, info.name, None))
            try:
                run = _execute(info, staging, params, settings, kernels, restarting)
            except Exception as exc:  # a runner bug must not leave the main thread waiting
                run = NotebookRun(info.name, "failed", 0.0, params, title=info.title,
                                  failure=CellFailure(-1, type(exc).__name__, str(exc)))
            if settings.fail_fast and run.status == "failed":
                kernels.stop()  # before this worker could take the next notebook
            events.put((position, info.name, run))
            pending.finished(info)

    workers = [threading.Thread(target=work, name=f"report-worker-{k}", daemon=True)
               for k in range(settings.jobs)]
    runs: list[NotebookRun] = []
    try:
        for worker in workers:
            worker.start()
        while any(w.is_alive() for w in workers) or not events.empty():
            try:
                position, name, run = events.get(timeout=_EVENT_WAIT_S)
            except queue_module.Empty:
                continue
            if progress:
                progress(position, total, name, run)
            if run is not None and run.status in ("ok", "failed"):
                runs.append(run)
    finally:
        kernels.stop_if_running(workers)
    names = [info.name for info in selected]
    runs.sort(key=lambda run: names.index(run.name))
    if not all(r.ok for r in runs):
        raise ReportError(runs)
    return runs


@contextlib.contextmanager
def _signals_deferred():
    """Hold SIGINT and SIGTERM until the block ends (they are then delivered)."""
    held = {signal.SIGINT, signal.SIGTERM}
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, held)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


@contextlib.contextmanager
def _signals_interrupt():
    """Turn SIGINT and SIGTERM into :class:`ReportInterrupted` (main thread only; elsewhere
    signals cannot be handled and this does nothing)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def interrupt(signum, _frame):
        raise ReportInterrupted(signum)

    previous = {sig: signal.signal(sig, interrupt) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


def default_notebooks_dir() -> Path:
    """The shipped notebooks (``notebooks/`` of a source checkout, or the installed copy)."""
    return notebooks_dir()


def default_output_dir() -> Path:
    """``reports/`` of the source checkout; for an installed wheel, ``reports/`` in the
    current folder (never inside the installed package)."""
    checkout = source_checkout()
    return (checkout if checkout is not None else Path.cwd()) / "reports"
