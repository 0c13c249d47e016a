"""The reader and writer interfaces every format implements, and file opening helpers."""

from __future__ import annotations

import contextlib
import dataclasses
import mmap
import os
from abc import ABC, abstractmethod
from collections.abc import Callable, Collection, Iterable, Iterator, Mapping, Sequence
from pathlib import Path
from types import TracebackType
from typing import Any, Protocol

from rostools.bag.formats.model import (
    BagFormatError,
    BagInfo,
    BagNotFoundError,
    BagUnindexedError,
    BagUsageError,
    Connection,
    connection_from_header,
    lost_data,
)
from rostools.bag.formats.ordering import Block, Entry, RawMessage, ordered
from rostools.bag.formats.sink import Sink
from rostools.errors import InvalidDataError, cannot_write

#: Times are u32 seconds in a ``.bag`` and u64 ns in MCAP; this bound covers both.
MAX_TIME_NS = (1 << 64) - 1


def map_file(path: Path) -> tuple[mmap.mmap | None, int]:
    """The file mapped read-only, and its size (an empty file maps to None).

    Mapping lets the readers slice headers, indexes and uncompressed chunks without copies.
    """
    try:
        with path.open("rb") as f:
            size = os.fstat(f.fileno()).st_size
            if size == 0:
                return None, 0
            return mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ), size
    except FileNotFoundError:
        raise BagNotFoundError(f"no such file: {path}") from None
    except IsADirectoryError:
        raise BagFormatError(f"{path} is a directory, not a bag file") from None
    except OSError as err:
        raise InvalidDataError(f"cannot read {path}: {err.strerror or err}") from err


#: A streaming read hands mapped pages back to the kernel in steps of this many bytes.
FORGET_STEP = 16 << 20


class Forgetting:
    """Hands back the pages of a map that a streaming read has left behind.

    A read-only map of a 50 GB bag would otherwise grow the process's RSS to 50 GB as it is
    read. ``MADV_DONTNEED`` drops the pages from this process only: they stay in the page cache,
    and touching one again (a payload still queued for writing) reads it back.
    """

    def __init__(self, mm: mmap.mmap | None) -> None:
        self.mm = mm
        self.below = 0  # pages before this offset have been handed back

    def up_to(self, pos: int) -> None:
        """The read has moved on to ``pos``: hand back what lies ``FORGET_STEP`` before it."""
        if pos < self.below:  # a second pass starts again from the front
            self.below = pos - pos % mmap.PAGESIZE
        elif self.mm is not None and pos - self.below >= FORGET_STEP:
            end = pos - pos % mmap.PAGESIZE
            with contextlib.suppress(OSError, ValueError):
                self.mm.madvise(mmap.MADV_DONTNEED, self.below, end - self.below)
            self.below = end


def release(mm: mmap.mmap | None) -> None:
    """Unmap, unless yielded messages still point into the map (then the GC unmaps it)."""
    if mm is not None:
        with contextlib.suppress(BufferError):
            mm.close()


