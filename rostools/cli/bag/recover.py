"""``rostools bag recover``: rebuild an unindexed or cut-short bag from its records."""

from __future__ import annotations

from typing import TYPE_CHECKING

import typer

from rostools.cli.bag.options import (
    BagArg,
    DstOpt,
    ForceOpt,
)
from rostools.cli.bag.shared import recover_report, recovered_name
from rostools.cli.common import FormatOpt, NoCrcCheckOpt, output_format
from rostools.cli.declare import command

if TYPE_CHECKING:
    pass


@command()
def recover(
    ctx: typer.Context,
    src: BagArg,
    dst: DstOpt = None,
    force: ForceOpt = False,
    no_crc_check: NoCrcCheckOpt = False,
    fmt: FormatOpt = None,
) -> None:
    """Rebuild an unindexed or cut-short bag or MCAP; exit 6 if anything was lost."""
    from rostools.bag.tools.recover import recover as run_recover

    dst = dst or recovered_name(src)
    report = run_recover(src, dst, overwrite=force, check_crcs=not no_crc_check)
    recover_report(output_format(ctx, fmt), report)
    report.raise_if_lost()
