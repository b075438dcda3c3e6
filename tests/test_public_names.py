"""The package's public names: every name in ``navlib.__all__`` resolves, so
``from navlib import *`` works (a moved module once left ``fleet`` behind in it); every
``__all__`` of every public module resolves; the modules stay small (600 lines at most)."""

import importlib
import pkgutil
import sys
from pathlib import Path

import pytest

import navlib

ROOT = Path(navlib.__file__).resolve().parent
MAX_LINES = 600
# the modules whose public names h38 listed (issue 38); every module under these names has
# an ``__all__`` naming each public function, class and constant it defines
WITH_ALL = ("navlib.earth", "navlib.rotations", "navlib.units", "navlib.quaternions",
            "navlib.discretize", "navlib.observability", "navlib.metrics", "navlib.covariance",
            "navlib.sensors", "navlib.sweep", "navlib.parallel", "navlib.cache", "navlib.kalman",
            "navlib.resolution")


def _public_modules() -> list[str]:
    """Every importable module of navlib whose dotted name has no private (``_``) part."""
    names = ["navlib"]
    for info in pkgutil.walk_packages(navlib.__path__, prefix="navlib."):
        if not any(part.startswith("_") for part in info.name.split(".")):
            names.append(info.name)
    return sorted(names)


PUBLIC_MODULES = _public_modules()


def test_the_walk_finds_the_subpackages_and_leaves():
    assert {"navlib.metrics", "navlib.metrics.sensing", "navlib.studies.assess",
            "navlib.reports.fleet"} <= set(PUBLIC_MODULES)
    assert not any(name.startswith("navlib.metrics._") for name in PUBLIC_MODULES)


def test_every_public_name_resolves():
    for name in navlib.__all__:
        assert getattr(navlib, name) is not None, name


@pytest.mark.parametrize("module", PUBLIC_MODULES)
def test_every_all_name_of_every_module_resolves(module):
    mod = importlib.import_module(module)
    names = getattr(mod, "__all__", ())
    assert len(set(names)) == len(names), f"{module}.__all__ repeats a name"
    missing = [name for name in names if not hasattr(mod, name)]
    assert not missing, f"{module}.__all__ names what it lacks: {missing}"


@pytest.mark.parametrize("module", [m for m in PUBLIC_MODULES if m.startswith(WITH_ALL)])
def test_listed_modules_name_their_public_definitions(module):
    mod = importlib.import_module(module)
    assert hasattr(mod, "__all__"), f"{module} has no __all__"
    defined = {name for name, value in vars(mod).items()
               if not name.startswith("_") and getattr(value, "__module__", None) == module
               and callable(value)}
    lacking = sorted(defined - set(mod.__all__))
    assert not lacking, f"{module}.__all__ lacks {lacking}"


def test_star_import_works():
    namespace: dict = {}
    exec("from navlib import *", namespace)
    assert "NavlibInputError" in namespace
    assert set(navlib.__all__) <= set(namespace)


def test_fleet_lives_under_reports():
    assert importlib.import_module("navlib.reports.fleet") is not None


def test_no_module_over_600_lines():
    lengths = {str(path.relative_to(ROOT.parent)): len(path.read_text(encoding="utf-8")
                                                       .splitlines())
               for path in ROOT.rglob("*.py")}
    assert len(lengths) > 100
    over = {path: n for path, n in sorted(lengths.items()) if n > MAX_LINES}
    assert not over, f"modules over {MAX_LINES} lines (split them by domain): {over}"


@pytest.mark.parametrize("old", sorted(navlib.MOVED))
def test_a_moved_address_warns_and_gives_the_new_module(old):
    """Issue 38 moved root modules; their old addresses import for one release, warning."""
    sys.modules.pop(old, None)
    with pytest.warns(DeprecationWarning, match=rf"{old} moved to"):
        module = importlib.import_module(old)
    homes = [importlib.import_module(home) for home in navlib.MOVED[old]]
    if len(homes) == 1:
        assert module is homes[0]
    for home in homes:
        assert all(getattr(module, name) is getattr(home, name) for name in home.__all__)
    assert not (ROOT / f"{old.rpartition('.')[2]}.py").exists()
