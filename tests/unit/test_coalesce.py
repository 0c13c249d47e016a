"""A counting subscriber lets small reads gather, and never holds back big frames."""

from __future__ import annotations

import asyncio
from typing import Any

from rostools.node.connection import InboundConnection
from rostools.wire.header import encode_header
from rostools.wire.tcpros import frame


class Counter:
    """The part of a Subscriber an InboundConnection talks to."""

    topic = "/t"
    max_frame = 10**9
    coalesce = 0.001
    reuse_frames = False

    def __init__(self) -> None:
        self.frames: list[Any] = []

    def header_received(self, conn: InboundConnection) -> None:
        """Nothing to do."""

    def frames_received(self, frames: list[Any], conn: InboundConnection, now: float) -> None:
        """Keep them."""
        self.frames += frames

    def connection_closed(self, conn: InboundConnection) -> None:
        """Nothing to do."""


class Transport:
    """Counts pauses."""

    def __init__(self) -> None:
        self.pauses = 0

    def pause_reading(self) -> None:
        """Counted."""
        self.pauses += 1

    def resume_reading(self) -> None:
        """Nothing to do."""

    def is_closing(self) -> bool:
        """Never."""
        return False


def _feed(conn: InboundConnection, data: bytes) -> None:
    while data:
        buf = conn.get_buffer(-1)
        n = min(len(buf), len(data), 48 * 1024)  # a loopback read's size
        buf[:n] = data[:n]
        conn.buffer_updated(n)
        data = data[n:]


def test_small_reads_pause_and_big_frames_never_wait() -> None:
    async def main() -> tuple[int, int, int]:
        sub = Counter()
        conn = InboundConnection(sub, "http://x:1/", 1, b"")
        transport = Transport()
        conn.transport = transport  # type: ignore[assignment]
        header = {"type": "std_msgs/String", "md5sum": "*", "callerid": "/p"}
        _feed(conn, encode_header(header))  # length-prefixed already
        _feed(conn, frame(b"small") * 3)
        small = transport.pauses
        image = frame(bytes(1_000_000))
        _feed(conn, image + image)  # every read under 64 KB, including each frame's tail
        return small, transport.pauses - small, len(sub.frames)

    small, big, frames = asyncio.run(main())
    assert small == 1  # three small messages in one read: one pause
    assert big == 0  # 1 MB frames at 48 KB a read: a pause per frame would cap bw at 1 GB/s
    assert frames == 5
