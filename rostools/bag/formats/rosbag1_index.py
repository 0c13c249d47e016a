"""A rosbag chunk's index entries, each checked against the message record it points at.

The INDEX_DATA records after a chunk give, per connection, the time and offset of each of its
messages. The records are the truth (rosbag returns a record's own time too):
``checked_entries`` reads each message through its entry and checks that the record there is a
message of that connection and time, and that the counts are those of the chunk info. It
costs a comparison or two per message beside reading the record's header, which the read
does anyway. ``Disagreement`` says how the index and the records differ. ``message_head``
reads a message record's header the same quick way for a walk over a chunk's records.
"""

from __future__ import annotations

import functools
import mmap
import struct
from collections.abc import Iterable, Mapping
from operator import itemgetter

from rostools.bag.formats import rosbag1_format as fmt
from rostools.bag.formats.model import Connection
from rostools.bag.formats.ordering import Entry

#: A chunk's records: the file map (uncompressed chunks) or the decompressed bytes.
Buffer = bytes | mmap.mmap
#: (connection id, raw entries) of one INDEX_DATA record.
IndexRecord = tuple[int, memoryview]
#: An index entry: its time as the u64 a time field reads as (secs | nsecs << 32), offset.
ENTRY = struct.Struct("<QI")
_EMPTY = memoryview(b"")
_NS = 1_000_000_000
_LOW = 0xFFFFFFFF
#: A 38-byte message record, as rosbag writes them: its first 34 bytes (the header length, the
#: conn and op fields and the name of the time field), its time as a u64, its data length.
_RECORD = struct.Struct("<34sQI")
_HEAD = 46  # bytes of such a record before its data


@functools.lru_cache(maxsize=1024)
def record_prefixes(conn_id: int) -> tuple[bytes, bytes]:
    """The 34 bytes a message record of ``conn_id`` starts with, in both of rosbag's layouts.

    Its C++ writer sorts the fields (conn, op, time); its Python writer writes op, conn, time.
    """
    conn = b"\t\x00\x00\x00conn=" + struct.pack("<I", conn_id)
    op, time = b"\x04\x00\x00\x00op=\x02", b"\r\x00\x00\x00time="
    return b"&\x00\x00\x00" + conn + op + time, b"&\x00\x00\x00" + op + conn + time


#: An entry's position in its chunk.
_OFFSET = itemgetter(2)
#: A 38-byte message record's fixed bytes around its connection id, in the C++ writer's
#: layout (conn, op, time) and the Python writer's (op, conn, time): (before, after, where
#: the id is).
_LAYOUTS = (
    (b"&\x00\x00\x00\t\x00\x00\x00conn=", b"\x04\x00\x00\x00op=\x02\r\x00\x00\x00time=", 13),
    (b"&\x00\x00\x00\x04\x00\x00\x00op=\x02\t\x00\x00\x00conn=", b"\r\x00\x00\x00time=", 21),
)
_TAIL = struct.Struct("<IIi")  # the time's secs and nsecs, the data length


def message_head(buf: Buffer, pos: int, end: int) -> tuple[int, int, int] | None:
    """(time ns, connection, record end) of the message record at ``pos``, or None.

    None for any record not laid out as rosbag writes message records (a 38-byte header):
    read that one whole. What walking a chunk spends its time on, without parsing the header
    into fields.
    """
    if pos + _HEAD > end:
        return None
    for before, after, at in _LAYOUTS:
        if buf[pos : pos + at] == before and buf[pos + at + 4 : pos + 34] == after:
            conn = int.from_bytes(buf[pos + at : pos + at + 4], "little")
            secs, nsecs, dlen = _TAIL.unpack_from(buf, pos + 34)
            stop = pos + _HEAD + dlen
            if dlen < 0 or stop > end:
                return None  # said as the whole record's parse says it
            return secs * _NS + nsecs, conn, stop
    return None


class Disagreement(Exception):  # noqa: N818 - a finding, not an error: readers note it
    """A chunk's index does not match its records; the text says how."""


