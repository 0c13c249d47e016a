"""``rostools bag convert``: .bag to MCAP or back, losslessly; or ROS 1 bags into rosbag2."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from rostools.cli.bag.options import CopyOutput, DistroOpt, OutArg, TypesOpt
from rostools.cli.bag.shared import copy_command
from rostools.cli.common import FormatOpt, output_format
from rostools.cli.declare import command
from rostools.errors import UsageError

if TYPE_CHECKING:
    from rostools.bag.tools.ops import CopyReport
    from rostools.bag.tools.options import Progress

ToOpt = Annotated[
    str,
    typer.Option(
        "--to",
        help="ros1: .bag <-> MCAP by the output's name; ros2: a rosbag2 folder (OUT.mcap: "
        "the MCAP alone) that ros2 bag plays.",
    ),
]
ExcludeOpt = Annotated[
    list[str] | None,
    typer.Option("--exclude", "-x", help="--to ros2: leave out this topic (repeatable)."),
]


@command()
def convert(
    ctx: typer.Context,
    src: Annotated[list[Path], typer.Argument(help="The .bag or .mcap file(s) to convert.")],
    dst: OutArg,
    to: ToOpt = "ros1",
    distro: DistroOpt = None,
    types: TypesOpt = None,
    exclude: ExcludeOpt = None,
    chunk_size: Annotated[int | None, typer.Option("--chunksize", help="Chunk size in KB.")] = None,
    how: CopyOutput = CopyOutput(),  # noqa: B008 - a record of options, never changed
    fmt: FormatOpt = None,
) -> None:
    """Convert .bag to MCAP or back, losslessly; --to ros2: into rosbag2 for ros2 bag play."""
    if to not in ("ros1", "ros2"):
        raise UsageError(f"--to takes ros1 or ros2, not {to!r}")
    if to == "ros2":
        size = chunk_size * 1024 if chunk_size else None
        _to_ros2(ctx, src, dst, distro, types, exclude or [], size, how, fmt)
        return
    given = [n for n, v in (("--distro", distro), ("--types", types), ("-x", exclude)) if v]
    if given:
        raise UsageError(f"{given[0]} is for --to ros2")
    if len(src) != 1:
        raise UsageError("convert takes one input, or several with --to ros2")
    from rostools.bag.tools.ops import convert as run_convert

    options = how.copy(chunk_size=chunk_size * 1024 if chunk_size else None)
    copy_command(output_format(ctx, fmt), how.quiet, "convert", lambda progress: run_convert(
        src[0], dst, options, progress=progress
    ))  # fmt: skip


def _to_ros2(
    ctx: typer.Context,
    src: list[Path],
    dst: Path,
    distro: str | None,
    types: Path | None,
    exclude: list[str],
    chunk_size: int | None,
    how: CopyOutput,
    fmt: FormatOpt,
) -> None:
    """``--to ros2``: every input, in one time order, into one rosbag2."""
    from rostools.bag.formats.ros2types import DEFAULT_DISTRO
    from rostools.bag.tools.ros2convert import convert_to_ros2

    if how.rename or how.rename_type:
        raise UsageError("--rename and --rename-type are not for --to ros2 (use a --types file)")

    def run(progress: Progress) -> CopyReport:
        return convert_to_ros2(
            src, dst, distro=distro or DEFAULT_DISTRO, types=types, exclude=exclude,
            compression=how.compression or "zstd", chunk_size=chunk_size, overwrite=how.force,
            check_crcs=not how.no_crc_check, progress=progress,
        )  # fmt: skip

    copy_command(output_format(ctx, fmt), how.quiet, "convert", run)
