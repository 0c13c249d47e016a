"""Recording: subscriptions on the event loop, a writer thread, raw frames in between.

Frames go from the socket into a bounded queue without being decoded; a thread takes them
out and writes them, so the disk never blocks receiving. When the queue holds more than the
buffer allows, the oldest message is dropped and counted against its topic, as rosbag does,
but the count is shown and makes the exit code say so. The file is written as ``NAME.active``
and renamed when it is closed; a recording killed outright, or cut short by a write that
failed (a full disk), is left for ``bag recover``.
"""

from __future__ import annotations

import asyncio
import collections
import logging
import struct
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rostools.bag.formats.access import file_name
from rostools.bag.formats.model import ENTRY_OVERHEAD
from rostools.bag.live.bagfile import BagFile, write_failure
from rostools.bag.live.follow import (
    Follower,
    FramesCallback,
    LiveOptions,
    TopicStats,
)
from rostools.errors import UsageError
from rostools.msgs.wellknown import STRING
from rostools.node.connection import Frame, InboundConnection
from rostools.node.node import LiveNode
from rostools.node.notice import Notice
from rostools.node.publisher import TopicPublisher

if TYPE_CHECKING:
    from rostools.bag.live.ros2file import Ros2Types

log = logging.getLogger(__name__)

#: How often the free disk space is checked against ``min_space`` (rosbag: 20 s).
DISK_PERIOD = 1.0
#: The writer gives back the budget of what it has written in steps of this many bytes.
RELEASE_STEP = 1024 * 1024
#: The writer takes what is queued this often (s), or as soon as the queue holds a
#: ``WAKE_STEP``: waking it for every batch (10,000 a second from 1,000 topics) cost more in
#: thread switches than the writing, and a busy machine starved the node of the CPU.
WRITE_PERIOD = 0.05
WAKE_STEP = 1024 * 1024
#: ``-p``: the name of each new file goes out latched on ``begin_write`` (rosbag record).
BEGIN_WRITE = "begin_write"


@dataclass
class RecordOptions(LiveOptions):
    """What to record and how to write it."""

    split: bool = False
    size: int | None = None  # bytes
    duration: float | None = None  # seconds
    max_splits: int | None = None
    repeat_latched: bool = False
    limit: int | None = None
    buffer_bytes: int = 256 * 1024 * 1024  # 0: unlimited
    publish: bool = False  # announce each file on begin_write
    #: The name for a file opened at a wall-clock time, when the name holds the date (``-o``,
    #: or no name): each split after the first is named by its own start, as rosbag names it.
    dated: Callable[[float], Path] | None = None
    #: ``--to ros2`` (format ``ros2``): the ROS 2 distro whose types the messages take, and
    #: the user's file of type renames and definitions (``--types``).
    distro: str | None = None
    types_file: str | None = None

    def check(self) -> None:
        """Raise ``UsageError`` for combinations rosbag record refuses."""
        if self.split and self.size is None and self.duration is None:
            raise UsageError("--split needs --size or --duration")
        if self.format == "ros2" and (self.split or self.repeat_latched):
            flag = "--split" if self.split else "--repeat-latched"
            raise UsageError(f"--to ros2 writes one rosbag2 file: {flag} is for .bag and MCAP")
        if self.limit is not None and (self.all or self.regex or not self.topics):
            raise UsageError("a count (-l) needs explicit topics, not -a or -e")


