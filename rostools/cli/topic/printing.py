"""What echo prints and how, shared by ``topic echo`` live and from a bag (``-b``).

A ``Printer`` is echo's policy (filter, field, CSV time, ``--clear``) over the ``Renderer`` of
one type as its publisher defines it; ``Echo`` hands each message to the printer of its type
and counts what it printed.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rostools.cli import output
from rostools.cli.output import Format
from rostools.cli.render import Renderer
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
    """Echo's policy over one connection's ``Renderer``: filter, field, CSV time, text extras."""

    def __init__(self, renderer: Renderer, topic: str, opts: EchoOptions) -> None:
        self.renderer = renderer
        self.type_name = renderer.type_name
        self.topic = topic
        self.opts = opts
        self.decode = renderer.decode
        #: frames -> texts, when nothing needs a per-message decision
        self.fast: Callable[[list[Any]], list[str]] | None = None
        if opts.plot:
            pass
        elif opts.fmt is Format.text and not (opts.filter or opts.field or opts.clear):
            self.fast = None if opts.offset else renderer.texts()
        elif opts.fmt is Format.json and not (opts.filter or opts.field):
            self.fast = renderer.jsons()

    def render(self, data: Any, stamp_ns: int | None, header_needed: bool) -> str | None:
        """The output for one message, or None when the filter rejects it."""
        msg = self.decode(data, 0)[0]
        if self.opts.filter is not None and not self.opts.filter(self.topic, msg):
            return None
        r, opts = self.renderer, self.opts
        value = r.value(msg)
        if opts.plot:
            now = time.time_ns()
            offset = now if opts.offset else 0
            # rostopic's order: a time given (a bag's record time), the header's stamp, now
            t = stamp_ns if stamp_ns is not None else r.stamp(value)
            t = now if t is None else t
            line = f"{t - offset},{r.csv_row(value, offset)}\n"
            return r.csv_header(value) + "\n" + line if header_needed else line
        if opts.fmt is Format.text:
            from rostools.msgs.message import Time

            prefix = "\033[2J\033[;H" if opts.clear else ""
            return prefix + r.text(value, Time.now() if opts.offset else None) + "\n---\n"
        return output.record(opts.fmt, r.plain(value))


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
            from rostools.msgs.plain import CsvOptions
            from rostools.msgs.text import TextOptions

            o = self.opts
            renderer = Renderer.learnt(
                self.store, type_name, md5, definition, field=o.field,
                text_options=TextOptions(o.nostr, o.noarr, o.width, o.offset),
                csv_options=CsvOptions(o.nostr, o.noarr),
            )  # fmt: skip
            found = self.printers[key] = Printer(renderer, topic, o)
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
        from rostools.msgs.codec import DECODE_ERRORS, DecodeError, why_not

        limit = self.opts.count
        if printer.fast is not None and limit is None:
            try:
                texts: list[str] = printer.fast(frames)
            except (DecodeError, *DECODE_ERRORS):
                pass  # one at a time below, to say which message and print the others
            else:
                self.printed += len(texts)
                output.put("".join(texts))
                output.flush()
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
                        f"{why_not(err)}"
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
                output.put("".join(out))
                output.flush()
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
