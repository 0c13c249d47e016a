"""Writing MCAP files under the ROS 1 profile (what Foxglove and ``mcap`` tools expect).

Profile ``ros1``; one schema per distinct type definition (encoding ``ros1msg``, the full
``message_definition`` text) and one channel per publisher connection (message encoding
``ros1``, metadata ``callerid``, ``latching`` as "true"/"false", and ``md5sum`` as Foxglove's
converter stores it). Channel ids are the connection ids, from 0 like a ``.bag``'s.

Chunked (zstd, lz4 or none), with message indexes after every chunk and a summary of schemas,
channels, statistics and chunk indexes plus summary offsets. Schemas and channels go outside
the chunks as soon as they are declared, and every chunk goes to the OS when it closes, so a
killed writer leaves everything but the open chunk recoverable.

``store_stream`` stores a whole stream in one loop, each message's bytes appended straight
into the open chunk by a function of the caller's (``bag convert --to ros2``'s converters):
a message costs its conversion, a record head and two index numbers.

Every CRC the format has is written: each chunk's (over its uncompressed records), the data
section's (in DataEnd) and the summary's (in the footer), so ``bag doctor`` and other readers
can tell a flipped bit. They cost one pass of ``crc32`` (zlib-ng's, ``mcap_format``) over
what is written; a chunk stored uncompressed is passed over once, its CRC folded into the data
section's (``crc32_combine``).
"""

from __future__ import annotations

import struct
from array import array
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any, Final

from rostools.bag.formats import mcap_format as fmt
from rostools.bag.formats.base import BagWriter
from rostools.bag.formats.model import BagUsageError, Connection, UnsupportedBagError
from rostools.bag.formats.sink import BIG_PAYLOAD, frozen, little_endian
from rostools.version import __version__

#: Chunk threshold (uncompressed bytes): rosbag's 768 KiB, close to the mcap library's 1 MiB.
DEFAULT_CHUNK_SIZE: Final = 768 * 1024
COMPRESSIONS: Final = ("zstd", "lz4", "none")
#: Channel ids are u16 in MCAP.
MAX_CHANNELS: Final = 1 << 16
#: zstd level 3 is the library default and what the mcap writers use.
ZSTD_LEVEL: Final = 3
_MAX_TIME: Final = (1 << 64) - 1
_MSG = fmt.MESSAGE_PREFIX
_Chunk = bytes | bytearray | memoryview
#: Compresses a chunk's records, given in pieces, into pieces of the stored bytes.
_Compress = Callable[[list[_Chunk]], list[_Chunk]]
#: Takes the open chunk's buffer and a big run of bytes (``buf[start:end]``) by reference;
#: gives the buffer to go on with.
Cut = Callable[[bytearray, _Chunk, int, int], bytearray]
#: Appends one message's bytes to the open chunk (``store_stream``).
Append = Callable[[Any, bytearray, int, Cut], bytearray]
_BLANK: Final = bytes(_MSG.size)


