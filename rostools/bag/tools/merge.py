"""``bag merge``: several bags into one, in time order, streaming.

Connections are deduplicated by (topic, type, md5sum, callerid) after renaming: the same
publisher recorded in two files is one connection in the output. Two inputs that give a topic
two different types are refused before anything is written. Library code: no printing.
"""

from __future__ import annotations

import contextlib
import heapq
from collections.abc import Callable, Collection, Iterator, Sequence
from operator import itemgetter
from pathlib import Path
from typing import TYPE_CHECKING

from rostools.bag.formats.access import (
    copy_extras,
    format_for_name,
    mcap_profile,
    open_bag,
    open_writer,
    require_ros1,
)
from rostools.bag.formats.base import BagReader, BagWriter, Targets, problems
from rostools.bag.formats.model import BagUsageError, Connection
from rostools.bag.tools.ops import CopyReport, compile_filter
from rostools.bag.tools.options import ALL, PROGRESS_EVERY, CopyOptions, Progress

if TYPE_CHECKING:
    from rostools.bag.tools.rename import Renames

#: A connection as merging tells connections apart.
Key = tuple[str, str, str, str]


class _Shared(Targets):
    """One input's connections, mapped onto the output's deduplicated ones."""

    def __init__(
        self, writer: BagWriter, renames: Renames | None, seen: dict[Key, Connection]
    ) -> None:
        self.seen = seen
        super().__init__(writer, (), renames)

    def resolve(self, conn: Connection) -> Connection:
        """The output's connection for ``conn``: an equal one already written, or a copy."""
        target = self.get(conn.id)
        if target is None:
            named = self.renames.connection(conn) if self.renames else conn
            key = (named.topic, named.type, named.md5sum, named.callerid)
            target = self.seen.get(key)
            if target is None:
                target = self.seen[key] = self.writer.copy_connection(named)
            self[conn.id] = target
        return target


def check_types(
    readers: Sequence[BagReader], renames: Renames | None, topics: Collection[str] | None = None
) -> None:
    """Refuse inputs that give one (renamed) topic two types, naming both files."""
    first: dict[str, tuple[str, Path]] = {}
    for reader in readers:
        for conn in reader.connections:
            if topics is not None and conn.topic not in topics:
                continue
            named = renames.connection(conn) if renames else conn
            kind, where = first.setdefault(named.topic, (named.type, reader.path))
            if kind != named.type:
                raise BagUsageError(
                    f"topic {named.topic} is {kind} in {where} but {named.type} in "
                    f"{reader.path}: a merged bag has one type per topic"
                )


def merge(
    sources: Sequence[str | Path],
    dst: str | Path,
    options: CopyOptions = ALL,
    *,
    progress: Progress | None = None,
) -> CopyReport:
    """Write the messages of every source into ``dst``, in time order (ties: argument order).

    ``options`` select as in ``ops.filter_bag``, on the input's names; their renames apply as
    messages are written. MCAP attachments and metadata of every input are copied into an
    MCAP output.
    """
    topics, start, end, renames = options.topics, options.start, options.end, options.renames
    expression = options.expression
    paths, dst = _checked_paths(sources, Path(dst))
    with contextlib.ExitStack() as stack:
        readers = [stack.enter_context(open_bag(p, check_crcs=options.check_crcs)) for p in paths]
        kind = format_for_name(dst)
        if kind != "mcap" or expression:  # an MCAP output takes any encoding as it is
            for reader in readers:
                require_ros1(reader, "bag merge", topics)
        check_types(readers, renames, topics)
        total = sum(r.info().message_count for r in readers)
        profile = mcap_profile(readers, topics)
        writer = open_writer(
            dst, kind, options.compression, options.chunk_size, overwrite=options.overwrite,
            profile=profile,
        )  # fmt: skip
        try:
            seen: dict[Key, Connection] = {}
            streams = [
                _stream(r, _Shared(writer, renames, seen), topics, start, end, expression)
                for r in readers
            ]
            read, written = _write(writer, heapq.merge(*streams, key=itemgetter(1)), progress,
                                   total)  # fmt: skip
            extras = [copy_extras(r, writer, start, end) for r in readers]
        except BaseException:
            writer.abort()
            raise
        writer.close()
        notes, lost = problems(readers)
    return CopyReport(
        source=paths[0],
        output=dst,
        format=kind,
        compression=getattr(writer, "compression", options.compression or ""),
        messages_read=read,
        messages_written=written,
        connections=len(seen),
        extras_copied=sum(e[0] for e in extras),
        extras_left_out=sum(e[1] for e in extras),
        notes=notes,
        lost=lost,
    )


def _checked_paths(sources: Sequence[str | Path], dst: Path) -> tuple[list[Path], Path]:
    """The inputs as paths, and the output; none of them the output itself."""
    paths = [Path(s) for s in sources]
    if not paths:
        raise BagUsageError("give at least one bag to merge")
    for path in paths:
        if dst.exists() and path.resolve() == dst.resolve():
            raise BagUsageError(f"cannot use the same file as input and output: {path}")
    return paths, dst


#: (output connection, time ns, data, whether the filter kept it)
_Item = tuple[Connection, int, memoryview, bool]


def _stream(
    reader: BagReader,
    targets: Targets,
    topics: Collection[str] | None,
    start: int | None,
    end: int | None,
    expression: str | None,
) -> Iterator[_Item]:
    """One input's messages, with the output's connections.

    Messages the filter rejects are marked, not dropped: they still count as read.
    """
    keep: Callable[[Connection, int, memoryview], bool] | None = (
        compile_filter(expression) if expression else None  # per input: ids are per file
    )
    resolve = targets.resolve
    for conn, t, data in reader.messages(topics=topics, start=start, end=end):
        kept = keep is None or keep(conn, t, data)
        yield (resolve(conn) if kept else conn), t, data, kept


def _write(
    writer: BagWriter, items: Iterator[_Item], progress: Progress | None, total: int
) -> tuple[int, int]:
    write = writer.write
    read = written = 0
    for conn, t, data, kept in items:
        read += 1
        if kept:
            write(conn, t, data)
            written += 1
        if progress is not None and read % PROGRESS_EVERY == 0:
            progress(read, total)
    if progress is not None:
        progress(read, total)
    return read, written
