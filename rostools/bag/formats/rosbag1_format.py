"""The rosbag v2.0 record layout: op codes, record headers, times, chunk compression.

Pure functions over bytes, shared by the reader, the writer and recovery. A record is
``u32 header_len, header, u32 data_len, data``; the header is ``u32 len; name=value`` fields
with binary values (https://wiki.ros.org/Bags/Format/2.0).
"""

from __future__ import annotations

import bz2
import mmap
import struct
from collections.abc import Collection, Mapping
from typing import Final

from rostools.bag.formats.model import NS_PER_SEC, BagFormatError, UnsupportedBagError
from rostools.wire.header import HeaderError, split_fields

MAGIC: Final = b"#ROSBAG V2.0\n"

OP_MSG_DEF: Final = 0x01  # v1.2 only
OP_MSG_DATA: Final = 0x02
OP_BAG_HEADER: Final = 0x03
OP_INDEX_DATA: Final = 0x04
OP_CHUNK: Final = 0x05
OP_CHUNK_INFO: Final = 0x06
OP_CONNECTION: Final = 0x07

#: rosbag pads the bag header record's *data* so that header_len + data_len is 4096; the
#: record is 4104 bytes and the first chunk starts at 13 + 4104 = 4117. ``rosbag reindex``
#: rewrites the header in place, so any other size corrupts the first chunk.
BAG_HEADER_SPACE: Final = 4096
#: Where the first chunk starts in a bag written by ROS (and by us).
FIRST_RECORD_POS: Final = len(MAGIC) + 4 + BAG_HEADER_SPACE + 4
#: rosbag's default chunk threshold (``rosbag record --chunksize`` 768 KB).
DEFAULT_CHUNK_SIZE: Final = 768 * 1024
#: Index entries are version 1 (u32 secs, u32 nsecs, u32 offset).
INDEX_VERSION: Final = 1
INDEX_ENTRY_SIZE: Final = 12

#: Largest record header we accept: real ones are under 100 bytes, except connection records
#: whose header holds only conn/op/topic. A corrupt length beyond this is a damaged record.
MAX_RECORD_HEADER: Final = 1024 * 1024
#: Largest decompressed chunk we allocate. ``size`` is a u32 in the file; rosbag's default
#: chunk is 768 KiB and nobody records chunks near this.
MAX_CHUNK_SIZE: Final = 1 << 30
#: Largest connection header (the data of a CONNECTION record): message definitions of the
#: biggest real types are tens of KB; roscpp caps a TCPROS header far lower than this.
MAX_CONNECTION_HEADER: Final = 64 * 1024 * 1024

COMPRESSIONS: Final = ("none", "bz2", "lz4")

#: Reading on after a damaged record looks for the next ``op`` field, then for the record's
#: start up to this many bytes before it: the fields that sort before ``op`` are short (a
#: chunk info's chunk_pos, count and end_time take 57 bytes).
RESYNC_REACH: Final = 256
#: An ``op`` field as it is stored: its length (4), then ``op=``.
_OP_TAG: Final = b"\x04\x00\x00\x00op="

#: What the record parsers read from: bytes, a memoryview, or the file map.
ReadBuffer = bytes | bytearray | memoryview | mmap.mmap

U32: Final = struct.Struct("<I")
U64: Final = struct.Struct("<Q")
TIME: Final = struct.Struct("<II")
#: header_len, then (after the header) data_len.
_LEN: Final = U32


class RecordError(BagFormatError):
    """A record that does not parse: truncated, or with a malformed header."""


def pack_time(t_ns: int) -> bytes:
    """A bag time field (u32 secs, u32 nsecs) from nanoseconds."""
    secs, nsecs = divmod(t_ns, NS_PER_SEC)
    return TIME.pack(secs, nsecs)


def unpack_time(raw: bytes | memoryview) -> int:
    """Nanoseconds from a bag time field."""
    secs, nsecs = TIME.unpack(raw)
    return int(secs) * NS_PER_SEC + int(nsecs)


def encode_header(fields: Mapping[str, bytes]) -> bytes:
    """Record header bytes (without its length), fields sorted by name as rosbag's C++ writes."""
    out = bytearray()
    for name in sorted(fields):
        item = name.encode() + b"=" + fields[name]
        out += U32.pack(len(item))
        out += item
    return bytes(out)


