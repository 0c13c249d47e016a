"""``rostools bag metadata``: an MCAP file's metadata records (a ``.bag`` has none)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import typer

from rostools.cli.bag.options import BagArg
from rostools.cli.bag.shared import extras_of
from rostools.cli.common import FormatOpt, output_format
from rostools.cli.declare import command
from rostools.cli.output import Format, emit

if TYPE_CHECKING:
    pass


@command()
def metadata(ctx: typer.Context, bag: BagArg, fmt: FormatOpt = None) -> None:
    """An MCAP file's metadata records, as JSON (or YAML with -F yaml), in file order."""
    from rostools.bag.formats.mcap_format import Metadata

    records = [
        {"name": m.name, "metadata": dict(m.metadata)}
        for m in extras_of(bag)
        if isinstance(m, Metadata)
    ]
    chosen = output_format(ctx, fmt)
    emit(Format.json if chosen is Format.text else chosen, records)
