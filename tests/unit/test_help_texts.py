"""Help texts read as text: no reStructuredText markup leaks into ``--help``.

Docstrings use ``code`` marks, but Typer prints a command's docstring as it is: ``param set
--help`` said "negative numbers need no ``--``".
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import typer

from rostools.cli.app import GROUPS, group_app


def _helps() -> Iterator[tuple[str, str]]:
    for group in GROUPS:
        root = typer.main.get_command(group_app(group))
        commands: dict[str, Any] = getattr(root, "commands", {}) or {group: root}
        for name, cmd in commands.items():
            yield f"{group} {name}", cmd.help or ""
            for param in cmd.params:
                yield f"{group} {name} {param.name}", getattr(param, "help", None) or ""


def test_no_help_text_shows_rst_code_marks() -> None:
    shown = {where: text for where, text in _helps() if "``" in text}
    assert shown == {}
