"""Design trade studies on Dask: a grid of parameters mapped over an evaluation as tasks.

Public contract (spec ``api.md``, "Scale")::

    df = navlib.sweep.sweep(grid, evaluate, scheduler=None, output=None)

``grid`` declares the points (a dict of value lists, whose product is swept, or a DataFrame
of points); ``evaluate`` is a named evaluation of :data:`EVALUATIONS` or any picklable
callable ``evaluate(**point) -> mapping``. The result is one row per point, parameter
columns first. ``output`` (a ``.parquet`` file) makes the sweep resumable: each finished
task is written at once to ``<output>.parts/``, a rerun skips the points already there, and
the complete table replaces ``output`` atomically at the end.

Where it runs (``scheduler``):

* ``None``: ``$NAVLIB_SCHEDULER`` if set, else a local Dask cluster sized to the machine
  (one single-threaded worker process per core), started and closed by the call;
* a ``dask.distributed.Client``, or an address ``"tcp://host:8786"`` of a running
  scheduler whose workers have the same environment (the README explains the set-up);
* ``"processes"`` / ``"threads"``: a local cluster of processes / of threads in this process;
* ``"synchronous"``: no Dask at all, the same tasks one after the other in this process
  (small grids, notebooks run headless, debugging).

Every task runs with BLAS limited to one thread (``threadpoolctl``), so a point gives the
same floating-point result whichever scheduler runs it: serial and cluster sweeps agree
exactly (``tests/test_sweep.py``).

Heavy shared inputs. A named evaluation declares which of its parameters define its heavy
input (:attr:`Evaluation.shared`: the trajectory, the sensor noise, the GNSS rate); that input
is built once per distinct value as its own task (``Evaluation.prepare``) and the cheap
per-point tasks depend on it, so Dask runs them where it lives instead of pickling it per
task. Evaluations whose inputs are too big to move (the launcher's 200 Hz filters) keep a
per-process cache instead, and the points are batched by shared input so that each batch
builds it at most once. Callables keep their own caches (``functools.cache`` in the worker
process); points reach them in grid order, batched.

:func:`map_tasks` is the same engine for the existing heavy loops (Table 2, the rocket
sensitivity sweep) and :func:`monte_carlo_linear` for the linear Monte Carlo, which accept
``scheduler=`` and keep their local default.
"""

from __future__ import annotations

import itertools
import json
import math
import os
import time
import uuid
from collections.abc import Callable, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, replace
from functools import lru_cache
from pathlib import Path

import numpy as np
import pandas as pd

from navlib._validation import reject_unknown
from navlib.errors import NavlibInputError

__all__ = ["EVALUATIONS", "SCHEDULER_ENV", "Evaluation", "evaluations_frame", "executor",
           "grid_points", "map_tasks", "monte_carlo_linear", "parameter_columns", "pivot",
           "read", "sweep"]

SCHEDULER_ENV = "NAVLIB_SCHEDULER"
"""Environment variable naming the default scheduler (an address or a keyword)."""
LOCAL_SCHEDULERS = ("processes", "threads", "synchronous")
"""Keywords accepted for ``scheduler`` besides a Client or an address."""
_ADDRESS_PREFIXES = ("tcp://", "tls://", "inproc://", "ucx://", "ws://", "wss://")
_METADATA_KEY = b"navlib.sweep"
_PROGRESS_MIN_POINTS = 50
"""Pending points from which ``progress=None`` shows a progress bar."""


# --------------------------------------------------------------------------- executor


def _local_cluster(processes: bool, n_workers: int | None):
    import logging

    from distributed import LocalCluster

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
    try:
        from distributed import Client
    except ImportError as exc:  # pragma: no cover - a core dependency
        raise NavlibInputError("scheduler: dask.distributed is not installed") from exc
    if isinstance(scheduler, Client):
        yield scheduler
        return
    if not isinstance(scheduler, str):
        raise NavlibInputError(f"scheduler: expected None, a dask.distributed.Client, an "
                               f"address 'tcp://host:port' or one of {LOCAL_SCHEDULERS}, "
                               f"got {type(scheduler).__name__}")
    if scheduler == "synchronous":
        yield None
        return
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


def _n_workers(client) -> int:
    return 1 if client is None else max(1, sum(client.nthreads().values()))


def _single_thread_blas():
    from threadpoolctl import threadpool_limits

    return threadpool_limits(1)


def _call(func, item, shared):
    with _single_thread_blas():
        return func(item, **shared)


def map_tasks(func: Callable, items: Sequence, scheduler=None, *, shared: Mapping | None = None,
              progress: bool = False, desc: str = "tasks") -> list:
    """``[func(item, **shared) for item in items]`` as Dask tasks, results in order.

    The engine behind the ``scheduler=`` keyword of the heavy study loops. ``func`` must be
    picklable (a module-level function or a ``functools.partial`` of one); ``shared``
    values are scattered once to every worker (``Client.scatter(broadcast=True)``), not
    pickled per task. BLAS is limited to one thread inside each task.
    """
    items = list(items)
    shared = dict(shared or {})
    from tqdm.auto import tqdm

    with executor(scheduler) as client:
        if client is None:
            return [_call(func, item, shared) for item in
                    tqdm(items, desc=desc, disable=not progress)]
        from distributed import as_completed

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


# --------------------------------------------------------------------------- Monte Carlo

