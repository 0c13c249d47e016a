"""``rostools bag merge``: one bag out of several.

It shares the options of ``filter`` and ``convert`` (``options.py``).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from rostools.cli.bag.options import (
    CopyOutput,
    CopyWindow,
    FilterExprOpt,
    OutArg,
)
from rostools.cli.bag.shared import copy_command
from rostools.cli.common import FormatOpt, output_format
from rostools.cli.declare import command

if TYPE_CHECKING:
    pass


@command()
def merge(
    ctx: typer.Context,
    dst: OutArg,
    sources: Annotated[list[Path], typer.Argument(help="The .bag or .mcap files to merge.")],
    window: CopyWindow = CopyWindow(),  # noqa: B008 - a record of options, never changed
    expression: FilterExprOpt = None,
    how: CopyOutput = CopyOutput(),  # noqa: B008
    fmt: FormatOpt = None,
) -> None:
    """Merge bags into one, in time order; the same connection in several is written once."""
    from rostools.bag.tools.merge import merge as run_merge

    options = how.copy(window, sources, expression=expression)
    copy_command(output_format(ctx, fmt), how.quiet, "merge", lambda progress: run_merge(
        sources, dst, options, progress=progress
    ))  # fmt: skip
