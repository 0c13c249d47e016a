"""A blocking service client: no node and no event loop needed.

``rosservice call`` is a one-shot, and a loop of calls is fastest on a plain socket: a call is
two syscalls, with none of an event loop's wake-ups. Against a rospy server the asyncio client
(``node.service.ServiceClient``) manages about three quarters of this one's rate, though it
reads a response at once when it is already there. The protocol parts come from
``rostools.wire.tcpros``, as in ``graph.service``.
"""

from __future__ import annotations

import socket
import time
from urllib.parse import urlsplit

from rostools.errors import RostoolsError, ServiceError, TimeoutExpired, UnreachableError
from rostools.rosgraph.masterapi import PROBE_TIMEOUT, SERVICE_TIMEOUT, WAIT_NOTICE, MasterProxy
from rostools.wire.tcpros import FrameError, ResponseReader, frame, service_request_header

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from collections.abc import Callable


class BlockingServiceClient:
    """Probe or call one service; ``persistent`` keeps one connection for every call.

    ``timeout`` bounds each probe and call; None is no limit for the response, as rosservice
    (connecting and the server's header still get ``PROBE_TIMEOUT``). ``waiting`` is told
    once, after ``WAIT_NOTICE`` seconds, what a response without a limit is waited for.
    """

    def __init__(
        self,
        master: MasterProxy,
        name: str,
        timeout: float | None = SERVICE_TIMEOUT,
        *,
        persistent: bool = False,
        waiting: Callable[[str], None] | None = None,
    ) -> None:
        self.master = master
        self.name = name
        self.timeout = timeout
        self.persistent = persistent
        self.waiting = waiting
        self._sock: socket.socket | None = None
        self._reader: ResponseReader | None = None
        self._md5 = ""

    def address(self) -> tuple[str, int]:
        """Host and port of the provider (NotFoundError when there is none)."""
        uri = self.master.lookup_service(self.name)
        parts = urlsplit(uri)
        if not parts.hostname or not parts.port:
            raise RostoolsError(f"the master gave {self.name} a bad URI: {uri}")
        return parts.hostname, parts.port

    def _setup_deadline(self) -> float:
        """When connecting and the server's header must be done by."""
        limit = PROBE_TIMEOUT if self.timeout is None else self.timeout
        return time.monotonic() + limit

    def _connect(self, header: bytes, deadline: float) -> tuple[socket.socket, ResponseReader]:
        """Connect, send the header, wait for the server's reply header."""
        host, port = self.address()
        try:
            sock = socket.create_connection((host, port), timeout=deadline - time.monotonic())
        except OSError as err:
            raise UnreachableError(
                f"cannot connect to service {self.name} at {host}:{port}: {err.strerror or err}"
            ) from err
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        reader = ResponseReader()
        try:
            sock.sendall(header)
            while reader.header is None:
                self._receive(sock, reader, deadline, "answering")
        except BaseException:
            sock.close()
            raise
        if "error" in reader.header:
            sock.close()
            raise RostoolsError(f"service {self.name} refused the call: {reader.header['error']}")
        return sock, reader

    def _receive(
        self, sock: socket.socket, reader: ResponseReader, deadline: float | None, what: str
    ) -> list[tuple[bool, bytes]]:
        """What the next read gives; with ``deadline`` None, however long it takes."""
        try:
            wait = None if deadline is None else max(deadline - time.monotonic(), 0.001)
            sock.settimeout(wait)
            data = sock.recv(65536)
        except TimeoutError:
            limit = PROBE_TIMEOUT if self.timeout is None else self.timeout
            why = f"service {self.name} did not respond within {limit:g} s"
            raise TimeoutExpired(why) from None
        except ConnectionResetError:
            data = b""  # a server that died mid-call: the same as one that closed
        except OSError as err:
            raise RostoolsError(f"service {self.name}: {err.strerror or err}") from err
        if not data:
            raise RostoolsError(f"service {self.name} closed the connection without {what}")
        try:
            return reader.feed(data)
        except FrameError as err:
            raise RostoolsError(f"garbage from service {self.name}: {err}") from err

    def probe(self, caller_id: str) -> dict[str, str]:
        """The server's header: ``type`` and ``md5sum``."""
        header = service_request_header(caller_id, self.name, "*", probe=True)
        sock, reader = self._connect(header, self._setup_deadline())
        sock.close()
        assert reader.header is not None
        return reader.header

    def call(self, caller_id: str, md5sum: str, request: bytes) -> bytes:
        """One request; the response bytes. ``ServiceError`` when the server says no."""
        started = time.monotonic()
        if self._sock is None or self._reader is None or md5sum != self._md5:
            self.close()
            header = service_request_header(
                caller_id, self.name, md5sum, persistent=self.persistent
            )
            # The request only after the reply header: rospy drops bytes that come with it.
            self._sock, self._reader = self._connect(header, self._setup_deadline())
            self._md5 = md5sum
        sock, reader = self._sock, self._reader
        deadline = None if self.timeout is None else started + self.timeout
        quiet_until = started + WAIT_NOTICE if deadline is None and self.waiting else None
        try:
            sock.sendall(frame(request))
            responses: list[tuple[bool, bytes]] = []
            while not responses:
                if quiet_until is None:
                    responses = self._receive(sock, reader, deadline, "responding")
                    continue
                try:  # no limit: say what we wait for once it has lasted a while
                    responses = self._receive(sock, reader, quiet_until, "responding")
                except TimeoutExpired:
                    assert self.waiting is not None
                    self.waiting(f"service {self.name} to respond")
                    quiet_until = None
        except BaseException:
            self.close()
            raise
        if not self.persistent:
            self.close()
        ok, payload = responses[0]
        if not ok:
            text = payload.decode("utf-8", "replace") or "(no reason given)"
            raise ServiceError(f"service {self.name} failed: {text}")
        return payload

    def close(self) -> None:
        """Drop the connection."""
        if self._sock is not None:
            self._sock.close()
        self._sock, self._reader = None, None
