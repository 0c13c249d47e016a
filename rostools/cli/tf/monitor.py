"""``rostools tf monitor``: delay and rate per frame and per broadcaster, as ``tf_monitor``.

Live, a report every second, each over everything heard so far (the last 1000 values of each
list, as tf_monitor's); from a bag, one report over the recording, its delays taken against
the record times. With SOURCE and TARGET, the frames of the chain between them only, and the
chain's net delay: the time less the newest time at which the whole chain is known, sampled
every 10 ms (live) or at each message (bag).
"""

from __future__ import annotations

import time
from functools import partial
from typing import TYPE_CHECKING, Annotated

import typer

from rostools.cli import output
from rostools.cli.common import FormatOpt, node_session, output_format
from rostools.cli.declare import command
from rostools.cli.output import Format
from rostools.cli.tf.options import BagOpt, CountOpt
from rostools.errors import NotFoundError, UsageError, one_line
from rostools.tf.edges import shown_broadcaster
from rostools.tf.monitor import Monitor
from rostools.tf.records import strip_slash

if TYPE_CHECKING:
    import asyncio
    from pathlib import Path

    from rostools.node.node import LiveNode

#: Seconds between live reports.
PERIOD = 1.0
#: Seconds between samples of a chain's net delay (tf_monitor's 10 ms).
SAMPLE = 0.01


def report_text(data: dict[str, object], source: str | None, target: str | None) -> str:
    """A report as tf_monitor prints it (numbers as C++ streams print them, 6 digits)."""
    lines = []
    if source is None:
        lines.append("RESULTS: for all Frames")
    else:
        lines.append(f"RESULTS: for {one_line(source)} to {one_line(str(target))}")
        chain = data.get("chain")
        if chain is None:
            lines.append("Chain is: not known yet")
        else:
            assert isinstance(chain, list)
            net = data["net_delay"]
            assert isinstance(net, dict)
            lines.append("Chain is: " + " -> ".join(map(one_line, chain)))
            lines.append(f"Net delay     avg = {net['average']:g}: max = {net['max']:g}")
    lines += ["", "Frames:"]
    for f in data["frames"]:  # type: ignore[attr-defined]
        lines.append(
            f"Frame: {one_line(f['frame'])} published by "
            f"{one_line(shown_broadcaster(f['broadcaster']))}"
            f" Average Delay: {f['average_delay']:g} Max Delay: {f['max_delay']:g}"
        )
    lines += ["", "All Broadcasters:"]
    for b in data["broadcasters"]:  # type: ignore[attr-defined]
        name = one_line(shown_broadcaster(b["broadcaster"])) + (" (static)" if b["static"] else "")
        rate = "" if b["rate"] is None else f" {b['rate']:g} Hz,"
        lines.append(
            f"Node: {name}{rate} Average Delay: {b['average_delay']:g}"
            f" Max Delay: {b['max_delay']:g}"
        )
    return "\n".join(lines) + "\n"


@command()
def monitor(
    ctx: typer.Context,
    source: Annotated[
        str | None, typer.Argument(help="With TARGET: only the chain between them.")
    ] = None,
    target: Annotated[str | None, typer.Argument(help="The chain's other end.")] = None,
    bag: BagOpt = None,
    count: CountOpt = None,
    fmt: FormatOpt = None,
) -> None:
    """Delay and rate per frame and per broadcaster (tf_monitor); live, a report a second."""
    if (source is None) != (target is None):
        raise UsageError("tf monitor takes no frame or two: SOURCE TARGET")
    if count is not None and count < 1:
        raise UsageError("-n must be at least 1")
    a = strip_slash(source) if source is not None else None
    b = strip_slash(target) if target is not None else None
    chosen = output_format(ctx, fmt)
    if bag is not None:
        mon = _from_bag(bag, a, b)
        _print(mon, a, b, chosen)
        return
    node_session(ctx, partial(_live, a, b, count, chosen), "tf_monitor", chosen)


def _print(mon: Monitor, a: str | None, b: str | None, fmt: Format) -> None:
    """One report."""
    chain = mon.chain(a, b) if a is not None and b is not None else None
    data = mon.report(chain)
    if a is not None and chain is None:
        data = {**data, "chain": None}
    output.write(fmt, data, lambda d: report_text(d, a, b))


def _from_bag(path: Path, a: str | None, b: str | None) -> Monitor:
    """The monitor fed every TF message of the bag, at its record time."""
    from rostools.cli.tf.shared import open_feed

    mon = Monitor()
    with open_feed(path) as feed:
        for batch in feed.batches():
            mon.add(batch.received_ns, batch.broadcaster, batch.static, batch.transforms)
            if a is not None and b is not None and (chain := mon.chain(a, b)) is not None:
                mon.sample_chain(chain, batch.received_ns)
    if not mon.edges.by_child and not mon.edges.refused:
        raise NotFoundError(f"no tf data in {path}")
    return mon


async def _live(
    a: str | None,
    b: str | None,
    count: int | None,
    fmt: Format,
    node: LiveNode,
    stop: asyncio.Event,
) -> None:
    """Report every ``PERIOD`` s until stopped, or ``count`` reports."""
    from rostools.cli.tf.shared import LiveFeed
    from rostools.node.session import first

    mon = Monitor()
    feed = LiveFeed(node, lambda x: mon.add(x.received_ns, x.broadcaster, x.static, x.transforms))
    await feed.start()
    reports = 0
    next_report = time.monotonic() + PERIOD
    try:
        while count is None or reports < count:
            wait = SAMPLE if a is not None else max(next_report - time.monotonic(), 0.0)
            if await first(stop.wait(), timeout=wait) == 0:
                return
            if a is not None and b is not None and (chain := mon.chain(a, b)) is not None:
                mon.sample_chain(chain, time.time_ns())
            if time.monotonic() >= next_report:
                if reports and fmt is Format.text:
                    output.put("\n")  # reports apart, as tf_monitor's
                _print(mon, a, b, fmt)
                reports += 1
                next_report += PERIOD
    finally:
        await feed.close()
