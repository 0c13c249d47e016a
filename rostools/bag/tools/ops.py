"""Bag operations the CLI calls: convert, filter, compress, decompress.

Library functions: no printing. Each reads through ``open_bag`` and writes through
``open_writer``, so every combination of ``.bag`` and MCAP works; messages pass as raw bytes
unless a filter expression needs the decoded message. A failure deletes the partial output.
Damage in the input does not fail a copy: every message that reads is written, and the report
lists what was left out (``CopyReport.lost``).
"""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Callable, Collection, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rostools.bag.formats.access import (
    copy_extras,
    format_for_name,
    latched_before,
    mcap_profile,
    open_bag,
    open_writer,
    require_ros1,
)
from rostools.bag.formats.base import BagReader, BagWriter, Targets, problems
from rostools.bag.formats.model import (
    BagUsageError,
    Connection,
    UnsupportedBagError,
    counted,
    lost_data,
)
from rostools.bag.formats.ordering import RawMessage
from rostools.bag.tools.options import ALL, PROGRESS_EVERY, CopyOptions, Progress
from rostools.errors import RostoolsError
from rostools.msgs.expr import Expression, compile_expression

if TYPE_CHECKING:
    from rostools.bag.formats.ros2 import ToRos1


@dataclass(frozen=True)
class CopyReport:
    """What a convert, filter or (de)compress wrote."""

    source: Path
    output: Path
    format: str
    compression: str
    messages_read: int
    messages_written: int
    connections: int
    #: MCAP attachments and metadata records copied, and left out (see ``copy_extras``).
    extras_copied: int = 0
    extras_left_out: int = 0
    #: How the inputs had to be read, and what of them could not be (``BagReader``), each
    #: naming its file.
    notes: tuple[str, ...] = ()
    lost: tuple[str, ...] = ()

    def raise_if_lost(self) -> None:
        """Raise ``BagDataLossError`` (exit code 6) naming what was left out, if anything."""
        if self.lost:
            raise lost_data(
                f"wrote {counted(self.messages_written, 'message')} to {self.output}", self.lost
            )


def convert(
    src: str | Path,
    dst: str | Path,
    options: CopyOptions = ALL,
    *,
    format: str | None = None,
    progress: Progress | None = None,
) -> CopyReport:
    """Copy every connection and message of ``src`` into ``dst`` (``.bag`` <-> MCAP).

    Lossless in connection headers (callerid, latching, definitions, extra fields), message
    bytes and times. The output format follows ``dst``'s name unless ``format`` is given.
    ``options`` may select and rename as for ``filter_bag``; every connection is copied.
    """
    return _copy(src, dst, options, format, progress, eager=True)


def compress(
    src: str | Path,
    dst: str | Path,
    options: CopyOptions = ALL,
    *,
    progress: Progress | None = None,
) -> CopyReport:
    """Rewrite a bag with chunks compressed as ``options.compression`` says.

    ``.bag``: bz2 (the default) or lz4; MCAP: zstd (the default) or lz4.
    """
    fmt = _same_format(src)
    if options.compression is None:
        options = dataclasses.replace(options, compression="bz2" if fmt == "bag" else "zstd")
    return _copy(src, dst, options, fmt, progress, eager=True)


def decompress(
    src: str | Path,
    dst: str | Path,
    options: CopyOptions = ALL,
    *,
    progress: Progress | None = None,
) -> CopyReport:
    """Rewrite a bag with uncompressed chunks (``options.compression`` must be None or none)."""
    if options.compression not in (None, "none"):
        raise BagUsageError(f"decompress writes no compression, not {options.compression}")
    options = dataclasses.replace(options, compression="none")
    return _copy(src, dst, options, _same_format(src), progress, eager=True)


def _same_format(src: str | Path) -> str:
    from rostools.bag.formats.access import detect_format

    return detect_format(src)


