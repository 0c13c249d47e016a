"""Imports in ``rostools/`` run one way: down the layers of ARCHITECTURE.md, and in no circle.

Every import counts, at module level or inside a function, under ``TYPE_CHECKING`` or not:
a lazy import is still a dependency, and a circle of them is still a circle.
"""

from __future__ import annotations

import ast
import functools
import json
from pathlib import Path

import pytest

# One worker reads the tree once for all of them (each read parses ~400 files).
pytestmark = pytest.mark.xdist_group("import_direction")

ROOT = Path(__file__).resolve().parents[2] / "rostools"

#: Bottom to top. A module may import its own package and anything on a lower layer. The
#: package root (``__init__``) stands above everything: its names are the API's, lazily.
LAYERS: list[set[str]] = [
    {"errors", "lazy", "version"},
    {"names", "yamlio", "selection"},
    {"wire"},
    {"msgs", "rates", "series", "tf"},
    {"rosgraph"},
    {"node"},
    {"master", "bag", "action", "web"},
    {"cli", "_api"},
    {"testing"},
    {"__main__", "__init__"},
]


def _unit(module: str) -> str:
    """The layered unit of ``rostools.x.y``: its top-level package or module, ``x``."""
    return module.split(".")[1] if module.count(".") else "__init__"


def _layer(unit: str) -> int:
    for rank, units in enumerate(LAYERS):
        if unit in units:
            return rank
    raise AssertionError(f"rostools/{unit} is on no layer: add it to LAYERS and ARCHITECTURE.md")


@functools.cache
def _parsed(path: Path) -> ast.Module:
    """``path``'s syntax tree, parsed once per process."""
    return ast.parse(path.read_text(), str(path))


def _is_type_checking(test: ast.expr) -> bool:
    """``if TYPE_CHECKING:`` (the only spelling rostools uses)."""
    return isinstance(test, ast.Name) and test.id == "TYPE_CHECKING"


def _nodes(tree: ast.AST, at_run_time: bool, on_import: bool) -> list[ast.AST]:
    """Every node of ``tree``; with ``at_run_time``, not those under ``if TYPE_CHECKING:``;
    with ``on_import``, not those in functions either (what importing the module runs)."""
    if not at_run_time:
        return list(ast.walk(tree))
    skipped = {
        id(n)
        for block in ast.walk(tree)
        if (isinstance(block, ast.If) and _is_type_checking(block.test))
        or (on_import and isinstance(block, ast.FunctionDef | ast.AsyncFunctionDef))
        for statement in (block.body if isinstance(block, ast.If) else [block])
        for n in ast.walk(statement)
    }
    return [n for n in ast.walk(tree) if id(n) not in skipped]


def _imports(
    at_run_time: bool = False, outside: tuple[str, ...] = (), on_import: bool = False
) -> dict[str, set[str]]:
    """Module -> the rostools modules it imports, and those of ``outside`` packages it names.

    ``at_run_time`` leaves out what is imported for annotations only, ``on_import`` also
    what functions import when they run.
    """
    return {m: set(t) for m, t in _read_imports(at_run_time, outside, on_import).items()}


@functools.cache
def _read_imports(
    at_run_time: bool, outside: tuple[str, ...], on_import: bool
) -> dict[str, frozenset[str]]:
    """``_imports`` as read once per process (callers get copies)."""
    graph: dict[str, frozenset[str]] = {}
    for path in ROOT.rglob("*.py"):
        parts = path.relative_to(ROOT.parent).with_suffix("").parts
        module = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        package = module if path.name == "__init__.py" else module.rpartition(".")[0]
        found: set[str] = set()
        # The package's own block of TYPE_CHECKING imports is its list of public names, which
        # load on first use (rostools.lazy): no import of anything when the package loads.
        runtime_only = at_run_time or module == "rostools"
        for node in _nodes(_parsed(path), runtime_only, on_import):
            if isinstance(node, ast.Import):
                found |= {a.name for a in node.names if a.name.startswith(("rostools", *outside))}
            elif (
                isinstance(node, ast.ImportFrom)
                and node.module
                and not node.level
                and (node.module.split(".")[0] in outside)
            ):
                found.add(node.module)
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
        graph[module] = frozenset(found - {module})
    return graph


def test_no_module_imports_upward() -> None:
    upward = [
        f"{module} imports {target}"
        for module, targets in _imports().items()
        if module != "rostools"
        for target in targets
        if _layer(_unit(target)) > _layer(_unit(module))
    ]
    assert not upward, "\n".join(sorted(upward))


def test_the_package_root_counts_as_a_module() -> None:
    """``from rostools import __version__`` imports the package root, the top of the layers:
    the check let it through (bag/formats/mcap_writer.py did it), as if the root were no module."""
    imports = _imports()
    assert _unit("rostools") == "__init__" and _layer("__init__") == len(LAYERS) - 1
    assert "rostools.version" in imports["rostools.bag.formats.mcap_writer"]
    assert not [m for m, targets in imports.items() if "rostools" in targets], "the root imported"


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
        if _unit(target) != _unit(module) and _layer(_unit(target)) == _layer(_unit(module))
    ]
    assert not sideways, "\n".join(sorted(sideways))


