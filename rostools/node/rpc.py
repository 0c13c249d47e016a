"""XML-RPC on asyncio: the server of the master and of every node's slave API, and a client.

The server is an ``asyncio.BufferedProtocol``: a request is parsed, dispatched and answered in
one ``buffer_updated`` call, with HTTP/1.1 keep-alive, any request path, and limits on what a
client can make it buffer. Dispatch is synchronous: the handlers are pure (see
``rostools.master.master_api``) and anything slow they cause is scheduled, never awaited inline.
"""

from __future__ import annotations

import asyncio
import contextlib
import email.utils
import logging
import socket
import time
from collections.abc import Callable
from typing import Any
from urllib.parse import urlsplit

from rostools.errors import one_line
from rostools.node.listen import Listener, listen
from rostools.wire.xmlrpc import (
    MAX_BODY,
    BadCall,
    HttpError,
    HttpMessage,
    HttpParser,
    answer_value,
    decode_call,
    format_request,
    format_response,
)
from rostools.wire.xmlvalues import Fault, dumps_fault, dumps_response

log = logging.getLogger(__name__)

#: A request that has started must complete within this time, however it trickles in
#: (slow or half-open clients).
REQUEST_TIMEOUT = 30.0
#: A request body bigger than this is decoded and encoded in a thread and, for a multicall,
#: run in slices: parsing a 23 MB multicall held rosmaster-size graphs up for 4.5 s.
BIG_REQUEST = 256 * 1024
#: Calls of a big multicall run between two turns of the event loop (about 2 ms of work).
MULTICALL_SLICE = 500
#: Bodies bigger than this count against a budget shared by every connection...
LARGE_BODY = 1024 * 1024
#: ...which holds two of the largest bodies we accept (``MAX_BODY``) at once. rosmaster has
#: no budget: six slow 63 MiB bodies held 416 MB there.
BODY_BUDGET = 2 * MAX_BODY
#: Outgoing calls (publisherUpdate, paramUpdate, shutdown) give up after this long.
CALL_TIMEOUT = 5.0
#: A notification a node did not answer in time is sent again, this many times, each with
#: twice the time: a node busy on a loaded machine missed its publisherUpdate for good, and
#: never connected to the publisher (rosmaster waits without a limit, a thread a call).
NOTIFY_RETRIES = 3
#: The server's receive buffer, shared by its connections (asyncio reads this much at once).
RECEIVE_CHUNK = 256 * 1024
#: A refused request (an HTTP error) is answered, our side shut, and what the client still
#: sends read and dropped for up to this long: closed with it unread, the socket was reset,
#: and a client still sending (a 1 MiB header line) lost the answer with it (rosmaster: 431).
REFUSE_LINGER = 2.0

Dispatch = Callable[[str, tuple[Any, ...]], Any]


class Encoded:
    """A result that is already an encoded XML-RPC response body (cached by the handler)."""

    __slots__ = ("body",)

    def __init__(self, body: bytes) -> None:
        self.body = body


def run_call(dispatch: Dispatch, method: str, params: tuple[Any, ...]) -> Any:
    """Run a decoded call: its result, or an encoded fault (every failure becomes one)."""
    try:
        return dispatch(method, params)
    except Fault as fault:
        return Encoded(dumps_fault(fault.faultCode, fault.faultString))
    except OverflowError:
        return Encoded(dumps_fault(1, "<class 'OverflowError'>:int exceeds XML-RPC limits"))
    except Exception as err:  # noqa: BLE001 - answered as a fault, logged in one line
        # the method's name and the error may be the caller's text: one line in the log
        log.warning(
            "XML-RPC method %s failed: %s",
            one_line(method),
            one_line(f"{type(err).__name__}: {err}"),
        )
        return Encoded(dumps_fault(1, f"<class '{type(err).__name__}'>:{err}"))


def encode_answer(result: Any) -> bytes:
    """A result as a response body (an ``Encoded`` one as it is)."""
    if isinstance(result, Encoded):
        return result.body
    try:
        return dumps_response(result)
    except OverflowError:
        return dumps_fault(1, "<class 'OverflowError'>:int exceeds XML-RPC limits")
    except RecursionError:
        return dumps_fault(1, "<class 'RecursionError'>:value nested too deep to encode")


def handle_body(dispatch: Dispatch, body: bytes | bytearray) -> bytes:
    """Decode a call, run it, encode the answer; every failure becomes a fault."""
    try:
        method, params = decode_call(body)
    except BadCall as err:
        return dumps_fault(1, str(err))
    return encode_answer(run_call(dispatch, method, params))


