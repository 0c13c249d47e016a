"""``rostools topic echo``: print messages as rostopic does, or as JSON, YAML or CSV."""

from __future__ import annotations

import time
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from rostools.cli.common import (
    FormatOpt,
    MsgPathOpt,
    NoCrcCheckOpt,
    node_session,
    output_format,
)
from rostools.cli.declare import command
from rostools.cli.settings import type_store
from rostools.cli.topic.live import (
    CountOpt,
    FilterOpt,
    StrictOpt,
    TimeoutOpt,
    Undecodable,
    wait_for_topic,
)
from rostools.cli.topic.printing import Echo, EchoOptions, echo_options
from rostools.errors import TimeoutExpired, UsageError
from rostools.names import script_resolve

if TYPE_CHECKING:
    import asyncio

    from rostools.msgs.codec import DecodeError
    from rostools.msgs.store import TypeStore
    from rostools.node.connection import Frame, InboundConnection
    from rostools.node.node import LiveNode


@command()
def echo(
    ctx: typer.Context,
    topic: Annotated[
        str | None, typer.Argument(help="Topic, optionally with a field path: /odom/pose/pose.")
    ] = None,
    count: CountOpt = None,
    filter_expr: FilterOpt = None,
    plot: Annotated[bool, typer.Option("-p", help="CSV with a %time,field... header.")] = False,
    nostr: Annotated[bool, typer.Option("--nostr", help="Hide strings.")] = False,
    noarr: Annotated[bool, typer.Option("--noarr", help="Hide arrays.")] = False,
    clear: Annotated[
        bool, typer.Option("--clear", "-c", help="Clear the screen before each message.")
    ] = False,
    offset: Annotated[bool, typer.Option("--offset", help="Times relative to now.")] = False,
    width: Annotated[int | None, typer.Option("-w", help="Fixed width for numbers.")] = None,
    bag: Annotated[
        Path | None, typer.Option("--bag", "-b", help="Read a .bag or .mcap instead.")
    ] = None,
    all_topics: Annotated[
        bool, typer.Option("--all", "-a", help="Every topic of the bag (-b).")
    ] = False,
    no_crc_check: NoCrcCheckOpt = False,
    timeout: TimeoutOpt = None,
    strict: StrictOpt = False,
    fmt: FormatOpt = None,
    msg_path: MsgPathOpt = None,
) -> None:
    """Print the messages of a topic (rostopic echo)."""
    fmt = output_format(ctx, fmt)
    if all_topics and bag is None:
        raise UsageError("--all needs --bag")
    if no_crc_check and bag is None:
        raise UsageError("--no-crc-check needs --bag")
    if bag is not None and offset:
        raise UsageError("--offset does not apply to a bag")
    if bag is not None and timeout is not None:
        raise UsageError("--timeout does not apply to a bag (-b): it is read to its end")
    if topic is None and not all_topics:
        raise UsageError("give a topic")
    name = script_resolve(topic, "rostopic", field_path=True) if topic else ""
    store = type_store(msg_path)
    if bag is not None:
        from rostools.cli.topic.bagecho import echo_bag

        opts = echo_options(fmt, "", count, filter_expr, plot, nostr, noarr, clear, offset, width)
        echo_bag(bag, name if not all_topics else None, store, opts, not no_crc_check)
        return
    opts = echo_options(fmt, "", count, filter_expr, plot, nostr, noarr, clear, offset, width)
    result = node_session(
        ctx,
        lambda node, stop: _live(node, stop, name, store, opts, timeout, strict),
        "rostools_echo",
        fmt,
    )
    if result == "timeout":
        wanted = f"{count} message(s)" if count else "a message"
        raise TimeoutExpired(f"{name} did not deliver {wanted} within {timeout:g} s")


async def _live(
    node: LiveNode,
    stop: asyncio.Event,
    name: str,
    store: TypeStore,
    opts: EchoOptions,
    timeout: float | None,
    strict: bool,
) -> str:
    import asyncio

    deadline = time.monotonic() + timeout if timeout is not None else None
    ref = await wait_for_topic(node, name, store, deadline, stop)
    if ref is None:
        return "stopped" if stop.is_set() else "timeout"
    opts.field = ref.field
    echo_ = Echo(store, opts)
    undecodable = Undecodable(node, strict)
    pending: list[tuple[list[Frame], InboundConnection]] = []
    wake = asyncio.Event()  # frames, a stop or the deadline: one event, no task per batch

    def on_frames(frames: list[Frame], conn: InboundConnection, now: float) -> None:
        pending.append((frames, conn))
        wake.set()

    loop = asyncio.get_running_loop()
    if deadline is not None:
        loop.call_at(loop.time() + max(deadline - time.monotonic(), 0), wake.set)
    watcher = loop.create_task(stop.wait())
    watcher.add_done_callback(lambda _: wake.set())
    await node.subscribe(ref.topic, on_frames)
    try:
        while True:
            await wake.wait()
            wake.clear()
            batch, pending[:] = list(pending), []
            for frames, conn in batch:
                header = conn.header or {}
                printer = echo_.printer(
                    header.get("type", "*"),
                    header.get("md5sum", ""),
                    header.get("message_definition", ""),
                    ref.topic,
                )

                def skip(err: DecodeError, data: Frame, conn: InboundConnection = conn) -> None:
                    undecodable.skip(err, conn, data)

                if not echo_.emit(printer, frames, skip=skip):
                    return "done"
            if stop.is_set() or (deadline is not None and time.monotonic() >= deadline):
                break
    finally:
        watcher.cancel()
        undecodable.report()
    if stop.is_set():
        return "stopped"
    if (opts.count and echo_.printed < opts.count) or echo_.printed == 0:
        return "timeout"
    return "done"
