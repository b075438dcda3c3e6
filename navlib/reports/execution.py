"""Executing one report notebook: papermill under the kernel watch, failures located, HTML.

Each notebook runs in its own kernel (launched with the interpreter running navlib, cwd =
the notebooks folder so relative paths work) through
:func:`~navlib.reports.kernel_watch.execute_notebook`; a stalled kernel gets one restart of
the whole notebook. The executed notebook is exported to HTML with nbconvert (outputs and
markdown only: no code inputs).
Kernels are started with BLAS/OpenMP thread counts that share the cores between the
notebooks running at once, and with ``NAVLIB_NO_CACHE=1`` when the run does not use the
cache (:mod:`navlib.cache`).
"""

from __future__ import annotations

import dataclasses
import os
import re
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from navlib.reports.discovery import NotebookInfo, notebook_format, read_notebook
from navlib.reports.kernel_watch import KernelWatch, NotebookAborted, execute_notebook
from navlib.reports.results import CellFailure, NotebookRun

__all__ = ["BLAS_THREAD_VARIABLES", "DEFAULT_CELL_TIMEOUT_S", "HIDE_OUTPUT_TAG", "HIDE_TAG",
           "HUGEPAGE_VARIABLES", "MALLOC_VARIABLES", "PAGE_CSS", "Kernels", "Settings",
           "available_cpus", "execute", "kernel_environment"]

DEFAULT_CELL_TIMEOUT_S = 600.0
"""Per-cell time limit of a report run, s: the heaviest full-mode cell takes about a minute
on an unloaded 2-core machine, so ten minutes only ever stops a runaway cell."""

_ANSI = re.compile(r"\x1b\[[0-9;]*[A-Za-z]")
_ABORT_NAMES = {"timeout": "CellTimeout", "stall": "KernelStalled", "died": "KernelDied"}


def _failure_from(exc: BaseException, executed_path: Path, source_nb) -> CellFailure:
    """Map a papermill error, an aborted run or any other error to a CellFailure.

    The failing cell is located by its error output in the saved executed notebook (papermill
    adds its injected-parameters cell and error banners, so indices differ) and mapped to
    the source notebook through its cell id, or by source text if ids are missing.
    """
    # the notebook stack (nbformat, papermill) loads only when a notebook runs, not on
    # ``import navlib.reports`` (the assess, plan and sweep commands import it too)
    nbformat = notebook_format()
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


HIDE_TAG = "report-hide"
"""Cell tag: the cell (input and outputs) is left off the report page (kept in the executed
notebook)."""
HIDE_OUTPUT_TAG = "report-hide-output"
"""Cell tag: the cell's outputs (e.g. internal timings) are left off the report page."""

PAGE_CSS = """
body { max-width: 1200px; margin: 0 auto; }
:root { --jp-content-font-size1: 16px; --jp-ui-font-size1: 14px; --jp-code-font-size: 14px;
        --jp-content-line-height: 1.5; }
.jp-RenderedHTMLCommon table { font-size: 14px; }
.jp-RenderedHTMLCommon td, .jp-RenderedHTMLCommon th { max-width: 40em; white-space: normal;
        vertical-align: top; }
.jp-OutputArea-output { overflow-x: auto; }
.jp-OutputArea-output img, .navlib-static img { max-width: 100%; height: auto; }
.jp-OutputArea-output pre { font-size: 14px; }
"""
"""Style added to every report page: content at most 1200 px wide, text at 16 px and
tables at 14 px (JupyterLab's 12-13 px are small at 100 % zoom), table cells wrapping
instead of running off the page, and images never wider than the page, always at their
own aspect ratio (``height: auto``)."""


