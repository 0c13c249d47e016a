"""``bag doctor``: checks a ``.bag`` or MCAP file without changing it, one finding per line.

What it checks: that the file opens and reads to the end (record lengths, bytes that do not
parse and what the reader skipped, cut-short or unindexed tails, and whether ``bag recover``
would help); the index against the records (each index entry's time and connection against
its record, chunk time ranges, the message count of each connection against the messages
read, each connection record in a chunk against the index's copy); MCAP CRCs: each chunk's,
the data section's and the summary's; each ROS 1 connection's md5sum against its definition
text, and that the text parses; and every message against its type (shorter or longer than
it).
Messages out of time order within a chunk are a note, not a finding: the formats allow it.
Library code: no printing.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rostools.bag.formats.model import counted
from rostools.errors import RostoolsError

if TYPE_CHECKING:
    from rostools.bag.formats.base import BagReader
    from rostools.bag.formats.model import Connection


@dataclass
class Checkup:
    """What ``doctor`` found in one file."""

    path: Path
    messages: int = 0
    findings: list[str] = field(default_factory=list)
    #: What is legal but worth knowing (messages out of time order within a chunk).
    notes: list[str] = field(default_factory=list)
    #: Whether ``bag recover`` would give a better file (a damaged or unindexed tail).
    recover_helps: bool = False

    @property
    def clean(self) -> bool:
        """No findings."""
        return not self.findings


#: Messages read between two calls of ``doctor``'s progress callback.
PROGRESS_STEP = 4096


def doctor(path: str | Path, progress: Callable[[int, int], None] | None = None) -> Checkup:
    """Check ``path``; never raises for what is in the file, only reports it.

    ``progress(done, total)`` is called as messages are read (total: the index's count).
    """
    from rostools.bag.formats.access import open_bag

    report = Checkup(Path(path))
    try:
        reader = open_bag(path)
    except RostoolsError as err:
        report.findings.append(f"does not open: {err}")
        return report
    from rostools.bag.formats.mcap_reader import McapReader
    from rostools.bag.formats.rosbag1_reader import Bag1Reader

    if isinstance(reader, McapReader):
        reader.check_crcs = True  # every chunk's, as its messages are read
    with reader:
        _connections(reader, report)
        _messages(reader, report, progress)
        problems: list[str] = []
        if isinstance(reader, McapReader):
            problems, report.notes = reader.chunk_checks()
        elif isinstance(reader, Bag1Reader):
            # Walks every chunk: a connection record there unlike the index's is noted too.
            report.notes = reader.order_notes()
        for note in reader.notes:
            report.findings.append(note)
            report.recover_helps = True
        for damage in reader.damage:
            report.findings.append(damage)
            report.recover_helps = True
        report.findings += problems
    if report.recover_helps:
        report.findings.append("bag recover would rebuild what can be read into a new file")
    return report


def _ros1(reader: BagReader) -> set[int]:
    """The connections whose messages are ROS 1 serialised, with a definition to check.

    A blank definition (std_msgs/Empty, or a writer that left it out) has nothing to check.
    """
    from rostools.bag.formats.mcap_reader import McapReader

    if isinstance(reader, McapReader):
        ros1 = {c.id for c in reader.channels.values() if c.message_encoding == "ros1"}
    else:
        ros1 = {c.id for c in reader.connections}
    return {c.id for c in reader.connections if c.id in ros1 and c.definition.strip()}


def _connections(reader: BagReader, report: Checkup) -> None:
    from rostools.msgs.store import md5_of

    ros1 = _ros1(reader)
    for conn in reader.connections:
        if conn.id not in ros1:
            continue
        got = md5_of(conn.type, conn.definition)
        where = f"connection {conn.id} ({conn.topic}, {conn.type})"
        if not got:
            report.findings.append(f"{where}: its definition text does not parse")
        elif conn.md5sum not in ("*", got):
            report.findings.append(
                f"{where}: md5sum {conn.md5sum} does not match its definition ({got})"
            )


def _decoder(conn: Connection, ros1: set[int]) -> Any:
    from rostools.msgs import learnt
    from rostools.msgs.store import TypeStore, md5_of

    if conn.id not in ros1 or not md5_of(conn.type, conn.definition):
        return None
    return learnt.decoder(TypeStore([]), conn.type, conn.md5sum, conn.definition)


def _messages(
    reader: BagReader, report: Checkup, progress: Callable[[int, int], None] | None
) -> None:
    """Read every message; decode those of ROS 1 types; count what does not fit its type."""
    ros1 = _ros1(reader)
    total = (_indexed(reader) or 0) if progress is not None else 0
    done = 0
    decoders: dict[int, Any] = {}
    counts: Counter[int] = Counter()
    short: Counter[int] = Counter()
    long: Counter[int] = Counter()
    conns: dict[int, Connection] = {}
    try:
        for conn, _, data in reader.messages():
            counts[conn.id] += 1
            done += 1
            if progress is not None and done % PROGRESS_STEP == 0:
                progress(done, max(total, done))
            decode = decoders.get(conn.id, False)
            if decode is False:
                decode = decoders[conn.id] = _decoder(conn, ros1)
                conns[conn.id] = conn
            if decode is None:
                continue
            try:
                _, end = decode(data, 0)
            except RostoolsError:
                short[conn.id] += 1
                continue
            if end != len(data):
                long[conn.id] += 1
    except RostoolsError as err:
        report.findings.append(f"reading stops: {err}")
        report.recover_helps = True
    report.messages = sum(counts.values())
    for sizes, how in ((short, "shorter"), (long, "longer")):
        for cid, n in sizes.items():
            c = conns[cid]
            verb = "is" if n == 1 else "are"
            report.findings.append(
                f"{counted(n, 'message')} on {c.topic} {verb} {how} than {c.type} says"
            )
    if progress is not None:
        progress(done, done)
    try:
        info = reader.info()
    except RostoolsError as err:
        report.findings.append(f"no summary: {err}")
        return
    if reader.notes:
        return  # the summary is not the file's own index: the notes say why
    if info.message_count != report.messages:
        report.findings.append(
            f"the index counts {counted(info.message_count, 'message')} but {report.messages}"
            f" {'was' if report.messages == 1 else 'were'} read"
        )
    by_id = {c.id: c for c in reader.connections}
    for cid in sorted(info.connection_counts.keys() | counts.keys()):
        listed, read = info.connection_counts.get(cid, 0), counts.get(cid, 0)
        if listed != read:
            topic = by_id[cid].topic if cid in by_id else "?"
            report.findings.append(
                f"the index counts {counted(listed, 'message')} of connection {cid} ({topic})"
                f" but {read} {'was' if read == 1 else 'were'} read"
            )


def _indexed(reader: BagReader) -> int | None:
    """The index's message count, or None when the file has no readable summary."""
    try:
        return reader.info().message_count
    except RostoolsError:
        return None
