"""Bounded notebook execution: kernel messages that cannot be missed, and a stall watchdog.

The report runner (:mod:`navlib.reports`) executes notebooks with papermill, which drives an
IPython kernel through nbclient and jupyter_client's asyncio ZeroMQ channels. Two things can
make such a run wait without bound; this module removes the first and bounds the second.

1. **Missed wake-ups in the runner.** jupyter_client waits for a kernel message with one
   ``zmq.asyncio`` poll for the whole cell time limit (none by default). That poll is woken
   by ZeroMQ's edge-triggered notification file descriptor; when the edge is consumed
   elsewhere the wake-up is lost, and the poll only looks at the socket again when its
   timeout expires. The kernel has replied and gone idle, the runner waits on: without a
   limit forever, with nbclient's per-cell limit exactly until that limit, after which the
   reply is found and the cell is recorded as "completed" (seen: notebook 02's widget cell,
   ``duration 600.03``). Here every wait is cut into :data:`POLL_SLICE_S` slices, each
   ending in a real poll of the socket, so a lost wake-up costs at most one slice. Each one
   is counted (:attr:`KernelWatch.lost_wakeups`) so the stress script can show how often
   they happen.
2. **A kernel that stops answering.** A request the kernel reports idle for (or never
   starts) without sending its reply is a stall, not a slow cell. :class:`KernelWatch` runs
   a watchdog thread that sees every message, kills the kernel's process tree on a stall
   and records why; the report runner then restarts the notebook once before failing.

:func:`execute_notebook` ties it together: papermill with the ``navlib-bounded`` engine,
whose client marks a timed-out, stalled or dead-kernel cell as *failed* with an error output
(papermill's own client records such a cell as "completed") and raises
:class:`NotebookAborted`.
"""

from __future__ import annotations

import datetime as _dt
import subprocess
import threading
import time
import weakref
from collections.abc import Mapping
from dataclasses import dataclass
from queue import Empty
from typing import NamedTuple

import psutil

from navlib.cache import memoized
from navlib.reports.discovery import notebook_format

__all__ = ["ENGINE_NAME", "IDLE_WITHOUT_REPLY_S", "KERNEL_NAME", "LOST_WAKEUP_WAIT_S",
           "NOT_STARTED_S", "POLL_SLICE_S", "KernelWatch", "NotebookAborted", "execute_notebook",
           "kernel_manager_class", "kill_all_kernels"]

POLL_SLICE_S = 0.25
"""Longest wait on a kernel socket before it is polled again, s."""

IDLE_WITHOUT_REPLY_S = 15.0
"""A request the kernel reported idle for this long without a reply is a stall, s."""

NOT_STARTED_S = 60.0
"""A request the kernel has not reported busy for this long is a stall, s."""

LOST_WAKEUP_WAIT_S = 0.05
"""A message found only when a poll slice expired, after waiting in the socket longer than
this, counts as a lost wake-up (ZeroMQ never woke the poll; the slicing recovered it), s."""

ENGINE_NAME = "navlib-bounded"
KERNEL_NAME = "python3"
"""The kernel spec name given to papermill (always started with ``sys.executable``)."""

_LIVE_WATCHES: weakref.WeakSet[KernelWatch] = weakref.WeakSet()
_LIVE_LOCK = threading.Lock()  # report runs start kernels from several threads


class NotebookAborted(RuntimeError):
    """A notebook run stopped at a cell that timed out, stalled or lost its kernel.

    Attributes
    ----------
    kind : str
        ``"timeout"`` (the per-cell limit passed while the kernel was busy), ``"stall"``
        (the watchdog found the kernel not answering and killed it) or ``"died"`` (the
        kernel process ended on its own).

    The failing cell is marked in the saved executed notebook (an error output), which is
    where :mod:`navlib.reports` locates it.
    """

    def __init__(self, kind: str, message: str):
        super().__init__(message)
        self.kind = kind


@dataclass
class _Request:
    sent: float
    busy: float | None = None
    idle: float | None = None
    replied: float | None = None


