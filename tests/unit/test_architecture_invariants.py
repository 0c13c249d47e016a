"""ARCHITECTURE.md names, for each of its Invariants, the tests that hold it, and they exist.

A test named there that is renamed or removed, or an invariant added without one, fails here.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

from tests.support import archmap
from tests.support.env import ROOT

#: A test as pytest names it: ``tests/...py::function``.
NODE_ID = re.compile(r"`(tests/[\w/]+\.py)::(\w+)`")


def invariants(text: str) -> list[str]:
    """The bullets of the Invariants section, each with its continuation lines."""
    section = text.split("\n## Invariants\n", 1)[1].split("\n## ", 1)[0]
    bullets: list[str] = []
    for line in section.splitlines():
        if line.startswith("- "):
            bullets.append(line)
        elif bullets:
            bullets[-1] += "\n" + line
    return bullets


def functions_in(path: Path) -> set[str]:
    """The names of the test functions in a test file (top level, and in classes)."""
    tree = ast.parse(path.read_text(), str(path))
    return {
        node.name
        for node in ast.walk(tree)
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef)
        and node.name.startswith("test_")
    }


BULLETS = invariants((ROOT / "ARCHITECTURE.md").read_text())


def test_the_section_is_found() -> None:
    assert len(BULLETS) >= 7, BULLETS
    assert all(b.startswith("- **") for b in BULLETS)


@pytest.mark.parametrize("bullet", BULLETS, ids=[b[4:].split("**")[0] for b in BULLETS])
def test_each_invariant_names_tests_that_exist(bullet: str) -> None:
    named = NODE_ID.findall(bullet)
    assert named, f"names no test (`tests/....py::test_name`): {bullet[:80]}"
    for file, function in named:
        path = ROOT / file
        assert path.is_file(), f"{file} does not exist"
        assert function in functions_in(path), f"{file} has no test {function}"


def test_the_parser_sees_what_is_wrong() -> None:
    """A bullet without a test, and a test that is not there, are both caught."""
    text = (
        "\n## Invariants\n\n- **A.** Tests: `tests/unit/test_architecture_invariants.py::nope`.\n"
        "- **B.** None.\n\n## Next\n- **C.** `tests/x.py::test_y`\n"
    )
    first, second = invariants(text)
    assert NODE_ID.findall(first) == [("tests/unit/test_architecture_invariants.py", "nope")]
    assert "nope" not in functions_in(Path(__file__))
    assert NODE_ID.findall(second) == []


# The map itself: every module on it, every file it or the code cites there, every wait and
# limit in its tables (issue 37). ``tests/support/archmap.py`` reads the map.

MAP_TEXT = archmap.text()
#: The roles every CLI group's package has, named once for all groups on the map.
GROUP_ROLES = ("__init__.py", "group.py", "options.py", "shared.py", "query.py")


def named_on_map(module: str, whole: str) -> bool:
    """Whether the map names ``module`` (a path under rostools/).

    A path that ends with the module's (``cli/bag/info.py``, ``bag/info.py``, or
    ``bag/info.Name`` for a name in it) names it anywhere; a path under its package
    (``codec.py``, ``codec.Codec``) names it in its package's row of the code map; a CLI
    group's role modules are named by their roles.
    """
    parts = module.split("/")
    tails = ["/".join(parts[i:]) for i in range(len(parts) - 1)]  # a/b/c.py, b/c.py
    tails.append(f"rostools/{module}")
    if any(archmap.mentions(whole, tail) for tail in tails):
        return True
    if parts[-1] == "__init__.py" and len(parts) > 1:
        package = "/".join(parts[:-1])
        return f"`{package}/`" in whole or f"`{parts[-2]}`" in whole
    if len(parts) == 3 and parts[0] == "cli" and parts[2] in GROUP_ROLES:
        return f"`{parts[2]}`" in whole
    code_map = archmap.section(whole, "Code map")
    for row in code_map.splitlines():
        cells = row.split("|")
        if len(cells) <= 3:
            continue
        # the row of its package, or of a sub-package (`bag/formats/`), says it relatively
        if len(parts) == 1 and f"`{module}`" in cells[2]:
            return True
        for depth in range(1, len(parts)):
            package = "/".join(parts[:depth])
            in_row = f"`{package}/`" in cells[2] or (depth == 1 and f"`{package}`" in cells[2])
            if in_row and archmap.mentions(row, "/".join(parts[depth:])):
                return True
    return False


MODULES = [archmap.relative(m) for m in archmap.modules()]


@pytest.mark.parametrize("module", MODULES)
def test_every_module_is_on_the_map(module: str) -> None:
    assert named_on_map(module, MAP_TEXT), f"ARCHITECTURE.md does not name {module}"


def cited_files() -> list[tuple[str, str]]:
    """(where, the file cited) for every file the map and the code's comments and strings cite."""
    found = [("ARCHITECTURE.md", c) for c in sorted(archmap.cited_in(MAP_TEXT))]
    for module in archmap.modules():
        where = f"rostools/{archmap.relative(module)}"
        found += [(where, c) for c in sorted(archmap.cited_in_source(module))]
    return found