class _Writer(threading.Thread):
    """Takes queued messages and writes them; opens, splits and closes the files."""

    def __init__(self, rec: Recorder) -> None:
        super().__init__(name="rostools-bag-writer", daemon=True)
        self.rec = rec
        self.error: BaseException | None = None
        self.file: BagFile | None = None
        self.index = 0
        self.file_start = 0
        self.written = 0
        self.files: list[Path] = []

    def run(self) -> None:
        try:
            self._loop()
        except BaseException as err:  # noqa: BLE001 - reported by the recorder
            self.error = err
        try:
            self._close_file()
        except BaseException as err:  # noqa: BLE001 - reported by the recorder, not the thread
            # A failed write fails the close too: the file stays .active for bag recover.
            self.file = None
            if self.error is None:
                self.error = err

    def _open_file(self, t_ns: int) -> BagFile:
        opts = self.rec.opts
        base = opts.base if opts.dated is None or not self.index else opts.dated(time.time())
        path = file_name(base, opts.split, self.index)
        if opts.format == "ros2":
            from rostools.bag.live.ros2file import Ros2File

            assert self.rec.ros2 is not None
            ros2 = Ros2File(path, self.rec.ros2, opts.compression, opts.chunk_size)
            ros2.unconverted = self.rec.unconverted
            self.file = ros2
        else:
            self.file = BagFile(path, opts.format, opts.compression, opts.chunk_size)
        self.file_start = t_ns
        self.rec.current_file = self.file.active
        self.rec.file_opened(path)
        if opts.repeat_latched:
            for (header, topic), (t, data) in list(self.rec.latched.items()):
                self.file.write(header, topic, dict(header), max(t, t_ns), data)
        return self.file

    def _close_file(self) -> None:
        if self.file is None:
            return
        self.file.close()
        self.files.append(self.file.path)
        self.rec.closed_files.append(self.file.path)
        self.file = None

    def _drop_old_splits(self) -> None:
        """At a split, keep ``--max-splits`` closed files beside the new one, as rosbag.

        The last file is kept when the recording stops: rosbag leaves N + 1 files.
        """
        max_splits = self.rec.opts.max_splits
        if max_splits is not None:
            while len(self.files) > max_splits:
                self.files.pop(0).unlink(missing_ok=True)

    def _split_due(self, t_ns: int) -> bool:
        opts = self.rec.opts
        if opts.size is not None and self.written >= opts.size:
            return True
        return opts.duration is not None and t_ns - self.file_start >= opts.duration * 1e9

    def _loop(self) -> None:
        rec = self.rec
        self._open_file(rec.clock.now())  # the file exists from the start, as rosbag's does
        last_disk_check = time.monotonic()
        while True:
            if time.monotonic() - last_disk_check > DISK_PERIOD:
                rec.check_disk()  # raises, and so closes the file, when the disk is nearly full
                last_disk_check = time.monotonic()
            with rec.cond:
                if rec.queued_bytes < rec.wake_at and not rec.closing:
                    rec.cond.wait(WRITE_PERIOD)
                batch = rec.queue
                rec.queue = collections.deque()
                rec.writing_bytes, rec.queued_bytes = rec.queued_bytes, 0
                closing = rec.closing
            self._write(batch)
            with rec.cond:
                rec.writing_bytes = 0
            if self.file is not None:
                self.file.flush_if_due()
            if closing and not rec.queue:
                return

    def _write(self, batch: collections.deque[tuple[Any, ...]]) -> None:
        """Write a batch, freeing each entry as it goes and giving back its budget."""
        rec = self.rec
        written = 0
        while batch:
            key, header, topic, t_ns, data = batch.popleft()
            written += len(data) + ENTRY_OVERHEAD
            if written >= RELEASE_STEP:
                with rec.cond:
                    rec.writing_bytes -= written
                written = 0
            if rec.limit_reached.is_set():
                batch.clear()  # a size or duration limit without --split: the rest is not kept
                return
            if self._split_due(t_ns):
                if not rec.opts.split:
                    rec.limit_reached.set()
                    continue
                self._close_file()
                self._drop_old_splits()
                self.index += 1
                self.written = 0
                self._open_file(t_ns)
            assert self.file is not None
            self.file.write(key, topic, header, t_ns, data)
            self.written += len(data)
            rec.written_bytes += len(data)
            rec.stats[topic].written += 1