def _export_html(executed_path: Path, html_path: Path, title: str) -> None:
    """The executed notebook as a static page of its results: code inputs and prompts are
    left out (the executed notebook keeps them), and so are the cells tagged
    :data:`HIDE_TAG` and the outputs of cells tagged :data:`HIDE_OUTPUT_TAG`. Widget
    outputs (the panels) are replaced by the HTML of their final state
    (:func:`navlib.widgets.static.freeze_widgets`: last figures as inline PNG, settings as
    text), so the page needs no kernel, no widget script and no network to show them. The
    page gets :data:`PAGE_CSS`."""
    # nbconvert and the widget stack (ipywidgets, matplotlib) are heavy: loaded only when
    # a page is exported
    nbformat = notebook_format()
    from nbconvert import HTMLExporter
    from nbconvert.preprocessors import TagRemovePreprocessor

    from navlib.widgets.static import freeze_widgets

    nb = nbformat.read(executed_path, as_version=4)
    freeze_widgets(nb)
    exporter = HTMLExporter(template_name="lab", exclude_input=True,
                            exclude_input_prompt=True, exclude_output_prompt=True)
    exporter.register_preprocessor(TagRemovePreprocessor(
        remove_cell_tags={HIDE_TAG}, remove_all_outputs_tags={HIDE_OUTPUT_TAG}), enabled=True)
    body, _ = exporter.from_notebook_node(nb, resources={"metadata": {"name": title}})
    body = body.replace("</head>", f"<style>{PAGE_CSS}</style>\n</head>", 1)
    html_path.write_text(body, encoding="utf-8")


_STOPPED = "stopped: another notebook failed and fail_fast was set"
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

HUGEPAGE_VARIABLES = {"NUMPY_MADVISE_HUGEPAGE": "0"}
"""NumPy setting :func:`kernel_environment` gives each kernel: no ``madvise(MADV_HUGEPAGE)``
on large arrays, so their memory comes in 4 KiB pages. On the 2-core reference machine (a
virtual machine that hands freed memory back to its host) the first touch of fresh huge
pages cost 2.5-4.4 s per GB in the kernel against 0.4 s for 4 KiB pages: with the report's
environment, notebook 05 took 21.3-21.5 CPU-s (system 1.7-2.0) without huge pages and
23.8-24.8 (system 5.0-5.7) with them, notebook 02 54.1 against 55.5, notebook 00 the same
(2026-12-05, load 2-3); run by ``navlib report --only 05``, 26.3-27.0 s of kernel time
(system 1.4 s) against 29.6-31.7 (system 5.4-5.9), runs alternated. The results do not
depend on it. Panels do the same in their own process
(:func:`navlib.widgets.memory.keep_pages`)."""


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
    (:data:`MALLOC_VARIABLES`) in small pages (:data:`HUGEPAGE_VARIABLES`); a variable already
    set in this process's environment is left to the user. ``cache=False`` adds
    ``NAVLIB_NO_CACHE=1`` (:mod:`navlib.cache`).
    """
    threads = str(max(1, available_cpus() // max(1, jobs)))
    wanted = {**dict.fromkeys(BLAS_THREAD_VARIABLES, threads), **MALLOC_VARIABLES,
              **HUGEPAGE_VARIABLES}
    env = {name: value for name, value in wanted.items() if not os.environ.get(name)}
    if not cache:
        env["NAVLIB_NO_CACHE"] = "1"
    return env


@dataclass(frozen=True)
class Settings:
    """What every notebook of one run is executed with."""

    quick: bool
    parameters: Mapping[str, object]
    fail_fast: bool
    timeout_s: float | None
    jobs: int
    env: Mapping[str, str]


class Kernels:
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


def execute(info: NotebookInfo, staging: Path, params: dict, settings: Settings,
            kernels: Kernels, on_restart: Callable[[CellFailure], None] | None = None
            ) -> NotebookRun:
    """Run one notebook; a stalled kernel gets one restart of the whole notebook. A run cut
    short by :meth:`Kernels.stop` (another notebook failed under ``fail_fast``) is
    ``"stopped"``."""
    executed = staging / f"{info.name}.ipynb"
    source_nb = read_notebook(info.path)
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
