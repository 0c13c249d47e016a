"""One interface over ``.bag`` v2.0 and MCAP: open by content, write by name.

``open_bag`` looks at the first bytes of a file, never its name, and returns a ``BagReader``;
``open_writer`` picks the format from the output name (``.mcap`` or not) unless told. Both
raise the errors of ``rostools.errors`` with a one-line message naming the problem.
"""

from __future__ import annotations

import statistics
from collections.abc import Collection, Iterable, Iterator, Sequence
from pathlib import Path
from typing import Final

from rostools.bag.formats import mcap_format, rosbag1_format
from rostools.bag.formats.base import BagReader, BagWriter
from rostools.bag.formats.model import (
    BagFormatError,
    BagInfo,
    BagNotFoundError,
    BagUsageError,
    UnsupportedBagError,
    not_a_bag,
)
from rostools.bag.formats.ordering import RawMessage, merge
from rostools.errors import InvalidDataError

FORMATS: Final = ("bag", "mcap")
#: Chunk compressions each format can write; the first is the default.
WRITE_COMPRESSIONS: Final = {"bag": ("none", "bz2", "lz4"), "mcap": ("zstd", "lz4", "none")}
_SNIFF = 16


def detect_format(path: str | Path) -> str:
    """``"bag"`` or ``"mcap"``, from the first bytes of the file (not its name)."""
    path = Path(path)
    try:
        with path.open("rb") as f:
            head = f.read(_SNIFF)
    except FileNotFoundError:
        raise BagNotFoundError(f"no such file: {path}") from None
    except IsADirectoryError:
        hint = " (a ROS 2 bag folder? give the .mcap or .db3 inside)" if _is_ros2(path) else ""
        raise BagFormatError(f"{path} is a directory, not a bag file{hint}") from None
    except OSError as err:
        raise InvalidDataError(f"cannot read {path}: {err.strerror or err}") from err
    if head.startswith(mcap_format.MAGIC):
        return "mcap"
    if head.startswith(rosbag1_format.MAGIC):
        return "bag"
    if not head:
        raise BagFormatError(f"{path} is empty, not a bag")
    raise not_a_bag(path, head, "neither a ROS 1 .bag nor an MCAP file")


def _is_ros2(path: Path) -> bool:
    return (path / "metadata.yaml").is_file()


def open_bag(path: str | Path, *, from_records: bool = False, check_crcs: bool = True) -> BagReader:
    """Open a ``.bag`` or MCAP file for reading, whatever its name.

    ``from_records``: a ``.bag`` is read by walking its chunks even when its index is whole,
    and the index is checked against them (what ``recover`` rebuilds from); an MCAP file's
    messages are always read from its records. ``check_crcs`` False: an MCAP file's chunk
    and data section CRCs are not checked (``--no-crc-check``; a ``.bag`` has none).
    """
    kind = detect_format(path)
    if kind == "mcap":
        from rostools.bag.formats.mcap_reader import McapReader

        reader = McapReader(path)
        reader.check_crcs = check_crcs
        return reader
    from rostools.bag.formats.rosbag1_reader import Bag1Reader

    return Bag1Reader(path, from_records=from_records)


def format_for_name(path: str | Path) -> str:
    """The format an output file gets from its name: ``mcap`` for ``*.mcap``, else ``bag``."""
    return "mcap" if Path(path).suffix.lower() == ".mcap" else "bag"


def file_name(base: Path, split: bool, index: int) -> Path:
    """``base`` itself, or ``base`` with ``_N`` before its suffix when splitting."""
    if not split:
        return base
    return base.with_name(f"{base.stem}_{index}{base.suffix}")


def open_writer(
    path: str | Path,
    format: str | None = None,
    compression: str | None = None,
    chunk_size: int | None = None,
    *,
    overwrite: bool = False,
    profile: str = "ros1",
) -> BagWriter:
    """Create a ``.bag`` or MCAP file (format from the name unless given).

    ``compression``: none, bz2 or lz4 for ``.bag`` (default none, as ``rosbag record``);
    zstd, lz4 or none for MCAP (default zstd). ``chunk_size`` in bytes (default 768 KiB).
    ``profile``: the MCAP header's profile (see ``mcap_profile``).
    """
    kind = format or format_for_name(path)
    if kind not in FORMATS:
        raise BagUsageError(f"unknown bag format {kind!r} (bag or mcap)")
    allowed = WRITE_COMPRESSIONS[kind]
    compression = compression or allowed[0]
    if compression not in allowed:
        raise BagUsageError(
            f"{kind} files cannot use {compression!r} compression (use {', '.join(allowed)})"
        )
    if kind == "mcap":
        from rostools.bag.formats.mcap_writer import DEFAULT_CHUNK_SIZE, McapWriter

        return McapWriter(
            path,
            compression=compression,
            chunk_size=chunk_size or DEFAULT_CHUNK_SIZE,
            overwrite=overwrite,
            profile=profile,
        )
    from rostools.bag.formats.rosbag1_writer import Bag1Writer

    return Bag1Writer(
        path,
        compression=compression,
        chunk_size=chunk_size or rosbag1_format.DEFAULT_CHUNK_SIZE,
        overwrite=overwrite,
    )


