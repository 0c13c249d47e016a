"""Reading MCAP files of any profile; ROS 1 channels become ``Connection``s.

``info`` reads only the summary section when the file has a complete one (a few records at the
end). Messages are read by walking the data section's top-level records (skipping over chunk
bodies) and loading chunks lazily in time order. The records inside chunks are authoritative:
a summary that lacks some channels or schemas (valid MCAP; the upstream Python indexed reader
fails on such files) makes the reader collect them from the data section instead. Files cut
short are read up to the last complete record, plus what decompresses of a cut-short chunk.

Damage never comes out silently wrong: times come from the message records; a record that
does not parse, at the top level or inside a chunk, is skipped to the next plausible record
(``mcap_format.next_record``) and listed in ``damage``, as is a chunk that does not
decompress; a chunk whose header's time range disagrees with its messages is noted.

CRCs: a summary that fails its CRC is not trusted (noted; the data section is read instead).
Every chunk's CRC is checked as the chunk is read, and the data section's by a read of the
whole file (``_SectionCrc``), unless ``check_crcs`` is unset (``--no-crc-check``). A chunk
that fails its CRC is damage, and its messages are left out: none of them can be shown
intact, and a copy would give them a fresh, valid CRC. The check is one pass of zlib-ng's
``crc32`` (20 to 30 GB/s) over the records of each chunk read, as it is decompressed or sliced.
"""

from __future__ import annotations

import mmap
import struct
from bisect import bisect_left
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path

from rostools.bag.formats import mcap_format as fmt
from rostools.bag.formats.base import MAX_TIME_NS, BagReader, Forgetting, map_file, release
from rostools.bag.formats.model import (
    BagFormatError,
    BagInfo,
    Connection,
    compression_rows,
    counted,
    summarize,
)
from rostools.bag.formats.ordering import Block, Entry, out_of_order

_MSG = fmt.MESSAGE_PREFIX
_PREFIX = fmt.PREFIX
#: A chunk record's fixed fields: start, end, uncompressed size, crc.
_CHUNK_HEAD = struct.Struct("<QQQI")
_U32 = struct.Struct("<I")
_U64 = struct.Struct("<Q")
_U16 = struct.Struct("<H")
#: What a damage note calls a record.
_NAMES = {fmt.OP_SCHEMA: "schema", fmt.OP_CHANNEL: "channel"}
#: Channel id -> (rank, connection) of a read; unfiltered reads add channels met late.
_Wanted = dict[int, tuple[int, Connection]]


@dataclass
class _Scan:
    """What a walk over the whole data section found (for files without a usable summary)."""

    counts: dict[int, int] = field(default_factory=dict)
    start: int | None = None
    end: int | None = None
    chunks: list[tuple[str, int, int]] = field(default_factory=list)
    attachments: int = 0
    metadata: int = 0


class _SectionCrc:
    """The data section's CRC, put together in file order from pieces as a whole read goes.

    The bytes between chunks are passed over as the read walks them, and each chunk's record
    as its block is loaded (its bytes are in hand then: the compressed ones, or the records
    the chunk's own check passed over). When the last piece is in, the sum is checked.
    """

    def __init__(self, reader: McapReader) -> None:
        self.reader = reader
        self.pieces: dict[int, tuple[int, int]] = {}  # start -> (crc, length)
        self.waiting: set[int] = set()  # chunks whose piece is still to come
        self.expected: int | None = None

    def between(self, buf: mmap.mmap, start: int, end: int) -> None:
        """The bytes from ``start`` to ``end``, outside any chunk."""
        if end > start:
            self.pieces[start] = (fmt.crc32(memoryview(buf)[start:end]), end - start)

    def expect(self, rec: int) -> None:
        """The chunk record at ``rec`` is a piece, to come when its block is loaded."""
        self.waiting.add(rec)

    def chunk(self, rec: int, crc: int, length: int) -> None:
        """The CRC of the chunk record at ``rec``."""
        self.pieces[rec] = (crc, length)
        self.waiting.discard(rec)
        self._check()

    def close(self, expected: int) -> None:
        """Every piece is named: the DataEnd record gives the CRC they must sum to."""
        self.expected = expected
        self._check()

    def _check(self) -> None:
        if self.expected is None or self.waiting:
            return
        crc = 0
        for start in sorted(self.pieces):
            piece, length = self.pieces[start]
            crc = fmt.crc32_combine(crc, piece, length)
        # A chunk that failed its own CRC already says where the damage is.
        if crc != self.expected and not self.reader.crc_failed:
            self.reader.damaged("the data section's CRC does not match its bytes")
        self.expected = None


