"""Sphinx configuration of navlib's API reference (``make docs``).

The source folder is ``docs/`` (so the narrative pages ``docs/*.md`` are pages of the same
site, read by myst-parser); this file, the page template and the index live in
``docs/api/``. Build (warnings are errors)::

    sphinx-build -W --keep-going -c docs/api docs build/docs

Each module page documents the names of the module's ``__all__`` (or its public names);
a subpackage's page documents what it re-exports, its modules' pages the rest.
"""

import importlib
import pkgutil
import re
from pathlib import Path

import navlib

project = "navlib"
author = "navlib developers"
release = version = navlib.__version__
root_doc = "api/index"

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "myst_parser",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
# absolute: autosummary reads templates relative to the source folder, not this one
templates_path = [str(Path(__file__).resolve().parent / "_templates")]
exclude_patterns = ["api/_templates"]

autosummary_generate = True
autodoc_default_options = {"members": True}
autodoc_typehints = "none"  # the numpydoc Parameters sections carry the types
numpydoc_show_class_members = False  # autodoc documents the members once
numpydoc_class_members_toctree = False

myst_heading_anchors = 4  # the narrative pages link to their own headings GitHub-style

html_theme = "alabaster"
html_title = f"navlib {release}"


def _clashing_modules() -> list[str]:
    """Modules whose dotted name is also a function or class of their package (the function
    ``navlib.filters.ekf`` and the module ``navlib.filters.ekf``): the name is documented on
    the package's page, the module gets no page of its own (one address per name)."""
    clashing = []
    for info in pkgutil.walk_packages(navlib.__path__, prefix="navlib."):
        parent, _, leaf = info.name.rpartition(".")
        value = getattr(importlib.import_module(parent), leaf, None)
        if value is not None and not hasattr(value, "__path__") and not hasattr(
                value, "__file__"):
            clashing.append(info.name)
    return clashing


autosummary_context = {"clashing_modules": _clashing_modules()}

_LITERAL = re.compile(r"(``.*?``|`[^`]*`)")
_BARS = re.compile(r"(?<![\\|\w])\|([^|\s][^|]*?)\|(?![\w|])")


def _escape_bars(app, what, name, obj, options, lines):
    """Docstrings write norms and absolute values as ``|f|`` in running text; reStructuredText
    would read them as substitutions (an error). Escape such bars outside literals, roles
    and literal blocks; the rendered text is unchanged."""
    block_indent = None
    for i, line in enumerate(lines):
        indent = len(line) - len(line.lstrip())
        if block_indent is not None:
            if line.strip() and indent <= block_indent:
                block_indent = None
            else:
                continue
        parts = _LITERAL.split(line)
        lines[i] = "".join(part if k % 2 else _BARS.sub(r"\\|\1\\|", part)
                           for k, part in enumerate(parts))
        if line.rstrip().endswith("::"):
            block_indent = indent


_MD_LINK = re.compile(r"\]\((?!\w+:|#)([^)\s#]+)(#[^)\s]*)?\)")


def _link_outside_files(app, docname, source):
    """Narrative pages link repository files outside ``docs/`` (``../README.md``), which
    are no pages of this site: link those as plain files (myst's ``path:`` scheme copies
    them beside the pages) instead of failing as missing cross-references."""
    if not app.env.doc2path(docname).suffix == ".md":
        return
    folder = app.env.doc2path(docname).parent
    srcdir = Path(app.srcdir).resolve()

    def plain(match):
        target = (folder / match.group(1)).resolve()
        if target.is_file() and not target.is_relative_to(srcdir):
            return f"](path:{match.group(1)})"
        return match.group(0)

    source[0] = _MD_LINK.sub(plain, source[0])


def setup(app):
    app.connect("autodoc-process-docstring", _escape_bars)
    app.connect("source-read", _link_outside_files)
