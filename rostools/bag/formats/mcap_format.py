"""MCAP records: opcodes, parsing and encoding (https://mcap.dev/spec).

Pure functions over bytes, shared by the MCAP reader, writer and recovery. Every record is
``u8 opcode, u64 length, content``; a record may carry bytes after its known fields (newer
writers, the conformance suite's ``pad`` variants), which readers must skip.

We parse and build the records ourselves rather than through the ``mcap`` package: its
readers mis-handle files whose summary lacks channels, and its writer spends about 6 us per
message, which caps a conversion of small messages far below the speed of the disk.
"""

from __future__ import annotations

import mmap
import struct
from collections.abc import Collection, Iterator, Mapping
from typing import Final, NamedTuple

# The one CRC-32 of the MCAP code, zlib-ng's: 20 to 30 GB/s here where zlib's is 2 to 4 (it
# folds with carry-less multiplies), which is what lets every read check every chunk's CRC;
# and crc32_combine (the CRC of a + b from those of a and b), which Python's zlib lacks.
from zlib_ng.zlib_ng import crc32 as crc32, crc32_combine as crc32_combine

from rostools.bag.formats.model import BagFormatError, UnsupportedBagError

MAGIC: Final = b"\x89MCAP0\r\n"

OP_HEADER: Final = 0x01
OP_FOOTER: Final = 0x02
OP_SCHEMA: Final = 0x03
OP_CHANNEL: Final = 0x04
OP_MESSAGE: Final = 0x05
OP_CHUNK: Final = 0x06
OP_MESSAGE_INDEX: Final = 0x07
OP_CHUNK_INDEX: Final = 0x08
OP_ATTACHMENT: Final = 0x09
OP_ATTACHMENT_INDEX: Final = 0x0A
OP_STATISTICS: Final = 0x0B
OP_METADATA: Final = 0x0C
OP_METADATA_INDEX: Final = 0x0D
OP_SUMMARY_OFFSET: Final = 0x0E
OP_DATA_END: Final = 0x0F

#: Largest record we read whole (a chunk, an attachment): the mcap library's default
#: ``record_size_limit`` is 4 GiB; chunks are about 1 MiB, so a bigger length is corruption.
MAX_RECORD_SIZE: Final = 1 << 32
#: Largest decompressed chunk we allocate (writers default to 1 MiB chunks; ours 768 KiB).
MAX_CHUNK_SIZE: Final = 1 << 30

#: u8 opcode, u64 length.
PREFIX: Final = struct.Struct("<BQ")
#: A whole message record up to its data: opcode, length, channel, sequence, log, publish.
MESSAGE_PREFIX: Final = struct.Struct("<BQHIQQ")
#: The footer record with the closing magic: the last 37 bytes of a finished file.
FOOTER_SIZE: Final = PREFIX.size + 20
_FOOTER: Final = struct.Struct("<BQQQI")
_U8 = struct.Struct("<B")
_U16 = struct.Struct("<H")
_U32 = struct.Struct("<I")
_U64 = struct.Struct("<Q")

#: What the parsers read from (bytes, a memoryview, a file map).
Buffer = bytes | bytearray | memoryview | mmap.mmap


class McapFormatError(BagFormatError):
    """MCAP bytes that do not parse: a truncated or malformed record."""


class Header(NamedTuple):
    """First record: the file's profile (``ros1``, ``ros2``, ...) and writing library."""

    profile: str
    library: str


class Footer(NamedTuple):
    """Last record: where the summary section and its offsets start (0: none)."""

    summary_start: int
    summary_offset_start: int
    summary_crc: int


class Schema(NamedTuple):
    """A message type: name, encoding (``ros1msg``) and definition bytes."""

    id: int
    name: str
    encoding: str
    data: bytes


class Channel(NamedTuple):
    """A stream of messages on one topic (for ROS 1: one publisher connection)."""

    id: int
    schema_id: int
    topic: str
    message_encoding: str
    metadata: dict[str, str]


