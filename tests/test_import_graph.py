"""The import graph of navlib/ (every import, inside functions too, read with ``ast``) has no
cycle and no arrow from a lower layer to a higher one (:data:`LAYERS`, docs/library.md
"Layers"): the parallel engine and the sweep know no study (the studies register their named
evaluations from above), the linear filter's Monte Carlo lives with the filters, and the
figures draw study results but no study draws a figure."""

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1] / "navlib"
LAYERS = (
    ("ground", ("navlib.errors", "navlib._validation", "navlib.units", "navlib.resolution",
                "navlib.resources", "navlib.earth", "navlib.rotations", "navlib.quaternions",
                "navlib.cache", "navlib.vehicles")),
    ("numerics", ("navlib.kalman", "navlib.kernel_copy", "navlib.discretize",
                  "navlib.sparse_discretize", "navlib.parallel")),
    ("world", ("navlib.strapdown", "navlib.io",
               "navlib.sensors", "navlib.models", "navlib.trajectory")),
    ("analysis", ("navlib.covariance", "navlib.observability", "navlib.metrics",
                  "navlib.filters",
                  "navlib.segmentation", "navlib.compiled")),
    ("sweep", ("navlib.sweep",)),
    ("studies", ("navlib.studies",)),
    ("figures", ("navlib.plots",)),
    ("panels", ("navlib.widgets",)),
    ("entry", ("navlib.reports", "navlib.__main__", "navlib")),
)
"""Layers from the bottom up, each a tuple of module prefixes; a module belongs to the layer
of its longest matching prefix (``navlib`` itself, the package with its lazy submodules, is
the entry layer). Imports within a layer are free as long as they make no cycle."""


def _modules() -> dict[str, Path]:
    out = {}
    for path in ROOT.rglob("*.py"):
        name = ".".join(path.relative_to(ROOT.parent).with_suffix("").parts)
        out[name.removesuffix(".__init__")] = path
    return out


def _edges(modules: dict[str, Path]) -> dict[str, set[str]]:
    edges = {}
    for name, path in modules.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        targets = set()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                found = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    parts = package.split(".")[: len(package.split(".")) - node.level + 1]
                    base = ".".join([*parts, base] if base else parts)
                found = [base, *(f"{base}.{a.name}" for a in node.names)]
            else:
                continue
            for target in found:
                while target and target not in modules:
                    target = target.rpartition(".")[0]
                if target and target != name and not name.startswith(target + "."):
                    targets.add(target)
        edges[name] = targets
    return edges


def _cyclic_groups(edges: dict[str, set[str]]) -> list[set[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on_stack, groups = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in edges.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = set()
            while True:
                w = stack.pop()
                on_stack.discard(w)
                group.add(w)
                if w == v:
                    break
            if len(group) > 1:
                groups.append(group)

    for v in edges:
        if v not in index:
            visit(v)
    return groups


def _layer(module: str) -> int | None:
    best = None
    for level, (_, prefixes) in enumerate(LAYERS):
        for prefix in prefixes:
            if (module == prefix or module.startswith(prefix + ".")) and (
                    best is None or len(prefix) > best[1]):
                best = (level, len(prefix))
    return None if best is None or (best[1] == len("navlib") and module != "navlib") \
        else best[0]


def test_every_module_has_a_layer():
    assert [m for m in _modules() if _layer(m) is None] == []


def test_no_arrow_points_up():
    upward = [f"{a} ({LAYERS[_layer(a)][0]}) -> {b} ({LAYERS[_layer(b)][0]})"
              for a, targets in _edges(_modules()).items() for b in targets
              if _layer(a) is not None and _layer(b) is not None and _layer(b) > _layer(a)]
    assert upward == []


def test_the_layer_check_finds_an_arrow_up():
    assert _layer("navlib.studies.rocket.claims") > _layer("navlib.filters.ekf")
    assert _layer("navlib.plots.ssac") > _layer("navlib.studies.ssac")
    assert _layer("navlib.new_module") is None


def test_no_import_cycle():
    assert _cyclic_groups(_edges(_modules())) == []


def test_the_engine_below_imports_no_study_and_no_filter():
    edges = _edges(_modules())
    for low in ("navlib.parallel", "navlib.sweep"):
        assert not {t for t in edges[low]
                    if t.startswith(("navlib.studies", "navlib.filters"))}, edges[low]


def test_the_cycle_finder_finds_a_cycle():
    assert _cyclic_groups({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [{"a", "b", "c"}]
    assert _cyclic_groups({"a": {"b"}, "b": set()}) == []
