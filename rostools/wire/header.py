"""Connection headers: ``u32 len ; "key=value"`` fields (TCPROS, services, bag records).

Pure functions over bytes. TCPROS wraps the fields in a leading ``u32`` total length; bag
record headers carry their length in the record instead and have binary values.
"""

from __future__ import annotations

import struct
from collections.abc import Mapping

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it

if TYPE_CHECKING:
    import mmap

_U32 = struct.Struct("<I")
#: roscpp refuses a header field longer than this (``Header::parse``), and so do we.
MAX_FIELD_LENGTH = 1_000_000
#: roscpp's limit for a whole TCPROS header is 1e9 (``Connection::onHeaderLengthRead``) and
#: rospy has none. Ours is small: the largest field real peers send is a full message
#: definition, and the largest in Noetic's message packages, visualization_msgs/
#: InteractiveMarkerUpdate with its comments, is 10.6 KB: a hundred times that.
MAX_HEADER_LENGTH = 1024 * 1024


if TYPE_CHECKING:
    #: What header fields are read from: bytes received, or a file's map read in place.
    Fields = bytes | bytearray | memoryview | mmap.mmap


class HeaderError(ValueError):
    """Bytes that are not a well-formed connection header."""


def split_fields(data: Fields, start: int = 0, end: int | None = None) -> dict[str, bytes]:
    """Split header field bytes (without the total length) into a dict of raw values.

    ``data[start:end]`` holds the fields: a TCPROS header's body, or a bag record's header in
    a file's map, read in place. Each field is split at its first ``=``. A later duplicate key
    wins, as in roscpp.
    """
    fields: dict[str, bytes] = {}
    pos, end = start, len(data) if end is None else end
    while pos < end:
        if pos + 4 > end:
            raise HeaderError("truncated field length")
        (length,) = _U32.unpack_from(data, pos)
        pos += 4
        if length == 0:
            raise HeaderError("empty header field")
        if length > MAX_FIELD_LENGTH or pos + length > end:
            raise HeaderError(f"header field of {length} bytes does not fit")
        field = bytes(data[pos : pos + length])
        pos += length
        key, sep, value = field.partition(b"=")
        if not sep:
            raise HeaderError(f"header field without '=': {field[:40]!r}")
        fields[key.decode("utf-8", "replace").strip()] = value
    return fields


def decode_fields(data: bytes | memoryview) -> dict[str, str]:
    """Split a TCPROS header body into text fields."""
    return {k: v.decode("utf-8", "replace") for k, v in split_fields(data).items()}


def encode_fields(fields: Mapping[str, str | bytes]) -> bytes:
    """Header field bytes, sorted by key as rospy and roscpp write them (no total length)."""
    out = bytearray()
    for key in sorted(fields):
        value = fields[key]
        raw = key.encode() + b"=" + (value if isinstance(value, bytes) else value.encode())
        out += _U32.pack(len(raw))
        out += raw
    return bytes(out)


def encode_header(fields: Mapping[str, str | bytes]) -> bytes:
    """A complete TCPROS connection header: total length, then the sorted fields."""
    body = encode_fields(fields)
    return _U32.pack(len(body)) + body
