"""The rolling buffer of ``bag snapshot``: raw frames by topic, oldest out first.

Frames are kept as they arrived, never decoded. Each topic keeps its messages in a deque;
one more deque, ``order``, holds a reference to the topic of every message in the order they
arrived, so the oldest message of all is found without looking at every topic. A message a
topic drops on its own (its own size limit, ``clear``) leaves its slot in ``order``: the
topic counts it in ``skip``, and the slot is let go when it reaches the front.

Memory is counted as ``bag record -b`` counts it: each message's bytes plus
``ENTRY_OVERHEAD`` for what holding it costs, so the limits bound what the process holds.
The last message of every latched publisher is kept aside, whatever the limits evict, and
counted too.

What the limits let go is remembered by receive time (``TopicBuffer.gone``, runs of messages
received at the same time, the last ``GONE_KEPT`` runs of each topic), so a trigger whose
window starts before the oldest message left is told exactly how many it lost (``lost``): a
remote trigger reaches the buffer some time after it read its clock, and a small buffer at a
high rate spans less than that.
"""

from __future__ import annotations

import collections
import itertools
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field

from rostools.bag.formats.model import ENTRY_OVERHEAD
from rostools.node.connection import Frame


class ConnInfo:
    """One publisher connection as the buffer keeps it: its topic and connection header."""

    __slots__ = ("header", "latched", "topic")

    def __init__(self, topic: str, header: Mapping[str, str]) -> None:
        self.topic = topic
        self.header = header
        self.latched = header.get("latching") == "1"


#: One buffered message: receive time (ns), its connection, its bytes.
Entry = tuple[int, ConnInfo, Frame]
#: Runs of evicted messages each topic remembers (a run: messages received at the same time).
GONE_KEPT = 256


@dataclass(frozen=True)
class Lost:
    """Messages of a window the limits let go: how many, and whether that is all (or at least)."""

    count: int = 0
    exact: bool = True


class TopicBuffer:
    """The messages of one topic, oldest first; ``bytes`` counts ``ENTRY_OVERHEAD`` each."""

    __slots__ = ("bytes", "entries", "evicted", "gone", "skip", "topic")

    def __init__(self, topic: str) -> None:
        self.topic = topic
        self.entries: collections.deque[Entry] = collections.deque()
        self.skip = 0  # slots in ``order`` whose message this topic has already let go
        self.bytes = 0
        self.evicted = 0  # messages the limits pushed out
        #: The latest runs of evicted messages: (receive time, how many), oldest first.
        self.gone: collections.deque[tuple[int, int]] = collections.deque(maxlen=GONE_KEPT)

    def evict(self) -> Entry:
        """Let go of the oldest message (the limits): counted, and remembered by its time."""
        entry = self.entries.popleft()
        self.bytes -= len(entry[2]) + ENTRY_OVERHEAD
        self.evicted += 1
        gone = self.gone
        if gone and gone[-1][0] == entry[0]:
            gone[-1] = (entry[0], gone[-1][1] + 1)
        else:
            gone.append((entry[0], 1))
        return entry

    def lost_since(self, start_ns: int) -> Lost:
        """Messages received at ``start_ns`` or later that the limits let go."""
        count = 0
        for t_ns, n in reversed(self.gone):
            if t_ns < start_ns:
                return Lost(count, True)
            count += n
        # every run remembered is in the window: exact if none was forgotten
        return Lost(count, self.evicted == count)

    def span(self) -> float:
        """Seconds between its oldest and newest message."""
        return (self.entries[-1][0] - self.entries[0][0]) / 1e9 if self.entries else 0.0


@dataclass
class Held:
    """What a snapshot took from the buffer: references, so the buffer can go on evicting."""

    order: list[TopicBuffer]
    topics: dict[TopicBuffer, tuple[collections.deque[Entry], int]]
    latched: list[Entry] = field(default_factory=list)

    def oldest(self) -> int | None:
        """The receive time of the oldest message held, if any."""
        return min((q[0][0] for q, _ in self.topics.values() if q), default=None)

    def any_between(self, start: int, stop: int) -> bool:
        """Whether some message held lies in [start, stop] (or a latched one is kept)."""
        if self.latched:
            return True
        # newest first: a window usually ends near the trigger, so this stops at once
        return any(start <= e[0] <= stop for q, _ in self.topics.values() for e in reversed(q))

    def messages(self, start: int, stop: int) -> Iterator[Entry]:
        """The messages in [start, stop], in the order they arrived, let go as they are read."""
        if len(self.topics) == 1:
            ((queue, _),) = self.topics.values()
            while queue:
                entry = queue.popleft()
                if start <= entry[0] <= stop:
                    yield entry
            return
        skips = {tb: skip for tb, (_, skip) in self.topics.items()}
        order, self.order = self.order, []
        for tb in order:
            held = self.topics.get(tb)
            if held is None:
                continue
            if skips[tb]:
                skips[tb] -= 1
                continue
            entry = held[0].popleft()
            if start <= entry[0] <= stop:
                yield entry

    def latched_before(self, start: int) -> list[Entry]:
        """Latched messages to open the file with, stamped at ``start``.

        Those older than the window, and those the limits pushed out of the buffer (the
        buffer would have given the others).
        """
        firsts = self._firsts()
        kept = []
        for t_ns, conn, data in self.latched:
            if t_ns < start or t_ns < firsts.get(conn.topic, t_ns + 1):
                kept.append((max(t_ns, start), conn, data))
        return kept

    def resent_since(self, start: int) -> list[str]:
        """The topics of latched messages in the window that the limits let go (one each).

        ``latched_before`` gives them back, so they are not lost.
        """
        firsts = self._firsts()
        return [c.topic for t, c, _ in self.latched if start <= t < firsts.get(c.topic, t + 1)]

    def _firsts(self) -> dict[str, int]:
        return {tb.topic: q[0][0] for tb, (q, _) in self.topics.items() if q}


