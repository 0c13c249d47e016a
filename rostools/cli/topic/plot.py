"""``rostools topic plot``: fields of live topics over a rolling time window, in the terminal.

rqt_plot without a GUI. Each message is sampled as it arrives, reading only the numbers
plotted (``msgs.sample``); the frame is drawn every ``FRAME_PERIOD`` from the window's
samples, so the cost of drawing does not grow with the message rate. On a terminal the plot
is redrawn live; into a pipe only the last frame is printed, and ``-F json|yaml`` prints the
samples instead of a picture.
"""

from __future__ import annotations

import sys
import time
from typing import TYPE_CHECKING, Annotated

import typer

from rostools.cli import output
from rostools.cli.common import FormatOpt, MsgPathOpt, node_session, output_format
from rostools.cli.declare import command
from rostools.cli.output import Format
from rostools.cli.settings import type_store
from rostools.cli.topic.live import (
    CountOpt,
    FilterOpt,
    StrictOpt,
    TimeoutOpt,
    Undecodable,
    wait_for_topic,
)
from rostools.errors import TimeoutExpired, UsageError
from rostools.names import script_resolve

if TYPE_CHECKING:
    import asyncio

    from rostools.msgs.codec import DecodeError
    from rostools.msgs.expr import Expression
    from rostools.msgs.sample import Sampler
    from rostools.msgs.store import TypeStore
    from rostools.node.connection import Frame, InboundConnection
    from rostools.node.node import LiveNode
    from rostools.series import SeriesSet

#: Seconds small reads gather before the callback runs: at 10 kHz, ten messages a wake-up.
COALESCE = 0.001


class _Live:
    """The state of one ``topic plot``: its samplers, its series, and why it stopped."""

    def __init__(
        self,
        names: list[str],
        store: TypeStore,
        plot: SeriesSet,
        stamp: bool,
        keep: Expression | None,
        count: int | None,
    ) -> None:
        self.names = names
        self.store = store
        self.plot = plot
        self.stamp = stamp
        self.keep = keep
        self.count = count
        self.paths: dict[str, list[str]] = {}
        self.samplers: dict[tuple[str, str, str, str], Sampler] = {}
        self.received = 0
        #: ``-n`` messages are in.
        self.done = False
        self.error: BaseException | None = None
        #: Set once the node runs: what does not decode is skipped there, or ends the plot.
        self.undecodable: Undecodable | None = None
        # Arrival times are monotonic; the plot's x is the wall clock.
        self.wall = time.time() - time.monotonic()

    def sampler(self, topic: str, header: dict[str, str]) -> Sampler:
        """The sampler for ``topic`` as this publisher's header defines its type."""
        from rostools.msgs import learnt
        from rostools.msgs.sample import Sampler

        kind = header.get("type", "*")
        definition = header.get("message_definition", "")
        key = (topic, kind, header.get("md5sum", ""), definition)
        found = self.samplers.get(key)
        if found is None:
            store = learnt.codec(self.store, *key[1:]).store
            paths = self.paths[topic]
            found = Sampler(store, kind, topic, paths, self.plot.sink, self.stamp, self.keep)
            self.samplers[key] = found
        return found

    def on_frames(
        self, topic: str, frames: list[Frame], conn: InboundConnection, now: float
    ) -> bool:
        """Sample what arrived; False once ``-n`` messages are in or something failed."""
        if self.done:  # another topic's reads may still come in: -n is exact across topics
            return False
        try:
            sampler = self.sampler(topic, conn.header or {})
            t = now + self.wall
            skip = None
            if (undecodable := self.undecodable) is not None:

                def skip(err: DecodeError, data: Frame) -> None:
                    undecodable.skip(err, conn, data)

            if self.count is None:
                self.received += sampler.feed(frames, t, skip)
                return True
            for data in frames:  # one at a time: the count is exact, filter or not
                self.received += sampler.feed([data], t, skip)
                if self.received >= self.count:
                    self.done = True
                    return False
            return True
        except Exception as err:  # noqa: BLE001 - re-raised by run(), not in asyncio's IO
            self.error = err
            return False

    def status(self, started: float) -> str:
        """The line under the plot: what arrived, how fast, and what was left out."""
        elapsed = max(time.monotonic() - started, 1e-9)
        missed = sum(s.missed for s in self.samplers.values())
        line = f"{self.received:,} messages, {self.received / elapsed:,.0f}/s"
        if missed:
            line += f", {missed:,} without the element asked for"
        skipped = sum(self.undecodable.counts.values()) if self.undecodable else 0
        if skipped:
            line += f", {skipped:,} skipped (they did not decode)"
        thinned = [label for label, s in self.plot.series.items() if s.thinned]
        if thinned:
            line += f", thinned: {', '.join(thinned)}"
        return line


