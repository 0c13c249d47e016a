"""The ``rostools bag`` group: its Typer app, with its commands in ``--help`` order."""

from __future__ import annotations

import typer

from rostools.cli.bag import (
    attachments,
    cat,
    compress,
    convert,
    doctor,
    export,
    filter,
    info,
    merge,
    metadata,
    play,
    plot,
    record,
    recover,
    reindex,
    snapshot,
    split,
    trigger,
)
from rostools.cli.register import add

app = typer.Typer(
    name="bag",
    help=(
        "Bags (.bag and MCAP): record, play, info, filter, convert, recover, reindex, "
        "compress, decompress, merge, split, cat, plot, snapshot, trigger, doctor, attachments, "
        "metadata, export."
    ),
    no_args_is_help=True,
    add_completion=False,
)
add(app, info.info, filter.filter_, convert.convert, compress.compress, compress.decompress)
add(app, recover.recover, reindex.reindex, merge.merge, split.split, cat.cat, plot.plot_cmd)
add(app, play.play, record.record, snapshot.snapshot, trigger.trigger)
add(app, attachments.attachments, metadata.metadata, doctor.doctor)
add(app, export.export)
