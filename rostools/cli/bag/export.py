"""``rostools bag export``: bags into a dataset of Parquet, Arrow, CSV or NDJSON tables.

One table per topic (per definition, when it changes between the bags), one file per bag,
under ``OUT/topic=<key>/bag=<key>/``: ``bag/tables/layout.py`` says how names become keys.
"""

from __future__ import annotations

import enum
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rostools.bag.formats.model import counted, lost_data
from rostools.cli import output
from rostools.cli.bag.options import CopyWindow, QuietOpt
from rostools.cli.bag.shared import Progress
from rostools.cli.common import output_format
from rostools.cli.declare import command
from rostools.cli.output import Format, emit
from rostools.errors import RostoolsError, one_line

if TYPE_CHECKING:
    from rostools.bag.tables.export import ExportReport


class TableFormat(str, enum.Enum):
    """The file format of ``bag export``'s tables."""

    parquet = "parquet"
    arrow = "arrow"
    csv = "csv"
    ndjson = "ndjson"


@command()
def export(
    ctx: typer.Context,
    bags: Annotated[list[Path], typer.Argument(help="The .bag or .mcap files to export.")],
    out: Annotated[Path, typer.Option("--output", "-o", help="The dataset's directory (created).")],
    table_format: Annotated[
        TableFormat,
        typer.Option("--format", help="The tables' files: parquet, arrow (IPC), csv or ndjson."),
    ] = TableFormat.parquet,
    window: CopyWindow = CopyWindow(),  # noqa: B008 - a record of options, never changed
    flatten: Annotated[
        bool,
        typer.Option("--flatten", help="Dotted columns (header.stamp), not structs; csv always."),
    ] = False,
    jobs: Annotated[
        int | None,
        typer.Option("--jobs", "-j", min=1, help="Bags exported at once (default: every core)."),
    ] = None,
    force: Annotated[
        bool,
        typer.Option("--force", "-f", help="Replace an existing OUT that holds only an export."),
    ] = False,
    quiet: QuietOpt = False,
    fmt: Annotated[
        Format | None,
        typer.Option("-F", help="The summary's format: text, json or yaml.", show_default=False),
    ] = None,
) -> None:
    """Export bags as tables: one per topic, a dataset partitioned by topic and bag.

    --format is the tables' files; the summary's is -F (or the global --format).
    """
    from rostools.bag.tables.export import export as run_export

    fmt = output_format(ctx, fmt)
    lo, hi = window.bounds(bags)
    progress = Progress("export", fmt, quiet)
    try:
        report = run_export(
            bags, out, overwrite=force, jobs=jobs, progress=progress,
            topics=window.topics or None, fmt=table_format.value, start_ns=lo, end_ns=hi,
            flatten=flatten or table_format is TableFormat.csv,
        )  # fmt: skip
    finally:
        progress.done()
    _report(fmt, report)
    skipped = report.skipped
    if report.lost:
        raise lost_data(f"exported {counted(len(report.bags), 'bag')}", [*report.lost, *skipped])
    if skipped:
        raise _left_out(skipped)


def _left_out(skipped: dict[str, int]) -> RostoolsError:
    """The error for tables that could not be read: the first one's exit code, every line."""
    lines = list(skipped)
    error = RostoolsError(
        f"left out {counted(len(lines), 'table')} that could not be read (the rest is written): "
        + "; ".join(lines)
    )
    error.exit_code = skipped[lines[0]]
    return error


def summary(report: ExportReport) -> dict[str, Any]:
    """``bag export``'s summary as data: its tables, their rows and files, and the splits."""
    tables: dict[str, dict[str, Any]] = {}
    for task in report.plan.tasks:
        for table in task.tables:
            tables.setdefault(table.key, {
                "topic": table.topic, "type": report.plan.types.get(table.topic, ""),
                "md5sum": table.md5sum, "path": f"topic={table.key}", "rows": 0, "files": [],
            })  # fmt: skip
    for bag in report.bags:
        for written in bag.files:
            tables[written.key]["rows"] += written.rows
            tables[written.key]["files"].append(written.file)
    return {
        "output": str(report.out),
        "format": report.plan.format,
        "bags": len(report.bags),
        "tables": list(tables.values()),
        "rows": sum(f.rows for bag in report.bags for f in bag.files),
        "files": sum(len(bag.files) for bag in report.bags),
        "split": [
            {"topic": s.topic, "tables": [{"md5sum": m, "path": f"topic={k}"} for m, k in s.tables]}
            for s in report.plan.splits
        ],
        "lost": report.lost,
        "skipped": list(report.skipped),
    }


def _report(fmt: Format, report: ExportReport) -> None:
    data = summary(report)
    if fmt is Format.json:
        output.write(fmt, data)  # the last record of the NDJSON progress stream
        return
    if fmt is not Format.text:
        emit(fmt, data)
        return
    for split in report.plan.splits:
        keys = ", ".join(f"topic={k} ({m})" for m, k in split.tables)
        sys.stderr.write(
            f"note: {one_line(split.topic)} changes definition between the bags: "
            f"one table for each md5sum, {keys}\n"
        )
    tables = len(data["tables"])
    sys.stderr.write(
        f"wrote {data['rows']} rows of {tables} table{'s' * (tables != 1)} in "
        f"{counted(data['files'], 'file')} from {counted(data['bags'], 'bag')} to {report.out} "
        f"({report.plan.format})\n"
    )