_PREPARE_KEYS = ("method", "update_every", "measured", "P0", "noise_input", "noise_names")
_FILTERS: dict = {}
"""This process's prepared filter: ``{id(model): (model, LinearFilter)}`` (one kept)."""


def _prepared_filter(model, options: dict):
    from navlib.filters import prepare_linear

    key = (id(model), repr(sorted((k, repr(v)) for k, v in options.items())))
    hit = _FILTERS.get(key)
    if hit is None or hit[0] is not model:
        _FILTERS.clear()
        hit = (model, prepare_linear(model, **options))
        _FILTERS[key] = hit
    return hit[1]


def _monte_carlo_chunk(chunk: tuple, model, prepare: dict, simulate: dict):
    from navlib.filters import simulate_linear

    seed, runs = chunk
    return simulate_linear(_prepared_filter(model, prepare), runs=runs, seed=seed, **simulate)


def monte_carlo_linear(model, *, runs: int, seed=None, runs_per_task: int = 25,
                       scheduler=None, record_every: int | None = None,
                       progress: bool = False, **options):
    """:func:`navlib.filters.simulate_linear` with the runs split over Dask tasks.

    The runs are cut into chunks of ``runs_per_task``; chunk ``i`` draws from the child
    ``i`` of ``numpy.random.SeedSequence(seed)`` (so the result depends on ``seed`` and
    ``runs_per_task``, never on the scheduler or the number of workers, but it is another
    random stream than one ``simulate_linear(model, runs=runs, seed=seed)`` batch). The model
    is scattered once to each worker, which discretises it and runs the covariance
    recursion once (:func:`navlib.filters.prepare_linear`) for all its chunks. The chunks'
    runs are joined on the run axis in order.

    ``options``: the other keywords of ``simulate_linear`` (``outliers``, ``noise``,
    ``method``, ``update_every``...); ``record_every`` defaults to the value
    ``simulate_linear`` picks for all ``runs`` at once.
    """
    from navlib._validation import finite_scalar
    from navlib.filters.linear import _MEMORY_BUDGET

    runs = int(finite_scalar(runs, "runs", low=1))
    per_task = int(finite_scalar(runs_per_task, "runs_per_task", low=1))
    if "rng" in options:
        raise NavlibInputError("rng: a split Monte Carlo draws from seed (SeedSequence)")
    reject_unknown(options, (*_PREPARE_KEYS, "outliers", "noise", "initial_error"),
                   "monte_carlo_linear")
    if record_every is None:
        n_epochs, n = np.asarray(model.t).size, len(model.state_names)
        record_every = max(1, int(np.ceil(n_epochs * 2 * 8 * runs * n / _MEMORY_BUDGET)))
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


# --------------------------------------------------------------------------- grid


def grid_points(grid) -> pd.DataFrame:
    """The points of a sweep grid as a DataFrame (one row per point).

    ``grid``: a dict ``name -> list of values`` (the product in dict order, first key
    slowest) or a DataFrame of points (copied). Raises on empty grids, non-string names,
    scalar values and duplicate points.
    """
    if isinstance(grid, pd.DataFrame):
        points = grid.reset_index(drop=True).copy()
        bad = [c for c in points.columns if not isinstance(c, str) or not c]
        if bad:
            raise NavlibInputError(f"grid: column names must be non-empty strings, got {bad}")
        if points.columns.duplicated().any():
            raise NavlibInputError("grid: duplicate column names "
                                   f"{sorted(set(points.columns[points.columns.duplicated()]))}")
    elif isinstance(grid, Mapping):
        values = {}
        for name, vals in grid.items():
            if not isinstance(name, str) or not name:
                raise NavlibInputError(f"grid: parameter names must be non-empty strings, "
                                       f"got {name!r}")
            if isinstance(vals, (str, bytes, Mapping)) or not isinstance(
                    vals, (Sequence, np.ndarray, pd.Series, pd.Index, range)):
                raise NavlibInputError(f"grid[{name!r}]: expected a list of values, got "
                                       f"{vals!r}")
            vals = [_plain(v) for v in vals]
            if not vals:
                raise NavlibInputError(f"grid[{name!r}]: no values")
            values[name] = vals
        points = pd.DataFrame(list(itertools.product(*values.values())),
                              columns=list(values))
    else:
        raise NavlibInputError(f"grid: expected a dict of value lists or a DataFrame, got "
                               f"{type(grid).__name__}")
    if points.shape[1] == 0 or len(points) == 0:
        raise NavlibInputError("grid: no points to sweep")
    keys = [_key(row) for row in points.itertuples(index=False)]
    if len(set(keys)) != len(keys):
        seen, dup = set(), None
        for i, k in enumerate(keys):
            if k in seen:
                dup = i
                break
            seen.add(k)
        raise NavlibInputError(f"grid: point {dup} repeats an earlier point "
                               f"{dict(zip(points.columns, keys[dup], strict=True))}")
    return points


def _plain(value):
    """Python scalar for numpy scalars (keys, JSON and the evaluations see plain values)."""
    return value.item() if isinstance(value, np.generic) else value


def _key(values) -> tuple:
    """Hashable identity of a point (1 == 1.0, NaN equal to NaN)."""
    out = []
    for v in values:
        v = _plain(v)
        if isinstance(v, float) and math.isnan(v):
            v = "__nan__"
        elif isinstance(v, list):
            v = tuple(v)
        out.append(v)
    return tuple(out)


# --------------------------------------------------------------------------- evaluations