class McapWriter(BagWriter):
    """An MCAP file being written; see the module docstring."""

    def __init__(
        self,
        path: str | Path,
        *,
        compression: str = "zstd",
        chunk_size: int = DEFAULT_CHUNK_SIZE,
        overwrite: bool = False,
        profile: str = "ros1",
        library: str = f"rostools {__version__}",
    ) -> None:
        if compression not in COMPRESSIONS:
            raise UnsupportedBagError(
                f"unknown MCAP compression {compression!r} (use zstd, lz4 or none)"
            )
        if chunk_size <= 0:
            raise BagUsageError(f"chunk size must be positive, not {chunk_size}")
        compress = _compressor(compression)
        super().__init__(path, overwrite)
        self.compression = compression
        self.chunk_size = chunk_size
        self._compress = compress
        self._schema_ids: dict[tuple[str, str, str], int] = {}
        self._schema_records: list[bytes] = []
        self._channel_records: list[bytes] = []
        self._counts: list[int] = []
        # The open chunk: its small records coalesced, big payloads kept by reference.
        self._chunk_small = bytearray()
        self._chunk_pieces: list[bytes | bytearray | memoryview] = []
        self._chunk_len = 0
        self._chunk_start = 0
        self._chunk_end = 0
        # Per channel, the open chunk's (log time, offset) pairs: emptied, not replaced, when
        # a chunk closes (``store_stream`` keeps them at hand).
        self._index: dict[int, array[int]] = {}
        self._unsorted = False
        self._chunk_indexes: list[fmt.ChunkIndex] = []
        self._attachment_indexes: list[bytes] = []
        self._metadata_indexes: list[bytes] = []
        self._start = _MAX_TIME
        self._end = 0
        self._data_crc = 0  # of every byte written so far, for DataEnd
        try:
            self._write(fmt.MAGIC)
            self._write(fmt.encode_header(profile, library))
            self._sink.flush()
        except BaseException:
            self.abort()  # a disk already full: no file, and no open descriptor
            raise

    # -- the public interface --------------------------------------------------------------

    def _declare(self, conn: Connection) -> None:
        """A channel (and its schema, once per definition), written at once."""
        if len(self._connections) >= MAX_CHANNELS:
            raise BagUsageError(f"an MCAP file holds at most {MAX_CHANNELS} channels")
        key = (conn.type, conn.definition, conn.schema_encoding)
        schema_id = 0 if not conn.schema_encoding else self._schema_ids.get(key)
        if schema_id is None:
            schema_id = self._schema_ids[key] = len(self._schema_records) + 1
            definition = conn.definition.encode()
            record = fmt.encode_schema(schema_id, conn.type, conn.schema_encoding, definition)
            self._schema_records.append(record)
            self._write(record)
        meta = channel_metadata(conn)
        record = fmt.encode_channel(conn.id, schema_id, conn.topic, conn.encoding, meta)
        self._channel_records.append(record)
        self._write(record)
        self._counts.append(0)

    def _store(self, cid: int, t_ns: int, data: bytes | bytearray | memoryview) -> None:
        if not 0 <= t_ns <= _MAX_TIME:
            raise BagUsageError(f"time {t_ns} ns does not fit an MCAP file")
        offset = self._chunk_len
        if not offset:
            self._chunk_start = self._chunk_end = t_ns
        elif t_ns > self._chunk_end:
            self._chunk_end = t_ns
        elif t_ns < self._chunk_end:
            self._unsorted = True  # message indexes get sorted when the chunk closes
            if t_ns < self._chunk_start:
                self._chunk_start = t_ns
        index = self._index.get(cid)
        if index is None:
            index = self._index[cid] = array("Q")
        seq = self._counts[cid]
        self._counts[cid] = seq + 1
        index.append(t_ns)
        index.append(offset)
        size = len(data)
        small = self._chunk_small
        small += _MSG.pack(5, 22 + size, cid, seq & 0xFFFFFFFF, t_ns, t_ns)
        if size >= BIG_PAYLOAD:
            self._chunk_pieces.append(small)
            self._chunk_pieces.append(frozen(data))
            self._chunk_small = bytearray()
        else:
            small += data
        self._chunk_len = offset + 31 + size
        if self._chunk_len >= self.chunk_size:
            self._close_chunk()

    def store_stream(
        self,
        stream: Iterable[tuple[object, int, _Chunk]],
        route: Callable[[Any], tuple[int, Append]],
        *,
        skip: type[Exception] | tuple[type[Exception], ...] = (),
        on_skip: Callable[[Any, Exception], None] | None = None,
    ) -> tuple[int, int]:
        """Store ``(key, log time ns, data)`` messages: (messages read, messages stored).

        ``route(key)``, asked once per key (known by identity: the caller keeps keys alive),
        gives the channel id and ``append(data, out, b, cut) -> out`` (the contract of
        ``ros2cdr.Converters.appender``): the message's bytes go straight into the open chunk,
        no buffer per message, and a big run of them by reference (``cut``). A message whose
        ``append`` raises one of ``skip`` is taken back out and given to ``on_skip``. Any other
        exception leaves the writer to be aborted.
        """
        self._check_open()
        routes: dict[int, tuple[int, Append, array[int]]] = {}
        keys = []  # alive while their ids are in ``routes``
        pack_into = _MSG.pack_into
        blank = _BLANK
        limit = self.chunk_size
        counts = self._counts
        before = sum(counts)
        small = self._chunk_small
        index = self._index
        cut = self._cut
        pb = self._chunk_len - len(small)  # bytes of the open chunk in ``_chunk_pieces``
        first, last, unsorted = self._chunk_start, self._chunk_end, self._unsorted
        skipped = t = 0
        # No closures: the loop's variables stay plain locals, the fastest kind.
        try:
            for key, t, data in stream:
                found = routes.get(id(key))
                if found is None:
                    cid, append = route(key)
                    entries = index.get(cid)
                    if entries is None:
                        entries = index[cid] = array("Q")
                    found = routes[id(key)] = (cid, append, entries)
                    keys.append(key)
                cid, append, entries = found
                at = len(small)
                off = pb + at
                small += blank  # the record's head, packed once its length is known
                try:
                    out = append(data, small, at + 35, cut)
                except skip as err:
                    pieces = self._chunk_pieces
                    for i, piece in enumerate(pieces):
                        if piece is small:  # a cut in this message: take it back
                            del pieces[i:]
                            break
                    del small[at:]
                    skipped += 1
                    if on_skip is not None:
                        on_skip(key, err)
                    continue
                if out is not small:  # a big run went by reference
                    pb = sum(map(len, self._chunk_pieces))
                seq = counts[cid]
                counts[cid] = seq + 1
                # the record's length: 22 + the data's (``pb`` grew by what was cut)
                pack_into(small, at, 5, pb + len(out) - off - 9, cid, seq & 0xFFFFFFFF, t, t)
                small = out
                entries.append(t)
                entries.append(off)
                if not off:
                    first = last = t
                elif t >= last:
                    last = t
                else:
                    unsorted = True  # message indexes get sorted when the chunk closes
                    if t < first:
                        first = t
                if pb + len(small) >= limit:
                    self._chunk_small, self._chunk_len = small, pb + len(small)
                    self._chunk_start, self._chunk_end, self._unsorted = first, last, unsorted
                    self._close_chunk()
                    small, pb, unsorted = self._chunk_small, 0, False
        except struct.error:
            raise BagUsageError(f"time {t} ns does not fit an MCAP file") from None
        finally:
            self._chunk_small, self._chunk_len = small, pb + len(small)
            self._chunk_start, self._chunk_end, self._unsorted = first, last, unsorted
        stored = sum(counts) - before
        return stored + skipped, stored

    def _cut(self, out: bytearray, buf: _Chunk, start: int, end: int) -> bytearray:
        """``store_stream``'s ``cut``: ``out`` and ``buf[start:end]`` join the chunk's pieces.

        The run goes by reference if it cannot change; the message goes on in a new buffer.
        """
        self._chunk_pieces.append(out)
        self._chunk_pieces.append(frozen(memoryview(buf)[start:end]))
        return bytearray()

    def time_span(self) -> tuple[int, int] | None:
        """The earliest and latest log time written so far, the open chunk's too (or None)."""
        start, end = self._start, self._end
        if self._chunk_len:
            start, end = min(start, self._chunk_start), max(end, self._chunk_end)
        return (start, end) if start <= end else None

    def sequence(self, channel_id: int) -> int:
        """How many messages a channel has so far (the next message's sequence number)."""
        return self._counts[channel_id]

    def end_chunk(self) -> None:
        """Close the open chunk, if any (the next message starts a new one)."""
        if self._chunk_len:
            self._close_chunk()

    def write_chunk(
        self,
        start: int,
        end: int,
        records: bytes | memoryview,
        indexes: Mapping[int, bytes],
        counts: Mapping[int, int],
    ) -> None:
        """Store a chunk built elsewhere (``fastcopy``): its message records, their index.

        ``indexes`` maps channels to packed (log time, offset) pairs; ``counts`` says how many
        messages of each channel the records hold.
        """
        self._check_open()
        self.end_chunk()
        self._chunk_pieces = [records]
        self._chunk_len = len(records)
        self._chunk_start, self._chunk_end = start, end
        for cid, n in counts.items():
            self._counts[cid] += n
        self._close_chunk(indexes)

    def _packed_index(self, cid: int) -> bytes:
        """A channel's (log time, offset) pairs in the open chunk, sorted, as file bytes."""
        entries = self._index[cid]
        if self._unsorted:
            pairs = sorted(zip(entries[::2], entries[1::2], strict=True))
            entries = array("Q", [v for pair in pairs for v in pair])
        return little_endian(entries)

    def add_extra(self, record: fmt.Attachment | fmt.Metadata) -> None:
        """Write an attachment or a metadata record (outside chunks) and index it."""
        self._check_open()
        pos = self._sink.tell()
        if isinstance(record, fmt.Attachment):
            raw = fmt.encode_attachment(record)
            index = fmt.encode_attachment_index(
                fmt.AttachmentIndex(
                    pos, len(raw), record.log_time, record.create_time, len(record.data),
                    record.name, record.media_type,
                )
            )  # fmt: skip
            self._attachment_indexes.append(index)
        else:
            raw = fmt.encode_metadata(record.name, record.metadata)
            self._metadata_indexes.append(
                fmt.encode_metadata_index(fmt.MetadataIndex(pos, len(raw), record.name))
            )
        self._write(raw)

    def flush(self) -> None:
        """Close the open chunk and hand everything to the OS."""
        self._check_open()
        if self._chunk_len:
            self._close_chunk()
        self._sink.flush()

    def close(self) -> None:
        """Write the last chunk, the data end, the summary and the footer."""
        if self._closed:
            return
        try:
            if self._chunk_len:
                self._close_chunk()
            self._sink.write(fmt.encode_data_end(self._data_crc))
            summary_start = self._sink.tell()
            summary = bytearray()
            offsets = bytearray()
            groups: list[tuple[int, list[bytes]]] = [
                (fmt.OP_SCHEMA, self._schema_records),
                (fmt.OP_CHANNEL, self._channel_records),
                (fmt.OP_STATISTICS, [fmt.encode_statistics(self._statistics())]),
                (fmt.OP_CHUNK_INDEX, [fmt.encode_chunk_index(i) for i in self._chunk_indexes]),
                (fmt.OP_ATTACHMENT_INDEX, self._attachment_indexes),
                (fmt.OP_METADATA_INDEX, self._metadata_indexes),
            ]
            for opcode, group in groups:
                if group:
                    body = b"".join(group)
                    offsets += fmt.encode_summary_offset(
                        opcode, summary_start + len(summary), len(body)
                    )
                    summary += body
            offset_start = summary_start + len(summary)
            summary += offsets
            self._sink.write(summary)
            self._sink.write(fmt.encode_footer(summary_start, offset_start, bytes(summary)))
            self._sink.flush()
        finally:
            self._release()

    # -- internals -------------------------------------------------------------------------

    def _write(self, data: _Chunk) -> None:
        """Append bytes of the data section, counting them into its CRC."""
        self._data_crc = fmt.crc32(data, self._data_crc)
        self._sink.write(data)

    def _statistics(self) -> fmt.Statistics:
        total = sum(self._counts)
        return fmt.Statistics(
            message_count=total,
            schema_count=len(self._schema_records),
            channel_count=len(self._channel_records),
            attachment_count=len(self._attachment_indexes),
            metadata_count=len(self._metadata_indexes),
            chunk_count=len(self._chunk_indexes),
            message_start_time=self._start if total else 0,
            message_end_time=self._end if total else 0,
            channel_message_counts={i: n for i, n in enumerate(self._counts) if n},
        )

    def _close_chunk(self, packed: Mapping[int, bytes] | None = None) -> None:
        pieces = self._chunk_pieces
        if self._chunk_small:
            pieces.append(self._chunk_small)
        size = self._chunk_len
        start, end = self._chunk_start, self._chunk_end
        self._start = min(self._start, start)
        self._end = max(self._end, end)
        compression = "" if self.compression == "none" else self.compression
        sink = self._sink
        chunk_pos = sink.tell()
        crc = 0
        for piece in pieces:
            crc = fmt.crc32(piece, crc)
        stored_pieces = self._compress(pieces)
        stored = sum(len(p) for p in stored_pieces)
        self._write(fmt.encode_chunk_head(start, end, size, compression, stored, crc))
        if compression:
            for piece in stored_pieces:
                self._write(piece)
        else:  # the records as they are: their CRC is known, fold it in
            for piece in stored_pieces:
                sink.write(piece)
            self._data_crc = fmt.crc32_combine(self._data_crc, crc, size)
        index_start = sink.tell()
        offsets: dict[int, int] = {}
        if packed is None:
            packed = {cid: self._packed_index(cid) for cid, e in self._index.items() if e}
        for cid in sorted(packed):
            offsets[cid] = sink.tell()
            self._write(fmt.encode_message_index(cid, packed[cid]))
        self._chunk_indexes.append(
            fmt.ChunkIndex(
                message_start_time=start,
                message_end_time=end,
                chunk_start_offset=chunk_pos,
                chunk_length=index_start - chunk_pos,
                message_index_offsets=offsets,
                message_index_length=sink.tell() - index_start,
                compression=compression,
                compressed_size=stored,
                uncompressed_size=size,
            )
        )
        self._chunk_small = bytearray()
        self._chunk_pieces = []
        self._chunk_len = 0
        for entries in self._index.values():
            del entries[:]
        self._unsorted = False
        sink.flush()


