"""``rostools bag reindex``: rebuild bags in place, keeping each original as x.orig.bag."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from rostools.cli.bag.options import (
    OutputDirOpt,
)
from rostools.cli.bag.shared import recover_report
from rostools.cli.common import FormatOpt, NoCrcCheckOpt, output_format
from rostools.cli.declare import command

if TYPE_CHECKING:
    pass


@command()
def reindex(
    ctx: typer.Context,
    bags: Annotated[list[Path], typer.Argument(help="Bags to reindex.")],
    output_dir: OutputDirOpt = None,
    force: Annotated[
        bool, typer.Option("--force", "-f", help="Replace an existing x.orig.bag backup.")
    ] = False,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="No report line.")] = False,
    no_crc_check: NoCrcCheckOpt = False,
    fmt: FormatOpt = None,
) -> None:
    """Reindex bags in place, keeping each original as x.orig.bag (rosbag reindex).

    Each bag is rebuilt as 'recover' does, or written into --output-dir; exit 6 if
    anything was lost.
    """
    from rostools.bag.tools.recover import recover as run_recover
    from rostools.cli.bag.inplace import each_in_place, swap

    fmt = output_format(ctx, fmt)

    def one(path: Path, dst: Path, keep: Path | None) -> list[str]:
        report = run_recover(path, dst, overwrite=True, check_crcs=not no_crc_check)
        swap(path, dst, keep)
        recover_report(fmt, dataclasses.replace(report, output=keep or dst), quiet)
        return [f"{path}: {what}" for what in report.lost]

    each_in_place(bags, output_dir, force, quiet, "reindex", one)
