"""Services over TCPROS (ROS1_PROTOCOL.md §6): servers, clients, and the type probe.

A client call never hangs: every step has a timeout, and a server that dies mid-call, refuses
the request or answers garbage raises one of our errors with a one-line reason.
"""

from __future__ import annotations

import asyncio
import inspect
import logging
from collections.abc import Awaitable, Callable
from typing import TYPE_CHECKING, NamedTuple
from urllib.parse import urlsplit

from rostools.errors import (
    NotFoundError,
    RostoolsError,
    ServiceError,
    TimeoutExpired,
    UnreachableError,
)
from rostools.msgs.store import TypeStore
from rostools.node.connection import Frame, ServerConnection, set_nodelay
from rostools.rosgraph.masterapi import SERVICE_TIMEOUT, MasterError
from rostools.wire import codes
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


class ServiceType(NamedTuple):
    """A service type as TCPROS headers carry it."""

    type: str
    md5sum: str

    @classmethod
    def of(cls, store: TypeStore, name: str) -> ServiceType:
        """The service type ``name`` as the store knows it."""
        return cls(store.srv(name).name, store.srv_md5(name))


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
                    reply = service_response(False, f"error processing request: {err}".encode())
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


class _ClientProtocol(asyncio.Protocol):
    """A client connection: the reply header, then one response per request, in order."""

    def __init__(self) -> None:
        loop = asyncio.get_running_loop()
        self.reader = ResponseReader()
        self.header: asyncio.Future[dict[str, str]] = loop.create_future()
        self.ready: list[tuple[bool, bytes]] = []
        self.waiter: asyncio.Future[tuple[bool, bytes]] | None = None
        self.failure: BaseException | None = None
        self.transport: asyncio.Transport | None = None

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        """Asyncio: connected."""
        assert isinstance(transport, asyncio.Transport)
        self.transport = transport
        set_nodelay(transport)

    def data_received(self, data: bytes) -> None:
        """Asyncio: bytes arrived."""
        try:
            responses = self.reader.feed(data)
        except FrameError as err:
            self._fail(RostoolsError(f"garbage from the service: {err}"))
            return
        if self.reader.header is not None and not self.header.done():
            self.header.set_result(self.reader.header)
        self.ready += responses
        if self.ready and self.waiter is not None and not self.waiter.done():
            self.waiter.set_result(self.ready.pop(0))

    def next_response(self) -> asyncio.Future[tuple[bool, bytes]]:
        """The next response (already here, or when it arrives)."""
        future: asyncio.Future[tuple[bool, bytes]] = asyncio.get_running_loop().create_future()
        if self.ready:
            future.set_result(self.ready.pop(0))
        elif self.failure is not None:
            future.set_exception(self.failure)
        else:
            self.waiter = future
        return future

    def _fail(self, err: BaseException) -> None:
        self.failure = err
        if not self.header.done():
            self.header.set_exception(err)
        if self.waiter is not None and not self.waiter.done():
            self.waiter.set_exception(err)
        if self.transport is not None:
            self.transport.close()

    def connection_lost(self, exc: Exception | None) -> None:
        """Asyncio: the connection closed."""
        self._fail(ConnectionError("the service closed the connection"))


async def lookup_service(node: Owner, name: str) -> tuple[str, int]:
    """Host and port of a service's provider."""
    try:
        uri = await node.master_call("lookupService", name)
    except MasterError as err:
        if err.code == codes.ERROR:
            raise NotFoundError(f"service {name} is not available") from err
        raise
    parts = urlsplit(str(uri))
    if parts.scheme != "rosrpc" or not parts.hostname or not parts.port:
        raise RostoolsError(f"the master gave {name} a bad URI: {uri}")
    return parts.hostname, parts.port


class ServiceClient:
    """Calls one service; ``persistent`` keeps the connection for the next call."""

    def __init__(
        self, node: Owner, name: str, srv_type: ServiceType | None = None, persistent: bool = False
    ) -> None:
        self.node = node
        self.name = name
        self.type = srv_type
        self.persistent = persistent
        self._proto: _ClientProtocol | None = None

    async def _connect(self, probe: bool, timeout: float) -> tuple[_ClientProtocol, dict[str, str]]:
        host, port = await lookup_service(self.node, self.name)
        md5 = "*" if probe or self.type is None else self.type.md5sum
        header = service_request_header(
            self.node.name, self.name, md5, persistent=self.persistent and not probe, probe=probe
        )
        loop = asyncio.get_running_loop()
        try:
            _, proto = await asyncio.wait_for(
                loop.create_connection(_ClientProtocol, host, port), timeout
            )
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

    async def probe(self, timeout: float = SERVICE_TIMEOUT) -> dict[str, str]:
        """The server's header (``type``, ``md5sum``, ...), without calling it."""
        proto, fields = await self._connect(True, timeout)
        assert proto.transport is not None
        proto.transport.close()  # roscpp keeps a probe open; we close it ourselves
        return fields

    async def call(self, request: bytes, timeout: float = SERVICE_TIMEOUT) -> bytes:
        """Send one request; the response bytes. ``ServiceError`` when the server says no."""
        proto = self._proto
        if proto is None or proto.transport is None or proto.transport.is_closing():
            proto, _ = await self._connect(False, timeout)
        assert proto.transport is not None
        response = proto.next_response()
        proto.transport.write(frame(request))
        # A timer, not wait_for: wait_for makes a task per call, a third of a fast call's cost.
        timer = asyncio.get_running_loop().call_later(timeout, response.cancel)
        try:
            ok, payload = await response
        except asyncio.CancelledError:
            proto.transport.close()
            self._proto = None
            if not response.cancelled():
                raise
            raise TimeoutExpired(
                f"service {self.name} did not respond within {timeout:g} s"
            ) from None
        except ConnectionError:
            self._proto = None
            raise RostoolsError(
                f"service {self.name} closed the connection without responding"
            ) from None
        except RostoolsError:
            self._proto = None
            raise
        finally:
            timer.cancel()
            if not self.persistent:
                proto.transport.close()
        self._proto = proto if self.persistent else None
        if not ok:
            text = payload.decode("utf-8", "replace")
            raise ServiceError(f"service {self.name} failed: {text or '(no reason given)'}")
        return payload

    def close(self) -> None:
        """Drop a persistent connection."""
        if self._proto is not None and self._proto.transport is not None:
            self._proto.transport.close()
        self._proto = None