class KernelWatch:
    """Watch one kernel: every message to and from it, and a stall watchdog thread.

    Parameters
    ----------
    idle_without_reply_s, not_started_s : float, optional
        Stall rules (default: the module's :data:`IDLE_WITHOUT_REPLY_S`,
        :data:`NOT_STARTED_S`, read when the watch is made).

    Attributes
    ----------
    stall : str or None
        Why the watchdog declared a stall (the kernel has then been killed).
    lost_wakeups : int
        Messages found only when a poll slice expired though they had been waiting longer
        than :data:`LOST_WAKEUP_WAIT_S` (wake-ups ZeroMQ never delivered, recovered).
    """

    def __init__(self, idle_without_reply_s: float | None = None,
                 not_started_s: float | None = None):
        self.idle_without_reply_s = float(
            IDLE_WITHOUT_REPLY_S if idle_without_reply_s is None else idle_without_reply_s)
        self.not_started_s = float(NOT_STARTED_S if not_started_s is None else not_started_s)
        self.stall: str | None = None
        self.lost_wakeups = 0
        self.pid: int | None = None
        self._requests: dict[str, _Request] = {}
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        with _LIVE_LOCK:
            _LIVE_WATCHES.add(self)

    # ------------------------------------------------------------------ messages
    def sent(self, msg: dict) -> None:
        """Record a message sent on the shell channel (execute requests are watched)."""
        if msg.get("header", {}).get("msg_type") == "execute_request":
            with self._lock:
                self._requests[msg["header"]["msg_id"]] = _Request(time.monotonic())

    def received(self, msg: dict, at_slice_end: bool) -> None:
        """Record a message received from the kernel (``at_slice_end``: the poll that found
        it was not woken, it returned when its slice expired).

        Parameters
        ----------
        msg : dict
            The message (Jupyter protocol).
        at_slice_end : bool
            Whether the poll that found it returned at the end of its slice.
        """
        now = time.monotonic()
        sent_at = msg.get("header", {}).get("date")
        if at_slice_end and isinstance(sent_at, _dt.datetime) and sent_at.tzinfo is not None:
            waited_s = (_dt.datetime.now(_dt.UTC) - sent_at).total_seconds()
            if waited_s > LOST_WAKEUP_WAIT_S:
                self.lost_wakeups += 1
        parent = msg.get("parent_header", {}).get("msg_id")
        msg_type = msg.get("header", {}).get("msg_type")
        with self._lock:
            request = self._requests.get(parent)
            if request is None:
                return
            if msg_type == "status":
                state = msg.get("content", {}).get("execution_state")
                if state == "busy" and request.busy is None:
                    request.busy = now
                elif state == "idle":
                    request.idle = now
            elif msg_type == "execute_reply":
                request.replied = now

    def check(self, now: float | None = None) -> str | None:
        """The stall rule: why the kernel is not answering, or None while all is well."""
        now = time.monotonic() if now is None else now
        with self._lock:
            for request in self._requests.values():
                if request.replied is not None:
                    continue
                if request.idle is not None and now - request.idle > self.idle_without_reply_s:
                    return (f"the kernel went idle {now - request.idle:.0f} s ago without "
                            "replying to the cell")
                if request.busy is None and now - request.sent > self.not_started_s:
                    return (f"the kernel has not started the cell {now - request.sent:.0f} s "
                            "after it was sent")
        return None

    # ------------------------------------------------------------------ watchdog
    def start(self, pid: int) -> None:
        """Start watching the kernel process ``pid`` (a daemon thread, 0.5 s period). A
        watch already stopped (the run was interrupted while this kernel was launching)
        kills the kernel instead."""
        self.pid = int(pid)
        if self._stop.is_set():
            self.kill_kernel()
            return
        self._thread = threading.Thread(target=self._run, name=f"kernel-watch-{pid}",
                                        daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.wait(0.5):
            reason = self.check()
            if reason is not None:
                self.stall = reason
                self.kill_kernel()
                return

    def stop(self) -> None:
        """Stop the watchdog thread (the kernel is left to its manager)."""
        self._stop.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout=2.0)

    def kill_kernel(self) -> None:
        """Kill the kernel process and everything it started (no-op when already gone)."""
        if self.pid is None:
            return
        try:
            root = psutil.Process(self.pid)
            processes = [*root.children(recursive=True), root]
        except psutil.NoSuchProcess:
            return
        for process in processes:
            try:
                process.kill()
            except psutil.NoSuchProcess:
                pass
        psutil.wait_procs(processes, timeout=5.0)


def kill_all_kernels() -> None:
    """Stop every watched kernel of this process (used when a report run is interrupted)."""
    with _LIVE_LOCK:
        watches = list(_LIVE_WATCHES)
    for watch in watches:
        watch.stop()
        watch.kill_kernel()


