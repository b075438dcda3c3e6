"""The on-disk cache of builders (navlib.cache): cached results equal uncached ones bit for
bit, damaged entries are rebuilt, the salt follows the source, ``--no-cache`` reaches the
kernels. conftest.py turns the cache off for every other test; the ``cache_on`` fixture turns
it on here, in the test's own folder."""

import dataclasses
import os
import pickle
import time
import types
from pathlib import Path

import nbformat
import numpy as np
import pandas as pd
import pytest
from scipy.spatial.transform import Rotation

from navlib import cache, kalman, strapdown
from navlib.models import ecef
from navlib.trajectory import launcher_ascent, sounding_rocket

SHORT_ROCKET = {"ignition_s": 2.0, "burnout_s": 12.0, "free_flight_s": 15.0,
                "despin_s": 18.0, "end_s": 22.0}
"""A 22 s flight: the code path of the default 86 s one at a quarter of the cost."""


@pytest.fixture
def cache_on(tmp_path, monkeypatch):
    folder = tmp_path / "cache"
    monkeypatch.delenv(cache.ENV_OFF, raising=False)
    monkeypatch.setenv(cache.ENV_DIR, str(folder))
    monkeypatch.delenv(cache.ENV_MAX_MB, raising=False)
    return folder


def _uncached(monkeypatch, build):
    with monkeypatch.context() as m:
        m.setenv(cache.ENV_OFF, "1")
        return build()


def _same(a, b, where="result"):
    """Bitwise equality of two results (arrays by dtype, shape and bytes)."""
    if isinstance(a, np.ndarray):
        assert isinstance(b, np.ndarray), where
        assert (a.dtype, a.shape) == (b.dtype, b.shape), where
        assert np.ascontiguousarray(a).tobytes() == np.ascontiguousarray(b).tobytes(), where
    elif isinstance(a, Rotation):
        _same(a.as_quat(), b.as_quat(), where)
    elif dataclasses.is_dataclass(a):
        assert type(a) is type(b), where
        for f in dataclasses.fields(a):
            _same(getattr(a, f.name), getattr(b, f.name), f"{where}.{f.name}")
    elif isinstance(a, dict):
        assert a.keys() == b.keys(), where
        for k in a:
            _same(a[k], b[k], f"{where}[{k!r}]")
    elif isinstance(a, float) and np.isnan(a):
        assert isinstance(b, float) and np.isnan(b), where
    else:
        assert type(a) is type(b) and a == b, where


def _entries(folder):
    return sorted(folder.glob("*.pickle"))


@pytest.mark.parametrize("build", [
    lambda: sounding_rocket(**SHORT_ROCKET),
    lambda: launcher_ascent(duration_s=20.0, rate_hz=50.0),
], ids=["sounding_rocket", "launcher_ascent"])
def test_cached_trajectory_equals_uncached_bitwise(cache_on, monkeypatch, build):
    fresh = _uncached(monkeypatch, build)
    before = cache.stats()
    first, second = build(), build()  # built and stored, then read back
    after = cache.stats()
    assert (after["misses"] - before["misses"], after["hits"] - before["hits"]) == (1, 1)
    assert len(_entries(cache_on)) == 1
    assert second is not first
    _same(fresh, first)
    _same(fresh, second)


def test_cached_rocket_model_equals_uncached_bitwise(cache_on, monkeypatch):
    def build():
        # a new trajectory object each time (read from the cache), so the in-memory cache
        # of ecef21_at_epochs (by object identity) misses and the disk entry is read
        return ecef.ecef21_at_epochs(sounding_rocket(**SHORT_ROCKET), attitude_error="body",
                                     gnss_sigma_m=3.0)

    fresh = _uncached(monkeypatch, build)
    before = cache.stats()
    first, second = build(), build()  # rocket and model built, then both read back
    after = cache.stats()
    assert (after["misses"] - before["misses"], after["hits"] - before["hits"]) == (2, 2)
    for model in (first, second):
        _same(fresh, model)
        assert not model.F.flags.writeable and not model.Q.flags.writeable


