"""The arguments and options the bag commands share.

Typer's: the commands import them for their annotations.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rostools.cli.common import FINITE

BagArg = Annotated[Path, typer.Argument(help="A .bag or .mcap file.")]
OutArg = Annotated[Path, typer.Argument(help="The file to write; its name picks the format.")]
ForceOpt = Annotated[bool, typer.Option("--force", "-f", help="Overwrite an existing output file.")]
QuietOpt = Annotated[bool, typer.Option("--quiet", "-q", help="No progress bar.")]
CompressionOpt = Annotated[
    str | None,
    typer.Option(
        "--compression",
        "-c",
        help="Chunk compression: none, bz2 or lz4 (.bag); zstd, lz4 or none (MCAP).",
    ),
]
TopicsOpt = Annotated[list[str] | None, typer.Option("--topics", "-t", help="Only these topics.")]
StartOpt = Annotated[
    float | None,
    typer.Option("--start", click_type=FINITE, help="Seconds from the (earliest) bag's start."),
]
EndOpt = Annotated[
    float | None,
    typer.Option("--end", click_type=FINITE, help="Seconds from the (earliest) bag's start."),
]
FilterExprOpt = Annotated[
    str | None,
    typer.Option("--filter", help="Only messages for which this is true (as bag filter)."),
]


RenameOpt = Annotated[
    list[str] | None,
    typer.Option("--rename", help="Write topic OLD as NEW (/old:=/new, as play); repeatable."),
]
RenameTypeOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--rename-type",
        help="Rename a type (pkg/Old:=pkg/New) where its md5sum stays the same; repeatable.",
    ),
]


OutputDirOpt = Annotated[
    Path | None, typer.Option("--output-dir", help="Write here instead of replacing the bag.")
]


DstOpt = Annotated[Path | None, typer.Argument(help="Output (default: NAME.recovered.bag|mcap).")]
