"""Services over TCPROS (wiki.ros.org/ROS/TCPROS): servers, clients, and the type probe.

A client call never hangs: every step has a timeout, and a server that dies mid-call, refuses
the request or answers garbage raises one of our errors with a one-line reason.
"""

from __future__ import annotations

import asyncio
import collections
import inspect
import logging
import socket
from collections.abc import Awaitable, Callable
from typing import TYPE_CHECKING
from urllib.parse import urlsplit

from rostools.errors import (
    RostoolsError,
    ServiceError,
    TimeoutExpired,
    UnreachableError,
)
from rostools.msgs.topictype import ServiceType
from rostools.node.connection import Frame, ServerConnection, set_nodelay
from rostools.rosgraph.masterapi import SERVICE_TIMEOUT
from rostools.wire.tcpros import (
    FrameError,
    ResponseReader,
    check_service_request,
    error_header,
    frame,
    service_reply_header,
    service_request_header,
    service_response,
)

if TYPE_CHECKING:
    from rostools.node.endpoint import Owner

log = logging.getLogger(__name__)

#: A handler gets the serialised request and returns the serialised response.
ServiceHandler = Callable[[bytes], bytes | Awaitable[bytes]]
#: A client receives into one buffer of this size; a bigger response takes several reads.
RECEIVE_CHUNK = 64 * 1024
#: Calls in a row that may complete without a turn of the event loop (``_read_now``).
EAGER_READS = 16


class ServiceServer:
    """Serves one service; ``handler`` may raise ``ServiceError`` to answer a failure."""

    def __init__(
        self, node: Owner, name: str, srv_type: ServiceType, handler: ServiceHandler
    ) -> None:
        self.node = node
        self.name = name
        self.type = srv_type
        self.handler = handler
        self.connections: set[ServerConnection] = set()
        self.calls = 0

    @property
    def uri(self) -> str:
        """The rosrpc URI clients connect to."""
        return f"rosrpc://{self.node.host}:{self.node.tcpros_port}"

    def accept(self, fields: dict[str, str], conn: ServerConnection) -> _ServiceLink | None:
        """A client's header arrived: check it, answer, serve."""
        problem = check_service_request(fields, self.name, self.type.md5sum)
        if problem is not None:
            conn.write(error_header(problem))
            conn.close()
            return None
        conn.write(
            service_reply_header(self.node.name, self.name, self.type.md5sum, self.type.type)
        )
        if fields.get("probe") == "1":
            conn.close()  # rospy ends a probe right after its header
            return None
        persistent = fields.get("persistent", "0").lower() in ("1", "true")
        self.connections.add(conn)
        return _ServiceLink(self, conn, persistent)

    def close(self) -> None:
        """Close every client connection."""
        for conn in list(self.connections):
            conn.close()


class _ServiceLink:
    """One client connection: requests in order, one response each."""

    def __init__(self, server: ServiceServer, conn: ServerConnection, persistent: bool) -> None:
        self.server = server
        self.conn = conn
        self.persistent = persistent
        self.queue: list[Frame] = []
        self.busy = False

    def frames_received(self, frames: list[Frame]) -> None:
        self.queue.extend(frames)
        if not self.busy:
            self.busy = True
            asyncio.get_running_loop().create_task(self._serve())

    async def _serve(self) -> None:
        try:
            while self.queue:
                request = bytes(self.queue.pop(0))
                self.server.calls += 1
                try:
                    result = self.server.handler(request)
                    if inspect.isawaitable(result):
                        result = await result
                    reply = service_response(True, bytes(result))
                except ServiceError as err:
                    reply = service_response(
                        False, f"service cannot process request: {err}".encode()
                    )
                except Exception as err:  # noqa: BLE001 - the handler's failure goes to the client
                    why = str(err) or type(err).__name__  # the handler's words, as rospy sends
                    reply = service_response(False, f"error processing request: {why}".encode())
                self.conn.write(reply)
                if not self.persistent:
                    self.conn.close()
                    return
        finally:
            self.busy = False

    def connection_lost(self) -> None:
        self.server.connections.discard(self.conn)

    def pause_writing(self) -> None:
        """Responses are small; nothing to hold back."""

    def resume_writing(self) -> None:
        """See pause_writing."""


