"""Process memory for panel moves: a move's large arrays on pages the process already has.

On Linux, numpy asks the kernel for transparent huge pages for each array of 4 MB or more
(``madvise``), and glibc gives memory freed at the top of its heap, or any block above its
mmap threshold (128 KB, raised up to 32 MB by the frees it sees), back to the kernel. A move
that allocates arrays of a size it has not allocated before then writes to fresh pages.
Where the kernel compacts memory for a huge page when it is first written (transparent
huge page defrag ``madvise``, as on this project's reference VM), that wait falls inside
the move: panel 05's first Monte Carlo of 62 runs spent 260-630 ms of its 440-820 ms in
the kernel (system time), and its first of 100 runs 550 of 820 ms.

:func:`keep_pages` turns numpy's huge-page advice off and raises glibc's mmap and trim
thresholds, once per process, when the first panel is built: the same Monte Carlo then
takes 230-245 ms at its first 62 runs, 290-340 at its first 100 and 180-200 ms at later ones
(was 227). The process keeps up to :data:`TRIM_THRESHOLD_BYTES` of freed memory for
its next arrays instead of returning it. Elsewhere (no glibc, or a numpy without the
setting) nothing changes. The kernels of a report get the same settings through their
environment (``navlib.reports.execution.MALLOC_VARIABLES`` and ``HUGEPAGE_VARIABLES``).
"""

from __future__ import annotations

import ctypes
import sys

import numpy as np

__all__ = ["MMAP_THRESHOLD_BYTES", "TRIM_THRESHOLD_BYTES", "keep_pages"]

MMAP_THRESHOLD_BYTES = 2**30
"""glibc's mmap threshold: blocks below it come from the heap (1 GiB, as in a report's
kernels)."""
TRIM_THRESHOLD_BYTES = 2**30
"""Free memory at the top of glibc's heap kept for later allocations (1 GiB)."""

_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3  # glibc's malloc.h
_kept = None


def keep_pages() -> bool:
    """Keep a panel's large arrays on pages the process has (module docstring), once.

    Returns
    -------
    bool
        True when glibc took the new thresholds (in this call or an earlier one).
    """
    global _kept
    if _kept is None:
        multiarray = getattr(np, "_core", getattr(np, "core", None)).multiarray
        advise = getattr(multiarray, "_set_madvise_hugepage", None)
        if advise is not None:
            advise(False)
        _kept = False
        if sys.platform.startswith("linux"):
            try:
                mallopt = ctypes.CDLL(None).mallopt
            except (AttributeError, OSError):
                return _kept
            _kept = bool(mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD_BYTES)) and \
                bool(mallopt(_M_TRIM_THRESHOLD, TRIM_THRESHOLD_BYTES))
    return _kept
