"""The ``rostools topic`` group: its Typer app, with its commands in ``--help`` order."""

from __future__ import annotations

import typer

from rostools.cli.register import add
from rostools.cli.topic import bw, delay, echo, hz, plot, pub, query

app = typer.Typer(
    name="topic",
    help="Topics: list, info, type, find, echo, hz, bw, delay, pub, plot.",
    no_args_is_help=True,
    add_completion=False,
)
add(app, query.list_topics, query.info, query.find, query.type_)
add(app, echo.echo, pub.pub, hz.hz, bw.bw, delay.delay, plot.plot)
