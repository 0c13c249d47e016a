"""``rostools bag convert``: .bag to MCAP or back, losslessly."""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated

import typer

from rostools.cli.bag.options import (
    BagArg,
    CopyOutput,
    OutArg,
)
from rostools.cli.bag.shared import copy_command
from rostools.cli.common import FormatOpt, output_format
from rostools.cli.declare import command

if TYPE_CHECKING:
    pass


@command()
def convert(
    ctx: typer.Context,
    src: BagArg,
    dst: OutArg,
    chunk_size: Annotated[int | None, typer.Option("--chunksize", help="Chunk size in KB.")] = None,
    how: CopyOutput = CopyOutput(),  # noqa: B008 - a record of options, never changed
    fmt: FormatOpt = None,
) -> None:
    """Convert .bag to MCAP or back, losslessly (renaming topics or types if asked)."""
    from rostools.bag.tools.ops import convert as run_convert

    options = how.copy(chunk_size=chunk_size * 1024 if chunk_size else None)
    copy_command(output_format(ctx, fmt), how.quiet, "convert", lambda progress: run_convert(
        src, dst, options, progress=progress
    ))  # fmt: skip
