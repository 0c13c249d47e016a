"""``rostools log echo``: print ``rosgraph_msgs/Log`` messages as rosconsole echo does.

Live, from ``/rosout_agg`` (or ``/rosout`` where nothing publishes the aggregate), or from a
``.bag`` or MCAP with ``-b``. Text is rosconsole's line, ``[ LEVEL ] [node]: message``, with
its colours on a terminal; ``--format json`` gives every field of the message.
"""

from __future__ import annotations

import os
import re
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rostools.cli import output
from rostools.cli.common import FINITE, FormatOpt, NoCrcCheckOpt, node_session, output_format
from rostools.cli.declare import command
from rostools.cli.output import Format
from rostools.errors import (
    InvalidDataError,
    NotFoundError,
    TimeoutExpired,
    UsageError,
    one_line,
)

if TYPE_CHECKING:
    import asyncio

    from rostools.cli.render import Renderer
    from rostools.node.connection import Frame, InboundConnection
    from rostools.node.node import LiveNode

LOG_TYPE = "rosgraph_msgs/Log"
#: The topics echo follows, the first that is there (rosout's aggregate, then the raw topic).
TOPICS = ("/rosout_agg", "/rosout")
#: rosgraph_msgs/Log's levels (a bit each) and rosconsole echo's names and colours for them.
LEVELS = {"debug": 1, "info": 2, "warn": 4, "error": 8, "fatal": 16}
_NAMES = {value: name.upper() for name, value in LEVELS.items()}
_COLOURS = {1: 92, 2: 97, 4: 93, 8: 91, 16: 95}  # light green, white, yellow, red, magenta
_WIDTH = 5  # the longest level name: rosconsole pads each to it

LevelOpt = Annotated[
    str,
    typer.Option(
        "--level",
        "-l",
        help="Print messages at this level or above: debug, info, warn, error,"
        " fatal (rosconsole's default: warn).",
    ),
]


def level_text(level: int, colour: bool) -> str:
    """A level as rosconsole echo shows it: padded, coloured on a terminal."""
    name = _NAMES.get(level, str(level)).ljust(_WIDTH)
    return f"\033[{_COLOURS[level]}m{name}\033[0m" if colour and level in _COLOURS else name


class LogPrinter:
    """Which messages echo shows and how: level, node and text filters, then one line each."""

    def __init__(
        self,
        level: int,
        node_re: re.Pattern[str] | None,
        grep_re: re.Pattern[str] | None,
        fmt: Format,
        colour: bool,
        verbose: bool,
        count: int | None,
    ) -> None:
        self.level, self.node_re, self.grep_re = level, node_re, grep_re
        self.fmt, self.colour, self.verbose, self.count = fmt, colour, verbose, count
        #: Messages printed so far; those skipped because they did not decode.
        self.printed = self.skipped = 0
        #: Raise at a message that does not decode (a bag's: the error names where).
        self.strict = False

    def wanted(self, msg: Any) -> bool:
        """Whether ``msg`` passes the level, node and text filters."""
        if msg.level < self.level:
            return False
        if self.node_re is not None and not self.node_re.search(msg.name):
            return False
        return self.grep_re is None or self.grep_re.search(msg.msg) is not None

    def line(self, msg: Any) -> str:
        """rosconsole echo's text for ``msg``; two lines with ``-v``."""
        name = one_line(msg.name)
        if self.colour:
            name = f"\033[1m{name}\033[22m"
        text = f"[ {level_text(msg.level, self.colour)} ] [{name}]: {one_line(msg.msg)}\n"
        if self.verbose:
            from datetime import datetime

            stamp = msg.header.stamp.to_sec()
            when = datetime.fromtimestamp(stamp).astimezone()
            where = f"{one_line(msg.function)}]: {one_line(msg.file)}:{msg.line}"
            text += f"          [{when} ({stamp:.6f})] [{where}\n"
        return text

    def show(self, renderer: Renderer, frames: list[Any]) -> bool:
        """Print the wanted messages of ``frames``; False once ``count`` are printed."""
        out: list[str] = []
        done = False
        for data in frames:
            try:
                msg = renderer.decode(data, 0)[0]
            except InvalidDataError as err:
                if self.strict:
                    raise
                self.skipped += 1
                if self.skipped == 1:  # the first said, the rest counted at the end
                    sys.stderr.write(
                        one_line(f"skipped a message that did not decode: {err}") + "\n"
                    )
                continue
            if not self.wanted(msg):
                continue
            if self.fmt is Format.text:
                out.append(self.line(msg))
            elif self.fmt is Format.json:
                out.append(renderer.json(msg) + "\n")
            else:
                out.append(output.record(self.fmt, renderer.plain(msg)) + "\n")
            self.printed += 1
            if self.count is not None and self.printed >= self.count:
                done = True
                break
        if out:
            output.put("".join(out))
        return not done


