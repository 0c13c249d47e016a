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
import fnmatch
import logging
import re
import shutil
import struct
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rostools.bag.access import file_name, open_writer
from rostools.bag.base import BagWriter
from rostools.bag.model import Connection
from rostools.bag.sink import WriteError
from rostools.errors import DataLossError, RostoolsError, UsageError
from rostools.msgs.topictype import TopicType
from rostools.node.clock import RosClock
from rostools.node.connection import Frame, InboundConnection
from rostools.node.node import Node
from rostools.node.publisher import Publisher

log = logging.getLogger(__name__)

#: How often the master is asked for new topics (rosbag record: 1 s).
POLL_PERIOD = 1.0
#: How often the writer hands its buffers to the OS, bounding what a crash can lose.
FLUSH_PERIOD = 1.0
#: How often ``run`` checks its limits and calls its ``tick`` (the live table).
TICK_PERIOD = 0.25
#: How often the free disk space is checked against ``min_space`` (rosbag: 20 s).
DISK_PERIOD = 1.0
#: What one queued message costs beyond its bytes: the queue entry, its time stamp and the
#: bytes object (measured: 137 B with CPython 3.11; rounded up for the allocator). ``-b``
#: counts it, so the limit bounds the memory held, not only the payload: 100 topics of
#: 16-byte messages hold ten times their payload.
ENTRY_OVERHEAD = 160
#: The writer gives back the budget of what it has written in steps of this many bytes.
RELEASE_STEP = 1024 * 1024
#: ``-p``: the name of each new file goes out latched on ``begin_write`` (rosbag record).
BEGIN_WRITE = "begin_write"
_STRING = TopicType("std_msgs/String", "992ce8a1687cec8c8bd883ec73ca41d1", "string data\n")


@dataclass
class RecordOptions:
    """What to record and how to write it."""

    topics: list[str] = field(default_factory=list)
    all: bool = False
    regex: bool = False
    exclude: list[str] = field(default_factory=list)  # regexes; a topic matching any is left out
    types: list[str] = field(default_factory=list)  # globs: topics of these types too
    exclude_types: list[str] = field(default_factory=list)  # globs: never these types
    node: str | None = None
    base: Path = Path("recording.bag")  # the file name before .active and split numbers
    format: str = "bag"
    compression: str | None = None
    chunk_size: int | None = None
    split: bool = False
    size: int | None = None  # bytes
    duration: float | None = None  # seconds
    max_splits: int | None = None
    repeat_latched: bool = False
    limit: int | None = None
    tcp_nodelay: bool = False
    buffer_bytes: int = 256 * 1024 * 1024  # 0: unlimited
    min_space: int = 100 * 1024**2  # stop when the disk has less free (bytes; 0: never)
    publish: bool = False  # announce each file on begin_write

    def check(self) -> None:
        """Raise ``UsageError`` for combinations rosbag record refuses."""
        if self.split and self.size is None and self.duration is None:
            raise UsageError("--split needs --size or --duration")
        if self.limit is not None and (self.all or self.regex or not self.topics):
            raise UsageError("a count (-l) needs explicit topics, not -a or -e")


@dataclass
class TopicStats:
    """What was received on one topic."""

    type: str = ""
    messages: int = 0  # received
    bytes: int = 0
    drops: int = 0
    written: int = 0  # less than received by the drops and what came after a size/time limit


def free_bytes(folder: Path) -> int:
    """Free space on the disk that holds ``folder``."""
    return shutil.disk_usage(folder).free


def active_name(path: Path) -> Path:
    """Where ``path`` is written until it is closed (rosbag's ``.active``)."""
    return path.with_name(path.name + ".active")


