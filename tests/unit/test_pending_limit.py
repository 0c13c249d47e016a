"""The limit on connections that have not sent their header (``connection.Pending``).

Past the limit the oldest silent connections are dropped. A connection whose header already
waits in its socket has spoken, though its loop has not read it yet: on a loaded machine a
burst of 300 real subscribers lost 61 of them to the limit before their headers were read.
"""

from __future__ import annotations

import asyncio
import socket
import time

from rostools.node import connection
from rostools.node.connection import Pending, ServerConnection
from tests.support.fakeconn import FakeTransport


def test_only_silent_connections_are_dropped_past_the_limit() -> None:
    async def main() -> tuple[list[bool], int]:
        pending = Pending(limit=2)
        pairs = [socket.socketpair() for _ in range(5)]
        conns = []
        try:
            for ours, _ in pairs:
                conn = ServerConnection(lambda fields, conn: None, pending)
                conn.connection_made(FakeTransport(ours))
                conns.append(conn)
            # the three oldest have sent bytes that nobody has read; the two newest nothing
            for _, theirs in pairs[:3]:
                theirs.sendall(b"\x10\x00\x00\x00")
            deadline = time.monotonic() + connection.PENDING_GRACE + 10
            while pending.dropped < 2 and time.monotonic() < deadline:
                await asyncio.sleep(0.05)
            return [c.transport.is_closing() for c in conns if c.transport], pending.dropped
        finally:
            for conn in conns:
                conn.connection_lost(None)  # cancels its handshake deadline
            for ours, theirs in pairs:
                ours.close()
                theirs.close()

    closed, dropped = asyncio.run(main())
    # the two silent ones go, though they are the newest; the speakers stay
    assert closed == [False, False, False, True, True]
    assert dropped == 2
