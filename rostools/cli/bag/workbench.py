"""``rostools bag merge``: the workbench commands that make new bags out of several or parts.

They share the options of ``filter`` and ``convert`` (``files.py``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rostools.cli.bag.files import (
    CompressionOpt,
    ForceOpt,
    OutArg,
    QuietOpt,
    RenameOpt,
    RenameTypeOpt,
    copy_command,
    renames,
    seconds_to_ns,
)
from rostools.cli.bag.group import app
from rostools.cli.common import FINITE, FormatOpt


@app.command()
def merge(
    ctx: typer.Context,
    dst: OutArg,
    sources: Annotated[list[Path], typer.Argument(help="The .bag or .mcap files to merge.")],
    topics: Annotated[
        list[str] | None, typer.Option("--topics", "-t", help="Only these topics.")
    ] = None,
    start: Annotated[
        float | None,
        typer.Option("--start", click_type=FINITE, help="Seconds from the earliest start."),
    ] = None,
    end: Annotated[
        float | None,
        typer.Option("--end", click_type=FINITE, help="Seconds from the earliest start."),
    ] = None,
    expression: Annotated[
        str | None,
        typer.Option("--filter", help="Keep messages for which this is true (as bag filter)."),
    ] = None,
    rename: RenameOpt = None,
    rename_type: RenameTypeOpt = None,
    compression: CompressionOpt = None,
    force: ForceOpt = False,
    quiet: QuietOpt = False,
    fmt: FormatOpt = None,
) -> None:
    """Merge bags into one, in time order; the same connection in several is written once."""
    from rostools.bag.access import bag_info
    from rostools.bag.merge import merge as run_merge

    lo = hi = None
    if start is not None or end is not None:
        begin = min(bag_info(s).start_ns or 0 for s in sources)
        lo = None if start is None else begin + (seconds_to_ns(start) or 0)
        hi = None if end is None else begin + (seconds_to_ns(end) or 0)
    rules = renames(rename, rename_type)
    copy_command(ctx, fmt, quiet, "merge", lambda progress: run_merge(
        sources, dst, topics=topics or None, start=lo, end=hi, expression=expression,
        compression=compression, progress=progress, overwrite=force, renames=rules,
    ))  # fmt: skip
