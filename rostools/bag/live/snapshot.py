"""Snapshot recording: the last minutes of the graph in memory, written when something happens.

A ``Snapshotter`` follows topics as ``bag record`` does (``follow.Follower``) but keeps their
raw frames in a ``RingBuffer`` bounded by a duration and a size, oldest out first. A trigger
(a service, a signal, a key: ``trigger``) takes references to the window's part of the
buffer and hands them to a ``SnapshotJob``, a thread that writes them as ``NAME.active``;
with a stop time ahead it goes on with the live messages, in the same file, read from the
queue every file shares (``snapshot_live.LiveQueue``, bounded by ``size``). The buffer is
not cleared by a write (unless ``clear_on_write``), so triggers close together each get
their whole window, and at most ``max_writes`` files are written at once. Memory is bounded
by ``size`` twice (the buffer, the live queue), the part of the buffer each file has yet to
write, and what each file's thread has in hand (``snapshot_live.BATCH_BYTES``).
"""

from __future__ import annotations

import asyncio
import collections
import contextlib
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from rostools.bag.formats.access import WRITE_COMPRESSIONS, format_for_name
from rostools.bag.live.bagfile import active_name
from rostools.bag.live.follow import Follower, FramesCallback, LiveOptions, TopicStats
from rostools.bag.live.ringbuffer import ConnInfo, Held, Lost, RingBuffer
from rostools.bag.live.snapshot_job import FileSpec, SnapshotJob, wait_joined
from rostools.bag.live.snapshot_live import LiveQueue
from rostools.bag.live.snapshot_services import serve
from rostools.bag.live.snapshot_srv import NO_DATA_MESSAGE, SnapshotRequest, TriggerError, window
from rostools.errors import RostoolsError, UsageError
from rostools.node.connection import Frame, InboundConnection
from rostools.node.node import LiveNode

#: Files written at once unless ``--max-writes`` says otherwise; more triggers are refused.
MAX_WRITES = 4
#: Files written that the recorder remembers (for its summary at the end).
FINISHED_KEPT = 1000
#: How long the end of a snapshot waits for its files to be complete (s).
CLOSE_TIMEOUT = 600.0


@dataclass
class SnapshotOptions(LiveOptions):
    """What to buffer, its limits, and the files triggers write.

    Every file goes into ``base``'s folder, remote triggers' included. ``name`` is the
    exact name of the first file (the next get ``_1``, ``_2``, ...); without it, files get
    rosbag's dated names, ``PREFIX_YYYY-MM-DD-HH-MM-SS.bag`` (the date alone without a
    ``prefix``).
    """

    name: str | None = None
    prefix: str = ""
    duration: float = 30.0  # seconds the buffer spans
    size: int = 256 * 1024**2  # bytes the buffer holds, all topics together
    topic_size: int = 0  # bytes each topic may hold (0: no limit of its own)
    clear_on_write: bool = False
    max_writes: int = MAX_WRITES
    before: float | None = None  # the window of a local trigger (None: the whole buffer)
    after: float = 0.0

    def check(self) -> None:
        """Raise ``UsageError`` for limits that cannot be met."""
        if self.duration <= 0 or self.size <= 0 or self.topic_size < 0 or self.max_writes < 1:
            raise UsageError("the snapshot's duration, size and --max-writes must be positive")
        if (self.before is not None and self.before <= 0) or self.after < 0:
            raise UsageError("--before must be positive and --after not negative")


def check_remote_name(name: str) -> None:
    """Refuse a file name from a remote trigger that could leave the output folder."""
    if "/" in name or "\\" in name or ".." in name or "\0" in name:
        raise TriggerError(
            f"refused the file name {name!r}: a trigger names a file in the output folder, "
            "without '/' or '..'"
        )


