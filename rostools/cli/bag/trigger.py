"""``rostools bag trigger``: ask a snapshot recorder for a file, and wait until it is complete.

The client of ``trigger_snapshot`` (rosbag_snapshot's service): ``rostools bag snapshot``, or
rosbag_snapshot itself, writes the file and answers when it is.
"""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rostools.cli.common import FormatOpt, node_session, output_format
from rostools.cli.declare import command
from rostools.cli.output import Format, emit
from rostools.cli.units import parse_duration
from rostools.errors import DataLossError, UsageError, one_line

if TYPE_CHECKING:
    import asyncio
    from collections.abc import Callable

    from rostools.bag.live.snapshot_srv import SnapshotRequest
    from rostools.node.node import LiveNode


@command()
def trigger(
    ctx: typer.Context,
    node: Annotated[
        str | None,
        typer.Argument(help="The snapshot node (default: trigger_snapshot in this namespace)."),
    ] = None,
    output_name_: Annotated[
        str | None,
        typer.Option("--output-name", "-O", help="The file's name in the recorder's folder."),
    ] = None,
    topics: Annotated[
        list[str] | None, typer.Option("--topics", help="Only these topics (repeatable, or a,b).")
    ] = None,
    before: Annotated[
        str | None, typer.Option("--before", help="From the buffer: 20, 20s, 1m (default all).")
    ] = None,
    after: Annotated[
        str | None, typer.Option("--after", help="Then live messages for this long: 10s.")
    ] = None,
    continue_: Annotated[
        bool,
        typer.Option("--continue", help="Go on writing live messages until Ctrl-C here."),
    ] = False,
    timeout: Annotated[
        str | None, typer.Option("--timeout", help="Give up waiting for the file (exit 5).")
    ] = None,
    fmt: FormatOpt = None,
) -> None:
    """Ask a snapshot recorder for a file; print its name once it is complete.

    The recorder is 'rostools bag snapshot' or rosbag_snapshot. With --format json: the file's
    name, message count, time span and the messages of the window lost. Exit 6 if some were.
    """
    if continue_ and after:
        raise UsageError("--continue writes until stopped; it takes no --after")
    limit = parse_duration(timeout, "--timeout") if timeout else None
    spans = (
        parse_duration(before, "--before") if before else None,
        parse_duration(after, "--after") if after else 0.0,
    )
    chosen = [t for item in topics or [] for t in item.split(",") if t]
    out = output_format(ctx, fmt)

    async def main(n: LiveNode, stop: asyncio.Event) -> dict[str, Any]:
        import asyncio

        from rostools.bag.live.snapshot_client import request_snapshot

        say = _say_continuing if continue_ and out is Format.text else None

        async def trigger() -> dict[str, Any]:
            request = await _window(n, output_name_ or "", chosen, spans, continue_)
            return await request_snapshot(n, node, request, stop, say)

        try:  # every wait is within --timeout: the master's answers too
            return await asyncio.wait_for(trigger(), limit)
        except asyncio.TimeoutError:
            from rostools.errors import TimeoutExpired

            raise TimeoutExpired(f"the snapshot was not complete within {timeout}") from None

    summary = node_session(ctx, main, "rostools_trigger")
    emit(out, summary, lambda d: one_line(d["name"]))
    if summary.get("error"):
        raise DataLossError(f"{summary['name']}: {summary['error']}")
    if summary.get("lost"):
        from rostools.cli.bag.snapview import lost_text

        raise DataLossError(f"{summary['name']}: {lost_text(summary)}")


async def _window(
    node: LiveNode, name: str, topics: list[str], spans: tuple[float | None, float], forever: bool
) -> Callable[[], SnapshotRequest]:
    """The request, its window in ROS time as this node sees it (``/clock`` under sim time).

    The clock is started here (under sim time it waits for ``/clock``); the window is read
    from it when the request is made, just before the call.
    """
    from rostools.bag.live.snapshot_srv import SnapshotRequest, window
    from rostools.node.clock import RosClock

    clock = RosClock()
    await clock.start(node)

    def request() -> SnapshotRequest:
        start, stop = window(clock.now(), *spans, forever)
        return SnapshotRequest(name, topics, start, stop)

    return request


def _say_continuing(name: str) -> None:
    sys.stderr.write(one_line(f"writing {name} until Ctrl-C") + "\n")
