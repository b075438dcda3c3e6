"""Which notebooks a report runs, and with which parameters.

A report notebook is ``NN_name.ipynb`` in the notebooks folder; its tagged ``parameters``
cell names what ``-p`` may inject (docs/reports.md). ``quick=True`` and
explicit parameters reach only the notebooks whose parameters cell assigns that name, so
papermill never warns about unknown parameters and ``-p imu_path x.csv`` reaches only the
notebooks that read flight data.
"""

from __future__ import annotations

import ast
import json
import re
import sys
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from navlib.errors import NavlibInputError
from navlib.resources import notebooks_dir as shipped_notebooks_dir

__all__ = ["NOTEBOOK_PATTERN", "NotebookInfo", "default_notebooks_dir", "dependencies",
           "list_notebooks", "notebook_format", "parameters_for", "parse_parameter_value",
           "parse_parameters", "read_notebook", "select_notebooks"]

NOTEBOOK_PATTERN = re.compile(r"^(\d{2})_\w+\.ipynb$")
"""Notebooks taking part in the report: ``NN_name.ipynb`` (two digits, underscore)."""


@dataclass(frozen=True)
class NotebookInfo:
    """A report notebook found on disk.

    Attributes
    ----------
    name : str
        File stem, e.g. ``"07_assess_flight"``.
    path : Path
        Absolute path of the source notebook.
    title : str
        Text of the first markdown heading (the stem when there is none).
    parameters : dict
        Name -> default source text of each assignment in the tagged ``parameters`` cell
        (empty when the notebook has no such cell).
    after : tuple of str
        The notebook's metadata ``{"navlib": {"after": ["02", ...]}}`` (numbers or stems):
        in a run that includes them it starts only when they have finished (the claims
        summary ``00_claims`` after 02 and 05, whose results its studies then read from the
        disk cache, :mod:`navlib.cache`); others run beside it meanwhile.
    """

    name: str
    path: Path
    title: str
    parameters: dict[str, str] = field(default_factory=dict)
    after: tuple[str, ...] = ()





def _parameter_defaults(nb) -> dict[str, str]:
    """Name -> default source text of the assignments in the tagged ``parameters`` cell."""
    for cell in nb.cells:
        if cell.cell_type == "code" and "parameters" in cell.get("metadata", {}).get("tags", []):
            source = cell.source
            try:
                tree = ast.parse(source)
            except SyntaxError:
                return {}
            out: dict[str, str] = {}
            for node in tree.body:
                targets = node.targets if isinstance(node, ast.Assign) else (
                    [node.target] if isinstance(node, ast.AnnAssign) and node.value else [])
                for target in targets:
                    if isinstance(target, ast.Name):
                        out[target.id] = ast.get_source_segment(source, node.value) or ""
            return out
    return {}


def _title(nb, fallback: str) -> str:
    for cell in nb.cells:
        if cell.cell_type == "markdown":
            for line in cell.source.splitlines():
                if line.startswith("#"):
                    return line.lstrip("#").strip()
    return fallback


def notebook_format():
    """nbformat, imported without the IRI grammars of ``rfc3987-syntax``.

    jsonschema (nbformat's validator) compiles 39 lark grammars on import when that package
    is installed (JupyterLab's event schemas pull it in), to check the ``iri`` formats that no
    notebook schema uses: about 2 CPU-s of every process that runs or exports notebooks
    (importing papermill and nbconvert: 2.9-3.2 CPU-s with them, 0.8-1.1 without, on the
    2-core machine of the README's timings). Marking the package absent first makes
    jsonschema skip those two format checkers (it imports them under ``suppress(ImportError)``); a
    process that imported it already keeps it."""
    sys.modules.setdefault("rfc3987_syntax", None)
    import nbformat  # only when a notebook is read: the assess, plan and sweep commands never do

    return nbformat


def read_notebook(path: Path):
    """The notebook at ``path`` (nbformat version 4); NavlibInputError when unreadable."""
    nbformat = notebook_format()
    try:
        return nbformat.read(path, as_version=4)
    except Exception as exc:  # nbformat raises several unrelated types for bad files
        raise NavlibInputError(f"notebook {path}: cannot be read ({exc})") from exc


def list_notebooks(notebooks_dir) -> list[NotebookInfo]:
    """The report notebooks (``NN_*.ipynb``) of ``notebooks_dir``, sorted by name."""
    folder = Path(notebooks_dir)
    if not folder.is_dir():
        raise NavlibInputError(f"notebooks_dir: {folder} is not a folder")
    infos = []
    for path in sorted(folder.iterdir()):
        if path.is_file() and NOTEBOOK_PATTERN.match(path.name):
            nb = read_notebook(path)
            after = nb.metadata.get("navlib", {}).get("after", ())
            if isinstance(after, str) or not all(isinstance(a, str) for a in after):
                raise NavlibInputError(f"notebook {path}: metadata navlib.after must be a "
                                       f"list of notebook names or numbers, got {after!r}")
            infos.append(NotebookInfo(path.stem, path.resolve(), _title(nb, path.stem),
                                      _parameter_defaults(nb), tuple(after)))
    return infos


