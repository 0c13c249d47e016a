"""TCPROS connections on asyncio: the thin IO layer over ``rostools.wire.tcpros``.

``ServerConnection`` is what a node's TCPROS server accepts; its first frame (the header) says
whether it is a subscriber (then an ``Outbound`` link sends it messages) or a service client.
``InboundConnection`` is a subscriber's connection to a publisher.
"""

from __future__ import annotations

import asyncio
import collections
import contextlib
import logging
import select
import socket
import time
from collections.abc import Callable
from typing import Any, Protocol

from rostools.errors import one_line
from rostools.rosgraph.network import Failure
from rostools.wire.header import MAX_HEADER_LENGTH
from rostools.wire.tcpros import (
    BIG_FRAME,
    HANDSHAKE_TIMEOUT,
    MAX_FRAME,
    Accepted,
    FrameError,
    FrameReader,
    Messages,
    SubscriberStream,
    frame_prefix,
    parse_header,
)

log = logging.getLogger(__name__)

Frame = bytes | memoryview
#: Outgoing bytes buffered per connection before we stop writing and queue messages instead.
WRITE_HIGH_WATER = 4 * 1024 * 1024
WRITE_LOW_WATER = 1024 * 1024
#: Reads smaller than this may wait for company (``Receiver.coalesce``); a busy socket fills
#: bigger reads than this and is never held back.
COALESCE_BELOW = 64 * 1024
#: Connections to one TCPROS server that have not sent their header yet: past this many, the
#: oldest are dropped. roscpp listens with a backlog of 100 (``MAX_TCPROS_CONN_QUEUE``) and
#: rospy and roscpp keep any number waiting, each with its buffers, for good.
MAX_PENDING = 100
#: Seconds between going past MAX_PENDING and dropping the oldest: a burst of real peers
#: (a recorder subscribing to 1,000 topics at once) is accepted faster than its headers,
#: which wait in the sockets, are read; by then they have been.
PENDING_GRACE = 1.0
#: Where a subscriber's bytes after its header go: a subscriber sends nothing then, and the
#: link only reads to see the connection close. One for all links; nobody reads it.
_ignored = bytearray(4096)


def set_nodelay(transport: asyncio.BaseTransport) -> None:
    """TCP_NODELAY, as ROS sets it on topic connections that ask for it."""
    sock = transport.get_extra_info("socket")
    if sock is not None:
        with contextlib.suppress(OSError):
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)


class ConnectionHandler(Protocol):
    """What an accepted connection hands its traffic to after the header."""

    def frames_received(self, frames: list[Frame]) -> None:
        """Frames after the header."""

    def connection_lost(self) -> None:
        """The peer went away."""

    def pause_writing(self) -> None:
        """Our send buffer is full."""

    def resume_writing(self) -> None:
        """Our send buffer drained."""


class Pending:
    """The connections of one TCPROS server that have not sent their header yet, oldest first.

    Past ``limit``, the oldest are dropped (``PENDING_GRACE`` later): a peer that opens
    connections and says nothing cannot hold more than ``limit`` of them for long, and a real
    peer, which sends its header at once, is never the oldest for long.
    """

    def __init__(self, limit: int = MAX_PENDING) -> None:
        self.limit = limit
        self._waiting: dict[ServerConnection, None] = {}  # insertion order: oldest first
        self._trim: asyncio.TimerHandle | None = None
        #: Connections dropped for the limit so far.
        self.dropped = 0

    def add(self, conn: ServerConnection) -> None:
        """A new connection waits for its header; past the limit, the oldest will go."""
        self._waiting[conn] = None
        if len(self._waiting) > self.limit and self._trim is None:
            self._trim = asyncio.get_running_loop().call_later(PENDING_GRACE, self._drop_oldest)

    def _drop_oldest(self) -> None:
        self._trim = None
        # A loaded loop can reach this before it has read headers that already wait in the
        # sockets: those peers have spoken, and only the silent ones are dropped.
        spoke = _readable(self._waiting)
        silent = [conn for conn in self._waiting if conn not in spoke]
        for oldest in silent[: max(0, len(self._waiting) - self.limit)]:
            del self._waiting[oldest]
            self.dropped += 1
            # One line per server, not one per connection of a flood.
            report = log.warning if self.dropped == 1 else log.debug
            report(
                "more than %d TCPROS connections are waiting for their header; dropping the "
                "oldest, from %s", self.limit, oldest.peer,
            )  # fmt: skip
            oldest.abort()
        if len(self._waiting) > self.limit:  # the speakers' headers are read by then
            self._trim = asyncio.get_running_loop().call_later(PENDING_GRACE, self._drop_oldest)

    def discard(self, conn: ServerConnection) -> None:
        """``conn`` sent its header or closed."""
        self._waiting.pop(conn, None)


