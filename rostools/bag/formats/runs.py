"""Messages many at a time, as numpy arrays: ``Run``, and a ``.bag``'s chunks read as runs.

For readers of many messages that want no Python object per message (``bag export``). A run
is messages in time order: their times, and their bytes where they lie in a buffer (a chunk's
records), which ``rows`` copies out as one 2-D array when every message has one size.

``chunk_arrays`` does what ``checked_entries`` does a message at a time, in one numpy pass:
each index entry's record must be a message of its connection and time laid out as rosbag
writes them (a 38-byte header), inside the chunk, no two entries at one record. Anything else
raises ``Irregular``, and ``bag_runs`` reads that chunk the careful way (``checked_entries``,
then a walk), which says what was wrong: so both ways give the same messages.
"""

from __future__ import annotations

import functools
import itertools
from collections.abc import Iterator, Mapping, Sequence
from typing import Any, Protocol

import numpy as np
from numpy.lib.stride_tricks import as_strided

from rostools.bag.formats import rosbag1_format as fmt
from rostools.bag.formats.model import BagFormatError, Connection
from rostools.bag.formats.ordering import Block, ordered
from rostools.bag.formats.rosbag1_index import record_prefixes

#: An index entry: its time as the u64 a time field reads as (secs | nsecs << 32), its offset.
_ENTRY = np.dtype([("t", "<u8"), ("off", "<u4")])
_HEAD = 46  # bytes of a 38-byte-header message record before its data
_SPAN = np.arange(_HEAD, dtype=np.int64)
_NS = np.uint64(1_000_000_000)
_LOW = np.uint64(0xFFFFFFFF)
#: Messages of at most this size are copied out with their record headers, in one pass, for
#: ``Run.rows`` (what fixed-layout types are: Imu, Odometry; bigger ones are not read so).
ROW_BYTES = 4096


class Irregular(Exception):  # noqa: N818 - not an error: the careful reader takes the chunk
    """The chunk is not as rosbag writes one; read it entry by entry."""


@functools.lru_cache(maxsize=1024)
def _layouts(conn_id: int) -> np.ndarray:
    """The 34 bytes a message record of ``conn_id`` starts with in rosbag's two layouts."""
    return np.frombuffer(b"".join(record_prefixes(conn_id)), np.uint8).reshape(2, 34)


