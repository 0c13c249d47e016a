""".bag -> MCAP chunk for chunk, with numpy: no Python work per message.

A chunk of small messages costs microseconds per message through ``messages()`` and
``write()``; here each chunk is rearranged with array operations instead. A rosbag message
record is ``u32 header_len (38), header, u32 data_len, data`` (46 bytes before the data); an
MCAP message record is ``u8 op, u64 length, u16 channel, u32 sequence, u64 log time, u64
publish time`` (31 bytes) before the same data. So dropping the first 15 bytes of every bag
message record (and the connection records between them) and overwriting the remaining 31
with MCAP fields turns the chunk's records into the MCAP chunk's records in two passes.

It applies when the bag is indexed, its chunks do not overlap in time, and inside each chunk
time order (ties: connection rank) is file order, so the MCAP file yields exactly the stream
the bag does; and when the index agrees with the records (connection, time, counts, the chunk's
time range), else the per-message path reads the chunk and says how they differ. Any chunk that
does not qualify, or whose messages are big (images: the per-message path is already cheap for
them), goes through the ordinary per-message path. numpy comes with rosbags; without it,
``convert`` simply uses the ordinary path.
"""

from __future__ import annotations

from collections.abc import Callable
from itertools import pairwise
from typing import TYPE_CHECKING, Any

from rostools.bag.formats.base import Targets
from rostools.bag.formats.model import BagFormatError

if TYPE_CHECKING:
    from rostools.bag.formats.mcap_writer import McapWriter
    from rostools.bag.formats.rosbag1_reader import Bag1Chunk, Bag1Reader

#: A 38-byte message record header as rosbag's C++ writer (fields sorted: conn, op, time)
#: and its Python writer (op, conn, time) lay it out: (place, bytes) of its fixed parts (the
#: header length, each field's length and name, the op), and where its numbers lie.
_LAYOUT_CPP = (
    ((0, b"&\x00\x00\x00\t\x00\x00\x00conn="), (17, b"\x04\x00\x00\x00op=\x02\r\x00\x00\x00time=")),
    [("pad0", "V13"), ("conn", "<u4"), ("pad1", "V17"), ("secs", "<u4"), ("nsecs", "<u4"),
     ("dlen", "<u4")],
)  # fmt: skip
_LAYOUT_PY = (
    ((0, b"&\x00\x00\x00\x04\x00\x00\x00op=\x02\t\x00\x00\x00conn="), (25, b"\r\x00\x00\x00time=")),
    [("pad0", "V21"), ("conn", "<u4"), ("pad1", "V9"), ("secs", "<u4"), ("nsecs", "<u4"),
     ("dlen", "<u4")],
)  # fmt: skip
#: The layouts as numpy wants them: ((place, bytes as an array), ...), record dtype.
_NUMPY_LAYOUTS: list[tuple[list[tuple[int, Any]], Any]] = []
#: Chunks whose messages average more than this many bytes go the per-message way: its cost
#: per message is small beside their size, and it hands payloads to the kernel without the
#: per-byte pass that compacting the chunk here costs.
SMALL_MESSAGE = 4096
_BAG_HEAD = 46
_MCAP_HEAD = 31


def convert_chunks(
    reader: Bag1Reader,
    writer: McapWriter,
    targets: Targets,
    progress: Callable[[int], None] | None = None,
) -> int | None:
    """Copy every message of an indexed bag into an MCAP writer; None if it does not qualify.

    ``targets`` maps the bag's connections to the writer's channels; ``progress`` gets the
    number of messages done after each chunk.
    """
    try:
        import numpy as np
    except ImportError:  # pragma: no cover - numpy comes with rosbags
        return None
    chunks = sorted(reader.chunks, key=lambda c: (c.start_ns, c.pos))
    if not reader.indexed or any(a.end_ns >= b.start_ns for a, b in pairwise(chunks)):
        return None
    wanted = reader.wanted(None, None)
    total = 0
    for chunk in chunks:
        many = sum(chunk.counts.values()) * SMALL_MESSAGE >= chunk.size
        done = _convert_chunk(np, reader, writer, targets, wanted, chunk) if many else None
        if done is None:  # this chunk does not qualify: the per-message path
            done = writer.write_many(reader.chunk_messages(chunk, wanted), targets)
            writer.end_chunk()
        total += done
        if progress is not None:
            progress(total)
    return total


