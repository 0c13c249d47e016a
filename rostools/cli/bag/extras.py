"""``rostools bag attachments|metadata|doctor``: what a file holds besides messages; its health.

A ``.bag`` has no attachments or metadata: its lists are empty.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rostools.bag.formats.model import counted
from rostools.cli import output
from rostools.cli.bag.options import BagArg, ForceOpt, QuietOpt
from rostools.cli.bag.shared import Progress
from rostools.cli.common import FormatOpt, output_format
from rostools.cli.declare import command
from rostools.cli.output import Format, emit
from rostools.errors import NotFoundError, QuietExit, UsageError, one_line

if TYPE_CHECKING:
    from rostools.bag.formats import mcap_format as fmt_


def _extras(path: Path) -> list[fmt_.Attachment | fmt_.Metadata]:
    from rostools.bag.formats.access import open_bag
    from rostools.bag.formats.mcap_reader import McapReader

    with open_bag(path) as bag:
        return bag.extras() if isinstance(bag, McapReader) else []


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

    found = [a for a in _extras(bag) if isinstance(a, Attachment)]
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


@command()
def metadata(ctx: typer.Context, bag: BagArg, fmt: FormatOpt = None) -> None:
    """An MCAP file's metadata records, as JSON (or YAML with -F yaml), in file order."""
    from rostools.bag.formats.mcap_format import Metadata

    records = [
        {"name": m.name, "metadata": dict(m.metadata)}
        for m in _extras(bag)
        if isinstance(m, Metadata)
    ]
    chosen = output_format(ctx, fmt)
    emit(Format.json if chosen is Format.text else chosen, records)


@command()
def doctor(
    ctx: typer.Context,
    bags: Annotated[list[Path], typer.Argument(help="One or more .bag or .mcap files.")],
    fmt: FormatOpt = None,
    quiet: QuietOpt = False,
) -> None:
    """Check bags without changing them: one line per finding; exit 1 if there is any."""
    from rostools.bag.tools.findings import doctor as check

    out = output_format(ctx, fmt)
    reports = []
    for path in bags:
        # A bar on a terminal only: the report is one document, so no progress events in it.
        bar = Progress(f"doctor {path.name}", Format.text, quiet)
        reports.append(check(path, bar if bar.bar else None))  # no bar: no count to read
        bar.done()
    if out is Format.text:
        for r in reports:  # a finding may quote the file's names: one line each, escaped
            shown = one_line(r.path)
            if r.clean:
                output.put(f"{shown}: clean ({counted(r.messages, 'message')})\n")
            for finding in r.findings:
                output.put(f"{shown}: {one_line(finding)}\n")
            for note in r.notes:
                output.put(f"{shown}: note: {one_line(note)}\n")
    else:
        data = [
            {"path": str(r.path), "clean": r.clean, "messages": r.messages,
             "findings": r.findings, "notes": r.notes, "recover_helps": r.recover_helps}
            for r in reports
        ]  # fmt: skip
        emit(out, data[0] if len(data) == 1 else data)
    if not all(r.clean for r in reports):
        raise QuietExit(1)