_date_cache: tuple[int, str] = (0, "")


def http_date() -> str:
    """Now as an HTTP ``Date`` (made once a second: busy masters answer thousands of calls)."""
    global _date_cache
    now = int(time.time())
    if _date_cache[0] != now:
        _date_cache = (now, email.utils.formatdate(now, usegmt=True))
    return _date_cache[1]


class _Connection(asyncio.BufferedProtocol):
    """One client connection: requests answered in order, big ones off the fast path.

    It receives into its server's scratch buffer and the parser copies out at once: asyncio's
    plain ``recv`` allocates 256 KiB per read, which malloc serves with mmap and munmap.
    """

    def __init__(self, server: XmlRpcServer) -> None:
        self.server = server
        self.parser = HttpParser()
        self.transport: asyncio.Transport | None = None
        self.deadline: asyncio.TimerHandle | None = None
        #: A big request is being handled; what arrives meanwhile waits in the parser.
        self.busy = False
        #: Bytes of the body budget this connection holds.
        self.reserved = 0
        #: Refused: what arrives from now on is dropped (``_refuse``).
        self.refused = False

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        assert isinstance(transport, asyncio.Transport)
        self.transport = transport
        self.server.connections.add(self)

    def connection_lost(self, exc: Exception | None) -> None:
        self.server.connections.discard(self)
        self._release()
        if self.deadline is not None:
            self.deadline.cancel()

    def get_buffer(self, sizehint: int) -> memoryview:
        return self.server.scratch

    def buffer_updated(self, nbytes: int) -> None:
        if self.refused:
            return
        self.parser.feed(self.server.scratch[:nbytes])
        if not self.busy:
            try:
                self._process()
            except Exception as err:  # noqa: BLE001 - one line per bad request, never a traceback
                log.warning("XML-RPC request failed: %s", one_line(f"{type(err).__name__}: {err}"))
                self._refuse(HttpError(500, "Internal Server Error"))

    def _process(self) -> None:
        transport = self.transport
        assert transport is not None
        try:
            while (message := self.parser.next_message()) is not None:
                self._stop_clock()
                if len(message.body) > BIG_REQUEST:
                    self.busy = True
                    transport.pause_reading()
                    task = asyncio.get_running_loop().create_task(self._handle_big(message))
                    self.server.tasks.add(task)
                    task.add_done_callback(self.server.tasks.discard)
                    return
                body = handle_body(self.server.dispatch, message.body)
                self._answer(body, message.keep_alive)
                if not message.keep_alive:
                    return
            self._reserve(self.parser.pending)
        except HttpError as err:
            self._refuse(err)
            return
        if self.parser.buffer and self.deadline is None:
            # one deadline for the whole request, not renewed by each byte of a trickle
            loop = asyncio.get_running_loop()
            self.deadline = loop.call_later(REQUEST_TIMEOUT, transport.abort)

    async def _handle_big(self, message: HttpMessage) -> None:
        """Decode and encode in a thread, and run a multicall in slices: others get turns."""
        transport = self.transport
        assert transport is not None
        loop = asyncio.get_running_loop()
        try:
            method, params = await loop.run_in_executor(None, decode_call, message.body)
            result = await self.server.run(method, params)
        except BadCall as err:
            result = Encoded(dumps_fault(1, str(err)))
        finally:
            self._release()
        body = await loop.run_in_executor(None, encode_answer, result)
        self._answer(body, message.keep_alive)
        self.busy = False
        if message.keep_alive and not transport.is_closing():
            transport.resume_reading()
            self._process()

    def _answer(self, body: bytes, keep_alive: bool) -> None:
        assert self.transport is not None
        self.transport.write(format_response(body, keep_alive, date=http_date()))
        if self.server.after_call is not None:
            self.server.after_call()
        if not keep_alive:
            self.transport.close()

    def _refuse(self, err: HttpError) -> None:
        """Answer ``err``, shut our side, and drop what still comes until the client closes."""
        transport = self.transport
        assert transport is not None
        page = f"{err.status} {err.reason}".encode()
        transport.write(format_response(page, False, f"{err.status} {err.reason}"))
        self.refused = True
        self.parser = HttpParser()  # what it buffered is no longer needed
        self._release()
        if not transport.can_write_eof():
            transport.close()
            return
        transport.write_eof()  # the answer, then our FIN; the client's EOF ends the connection
        self._stop_clock()
        self.deadline = asyncio.get_running_loop().call_later(REFUSE_LINGER, transport.close)

    def _reserve(self, length: int) -> None:
        """Hold ``length`` of the body budget while a large body arrives (503 past it)."""
        if length <= LARGE_BODY or self.reserved:
            return
        if self.server.budget_used + length > BODY_BUDGET:
            raise HttpError(503, "Service Unavailable: too many large requests at once")
        self.reserved = length
        self.server.budget_used += length

    def _release(self) -> None:
        self.server.budget_used -= self.reserved
        self.reserved = 0

    def _stop_clock(self) -> None:
        if self.deadline is not None:
            self.deadline.cancel()
            self.deadline = None


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
        self.tasks: set[asyncio.Task[None]] = set()
        #: Bytes of large request bodies being received or handled, across connections.
        self.budget_used = 0
        #: Where every connection receives: each read is copied out before the next one.
        self.scratch = memoryview(bytearray(RECEIVE_CHUNK))
        self._server: Listener | None = None

    async def start(self) -> None:
        """Bind and listen; ``port`` holds the bound port afterwards."""
        self._server = await listen(lambda: _Connection(self), self.host, self.port)
        self.port = self._server.port

    async def run(self, method: str, params: tuple[Any, ...]) -> Any:
        """Run a call; a big ``system.multicall`` in slices, with turns for others between."""
        calls = params[0] if method == "system.multicall" and len(params) == 1 else None
        if not isinstance(calls, list) or len(calls) <= MULTICALL_SLICE:
            return run_call(self.dispatch, method, params)
        results: list[Any] = []
        for start in range(0, len(calls), MULTICALL_SLICE):
            part = run_call(self.dispatch, method, (calls[start : start + MULTICALL_SLICE],))
            if isinstance(part, Encoded):
                return part  # the multicall as a whole failed
            results += part
            if self.after_call is not None:
                self.after_call()
            await asyncio.sleep(0)
        return results

    async def close(self) -> None:
        """Stop listening and drop every connection."""
        if self._server is not None:
            self._server.close()
            for conn in list(self.connections):
                if conn.transport is not None:
                    conn.transport.abort()
            self._server = None