class MessageRecord(NamedTuple):
    """One message."""

    channel_id: int
    sequence: int
    log_time: int
    publish_time: int
    data: bytes


class McapChunk(NamedTuple):
    """A compressed batch of schema, channel and message records."""

    message_start_time: int
    message_end_time: int
    uncompressed_size: int
    uncompressed_crc: int
    compression: str
    records: bytes


class MessageIndex(NamedTuple):
    """(log_time, offset in the uncompressed chunk) of one channel's messages in a chunk."""

    channel_id: int
    records: list[tuple[int, int]]


class ChunkIndex(NamedTuple):
    """Summary entry of one chunk: times, position, sizes, message index offsets."""

    message_start_time: int
    message_end_time: int
    chunk_start_offset: int
    chunk_length: int
    message_index_offsets: dict[int, int]
    message_index_length: int
    compression: str
    compressed_size: int
    uncompressed_size: int


class Attachment(NamedTuple):
    """An arbitrary file stored in the recording."""

    log_time: int
    create_time: int
    name: str
    media_type: str
    data: bytes
    crc: int


class AttachmentIndex(NamedTuple):
    """Summary entry of one attachment."""

    offset: int
    length: int
    log_time: int
    create_time: int
    data_size: int
    name: str
    media_type: str


class Statistics(NamedTuple):
    """Counts and the time range of the whole file."""

    message_count: int
    schema_count: int
    channel_count: int
    attachment_count: int
    metadata_count: int
    chunk_count: int
    message_start_time: int
    message_end_time: int
    channel_message_counts: dict[int, int]


class Metadata(NamedTuple):
    """A named string map."""

    name: str
    metadata: dict[str, str]


class MetadataIndex(NamedTuple):
    """Summary entry of one metadata record."""

    offset: int
    length: int
    name: str


class SummaryOffset(NamedTuple):
    """Where the summary's records of one opcode are."""

    group_opcode: int
    group_start: int
    group_length: int


class DataEnd(NamedTuple):
    """End of the data section."""

    data_section_crc: int


Record = (
    Header
    | Footer
    | Schema
    | Channel
    | MessageRecord
    | McapChunk
    | MessageIndex
    | ChunkIndex
    | Attachment
    | AttachmentIndex
    | Statistics
    | Metadata
    | MetadataIndex
    | SummaryOffset
    | DataEnd
)


class _Cursor:
    """Reads the fields of one record's content, never past its end."""

    __slots__ = ("buf", "end", "pos")

    def __init__(self, buf: Buffer, pos: int, end: int) -> None:
        self.buf, self.pos, self.end = buf, pos, end

    def take(self, size: int) -> int:
        start = self.pos
        if size < 0 or start + size > self.end:
            raise McapFormatError(f"record field of {size} bytes overruns its record")
        self.pos = start + size
        return start

    def u8(self) -> int:
        return int(_U8.unpack_from(self.buf, self.take(1))[0])

    def u16(self) -> int:
        return int(_U16.unpack_from(self.buf, self.take(2))[0])

    def u32(self) -> int:
        return int(_U32.unpack_from(self.buf, self.take(4))[0])

    def u64(self) -> int:
        return int(_U64.unpack_from(self.buf, self.take(8))[0])

    def raw(self, size: int) -> bytes:
        start = self.take(size)
        return bytes(self.buf[start : start + size])

    def string(self) -> str:
        try:
            return self.raw(self.u32()).decode("utf-8")
        except UnicodeDecodeError as err:
            raise McapFormatError(f"string field is not UTF-8: {err}") from err

    def str_map(self) -> dict[str, str]:
        size = self.u32()
        start = self.take(size)
        inner = _Cursor(self.buf, start, start + size)
        out: dict[str, str] = {}
        while inner.pos < inner.end:
            key = inner.string()
            out[key] = inner.string()
        return out

    def id_map(self) -> dict[int, int]:
        size = self.u32()
        start = self.take(size)
        inner = _Cursor(self.buf, start, start + size)
        out: dict[int, int] = {}
        while inner.pos < inner.end:
            key = inner.u16()
            out[key] = inner.u64()
        return out


