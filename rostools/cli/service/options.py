"""The arguments and options the service commands share.

Typer's: the commands import them for their annotations only.
"""

from __future__ import annotations

from typing import Annotated

import typer

from rostools.cli.common import FINITE

ServiceArg = Annotated[str, typer.Argument(help="Service name; relative names join ROS_NAMESPACE.")]
TimeoutOpt = Annotated[
    float, typer.Option("--timeout", click_type=FINITE, help="Seconds to wait for the service.")
]
CallTimeoutOpt = Annotated[
    float | None,
    typer.Option(
        "--timeout",
        click_type=FINITE,
        help="Give up after this many seconds, for --wait and for each call (exit 5). "
        "Without it there is no limit, as with rosservice.",
        show_default=False,
    ),
]
