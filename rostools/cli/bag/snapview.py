"""What ``bag snapshot`` shows: the buffer per topic on a terminal, or a line per file elsewhere.

The live table gives, per topic, its publishers, the messages buffered, the buffer's fill and
time span, the rate, and what the limits evicted; below it, a progress line for each file
being written and the files written last.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any

from rostools.cli.bag.shared import human_size as size_text
from rostools.cli.liveview import LiveView
from rostools.errors import one_line

if TYPE_CHECKING:
    from rostools.bag.live.snapshot import Snapshotter
    from rostools.bag.live.snapshot_job import SnapshotJob

#: Files written that the table keeps listing.
SHOWN_FILES = 5
KEYS = "keys: s snapshot, p pause, r resume"


def written_text(summary: dict[str, Any]) -> str:
    """``wrote NAME: N messages (SIZE), S s`` for a complete file, and what it lost."""
    lost = summary.get("lost")
    return (
        f"wrote {one_line(summary['name'])}: {summary['messages']} messages "
        f"({size_text(summary['bytes'])}), {summary['duration']:.1f} s"
        + (f", {lost_text(summary)}" if lost else "")
    )


def lost_text(summary: dict[str, Any]) -> str:
    """``N messages of the window LOST (...)``: where they went, from a file's summary."""
    why = []
    if summary.get("evicted"):
        why.append(f"{summary['evicted']} let go by the buffer's limits before the trigger came")
    if summary.get("drops"):
        why.append(f"{summary['drops']} dropped waiting for the disk")
    least = "" if summary.get("lost_exact", True) else "at least "
    return f"{least}{summary['lost']} messages of the window LOST ({', '.join(why)})"


def stopped_data(snap: Snapshotter) -> dict[str, Any]:
    """What the recorder received, held at the end and evicted, and the files it wrote."""
    topics = {
        topic: {
            "type": s.type,
            "received": s.messages,
            "buffered": len(snap.ring.topic(topic).entries),
            "evicted": snap.ring.topic(topic).evicted,
        }
        for topic, s in sorted(snap.stats.items())
    }
    return {
        "received": sum(t["received"] for t in topics.values()),
        "evicted": sum(t["evicted"] for t in topics.values()),
        "files": [str(job.path) for job in snap.finished if job.error is None],
        "topics": topics,
    }


def stopped_text(data: dict[str, Any]) -> str:
    """The line at the end: what was received and evicted, and how many files were written."""
    return (
        f"received {data['received']} messages on {len(data['topics'])} topics, "
        f"{data['evicted']} evicted; wrote {len(data['files'])} snapshots"
    )


def progress_text(job: SnapshotJob) -> str:
    """Where a file being written is: its part from the buffer, then live until its stop."""
    name = one_line(job.path.name)
    if job.total == 0 or job.done < job.total:
        share = job.done / job.total if job.total else 0.0
        return f"writing {name}: {share:.0%} of the buffered part ({size_text(job.done)})"
    out = job.file
    count = out.messages if out is not None else 0
    until = "until stopped" if job.stop_ns is None else "to the end of its window"
    return f"writing {name}: {count} messages, live {until}"


class SnapshotTable(LiveView):
    """The terminal view of a snapshot recorder, redrawn twice a second."""

    def __init__(self) -> None:
        super().__init__()
        self.files: list[str] = []

    def written(self, job: SnapshotJob) -> None:
        """A file is complete (or failed): list it under the table."""
        if job.error is None:
            self.files = [*self.files, written_text(job.summary())][-SHOWN_FILES:]

    def tick(self, snap: Snapshotter, force: bool = False) -> None:
        """Redraw, at most twice a second unless ``force``."""
        if not self.due(force):
            return
        self.measure(snap.stats, snap.started, time.monotonic())
        self.live.update(self._view(snap), refresh=True)

    def _view(self, snap: Snapshotter) -> Any:
        from rich.console import Group
        from rich.markup import escape
        from rich.table import Table
        from rich.text import Text

        ring = snap.ring
        state = "[bold yellow]PAUSED[/]" if snap.paused else "buffering"
        title = (
            f"{state} {len(ring.topics)} topics: {size_text(ring.held)} of "
            f"{size_text(ring.size)}, {snap.opts.duration:g} s at most"
        )
        table = Table(title=title, title_justify="left")
        columns = ("topic", "type", "pubs", "buffered", "fill", "span", "rate", "evicted")
        for col in columns:
            table.add_column(col, justify="left" if col in ("topic", "type") else "right")
        for topic, tb in sorted(ring.topics.items()):
            s = snap.stats.get(topic)
            kind = escape(one_line(s.type)) if s and s.type else "[dim]no publisher yet[/]"
            table.add_row(
                escape(one_line(topic)), kind, str(snap.publishers(topic)),
                str(len(tb.entries)), size_text(tb.bytes), f"{tb.span():.1f} s",
                f"{self.rates.get(topic, (0.0, 0.0))[0]:.1f} Hz", str(tb.evicted),
            )  # fmt: skip
        lines = [KEYS, *(progress_text(job) for job in snap.jobs), *self.files]
        return Group(table, *(Text(line) for line in lines))