def _matching(entry, available: Sequence[NotebookInfo]) -> list[str]:
    """Names of the notebooks an ``--only`` entry selects (stem, ``NN`` prefix, file name
    or path)."""
    key = Path(str(entry)).name.removesuffix(".ipynb")
    return [nb.name for nb in available
            if nb.name == key or (key.isdigit() and int(nb.name[:2]) == int(key))]


def dependencies(info: NotebookInfo, selected: Sequence[NotebookInfo]) -> set[str]:
    """The notebooks of ``selected`` that ``info`` starts after (its ``after`` entries
    matched as ``--only`` entries; entries matching none are ignored).

    Parameters
    ----------
    info : NotebookInfo
        The notebook.
    selected : sequence of NotebookInfo
        The notebooks of the run.

    Returns
    -------
    set of str
        Their names.
    """
    return {name for entry in info.after for name in _matching(entry, selected)
            if name != info.name}


def select_notebooks(available: Sequence[NotebookInfo],
                     only: Iterable[str] | None) -> list[NotebookInfo]:
    """Filter ``available`` by ``only`` entries (stem, ``NN`` prefix, file name or path).

    Raises NavlibInputError listing the available notebooks for an entry matching none.

    Parameters
    ----------
    available : sequence of NotebookInfo
        The notebooks found.
    only : iterable of str or None
        Entries; None keeps all.

    Returns
    -------
    list of NotebookInfo

    Raises
    ------
    NavlibInputError
        For an entry that matches no notebook.
    """
    if only is None:
        return list(available)
    only = [only] if isinstance(only, str) else list(only)
    wanted: set[str] = set()
    for entry in only:
        hits = _matching(entry, available)
        if not hits:
            names = ", ".join(nb.name for nb in available) or "(none)"
            raise NavlibInputError(
                f"only: no notebook matches {entry!r}; available: {names}")
        wanted.update(hits)
    return [nb for nb in available if nb.name in wanted]


def parse_parameter_value(text: str):
    """A ``-p`` value: a JSON or Python literal when it parses as one, else the string.

    ``2.5`` -> float, ``true``/``True`` -> bool, ``[1, 2]`` -> list, ``null``/``None`` ->
    None, ``Churchill`` -> ``"Churchill"``. Text that starts like a container (``[ { (``) but
    does not parse raises NavlibInputError rather than silently becoming a string.
    """
    for parse in (json.loads, ast.literal_eval):
        try:
            return parse(text)
        except (ValueError, SyntaxError, TypeError, MemoryError, RecursionError):
            pass
    if text.strip()[:1] in "[{(" and text.strip():
        raise NavlibInputError(f"parameter value {text!r}: looks like a list/dict/tuple but "
                               "does not parse as JSON or a Python literal")
    return text


def parse_parameters(pairs: Iterable[Sequence[str]], cwd=None) -> dict[str, object]:
    """Turn ``-p key value`` pairs into a parameter dict.

    Values go through :func:`parse_parameter_value`. A string value naming an existing file
    or folder relative to ``cwd`` (default: the current directory) is made absolute, because
    notebooks run with the notebooks folder as their working directory. A parameter whose
    name ends in ``_path`` must name an existing file or folder: a missing one is refused
    here, naming the folder it was looked up in, rather than inside the notebook.

    Parameters
    ----------
    pairs : iterable of (str, str)
        ``(key, value)`` pairs from the command line.
    cwd : path-like or None, optional
        Folder relative paths are resolved against; None: the current directory.

    Returns
    -------
    dict
    """
    base = Path.cwd() if cwd is None else Path(cwd)
    out: dict[str, object] = {}
    for pair in pairs:
        if len(pair) != 2:
            raise NavlibInputError(f"parameter: expected 'key value', got {list(pair)}")
        key, text = pair
        if not key.isidentifier():
            hint = ""
            if "=" in key:
                k, _, v = key.partition("=")
                hint = f" (write: -p {k} {v})"
            raise NavlibInputError(
                f"parameter name {key!r}: must be a Python identifier{hint}")
        value = parse_parameter_value(text)
        if isinstance(value, str) and value:
            candidate = Path(value) if Path(value).is_absolute() else base / value
            if candidate.exists():
                value = str(candidate.resolve())
            elif key.endswith("_path"):
                raise NavlibInputError(
                    f"parameter {key}: {value!r} not found (looked in {candidate.parent})")
        out[key] = value
    return out


def parameters_for(info: NotebookInfo, quick: bool,
                   parameters: Mapping[str, object]) -> dict[str, object]:
    """What ``info`` is run with: ``quick=True`` and those of ``parameters`` that its
    parameters cell assigns (the others are left out, not passed to papermill).

    Parameters
    ----------
    info : NotebookInfo
        The notebook.
    quick : bool
        Whether the run is quick.
    parameters : Mapping
        Parameters given on the command line.

    Returns
    -------
    dict
    """
    chosen: dict[str, object] = {}
    if quick and "quick" in info.parameters:
        chosen["quick"] = True
    chosen.update({k: v for k, v in parameters.items() if k in info.parameters})
    return chosen


def default_notebooks_dir() -> Path:
    """The shipped notebooks (``notebooks/`` of a source checkout, or the installed copy)."""
    return shipped_notebooks_dir()