class _ClientProtocol(asyncio.BufferedProtocol):
    """A client connection: the reply header, then one response per request, in order.

    Calls may be pipelined: each ``send`` queues a future, and responses resolve them in the
    order the requests went out (a service answers one request at a time, in order). Replies
    are received into one reused buffer: asyncio's default ``recv`` allocates 256 KiB per
    read, which malloc serves with mmap and munmap, three system calls per call.
    """

    def __init__(self) -> None:
        loop = asyncio.get_running_loop()
        self.loop = loop
        self.reader = ResponseReader()
        self.header: asyncio.Future[dict[str, str]] = loop.create_future()
        #: A future and a deadline for each request sent, in order.
        self.waiters: collections.deque[tuple[asyncio.Future[tuple[bool, bytes]], float]] = (
            collections.deque()
        )
        self.failure: BaseException | None = None
        self.transport: asyncio.Transport | None = None
        self._view = memoryview(bytearray(RECEIVE_CHUNK))
        self._timer: asyncio.TimerHandle | None = None
        self._timer_at = 0.0
        #: Our own socket, for reads that need not wait for the loop (``_read_now``).
        self.sock: socket.socket | None = None
        self._eager = 0

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        """Asyncio: connected."""
        assert isinstance(transport, asyncio.Transport)
        self.transport = transport
        set_nodelay(transport)

    def get_buffer(self, sizehint: int) -> memoryview:
        """Asyncio: where the next bytes go."""
        return self._view

    def buffer_updated(self, nbytes: int) -> None:
        """Asyncio: ``nbytes`` arrived."""
        try:
            responses = self.reader.feed(self._view[:nbytes])
        except FrameError as err:
            self.fail(RostoolsError(f"garbage from the service: {err}"))
            return
        if not self.header.done() and self.reader.header is not None:
            self.header.set_result(self.reader.header)
        waiters = self.waiters
        for response in responses:
            if not waiters:
                self.fail(RostoolsError("the service sent a response nobody asked for"))
                return
            future = waiters.popleft()[0]
            if not future.done():  # a caller cancelled: its response is dropped
                future.set_result(response)

    def send(self, data: bytes, deadline: float) -> asyncio.Future[tuple[bool, bytes]]:
        """Write one request; its response, when it arrives (it may have, already)."""
        future: asyncio.Future[tuple[bool, bytes]] = self.loop.create_future()
        if self.failure is not None:
            future.set_exception(self.failure)
            return future
        assert self.transport is not None
        self.waiters.append((future, deadline))
        self.transport.write(data)
        # One timer watches every call on the connection: a timer per call costs a handle and
        # a heap push and pull, a fifth of what a fast call costs.
        if self._timer is None or deadline < self._timer_at:
            self._arm(deadline)
        if self.sock is not None:
            self._read_now()
        return future

    def _read_now(self) -> None:
        """Read what has arrived without waiting for the event loop.

        On loopback a server often runs on our CPU as soon as the request is sent, and its
        response is in the socket when ``write`` returns: read now, and the call completes
        without two turns of the event loop and an epoll_wait (a third of its cost). Every
        ``EAGER_READS``th call waits for the loop instead, so a caller that never has to wait
        still lets other tasks run.
        """
        self._eager += 1
        if self._eager > EAGER_READS:
            self._eager = 0
            return
        assert self.sock is not None
        try:
            nbytes = self.sock.recv_into(self._view)
        except OSError:  # nothing yet (EAGAIN), or an error the transport will report
            return
        if nbytes:  # 0 is the end of the stream, which the transport sees too
            self.buffer_updated(nbytes)

    def _arm(self, when: float) -> None:
        if self._timer is not None:
            self._timer.cancel()
        self._timer_at = when
        self._timer = self.loop.call_at(when, self._check_deadlines)

    def _check_deadlines(self) -> None:
        self._timer = None
        if not self.waiters:
            return
        now = self.loop.time()
        earliest = min(deadline for _, deadline in self.waiters)
        if earliest > now:
            self._arm(earliest)
            return
        # A service that does not answer in time is dropped: a response that came later would
        # be taken for the next call's.
        self.fail(_NoResponseError())

    def fail(self, err: BaseException) -> None:
        """Fail every call waiting here and close the connection."""
        if self.failure is None:
            self.failure = err
        if not self.header.done():
            self.header.set_exception(err)
        while self.waiters:
            future = self.waiters.popleft()[0]
            if not future.done():
                future.set_exception(err)
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        if self.transport is not None:
            self.transport.close()

    @property
    def usable(self) -> bool:
        """Whether another request may go out on this connection."""
        return (
            self.failure is None and self.transport is not None and not self.transport.is_closing()
        )

    def connection_lost(self, exc: Exception | None) -> None:
        """Asyncio: the connection closed."""
        self.fail(ConnectionError("the service closed the connection"))


class _NoResponseError(Exception):
    """A call's deadline passed: the connection was dropped."""


