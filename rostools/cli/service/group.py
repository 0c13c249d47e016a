"""The ``rostools service`` group: its Typer app, with its commands in ``--help`` order."""

from __future__ import annotations

import typer

from rostools.cli.register import add
from rostools.cli.service import call, query

app = typer.Typer(
    name="service",
    help="Services: list, info, type, find, uri, args, call.",
    no_args_is_help=True,
    add_completion=False,
)
add(app, query.list_services, query.uri, query.node, query.type_, query.args, query.info)
add(app, query.find, call.call)