class McapReader(BagReader):
    """An MCAP file; see the module docstring."""

    format = "mcap"
    #: Check each chunk's CRC as it is read, and the data section's on a whole read (a
    #: mismatch goes into ``damage``); ``--no-crc-check`` unsets it.
    check_crcs = True

    def __init__(self, path: str | Path) -> None:
        super().__init__(path)
        self.profile = ""
        self.library = ""
        self.schemas: dict[int, fmt.Schema] = {}
        self.channels: dict[int, fmt.Channel] = {}
        self.statistics: fmt.Statistics | None = None
        self.chunk_indexes: list[fmt.ChunkIndex] = []
        self.attachment_indexes: list[fmt.AttachmentIndex] = []
        self.metadata_indexes: list[fmt.MetadataIndex] = []
        self._scan_result: _Scan | None = None
        self._by_id: dict[int, Connection] = {}
        #: Whether some chunk failed its CRC (its messages left out).
        self.crc_failed = False
        mm, self.size = map_file(self.path)
        if mm is None:
            raise BagFormatError(f"{self.path} is empty, not an MCAP file")
        self._mm = mm
        self._forget = Forgetting(mm)
        try:
            self._open()
        except BaseException:
            self.close()
            raise

    # -- opening ---------------------------------------------------------------------------

    def _open(self) -> None:
        mm, size = self._mm, self.size
        if mm[: len(fmt.MAGIC)] != fmt.MAGIC:
            raise BagFormatError(f"{self.path} is not an MCAP file (bad magic)")
        try:
            _, op, start, end = next(fmt.records(mm, len(fmt.MAGIC), size))
            header = fmt.parse(op, mm, start, end)
        except (StopIteration, fmt.McapFormatError) as err:
            raise BagFormatError(f"{self.path}: MCAP file cut short in its header") from err
        if not isinstance(header, fmt.Header):
            raise BagFormatError(f"{self.path}: MCAP file does not start with a header record")
        self.profile, self.library = header.profile, header.library
        self._data_start = end
        self._data_end = size
        footer = fmt.parse_footer(mm[max(0, size - fmt.FOOTER_SIZE - len(fmt.MAGIC)) :])
        if footer is None:
            self.read_unindexed("no footer (unfinished or cut short)")
        else:
            self._data_end = size - fmt.FOOTER_SIZE - len(fmt.MAGIC)
            if footer.summary_start:
                self._read_summary(footer)
        if not self._summary_complete():
            self.schemas, self.channels = {}, {}
            self._scan_result = self._scan()
        for channel_id in sorted(self.channels):
            self._connection(channel_id)

    def _read_summary(self, footer: fmt.Footer) -> None:
        end = footer.summary_offset_start or self._data_end
        if not (self._data_start <= footer.summary_start <= end <= self._data_end):
            self.read_unindexed("its footer points outside the file")
            return
        crc_end = self.size - len(fmt.MAGIC) - 4  # through the footer's offsets
        if footer.summary_crc and footer.summary_crc != fmt.crc32(
            memoryview(self._mm)[footer.summary_start : crc_end]
        ):
            self.note("the summary does not match its CRC; scanned the data section")
            return
        try:
            for _, op, start, stop in fmt.records(self._mm, footer.summary_start, end):
                record = fmt.parse(op, self._mm, start, stop)
                if isinstance(record, fmt.Schema):
                    self.schemas.setdefault(record.id, record)
                elif isinstance(record, fmt.Channel):
                    self.channels.setdefault(record.id, record)
                elif isinstance(record, fmt.Statistics):
                    self.statistics = record
                elif isinstance(record, fmt.ChunkIndex):
                    self.chunk_indexes.append(record)
                elif isinstance(record, fmt.AttachmentIndex):
                    self.attachment_indexes.append(record)
                elif isinstance(record, fmt.MetadataIndex):
                    self.metadata_indexes.append(record)
        except fmt.McapFormatError as err:
            self.read_unindexed(f"its summary is damaged ({err})")
            self.statistics, self.chunk_indexes = None, []
            return
        self._data_end = footer.summary_start
        self.indexed = self.statistics is not None or bool(self.chunk_indexes)

    def _summary_complete(self) -> bool:
        """Whether the summary names every channel (and schema) the data uses."""
        if not self.indexed:
            return False
        used: set[int] = set()
        if self.statistics is not None:
            used.update(self.statistics.channel_message_counts)
        for index in self.chunk_indexes:
            used.update(index.message_index_offsets)
        if self.statistics is None and self.chunk_indexes and not used:
            return False  # chunks without message indexes: nothing says which channels exist
        if not used <= self.channels.keys():
            return False
        return all(c.schema_id == 0 or c.schema_id in self.schemas for c in self.channels.values())

    def _top(self, pos: int, end: int) -> Iterator[tuple[int, int, int, int, bool]]:
        """(record, opcode, content start, content end, complete) of top-level records.

        At a record that does not fit, the walk reads on at the next plausible record; if
        that record is a chunk whose header is whole, it is yielded with ``complete`` False
        and the place the walk reads on at (or the end) as its end, so what decompresses of
        it can still be read.
        """
        mm = self._mm
        while pos < end:
            nxt = pos
            try:
                for rec, op, start, stop in fmt.records(mm, pos, end):
                    if op == fmt.OP_MESSAGE and stop - start < 22:
                        raise fmt.McapFormatError(f"message at {rec} is too short")
                    nxt = stop
                    yield rec, op, start, stop, True
                return
            except fmt.McapFormatError as err:
                chunk_end = None
                if nxt + 9 <= end and mm[nxt] == fmt.OP_CHUNK:
                    chunk_end = nxt + 9 + _PREFIX.unpack_from(mm, nxt)[1]
                resume = self._next_top(nxt, end, chunk_end)
                stop = end if resume is None else resume
                if nxt + 9 + 40 <= stop and mm[nxt] == fmt.OP_CHUNK:
                    how = "is cut short" if resume is None else "does not fit its record"
                    self.damaged(f"chunk at {nxt} {how}; read what decompresses")
                    yield nxt, fmt.OP_CHUNK, nxt + 9, stop, False
                elif resume is None:
                    self.damaged(f"data section ends in a damaged or cut-short record ({err})")
                else:
                    self.damaged(
                        f"{resume - nxt} bytes at {nxt} do not parse ({err}); read on at {resume}"
                    )
                pos = stop

    def _next_top(self, pos: int, end: int, chunk_end: int | None) -> int | None:
        """The next plausible top-level record after the damage at ``pos``, or None.

        Before ``chunk_end`` (the end a broken chunk at ``pos`` declares), schema, channel
        and message records are the chunk's own content (the records of an uncompressed
        chunk, or a zstd or lz4 block stored raw), not places to read on at: read on there,
        a record with a block header inside it went out as a message. The search goes on
        after each such record, so that a chunk of many records costs one pass.
        """
        start = pos + 1
        while True:
            resume = fmt.next_record(self._mm, start, end, fmt.DATA_OPS)
            if resume is None or chunk_end is None or resume >= chunk_end:
                return resume
            op, length = _PREFIX.unpack_from(self._mm, resume)
            if op not in fmt.CHUNK_OPS:
                return resume
            start = resume + 9 + length  # plausible, so it ends before ``end``

    def _scan(self) -> _Scan:
        """Walk the data section for schemas, channels, counts and times (no summary).

        Schema and channel records are registered on the way, inside chunks too.
        """
        scan = _Scan()
        mm = self._mm
        times: list[int] = []
        for rec, op, start, stop, complete in self._top(self._data_start, self._data_end):
            if op == fmt.OP_MESSAGE:
                channel_id, log = struct.unpack_from("<H4xQ", mm, start)
                scan.counts[channel_id] = scan.counts.get(channel_id, 0) + 1
                times.append(log)
            elif op == fmt.OP_CHUNK:
                try:
                    compression, size, data_start, data_len = self._chunk_fields(
                        rec, start, stop, complete
                    )
                    data, base, data_end = self._chunk_data(
                        compression, size, data_start, data_len, complete
                    )
                except fmt.McapFormatError as err:
                    self.damaged(f"chunk at {rec} is unreadable ({err})")
                    continue
                if complete:
                    scan.chunks.append((compression or "none", data_len, size))
                    if self._crc_holds(rec, start, data, base, data_end)[0] is False:
                        continue
                for channel_id, log in self._inner(data, base, data_end, rec, complete):
                    scan.counts[channel_id] = scan.counts.get(channel_id, 0) + 1
                    times.append(log)
            elif op in (fmt.OP_SCHEMA, fmt.OP_CHANNEL):
                self._register_inner(op, mm, rec, stop, None)
            elif op == fmt.OP_ATTACHMENT:
                scan.attachments += 1
            elif op == fmt.OP_METADATA:
                scan.metadata += 1
            elif op in (fmt.OP_DATA_END, fmt.OP_FOOTER):
                break
        if times:
            scan.start, scan.end = min(times), max(times)
        return scan

    def extras(self) -> list[fmt.Attachment | fmt.Metadata]:
        """The file's attachments and metadata records, in file order.

        They lie outside chunks, so a walk over the top-level records finds them, summary or
        not; a damaged one is skipped and noted.
        """
        found: list[fmt.Attachment | fmt.Metadata] = []
        info = self.info()
        if not info.attachment_count and not info.metadata_count:
            return found  # the statistics (or the scan) say there are none: skip the walk
        for _, op, start, stop, _ in self._top(self._data_start, self._data_end):
            if op in (fmt.OP_ATTACHMENT, fmt.OP_METADATA):
                try:
                    record = fmt.parse(op, self._mm, start, stop)
                except fmt.McapFormatError as err:
                    self.damaged(f"unreadable attachment or metadata record ({err})")
                    continue
                assert isinstance(record, fmt.Attachment | fmt.Metadata)
                found.append(record)
            elif op in (fmt.OP_DATA_END, fmt.OP_FOOTER):
                break
        return found

    def chunk_checks(self) -> tuple[list[str], list[str]]:
        """(problems, notes) of the chunks.

        Problems: chunks that do not decompress (the CRCs are checked by a read, into
        ``damage``). Notes: chunks whose messages are out of time order, which is legal
        (readers sort them).
        """
        found: list[str] = []
        notes: list[str] = []
        for rec, op, start, stop, complete in self._top(self._data_start, self._data_end):
            if op == fmt.OP_CHUNK and complete:
                try:
                    compression, size, data_start, dlen = self._chunk_fields(rec, start, stop)
                    buf, pos, end = self._chunk_data(compression, size, data_start, dlen, True)
                except fmt.McapFormatError as err:
                    found.append(f"chunk at {rec}: {err}")
                    continue
                late = self._out_of_order(buf, pos, end)
                if late:
                    notes.append(f"chunk at {rec}: {counted(late, 'message')} out of time order")
            elif op == fmt.OP_DATA_END:
                break
        return found, notes

    @staticmethod
    def _out_of_order(buf: bytes | memoryview, pos: int, end: int) -> int:
        """Message records of a chunk whose log time is before the one stored ahead of them."""
        times: list[int] = []
        try:
            for _, op, start, _ in fmt.records(buf, pos, end):
                if op == fmt.OP_MESSAGE:
                    times.append(_U64.unpack_from(buf, start + 6)[0])
        except fmt.McapFormatError:
            pass  # a damaged record is reported by the read itself
        return out_of_order(times)

    def _chunk_fields(
        self, rec: int, start: int, stop: int, complete: bool = True
    ) -> tuple[str, int, int, int]:
        """(compression, uncompressed size, records start, records length) of a chunk.

        For a cut-short chunk (``complete`` False) the records run to ``stop``.
        """
        try:
            _, _, size, _ = _CHUNK_HEAD.unpack_from(self._mm, start)
            (clen,) = _U32.unpack_from(self._mm, start + 28)
            compression = bytes(self._mm[start + 32 : start + 32 + clen]).decode()
            (dlen,) = _U64.unpack_from(self._mm, start + 32 + clen)
        except (struct.error, UnicodeDecodeError) as err:
            raise fmt.McapFormatError(f"chunk at {rec} has a malformed header") from err
        data_start = start + 40 + clen
        if not complete:
            return compression, size, data_start, max(0, min(dlen, stop - data_start))
        if data_start + dlen > stop:
            raise fmt.McapFormatError(f"chunk at {rec} holds more than its record")
        return compression, size, data_start, dlen

    def _chunk_data(
        self, compression: str, size: int, start: int, length: int, complete: bool
    ) -> tuple[bytes | memoryview, int, int]:
        """(buffer, start, end) of a chunk's records: in place when uncompressed."""
        if compression == "":
            return memoryview(self._mm), start, start + length
        raw = memoryview(self._mm)[start : start + length]
        try:
            data = (
                fmt.decompress(compression, raw, size)
                if complete
                else fmt.decompress_prefix(compression, raw, size)
            )
        finally:
            raw.release()
        return data, 0, len(data)

    def _inner(
        self, buf: bytes | memoryview, pos: int, end: int, rec: int, complete: bool
    ) -> Iterator[tuple[int, int]]:
        """(channel, log time) of the messages in a chunk; registers schemas and channels."""
        for _, op, start, stop in self._chunk_records(buf, pos, end, rec, complete):
            if op == fmt.OP_MESSAGE:
                channel_id, log = struct.unpack_from("<H4xQ", buf, start)
                yield channel_id, log
            elif op in (fmt.OP_SCHEMA, fmt.OP_CHANNEL):
                self._register_inner(op, buf, start - 9, stop, rec)

    def _chunk_records(
        self, buf: bytes | memoryview, pos: int, end: int, rec: int, complete: bool
    ) -> Iterator[tuple[int, int, int, int]]:
        """The records of a chunk, reading on past bytes that do not parse (listed in damage).

        Message records shorter than their fixed fields count as bytes that do not parse.
        """
        while pos < end:
            nxt = pos
            try:
                for at, op, start, stop in fmt.records(buf, pos, end):
                    if op == fmt.OP_MESSAGE and stop - start < 22:
                        raise fmt.McapFormatError(f"message at {at} is too short")
                    nxt = stop
                    yield at, op, start, stop
                return
            except fmt.McapFormatError as err:
                pos = self._read_on(buf, nxt, end, rec, complete, err)

    def _read_on(
        self, buf: bytes | memoryview, pos: int, end: int, rec: int, complete: bool, err: Exception
    ) -> int:
        """Where reading a chunk goes on after bytes at ``pos`` that do not parse (or ``end``)."""
        resume = fmt.next_record(buf, pos + 1, end, fmt.CHUNK_OPS) if complete else None
        if resume is None:
            how = "ends in a damaged record" if complete else "is cut short"
            self.damaged(f"chunk at {rec} {how} ({err})")
            return end
        self.damaged(
            f"chunk at {rec}: {resume - pos} bytes at {pos} do not parse ({err});"
            f" read on at {resume}"
        )
        return resume

    def _register_inner(
        self, op: int, buf: bytes | memoryview | mmap.mmap, pos: int, nxt: int, rec: int | None
    ) -> None:
        """Register the schema or channel record at ``pos``; a damaged one is listed.

        ``rec``: the chunk it lies in, or None at the top level.
        """
        try:
            self._register(fmt.parse(op, buf, pos + 9, nxt))
        except fmt.McapFormatError as err:
            where = f"chunk at {rec}: " if rec is not None else ""
            self.damaged(f"{where}skipped a damaged {_NAMES[op]} record at {pos} ({err})")

    def _register(self, record: fmt.Record | None) -> None:
        if isinstance(record, fmt.Schema):
            self.schemas.setdefault(record.id, record)
        elif isinstance(record, fmt.Channel) and record.id not in self.channels:
            self.channels[record.id] = record
            if self.connections:  # found while reading messages: add it now
                self._connection(record.id)

    def _connection(self, channel_id: int) -> Connection:
        conn = self._by_id.get(channel_id)
        if conn is None:
            conn = channel_connection(self.channels[channel_id], self.schemas)
            self._by_id[channel_id] = conn
            self.connections.append(conn)
        return conn

    # -- reading ---------------------------------------------------------------------------

    def info(self) -> BagInfo:
        """The summary, from the summary section when there is a complete one."""
        stats, scan = self.statistics, self._scan_result
        if scan is None and stats is not None:
            counts = dict(stats.channel_message_counts)
            total = stats.message_count
            start = stats.message_start_time if total else None
            end = stats.message_end_time if total else None
            chunks = [
                (i.compression or "none", i.compressed_size, i.uncompressed_size)
                for i in self.chunk_indexes
            ]
            attachments, metadata = stats.attachment_count, stats.metadata_count
        else:
            scan = scan or self._scan()
            counts, total = scan.counts, sum(scan.counts.values())
            start, end = scan.start, scan.end
            chunks, attachments, metadata = scan.chunks, scan.attachments, scan.metadata
        topics, types = summarize(self.connections, counts)
        return BagInfo(
            path=self.path,
            format="mcap",
            version="0",
            size=self.size,
            start_ns=start,
            end_ns=end,
            message_count=total,
            indexed=self.indexed,
            chunk_count=len(chunks),
            compression=compression_rows(chunks),
            connections=tuple(self.connections),
            connection_counts=counts,
            topics=topics,
            types=types,
            profile=self.profile,
            library=self.library,
            attachment_count=attachments,
            metadata_count=metadata,
        )

    def blocks(
        self, wanted: Mapping[int, tuple[int, Connection]], lo: int, hi: int, everything: bool
    ) -> list[Block]:
        """One block per chunk (loaded lazily) and per run of top-level messages."""
        wanted = dict(wanted)  # channels first seen inside chunks join it as they come
        mm = self._mm
        by_offset = {i.chunk_start_offset: i for i in self.chunk_indexes}
        blocks: list[Block] = []
        loose: list[Entry] = []
        whole = self.check_crcs and everything and lo == 0 and hi == MAX_TIME_NS
        section = _SectionCrc(self) if whole else None
        between = 0  # where the bytes after the last chunk start
        for rec, op, start, stop, complete in self._top(self._data_start, self._data_end):
            if op == fmt.OP_MESSAGE:
                _, _, channel_id, seq, log, pub = _MSG.unpack_from(mm, rec)
                if lo <= log <= hi and self._selects(channel_id, wanted, everything):
                    rank, conn = wanted[channel_id]
                    data = memoryview(mm)[start + 22 : stop]
                    loose.append((log, rank, rec, conn, data, seq, pub))
                continue
            if loose:
                blocks.append(_loose_block(loose, len(blocks)))
                loose = []
            if op == fmt.OP_CHUNK:
                first, last, _, _ = _CHUNK_HEAD.unpack_from(mm, start)
                index = by_offset.get(rec)
                if complete and (last < lo or first > hi):
                    continue
                if index is not None and (
                    index.message_start_time,
                    index.message_end_time,
                    index.chunk_length,
                ) != (first, last, stop - rec):
                    self.note(f"the summary's index of the chunk at {rec} does not match it")
                    index = None  # its channels are not this chunk's: read the chunk
                if (
                    index is not None
                    and index.message_index_offsets
                    and not everything
                    and wanted.keys().isdisjoint(index.message_index_offsets)
                    and self._channels_agree(index)
                ):
                    continue
                if section is not None:
                    section.between(mm, between, rec)
                    section.expect(rec)
                    between = stop
                load = partial(
                    self._entries,
                    rec,
                    start,
                    stop,
                    wanted,
                    everything,
                    lo,
                    hi,
                    complete,
                    section,
                )
                blocks.append(Block(first, len(blocks), load))
            elif op in (fmt.OP_SCHEMA, fmt.OP_CHANNEL):
                self._register_inner(op, mm, rec, stop, None)
            elif op == fmt.OP_DATA_END:
                (crc,) = _U32.unpack_from(mm, start)
                if section is not None and crc:  # 0: the writer computed none
                    section.between(mm, between, rec)
                    section.close(crc)
                break
            elif op == fmt.OP_FOOTER:
                break
        if loose:
            blocks.append(_loose_block(loose, len(blocks)))
        return blocks

    def _channels_agree(self, index: fmt.ChunkIndex) -> bool:
        """Whether the message indexes a chunk index points at are of the channels it names.

        Checked before the chunk is left out of a read by its channels, so a damaged chunk
        index hides nothing (noted when it disagrees).
        """
        mm = self._mm
        for channel_id, offset in index.message_index_offsets.items():
            if not (
                offset + 11 <= self.size
                and mm[offset] == fmt.OP_MESSAGE_INDEX
                and _U16.unpack_from(mm, offset + 9)[0] == channel_id
            ):
                self.note(
                    f"the summary's index of the chunk at {index.chunk_start_offset} names"
                    f" channels its message indexes do not"
                )
                return False
        return True

    def _selects(self, channel_id: int, wanted: _Wanted, everything: bool) -> bool:
        """Whether a read selects a channel.

        A channel first seen while reading (only inside chunks) joins an unfiltered read.
        """
        if channel_id in wanted:
            return True
        if not everything:
            return False
        if channel_id not in self.channels:
            self.damaged(f"messages on channel {channel_id}, which no channel record defines")
            return False
        wanted[channel_id] = (len(self.connections), self._connection(channel_id))
        return True

    def _entries(
        self,
        rec: int,
        start: int,
        stop: int,
        wanted: _Wanted,
        everything: bool,
        lo: int,
        hi: int,
        complete: bool,
        section: _SectionCrc | None = None,
    ) -> list[Entry]:
        """The wanted messages of one chunk from ``lo`` to ``hi`` ns, sorted.

        Never raises for what is in the file: a chunk that does not read, or fails its CRC,
        is listed in ``damage``, a time range that disagrees with the messages in ``notes``.
        ``section``: a whole read's data section CRC, which takes this chunk's record.
        """
        self._forget.up_to(rec)
        try:
            compression, size, data_start, dlen = self._chunk_fields(rec, start, stop, complete)
            buf, pos, end = self._chunk_data(compression, size, data_start, dlen, complete)
        except BagFormatError as err:
            what = "" if complete else "cut-short "
            self.damaged(f"{what}chunk at {rec} is unreadable ({err}); its messages are left out")
            return []
        view = memoryview(buf)
        holds, crc = self._crc_holds(rec, start, buf, pos, end) if complete else (None, 0)
        if section is not None:
            mm = memoryview(self._mm)
            if compression or holds is None:
                section.chunk(rec, fmt.crc32(mm[rec:stop]), stop - rec)
            else:  # the records are the file's bytes, and their CRC is known: fold it in
                crc = fmt.crc32_combine(fmt.crc32(mm[rec:pos]), crc, end - pos)
                crc = fmt.crc32_combine(crc, fmt.crc32(mm[end:stop]), stop - end)
                section.chunk(rec, crc, stop - rec)
        if holds is False:
            return []
        out = self._records(rec, buf, view, pos, end, wanted, everything, complete)
        out.sort()
        if out and complete:
            self._check_range(rec, start, out[0][0], out[-1][0], everything)
        if out and lo > out[0][0]:
            out = out[bisect_left(out, (lo,)) :]
        if out and hi < out[-1][0]:
            out = out[: bisect_left(out, (hi + 1,))]
        return out

    def _records(
        self,
        rec: int,
        buf: bytes | memoryview,
        view: memoryview,
        pos: int,
        end: int,
        wanted: _Wanted,
        everything: bool,
        complete: bool,
    ) -> list[Entry]:
        """The wanted messages among a chunk's records, in file order, from ``pos`` to ``end``.

        Schemas and channels inside the chunk are registered on the way; bytes that do not
        parse are read past (``_read_on``).
        """
        out: list[Entry] = []
        append = out.append
        unpack = _MSG.unpack_from
        while pos < end:
            try:
                while pos < end:
                    if pos + 31 > end:
                        op, length = (
                            _PREFIX.unpack_from(buf, pos) if pos + 9 <= end else (0, 1 << 62)
                        )
                        if pos + 9 + length > end:
                            raise _cut(pos, length, end)
                        if op in (fmt.OP_SCHEMA, fmt.OP_CHANNEL):  # short: a channel's, say
                            self._register_inner(op, buf, pos, pos + 9 + length, rec)
                        pos += 9 + length
                        continue
                    op, length, channel_id, seq, log, pub = unpack(buf, pos)
                    nxt = pos + 9 + length
                    if nxt > end:
                        raise _cut(pos, length, end)
                    if op == fmt.OP_MESSAGE:
                        if length < 22:
                            raise fmt.McapFormatError(f"message at {pos} is too short")
                        if self._selects(channel_id, wanted, everything):
                            rank, conn = wanted[channel_id]
                            append((log, rank, pos, conn, view[pos + 31 : nxt], seq, pub))
                    elif op in (fmt.OP_SCHEMA, fmt.OP_CHANNEL):
                        self._register_inner(op, buf, pos, nxt, rec)
                    pos = nxt
            except fmt.McapFormatError as err:
                pos = self._read_on(buf, pos, end, rec, complete, err)
        return out

    def _crc_holds(
        self, rec: int, start: int, buf: bytes | memoryview, pos: int, end: int
    ) -> tuple[bool | None, int]:
        """(whether a whole chunk's records, ``buf[pos:end]``, match its CRC, the CRC).

        (None, 0) when unchecked. A mismatch is damage, said once with the messages it costs
        (all of the chunk's: none of them can be shown intact).
        """
        stored = _CHUNK_HEAD.unpack_from(self._mm, start)[3]
        if not stored or not self.check_crcs:  # 0: the writer computed none
            return None, 0
        crc = fmt.crc32(memoryview(buf)[pos:end])
        if crc == stored:
            return True, crc
        self.crc_failed = True
        count = 0
        try:
            for _, op, _, _ in fmt.records(buf, pos, end):
                count += op == fmt.OP_MESSAGE
        except fmt.McapFormatError:
            pass  # what parses is counted: the damage may be anywhere
        self.damaged(
            f"chunk at {rec}: its CRC does not match its records; its"
            f" {counted(count, 'message')} {'is' if count == 1 else 'are'} left out"
        )
        return False, crc

    def _check_range(self, rec: int, start: int, low: int, high: int, everything: bool) -> None:
        """Note a chunk whose messages run outside its header's time range.

        Every message read: the range must be the header's; some: within it.
        """
        first, last = _CHUNK_HEAD.unpack_from(self._mm, start)[:2]
        if (low, high) != (first, last) if everything else (low < first or high > last):
            self.note(
                f"chunk at {rec}: its messages run from {low} to {high} ns, its"
                f" header says {first} to {last}"
            )

    def close(self) -> None:
        """Release the file map."""
        release(getattr(self, "_mm", None))


