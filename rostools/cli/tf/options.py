"""The Typer option aliases the ``tf`` commands share, each declared once."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rostools.cli.common import FINITE

BagOpt = Annotated[
    Path | None,
    typer.Option("--bag", "-b", help="Read /tf and /tf_static from a .bag or .mcap instead."),
]
TimeoutOpt = Annotated[
    float | None,
    typer.Option(
        "--timeout",
        click_type=FINITE,
        help="Give up after this many seconds (exit 5).",
    ),
]
CountOpt = Annotated[int | None, typer.Option("-n", "--count", help="Exit after this many.")]
FrameArg = Annotated[str, typer.Argument(help="A frame id (a leading / is dropped, as tf2).")]
