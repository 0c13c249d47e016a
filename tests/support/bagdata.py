"""Sample bags for the bag tests: deterministic messages, written with our writers.

Every message is a function of its index, so a test (or a killed child process) can say which
messages a file must hold without keeping them.
"""

from __future__ import annotations

import hashlib
import struct
from dataclasses import dataclass
from pathlib import Path

from rostools.bag.formats.access import open_bag, open_writer
from rostools.bag.formats.model import Connection

STRING_MD5 = "992ce8a1687cec8c8bd883ec73ca41d1"
INT32_MD5 = "da5909fbe378aeaf85e547e830cc1bb7"
POINT_DEF = "float64 x\nfloat64 y\nfloat64 z\n"
POINT_MD5 = "4a842b65f413084dc2b10fb484ea7f17"

#: (topic, type, md5sum, definition, callerid, latching) of the sample connections; two
#: connections share /chatter (two publishers), as rosbag record keeps them apart.
SAMPLE_CONNECTIONS = (
    ("/chatter", "std_msgs/String", STRING_MD5, "string data\n", "/talker", True),
    ("/chatter", "std_msgs/String", STRING_MD5, "string data\n", "/talker2", False),
    ("/count", "std_msgs/Int32", INT32_MD5, "int32 data\n", "/counter", False),
    ("/point", "geometry_msgs/Point", POINT_MD5, POINT_DEF, "/pointer", False),
)
#: Times start at 0 on purpose: time 0 is a real time.
STEP_NS = 1_000_003


def message(i: int) -> tuple[int, int, bytes]:
    """(connection index, time ns, serialized data) of sample message ``i``."""
    k = i % len(SAMPLE_CONNECTIONS)
    t = i * STEP_NS
    if k in (0, 1):
        text = b"hello %d " % i + b"x" * (i % 200)
        return k, t, struct.pack("<I", len(text)) + text
    if k == 2:
        return k, t, struct.pack("<i", i)
    return k, t, struct.pack("<3d", i, -i, i / 7)


@dataclass(frozen=True)
class Sample:
    """A written sample bag and the stream it holds: (topic, callerid, time, data)."""

    path: Path
    stream: list[tuple[str, str, int, bytes]]


def write_sample(
    path: Path,
    count: int,
    *,
    compression: str | None = None,
    chunk_size: int | None = None,
    close: bool = True,
) -> Sample:
    """Write ``count`` sample messages; the format follows the name."""
    writer = open_writer(path, compression=compression, chunk_size=chunk_size)
    conns = [
        writer.add_connection(topic, kind, md5, definition, callerid=caller, latching=latch)
        for topic, kind, md5, definition, caller, latch in SAMPLE_CONNECTIONS
    ]
    stream = []
    for i in range(count):
        k, t, data = message(i)
        writer.write(conns[k], t, data)
        stream.append((conns[k].topic, conns[k].callerid, t, data))
    if close:
        writer.close()
    else:
        writer.flush()
    return Sample(path, stream)


def read_stream(path: Path, **kwargs: object) -> list[tuple[str, str, int, bytes]]:
    """The (topic, callerid, time, data) stream our reader yields."""
    with open_bag(path) as reader:
        return [(c.topic, c.callerid, t, bytes(d)) for c, t, d in reader.messages(**kwargs)]  # type: ignore[arg-type]


def headers(path: Path) -> list[tuple[str, dict[str, str]]]:
    """(topic, connection header) of every connection, in id order."""
    with open_bag(path) as reader:
        return [(c.topic, c.header()) for c in sorted(reader.connections, key=_id)]


def _id(conn: Connection) -> int:
    return conn.id


def digest(data: bytes) -> str:
    """A short hash for comparing message bytes across processes."""
    return hashlib.md5(data).hexdigest()


