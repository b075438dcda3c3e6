"""The package's public names: every name in ``navlib.__all__`` resolves, so
``from navlib import *`` works (a moved module once left ``fleet`` behind in it); every public
module defines ``__all__`` (issue 38), a star import of it gives every name it lists, a leaf
module lists what it defines (not what it imports) and every public function and class it
defines; the modules stay small (600 lines at most)."""

import importlib
import inspect
import pkgutil
import sys
from pathlib import Path

import pytest

import navlib

ROOT = Path(navlib.__file__).resolve().parent
MAX_LINES = 600


def _public_modules() -> dict[str, bool]:
    """Every importable module of navlib whose dotted name has no private (``_``) part, and
    whether it is a package."""
    modules = {"navlib": True}
    for info in pkgutil.walk_packages(navlib.__path__, prefix="navlib."):
        if not any(part.startswith("_") for part in info.name.split(".")):
            modules[info.name] = info.ispkg
    return dict(sorted(modules.items()))


PUBLIC_MODULES = list(_public_modules())
LEAF_MODULES = [name for name, ispkg in _public_modules().items() if not ispkg]
AT_THE_LIMIT = ("navlib.io.checks", "navlib.studies.ssac.claims",
                "navlib.studies.ssac.experiment")
"""Modules 0-3 lines under :data:`MAX_LINES` that an ``__all__`` (3-7 lines) would push over it:
they get theirs when they are split by domain (a test below says when)."""
REEXPORTS = {"navlib.io.quality": {"faulty_time", "gnss_faults", "load_thresholds"}}
"""Names a leaf module lists though another module defines them: ``navlib.io.quality`` is the
home of the old ``navlib.quality`` (issue 38), whose callers found these there."""


def test_the_walk_finds_the_subpackages_and_leaves():
    assert {"navlib.metrics", "navlib.metrics.sensing", "navlib.studies.assess",
            "navlib.reports.fleet"} <= set(PUBLIC_MODULES)
    assert not any(name.startswith("navlib.metrics._") for name in PUBLIC_MODULES)


def test_every_public_name_resolves():
    for name in navlib.__all__:
        assert getattr(navlib, name) is not None, name


@pytest.mark.parametrize("module", [m for m in PUBLIC_MODULES if m not in AT_THE_LIMIT])
def test_every_module_has_an_all_that_a_star_import_resolves(module):
    """A star import raises when ``__all__`` names what the module lacks; a package may list
    its submodules (``navlib.plots``), which the star import imports."""
    mod = importlib.import_module(module)
    assert hasattr(mod, "__all__"), f"{module} has no __all__"
    names = mod.__all__
    assert all(isinstance(name, str) for name in names), f"{module}.__all__ holds a non-string"
    assert len(set(names)) == len(names), f"{module}.__all__ repeats a name"
    namespace: dict = {}
    exec(f"from {module} import *", namespace)
    missing = sorted(set(names) - set(namespace))
    assert not missing, f"{module}.__all__ names what it lacks: {missing}"


@pytest.mark.parametrize("module", sorted(AT_THE_LIMIT))
def test_a_module_without_all_is_still_at_the_line_limit(module):
    mod = importlib.import_module(module)
    lines = len(Path(mod.__file__).read_text(encoding="utf-8").splitlines())
    assert not hasattr(mod, "__all__"), f"{module} has an __all__ now: drop it from AT_THE_LIMIT"
    assert lines > MAX_LINES - 5, (f"{module} has {lines} lines, room for an __all__: give it "
                                   "one and drop it from AT_THE_LIMIT")


@pytest.mark.parametrize("module", [m for m in PUBLIC_MODULES if m not in AT_THE_LIMIT])
def test_every_module_names_its_public_definitions(module):
    mod = importlib.import_module(module)
    defined = {name for name, value in vars(mod).items()
               if not name.startswith("_") and getattr(value, "__module__", None) == module
               and callable(value)}
    lacking = sorted(defined - set(mod.__all__))
    assert not lacking, f"{module}.__all__ lacks {lacking}"


@pytest.mark.parametrize("module", [m for m in LEAF_MODULES if m not in AT_THE_LIMIT])
def test_a_leaf_module_lists_no_imported_name(module):
    """One address per name: a function or class of another module is listed where it is
    defined (or by a package that re-exports it), not by a leaf module that imports it
    (:data:`REEXPORTS` excepted)."""
    mod = importlib.import_module(module)
    imported = {name for name in mod.__all__
                if (inspect.isclass(value := getattr(mod, name)) or inspect.isroutine(value))
                and value.__module__ != module}
    unexpected = sorted(imported - REEXPORTS.get(module, set()))
    assert not unexpected, f"{module}.__all__ lists imported names: {unexpected}"


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
