"""The dependencies in pyproject.toml say what is used (issue 28).

Every runtime dependency is imported by some module under rostools/ (``mcap`` was declared for
years while only the tests used it), and every third-party module rostools imports is declared:
as a runtime dependency or an optional extra, or in ``PROVIDED`` with the reason.
Imports under ``if TYPE_CHECKING:`` are not runtime use and are not counted.
"""

from __future__ import annotations

import ast
import re
import sys
from collections.abc import Iterable, Set
from functools import cache
from importlib.metadata import distributions
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
#: Third-party modules rostools imports without declaring them, and why that is right.
PROVIDED = {
    "click": "typer before 0.27 depends on it; imported only when typer._click is absent",
    "pytest": "the pytest plugin (rostools.testing) is loaded by pytest itself",
}


def pyproject() -> dict[str, Any]:
    """pyproject.toml, parsed."""
    if sys.version_info >= (3, 11):
        import tomllib
    else:
        import tomli as tomllib  # the test extra installs it before 3.11
    with (ROOT / "pyproject.toml").open("rb") as f:
        data: dict[str, Any] = tomllib.load(f)
    return data


def dist_name(requirement: str) -> str:
    """The normalized distribution name of a requirement (PEP 503): ``PyYAML>=6`` -> pyyaml."""
    match = re.match(r"[A-Za-z0-9][A-Za-z0-9._-]*", requirement)
    assert match, requirement
    return re.sub(r"[-_.]+", "-", match.group()).lower()


@cache
def import_names() -> dict[str, set[str]]:
    """Installed distributions (normalized names) -> the top-level modules each provides.

    From each one's files, as 3.11's ``packages_distributions`` does: 3.10's reads only
    ``top_level.txt``, which wheels built by hatch or meson (typer, rich, numpy) lack.
    """
    names: dict[str, set[str]] = {}
    for dist in distributions():
        modules = names.setdefault(dist_name(dist.metadata["Name"]), set())
        for file in dist.files or ():
            top = file.parts[0]
            if top.endswith(".py"):
                modules.add(top[:-3])
            elif len(file.parts) > 1 and not top.endswith((".dist-info", ".data")):
                modules.add(top)
    return names


def _is_type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def runtime_imports(package: Path) -> set[str]:
    """Top-level modules imported anywhere in ``package`` (lazy imports in functions too)."""
    found: set[str] = set()

    def visit(node: ast.AST) -> None:
        if isinstance(node, ast.If) and _is_type_checking(node):
            for child in node.orelse:
                visit(child)
            return
        if isinstance(node, ast.Import):
            found.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            found.add(node.module.split(".")[0])
        for child in ast.iter_child_nodes(node):
            visit(child)

    for path in package.rglob("*.py"):
        visit(ast.parse(path.read_text(encoding="utf-8"), str(path)))
    return found


def unimported(
    requirements: Iterable[str], imported: Set[str], names: dict[str, set[str]]
) -> list[str]:
    """The requirements none of whose modules is imported (or not installed: unknown names)."""
    out = []
    for requirement in requirements:
        dist = dist_name(requirement)
        modules = names.get(dist)
        if not modules:
            out.append(f"{dist} (not installed: its import names are unknown)")
        elif not modules & imported:
            out.append(dist)
    return out


@cache
def rostools_imports() -> frozenset[str]:
    """What rostools imports (parsing it takes seconds: once per session)."""
    return frozenset(runtime_imports(ROOT / "rostools"))


def runtime_requirements() -> list[str]:
    """[project] dependencies."""
    deps: list[str] = pyproject()["project"]["dependencies"]
    return deps


def test_every_runtime_dependency_is_imported_by_rostools() -> None:
    imported = rostools_imports()
    assert unimported(runtime_requirements(), imported, import_names()) == []


def test_the_check_names_a_dependency_nothing_imports() -> None:
    """What the test above says if ``mcap`` goes back into the runtime dependencies."""
    imported = rostools_imports()
    others = [r for r in runtime_requirements() if dist_name(r) != "mcap"]
    requirements = [*others, "mcap>=1.1"]
    assert unimported(requirements, imported, import_names()) == ["mcap"]


def test_imports_under_type_checking_do_not_count(tmp_path: Path) -> None:
    (tmp_path / "m.py").write_text(
        "from typing import TYPE_CHECKING\n"
        "if TYPE_CHECKING:\n    import numpy\nelse:\n    import yaml\n"
        "def f():\n    import lz4.frame\n"
    )
    assert runtime_imports(tmp_path) == {"typing", "yaml", "lz4"}


def test_every_third_party_import_is_declared() -> None:
    project = pyproject()["project"]
    extras = [
        r for name, reqs in project["optional-dependencies"].items() if name != "test" for r in reqs
    ]
    names = import_names()
    declared = {m for r in [*project["dependencies"], *extras] for m in names.get(dist_name(r), ())}
    third_party = rostools_imports() - set(sys.stdlib_module_names) - {"rostools"}
    assert sorted(third_party - declared - PROVIDED.keys()) == []