@command()
def plot(
    ctx: typer.Context,
    fields: Annotated[
        list[str],
        typer.Argument(
            help="Topics with a field path to a number: /odom/pose/pose/position/x, "
            "/scan/ranges[0:5]."
        ),
    ],
    window: Annotated[
        str, typer.Option("--window", "-w", help="The time shown: 10s, 500ms, 2m.")
    ] = "10s",
    stamp: Annotated[
        bool, typer.Option("--stamp", help="x is each message's header.stamp, not receive time.")
    ] = False,
    count: CountOpt = None,
    filter_expr: FilterOpt = None,
    timeout: TimeoutOpt = None,
    strict: StrictOpt = False,
    fmt: FormatOpt = None,
    msg_path: MsgPathOpt = None,
) -> None:
    """Plot fields of topics live in the terminal (rqt_plot); -n or --timeout ends it."""
    from rostools.cli.units import parse_duration
    from rostools.series import SeriesSet

    fmt = output_format(ctx, fmt)
    seconds = parse_duration(window, "--window")
    if count is not None and count < 1:
        raise UsageError("-n must be at least 1")
    keep = None
    if filter_expr:
        from rostools.msgs.expr import compile_expression

        keep = compile_expression(filter_expr)
    names = [script_resolve(f, "rostopic", field_path=True) for f in fields]
    live = _Live(names, type_store(msg_path), SeriesSet(seconds), stamp, keep, count)
    result = node_session(
        ctx, lambda node, stop: _run(node, stop, live, timeout, fmt, strict), "rostools_plot", fmt
    )
    if result == "timeout":
        wanted = f"{count} message(s)" if count else "a message"
        raise TimeoutExpired(f"{', '.join(names)} did not deliver {wanted} within {timeout:g} s")


async def _subscribe(
    node: LiveNode, stop: asyncio.Event, live: _Live, deadline: float | None
) -> bool:
    """Find each topic, check its paths where the type is known, subscribe; False if stopped."""
    from rostools.msgs.sample import Labels, Sampler

    refs = []
    for name in live.names:
        ref = await wait_for_topic(node, name, live.store, deadline, stop)
        if ref is None:
            return False
        live.paths.setdefault(ref.topic, []).append(ref.field)
        live.plot.declare(Labels(ref.topic, ref.field).known())
        refs.append(ref)
    for ref in refs:  # a typo fails now, not at the first message
        if ref.type and live.store.has_msg(ref.type):
            paths = live.paths[ref.topic]
            Sampler(live.store, ref.type, ref.topic, paths, live.plot.sink, live.stamp, live.keep)
    for topic in live.paths:

        def on_frames(
            frames: list[Frame], conn: InboundConnection, now: float, topic: str = topic
        ) -> None:
            if not live.on_frames(topic, frames, conn, now):
                stop.set()

        await node.subscribe(topic, on_frames, coalesce=COALESCE, reuse_frames=True)
    return True


class _Frames:
    """The live plot's frames: the x axis from the start (receive time) or the first stamp."""

    def __init__(self, live: _Live, started: float, kind: str) -> None:
        from rostools.cli import plotting

        self.live, self.started, self.kind = live, started, kind
        self.color = plotting.use_color()
        self.window = live.plot.window or 0.0
        self.start_wall = live.wall + started
        self.first_stamp: float | None = None  # stamps may be on any clock: count from the first

    def __call__(self) -> str:
        """The frame now."""
        from rostools.cli import plotting

        live, now = self.live, time.time()
        if not live.stamp:
            origin, right = self.start_wall, now
        else:
            held = live.plot.bounds()
            if held is not None and self.first_stamp is None:
                self.first_stamp = held[0]
            origin = self.first_stamp if self.first_stamp is not None else now
            right = live.plot.newest if held is not None else now
        return plotting.frame(
            live.plot, origin=origin, title=f"topic plot, last {self.window:g} s",
            color=self.color, xlabel=plotting.axis_label(self.kind, origin),
            status=live.status(self.started), x_range=(max(right - self.window, origin), right),
        )  # fmt: skip


async def _run(
    node: LiveNode,
    stop: asyncio.Event,
    live: _Live,
    timeout: float | None,
    fmt: Format,
    strict: bool,
) -> str:
    import contextlib

    from rostools.cli import plotting
    from rostools.node.session import first

    started = time.monotonic()
    deadline = started + timeout if timeout is not None else None
    draw = fmt is Format.text
    screen = plotting.Screen() if draw and sys.stdout.isatty() else None
    kind = "stamp" if live.stamp else "receive"
    render = _Frames(live, started, kind)

    live.undecodable = Undecodable(node, strict)
    stack = contextlib.ExitStack()
    try:
        if screen is not None:
            stack.enter_context(screen)
            screen.show(render())
        if not await _subscribe(node, stop, live, deadline):
            return "stopped" if stop.is_set() else "timeout"
        while True:
            wait = plotting.FRAME_PERIOD
            if deadline is not None:
                wait = min(wait, max(deadline - time.monotonic(), 0))
            stopped = await first(stop.wait(), timeout=wait) == 0
            if live.error is not None:
                raise live.error
            live.plot.trim(None if live.stamp else time.time())
            if screen is not None:
                screen.show(render())
            if stopped or (deadline is not None and time.monotonic() >= deadline):
                break
    finally:
        stack.close()
        live.undecodable.report()
    if live.error is not None:
        raise live.error
    if not draw:
        plotting.emit_records(fmt, live.plot, kind)
    elif screen is None:
        output.put(render())
    if live.done:
        return "done"
    if stop.is_set():
        return "stopped"
    return "timeout" if live.received == 0 or live.count else "done"