def write_play_bag(path: Path, compression: str | None = None) -> None:
    """/chatter "m0".."m9" every 0.1 s from t = 100 s, and /latched "old" at 100 s (latched)."""
    with open_writer(path, compression=compression) as writer:
        chatter = writer.add_connection(
            "/chatter", "std_msgs/String", STRING_MD5, "string data\n", callerid="/talker"
        )
        latched = writer.add_connection(
            "/latched",
            "std_msgs/String",
            STRING_MD5,
            "string data\n",
            callerid="/latcher",
            latching=True,
        )
        writer.write(latched, 100 * 10**9, struct.pack("<I", 3) + b"old")
        for i in range(10):
            text = f"m{i}".encode()
            writer.write(chatter, 100 * 10**9 + i * 10**8, struct.pack("<I", len(text)) + text)


def first_chunk_data(raw: bytes) -> tuple[int, int]:
    """(offset, length) of the data of a ``.bag``'s first chunk, the record after its header."""
    pos = 13  # after "#ROSBAG V2.0\n"
    for _ in range(2):  # skip the bag header record, then stop at the chunk's data
        header_len = struct.unpack_from("<I", raw, pos)[0]
        data_at = pos + 4 + header_len + 4
        data_len = struct.unpack_from("<I", raw, data_at - 4)[0]
        pos = data_at + data_len
    return data_at, data_len


def write_static_bag(path: Path) -> None:
    """/static from three recorded publishers, as /tf_static often is.

    /a "a1" at 100.0 s, /b "b1" at 100.1 s (both latched), /c "c1" at 100.2 s (not latched)
    and /a "a2" at 100.3 s: a late subscriber should get "b1" then "a2".
    """
    with open_writer(path) as writer:
        conns = {}
        for name in ("/a", "/b", "/c"):
            conns[name] = writer.add_connection(
                "/static", "std_msgs/String", STRING_MD5, "string data\n", callerid=name,
                latching=name != "/c",
            )  # fmt: skip
        for k, text in enumerate(["a1", "b1", "c1", "a2"]):
            payload = struct.pack("<I", 2) + text.encode()
            writer.write(conns["/" + text[0]], 100 * 10**9 + k * 10**8, payload)


#: (position, op, header fields, data start, data length) of one record of a ``.bag``.
Record = tuple[int, int, dict[str, bytes], int, int]


def bag_records(raw: bytes, start: int = 13, end: int | None = None) -> list[Record]:
    """The records of an intact ``.bag`` from ``start`` (after the magic line) to ``end``.

    Top level by default; give a chunk's data span for the records inside an uncompressed one.
    """
    from rostools.bag.formats import rosbag1_format as fmt

    end = len(raw) if end is None else end
    out: list[Record] = []
    pos = start
    while pos < end:
        fields, data, dlen = fmt.read_record(raw, pos, end)
        op = fmt.op_of(fields)
        if op == fmt.OP_INDEX_DATA:
            dlen = fmt.INDEX_ENTRY_SIZE * fmt.u32_field(fields, "count")
        out.append((pos, op, fields, data, dlen))
        pos = data + dlen
    return out


def chunk_spans(raw: bytes) -> list[tuple[int, int]]:
    """[start, end) of each chunk record of a ``.bag`` together with the index records after it."""
    from rostools.bag.formats import rosbag1_format as fmt

    records = bag_records(raw)
    starts = [r[0] for r in records if r[1] == fmt.OP_CHUNK]
    index = next(r[0] for r in records if r[0] > starts[-1] and r[1] == fmt.OP_CONNECTION)
    return list(zip(starts, [*starts[1:], index], strict=True))


def swap_spans(raw: bytes, first: tuple[int, int], second: tuple[int, int]) -> bytes:
    """``raw`` with two byte ranges (first before second) swapped."""
    (a, b), (c, d) = first, second
    return raw[:a] + raw[c:d] + raw[b:c] + raw[a:b] + raw[d:]


