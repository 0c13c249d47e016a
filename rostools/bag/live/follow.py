"""What every live recorder does: choose topics, subscribe as they appear, keep time.

``bag record`` and ``bag snapshot`` differ only in what they do with the frames they receive
(queue them for a writer, or keep them in a rolling buffer). Both are a ``Follower``: it
subscribes to the topics the options select (names, regexes, types, what a node subscribes
to, everything), asks the master for new ones every ``poll_period``, stamps frames in ROS
time (``/clock`` under ``/use_sim_time``, as rosbag) and checks the free disk.
"""

from __future__ import annotations

import asyncio
import logging
import shutil
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rostools.errors import RostoolsError
from rostools.node.clock import RosClock
from rostools.node.connection import Frame, InboundConnection
from rostools.node.node import LiveNode
from rostools.node.notice import Notice
from rostools.rosgraph.masterapi import master_timeout
from rostools.selection import Selection, TopicChoice

log = logging.getLogger(__name__)

#: How often the master is asked for new topics (rosbag record: 1 s).
POLL_PERIOD = 1.0
#: Registrations of new topics in flight at once: one multicall (node/registration.py).
SUBSCRIBE_AT_ONCE = 64
#: How often ``run`` checks its limits and calls its ``tick`` (the live table).
TICK_PERIOD = 0.25

FramesCallback = Callable[[list[Frame], InboundConnection, float], None]


@dataclass
class TopicStats:
    """What was received on one topic."""

    type: str = ""
    messages: int = 0  # received
    bytes: int = 0
    drops: int = 0
    written: int = 0  # less than received by the drops and what came after a size/time limit


@dataclass
class LiveOptions(TopicChoice):
    """What every live recorder takes: the topics, the files' name and format, the disk."""

    base: Path = Path("recording.bag")  # the file name (before .active and split numbers)
    format: str = "bag"
    compression: str | None = None
    chunk_size: int | None = None
    tcp_nodelay: bool = False
    min_space: int = 100 * 1024**2  # stop when the disk has less free (bytes; 0: never)


def free_bytes(folder: Path) -> int:
    """Free space on the disk that holds ``folder``."""
    return shutil.disk_usage(folder).free