def checked_entries(
    buf: Buffer,
    base: int,
    end: int,
    records: list[IndexRecord],
    counts: Mapping[int, int],
    wanted: Mapping[int, tuple[int, Connection]],
) -> list[Entry]:
    """The wanted messages of the chunk whose records are ``buf[base:end]``, sorted.

    ``records`` are its index records, ``counts`` its chunk info's messages per connection.
    Raises ``Disagreement`` when they and the records do not say the same.
    """
    listed = dict(counts)
    for conn_id, raw in records:
        n = len(raw) // fmt.INDEX_ENTRY_SIZE
        if listed.pop(conn_id, None) != n:
            raise Disagreement(
                f"{n} index entries of connection {conn_id}; its chunk info lists"
                f" {counts.get(conn_id, 0)}"
            )
    if listed:
        raise Disagreement(f"no index entries of connection {min(listed)}")
    view = memoryview(buf)
    out: list[Entry] = []
    append = out.append
    unpack = _RECORD.unpack_from
    low, ns, head = _LOW, _NS, _HEAD
    limit = end - head
    rising = True  # each connection's offsets rise: no two entries can share a record
    for conn_id, raw in records:
        if conn_id not in wanted:
            continue
        rank, conn = wanted[conn_id]
        expected, other = record_prefixes(conn_id)
        last = -1
        for traw, off in ENTRY.iter_unpack(raw):
            p = base + off
            if p <= limit:
                prefix, rtime, dlen = unpack(buf, p)
                if prefix != expected:  # the other writer's layout, or anything else
                    expected, other = other, expected
                    if prefix != expected:
                        c, rtime, q, dlen = record_at(buf, p, end)
                        if c != conn_id:
                            raise Disagreement(_mismatch(conn_id, traw, off, c, rtime))
                q = p + head
            else:
                c, rtime, q, dlen = record_at(buf, p, end)
                if c != conn_id:
                    raise Disagreement(_mismatch(conn_id, traw, off, c, rtime))
            if rtime != traw or q + dlen > end:
                raise Disagreement(_mismatch(conn_id, traw, off, conn_id, rtime))
            if off <= last:
                rising = False
            last = off
            append(((traw & low) * ns + (traw >> 32), rank, off, conn, view[q : q + dlen]))
    if not rising and len(set(map(_OFFSET, out))) != len(out):
        raise Disagreement("two index entries point at one record")
    out.sort()
    return out


def index_times(
    records: Iterable[IndexRecord], wanted: Mapping[int, tuple[int, Connection]]
) -> list[Entry]:
    """Entries with empty data from the index alone, sorted: for timing statistics."""
    out: list[Entry] = []
    for conn_id, raw in records:
        if conn_id in wanted:
            rank, conn = wanted[conn_id]
            out += [
                ((traw & _LOW) * _NS + (traw >> 32), rank, off, conn, _EMPTY)
                for traw, off in ENTRY.iter_unpack(raw)
            ]
    out.sort()
    return out


def record_at(buf: Buffer, pos: int, end: int) -> tuple[int, int, int, int]:
    """(connection, time as a u64, data start, data length) of the record at ``pos``.

    Connection records before it are skipped, as rosbag does; anything else that is not a
    message record is a ``Disagreement``.
    """
    try:
        while True:
            fields, data, dlen = fmt.read_record(buf, pos, end)
            op = fmt.op_of(fields)
            if op == fmt.OP_MSG_DATA:
                raw = fields.get("time", b"")
                if len(raw) != 8:
                    raise fmt.RecordError("a message record without a time")
                return fmt.u32_field(fields, "conn"), int(fmt.U64.unpack(raw)[0]), data, dlen
            if op != fmt.OP_CONNECTION:
                raise fmt.RecordError(f"a record with op {op}")
            pos = data + dlen
    except fmt.RecordError as err:
        raise Disagreement(f"an index entry points at no message record: {err}") from err


def _mismatch(conn_id: int, traw: int, off: int, c: int, rtime: int) -> str:
    """How an index entry and the record it points at differ."""
    if c != conn_id:
        return f"an entry of connection {conn_id} points at a record of connection {c}"
    if rtime != traw:
        said, stored = (f"{x & _LOW}.{x >> 32:09d} s" for x in (traw, rtime))
        return f"an entry says {said}, its record (at offset {off}) {stored}"
    return f"an entry points at a record (at offset {off}) that runs past the chunk"