@dataclass(frozen=True)
class Evaluation:
    """A named evaluation: its parameters (with defaults) and its heavy shared input.

    Attributes
    ----------
    name, description : str
    parameters : dict
        Accepted point parameters and their defaults.
    shared : tuple of str
        The parameters that define the heavy input built by ``prepare``.
    run : callable
        ``run(prepared, **parameters) -> dict`` of result columns.
    prepare : callable, optional
        ``prepare(**shared) -> object`` built once per distinct shared values (a task of its
        own, moved between workers by Dask). None: ``run`` keeps a per-process cache.
    """

    name: str
    description: str
    parameters: dict
    shared: tuple
    run: Callable
    prepare: Callable | None = None

    def complete(self, point: Mapping) -> dict:
        """``point`` with the defaults of the parameters it leaves out."""
        reject_unknown(point, self.parameters, f"evaluation {self.name!r}")
        return {**self.parameters, **{k: _plain(v) for k, v in point.items()}}

    def shared_key(self, full: Mapping) -> tuple:
        return tuple((k, full[k]) for k in self.shared)

    def __call__(self, **point) -> dict:
        """Evaluate one point in this process (shared input from a process cache)."""
        full = self.complete(point)
        return self.run(_prepared(self.name, self.shared_key(full)), **full)


@lru_cache(maxsize=8)
def _prepared(name: str, key: tuple):
    ev = EVALUATIONS[name]
    return None if ev.prepare is None else ev.prepare(**dict(key))


def _prepare_task(name: str, key: tuple) -> tuple:
    """The shared input of ``key`` and the seconds it took (0 when cached here)."""
    t0 = time.perf_counter()
    with _single_thread_blas():
        value = _prepared(name, key)
    return value, time.perf_counter() - t0


# ----- rocket family: the 21-state ECEF model on the sounding-rocket flight (España et al.)

_ROCKET_SHARED = {"spin_hz": 2.0, "coning_deg": 0.0, "coning_hz": 0.5,
                  "preset": "motionpak_tactical", "imu_grade": 1.0, "gnss_rate_hz": 1.0,
                  "attitude_error": "ecef"}
_ROCKET_POINT = {"gnss_sigma_m": 5.0, "sigma_p0_m": 30.0, "sigma_v0_m_s": 3.0,
                 "sigma_theta0_deg": 1.0, "sigma_bg_deg_s": None, "sigma_ba_m_s2": None,
                 "sigma_sg_ppm": None, "sigma_sa_ppm": None, "eta": 1e-3, "nu": 0.985,
                 "d0": "global"}


def _rocket_prepare(spin_hz, coning_deg, coning_hz, preset, imu_grade, gnss_rate_hz,
                    attitude_error):
    """The discretised 21-state model (no P0/R yet) and the body x axis at its epochs."""
    from navlib._validation import finite_scalar
    from navlib.models.ecef import ATTITUDE_ERRORS, ecef21_at_epochs, imu_noise_densities
    from navlib.studies.rocket import rocket_trajectory

    if attitude_error not in ATTITUDE_ERRORS:
        raise NavlibInputError(f"attitude_error: expected one of {ATTITUDE_ERRORS}, got "
                               f"{attitude_error!r}")
    grade = finite_scalar(imu_grade, "imu_grade", 0.0, low_open=True)
    coning = {"coning_deg": coning_deg, "coning_hz": coning_hz} if coning_deg else {}
    traj = rocket_trajectory(spin_hz, **coning)
    noise = preset if grade == 1.0 else {k: v * grade
                                         for k, v in imu_noise_densities(preset).items()}
    model = ecef21_at_epochs(traj, gnss_rate_hz, sensors=noise, attitude_error=attitude_error)
    k = np.clip(np.searchsorted(traj.t, model.t - 1e-9), 0, traj.t.size - 1)
    C = traj.C_b_e()[k]
    roll_axis = C[:, :, 0] if attitude_error == "ecef" else np.tile([1.0, 0.0, 0.0],
                                                                    (k.size, 1))
    return model, roll_axis


def _rocket_model(prepared, full):
    """The prepared model with this point's P0 and R."""
    from navlib._validation import finite_scalar
    from navlib.models.ecef import initial_covariance, parameter_sigmas

    base, _ = prepared
    grade = float(full["imu_grade"])
    sigmas = {k: v * grade for k, v in parameter_sigmas(full["preset"]).items()}
    for name in _ROCKET_POINT:
        if name.startswith("sigma_") and full[name] is not None:
            sigmas[name] = full[name]
    sigma = finite_scalar(full["gnss_sigma_m"], "gnss_sigma_m", 0.0, low_open=True)
    R = np.broadcast_to(sigma**2 * np.eye(3), base.R.shape)
    return replace(base, P0=initial_covariance(full["preset"], **sigmas), R=R)


def _sensability(model, full):
    from navlib.metrics import sensability_model

    return sensability_model(model, nu=full["nu"])


def _excitability_run(prepared, **full) -> dict:
    from navlib.metrics import excitability_segments
    from navlib.studies.rocket import SEGMENT_LABELS, SEGMENTS

    model = _rocket_model(prepared, full)
    se = _sensability(model, full) if full["d0"] == "filter" else None
    ex = excitability_segments(model, SEGMENTS, full["eta"], full["d0"], se)
    out = {}
    for label, res in zip(SEGMENT_LABELS, ex, strict=True):
        out[f"ne_{label}"] = int(res.ne)
        out.update({f"e_{s}_{label}": float(v) for s, v in zip(model.state_names, res.e,
                                                               strict=True)})
    return out