def test_arguments_are_keyed_exactly():
    def call(*args, **kwargs):
        return cache.key(sounding_rocket, args, kwargs)

    base = call(spin_hz=2.0)
    assert call(spin_hz=2.0) == base
    assert call(spin_hz=np.nextafter(2.0, 3.0)) != base  # floats exactly
    assert call(spin_hz=2) != base                        # int is not float
    assert call(spin_hz=np.float64(2.0)) != base
    assert call(spin_hz=2.0, end_s=80.0) == call(end_s=80.0, spin_hz=2.0)

    def total(x, scale=1.0):
        return scale * np.sum(x)

    def arrays(x):
        return cache.key(total, (x,), {})

    x = np.arange(6.0)
    assert arrays(x) == arrays(x.copy()) == cache.key(total, (x, 1.0), {})  # defaults bound
    assert arrays(x) != arrays(x.reshape(2, 3))          # shape
    assert arrays(x) != arrays(x.astype(np.float32))     # dtype
    with pytest.raises(TypeError):
        arrays(object())


def test_unencodable_argument_bypasses_the_cache(cache_on):
    calls = []

    @cache.cached
    def build(x):
        calls.append(x)
        return np.ones(3)

    marker = object()
    before = cache.stats()["bypassed"]
    build(marker)
    build(marker)
    assert calls == [marker, marker] and cache.stats()["bypassed"] == before + 2
    assert not cache_on.exists()