def _convert_chunk(
    np: Any,
    reader: Bag1Reader,
    writer: McapWriter,
    targets: Targets,
    wanted: Any,
    chunk: Bag1Chunk,
) -> int | None:
    """One bag chunk as one MCAP chunk; None when the chunk does not qualify.

    Nor does a chunk that does not read, or whose index disagrees with its records in
    count, connection or time: the per-message path reads it from its records and says so.
    """
    try:
        buf, base, end = reader.chunk_data(chunk)
        index = list(reader.index_records(chunk))
    except BagFormatError:
        return None
    if {conn_id: len(raw) // 12 for conn_id, raw in index} != chunk.counts:
        return None
    if not index:
        return 0
    arr = np.frombuffer(buf, dtype=np.uint8, count=end - base, offset=base)
    entries = _Entries.read(np, index, wanted, targets, chunk)
    dlen = None if entries is None else _data_lengths(np, arr, entries)
    if entries is None or dlen is None:
        return None
    records, starts = _message_records(np, arr, entries.offs, dlen)
    _write_headers(np, writer, records, starts, entries, dlen)
    return len(starts)


class _Entries:
    """A chunk's index entries in file order: where each record is, its time and channel."""

    def __init__(self, offs: Any, times: Any, cids: Any, conns: Any, secs: Any, nsecs: Any):
        self.offs, self.times, self.cids = offs, times, cids
        #: What each record's own header must say: its connection and time.
        self.conns, self.secs, self.nsecs = conns, secs, nsecs

    @classmethod
    def read(
        cls, np: Any, index: list[tuple[int, Any]], wanted: Any, targets: Targets, chunk: Bag1Chunk
    ) -> _Entries | None:
        """The entries, if time order is file order and the chunk info agrees, else None."""
        entry = np.dtype([("secs", "<u4"), ("nsecs", "<u4"), ("off", "<u4")])
        parts, channels, ranks, sources = [], [], [], []
        for conn_id, raw in index:
            if conn_id not in wanted:
                return None
            rank, conn = wanted[conn_id]
            found = np.frombuffer(raw, dtype=entry)
            parts.append(found)
            channels.append(np.full(len(found), targets.resolve(conn).id, dtype=np.uint16))
            ranks.append(np.full(len(found), rank, dtype=np.uint32))
            sources.append(np.full(len(found), conn_id, dtype=np.uint32))
        entries = np.concatenate(parts)
        order = np.argsort(entries["off"].astype(np.int64), kind="stable")  # file order
        entries = entries[order]
        offs = entries["off"].astype(np.int64)
        times = entries["secs"].astype(np.uint64) * np.uint64(1_000_000_000) + entries["nsecs"]
        rank = np.concatenate(ranks)[order]
        if (int(times.min()), int(times.max())) != (chunk.start_ns, chunk.end_ns):
            return None  # the chunk info disagrees: the per-message path says how
        if len(entries) > 1:
            # Time order (time, rank, position) must be file order: no step back in it.
            step = np.diff(times.astype(np.int64))
            same_time_in_rank = (step == 0) & (np.diff(rank.astype(np.int64)) >= 0)
            if not bool(np.all((step > 0) | same_time_in_rank)):
                return None
            if not bool(np.all(offs[1:] > offs[:-1])):
                return None  # two index entries for one record
        conns = np.concatenate(sources)[order]
        cids = np.concatenate(channels)[order]
        return cls(offs, times, cids, conns, entries["secs"], entries["nsecs"])


def _data_lengths(np: Any, arr: Any, entries: _Entries) -> Any:
    """Each message's data length, read from its record; None if a record disagrees.

    Every record's 46-byte head in one gather: the fixed bytes say which layout it is in,
    and its connection and time must be its index entry's.
    """
    size, offs = len(arr), entries.offs
    if int(offs[-1]) + _BAG_HEAD > size:
        return None
    windows = np.lib.stride_tricks.as_strided(
        arr, shape=(size - _BAG_HEAD + 1, _BAG_HEAD), strides=(1, 1)
    )
    heads = windows[offs]
    layout = next(
        (
            lay
            for lay in _layouts(np)
            if all(bool(np.all(heads[:, at : at + len(b)] == b)) for at, b in lay[0])
        ),
        None,
    )
    if layout is None:
        return None
    fields = heads.view(layout[1])[:, 0]
    if not (
        np.array_equal(fields["conn"], entries.conns)
        and np.array_equal(fields["secs"], entries.secs)
        and np.array_equal(fields["nsecs"], entries.nsecs)
    ):
        return None
    dlen = fields["dlen"].astype(np.int64)
    ends = offs + _BAG_HEAD + dlen
    if int(ends[-1]) > size or (len(offs) > 1 and not bool(np.all(ends[:-1] <= offs[1:]))):
        return None
    return dlen


def _message_records(np: Any, arr: Any, offs: Any, dlen: Any) -> tuple[Any, Any]:
    """The chunk's message records, 31 bytes of head each, and where each starts.

    Keep [record + 15, record end) of every message record; drop the rest (the first 15
    bytes of each message record, connection records): alternating drop/keep runs.
    """
    count = len(offs)
    ends = offs + _BAG_HEAD + dlen
    runs = np.empty(2 * count + 1, dtype=np.int64)
    runs[0] = offs[0] + (_BAG_HEAD - _MCAP_HEAD)
    runs[1::2] = _MCAP_HEAD + dlen
    runs[2:-1:2] = offs[1:] + (_BAG_HEAD - _MCAP_HEAD) - ends[:-1]
    runs[-1] = len(arr) - ends[-1]
    keep = np.zeros(2 * count + 1, dtype=np.bool_)
    keep[1::2] = True
    records = arr[np.repeat(keep, runs)]
    starts = np.zeros(count, dtype=np.int64)
    np.cumsum(runs[1:-2:2], out=starts[1:])
    return records, starts


def _write_headers(
    np: Any, writer: McapWriter, records: Any, starts: Any, entries: _Entries, dlen: Any
) -> None:
    """Overwrite each record's head with MCAP's, index it by channel, write the chunk."""
    count, times, cids = len(starts), entries.times, entries.cids
    header = np.empty(count, dtype=_mcap_header(np))
    header["op"] = 5
    header["length"] = 22 + dlen
    header["channel"] = cids
    header["log_time"] = times
    header["publish_time"] = times
    sequence = np.empty(count, dtype=np.uint32)
    indexes: dict[int, bytes] = {}
    counts: dict[int, int] = {}
    by_channel = np.argsort(cids, kind="stable")  # each channel's messages, in order
    cuts = np.flatnonzero(np.diff(cids[by_channel])) + 1
    for mine in np.split(by_channel, cuts):
        cid = int(cids[mine[0]])
        first = writer.sequence(cid)
        sequence[mine] = (np.arange(first, first + len(mine)) & 0xFFFFFFFF).astype(np.uint32)
        pairs = np.empty((len(mine), 2), dtype="<u8")
        pairs[:, 0] = times[mine]
        pairs[:, 1] = starts[mine]
        indexes[cid] = pairs.tobytes()
        counts[cid] = len(mine)
    header["sequence"] = sequence
    # Rows k of this view are records[k:k + 31]: one row copy per message header.
    windows = np.lib.stride_tricks.as_strided(
        records, shape=(len(records) - _MCAP_HEAD + 1, _MCAP_HEAD), strides=(1, 1)
    )
    windows[starts] = header.view(np.uint8).reshape(count, _MCAP_HEAD)
    writer.write_chunk(int(times[0]), int(times.max()), memoryview(records), indexes, counts)


def _layouts(np: Any) -> list[tuple[list[tuple[int, Any]], Any]]:
    """The message record layouts (fixed parts, record dtype), made once numpy is loaded."""
    if not _NUMPY_LAYOUTS:
        for fixed, fields in (_LAYOUT_CPP, _LAYOUT_PY):
            parts = [(at, np.frombuffer(b, dtype=np.uint8)) for at, b in fixed]
            _NUMPY_LAYOUTS.append((parts, np.dtype(fields)))
    return _NUMPY_LAYOUTS


def _mcap_header(np: Any) -> Any:
    """An MCAP message record up to its data, as a packed 31-byte numpy record."""
    return np.dtype(
        [
            ("op", "u1"),
            ("length", "<u8"),
            ("channel", "<u2"),
            ("sequence", "<u4"),
            ("log_time", "<u8"),
            ("publish_time", "<u8"),
        ]
    )