class Selection:
    """Which topics to record: names, regexes (full match, as rosbag), types, all, minus excludes.

    Types are globs (``sensor_msgs/*``), as rosbag2's ``--topic-types``; a topic whose type is
    not known yet waits for the next poll when types decide.
    """

    def __init__(self, opts: RecordOptions) -> None:
        self.types = opts.types
        self.exclude_types = opts.exclude_types
        self.names = set(opts.topics) if not opts.regex else set()
        try:
            self.patterns = [re.compile(p) for p in opts.topics] if opts.regex else []
            self.exclude = [re.compile(x) for x in opts.exclude]
        except re.error as err:
            raise UsageError(f"bad regular expression: {err}") from err
        # --node records what the node subscribes to; -x alone means everything but that
        self.everything = (
            opts.all or opts.node is not None or (bool(opts.exclude) and not opts.topics)
        )

    @property
    def by_type(self) -> bool:
        """Whether topic types take part in the choice."""
        return bool(self.types or self.exclude_types)

    def wants(self, topic: str, topic_type: str | None = None) -> bool:
        """Whether to record ``topic`` (of ``topic_type``, if known)."""
        if any(x.fullmatch(topic) for x in self.exclude):
            return False
        if self.exclude_types and (topic_type is None or _matches(topic_type, self.exclude_types)):
            return False
        if self.everything or topic in self.names or any(p.fullmatch(topic) for p in self.patterns):
            return True
        return topic_type is not None and _matches(topic_type, self.types)


def _matches(topic_type: str, globs: list[str]) -> bool:
    return any(fnmatch.fnmatchcase(topic_type, g) for g in globs)


class _Writer(threading.Thread):
    """Takes queued messages and writes them; opens, splits and closes the files."""

    def __init__(self, rec: Recorder) -> None:
        super().__init__(name="rostools-bag-writer", daemon=True)
        self.rec = rec
        self.error: BaseException | None = None
        self.writer: BagWriter | None = None
        self.path: Path | None = None
        self.index = 0
        self.file_start = 0
        self.written = 0
        self.connections: dict[tuple[int, str], Connection] = {}
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
            self.writer = None
            if self.error is None:
                self.error = err

    def _open_file(self, t_ns: int) -> BagWriter:
        opts = self.rec.opts
        self.path = file_name(opts.base, opts.split, self.index)
        active = active_name(self.path)
        self.writer = open_writer(active, opts.format, opts.compression, opts.chunk_size)
        self.file_start = t_ns
        self.connections.clear()
        self.rec.current_file = active
        self.rec.file_opened(self.path)
        if opts.repeat_latched:
            for (header, topic), (t, data) in list(self.rec.latched.items()):
                conn = self.writer.connection_for(topic, dict(header))
                self.writer.write(conn, max(t, t_ns), data)
        return self.writer

    def _close_file(self) -> None:
        if self.writer is None or self.path is None:
            return
        self.writer.close()
        active_name(self.path).replace(self.path)
        self.files.append(self.path)
        self.rec.closed_files.append(self.path)
        self.writer = None

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
        last_flush = last_disk_check = time.monotonic()
        while True:
            if time.monotonic() - last_disk_check > DISK_PERIOD:
                rec.check_disk()  # raises, and so closes the file, when the disk is nearly full
                last_disk_check = time.monotonic()
            with rec.cond:
                while not rec.queue and not rec.closing:
                    rec.cond.wait(0.5)
                    if time.monotonic() - last_flush > FLUSH_PERIOD and self.writer is not None:
                        break
                batch = rec.queue
                rec.queue = collections.deque()
                rec.writing_bytes, rec.queued_bytes = rec.queued_bytes, 0
                closing = rec.closing
            self._write(batch)
            with rec.cond:
                rec.writing_bytes = 0
            if self.writer is not None and time.monotonic() - last_flush > FLUSH_PERIOD:
                self.writer.flush()
                last_flush = time.monotonic()
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
            writer = self.writer
            assert writer is not None
            conn = self.connections.get(key)
            if conn is None:
                conn = self.connections[key] = writer.connection_for(topic, header)
            writer.write(conn, t_ns, data)
            self.written += len(data)
            rec.written_bytes += len(data)
            rec.stats[topic].written += 1