def parse(op: int, buf: Buffer, pos: int, end: int) -> Record | None:
    """The record with opcode ``op`` whose content is ``buf[pos:end]``; None if unknown."""
    c = _Cursor(buf, pos, end)
    try:
        if op == OP_MESSAGE:
            channel, seq, log, pub = struct.unpack_from("<HIQQ", buf, c.take(22))
            return MessageRecord(channel, seq, log, pub, bytes(buf[c.pos : end]))
        if op == OP_SCHEMA:
            return Schema(c.u16(), c.string(), c.string(), c.raw(c.u32()))
        if op == OP_CHANNEL:
            return Channel(c.u16(), c.u16(), c.string(), c.string(), c.str_map())
        if op == OP_HEADER:
            return Header(c.string(), c.string())
        if op == OP_FOOTER:
            return Footer(c.u64(), c.u64(), c.u32())
        if op == OP_CHUNK:
            start, stop, size, crc = c.u64(), c.u64(), c.u64(), c.u32()
            compression = c.string()
            return McapChunk(start, stop, size, crc, compression, c.raw(c.u64()))
        if op == OP_MESSAGE_INDEX:
            channel = c.u16()
            size = c.u32()
            if size % 16:
                raise McapFormatError("message index entries are not 16 bytes each")
            flat = struct.unpack_from(f"<{size // 8}Q", buf, c.take(size))
            return MessageIndex(channel, list(zip(flat[::2], flat[1::2], strict=True)))
        if op == OP_CHUNK_INDEX:
            return ChunkIndex(
                c.u64(),
                c.u64(),
                c.u64(),
                c.u64(),
                c.id_map(),
                c.u64(),
                c.string(),
                c.u64(),
                c.u64(),
            )
        if op == OP_ATTACHMENT:
            log, create = c.u64(), c.u64()
            name, media = c.string(), c.string()
            return Attachment(log, create, name, media, c.raw(c.u64()), c.u32())
        if op == OP_ATTACHMENT_INDEX:
            return AttachmentIndex(
                c.u64(), c.u64(), c.u64(), c.u64(), c.u64(), c.string(), c.string()
            )
        if op == OP_STATISTICS:
            return Statistics(
                c.u64(), c.u16(), c.u32(), c.u32(), c.u32(), c.u32(), c.u64(), c.u64(), c.id_map()
            )
        if op == OP_METADATA:
            return Metadata(c.string(), c.str_map())
        if op == OP_METADATA_INDEX:
            return MetadataIndex(c.u64(), c.u64(), c.string())
        if op == OP_SUMMARY_OFFSET:
            return SummaryOffset(c.u8(), c.u64(), c.u64())
        if op == OP_DATA_END:
            return DataEnd(c.u32())
    except struct.error as err:
        raise McapFormatError(f"record with opcode {op:#04x} is cut short") from err
    return None


def records(buf: Buffer, pos: int, end: int) -> Iterator[tuple[int, int, int, int]]:
    """(record start, opcode, content start, content end) of each record in ``buf[pos:end]``.

    Raises ``McapFormatError`` at a record that does not fit before ``end``.
    """
    while pos < end:
        if pos + 9 > end:
            raise McapFormatError(f"record at {pos} is cut short")
        op, length = PREFIX.unpack_from(buf, pos)
        content = pos + 9
        if length > MAX_RECORD_SIZE or content + length > end:
            raise McapFormatError(f"record at {pos} ({length} bytes) is cut short or corrupt")
        yield pos, op, content, content + length
        pos = content + length


#: Records worth reading on at after damage in the data section, and inside a chunk.
DATA_OPS: Final = frozenset(
    (OP_SCHEMA, OP_CHANNEL, OP_MESSAGE, OP_CHUNK, OP_MESSAGE_INDEX, OP_ATTACHMENT,
     OP_METADATA, OP_DATA_END)
)  # fmt: skip
CHUNK_OPS: Final = frozenset((OP_SCHEMA, OP_CHANNEL, OP_MESSAGE))
#: Compression names a chunk may give: what a resync takes a chunk header to be.
_KNOWN_COMPRESSIONS: Final = ("", "zstd", "lz4")