class RingBuffer:
    """Messages by topic, bounded by ``duration_ns``, ``size`` and ``topic_size`` (0: none)."""

    def __init__(self, duration_ns: int, size: int, topic_size: int = 0) -> None:
        self.duration_ns = duration_ns
        self.size = size
        self.topic_size = topic_size
        self.topics: dict[str, TopicBuffer] = {}
        self.order: collections.deque[TopicBuffer] = collections.deque()
        #: Bytes of the messages held, plus ``ENTRY_OVERHEAD`` per slot of ``order``.
        self.bytes = 0
        #: The last message of each latched publisher, by (topic, callerid).
        self.latched: dict[tuple[str, str], Entry] = {}
        self.latched_bytes = 0

    def topic(self, name: str) -> TopicBuffer:
        """The buffer of topic ``name`` (made on first use)."""
        tb = self.topics.get(name)
        if tb is None:
            tb = self.topics[name] = TopicBuffer(name)
        return tb

    @property
    def held(self) -> int:
        """Bytes held: messages, their overhead and the latched copies."""
        return self.bytes + self.latched_bytes

    def add(self, tb: TopicBuffer, conn: ConnInfo, t_ns: int, frames: list[Frame]) -> None:
        """Keep ``frames`` received at ``t_ns``, then evict what the limits no longer allow."""
        count = len(frames)
        tb.entries.extend(zip(itertools.repeat(t_ns, count), itertools.repeat(conn), frames))
        self.order.extend(itertools.repeat(tb, count))
        size = sum(map(len, frames)) + count * ENTRY_OVERHEAD
        tb.bytes += size
        self.bytes += size
        if conn.latched and frames:
            self._latch(conn, t_ns, frames[-1])
        if self.topic_size and tb.bytes > self.topic_size:
            self._trim_topic(tb)
        while self.order and self.bytes + self.latched_bytes > self.size:
            self._pop_oldest()
        self.evict_old(t_ns)

    def _latch(self, conn: ConnInfo, t_ns: int, data: Frame) -> None:
        key = (conn.topic, conn.header.get("callerid", ""))
        old = self.latched.get(key)
        if old is None:
            self.latched_bytes += ENTRY_OVERHEAD
        else:
            self.latched_bytes -= len(old[2])
        self.latched_bytes += len(data)
        self.latched[key] = (t_ns, conn, data)

    def _trim_topic(self, tb: TopicBuffer) -> None:
        while tb.bytes > self.topic_size and tb.entries:
            _, _, data = tb.evict()
            self.bytes -= len(data)  # its slot in ``order`` is counted until it goes
            tb.skip += 1

    def _pop_oldest(self) -> None:
        tb = self.order.popleft()
        self.bytes -= ENTRY_OVERHEAD
        if tb.skip:
            tb.skip -= 1
            return
        _, _, data = tb.evict()
        self.bytes -= len(data)

    def evict_old(self, now_ns: int) -> None:
        """Let go of the messages older than ``duration_ns`` before ``now_ns``."""
        cutoff = now_ns - self.duration_ns
        order = self.order
        while order:
            tb = order[0]
            if not tb.skip and tb.entries[0][0] >= cutoff:
                return
            self._pop_oldest()

    def copy(self, topics: set[str] | None = None) -> Held:
        """References to what is held now, of ``topics`` (None: all)."""
        chosen = {
            tb: (collections.deque(tb.entries), tb.skip)
            for name, tb in self.topics.items()
            if topics is None or name in topics
        }
        order = list(self.order) if len(chosen) > 1 else []
        latched = [e for (t, _), e in self.latched.items() if topics is None or t in topics]
        return Held(order, chosen, latched)

    def clear(self, topics: set[str] | None = None) -> None:
        """Let go of the messages of ``topics`` (None: all); the latched copies stay."""
        for name, tb in self.topics.items():
            if topics is None or name in topics:
                freed = sum(len(d) for _, _, d in tb.entries)
                self.bytes -= freed
                tb.skip += len(tb.entries)
                tb.bytes = 0
                tb.entries.clear()
