"""``rostools topic hz|bw|delay``: rate meters that never decode what they only count."""

from __future__ import annotations

import struct
import sys
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rostools.cli import output
from rostools.cli.common import FormatOpt, node_session, output_format
from rostools.cli.declare import command
from rostools.cli.output import Format
from rostools.cli.topic.live import FilterOpt, StrictOpt, TimeoutOpt, Undecodable, wait_for_topic
from rostools.errors import NotFoundError, TimeoutExpired, UsageError, one_line
from rostools.names import script_resolve

if TYPE_CHECKING:
    import asyncio

    from rostools.msgs.codec import DecodeError
    from rostools.msgs.store import TypeStore
    from rostools.node.connection import Frame, InboundConnection
    from rostools.node.node import LiveNode

_STAMP = struct.Struct("<II")
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


def _run(ctx: typer.Context, meter: Meter, sink: Any, report: Any) -> None:
    result = node_session(
        ctx, lambda node, stop: meter.run(node, stop, sink, report), "rostools_rates", meter.fmt
    )
    if result == "timeout":
        raise TimeoutExpired(f"no message on {', '.join(meter.topics)} within {meter.timeout:g} s")


@command()
def hz(
    ctx: typer.Context,
    topics: Annotated[list[str], typer.Argument(help="One or more topics.")],
    window: HzWindowOpt = None,
    filter_expr: FilterOpt = None,
    wall_time: Annotated[
        bool,
        typer.Option(
            "--wall-time", help="Time arrivals by the wall clock, even under /use_sim_time."
        ),
    ] = False,
    tcp_nodelay: NodelayOpt = False,
    timeout: TimeoutOpt = None,
    strict: StrictOpt = False,
    fmt: FormatOpt = None,
) -> None:
    """The publishing rate of topics (rostopic hz); counts raw frames, decodes only for --filter."""
    from rostools.rates import DEFAULT_SPAN, DEFAULT_WINDOW, RateMeter, format_rate, rate_table

    fmt = output_format(ctx, fmt)
    names = [script_resolve(t, "rostopic") for t in topics]
    span = 0.0 if window else DEFAULT_SPAN  # an explicit window is rostopic's, exactly
    meters = {n: RateMeter(window or DEFAULT_WINDOW, span) for n in names}
    runner = Meter(names, timeout, fmt, tcp_nodelay, wall_time, COALESCE, strict)
    check = _filter(filter_expr, runner.skip)

    def sink(topic: str, frames: list[Frame], conn: InboundConnection, now: float) -> None:
        if check is not None:
            frames = check(frames, conn, topic)
        meters[topic].add(len(frames), now)

    def report(last: bool = False) -> None:
        rows = [(n, s) for n in names if (s := meters[n].report(last)) is not None]
        if fmt is not Format.text:
            for n, s in rows:
                row = {"topic": n, "rate": s.value, "min": s.min, "max": s.max,
                       "std_dev": s.std_dev, "window": s.window}  # fmt: skip
                output.write(fmt, row)
        elif not rows:
            output.put("no new messages\n")
        elif len(names) == 1:
            output.put(format_rate(rows[0][1]) + "\n")
        else:
            output.put(rate_table(rows))

    _run(ctx, runner, sink, report)


def _filter(
    expr: str | None, skip: Callable[[DecodeError, InboundConnection, Frame], None]
) -> Callable[[list[Frame], InboundConnection, str], list[Frame]] | None:
    """A frames filter that decodes and evaluates ``expr``, or None.

    A message that does not decode goes to ``skip`` and is not counted.
    """
    if not expr:
        return None
    from rostools.msgs import learnt
    from rostools.msgs.codec import DECODE_ERRORS, DecodeError, why_not
    from rostools.msgs.expr import compile_expression
    from rostools.msgs.store import TypeStore

    wanted = compile_expression(expr)
    base = TypeStore.default()

    def keep(frames: list[Frame], conn: InboundConnection, topic: str) -> list[Frame]:
        header = conn.header or {}
        kind, md5 = header.get("type", ""), header.get("md5sum", "")
        decode = learnt.decoder(base, kind, md5, header.get("message_definition", ""))
        kept = []
        for data in frames:
            try:
                msg = decode(data, 0)[0]
            except (DecodeError, *DECODE_ERRORS) as err:
                why = f"a message on {topic} does not decode as {kind}: {why_not(err)}"
                skip(DecodeError(why), conn, data)
                continue
            if wanted(topic, msg):
                kept.append(data)
        return kept

    return keep


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

    _run(ctx, runner, sink, report)


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

    _run(ctx, runner, sink, report)
