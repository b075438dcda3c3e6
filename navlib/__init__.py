"""navlib: which parts of the navigation state can this flight estimate, and how well?

A workbook library for navigation-system designers. See docs/library.md for the data flow;
the public contract is the set of names in ``navlib.trajectory``, ``navlib.models``,
``navlib.observability``, ``navlib.metrics``, ``navlib.io`` and the report command.
Submodules are imported on first attribute access, so ``import navlib`` stays cheap and
``navlib.metrics.excitability(...)`` works without a separate import.
"""

import importlib
import importlib.abc
import importlib.util
import sys
import types
import warnings

from navlib.errors import NavlibInputError

__version__ = "0.1.0"

_SUBMODULES = (
    "covariance", "discretize", "earth", "filters", "io", "metrics", "models",
    "observability", "parallel", "plots", "reports", "rotations", "segmentation",
    "sensors", "strapdown",
    "studies", "sweep", "trajectory", "units", "widgets",
)

__all__ = ["NavlibInputError", "__version__", *_SUBMODULES]


MOVED = {
    "navlib.allan": ("navlib.sensors.allan",),
    "navlib.estimability": ("navlib.covariance.estimability",),
    "navlib.outliers": ("navlib.sensors.faults", "navlib.filters.recovery",
                        "navlib.studies.outliers.paper"),
    "navlib.quality": ("navlib.io.quality",),
    "navlib.readings": ("navlib.studies.design", "navlib.studies.plan",
                        "navlib.studies.outliers.reading"),
}
"""Module addresses that moved (issue 38), kept importable for one release: importing the old
name warns (DeprecationWarning) and gives the new module, or, for a module spread over
several, one holding the public names of each (:class:`_MovedModules`)."""


class _MovedModules(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Import hook that answers the old addresses of :data:`MOVED` (no shim files)."""

    def find_spec(self, fullname, path=None, target=None):
        return importlib.util.spec_from_loader(fullname, self) if fullname in MOVED else None

    def create_module(self, spec):
        homes = MOVED[spec.name]
        warnings.warn(f"{spec.name} moved to {' and '.join(homes)}; import it from there (the "
                      f"old name goes in the next release)", DeprecationWarning, stacklevel=2)
        modules = [importlib.import_module(home) for home in homes]
        if len(modules) == 1:
            return modules[0]
        merged = types.ModuleType(spec.name, f"Deprecated: see {', '.join(homes)}.")
        for module in modules:
            for name in module.__all__:
                setattr(merged, name, getattr(module, name))
        return merged

    def exec_module(self, module):
        """Nothing to run: :meth:`create_module` gave the moved module itself."""


if not any(isinstance(finder, _MovedModules) for finder in sys.meta_path):
    sys.meta_path.append(_MovedModules())


def __getattr__(name):
    if name in _SUBMODULES:
        return importlib.import_module(f"navlib.{name}")
    raise AttributeError(f"module 'navlib' has no attribute {name!r}")