# ---------------------------------------------------------------------- kernel plumbing


class _Classes(NamedTuple):
    channel: type
    client: type
    kernel_manager: type


@memoized(maxsize=1)
def _classes() -> _Classes:
    """The watched channel, client and kernel-manager classes (imported lazily)."""
    # the Jupyter stack is heavy: loaded when the first kernel starts, not on import
    from ipykernel.kernelspec import get_kernel_dict
    from jupyter_client.asynchronous import AsyncKernelClient
    from jupyter_client.channels import AsyncZMQSocketChannel
    from jupyter_client.kernelspec import KernelSpec
    from jupyter_client.manager import AsyncKernelManager
    from traitlets import Type

    class SlicedPollChannel(AsyncZMQSocketChannel):
        """An asyncio channel whose waits end in a real socket poll every slice."""

        watch: KernelWatch | None = None

        async def get_msg(self, timeout: float | None = None) -> dict:
            deadline = None if timeout is None else time.monotonic() + timeout
            while True:
                left = POLL_SLICE_S if deadline is None else deadline - time.monotonic()
                wait_s = max(0.0, min(POLL_SLICE_S, left))
                polled_at = time.monotonic()
                if await self.socket.poll(int(wait_s * 1000)):
                    at_slice_end = wait_s > 0 and time.monotonic() - polled_at >= wait_s
                    msg = await self._recv()
                    if self.watch is not None:
                        self.watch.received(msg, at_slice_end)
                    return msg
                if deadline is not None and time.monotonic() >= deadline:
                    raise Empty

        def send(self, msg: dict) -> None:
            if self.watch is not None:
                self.watch.sent(msg)
            super().send(msg)

    class WatchedKernelClient(AsyncKernelClient):
        shell_channel_class = Type(SlicedPollChannel)
        iopub_channel_class = Type(SlicedPollChannel)
        watch: KernelWatch | None = None

        @property
        def shell_channel(self):
            channel = super().shell_channel
            channel.watch = self.watch
            return channel

        @property
        def iopub_channel(self):
            channel = super().iopub_channel
            channel.watch = self.watch
            return channel

    class CurrentPythonKernelManager(AsyncKernelManager):
        """Starts ipykernel with ``sys.executable`` (its environment: this process's plus
        ``extra_env``) and hands its client the watch."""

        watch: KernelWatch | None = None
        extra_env: Mapping[str, str] | None = None

        async def _async_launch_kernel(self, kernel_cmd, **kw):
            kw.setdefault("stderr", subprocess.DEVNULL)
            await super()._async_launch_kernel(kernel_cmd, **kw)
            if self.watch is not None:
                self.watch.start(self.provisioner.process.pid)

        def client(self, **kwargs):
            """A watched client (same construction as ``KernelManager.client``)."""
            kw = {**self.get_connection_info(session=True),
                  "connection_file": self.connection_file, "parent": self, **kwargs}
            client = WatchedKernelClient(**kw)
            client.watch = self.watch
            return client

        @property
        def kernel_spec(self):
            if self._kernel_spec is None:
                spec = get_kernel_dict()
                # inline figures even when the caller exports MPLBACKEND=Agg (headless CI)
                spec["env"] = {"MPLBACKEND": "module://matplotlib_inline.backend_inline",
                               **(self.extra_env or {})}
                self._kernel_spec = KernelSpec(resource_dir="", **spec)
            return self._kernel_spec

    return _Classes(SlicedPollChannel, WatchedKernelClient, CurrentPythonKernelManager)


def kernel_manager_class(watch: KernelWatch, env: Mapping[str, str] | None = None):
    """A kernel-manager class bound to ``watch`` and the kernel's extra environment ``env``
    (papermill instantiates it itself).

    Parameters
    ----------
    watch : KernelWatch
        The watch.
    env : Mapping or None, optional
        Extra environment of the kernel.

    Returns
    -------
    type
    """
    return type("WatchedKernelManager", (_classes().kernel_manager,),
                {"watch": watch, "extra_env": dict(env or {})})


