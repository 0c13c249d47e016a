"""The ``rostools action`` group: its Typer app, with its commands in ``--help`` order."""

from __future__ import annotations

import typer

from rostools.cli.action import control, query, send_goal
from rostools.cli.register import add

app = typer.Typer(
    name="action",
    help="Actions (actionlib): list, info, send-goal, cancel, status.",
    no_args_is_help=True,
    add_completion=False,
)
add(app, query.list_actions, query.info, send_goal.send_goal, control.cancel, control.status)