def next_record(buf: Buffer, start: int, end: int, ops: Collection[int]) -> int | None:
    """Where the first plausible record of one of ``ops`` at or after ``start`` begins, or None.

    What reading on after damage needs. MCAP records have no marker, so a place counts when
    its record parses as its opcode says (a chunk's header is checked field by field) and the
    record after it is one of ``ops`` that fits too, or the end: random bytes pass both
    checks about once in 2**70 places.
    """
    import re  # only after damage: 5 ms that opening a file need not pay

    pattern = re.compile(b"[" + re.escape(bytes(sorted(ops))) + b"]")
    hit = pattern.search(buf, start, end)
    while hit is not None:
        at = hit.start()
        nxt = _plausible(buf, at, end, ops)
        if nxt is not None and (nxt == end or _plausible(buf, nxt, end, ops) is not None):
            return at
        hit = pattern.search(buf, at + 1, end)
    return None


def _plausible(buf: Buffer, at: int, end: int, ops: Collection[int]) -> int | None:
    """The end of the record at ``at`` if it could be one of ``ops``, else None."""
    if at + 9 > end:
        return None
    op, length = PREFIX.unpack_from(buf, at)
    stop = at + 9 + int(length)
    if op not in ops or stop > end:
        return None
    try:
        if op == OP_CHUNK:
            c = _Cursor(buf, at + 9, stop)
            c.take(28)  # times, uncompressed size, crc
            if c.string() not in _KNOWN_COMPRESSIONS:
                return None
            records_at = c.pos + 8
            if records_at + c.u64() != stop:
                return None
        elif op == OP_MESSAGE:
            if length < 22:
                return None
        elif op == OP_DATA_END:
            if length != 4:
                return None
        elif op in (OP_SCHEMA, OP_CHANNEL, OP_MESSAGE_INDEX, OP_METADATA, OP_ATTACHMENT):
            parse(op, buf, at + 9, stop)
    except McapFormatError:
        return None
    return stop


def decompress(compression: str, data: bytes | memoryview, size: int) -> bytes:
    """A chunk's records, decompressed (``""`` is no compression)."""
    if size > MAX_CHUNK_SIZE:
        raise McapFormatError(f"chunk of {size} bytes exceeds the {MAX_CHUNK_SIZE}-byte limit")
    try:
        if compression == "":
            out = bytes(data)
        elif compression == "zstd":
            import zstandard

            try:
                out = zstandard.ZstdDecompressor().decompress(data, max_output_size=size)
            except zstandard.ZstdError as err:  # not an OSError: name it ourselves
                raise McapFormatError(f"zstd chunk does not decompress: {err}") from err
        elif compression == "lz4":
            import lz4.frame

            out = bytes(lz4.frame.LZ4FrameDecompressor().decompress(data, size + 1))
        else:
            raise UnsupportedBagError(f"unsupported MCAP chunk compression {compression!r}")
    except (OSError, ValueError, RuntimeError) as err:
        if isinstance(err, BagFormatError):
            raise
        raise McapFormatError(f"{compression} chunk does not decompress: {err}") from err
    if len(out) != size:
        raise McapFormatError(f"chunk holds {len(out)} bytes, its header says {size}")
    return out