def _pattern(text: str | None, option: str) -> re.Pattern[str] | None:
    if text is None:
        return None
    try:
        return re.compile(text)
    except re.error as err:
        raise UsageError(f"{option} {text!r} is not a regular expression: {err}") from err


@command()
def echo(
    ctx: typer.Context,
    node_filter: Annotated[
        str | None,
        typer.Argument(help="Regex on the node's name, as rosconsole echo's FILTER (--node)."),
    ] = None,
    level: LevelOpt = "warn",
    node: Annotated[
        str | None, typer.Option("--node", help="Only nodes whose name this regex finds.")
    ] = None,
    grep: Annotated[
        str | None, typer.Option("--grep", help="Only messages whose text this regex finds.")
    ] = None,
    topic: Annotated[
        str | None,
        typer.Option("--topic", help="Read this topic (default: /rosout_agg, else /rosout)."),
    ] = None,
    count: Annotated[
        int | None, typer.Option("-n", min=1, help="Exit after printing this many.")
    ] = None,
    once: Annotated[bool, typer.Option("--once", "-1", help="Print one message, exit.")] = False,
    nocolor: Annotated[bool, typer.Option("--nocolor", help="No colours.")] = False,
    verbose: Annotated[
        bool, typer.Option("--verbose", "-v", help="Also the stamp, function, file and line.")
    ] = False,
    bag: Annotated[
        Path | None, typer.Option("--bag", "-b", help="Read a .bag or .mcap instead.")
    ] = None,
    no_crc_check: NoCrcCheckOpt = False,
    timeout: Annotated[
        float | None,
        typer.Option(
            "--timeout",
            click_type=FINITE,
            help="Stop after this many seconds (exit 5 if -n/--once got fewer).",
        ),
    ] = None,
    fmt: FormatOpt = None,
) -> None:
    """Print what nodes log, from /rosout_agg or /rosout (rosconsole echo)."""
    out = output_format(ctx, fmt)
    if level.lower() not in LEVELS:
        raise UsageError(f"--level {level!r} is not one of {', '.join(LEVELS)}")
    if node is not None and node_filter is not None:
        raise UsageError("give the node filter once: as FILTER or as --node")
    if bag is not None and timeout is not None:
        raise UsageError("--timeout does not apply to a bag (-b): it is read to its end")
    if no_crc_check and bag is None:
        raise UsageError("--no-crc-check needs --bag")
    if once:
        count = 1
    colour = out is Format.text and not nocolor and sys.stdout.isatty()
    colour = colour and not os.environ.get("NO_COLOR")
    printer = LogPrinter(
        LEVELS[level.lower()],
        _pattern(node if node is not None else node_filter, "--node"),
        _pattern(grep, "--grep"),
        out,
        colour,
        verbose,
        count,
    )
    if bag is not None:
        _from_bag(bag, topic, printer, not no_crc_check)
        return
    result = node_session(
        ctx, lambda n, stop: _live(n, stop, topic, printer, timeout), "rostools_log", out
    )
    if result == "timeout":
        raise TimeoutExpired(f"{count} message(s) did not arrive within {timeout:g} s")


