"""The ``rostools log`` group: its Typer app, with its commands in ``--help`` order."""

from __future__ import annotations

import typer

from rostools.cli.log import echo, loggers
from rostools.cli.register import add

app = typer.Typer(
    name="log",
    help="Node logs (rosconsole): echo /rosout, list, get and set logger levels.",
    no_args_is_help=True,
    add_completion=False,
)
add(app, echo.echo, loggers.list_loggers, loggers.get, loggers.set_)