def _readable(conns: dict[ServerConnection, None]) -> set[ServerConnection]:
    """Those of ``conns`` whose sockets hold bytes not read yet (poll: no FD_SETSIZE limit)."""
    by_fd: dict[int, ServerConnection] = {}
    poller = select.poll()
    for conn in conns:
        sock = conn.transport.get_extra_info("socket") if conn.transport else None
        if sock is not None and sock.fileno() >= 0:
            by_fd[sock.fileno()] = conn
            poller.register(sock.fileno(), select.POLLIN)
    return {by_fd[fd] for fd, _ in poller.poll(0)}


class ServerConnection(asyncio.BufferedProtocol):
    """A connection accepted by a node's TCPROS server.

    It costs no receive buffer until bytes arrive (``FrameReader``), waits among its server's
    ``pending`` connections until its header comes, and reads a subscriber's link into a
    shared buffer that nobody reads.
    """

    def __init__(
        self,
        accept: Callable[[dict[str, str], ServerConnection], ConnectionHandler | None],
        pending: Pending | None = None,
    ) -> None:
        self.accept = accept
        self.pending = pending
        self.reader: FrameReader | None = FrameReader(MAX_FRAME, first_max=MAX_HEADER_LENGTH)
        self.transport: asyncio.Transport | None = None
        self.handler: ConnectionHandler | None = None
        self.peer = "?"
        self._deadline: asyncio.TimerHandle | None = None

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        """Asyncio: connected; the peer has ``HANDSHAKE_TIMEOUT`` to send its header."""
        assert isinstance(transport, asyncio.Transport)
        self.transport = transport
        transport.set_write_buffer_limits(WRITE_HIGH_WATER, WRITE_LOW_WATER)
        peer = transport.get_extra_info("peername")
        self.peer = f"{peer[0]}:{peer[1]}" if peer else "?"
        loop = asyncio.get_running_loop()
        self._deadline = loop.call_later(HANDSHAKE_TIMEOUT, self._handshake_expired)
        if self.pending is not None:
            self.pending.add(self)

    def _handshake_expired(self) -> None:
        self._deadline = None
        if self.handler is None and self.transport is not None:
            log.warning("TCPROS connection from %s sent no header in time; closing it", self.peer)
            self.transport.abort()

    def _handshake_over(self) -> None:
        if self._deadline is not None:
            self._deadline.cancel()
            self._deadline = None
        if self.pending is not None:
            self.pending.discard(self)

    def get_buffer(self, sizehint: int) -> memoryview:
        """Asyncio: where to receive into."""
        if self.reader is None:
            return memoryview(_ignored)
        return self.reader.get_buffer()

    def buffer_updated(self, nbytes: int) -> None:
        """Asyncio: bytes arrived."""
        if self.reader is None:
            return
        try:
            frames = self.reader.buffer_updated(nbytes)
        except FrameError as err:
            log.warning("TCPROS connection from %s: %s; closing it", self.peer, one_line(err))
            self.close()
            return
        if self.handler is None and frames:
            self._handshake_over()
            try:
                fields = parse_header(frames[0])
            except FrameError as err:
                log.warning("TCPROS connection from %s: %s; closing it", self.peer, one_line(err))
                self.close()
                return
            self.handler = self.accept(fields, self)
            frames = frames[1:]
            if self.handler is None:
                return
            if isinstance(self.handler, Outbound):
                self.reader = None  # a subscriber says nothing after its header
                return
        if frames and self.handler is not None:
            self.handler.frames_received(frames)

    def write(self, data: Frame) -> None:
        """Send bytes as they are."""
        if self.transport is not None and not self.transport.is_closing():
            self.transport.write(data)

    def close(self) -> None:
        """Close after what is buffered is sent."""
        if self.transport is not None:
            self.transport.close()

    def abort(self) -> None:
        """Close now, dropping what is buffered."""
        if self.transport is not None:
            self.transport.abort()

    def connection_lost(self, exc: Exception | None) -> None:
        """Asyncio: the connection closed."""
        self._handshake_over()
        self.reader = None
        if self.handler is not None:
            self.handler.connection_lost()

    def pause_writing(self) -> None:
        """Asyncio: the send buffer is full."""
        if self.handler is not None:
            self.handler.pause_writing()

    def resume_writing(self) -> None:
        """Asyncio: the send buffer drained."""
        if self.handler is not None:
            self.handler.resume_writing()


