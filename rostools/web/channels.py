"""The bridge's channels (a topic and its type) and its ROS subscriptions, made on demand.

A topic of a type the store knows is a channel at once, with the store's definition. Any
other type is learnt from a publisher's connection header (``message_definition``): the
bridge subscribes, reads the header, and lets go again unless a client wants the topic. So no
``.msg`` file is needed anywhere.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from rostools.msgs.topictype import ANY, TopicType

if TYPE_CHECKING:
    from rostools.node.connection import Frame, InboundConnection
    from rostools.node.node import LiveNode
    from rostools.node.subscriber import Subscriber
    from rostools.web.client import Client, Subscription

#: The message encoding and schema encoding of every channel: ROS 1 bytes, ``.msg`` text.
ENCODING, SCHEMA_ENCODING = "ros1", "ros1msg"


@dataclass
class Channel:
    """A topic as clients see it."""

    id: int
    topic: str
    type: TopicType

    def advertisement(self) -> dict[str, object]:
        """The channel in an ``advertise`` message."""
        return {
            "id": self.id,
            "topic": self.topic,
            "encoding": ENCODING,
            "schemaName": self.type.type,
            "schema": self.type.definition,
            "schemaEncoding": SCHEMA_ENCODING,
        }


@dataclass
class TopicStats:
    """What came in on one topic."""

    messages: int = 0
    bytes: int = 0


@dataclass
class TopicLink:
    """The bridge's ROS subscription to one topic, and the clients' subscriptions it feeds."""

    topic: str
    sub: Subscriber | None = None
    #: The node's subscription under way or made (``Links.open``): one, however many ask.
    opening: asyncio.Future[Subscriber] | None = None
    readers: dict[tuple[int, int], tuple[Client, Subscription]] = field(default_factory=dict)
    #: The last message of each latching publisher (by its URI): what a new reader gets first.
    latched: dict[str, Frame] = field(default_factory=dict)
    #: Subscribed only to read a publisher's header (the type); let go once it is read.
    learning: bool = False
    #: The type the last publisher's header gave (what a rosbridge client's JSON is made by).
    type: TopicType | None = None
    stats: TopicStats = field(default_factory=TopicStats)


class Links:
    """The ROS subscriptions, one per topic, made while a client reads or a type is learnt."""

    def __init__(
        self,
        node: LiveNode,
        stamp: Callable[[], int],
        clock: Callable[[], float],
        on_type: Callable[[str, TopicType], None],
    ) -> None:
        self.node = node
        self.stamp = stamp
        self.clock = clock
        self.on_type = on_type
        self.links: dict[str, TopicLink] = {}
        #: Topics the node already follows for itself (``/clock`` on sim time): their frames
        #: come through ``feed``, as a node subscribes to a topic once.
        self.borrowed: set[str] = set()

    def feed(self, topic: str, frames: list[Frame], conn: InboundConnection) -> None:
        """Frames of a borrowed topic."""
        link = self.links.get(topic)
        if link is not None:
            self.deliver(link, frames, conn)

    async def open(self, topic: str, learning: bool = False) -> TopicLink:
        """The link of ``topic``, subscribed if it was not."""
        link = self.links.get(topic)
        if link is None:
            link = self.links[topic] = TopicLink(topic, learning=learning)
        if link.opening is not None and link.opening.done() and link.opening.exception():
            link.opening = None  # it failed: this call tries again
        if link.opening is None and topic not in self.borrowed:
            # one subscription, however many clients ask at once: the later ones wait for it
            link.opening = asyncio.ensure_future(
                self.node.subscribe(
                    topic,
                    lambda frames, conn, _: self.deliver(link, frames, conn),
                    ANY,
                    on_header=self._header(link),
                )
            )
        if link.opening is not None:
            link.sub = await asyncio.shield(link.opening)
        return link

    async def release(self, topic: str) -> None:
        """Let go of ``topic`` when no client reads it and no type is being learnt."""
        link = self.links.get(topic)
        if link is None or link.readers or link.learning:
            return
        del self.links[topic]
        if link.opening is not None:
            await asyncio.wait([link.opening])  # subscribed first, so that it is undone
            link.sub = link.opening = None
            await self.node.unsubscribe(topic)

    def _header(self, link: TopicLink) -> Callable[[InboundConnection], None]:
        def on_header(conn: InboundConnection) -> None:
            header = conn.header or {}
            if "type" in header and "md5sum" in header:
                link.type = TopicType.from_header(header)
                self.on_type(link.topic, link.type)

        return on_header

    def deliver(self, link: TopicLink, frames: list[Frame], conn: InboundConnection) -> None:
        """Frames of ``link``'s topic: counted, the latched one kept, offered to each reader."""
        link.stats.messages += len(frames)
        link.stats.bytes += sum(len(f) for f in frames)
        if frames and (conn.header or {}).get("latching") == "1":
            link.latched[conn.publisher_uri] = frames[-1]
        if not link.readers:
            return
        stamp, now = self.stamp(), self.clock()
        for client, sub in list(link.readers.values()):
            for frame in frames:
                client.offer(sub, stamp, frame, now)
