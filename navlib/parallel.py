"""The parallel engine: a scheduler resolved to a Dask client, and tasks mapped over it.

Knows no study and no filter: the sweep (:mod:`navlib.sweep`), the linear Monte Carlo
(:mod:`navlib.filters.monte_carlo`), fleet assessment and the heavy study loops hand it
picklable callables.

Where it runs (``scheduler``):

* ``None``: ``$NAVLIB_SCHEDULER`` if set, else a local Dask cluster sized to the machine
  (one single-threaded worker process per core), started and closed by the call;
* a ``dask.distributed.Client``, or an address ``"tcp://host:8786"`` of a running
  scheduler whose workers have the same environment (docs/sweeps.md explains the set-up);
* ``"processes"`` / ``"threads"``: a local cluster of processes / of threads in this process;
* ``"synchronous"``: no Dask at all, the same tasks one after the other in this process
  (small grids, notebooks run headless, debugging).

Every task runs with BLAS limited to one thread (``threadpoolctl``), so a task gives the
same floating-point result whichever scheduler runs it.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Callable, Mapping, Sequence
from contextlib import contextmanager

from threadpoolctl import threadpool_limits
from tqdm.auto import tqdm

from navlib.errors import NavlibInputError

__all__ = ["LOCAL_SCHEDULERS", "SCHEDULER_ENV", "executor", "map_tasks", "n_workers",
           "single_thread_blas"]

SCHEDULER_ENV = "NAVLIB_SCHEDULER"
"""Environment variable naming the default scheduler (an address or a keyword)."""
LOCAL_SCHEDULERS = ("processes", "threads", "synchronous")
"""Keywords accepted for ``scheduler`` besides a Client or an address."""
_ADDRESS_PREFIXES = ("tcp://", "tls://", "inproc://", "ucx://", "ws://", "wss://")


def _local_cluster(processes: bool, n_workers: int | None):
    from distributed import LocalCluster  # heavy (about 1 s): imported when a cluster starts

    cores = max(1, os.cpu_count() or 1)
    if processes:
        return LocalCluster(n_workers=n_workers or cores, threads_per_worker=1, processes=True,
                            dashboard_address=":0", silence_logs=logging.ERROR)
    return LocalCluster(n_workers=1, threads_per_worker=n_workers or cores, processes=False,
                        dashboard_address=":0", silence_logs=logging.ERROR)


@contextmanager
def executor(scheduler=None, *, n_workers: int | None = None):
    """Resolve ``scheduler`` to a Dask client for the duration of a ``with`` block.

    Parameters
    ----------
    scheduler : None, str or distributed.Client
        See the module docstring. ``None`` reads :data:`SCHEDULER_ENV` first.
    n_workers : int, optional
        Workers of a local cluster started here (default one per core).

    Yields
    ------
    distributed.Client or None
        ``None`` for ``"synchronous"`` (run in this process). A cluster started here is
        closed on exit; a Client passed in is left open.
    """
    if scheduler is None:
        scheduler = os.environ.get(SCHEDULER_ENV) or "processes"
    if isinstance(scheduler, str) and scheduler == "synchronous":  # no Dask needed
        yield None
        return
    from distributed import Client  # heavy (about 1 s): imported when a scheduler is resolved
    if isinstance(scheduler, Client):
        yield scheduler
        return
    if not isinstance(scheduler, str):
        raise NavlibInputError(f"scheduler: expected None, a dask.distributed.Client, an "
                               f"address 'tcp://host:port' or one of {LOCAL_SCHEDULERS}, "
                               f"got {type(scheduler).__name__}")
    if scheduler in ("processes", "threads"):
        cluster = _local_cluster(scheduler == "processes", n_workers)
        try:
            with Client(cluster) as client:
                yield client
        finally:
            cluster.close()
        return
    if not scheduler.startswith(_ADDRESS_PREFIXES):
        raise NavlibInputError(f"scheduler: {scheduler!r} is neither an address "
                               f"(tcp://host:port) nor one of {LOCAL_SCHEDULERS}")
    try:
        client = Client(scheduler, timeout="10s")
    except (OSError, TimeoutError) as exc:
        raise NavlibInputError(f"scheduler: cannot reach the Dask scheduler at {scheduler} "
                               f"({exc})") from exc
    with client:
        yield client


def n_workers(client) -> int:
    """Threads of all the workers of ``client`` (1 for ``None``, the synchronous run)."""
    return 1 if client is None else max(1, sum(client.nthreads().values()))


def single_thread_blas():
    """A context in which BLAS uses one thread (the same floating-point result on any
    scheduler)."""
    return threadpool_limits(1)


def _call(func, item, shared):
    with single_thread_blas():
        return func(item, **shared)


def map_tasks(func: Callable, items: Sequence, scheduler=None, *, shared: Mapping | None = None,
              progress: bool = False, desc: str = "tasks") -> list:
    """``[func(item, **shared) for item in items]`` as Dask tasks, results in order.

    The engine behind the ``scheduler=`` keyword of the heavy study loops. ``func`` must be
    picklable (a module-level function or a ``functools.partial`` of one); ``shared``
    values are scattered once to every worker (``Client.scatter(broadcast=True)``), not
    pickled per task. BLAS is limited to one thread inside each task.

    Parameters
    ----------
    func : callable
        Called as ``func(item, **shared)``; picklable.
    items : sequence
        One task per item.
    scheduler : None, str or distributed.Client, optional
        Where the tasks run (see :func:`executor`).
    shared : mapping, optional
        Keyword arguments common to every task, sent to each worker once.
    progress : bool, optional
        Show a progress bar.
    desc : str, optional
        Label of the progress bar.

    Returns
    -------
    list
        The results in the order of ``items``.
    """
    items = list(items)
    shared = dict(shared or {})
    with executor(scheduler) as client:
        if client is None:
            return [_call(func, item, shared) for item in
                    tqdm(items, desc=desc, disable=not progress)]
        from distributed import as_completed  # heavy (dask.distributed): only with a cluster

        # a one-element list: scatter() would split a dict or list value into items
        scattered = {k: client.scatter([v], broadcast=True)[0] for k, v in shared.items()}
        futures = [client.submit(_call, func, item, scattered, pure=False) for item in items]
        order = {f.key: i for i, f in enumerate(futures)}
        out: list = [None] * len(items)
        try:
            with tqdm(total=len(items), desc=desc, disable=not progress) as bar:
                for fut in as_completed(futures):
                    out[order[fut.key]] = fut.result()
                    bar.update(1)
        finally:
            client.cancel(futures)
        return out

