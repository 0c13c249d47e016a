"""One WebSocket client of the bridge: its subscriptions, their queues, and the one writer.

The ROS side never waits on a client. A message for a client goes into that subscription's
own bounded queue, and returns; the client's writer task sends, one message of each waiting
subscription in turn, so a topic of big messages cannot starve a small one. A full queue
drops its oldest message ("latest wins"), and the drop is counted.
"""

from __future__ import annotations

import asyncio
import collections
import logging
import struct
from collections.abc import Awaitable, Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

from rostools.node.connection import Frame
from rostools.wire import foxglove

log = logging.getLogger(__name__)

#: Messages a subscription queues for a client that reads slower than they come.
QUEUE_MESSAGES = 100
#: Bytes a subscription queues; its newest message is always kept, whatever its size, so a
#: stalled client holds at most this, or one message, per subscription.
QUEUE_BYTES = 8 * 1024 * 1024
#: Subscriptions one client may hold at once (a subscription flood is refused past it).
MAX_SUBSCRIPTIONS = 1024
#: Control messages (statuses, advertisements, time) waiting for a client that does not read:
#: past this many it is let go, as a client that floods us with refusals and reads nothing.
MAX_CONTROL = 10_000
#: Messages at least this big go to the connection's transport behind a frame header of our
#: own (``DirectWrite``): ``websockets`` would copy each three times first (our join of the
#: prefix, its frame's ``BytesIO``, and the slice asyncio keeps of what the socket did not
#: take at once), which was most of the bridge's CPU for big images and point clouds.
DIRECT_WRITE = 64 * 1024


#: A message as a subscription renders it: text, bytes, or bytes then a frame as it came (sent
#: as one binary message without joining them: see ``DirectWrite``).
Rendered = str | bytes | tuple[bytes, Frame]


class Socket(Protocol):
    """What the writer needs of a WebSocket connection (``websockets``' has it)."""

    async def send(self, message: str | bytes) -> None:
        """Send one message, waiting while the socket's buffer is full."""
        ...


@dataclass
class Subscription:
    """A client's subscription to one channel."""

    id: int
    channel: int
    topic: str
    #: Seconds between two messages sent (0: every one): the bridge's ``--max-rate`` for the
    #: topic, or the client's own ``maxRate``, whichever is slower.
    interval: float = 0.0
    queue: collections.deque[tuple[int, Frame]] = field(default_factory=collections.deque)
    #: Messages it queues at most (its bytes are bounded by ``QUEUE_BYTES`` whatever this is).
    limit: int = QUEUE_MESSAGES
    #: What a message is sent as, made when it is sent (a rosbridge client's JSON, CBOR or
    #: fragments); None: the Foxglove protocol's binary message, undecoded.
    render: Callable[[int, Frame], Sequence[Rendered]] | None = None
    queued_bytes: int = 0
    last_taken: float = 0.0
    sent: int = 0
    sent_bytes: int = 0
    dropped: int = 0
    throttled: int = 0


@dataclass
class ClientStats:
    """What one client was sent and what it missed, for the live table."""

    messages: int = 0
    bytes: int = 0
    dropped: int = 0
    throttled: int = 0


