"""The ``rostools action`` group, to which its modules add their commands."""

from __future__ import annotations

import typer

app = typer.Typer(
    name="action",
    help="Actions (actionlib): list, info, send-goal, cancel, status.",
    no_args_is_help=True,
    add_completion=False,
)