def filter_bag(
    src: str | Path,
    dst: str | Path,
    options: CopyOptions = ALL,
    *,
    progress: Progress | None = None,
    show: tuple[str, Callable[[bool, Any], None]] | None = None,
    latched: bool = False,
) -> CopyReport:
    """Copy the messages of ``src`` that ``options`` select into ``dst``.

    ``options.topics`` and ``start``/``end`` (inclusive, ns) select without decoding.
    ``options.expression`` is Python over ``topic``, ``m`` and ``t`` as in ``rosbag filter``
    (``t`` has ``secs``, ``nsecs``, ``to_sec()``); a message is decoded only when the
    expression mentions ``m``. ``show`` is rosbag filter's ``--print``: an expression over the
    same names, whose value goes to the callback with the verdict for every message the
    expression judges. ``latched`` also copies, stamped at ``start``, the last message before
    ``start`` of every latched connection, so the cut file starts with what a late subscriber
    would have had. Only connections that keep a message are written. The output format
    follows ``dst``. ``options.renames`` renames topics and types as they are written:
    ``topics`` and ``expression`` see the names in ``src``.
    """
    return _copy(src, dst, options, None, progress, eager=False, show=show, latched=latched)


# Filter is the public name the CLI uses; ``filter`` shadows a builtin inside this module only.
filter = filter_bag


@dataclass
class _Filter:
    """A compiled filter expression (and ``--print``'s) and the decoders it needs."""

    keep: Expression
    show: tuple[Expression, Callable[[bool, Any], None]] | None = None
    decoders: dict[int, Callable[[Any], Any]] = field(default_factory=dict)

    def __call__(self, conn: Connection, t_ns: int, data: memoryview) -> bool:
        from rostools.msgs.message import Time

        needs = self.keep.needs_message or (self.show is not None and self.show[0].needs_message)
        msg = self._decode(conn, data) if needs else None
        t = Time.from_nsec(t_ns)
        verdict = bool(self.keep(conn.topic, msg, t))
        if self.show is not None:
            self.show[1](verdict, self.show[0](conn.topic, msg, t))
        return verdict

    def _decode(self, conn: Connection, data: memoryview) -> Any:
        decode = self.decoders.get(conn.id)
        if decode is None:
            decode = self.decoders[conn.id] = _decoder(conn)
        return decode(data)


def compile_filter(
    expression: str, show: tuple[str, Callable[[bool, Any], None]] | None = None
) -> Callable[[Connection, int, memoryview], bool]:
    """A predicate over (connection, time ns, raw data) from a ``rosbag filter`` expression.

    ``show`` is (expression, callback): see ``filter_bag``.
    """
    keep = compile_expression(expression, "filter expression")
    if show is None:
        return _Filter(keep)
    return _Filter(keep, (compile_expression(show[0], "--print expression"), show[1]))


def _decoder(conn: Connection) -> Callable[[Any], Any]:
    """Decode a connection's messages with the definition stored in the bag."""
    from rostools.msgs import learnt
    from rostools.msgs.store import TypeStore

    try:
        codec = learnt.codec(TypeStore.default(), conn.type, conn.md5sum, conn.definition)
        codec.decoder(conn.type)
    except RostoolsError as err:
        raise UnsupportedBagError(
            f"cannot decode {conn.topic} ({conn.type}) for the filter expression: {err}"
        ) from err

    def decode(data: Any) -> Any:
        return codec.decode(conn.type, data)

    return decode


