"""Recovering unindexed, unfinished or cut-short bags (``rosbag reindex``, ``mcap recover``).

The readers already read such files by walking them; recovery copies everything they salvage
into a new, fully indexed file and reports what could not be read. It rebuilds from the
records, as ``rosbag reindex`` does: a ``.bag`` is walked chunk by chunk even when its index is
whole, and where a connection's record in a chunk differs from the index's, the chunk's is
kept (it travels with the messages). Unlike ``rosbag reindex``
it never truncates the source, and it keeps the records of a chunk that was never closed
(rosbag throws that whole chunk away) and whatever decompresses of a cut-short one.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from rostools.bag.formats.access import (
    copy_extras,
    format_for_name,
    mcap_profile,
    open_bag,
    open_writer,
    require_ros1,
)
from rostools.bag.formats.base import Targets
from rostools.bag.formats.model import BagDataLossError, BagUsageError, CompressionStats, counted


@dataclass(frozen=True)
class RecoverReport:
    """What a recovery salvaged and what it could not.

    ``lost`` lists the damage (empty when everything in the file was read); ``notes`` says
    how the file had to be read (no index, no summary, ...).
    """

    source: Path
    output: Path
    format: str
    was_indexed: bool
    messages: int
    connections: int
    notes: tuple[str, ...]
    lost: tuple[str, ...]

    @property
    def complete(self) -> bool:
        """True when nothing was lost."""
        return not self.lost

    def raise_if_lost(self) -> None:
        """Raise ``DataLossError`` (exit code 6) naming the damage, if any."""
        if self.lost:
            raise BagDataLossError(
                f"recovered {counted(self.messages, 'message')} into {self.output}, but lost data: "
                + "; ".join(self.lost)
            )


def recover(
    src: str | Path,
    dst: str | Path,
    *,
    compression: str | None = None,
    chunk_size: int | None = None,
    overwrite: bool = False,
    check_crcs: bool = True,
) -> RecoverReport:
    """Write every message that can be salvaged from ``src`` into a new indexed ``dst``.

    The output format follows ``dst``'s name. ``compression`` defaults to the source's most
    used chunk compression (``.bag`` into ``.bag``) or the writer's default. An MCAP chunk
    that fails its CRC is left out (and listed), unless ``check_crcs`` is False.
    """
    src, dst = Path(src), Path(dst)
    if dst.exists() and src.resolve() == dst.resolve():
        raise BagUsageError(f"cannot recover {src} into itself; give another output file")
    # never from an index that disagrees with the records
    with open_bag(src, from_records=True, check_crcs=check_crcs) as reader:
        kind = format_for_name(dst)
        if kind != "mcap":  # an MCAP output takes any encoding as it is
            require_ros1(reader, f"writing to .{kind}")
        info = reader.info()
        writer = open_writer(
            dst,
            compression=compression or _same_compression(info.format, dst, info.compression),
            chunk_size=chunk_size,
            overwrite=overwrite,
            profile=mcap_profile([reader]),
        )
        try:
            out = Targets(writer, reader.connections)
            count = writer.write_many(reader.messages(), out)
            copy_extras(reader, writer)
        except BaseException:
            writer.abort()
            raise
        writer.close()
        return RecoverReport(
            source=src,
            output=dst,
            format=info.format,
            was_indexed=reader.indexed,
            messages=count,
            connections=len(out),
            notes=tuple(reader.notes),
            lost=tuple(reader.damage),
        )


#: ``rosbag reindex`` by its ROS name.
reindex = recover


def _same_compression(kind: str, dst: Path, rows: tuple[CompressionStats, ...]) -> str | None:
    """The source's main chunk compression when the output has the same format, else None."""
    if not rows or format_for_name(dst) != kind:
        return None
    return rows[0].compression