def _loose_block(entries: list[Entry], order: int) -> Block:
    """A block for a run of messages outside chunks."""
    entries.sort()
    return Block(entries[0][0], order, lambda: entries)


def channel_connection(channel: fmt.Channel, schemas: Mapping[int, fmt.Schema]) -> Connection:
    """The ``Connection`` a channel stands for under the ROS 1 profile.

    Metadata ``callerid``, ``latching`` ("true"/"false") and ``md5sum`` become attributes; any
    other metadata is kept in ``extra``. A missing md5sum is computed from a ``ros1msg``
    definition, as converters do.
    """
    schema = schemas.get(channel.schema_id)
    meta = dict(channel.metadata)
    callerid = meta.pop("callerid", "")
    latching = meta.pop("latching", None)
    md5sum = meta.pop("md5sum", "")
    name = schema.name if schema else ""
    definition = schema.data.decode("utf-8", "replace") if schema else ""
    if not md5sum and schema is not None and schema.encoding == "ros1msg":
        from rostools.msgs.store import md5_of

        md5sum = md5_of(name, definition)
    return Connection(
        id=channel.id,
        topic=channel.topic,
        type=name,
        md5sum=md5sum,
        definition=definition,
        callerid=callerid,
        latching=latching in ("true", "1"),
        extra=meta,
        absent=frozenset() if latching is not None else frozenset({"latching"}),
        encoding=channel.message_encoding,
        schema_encoding=schema.encoding if schema else "",
    )


def _cut(pos: int, length: int, end: int) -> fmt.McapFormatError:
    """A record that does not fit, said as ``fmt.records`` says it.

    The scan before a read met it too, and the damage lists it once.
    """
    if pos + 9 > end:
        return fmt.McapFormatError(f"record at {pos} is cut short")
    return fmt.McapFormatError(f"record at {pos} ({length} bytes) is cut short or corrupt")
