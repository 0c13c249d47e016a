"""A topic publisher: links to its subscribers, latching, ``header.seq`` as rospy sets it."""

from __future__ import annotations

import struct
import time
from collections.abc import Callable, Hashable
from typing import TYPE_CHECKING

from rostools.msgs.topictype import TopicType
from rostools.node.connection import Frame, Outbound, ServerConnection, set_nodelay
from rostools.wire.tcpros import check_subscription, error_header, publisher_header

if TYPE_CHECKING:
    from rostools.node.endpoint import Owner

_SEQ = struct.Struct("<I")
#: The source of latched messages that ``publish`` counted: their ``seq`` counts on.
_COUNTED = "publish"


class TopicPublisher:
    """Publishes on one topic to every connected subscriber."""

    def __init__(
        self,
        node: Owner,
        topic: str,
        topic_type: TopicType,
        latch: bool = False,
        queue_size: int = 100,
    ) -> None:
        self.node = node
        self.topic = topic
        self.type = topic_type
        self.latch = latch
        self.queue_size = queue_size
        self.links: list[Outbound] = []
        #: The last message of each source, oldest first: what a late subscriber gets.
        self.latched: dict[Hashable, Frame] = {}
        self.seq = 0
        self.closed = False
        #: Caller ids of the subscribers that reached us, connected or not.
        self.contacted: set[str] = set()
        #: The subscribers the master listed when we advertised (their XML-RPC URIs).
        self.reported: list[str] = []
        #: Called with each subscriber's header before it is checked: a publisher advertised
        #: with md5sum ``*`` may learn its type here (``self.type``) from what the peer wants.
        self.on_subscriber: Callable[[dict[str, str]], None] | None = None
        #: Messages published before ``early_until`` (monotonic), for subscribers that connect
        #: until then (``keep_early``).
        self.early: list[Frame] = []
        self.early_until = 0.0

    @property
    def subscriber_count(self) -> int:
        """How many subscribers are connected."""
        return len(self.links)

    def publish(self, payload: Frame) -> None:
        """Send serialised message bytes; a Header's ``seq`` is rewritten as rospy does.

        rospy counts the publishes that reach at least one subscriber, starting at 1, and
        each time it sends the latched message to a subscriber that connects later.
        """
        if self.early_until:
            if time.monotonic() >= self.early_until:
                self.early_until, self.early = 0.0, []
            elif len(self.early) < self.queue_size:
                self.early.append(payload)
        if self.links:
            payload = self._counted(payload)
        self.publish_raw(payload, _COUNTED)

    def keep_early(self, seconds: float) -> None:
        """Send what is published in the next ``seconds`` to subscribers that connect in them.

        rosbridge's publishers do so: a web client advertises and publishes at once, before
        the graph's subscribers have connected, and its first message would be lost.
        """
        self.early_until = time.monotonic() + seconds

    def _counted(self, payload: Frame) -> Frame:
        """``payload`` with the next ``seq`` in its Header, if its type has one."""
        if not self.type.has_header or len(payload) < 4:
            return payload
        self.seq = (self.seq + 1) & 0xFFFFFFFF
        data = bytearray(payload)
        _SEQ.pack_into(data, 0, self.seq)
        return bytes(data)

    def publish_raw(self, payload: Frame, source: Hashable = None, keep: bool = True) -> None:
        """Send bytes exactly as given (bag play, relays).

        A latching publisher keeps the last message of each ``source`` (when ``keep``) for
        subscribers that connect later, oldest first. bag play names each recorded publisher
        as a source, so a late subscriber to ``/tf_static`` gets every recorded publisher's
        last message, as rosbag play's one publisher per recorded connection gives.
        """
        if self.latch and keep:
            self.latched.pop(source, None)  # re-inserted last: the order is that of sending
            self.latched[source] = payload
        for link in self.links:
            link.send(payload)

    def accept(self, fields: dict[str, str], conn: ServerConnection) -> Outbound | None:
        """A subscriber's header arrived: check it, answer, and start sending."""
        if self.on_subscriber is not None:
            self.on_subscriber(fields)
        problem = check_subscription(fields, self.topic, self.type.md5sum, self.type.type)
        if problem is not None:
            conn.write(error_header(problem))
            conn.close()
            return None
        if fields.get("tcp_nodelay") == "1" and conn.transport is not None:
            set_nodelay(conn.transport)
        conn.write(
            publisher_header(
                self.node.name, self.topic, self.type.md5sum, self.type.type, self.type.definition,
                self.latch,
            )
        )  # fmt: skip
        link = Outbound(
            conn, self.node.next_connection_id(), fields.get("callerid", "?"), self.queue_size
        )
        link.on_close = self._lost
        self.links.append(link)
        if self.early_until and time.monotonic() < self.early_until:
            for payload in self.early:
                link.send(self._counted(payload))
        for source, payload in self.latched.items():
            link.send(self._counted(payload) if source == _COUNTED else payload)
        return link

    def _lost(self, link: Outbound) -> None:
        if link in self.links:
            self.links.remove(link)

    def flush(self) -> None:
        """Write what this loop turn queued now, not at the next turn (bag play's timing)."""
        for link in self.links:
            link.flush()

    def close(self) -> None:
        """Close every link."""
        self.closed = True
        for link in list(self.links):
            link.close()
        self.links.clear()
