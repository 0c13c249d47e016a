"""The ``rostools tf`` group: its Typer app, with its commands in ``--help`` order."""

from __future__ import annotations

import typer

from rostools.cli.register import add
from rostools.cli.tf import echo, frames, monitor, pub

app = typer.Typer(
    name="tf",
    help="Transforms (tf2): echo, frames, monitor, pub.",
    no_args_is_help=True,
    add_completion=False,
)
add(app, echo.echo)
add(app, frames.frames, monitor.monitor, pub.pub)


@app.callback()
def _group() -> None:
    """Keep ``tf`` a group while it has one command (Typer would make it the command)."""
