"""ARCHITECTURE.md's command table is the code's: each command, its function and its file.

The table is generated (``scripts/gen-command-table.py``); these tests fail when a command
is added, renamed or moved and the table is not generated again, and read the files the
table names to check each row without the generator.
"""

from __future__ import annotations

import ast
import importlib.util
import re
from pathlib import Path
from types import ModuleType

import pytest

from tests.support.env import ROOT

ROW = re.compile(r"^\| `([\w -]+)` \| `(\w+)` \| `([\w/]+\.py)` \|$")


def generator() -> ModuleType:
    """scripts/gen-command-table.py as a module."""
    spec = importlib.util.spec_from_file_location(
        "gen_command_table", ROOT / "scripts/gen-command-table.py"
    )
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


GEN = generator()
ROWS = [
    m.groups()
    for line in GEN.current((ROOT / "ARCHITECTURE.md").read_text()).splitlines()
    if (m := ROW.match(line))
]


def test_the_table_is_current() -> None:
    assert GEN.main(["--check"]) == 0, "run scripts/gen-command-table.py"


def test_every_command_has_a_row() -> None:
    """Every group, and the verbs the issue names, are in the table."""
    from rostools.cli.app import GROUPS

    commands = {c for c, _, _ in ROWS}
    assert {c.split()[0] for c in commands} == set(GROUPS)
    assert {"topic hz", "bag doctor", "doctor", "bag filter", "bag trigger"} <= commands


def declared_functions(path: Path) -> set[str]:
    """The functions a module declares as commands.

    ``@command(...)``, or ``@app.command()`` in a group of one module.
    """
    tree = ast.parse(path.read_text(), str(path))
    return {
        f.name
        for f in tree.body
        if isinstance(f, ast.FunctionDef)
        and any(
            isinstance(d, ast.Call) and ast.unparse(d.func) in ("command", "app.command")
            for d in f.decorator_list
        )
    }


@pytest.mark.parametrize(("command", "function", "file"), ROWS, ids=[r[0] for r in ROWS])
def test_each_row_names_the_file_that_declares_the_function(
    command: str, function: str, file: str
) -> None:
    assert function in declared_functions(ROOT / "rostools" / file), (
        f"{file} declares no {function}"
    )


def test_a_verb_is_found_from_its_name() -> None:
    """A verb lives in a module named after it, or in a group module (a row says which)."""
    group_modules = {
        "query.py",  # the quick commands of a group (the map's "query.py" role)
        "cli/msg/definitions.py",
        "cli/param/edit.py",
        "cli/action/control.py",
        "cli/node/kill.py",
        "cli/completion.py",
        "cli/bag/compress.py",
    }
    astray = [
        f"{command} in {file}"
        for command, _, file in ROWS
        if Path(file).stem != command.split()[-1].replace("-", "_")
        and file not in group_modules
        and Path(file).name not in group_modules
    ]
    assert not astray, astray


def test_a_stale_table_is_caught(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A row that no longer says what the code does fails the check."""
    stale = tmp_path / "ARCHITECTURE.md"
    text = (ROOT / "ARCHITECTURE.md").read_text()
    stale.write_text(text.replace("`cli/topic/hz.py`", "`cli/topic/meters.py`"))
    monkeypatch.setattr(GEN, "MAP", stale)
    assert GEN.main(["--check"]) == 1
    assert GEN.main([]) == 0  # written again from the code
    assert stale.read_text() == text