class BagReader(ABC):
    """A ``.bag`` or MCAP file opened for reading.

    ``connections`` lists every connection (MCAP: channel) in id order. ``messages`` yields
    ``(connection, time_ns, data)`` in time order with ``data`` the raw serialized message (a
    memoryview into the file or a decompressed chunk; never decoded). ``notes`` says how an
    unindexed, unfinished or inconsistent file was read (nothing lost); ``damage`` lists data
    that could not be read, which a read skips: it gives every message it can, and what it
    left out is in ``damage`` when it ends.
    """

    path: Path
    format: str
    indexed: bool
    connections: list[Connection]

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.connections = []
        self.indexed = False
        self.notes: list[str] = []
        self.damage: list[str] = []
        #: Why the file was read without its index (rosbag's "unindexed"): its note, or None
        self.unindexed: str | None = None

    def note(self, text: str) -> None:
        """Record how the file had to be read (no data lost)."""
        if text not in self.notes:
            self.notes.append(text)

    def read_unindexed(self, why: str, scanned: str = "it") -> None:
        """The index (MCAP: summary) cannot be used, for this reason: the file is scanned."""
        self.unindexed = f"unindexed: {why}; read by scanning {scanned}"
        self.note(self.unindexed)

    def damaged(self, text: str) -> None:
        """Record data that could not be read (reading a chunk twice records it once)."""
        if text not in self.damage:
            self.damage.append(text)

    @abstractmethod
    def info(self) -> BagInfo:
        """The summary ``bag info`` shows, from the index alone when there is one."""

    def messages(
        self,
        topics: Collection[str] | None = None,
        start: int | None = None,
        end: int | None = None,
        connections: Iterable[Connection] | None = None,
    ) -> Iterator[RawMessage]:
        """Messages in time order, optionally only some topics/connections and times.

        ``start`` and ``end`` are inclusive bounds in ns; None means unbounded (0 is a time).
        """
        return ordered(self._selected(topics, start, end, connections))

    def runs(
        self, connections: Iterable[Connection], start: int | None = None, end: int | None = None
    ) -> Iterator[Any]:
        """``messages`` of ``connections`` many at a time: (times ns, their data) per run.

        The times a numpy ``int64`` array, for readers of many messages that want no Python
        object per message (``bag export``): a ``.bag`` reads a chunk in one go.
        """
        from rostools.bag.formats.runs import runs_of

        return runs_of(self.messages(start=start, end=end, connections=connections))

    def entries(
        self,
        topics: Collection[str] | None = None,
        start: int | None = None,
        end: int | None = None,
    ) -> Iterator[Entry]:
        """Like ``messages``, as whole entries: MCAP's carry sequence and publish time too."""
        return ordered(self._selected(topics, start, end, None), whole=True)

    def _selected(
        self,
        topics: Collection[str] | None,
        start: int | None,
        end: int | None,
        connections: Iterable[Connection] | None,
    ) -> list[Block]:
        wanted = self.wanted(topics, connections)
        lo = 0 if start is None else start
        hi = MAX_TIME_NS if end is None else end
        everything = topics is None and connections is None
        return self.blocks(wanted, lo, hi, everything)

    @abstractmethod
    def blocks(
        self, wanted: Mapping[int, tuple[int, Connection]], lo: int, hi: int, everything: bool
    ) -> list[Block]:
        """The blocks that hold the wanted messages from ``lo`` to ``hi`` ns, each loaded lazily.

        ``everything``: no topic or connection was named, so every connection is wanted.
        """

    def times(self, topics: Collection[str] | None = None) -> Iterator[RawMessage]:
        """Like ``messages`` but the data may be left empty: for timing statistics only.

        Formats with a per-message index answer from it without reading the messages.
        """
        return self.messages(topics=topics)

    @abstractmethod
    def close(self) -> None:
        """Release the file."""

    def __enter__(self) -> BagReader:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    def wanted(
        self, topics: Collection[str] | None, connections: Iterable[Connection] | None
    ) -> Mapping[int, tuple[int, Connection]]:
        """Connection id -> (rank, connection) for the connections a read selects."""
        ids = None if connections is None else {c.id for c in connections}
        topic_set = None if topics is None else set(topics)
        return {
            c.id: (rank, c)
            for rank, c in enumerate(self.connections)
            if (topic_set is None or c.topic in topic_set) and (ids is None or c.id in ids)
        }


def problems(readers: Sequence[BagReader]) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """(notes, damage) of the readers so far, each naming its file."""
    notes = tuple(f"{r.path}: {n}" for r in readers for n in r.notes)
    return notes, tuple(f"{r.path}: {d}" for r in readers for d in r.damage)


#: What makes a file read without its index whole again, said with its note.
REBUILD_HINT = "`bag reindex` or `bag recover` makes it whole"


def after_reading(
    readers: Sequence[BagReader],
    done: str,
    say: Callable[[str], object],
    *,
    unindexed_fails: bool = False,
) -> None:
    """Hand each note of these readers to ``say``; raise if they left anything out.

    What a command does once it has read its bags: the error is ``BagDataLossError`` (exit
    code 6) naming what was left out; ``done`` says what the command did, for its line. A
    file read without its index is said in one line with ``REBUILD_HINT``; with
    ``unindexed_fails`` (``bag info``, as rosbag info) that line is a ``BagUnindexedError``
    (exit 1), unless data was lost too (exit 6).
    """
    notes, lost = problems(readers)
    cut = [f"{r.path}: {r.unindexed}" for r in readers if r.unindexed is not None]
    for note in notes:
        if note not in cut:
            say(note)
        elif lost or not unindexed_fails:
            say(f"{note}; {REBUILD_HINT}")
    if lost:
        raise lost_data(done, lost)
    if cut and unindexed_fails:
        raise BagUnindexedError("; ".join(cut) + f"; {REBUILD_HINT}")


