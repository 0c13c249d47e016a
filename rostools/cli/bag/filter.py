"""``rostools bag filter``: copy the messages that pass topic, time and expression filters."""

from __future__ import annotations

from functools import partial
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rostools.cli import output
from rostools.cli.bag.options import (
    BagArg,
    CopyOutput,
    CopyWindow,
    OutArg,
)
from rostools.cli.bag.shared import copy_command
from rostools.cli.common import FormatOpt, output_format
from rostools.cli.declare import command
from rostools.cli.output import Format

if TYPE_CHECKING:
    pass


@command("filter")
def filter_(
    ctx: typer.Context,
    src: BagArg,
    dst: OutArg,
    expression: Annotated[
        str | None,
        typer.Argument(
            help="Python over topic, m (the message) and t (its time), as rosbag filter."
        ),
    ] = None,
    window: CopyWindow = CopyWindow(),  # noqa: B008 - a record of options, never changed
    print_: Annotated[
        str | None,
        typer.Option(
            "--print", "-p", help="Print MATCH or NO MATCH and this expression for each message."
        ),
    ] = None,
    latched: Annotated[
        bool,
        typer.Option(
            "--latched", help="With --start: keep each latched topic's last earlier message."
        ),
    ] = False,
    how: CopyOutput = CopyOutput(),  # noqa: B008
    fmt: FormatOpt = None,
) -> None:
    """Copy the messages that pass topic, time and expression filters (rosbag filter).

    Filters see the topic names in the input; --rename applies as they are written.
    """
    from rostools.bag.tools.ops import filter_bag

    options = how.copy(window, [src], expression=expression)
    out = output_format(ctx, fmt)
    show = None if print_ is None else (print_, partial(_say, out))
    copy_command(out, how.quiet or show is not None, "filter", lambda progress: filter_bag(
        src, dst, options, progress=progress, show=show, latched=latched
    ))  # fmt: skip


def _say(fmt: Format, matched: bool, value: Any) -> None:
    """One line of ``filter --print``: text as rosbag prints it, or an NDJSON object."""
    text = f"{'MATCH' if matched else 'NO MATCH'} {value}"
    output.write(fmt, {"match": matched, "print": value}, lambda _: text)