def encode_record(fields: Mapping[str, bytes], data: bytes | memoryview = b"") -> bytes:
    """A whole record: header length, header, data length, data."""
    header = encode_header(fields)
    return b"".join((U32.pack(len(header)), header, U32.pack(len(data)), data))


def parse_header(buf: ReadBuffer, start: int, end: int) -> dict[str, bytes]:
    """The fields of a record header occupying ``buf[start:end]``.

    A record header is encoded as a TCPROS connection header is (``wire/header``).
    """
    try:
        return split_fields(buf, start, end)
    except HeaderError as err:
        raise RecordError(f"record header: {err}") from None


def read_record(
    buf: ReadBuffer, pos: int, end: int, *, max_data: int | None = None
) -> tuple[dict[str, bytes], int, int]:
    """Parse the record at ``pos``: (header fields, data start, data length).

    Raises ``RecordError`` when the record does not fit before ``end`` or is malformed.
    ``max_data`` caps the data length (beyond ``end`` is always an error).
    """
    if pos + 4 > end:
        raise RecordError(f"record at {pos} is cut short")
    (hlen,) = _LEN.unpack_from(buf, pos)
    if hlen > MAX_RECORD_HEADER or pos + 8 + hlen > end:
        raise RecordError(f"record header at {pos} ({hlen} bytes) is cut short or corrupt")
    try:
        fields = parse_header(buf, pos + 4, pos + 4 + hlen)
    except RecordError as err:
        raise RecordError(f"record header at {pos}: {err}") from err
    (dlen,) = _LEN.unpack_from(buf, pos + 4 + hlen)
    data = pos + 8 + hlen
    if max_data is not None and dlen > max_data:
        raise RecordError(f"record data at {pos} ({dlen} bytes) is larger than allowed")
    if data + dlen > end:
        raise RecordError(f"record data at {pos} ({dlen} bytes) is cut short")
    return fields, data, dlen


def next_record(
    buf: bytes | bytearray | mmap.mmap, start: int, end: int, ops: Collection[int]
) -> int | None:
    """Where the first whole record of one of ``ops`` at or after ``start`` begins, or None.

    What reading on after damage needs. A record is recognised by its ``op`` field, then
    parsed whole (with the fields its op requires) from each place its header could start,
    nearest first; and the record after it must be one of ``ops`` too, or the end. So the
    bytes of a message (or the literals of an lz4 chunk) that hold one record header are not
    taken for a record.
    """
    find = buf.find
    hit = find(_OP_TAG, start + 4, end)
    while hit >= 0 and hit + 8 <= end:
        op = buf[hit + 7]
        if op in ops:
            for at in range(hit - 4, max(start, hit - 4 - RESYNC_REACH) - 1, -1):
                (hlen,) = _LEN.unpack_from(buf, at)
                if hit + 8 <= at + 4 + hlen <= at + 4 + MAX_RECORD_HEADER:
                    after = _whole(buf, at, end, ops)
                    if after is not None and (after == end or _whole(buf, after, end, ops)):
                        return at
        hit = find(_OP_TAG, hit + 1, end)
    return None


def _whole(
    buf: bytes | bytearray | mmap.mmap, at: int, end: int, ops: Collection[int]
) -> int | None:
    """Where the record at ``at`` ends, if it is a well-formed record of one of ``ops``."""
    try:
        fields, data, dlen = read_record(buf, at, end)
        op = op_of(fields)
    except RecordError:
        return None
    if op not in ops or not _well_formed(op, fields):
        return None
    if op == OP_INDEX_DATA:  # rosbag reads `count` entries whatever data_len says
        dlen = INDEX_ENTRY_SIZE * int(U32.unpack(fields["count"])[0])
    return data + dlen if data + dlen <= end else None


#: The fields each op requires, with their sizes (None: any size).
_REQUIRED: Final[dict[int, dict[str, int | None]]] = {
    OP_MSG_DATA: {"conn": 4, "time": 8},
    OP_CHUNK: {"compression": None, "size": 4},
    OP_INDEX_DATA: {"ver": 4, "conn": 4, "count": 4},
    OP_CHUNK_INFO: {"ver": 4, "chunk_pos": 8, "start_time": 8, "end_time": 8, "count": 4},
    OP_CONNECTION: {"conn": 4, "topic": None},
}


def _well_formed(op: int, fields: Mapping[str, bytes]) -> bool:
    """Whether a header has every field its op requires, each of the right size."""
    for name, size in _REQUIRED.get(op, {}).items():
        value = fields.get(name)
        if value is None or (size is not None and len(value) != size):
            return False
    if op == OP_CHUNK:
        return fields["compression"].decode("ascii", "replace") in COMPRESSIONS
    return True