class Recorder:
    """Records topics of a live graph into ``.bag`` or MCAP files."""

    def __init__(self, node: Node, opts: RecordOptions) -> None:
        opts.check()
        if not opts.regex:
            opts.topics = [node.resolve(t) for t in opts.topics]
        self.node = node
        self.opts = opts
        self.selection = Selection(opts)
        self.stats: dict[str, TopicStats] = {}
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
        self.started = time.monotonic()
        #: Message times: ROS time, so /clock under /use_sim_time (as rosbag record).
        self.clock = RosClock()
        self.start_ns = 0
        #: Called with each topic as it is subscribed to (rosbag's "Subscribing to" lines).
        self.on_subscribe: Callable[[str], None] | None = None
        self._writer = _Writer(self)
        self._begin_write: Publisher | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._space_warned = False

    def check_disk(self, started: bool = True) -> None:
        """Raise ``RostoolsError`` when the output disk has less than ``min_space`` free."""
        need = self.opts.min_space
        if not need:
            return
        folder = self.opts.base.parent.resolve()
        free = free_bytes(folder)
        if free < need:
            outcome = "recording stopped; what was written is kept" if started else "not recording"
            raise RostoolsError(
                f"less than {_gib(need)} free on the disk of {folder} ({_gib(free)}): {outcome}",
                hint="free some space, or lower the limit with -L/--min-space",
            )
        if free < 5 * need and not self._space_warned:
            self._space_warned = True
            log.warning("less than 5 x %s free on the disk of %s", _gib(need), folder)

    def file_opened(self, path: Path) -> None:
        """A new file is being written (writer thread): announce it on ``begin_write``."""
        if self._begin_write is not None and self._loop is not None:
            name = str(path).encode()
            data = struct.pack("<I", len(name)) + name
            self._loop.call_soon_threadsafe(self._announce, self._begin_write, data)

    @staticmethod
    def _announce(pub: Publisher, data: bytes) -> None:
        pub.publish_raw(data)
        pub.flush()

    @property
    def drops(self) -> int:
        """Messages dropped because the buffer was full."""
        return sum(s.drops for s in self.stats.values())

    def _on_frames(self, topic: str) -> Callable[[list[Frame], InboundConnection, float], None]:
        stats = self.stats.setdefault(topic, TopicStats())

        def on_frames(frames: list[Frame], conn: InboundConnection, now: float) -> None:
            t_ns = self.clock.now()
            header = conn.header or {}
            key = (conn.id, topic)
            if not stats.type:
                stats.type = header.get("type", "")
            if self.closing:
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
                self.cond.notify()

        return on_frames

    async def _poll(self) -> None:
        """Subscribe to every wanted topic the master knows of (new ones as they appear)."""
        if self.opts.node is not None:
            candidates = await self._node_topics(self.opts.node)
        elif self.selection.everything or self.selection.patterns or self.selection.types:
            pubs, _, _ = await self.node.master.system_state()
            candidates = [topic for topic, _ in pubs]
        else:
            candidates = sorted(self.selection.names)  # subscribed before anyone publishes
        types: dict[str, str] = {}
        if self.selection.by_type:
            types = await self.node.master.topic_types()
        for topic in candidates:
            if not self.selection.wants(topic, types.get(topic)):
                continue
            if topic == "/clock" and self.clock.sim:  # already subscribed, for the time
                if self.clock.forward is None:
                    self._say_subscribing(topic)
                    self.clock.forward = self._on_frames(topic)
            elif topic not in self.node.subscribers:
                self._say_subscribing(topic)
                await self.node.subscribe(
                    topic, self._on_frames(topic), tcp_nodelay=self.opts.tcp_nodelay
                )
        if any(not s.type for s in self.stats.values()):
            # a topic with no message yet shows the type the master knows (it showed "?")
            known = types or await self.node.master.topic_types()
            for topic, stats in self.stats.items():
                if not stats.type and known.get(topic, "*") != "*":
                    stats.type = known[topic]

    def _say_subscribing(self, topic: str) -> None:
        if self.on_subscribe is not None:
            self.on_subscribe(topic)

    def publishers(self, topic: str) -> int:
        """How many publishers ``topic`` is connected to now."""
        sub = self.node.subscribers.get(topic)
        return len(sub.connections) if sub is not None else 0

    async def _node_topics(self, name: str) -> list[str]:
        """The topics node ``name`` subscribes to (rosbag record --node)."""
        from rostools.node.mastercalls import peer_value

        try:
            uri = await self.node.master.lookup_node(self.node.resolve(name))
            subs = await peer_value(uri, self.node.name, "getSubscriptions")
        except (RostoolsError, OSError) as err:
            log.debug("node %s: %s", name, err)
            return []
        return [topic for topic, _ in subs]

    def _finished(self) -> bool:
        """A count, a size or a duration without --split, or the writer failed."""
        opts = self.opts
        if opts.limit is not None and self.done_topics >= self.selection.names:
            return True
        if not opts.split and opts.duration is not None and self._elapsed() >= opts.duration:
            return True
        return self.limit_reached.is_set() or self._writer.error is not None

    def _elapsed(self) -> float:
        return (self.clock.now() - self.start_ns) / 1e9

    async def run(
        self, stop: asyncio.Event, tick: Callable[[Recorder], None] | None = None
    ) -> None:
        """Record until ``stop`` or ``_finished``; ``tick`` is called four times a second."""
        from rostools.node.session import first

        self.check_disk(started=False)
        await self.clock.start(self.node)  # no master: say so (no file) rather than wait forever
        if not await self._clock_valid(stop):
            return
        self.start_ns = self.clock.now()
        await self._poll()
        if self.opts.publish:
            self._loop = asyncio.get_running_loop()
            self._begin_write = await self.node.advertise(BEGIN_WRITE, _STRING, latch=True)
        self._writer.start()
        next_poll = time.monotonic() + POLL_PERIOD
        try:
            while not stop.is_set() and not self._finished():
                if time.monotonic() >= next_poll:
                    try:
                        await self._poll()
                    except RostoolsError as err:  # the node says once that the master is gone
                        log.debug("recording goes on; the master did not answer: %s", err)
                    next_poll = time.monotonic() + POLL_PERIOD
                if tick is not None:
                    tick(self)
                await first(stop.wait(), timeout=TICK_PERIOD)
        finally:
            await self._finish()
        if self._writer.error is not None:
            raise self._failure(self._writer.error)

    def _failure(self, err: BaseException) -> BaseException:
        """What to raise for the writer's error: a failed write says what is kept, and where."""
        if not isinstance(err, WriteError):
            return err
        active = Path(err.path)
        space = "free some space" if err.disk_full else None
        if active.exists():
            failure = DataLossError(
                f"{err}: the recording stopped; what was written stays in {active}",
                hint=f"{space}, then run 'rostools bag recover {active}'"
                if space
                else f"run 'rostools bag recover {active}'",
            )
        else:  # a new file (the first, or a split) that could not even be started
            failure = DataLossError(f"{err}: the recording stopped", hint=space)
        failure.__cause__ = err
        return failure

    async def _clock_valid(self, stop: asyncio.Event) -> bool:
        """Under sim time, wait for the first /clock (False if stopped first), as rosbag."""
        from rostools.node.session import first

        warn_at = time.monotonic() + 2.0
        while not self.clock.valid:
            if await first(stop.wait(), timeout=0.05) is not None:
                return False
            if time.monotonic() >= warn_at and not self.clock.valid:
                warn_at += 2.0
                log.warning("/use_sim_time is set and no clock is published; still waiting")
        return True

    async def _finish(self) -> None:
        for sub in list(self.node.subscribers.values()):
            await sub.close()
        with self.cond:
            self.closing = True
            self.cond.notify()
        await asyncio.get_running_loop().run_in_executor(None, self._writer.join)


def _gib(size: int) -> str:
    """A byte count as rosbag writes -L limits: ``1G``, ``500M``, ``64K``."""
    for unit, scale in (("G", 1024**3), ("M", 1024**2), ("K", 1024)):
        if size >= scale:
            return f"{size / scale:.1f}".removesuffix(".0") + unit
    return f"{size}B"
