"""What every bag format has in common: connections, the info summary, and the bag errors.

Plain data, no I/O. The readers and writers of each format (``rosbag1_*``, ``mcap_*``) build
and consume these, so the operations in ``ops`` and ``recover`` never see a format's records.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from rostools.errors import DataLossError, InvalidDataError, NotFoundError, UsageError

#: Nanoseconds in a second: bag times are (u32 secs, u32 nsecs), we carry them as one int.
NS_PER_SEC = 1_000_000_000
#: What one message held in memory costs beyond its bytes: the queue entry, its time stamp
#: and the bytes object (measured: 137 B with CPython 3.11; rounded up for the allocator).
#: ``bag record -b`` and ``bag snapshot --size`` count it, so their limits bound the memory
#: held, not only the payload: 100 topics of 16-byte messages hold ten times their payload.
ENTRY_OVERHEAD = 160


def counted(n: int, noun: str, many: str | None = None, *, grouped: bool = False) -> str:
    """``1 message``, ``0 messages``, ``2 messages`` (``grouped``: ``1,000 messages``)."""
    number = f"{n:,}" if grouped else str(n)
    return f"{number} {noun if n == 1 else many or noun + 's'}"


@dataclass(frozen=True)
class Connection:
    """One recorded connection: a publisher's topic, type and connection header.

    ``topic`` is the topic the messages are stored under. ``extra`` holds every other field of
    the original connection header (including a ``topic`` that differs from the stored one), so
    a conversion between formats loses nothing. ``absent`` names the standard fields the
    original header lacked (rosbag's Python writer omits ``latching`` and ``callerid``; some
    writers omit ``topic``), so ``header()`` does not invent them.
    """

    id: int
    topic: str
    type: str
    md5sum: str
    definition: str
    callerid: str = ""
    latching: bool = False
    extra: Mapping[str, str] = field(default_factory=dict, hash=False)
    absent: frozenset[str] = frozenset()
    #: How the messages are serialised (MCAP's message encoding: ``cdr`` for ROS 2) and how
    #: the definition is written (its schema encoding; empty for a channel with no schema).
    encoding: str = "ros1"
    schema_encoding: str = "ros1msg"

    def header(self) -> dict[str, str]:
        """The connection header as ROS 1 writes it (``latching`` as "1"/"0")."""
        fields = dict(self.extra)
        standard = {
            "topic": fields.get("topic", self.topic),
            "type": self.type,
            "md5sum": self.md5sum,
            "message_definition": self.definition,
            "callerid": self.callerid,
            "latching": "1" if self.latching else "0",
        }
        for key, value in standard.items():
            if key not in self.absent and (value or key != "callerid"):
                fields[key] = value
        return fields


#: The fields of a connection header that ``Connection`` keeps as attributes.
HEADER_FIELDS = frozenset(("type", "md5sum", "message_definition", "callerid", "latching"))
#: Standard fields whose absence from a header is remembered (``Connection.absent``).
OPTIONAL_FIELDS = frozenset(("topic", *HEADER_FIELDS))


def connection_from_header(conn_id: int, topic: str, fields: Mapping[str, str]) -> Connection:
    """A ``Connection`` from a decoded connection header stored under ``topic``."""
    extra = {k: v for k, v in fields.items() if k not in HEADER_FIELDS}
    if extra.get("topic") == topic:
        del extra["topic"]  # the common case: nothing to remember
    return Connection(
        id=conn_id,
        topic=topic,
        type=fields.get("type", ""),
        md5sum=fields.get("md5sum", ""),
        definition=fields.get("message_definition", ""),
        callerid=fields.get("callerid", ""),
        latching=fields.get("latching", "0") in ("1", "true"),
        extra=extra,
        absent=OPTIONAL_FIELDS - fields.keys() - {"callerid"},
    )


@dataclass(frozen=True)
class CompressionStats:
    """The chunks of one compression kind: how many, and their stored and raw sizes."""

    compression: str
    chunks: int
    compressed_size: int
    uncompressed_size: int


@dataclass(frozen=True)
class BagTopic:
    """One topic of a bag: its type, message count and how many connections carry it."""

    topic: str
    type: str
    md5sum: str
    messages: int
    connections: int


@dataclass(frozen=True)
class BagInfo:
    """Everything ``bag info`` shows, read from the index alone when the file has one.

    Times are nanoseconds; ``start_ns``/``end_ns`` are None when the bag holds no message
    (time 0 is a real time). ``compression`` lists each chunk compression, most chunks first.
    """

    path: Path
    format: str
    version: str
    size: int
    start_ns: int | None
    end_ns: int | None
    message_count: int
    indexed: bool
    chunk_count: int
    compression: tuple[CompressionStats, ...]
    connections: tuple[Connection, ...]
    connection_counts: Mapping[int, int]
    topics: tuple[BagTopic, ...]
    types: Mapping[str, str]
    profile: str = ""
    library: str = ""
    attachment_count: int = 0
    metadata_count: int = 0

    @property
    def duration_ns(self) -> int:
        """End minus start, 0 for an empty bag."""
        if self.start_ns is None or self.end_ns is None:
            return 0
        return self.end_ns - self.start_ns

    @property
    def compressed_size(self) -> int:
        """Bytes the chunks take on disk."""
        return sum(c.compressed_size for c in self.compression)

    @property
    def uncompressed_size(self) -> int:
        """Bytes the chunks hold once decompressed."""
        return sum(c.uncompressed_size for c in self.compression)


def summarize(
    connections: list[Connection], counts: Mapping[int, int]
) -> tuple[tuple[BagTopic, ...], dict[str, str]]:
    """Per-topic rows (sorted by topic) and type -> md5sum (first connection of a type wins)."""
    by_topic: dict[str, list[Connection]] = {}
    types: dict[str, str] = {}
    for conn in connections:
        by_topic.setdefault(conn.topic, []).append(conn)
        types.setdefault(conn.type, conn.md5sum)
    topics = tuple(
        BagTopic(
            topic=topic,
            type=conns[0].type,
            md5sum=conns[0].md5sum,
            messages=sum(counts.get(c.id, 0) for c in conns),
            connections=len(conns),
        )
        for topic, conns in sorted(by_topic.items())
    )
    return topics, dict(sorted(types.items()))


def compression_rows(
    chunks: list[tuple[str, int, int]],
) -> tuple[CompressionStats, ...]:
    """Group (compression, stored size, raw size) per chunk into rows, most chunks first."""
    rows: dict[str, list[int]] = {}
    for kind, stored, raw in chunks:
        row = rows.setdefault(kind, [0, 0, 0])
        row[0] += 1
        row[1] += stored
        row[2] += raw
    ordered = sorted(rows.items(), key=lambda kv: (-kv[1][0], kv[0]))
    return tuple(CompressionStats(k, v[0], v[1], v[2]) for k, v in ordered)


class BagFormatError(InvalidDataError):
    """A file that is not a bag, or a bag that is damaged beyond reading."""


class UnsupportedBagError(BagFormatError):
    """A bag of a format version, compression or encoding we cannot read."""


class BagNotFoundError(NotFoundError):
    """A bag file that does not exist."""


class BagUsageError(UsageError):
    """A bag API used wrongly: writing to a closed writer, an unknown connection, bad times."""


class BagDataLossError(DataLossError):
    """Recovery could not salvage everything; the report says what was lost."""


class BagUnindexedError(InvalidDataError):
    """``bag info`` of a bag read without its index (exit 1, as rosbag info's "unindexed")."""


#: A data-loss error lists this many of the problems found; ``bag doctor`` lists them all.
LISTED = 5


def not_a_bag(path: object, head: bytes, otherwise: str) -> BagFormatError:
    """The error for a file whose first bytes are no bag we read: what they are, if known.

    ``otherwise`` says what the file is not, when its first bytes say nothing.
    """
    if head.startswith(b"#ROSBAG V"):
        version = head[len(b"#ROSBAG V") :].split(b"\n")[0].decode("ascii", "replace")
        return UnsupportedBagError(f"{path} is a rosbag of version {version}; only 2.0 is read")
    if head.startswith(b"SQLite format"):
        return BagFormatError(f"{path} is an SQLite database (a ROS 2 bag?), not a ROS 1 bag")
    return BagFormatError(f"{path} is {otherwise}")


def lost_data(what: str, lost: Sequence[str]) -> BagDataLossError:
    """The error (exit code 6) for ``what`` was done, with ``lost`` left out."""
    shown = "; ".join(lost[:LISTED])
    more = f"; and {len(lost) - LISTED} more (bag doctor lists them)" if len(lost) > LISTED else ""
    return BagDataLossError(f"{what}, but left out what could not be read: {shown}{more}")
