"""``rostools topic delay``: now minus each message's header.stamp, reading only the stamp."""

from __future__ import annotations

import struct
from typing import TYPE_CHECKING, Annotated

import typer

from rostools.cli import output
from rostools.cli.common import FormatOpt, output_format
from rostools.cli.declare import command
from rostools.cli.topic.live import StrictOpt, TimeoutOpt
from rostools.cli.topic.meters import Meter, NodelayOpt, WindowOpt, run_meter
from rostools.errors import NotFoundError
from rostools.names import script_resolve

if TYPE_CHECKING:
    from rostools.node.connection import Frame, InboundConnection


_STAMP = struct.Struct("<II")


@command()
def delay(
    ctx: typer.Context,
    topic: Annotated[str, typer.Argument(help="A topic whose messages start with a Header.")],
    window: WindowOpt = None,
    tcp_nodelay: NodelayOpt = False,
    timeout: TimeoutOpt = None,
    strict: StrictOpt = False,
    fmt: FormatOpt = None,
) -> None:
    """Now minus header.stamp of each message (rostopic delay); reads only the stamp."""
    from rostools.msgs import learnt
    from rostools.msgs.codec import DecodeError
    from rostools.msgs.store import TypeStore
    from rostools.rates import DEFAULT_WINDOW, DelayMeter, format_delay

    fmt = output_format(ctx, fmt)
    name = script_resolve(topic, "rostopic")
    meter = DelayMeter(window or DEFAULT_WINDOW)
    runner = Meter([name], timeout, fmt, tcp_nodelay, strict=strict)
    base = TypeStore.default()
    checked: dict[str, bool] = {}

    def sink(t: str, frames: list[Frame], conn: InboundConnection, now: float) -> None:
        header = conn.header or {}
        kind = header.get("type", "")
        if kind not in checked:
            md5, definition = header.get("md5sum", ""), header.get("message_definition", "")
            checked[kind] = learnt.codec(base, kind, md5, definition).store.msg(kind).has_header
        if not checked[kind]:
            raise NotFoundError(f"{t} carries {kind}, which has no Header to take a stamp from")
        ref = runner.clock.now() / 1e9  # ROS time: /clock under sim time, else the wall clock
        delays = []
        for data in frames:
            if len(data) < 4 + _STAMP.size:  # seq, then the stamp
                why = f"a message on {t} is {len(data)} bytes, too short for a {kind} Header"
                runner.skip(DecodeError(why), conn, data)
                continue
            secs, nsecs = _STAMP.unpack_from(data, 4)
            delays.append(ref - (secs + nsecs * 1e-9))
        meter.add(delays)

    def report(last: bool = False) -> None:
        stats = meter.report(last)
        if stats is None:
            return
        row = {"topic": name, "delay": stats.value, "min": stats.min, "max": stats.max,
               "std_dev": stats.std_dev, "window": stats.window}  # fmt: skip
        output.write(fmt, row, lambda _: format_delay(stats))

    run_meter(ctx, runner, sink, report)