@pytest.mark.parametrize("damage", ["garbage", "truncated", "other key"])
def test_corrupt_entry_is_rebuilt(cache_on, monkeypatch, damage):
    def build():
        return launcher_ascent(duration_s=20.0, rate_hz=50.0)

    fresh = _uncached(monkeypatch, build)
    build()
    (entry,) = _entries(cache_on)
    good = entry.read_bytes()
    if damage == "garbage":
        entry.write_bytes(b"not a pickle")
    elif damage == "truncated":
        entry.write_bytes(good[: len(good) // 2])
    else:
        _, value = pickle.loads(good)
        entry.write_bytes(pickle.dumps(("0" * 64, value)))
    before = cache.stats()
    _same(fresh, build())
    after = cache.stats()
    assert after["rebuilt"] == before["rebuilt"] + 1
    assert after["misses"] == before["misses"] + 1
    assert entry.read_bytes() == good  # replaced by a good entry
    _same(fresh, build())
    assert cache.stats()["hits"] == after["hits"] + 1


def test_salt_follows_the_source_of_the_modules_involved(monkeypatch):
    closure = cache.source_closure("navlib.trajectory.rocket")
    assert {"navlib.trajectory.rocket", "navlib.trajectory._flight", "navlib.earth",
            "navlib.cache"} <= set(closure)
    assert "navlib.models.ecef" not in closure  # not imported by the rocket builder
    # imports inside functions count: the launcher model imports its default trajectory
    # lazily
    assert "navlib.trajectory.launcher" in cache.source_closure("navlib.models.launcher")
    modules = ("navlib.trajectory.rocket", "navlib.discretize")
    original = {m: cache.salt(m) for m in modules}
    real_source = cache._module_source

    def edited(name):
        found = real_source(name)
        if name == "navlib.trajectory._flight":
            return found[0] + b"\n# edited\n", found[1]
        return found

    cache.salt.cache_clear()
    cache.source_closure.cache_clear()
    try:
        monkeypatch.setattr(cache, "_module_source", edited)
        assert cache.salt("navlib.trajectory.rocket") != original["navlib.trajectory.rocket"]
        assert cache.salt("navlib.discretize") == original["navlib.discretize"]  # unrelated
    finally:
        monkeypatch.undo()
        cache.salt.cache_clear()
        cache.source_closure.cache_clear()
    assert {m: cache.salt(m) for m in modules} == original


def test_size_bound_drops_least_recently_used(cache_on, monkeypatch):
    monkeypatch.setenv(cache.ENV_MAX_MB, "0.7")  # room for four entries of 0.16 MB

    @cache.cached
    def block(seed):
        return np.full(20_000, float(seed))

    for seed in range(4):
        block(seed)
    block(0)  # read again: now the most recently used
    block(4)  # a fifth entry: the least recently used one (seed 1) goes
    kept = {pickle.loads(p.read_bytes())[1][0] for p in _entries(cache_on)}
    assert kept == {0.0, 2.0, 3.0, 4.0}
    monkeypatch.setenv(cache.ENV_MAX_MB, "0.5")
    block(5)  # larger than a quarter of the bound: not stored
    assert len(_entries(cache_on)) == 4 and not list(cache_on.glob(".tmp-*"))


def test_entries_appear_by_rename_only(cache_on, monkeypatch):
    """A reader never sees a partial entry: the final name appears with os.replace."""
    seen = []
    real_replace = cache.os.replace

    def replace(src, dst):
        seen.append((Path(src).parent, Path(dst).exists(), Path(src).stat().st_size))
        real_replace(src, dst)

    monkeypatch.setattr(cache.os, "replace", replace)
    launcher_ascent(duration_s=5.0, rate_hz=20.0)
    ((folder, existed, size),) = seen
    assert folder == cache_on and not existed
    assert size == _entries(cache_on)[0].stat().st_size


def test_disabled_cache_reads_and_writes_nothing(cache_on, monkeypatch):
    monkeypatch.setenv(cache.ENV_OFF, "1")
    before = cache.stats()["bypassed"]
    launcher_ascent(duration_s=5.0, rate_hz=20.0)
    assert cache.stats()["bypassed"] == before + 1 and not cache_on.exists()


PROBE = """\
import os
from navlib import cache
from navlib.trajectory import launcher_ascent
launcher_ascent(duration_s=5.0, rate_hz=20.0)
s = cache.stats()
print(f"no_cache={os.environ.get('NAVLIB_NO_CACHE')} hits={s['hits']} misses={s['misses']} "
      f"bypassed={s['bypassed']}")
"""


@pytest.mark.notebook
def test_no_cache_reaches_the_kernels_and_forces_a_rebuild(cache_on, tmp_path):
    from navlib.__main__ import main

    nbdir = tmp_path / "notebooks"
    nbdir.mkdir()
    nb = nbformat.v4.new_notebook()
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3",
                                 "language": "python"}
    nb.cells.append(nbformat.v4.new_code_cell(PROBE))
    nbformat.write(nb, nbdir / "01_probe.ipynb")
    out = tmp_path / "out"

    def probe(*flags):
        assert main(["report", "--notebooks", str(nbdir), "--output", str(out), *flags]) == 0
        executed = nbformat.read(out / "01_probe.ipynb", as_version=4)
        return "".join(o.get("text", "") for o in executed.cells[0].outputs).strip()

    assert probe() == "no_cache=None hits=0 misses=1 bypassed=0"  # built and stored
    assert probe() == "no_cache=None hits=1 misses=0 bypassed=0"  # read back
    assert probe("--no-cache") == "no_cache=1 hits=0 misses=0 bypassed=1"  # rebuilt
    assert len(_entries(cache_on)) == 1


def test_scope_keeps_items_apart_and_follows_its_context(cache_on):
    traj = launcher_ascent(duration_s=5.0, rate_hz=20.0)
    scope = cache.Scope("navlib.studies.outliers", "test", traj, {"a1_sign": 1.0})
    assert scope.get(("x", 1)) == (False, None)
    scope.put(("x", 1), np.arange(3.0))
    found, value = scope.get(("x", 1))
    assert found
    _same(value, np.arange(3.0))
    assert scope.get(("x", 2)) == (False, None)                  # another item
    other = cache.Scope("navlib.studies.outliers", "test", traj, {"a1_sign": -1.0})
    assert other.get(("x", 1)) == (False, None)                  # another context
    assert cache.Scope("navlib.studies.outliers", "test", traj, {"f": print}).get(1) \
        == (False, None)                                         # unencodable: bypassed


def test_outlier_results_are_read_back_bitwise_without_preparing(cache_on, monkeypatch):
    from navlib.sensors.faults import Outlier
    from navlib.studies import outliers as study

    traj = launcher_ascent(duration_s=20.0, rate_hz=20.0)
    requests = [(Outlier("gnss_vel_x", 10.0, 3.0), "roll"), (Outlier("gyro_x", 8.0, 0.1), "bp")]

    def read(fresh):
        got = fresh.unit_responses("ins_gps_rt", requests), fresh.summary("ins_gps_rt")
        return got, fresh

    (computed, summary), first = read(study.FilterCache(traj, a1_sign=-1.0))
    assert first._items                                          # a filter was prepared
    (loaded, summary_loaded), second = read(study.FilterCache(traj, a1_sign=-1.0))
    assert not second._items                                     # read from the disk
    for a, b in zip(computed, loaded, strict=True):
        _same(a, b)
    _same(summary, summary_loaded)
    (_, _), third = read(study.FilterCache(traj, a1_sign=1.0))   # other model options
    assert third._items
    monkeypatch.setenv(cache.ENV_OFF, "1")
    (uncached, _), _ = read(study.FilterCache(traj, a1_sign=-1.0))
    for a, b in zip(computed, uncached, strict=True):
        _same(a, b)


def test_covariance_evolution_variants_are_read_back_bitwise(cache_on, monkeypatch):
    from navlib.studies import launcher as study

    traj = launcher_ascent(duration_s=10.0, rate_hz=20.0)
    cases = dict(list(study.EVOLUTION_CASES.items())[:2])
    kws = [{"sigma0_att": np.radians(0.03)}, {}]
    baseline = study.covariance_evolution(traj, cases=cases)
    before = cache.stats()
    both = study.evolution._evolution_tables(traj, cases, False, kws)      # {} read, one built
    assert cache.stats()["hits"] - before["hits"] == 1
    assert len(list(cache_on.glob("covariance_evolution-*"))) == 2
    with monkeypatch.context() as m:
        m.setenv(cache.ENV_OFF, "1")
        fresh = study.evolution._evolution_tables(traj, cases, False, kws)
    for got, want in zip([*both, baseline], [*fresh, fresh[1]], strict=True):
        pd.testing.assert_frame_equal(got, want, check_exact=True)


def test_claims_reading_of_a_sensitivity_variant_prepares_no_filter(cache_on, monkeypatch):
    """Notebook 05's sensitivity variant keeps the T4 divergence response it does not
    report, so the claims engine's study of the same model (notebook 00, a1_sign = -1,
    divergence reported) reads everything from the disk."""
    from navlib.studies import outliers as study

    traj = launcher_ascent(duration_s=20.0, rate_hz=20.0)
    options = dict(outlier_time_s=8.0, window=5.0)
    study.assumption_sensitivity({"text's A1": {"a1_sign": -1.0}}, traj, **options)

    def no_preparation(*args, **kwargs):
        raise AssertionError("a filter was prepared")

    with monkeypatch.context() as m:
        m.setattr(study.response, "prepare_linear", no_preparation)
        st, _ = study.study_claims(study.FilterCache(traj, a1_sign=-1.0), shapes=("spike",),
                                   **options)
    assert ("T4", "ins_gps_att_rt", "divergence") in st.responses
    monkeypatch.setenv(cache.ENV_OFF, "1")
    fresh, _ = study.study_claims(study.FilterCache(traj, a1_sign=-1.0), shapes=("spike",),
                                  **options)
    for key, response in fresh.responses.items():
        np.testing.assert_array_equal(st.responses[key].induced, response.induced)


def _fake_kernel(module: str, index):
    """An object shaped like a numba dispatcher with an on-disk cache index."""
    cache_file = types.SimpleNamespace(_index_path=str(index))
    return types.SimpleNamespace(__module__=module, _cache=types.SimpleNamespace(
        _cache_file=cache_file))


def test_a_kernel_index_older_than_a_kernel_it_calls_is_dropped(tmp_path):
    """numba checks a cached kernel against its own file only: the EKF loop's index must go
    when a module whose kernels it compiles in (the Kalman algebra) is newer."""
    old, fresh, other = (tmp_path / f"{n}.nbi" for n in ("old", "fresh", "other"))
    for path in (old, fresh, other):
        path.write_bytes(b"index")
    callee = min(Path(m.__file__).stat().st_mtime for m in (kalman, strapdown._kernel))
    os.utime(old, (callee - 10.0, callee - 10.0))
    os.utime(fresh, (time.time() + 60.0,) * 2)
    os.utime(other, (callee - 10.0, callee - 10.0))
    namespace = {"a": _fake_kernel("navlib.filters.ekf_loop", old),
                 "b": _fake_kernel("navlib.filters.ekf_loop", fresh),
                 "imported": _fake_kernel("navlib.kalman", other), "x": 1.0}
    cache.drop_stale_kernel_caches("navlib.filters.ekf_loop", namespace)
    assert not old.exists()
    assert fresh.exists()
    assert other.exists()  # a kernel imported from elsewhere is its own module's business
