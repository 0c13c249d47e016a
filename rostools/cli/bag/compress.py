"""``rostools bag compress|decompress``: rewrite bags in place with other chunks, as rosbag does."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rostools.cli.bag.inplace import copy_in_place
from rostools.cli.bag.options import (
    ForceOpt,
    OutputDirOpt,
    QuietOpt,
)
from rostools.cli.common import FormatOpt, NoCrcCheckOpt, output_format
from rostools.cli.declare import command
from rostools.errors import UsageError

if TYPE_CHECKING:
    from rostools.bag.tools.ops import CopyReport


@command()
def compress(
    ctx: typer.Context,
    bags: Annotated[list[Path], typer.Argument(help="Bags to compress.")],
    bz2: Annotated[
        bool, typer.Option("--bz2", "-j", help="bz2 chunks (the default for .bag).")
    ] = False,
    lz4: Annotated[bool, typer.Option("--lz4", help="lz4 chunks.")] = False,
    output_dir: OutputDirOpt = None,
    force: ForceOpt = False,
    quiet: QuietOpt = False,
    no_crc_check: NoCrcCheckOpt = False,
    fmt: FormatOpt = None,
) -> None:
    """Compress bags in place, keeping the original as x.orig.bag (rosbag compress)."""
    from rostools.bag.tools.ops import compress as run_compress
    from rostools.bag.tools.options import CopyOptions

    if bz2 and lz4:
        raise UsageError("--bz2 and --lz4 cannot be combined")
    # lz4, or the format's default (bz2 for .bag, zstd for MCAP)
    options = CopyOptions(compression="lz4" if lz4 else None, overwrite=True,
                          check_crcs=not no_crc_check)  # fmt: skip

    def run(src: Path, dst: Path, progress: Any) -> CopyReport:
        return run_compress(src, dst, options, progress=progress)

    copy_in_place(bags, output_dir, force, output_format(ctx, fmt), quiet, "compress", run)


@command()
def decompress(
    ctx: typer.Context,
    bags: Annotated[list[Path], typer.Argument(help="Bags to decompress.")],
    output_dir: OutputDirOpt = None,
    force: ForceOpt = False,
    quiet: QuietOpt = False,
    no_crc_check: NoCrcCheckOpt = False,
    fmt: FormatOpt = None,
) -> None:
    """Decompress bags in place, keeping the original as x.orig.bag (rosbag decompress)."""
    from rostools.bag.tools.ops import decompress as run_decompress
    from rostools.bag.tools.options import CopyOptions

    options = CopyOptions(overwrite=True, check_crcs=not no_crc_check)

    def run(src: Path, dst: Path, progress: Any) -> CopyReport:
        return run_decompress(src, dst, options, progress=progress)

    copy_in_place(bags, output_dir, force, output_format(ctx, fmt), quiet, "decompress", run)