async def call(
    uri: str, method: str, params: tuple[Any, ...], timeout: float = CALL_TIMEOUT
) -> Any:
    """One XML-RPC call on a fresh connection.

    Raises what ``rosgraph.masterapi.call_error`` turns into our errors: ``TimeoutError``
    (never asyncio's own, which differs before Python 3.11), ``OSError``, ``Fault``,
    ``BadAnswer``, ``HttpError``.
    """
    parts = urlsplit(uri)
    host, port = parts.hostname or "localhost", parts.port or 80
    request = format_request(parts.netloc, parts.path or "/", method, params)

    async def exchange() -> Any:
        try:
            reader, writer = await asyncio.open_connection(host, port)
        except UnicodeError as err:  # a peer's URI with U+2028 in its host: no name to look up
            raise socket.gaierror(socket.EAI_NONAME, f"{host!r} is not a host name") from err
        try:
            writer.write(request)
            parser = HttpParser()
            while (message := parser.next_message()) is None:
                data = await reader.read(65536)
                if not data:
                    raise ConnectionError(f"{uri} closed the connection")
                parser.feed(data)
            return answer_value(message)
        finally:
            writer.close()
            with contextlib.suppress(OSError):
                await writer.wait_closed()

    try:
        return await asyncio.wait_for(exchange(), timeout)
    except asyncio.TimeoutError as err:
        raise TimeoutError(f"{uri} did not answer {method} within {timeout} s") from err


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
                    await self._deliver(uri, method, params)
        finally:
            self.queues.pop(uri, None)
            self.busy.discard(uri)

    async def _deliver(self, uri: str, method: str, params: tuple[Any, ...]) -> None:
        """One call, sent again with twice the time while the node is too slow to answer.

        Not when a newer call of the same method and subject waits behind it: it says more.
        """
        timeout = CALL_TIMEOUT
        for attempt in range(NOTIFY_RETRIES + 1):
            try:
                await call(uri, method, params, timeout)
                return
            except TimeoutError as err:
                log.debug("%s to %s: %s (attempt %d)", method, uri, err, attempt + 1)
                newer = any(m == method and p[:2] == params[:2] for m, p in self.queues[uri])
                if newer:
                    return
                timeout *= 2
            except Exception as err:  # noqa: BLE001 - best effort, as rosmaster's
                log.debug("%s to %s failed: %s", method, uri, err)
                return

    async def close(self) -> None:
        """Cancel what is still queued."""
        for task in list(self.tasks):
            task.cancel()
        for task in list(self.tasks):
            with contextlib.suppress(asyncio.CancelledError):
                await task
