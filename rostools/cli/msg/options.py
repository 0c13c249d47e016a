"""The arguments and options the msg commands share.

Typer's: the commands import them for their annotations only.
"""

from __future__ import annotations

from typing import Annotated

import typer

TypeArg = Annotated[
    str | None,
    typer.Argument(
        help="pkg/Type, or a bare Type to search every package; read from stdin when omitted.",
        show_default=False,
    ),
]
SrvOpt = Annotated[bool, typer.Option("--srv", help="Services instead of messages.")]
OneLineOpt = Annotated[bool, typer.Option("-s", help="All on one line, space-separated.")]
