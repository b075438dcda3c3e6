"""Signals during a report run: Ctrl-C and SIGTERM end it cleanly, never half-way through a swap.

A run turns SIGINT and SIGTERM into :class:`ReportInterrupted`, so its kernels are stopped and
its staging folder removed (docs/reports.md); the two renames that
publish a report hold both signals until they are done.
"""

from __future__ import annotations

import contextlib
import signal
import threading

__all__ = ["ReportInterrupted", "signals_deferred", "signals_interrupt"]


class ReportInterrupted(BaseException):
    """The run was interrupted (Ctrl-C or SIGTERM; a BaseException, like KeyboardInterrupt,
    so no handler of ordinary errors swallows it); its kernels were stopped, its staging
    folder removed and the previous report left untouched. ``signum`` names the signal."""

    def __init__(self, signum: int):
        self.signum = int(signum)
        super().__init__(f"interrupted by {signal.Signals(self.signum).name}: kernels "
                         "stopped, nothing published, the previous report was left untouched")


@contextlib.contextmanager
def signals_deferred():
    """Hold SIGINT and SIGTERM until the block ends (they are then delivered)."""
    held = {signal.SIGINT, signal.SIGTERM}
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, held)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


@contextlib.contextmanager
def signals_interrupt():
    """Turn SIGINT and SIGTERM into :class:`ReportInterrupted` (main thread only; elsewhere
    signals cannot be handled and this does nothing)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def interrupt(signum, _frame):
        raise ReportInterrupted(signum)

    previous = {sig: signal.signal(sig, interrupt) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