def decompress_prefix(compression: str, data: bytes | memoryview, limit: int) -> bytes:
    """As much of a cut-short chunk as decompresses, at most ``limit`` bytes."""
    limit = min(limit, MAX_CHUNK_SIZE)
    try:
        if compression == "":
            return bytes(data[:limit])
        if compression == "zstd":
            import io

            import zstandard

            # A stream reader stops at ``limit``: a small frame cannot make us allocate more.
            reader = zstandard.ZstdDecompressor().stream_reader(io.BytesIO(data))
            out = bytearray()
            while len(out) < limit:
                try:
                    piece = reader.read(min(limit - len(out), 1 << 20))
                except zstandard.ZstdError:
                    break  # the cut: keep what came before it
                if not piece:
                    break
                out += piece
            return bytes(out)
        if compression == "lz4":
            from rostools.bag.formats import lz4cut

            return lz4cut.salvage(data, limit)  # every sequence before the cut
    except (OSError, ValueError, RuntimeError) as err:
        raise McapFormatError(f"{compression} chunk does not decompress: {err}") from err
    raise UnsupportedBagError(f"unsupported MCAP chunk compression {compression!r}")


# -- encoding ----------------------------------------------------------------------------------


def _record(op: int, content: bytes) -> bytes:
    return PREFIX.pack(op, len(content)) + content


def _str(value: str) -> bytes:
    raw = value.encode()
    return _U32.pack(len(raw)) + raw


def _str_map(values: Mapping[str, str]) -> bytes:
    body = b"".join(_str(k) + _str(v) for k, v in values.items())
    return _U32.pack(len(body)) + body


def _id_map(values: Mapping[int, int]) -> bytes:
    body = b"".join(_U16.pack(k) + _U64.pack(v) for k, v in sorted(values.items()))
    return _U32.pack(len(body)) + body


def encode_header(profile: str, library: str) -> bytes:
    """A Header record."""
    return _record(OP_HEADER, _str(profile) + _str(library))


def encode_schema(schema_id: int, name: str, encoding: str, data: bytes) -> bytes:
    """A Schema record."""
    content = _U16.pack(schema_id) + _str(name) + _str(encoding) + _U32.pack(len(data)) + data
    return _record(OP_SCHEMA, content)


def encode_channel(
    channel_id: int, schema_id: int, topic: str, encoding: str, metadata: Mapping[str, str]
) -> bytes:
    """A Channel record."""
    content = (
        _U16.pack(channel_id)
        + _U16.pack(schema_id)
        + _str(topic)
        + _str(encoding)
        + _str_map(metadata)
    )
    return _record(OP_CHANNEL, content)


def encode_chunk_head(
    start: int, end: int, size: int, compression: str, data_len: int, crc: int
) -> bytes:
    """A Chunk record up to its records: append ``data_len`` bytes of (compressed) records.

    ``crc``: the CRC-32 of the uncompressed records (0 says "not computed").
    """
    content_head = (
        _U64.pack(start)
        + _U64.pack(end)
        + _U64.pack(size)
        + _U32.pack(crc)
        + _str(compression)
        + _U64.pack(data_len)
    )
    return PREFIX.pack(OP_CHUNK, len(content_head) + data_len) + content_head


def encode_message_index(channel_id: int, entries: bytes) -> bytes:
    """A MessageIndex record from packed (u64 log_time, u64 offset) pairs."""
    return _record(OP_MESSAGE_INDEX, _U16.pack(channel_id) + _U32.pack(len(entries)) + entries)


def encode_chunk_index(index: ChunkIndex) -> bytes:
    """A ChunkIndex record."""
    content = (
        _U64.pack(index.message_start_time)
        + _U64.pack(index.message_end_time)
        + _U64.pack(index.chunk_start_offset)
        + _U64.pack(index.chunk_length)
        + _id_map(index.message_index_offsets)
        + _U64.pack(index.message_index_length)
        + _str(index.compression)
        + _U64.pack(index.compressed_size)
        + _U64.pack(index.uncompressed_size)
    )
    return _record(OP_CHUNK_INDEX, content)


def encode_statistics(stats: Statistics) -> bytes:
    """A Statistics record."""
    content = (
        _U64.pack(stats.message_count)
        + _U16.pack(stats.schema_count)
        + _U32.pack(stats.channel_count)
        + _U32.pack(stats.attachment_count)
        + _U32.pack(stats.metadata_count)
        + _U32.pack(stats.chunk_count)
        + _U64.pack(stats.message_start_time)
        + _U64.pack(stats.message_end_time)
        + _id_map(stats.channel_message_counts)
    )
    return _record(OP_STATISTICS, content)


