"""The linear filter's Monte Carlo split over tasks of the parallel engine.

:func:`monte_carlo_linear` cuts the runs of :func:`navlib.filters.simulate_linear` into chunks
run as tasks of :func:`navlib.parallel.map_tasks` (a Dask cluster or this process), each chunk
drawing from its own child of ``numpy.random.SeedSequence(seed)``.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from navlib._validation import finite_scalar, reject_unknown
from navlib.errors import NavlibInputError
from navlib.filters.linear import MEMORY_BUDGET, prepare_linear, simulate_linear
from navlib.parallel import map_tasks

__all__ = ["monte_carlo_linear"]

_PREPARE_KEYS = ("method", "update_every", "measured", "P0", "noise_input", "noise_names")
_FILTERS: dict = {}
"""This process's prepared filter: ``{id(model): (model, LinearFilter)}`` (one kept: the
model is scattered once to each worker, which prepares it once for all its chunks)."""


def _prepared_filter(model, options: dict):
    key = (id(model), repr(sorted((k, repr(v)) for k, v in options.items())))
    hit = _FILTERS.get(key)
    if hit is None or hit[0] is not model:
        _FILTERS.clear()
        hit = (model, prepare_linear(model, **options))
        _FILTERS[key] = hit
    return hit[1]


def _monte_carlo_chunk(chunk: tuple, model, prepare: dict, simulate: dict):
    seed, runs = chunk
    return simulate_linear(_prepared_filter(model, prepare), runs=runs, seed=seed, **simulate)


def monte_carlo_linear(model, *, runs: int, seed=None, runs_per_task: int = 25,
                       scheduler=None, record_every: int | None = None,
                       progress: bool = False, **options):
    """:func:`navlib.filters.simulate_linear` with the runs split over parallel tasks.

    The runs are cut into chunks of ``runs_per_task``; chunk ``i`` draws from the child
    ``i`` of ``numpy.random.SeedSequence(seed)`` (so the result depends on ``seed`` and
    ``runs_per_task``, never on the scheduler or the number of workers, but it is another
    random stream than one ``simulate_linear(model, runs=runs, seed=seed)`` batch). The model
    is scattered once to each worker, which discretises it and runs the covariance
    recursion once (:func:`navlib.filters.prepare_linear`) for all its chunks. The chunks'
    runs are joined on the run axis in order.

    Parameters
    ----------
    model : LinearModel or DiscreteModel
        As for :func:`~navlib.filters.simulate_linear`.
    runs : int
        Monte-Carlo runs in all.
    seed : int or SeedSequence, optional
        Root of the chunks' seeds.
    runs_per_task : int
        Runs per task (default 25).
    scheduler : optional
        Where the tasks run (:func:`navlib.parallel.executor`: a Client,
        ``tcp://host:port``, ``"processes"``, ``"threads"``, ``"synchronous"``).
    record_every : int, optional
        Defaults to the value ``simulate_linear`` picks for all ``runs`` at once.
    progress : bool
        A progress bar of the tasks.
    **options
        The other keywords of ``simulate_linear`` (``outliers``, ``noise``,
        ``initial_error``, ``method``, ``update_every``, ``measured``, ``P0``,
        ``noise_input``, ``noise_names``).

    Returns
    -------
    LinearSimulation
    """
    runs = int(finite_scalar(runs, "runs", low=1))
    per_task = int(finite_scalar(runs_per_task, "runs_per_task", low=1))
    if "rng" in options:
        raise NavlibInputError("rng: a split Monte Carlo draws from seed (SeedSequence)")
    reject_unknown(options, (*_PREPARE_KEYS, "outliers", "noise", "initial_error"),
                   "monte_carlo_linear")
    if record_every is None:
        n_epochs, n = np.asarray(model.t).size, len(model.state_names)
        record_every = max(1, int(np.ceil(n_epochs * 2 * 8 * runs * n / MEMORY_BUDGET)))
    sizes = [min(per_task, runs - i) for i in range(0, runs, per_task)]
    seeds = np.random.SeedSequence(seed).spawn(len(sizes))
    prepare = {k: v for k, v in options.items() if k in _PREPARE_KEYS}
    simulate = {k: v for k, v in options.items() if k not in _PREPARE_KEYS}
    simulate["record_every"] = record_every
    parts = map_tasks(_monte_carlo_chunk, list(zip(seeds, sizes, strict=True)), scheduler,
                      shared={"model": model, "prepare": prepare, "simulate": simulate},
                      progress=progress, desc="Monte Carlo")
    first = parts[0]
    return replace(first, **{name: np.concatenate([getattr(p, name) for p in parts], axis=1)
                             for name in ("truth", "estimate", "nees", "nis", "innovation")})
