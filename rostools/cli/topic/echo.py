"""``rostools topic echo``: print messages as rostopic does, or as JSON, YAML or CSV."""

from __future__ import annotations

import contextlib
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rostools.cli.common import (
    FINITE,
    FormatOpt,
    MsgPathOpt,
    node_session,
    output_format,
    type_store,
)
from rostools.cli.output import Format
from rostools.cli.topic import app
from rostools.errors import TimeoutExpired, UsageError
from rostools.names import script_resolve

if TYPE_CHECKING:
    import asyncio

    from rostools.msgs.expr import Expression

CountOpt = Annotated[int | None, typer.Option("-n", help="Exit after this many messages.")]
TimeoutOpt = Annotated[
    float | None,
    typer.Option(
        "--timeout",
        click_type=FINITE,
        help="Give up after this many seconds (exit 5 if fewer messages than asked arrived).",
    ),
]
FilterOpt = Annotated[
    str | None,
    typer.Option(
        "--filter",
        help="Python expression over m (the message) and topic; print only where it is true.",
    ),
]


@dataclass
class EchoOptions:
    """What the user asked echo to do."""

    field: str
    count: int | None
    filter: Expression | None
    plot: bool
    nostr: bool
    noarr: bool
    clear: bool
    offset: bool
    width: int | None
    fmt: Format


class Printer:
    """Turns raw messages of one type into output text, compiled once per type."""

    def __init__(self, store: Any, type_name: str, topic: str, opts: EchoOptions) -> None:
        from rostools.msgs import fieldpath, plain, text
        from rostools.msgs.codec import Codec

        self.codec = Codec.of(store)
        self.type_name = type_name
        self.topic = topic
        self.opts = opts
        self.decode = self.codec.decoder(type_name)
        if opts.field:
            path = fieldpath.resolve(store, type_name, opts.field)
            self.value_type = path.result
            self.get: Any = path.get
        else:
            self.value_type = text.message_type(type_name)
            self.get = None
        self.fast: Any = None  # frames -> texts, when nothing needs a per-message decision
        if opts.plot:
            self.csv_opts = plain.CsvOptions(opts.nostr, opts.noarr)
            self.row = plain.csv_row(self.codec, self.value_type, self.csv_opts)
        elif opts.fmt is Format.text:
            options = text.TextOptions(opts.nostr, opts.noarr, opts.width, opts.offset)
            self.text = text.formatter(self.codec, self.value_type, options)
            if not (opts.filter or opts.field or opts.clear or opts.offset):
                fmt = text.formatter(self.codec, self.value_type, options, suffix="\n---\n")
                decode = self.decode
                self.fast = lambda frames: [fmt(decode(f, 0)[0]) for f in frames]
        else:
            self.plain = plain.to_plain(self.codec, self.value_type)
            if opts.fmt is Format.json and not (opts.filter or opts.field):
                to_plain, decode, dumps = self.plain, self.decode, plain.dumps
                self.fast = lambda frames: [dumps(to_plain(decode(f, 0)[0])) + "\n" for f in frames]

    def render(self, data: Any, stamp_ns: int | None, header_needed: bool) -> str | None:
        """The output for one message, or None when the filter rejects it."""
        from rostools.msgs import plain

        msg = self.decode(data, 0)[0]
        if self.opts.filter is not None and not self.opts.filter(self.topic, msg):
            return None
        value = self.get(msg) if self.get is not None else msg
        opts = self.opts
        if opts.plot:
            now = time.time_ns()
            offset = now if opts.offset else 0
            stamp = plain.stamp_ns(value)
            t = stamp if stamp is not None else (stamp_ns if stamp_ns is not None else now)
            line = f"{t - offset},{self.row(value, offset)}\n"
            if header_needed:
                line = (
                    plain.csv_header(self.codec, self.value_type, value, self.csv_opts)
                    + "\n"
                    + line
                )
            return line
        if opts.fmt is Format.text:
            from rostools.msgs.message import Time

            prefix = "\033[2J\033[;H" if opts.clear else ""
            return prefix + self.text(value, Time.now() if opts.offset else None) + "\n---\n"
        from rostools.cli import output

        return output.record(opts.fmt, self.plain(value))