@memoized(maxsize=1)
def _register_engine() -> None:
    """Register the ``navlib-bounded`` papermill engine (once per process)."""
    # papermill and nbclient are heavy: loaded when the first notebook runs, not on import
    nbformat = notebook_format()
    from nbclient.exceptions import CellExecutionError, CellTimeoutError, DeadKernelError
    from papermill.clientwrap import PapermillNotebookClient
    from papermill.engines import NBClientEngine, papermill_engines

    class BoundedNotebookClient(PapermillNotebookClient):
        """papermill's client, with timed-out, stalled and dead-kernel cells failed."""

        def papermill_execute_cells(self):
            for index, cell in enumerate(self.nb.cells):
                try:
                    self.nb_man.cell_start(cell, index)
                    self.execute_cell(cell, index)
                except CellExecutionError as ex:
                    self.nb_man.cell_exception(self.nb.cells[index], cell_index=index,
                                               exception=ex)
                    break
                except (CellTimeoutError, DeadKernelError) as ex:
                    aborted = self._aborted(ex)
                    cell = self.nb.cells[index]
                    cell.outputs.append(nbformat.v4.new_output(
                        "error", ename=type(aborted).__name__, evalue=str(aborted),
                        traceback=[f"{type(aborted).__name__}: {aborted}"]))
                    self.nb_man.cell_exception(cell, cell_index=index, exception=aborted)
                    raise aborted from None
                finally:
                    self.nb_man.cell_complete(self.nb.cells[index], cell_index=index)

        def _aborted(self, ex: Exception) -> NotebookAborted:
            watch = getattr(self.km, "watch", None)
            if isinstance(ex, CellTimeoutError):
                if watch is not None:
                    watch.kill_kernel()  # a busy kernel would delay the shutdown
                return NotebookAborted(
                    "timeout", f"cell timed out after the per-cell limit of "
                    f"{self.timeout} s (the kernel was still busy; it was stopped)")
            if watch is not None and watch.stall is not None:
                return NotebookAborted("stall", f"kernel stalled: {watch.stall}; "
                                       "the watchdog stopped it")
            return NotebookAborted("died", "the kernel died while running the cell")

    class BoundedEngine(NBClientEngine):
        @classmethod
        def execute_managed_notebook(cls, nb_man, kernel_name, log_output=False,
                                     stdout_file=None, stderr_file=None, start_timeout=60,
                                     execution_timeout=None, kernel_cwd=None, **kwargs):
            kwargs.pop("input_path", None)
            kwargs.pop("timeout", None)
            kwargs.pop("startup_timeout", None)
            # the kernel starts in kernel_cwd; papermill's own ``cwd`` would chdir the whole
            # process, which several notebooks running in threads cannot share
            return BoundedNotebookClient(
                nb_man, timeout=execution_timeout, startup_timeout=start_timeout,
                resources={"metadata": {"path": kernel_cwd}} if kernel_cwd else {},
                kernel_name=kernel_name, log_output=log_output, stdout_file=stdout_file,
                stderr_file=stderr_file, **kwargs).execute()

    papermill_engines.register(ENGINE_NAME, BoundedEngine)


def execute_notebook(input_path, output_path, *, parameters: dict, cwd,
                     timeout_s: float | None, watch: KernelWatch,
                     env: Mapping[str, str] | None = None) -> None:
    """Execute one notebook with papermill, bounded: see the module docstring. The kernel
    runs in ``cwd`` with ``env`` added to its environment; this process's working
    directory is never changed, so several threads may call this at once (one kernel
    each).

    Raises
    ------
    NotebookAborted
        A cell timed out, stalled or lost its kernel (the executed notebook is saved with
        that cell marked failed and an error output naming the reason).
    papermill.PapermillExecutionError
        A cell raised an exception.

    Parameters
    ----------
    input_path, output_path : path-like
        Notebook read and executed notebook written.
    parameters : dict
        Papermill parameters.
    cwd : path-like
        Working directory of the kernel.
    timeout_s : float or None
        Time limit per cell, s.
    watch : KernelWatch
        The watch that bounds the run.
    env : Mapping or None, optional
        Extra environment of the kernel.
    """
    import papermill  # heavy: loaded when the first notebook runs, not on import

    _register_engine()
    try:
        papermill.execute_notebook(
            str(input_path), str(output_path), parameters=parameters,
            kernel_name=KERNEL_NAME, engine_name=ENGINE_NAME, kernel_cwd=str(cwd),
            progress_bar=False, log_output=False, execution_timeout=timeout_s,
            kernel_manager_class=kernel_manager_class(watch, env))
    finally:
        watch.stop()
        watch.kill_kernel()