def channel_metadata(conn: Connection) -> dict[str, str]:
    """The ROS 1 profile's channel metadata for a connection (plus its extra header fields).

    A channel that is not ROS 1 (ROS 2 CDR, copied as it is) keeps its own metadata alone.
    """
    meta = dict(conn.extra)
    if conn.encoding != "ros1":
        return meta
    if conn.callerid:
        meta["callerid"] = conn.callerid
    if "latching" not in conn.absent:
        meta["latching"] = "true" if conn.latching else "false"
    meta["md5sum"] = conn.md5sum
    return meta


def _compressor(kind: str) -> _Compress:
    """Compresses a chunk given as pieces, into pieces: big payloads are never joined."""
    if kind == "zstd":
        import zstandard

        compressor = zstandard.ZstdCompressor(level=ZSTD_LEVEL)

        def zstd(pieces: list[_Chunk]) -> list[_Chunk]:
            if len(pieces) == 1:
                return [compressor.compress(pieces[0])]
            stream = compressor.compressobj(size=sum(len(p) for p in pieces))
            out: list[_Chunk] = [stream.compress(piece) for piece in pieces]
            out.append(stream.flush())
            return out

        return zstd
    if kind == "lz4":
        import lz4.frame

        def lz4_frame(pieces: list[_Chunk]) -> list[_Chunk]:
            if len(pieces) == 1:
                return [bytes(lz4.frame.compress(pieces[0]))]
            stream = lz4.frame.LZ4FrameCompressor()
            out: list[_Chunk] = [stream.begin()]
            out += [stream.compress(piece) for piece in pieces]
            out.append(stream.flush())
            return out

        return lz4_frame
    return list
