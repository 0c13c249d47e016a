"""``rostools bag plot``: fields of a bag's topics over the whole bag, in one streaming pass.

The same fields, sampling and drawing as ``topic plot``: each message gives up only the
numbers plotted (``msgs.sample``), the series keep at most ``series.MAX_POINTS`` samples
each (thinned by min and max beyond that), and the picture goes to the terminal, to an
image with ``-o plot.svg|png`` (the ``plot`` extra), or out as data with ``-F json|yaml``.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from rostools.bag.formats.model import counted
from rostools.cli import output
from rostools.cli.bag.options import EndOpt, StartOpt
from rostools.cli.bag.shared import check_read, time_window
from rostools.cli.common import FormatOpt, NoCrcCheckOpt, output_format
from rostools.cli.declare import command
from rostools.cli.output import Format
from rostools.errors import InvalidDataError, NotFoundError, one_line

if TYPE_CHECKING:
    from rostools.bag.formats.base import BagReader
    from rostools.msgs.expr import Expression
    from rostools.msgs.sample import Sampler
    from rostools.series import SeriesSet


@command("plot")
def plot_cmd(
    ctx: typer.Context,
    bag: Annotated[Path, typer.Argument(help="A .bag or .mcap file.")],
    fields: Annotated[
        list[str],
        typer.Argument(
            help="Topics with a field path to a number: /odom/pose/pose/position/x, "
            "/scan/ranges[0:5]."
        ),
    ],
    start: StartOpt = None,
    end: EndOpt = None,
    stamp: Annotated[
        bool, typer.Option("--stamp", help="x is each message's header.stamp, not bag time.")
    ] = False,
    filter_expr: Annotated[
        str | None,
        typer.Option(
            "--filter", help="Python expression over topic, m and t; plot only where it is true."
        ),
    ] = None,
    out: Annotated[
        Path | None,
        typer.Option("--output", "-o", help="Draw into an image: .png, .svg or .pdf."),
    ] = None,
    no_crc_check: NoCrcCheckOpt = False,
    fmt: FormatOpt = None,
) -> None:
    """Plot fields of a bag's topics in the terminal or into an image (one pass)."""
    from rostools.bag.formats.access import open_bag, require_ros1
    from rostools.cli import plotting
    from rostools.series import SeriesSet

    fmt = output_format(ctx, fmt)
    if out is not None:
        plotting.check_image_target(out, "bag plot")  # before the bag is read
    keep = None
    if filter_expr:
        from rostools.msgs.expr import compile_expression

        keep = compile_expression(filter_expr)
    plot = SeriesSet()
    with open_bag(bag, check_crcs=not no_crc_check) as reader:
        paths = _topics(reader, fields, plot)
        require_ros1(reader, "bag plot", list(paths))
        samplers = _samplers(reader, paths, plot, stamp, keep)
        lo, hi = time_window([bag], start, end)
        count = _read(reader, samplers, lo, hi)
        begin = lo if lo is not None else (reader.info().start_ns or 0)
    _draw(plot, bag, fields, fmt, out, stamp, begin, count)
    check_read([reader], f"plotted {counted(count, 'message', grouped=True)}")


def _draw(
    plot: SeriesSet,
    bag: Path,
    fields: list[str],
    fmt: Format,
    out: Path | None,
    stamp: bool,
    begin: int,
    count: int,
) -> None:
    """The picture (terminal or image) or the samples as data."""
    from rostools.cli import plotting

    kind = "stamp" if stamp else "bag"
    held = plot.bounds()
    origin = held[0] if stamp and held else begin / 1e9
    if count == 0:
        sys.stderr.write(f"WARNING: no messages of {', '.join(fields)} to plot in {bag}\n")
    if fmt is not Format.text:
        plotting.emit_records(fmt, plot, kind)
        return
    xlabel = plotting.axis_label(kind, origin, with_date=True)
    if out is not None:
        plotting.write_image(
            plot, out, origin=origin, title=bag.name, xlabel=xlabel, command="bag plot"
        )
        sys.stderr.write(f"wrote {one_line(out)}: {_status(count, plot)}\n")
        return
    picture = plotting.frame(
        plot, origin=origin, title=bag.name, xlabel=xlabel, color=plotting.use_color(),
        status=_status(count, plot),
    )  # fmt: skip
    output.put(picture)


def _topics(reader: BagReader, fields: list[str], plot: SeriesSet) -> dict[str, list[str]]:
    """The field paths asked for, by the bag topic each starts with; their series declared."""
    from rostools.cli.settings import type_store
    from rostools.msgs.sample import Labels
    from rostools.msgs.topicpath import split_field
    from rostools.names import script_resolve

    store = type_store(None)
    types = {c.topic: c.type for c in reader.connections}
    paths: dict[str, list[str]] = {}
    for field in fields:
        name = script_resolve(field, "rostopic", field_path=True)
        ref = split_field(name, types, store)
        if ref is None:
            raise NotFoundError(
                f"topic {name} is not in {reader.path}",
                hint="its topics are: " + ", ".join(sorted(types)),
            )
        paths.setdefault(ref.topic, []).append(ref.field)
        plot.declare(Labels(ref.topic, ref.field).known())
    return paths


def _samplers(
    reader: BagReader,
    paths: dict[str, list[str]],
    plot: SeriesSet,
    stamp: bool,
    keep: Expression | None,
) -> dict[int, Sampler]:
    """A sampler per connection of the topics named, each checked before anything is read."""
    from rostools.cli.settings import type_store
    from rostools.msgs import learnt
    from rostools.msgs.sample import Sampler

    store = type_store(None)
    found: dict[int, Sampler] = {}
    for conn in reader.connections:
        if conn.topic in paths:
            own = learnt.codec(store, conn.type, conn.md5sum, conn.definition).store
            topic = conn.topic
            found[conn.id] = Sampler(own, conn.type, topic, paths[topic], plot.sink, stamp, keep)
    return found


def _read(reader: BagReader, samplers: dict[int, Sampler], lo: int | None, hi: int | None) -> int:
    """Sample every message of the connections in ``samplers`` from ``lo`` to ``hi``."""
    count = 0
    topics = sorted({s.topic for s in samplers.values()})
    for conn, t_ns, data in reader.messages(topics=topics, start=lo, end=hi):
        sampler = samplers.get(conn.id)
        if sampler is None:
            continue
        try:
            count += sampler.feed((data,), t_ns / 1e9)
        except InvalidDataError as err:  # a message that does not decode: say where
            raise InvalidDataError(f"{reader.path}: message at {t_ns / 1e9:.9f} s: {err}") from err
    return count


def _status(count: int, plot: SeriesSet) -> str:
    held = plot.bounds()
    span = f" over {held[1] - held[0]:,.1f} s" if held else ""
    thinned = [label for label, s in plot.series.items() if s.thinned]
    note = f"; thinned (min and max kept): {', '.join(thinned)}" if thinned else ""
    return f"{counted(count, 'message', grouped=True)}{span}{note}"
