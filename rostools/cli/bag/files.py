"""``rostools bag info|filter|convert|recover|reindex|compress|decompress``: the file commands.

record and play live beside this module.
"""

from __future__ import annotations

import dataclasses
import sys
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rostools.bag.formats.model import counted
from rostools.cli import output
from rostools.cli.bag.options import (
    BagArg,
    CopyOutput,
    CopyWindow,
    DstOpt,
    ForceOpt,
    OutArg,
    OutputDirOpt,
    QuietOpt,
)
from rostools.cli.bag.shared import check_read, copy_command, recovered_name
from rostools.cli.common import FormatOpt, NoCrcCheckOpt, output_format
from rostools.cli.declare import command
from rostools.cli.output import Format, emit, render
from rostools.errors import UsageError, one_line

if TYPE_CHECKING:
    from rostools.bag.tools.ops import CopyReport
    from rostools.bag.tools.recover import RecoverReport


@command()
def info(
    ctx: typer.Context,
    bags: Annotated[list[str], typer.Argument(help="One or more .bag or .mcap files.")],
    freq: Annotated[bool, typer.Option("--freq", help="Median rate of each topic.")] = False,
    yaml_: Annotated[bool, typer.Option("--yaml", "-y", help="The same as -F yaml.")] = False,
    key: Annotated[
        str | None,
        typer.Option("--key", "-k", help="Only this key, e.g. duration or topics[0].messages."),
    ] = None,
    no_crc_check: NoCrcCheckOpt = False,
    fmt: FormatOpt = None,
) -> None:
    """Summarise bags from their index alone (rosbag info); exit 1 if unindexed, 6 if damaged."""
    from rostools.bag.formats.access import open_bag, topic_frequencies
    from rostools.cli.bag.infotext import (
        as_rosbag_reads,
        info_data,
        info_key,
        info_text,
        info_yaml,
        key_yaml,
    )

    fmt = Format.yaml if yaml_ and fmt is None else output_format(ctx, fmt)
    if key is not None and fmt is Format.text:
        fmt = Format.yaml  # a key is a path into the YAML document; rosbag demands -y for it
    results = []
    readers = []
    for name in bags:
        with open_bag(name, check_crcs=not no_crc_check) as reader:
            summary = reader.info()
            freqs = topic_frequencies(reader) if freq else None
        results.append((summary, freqs, name))
        readers.append(reader)
    if fmt is Format.text:
        output.put("\n---\n".join(info_text(*r) for r in results) + "\n")
    elif fmt is Format.yaml:  # rosbag's text, one document per bag
        data = [info_data(*r) for r in results]
        if key is None:
            docs = [info_yaml(d) + "\n" for d in data]
        else:
            docs = [key_yaml(info_key(as_rosbag_reads(d), key)) for d in data]
        output.put("---\n".join(docs))
    else:
        data = [info_data(*r) for r in results]
        if key is not None:
            data = [info_key(d, key) for d in data]
        emit(fmt, data[0] if len(data) == 1 else data)
    check_read(readers, "summarised " + ", ".join(bags), unindexed_fails=True)


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


@command()
def convert(
    ctx: typer.Context,
    src: BagArg,
    dst: OutArg,
    chunk_size: Annotated[int | None, typer.Option("--chunksize", help="Chunk size in KB.")] = None,
    how: CopyOutput = CopyOutput(),  # noqa: B008 - a record of options, never changed
    fmt: FormatOpt = None,
) -> None:
    """Convert .bag to MCAP or back, losslessly (renaming topics or types if asked)."""
    from rostools.bag.tools.ops import convert as run_convert

    options = how.copy(chunk_size=chunk_size * 1024 if chunk_size else None)
    copy_command(output_format(ctx, fmt), how.quiet, "convert", lambda progress: run_convert(
        src, dst, options, progress=progress
    ))  # fmt: skip


def _in_place(
    ctx: typer.Context,
    bags: list[Path],
    output_dir: Path | None,
    force: bool,
    fmt: Format | None,
    quiet: bool,
    label: str,
    run: Callable[[Path, Path, Any], CopyReport],
) -> None:
    """rosbag compress's way: write beside, keep the original as ``x.orig.bag`` (``inplace``).

    A damaged bag is rewritten with what reads (the original is kept all the same); exit 6
    at the end, naming what was left out.
    """
    from rostools.cli.bag.inplace import each_in_place, swap

    def one(path: Path, dst: Path, keep: Path | None) -> list[str]:
        def step(progress: Any) -> CopyReport:
            return dataclasses.replace(run(path, dst, progress), output=keep or dst)

        report = copy_command(
            output_format(ctx, fmt), quiet, label, step, check=False, say=not quiet
        )
        swap(path, dst, keep)
        return list(report.lost)

    each_in_place(bags, output_dir, force, quiet, label, one)


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

    _in_place(ctx, bags, output_dir, force, fmt, quiet, "compress", run)


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

    _in_place(ctx, bags, output_dir, force, fmt, quiet, "decompress", run)


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
    _recover_report(output_format(ctx, fmt), report)
    report.raise_if_lost()


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
        _recover_report(fmt, dataclasses.replace(report, output=keep or dst), quiet)
        return [f"{path}: {what}" for what in report.lost]

    each_in_place(bags, output_dir, force, quiet, "reindex", one)


def _recover_report(fmt: Format, report: RecoverReport, quiet: bool = False) -> None:
    if fmt is not Format.text:
        data = {
            "source": str(report.source), "output": str(report.output), "format": report.format,
            "was_indexed": report.was_indexed, "messages": report.messages,
            "connections": report.connections, "notes": list(report.notes),
            "lost": list(report.lost),
        }  # fmt: skip
        output.put(render(fmt, data) + "\n")
    elif not quiet:
        for note in report.notes:
            sys.stderr.write(f"note: {one_line(note)}\n")  # may quote the file's names
        sys.stderr.write(f"recovered {counted(report.messages, 'message')} into {report.output}\n")
