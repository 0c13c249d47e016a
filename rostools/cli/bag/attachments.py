"""``rostools bag attachments``: an MCAP file's attachments, listed or extracted.

A ``.bag`` has no attachments: its list is empty.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rostools.cli import output
from rostools.cli.bag.options import BagArg, ForceOpt
from rostools.cli.bag.shared import extras_of
from rostools.cli.common import FormatOpt, output_format
from rostools.cli.declare import command
from rostools.cli.output import emit
from rostools.errors import NotFoundError, UsageError, one_line

if TYPE_CHECKING:
    from rostools.bag.formats import mcap_format as fmt_


def _attachment_rows(found: list[fmt_.Attachment]) -> list[dict[str, Any]]:
    return [
        {"name": a.name, "media_type": a.media_type, "log_time": a.log_time,
         "create_time": a.create_time, "size": len(a.data)}
        for a in found
    ]  # fmt: skip


def _attachments_text(rows: list[dict[str, Any]]) -> str:
    if not rows:
        return "no attachments"
    head = ("name", "media type", "log time", "create time", "size")
    table = [head] + [
        (one_line(r["name"]), one_line(r["media_type"]), f"{r['log_time'] / 1e9:.9f}",
         f"{r['create_time'] / 1e9:.9f}", str(r["size"]))
        for r in rows
    ]  # fmt: skip
    widths = [max(len(row[i]) for row in table) for i in range(len(head))]
    return "\n".join("  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)).rstrip()
                     for row in table)  # fmt: skip


@command()
def attachments(
    ctx: typer.Context,
    bag: BagArg,
    get: Annotated[
        str | None, typer.Option("--get", help="Extract the attachment of this name.")
    ] = None,
    out: Annotated[
        Path | None,
        typer.Option("--output", "-o", help="Where --get writes it (default: stdout)."),
    ] = None,
    force: ForceOpt = False,
    fmt: FormatOpt = None,
) -> None:
    """List an MCAP file's attachments, or extract one with --get NAME -o FILE."""
    from rostools.bag.formats.mcap_format import Attachment

    found = [a for a in extras_of(bag) if isinstance(a, Attachment)]
    if get is None:
        if out is not None:
            raise UsageError("--output goes with --get NAME")
        emit(output_format(ctx, fmt), _attachment_rows(found), _attachments_text)
        return
    named = [a for a in found if a.name == get]
    if not named:
        names = ", ".join(sorted({a.name for a in found})) or "none"
        raise NotFoundError(f"{bag} has no attachment named {get!r} (it has: {names})")
    if len(named) > 1:
        raise UsageError(f"{bag} has {len(named)} attachments named {get!r}")
    data = named[0].data
    if out is None:
        if sys.stdout.isatty():
            raise UsageError("give -o FILE: the attachment is not written to a terminal")
        output.put_bytes(data)
        return
    if out.exists() and not force:
        raise UsageError(f"{out} exists (use -f to overwrite)")
    out.write_bytes(data)
