"""XML-RPC on asyncio: the server of the master and of every node's slave API, and a client.

The server is an ``asyncio.Protocol``: a request is parsed, dispatched and answered in one
``data_received`` call, with HTTP/1.1 keep-alive, any request path, and limits on what a
client can make it buffer. Dispatch is synchronous: the handlers are pure (see
``rostools.master.api``) and anything slow they cause is scheduled, never awaited inline.
"""

from __future__ import annotations

import asyncio
import contextlib
import email.utils
import logging
import time
import xmlrpc.client
from collections.abc import Callable
from typing import Any
from urllib.parse import urlsplit

from rostools.wire.xmlrpc import (
    HttpError,
    HttpParser,
    decode_call,
    decode_response,
    encode_fault,
    encode_result,
    format_request,
    format_response,
)

log = logging.getLogger(__name__)

#: A request that has started must complete within this time (slow or half-open clients).
REQUEST_TIMEOUT = 30.0
#: Outgoing calls (publisherUpdate, paramUpdate, shutdown) give up after this long.
CALL_TIMEOUT = 5.0

Dispatch = Callable[[str, tuple[Any, ...]], Any]


class Encoded:
    """A result that is already an encoded XML-RPC response body (cached by the handler)."""

    __slots__ = ("body",)

    def __init__(self, body: bytes) -> None:
        self.body = body


def handle_body(dispatch: Dispatch, body: bytes) -> bytes:
    """Decode a call, run it, encode the answer; every failure becomes a fault."""
    method, params = decode_call(body)
    try:
        result = dispatch(method, params)
        return result.body if isinstance(result, Encoded) else encode_result(result)
    except xmlrpc.client.Fault as fault:
        return encode_fault(fault.faultCode, fault.faultString)
    except OverflowError:
        return encode_fault(1, "<class 'OverflowError'>:int exceeds XML-RPC limits")
    except Exception as err:
        log.exception("XML-RPC method %s failed", method)
        return encode_fault(1, f"<class '{type(err).__name__}'>:{err}")


_date_cache: tuple[int, str] = (0, "")


def http_date() -> str:
    """Now as an HTTP ``Date`` (made once a second: busy masters answer thousands of calls)."""
    global _date_cache
    now = int(time.time())
    if _date_cache[0] != now:
        _date_cache = (now, email.utils.formatdate(now, usegmt=True))
    return _date_cache[1]


class _Connection(asyncio.Protocol):
    def __init__(self, server: XmlRpcServer) -> None:
        self.server = server
        self.parser = HttpParser()
        self.transport: asyncio.Transport | None = None
        self.deadline: asyncio.TimerHandle | None = None

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        assert isinstance(transport, asyncio.Transport)
        self.transport = transport
        self.server.connections.add(self)

    def connection_lost(self, exc: Exception | None) -> None:
        self.server.connections.discard(self)
        if self.deadline is not None:
            self.deadline.cancel()

    def data_received(self, data: bytes) -> None:
        transport = self.transport
        assert transport is not None
        self.parser.feed(data)
        try:
            while (message := self.parser.next_message()) is not None:
                body = handle_body(self.server.dispatch, message.body)
                transport.write(format_response(body, message.keep_alive, date=http_date()))
                if self.server.after_call is not None:
                    self.server.after_call()
                if not message.keep_alive:
                    transport.close()
                    return
        except HttpError as err:
            page = f"{err.status} {err.reason}".encode()
            transport.write(format_response(page, False, f"{err.status} {err.reason}"))
            transport.close()
            return
        self._arm_deadline()

    def _arm_deadline(self) -> None:
        if self.deadline is not None:
            self.deadline.cancel()
            self.deadline = None
        if self.parser.buffer and self.transport is not None:
            loop = asyncio.get_running_loop()
            self.deadline = loop.call_later(REQUEST_TIMEOUT, self.transport.abort)


class XmlRpcServer:
    """An XML-RPC server on the running event loop."""

    def __init__(
        self,
        dispatch: Dispatch,
        host: str = "127.0.0.1",
        port: int = 0,
        after_call: Callable[[], None] | None = None,
    ) -> None:
        self.dispatch = dispatch
        self.host = host
        self.port = port
        self.after_call = after_call
        self.connections: set[_Connection] = set()
        self._server: asyncio.base_events.Server | None = None

    async def start(self) -> None:
        """Bind and listen; ``port`` holds the bound port afterwards."""
        loop = asyncio.get_running_loop()
        self._server = await loop.create_server(
            lambda: _Connection(self), self.host, self.port, reuse_address=True
        )
        self.port = self._server.sockets[0].getsockname()[1]

    async def close(self) -> None:
        """Stop listening and drop every connection."""
        if self._server is not None:
            self._server.close()
            for conn in list(self.connections):
                if conn.transport is not None:
                    conn.transport.abort()
            await self._server.wait_closed()
            self._server = None


async def call(
    uri: str, method: str, params: tuple[Any, ...], timeout: float = CALL_TIMEOUT
) -> Any:
    """One XML-RPC call on a fresh connection; raises OSError/TimeoutError/Fault."""
    parts = urlsplit(uri)
    host, port = parts.hostname or "localhost", parts.port or 80
    request = format_request(parts.netloc, parts.path or "/", method, params)

    async def exchange() -> Any:
        reader, writer = await asyncio.open_connection(host, port)
        try:
            writer.write(request)
            parser = HttpParser()
            while (message := parser.next_message()) is None:
                data = await reader.read(65536)
                if not data:
                    raise ConnectionError(f"{uri} closed the connection")
                parser.feed(data)
            return decode_response(message.body)
        finally:
            writer.close()
            with contextlib.suppress(OSError):
                await writer.wait_closed()

    return await asyncio.wait_for(exchange(), timeout)


class Notifier:
    """Sends calls to nodes in the background, in order per node, a few nodes at a time.

    rosmaster does the same with a pool of 3 threads and at most one call in flight per
    target URI, so that the notifications one node receives stay ordered.
    """

    def __init__(self, workers: int = 8) -> None:
        self.queues: dict[str, list[tuple[str, tuple[Any, ...]]]] = {}
        self.busy: set[str] = set()
        self.slots = asyncio.Semaphore(workers)
        self.tasks: set[asyncio.Task[None]] = set()

    def send(self, uri: str, method: str, params: tuple[Any, ...]) -> None:
        """Queue a call to ``uri``."""
        self.queues.setdefault(uri, []).append((method, params))
        if uri not in self.busy:
            self.busy.add(uri)
            task = asyncio.get_running_loop().create_task(self._drain(uri))
            self.tasks.add(task)
            task.add_done_callback(self.tasks.discard)

    async def _drain(self, uri: str) -> None:
        try:
            async with self.slots:
                while self.queues.get(uri):
                    method, params = self.queues[uri].pop(0)
                    try:
                        await call(uri, method, params)
                    except Exception as err:  # noqa: BLE001 - best effort, as rosmaster's
                        log.debug("%s to %s failed: %s", method, uri, err)
        finally:
            self.queues.pop(uri, None)
            self.busy.discard(uri)

    async def close(self) -> None:
        """Cancel what is still queued."""
        for task in list(self.tasks):
            task.cancel()
        for task in list(self.tasks):
            with contextlib.suppress(asyncio.CancelledError):
                await task