def _roll_sensability(se, roll_axis) -> tuple[np.ndarray, np.ndarray]:
    """Sensability and 1-sigma (rad) of the attitude error about the body x (roll) axis."""
    v = np.zeros((roll_axis.shape[0], se.n))
    v[:, 6:9] = roll_axis
    w = v / np.sqrt(se.d0)
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    proj = np.einsum("kji,kj->ki", se.V, w) ** 2
    keep = np.arange(se.n) < se.nr[:, None]
    sigma = np.sqrt(np.einsum("ki,kij,kj->k", v, se.P, v))
    return np.sqrt(np.sum(proj * keep, axis=1)), sigma


def _sensability_run(prepared, **full) -> dict:
    from navlib.metrics import S_THRESHOLD
    from navlib.studies.rocket import TRANSIENT_S

    model = _rocket_model(prepared, full)
    se = _sensability(model, full)
    later = se.t > se.t[0] + TRANSIENT_S
    s_roll, sigma_roll = _roll_sensability(se, prepared[1])
    out = {"nr_end": int(se.nr[-1]),
           "n_sensible_end": int(np.sum(se.s[-1] >= S_THRESHOLD)),
           "s_end_roll": float(s_roll[-1]),
           "s_frac_roll": float(np.mean(s_roll[later] >= S_THRESHOLD)),
           "sigma_end_roll_deg": float(np.degrees(sigma_roll[-1]))}
    for j, s in enumerate(model.state_names):
        out[f"s_end_{s}"] = float(se.s[-1, j])
        out[f"s_frac_{s}"] = float(np.mean(se.s[later, j] >= S_THRESHOLD))
    return out


def _covariance_run(prepared, **full) -> dict:
    model = _rocket_model(prepared, full)
    se = _sensability(model, full)
    sigma0 = np.sqrt(np.diag(model.P0))
    out = {}
    for j, s in enumerate(model.state_names):
        out[f"sigma_end_{s}"] = float(se.sigma[-1, j])
        out[f"ratio_{s}"] = float(sigma0[j] / se.sigma[-1, j])
    return out


def _nees_run(prepared, *, runs, seed, **full) -> dict:
    from navlib.filters import simulate_linear

    model = _rocket_model(prepared, full)
    sim = simulate_linear(model, runs=int(runs), seed=int(seed))
    c = sim.consistency()
    frame = sim.nees_frame()
    return {"nees_in_bounds": c["nees"], "nees_mean_over_dof": c["nees_mean_over_dof"],
            "nis_in_bounds": c["nis"], "nis_mean_over_dof": c["nis_mean_over_dof"],
            "nees_end": float(frame["nees"].iloc[-1]), "nees_dof_end": int(frame["dof"].iloc[-1])}


def _claims_run(prepared, **full) -> dict:
    from navlib.studies import rocket

    coning = {"coning_deg": full["coning_deg"], "coning_hz": full["coning_hz"]} \
        if full["coning_deg"] else {}
    analysis = rocket.RocketAnalysis.build(
        _rocket_model(prepared, full), rocket.SEGMENTS,
        trajectory=rocket.rocket_trajectory(full["spin_hz"], **coning), eta=full["eta"],
        nu=full["nu"], d0=full["d0"],
        settings={k: full[k] for k in ("spin_hz", "attitude_error", "gnss_sigma_m", "preset",
                                       "imu_grade", "coning_deg")})
    claims = rocket.excitability_claims(analysis) + rocket.sensability_claims(
        analysis, _quiet_gyro_analysis(full))
    passed = {c.claim_id: c.verdict == "reproduced" for c in claims}
    return {**passed, "n_reproduced": int(sum(passed.values()))}


@lru_cache(maxsize=4)
def _quiet_model(spin_hz, coning_deg, coning_hz, preset, imu_grade, gnss_rate_hz,
                 attitude_error):
    """The discretised model of :func:`_rocket_prepare` with the gyro noise scaled by
    ``rocket.QUIET_GYRO_SCALE`` (kept per process: the points of a shared input reuse it)."""
    from navlib.models.ecef import ecef21_at_epochs, imu_noise_densities
    from navlib.studies import rocket

    grade = float(imu_grade)
    noise = {k: v * grade * (rocket.QUIET_GYRO_SCALE if k in rocket.GYRO_NOISE_KEYS else 1.0)
             for k, v in imu_noise_densities(preset).items()}
    coning = {"coning_deg": coning_deg, "coning_hz": coning_hz} if coning_deg else {}
    traj = rocket.rocket_trajectory(spin_hz, **coning)
    return traj, ecef21_at_epochs(traj, gnss_rate_hz, sensors=noise,
                                  attitude_error=attitude_error)


def _quiet_gyro_analysis(full):
    """S5's counterfactual of a "claims" point: the same model with the gyro noise and the
    initial gyro-bias sigma scaled by ``rocket.QUIET_GYRO_SCALE`` (docs/assumptions.md,
    A-S5-cause)."""
    from navlib.models.ecef import parameter_sigmas
    from navlib.studies import rocket

    scale, grade = rocket.QUIET_GYRO_SCALE, float(full["imu_grade"])
    traj, model = _quiet_model(*(full[k] for k in _ROCKET_SHARED))
    bg = full["sigma_bg_deg_s"]
    bg = parameter_sigmas(full["preset"])["sigma_bg_deg_s"] * grade if bg is None else bg
    quiet = {**full, "sigma_bg_deg_s": bg * scale}
    return rocket.RocketAnalysis.build(
        _rocket_model((model, None), quiet), rocket.SEGMENTS, trajectory=traj,
        eta=full["eta"], nu=full["nu"], d0=full["d0"],
        settings={k: full[k] for k in ("spin_hz", "attitude_error", "gnss_sigma_m", "preset",
                                       "imu_grade", "coning_deg")})


