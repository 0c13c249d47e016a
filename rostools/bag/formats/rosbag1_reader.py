"""Reading rosbag v2.0 files: indexed ones from their index, others by scanning the chunks.

Opening an indexed bag reads the bag header, the CONNECTION and CHUNK_INFO records at
``index_pos`` and one small chunk header per chunk, which is all ``info`` needs (rosbags and
``rosbag.Bag`` read every per-message index entry up front). The per-message INDEX_DATA records
after a chunk are read only when that chunk's messages are. A bag without a usable index (a
killed recorder, a cut-short copy) is read by walking its chunks, including the records of a
chunk that was never closed and the decompressible part of one that was cut short.

Damage never comes out silently wrong. The message records are the truth: times and connections
come from them, and each index entry is checked against the record it points at as the chunk is
read (``rosbag1_index``). A chunk whose index disagrees with its records is read by walking the
records, and the disagreement is noted. The chunk infos must name the file's chunks one for one
(checked on opening, ``_misfit``): one that names another chunk would have that chunk read twice
and its own never, so such an index is not used, and the file is read by walking its chunks.
Two copies of a connection record that differ (the index's and a chunk's) are noted; a read
through the index uses the index's, as rosbag does, and ``from_records`` (``recover``) the
chunk's, which travels with the messages. Bytes that do not parse, at the top level or inside a
chunk, are skipped to the next whole record (``rosbag1_format.next_record``), and what they
held is listed in ``damage``; a chunk that does not decompress is left out and listed there.
"""

from __future__ import annotations

import struct
from bisect import bisect_left
from collections.abc import Collection, Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from functools import partial
from operator import attrgetter
from pathlib import Path
from typing import Any

from rostools.bag.formats import rosbag1_format as fmt
from rostools.bag.formats.base import MAX_TIME_NS, BagReader, Forgetting, map_file, release
from rostools.bag.formats.model import (
    BagFormatError,
    BagInfo,
    Connection,
    UnsupportedBagError,
    compression_rows,
    connection_from_header,
    counted,
    not_a_bag,
    summarize,
)
from rostools.bag.formats.ordering import Block, Entry, RawMessage, ordered, out_of_order
from rostools.bag.formats.rosbag1_index import (
    Buffer,
    Disagreement,
    checked_entries,
    index_times,
    message_head,
)
from rostools.wire.header import HeaderError, split_fields

_U32 = fmt.U32
_ID = attrgetter("id")
#: Records worth reading on at after damage: at the top level, and inside a chunk.
_TOP_OPS = frozenset(
    (fmt.OP_CHUNK, fmt.OP_CONNECTION, fmt.OP_INDEX_DATA, fmt.OP_CHUNK_INFO, fmt.OP_MSG_DATA)
)
_CHUNK_OPS = frozenset((fmt.OP_MSG_DATA, fmt.OP_CONNECTION))
#: The op field of an INDEX_DATA record header, as stored.
_INDEX_OP = b"\x04\x00\x00\x00op=\x04"
#: What an unindexed bag is read by.
_CHUNKS = "its chunks"
#: The bytes of an INDEX_DATA record besides its entries, as rosbag writes it: the header's
#: length, its four fields (op, ver, conn, count: 8 + 12 + 13 + 14 bytes), the data's length.
_INDEX_RECORD = 4 + 47 + 4
_POS = attrgetter("pos")


@dataclass
class Bag1Chunk:
    """A chunk record: where its data is, its times, and messages per connection.

    ``index_pos`` is the first INDEX_DATA record after it, or -1 when the chunk is read by
    scanning its records. ``complete`` is False for a chunk that was never closed or is cut
    short: only what parses (or decompresses) of it is read.
    """

    pos: int
    compression: str
    size: int
    data_pos: int
    data_len: int
    start_ns: int = 0
    end_ns: int = 0
    counts: dict[int, int] = field(default_factory=dict)
    index_pos: int = -1
    complete: bool = True


