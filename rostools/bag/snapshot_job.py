"""One snapshot being written: the window's buffered part, then its live part, by a thread.

The trigger hands the job references to what the buffer held (``ringbuffer.Held``), so the
buffer goes on taking and evicting messages while the job writes; the live part (``--after``,
``--continue``) reaches the job through ``push`` on the event loop, in a queue of its own.
The file is ``NAME.active`` until it is complete, and handed to the OS every second.
"""

from __future__ import annotations

import collections
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rostools.bag.bagfile import FLUSH_PERIOD, BagFile
from rostools.bag.recorder import ENTRY_OVERHEAD
from rostools.bag.ringbuffer import ConnInfo, Entry, Held
from rostools.node.connection import Frame


@dataclass
class FileSpec:
    """Where and how a snapshot is written."""

    path: Path
    format: str
    compression: str | None
    chunk_size: int | None


class SnapshotJob(threading.Thread):
    """Writes one snapshot: messages held in [start_ns, until_ns], then live ones to stop_ns.

    ``stop_ns`` None writes live messages until ``end()``; ``max_pending`` bounds the bytes
    of live messages waiting for the disk (past it the oldest are dropped and counted).
    ``on_done`` is called from the thread once the file is complete or has failed.
    """

    def __init__(
        self,
        spec: FileSpec,
        held: Held,
        start_ns: int,
        until_ns: int,
        stop_ns: int | None,
        topics: set[str] | None,
        max_pending: int,
        on_done: Callable[[SnapshotJob], None],
    ) -> None:
        super().__init__(name=f"rostools-snapshot-{spec.path.name}", daemon=True)
        self.spec = spec
        self.held = held
        self.start_ns = start_ns
        self.until_ns = until_ns
        self.stop_ns = stop_ns
        self.topics = topics
        self.max_pending = max_pending
        self.on_done = on_done
        self.cond = threading.Condition()
        self.pending: collections.deque[Entry] = collections.deque()
        self.pending_bytes = 0
        self.ended = stop_ns is not None and stop_ns <= until_ns
        self.drops = 0
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

    def push(self, conn: ConnInfo, t_ns: int, frames: list[Frame]) -> None:
        """Live messages received at ``t_ns`` (event loop); past ``stop_ns`` the file ends."""
        if self.ended:
            return
        if self.stop_ns is not None and t_ns > self.stop_ns:
            self.end()
            return
        with self.cond:
            for data in frames:
                self.pending.append((t_ns, conn, data))
                self.pending_bytes += len(data) + ENTRY_OVERHEAD
            while self.pending_bytes > self.max_pending and len(self.pending) > 1:
                _, _, old = self.pending.popleft()
                self.pending_bytes -= len(old) + ENTRY_OVERHEAD
                self.drops += 1
            self.cond.notify()

    def end(self) -> None:
        """No more live messages: the file is closed once what waits is written."""
        with self.cond:
            self.ended = True
            self.cond.notify()

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
        while True:
            with self.cond:
                if not self.pending and not self.ended:
                    self.cond.wait(FLUSH_PERIOD / 2)
                batch, self.pending = self.pending, collections.deque()
                self.pending_bytes = 0
                ended = self.ended
            while batch:
                t_ns, conn, data = batch.popleft()
                out.write(conn, conn.topic, conn.header, t_ns, data)
            out.flush_if_due()
            if ended and not self.pending:
                return

    def summary(self) -> dict[str, Any]:
        """What the file holds, or why it failed: name, messages, bytes, time span, drops.

        ``start`` and ``end`` are the first and last message's receive times (s);
        ``window_ns`` the range of receive times asked for (its end None: until stopped);
        ``seconds`` how long the file took, from the trigger until complete.
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
            "drops": self.drops,
            "error": str(self.error) if self.error is not None else None,
        }


def wait_joined(jobs: list[SnapshotJob], timeout: float) -> None:
    """Join ``jobs`` within ``timeout`` seconds in all (a thread, not the event loop)."""
    deadline = time.monotonic() + timeout
    for job in jobs:
        job.join(max(deadline - time.monotonic(), 0.0))
