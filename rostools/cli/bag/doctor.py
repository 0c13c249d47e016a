"""``rostools bag doctor``: check bags without changing them, one line per finding."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from rostools.bag.formats.model import counted
from rostools.cli import output
from rostools.cli.bag.options import QuietOpt
from rostools.cli.bag.shared import Progress
from rostools.cli.common import FormatOpt, output_format
from rostools.cli.declare import command
from rostools.cli.output import Format, emit
from rostools.errors import QuietExit, one_line

if TYPE_CHECKING:
    pass


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
