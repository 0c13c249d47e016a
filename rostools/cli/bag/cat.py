"""``rostools bag cat``: the messages of bags as NDJSON (or CSV), in time order across files.

One JSON object per message: ``topic``, ``type``, ``log_time`` (ns), ``publish_time`` and
``sequence`` where the file has them (MCAP), ``stamp`` (``header.stamp`` in ns) where the
message has one, and ``msg``, the decoded message (``data``, base64 bytes, with ``--raw``).
The field names are those of ``mcap cat --json`` where they overlap.
"""

from __future__ import annotations

import contextlib
import enum
import heapq
from collections.abc import Callable, Iterator
from operator import itemgetter
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rostools.bag.formats.model import counted
from rostools.cli import output
from rostools.cli.bag.options import EndOpt, FilterExprOpt, StartOpt
from rostools.cli.bag.shared import check_read, time_window
from rostools.cli.common import NoCrcCheckOpt
from rostools.cli.declare import command
from rostools.cli.render import Renderer
from rostools.errors import InvalidDataError, UsageError

if TYPE_CHECKING:
    from rostools.bag.formats.base import BagReader
    from rostools.bag.formats.model import Connection
    from rostools.bag.formats.ordering import Entry
    from rostools.bag.formats.ros2 import Ros2Types


#: Lines are written in batches of this many, or of this many characters, whichever is first.
FLUSH_LINES = 512
FLUSH_BYTES = 1 << 20


class CatFormat(str, enum.Enum):
    """What ``bag cat`` prints."""

    json = "json"
    csv = "csv"


class _Lines:
    """One connection's messages as ``bag cat`` lines: its ``Renderer`` in cat's envelope.

    ``ros2``: the connection's messages are CDR, decoded through these types.
    """

    def __init__(self, conn: Connection, raw: bool, ros2: Ros2Types | None = None) -> None:
        from rostools.msgs import plain
        from rostools.msgs.store import TypeStore

        self.raw = raw
        self.head = plain.dumps({"topic": conn.topic, "type": conn.type})[:-1]
        if raw:
            return  # bytes as they are: no definition needed
        if ros2 is not None:
            self._ros2(conn, ros2)
            return
        # The bag's definition first; a bag that left it out falls back to the built-in types.
        self.renderer = Renderer.learnt(
            TypeStore.default(), conn.type, conn.md5sum, conn.definition
        )
        self.decode = self.renderer.decode
        self.as_json = self.renderer.json
        self.stamp = self.renderer.stamp

    def _ros2(self, conn: Connection, types: Ros2Types) -> None:
        from rostools.bag.formats import ros2
        from rostools.msgs.plain import dumps

        types.learn(conn.type, conn.definition)
        kind = conn.type
        self.decode = lambda data, _: (types.decode(kind, data), len(data))
        self.as_json = lambda msg: dumps(ros2.plain(msg))
        self.stamp = ros2.stamp_ns

    def json(self, entry: Entry) -> str:
        """One NDJSON line."""
        times = f',"log_time":{entry[0]}'
        if len(entry) == 7:
            times += f',"publish_time":{entry[6]},"sequence":{entry[5]}'
        if self.raw:
            import base64

            return f'{self.head}{times},"data":"{base64.b64encode(entry[4]).decode()}"}}\n'
        msg = self.decode(entry[4], 0)[0]
        stamp = self.stamp(msg)
        if stamp is not None:
            times += f',"stamp":{stamp}'
        return f'{self.head}{times},"msg":{self.as_json(msg)}}}\n'

    def csv(self, t: int, data: Any, header: bool) -> str:
        """One CSV line (the time, then the row), after the header if ``header``."""
        msg = self.decode(data, 0)[0]
        line = f"{t},{self.renderer.csv_row(msg, 0)}\n"
        return self.renderer.csv_header(msg) + "\n" + line if header else line


def _entries(
    readers: list[BagReader], topics: list[str] | None, lo: int | None, hi: int | None
) -> Iterator[tuple[int, int, Entry]]:
    """(time, input index, entry) of every message, in time order (ties: argument order)."""

    def tagged(i: int, reader: BagReader) -> Iterator[tuple[int, int, Entry]]:
        for e in reader.entries(topics=topics, start=lo, end=hi):
            yield e[0], i, e

    if len(readers) == 1:
        return tagged(0, readers[0])
    return heapq.merge(*(tagged(i, r) for i, r in enumerate(readers)), key=itemgetter(0, 1))