class Client:
    """A connected WebSocket client."""

    #: Whether it speaks the Foxglove protocol (what ``BridgeState.broadcast`` sends).
    foxglove = True

    def __init__(self, socket: Socket, name: str, on_gone: Callable[[Client], None]) -> None:
        self.socket = socket
        self.name = name
        self.on_gone = on_gone
        self.subscriptions: dict[int, Subscription] = {}
        #: Channels the client advertised (its id -> the ROS topic it publishes).
        self.channels: dict[int, str] = {}
        #: Parameter names it follows, and whether it follows the connection graph.
        self.parameters: set[str] = set()
        self.graph = False
        self.closed = False
        self._waiting: collections.OrderedDict[int, None] = collections.OrderedDict()
        self._control: collections.deque[str | bytes] = collections.deque()
        self._wake = asyncio.Event()
        self._direct = DirectWrite.of(socket)
        self.writer = asyncio.get_running_loop().create_task(self._write())

    # what the bridge hands over ------------------------------------------------------------

    def offer(self, sub: Subscription, stamp: int, frame: Frame, now: float) -> None:
        """Queue one message for ``sub``; never waits."""
        if sub.interval and now - sub.last_taken < sub.interval:
            sub.throttled += 1
            return
        sub.last_taken = now
        sub.queue.append((stamp, frame))
        sub.queued_bytes += len(frame)
        while len(sub.queue) > 1 and (len(sub.queue) > sub.limit or sub.queued_bytes > QUEUE_BYTES):
            _, old = sub.queue.popleft()
            sub.queued_bytes -= len(old)
            sub.dropped += 1
        self._waiting[sub.id] = None
        self._wake.set()

    def send(self, message: dict[str, Any] | str | bytes) -> None:
        """Queue a control message (JSON as a dict or text, or binary), sent before any data."""
        if self.closed:
            return
        if len(self._control) >= MAX_CONTROL:
            log.info("client %s reads nothing: let go", self.name)
            self.close()
            return
        self._control.append(foxglove.dumps(message) if isinstance(message, dict) else message)
        self._wake.set()

    def status(self, level: int, text: str) -> None:
        """Tell the client something in a ``status`` message."""
        self.send({"op": "status", "level": level, "message": text})

    def unsubscribe(self, sub_id: int) -> Subscription | None:
        """Forget a subscription and what it had queued."""
        sub = self.subscriptions.pop(sub_id, None)
        self._waiting.pop(sub_id, None)
        return sub

    @property
    def stats(self) -> ClientStats:
        """Totals over the client's subscriptions."""
        out = ClientStats()
        for sub in self.subscriptions.values():
            out.messages += sub.sent
            out.bytes += sub.sent_bytes
            out.dropped += sub.dropped
            out.throttled += sub.throttled
        return out

    def close(self) -> None:
        """Stop writing, and tell the server (``on_gone``) to close the socket."""
        if self.closed:
            return
        self.closed = True
        self.writer.cancel()
        self.on_gone(self)

    # the writer --------------------------------------------------------------------------

    async def _write(self) -> None:
        try:
            while not self.closed:
                await self._wake.wait()
                self._wake.clear()
                await self._drain()
        except asyncio.CancelledError:
            raise
        except Exception as err:  # noqa: BLE001 - a socket gone mid-send ends this client only
            log.debug("client %s: %s", self.name, err)
        self.close()

    async def _drain(self) -> None:
        """Send everything waiting: control messages first, then a message per topic in turn."""
        while self._control or self._waiting:
            while self._control:
                await self.socket.send(self._control.popleft())
            if not self._waiting:
                return
            sub_id, _ = self._waiting.popitem(last=False)
            sub = self.subscriptions.get(sub_id)
            if sub is None or not sub.queue:
                continue
            stamp, frame = sub.queue.popleft()
            sub.queued_bytes -= len(frame)
            if sub.queue:
                self._waiting[sub_id] = None  # its turn comes again after the others'
            if sub.render is not None:
                for part in sub.render(stamp, frame):
                    if isinstance(part, tuple):
                        await self._send_binary(*part)
                    elif isinstance(part, str) and len(part) >= DIRECT_WRITE:
                        await self._send_text(part)
                    else:
                        await self.socket.send(part)
            else:
                await self._send_data(sub, stamp, frame)
            sub.sent += 1
            sub.sent_bytes += len(frame)

    async def _send_data(self, sub: Subscription, stamp: int, frame: Frame) -> None:
        """One Foxglove ``messageData``: its prefix, then the frame as it came."""
        await self._send_binary(foxglove.message_data(sub.id, stamp), frame)

    async def _send_text(self, text: str) -> None:
        """One big text message (rosbridge's JSON), framed here as for binary ones."""
        if self._direct is not None and self._direct.ready():
            await self._direct.send(b"", text.encode(), text=True)
        else:
            await self.socket.send(text)

    async def _send_binary(self, head: bytes, frame: Frame) -> None:
        """One binary message of ``head`` then ``frame``, a big frame uncopied."""
        if self._direct is not None and len(frame) >= DIRECT_WRITE and self._direct.ready():
            await self._direct.send(head, frame)
        else:
            await self.socket.send(b"".join((head, frame)))


class DirectWrite:
    """Big messages written to a ``websockets`` connection's transport, uncopied.

    The frame is the one ``websockets`` would send (FIN, binary or text, unmasked), its
    header and the message's prefix in one write and the message itself in another, so the
    message is copied once, into the transport's buffer, and only for what the socket does
    not take at once. Flow control is the connection's own (``drain``: ``WRITE_LIMIT``).
    Frames go out whole and in order on the one loop, so pings and control messages still
    fall between messages. Only an open connection without extensions, and outside a
    fragmented message, is written so; anything else goes through ``send``.
    """

    def __init__(self, socket: Any, open_state: object) -> None:
        self.socket = socket
        self.open_state = open_state
        self.drain: Callable[[], Awaitable[None]] = socket.drain

    @classmethod
    def of(cls, socket: object) -> DirectWrite | None:
        """The direct writer of a ``websockets`` asyncio connection; None for anything else."""
        if not all(hasattr(socket, a) for a in ("transport", "protocol", "drain")):
            return None
        try:
            from websockets.protocol import State
        except ImportError:  # pragma: no cover - websockets is a dependency
            return None
        return cls(socket, State.OPEN)

    def ready(self) -> bool:
        """Whether a message may be written directly now."""
        sock = self.socket
        protocol = sock.protocol
        return (
            protocol.state is self.open_state
            and not protocol.extensions
            and getattr(sock, "send_in_progress", None) is None
            and not sock.transport.is_closing()
        )

    async def send(self, head: bytes, frame: Frame, text: bool = False) -> None:
        """One message: ``head`` then ``frame``; waits while the transport is full."""
        transport = self.socket.transport
        transport.write(frame_header(len(head) + len(frame), text) + head)
        transport.write(frame)
        await self.drain()


def frame_header(length: int, text: bool = False) -> bytes:
    """A server's WebSocket frame header of a whole binary or text message (RFC 6455, 5.2)."""
    first = 0x81 if text else 0x82
    if length < 126:
        return struct.pack("!BB", first, length)
    if length < 65536:
        return struct.pack("!BBH", first, 126, length)
    return struct.pack("!BBQ", first, 127, length)