class Outbound:
    """A publisher's link to one subscriber: coalesced writes and a bounded backlog.

    Small frames published in one event-loop turn go out in one write (one syscall for many
    messages). While the socket is backed up, messages wait in a queue of ``queue_size``
    whose oldest entries are dropped, so a slow subscriber never stalls the others.
    """

    def __init__(self, conn: ServerConnection, conn_id: int, peer: str, queue_size: int) -> None:
        self.conn = conn
        self.id = conn_id
        self.peer = peer  # the subscriber's caller id
        self.backlog: collections.deque[tuple[bytes, Frame]] = collections.deque(
            maxlen=max(queue_size, 1)
        )
        self.pending: list[Frame] = []
        self.paused = False
        self.scheduled = False
        self.closed = False
        self.bytes_sent = 0
        self.messages_sent = 0
        self.dropped = 0
        self.on_close: Callable[[Outbound], None] | None = None

    def send(self, payload: Frame) -> None:
        """Queue one message."""
        if self.closed:
            return
        prefix = frame_prefix(len(payload))
        if self.paused:
            if len(self.backlog) == self.backlog.maxlen:
                self.dropped += 1
            self.backlog.append((prefix, payload))
            return
        self._write(prefix, payload)

    def _write(self, prefix: bytes, payload: Frame) -> None:
        self.bytes_sent += len(payload)
        self.messages_sent += 1
        if len(payload) >= BIG_FRAME:
            self.flush()
            self.conn.write(prefix)
            self.conn.write(payload)  # no join: a big payload is written without a copy
            return
        self.pending += (prefix, payload)
        if not self.scheduled:
            self.scheduled = True
            asyncio.get_running_loop().call_soon(self.flush)

    def flush(self) -> None:
        """Write what this loop turn queued, in one write."""
        self.scheduled = False
        if self.pending:
            self.conn.write(b"".join(self.pending))
            self.pending.clear()

    def frames_received(self, frames: list[Frame]) -> None:
        """Subscribers send nothing after their header; ignore it."""

    def pause_writing(self) -> None:
        """The socket is backed up: queue from now on."""
        self.paused = True

    def resume_writing(self) -> None:
        """The socket drained: send the queue."""
        self.paused = False
        while self.backlog and not self.paused:
            self._write(*self.backlog.popleft())

    def connection_lost(self) -> None:
        """The subscriber went away."""
        self.closed = True
        if self.on_close is not None:
            self.on_close(self)

    def close(self) -> None:
        """Close the link."""
        self.flush()
        self.closed = True
        self.conn.close()


class Receiver(Protocol):
    """What an inbound connection reports to: its subscriber (``ConnectionHandler``: a server)."""

    topic: str
    #: The largest frame it accepts.
    max_frame: int
    #: Seconds a small read waits for company before the next (0: none).
    coalesce: float
    #: Whether it is done with each frame when ``frames_received`` returns (``FrameReader.reuse``).
    reuse_frames: bool

    def header_received(self, conn: InboundConnection) -> None:
        """The publisher's header arrived and passed the checks."""

    def frames_received(self, frames: list[Frame], conn: InboundConnection, now: float) -> None:
        """Messages, raw, with the time they were read."""

    def connection_closed(self, conn: InboundConnection) -> None:
        """The connection is gone (``conn.failure`` says why, if it failed)."""


