"""numpydoc coverage of navlib's public surface (issue 38), read with numpydoc's own parser.

A *public function* is a function, or a method of a class, whose name has no leading
underscore, defined at the top level of a module whose dotted name has no private part
(``navlib.metrics._arrays`` is private). Its arguments are those of its signature without
``self``/``cls``. Each docstring is parsed by :class:`numpydoc.docscrape.NumpyDocString`;
a function "carries Parameters" when that parser finds a non-empty ``Parameters`` section.

Run as a script (``make test`` does) to print the share::

    python tests/docstring_coverage.py
"""

from __future__ import annotations

import ast
import warnings
from dataclasses import dataclass
from pathlib import Path

from numpydoc.docscrape import NumpyDocString

PACKAGE = Path(__file__).resolve().parents[1] / "navlib"


@dataclass(frozen=True)
class PublicFunction:
    """One public function or method: where it is, its argument names and its docstring."""

    module: str
    name: str
    arguments: tuple[str, ...]
    docstring: str | None
    keywords: bool = False
    """Whether the signature takes ``**kwargs``."""

    def parsed(self) -> NumpyDocString | None:
        """The docstring read by numpydoc (None without a docstring)."""
        if not self.docstring:
            return None
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # numpydoc warns on sections it does not know
            return NumpyDocString(self.docstring)

    def documented_parameters(self) -> list[str]:
        """Argument names listed in the Parameters section (``x, y : float`` lists two)."""
        doc = self.parsed()
        if doc is None:
            return []
        return [name.strip().lstrip("*") for p in doc["Parameters"]
                for name in p.name.split(",")]


def _arguments(node: ast.FunctionDef | ast.AsyncFunctionDef, method: bool) -> tuple[str, ...]:
    a = node.args
    names = [x.arg for x in (*a.posonlyargs, *a.args, *a.kwonlyargs)]
    if method and names and names[0] in ("self", "cls"):
        names = names[1:]
    if a.vararg:
        names.append(a.vararg.arg)
    if a.kwarg:
        names.append(a.kwarg.arg)
    return tuple(names)


def public_functions(package: Path = PACKAGE) -> list[PublicFunction]:
    """Every public function and public method of a public class in ``package``."""
    found = []
    for path in sorted(package.rglob("*.py")):
        parts = path.relative_to(package.parent).with_suffix("").parts
        if any(p.startswith("_") and p != "__init__" for p in parts):
            continue
        module = ".".join(parts).removesuffix(".__init__")
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in tree.body:
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                members = [(node.name, node, False)]
            elif isinstance(node, ast.ClassDef):
                members = [(f"{node.name}.{m.name}", m, True) for m in node.body
                           if isinstance(m, (ast.FunctionDef, ast.AsyncFunctionDef))]
                if node.name.startswith("_"):
                    members = []
            else:
                continue
            for name, fn, method in members:
                if not name.rpartition(".")[2].startswith("_"):
                    found.append(PublicFunction(module, name, _arguments(fn, method),
                                                ast.get_docstring(fn), fn.args.kwarg is not None))
    return found


def parameters_share(functions: list[PublicFunction]) -> tuple[int, int]:
    """(functions with two or more arguments carrying Parameters, functions with two or more
    arguments)."""
    several = [f for f in functions if len(f.arguments) >= 2]
    return sum(bool(f.documented_parameters()) for f in several), len(several)


if __name__ == "__main__":
    with_parameters, total = parameters_share(public_functions())
    print(f"numpydoc Parameters: {with_parameters} of {total} public functions with two or "
          f"more arguments ({100 * with_parameters / total:.1f} %)")