class Follower:
    """Subscribes to the chosen topics of a live graph; a subclass says what frames become."""

    def __init__(self, node: LiveNode, opts: LiveOptions) -> None:
        if not opts.regex:
            opts.topics = [node.resolve(t) for t in opts.topics]
        self.node = node
        self.live_opts = opts
        self.selection = Selection(opts)
        self.stats: dict[str, TopicStats] = {}
        self.started = time.monotonic()
        #: Message times: ROS time, so /clock under /use_sim_time (as rosbag record).
        self.clock = RosClock()
        self.start_ns = 0
        self.poll_period = POLL_PERIOD
        #: Called with each topic as it is subscribed to (rosbag's "Subscribing to" lines).
        self.on_subscribe: Callable[[str], None] | None = None
        self._space_warned = False
        #: How long the next poll may wait for the master, and whether the last was too slow.
        self._poll_limit = master_timeout()
        self._poll_slow = False

    # what a subclass provides -------------------------------------------------------------

    def _on_frames(self, topic: str) -> FramesCallback:
        """The callback that takes the frames of ``topic``."""
        raise NotImplementedError

    async def _begin(self) -> None:
        """Subscribed and on time: start whatever writes."""

    def _finished(self) -> bool:
        """Whether to stop before ``stop`` is set."""
        return False

    async def _end(self) -> None:
        """Unsubscribed: finish writing."""

    # the run --------------------------------------------------------------------------------

    async def run(self, stop: asyncio.Event, tick: Callable[[Any], None] | None = None) -> None:
        """Follow until ``stop`` or ``_finished``; ``tick`` is called four times a second."""
        from rostools.node.session import first

        self.check_disk(started=False)
        await self.clock.start(self.node)  # no master: say so (no file) rather than wait forever
        if not await self._clock_valid(stop):
            return
        self.start_ns = self.clock.now()
        await self._poll_until(stop)
        await self._begin()
        next_poll = time.monotonic() + self.poll_period
        try:
            while not stop.is_set() and not self._finished():
                if time.monotonic() >= next_poll:
                    await self._poll_until(stop)
                    next_poll = time.monotonic() + self.poll_period
                if tick is not None:
                    tick(self)
                await first(stop.wait(), timeout=TICK_PERIOD)
        finally:
            for sub in list(self.node.subscribers.values()):
                await sub.close()
            await self._end()

    def check_disk(self, started: bool = True) -> None:
        """Raise ``RostoolsError`` when the output disk has less than ``min_space`` free."""
        need = self.live_opts.min_space
        if not need:
            return
        folder = self.live_opts.base.parent.resolve()
        free = free_bytes(folder)
        if free < need:
            outcome = "recording stopped; what was written is kept" if started else "not recording"
            raise RostoolsError(
                f"less than {gib(need)} free on the disk of {folder} ({gib(free)}): {outcome}",
                hint="free some space, or lower the limit with -L/--min-space",
            )
        if free < 5 * need and not self._space_warned:
            self._space_warned = True
            log.warning("less than 5 x %s free on the disk of %s", gib(need), folder)

    def publishers(self, topic: str) -> int:
        """How many publishers ``topic`` is connected to now."""
        sub = self.node.subscribers.get(topic)
        return len(sub.connections) if sub is not None else 0

    async def _poll_until(self, stop: asyncio.Event) -> None:
        """Poll, unless ``stop`` comes first; a master too slow to answer is asked again later.

        The next poll gives the master twice as long (``registration.longer``), and the first
        slow one is said in one line (``poll_slow``), unless the node has said the master is
        gone. Recording goes on meanwhile.
        """
        from rostools.node.registration import NOT_YET, longer

        poll = asyncio.ensure_future(self._poll(self._poll_limit))
        waiting = asyncio.ensure_future(stop.wait())
        try:
            await asyncio.wait((poll, waiting), return_when=asyncio.FIRST_COMPLETED)
        finally:
            waiting.cancel()
            if not poll.done():
                poll.cancel()
                await asyncio.wait((poll,))
        err = None if poll.cancelled() else poll.exception()
        if err is None:
            self._poll_limit, self._poll_slow = master_timeout(), False
            return
        if not isinstance(err, RostoolsError):
            raise err
        log.debug("recording goes on; the master did not answer: %s", err)
        if isinstance(err, NOT_YET):
            self._poll_limit = longer(self._poll_limit)
            if not self._poll_slow and not self.node.master_lost:
                self.node.notify(
                    Notice(
                        "poll_slow",
                        f"{err}; recording goes on, and new topics wait until it answers",
                        {"uri": self.node.master_uri},
                    )
                )
            self._poll_slow = True

    async def _poll(self, limit: float) -> None:
        """Subscribe to every wanted topic the master knows of (new ones as they appear).

        Each question to the master may take ``limit`` seconds.
        """
        types: dict[str, str] = {}
        if self.live_opts.node is not None:
            candidates = await self._node_topics(self.live_opts.node, limit)
        elif self.selection.everything or self.selection.patterns or self.selection.types:
            # the published topics and their types: a poll of 1,000 topics parsed a
            # getSystemState of every publisher and subscriber, a second, for their names alone
            types = await self.node.master.published_topics(limit)
            candidates = list(types)
        else:
            candidates = sorted(self.selection.names)  # subscribed before anyone publishes
        if self.selection.by_type and not types:
            types = await self.node.master.topic_types(limit)
        new: list[str] = []
        for topic in candidates:
            if not self.selection.wants(topic, types.get(topic)):
                continue
            if topic == "/clock" and self.clock.sim:  # already subscribed, for the time
                if self.clock.forward is None:
                    self._say_subscribing(topic)
                    self.clock.forward = self._on_frames(topic)
            elif topic not in self.node.subscribers:
                self._say_subscribing(topic)
                new.append(topic)
        await self._subscribe(new)
        if any(not s.type for s in self.stats.values()):
            # a topic with no message yet shows the type the master knows (it showed "?")
            known = types or await self.node.master.topic_types(limit)
            for topic, stats in self.stats.items():
                if not stats.type and known.get(topic, "*") != "*":
                    stats.type = known[topic]

    async def _subscribe(self, topics: list[str]) -> None:
        """Subscribe to ``topics``, with ``SUBSCRIBE_AT_ONCE`` registrations in flight.

        One at a time, a busy master's answer times were added up: 1,000 topics on a loaded
        machine took minutes to follow.
        """
        gate = asyncio.Semaphore(SUBSCRIBE_AT_ONCE)

        async def one(topic: str) -> None:
            async with gate:
                await self.node.subscribe(
                    topic, self._on_frames(topic), tcp_nodelay=self.live_opts.tcp_nodelay
                )

        await asyncio.gather(*(one(topic) for topic in topics))

    def _say_subscribing(self, topic: str) -> None:
        if self.on_subscribe is not None:
            self.on_subscribe(topic)

    async def _node_topics(self, name: str, limit: float) -> list[str]:
        """The topics node ``name`` subscribes to (rosbag record --node)."""
        from rostools.node.mastercalls import peer_value

        try:
            uri = await self.node.master.lookup_node(self.node.resolve(name), limit)
            subs = await peer_value(uri, self.node.name, "getSubscriptions")
        except (RostoolsError, OSError) as err:
            log.debug("node %s: %s", name, err)
            return []
        return [topic for topic, _ in subs]

    def _elapsed(self) -> float:
        return (self.clock.now() - self.start_ns) / 1e9

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


def gib(size: int) -> str:
    """A byte count as rosbag writes -L limits: ``1G``, ``500M``, ``64K``."""
    for unit, scale in (("G", 1024**3), ("M", 1024**2), ("K", 1024)):
        if size >= scale:
            return f"{size / scale:.1f}".removesuffix(".0") + unit
    return f"{size}B"