#: Files of other projects that the code cites by name, and whose they are.
ELSEWHERE = {"genaction.py": "actionlib_msgs' generator of an action's messages"}


def test_every_file_cited_exists() -> None:
    missing = [
        f"{where} cites {cited}"
        for where, cited in cited_files()
        if not archmap.exists(cited) and cited not in ELSEWHERE
    ]
    assert not missing, "\n".join(missing)


CONSTANTS = archmap.bounded_constants()


@pytest.mark.parametrize(("module", "name"), CONSTANTS, ids=[f"{m}:{n}" for m, n in CONSTANTS])
def test_every_wait_and_limit_is_in_a_table_with_its_home(module: str, name: str) -> None:
    """Each ``*_TIMEOUT``, ``*_WAIT`` and ``MAX_*`` is in the timeouts list or the limits table.

    The item that names it gives its module: the file cited nearest before it, else after.
    """
    given = [h for item in archmap.bounded_items(MAP_TEXT) for h in archmap.homes_in(item, name)]
    assert given, f"{module} {name} is in neither the timeouts list nor the limits table"
    assert any(archmap.names_module(h, module) for h in given), (
        f"the map gives {name}'s home as {', '.join(given)}, not {module}"
    )


def test_the_map_checks_see_what_is_wrong() -> None:
    """A module left off, a file that is not there and a constant put in the wrong home."""
    text = (
        "\n## Code map\n\n| layer | package | what | look |\n|---|---|---|---|\n"
        "| 2 | `wire/` | `tcpros.py` | x |\n\n## Invariants\n\n"
        "- **Limits on everything** x\n\n  | limit | constant | value |\n"
        "  | a | `wire/tcpros.py` `MAX_FRAME`; `wire/header.py` `MAX_FIELD_LENGTH` | 1 |\n\n"
        "## Cross-cutting concerns\n\n- **Timeouts.** Each has one home:\n"
        "  - `NODE_TIMEOUT`, for nodes (`rosgraph/nodeapi.py`);\n"
    )
    assert named_on_map("wire/tcpros.py", text)
    assert not named_on_map("wire/header.py", text.split("## Invariants")[0])
    assert not archmap.exists("bag/no_such_module.py")
    assert archmap.exists("bag/recorder.py") or archmap.exists("bag/live/recorder.py")
    items = archmap.bounded_items(text)
    assert [archmap.homes_in(i, "MAX_FIELD_LENGTH") for i in items] == [[], [], ["wire/header.py"]]
    assert archmap.homes_in(items[0], "NODE_TIMEOUT") == ["rosgraph/nodeapi.py"]
    assert not archmap.names_module("rosgraph/nodeapi.py", "rosgraph/masterapi.py")
