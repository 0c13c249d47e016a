"""The live part of the snapshots being written: one queue for every file, each message once.

A trigger with a stop time ahead (``--after``, ``--continue``) writes the messages that arrive
after it. The recorder appends them here once (``push``, on the event loop), whatever number of
files want them; each file's thread reads on from its own place (``LiveReader``), and a message
is let go once every file has written it. So four overlapping files cost the memory of one.

The bytes waiting are bounded by ``limit`` for all files together (``--size``). Past it the
oldest message goes, and each file that had not taken it counts it as dropped, exactly: the
disk did not keep up. A file's thread takes at most ``BATCH_BYTES`` at a time (or one message),
so what it holds while writing, beyond the queue, is bounded too.
"""

from __future__ import annotations

import collections
import itertools
import threading

from rostools.bag.formats.model import ENTRY_OVERHEAD
from rostools.bag.live.ringbuffer import ConnInfo, Entry
from rostools.node.connection import Frame

#: The most a file's thread takes from the queue at once (one message at least).
BATCH_BYTES = 4 * 1024 * 1024
BATCH_MESSAGES = 1000


class LiveReader:
    """One file's place in the queue: its topics (None: all) and its stop time (None: none)."""

    __slots__ = ("drops", "end_at", "pos", "stop_ns", "taken", "topics")

    def __init__(self, pos: int, topics: set[str] | None, stop_ns: int | None) -> None:
        self.pos = pos  # the index of the first message not yet written
        self.taken = pos  # the index of the first message not yet taken to be written
        self.end_at: int | None = None  # once ended: the index it reads up to
        self.topics = topics
        self.stop_ns = stop_ns
        self.drops = 0

    def wants(self, topic: str, t_ns: int) -> bool:
        """Whether a message of ``topic`` received at ``t_ns`` belongs in the file."""
        return (self.topics is None or topic in self.topics) and (
            self.stop_ns is None or t_ns <= self.stop_ns
        )


class LiveQueue:
    """Live messages waiting for the files being written; at most ``limit`` bytes."""

    def __init__(self, limit: int) -> None:
        self.limit = limit
        self.cond = threading.Condition()
        self.entries: collections.deque[Entry] = collections.deque()
        self.base = 0  # the index of ``entries[0]`` since the start
        self.bytes = 0  # of the messages queued, ``ENTRY_OVERHEAD`` each
        self.readers: list[LiveReader] = []

    @property
    def tail(self) -> int:
        """The index the next message will have."""
        return self.base + len(self.entries)

    def open(self, topics: set[str] | None, stop_ns: int | None) -> LiveReader:
        """A file's place, from the next message on (event loop, at its trigger)."""
        with self.cond:
            reader = LiveReader(self.tail, topics, stop_ns)
            self.readers.append(reader)
            return reader

    def wanted(self, topic: str) -> bool:
        """Whether some live file wants messages of ``topic`` (cheap: a few files at most)."""
        with self.cond:  # a file's thread may be closing its reader
            return any(r.end_at is None and (r.topics is None or topic in r.topics)
                       for r in self.readers)  # fmt: skip

    def push(self, conn: ConnInfo, t_ns: int, frames: list[Frame]) -> None:
        """Messages received at ``t_ns`` (event loop); past ``limit``, the oldest go."""
        with self.cond:
            self.entries.extend(zip(itertools.repeat(t_ns), itertools.repeat(conn), frames))
            self.bytes += sum(map(len, frames)) + len(frames) * ENTRY_OVERHEAD
            while self.bytes > self.limit and len(self.entries) > 1:
                self._drop_oldest()
            self.cond.notify_all()

    def _drop_oldest(self) -> None:
        t_ns, conn, data = self.entries.popleft()
        for reader in self.readers:
            if reader.taken <= self.base:  # not yet taken: it will never be written
                reader.pos = reader.taken = self.base + 1
                ended = reader.end_at is not None and reader.end_at <= self.base
                if not ended and reader.wants(conn.topic, t_ns):
                    reader.drops += 1
            elif reader.pos <= self.base:  # being written now: its batch holds it
                reader.pos = self.base + 1
        self.base += 1
        self.bytes -= len(data) + ENTRY_OVERHEAD

    def take(self, reader: LiveReader, timeout: float) -> tuple[list[Entry], bool]:
        """The next messages for ``reader`` (its thread), waiting up to ``timeout`` for some.

        Also whether the file has had them all (ended, and nothing left after these).
        """
        with self.cond:
            last = self.tail if reader.end_at is None else reader.end_at
            if reader.taken >= last and reader.end_at is None:
                self.cond.wait(timeout)
                last = self.tail if reader.end_at is None else reader.end_at
            # the queue may have dropped past an ended file's end (another file kept it moving)
            first, last = reader.taken - self.base, max(last, reader.taken) - self.base
            batch: list[Entry] = []
            size = 0
            for entry in itertools.islice(self.entries, first, last):
                if batch and (size >= BATCH_BYTES or len(batch) >= BATCH_MESSAGES):
                    break
                batch.append(entry)
                size += len(entry[2])
            reader.taken += len(batch)
            done = reader.end_at is not None and reader.taken >= reader.end_at
            return batch, done

    def written(self, reader: LiveReader) -> None:
        """``reader`` wrote what it took: let go of what every file has written."""
        with self.cond:
            reader.pos = max(reader.pos, reader.taken)
            self._let_go()

    def end(self, reader: LiveReader) -> None:
        """No more messages for ``reader`` than those queued now (event loop or its thread)."""
        with self.cond:
            if reader.end_at is None:
                reader.end_at = max(self.tail, reader.taken)
            self.cond.notify_all()

    def close(self, reader: LiveReader) -> None:
        """``reader``'s file is complete (or failed): it holds nothing any more."""
        with self.cond:
            if reader in self.readers:
                self.readers.remove(reader)
            self._let_go()

    def _let_go(self) -> None:
        lowest = min((r.pos for r in self.readers), default=self.tail)
        while self.base < lowest and self.entries:
            _, _, data = self.entries.popleft()
            self.base += 1
            self.bytes -= len(data) + ENTRY_OVERHEAD
