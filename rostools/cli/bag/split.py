"""``rostools bag split``: a bag cut into parts by size, duration or count.

It shares the options of ``filter`` and ``convert`` (``options.py``).
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rostools.bag.formats.model import counted
from rostools.cli import output
from rostools.cli.bag.options import (
    CopyOutput,
)
from rostools.cli.bag.shared import Progress, say_notes
from rostools.cli.common import FormatOpt, output_format
from rostools.cli.declare import command
from rostools.cli.output import Format, emit
from rostools.errors import UsageError

if TYPE_CHECKING:
    from rostools.bag.tools.split import SplitReport


def _split_report(fmt: Format, report: SplitReport) -> None:
    data: dict[str, Any] = {
        "source": str(report.source),
        "parts": [
            {"path": str(p.path), "messages": p.messages, "start": p.start_ns, "end": p.end_ns}
            for p in report.parts
        ],
    }
    if report.notes or report.lost:
        data.update(notes=list(report.notes), lost=list(report.lost))
    if fmt is Format.text:
        for p in report.parts:
            sys.stderr.write(f"wrote {counted(p.messages, 'message')} to {p.path}\n")
        say_notes(report.notes)
    elif fmt is Format.json:
        output.write(fmt, data)  # the last record of the NDJSON progress stream
    else:
        emit(fmt, data)


@command()
def split(
    ctx: typer.Context,
    src: Annotated[Path, typer.Argument(help="The .bag or .mcap file to split.")],
    out: Annotated[
        Path | None,
        typer.Option(
            "--output", "-o", help="Name the parts after this (NAME_0.bag, ...); default: SRC."
        ),
    ] = None,
    duration: Annotated[
        str | None, typer.Option("--duration", help="Parts of 30, 30s, 5m or 2h of bag time.")
    ] = None,
    size: Annotated[int | None, typer.Option("--size", help="Parts of about this many MB.")] = None,
    count: Annotated[int | None, typer.Option("--count", help="Parts of N messages.")] = None,
    at: Annotated[
        str | None,
        typer.Option("--at", help="Cut at these times, in seconds from the start: T1,T2,..."),
    ] = None,
    repeat_latched: Annotated[
        bool,
        typer.Option("--repeat-latched", help="Start each part with the latched messages so far."),
    ] = False,
    how: CopyOutput = CopyOutput(),  # noqa: B008 - a record of options, never changed
    fmt: FormatOpt = None,
) -> None:
    """Split a bag into parts by duration, size, message count or times (record --split's names)."""
    from rostools.bag.formats.access import bag_info
    from rostools.bag.tools.split import Cut, split as run_split
    from rostools.cli.units import parse_duration

    times: list[int] = []
    if at is not None:
        begin = bag_info(src).start_ns or 0
        try:
            times = [begin + round(float(x) * 1e9) for x in at.split(",") if x.strip()]
        except ValueError:
            raise UsageError(
                f"--at takes seconds from the start, e.g. 10,20.5; not {at!r}"
            ) from None
    cut = Cut(
        duration_ns=round(parse_duration(duration, "--duration") * 1e9) if duration else None,
        size=size * 1_000_000 if size is not None else None,
        count=count,
        at_ns=times,
    )
    chosen = output_format(ctx, fmt)
    progress = Progress("split", chosen, how.quiet)
    try:
        report = run_split(
            src, out or src, cut, how.copy(), repeat_latched=repeat_latched, progress=progress
        )
    finally:
        progress.done()
    _split_report(chosen, report)
    report.raise_if_lost()
