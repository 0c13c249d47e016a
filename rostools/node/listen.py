"""Listening sockets whose accepts survive running out of file descriptors.

asyncio's own accept loop, past the descriptor limit, logs a traceback and schedules a retry
for every connection waiting in the backlog, on every turn: 400,000 tracebacks a minute, and a
flood that grows. Here, running out is one line per episode, and accepting is tried again
after ``RETRY_DELAY`` while connections wait in the kernel's backlog, as rosmaster's do.
"""

from __future__ import annotations

import asyncio
import contextlib
import errno
import logging
import resource
import socket
import time
from collections.abc import Callable

log = logging.getLogger(__name__)

#: Connections accepted per readiness event, as asyncio's accept loop (its ``backlog``).
BACKLOG = 100
#: While no descriptor is free, accept is tried again this often (rosmaster recovered 0.13 s
#: after connections closed).
RETRY_DELAY = 0.1
#: After an episode is reported, the next one is not for this long (s).
QUIET = 10.0
#: accept(2) errors that say a resource ran out, not that this connection failed.
_EXHAUSTED = {errno.EMFILE, errno.ENFILE, errno.ENOBUFS, errno.ENOMEM}


def raise_descriptor_limit() -> None:
    """Raise the soft limit on open files to the hard one, as servers do at start.

    A master or a ``record -a`` of a thousand topics holds a descriptor per connection;
    Debian's default soft limit is 1,024 where the hard one is often 500 times that.
    """
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    if hard == resource.RLIM_INFINITY or soft < hard:
        with contextlib.suppress(ValueError, OSError):
            resource.setrlimit(resource.RLIMIT_NOFILE, (hard, hard))


def exhausted_line(err: OSError) -> str:
    """The one line that says which descriptors ran out."""
    if err.errno == errno.EMFILE:
        limit = resource.getrlimit(resource.RLIMIT_NOFILE)[0]
        # EMFILE means every descriptor below the soft limit is taken
        return f"out of file descriptors: {limit} open, limit {limit}"
    if err.errno == errno.ENFILE:
        return "the system is out of file descriptors (ENFILE)"
    return f"out of memory for sockets ({errno.errorcode.get(err.errno or 0, err.errno)})"


class Listener:
    """Accepts on one or more listening sockets and hands each connection to ``factory``."""

    def __init__(
        self, factory: Callable[[], asyncio.BaseProtocol], sockets: list[socket.socket]
    ) -> None:
        self.factory = factory
        self.sockets = sockets
        self._loop = asyncio.get_running_loop()
        self._retry: asyncio.TimerHandle | None = None
        self._tasks: set[asyncio.Task[object]] = set()
        #: When running out was last reported (monotonic seconds), and whether it lasts.
        self._reported = -QUIET
        self._exhausted = False
        for sock in sockets:
            self._loop.add_reader(sock.fileno(), self._accept, sock)

    @property
    def port(self) -> int:
        """The bound port."""
        port: int = self.sockets[0].getsockname()[1]
        return port

    def _accept(self, sock: socket.socket) -> None:
        for _ in range(BACKLOG):
            try:
                conn, _ = sock.accept()
            except (BlockingIOError, InterruptedError, ConnectionAbortedError):
                return
            except OSError as err:
                if err.errno not in _EXHAUSTED:
                    log.warning("accepting a connection failed: %s", err)
                    return
                self._out_of_descriptors(err)
                return
            self._exhausted = False
            conn.setblocking(False)
            task = self._loop.create_task(self._loop.connect_accepted_socket(self.factory, conn))
            self._tasks.add(task)
            task.add_done_callback(self._accepted)

    def _accepted(self, task: asyncio.Task[object]) -> None:
        self._tasks.discard(task)
        if not task.cancelled() and (err := task.exception()) is not None:
            log.debug("an accepted connection failed to start: %s", err)

    def _out_of_descriptors(self, err: OSError) -> None:
        """Stop accepting for ``RETRY_DELAY``; say so once per episode."""
        now = time.monotonic()
        if not self._exhausted and now - self._reported >= QUIET:
            self._reported = now
            log.warning("%s; new connections wait until some close", exhausted_line(err))
        self._exhausted = True
        for sock in self.sockets:
            self._loop.remove_reader(sock.fileno())
        if self._retry is None:
            self._retry = self._loop.call_later(RETRY_DELAY, self._resume)

    def _resume(self) -> None:
        self._retry = None
        for sock in self.sockets:
            if sock.fileno() >= 0:
                self._loop.add_reader(sock.fileno(), self._accept, sock)

    def close(self) -> None:
        """Stop listening; connections already accepted stay as they are."""
        if self._retry is not None:
            self._retry.cancel()
            self._retry = None
        for sock in self.sockets:
            if sock.fileno() >= 0:
                self._loop.remove_reader(sock.fileno())
                sock.close()
        for task in self._tasks:
            task.cancel()


async def listen(
    factory: Callable[[], asyncio.BaseProtocol], host: str | None, port: int
) -> Listener:
    """Listen on ``host:port`` (every address the name has, as ``loop.create_server``)."""
    loop = asyncio.get_running_loop()
    infos = await loop.getaddrinfo(
        host or None, port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE
    )
    sockets: list[socket.socket] = []
    try:
        for family, kind, proto, _, address in dict.fromkeys(infos):
            sock = socket.socket(family, kind, proto)
            sockets.append(sock)
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            if family == socket.AF_INET6:
                # one socket per family, as create_server: no dual-stack surprises
                sock.setsockopt(socket.IPPROTO_IPV6, socket.IPV6_V6ONLY, 1)
            try:
                sock.bind(address)
            except OSError as err:  # worded as create_server words it
                reason = (err.strerror or str(err)).lower()
                raise OSError(
                    err.errno, f"error while attempting to bind on address {address!r}: {reason}"
                ) from None
            sock.listen(BACKLOG)
            sock.setblocking(False)
    except BaseException:
        for sock in sockets:
            sock.close()
        raise
    return Listener(factory, sockets)
