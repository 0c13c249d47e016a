"""A topic subscriber: connects to every publisher, follows publisherUpdate, reconnects.

Frames are handed to the callback in batches, as they came off the socket, with the arrival
time: per-message work is the consumer's, in its own loop (hz at 200 kHz depends on it).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from rostools.graph.connection import Frame, InboundConnection
from rostools.graph.topic import TopicType
from rostools.graph.xmlrpc import call
from rostools.wire.tcpros import MAX_FRAME, subscriber_header

if TYPE_CHECKING:
    from rostools.graph.node import Node

log = logging.getLogger(__name__)

FramesCallback = Callable[[list[Frame], InboundConnection, float], None]
#: Waits between attempts to reach a publisher that is registered but not answering.
RETRY_FIRST, RETRY_MAX = 0.2, 5.0


class Subscriber:
    """Subscribes to one topic; ``type`` is learnt from the first publisher when it is ``*``."""

    def __init__(
        self,
        node: Node,
        topic: str,
        topic_type: TopicType,
        callback: FramesCallback,
        tcp_nodelay: bool = False,
        max_frame: int = MAX_FRAME,
    ) -> None:
        self.node = node
        self.topic = topic
        self.type = topic_type
        self.callback = callback
        self.tcp_nodelay = tcp_nodelay
        self.max_frame = max_frame
        self.publishers: set[str] = set()
        self.connections: dict[str, InboundConnection] = {}
        self.tasks: dict[str, asyncio.Task[None]] = {}
        self.closed = False
        self.on_header: Callable[[InboundConnection], None] | None = None

    def update(self, uris: list[str]) -> None:
        """The publishers now (from registerSubscriber or publisherUpdate)."""
        self.publishers = set(uris)
        for uri in uris:
            if uri not in self.tasks and not self.closed:
                task = asyncio.get_running_loop().create_task(self._follow(uri))
                self.tasks[uri] = task
                task.add_done_callback(self._forget_task)
        for uri in list(self.connections):
            if uri not in self.publishers:
                self.connections[uri].close()  # roscpp drops publishers no longer listed

    def _forget_task(self, task: asyncio.Task[None]) -> None:
        for uri, known in list(self.tasks.items()):
            if known is task:
                del self.tasks[uri]

    async def _follow(self, uri: str) -> None:
        """Stay connected to ``uri`` while it is listed as a publisher."""
        delay = RETRY_FIRST
        while not self.closed and uri in self.publishers:
            conn = await self._connect(uri)
            if conn is not None:
                delay = RETRY_FIRST
                await conn.closed
                self.connections.pop(uri, None)
            if self.closed or uri not in self.publishers:
                return
            await asyncio.sleep(delay)
            delay = min(delay * 2, RETRY_MAX)

    async def _connect(self, uri: str) -> InboundConnection | None:
        try:
            code, message, proto = await call(
                uri, "requestTopic", (self.node.name, self.topic, [["TCPROS"]])
            )
        except Exception as err:  # noqa: BLE001 - any failure means: try again later
            log.debug("requestTopic %s at %s failed: %s", self.topic, uri, err)
            return None
        if code != 1 or not isinstance(proto, list) or len(proto) < 3 or proto[0] != "TCPROS":
            log.debug("requestTopic %s at %s: %s %s", self.topic, uri, code, message)
            return None
        host, port = str(proto[1]), int(proto[2])
        header = subscriber_header(
            self.node.name, self.topic, self.type.md5sum, self.type.type, self.type.definition,
            self.tcp_nodelay,
        )  # fmt: skip
        loop = asyncio.get_running_loop()
        try:
            _, conn = await loop.create_connection(
                lambda: InboundConnection(self, uri, self.node.next_connection_id(), header),
                host,
                port,
            )
        except OSError as err:
            log.debug("connecting to %s:%s for %s failed: %s", host, port, self.topic, err)
            return None
        if self.closed:
            conn.close()
            return None
        self.connections[uri] = conn
        return conn

    def header_received(self, conn: InboundConnection) -> None:
        """A publisher answered: learn the type if we asked for ``*``."""
        if self.type.md5sum == "*" and conn.header is not None:
            self.type = TopicType.from_header(conn.header)
        if self.on_header is not None:
            self.on_header(conn)

    def frames_received(self, frames: list[Frame], conn: InboundConnection, now: float) -> None:
        """Messages arrived."""
        if not self.closed:
            self.callback(frames, conn, now)

    def connection_closed(self, conn: InboundConnection) -> None:
        """A connection went away (the follow task reconnects if it should)."""
        if self.connections.get(conn.publisher_uri) is conn:
            del self.connections[conn.publisher_uri]

    def stats(self) -> list[Any]:
        """rospy's getBusStats entries for this subscription."""
        return [
            [c.id, c.bytes_received, c.messages_received, -1, True]
            for c in self.connections.values()
        ]

    async def close(self) -> None:
        """Disconnect from every publisher."""
        self.closed = True
        for conn in list(self.connections.values()):
            conn.close()
        for task in list(self.tasks.values()):
            task.cancel()
        for task in list(self.tasks.values()):
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await task
