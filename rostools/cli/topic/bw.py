"""``rostools topic bw``: the bandwidth a topic uses, from the size of each raw frame."""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated

import typer

from rostools.cli import output
from rostools.cli.common import FormatOpt, output_format
from rostools.cli.declare import command
from rostools.cli.topic.live import TimeoutOpt
from rostools.cli.topic.meters import COALESCE, Meter, WindowOpt, run_meter
from rostools.names import script_resolve

if TYPE_CHECKING:
    from rostools.node.connection import Frame, InboundConnection


@command()
def bw(
    ctx: typer.Context,
    topic: Annotated[str, typer.Argument(help="A topic.")],
    window: WindowOpt = None,
    timeout: TimeoutOpt = None,
    fmt: FormatOpt = None,
) -> None:
    """The bandwidth a topic uses (rostopic bw), from the size of each raw frame."""
    from rostools.rates import BandwidthMeter, format_bandwidth

    fmt = output_format(ctx, fmt)
    name = script_resolve(topic, "rostopic")
    meter = BandwidthMeter(window or 100)
    runner = Meter([name], timeout, fmt, coalesce=COALESCE)

    def sink(t: str, frames: list[Frame], conn: InboundConnection, now: float) -> None:
        meter.add([len(f) for f in frames], now)

    def report(last: bool = False) -> None:
        stats = meter.report(runner.now())
        if stats is None:
            return
        row = {"topic": name, "bytes_per_s": stats.rate, "mean": stats.mean,
               "min": stats.min, "max": stats.max, "window": stats.window}  # fmt: skip
        output.write(fmt, row, lambda _: format_bandwidth(stats))

    run_meter(ctx, runner, sink, report)