class Snapshotter(Follower):
    """Buffers topics of a live graph and writes snapshots of them on request."""

    def __init__(self, node: LiveNode, opts: SnapshotOptions) -> None:
        opts.check()
        super().__init__(node, opts)
        self.opts = opts
        self.ring = RingBuffer(round(opts.duration * 1e9), opts.size, opts.topic_size)
        self.live = LiveQueue(opts.size)
        self.paused = False
        self.closing = False
        self.jobs: list[SnapshotJob] = []
        #: The last files written (or failed), how many failed, and how many lost messages.
        self.finished: collections.deque[SnapshotJob] = collections.deque(maxlen=FINISHED_KEPT)
        self.failed = 0
        self.lossy = 0
        #: Called on the event loop as each file is started and once it is complete.
        self.on_started: Callable[[SnapshotJob], None] | None = None
        self.on_written: Callable[[SnapshotJob], None] | None = None
        #: Publishes each complete file on ``~written`` (set by the services).
        self.announce: Callable[[SnapshotJob], None] | None = None
        self._loop: asyncio.AbstractEventLoop | None = None

    # receiving ---------------------------------------------------------------------------

    def _on_frames(self, topic: str) -> FramesCallback:
        stats = self.stats.setdefault(topic, TopicStats())
        tb = self.ring.topic(topic)
        conns: dict[int, ConnInfo] = {}

        def on_frames(frames: list[Frame], conn: InboundConnection, now: float) -> None:
            t_ns = self.clock.now()
            info = conns.get(conn.id)
            if info is None:
                self._forget_closed(topic, conns)
                info = conns[conn.id] = ConnInfo(topic, conn.header or {})
                # what is buffered, over the master's word (it may be stale), as bag record
                stats.type = info.header.get("type") or stats.type
            stats.messages += len(frames)
            stats.bytes += sum(map(len, frames))
            if self.live.readers and self.live.wanted(topic):
                self.live.push(info, t_ns, frames)
            if not self.paused and not self.closing:
                self.ring.add(tb, info, t_ns, frames)

        return on_frames

    def _forget_closed(self, topic: str, conns: dict[int, ConnInfo]) -> None:
        """Let go of the connections of ``topic`` that have closed (publishers come and go)."""
        sub = self.node.subscribers.get(topic)
        live = {c.id for c in sub.connections.values()} if sub is not None else set()
        for gone in set(conns) - live:
            del conns[gone]  # what the buffer holds of it keeps its header

    # triggers ----------------------------------------------------------------------------

    def trigger(self, request: SnapshotRequest, remote: bool = True) -> SnapshotJob:
        """Start writing a snapshot (event loop); ``TriggerError`` says why not."""
        if remote and request.filename:
            check_remote_name(request.filename)
        if len(self.jobs) >= self.opts.max_writes:
            raise TriggerError(
                f"{len(self.jobs)} snapshots are being written, the most at once "
                f"(--max-writes {self.opts.max_writes}); try again when one is complete"
            )
        try:
            self.check_disk(started=False)
        except RostoolsError as err:
            raise TriggerError(str(err)) from None
        topics = self._topics(request.topics)
        now = self.clock.now()
        held = self.ring.copy(topics)
        stop: int | None = None if request.forever else (request.stop_ns or now)
        start = request.start_ns or held.oldest() or now
        live = stop is None or stop > now
        if not live and not held.any_between(start, stop or now):
            raise TriggerError(NO_DATA_MESSAGE)
        spec = self._file_spec(request.filename)
        until = now if stop is None else min(stop, now)
        lost = _evicted(self.ring, held, request.start_ns, topics)
        job = SnapshotJob(
            spec, held, start, until, stop, topics, self.live, self._done_threadsafe, lost
        )
        self.jobs.append(job)
        job.start()
        if self.opts.clear_on_write:
            self.ring.clear(topics)
        if self.on_started is not None:
            self.on_started(job)
        return job

    def local_request(self) -> SnapshotRequest:
        """The window of a local trigger (a signal, a key, ``~trigger``): ``--before/--after``."""
        start, stop = window(self.clock.now(), self.opts.before, self.opts.after)
        return SnapshotRequest(start_ns=start, stop_ns=stop)

    def _topics(self, requested: list[str]) -> set[str] | None:
        """The buffered topics a request names (None: all), as rosbag_snapshot resolves them."""
        names = [t for t in requested if t]
        if not names:
            return None
        chosen = {self.node.resolve(t) for t in names} & set(self.ring.topics)
        if not chosen:
            raise TriggerError(NO_DATA_MESSAGE)
        return chosen

    def _file_spec(self, requested: str) -> FileSpec:
        """A free name in the output folder for a snapshot (``requested``: a remote's)."""
        opts = self.opts
        folder = opts.base.parent
        ext = "." + opts.format
        stamp = time.strftime("%Y-%m-%d-%H-%M-%S")
        if requested.endswith((".bag", ".mcap")):
            name = requested
        elif requested:
            name = requested + stamp + ext  # rosbag_snapshot: "test" -> test2018-05-23-....bag
        elif opts.name is not None:
            name = opts.name
        else:
            name = (f"{opts.prefix}_{stamp}" if opts.prefix else stamp) + ext
        path = folder / name
        taken = {job.path for job in self.jobs}
        number = 0
        while path in taken or path.exists() or active_name(path).exists():
            number += 1
            path = folder / f"{Path(name).stem}_{number}{Path(name).suffix}"
        kind = format_for_name(path)
        compression = opts.compression if opts.compression in WRITE_COMPRESSIONS[kind] else None
        return FileSpec(path, kind, compression, opts.chunk_size)

    def stop_open_ended(self) -> int:
        """End every file written until stopped (``--continue``); how many there were."""
        open_ended = [job for job in self.jobs if job.live and job.stop_ns is None]
        for job in open_ended:
            job.end()
        return len(open_ended)

    def set_paused(self, paused: bool) -> bool:
        """Stop or go on buffering new messages; whether that changed anything."""
        changed = paused != self.paused
        self.paused = paused
        return changed

    # the run ------------------------------------------------------------------------------

    async def _begin(self) -> None:
        self._loop = asyncio.get_running_loop()
        await serve(self)

    def tick_limits(self) -> None:
        """Evict what the duration no longer allows; end files whose stop time has passed."""
        now = self.clock.now()
        if not self.paused:  # a paused buffer holds what it has until resumed
            self.ring.evict_old(now)
        for job in self.jobs:
            if job.live and job.stop_ns is not None and now > job.stop_ns:
                job.end()

    async def run(
        self, stop: asyncio.Event, tick: Callable[[Snapshotter], None] | None = None
    ) -> None:
        """Buffer and serve triggers until ``stop``; ``tick`` is called four times a second."""

        def on_tick(_: object) -> None:
            self.tick_limits()
            if tick is not None:
                tick(self)

        await super().run(stop, on_tick)

    async def _end(self) -> None:
        self.closing = True
        for job in self.jobs:
            job.end()
        jobs = list(self.jobs)
        if jobs:
            await asyncio.get_running_loop().run_in_executor(None, wait_joined, jobs, CLOSE_TIMEOUT)
        await asyncio.sleep(0)  # the last on_done calls run
        for job in jobs:
            if job in self.jobs:
                self._done(job)

    def _done_threadsafe(self, job: SnapshotJob) -> None:
        loop = self._loop
        if loop is not None and not loop.is_closed():
            with contextlib.suppress(RuntimeError):  # the loop closed: _end reports it
                loop.call_soon_threadsafe(self._done, job)

    def _done(self, job: SnapshotJob) -> None:
        if job not in self.jobs:
            return
        self.jobs.remove(job)
        self.finished.append(job)
        self.failed += job.error is not None
        self.lossy += job.error is None and job.lost > 0
        if self.announce is not None:
            self.announce(job)
        if self.on_written is not None:
            self.on_written(job)


def _evicted(ring: RingBuffer, held: Held, start_ns: int, topics: set[str] | None) -> Lost:
    """What the window starting at ``start_ns`` (0: the oldest held) lost to the limits.

    A latched message let go is no loss: the file starts with its copy.
    """
    if not start_ns:
        return Lost()
    resent = collections.Counter(held.resent_since(start_ns))
    count, exact = 0, True
    for name, tb in ring.topics.items():
        if topics is None or name in topics:
            lost = tb.lost_since(start_ns)
            count += max(lost.count - resent[name], 0)
            exact = exact and lost.exact
    return Lost(count, exact)
