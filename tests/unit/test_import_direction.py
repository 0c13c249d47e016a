"""Imports in ``rostools/`` run one way: down the layers of ARCHITECTURE.md, and in no circle.

Every import counts, at module level or inside a function, under ``TYPE_CHECKING`` or not:
a lazy import is still a dependency, and a circle of them is still a circle.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2] / "rostools"

#: Bottom to top. A module may import its own package and anything on a lower layer.
LAYERS: list[set[str]] = [
    {"errors"},
    {"names", "yamlio"},
    {"wire"},
    {"msgs", "rates", "series"},
    {"rosgraph"},
    {"node"},
    {"master", "bag", "action"},
    {"cli", "_api"},
    {"testing"},
    {"__main__"},
]


def _unit(module: str) -> str:
    """The layered unit of ``rostools.x.y``: its top-level package or module, ``x``."""
    return module.split(".")[1] if module.count(".") else "__init__"


def _layer(unit: str) -> int:
    for rank, units in enumerate(LAYERS):
        if unit in units:
            return rank
    raise AssertionError(f"rostools/{unit} is on no layer: add it to LAYERS and ARCHITECTURE.md")


def _imports() -> dict[str, set[str]]:
    """Module -> the rostools modules it imports."""
    graph: dict[str, set[str]] = {}
    for path in ROOT.rglob("*.py"):
        parts = path.relative_to(ROOT.parent).with_suffix("").parts
        module = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        package = module if path.name == "__init__.py" else module.rpartition(".")[0]
        found: set[str] = set()
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                found |= {a.name for a in node.names if a.name.startswith("rostools")}
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:  # relative: from the package, up level - 1
                    base = ".".join(
                        [*package.split(".")[: len(package.split(".")) - node.level + 1], base]
                    ).rstrip(".")
                if base.startswith("rostools"):
                    # ``from rostools.cli import output`` imports the module rostools.cli.output
                    for alias in node.names:
                        sub = f"{base}.{alias.name}"
                        is_module = (
                            (ROOT.parent / Path(*sub.split("."))).with_suffix(".py").exists()
                        )
                        found.add(sub if is_module else base)
        graph[module] = found - {module}
    return graph


def test_no_module_imports_upward() -> None:
    upward = [
        f"{module} imports {target}"
        for module, targets in _imports().items()
        if module != "rostools"
        for target in targets
        if target != "rostools" and _layer(_unit(target)) > _layer(_unit(module))
    ]
    assert not upward, "\n".join(sorted(upward))


def test_no_import_circle() -> None:
    graph = _imports()
    circles: list[list[str]] = []
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    path: list[str] = []

    def visit(module: str) -> None:
        state[module] = 1
        path.append(module)
        for target in sorted(graph.get(module, ())):
            if state.get(target) == 1:
                circles.append([*path[path.index(target) :], target])
            elif target not in state:
                visit(target)
        path.pop()
        state[module] = 2

    for module in sorted(graph):
        if module not in state:
            visit(module)
    assert not circles, "\n".join(" -> ".join(c) for c in circles)


def test_every_package_is_on_a_layer() -> None:
    units = {_unit(m) for m in _imports() if m != "rostools"}
    assert units <= set().union(*LAYERS), units - set().union(*LAYERS)


def test_no_module_imports_across_its_own_layer() -> None:
    """A module may not import another package on its own layer (bag -> master, say)."""
    sideways = [
        f"{module} imports {target}"
        for module, targets in _imports().items()
        if module != "rostools"
        for target in targets
        if target != "rostools"
        and _unit(target) != _unit(module)
        and _layer(_unit(target)) == _layer(_unit(module))
    ]
    assert not sideways, "\n".join(sorted(sideways))