class BagWriter(ABC):
    """A ``.bag`` or MCAP file being written.

    ``add_connection`` declares a publisher connection and returns its ``Connection`` (with
    the id in the file); ``write`` stores one raw message; ``close`` writes the index. Leaving
    a ``with`` block by an exception calls ``abort``. A format implements ``_declare`` (what a
    new connection needs in the file) and ``_store`` (one message), plus flush and close.
    """

    def __init__(self, path: str | Path, overwrite: bool) -> None:
        """Create the file; an existing one is refused unless ``overwrite``."""
        self.path = Path(path)
        flags = os.O_WRONLY | os.O_CREAT | (os.O_TRUNC if overwrite else os.O_EXCL)
        try:
            self._fd = os.open(self.path, flags, 0o644)
        except FileExistsError:
            raise BagUsageError(f"{self.path} exists; refusing to overwrite it") from None
        except OSError as err:
            # The path is the user's to fix (a missing folder, no permission): exit 2, as
            # every command's unwritable output
            folder = self.path.parent
            why = "no such folder" if not folder.is_dir() else err.strerror or str(err)
            raise cannot_write(self.path, f"{folder}: {why}") from err
        self._closed = False
        self._sink = Sink(self._fd, str(self.path))
        self._connections: list[Connection] = []
        self._by_header: dict[tuple[str, tuple[tuple[str, str], ...]], Connection] = {}

    def add_connection(
        self,
        topic: str,
        type: str,
        md5sum: str,
        definition: str,
        *,
        callerid: str = "",
        latching: bool = False,
        extra: Mapping[str, str] | None = None,
        absent: frozenset[str] = frozenset(),
    ) -> Connection:
        """Declare a connection; messages are written against the returned one."""
        return self.copy_connection(
            Connection(
                id=0,
                topic=topic,
                type=type,
                md5sum=md5sum,
                definition=definition,
                callerid=callerid,
                latching=latching,
                extra=extra or {},
                absent=absent,
            )
        )

    @abstractmethod
    def _declare(self, conn: Connection) -> None:
        """Prepare the file for a new connection (it may refuse with ``BagUsageError``)."""

    def write(self, conn: Connection, t_ns: int, data: bytes | bytearray | memoryview) -> None:
        """Store one serialized message of ``conn`` received at ``t_ns``."""
        cid = conn.id
        if self._closed or cid >= len(self._connections) or self._connections[cid] is not conn:
            self._check_open()
            raise BagUsageError(f"connection {cid} ({conn.topic}) was not added to this writer")
        self._store(cid, t_ns, data)

    @abstractmethod
    def _store(self, cid: int, t_ns: int, data: bytes | bytearray | memoryview) -> None:
        """Store one message of connection ``cid`` (already checked)."""

    def write_many(self, messages: Iterable[RawMessage], targets: Targets) -> int:
        """Store a stream of messages read from another bag; how many were written.

        ``targets`` maps source connections to this writer's (see ``Targets``).
        """
        self._check_open()
        ids: dict[int, int] = {}
        store = self._store
        n = 0
        for conn, t, data in messages:
            cid = ids.get(conn.id)
            if cid is None:
                cid = ids[conn.id] = self._target(targets, conn)
            store(cid, t, data)
            n += 1
        return n

    def _target(self, targets: Targets, conn: Connection) -> int:
        target = targets.resolve(conn)
        if target.id >= len(self._connections) or self._connections[target.id] is not target:
            raise BagUsageError(f"connection {target.id} was not added to this writer")
        return target.id

    def _check_open(self) -> None:
        if self._closed:
            raise BagUsageError(f"{self.path} is closed")

    def _release(self) -> None:
        """The file is finished (or given up): no more writes."""
        self._closed = True
        os.close(self._fd)

    @abstractmethod
    def flush(self) -> None:
        """Hand everything written so far to the OS: a killed writer then loses none of it."""

    @abstractmethod
    def close(self) -> None:
        """Finish the file: last chunk, index or summary, header."""

    def abort(self) -> None:
        """Stop writing and delete the unfinished file."""
        if not self._closed:
            self._release()
        with contextlib.suppress(FileNotFoundError):
            self.path.unlink()

    def connection_for(self, topic: str, header: Mapping[str, str]) -> Connection:
        """The connection for a publisher's connection header, declared on first use.

        What ``bag record`` needs: messages arriving with the same header on a topic share a
        connection; each other publisher (callerid, latching, definition) gets its own, as
        ``rosbag record`` keeps them.
        """
        key = (topic, tuple(sorted(header.items())))
        conn = self._by_header.get(key)
        if conn is None:
            conn = self.copy_connection(connection_from_header(0, topic, header))
            self._by_header[key] = conn
        return conn

    def copy_connection(self, conn: Connection) -> Connection:
        """Declare a connection identical to ``conn`` (from another bag) in this file."""
        self._check_open()
        copy = dataclasses.replace(conn, id=len(self._connections), extra=dict(conn.extra))
        self._declare(copy)
        self._connections.append(copy)
        return copy

    def __enter__(self) -> BagWriter:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        if exc_type is None:
            self.close()
        else:
            self.abort()


class Renaming(Protocol):
    """How a copy renames connections: ``bag.tools.rename.Renames`` (formats import no tool)."""

    def connection(self, conn: Connection) -> Connection:
        """``conn`` as it is written."""
        ...


class Targets(dict[int, Connection]):
    """Source connection id -> a writer's copy of that connection.

    ``resolve`` copies a connection on first use, so a stream whose reader meets a connection
    only while reading is still copied whole. ``renames`` renames topics and types on the way.
    """

    def __init__(
        self, writer: BagWriter, sources: Iterable[Connection] = (), renames: Renaming | None = None
    ) -> None:
        super().__init__()
        self.writer = writer
        self.renames = renames
        for conn in sources:
            self.resolve(conn)

    def resolve(self, conn: Connection) -> Connection:
        """The writer's connection for a source connection, copied if new."""
        target = self.get(conn.id)
        if target is None:
            named = self.renames.connection(conn) if self.renames else conn
            target = self[conn.id] = self.writer.copy_connection(named)
        return target
