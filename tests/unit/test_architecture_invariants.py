"""ARCHITECTURE.md names, for each of its Invariants, the tests that hold it, and they exist.

A test named there that is renamed or removed, or an invariant added without one, fails here.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

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
