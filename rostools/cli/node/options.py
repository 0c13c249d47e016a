"""The options the node commands share.

Typer's: the commands import them for their annotations only.
"""

from __future__ import annotations

from typing import Annotated

import typer

from rostools.cli.common import FiniteFloat

TimeoutOpt = Annotated[
    float,
    typer.Option(
        "--timeout",
        "-t",
        click_type=FiniteFloat(min=0.001),
        help="Seconds to wait for each node's answer.",
    ),
]
