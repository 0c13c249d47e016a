"""Playback: bag messages published on the live graph at their recorded pace.

Messages go out as the raw bytes in the file (never decoded, ``header.seq`` untouched). Each
topic gets one publisher, latched when any recorded connection on it was latched; like
rosbag's publisher per recorded connection, it keeps the last message of each latched one,
so a late subscriber gets them all.
Timing: the loop sleeps on asyncio until about 2 ms before a message is due, then on
``time.sleep`` to the due time, so sockets are served while waiting and the send is still on
time.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from enum import Enum

from rostools.bag.formats.access import latched_before, merged_messages
from rostools.bag.formats.base import BagReader
from rostools.bag.formats.model import NS_PER_SEC, Connection
from rostools.bag.live.play_control import RateControl, set_bool_reply
from rostools.errors import UsageError
from rostools.msgs.topictype import TopicType
from rostools.msgs.wellknown import CLOCK, SET_BOOL
from rostools.node.clock import TIME, tighten_timer_slack
from rostools.node.connection import Frame
from rostools.node.node import LiveNode
from rostools.node.publisher import TopicPublisher
from rostools.node.session import first

#: The last stretch before a due time is slept with ``time.sleep`` (asyncio wakes late).
FINE_SLEEP = 0.002
#: The longest the event loop goes unserved while messages are sent back to back.
YIELD_PERIOD = 0.001
#: How long play waits for the subscribers the master listed to connect before it starts.
CONNECT_GRACE = 2.0


@dataclass
class PlayOptions:
    """rosbag play's options."""

    rate: float = 1.0
    start: float = 0.0  # seconds into the bags
    duration: float | None = None  # seconds to play
    loop: bool = False
    clock: bool = False
    hz: float = 100.0
    delay: float = 0.2
    immediate: bool = False
    pause: bool = False
    topics: list[str] = field(default_factory=list)
    prefix: str = ""
    keep_alive: bool = False
    skip_empty: float | None = None
    queue_size: int = 100
    wait_for_subscribers: bool = False
    pause_topics: list[str] = field(default_factory=list)  # pause before their messages
    rate_control_topic: str | None = None
    rate_control_max_delay: float = 1.0


class State(Enum):
    """What the player is doing, as rosbag's status line says."""

    RUNNING = "RUNNING"
    PAUSED = "PAUSED "
    DELAYED = "DELAYED"  # waiting for the rate-control topic
    DONE = "DONE   "


@dataclass
class Status:
    """Where playback is: shown in the status line."""

    state: State = State.RUNNING
    bag_time: int = 0  # ns
    elapsed: float = 0.0  # s of bag time since the start point
    total: float = 0.0  # s of bag time to play
    published: int = 0
    delay: float = 0.0  # s the rate-control topic lags, while DELAYED