#: The rooms of ``bag/`` and the other rooms each may import (ARCHITECTURE.md, the code map).
BAG_ROOMS: dict[str, set[str]] = {
    "formats": set(),
    "live": {"formats"},
    "tools": {"formats"},
    "tables": {"formats"},
}


def _bag_room(module: str) -> str | None:
    """``live`` for ``rostools.bag.live.player``; None outside ``bag`` and for its root."""
    parts = module.split(".")
    return parts[2] if parts[:2] == ["rostools", "bag"] and len(parts) > 2 else None


def test_every_bag_module_is_in_a_room() -> None:
    modules = [m for m in _imports() if m.startswith("rostools.bag.")]
    assert {_bag_room(m) for m in modules} == set(BAG_ROOMS), sorted(modules)
    assert all(m.count(".") == 3 or m in {f"rostools.bag.{r}" for r in BAG_ROOMS} for m in modules)


def test_bag_rooms_import_only_formats() -> None:
    """``live`` and ``tools`` import ``formats``, not each other; ``formats`` imports neither."""
    crossing = [
        f"{module} imports {target}"
        for module, targets in _imports().items()
        if (room := _bag_room(module))
        for target in targets
        if _bag_room(target) not in (None, room, *BAG_ROOMS[room])
    ]
    assert not crossing, "\n".join(sorted(crossing))


def _group_of(module: str) -> str | None:
    """``topic`` for ``rostools.cli.topic.echo``; None for a module of ``cli`` itself."""
    parts = module.split(".")
    if parts[:2] != ["rostools", "cli"] or len(parts) < 3:
        return None
    return parts[2] if (ROOT / "cli" / parts[2]).is_dir() else None


def test_no_cli_group_imports_another() -> None:
    """A group (cli/topic, cli/bag, ...) imports its own modules and cli's shared ones only."""
    across = [
        f"{module} imports {target}"
        for module, targets in _imports().items()
        if _group_of(module)
        for target in targets
        if _group_of(target) not in (None, _group_of(module))
    ]
    assert not across, "\n".join(sorted(across))


def _verbs() -> set[str]:
    """The modules of cli that declare commands (``@command(...)``) and are no group's app."""
    verbs = set()
    for path in (ROOT / "cli").rglob("*.py"):
        tree = ast.parse(path.read_text())
        declares = any(
            isinstance(d, ast.Call) and ast.unparse(d.func) in ("command", "app.command")
            for f in tree.body
            if isinstance(f, ast.FunctionDef)
            for d in f.decorator_list
        )
        if declares:
            verbs.add(".".join(path.relative_to(ROOT.parent).with_suffix("").parts))
    return verbs


def test_no_verb_imports_a_verb() -> None:
    """What two commands share lives in a module no command owns (a group's shared.py)."""
    verbs = _verbs()
    assert {"rostools.cli.topic.echo", "rostools.cli.bag.record"} <= verbs, verbs
    found = [
        f"{module} imports {target}"
        for module, targets in _imports().items()
        if module in verbs
        for target in targets & verbs
    ]
    assert not found, "\n".join(sorted(found))


def test_group_packages_start_empty() -> None:
    """A group's ``__init__`` imports nothing: its Typer app is in ``group.py``."""
    for package in (p for p in (ROOT / "cli").iterdir() if (p / "__init__.py").exists()):
        tree = ast.parse((package / "__init__.py").read_text())
        assert not [n for n in ast.walk(tree) if isinstance(n, ast.Import | ast.ImportFrom)], (
            package.name
        )


def test_quick_commands_reach_no_typer() -> None:
    """What the launcher runs imports no Typer or Click at run time, however deep or lazily.

    Importing a module imports its packages first, so ``rostools.cli.topic``'s ``__init__``
    counts for ``rostools.cli.topic.query`` (but not what the functions of a package run:
    ``rostools.cli.main`` hands over to Typer when the launcher does not run a command).
    """
    specs = json.loads((ROOT / "cli" / "quick.json").read_text())
    graph = _imports(at_run_time=True, outside=("typer", "click"))
    packages = _imports(at_run_time=True, outside=("typer", "click"), on_import=True)
    todo = [
        "rostools.cli.launch",
        *(s["target"].partition(":")[0] for s in specs.values() if s["target"]),
    ]
    seen: set[str] = set()
    while todo:
        module = todo.pop()
        parents = [".".join(module.split(".")[:i]) for i in range(2, module.count(".") + 1)]
        for name in (module, *parents):
            if name not in seen:
                seen.add(name)
                todo += (graph if name == module else packages).get(name, set())
    assert not {m for m in seen if m.split(".")[0] in ("typer", "click")}, sorted(
        m for m in seen if m.startswith("rostools")
    )


def test_the_trigger_and_the_ring_buffer_stand_alone() -> None:
    """``bag trigger`` needs the service's bytes and error, not the snapshot recorder; the ring
    buffer needs the entry overhead, not ``bag record`` (each imported the other for one name)."""
    imports = _imports()
    assert "rostools.bag.live.snapshot" not in imports["rostools.bag.live.snapshot_client"]
    for module in ("ringbuffer", "snapshot_live", "snapshot_services"):
        assert "rostools.bag.live.recorder" not in imports[f"rostools.bag.live.{module}"], module