def encode_metadata(name: str, metadata: Mapping[str, str]) -> bytes:
    """A Metadata record."""
    return _record(OP_METADATA, _str(name) + _str_map(metadata))


def encode_attachment(att: Attachment) -> bytes:
    """An Attachment record, its CRC computed over the fields before it."""
    content = (
        _U64.pack(att.log_time)
        + _U64.pack(att.create_time)
        + _str(att.name)
        + _str(att.media_type)
        + _U64.pack(len(att.data))
        + att.data
    )
    return _record(OP_ATTACHMENT, content + _U32.pack(crc32(content)))


def encode_attachment_index(index: AttachmentIndex) -> bytes:
    """An AttachmentIndex record."""
    content = (
        _U64.pack(index.offset)
        + _U64.pack(index.length)
        + _U64.pack(index.log_time)
        + _U64.pack(index.create_time)
        + _U64.pack(index.data_size)
        + _str(index.name)
        + _str(index.media_type)
    )
    return _record(OP_ATTACHMENT_INDEX, content)


def encode_metadata_index(index: MetadataIndex) -> bytes:
    """A MetadataIndex record."""
    return _record(
        OP_METADATA_INDEX, _U64.pack(index.offset) + _U64.pack(index.length) + _str(index.name)
    )


def encode_summary_offset(opcode: int, start: int, length: int) -> bytes:
    """A SummaryOffset record."""
    return _record(OP_SUMMARY_OFFSET, _U8.pack(opcode) + _U64.pack(start) + _U64.pack(length))


def encode_data_end(crc: int = 0) -> bytes:
    """A DataEnd record; ``crc`` covers every byte before it, from the magic (0: not computed)."""
    return _record(OP_DATA_END, _U32.pack(crc))


def encode_footer(summary_start: int, summary_offset_start: int, summary: bytes) -> bytes:
    """The Footer record and closing magic; ``summary`` is every byte since summary_start."""
    head = PREFIX.pack(OP_FOOTER, 20) + _U64.pack(summary_start) + _U64.pack(summary_offset_start)
    crc = crc32(head, crc32(summary)) if summary_start else 0
    return head + _U32.pack(crc) + MAGIC


def parse_footer(tail: Buffer) -> Footer | None:
    """The footer from a file's last ``FOOTER_SIZE + 8`` bytes, or None if it is not there."""
    if len(tail) < FOOTER_SIZE + len(MAGIC) or bytes(tail[-len(MAGIC) :]) != MAGIC:
        return None
    op, length, start, offsets, crc = _FOOTER.unpack_from(
        tail, len(tail) - len(MAGIC) - FOOTER_SIZE
    )
    if op != OP_FOOTER or length != 20:
        return None
    return Footer(start, offsets, crc)


def stream(buf: Buffer) -> Iterator[Record]:
    """Every record of a whole MCAP file in file order, chunks replaced by their records.

    What a streaming reader emits (the conformance suite's expected output lists these, minus
    message indexes). Raises ``McapFormatError`` on bad magic or a damaged record.
    """
    if bytes(buf[: len(MAGIC)]) != MAGIC:
        raise McapFormatError("not an MCAP file (bad magic)")
    for _, op, start, stop in records(buf, len(MAGIC), len(buf)):
        record = parse(op, buf, start, stop)
        if isinstance(record, McapChunk):
            data = decompress(record.compression, record.records, record.uncompressed_size)
            for _, inner_op, inner_start, inner_stop in records(data, 0, len(data)):
                inner = parse(inner_op, data, inner_start, inner_stop)
                if inner is not None:
                    yield inner
        elif record is not None:
            yield record
        if op == OP_FOOTER:
            if bytes(buf[stop : stop + len(MAGIC)]) != MAGIC:
                raise McapFormatError("the footer is not followed by the closing magic")
            return
    raise McapFormatError("the file ends without a footer")
