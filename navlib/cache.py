"""On-disk cache of deterministic builders, keyed by a content hash of their inputs.

Several notebooks build the same trajectories and discretised models (the sounding rocket
and its 21-state model at the GNSS epochs in 00, 01, 03, 04 and 08; the launcher ascent in
00, 01, 02, 05 and 08). :func:`cached` stores a builder's result on disk under a hash of

* the builder's qualified name,
* its bound arguments (defaults applied), encoded exactly: arrays by dtype, shape and bytes,
  floats by their hexadecimal form, mappings in sorted order, dataclasses (a
  :class:`~navlib.trajectory.Trajectory`) field by field, rotations by their quaternions;
* a salt: the navlib version, the source text of every navlib module the builder's module
  imports (directly or through others, imports inside functions included) and the shipped
  sensor presets, so editing any of them invalidates the entries.

An argument the encoder does not know (an open file, a callable) makes the call bypass the
cache: the builder runs as if undecorated. So does a builder that raises (its exception is
never stored). The cache never changes a number: an entry holds the pickled result, which
unpickles to arrays bitwise equal to a fresh build (``tests/test_cache.py`` compares each
cached builder with an uncached call).

Location and bounds (environment variables, read at every call):

* ``NAVLIB_CACHE_DIR``: the folder; default ``$XDG_CACHE_HOME/navlib`` or
  ``~/.cache/navlib``;
* ``NAVLIB_CACHE_MAX_MB``: size bound of the folder (default :data:`DEFAULT_MAX_MB`); after
  each write the least recently used entries are deleted until it holds; a result larger
  than a quarter of the bound is not stored;
* ``NAVLIB_NO_CACHE=1``: nothing is read or written (``python -m navlib report --no-cache``
  sets it in its kernels; the test suite sets it except in the cache tests).

Entries are written to a temporary file in the folder and renamed into place
(:func:`os.replace`), so concurrent kernels never read a half-written entry; an entry that
does not unpickle, or that holds another key, is deleted and rebuilt. Entries are pickles
and are only ever read from the user's own cache folder: do not point ``NAVLIB_CACHE_DIR``
at a folder others can write to.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import inspect
import os
import pickle
import re
import struct
import tempfile
import time
from collections.abc import Callable, Mapping
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from navlib import __version__
from navlib.resources import data_dir

__all__ = ["DEFAULT_MAX_MB", "Scope", "cache_dir", "cached", "clear_memos",
           "drop_stale_kernel_caches", "enabled", "key", "max_bytes", "memoized", "salt",
           "source_closure", "stats"]

DEFAULT_MAX_MB = 1024.0
"""Default size bound of the cache folder, MB."""

ENV_DIR, ENV_MAX_MB, ENV_OFF = "NAVLIB_CACHE_DIR", "NAVLIB_CACHE_MAX_MB", "NAVLIB_NO_CACHE"
_SUFFIX = ".pickle"
_STALE_TEMP_S = 3600.0  # a temporary file this old belongs to a writer that was killed

_stats = {"hits": 0, "misses": 0, "bypassed": 0, "rebuilt": 0}


class _Unencodable(TypeError):
    """An argument the key encoder does not know (the call then bypasses the cache)."""


# --------------------------------------------------------------------------- settings


def enabled() -> bool:
    """False when ``NAVLIB_NO_CACHE`` is set to anything but ``""`` or ``"0"``."""
    return os.environ.get(ENV_OFF, "") in ("", "0")


def cache_dir() -> Path:
    """The cache folder (``NAVLIB_CACHE_DIR``, else ``$XDG_CACHE_HOME/navlib``, else
    ``~/.cache/navlib``); not created here."""
    if os.environ.get(ENV_DIR):
        return Path(os.environ[ENV_DIR]).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base).expanduser() / "navlib"


def max_bytes() -> int:
    """The size bound of the cache folder, bytes (``NAVLIB_CACHE_MAX_MB``)."""
    text = os.environ.get(ENV_MAX_MB, "")
    try:
        mb = float(text) if text else DEFAULT_MAX_MB
    except ValueError:
        mb = DEFAULT_MAX_MB
    return int(max(mb, 0.0) * 1e6)


def stats() -> dict[str, int]:
    """Counts of this process: ``hits``, ``misses`` (built and stored), ``bypassed`` (cache
    disabled or an argument it cannot key on) and ``rebuilt`` (corrupt entries replaced)."""
    return dict(_stats)


# --------------------------------------------------------------------------- keys


def _encode(value, out: list) -> None:
    """Append an exact, type-tagged byte encoding of ``value`` to ``out``."""
    if isinstance(value, np.ndarray | np.generic):  # before float: np.float64 is a float
        array = np.ascontiguousarray(value)
        if array.dtype.hasobject:
            raise _Unencodable("object array")
        out.append(f"{type(value).__name__}:{array.dtype.str}:{array.shape};".encode())
        out.append(array.tobytes())
    elif value is None or isinstance(value, bool | int | str):
        out.append(f"{type(value).__name__}:{value!r};".encode())
    elif isinstance(value, float):
        out.append(f"float:{value.hex()};".encode())
    elif isinstance(value, tuple | list):
        out.append(f"{type(value).__name__}:{len(value)}[".encode())
        for item in value:
            _encode(item, out)
        out.append(b"]")
    elif isinstance(value, Mapping):
        items = []
        for key, item in value.items():
            parts: list = []
            _encode(key, parts)
            _encode(item, parts)
            items.append(b"".join(parts))
        out.append(f"mapping:{len(items)}{{".encode() + b"".join(sorted(items)) + b"}")
    elif dataclasses.is_dataclass(value) and not isinstance(value, type):
        cls = type(value)
        out.append(f"dataclass:{cls.__module__}.{cls.__qualname__}(".encode())
        for f in dataclasses.fields(value):
            out.append(f"{f.name}=".encode())
            _encode(getattr(value, f.name), out)
        out.append(b")")
    elif isinstance(value, Rotation):
        out.append(b"rotation:")
        _encode(value.as_quat(), out)
    else:
        raise _Unencodable(type(value).__name__)


_FROM = re.compile(r"^[ \t]*from[ \t]+(\.*[\w.]*)[ \t]+import[ \t]+(\([^)]*\)|[^\n]*)", re.M)
_IMPORT = re.compile(r"^[ \t]*import[ \t]+([^\n]*)", re.M)
_COMMENT = re.compile(r"#[^\n]*")


def _first_words(names: str) -> list[str]:
    """``"a as b, c"`` (comments, parentheses and line breaks allowed) -> ``["a", "c"]``."""
    items = _COMMENT.sub("", names).strip().strip("()").split(",")
    return [item.split()[0] for item in items if item.split()]


def _navlib_imports(module: str, source: str, is_package: bool) -> set[str]:
    """Names of the navlib modules (and candidate submodules) imported anywhere in
    ``source``, at the top or inside functions (a line scan: ``import`` and ``from ...
    import`` statements, relative ones resolved; a match inside a docstring only adds a
    dependency, which is safe)."""
    names = set(_first_words(" ".join(m.group(1) for m in _IMPORT.finditer(source))))
    for match in _FROM.finditer(source):
        base = match.group(1)
        level = len(base) - len(base.lstrip("."))
        if level:
            package = module if is_package else module.rpartition(".")[0]
            for _ in range(level - 1):
                package = package.rpartition(".")[0]
            base = f"{package}.{base[level:]}" if base[level:] else package
        names.add(base)
        names.update(f"{base}.{name}" for name in _first_words(match.group(2)))
    return {n for n in names if n == "navlib" or n.startswith("navlib.")}


def _module_source(name: str) -> tuple[bytes, bool] | None:
    """Source bytes of navlib module ``name`` and whether it is a package, found from the
    package folder without importing anything (None: no such module, e.g. a function name
    imported from a package)."""
    top, *parts = name.split(".")
    if top != "navlib":
        return None
    base = Path(__file__).resolve().parent.joinpath(*parts)
    for path, is_package in ((base / "__init__.py", True), (base.with_suffix(".py"), False)):
        if parts or is_package:
            try:
                return path.read_bytes(), is_package
            except OSError:
                continue
    return None


@functools.cache
def source_closure(module: str) -> tuple[str, ...]:
    """The navlib modules ``module`` depends on: itself, every navlib module it imports
    (at the top or inside functions; a package for the names it re-exports) and,
    recursively, theirs; sorted."""
    seen: set[str] = set()
    todo = [module]
    while todo:
        name = todo.pop()
        if name in seen:
            continue
        found = _module_source(name)
        if found is None:
            continue
        source, is_package = found
        seen.add(name)
        todo += _navlib_imports(name, source.decode("utf-8"), is_package)
    return tuple(sorted(seen))


def _module_path(name: str) -> Path | None:
    """The source file of navlib module ``name`` (None when there is none)."""
    base = Path(__file__).resolve().parent.joinpath(*name.split(".")[1:])
    for path in (base / "__init__.py", base.with_suffix(".py")):
        if path.is_file():
            return path
    return None


def drop_stale_kernel_caches(module: str, namespace: Mapping) -> None:
    """Delete the numba cache index of each compiled kernel defined in ``module`` that is
    older than a kernel module it depends on.

    numba compares a cached kernel with its own source file only (numba issue #1833): a
    kernel that compiles in kernels of other modules (the EKF's loop, the Kalman algebra's
    sparse prediction) would keep running their old code after they change, in a checkout
    where they were edited. The dependencies are the modules of :func:`source_closure`
    that define compiled kernels (their source says ``njit``); a deleted index makes numba
    compile afresh on first use. A dispatcher without numba's usual cache attributes is
    left alone.

    Parameters
    ----------
    module : str
        The kernel module's name (its ``__name__``).
    namespace : Mapping
        Its globals: the dispatchers whose ``__module__`` is ``module`` are checked.
    """
    paths = [_module_path(name) for name in source_closure(module)]
    newest = max((path.stat().st_mtime for path in paths
                  if path is not None and b"njit" in path.read_bytes()), default=None)
    if newest is None:
        return
    for value in list(namespace.values()):
        if getattr(value, "__module__", None) != module:
            continue
        index = getattr(getattr(getattr(value, "_cache", None), "_cache_file", None),
                        "_index_path", None)
        if index is None:
            continue
        try:
            if os.stat(index).st_mtime < newest:
                os.remove(index)
        except OSError:
            continue


@functools.cache
def salt(module: str) -> str:
    """Hex digest of the navlib version, the source of :func:`source_closure` of
    ``module`` and the shipped sensor presets: entries made under another salt are never
    read."""
    digest = hashlib.sha256(f"navlib {__version__};".encode())
    for name in source_closure(module):
        digest.update(f"{name}:".encode())
        digest.update(_module_source(name)[0])
    for path in sorted((data_dir() / "sensors").glob("*.toml")):
        digest.update(f"{path.name}:".encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def _digest(parts: list) -> str:
    digest = hashlib.sha256()
    for part in parts:
        digest.update(struct.pack("<Q", len(part)))
        digest.update(part)
    return digest.hexdigest()


def key(fn: Callable, args: tuple, kwargs: dict) -> str:
    """Content hash of a call of ``fn``: its qualified name, its bound arguments and
    :func:`salt` of its module.

    Parameters
    ----------
    fn : callable
        The builder.
    args : tuple
        Positional arguments of the call.
    kwargs : dict
        Keyword arguments of the call.

    Returns
    -------
    str
        Hex digest.

    Raises
    ------
    TypeError
        For an argument it cannot encode.
    """
    bound = inspect.signature(fn).bind(*args, **kwargs)
    bound.apply_defaults()
    parts = [f"{fn.__module__}.{fn.__qualname__};{salt(fn.__module__)};".encode()]
    _encode(dict(bound.arguments), parts)
    return _digest(parts)


# --------------------------------------------------------------------------- storage


def _load(path: Path, digest: str):
    """``(True, value)`` for a good entry, ``(False, None)`` when there is none; a corrupt
    entry (or one holding another key) is deleted and reported as none."""
    try:
        data = path.read_bytes()
    except OSError:  # no entry (or an unreadable one: then it is rebuilt and replaced)
        return False, None
    try:
        stored, value = pickle.loads(data)
        if stored != digest:
            raise ValueError("entry holds another key")
    except Exception:  # a damaged pickle raises many types; the entry is rebuilt
        _stats["rebuilt"] += 1
        _remove(path)
        return False, None
    try:
        os.utime(path)  # most recently used
    except OSError:
        pass
    return True, value


def _remove(path: Path) -> None:
    try:
        path.unlink()
    except OSError:
        pass


def _store(folder: Path, path: Path, digest: str, value) -> None:
    """Write the entry atomically, then keep the folder within its bound (a cache that
    cannot be written is skipped, never an error of the build)."""
    try:
        data = pickle.dumps((digest, value), protocol=pickle.HIGHEST_PROTOCOL)
    except Exception:  # an unpicklable result is simply not cached
        return
    bound = max_bytes()
    if len(data) > bound / 4:
        return
    try:
        folder.mkdir(parents=True, exist_ok=True)
        handle, temp = tempfile.mkstemp(prefix=f".tmp-{os.getpid()}-", dir=folder)
        try:
            with os.fdopen(handle, "wb") as file:
                file.write(data)
            os.replace(temp, path)
        except BaseException:
            _remove(Path(temp))
            raise
    except OSError:
        return
    _evict(folder, bound)


def _evict(folder: Path, bound: int) -> None:
    """Delete least recently used entries until the folder holds at most ``bound`` bytes;
    delete temporary files left by killed writers."""
    entries = []
    now = time.time()
    for path in folder.iterdir():
        try:
            info = path.stat()
        except OSError:
            continue
        if path.name.startswith(".tmp-"):
            if now - info.st_mtime > _STALE_TEMP_S:
                _remove(path)
        elif path.suffix == _SUFFIX:
            entries.append((info.st_mtime, info.st_size, path))
    total = sum(size for _, size, _ in entries)
    for _, size, path in sorted(entries):
        if total <= bound:
            break
        _remove(path)
        total -= size


# --------------------------------------------------------------------------- decorator


def cached(fn: Callable) -> Callable:
    """Decorate a deterministic builder so its results are kept on disk (module docstring).

    The wrapped function has the same signature, docstring and errors; its result is a
    fresh object on every call (unpickled from the entry, or built), equal to what the
    undecorated builder returns.
    """

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        if not enabled():
            _stats["bypassed"] += 1
            return fn(*args, **kwargs)
        try:
            digest = key(fn, args, kwargs)
        except TypeError:  # unbindable call (the builder raises it) or unencodable argument
            _stats["bypassed"] += 1
            return fn(*args, **kwargs)
        folder = cache_dir()
        path = folder / f"{fn.__qualname__.replace('.', '-')}-{digest[:32]}{_SUFFIX}"
        found, value = _load(path, digest)
        if found:
            _stats["hits"] += 1
            return value
        value = fn(*args, **kwargs)
        _stats["misses"] += 1
        _store(folder, path, digest, value)
        return value

    return wrapper


# --------------------------------------------------------------------------- scopes


class Scope:
    """Entries of one computation context, item by item: for results a caller computes
    several at a time but reads one by one (the outlier responses of a filter).

    The context is ``module`` (its :func:`salt`), a ``label`` and ``values`` (encoded as
    builder arguments, e.g. a trajectory and model options), hashed once; an item (any
    encodable value) adds its own encoding. :meth:`get` and :meth:`put` are no-ops when the
    cache is disabled or a value cannot be encoded, like a bypassed builder.
    """

    def __init__(self, module: str, label: str, *values):
        self.label = label
        parts = [f"{module}.{label};{salt(module)};".encode()]
        try:
            _encode(list(values), parts)
        except _Unencodable:
            self._digest = None
        else:
            self._digest = _digest(parts)

    def _entry(self, item):
        if self._digest is None or not enabled():
            return None
        parts = [self._digest.encode()]
        try:
            _encode(item, parts)
        except _Unencodable:
            return None
        digest = _digest(parts)
        return digest, cache_dir() / f"{self.label}-{digest[:32]}{_SUFFIX}"

    def get(self, item) -> tuple[bool, object]:
        """``(True, value)`` for an item kept before, else ``(False, None)``."""
        entry = self._entry(item)
        if entry is None:
            _stats["bypassed"] += 1
            return False, None
        found, value = _load(entry[1], entry[0])
        _stats["hits" if found else "misses"] += 1
        return found, value

    def put(self, item, value) -> None:
        """Keep ``value`` for ``item`` (atomic write, as a builder's result).

        Parameters
        ----------
        item : object
            Encodable key within the scope.
        value : object
            Picklable result.
        """
        entry = self._entry(item)
        if entry is not None:
            _store(entry[1].parent, entry[1], entry[0], value)


# --------------------------------------------------------------------------- in-process memos

_MEMOS: list = []


def memoized(maxsize: int = 4) -> Callable[[Callable], Callable]:
    """Keep a study's last ``maxsize`` results in the process (:func:`functools.lru_cache`).

    The one in-process memoisation of navlib: a study's experiment (a claims grid, a table at
    every step) is computed once per argument set and shared by the claims, the notebook and
    the panels that read it. Results are returned as built (not copied): callers must not
    modify them. :func:`clear_memos` empties every memo (tests that change the environment
    between calls use it). On-disk keeping across processes is :func:`cached`.
    """

    def decorate(fn: Callable) -> Callable:
        memo = functools.lru_cache(maxsize=maxsize)(fn)
        _MEMOS.append(memo)
        return memo

    return decorate


def clear_memos() -> None:
    """Empty every :func:`memoized` memo of this process."""
    for memo in _MEMOS:
        memo.cache_clear()