class Player:
    """Publishes the messages of ``readers`` on ``node``."""

    def __init__(self, node: LiveNode, readers: Sequence[BagReader], opts: PlayOptions) -> None:
        if opts.rate <= 0:
            raise UsageError("the rate (-r) must be positive")
        if opts.clock and opts.hz <= 0:
            raise UsageError("--hz must be positive")
        self.node = node
        self.readers = readers
        self.opts = opts
        self.publishers: dict[str, TopicPublisher] = {}
        self.clock: TopicPublisher | None = None
        self.status = Status(state=State.PAUSED if opts.pause else State.RUNNING)
        self.steps = 0  # messages to send while paused (the ``s`` key)
        self.wake = asyncio.Event()
        self.pause_topics = set(opts.pause_topics)
        self.pausing_on_topics = bool(self.pause_topics)  # the ``t`` key toggles it
        self.rate_control: RateControl | None = None
        if opts.rate_control_topic:
            self.rate_control = RateControl(
                opts.rate_control_topic, opts.rate_control_max_delay, self.wake.set
            )
        self._origin: float | None = None  # when (monotonic) bag time from_ns plays
        self._next_clock = self._next_show = self._yielded = 0.0  # monotonic times
        infos = [r.info() for r in readers]
        starts = [i.start_ns for i in infos if i.start_ns is not None]
        ends = [i.end_ns for i in infos if i.end_ns is not None]
        self.bag_start: int = min(starts, default=0)
        self.bag_end: int = max(ends, default=0)
        self.from_ns = self.bag_start + round(opts.start * NS_PER_SEC)
        self.until_ns = self.bag_end
        if opts.duration is not None:
            self.until_ns = min(self.bag_end, self.from_ns + round(opts.duration * NS_PER_SEC))
        # The span of bag time the status line shows
        self.shown_from, self.shown_until = self.from_ns, self.until_ns
        self.status.total = max(self.until_ns - self.from_ns, 0) / NS_PER_SEC

    def measure(self) -> None:
        """The status line's times span the messages played, as rosbag's.

        From the first message at or after ``-s`` to the last within ``-u``, of ``--topics``
        if given (it showed the window asked for: ``-u 0.55`` was 0.55 s, rosbag's 0.5). It
        reads index entries (about 2 us each) up to the end of what is played, so only a
        caller that shows the status asks for it. Without ``-s``, ``-u`` and ``--topics``, the
        span is the bags' own.
        """
        topics = self._topics()
        to_the_end = topics is None and self.until_ns >= self.bag_end
        first: int | None = None
        last: int | None = self.bag_end if to_the_end else None
        for reader in self.readers:
            for _, t, _ in reader.times(topics):  # in time order
                if t < self.from_ns:
                    continue
                if t > self.until_ns:
                    break
                first = t if first is None else min(first, t)
                if to_the_end:
                    break
                last = t if last is None else max(last, t)
        if first is not None and last is not None:
            self.shown_from, self.shown_until = first, last
            self.status.total = (last - first) / NS_PER_SEC

    # controls ---------------------------------------------------------------------------

    def toggle_pause(self) -> None:
        """Space: pause or go on."""
        self.set_paused(self.status.state is not State.PAUSED)

    def set_paused(self, paused: bool) -> None:
        """Pause or go on (also the ``~pause_playback`` service)."""
        if self.status.state is not State.DONE:
            self.status.state = State.PAUSED if paused else State.RUNNING
        self.wake.set()

    def toggle_pause_topics(self) -> None:
        """``t``: whether ``--pause-topics`` pause playback."""
        self.pausing_on_topics = not self.pausing_on_topics

    def step(self) -> None:
        """``s``: while paused, publish the next message now."""
        if self.status.state is State.PAUSED:
            self.steps += 1
            self.wake.set()

    # setup ------------------------------------------------------------------------------

    def _topics(self) -> set[str] | None:
        return set(self.opts.topics) if self.opts.topics else None

    def connections(self) -> list[Connection]:
        """The recorded connections that will be played."""
        wanted = self._topics()
        return [
            c for r in self.readers for c in r.connections if wanted is None or c.topic in wanted
        ]

    async def advertise(self) -> None:
        """One publisher per topic, latched if any of its connections was."""
        latched: dict[str, bool] = {}
        first_conn: dict[str, Connection] = {}
        for conn in self.connections():
            first_conn.setdefault(conn.topic, conn)
            latched[conn.topic] = latched.get(conn.topic, False) or conn.latching
        for topic, conn in first_conn.items():
            topic_type = TopicType(conn.type, conn.md5sum, conn.definition)
            name = self.opts.prefix + topic if self.opts.prefix else topic
            self.publishers[topic] = await self.node.advertise(
                name, topic_type, latch=latched[topic], queue_size=self.opts.queue_size
            )
        if self.opts.clock:
            self.clock = await self.node.advertise("/clock", CLOCK, queue_size=1)
        if self.rate_control is not None:
            await self.rate_control.subscribe(self.node)
        await self.node.advertise_service("~pause_playback", SET_BOOL, self._pause_service)

    def _publish(self, conn: Connection, data: Frame) -> TopicPublisher:
        # Latched per recorded publisher, as rosbag's latched_before keys them.
        pub = self.publishers[conn.topic]
        pub.publish_raw(data, (conn.topic, conn.callerid), conn.latching)
        return pub

    def _pause_service(self, request: bytes) -> bytes:
        return set_bool_reply(request, self.status.state is State.PAUSED, self.set_paused)

    # playing ----------------------------------------------------------------------------

    async def run(
        self,
        stop: asyncio.Event,
        show: Callable[[Status], None] | None = None,
        say: Callable[[str], None] | None = None,
    ) -> int:
        """Advertise, wait ``-d``, play (looping if asked); the number of messages sent.

        ``say`` gets rosbag play's lines about waiting (each ends in a newline).
        """
        tighten_timer_slack()
        await self.advertise()
        advertised = time.monotonic()
        await self._until_connected(stop, advertised + CONNECT_GRACE)
        if self.opts.wait_for_subscribers:
            if say is not None:
                say("Waiting for subscribers.\n")
            while not stop.is_set() and any(
                p.subscriber_count == 0 for p in self.publishers.values()
            ):
                await first(stop.wait(), timeout=0.05)
            if say is not None:
                say("Finished waiting for subscribers.\n")
        rest = advertised + self.opts.delay - time.monotonic()
        if rest > 0:
            await first(stop.wait(), timeout=rest)
        if say is not None:
            say(f"Waiting {self.opts.delay:g} seconds after advertising topics... done.\n")
        # -s: what a late subscriber would still get (unless stopped while waiting)
        if self.from_ns > self.bag_start and not stop.is_set():
            for conn, _, data in latched_before(self.readers, self._topics(), self.from_ns):
                self._publish(conn, data)
        if self.rate_control is not None:
            self.rate_control.start(self.from_ns)
        while not stop.is_set():
            await self._play_once(stop, show)
            if not self.opts.loop:
                break
        self.status.state = State.DONE
        if show is not None:
            show(self.status)
        if self.opts.keep_alive:
            await stop.wait()
        return self.status.published

    async def _until_connected(self, stop: asyncio.Event, deadline: float) -> None:
        """Until every subscriber the master listed at advertising has connected.

        A roscpp subscriber takes about 250 ms to connect (it polls its XML-RPC replies every
        100 ms), longer than ``-d``'s 0.2 s: without this, it missed the first messages. A
        listed subscriber that never connects (a dead node) holds play up to ``deadline``.
        """
        while not stop.is_set() and time.monotonic() < deadline:
            if all(p.subscriber_count >= len(p.reported) for p in self.publishers.values()):
                return
            await first(stop.wait(), timeout=0.005)

    async def _play_once(self, stop: asyncio.Event, show: Callable[[Status], None] | None) -> None:
        messages = merged_messages(self.readers, self._topics(), self.from_ns, self.until_ns)
        self._origin = None
        self._next_clock = self._next_show = self._yielded = 0.0
        for conn, t, data in messages:
            if stop.is_set():
                return
            if (
                self.pausing_on_topics
                and conn.topic in self.pause_topics
                and self.status.state is State.RUNNING
            ):
                self.status.state = State.PAUSED  # as rosbag: before the message; ``s`` sends it
            if not self.opts.immediate and not await self._wait_for(t, stop, show):
                return
            self._publish(conn, data).flush()
            self.status.published += 1
            self.status.bag_time = t
            if time.monotonic() - self._yielded > YIELD_PERIOD:
                # Back-to-back messages: still serve new subscribers, the keys and Ctrl-C.
                await asyncio.sleep(0)
                self._yielded = time.monotonic()
        if self.clock is not None:
            self._publish_clock(self.until_ns)
        self.status.bag_time = self.shown_until
        self.status.elapsed = self.status.total

    async def _wait_for(
        self, t: int, stop: asyncio.Event, show: Callable[[Status], None] | None
    ) -> bool:
        """Until bag time ``t`` is due (pauses, steps, /clock and the status on the way).

        False when stopped.
        """
        opts = self.opts
        scale = 1.0 / (NS_PER_SEC * opts.rate)
        if self._origin is None:
            self._origin = time.monotonic() - (t - self.from_ns) * scale
        while True:
            now = time.monotonic()
            if show is not None and now >= self._next_show:
                self._next_show = now + 0.1
                self.status.bag_time = self._bag_time(now, t)
                self.status.elapsed = (self.status.bag_time - self.shown_from) / NS_PER_SEC
                show(self.status)
            if self.status.state is State.PAUSED:
                if self.steps:
                    self.steps -= 1
                    self._origin = now - (t - self.from_ns) * scale
                    return True
                self.wake.clear()
                await first(self.wake.wait(), stop.wait(), timeout=0.1)
                self._origin += time.monotonic() - now  # paused time does not count
                if stop.is_set():
                    return False
                continue
            if self.rate_control is not None and self.rate_control.holds(t):
                self.status.state = State.DELAYED
                self.status.delay = self.rate_control.lag(t)
                self.wake.clear()
                await first(self.wake.wait(), stop.wait(), timeout=0.1)
                self._origin += time.monotonic() - now  # so is delayed time
                if stop.is_set():
                    return False
                continue
            if self.status.state is State.DELAYED:
                self.status.state = State.RUNNING
            due = self._origin + (t - self.from_ns) * scale
            if opts.skip_empty is not None and due - now > opts.skip_empty / opts.rate:
                self._origin -= due - now  # a long gap in the recording: jump over it
                due = now
            if self.clock is not None and self._next_clock <= now:
                self._next_clock = now + 1.0 / opts.hz
                self._publish_clock(self._bag_time(now, t))
            if due <= now:
                return True
            wait = (min(due, self._next_clock) if self.clock is not None else due) - now
            if wait > FINE_SLEEP:
                self.wake.clear()
                await first(stop.wait(), self.wake.wait(), timeout=min(wait - FINE_SLEEP, 0.1))
                self._yielded = time.monotonic()
                if stop.is_set():
                    return False
            else:
                time.sleep(wait)

    def _bag_time(self, now: float, next_t: int) -> int:
        """The bag time playing at ``now`` (never past the next message)."""
        assert self._origin is not None
        t = self.from_ns + round((now - self._origin) * NS_PER_SEC * self.opts.rate)
        return min(t, next_t)

    def _publish_clock(self, t_ns: int) -> None:
        if self.clock is not None:
            secs, nsecs = divmod(t_ns, NS_PER_SEC)
            self.clock.publish_raw(TIME.pack(secs, nsecs))
            self.clock.flush()