class InboundConnection(asyncio.BufferedProtocol):
    """A subscriber's connection to one publisher."""

    def __init__(
        self,
        subscriber: Receiver,
        publisher_uri: str,
        conn_id: int,
        header: bytes,
        handshake: float = HANDSHAKE_TIMEOUT,
    ) -> None:
        self.subscriber = subscriber
        self.publisher_uri = publisher_uri
        self.id = conn_id
        self.request = header
        self.session = SubscriberStream(subscriber.max_frame)
        self.session.reader.reuse = subscriber.reuse_frames
        self.transport: asyncio.Transport | None = None
        self.header: dict[str, str] | None = None
        self.closed: asyncio.Future[None] = asyncio.get_running_loop().create_future()
        self.bytes_received = 0
        self.messages_received = 0
        self.peer = "?"
        #: Why we dropped the connection, when we did.
        self.failure: Failure | None = None
        #: How long the publisher has to send its header, and whether it ran out.
        self.handshake = handshake
        self.timed_out = False
        self._deadline: asyncio.TimerHandle | None = None

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        """Asyncio: connected."""
        assert isinstance(transport, asyncio.Transport)
        self.transport = transport
        set_nodelay(transport)
        peer = transport.get_extra_info("peername")
        self.peer = f"{peer[0]}:{peer[1]}" if peer else "?"
        transport.write(self.request)
        loop = asyncio.get_running_loop()
        self._deadline = loop.call_later(self.handshake, self._handshake_expired)

    def _handshake_expired(self) -> None:
        self._deadline = None
        if self.header is None and self.failure is None and not self.closed.done():
            self.timed_out = True
            self._drop(f"no connection header within {self.handshake:g} s")

    def _handshake_over(self) -> None:
        if self._deadline is not None:
            self._deadline.cancel()
            self._deadline = None

    def get_buffer(self, sizehint: int) -> memoryview:
        """Asyncio: where to receive into."""
        return self.session.get_buffer()

    def buffer_updated(self, nbytes: int) -> None:
        """Asyncio: bytes arrived."""
        now = time.monotonic()
        small = False
        for event in self.session.buffer_updated(nbytes):
            if isinstance(event, Messages):
                self.messages_received += len(event.frames)
                self.bytes_received += nbytes  # what arrived on the wire, prefixes included
                small = len(event.frames[0]) < BIG_FRAME  # a big frame comes alone
                self.subscriber.frames_received(event.frames, self, now)
            elif isinstance(event, Accepted):
                self._handshake_over()
                self.header = event.header
                self.subscriber.header_received(self)
            else:
                self._drop(event.reason)
        wait = self.subscriber.coalesce
        if (
            wait
            and small
            and nbytes < COALESCE_BELOW
            and not self.session.reader.mid_big_frame
            and self.transport is not None
            and not self.transport.is_closing()
        ):
            # Small messages, a few at a time: pause, so that what comes next arrives as one
            # read, not as a wake-up per message. Big frames and busy sockets never wait.
            self.transport.pause_reading()
            asyncio.get_running_loop().call_later(wait, self._resume)

    def _resume(self) -> None:
        if self.transport is not None and not self.transport.is_closing():
            self.transport.resume_reading()

    def _drop(self, reason: str) -> None:
        # the subscriber reports it once (a publisher that keeps refusing is not a flood)
        log.debug(
            "subscription to %s from %s: %s", self.subscriber.topic, self.publisher_uri, reason
        )
        self.failure = Failure(reason, dropped=self.header is not None)
        self.close()

    def close(self) -> None:
        """Close the connection."""
        if self.transport is not None:
            self.transport.close()

    def connection_lost(self, exc: Exception | None) -> None:
        """Asyncio: the connection closed."""
        self._handshake_over()
        if not self.closed.done():
            self.closed.set_result(None)
        self.subscriber.connection_closed(self)

    @property
    def latching(self) -> bool:
        """Whether the publisher latches."""
        return (self.header or {}).get("latching") == "1"

    def info(self) -> dict[str, Any]:
        """The publisher's header fields."""
        return dict(self.header or {})
