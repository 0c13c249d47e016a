"""The arguments and options the action commands share.

Typer's: the commands import them for their annotations only.
"""

from __future__ import annotations

from typing import Annotated

import typer

from rostools.cli.common import FINITE

ActionArg = Annotated[
    str, typer.Argument(help="Action name (its topics are NAME/goal, NAME/status, ...).")
]
WaitOpt = Annotated[
    float | None,
    typer.Option(
        "--timeout",
        click_type=FINITE,
        help="Give up after this many seconds (exit 5).",
        show_default=False,
    ),
]