class Bag1Reader(BagReader):
    """A rosbag v2.0 file; see the module docstring for how it is read.

    ``from_records``: read by walking the chunks even when the index is whole (what
    ``recover`` rebuilds from), with each chunk info and connection record of the index
    checked against what the walk found (a difference is a note).
    """

    format = "bag"

    def __init__(self, path: str | Path, *, from_records: bool = False) -> None:
        super().__init__(path)
        self.from_records = from_records
        self.chunks: list[Bag1Chunk] = []
        self._by_id: dict[int, Connection] = {}
        #: Where each connection's record was read (``_add_connection``), for a note.
        self._where: dict[int, str] = {}
        self._index_pos = 0
        #: (chunk position, start, end, messages per connection) as the index lists them.
        self._infos: list[tuple[int, int, int, dict[int, int]]] = []
        mm, self.size = map_file(self.path)
        if mm is None:
            raise BagFormatError(f"{self.path} is empty, not a bag")
        self._mm = mm
        self._forget = Forgetting(mm)
        self._view = memoryview(mm)
        try:
            self._open()
        except BaseException:
            self.close()
            raise

    # -- opening ---------------------------------------------------------------------------

    def _open(self) -> None:
        head = self._mm[: len(fmt.MAGIC)]
        if head != fmt.MAGIC:
            raise not_a_bag(self.path, head, "not a ROS 1 bag (no '#ROSBAG V2.0' line)")
        try:
            fields, data, dlen = fmt.read_record(self._mm, len(fmt.MAGIC), self.size)
            if fmt.op_of(fields) != fmt.OP_BAG_HEADER:
                raise fmt.RecordError("the first record is not a bag header")
        except fmt.RecordError as err:
            raise BagFormatError(f"{self.path}: damaged bag header ({err})") from err
        if "encryptor" in fields:
            raise UnsupportedBagError(
                f"{self.path} is encrypted (rosbag encrypt); decrypt it first"
            )
        self._records_start = data + dlen
        index_pos = self._index_pos = _u64_or(fields, "index_pos", 0)
        if self._records_start <= index_pos <= self.size:
            try:
                # Without its counts the index cannot be read: rosbag too reads it unindexed.
                counts = fmt.u32_field(fields, "conn_count"), fmt.u32_field(fields, "chunk_count")
                self._read_index(index_pos, *counts)
                why = self._misfit(index_pos)
                if why is not None:
                    raise fmt.RecordError(why)
                self.indexed = True
                if self.from_records:
                    self._rebuild()
                return
            except (fmt.RecordError, HeaderError, struct.error) as err:
                self.read_unindexed(f"its index at {index_pos} is damaged ({err})", _CHUNKS)
                self.connections, self.chunks, self._by_id, self._where = [], [], {}, {}
        elif index_pos == 0:
            self.read_unindexed("an unclosed recording", _CHUNKS)
        else:
            self.read_unindexed(
                f"cut short (its index at {index_pos} is past the end, {self.size} bytes)", _CHUNKS
            )
        self._scan()
        if not self.chunks and not self.connections:
            if self.size > self._records_start:
                raise BagFormatError(
                    f"{self.path}: unindexed bag with nothing readable after its header"
                )
            raise BagFormatError(
                f"{self.path}: unindexed bag that ends after its header (no chunks, no index)"
            )

    def _read_index(self, pos: int, conn_count: int, chunk_count: int) -> None:
        mm, size = self._mm, self.size
        for _ in range(conn_count):
            fields, data, dlen = fmt.read_record(mm, pos, size, max_data=fmt.MAX_CONNECTION_HEADER)
            if fmt.op_of(fields) != fmt.OP_CONNECTION:
                raise fmt.RecordError(f"expected a connection record at {pos}")
            self._add_connection(fields, data, dlen, where="the index")
            pos = data + dlen
        infos: list[tuple[int, int, int, dict[int, int]]] = []
        for _ in range(chunk_count):
            fields, data, dlen = fmt.read_record(mm, pos, size)
            if fmt.op_of(fields) != fmt.OP_CHUNK_INFO:
                raise fmt.RecordError(f"expected a chunk info record at {pos}")
            count = fmt.u32_field(fields, "count")
            if dlen != 8 * count:
                raise fmt.RecordError(f"chunk info at {pos} lists {count} connections in {dlen} B")
            pairs = struct.unpack_from(f"<{2 * count}I", mm, data)
            counts = dict(zip(pairs[::2], pairs[1::2], strict=True))
            if len(counts) != count:
                raise fmt.RecordError(f"chunk info at {pos} lists a connection twice")
            chunk_pos = fmt.u64_field(fields, "chunk_pos")
            start, end = fmt.time_field(fields, "start_time"), fmt.time_field(fields, "end_time")
            infos.append((chunk_pos, start, end, counts))
            pos = data + dlen
        self._infos = infos  # for a damage report, should the chunks not be where it says
        for chunk_pos, start, end, counts in infos:
            unknown = counts.keys() - self._by_id.keys()
            if unknown:
                raise fmt.RecordError(
                    f"the chunk info of the chunk at {chunk_pos} lists connection"
                    f" {min(unknown)}, which no connection record defines"
                )
            chunk = self._chunk_header(chunk_pos)
            chunk.start_ns, chunk.end_ns, chunk.counts = start, end, counts
            chunk.index_pos = chunk.data_pos + chunk.data_len
            self.chunks.append(chunk)

    def _misfit(self, index_pos: int) -> str | None:
        """Why the chunk infos do not name the file's chunks one for one, or None.

        Each must name a chunk of its own, and every chunk before the index must be named:
        else a read through the index reads one chunk twice and another never. In rosbag's
        files each chunk's index records are followed by the next chunk, so this costs a sum
        per chunk; other bytes between them (connection records, or index records unlike
        rosbag's) are walked.
        """
        cursor, last = self._records_start, None
        for chunk in sorted(self.chunks, key=_POS):
            if last is not None and chunk.pos == last.pos:
                return f"two chunk infos name the chunk at {chunk.pos}"
            if chunk.pos < cursor:
                return f"a chunk info names {chunk.pos}, inside the chunk before it"
            if chunk.pos != cursor + _index_size(last):
                stray = self._stray_chunk(cursor, chunk.pos)
                if stray is not None:
                    return f"no chunk info names the chunk at {stray}"
            last, cursor = chunk, chunk.index_pos
        if index_pos != cursor + _index_size(last):
            stray = self._stray_chunk(cursor, index_pos)
            if stray is not None:
                return f"no chunk info names the chunk at {stray}"
        return None

    def _stray_chunk(self, pos: int, end: int) -> int | None:
        """The first chunk record from ``pos`` to ``end`` (top-level records), or None.

        Bytes that do not parse are searched for the next whole record; what they are is
        said when they are read (or not: a read through the index never goes there).
        """
        mm = self._mm
        while pos < end:
            try:
                fields, data, dlen = fmt.read_record(mm, pos, end)
                op = fmt.op_of(fields)
            except fmt.RecordError:
                nxt = fmt.next_record(mm, pos + 1, end, _TOP_OPS)
                if nxt is None:
                    return None
                pos = nxt
                continue
            if op == fmt.OP_CHUNK:
                return pos
            if op == fmt.OP_INDEX_DATA:
                dlen = fmt.INDEX_ENTRY_SIZE * _u32_or(fields, "count", dlen // 12)
            pos = data + dlen
        return None

    def _rebuild(self) -> None:
        """Read the chunks by walking them (``from_records``), and check the index against them.

        The chunk copies of the connection records come first, so they are the ones used;
        the index's are met last, and a copy that differs is noted. A chunk whose chunk info
        says what the walk found is read through its index records, checked as ever.
        """
        infos = self._infos
        self.connections, self.chunks, self._by_id, self._where = [], [], {}, {}
        self._scan()
        found = {c.pos: c for c in self.chunks}
        for chunk_pos, start, end, counts in infos:
            chunk = found.get(chunk_pos)
            walked = None if chunk is None else (chunk.start_ns, chunk.end_ns, chunk.counts)
            if chunk is not None and walked == (start, end, counts):
                # Its index records are read, each entry checked against its record (and
                # the chunk read from its records where one disagrees, noted): it is faster.
                chunk.index_pos = chunk.data_pos + chunk.data_len
            else:
                self.note(
                    f"the chunk info of the chunk at {chunk_pos} disagrees with its records"
                    f" ({_said(start, end, counts)}; the records: "
                    + ("none" if walked is None else _said(*walked))
                    + "); read from the records"
                )

    def _chunk_header(self, pos: int) -> Bag1Chunk:
        fields, data, dlen = fmt.read_record(self._mm, pos, self.size)
        if fmt.op_of(fields) != fmt.OP_CHUNK:
            raise fmt.RecordError(f"chunk info points at {pos}, which is not a chunk")
        return Bag1Chunk(
            pos=pos,
            compression=fields.get("compression", b"none").decode("ascii", "replace"),
            size=fmt.u32_field(fields, "size"),
            data_pos=data,
            data_len=dlen,
        )

    def _add_connection(
        self,
        fields: Mapping[str, bytes],
        data: int,
        dlen: int,
        buf: Buffer | None = None,
        where: str = "",
    ) -> Connection:
        """Register the connection record whose header is ``buf[data:data + dlen]``.

        ``buf`` is the file map unless the record sits in a decompressed chunk; ``where`` says
        where the record is, for a note. The first record of an id wins (the index repeats
        those in the chunks); a later one that differs from it is noted.
        """
        conn_id = fmt.u32_field(fields, "conn")
        existing = self._by_id.get(conn_id)
        if existing is not None and self._where.get(conn_id) == where:
            return existing  # rosbag repeats a record per chunk: compare it once per place
        try:
            view = self._view if buf is None else memoryview(buf)
            header = split_fields(view[data : data + dlen])
        except HeaderError as err:
            raise fmt.RecordError(f"connection {conn_id} has a malformed header: {err}") from err
        text = {k: v.decode("utf-8", "replace") for k, v in header.items()}
        topic = fields.get("topic", header.get("topic", b"")).decode("utf-8", "replace")
        conn = connection_from_header(conn_id, topic, text)
        if existing is not None:
            self._compare(existing, conn, where)
            return existing
        self.connections.append(conn)
        self._by_id[conn_id] = conn
        self._where[conn_id] = where
        return conn

    def _compare(self, first: Connection, other: Connection, where: str) -> None:
        """Note a second copy of a connection record that differs from the one in use."""
        a, b = {"topic": first.topic, **first.header()}, {"topic": other.topic, **other.header()}
        differ = [k for k in sorted(a.keys() | b.keys()) if a.get(k) != b.get(k)]
        if differ:
            used = self._where.get(first.id) or "the file"
            said = ", ".join(_difference(k, b.get(k), a.get(k)) for k in differ)
            self.note(
                f"connection {first.id} ({first.topic}): its record in {where or 'the file'}"
                f" differs from the one in {used} ({said}); the one in {used} is used"
            )

    def _scan(self) -> None:
        """Walk the records after the bag header: chunks, their connections and messages.

        Bytes that do not parse are skipped to the next whole record. Messages of a
        connection whose record comes later (chunks out of place) are kept.
        """
        mm, size, pos = self._mm, self.size, self._records_start
        while pos < size:
            try:
                fields, data, dlen = fmt.read_record(mm, pos, size)
                op = fmt.op_of(fields)
                chunk = self._chunk_header(pos) if op == fmt.OP_CHUNK else None
            except fmt.RecordError as err:
                pos = self._read_on(pos, err)
                continue
            if chunk is not None:
                if dlen == 0 and chunk.size == 0:
                    # Never closed: its records follow the provisional header up to EOF.
                    chunk.data_len = size - data
                    chunk.complete = False
                    self._add_scanned(chunk)
                    break
                self._add_scanned(chunk)
            elif op == fmt.OP_CONNECTION:
                where = "the index" if 0 < self._index_pos <= pos else f"the record at {pos}"
                try:
                    self._add_connection(fields, data, dlen, where=where)
                except fmt.RecordError as err:
                    self.damaged(f"skipped a damaged connection record at {pos}: {err}")
            elif op == fmt.OP_INDEX_DATA:
                # rosbag reads `count` entries whatever data_len says (a known writer bug).
                dlen = fmt.INDEX_ENTRY_SIZE * _u32_or(fields, "count", dlen // 12)
            elif op == fmt.OP_MSG_DATA:
                pos = self._loose(pos)
                continue
            pos = data + dlen
        self._drop_orphans()
        self.connections.sort(key=_ID)  # in id order, as the index lists them

    def _read_on(self, pos: int, err: Exception) -> int:
        """The record at ``pos`` does not parse: salvage what can be, and find the next one.

        A chunk whose header is whole but whose data runs past the next record (or the end
        of the file) is read as far as it decompresses.
        """
        head = self._chunk_head(pos)
        nxt = self._next_top(pos, None if head is None else head[2])
        stop = self.size if nxt is None else nxt
        listed = sum(sum(c.values()) for p, _, _, c in self._infos if pos <= p < stop)
        lost = f"; the index lists {counted(listed, 'message')} in chunks there" if listed else ""
        if head is not None and head[1] <= stop:
            fields, data, _ = head
            chunk = Bag1Chunk(
                pos=pos,
                compression=fields.get("compression", b"none").decode("ascii", "replace"),
                size=_u32_or(fields, "size", 0),
                data_pos=data,
                data_len=stop - data,
                complete=False,
            )
            self._add_scanned(chunk)
            got = sum(chunk.counts.values())
            if nxt is None:
                self.damaged(
                    f"chunk at {pos} is cut short ({self.size - chunk.data_pos} of its bytes"
                    f" are in the file); {counted(got, 'message')} salvaged from it"
                )
            else:
                self.damaged(
                    f"chunk at {pos} does not fit its record ({err});"
                    f" {counted(got, 'message')} salvaged from it, read on at {nxt}"
                )
        elif nxt is None:
            self.damaged(f"{self.size - pos} bytes at {pos} do not parse ({err}){lost}")
        else:
            self.damaged(f"{nxt - pos} bytes at {pos} do not parse ({err}){lost}; read on at {nxt}")
        return stop

    def _chunk_head(self, pos: int) -> tuple[dict[str, bytes], int, int] | None:
        """(fields, data start, declared data end) of the chunk at ``pos``, if it parses."""
        try:
            hlen = _U32.unpack_from(self._mm, pos)[0]
            if hlen > fmt.MAX_RECORD_HEADER or pos + 8 + hlen > self.size:
                return None
            fields = fmt.parse_header(self._mm, pos + 4, pos + 4 + hlen)
            if fmt.op_of(fields) != fmt.OP_CHUNK:
                return None
            (dlen,) = _U32.unpack_from(self._mm, pos + 4 + hlen)
        except (fmt.RecordError, struct.error):
            return None
        data = pos + 8 + hlen
        return fields, data, data + dlen

    def _next_top(self, pos: int, chunk_end: int | None) -> int | None:
        """The next whole top-level record after the damage at ``pos``, or None.

        Before ``chunk_end`` (the end a broken chunk at ``pos`` declares), message and
        connection records are the chunk's own content (the records of an uncompressed chunk,
        or an lz4 block stored raw), not places to read on at: read on there, the chunk's
        messages were taken for loose ones, and a record with an lz4 block header inside it
        went out as a message. The search goes on after each such record, so that a chunk of
        many records costs one pass.
        """
        start = pos + 1
        while True:
            nxt = fmt.next_record(self._mm, start, self.size, _TOP_OPS)
            if nxt is None or chunk_end is None or nxt >= chunk_end:
                return nxt
            fields, data, dlen = fmt.read_record(self._mm, nxt, self.size)  # whole, as found
            if fmt.op_of(fields) not in _CHUNK_OPS:
                return nxt
            start = data + dlen

    def _loose(self, pos: int) -> int:
        """Message records outside any chunk (its header lost): read them as one chunk."""
        mm, size, end = self._mm, self.size, pos
        while end < size:
            try:
                fields, data, dlen = fmt.read_record(mm, end, size)
                if fmt.op_of(fields) not in _CHUNK_OPS:
                    break
            except fmt.RecordError:
                break
            end = data + dlen
        chunk = Bag1Chunk(pos, "none", end - pos, pos, end - pos)
        self._add_scanned(chunk)
        self.note(
            f"{sum(chunk.counts.values())} message records at {pos} lie outside any chunk;"
            " read them as they are"
        )
        return end

    def _add_scanned(self, chunk: Bag1Chunk) -> None:
        self._scan_chunk(chunk)
        if chunk.counts:
            self.chunks.append(chunk)

    def _drop_orphans(self) -> None:
        """Leave out (and list) messages whose connection record the whole scan never met."""
        for chunk in self.chunks:
            orphans = [c for c in chunk.counts if c not in self._by_id]
            if orphans:
                lost = sum(chunk.counts.pop(c) for c in orphans)
                self.damaged(
                    f"chunk at {chunk.pos}: {counted(lost, 'message')} of connections"
                    " whose record is lost"
                )
        self.chunks = [c for c in self.chunks if c.counts]

    def _scan_chunk(self, chunk: Bag1Chunk) -> None:
        """Fill a chunk's counts and times by walking its records (no index)."""
        try:
            buf, base, end = self.chunk_data(chunk)
        except BagFormatError as err:
            self.damaged(f"chunk at {chunk.pos} is unreadable: {err}")
            return
        first = True
        for t, conn_id, _ in self._walk(chunk, buf, base, end):
            chunk.counts[conn_id] = chunk.counts.get(conn_id, 0) + 1
            if first:
                chunk.start_ns = chunk.end_ns = t
                first = False
            elif t < chunk.start_ns:
                chunk.start_ns = t
            elif t > chunk.end_ns:
                chunk.end_ns = t

    def order_notes(self) -> list[str]:
        """Chunks whose message records are not in time order (legal: readers sort them)."""
        found: list[str] = []
        for chunk in self.chunks:
            try:
                buf, base, end = self.chunk_data(chunk)
            except BagFormatError as err:
                found.append(f"chunk at {chunk.pos}: {err}")
                continue
            late = out_of_order(t for t, _, _ in self._walk(chunk, buf, base, end))
            if late:
                found.append(f"chunk at {chunk.pos}: {counted(late, 'message')} out of time order")
        return found

    def _walk(
        self, chunk: Bag1Chunk, buf: Buffer, base: int, end: int
    ) -> Iterator[tuple[int, int, int]]:
        """(time, connection id, record offset) of each message record, by walking records.

        Connection records met on the way are registered. Bytes that do not parse are
        skipped to the next whole record, and listed in ``damage``; at the end of an unclosed
        or cut-short chunk they are its partial last record.
        """
        pos = base
        while pos < end:
            head = message_head(buf, pos, end)
            if head is not None:
                yield head[0], head[1], pos - base
                pos = head[2]
                continue
            try:
                fields, data, dlen = fmt.read_record(buf, pos, end)
                op = fmt.op_of(fields)
                found = None
                if op == fmt.OP_MSG_DATA:
                    found = (fmt.time_field(fields, "time"), fmt.u32_field(fields, "conn"))
            except fmt.RecordError as err:
                pos = self._skip(chunk, buf, base, end, pos, err)
                continue
            if found is not None:
                yield found[0], found[1], pos - base
            elif op == fmt.OP_CONNECTION:
                try:
                    self._add_connection(fields, data, dlen, buf, f"the chunk at {chunk.pos}")
                except fmt.RecordError as err:
                    self.damaged(
                        f"chunk at {chunk.pos}: skipped a damaged connection record: {err}"
                    )
            pos = data + dlen

    def _skip(
        self, chunk: Bag1Chunk, buf: Buffer, base: int, end: int, pos: int, err: Exception
    ) -> int:
        """Where the walk of a chunk reads on after bytes at ``pos`` that do not parse."""
        nxt = fmt.next_record(buf, pos + 1, end, _CHUNK_OPS)
        if nxt is not None:
            self.damaged(
                f"chunk at {chunk.pos}: {nxt - pos} bytes at offset {pos - base} do not parse"
                f" ({err}); read on at offset {nxt - base}"
            )
            return nxt
        if chunk.complete:
            self.damaged(f"chunk at {chunk.pos}: record at {pos - base}: {err}")
        else:
            self.damaged(f"chunk at {chunk.pos} ends in a partial record ({end - pos} bytes lost)")
        return end

    def chunk_data(self, chunk: Bag1Chunk) -> tuple[Buffer, int, int]:
        """(buffer, start, end) of a chunk's uncompressed records.

        Uncompressed chunks are read in place from the map; others are decompressed.
        """
        self._forget.up_to(chunk.pos)
        if chunk.compression == "none":
            return self._mm, chunk.data_pos, chunk.data_pos + chunk.data_len
        raw = self._view[chunk.data_pos : chunk.data_pos + chunk.data_len]
        if chunk.compression not in fmt.COMPRESSIONS:
            raise UnsupportedBagError(
                f"{self.path}: chunk at {chunk.pos} uses unknown compression {chunk.compression!r}"
            )
        if chunk.complete:
            data = fmt.decompress(chunk.compression, raw, chunk.size)
        else:
            data = fmt.decompress_prefix(chunk.compression, raw, chunk.size or fmt.MAX_CHUNK_SIZE)
        return data, 0, len(data)

    # -- reading ---------------------------------------------------------------------------

    def info(self) -> BagInfo:
        """The ``rosbag info`` summary, from the index (or the scan) alone."""
        counts: dict[int, int] = {}
        for chunk in self.chunks:
            for conn_id, n in chunk.counts.items():
                counts[conn_id] = counts.get(conn_id, 0) + n
        total = sum(counts.values())
        live = [c for c in self.connections if counts.get(c.id)]
        topics, types = summarize(live, counts)
        return BagInfo(
            path=self.path,
            format="bag",
            version="2.0",
            size=self.size,
            start_ns=min((c.start_ns for c in self.chunks), default=None) if total else None,
            end_ns=max((c.end_ns for c in self.chunks), default=None) if total else None,
            message_count=total,
            indexed=self.indexed,
            chunk_count=len(self.chunks),
            compression=compression_rows(
                [(c.compression, c.data_len, c.size) for c in self.chunks]
            ),
            connections=tuple(self.connections),
            connection_counts=counts,
            topics=topics,
            types=types,
        )

    def blocks(
        self, wanted: Mapping[int, tuple[int, Connection]], lo: int, hi: int, everything: bool
    ) -> list[Block]:
        """One block per chunk that may hold a wanted message in time.

        A chunk is left out by its chunk info's times and connections; the connections only
        once its index records (their headers) agree: a damaged chunk info hides nothing.
        """
        blocks = [
            Block(chunk.start_ns, order, partial(self._entries, chunk, wanted, lo, hi))
            for order, chunk in enumerate(self.chunks)
            if chunk.end_ns >= lo
            and chunk.start_ns <= hi
            and (not wanted.keys().isdisjoint(chunk.counts) or not self._lists_truly(chunk))
        ]
        return blocks

    def runs(
        self, connections: Iterable[Connection], start: int | None = None, end: int | None = None
    ) -> Iterator[Any]:
        """``messages`` of ``connections`` a chunk at a time (``runs``)."""
        from rostools.bag.formats.runs import bag_runs

        lo, hi = 0 if start is None else start, MAX_TIME_NS if end is None else end
        return bag_runs(self, self.wanted(None, connections), lo, hi)

    def _lists_truly(self, chunk: Bag1Chunk) -> bool:
        """Whether a chunk's index records are of the connections its chunk info lists."""
        if chunk.index_pos < 0:
            return True  # counted by walking its records
        try:
            found = {conn_id: len(raw) // 12 for conn_id, raw in self.index_records(chunk)}
        except fmt.RecordError:
            return False
        return found == chunk.counts

    def chunk_messages(
        self, chunk: Bag1Chunk, wanted: Mapping[int, tuple[int, Connection]]
    ) -> Iterator[RawMessage]:
        """The wanted messages of one chunk, in time order."""
        for e in self._entries(chunk, wanted, 0, MAX_TIME_NS):
            yield e[3], e[0], e[4]

    def times(self, topics: Collection[str] | None = None) -> Iterator[RawMessage]:
        """(connection, time, empty data) of each message in time order, from the index alone.

        What ``info --freq`` needs, without decompressing a chunk (unindexed bags: a full read).
        """
        if not self.indexed or self.from_records:
            yield from self.messages(topics=topics)
            return
        wanted = self.wanted(topics, None)
        blocks = [
            Block(chunk.start_ns, order, partial(self._index_entries, chunk, wanted))
            for order, chunk in enumerate(self.chunks)
            if not wanted.keys().isdisjoint(chunk.counts)
        ]
        yield from ordered(blocks)

    def _index_entries(
        self, chunk: Bag1Chunk, wanted: Mapping[int, tuple[int, Connection]]
    ) -> list[Entry]:
        try:
            return index_times(self.index_records(chunk), wanted)
        except fmt.RecordError:  # no usable index: the records say
            return self._entries(chunk, wanted, 0, MAX_TIME_NS)

    def _entries(
        self,
        chunk: Bag1Chunk,
        wanted: Mapping[int, tuple[int, Connection]],
        lo: int,
        hi: int,
    ) -> list[Entry]:
        """The wanted messages of one chunk from ``lo`` to ``hi`` ns, sorted.

        Never raises for what is in the file: a chunk that does not read is listed in
        ``damage``, an index that disagrees with the records in ``notes``.
        """
        try:
            buf, base, end = self.chunk_data(chunk)
        except BagFormatError as err:
            listed = sum(chunk.counts.values())
            self.damaged(
                f"chunk at {chunk.pos} is unreadable ({err}); its {counted(listed, 'message')}"
                f" {'is' if listed == 1 else 'are'} lost"
            )
            return []
        out = None
        if chunk.index_pos >= 0:
            try:
                try:
                    records = list(self.index_records(chunk))
                except fmt.RecordError as err:
                    raise Disagreement(f"its index records do not parse: {err}") from err
                out = checked_entries(buf, base, end, records, chunk.counts, wanted)
            except Disagreement as why:
                self.note(
                    f"chunk at {chunk.pos}: its index disagrees with its records ({why});"
                    " read from the records"
                )
        if out is None:
            out = self._walked(chunk, buf, base, end, wanted)
        # Every message of the chunk read: its range must be the chunk info's; some: within it.
        whole = wanted.keys() >= chunk.counts.keys()
        if (
            out
            and chunk.index_pos >= 0
            and (
                (out[0][0], out[-1][0]) != (chunk.start_ns, chunk.end_ns)
                if whole
                else out[0][0] < chunk.start_ns or out[-1][0] > chunk.end_ns
            )
        ):
            self.note(
                f"chunk at {chunk.pos}: its records run from {out[0][0]} to {out[-1][0]} ns,"
                f" its chunk info says {chunk.start_ns} to {chunk.end_ns}"
            )
        if out and lo > out[0][0]:
            out = out[bisect_left(out, (lo,)) :]
        if out and hi < out[-1][0]:
            out = out[: bisect_left(out, (hi + 1,))]
        return out

    def _walked(
        self,
        chunk: Bag1Chunk,
        buf: Buffer,
        base: int,
        end: int,
        wanted: Mapping[int, tuple[int, Connection]],
    ) -> list[Entry]:
        """The wanted messages of a chunk by walking its records, sorted."""
        view = memoryview(buf)
        out: list[Entry] = []
        unpack = _U32.unpack_from
        orphans = 0
        for t, conn_id, off in self._walk(chunk, buf, base, end):
            item = wanted.get(conn_id)
            if item is None:
                orphans += conn_id not in self._by_id
                continue
            p = base + off
            q = p + 8 + unpack(buf, p)[0]
            dlen = unpack(buf, q - 4)[0]
            out.append((t, item[0], off, item[1], view[q : q + dlen]))
        if orphans:
            self.damaged(
                f"chunk at {chunk.pos}: {counted(orphans, 'message')} of connections"
                " whose record is lost"
            )
        out.sort()
        return out

    def index_records(self, chunk: Bag1Chunk) -> Iterator[tuple[int, memoryview]]:
        """(connection id, raw entries) of each INDEX_DATA record after a chunk.

        Raises ``RecordError`` when they do not parse.
        """
        pos = chunk.index_pos
        if pos < 0:
            raise fmt.RecordError(f"the chunk at {chunk.pos} was read without its index")
        for _ in range(len(chunk.counts)):
            fields, data, _dlen = fmt.read_record(self._mm, pos, self.size)
            if fmt.op_of(fields) != fmt.OP_INDEX_DATA:
                raise fmt.RecordError(f"expected index data at {pos}")
            if fmt.u32_field(fields, "ver") != fmt.INDEX_VERSION:
                raise fmt.RecordError(f"index data at {pos} has an unknown version")
            count = fmt.u32_field(fields, "count")
            conn_id = fmt.u32_field(fields, "conn")
            pos = data + fmt.INDEX_ENTRY_SIZE * count
            if pos > self.size:
                raise fmt.RecordError(f"index data at {data} is cut short")
            yield conn_id, self._view[data:pos]
        # No index records of a connection the chunk info does not list: the next record's
        # header has no index data op (what follows is otherwise read, or noted, on its own).
        if pos + 4 <= self.size:
            header_end = min(pos + 4 + _U32.unpack_from(self._mm, pos)[0], self.size)
            if self._mm.find(_INDEX_OP, pos + 4, header_end) >= 0:
                raise fmt.RecordError(
                    f"the chunk at {chunk.pos} has more index records than its chunk info lists"
                )

    def close(self) -> None:
        """Release the file map."""
        view = getattr(self, "_view", None)
        if view is not None:
            view.release()
        release(getattr(self, "_mm", None))


def _u32_or(fields: Mapping[str, bytes], name: str, default: int) -> int:
    raw = fields.get(name)
    return int(_U32.unpack(raw)[0]) if raw is not None and len(raw) == 4 else default


def _u64_or(fields: Mapping[str, bytes], name: str, default: int) -> int:
    raw = fields.get(name)
    return int(fmt.U64.unpack(raw)[0]) if raw is not None and len(raw) == 8 else default


def _said(start: int, end: int, counts: Mapping[int, int]) -> str:
    """A chunk's time range and messages per connection, for a note."""
    per = ", ".join(f"{n} of connection {c}" for c, n in sorted(counts.items()))
    return f"{start} to {end} ns, {per or 'no messages'}"


def _difference(key: str, value: str | None, used: str | None) -> str:
    """How a field of a second connection record differs from the one in use, for a note."""
    shown = [v for v in (value, used) if v is not None]
    if all(len(v) <= 40 for v in shown):
        return f"{key} {value!r} against {used!r}" if len(shown) == 2 else f"{key} in one only"
    return key  # a definition: too long to quote


def _index_size(chunk: Bag1Chunk | None) -> int:
    """The bytes of a chunk's index records as rosbag writes them (0 before the first chunk)."""
    if chunk is None:
        return 0
    return sum(_INDEX_RECORD + fmt.INDEX_ENTRY_SIZE * n for n in chunk.counts.values())
