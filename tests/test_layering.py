"""The layout of docs/architecture.md, read from every module's imports (ast): imports go only
downward in the layer order, no two modules import each other (directly or around a circle, lazy
imports inside functions included), and no module imports another's private names."""
from __future__ import annotations

import ast
import sys
from pathlib import Path

import networkx as nx
import pytest

ROOT = Path(__file__).resolve().parents[1]
#: Lowest first: a module may import its own layer and the layers before it.
LAYERS = ("bondgraph", "bondgraph.numerics", "plants", "fmus", "estimators", "cosim", "reproductions",
          "diagnosis", "sweeps", "bondcosim")
PACKAGES = ("bondgraph", "plants", "fmus", "estimators", "cosim", "reproductions", "diagnosis", "sweeps",
            "bondcosim")


def _module_name(path: Path) -> tuple[str, str]:
    """(module, package its relative imports start from)."""
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        name = ".".join(parts[:-1])
        return name, name
    name = ".".join(parts)
    return name, name.rpartition(".")[0]


def _modules() -> dict[str, Path]:
    out = {}
    for package in PACKAGES:
        for path in (ROOT / package).rglob("*.py"):
            out[_module_name(path)[0]] = path
    return out


MODULES = _modules()


def _type_checking_only(node: ast.AST) -> bool:
    return isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test)


def _imports(path: Path):
    """(target module, imported name or None, line) of every import in `path`, lazy ones included,
    ``if TYPE_CHECKING:`` blocks left out (annotations only, never executed)."""
    _, package = _module_name(path)
    stack = [ast.parse(path.read_text(encoding="utf-8"))]
    while stack:
        node = stack.pop()
        if _type_checking_only(node):
            continue
        stack.extend(ast.iter_child_nodes(node))
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name, None, node.lineno
        elif isinstance(node, ast.ImportFrom):
            module = node.module or ""
            if node.level:
                base = package.split(".")
                base = base[:len(base) - (node.level - 1)]
                module = ".".join(base + ([node.module] if node.module else []))
            for alias in node.names:
                yield module, alias.name, node.lineno


def _edges():
    """(importer, imported module, name, line) for imports among the project's modules."""
    for importer, path in MODULES.items():
        for module, name, line in _imports(path):
            if module.split(".")[0] not in PACKAGES:
                continue
            target = f"{module}.{name}" if name and f"{module}.{name}" in MODULES else module
            yield importer, target, (None if target != module else name), line


EDGES = list(_edges())


def _layer(module: str) -> int:
    return max(i for i, layer in enumerate(LAYERS) if module == layer or module.startswith(layer + "."))


def test_every_module_is_in_a_layer():
    assert set(MODULES) and all(_layer(m) >= 0 for m in MODULES)


def test_imports_go_only_downward():
    upward = [f"{MODULES[a].relative_to(ROOT)}:{line} imports {b} ({LAYERS[_layer(b)]} is above "
              f"{LAYERS[_layer(a)]})" for a, b, _, line in EDGES if _layer(b) > _layer(a)]
    assert upward == []


def test_no_import_cycles():
    graph = nx.DiGraph((a, b) for a, b, _, _ in EDGES if a != b)
    cycles = sorted(" -> ".join(c + [c[0]]) for c in nx.simple_cycles(graph))
    assert cycles == []


def _private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def test_no_private_names_cross_modules():
    """A private name (``_x``) is imported from nowhere; a private module (``_pam_rig``) only from
    within its own package."""
    found = []
    for importer, target, name, line in EDGES:
        where = f"{MODULES[importer].relative_to(ROOT)}:{line}"
        if name is not None and _private(name):
            found.append(f"{where} imports {name} from {target}")
        parts = target.split(".")
        for i, part in enumerate(parts):
            if _private(part) and not importer.startswith(".".join(parts[:i]) + "."):
                found.append(f"{where} imports the private module {target} from outside its package")
    assert found == []


@pytest.mark.parametrize("rule", [test_imports_go_only_downward, test_no_import_cycles,
                                  test_no_private_names_cross_modules])
def test_the_rules_can_fail(rule, monkeypatch):
    """Each rule fails on a planted violation (the checks are not vacuous)."""
    planted = {test_imports_go_only_downward: ("bondgraph.graph", "bondgraph.numerics.simulation", None, 1),
               test_no_import_cycles: ("bondgraph.errors", "bondgraph.graph", None, 1),
               test_no_private_names_cross_modules: ("cosim.master", "reproductions._pam_rig", None, 1)}[rule]
    monkeypatch.setattr(sys.modules[__name__], "EDGES", EDGES + [planted])
    with pytest.raises(AssertionError):
        rule()
