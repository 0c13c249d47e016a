"""The connections (topic, type, md5sum, definition) recorded in a ``.bag`` or MCAP file.

Enough of each format to let ``msg show --bag`` read a stored definition; the full readers
live beside this module.
"""

from __future__ import annotations

import bz2
import struct
from dataclasses import dataclass
from pathlib import Path

from rostools.errors import InvalidDataError, NotFoundError
from rostools.wire.header import HeaderError, split_fields

BAG_MAGIC = b"#ROSBAG V2.0\n"
MCAP_MAGIC = b"\x89MCAP0\r\n"
_U32 = struct.Struct("<I")
_OP_CHUNK, _OP_CONNECTION, _OP_HEADER = 0x05, 0x07, 0x03


@dataclass(frozen=True)
class Connection:
    """One recorded connection."""

    id: int
    topic: str
    type: str
    md5sum: str
    definition: str
    callerid: str = ""
    latching: bool = False


class BagFormatError(InvalidDataError):
    """A file that is not a bag, or a bag that is damaged beyond reading."""


def detect_format(path: Path) -> str:
    """``"bag"`` or ``"mcap"``, from the first bytes of the file."""
    try:
        with path.open("rb") as f:
            head = f.read(len(BAG_MAGIC))
    except FileNotFoundError:
        raise NotFoundError(f"no such file: {path}") from None
    except OSError as err:
        raise InvalidDataError(f"cannot read {path}: {err.strerror}") from err
    if head.startswith(MCAP_MAGIC):
        return "mcap"
    if head == BAG_MAGIC:
        return "bag"
    if not head:
        raise BagFormatError(f"{path} is empty, not a bag")
    if head.startswith(b"#ROSBAG"):
        raise BagFormatError(f"{path} is a rosbag of an unsupported version ({head.strip()!r})")
    if head.startswith(b"SQLite format"):
        raise BagFormatError(f"{path} is an SQLite database (a ROS 2 .db3 bag?), not a ROS 1 bag")
    raise BagFormatError(f"{path} is neither a ROS 1 .bag nor an MCAP file")


def read_connections(path: Path) -> list[Connection]:
    """Every connection of a ``.bag`` or MCAP file."""
    return _mcap_connections(path) if detect_format(path) == "mcap" else _bag_connections(path)


def _records(data: bytes, pos: int) -> list[tuple[dict[str, bytes], int, int]]:
    """(header fields, data start, data end) of each whole record from ``pos`` on."""
    out = []
    while pos + 4 <= len(data):
        (hlen,) = _U32.unpack_from(data, pos)
        if pos + 8 + hlen > len(data):
            break
        try:
            fields = split_fields(data[pos + 4 : pos + 4 + hlen])
        except HeaderError:
            break
        (dlen,) = _U32.unpack_from(data, pos + 4 + hlen)
        start = pos + 8 + hlen
        if start + dlen > len(data):
            break
        out.append((fields, start, start + dlen))
        pos = start + dlen
    return out


def _decompress(kind: bytes, payload: bytes) -> bytes:
    if kind == b"none":
        return payload
    if kind == b"bz2":
        return bz2.decompress(payload)
    if kind == b"lz4":
        import lz4.frame

        return bytes(lz4.frame.decompress(payload))
    raise BagFormatError(f"unknown chunk compression {kind.decode(errors='replace')}")


def _connection(fields: dict[str, bytes], data: bytes) -> Connection:
    conn = split_fields(data)
    text = {k: v.decode("utf-8", "replace") for k, v in conn.items()}
    return Connection(
        id=_U32.unpack(fields["conn"])[0],
        topic=fields.get("topic", conn.get("topic", b"")).decode("utf-8", "replace"),
        type=text.get("type", ""),
        md5sum=text.get("md5sum", ""),
        definition=text.get("message_definition", ""),
        callerid=text.get("callerid", ""),
        latching=text.get("latching", "0") == "1",
    )


def _bag_connections(path: Path) -> list[Connection]:
    data = path.read_bytes()
    found: dict[int, Connection] = {}
    try:
        records = _records(data, len(BAG_MAGIC))
        if not records or records[0][0].get("op") != bytes([_OP_HEADER]):
            raise BagFormatError(f"{path}: no bag header record")
        header = records[0][0]
        index_pos = struct.unpack("<Q", header["index_pos"])[0] if "index_pos" in header else 0
        if 0 < index_pos < len(data):
            for fields, start, end in _records(data, index_pos):
                if fields.get("op") == bytes([_OP_CONNECTION]):
                    c = _connection(fields, data[start:end])
                    found.setdefault(c.id, c)
        if not found:  # unindexed: connection records are inside the chunks
            for fields, start, end in records[1:]:
                if fields.get("op") != bytes([_OP_CHUNK]):
                    continue
                inner = _decompress(fields.get("compression", b"none"), data[start:end])
                for f2, s2, e2 in _records(inner, 0):
                    if f2.get("op") == bytes([_OP_CONNECTION]):
                        c = _connection(f2, inner[s2:e2])
                        found.setdefault(c.id, c)
    except (KeyError, struct.error, HeaderError, OSError, ValueError) as err:
        if isinstance(err, BagFormatError):
            raise
        raise BagFormatError(f"{path}: damaged bag ({err})") from err
    return [found[k] for k in sorted(found)]


def _mcap_connections(path: Path) -> list[Connection]:
    from mcap.exceptions import McapError
    from mcap.records import Channel, Schema
    from mcap.stream_reader import StreamReader

    schemas: dict[int, Schema] = {}
    found: dict[int, Connection] = {}
    with path.open("rb") as f:
        try:
            for record in StreamReader(f, skip_magic=False).records:
                if isinstance(record, Schema):
                    schemas[record.id] = record
                elif isinstance(record, Channel) and record.id not in found:
                    schema = schemas.get(record.schema_id)
                    meta = record.metadata
                    found[record.id] = Connection(
                        id=record.id,
                        topic=record.topic,
                        type=schema.name if schema else "",
                        md5sum=meta.get("md5sum", ""),
                        definition=schema.data.decode("utf-8", "replace") if schema else "",
                        callerid=meta.get("callerid", ""),
                        latching=meta.get("latching", "false") in ("true", "1"),
                    )
        except (McapError, EOFError, struct.error, ValueError) as err:
            if not found:
                raise BagFormatError(f"{path}: damaged MCAP file ({err})") from err
    return [found[k] for k in sorted(found)]