# ----- launcher family: Beaudoin et al.'s models along the launcher ascent

_LAUNCHER = {"solution": "ins_gps_att", "biases": "GAP", "bias_model": "markov",
             "duration_s": 150.0, "rate_hz": 200.0}


@lru_cache(maxsize=2)
def _launcher_trajectory(duration_s: float, rate_hz: float):
    from navlib.trajectory import launcher_ascent

    return launcher_ascent(duration_s=duration_s, rate_hz=rate_hz)


def _observability_run(_, *, solution, biases, bias_model, duration_s, rate_hz, stride,
                       variant) -> dict:
    from navlib.models.launcher import launcher
    from navlib.observability import analyze, local_matrix, local_observability

    traj = _launcher_trajectory(float(duration_s), float(rate_hz))
    model = launcher(solution, biases, bias_model, trajectory=traj)
    res = local_observability(model, variant=variant, stride=int(stride), n_jobs=1)
    k = int(res.step[res.step.size // 2])
    mid = analyze(local_matrix(model, k, variant=variant), rtol=res.rtol,
                  state_names=model.state_names)
    out = {"n_states": int(model.n), "n_unobservable": int(res.n_unobservable),
           "log10_cond": float(res.log10_max_cond), "rank_constant": bool(res.rank_constant)}
    out.update({f"unobs_{s}": float(v) for s, v in zip(model.state_names,
                                                       mid.unobservable_share, strict=True)})
    return out


@lru_cache(maxsize=1)
def _outlier_cache(duration_s: float, rate_hz: float):
    from navlib.studies.outliers import FilterCache

    return FilterCache(_launcher_trajectory(duration_s, rate_hz), size=1)


def _outliers_run(_, *, solution, biases, bias_model, duration_s, rate_hz, channel, magnitude,
                  time_s, shape, pulse_s, watch, window_s) -> dict:
    from navlib.outliers import Outlier
    from navlib.studies.outliers import outlier_response

    outlier = Outlier(channel, float(time_s), float(magnitude), shape,
                      None if shape != "pulse" else float(pulse_s))
    res = outlier_response(solution, outlier, watch, biases=biases, bias_model=bias_model,
                           window=float(window_s),
                           cache=_outlier_cache(float(duration_s), float(rate_hz)))
    score = res.score
    return {"applied": bool(res.applied), "verdict": str(score.verdict),
            "recovers": score.verdict == "recovers", "peak": float(score.peak),
            "residual": float(score.residual), "retained": float(score.retained)}


EVALUATIONS: dict[str, Evaluation] = {ev.name: ev for ev in (
    Evaluation("excitability", "rocket flight: e of the 21 states per segment (e_<state>_tauN, "
               "ne_tauN)", {**_ROCKET_SHARED, **_ROCKET_POINT}, tuple(_ROCKET_SHARED),
               _excitability_run, _rocket_prepare),
    Evaluation("sensability", "rocket flight: sensability at the end and share of the epochs "
               "after the transient with s >= 1/sqrt2, per state and for the roll axis",
               {**_ROCKET_SHARED, **_ROCKET_POINT}, tuple(_ROCKET_SHARED), _sensability_run,
               _rocket_prepare),
    Evaluation("covariance", "rocket flight: physical 1-sigma at the end and sigma_0/sigma_end "
               "per state", {**_ROCKET_SHARED, **_ROCKET_POINT}, tuple(_ROCKET_SHARED),
               _covariance_run, _rocket_prepare),
    Evaluation("nees", "rocket flight: linear Monte-Carlo filter consistency (NEES/NIS share "
               "inside the 95 % chi-square bounds)",
               {**_ROCKET_SHARED, **_ROCKET_POINT, "runs": 20, "seed": 0},
               tuple(_ROCKET_SHARED), _nees_run, _rocket_prepare),
    Evaluation("claims", "rocket flight: verdicts of the paper's X1-X7 and S1-S8 statements "
               "(True = reproduced)", {**_ROCKET_SHARED, **_ROCKET_POINT},
               tuple(_ROCKET_SHARED), _claims_run, _rocket_prepare),
    Evaluation("observability", "launcher ascent: local observability (unobservable states, "
               "log10 max condition number; unobservable share per state at mid-mission)",
               {**_LAUNCHER, "stride": 200, "variant": "time_varying"},
               ("duration_s", "rate_hz"), _observability_run),
    Evaluation("outliers", "launcher ascent: outlier recovery verdict of the linear filter "
               "(recovers / static error, peak, residual, retained)",
               {**_LAUNCHER, "channel": "gyro_x", "magnitude": 0.002, "time_s": 50.0,
                "shape": "spike", "pulse_s": 1.0, "watch": "roll", "window_s": 100.0},
               ("duration_s", "rate_hz", "solution", "biases", "bias_model"), _outliers_run),
)}
"""The named evaluations of :func:`sweep`, by name."""


# --------------------------------------------------------------------------- tasks


def _check_row(row, point: Mapping, columns) -> dict:
    if not isinstance(row, Mapping):
        raise NavlibInputError(f"evaluate: must return a mapping of result columns, got "
                               f"{type(row).__name__} at point {dict(point)}")
    clash = [k for k in row if k in columns]
    if clash:
        raise NavlibInputError(f"evaluate: result column(s) {clash} repeat parameter names "
                               f"(point {dict(point)})")
    out = {}
    for k, v in row.items():
        if not isinstance(k, str):
            raise NavlibInputError(f"evaluate: result column names must be strings, got {k!r}")
        v = _plain(v)
        if not (v is None or isinstance(v, (bool, int, float, str))):
            raise NavlibInputError(f"evaluate: result {k!r} must be a number, bool or string, "
                                   f"got {type(v).__name__} at point {dict(point)}")
        out[k] = v
    return out


def _run_batch(evaluate, batch: list, prepared=None) -> tuple[list, float, float]:
    """Evaluate a batch of ``(index, point)``; returns ``[(index, row)]``, wall and CPU
    seconds (the CPU time of this process: the share of a core the task got).

    ``prepared``: the ``(value, seconds)`` of :func:`_prepare_task` for the batch's shared
    input (named evaluations with ``prepare``), or None.
    """
    t0, c0 = time.perf_counter(), time.process_time()
    rows = []
    with _single_thread_blas():
        for index, point in batch:
            if isinstance(evaluate, str):
                ev = EVALUATIONS[evaluate]
                full = ev.complete(point)
                row = ev.run(None if prepared is None else prepared[0], **full)
            else:
                row = evaluate(**point)
            rows.append((index, _check_row(row, point, point.keys())))
    return rows, time.perf_counter() - t0, time.process_time() - c0


def _batches(evaluate, points: list[tuple[int, dict]], size: int) -> list[tuple]:
    """``(shared_key or None, [(index, point), ...])`` batches, never across shared inputs."""
    if isinstance(evaluate, str):
        ev = EVALUATIONS[evaluate]
        groups: dict = {}
        for index, point in points:
            groups.setdefault(ev.shared_key(ev.complete(point)), []).append((index, point))
    else:
        groups = {None: points}
    out = []
    for key, members in groups.items():
        out += [(key, members[i:i + size]) for i in range(0, len(members), size)]
    return out


def _batch_size(n_points: int, n_workers: int, batch_size) -> int:
    if batch_size is not None:
        size = int(batch_size)
        if size < 1 or size != batch_size:
            raise NavlibInputError(f"batch_size: expected a positive integer, got {batch_size!r}")
        return size
    return max(1, min(32, math.ceil(n_points / (4 * n_workers))))


# --------------------------------------------------------------------------- Parquet


def _parts_dir(output: Path) -> Path:
    return output.with_name(output.name + ".parts")


def _metadata(evaluate, columns) -> dict:
    if isinstance(evaluate, str):
        name = evaluate
    else:
        func = getattr(evaluate, "func", evaluate)  # functools.partial
        qual = getattr(func, "__qualname__", None) or type(func).__qualname__
        name = f"{getattr(func, '__module__', '?')}.{qual}"
    return {"evaluate": name, "parameters": list(columns)}


def _write(frame: pd.DataFrame, path: Path, meta: dict) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.Table.from_pandas(frame, preserve_index=False)
    table = table.replace_schema_metadata({**(table.schema.metadata or {}),
                                           _METADATA_KEY: json.dumps(meta).encode()})
    tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex}.tmp")
    try:
        pq.write_table(table, tmp)
        os.replace(tmp, path)
    except (pa.ArrowInvalid, pa.ArrowTypeError) as exc:
        tmp.unlink(missing_ok=True)
        raise NavlibInputError(f"output: cannot write the results to Parquet ({exc}); "
                               f"columns need one type each") from exc


def _parquet(path: Path, name: str) -> tuple[pd.DataFrame, dict | None]:
    """A Parquet file's table and its navlib sweep metadata (None when absent)."""
    import pyarrow.parquet as pq

    try:
        table = pq.read_table(path)
    except Exception as exc:
        raise NavlibInputError(f"{name}: {path} is not a readable Parquet file ({exc})") \
            from exc
    stored = (table.schema.metadata or {}).get(_METADATA_KEY)
    return table.to_pandas(), (json.loads(stored) if stored else None)


def _read(path: Path, meta: dict) -> pd.DataFrame:
    frame, stored = _parquet(path, "output")
    if stored != meta:
        raise NavlibInputError(
            f"output: {path} holds another sweep ({stored or 'not a navlib sweep'}); this one "
            f"is {meta}. Use another output file or delete it")
    return frame


def _load_done(output: Path, meta: dict) -> pd.DataFrame:
    frames = [_read(output, meta)] if output.exists() else []
    parts = _parts_dir(output)
    if parts.is_dir():
        frames += [_read(p, meta) for p in sorted(parts.glob("part-*.parquet"))]
    frames = [f for f in frames if len(f)]
    return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()


# --------------------------------------------------------------------------- sweep


def _validate_evaluate(evaluate, columns, local: bool):
    if isinstance(evaluate, str):
        if evaluate not in EVALUATIONS:
            raise NavlibInputError(f"evaluate: unknown evaluation {evaluate!r}; named "
                                   f"evaluations: {sorted(EVALUATIONS)}")
        reject_unknown(dict.fromkeys(columns), EVALUATIONS[evaluate].parameters,
                       f"grid for evaluation {evaluate!r}")
        return
    if not callable(evaluate):
        raise NavlibInputError(f"evaluate: expected a named evaluation {sorted(EVALUATIONS)} "
                               f"or a callable, got {type(evaluate).__name__}")
    if not local:
        import cloudpickle

        try:
            cloudpickle.dumps(evaluate)
        except Exception as exc:
            raise NavlibInputError(f"evaluate: cannot be pickled for the Dask workers "
                                   f"({exc}); use a module-level function") from exc


def _progress_bar(progress, total: int, desc: str):
    from tqdm.auto import tqdm

    show = total >= _PROGRESS_MIN_POINTS if progress is None else bool(progress)
    return tqdm(total=total, desc=desc, disable=not show)


def sweep(grid, evaluate, scheduler=None, output=None, *, progress: bool | None = None,
          batch_size: int | None = None) -> pd.DataFrame:
    """Map ``evaluate`` over the points of ``grid`` as Dask tasks; one row per point.

    Parameters
    ----------
    grid : dict or DataFrame
        ``name -> list of values`` (the product is swept, first key slowest) or a
        DataFrame of points (:func:`grid_points`).
    evaluate : str or callable
        A name of :data:`EVALUATIONS` (its parameters, with defaults, are the grid's
        possible columns; ``EVALUATIONS[name].description`` says what it returns), or a
        picklable callable ``evaluate(**point)`` returning a mapping of result columns
        (numbers, booleans or strings).
    scheduler : None, str or distributed.Client
        Where to run (module docstring): None = ``$NAVLIB_SCHEDULER`` or a local cluster
        sized to the machine; a Client; ``"tcp://host:port"``; ``"processes"``,
        ``"threads"`` or ``"synchronous"``.
    output : str or Path, optional
        Parquet file for the results. Finished tasks are saved as they complete (in
        ``<output>.parts/``); a rerun with the same grid and evaluation skips the points
        already saved, and the full table replaces ``output`` at the end.
    progress : bool, optional
        Progress bar (tqdm); default shown from 50 pending points.
    batch_size : int, optional
        Points per task (default: about four tasks per worker, at most 32 points; batches
        never mix shared inputs).

    Returns
    -------
    DataFrame
        The parameter columns (grid order) then the result columns, one row per point in
        grid order. ``attrs["sweep"]`` holds ``parameters`` (the parameter columns),
        ``n_points``, ``n_computed`` (points not taken
        from ``output``), ``n_tasks``, ``n_workers``, ``wall_s`` (from submission to the last
        result), ``compute_s`` (wall time spent inside the evaluations), ``compute_cpu_s``
        (their CPU time: below ``compute_s`` when the cores are shared) and ``prepare_s``
        (building the shared inputs).

    Raises
    ------
    NavlibInputError
        A bad grid (empty, scalar values, duplicate points), an unknown evaluation or a
        grid column it does not accept, an unpicklable callable, a bad scheduler, an
        ``output`` holding another sweep, or a result that is not a mapping of scalars.
    """
    points = grid_points(grid)
    columns = list(points.columns)
    _validate_evaluate(evaluate, columns, local=scheduler == "synchronous")
    meta = _metadata(evaluate, columns)
    output = None if output is None else Path(output)
    keys = [_key(row) for row in points.itertuples(index=False)]
    done: dict = {}
    if output is not None:
        if output.suffix != ".parquet":
            raise NavlibInputError(f"output: expected a .parquet file name, got {output}")
        if not output.parent.is_dir():
            raise NavlibInputError(f"output: folder {output.parent} does not exist")
        previous = _load_done(output, meta)
        if len(previous):
            missing = [c for c in columns if c not in previous.columns]
            if missing:  # pragma: no cover - the metadata check already compares columns
                raise NavlibInputError(f"output: saved results lack parameter(s) {missing}")
            results = previous.drop(columns=columns)
            for pkey, rec in zip((_key(r) for r in previous[columns].itertuples(index=False)),
                                 results.to_dict("records"), strict=True):
                done[pkey] = rec
    records = points.to_dict("records")
    todo = [(i, {k: _plain(v) for k, v in records[i].items()})
            for i, k in enumerate(keys) if k not in done]
    rows: dict[int, dict] = {i: done[k] for i, k in enumerate(keys) if k in done}
    stats = {"parameters": columns, "n_points": len(points), "n_computed": len(todo),
             "n_tasks": 0, "n_workers": 0,
             "wall_s": 0.0, "compute_s": 0.0, "compute_cpu_s": 0.0, "prepare_s": 0.0}
    if todo:
        parts = None
        if output is not None:
            parts = _parts_dir(output)
            parts.mkdir(exist_ok=True)

        def save(batch_rows):
            for i, row in batch_rows:
                rows[i] = row
            if parts is not None:
                frame = pd.concat([points.iloc[[i for i, _ in batch_rows]].reset_index(drop=True),
                                   pd.DataFrame([r for _, r in batch_rows])], axis=1)
                _write(frame, parts / f"part-{uuid.uuid4().hex}.parquet", meta)

        desc = f"sweep {evaluate if isinstance(evaluate, str) else meta['evaluate']}"
        with executor(scheduler) as client:
            n_workers = _n_workers(client)
            size = _batch_size(len(todo), n_workers, batch_size)
            batches = _batches(evaluate, todo, size)
            stats.update(n_tasks=len(batches), n_workers=n_workers)
            start = time.perf_counter()
            with _progress_bar(progress, len(todo), desc) as bar:
                if client is None:
                    prepared: dict = {}
                    for key, batch in batches:
                        if _needs_prepare(evaluate) and key not in prepared:
                            prepared = {key: _prepare_task(evaluate, key)}
                            stats["prepare_s"] += prepared[key][1]
                        batch_rows, seconds, cpu = _run_batch(evaluate, batch,
                                                              prepared.get(key))
                        save(batch_rows)
                        stats["compute_s"] += seconds
                        stats["compute_cpu_s"] += cpu
                        bar.update(len(batch_rows))
                else:
                    _run_on(client, evaluate, batches, save, bar, stats)
            stats["wall_s"] = time.perf_counter() - start
    frame = pd.concat([points, pd.DataFrame([rows[i] for i in range(len(points))])], axis=1)
    if output is not None:
        _write(frame, output, meta)
        parts = _parts_dir(output)
        if parts.is_dir():
            for p in parts.glob("part-*.parquet"):
                p.unlink()
            try:
                parts.rmdir()
            except OSError:  # pragma: no cover - a stray file left by the user
                pass
    frame.attrs["sweep"] = stats
    return frame


def _needs_prepare(evaluate) -> bool:
    return isinstance(evaluate, str) and EVALUATIONS[evaluate].prepare is not None


def _seconds(prepared: tuple) -> float:
    return prepared[1]


def _run_on(client, evaluate, batches, save, bar, stats) -> None:
    """Submit the batches (after their shared inputs) and save results as they arrive."""
    from distributed import as_completed

    prepared = {}
    if _needs_prepare(evaluate):
        for key, _ in batches:
            if key not in prepared:
                prepared[key] = client.submit(_prepare_task, evaluate, key, pure=False)
    futures = [client.submit(_run_batch, evaluate, batch, prepared.get(key), pure=False)
               for key, batch in batches]
    try:
        for fut in as_completed(futures):
            batch_rows, seconds, cpu = fut.result()
            save(batch_rows)
            stats["compute_s"] += seconds
            stats["compute_cpu_s"] += cpu
            bar.update(len(batch_rows))
        if prepared:
            stats["prepare_s"] += sum(client.gather(
                [client.submit(_seconds, p, pure=False) for p in prepared.values()]))
    finally:
        client.cancel(futures + list(prepared.values()))


AGGREGATES = ("mean", "min", "max", "median")
"""How :func:`pivot` combines the points that share an ``(x, y)`` cell."""


def parameter_columns(frame: pd.DataFrame) -> list[str]:
    """The parameter columns of a sweep result (from :func:`sweep` or :func:`read`)."""
    params = frame.attrs.get("sweep", {}).get("parameters") \
        if isinstance(frame, pd.DataFrame) else None
    if not params:
        raise NavlibInputError("frame: not a sweep result (no attrs['sweep']['parameters']); "
                               "pass the parameter names explicitly")
    return list(params)


def read(path) -> pd.DataFrame:
    """A sweep result saved by :func:`sweep` (``output=``), parameters in ``attrs``."""
    path = Path(path)
    if not path.is_file():
        raise NavlibInputError(f"path: no sweep result at {path}")
    frame, meta = _parquet(path, "path")
    if meta is None:
        raise NavlibInputError(f"path: {path} is not a navlib sweep result")
    frame.attrs["sweep"] = {"parameters": meta["parameters"], "evaluate": meta["evaluate"]}
    return frame


def pivot(frame: pd.DataFrame, x: str, y: str, value: str, fixed: Mapping | None = None,
          agg: str = "mean") -> pd.DataFrame:
    """A heat-map table of a sweep result: ``value`` by ``y`` (rows) and ``x`` (columns).

    ``fixed`` selects rows (``{column: value}``); the points left in a cell (other
    parameters) are combined with ``agg`` (:data:`AGGREGATES`).
    """
    if not isinstance(frame, pd.DataFrame):
        raise NavlibInputError(f"frame: expected a sweep DataFrame, got {type(frame).__name__}")
    missing = [c for c in (x, y, value, *(fixed or {})) if c not in frame.columns]
    if missing:
        raise NavlibInputError(f"pivot: unknown column(s) {missing}; columns are "
                               f"{list(frame.columns)}")
    if x == y:
        raise NavlibInputError(f"pivot: x and y must differ, both are {x!r}")
    if agg not in AGGREGATES:
        raise NavlibInputError(f"agg: expected one of {AGGREGATES}, got {agg!r}")
    sel = np.ones(len(frame), dtype=bool)
    for col, val in (fixed or {}).items():
        sel &= (frame[col] == val).to_numpy()
    part = frame[sel]
    if part.empty:
        raise NavlibInputError(f"pivot: no point matches {dict(fixed or {})}")
    values = part[value]
    if values.dtype == bool:
        values = values.astype(float)
    if not pd.api.types.is_numeric_dtype(values):
        raise NavlibInputError(f"pivot: value {value!r} is not numeric")
    return part.assign(**{value: values}).pivot_table(index=y, columns=x, values=value,
                                                      aggfunc=agg, dropna=False)


def evaluations_frame() -> pd.DataFrame:
    """The named evaluations: ``name``, ``description``, ``parameters`` (with defaults),
    ``shared`` (the parameters defining the heavy input)."""
    return pd.DataFrame([{"name": ev.name, "description": ev.description,
                          "parameters": ", ".join(f"{k}={v!r}" for k, v in ev.parameters.items()),
                          "shared": ", ".join(ev.shared)} for ev in EVALUATIONS.values()])


