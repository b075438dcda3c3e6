"""Run the workbook notebooks headlessly and publish them as HTML (the report command).

Contract: docs/reports.md. :func:`run_reports` executes every
``NN_*.ipynb`` of a notebooks folder with papermill and writes each executed notebook, its
HTML page (results only, no code) and an ``index.html`` saying what each page answers, with
its headline, status and run time. Publishing
is all-or-nothing: on failure the previous report stays untouched and :class:`ReportError`
names the notebook and the failing cell.

The package, one module a step:

- :mod:`~navlib.reports.discovery`: which notebooks, with which parameters;
- :mod:`~navlib.reports.kernel_watch`: bounded papermill runs (sliced polls, stall watchdog);
- :mod:`~navlib.reports.execution`: one notebook run, its failure located, its HTML page;
- :mod:`~navlib.reports.runner`: :func:`run_reports`, the queue and the worker threads;
- :mod:`~navlib.reports.publishing`: staging folder, atomic swap, manifest and index;
- :mod:`~navlib.reports.headlines`: what each page answers and its headline, for the index;
- :mod:`~navlib.reports.signals`: Ctrl-C and SIGTERM as :class:`ReportInterrupted`;
- :mod:`~navlib.reports.results`: :class:`NotebookRun`, :class:`CellFailure`,
  :class:`ReportError`.
"""

from navlib.reports.discovery import (
    NOTEBOOK_PATTERN,
    NotebookInfo,
    default_notebooks_dir,
    list_notebooks,
    parse_parameter_value,
    parse_parameters,
    select_notebooks,
)
from navlib.reports.execution import (
    BLAS_THREAD_VARIABLES,
    DEFAULT_CELL_TIMEOUT_S,
    HUGEPAGE_VARIABLES,
    MALLOC_VARIABLES,
    available_cpus,
    kernel_environment,
)
from navlib.reports.publishing import INDEX, MANIFEST, default_output_dir
from navlib.reports.results import CellFailure, NotebookRun, Progress, ReportError
from navlib.reports.runner import run_reports
from navlib.reports.signals import ReportInterrupted

__all__ = [
    "BLAS_THREAD_VARIABLES", "DEFAULT_CELL_TIMEOUT_S", "HUGEPAGE_VARIABLES", "INDEX",
    "MALLOC_VARIABLES", "MANIFEST",
    "NOTEBOOK_PATTERN", "CellFailure", "NotebookInfo", "NotebookRun", "Progress",
    "ReportError", "ReportInterrupted", "available_cpus", "default_notebooks_dir",
    "default_output_dir", "kernel_environment", "list_notebooks", "parse_parameter_value",
    "parse_parameters", "run_reports", "select_notebooks",
]
