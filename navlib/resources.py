"""Where the shipped data and notebooks are: the top-level ``data/`` and ``notebooks/``.

The repository keeps them at the top level; the wheel ships them inside the package as
``navlib.data`` and ``navlib.notebooks`` (``pyproject.toml`` maps the folders with
``package-dir``), so a non-editable install has the sensor presets, the Table 2 reference,
the sample flight and the notebooks too. In an editable install the same names resolve to
the top-level folders. Notebooks refer to ``../data/...``, which holds in both layouts.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

from navlib.errors import NavlibInputError

__all__ = ["data_dir", "is_shipped_name", "notebooks_dir", "source_checkout", "toml_names",
           "toml_path"]


def _package_folder(name: str, checkout_folder: str) -> Path:
    """Folder of the (namespace) package ``name``; the checkout's folder when navlib is
    imported from a source tree that is not installed."""
    try:
        spec = importlib.util.find_spec(name)
    except ModuleNotFoundError:
        spec = None
    if spec is not None and spec.submodule_search_locations:
        return Path(next(iter(spec.submodule_search_locations))).resolve()
    return Path(__file__).resolve().parent.parent / checkout_folder


def data_dir() -> Path:
    """The shipped data folder (sensor presets, paper tables, sample flight)."""
    return _package_folder("navlib.data", "data")


def notebooks_dir() -> Path:
    """The shipped report notebooks folder."""
    return _package_folder("navlib.notebooks", "notebooks")


def source_checkout() -> Path | None:
    """Root of the source checkout the notebooks come from, or None for an installed wheel."""
    root = notebooks_dir().parent
    return root if (root / "pyproject.toml").is_file() else None


def toml_names(folder: Path) -> list[str]:
    """Names (file stems) of the ``*.toml`` files shipped in ``folder``, sorted."""
    return sorted(p.stem for p in folder.glob("*.toml"))


def is_shipped_name(name_or_path) -> bool:
    """Whether ``name_or_path`` names a shipped TOML file rather than a path: no ``.toml``
    suffix and no folder part (the rule of :func:`toml_path`)."""
    path = Path(str(name_or_path))
    return path.suffix != ".toml" and path.parent == Path(".")


def toml_path(folder: Path, name_or_path, argument: str, file_kind: str, kind: str) -> Path:
    """The TOML file ``name_or_path`` names: a path (a ``.toml`` suffix or a folder part)
    as given, else the shipped ``folder/<name>.toml``. A NavlibInputError starting with
    ``argument`` says which ``file_kind`` is missing, or which ``kind`` is unknown and the
    shipped names (:func:`toml_names`)."""
    text = str(name_or_path)
    path = Path(text)
    if not is_shipped_name(text):
        if not path.is_file():
            raise NavlibInputError(f"{argument}: {file_kind} {text!r} not found")
        return path
    path = folder / f"{text}.toml"
    if not path.is_file():
        raise NavlibInputError(f"{argument}: unknown {kind} {text!r}; available: "
                               f"{toml_names(folder)}")
    return path

