"""Lint, formatting and types run with the tests, so one command checks everything."""

from __future__ import annotations

import re
import subprocess
import sys

import pytest

from rostools.errors import EXIT_CODES
from tests.support.env import ROOT


@pytest.mark.parametrize(
    "argv",
    [
        ["ruff", "check", "rostools", "tests", "scripts", "benchmarks"],
        ["ruff", "format", "--check", "rostools", "tests", "scripts", "benchmarks"],
        ["mypy"],
    ],
    ids=["ruff-check", "ruff-format", "mypy"],
)
def test_tool_is_clean(argv: list[str]) -> None:
    proc = subprocess.run(
        [sys.executable, "-m", *argv], cwd=ROOT, capture_output=True, text=True, check=False
    )
    assert proc.returncode == 0, proc.stdout[-4000:] + proc.stderr[-2000:]


def test_the_docs_list_every_exit_code() -> None:
    page = (ROOT / "docs" / "scripting.md").read_text()
    rows = dict(re.findall(r"^\| (\d+) \| ([^|]+?) \|", page, re.M))
    assert {int(k): v for k, v in rows.items()} == {code: name for code, name, _ in EXIT_CODES}
