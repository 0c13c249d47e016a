"""The ``rostools param`` group: its Typer app, with its commands in ``--help`` order."""

from __future__ import annotations

import typer

from rostools.cli.param import edit, query
from rostools.cli.register import add

app = typer.Typer(
    name="param",
    help="The parameter server: list, get, set, delete, load, dump.",
    no_args_is_help=True,
    add_completion=False,
)
add(app, query.list_params, query.get, edit.set, edit.delete, edit.load, edit.dump)
