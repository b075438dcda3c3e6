"""navlib: which parts of the navigation state can this flight estimate, and how well?

A workbook library for navigation-system designers. See docs/library.md for the data flow;
the public contract is the set of names in ``navlib.trajectory``, ``navlib.models``,
``navlib.observability``, ``navlib.metrics``, ``navlib.io`` and the report command.
Submodules are imported on first attribute access, so ``import navlib`` stays cheap and
``navlib.metrics.excitability(...)`` works without a separate import.
"""

import importlib

from navlib.errors import NavlibInputError

__version__ = "0.1.0"

_SUBMODULES = (
    "covariance", "discretize", "earth", "filters", "io", "metrics", "models",
    "observability", "outliers", "parallel", "plots", "reports", "rotations", "segmentation",
    "sensors", "strapdown",
    "studies", "sweep", "trajectory", "units", "widgets",
)

__all__ = ["NavlibInputError", "__version__", *_SUBMODULES]


def __getattr__(name):
    if name in _SUBMODULES:
        return importlib.import_module(f"navlib.{name}")
    raise AttributeError(f"module 'navlib' has no attribute {name!r}")
