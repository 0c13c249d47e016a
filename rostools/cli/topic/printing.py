"""What echo prints and how, shared by ``topic echo`` live and from a bag (``-b``).

A ``Printer`` turns raw messages of one type into text, CSV, YAML or NDJSON, compiled once
per type; ``Echo`` hands each message to the printer of its type and counts what it printed.
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rostools.cli.output import Format
from rostools.errors import UsageError

if TYPE_CHECKING:
    from collections.abc import Callable

    from rostools.msgs.codec import DecodeError
    from rostools.msgs.expr import Expression
    from rostools.msgs.store import TypeStore
    from rostools.node.connection import Frame


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

    def __init__(self, store: TypeStore, type_name: str, topic: str, opts: EchoOptions) -> None:
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
                as_json, decode = plain.to_json(self.codec, self.value_type), self.decode
                self.fast = lambda frames: [as_json(decode(f, 0)[0]) + "\n" for f in frames]

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
            # rostopic's order: a time given (a bag's record time), the header's stamp, now
            t = stamp_ns if stamp_ns is not None else plain.stamp_ns(value)
            t = now if t is None else t
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

    def __init__(self, store: TypeStore, opts: EchoOptions) -> None:
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
            from rostools.msgs import learnt

            store = learnt.codec(self.store, type_name, md5, definition).store
            found = self.printers[key] = Printer(store, type_name, topic, self.opts)
        return found

    def emit(
        self,
        printer: Printer,
        frames: list[Frame],
        stamp_ns: int | None = None,
        skip: Callable[[DecodeError, Frame], None] | None = None,
    ) -> bool:
        """Print messages; False once ``-n`` is reached.

        Bytes that do not decode as their type says are a ``DecodeError`` naming both; with
        ``skip``, it is handed the error and the message, and printing goes on.
        """
        from rostools.msgs.codec import DECODE_ERRORS, DecodeError

        limit = self.opts.count
        if printer.fast is not None and limit is None:
            try:
                texts: list[str] = printer.fast(frames)
            except (DecodeError, *DECODE_ERRORS):
                pass  # one at a time below, to say which message and print the others
            else:
                self.printed += len(texts)
                sys.stdout.write("".join(texts))
                sys.stdout.flush()
                return True
        out: list[str] = []
        try:
            for data in frames:
                if limit is not None and self.printed >= limit:
                    break
                try:
                    text = printer.render(data, stamp_ns, self.opts.plot and not self.header_done)
                except (DecodeError, *DECODE_ERRORS) as err:
                    failure = DecodeError(
                        f"a message on {printer.topic} does not decode as {printer.type_name}: "
                        f"{err}"
                    )
                    if skip is None:
                        raise failure from err
                    skip(failure, data)
                    continue
                if text is None:
                    continue
                self.header_done = True
                out.append(text)
                self.printed += 1
        finally:  # what came before a message that stops us is printed first
            if out:
                sys.stdout.write("".join(out))
                sys.stdout.flush()
        return limit is None or self.printed < limit


def echo_options(
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
    """Check and compile what the user asked for."""
    compiled = None
    if filter_expr:
        from rostools.msgs.expr import compile_expression

        compiled = compile_expression(filter_expr)
    if width is not None and width < 2:
        raise UsageError("-w must be at least 2")
    if count is not None and count < 1:
        raise UsageError("-n must be at least 1")
    return EchoOptions(field, count, compiled, plot, nostr, noarr, clear, offset, width, fmt)