async def _open_connection(host: str, port: int) -> _ClientProtocol:
    """Connect a client protocol on a socket of our own (asyncio's is not to be read)."""
    loop = asyncio.get_running_loop()
    infos = await loop.getaddrinfo(host, port, type=socket.SOCK_STREAM)
    failure: OSError = OSError(f"{host} has no address")
    for family, kind, proto_number, _, address in infos:
        sock = socket.socket(family, kind, proto_number)
        try:
            sock.setblocking(False)
            await loop.sock_connect(sock, address)
            _, proto = await loop.create_connection(_ClientProtocol, sock=sock)
        except OSError as err:
            sock.close()
            failure = err
            continue
        except BaseException:
            sock.close()
            raise
        proto.sock = sock
        return proto
    raise failure


async def lookup_service(node: Owner, name: str) -> tuple[str, int]:
    """Host and port of a service's provider."""
    uri = await node.master.lookup_service(name)
    parts = urlsplit(str(uri))
    if parts.scheme != "rosrpc" or not parts.hostname or not parts.port:
        raise RostoolsError(f"the master gave {name} a bad URI: {uri}")
    return parts.hostname, parts.port


class ServiceClient:
    """Calls one service; ``persistent`` keeps the connection for the next call.

    Concurrent calls on a persistent client share its connection, pipelined: each waits for
    its own response. A failed call drops the connection, and the next call connects anew.
    """

    def __init__(
        self, node: Owner, name: str, srv_type: ServiceType | None = None, persistent: bool = False
    ) -> None:
        self.node = node
        self.name = name
        self.type = srv_type
        self.persistent = persistent
        self._proto: _ClientProtocol | None = None
        #: The connection being opened, which concurrent first calls share.
        self._opening: asyncio.Future[_ClientProtocol] | None = None

    async def _connect(self, probe: bool, timeout: float) -> tuple[_ClientProtocol, dict[str, str]]:
        host, port = await lookup_service(self.node, self.name)
        md5 = "*" if probe or self.type is None else self.type.md5sum
        header = service_request_header(
            self.node.name, self.name, md5, persistent=self.persistent and not probe, probe=probe
        )
        try:
            proto = await asyncio.wait_for(_open_connection(host, port), timeout)
        except (OSError, asyncio.TimeoutError) as err:
            raise UnreachableError(
                f"cannot connect to service {self.name} at {host}:{port}: {err or 'timed out'}"
            ) from err
        assert proto.transport is not None
        proto.transport.write(header)
        try:
            fields = await asyncio.wait_for(proto.header, timeout)
        except asyncio.TimeoutError:
            proto.transport.close()
            raise TimeoutExpired(
                f"service {self.name} did not answer within {timeout:g} s"
            ) from None
        except ConnectionError:
            raise RostoolsError(
                f"service {self.name} closed the connection before its header"
            ) from None
        if "error" in fields:
            proto.transport.close()
            raise RostoolsError(f"service {self.name} refused the call: {fields['error']}")
        return proto, fields

    async def _open(self, timeout: float) -> _ClientProtocol:
        """A connection for calls: the persistent one, or a new one."""
        if not self.persistent:
            proto, _ = await self._connect(False, timeout)
            return proto
        while (opening := self._opening) is not None:
            # Another call is connecting: share its connection, or try anew if it failed.
            await asyncio.wait([opening])
            if not opening.cancelled() and opening.result().usable:
                return opening.result()
        opening = self._opening = asyncio.get_running_loop().create_future()
        try:
            proto, _ = await self._connect(False, timeout)
        except BaseException:
            opening.cancel()  # the others connect for themselves, and get their own error
            raise
        finally:
            self._opening = None
        opening.set_result(proto)
        self._proto = proto
        return proto

    async def probe(self, timeout: float = SERVICE_TIMEOUT) -> dict[str, str]:
        """The server's header (``type``, ``md5sum``, ...), without calling it."""
        proto, fields = await self._connect(True, timeout)
        assert proto.transport is not None
        proto.transport.close()  # roscpp keeps a probe open; we close it ourselves
        return fields

    async def call(self, request: bytes, timeout: float = SERVICE_TIMEOUT) -> bytes:
        """Send one request; the response bytes. ``ServiceError`` when the server says no."""
        proto = self._proto
        if proto is None or not proto.usable:
            proto = await self._open(timeout)
        response = proto.send(frame(request), proto.loop.time() + timeout)
        try:
            ok, payload = await response
        except _NoResponseError:
            raise TimeoutExpired(
                f"service {self.name} did not respond within {timeout:g} s"
            ) from None
        except ConnectionError:
            raise RostoolsError(
                f"service {self.name} closed the connection without responding"
            ) from None
        finally:
            if not self.persistent:
                proto.fail(ConnectionError("closed after the call"))
        if not ok:
            text = payload.decode("utf-8", "replace")
            raise ServiceError(f"service {self.name} failed: {text or '(no reason given)'}")
        return payload

    def close(self) -> None:
        """Drop a persistent connection."""
        if self._proto is not None:
            self._proto.fail(ConnectionError("the client closed the connection"))
        self._proto = None
