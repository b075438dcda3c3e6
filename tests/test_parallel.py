"""navlib.parallel: scheduler resolution and task mapping in this process (the cluster runs
are compared with these in ``tests/test_sweep.py``)."""

from __future__ import annotations

import numpy as np
import pytest
from threadpoolctl import threadpool_info

from navlib import NavlibInputError, parallel


def _scaled(x, factor):
    return x * factor


def test_synchronous_runs_here_in_order_with_shared():
    with parallel.executor("synchronous") as client:
        assert client is None
        assert parallel.n_workers(client) == 1
    out = parallel.map_tasks(_scaled, [1.0, 2.0], "synchronous", shared={"factor": np.ones(2)})
    assert [o.tolist() for o in out] == [[1.0, 1.0], [2.0, 2.0]]


def test_the_environment_names_the_default_scheduler(monkeypatch):
    monkeypatch.setenv(parallel.SCHEDULER_ENV, "synchronous")
    with parallel.executor() as client:
        assert client is None


@pytest.mark.parametrize("scheduler, match", [
    ("my-laptop", "neither an address"),
    (8786, "expected None, a dask.distributed.Client"),
])
def test_bad_schedulers_are_refused(scheduler, match):
    with pytest.raises(NavlibInputError, match=match), parallel.executor(scheduler):
        pass


def test_blas_is_limited_to_one_thread_inside_a_task():
    with parallel.single_thread_blas():
        assert all(pool["num_threads"] == 1 for pool in threadpool_info())
