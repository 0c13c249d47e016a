"""``bag convert --to ros2``: ROS 1 bags (``.bag``, or MCAP of ROS 1 messages) into rosbag2.

Library function, no printing. Every input's connections are mapped first (``ros2types``):
a type with no ROS 2 form is refused in one line naming it before anything is written, unless
its topic is excluded. The messages of all inputs then pass in one time order into
``formats.rosbag2_writer``, converted to CDR as they go. Damage in an input is read past as
every copying command does (``bag recover``'s reading) and listed in the report (exit 6); a
message whose bytes do not fit its type is left out and listed the same way. A failure
deletes the partial output.
"""

from __future__ import annotations

import contextlib
import gc
import itertools
from collections.abc import Collection, Iterator, Sequence
from pathlib import Path

from rostools.bag.formats.access import merged_messages, open_bag, require_ros1
from rostools.bag.formats.base import problems
from rostools.bag.formats.mcap_writer import DEFAULT_CHUNK_SIZE
from rostools.bag.formats.model import BagUsageError, Connection, counted
from rostools.bag.formats.ordering import RawMessage
from rostools.bag.formats.ros2types import DEFAULT_DISTRO, Ros2Mapping
from rostools.bag.formats.rosbag2_writer import Rosbag2Writer
from rostools.bag.tools.ops import CopyReport
from rostools.bag.tools.options import PROGRESS_EVERY, Progress


def convert_to_ros2(
    sources: str | Path | Sequence[str | Path],
    dst: str | Path,
    *,
    distro: str = DEFAULT_DISTRO,
    types: str | Path | None = None,
    exclude: Collection[str] = (),
    compression: str = "zstd",
    chunk_size: int | None = None,
    overwrite: bool = False,
    check_crcs: bool = True,
    progress: Progress | None = None,
) -> CopyReport:
    """Write the ROS 1 messages of ``sources`` as rosbag2 at ``dst`` (a folder, or ``.mcap``).

    ``distro`` picks the ROS 2 types (``ros2types.DISTROS``); ``types`` is a YAML file of
    renames and definitions (see ``ros2types``); ``exclude`` names topics left out.
    ``compression`` and ``chunk_size`` (bytes) are the MCAP's chunks'. Returns what was written;
    ``report.raise_if_lost()`` raises exit 6 if some input could not be read.
    """
    paths = [Path(sources)] if isinstance(sources, str | Path) else [Path(s) for s in sources]
    if not paths:
        raise BagUsageError("bag convert --to ros2 needs at least one input")
    out = Path(dst)
    for path in paths:
        if out.exists() and path.resolve() == out.resolve():
            raise BagUsageError(f"cannot use the same file as input and output: {path}")
    mapping = Ros2Mapping(distro, types)
    skip = set(exclude)
    with contextlib.ExitStack() as stack:
        readers = [stack.enter_context(open_bag(p, check_crcs=check_crcs)) for p in paths]
        topics = sorted({c.topic for r in readers for c in r.connections} - skip)
        for reader in readers:
            require_ros1(reader, "bag convert --to ros2", topics)
        conns = [c for r in readers for c in r.connections if c.topic not in skip]
        for conn in conns:
            mapping.map(conn)  # every refusal before the output exists
        total = sum(r.info().message_count for r in readers)
        writer = Rosbag2Writer(
            out, mapping=mapping, compression=compression, overwrite=overwrite,
            chunk_size=chunk_size or DEFAULT_CHUNK_SIZE,
        )  # fmt: skip
        # One input needs no merging (a heap step per message)
        stream = (
            readers[0].messages(topics=topics)
            if len(readers) == 1
            else merged_messages(readers, topics)
        )
        try:
            with _fewer_collections():
                read, written, misfits = _pump(writer, stream, progress, total)
        except BaseException:
            writer.abort()
            raise
        writer.close()
        notes, lost = problems(readers)
    return CopyReport(
        source=paths[0],
        output=out,
        format="ros2",
        compression=compression,
        messages_read=read,
        messages_written=written,
        connections=len(writer.topics),
        notes=notes,
        lost=lost + misfits,
    )


#: The cyclic collector's first threshold while converting (Python's is 700 allocations).
GC_THRESHOLD = 100_000


@contextlib.contextmanager
def _fewer_collections() -> Iterator[None]:
    """The cyclic collector run less often, for the conversion's time.

    A chunk's entries (thousands of tuples, no cycles) outlive several collections at
    Python's threshold and are walked each time (5 to 10% of a conversion of small messages);
    at this one most are gone before one runs. Cycles are still collected.
    """
    old = gc.get_threshold()
    gc.set_threshold(GC_THRESHOLD, *old[1:])
    try:
        yield
    finally:
        gc.set_threshold(*old)


def _pump(
    writer: Rosbag2Writer,
    stream: Iterator[RawMessage],
    progress: Progress | None,
    total: int,
) -> tuple[int, int, tuple[str, ...]]:
    """Convert and write a message stream: (read, written, what did not convert)."""
    bad: dict[tuple[str, str], list[int | str]] = {}

    def misfit(conn: Connection, err: Exception) -> None:
        seen = bad.setdefault((conn.topic, conn.type), [0, str(err)])
        seen[0] = int(seen[0]) + 1

    if progress is None:
        read, written = writer.write_stream(stream, misfit)
    else:  # in batches: no count to check per message
        read = written = 0
        while True:
            n, stored = writer.write_stream(itertools.islice(stream, PROGRESS_EVERY), misfit)
            read, written = read + n, written + stored
            progress(read, total)
            if n < PROGRESS_EVERY:
                break
    misfits = tuple(
        f"{counted(int(n), 'message')} on {topic} do not fit {type_} ({why})"
        for (topic, type_), (n, why) in bad.items()
    )
    return read, written, misfits
