"""ipywidgets panels, one module per domain: build controls, call navlib, redraw.

Kept thin: every number shown comes from a library call that tests exercise directly.
"""

__all__ = ["assess", "base", "metrics", "observability", "outliers", "plan", "ssac", "static",
           "sweep", "trajectory"]
