"""Running the report: notebooks selected, queued longest first, run on worker threads.

:func:`run_reports` executes every ``NN_*.ipynb`` of a notebooks folder
(:mod:`navlib.reports.execution`) and publishes them all or nothing
(:mod:`navlib.reports.publishing`). Notebooks run one after the other, or up to ``jobs`` at
once (each in its own kernel, on a worker thread of the runner; the guarantees hold for
each, and Ctrl-C or SIGTERM stops them all, :mod:`navlib.reports.signals`).
"""

from __future__ import annotations

import math
import queue as queue_module
import shutil
import subprocess
import sys
import threading
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path

from navlib.errors import NavlibInputError
from navlib.reports.discovery import (
    NotebookInfo,
    dependencies,
    list_notebooks,
    parameters_for,
    select_notebooks,
)
from navlib.reports.execution import (
    DEFAULT_CELL_TIMEOUT_S,
    Kernels,
    Settings,
    execute,
    kernel_environment,
)
from navlib.reports.kernel_watch import kill_all_kernels
from navlib.reports.publishing import (
    check_output_dir,
    default_output_dir,
    load_manifest,
    publish,
    remove_orphaned_staging,
    staging_folder,
)
from navlib.reports.results import CellFailure, NotebookRun, Progress, ReportError
from navlib.reports.signals import ReportInterrupted, signals_interrupt

__all__ = ["queue_order", "run_reports"]

_EVENT_WAIT_S = 0.25  # the main thread's wait for worker events (signals are handled between)


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
        Report folder; created, or replaced on success (:mod:`navlib.reports.publishing`:
        a run with ``only`` keeps the other pages, a full run keeps only README files).
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
        (:mod:`navlib.reports.kernel_watch`).
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
    check_output_dir(output, notebooks)
    output.parent.mkdir(parents=True, exist_ok=True)

    jobs = min(jobs, len(selected))
    settings = Settings(quick, parameters, fail_fast, timeout_s, jobs,
                        kernel_environment(jobs, cache))
    queue = queue_order(selected, output) if jobs > 1 else list(selected)
    remove_orphaned_staging(output)
    staging = staging_folder(output)
    try:
        with signals_interrupt():
            runs = _run_all(selected, queue, staging, settings, progress,
                            warm_up=_compile_shared_kernels if jobs > 1 else None)
            publish(staging, output, runs, partial=only is not None)
        return runs
    except (ReportInterrupted, KeyboardInterrupt):
        kill_all_kernels()
        raise
    finally:
        if staging.exists():
            shutil.rmtree(staging, ignore_errors=True)


_COMPILE_SHARED = "from navlib.compiled import compile_shared_kernels; compile_shared_kernels()"


def _compile_shared_kernels(stopped: Callable[[], bool]) -> None:
    """Compile navlib's shared numba kernels (or load them from numba's disk cache) in a
    process of their own, so that the notebook kernels started after it load them instead
    of each compiling the same code on a machine's first run (docs/performance.md).
    Killed when ``stopped()``; should it fail, each notebook compiles what it uses on first
    use (a broken kernel then fails the cell that calls it, with its traceback)."""
    process = subprocess.Popen([sys.executable, "-c", _COMPILE_SHARED])
    try:
        while not stopped():
            try:
                process.wait(timeout=_EVENT_WAIT_S)
                return
            except subprocess.TimeoutExpired:
                continue
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()


def queue_order(selected: Sequence[NotebookInfo], output: Path) -> list[NotebookInfo]:
    """Longest path first: a notebook's ``seconds`` in the previous manifest (of ``output``
    or, when it has none, a new folder, of :func:`default_output_dir`: the last ``make
    report``) plus the longest of the notebooks that start :attr:`~NotebookInfo.after` it,
    so a summary that waits for others does not start late because they did. Notebooks the
    manifest does not time count as infinitely long (they may be long); among equals (a
    first report has no manifest), those others wait for come first, then name order. A
    notebook that waits keeps its place: the workers take the first notebook of the queue
    that is ready, so it starts as soon as those have finished (beside the rest) instead of
    after every other notebook."""
    entries: dict = {}
    for folder in (output, default_output_dir()):
        entries = load_manifest(folder).get("notebooks", {})
        if entries:
            break

    def seconds(info: NotebookInfo) -> float:
        entry = entries.get(info.name)
        try:
            return float(entry["seconds"])
        except (TypeError, KeyError, ValueError):
            return math.inf

    waiting = {info.name: [seconds(other) for other in selected
                           if info.name in dependencies(other, selected)]
               for info in selected}

    def priority(info: NotebookInfo) -> tuple[float, bool]:
        path = seconds(info) + max(waiting[info.name], default=0.0)
        return -path, not waiting[info.name]

    return sorted(selected, key=priority)  # stable: ties by name


class _Pending:
    """The queue of :func:`_run_all`: each worker takes the first notebook whose
    :func:`~navlib.reports.discovery.dependencies` have finished, waiting while none is
    ready."""

    def __init__(self, queue: Sequence[NotebookInfo]):
        self._items = list(queue)
        self._waits = {info.name: dependencies(info, queue) for info in queue}
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
             settings: Settings, progress: Progress | None,
             warm_up: Callable[[Callable[[], bool]], None] | None = None) -> list[NotebookRun]:
    """Execute the notebooks of ``queue`` (in that order) on ``settings.jobs`` worker
    threads into ``staging``; their runs in the order of ``selected``, or ReportError
    with them unless all are ok.

    ``warm_up(stopped)`` (the shared kernels' compile) runs once on the second worker while
    the first starts the head of the queue, the longest path (notebook 02, whose every-step
    observability window is the one kernel only it uses, compiled there); the other workers
    take notebooks once it has returned.

    Only the calling thread reports progress (workers post their events to it), so
    progress lines never interleave mid-line and Ctrl-C / SIGTERM reach it while it
    waits. On any exception here (an interrupt included) the kernels are stopped and the
    workers joined before it propagates, so nothing writes into ``staging`` afterwards.
    """
    events: queue_module.SimpleQueue = queue_module.SimpleQueue()
    kernels = Kernels()
    pending = _Pending(queue)
    total = len(queue)

    warmed = threading.Lock()
    not_warmed = [warm_up] if warm_up is not None else []  # emptied by the worker warming up

    def work(index: int):
        if index > 0:
            with warmed:  # the first of the other workers warms up, the rest wait for it
                if not_warmed and not kernels.stopped:
                    not_warmed.pop()(lambda: kernels.stopped)
        while not kernels.stopped:
            position, info = pending.take(lambda: kernels.stopped)
            if info is None:
                return
            params = parameters_for(info, settings.quick, settings.parameters)

            def restarting(failure, position=position, info=info, params=params):
                events.put((position, info.name, NotebookRun(
                    info.name, "restarting", 0.0, params, failure=failure)))

            events.put((position, info.name, None))
            try:
                run = execute(info, staging, params, settings, kernels, restarting)
            except Exception as exc:  # a runner bug must not leave the main thread waiting
                run = NotebookRun(info.name, "failed", 0.0, params, title=info.title,
                                  failure=CellFailure(-1, type(exc).__name__, str(exc)))
            if settings.fail_fast and run.status == "failed":
                kernels.stop()  # before this worker could take the next notebook
            events.put((position, info.name, run))
            pending.finished(info)

    workers = [threading.Thread(target=work, args=(k,), name=f"report-worker-{k}", daemon=True)
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