def _copy(
    src: str | Path,
    dst: str | Path,
    options: CopyOptions,
    format: str | None,
    progress: Progress | None,
    *,
    eager: bool,
    show: tuple[str, Callable[[bool, Any], None]] | None = None,
    latched: bool = False,
) -> CopyReport:
    """``src`` into ``dst``; ``eager`` copies every connection, not only those written."""
    expression = options.expression
    keep = compile_filter(expression or "True", show) if expression or show else None
    topics, start, end, renames = options.topics, options.start, options.end, options.renames
    compression = options.compression
    src, dst = Path(src), Path(dst)
    if dst.exists() and src.resolve() == dst.resolve():
        raise BagUsageError(f"cannot use the same file as input and output: {src}")
    kind = format or format_for_name(dst)
    with open_bag(src, check_crcs=options.check_crcs) as reader:
        to_ros1 = _ros2_to_ros1(reader, kind, topics, keep is not None)
        total = reader.info().message_count
        profile = mcap_profile([reader], topics)
        writer = open_writer(
            dst, kind, compression, options.chunk_size, overwrite=options.overwrite,
            profile=profile,
        )  # fmt: skip
        try:
            stream = reader.messages(topics=topics, start=start, end=end)
            if latched and start is not None:
                kept = [(c, start, d) for c, _, d in latched_before([reader], topics, start)]
                stream = itertools.chain(kept, stream)
            sources = reader.connections if eager else []
            if to_ros1 is not None:
                stream = ((to_ros1.connection(c), t, to_ros1.message(c, d)) for c, t, d in stream)
                sources = [to_ros1.connection(c) for c in sources]
            whole = eager and not renames and not to_ros1 and not options.selects
            out = Targets(writer, sources, renames)
            read, written, conns = _pump(reader, writer, out, stream, whole, keep, progress, total)
            extras = copy_extras(reader, writer, start, end)
        except BaseException:
            writer.abort()
            raise
        writer.close()
        notes, lost = problems([reader])
    return CopyReport(
        source=src,
        output=dst,
        format=kind,
        compression=getattr(writer, "compression", compression or ""),
        messages_read=read,
        messages_written=written,
        connections=conns,
        extras_copied=extras[0],
        extras_left_out=extras[1],
        notes=notes,
        lost=lost,
    )


def _ros2_to_ros1(
    reader: BagReader, kind: str, topics: Collection[str] | None, decodes: bool
) -> ToRos1 | None:
    """ROS 2 CDR into a .bag: its ROS 1 twins; anything else not ROS 1 is refused in one line.

    An MCAP output takes every encoding as it is, unless a filter expression ``decodes``.
    """
    from rostools.bag.formats.ros2 import ToRos1, cdr_connections

    if kind == "mcap":
        if decodes:
            require_ros1(reader, "a filter expression", topics)
        return None
    cdr = cdr_connections(reader, topics) if kind == "bag" else set()
    if not cdr:
        require_ros1(reader, f"writing to .{kind}", topics)
        return None
    others = [c.topic for c in reader.connections if c.id not in cdr]
    if topics is not None:
        others = [t for t in others if t in topics]
    if others:
        require_ros1(reader, f"writing to .{kind}", others)
    return ToRos1(cdr)


def _pump(
    reader: BagReader,
    writer: BagWriter,
    out: Targets,
    stream: Iterator[RawMessage],
    whole: bool,
    keep: Callable[[Connection, int, memoryview], bool] | None,
    progress: Progress | None,
    total: int,
) -> tuple[int, int, int]:
    """Copy a message stream; (messages read, messages written, connections written).

    ``whole``: every message, with its connection as it is, so chunks may be copied whole.
    """
    if keep is None:
        written = None
        if whole:
            written = _chunk_for_chunk(reader, writer, out, progress, total)
        if written is None:
            counted = stream if progress is None else _counting(stream, progress, total)
            written = writer.write_many(counted, out)
        if progress is not None:
            progress(written, total)
        return written, written, len(out)
    write = writer.write
    read = written = 0
    for conn, t, data in stream:
        read += 1
        if progress is not None and read % PROGRESS_EVERY == 0:
            progress(read, total)
        if keep is not None and not keep(conn, t, data):
            continue
        write(out.get(conn.id) or out.resolve(conn), t, data)
        written += 1
    if progress is not None:
        progress(read, total)
    return read, written, len(out)


def _counting(stream: Iterator[RawMessage], progress: Progress, total: int) -> Iterator[RawMessage]:
    """The stream, calling ``progress`` every ``PROGRESS_EVERY`` messages."""
    for done, message in enumerate(stream, 1):
        if done % PROGRESS_EVERY == 0:
            progress(done, total)
        yield message


def _chunk_for_chunk(
    reader: BagReader, writer: BagWriter, targets: Targets, progress: Progress | None, total: int
) -> int | None:
    """The whole-file .bag -> MCAP copy without per-message work, when it applies."""
    from rostools.bag.formats.mcap_writer import McapWriter
    from rostools.bag.formats.rosbag1_reader import Bag1Reader

    if isinstance(reader, Bag1Reader) and isinstance(writer, McapWriter):
        from rostools.bag.formats.fastcopy import convert_chunks

        report = None if progress is None else (lambda done: progress(done, total))
        return convert_chunks(reader, writer, targets, report)
    return None