class Recorder(Follower):
    """Records topics of a live graph into ``.bag`` or MCAP files."""

    def __init__(self, node: LiveNode, opts: RecordOptions) -> None:
        opts.check()
        super().__init__(node, opts)
        self.opts = opts
        self.queue: collections.deque[tuple[Any, ...]] = collections.deque()
        #: What the queue holds, and what the writer's batch still holds (``-b`` bounds both).
        self.queued_bytes = 0
        self.writing_bytes = 0
        self.written_bytes = 0
        self.cond = threading.Condition()
        self.closing = False
        self.limit_reached = threading.Event()
        self.latched: dict[tuple[tuple[tuple[str, str], ...], str], tuple[int, Frame]] = {}
        self.current_file: Path | None = None
        self.closed_files: list[Path] = []
        self.done_topics: set[str] = set()
        self._writer = _Writer(self)
        #: Queued bytes that wake the writer before its period (a quarter of ``-b`` at most).
        self.wake_at = min(WAKE_STEP, opts.buffer_bytes // 4) if opts.buffer_bytes else WAKE_STEP
        self._begin_write: TopicPublisher | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        #: ``--to ros2``: why each connection's type cannot be converted ("" when it can),
        #: decided when it first sends; ``left_out``: each topic refused, and why.
        self._verdicts: dict[tuple[int, str], str] = {}
        self.left_out: dict[str, str] = {}
        #: ``--to ros2``: per topic, messages whose bytes did not fit their type (the writer's).
        self.unconverted: dict[str, int] = {}
        self.ros2: Ros2Types | None = None
        if opts.format == "ros2":
            from rostools.bag.live.ros2file import Ros2Types

            self.ros2 = Ros2Types(opts.distro, opts.types_file)

    def file_opened(self, path: Path) -> None:
        """A new file is being written (writer thread): announce it on ``begin_write``."""
        if self._begin_write is not None and self._loop is not None:
            name = str(path).encode()
            data = struct.pack("<I", len(name)) + name
            self._loop.call_soon_threadsafe(self._announce, self._begin_write, data)

    @staticmethod
    def _announce(pub: TopicPublisher, data: bytes) -> None:
        pub.publish_raw(data)
        pub.flush()

    @property
    def drops(self) -> int:
        """Messages dropped because the buffer was full."""
        return sum(s.drops for s in self.stats.values())

    def _on_frames(self, topic: str) -> FramesCallback:
        stats = self.stats.setdefault(topic, TopicStats())

        def on_frames(frames: list[Frame], conn: InboundConnection, now: float) -> None:
            t_ns = self.clock.now()
            header = conn.header or {}
            key = (conn.id, topic)
            if not stats.messages:  # what is recorded, over the master's word (it may be stale)
                stats.type = header.get("type") or stats.type
            if self.closing or (self.ros2 is not None and self._refused(topic, conn)):
                return
            limit = self.opts.limit
            if limit is not None:
                frames = frames[: max(limit - stats.messages, 0)]
                if stats.messages + len(frames) >= limit:
                    self.done_topics.add(topic)
            size = sum(len(f) for f in frames)
            stats.messages += len(frames)
            stats.bytes += size
            if self.opts.repeat_latched and header.get("latching") == "1" and frames:
                self.latched[(tuple(sorted(header.items())), topic)] = (t_ns, frames[-1])
            buffer = self.opts.buffer_bytes
            with self.cond:
                for data in frames:
                    self.queue.append((key, header, topic, t_ns, data))
                self.queued_bytes += size + len(frames) * ENTRY_OVERHEAD
                while (
                    buffer
                    and self.queued_bytes + self.writing_bytes > buffer
                    and len(self.queue) > 1
                ):
                    _, _, old_topic, _, old = self.queue.popleft()
                    self.queued_bytes -= len(old) + ENTRY_OVERHEAD
                    self.stats[old_topic].drops += 1
                if self.queued_bytes >= self.wake_at:
                    self.cond.notify()

        return on_frames

    def _refused(self, topic: str, conn: InboundConnection) -> bool:
        """Whether ``--to ros2`` leaves this connection out: its type does not convert.

        Decided once per connection, when it first sends; the first refusal of a topic is
        said in one line, and ``bag record`` exits 6 at the end.
        """
        why = self._verdicts.get((conn.id, topic))
        if why is None:
            assert self.ros2 is not None
            why = self.ros2.why_not(topic, conn.header or {})
            self._verdicts[conn.id, topic] = why
            if why and topic not in self.left_out:
                self.left_out[topic] = why
                self.done_topics.add(topic)  # a count (-l) does not wait for it
                kind = (conn.header or {}).get("type", "?")
                self.node.notify(
                    Notice(
                        "topic_left_out",
                        f"{why}: {topic} is left out of the recording",
                        {"topic": topic, "type": kind, "reason": why},
                    )
                )
        return bool(why)

    def _finished(self) -> bool:
        """A count, a size or a duration without --split, or the writer failed."""
        opts = self.opts
        if opts.limit is not None and self.done_topics >= self.selection.names:
            return True
        if not opts.split and opts.duration is not None and self._elapsed() >= opts.duration:
            return True
        return self.limit_reached.is_set() or self._writer.error is not None

    async def _begin(self) -> None:
        if self.opts.publish:
            self._loop = asyncio.get_running_loop()
            self._begin_write = await self.node.advertise(BEGIN_WRITE, STRING, latch=True)
        self._writer.start()

    async def run(self, stop: asyncio.Event, tick: Callable[[Any], None] | None = None) -> None:
        """Record until ``stop`` or a limit; ``tick`` is called four times a second."""
        await super().run(stop, tick)
        if self._writer.error is not None:
            raise write_failure(self._writer.error)

    async def _end(self) -> None:
        with self.cond:
            self.closing = True
            self.cond.notify()
        if self._writer.is_alive():
            await asyncio.get_running_loop().run_in_executor(None, self._writer.join)
