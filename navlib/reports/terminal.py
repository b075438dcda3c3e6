"""Warnings on the terminal of ``python -m navlib``: one readable line each.

Python's default display of a warning is ``file.py:NN: Category: message`` followed by the
source line that raised it: the library's inside, not the user's concern. The command line
shows ``Category: message`` on one line instead (:func:`warning_lines`); the text of a
warning names what was found in the flight or mission, which is what the user acts on.
"""

from __future__ import annotations

import functools
import sys
import warnings

__all__ = ["warning_line", "warning_lines"]


def warning_line(message, category) -> str:
    """``Category: message`` with the message's whitespace (newlines included) folded to
    single spaces."""
    return f"{category.__name__}: {' '.join(str(message).split())}"


def _show(message, category, filename, lineno, file=None, line=None) -> None:
    """A :func:`warnings.showwarning` printing :func:`warning_line` (no file, line or source)."""
    stream = sys.stderr if file is None else file
    if stream is None:       # no terminal (pythonw): nowhere to show it, as in the default
        return
    try:
        stream.write(warning_line(message, category) + "\n")
    except OSError:          # a closed or broken stream: as the default display does
        pass


def warning_lines(fn):
    """Decorate a command-line entry point: while it runs, warnings that reach the terminal
    are shown as :func:`warning_line` (the filters, and ``catch_warnings`` blocks recording
    warnings, are untouched); the previous display is restored when it returns."""

    @functools.wraps(fn)
    def run(*args, **kwargs):
        previous = warnings.showwarning
        warnings.showwarning = _show
        try:
            return fn(*args, **kwargs)
        finally:
            warnings.showwarning = previous

    return run
