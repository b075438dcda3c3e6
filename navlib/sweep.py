"""Design trade studies: a grid of parameters mapped over an evaluation as parallel tasks.

Contract (docs/sweeps.md):
``df = sweep(grid, evaluate, scheduler=None, output=None)``. ``grid`` is a dict of value
lists (their product is swept) or a DataFrame of points; ``evaluate`` is a named evaluation
of :data:`EVALUATIONS` (studies :func:`register` them when imported) or any picklable
``evaluate(**point) -> mapping``. One row per point, parameter columns first; ``output`` (a
``.parquet`` file) makes the sweep resumable. ``scheduler`` is resolved by
:func:`navlib.parallel.executor`; BLAS runs one thread per task, so serial and cluster
sweeps agree exactly. An evaluation's heavy input (:attr:`Evaluation.shared`) is built once
per distinct value and the points are batched by it.
"""

from __future__ import annotations

import itertools
import json
import math
import os
import time
import uuid
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import cloudpickle
import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
from tqdm.auto import tqdm

from navlib._validation import reject_unknown
from navlib.cache import memoized
from navlib.errors import NavlibInputError
from navlib.parallel import SCHEDULER_ENV, executor, n_workers, single_thread_blas

__all__ = ["AGGREGATES", "EVALUATIONS", "SCHEDULER_ENV", "Evaluation", "evaluation",
           "evaluations_frame", "grid_points", "parameter_columns", "pivot", "read",
           "register", "sweep"]

_METADATA_KEY = b"navlib.sweep"
_PROGRESS_MIN_POINTS = 50
"""Pending points from which ``progress=None`` shows a progress bar."""


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
        prepared = None if self.prepare is None else _prepared(self.prepare,
                                                                self.shared_key(full))
        return self.run(prepared, **full)


@memoized(maxsize=8)
def _prepared(prepare: Callable, key: tuple):
    """The shared input ``prepare(**key)``, kept per process (module-level ``prepare``
    functions unpickle to the same object, so a worker's tasks share it)."""
    return prepare(**dict(key))


def _prepare_task(ev: Evaluation, key: tuple) -> tuple:
    """The shared input of ``key`` and the seconds it took (0 when cached here)."""
    t0 = time.perf_counter()
    with single_thread_blas():
        value = _prepared(ev.prepare, key)
    return value, time.perf_counter() - t0


EVALUATIONS: dict[str, Evaluation] = {}
"""The named evaluations of :func:`sweep`, by name (filled by :func:`register`)."""


def register(ev: Evaluation) -> Evaluation:
    """Add (or replace) a named evaluation; the studies call it when imported."""
    if not isinstance(ev, Evaluation):
        raise NavlibInputError(f"evaluation: expected a navlib.sweep.Evaluation, got "
                               f"{type(ev).__name__}")
    EVALUATIONS[ev.name] = ev
    return ev


def evaluation(name: str) -> Evaluation:
    """The named evaluation ``name``.

    Raises
    ------
    NavlibInputError
        For a name nobody registered, listing the known names (import ``navlib.studies``
        first: the studies register theirs when imported).
    """
    if name not in EVALUATIONS:
        raise NavlibInputError(f"evaluate: unknown evaluation {name!r}; named evaluations: "
                               f"{sorted(EVALUATIONS)}")
    return EVALUATIONS[name]


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
    with single_thread_blas():
        for index, point in batch:
            if isinstance(evaluate, Evaluation):
                full = evaluate.complete(point)
                row = evaluate.run(None if prepared is None else prepared[0], **full)
            else:
                row = evaluate(**point)
            rows.append((index, _check_row(row, point, point.keys())))
    return rows, time.perf_counter() - t0, time.process_time() - c0


def _batches(evaluate, points: list[tuple[int, dict]], size: int) -> list[tuple]:
    """``(shared_key or None, [(index, point), ...])`` batches, never across shared inputs."""
    if isinstance(evaluate, Evaluation):
        groups: dict = {}
        for index, point in points:
            groups.setdefault(evaluate.shared_key(evaluate.complete(point)),
                              []).append((index, point))
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