class Echo:
    """Prints every message it is given; counts what it printed."""

    def __init__(self, store: Any, opts: EchoOptions) -> None:
        self.store = store
        self.opts = opts
        self.printers: dict[tuple[str, str, str], Printer] = {}
        self.printed = 0
        self.header_done = False

    def printer(self, type_name: str, md5: str, definition: str, topic: str) -> Printer:
        """The printer for a type as one publisher defines it."""
        key = (type_name, md5, definition)
        found = self.printers.get(key)
        if found is None:
            store = self.store.with_definition(type_name, definition)
            found = self.printers[key] = Printer(store, type_name, topic, self.opts)
        return found

    def emit(self, printer: Printer, frames: list[Any], stamp_ns: int | None = None) -> bool:
        """Print messages; False once ``-n`` is reached.

        Bytes that do not decode as their type says are a ``DecodeError`` naming both.
        """
        from rostools.msgs.codec import DECODE_ERRORS, DecodeError

        try:
            return self._emit(printer, frames, stamp_ns)
        except (DecodeError, *DECODE_ERRORS) as err:
            raise DecodeError(
                f"a message on {printer.topic} does not decode as {printer.type_name}: {err}"
            ) from err

    def _emit(self, printer: Printer, frames: list[Any], stamp_ns: int | None) -> bool:
        limit = self.opts.count
        if printer.fast is not None and limit is None:
            texts: list[str] = printer.fast(frames)
            self.printed += len(texts)
            sys.stdout.write("".join(texts))
            sys.stdout.flush()
            return True
        out: list[str] = []
        for data in frames:
            if limit is not None and self.printed >= limit:
                break
            text = printer.render(data, stamp_ns, self.opts.plot and not self.header_done)
            if text is None:
                continue
            self.header_done = True
            out.append(text)
            self.printed += 1
        if out:
            sys.stdout.write("".join(out))
            sys.stdout.flush()
        return limit is None or self.printed < limit


def _options(
    fmt: Format,
    field: str,
    count: int | None,
    filter_expr: str | None,
    plot: bool,
    nostr: bool,
    noarr: bool,
    clear: bool,
    offset: bool,
    width: int | None,
) -> EchoOptions:
    compiled = None
    if filter_expr:
        from rostools.msgs.expr import compile_expression

        compiled = compile_expression(filter_expr)
    if width is not None and width < 2:
        raise UsageError("-w must be at least 2")
    if count is not None and count < 1:
        raise UsageError("-n must be at least 1")
    return EchoOptions(field, count, compiled, plot, nostr, noarr, clear, offset, width, fmt)


@app.command()
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
    timeout: TimeoutOpt = None,
    fmt: FormatOpt = None,
    msg_path: MsgPathOpt = None,
) -> None:
    """Print the messages of a topic (rostopic echo)."""
    fmt = output_format(ctx, fmt)
    if all_topics and bag is None:
        raise UsageError("--all needs --bag")
    if bag is not None and offset:
        raise UsageError("--offset does not apply to a bag")
    if topic is None and not all_topics:
        raise UsageError("give a topic")
    name = script_resolve(topic, "rostopic", field_path=True) if topic else ""
    store = type_store(msg_path)
    if bag is not None:
        from rostools.cli.topic.bagecho import echo_bag

        opts = _options(fmt, "", count, filter_expr, plot, nostr, noarr, clear, offset, width)
        echo_bag(bag, name if not all_topics else None, store, opts)
        return
    opts = _options(fmt, "", count, filter_expr, plot, nostr, noarr, clear, offset, width)
    result = node_session(
        ctx, lambda node, stop: _live(node, stop, name, store, opts, timeout), "rostools_echo", fmt
    )
    if result == "timeout":
        wanted = f"{count} message(s)" if count else "a message"
        raise TimeoutExpired(f"{name} did not deliver {wanted} within {timeout:g} s")


async def _resolve(
    node: Any, name: str, store: Any, deadline: float | None, stop: asyncio.Event
) -> Any:
    """Wait until the topic is advertised; the topic and field path."""
    import asyncio

    from rostools.graph.topics import split_field

    name = node.resolve(name)  # command-line remappings apply
    warned = False
    while True:
        types = dict(await node.master_call("getTopicTypes"))
        ref = split_field(name, types, store)
        if ref is not None:
            return ref
        if not warned:
            sys.stderr.write(f"WARNING: topic [{name}] does not appear to be published yet\n")
            warned = True
        if stop.is_set() or (deadline is not None and time.monotonic() > deadline):
            return None
        with contextlib.suppress(asyncio.TimeoutError):
            await asyncio.wait_for(stop.wait(), 0.2)


async def _live(
    node: Any, stop: asyncio.Event, name: str, store: Any, opts: EchoOptions, timeout: float | None
) -> str:
    import asyncio

    deadline = time.monotonic() + timeout if timeout is not None else None
    ref = await _resolve(node, name, store, deadline, stop)
    if ref is None:
        return "stopped" if stop.is_set() else "timeout"
    opts.field = ref.field
    echo_ = Echo(store, opts)
    pending: list[tuple[list[Any], Any]] = []
    wake = asyncio.Event()  # frames, a stop or the deadline: one event, no task per batch

    def on_frames(frames: list[Any], conn: Any, now: float) -> None:
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
                if not echo_.emit(printer, frames):
                    return "done"
            if stop.is_set() or (deadline is not None and time.monotonic() >= deadline):
                break
    finally:
        watcher.cancel()
    if stop.is_set():
        return "stopped"
    if (opts.count and echo_.printed < opts.count) or echo_.printed == 0:
        return "timeout"
    return "done"
