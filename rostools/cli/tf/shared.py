"""The feed every ``tf`` command reads: ``/tf`` and ``/tf_static``, live or from a bag.

Each message received (or recorded) is one ``Batch``: when it arrived, who sent it, whether
it is static, and its transforms. Live, a short-lived node subscribes to both topics (each
latched ``/tf_static`` publisher hands over its last message on connecting); from a bag, the
connections of both topics are read in record order.
"""

from __future__ import annotations

import contextlib
import struct
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from rostools.errors import InvalidDataError, NotFoundError
from rostools.tf.records import TF_MD5, Stamped, decode

if TYPE_CHECKING:
    from rostools.bag.formats.base import BagReader
    from rostools.bag.formats.model import Connection
    from rostools.node.connection import Frame, InboundConnection
    from rostools.node.node import LiveNode
    from rostools.rosgraph.masterapi import MasterProxy

#: The two topics, as tf2_ros's TransformListener names them.
TF_TOPIC, TF_STATIC_TOPIC = "/tf", "/tf_static"


@dataclass(frozen=True, slots=True)
class Batch:
    """One ``/tf`` or ``/tf_static`` message as it was received.

    ``received_ns``: live, the wall clock (ns since the epoch) when it arrived; in a bag, its
    record time. ``broadcaster``: the publisher's ``callerid`` (live: its URI when the header
    has none; in a bag, empty when the recorder did not keep it).
    """

    received_ns: int
    broadcaster: str
    static: bool
    transforms: list[Stamped]


def _is_tf(conn: Connection) -> bool:
    """A bag connection of ``/tf`` or ``/tf_static`` (or an old bag's ``tf``), as ROS 1."""
    return (
        conn.topic.lstrip("/") in ("tf", "tf_static")
        and conn.encoding == "ros1"
        and conn.md5sum in (TF_MD5, "*")
    )


class BagFeed:
    """The TF messages of one ``.bag`` or MCAP file; ``open_feed`` opens it.

    ``start_ns`` and ``end_ns`` are the recording's first and last record times (of every
    topic, so that ``--at`` can name any time of it); both None for an empty bag.
    """

    def __init__(self, reader: BagReader) -> None:
        self.reader = reader
        self.path = reader.path
        info = reader.info()
        self.start_ns: int | None = info.start_ns
        self.end_ns: int | None = info.end_ns
        self.connections = [c for c in reader.connections if _is_tf(c)]
        if not self.connections:
            raise NotFoundError(f"{self.path} holds no /tf or /tf_static (tf2_msgs/TFMessage)")

    def batches(self, end_ns: int | None = None) -> Iterator[Batch]:
        """Every TF message in record order, up to ``end_ns`` (record time) if given.

        A message that does not decode ends the reading (``InvalidDataError``, naming it).
        """
        for conn, t_ns, data in self.reader.messages(connections=self.connections, end=end_ns):
            try:
                transforms = decode(data)
            except (ValueError, struct.error) as err:
                raise InvalidDataError(
                    f"{self.path}: {conn.topic} message at {t_ns / 1e9:.9f} s: {err}"
                ) from err
            static = conn.topic.lstrip("/") == "tf_static"
            yield Batch(t_ns, conn.callerid, static, transforms)


@contextlib.contextmanager
def open_feed(path: Path, check_crcs: bool = True) -> Iterator[BagFeed]:
    """The TF feed of the bag at ``path`` (``NotFoundError`` when it has no TF topic)."""
    from rostools.bag.formats.access import open_bag

    with open_bag(path, check_crcs=check_crcs) as reader:
        yield BagFeed(reader)


BatchCallback = Callable[[Batch], None]