def recorded(path: Path, topic: str) -> int:
    """How many messages on ``topic`` a file still being written holds on disk so far.

    Read as a killed recorder's file is: a chunk that is not whole yet is skipped. 0 while
    the file is missing or holds no whole header yet.
    """
    from rostools.errors import RostoolsError

    try:
        with open_bag(path) as reader:
            return sum(1 for _ in reader.messages([topic]))
    except (RostoolsError, OSError):
        return 0


def handmade_mcap(path: Path, profile: str, records: bytes = b"") -> Path:
    """An unindexed MCAP file: magic, header, ``records``, data end, an empty footer."""
    from rostools.bag.formats import mcap_format as fmt

    out = fmt.MAGIC + fmt.encode_header(profile, "") + records
    path.write_bytes(out + fmt.encode_data_end() + fmt.encode_footer(0, 0, b""))
    return path


#: Times written in this order make two messages late: 1 after 5, and 3 after 9.
LATE_TWICE = (5, 1, 2, 9, 3, 7)


def write_late_chunk(path: Path) -> None:
    """A chunk of ``LATE_TWICE``, then one in time order (10, 11); the format follows the name."""
    with open_writer(path, chunk_size=10**6) as writer:
        conn = writer.add_connection("/t", "std_msgs/String", STRING_MD5, "string data\n")
        for t in LATE_TWICE:
            writer.write(conn, t, struct.pack("<I", 0))
        writer.flush()
        for t in (10, 11):
            writer.write(conn, t, struct.pack("<I", 0))


def bag_connection(conn: int, topic: str, *, in_record: bool = True) -> bytes:
    """A ``.bag`` CONNECTION record of std_msgs/String; ``in_record`` False leaves out the
    record header's topic field (the connection header in its data still names the topic,
    as the format says)."""
    from rostools.bag.formats import rosbag1_format as fmt
    from rostools.wire.header import encode_fields

    fields = {"op": bytes([fmt.OP_CONNECTION]), "conn": fmt.U32.pack(conn)}
    if in_record:
        fields["topic"] = topic.encode()
    header = {"topic": topic, "type": "std_msgs/String", "md5sum": STRING_MD5}
    header["message_definition"] = "string data\n"
    return fmt.encode_record(fields, encode_fields(header))


def bag_message(conn: int, t_ns: int, text: bytes = b"") -> bytes:
    """A ``.bag`` MSG_DATA record: a std_msgs/String of ``text`` on connection ``conn``."""
    from rostools.bag.formats import rosbag1_format as fmt

    fields = {"op": bytes([fmt.OP_MSG_DATA]), "conn": fmt.U32.pack(conn)}
    fields["time"] = fmt.pack_time(t_ns)
    return fmt.encode_record(fields, struct.pack("<I", len(text)) + text)


def bag_chunk(records: bytes, compression: str | None = "none") -> bytes:
    """A ``.bag`` CHUNK record holding ``records``; None leaves the compression field out."""
    from rostools.bag.formats import rosbag1_format as fmt

    fields = {"op": bytes([fmt.OP_CHUNK]), "size": fmt.U32.pack(len(records))}
    if compression is None:
        return fmt.encode_record(fields, records)
    fields["compression"] = compression.encode()
    return fmt.encode_record(fields, fmt.compress(compression, records))


def handmade_bag(path: Path, records: bytes) -> Path:
    """An unclosed ``.bag`` (index_pos 0, as rosbag leaves one while recording): the magic,
    rosbag's padded bag header, then ``records``."""
    from rostools.bag.formats import rosbag1_format as fmt

    header = fmt.encode_header(
        {
            "op": bytes([fmt.OP_BAG_HEADER]),
            "index_pos": fmt.U64.pack(0),
            "conn_count": fmt.U32.pack(0),
            "chunk_count": fmt.U32.pack(0),
        }
    )
    padding = b" " * (fmt.BAG_HEADER_SPACE - len(header))
    head = fmt.U32.pack(len(header)) + header + fmt.U32.pack(len(padding)) + padding
    path.write_bytes(fmt.MAGIC + head + records)
    return path
