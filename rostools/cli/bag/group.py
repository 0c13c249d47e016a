"""The ``rostools bag`` group: its Typer app, with its commands in ``--help`` order."""

from __future__ import annotations

import typer

from rostools.cli.bag import cat, extras, files, play, plot, record, snapshot, workbench
from rostools.cli.register import add

app = typer.Typer(
    name="bag",
    help=(
        "Bags (.bag and MCAP): record, play, info, filter, convert, recover, reindex, "
        "compress, decompress, merge, split, cat, plot, snapshot, trigger, doctor, attachments, "
        "metadata."
    ),
    no_args_is_help=True,
    add_completion=False,
)
add(app, files.info, files.filter_, files.convert, files.compress, files.decompress)
add(app, files.recover, files.reindex, workbench.merge, workbench.split, cat.cat, plot.plot_cmd)
add(app, play.play, record.record, snapshot.snapshot, snapshot.trigger)
add(app, extras.attachments, extras.metadata, extras.doctor)
