"""ipywidgets panels, one module per domain: build controls, call navlib, redraw.

Kept thin: every number shown comes from a library call that tests exercise directly.
"""