def _renderer() -> Renderer:
    from rostools.cli.render import Renderer
    from rostools.cli.settings import type_store
    from rostools.msgs.codec import Codec

    return Renderer(Codec.of(type_store()), LOG_TYPE)


async def _live(
    node: LiveNode,
    stop: asyncio.Event,
    topic: str | None,
    printer: LogPrinter,
    timeout: float | None,
) -> str:
    import asyncio

    from rostools.msgs.topictype import TopicType
    from rostools.rosgraph.masterapi import within

    deadline = time.monotonic() + timeout if timeout is not None else None
    renderer = _renderer()
    if topic is None:
        published = await node.master.call("getPublishedTopics", "", timeout=within(deadline))
        names = {name for name, _ in published}
        topic = next((t for t in TOPICS if t in names), TOPICS[-1])
    pending: list[list[Frame]] = []
    wake = asyncio.Event()  # frames, a stop or the deadline: one event, no task per batch

    def on_frames(frames: list[Frame], conn: InboundConnection, now: float) -> None:
        pending.append(frames)
        wake.set()

    loop = asyncio.get_running_loop()
    if deadline is not None:
        loop.call_at(loop.time() + max(deadline - time.monotonic(), 0), wake.set)
    watcher = loop.create_task(stop.wait())
    watcher.add_done_callback(lambda _: wake.set())
    # small reads gather for 1 ms: at 10k messages a second, a wake-up each costs the CPU
    log_type = TopicType.of(renderer.codec.store, LOG_TYPE)
    await node.subscribe(topic, on_frames, log_type, coalesce=0.001)
    try:
        while not stop.is_set():
            if deadline is not None and time.monotonic() >= deadline:
                break
            await wake.wait()
            wake.clear()
            batch, pending[:] = list(pending), []
            for frames in batch:
                if not printer.show(renderer, frames):
                    return "done"
    finally:
        watcher.cancel()
        if printer.skipped > 1:
            sys.stderr.write(f"skipped {printer.skipped} messages that did not decode\n")
    if stop.is_set():
        return "stopped"
    return "timeout" if printer.count is not None else "done"


def _from_bag(path: Path, topic: str | None, printer: LogPrinter, check_crcs: bool) -> None:
    """Print the log messages a bag holds: ``/rosout_agg``'s, else ``/rosout``'s."""
    from rostools.bag.formats.access import open_bag, require_ros1
    from rostools.bag.formats.base import after_reading
    from rostools.bag.formats.model import counted
    from rostools.cli.render import Renderer
    from rostools.cli.settings import type_store

    store = type_store()
    printer.strict = True
    with open_bag(path, check_crcs=check_crcs) as bag:
        # a relative name (rosbag2_bag_v2's "rosout") is the global one, as a bag is read
        logs = {_global(c.topic): c.topic for c in bag.connections if c.type == LOG_TYPE}
        wanted = _global(topic) if topic else next((t for t in TOPICS if t in logs), None)
        if wanted is None or wanted not in logs:
            what = wanted or " or ".join(TOPICS)
            raise NotFoundError(f"{path} has no {LOG_TYPE} messages on {what}")
        require_ros1(bag, "log echo -b", [logs[wanted]])
        renderers: dict[int, Renderer] = {}
        for conn, t_ns, data in bag.messages(topics=[logs[wanted]]):
            try:
                renderer = renderers.get(id(conn))
                if renderer is None:
                    renderer = renderers[id(conn)] = Renderer.learnt(
                        store, conn.type, conn.md5sum, conn.definition
                    )
                if not printer.show(renderer, [data]):
                    break
            except InvalidDataError as err:  # a bad definition or message: say where
                raise InvalidDataError(f"{path}: message at {t_ns / 1e9:.9f} s: {err}") from err
    after_reading(
        [bag],
        f"printed {counted(printer.printed, 'message')}",
        lambda n: sys.stderr.write(f"note: {n}\n"),
    )


def _global(topic: str) -> str:
    return topic if topic.startswith("/") else "/" + topic