def bag_info(path: str | Path) -> BagInfo:
    """``open_bag(path).info()``, closing the file."""
    with open_bag(path) as reader:
        return reader.info()


def merged_messages(
    readers: Iterable[BagReader],
    topics: Collection[str] | None = None,
    start: int | None = None,
    end: int | None = None,
) -> Iterator[RawMessage]:
    """The messages of several bags in one time order (``bag play a.bag b.bag``)."""
    return merge(r.messages(topics=topics, start=start, end=end) for r in readers)


def latched_before(
    readers: Sequence[BagReader], topics: Collection[str] | None, before: int
) -> list[RawMessage]:
    """The last message of every latched connection before ``before`` (ns), in time order.

    What a late subscriber would still get: ``play -s`` and ``filter --latched`` send them.
    """
    latched = {
        c.topic
        for r in readers
        for c in r.connections
        if c.latching and (topics is None or c.topic in topics)
    }
    if not latched:
        return []
    last: dict[tuple[str, str], RawMessage] = {}
    for conn, t, data in merged_messages(readers, latched, None, before - 1):
        if conn.latching:
            last[(conn.topic, conn.callerid)] = (conn, t, data)
    return sorted(last.values(), key=lambda m: m[1])


def mcap_profile(readers: Iterable[BagReader], topics: Collection[str] | None = None) -> str:
    """The profile of an MCAP copy of these readers' topics: ``ros2`` when all are CDR."""
    encodings = {
        c.encoding for r in readers for c in r.connections if topics is None or c.topic in topics
    }
    return "ros2" if encodings == {"cdr"} else "ros1"


def require_ros1(reader: BagReader, what: str, topics: Collection[str] | None = None) -> None:
    """Refuse in one line to decode or rewrite messages that are not ROS 1 (ROS 2 CDR, JSON).

    ``what`` names the command; ``topics`` limits the check to the topics it will read.
    """
    from rostools.bag.formats.mcap_reader import McapReader

    if not isinstance(reader, McapReader):
        return
    for channel in reader.channels.values():
        if channel.message_encoding == "ros1" or (topics and channel.topic not in topics):
            continue
        schema = reader.schemas.get(channel.schema_id)
        kind = "ROS 2 CDR" if channel.message_encoding == "cdr" else repr(channel.message_encoding)
        raise UnsupportedBagError(
            f"{reader.path}: {channel.topic} holds {kind} messages"
            f" ({schema.name if schema else 'no schema'}); {what} does not support {kind},"
            " only ROS 1 messages",
            hint="bag cat decodes ROS 2 messages; filter and convert write them into a .bag"
            if channel.message_encoding == "cdr"
            else None,
        )


def copy_extras(
    reader: BagReader, writer: BagWriter, start: int | None = None, end: int | None = None
) -> tuple[int, int]:
    """Copy MCAP attachments and metadata into an MCAP output: (copied, left out).

    Left out: all of them when the output is a ``.bag``, which has no place for them, and
    attachments logged outside ``start``..``end`` (ns, inclusive), as ``mcap filter`` does.
    """
    from rostools.bag.formats.mcap_reader import McapReader
    from rostools.bag.formats.mcap_writer import McapWriter

    if not isinstance(reader, McapReader):
        return 0, 0
    extras = reader.extras()
    if not isinstance(writer, McapWriter):
        return 0, len(extras)
    copied = 0
    for record in extras:
        if isinstance(record, mcap_format.Attachment) and not (
            (start is None or record.log_time >= start) and (end is None or record.log_time <= end)
        ):
            continue
        writer.add_extra(record)
        copied += 1
    return copied, len(extras) - copied


def topic_frequencies(reader: BagReader) -> dict[str, float]:
    """Topic -> median message rate in Hz, as ``rosbag info --freq`` computes it.

    The median of the gaps between consecutive messages of a topic (all its connections
    merged); topics with fewer than two messages or a zero median gap are left out.
    """
    last: dict[str, int] = {}
    gaps: dict[str, list[int]] = {}
    for conn, t, _ in reader.times():
        prev = last.get(conn.topic)
        if prev is not None:
            gaps.setdefault(conn.topic, []).append(t - prev)
        last[conn.topic] = t
    rates: dict[str, float] = {}
    for topic, values in gaps.items():
        median = statistics.median(values)
        if median > 0:
            rates[topic] = 1e9 / median
    return rates