@command()
def cat(
    args: Annotated[
        list[str], typer.Argument(help="Bags (.bag, .mcap), then topics (default: all).")
    ],
    fmt: Annotated[
        CatFormat, typer.Option("--format", "-F", help="json (NDJSON) or csv (one topic).")
    ] = CatFormat.json,
    raw: Annotated[bool, typer.Option("--raw", help="Base64 bytes instead of decoding.")] = False,
    count: Annotated[int | None, typer.Option("-n", help="Stop after N messages.")] = None,
    start: StartOpt = None,
    end: EndOpt = None,
    expression: FilterExprOpt = None,
    no_crc_check: NoCrcCheckOpt = False,
) -> None:
    """Print the messages of bags, one JSON object per line, in time order across files."""
    from rostools.bag.formats.access import open_bag
    from rostools.bag.tools.ops import compile_filter

    paths = [Path(a) for a in args if not (a.startswith("/") and not Path(a).is_file())]
    topics = [a for a in args if a.startswith("/") and not Path(a).is_file()] or None
    if not paths:
        raise UsageError("give at least one bag")
    if count is not None and count < 0:
        raise UsageError("-n cannot be negative")
    if raw and fmt is CatFormat.csv:
        raise UsageError("--raw goes with JSON, not CSV")
    with contextlib.ExitStack() as stack:
        readers = [stack.enter_context(open_bag(p, check_crcs=not no_crc_check)) for p in paths]
        cdr = [_cdr_connections(r, topics, fmt, raw) for r in readers]
        if fmt is CatFormat.csv:
            found = {
                c.topic for r in readers for c in r.connections if not topics or c.topic in topics
            }
            if len(found) != 1:
                raise UsageError(
                    f"--format csv prints one topic; give one of: {', '.join(sorted(found))}"
                )
        lo, hi = time_window(paths, start, end)
        keeps = [compile_filter(expression) if expression else None for _ in readers]
        if expression and any(cdr):
            raise UsageError("--filter reads ROS 1 messages only; this selection has ROS 2 ones")
        printed = _print(readers, cdr, topics, lo, hi, keeps, fmt, raw, count)
        check_read(readers, f"printed {counted(printed, 'message')}")


def _cdr_connections(
    reader: BagReader, topics: list[str] | None, fmt: CatFormat, raw: bool
) -> set[int]:
    """The connections of ``reader`` whose messages are ROS 2 CDR.

    Encodings that are neither ROS 1 nor CDR are refused in one line (``--raw`` prints any).
    """
    from rostools.bag.formats.mcap_reader import McapReader
    from rostools.bag.formats.model import UnsupportedBagError
    from rostools.bag.formats.ros2 import cdr_connections

    if raw or not isinstance(reader, McapReader):
        return set()
    found = cdr_connections(reader, topics)
    for c in reader.channels.values():
        if c.message_encoding in ("ros1", "cdr") or (topics and c.topic not in topics):
            continue
        raise UnsupportedBagError(
            f"{reader.path}: {c.topic} holds {c.message_encoding!r} messages, which bag cat "
            "does not decode (--raw prints them as bytes)"
        )
    if found and fmt is CatFormat.csv:
        raise UsageError("--format csv reads ROS 1 messages only; use JSON for ROS 2 ones")
    return found


def _print(
    readers: list[BagReader],
    cdr: list[set[int]],
    topics: list[str] | None,
    lo: int | None,
    hi: int | None,
    keeps: list[Callable[[Connection, int, memoryview], bool] | None],
    fmt: CatFormat,
    raw: bool,
    count: int | None,
) -> int:
    """Print the messages; how many."""
    from rostools.bag.formats.ros2 import Ros2Types

    lines: dict[tuple[int, int], _Lines] = {}
    ros2_types: dict[int, Ros2Types] = {}
    out: list[str] = []
    write = output.put
    printed = pending = 0
    header_done = False
    for t, i, e in _entries(readers, topics, lo, hi):
        if count is not None and printed >= count:
            break
        conn = e[3]
        keep = keeps[i]
        if keep is not None and not keep(conn, t, e[4]):
            continue
        render = lines.get((i, conn.id))
        if render is None:
            types = ros2_types.setdefault(i, Ros2Types()) if conn.id in cdr[i] else None
            render = lines[(i, conn.id)] = _Lines(conn, raw, types)
        try:
            if fmt is CatFormat.json:
                line = render.json(e)
            else:
                line = render.csv(t, e[4], not header_done)
                header_done = True
        except InvalidDataError as err:  # say where: the file, the topic and the time
            write("".join(out))
            raise InvalidDataError(
                f"{readers[i].path}: {conn.topic} at {t / 1e9:.9f} s: {err}"
            ) from err
        out.append(line)
        pending += len(line)
        printed += 1
        if len(out) >= FLUSH_LINES or pending >= FLUSH_BYTES:  # memory stays flat for images
            write("".join(out))
            out.clear()
            pending = 0
    write("".join(out))
    return printed
