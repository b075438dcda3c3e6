"""navlib: which parts of the navigation state can this flight estimate, and how well?

A workbook library for navigation-system designers. See the README for the data flow;
the public contract is the set of names in ``navlib.trajectory``, ``navlib.models``,
``navlib.observability``, ``navlib.metrics``, ``navlib.io`` and the report command.
"""

from navlib.errors import NavlibInputError

__version__ = "0.1.0"

__all__ = ["NavlibInputError", "__version__"]
