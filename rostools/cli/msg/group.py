"""The ``rostools msg`` group: its Typer app, with its commands in ``--help`` order."""

from __future__ import annotations

import typer

from rostools.cli.msg import definitions, query
from rostools.cli.register import add, alias

app = typer.Typer(
    name="msg",
    help="Message and service types: show, md5, list, package, packages, proto.",
    no_args_is_help=True,
    add_completion=False,
)
add(app, definitions.show)
alias(app, "info", definitions.show, "The same as show (rosmsg info).")
add(app, query.md5, definitions.list_types, definitions.package, definitions.packages)
add(app, definitions.proto)
