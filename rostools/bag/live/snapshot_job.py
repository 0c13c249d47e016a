"""One snapshot being written: the window's buffered part, then its live part, by a thread.

The trigger hands the job references to what the buffer held (``ringbuffer.Held``), so the
buffer goes on taking and evicting messages while the job writes; the live part (``--after``,
``--continue``) it reads from the queue all files share (``snapshot_live.LiveQueue``), from
the moment of the trigger on. The file is ``NAME.active`` until it is complete, and handed to
the OS every second. What the window lost is counted exactly: ``evicted``, messages the
buffer's limits had let go before the trigger reached it; ``drops``, live messages the queue
let go because the disk did not keep up.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rostools.bag.live.bagfile import FLUSH_PERIOD, BagFile
from rostools.bag.live.ringbuffer import Held, Lost
from rostools.bag.live.snapshot_live import LiveQueue


@dataclass
class FileSpec:
    """Where and how a snapshot is written."""

    path: Path
    format: str
    compression: str | None
    chunk_size: int | None


class SnapshotJob(threading.Thread):
    """Writes one snapshot: messages held in [start_ns, until_ns], then live ones to stop_ns.

    ``stop_ns`` None writes live messages until ``end()``; they come from ``live``, the queue
    every file shares. ``evicted`` is what the window had already lost when the trigger
    reached the buffer. ``on_done`` is called from the thread once the file is complete or
    has failed.
    """

    def __init__(
        self,
        spec: FileSpec,
        held: Held,
        start_ns: int,
        until_ns: int,
        stop_ns: int | None,
        topics: set[str] | None,
        live: LiveQueue,
        on_done: Callable[[SnapshotJob], None],
        evicted: Lost | None = None,
    ) -> None:
        super().__init__(name=f"rostools-snapshot-{spec.path.name}", daemon=True)
        self.spec = spec
        self.held = held
        self.start_ns = start_ns
        self.until_ns = until_ns
        self.stop_ns = stop_ns
        self.topics = topics
        self.queue = live
        self.on_done = on_done
        self.evicted = evicted if evicted is not None else Lost()
        self.ended = stop_ns is not None and stop_ns <= until_ns
        self.reader = live.open(topics, stop_ns)
        if self.ended:
            live.end(self.reader)
        self.file: BagFile | None = None
        self.error: BaseException | None = None
        #: Progress of the buffered part: bytes of it written, of ``total`` (0 until known).
        self.total = 0
        self.done = 0
        self._result: dict[str, Any] | None = None
        self.began = time.monotonic()

    @property
    def path(self) -> Path:
        """The file's name once complete."""
        return self.spec.path

    @property
    def live(self) -> bool:
        """Whether live messages still go into the file."""
        return not self.ended

    def wants(self, topic: str) -> bool:
        """Whether messages of ``topic`` belong in the file."""
        return self.topics is None or topic in self.topics

    @property
    def drops(self) -> int:
        """Live messages of the window let go before they were written (the disk was slow)."""
        return self.reader.drops

    @property
    def lost(self) -> int:
        """Messages of the window not in the file: evicted before the trigger, or dropped."""
        return self.evicted.count + self.drops

    def end(self) -> None:
        """No more live messages: the file is closed once those queued are written."""
        self.ended = True
        self.queue.end(self.reader)

    def run(self) -> None:
        """Write the file, then report."""
        try:
            spec = self.spec
            self.file = BagFile(spec.path, spec.format, spec.compression, spec.chunk_size)
            self._write_held(self.file)
            self._write_live(self.file)
            self.file.close()
        except BaseException as err:  # noqa: BLE001 - reported through on_done
            self.error = err
            self.end()
        finally:
            self.queue.close(self.reader)
            self._result = self._summary()
            self.file = None  # the writer's index goes: the recorder keeps the job a while
            self.on_done(self)

    def _write_held(self, out: BagFile) -> None:
        held, self.held = self.held, Held([], {})  # let go of the buffer's messages as written
        for t_ns, conn, data in held.latched_before(self.start_ns):
            out.write(conn, conn.topic, conn.header, t_ns, data)
        entries: list[Any] = list(held.messages(self.start_ns, self.until_ns))
        del held
        self.total = sum(len(e[2]) for e in entries) or 1
        for i, (t_ns, conn, data) in enumerate(entries):
            entries[i] = None
            out.write(conn, conn.topic, conn.header, t_ns, data)
            self.done += len(data)
            out.flush_if_due()
        self.done = self.total

    def _write_live(self, out: BagFile) -> None:
        queue, reader = self.queue, self.reader
        while True:
            batch, done = queue.take(reader, FLUSH_PERIOD / 2)
            for t_ns, conn, data in batch:
                if reader.wants(conn.topic, t_ns):
                    out.write(conn, conn.topic, conn.header, t_ns, data)
                elif reader.stop_ns is not None and t_ns > reader.stop_ns:
                    self.end()  # past the window: what follows is not wanted either
            del batch
            queue.written(reader)
            out.flush_if_due()
            if done:
                return

    def summary(self) -> dict[str, Any]:
        """What the file holds, or why it failed: name, messages, bytes, time span, drops.

        ``start`` and ``end`` are the first and last message's receive times (s);
        ``window_ns`` the range of receive times asked for (its end None: until stopped);
        ``seconds`` how long the file took, from the trigger until complete; ``lost`` the
        messages of the window not in the file: ``evicted`` by the buffer's limits before the
        trigger reached it (``lost_exact`` false: at least that many), ``drops`` let go
        while waiting for the disk.
        """
        return self._result if self._result is not None else self._summary()

    def _summary(self) -> dict[str, Any]:
        out = self.file
        first = out.first_ns if out is not None else None
        last = out.last_ns if out is not None else None
        return {
            "name": str(self.path),
            "messages": out.messages if out is not None else 0,
            "bytes": out.bytes if out is not None else 0,
            "start": first / 1e9 if first is not None else None,
            "end": last / 1e9 if last is not None else None,
            "duration": (last - first) / 1e9 if first is not None and last is not None else 0.0,
            "window_ns": [self.start_ns, self.stop_ns],
            "seconds": round(time.monotonic() - self.began, 3),
            "lost": self.lost,
            "lost_exact": self.evicted.exact,
            "evicted": self.evicted.count,
            "drops": self.drops,
            "error": str(self.error) if self.error is not None else None,
        }


def wait_joined(jobs: list[SnapshotJob], timeout: float) -> None:
    """Join ``jobs`` within ``timeout`` seconds in all (a thread, not the event loop)."""
    deadline = time.monotonic() + timeout
    for job in jobs:
        job.join(max(deadline - time.monotonic(), 0.0))
