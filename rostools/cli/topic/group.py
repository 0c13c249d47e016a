"""The ``rostools topic`` group, to which its modules add their commands."""

from __future__ import annotations

import typer

app = typer.Typer(
    name="topic",
    help="Topics: list, info, type, find, echo, hz, bw, delay, pub, plot.",
    no_args_is_help=True,
    add_completion=False,
)