def op_of(fields: Mapping[str, bytes]) -> int:
    """The ``op`` of a record header."""
    op = fields.get("op")
    if op is None or len(op) != 1:
        raise RecordError("record header without a one-byte 'op' field")
    return op[0]


def u32_field(fields: Mapping[str, bytes], name: str) -> int:
    """A u32 header field."""
    raw = fields.get(name)
    if raw is None or len(raw) != 4:
        raise RecordError(f"record header field {name!r} is missing or not 4 bytes")
    return int(U32.unpack(raw)[0])


def u64_field(fields: Mapping[str, bytes], name: str) -> int:
    """A u64 header field."""
    raw = fields.get(name)
    if raw is None or len(raw) != 8:
        raise RecordError(f"record header field {name!r} is missing or not 8 bytes")
    return int(U64.unpack(raw)[0])


def time_field(fields: Mapping[str, bytes], name: str) -> int:
    """A time header field, in nanoseconds."""
    raw = fields.get(name)
    if raw is None or len(raw) != 8:
        raise RecordError(f"record header field {name!r} is missing or not a time")
    return unpack_time(raw)


def lz4_compress(data: bytes | bytearray | memoryview) -> bytes:
    """An LZ4 frame that roslz4 (``rosbag play``, ``rosbag.Bag``) can read.

    roslz4 accepts only independent 1 MB blocks with a content checksum and no stored size;
    ``lz4.frame`` defaults give frames it rejects as "malformed data" (rosbags' writer makes
    such frames; a test plays ours with rosbag).
    """
    import lz4.frame

    return bytes(
        lz4.frame.compress(
            data,
            block_size=lz4.frame.BLOCKSIZE_MAX1MB,
            block_linked=False,
            content_checksum=True,
            store_size=False,
        )
    )


def compress(kind: str, data: bytes | bytearray | memoryview) -> bytes:
    """Chunk data compressed as ``kind`` (none, bz2 or lz4)."""
    if kind == "none":
        return bytes(data)
    if kind == "bz2":
        return bz2.compress(data, 9)  # rosbag's BZ2Stream uses block size 9
    if kind == "lz4":
        return lz4_compress(data)
    raise UnsupportedBagError(f"unknown chunk compression {kind!r} (none, bz2 or lz4)")


def decompress(kind: str, data: bytes | memoryview, size: int) -> bytes:
    """Chunk data decompressed; at most ``size`` bytes, the chunk's declared size.

    Raises ``RecordError`` when the data is corrupt or shorter than declared.
    """
    if kind == "none":
        return bytes(data)
    if size > MAX_CHUNK_SIZE:
        raise RecordError(f"chunk of {size} bytes exceeds the {MAX_CHUNK_SIZE}-byte limit")
    out = _decode(kind, data, size + 1)  # one more byte shows a lying header
    if len(out) != size:
        raise RecordError(f"{kind} chunk holds {len(out)} bytes, its header says {size}")
    return out


def decompress_prefix(kind: str, data: bytes | memoryview, limit: int) -> bytes:
    """As much of the chunk as decompresses from ``data`` (which may be cut short).

    Salvages the complete bz2 blocks of a partly written chunk, and of an lz4 one every
    sequence before the cut; never more than ``limit`` bytes. Corrupt data raises
    ``RecordError``.
    """
    limit = min(limit, MAX_CHUNK_SIZE)
    if kind != "lz4":
        return _decode(kind, data, limit)
    from rostools.bag.formats import lz4cut

    try:
        return lz4cut.salvage(data, limit)
    except ValueError as err:
        raise RecordError(f"lz4 chunk does not decompress: {err}") from err


def _decode(kind: str, data: bytes | memoryview, limit: int) -> bytes:
    try:
        if kind == "none":
            return bytes(data[:limit])
        if kind == "bz2":
            return bz2.BZ2Decompressor().decompress(data, limit)
        if kind == "lz4":
            import lz4.frame

            return bytes(lz4.frame.LZ4FrameDecompressor().decompress(data, limit))
    except (OSError, ValueError, RuntimeError, EOFError) as err:
        raise RecordError(f"{kind} chunk does not decompress: {err}") from err
    raise UnsupportedBagError(f"unknown chunk compression {kind!r}")
