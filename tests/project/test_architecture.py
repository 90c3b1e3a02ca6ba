"""The rules of the house (docs/architecture.md) that a machine can check.

No import circles between the package's modules, counting imports inside functions too
(a lazy import only hides a circle).  The imports are read from the source with ``ast``,
not by importing, so the test sees every one.
"""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
from scipy.sparse import csr_array
from scipy.sparse.csgraph import connected_components

SRC = Path(__file__).resolve().parents[2] / "src"


def _module_name(path: Path) -> str:
    parts = path.relative_to(SRC).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path, modules: set[str]) -> set[str]:
    """The package's modules that ``path`` imports: ``from echocal.x import y`` is module
    ``echocal.x.y`` when that is a module, else ``echocal.x``."""
    found: set[str] = set()
    package = _module_name(path) if path.name == "__init__.py" else _module_name(path.parent / "x")
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                base = f"{anchor}.{base}" if base else anchor
            names = [f"{base}.{alias.name}" for alias in node.names] + [base]
        else:
            continue
        for name in names:
            while name and name not in modules:
                name = name.rpartition(".")[0]
            if name:
                found.add(name)
    return found


def _graph() -> tuple[list[str], dict[str, set[str]]]:
    files = sorted((SRC / "echocal").rglob("*.py"))
    modules = {_module_name(f): f for f in files}
    edges = {name: _imports(f, set(modules)) - {name} for name, f in modules.items()}
    return sorted(modules), edges


def _circles(names: list[str], edges: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected sets of two or more modules, ignoring imports of a package's
    ``__init__`` by its own submodules' parents (a package re-exporting its members)."""
    index = {name: i for i, name in enumerate(names)}
    rows, cols = [], []
    for a, targets in edges.items():
        for b in targets:
            if a.startswith(b + ".") or b.startswith(a + "."):
                continue  # a package and its own members: re-exports, not layering
            rows.append(index[a])
            cols.append(index[b])
    matrix = csr_array((np.ones(len(rows)), (rows, cols)), shape=(len(names), len(names)))
    _, labels = connected_components(matrix, directed=True, connection="strong")
    groups: dict[int, list[str]] = {}
    for name, label in zip(names, labels, strict=True):
        groups.setdefault(int(label), []).append(name)
    return [g for g in groups.values() if len(g) > 1]


def test_the_reader_finds_imports() -> None:
    names, edges = _graph()
    assert "echocal.wave.image" in names
    assert "echocal.specimen.casting" in edges["echocal.wave.image"]
    assert "echocal.setups" in edges["echocal.setup_digest"]


def test_no_import_circles() -> None:
    circles = _circles(*_graph())
    assert not circles, "import circles: " + "; ".join(" ↔ ".join(c) for c in circles)


def test_a_circle_is_found() -> None:
    names = ["echocal.a", "echocal.b", "echocal.c"]
    edges = {"echocal.a": {"echocal.b"}, "echocal.b": {"echocal.a"}, "echocal.c": set()}
    assert _circles(names, edges) == [["echocal.a", "echocal.b"]]
