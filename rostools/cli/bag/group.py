"""The ``rostools bag`` group, to which its modules add their commands."""

from __future__ import annotations

import typer

app = typer.Typer(
    name="bag",
    help=(
        "Bags (.bag and MCAP): record, play, info, filter, convert, recover, reindex, "
        "compress, decompress, merge, split, cat, plot, doctor, attachments, metadata."
    ),
    no_args_is_help=True,
    add_completion=False,
)
