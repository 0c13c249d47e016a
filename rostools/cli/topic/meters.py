"""What ``topic hz``, ``bw`` and ``delay`` share: the meter that subscribes, feeds and reports.

The meters never decode what they only count.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rostools.cli import output
from rostools.cli.common import node_session
from rostools.cli.output import Format
from rostools.cli.topic.live import Undecodable, wait_for_topic
from rostools.errors import TimeoutExpired, UsageError, one_line

if TYPE_CHECKING:
    import asyncio

    from rostools.msgs.codec import DecodeError
    from rostools.msgs.store import TypeStore
    from rostools.node.connection import Frame, InboundConnection
    from rostools.node.node import LiveNode

WindowOpt = Annotated[int | None, typer.Option("--window", "-w", help="Messages to average over.")]
HzWindowOpt = Annotated[
    int | None,
    typer.Option(
        "--window", "-w", help="Messages to average over [default: 50,000, and at least 5 s]."
    ),
]
NodelayOpt = Annotated[
    bool, typer.Option("--tcpnodelay", help="Ask publishers for TCP_NODELAY (rostopic's flag).")
]
REPORT_PERIOD = 1.0
#: How long hz and bw let small reads gather: at most ~1,000 wake-ups a second at any rate,
#: where one per message would cost more CPU than the counting itself.
COALESCE = 0.001


class Meter:
    """Resolves topics, subscribes, feeds a per-topic sink, reports every second.

    Under ``/use_sim_time`` the sink's times are ROS time from ``/clock``, as rostopic's, and
    messages that come before the first ``/clock`` are not counted; ``wall_time`` keeps the
    wall clock. A sink that decodes hands what does not decode to ``skip``.
    """

    def __init__(
        self,
        topics: list[str],
        timeout: float | None,
        fmt: Format,
        tcp_nodelay: bool = False,
        wall_time: bool = False,
        coalesce: float = 0.0,
        strict: bool = False,
    ) -> None:
        from rostools.node.clock import RosClock

        self.topics = topics
        self.timeout = timeout
        self.fmt = fmt
        self.tcp_nodelay = tcp_nodelay
        self.wall_time = wall_time
        self.coalesce = coalesce
        self.clock = RosClock()
        self.received = 0
        #: Topics subscribed so far: reports start with the first, as rostopic's.
        self.subscribed = 0
        self.error: BaseException | None = None
        self.strict = strict
        self.undecodable: Undecodable | None = None

    def skip(self, err: DecodeError, conn: InboundConnection, data: Frame) -> None:
        """A message that does not decode: skipped and said, or the end with ``--strict``."""
        assert self.undecodable is not None, "run() first"
        self.undecodable.skip(err, conn, data)

    def now(self) -> float:
        """Seconds on the meter's clock: ROS time under sim time, else monotonic."""
        return self.clock.now() / 1e9 if self.clock.sim else time.monotonic()

    async def run(
        self,
        node: LiveNode,
        stop: asyncio.Event,
        sink: Callable[[str, list[Frame], InboundConnection, float], None],
        report: Callable[[bool], None],
    ) -> str:
        """Subscribe to every topic and report until stopped or timed out."""
        from rostools.msgs.store import TypeStore

        deadline = time.monotonic() + self.timeout if self.timeout is not None else None
        store = TypeStore.default()
        self.undecodable = Undecodable(node, self.strict)
        try:
            return await self._run(node, stop, sink, report, store, deadline)
        finally:
            self.undecodable.report()

    async def _run(
        self,
        node: LiveNode,
        stop: asyncio.Event,
        sink: Callable[[str, list[Frame], InboundConnection, float], None],
        report: Callable[[bool], None],
        store: TypeStore,
        deadline: float | None,
    ) -> str:
        import asyncio

        if not self.wall_time:
            await self.clock.start(node)
        # each topic is subscribed once it appears: one not published yet holds none of the
        # others back (rostopic waits for each in turn, and reports nothing meanwhile)
        waits = [
            asyncio.ensure_future(self._attach(node, topic, stop, sink, store, deadline))
            for topic in self.topics
        ]

        def failed(task: asyncio.Future[None]) -> None:
            if not task.cancelled() and task.exception() is not None:
                stop.set()  # a failed wait (a field path, the master) ends the command now

        for task in waits:
            task.add_done_callback(failed)
        try:
            return await self._report(stop, report, deadline, waits)
        finally:
            for task in waits:
                task.cancel()
            await asyncio.gather(*waits, return_exceptions=True)

    async def _attach(
        self,
        node: LiveNode,
        topic: str,
        stop: asyncio.Event,
        sink: Callable[[str, list[Frame], InboundConnection, float], None],
        store: TypeStore,
        deadline: float | None,
    ) -> None:
        """Subscribe to ``topic`` once it is advertised (nothing if stopped or late first)."""
        ref = await wait_for_topic(node, topic, store, deadline, stop)
        if ref is None:
            return
        if ref.field:
            raise UsageError(f"{topic}: field paths do not apply here; give the topic itself")

        # the sink's key is the topic as given: hz keeps a meter per argument, and
        # ``hz foo foo:=/chatter`` subscribes to /chatter (a KeyError before)
        def on_frames(frames: list[Frame], conn: InboundConnection, now: float) -> None:
            if self.clock.sim:
                if not self.clock.valid:
                    return  # sim time is zero until the first /clock: rostopic skips these
                now = self.clock.now() / 1e9
            self.received += len(frames)
            try:
                sink(topic, frames, conn, now)
            except Exception as err:  # noqa: BLE001 - re-raised by run(), not in asyncio's IO
                self.error = err
                stop.set()

        if ref.topic == "/clock" and self.clock.sim:
            self.clock.forward = on_frames  # the clock's subscription is this node's one
        else:
            await node.subscribe(
                ref.topic, on_frames, tcp_nodelay=self.tcp_nodelay, coalesce=self.coalesce,
                reuse_frames=True,  # the sinks only look at a frame during the call
            )  # fmt: skip
        self.subscribed += 1
        sys.stderr.write(f"subscribed to [{one_line(ref.topic)}]\n")

    async def _report(
        self,
        stop: asyncio.Event,
        report: Callable[[bool], None],
        deadline: float | None,
        waits: list[asyncio.Task[None]],
    ) -> str:
        """Report every second until stopped or timed out; a topic's failed wait ends it."""
        from rostools.node.session import first

        next_report = time.monotonic() + REPORT_PERIOD
        while True:
            now = time.monotonic()
            wait = next_report - now
            if deadline is not None:
                wait = min(wait, deadline - now)
            if await first(stop.wait(), timeout=max(wait, 0)) == 0:
                for task in waits:
                    if task.done() and not task.cancelled() and (err := task.exception()):
                        raise err
                if self.error is not None:
                    raise self.error
                if self.subscribed:
                    report(True)  # Ctrl-C: rostopic prints the window once more
                    output.flush()
                return "stopped"
            if time.monotonic() >= next_report and self.subscribed:
                report(False)
                output.flush()
                next_report += REPORT_PERIOD
            if deadline is not None and time.monotonic() >= deadline:
                return "done" if self.received else "timeout"


def run_meter(ctx: typer.Context, meter: Meter, sink: Any, report: Any) -> None:
    """Run ``meter`` as the command's node until it stops; no message in ``--timeout``: exit 5."""
    result = node_session(
        ctx, lambda node, stop: meter.run(node, stop, sink, report), "rostools_rates", meter.fmt
    )
    if result == "timeout":
        raise TimeoutExpired(f"no message on {', '.join(meter.topics)} within {meter.timeout:g} s")
