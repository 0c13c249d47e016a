"""``rostools bag info``: a summary of bags from their index alone (rosbag info)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated

import typer

from rostools.cli import output
from rostools.cli.bag.shared import check_read
from rostools.cli.common import FormatOpt, NoCrcCheckOpt, output_format
from rostools.cli.declare import command
from rostools.cli.output import Format, emit

if TYPE_CHECKING:
    pass


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
