"""The package's layers point one way: a test, not a manual check.

Every ``import`` of every module under ``touchbench/`` (function-local ones
included) is read from the source with :mod:`ast`; each module belongs to a
layer (below, bottom first). An import may point to the same layer or one
below, never up, and no group of modules may import each other in a circle.

The package root (``touchbench/__init__.py``) is the top layer: the
user-facing names, loaded on first use (PEP 562) from the layers that define
them, and ``__version__`` taken from ``touchbench.core.version`` (the bottom
layer, where every module reads it); its ``if TYPE_CHECKING:`` imports are
for type checkers only. No module of the package takes anything from the
root, so the facade never takes part in an import.
"""

from __future__ import annotations

import ast
import functools
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parent.parent / "touchbench"

# Bottom first. A module belongs to the layer of the longest prefix it matches.
LAYERS: list[tuple[str, ...]] = [
    ("touchbench.core",),                            # errors, registry, paths, hashing, atomic IO, versions
    ("touchbench.datasets",),                        # the data model and the real-data readers
    ("touchbench.scenes",),                          # synthetic scenes
    ("touchbench.catalog",),                         # dataset references: registered name, scene:NAME, file
    ("touchbench.features",),
    ("touchbench.classifiers",),
    ("touchbench.methods",),                         # feature sets -> estimator; the one fit path
    ("touchbench.streams",),                         # live recognition: recogniser, rules, streams, replay
    ("touchbench.protocols", "touchbench.scoring"),  # schema, splitters; metrics, stream scores, scene fidelity
    ("touchbench.results",),                         # the results store and run manifests
    ("touchbench.engine",),                          # planning and running tasks
    ("touchbench.reports",),                         # leaderboards, plots, HTML
    ("touchbench.papers",),                          # the paper reproduction (runs the engine, writes reports)
    ("touchbench.deploy",),                          # train / predict / stream
    ("touchbench.cli",),
    ("touchbench",),                                 # the facade: user-level names, loaded on first use
]


def module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


@functools.lru_cache(maxsize=None)
def all_modules() -> dict[str, Path]:
    """Every module of the package (read once per test process: the tests only read it)."""
    return {module_name(p): p for p in PACKAGE.rglob("*.py")}


@functools.lru_cache(maxsize=None)
def parsed(path: Path) -> ast.Module:
    """``path``'s syntax tree, parsed once per test process (the tests only read it)."""
    return ast.parse(path.read_text(encoding="utf-8"))


def imports_of(name: str, path: Path, modules: dict[str, Path]) -> set[str]:
    """The touchbench modules that ``name`` imports (a name imported from a
    package counts as its submodule when it is one)."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    body = parsed(path).body
    if name == "touchbench":  # the facade's imports for type checkers (module docstring)
        body = [n for n in body if not _type_checking_only(n)]
    out: set[str] = set()
    for node in (n for top in body for n in ast.walk(top)):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            targets = [f"{mod}.{a.name}" if f"{mod}.{a.name}" in modules else mod for a in node.names]
        else:
            continue
        out.update(t for t in targets if t == "touchbench" or t.startswith("touchbench."))
    out.discard(name)
    return out


def _type_checking_only(node: ast.stmt) -> bool:
    return isinstance(node, ast.If) and isinstance(node.test, ast.Name) and node.test.id == "TYPE_CHECKING"


def layer_of(name: str) -> int:
    best, best_len = None, -1
    for i, prefixes in enumerate(LAYERS):
        for p in prefixes:
            if (name == p or name.startswith(p + ".")) and len(p) > best_len:
                best, best_len = i, len(p)
    assert best is not None, f"{name} belongs to no layer: add it to LAYERS"
    return best


def import_graph() -> dict[str, set[str]]:
    modules = all_modules()
    return {name: imports_of(name, path, modules) for name, path in modules.items()}


def test_every_module_has_a_layer():
    for name in all_modules():
        layer_of(name)


def test_no_import_points_up():
    up = [f"{a} (layer {layer_of(a)}) imports {b} (layer {layer_of(b)})"
          for a, targets in import_graph().items() for b in sorted(targets) if layer_of(b) > layer_of(a)]
    assert not up, "imports that point up the layers:\n" + "\n".join(sorted(up))


def strongly_connected(graph: dict[str, set[str]]) -> list[list[str]]:
    """Tarjan's algorithm: the groups of modules that reach each other."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_no_import_circle():
    circles = [c for c in strongly_connected(import_graph()) if len(c) > 1]
    assert not circles, "modules that import each other in a circle: " + "; ".join(" <-> ".join(c) for c in circles)


@pytest.mark.parametrize("graph, expected", [
    ({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}, [["a", "b", "c"]]),
    ({"a": {"b"}, "b": set()}, []),
])
def test_circle_finder_on_hand_made_graphs(graph, expected):
    assert [c for c in strongly_connected(graph) if len(c) > 1] == expected


def test_layer_of_takes_the_longest_prefix():
    assert layer_of("touchbench.core.errors") == 0
    assert layer_of("touchbench.catalog") == 3
    assert layer_of("touchbench.cli.run") == len(LAYERS) - 2
    assert layer_of("touchbench") == len(LAYERS) - 1


def root_names_used(name: str, path: Path) -> set[str]:
    """The names ``name`` takes from the package root: ``from touchbench import X``,
    ``from .. import X`` reaching the root, ``touchbench.X`` after ``import touchbench``."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out: set[str] = set()
    for node in ast.walk(parsed(path)):
        if isinstance(node, ast.ImportFrom):
            mod = node.module or ""
            if node.level:
                mod = ".".join(package.split(".")[: len(package.split(".")) - (node.level - 1)] + ([mod] if mod else []))
            if mod == "touchbench":
                out.update(a.name for a in node.names if f"touchbench.{a.name}" not in all_modules())
        elif (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id == "touchbench"
              and f"touchbench.{node.attr}" not in all_modules()):
            out.add(node.attr)
    return out


def test_modules_take_nothing_from_the_package_root():
    taken = {name: sorted(root_names_used(name, path) - {"__file__"})
             for name, path in all_modules().items() if name != "touchbench"}
    assert not {k: v for k, v in taken.items() if v}, "modules taking facade names from the package root"


def test_root_name_finder_on_hand_made_sources(tmp_path):
    f = tmp_path / "m.py"
    f.write_text("import touchbench\nfrom .. import __version__, load_dataset\nx = touchbench.run_protocol\n")
    assert root_names_used("touchbench.engine.m", f) == {"__version__", "load_dataset", "run_protocol"}