class LiveFeed:
    """``/tf`` and ``/tf_static`` followed on a live node: each message to ``on_batch``.

    ``on_batch`` runs on the node's loop, once per message, in arrival order per publisher.
    A message that does not decode is skipped; the first from each publisher is told
    through the node's notices.
    """

    def __init__(self, node: LiveNode, on_batch: BatchCallback) -> None:
        self.node = node
        self.on_batch = on_batch
        #: Messages skipped per publisher.
        self.skipped: dict[str, int] = {}
        self.topics: list[str] = []

    async def start(self) -> None:
        """Subscribe to both topics (names resolve and remap as the node's)."""
        from rostools.msgs.topictype import TopicType

        # md5 "*": tf/tfMessage publishers (the same bytes) connect too.
        kind = TopicType("tf2_msgs/TFMessage", "*", "")
        for topic, static in ((TF_TOPIC, False), (TF_STATIC_TOPIC, True)):
            sub = await self.node.subscribe(topic, self._receiver(static), kind)
            self.topics.append(sub.topic)

    async def close(self) -> None:
        """Unsubscribe from both."""
        for topic in self.topics:
            await self.node.unsubscribe(topic)
        self.topics.clear()

    def _receiver(self, static: bool) -> Callable[[list[Frame], InboundConnection, float], None]:
        def received(frames: list[Frame], conn: InboundConnection, now: float) -> None:
            received_ns = time.time_ns()
            who = (conn.header or {}).get("callerid") or conn.publisher_uri
            for frame in frames:
                try:
                    transforms = decode(frame)
                except (ValueError, struct.error) as err:
                    self._skip(who, err)
                    continue
                self.on_batch(Batch(received_ns, who, static, transforms))

        return received

    def _skip(self, who: str, err: Exception) -> None:
        from rostools.node.notice import Notice

        self.skipped[who] = self.skipped.get(who, 0) + 1
        if self.skipped[who] == 1:
            text = f"skipped a TF message from {who} that does not decode: {err}"
            self.node.notify(Notice("message_skipped", text, {"node": who, "reason": str(err)}))


def peek_frames(master: MasterProxy, found: set[str], left: Callable[[], float]) -> None:
    """Add to ``found`` the frames each ``/tf`` and ``/tf_static`` publisher sends first.

    Blocking and without a node (for completion): each publisher is asked for its topic and
    read until its first message, each wait bounded by ``left()`` seconds. ``found`` fills
    as answers come, so a caller that gives up keeps what arrived.
    """
    from rostools.rosgraph.masterapi import XmlRpcNode

    pubs = master.system_state()[0]
    for topic, nodes in pubs:
        if topic not in (TF_TOPIC, TF_STATIC_TOPIC):
            continue
        for name in nodes:
            uri = master.lookup_node(name)
            node = XmlRpcNode(uri, master.caller_id, left(), what=f"node {name}")
            answer = node.call("requestTopic", topic, [["TCPROS"]])
            if isinstance(answer, list) and len(answer) >= 3 and answer[0] == "TCPROS":
                for t in _first_message(str(answer[1]), int(answer[2]), topic, master, left):
                    found.update((t.parent, t.child))


def _first_message(
    host: str, port: int, topic: str, master: MasterProxy, left: Callable[[], float]
) -> list[Stamped]:
    """One publisher's first message on ``topic``: its transforms ([] if it sends none)."""
    import socket

    from rostools.wire.tcpros import (
        Accepted,
        Failed,
        Messages,
        SubscriberStream,
        subscriber_header,
    )

    header = subscriber_header(master.caller_id, topic, "*", "tf2_msgs/TFMessage", "", True)
    with socket.create_connection((host, port), timeout=left()) as sock:
        sock.sendall(header)  # it carries its own length
        stream = SubscriberStream()
        while True:
            sock.settimeout(left())
            buf = stream.get_buffer()
            n = sock.recv_into(buf)
            if n == 0:
                return []
            for event in stream.buffer_updated(n):
                if isinstance(event, Failed):
                    return []
                if isinstance(event, Messages):
                    try:
                        return decode(event.frames[0])
                    except (ValueError, struct.error):
                        return []
                assert isinstance(event, Accepted)
