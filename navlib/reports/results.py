"""What a report run returns: the outcome of each notebook, and the error naming the failures.

Contract: docs/reports.md (the notebook and cell named on failure).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

__all__ = ["CellFailure", "NotebookRun", "Progress", "ReportError"]


@dataclass(frozen=True)
class CellFailure:
    """Where and how a notebook failed.

    ``cell_index`` is the 0-based index in the *source* notebook (markdown cells count).
    ``-1`` marks a failure not located in a cell (kernel died, HTML export error).
    """

    cell_index: int
    ename: str
    evalue: str
    source: str = ""
    traceback: str = ""

    def describe(self) -> str:
        """One-line description: cell, first source line, exception."""
        if self.cell_index < 0:
            where = "outside a cell"
        else:
            first = next((ln.strip() for ln in self.source.splitlines() if ln.strip()), "")
            if len(first) > 60:
                first = first[:57] + "..."
            where = f"cell {self.cell_index} (0-based)" + (f" `{first}`" if first else "")
        return f"{where}: {self.ename}: {self.evalue}"


@dataclass(frozen=True)
class NotebookRun:
    """Outcome of executing one notebook.

    Attributes
    ----------
    name : str
        Notebook stem.
    status : str
        ``"ok"`` or ``"failed"`` (in progress calls only: ``"restarting"`` announcing a
        restart after a stall, ``"stopped"`` for a run cut short because another notebook
        failed under ``fail_fast``).
    seconds : float
        Wall time of the papermill execution (kernel start included), s.
    parameters : dict
        The parameters injected into this notebook.
    html : str or None
        File name of the HTML page inside the output folder (None when failed).
    ipynb : str or None
        File name of the executed notebook inside the output folder (None when failed).
    failure : CellFailure or None
        Set when ``status == "failed"``.
    stalls : tuple of str
        Stalls met on the way (each ended by killing the kernel); a run that stalled once
        and then succeeded is ``ok`` with one entry here.
    lost_wakeups : int
        Kernel messages whose ZeroMQ wake-up never came, found when a 0.25 s poll slice
        expired (recovered, not stalls; see :mod:`navlib.reports.kernel_watch`).
    """

    name: str
    status: str
    seconds: float
    parameters: dict[str, object]
    html: str | None = None
    ipynb: str | None = None
    failure: CellFailure | None = None
    title: str = ""
    stalls: tuple[str, ...] = ()
    lost_wakeups: int = 0

    @property
    def ok(self) -> bool:
        return self.status == "ok"


class ReportError(RuntimeError):
    """At least one notebook failed; nothing was published.

    ``runs`` holds every :class:`NotebookRun` that ran to its end (in name order), failed
    ones with their :class:`CellFailure`; runs stopped because of ``fail_fast`` are left
    out.
    """

    def __init__(self, runs: Sequence[NotebookRun]):
        self.runs = list(runs)
        failed = [r for r in self.runs if not r.ok]
        lines = [f"{len(failed)} notebook(s) failed; the previous report was left untouched"]
        lines += [f"  {r.name}: {r.failure.describe()}" for r in failed if r.failure]
        super().__init__("\n".join(lines))


Progress = Callable[[int, int, str, "NotebookRun | None"], None]
"""``progress(position, total, name, run)``: called with ``run=None`` when notebook number
``position`` (1-based, in the order notebooks start) starts and with its
:class:`NotebookRun` when it ends; always from the thread that called
:func:`navlib.reports.run_reports`, also when several notebooks run at once (their events
then interleave)."""