def chunk_arrays(
    buf: Any,
    base: int,
    end: int,
    records: Sequence[tuple[int, memoryview]],
    counts: Mapping[int, int],
    wanted: Mapping[int, tuple[int, Connection]],
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
    """(times ns, data starts, data lengths, rows) of the wanted messages of a chunk.

    In time order; ``rows`` their bytes as one 2-D array when they share a size of at most
    ``ROW_BYTES``, else None.

    ``buf[base:end]`` holds the chunk's records, ``records`` are its index records and
    ``counts`` its chunk info's messages per connection. Ties in time go by the connection's
    rank, then by position, as ``checked_entries`` sorts them.
    """
    found = {conn_id: len(raw) // fmt.INDEX_ENTRY_SIZE for conn_id, raw in records}
    if found != dict(counts) or len(found) != len(records):
        raise Irregular("the index records are not those of the chunk info")
    data = np.frombuffer(buf, np.uint8)
    parts: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = []
    blocks: list[np.ndarray | None] = []
    for conn_id, raw in records:
        if conn_id not in wanted or not len(raw):
            continue
        entries = np.frombuffer(raw, _ENTRY)
        pos = entries["off"].astype(np.int64) + base
        # Rising offsets: no two entries at one record (a record is of one connection).
        if int(pos[-1]) + _HEAD > end or (len(pos) > 1 and not (np.diff(pos) > 0).all()):
            raise Irregular("the entries do not point at records one for one, in order")
        # The records with the first one's size, when small: one strided copy per stretch of
        # records a step apart, headers and data at once.
        size = int.from_bytes(buf[int(pos[0]) + 42 : int(pos[0]) + _HEAD], "little")
        block = None
        if size <= ROW_BYTES and int(pos[-1]) + _HEAD + size <= end:
            block = _gather(data, pos, _HEAD + size)
            heads = block[:, :_HEAD]
        else:
            heads = data[pos[:, None] + _SPAN]
        layouts = _layouts(conn_id)
        if not (heads[:, :34] == layouts[0]).all() and not (heads[:, :34] == layouts[1]).all():
            raise Irregular("a record is not laid out as rosbag writes them")
        tail = np.ascontiguousarray(heads[:, 34:])
        stamps = tail[:, :8].view("<u8").reshape(-1)
        lengths = tail[:, 8:].view("<u4").reshape(-1).astype(np.int64)
        starts = pos + _HEAD
        if (stamps != entries["t"]).any() or int((starts + lengths).max()) > end:
            raise Irregular("an entry's time or length is not its record's")
        times = ((stamps & _LOW) * _NS + (stamps >> np.uint64(32))).astype(np.int64)
        rank = np.full(len(times), wanted[conn_id][0], np.int64)
        parts.append((times, rank, starts, lengths))
        blocks.append(block[:, _HEAD:] if block is not None and (lengths == size).all() else None)
    if not parts:
        empty = np.zeros(0, np.int64)
        return empty, empty, empty, None
    if len(parts) == 1 and (np.diff(parts[0][0]) >= 0).all():
        return parts[0][0], parts[0][2], parts[0][3], blocks[0]  # in time order already
    times, ranks, starts, lengths = (np.concatenate(column) for column in zip(*parts, strict=True))
    order = np.lexsort((starts, ranks, times))
    rows: np.ndarray | None = None
    if (
        all(b is not None for b in blocks)
        and len({b.shape[1] for b in blocks if b is not None}) == 1
    ):
        rows = np.concatenate(blocks)[order]  # type: ignore[arg-type]
    return times[order], starts[order], lengths[order], rows


#: Messages per run when a run is cut from a stream of messages.
RUN_MESSAGES = 4096


class Run:
    """Messages in time order: ``times`` (ns, ``int64``) and their bytes.

    The bytes are ``data`` (a list of buffers), or ``lengths`` bytes at ``starts`` in ``buf``
    (a chunk), viewed only when asked for.
    """

    def __init__(
        self,
        times: np.ndarray,
        data: list[memoryview] | None = None,
        buf: Any = None,
        starts: np.ndarray | None = None,
        lengths: np.ndarray | None = None,
        rows: np.ndarray | None = None,
    ) -> None:
        self.times, self._data, self.buf = times, data, buf
        self.starts, self.lengths = starts, lengths
        self._rows = rows  # the bytes as one 2-D array, when the reader copied them out so

    def __len__(self) -> int:
        return len(self.times)

    def data(self) -> list[memoryview]:
        """Each message's bytes."""
        if self._data is None:
            assert self.starts is not None and self.lengths is not None
            view = memoryview(self.buf)
            ends = (self.starts + self.lengths).tolist()
            self._data = [view[a:b] for a, b in zip(self.starts.tolist(), ends, strict=True)]
        return self._data

    def sizes(self) -> np.ndarray:
        """Each message's length in bytes."""
        if self.lengths is None:
            self.lengths = np.fromiter(map(len, self.data()), np.int64, len(self))
        return self.lengths

    def part(self, i: int, j: int) -> Run:
        """Messages ``i`` to ``j`` (excluded)."""
        if self._data is not None:
            part = Run(self.times[i:j], self._data[i:j])
            part.lengths = None if self.lengths is None else self.lengths[i:j]
            return part
        assert self.starts is not None and self.lengths is not None
        rows = None if self._rows is None else self._rows[i:j]
        return Run(self.times[i:j], None, self.buf, self.starts[i:j], self.lengths[i:j], rows)

    def rows(self, size: int) -> np.ndarray | None:
        """The messages as one ``(count, size)`` byte array, or None if one is not ``size``."""
        if self._rows is not None and self._rows.shape[1] == size:
            return self._rows
        if len(self) and (self.sizes() != size).any():
            return None
        if self.starts is None:
            return np.frombuffer(b"".join(self.data()), np.uint8).reshape(len(self), size)
        return _gather(np.frombuffer(self.buf, np.uint8), self.starts, size)


def _gather(data: np.ndarray, starts: np.ndarray, size: int) -> np.ndarray:
    """``size`` bytes at each of ``starts``: records a fixed step apart are one strided copy."""
    out = np.empty((len(starts), size), np.uint8)
    if len(starts) == 0:
        return out
    steps = np.diff(starts)
    # Where the step changes: each stretch between two is one strided copy.
    cuts = np.flatnonzero(steps[1:] != steps[:-1]) + 1
    if len(cuts) > len(starts) // 8:  # no stretches to speak of: an index per byte
        return data[starts[:, None] + np.arange(size)]
    bounds = [0, *cuts.tolist(), len(steps)]
    for a, b in itertools.pairwise(bounds):
        if b > a:
            step = int(steps[a])
            first = int(starts[a])
            out[a:b] = as_strided(data[first:], shape=(b - a, size), strides=(step, 1))
    last = int(starts[-1])
    out[-1] = data[last : last + size]
    return out


def runs_of(messages: Iterator[tuple[Connection, int, memoryview]]) -> Iterator[Run]:
    """A message stream cut into runs of ``RUN_MESSAGES``."""
    while batch := list(itertools.islice(messages, RUN_MESSAGES)):
        yield Run(np.array([m[1] for m in batch], np.int64), [m[2] for m in batch])


class ChunkReader(Protocol):
    """What ``bag_runs`` needs of a ``.bag`` reader (``Bag1Reader``, its chunks ``Bag1Chunk``)."""

    chunks: list[Any]

    def blocks(
        self, wanted: Mapping[int, tuple[int, Connection]], lo: int, hi: int, everything: bool
    ) -> list[Block]:
        """One block per chunk that may hold a wanted message in time."""

    def chunk_data(self, chunk: Any) -> tuple[Any, int, int]:
        """(buffer, start, end) of a chunk's uncompressed records."""

    def index_records(self, chunk: Any) -> Iterator[tuple[int, memoryview]]:
        """(connection id, raw entries) of each INDEX_DATA record after a chunk."""


def bag_runs(
    reader: ChunkReader, wanted: Mapping[int, tuple[int, Connection]], lo: int, hi: int
) -> Iterator[Run]:
    """The wanted messages from ``lo`` to ``hi`` ns of a ``.bag``, a chunk per run at most.

    The same messages in the same order as ``reader.messages``: a chunk that is not as rosbag
    writes them is read by its careful path, and once chunks overlap in time the rest is
    merged as ``messages`` merges it.
    """
    blocks = sorted(reader.blocks(wanted, lo, hi, False), key=lambda b: (b.start_ns, b.order))
    for k, block in enumerate(blocks):
        run = _chunk_run(reader, reader.chunks[block.order], wanted, lo, hi)
        if run is None:
            entries = block.load()  # notes why, as a read through messages would
            run = Run(np.array([e[0] for e in entries], np.int64), [e[4] for e in entries])
        if k + 1 < len(blocks) and len(run) and run.times[-1] >= blocks[k + 1].start_ns:
            # Chunks that overlap in time: merged from here on (a block loads its entries again).
            yield from runs_of(ordered(blocks[k:]))
            return
        if len(run):
            yield run


def _chunk_run(
    reader: ChunkReader,
    chunk: Any,
    wanted: Mapping[int, tuple[int, Connection]],
    lo: int,
    hi: int,
) -> Run | None:
    """A regular chunk's wanted messages, or None for the careful path."""
    if chunk.index_pos < 0:
        return None
    try:
        buf, base, end = reader.chunk_data(chunk)
        records = list(reader.index_records(chunk))
        times, starts, lengths, rows = chunk_arrays(buf, base, end, records, chunk.counts, wanted)
    except (BagFormatError, Irregular):
        return None
    if len(times):
        # Its records' times are its chunk info's (all of them when every message is read).
        whole = wanted.keys() >= chunk.counts.keys()
        first, last = int(times[0]), int(times[-1])
        if (
            (first, last) != (chunk.start_ns, chunk.end_ns)
            if whole
            else (first < chunk.start_ns or last > chunk.end_ns)
        ):
            return None
        keep = slice(np.searchsorted(times, lo), np.searchsorted(times, hi, side="right"))
        times, starts, lengths = times[keep], starts[keep], lengths[keep]
        rows = None if rows is None else rows[keep]
    return Run(times, None, buf, starts, lengths, rows)