def _resolve(evaluate, columns, local: bool):
    """The :class:`Evaluation` named ``evaluate``, or the callable itself, checked."""
    if isinstance(evaluate, str):
        ev = evaluation(evaluate)
        reject_unknown(dict.fromkeys(columns), ev.parameters,
                       f"grid for evaluation {evaluate!r}")
        return ev
    if not callable(evaluate):
        raise NavlibInputError(f"evaluate: expected a named evaluation {sorted(EVALUATIONS)} "
                               f"or a callable, got {type(evaluate).__name__}")
    if not local:
        try:
            cloudpickle.dumps(evaluate)
        except Exception as exc:
            raise NavlibInputError(f"evaluate: cannot be pickled for the Dask workers "
                                   f"({exc}); use a module-level function") from exc
    return evaluate


def _progress_bar(progress, total: int, desc: str):
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
        Where to run (:func:`navlib.parallel.executor`): None = ``$NAVLIB_SCHEDULER`` or a
        local cluster; a Client; ``"tcp://host:port"``; ``"processes"``, ``"threads"``...
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
        ``n_points``, ``n_computed`` (points not taken from ``output``), ``n_tasks``,
        ``n_workers``, ``wall_s`` (submission to last result), ``compute_s`` (wall time in
        the evaluations), ``compute_cpu_s`` (their CPU time) and ``prepare_s`` (building
        the shared inputs).

    Raises
    ------
    NavlibInputError
        A bad grid (empty, scalar values, duplicate points), an unknown evaluation or a
        grid column it does not accept, an unpicklable callable, a bad scheduler, an
        ``output`` holding another sweep, or a result that is not a mapping of scalars.
    """
    points = grid_points(grid)
    columns = list(points.columns)
    task = _resolve(evaluate, columns, local=scheduler == "synchronous")
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
            workers = n_workers(client)
            size = _batch_size(len(todo), workers, batch_size)
            batches = _batches(task, todo, size)
            stats.update(n_tasks=len(batches), n_workers=workers)
            start = time.perf_counter()
            with _progress_bar(progress, len(todo), desc) as bar:
                if client is None:
                    prepared: dict = {}
                    for key, batch in batches:
                        if _needs_prepare(task) and key not in prepared:
                            prepared = {key: _prepare_task(task, key)}
                            stats["prepare_s"] += prepared[key][1]
                        batch_rows, seconds, cpu = _run_batch(task, batch,
                                                              prepared.get(key))
                        save(batch_rows)
                        stats["compute_s"] += seconds
                        stats["compute_cpu_s"] += cpu
                        bar.update(len(batch_rows))
                else:
                    _run_on(client, task, batches, save, bar, stats)
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
    return isinstance(evaluate, Evaluation) and evaluate.prepare is not None


def _seconds(prepared: tuple) -> float:
    return prepared[1]


def _run_on(client, evaluate, batches, save, bar, stats) -> None:
    """Submit the batches (after their shared inputs) and save results as they arrive."""
    from distributed import as_completed  # heavy (dask.distributed): only with a cluster

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

    Parameters
    ----------
    frame : pandas.DataFrame
        A sweep result (one row per grid point).
    x, y : str
        Columns spread along the table's columns and rows.
    value : str
        Numeric column shown in the cells.
    fixed : mapping, optional
        ``{column: value}`` rows to keep before pivoting.
    agg : str, optional
        How the points in one cell (other parameters) combine: one of :data:`AGGREGATES`.

    Returns
    -------
    pandas.DataFrame
        ``value`` with ``y`` as index and ``x`` as columns.

    Raises
    ------
    NavlibInputError
        A frame that is no DataFrame, an unknown or non-numeric column, ``x == y``, an
        unknown ``agg`` or no row matching ``fixed``.
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
    """The named evaluations: name, description, parameters (with defaults), shared."""
    return pd.DataFrame([{"name": ev.name, "description": ev.description,
                          "parameters": ", ".join(f"{k}={v!r}" for k, v in ev.parameters.items()),
                          "shared": ", ".join(ev.shared)} for ev in EVALUATIONS.values()])


